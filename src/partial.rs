//! Output files that appear whole or not at all: written beside the target under a hidden
//! temporary name, renamed onto it when complete, removed if dropped before.

use std::fs::File;
use std::path::{Path, PathBuf};

/// A file being written for `target`.
pub struct Partial {
    tmp: PathBuf,
    target: PathBuf,
    done: bool,
}

impl Partial {
    /// Creates `.NAME.partial-PID` beside `target` and returns it open for writing.
    /// Refuses a target that exists but is not a regular file: renaming onto a device such
    /// as `/dev/null` would replace the device node itself.
    pub fn create(target: &Path) -> Result<(Self, File), String> {
        if let Ok(meta) = std::fs::metadata(target) {
            if !meta.is_file() {
                return Err(format!(
                    "{}: not a regular file (a directory, device or pipe), so it cannot be \
                     replaced whole; name a file to write, e.g. out.csv",
                    target.display()
                ));
            }
        }
        let name = target
            .file_name()
            .ok_or_else(|| format!("{}: not a file name", target.display()))?;
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".partial-{}", std::process::id()));
        let tmp = target.with_file_name(tmp_name);
        let file =
            File::create(&tmp).map_err(|e| format!("cannot create {}: {e}", target.display()))?;
        let partial = Self {
            tmp,
            target: target.to_path_buf(),
            done: false,
        };
        Ok((partial, file))
    }

    /// Renames the finished file onto the target.
    pub fn commit(mut self) -> Result<(), String> {
        std::fs::rename(&self.tmp, &self.target)
            .map_err(|e| format!("cannot write {}: {e}", self.target.display()))?;
        self.done = true;
        Ok(())
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Writes `bytes` to `target` whole or not at all.
pub fn write(target: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write;
    let (partial, mut file) = Partial::create(target)?;
    file.write_all(bytes)
        .and_then(|()| file.flush())
        .map_err(|e| format!("cannot write {}: {e}", target.display()))?;
    partial.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_device_or_directory_target_is_refused_and_left_alone() {
        for target in ["/dev/null", "/tmp"] {
            let err = Partial::create(Path::new(target)).err().expect("refused");
            assert!(err.contains("not a regular file"), "{err}");
        }
        let dev_null = std::fs::metadata("/dev/null").expect("/dev/null exists");
        assert!(!dev_null.is_file(), "/dev/null is still a device");
        let tmp = format!("/dev/.null.partial-{}", std::process::id());
        assert!(!Path::new(&tmp).exists(), "{tmp} was not created");
    }

    #[test]
    fn a_file_appears_whole_on_commit() {
        let target = std::env::temp_dir().join(format!("partial-test-{}.txt", std::process::id()));
        write(&target, b"whole").expect("written");
        assert_eq!(std::fs::read(&target).expect("read back"), b"whole");
        std::fs::remove_file(&target).expect("removed");
    }
}

//! Output files that appear whole or not at all. Each is written to a hidden temporary
//! `.NAME.tmpXXXXXX.tensegrity-fmu` beside the target, created exclusively under an unpredictable name
//! (the `tempfile` crate: `O_EXCL`, so a symlink planted there is never followed), and
//! renamed over the target when complete: the target keeps its old content until then.
//!
//! While a temporary exists it is locked (`flock`) and listed here, so that
//! [`remove_temps_and_exit`] (the CLI's signal handler) can remove it, and so that the next
//! run writing into the same folder removes what a killed run left ([`leftovers`]) but never
//! a file that a live process is still writing.

mod leftovers;

use std::fs::{File, Permissions};
use std::io::{BufWriter, Write};
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

use tempfile::{Builder, TempDir, TempPath};

/// The temporaries of this process that are being written.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary being written and ends the process with `code`; the files
/// already committed stay. Holds the list until the end, so no new one appears meanwhile.
/// With `wait` false (from a panic hook, whose thread may hold the list), gives up on the
/// removal rather than wait.
pub fn remove_temps_and_exit(code: i32, wait: bool) -> ! {
    let guard = if wait {
        Some(live())
    } else {
        LIVE.try_lock().ok()
    };
    if let Some(paths) = &guard {
        paths.iter().for_each(|p| remove_any(p));
    }
    std::process::exit(code)
}

fn remove_any(path: &Path) {
    if path.is_dir() {
        let _ = std::fs::remove_dir_all(path);
    } else {
        let _ = std::fs::remove_file(path);
    }
}

/// A file being written for `target`.
pub struct Partial {
    /// `None` once committed.
    tmp: Option<TempPath>,
    target: PathBuf,
    /// Holds the advisory lock until the end.
    _lock: File,
}

impl Partial {
    /// Creates `.NAME.tmpXXXXXX.tensegrity-fmu` beside `target` (after removing what killed runs left
    /// there) and returns it open for writing. Refuses a target that exists but is not a
    /// regular file: renaming onto a device such as `/dev/null` would replace the device
    /// node itself.
    pub fn create(target: &Path) -> Result<(Self, File), String> {
        let (dir, prefix) = temp_place(target)?;
        let mode = match std::fs::metadata(target) {
            Ok(meta) if !meta.is_file() => {
                return Err(format!(
                    "{}: not a regular file (a directory, device or pipe), so it cannot be \
                     replaced whole; name a file to write, e.g. out.csv",
                    target.display()
                ))
            }
            Ok(meta) => meta.mode() & 0o777, // never setuid, setgid or sticky
            Err(_) => 0o666,
        };
        let cannot = |e: std::io::Error| format!("cannot create {}: {e}", target.display());
        loop {
            let mut live = live();
            let file = named(&prefix, mode).tempfile_in(&dir).map_err(cannot)?;
            let (file, tmp) = file.into_parts();
            if !lock_and_still_there(&file, &tmp).map_err(cannot)? {
                continue; // another run took it for a leftover: make another
            }
            live.push(tmp.to_path_buf());
            let writer = file.try_clone().map_err(cannot)?;
            let target = target.to_path_buf();
            return Ok((
                Self {
                    tmp: Some(tmp),
                    target,
                    _lock: file,
                },
                writer,
            ));
        }
    }

    /// Renames the finished file onto the target.
    pub fn commit(mut self) -> Result<(), String> {
        let mut live = live();
        let tmp = self.tmp.take().expect("committed once");
        live.retain(|p| p != &*tmp);
        tmp.persist(&self.target)
            .map_err(|e| format!("cannot write {}: {}", self.target.display(), e.error))
    }

    fn tmp_path(&self) -> &Path {
        self.tmp.as_deref().expect("not committed")
    }
}

impl Drop for Partial {
    fn drop(&mut self) {
        // `TempPath` removes the file itself.
        if let Some(tmp) = &self.tmp {
            live().retain(|p| p != &**tmp);
        }
    }
}

/// A folder being written for `target` (a folder of several files, replaced as one).
pub struct PartialDir {
    /// `None` once committed.
    tmp: Option<TempDir>,
    target: PathBuf,
    _lock: File,
}

impl PartialDir {
    /// Creates the empty folder `.NAME.tmpXXXXXX.tensegrity-fmu` beside `target`.
    pub fn create(target: &Path) -> Result<Self, String> {
        let (dir, prefix) = temp_place(target)?;
        let cannot = |e: std::io::Error| format!("cannot create {}: {e}", target.display());
        loop {
            let mut live = live();
            let tmp = named(&prefix, 0o777).tempdir_in(&dir).map_err(cannot)?;
            let lock = match File::open(tmp.path()) {
                Ok(lock) => lock,
                // Another run took it for a leftover between creation and opening.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(cannot(e)),
            };
            if !lock_and_still_there(&lock, tmp.path()).map_err(cannot)? {
                continue;
            }
            live.push(tmp.path().to_path_buf());
            let target = target.to_path_buf();
            return Ok(Self {
                tmp: Some(tmp),
                target,
                _lock: lock,
            });
        }
    }

    /// Where to write the folder's files.
    pub fn path(&self) -> &Path {
        self.tmp.as_ref().expect("not committed").path()
    }
}

impl Drop for PartialDir {
    fn drop(&mut self) {
        // `TempDir` removes the folder itself.
        if let Some(tmp) = &self.tmp {
            live().retain(|p| p != tmp.path());
        }
    }
}

/// Puts the folder `dir` and then the file `file` into place, an existing folder at
/// `dir`'s target being replaced (and restored if the file cannot be put in place). A
/// signal meanwhile waits for the end, so that it never finds the old folder moved aside.
pub fn commit_folder_and_file(mut dir: PartialDir, mut file: Partial) -> Result<(), String> {
    let shown = dir.target.display().to_string();
    let aside = if dir.target.exists() {
        Some(PartialDir::create(&dir.target)?)
    } else {
        None
    };
    let mut live = live();
    let old = aside.as_ref().map(|a| a.path().join("old"));
    if let Some(old) = &old {
        std::fs::rename(&dir.target, old).map_err(|e| format!("{shown}: cannot replace: {e}"))?;
    }
    let restore = || {
        if let Some(old) = &old {
            let _ = std::fs::rename(old, &dir.target);
        }
    };
    if let Err(e) = std::fs::rename(dir.path(), &dir.target) {
        restore();
        return Err(format!("{shown}: cannot create: {e}"));
    }
    if let Err(e) = std::fs::rename(file.tmp_path(), &file.target) {
        let _ = std::fs::rename(&dir.target, dir.path());
        restore();
        return Err(format!("{}: cannot create: {e}", file.target.display()));
    }
    live.retain(|p| p != file.tmp_path() && p != dir.path());
    // Both were renamed away: nothing is left for them to remove.
    if let Some(tmp) = file.tmp.take() {
        let _ = tmp.keep();
    }
    if let Some(tmp) = dir.tmp.take() {
        let _ = tmp.keep();
    }
    drop(live);
    Ok(())
}

/// A temporary's name, `PREFIX` + six random letters or digits + the suffix that marks it
/// as this program's, and its permission bits.
fn named(prefix: &std::ffi::OsStr, mode: u32) -> Builder<'_, 'static> {
    let mut builder = Builder::new();
    builder
        .prefix(prefix)
        .rand_bytes(6)
        .suffix(leftovers::SUFFIX)
        .permissions(Permissions::from_mode(mode));
    builder
}

/// The folder of `target` and the prefix of its temporaries, after removing the leftovers
/// of killed runs there.
fn temp_place(target: &Path) -> Result<(PathBuf, std::ffi::OsString), String> {
    let name = target
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", target.display()))?;
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    leftovers::remove(&dir);
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name);
    prefix.push(".tmp");
    Ok((dir, prefix))
}

/// Locks `file` (just created at `path`) and checks that `path` still names it: another
/// run's [`leftovers::remove`] may have taken it before the lock.
fn lock_and_still_there(file: &File, path: &Path) -> std::io::Result<bool> {
    if leftovers::try_lock(file)? == leftovers::Lock::Busy {
        return Ok(false);
    }
    leftovers::same_file(file, path)
}

/// Writes `target` whole or not at all, its bytes written by `write`.
pub fn write_with(
    target: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), String> {
    let (partial, file) = Partial::create(target)?;
    let mut w = BufWriter::new(file);
    write(&mut w)
        .and_then(|()| w.flush())
        .map_err(|e| format!("cannot write {}: {e}", target.display()))?;
    drop(w);
    partial.commit()
}

/// Writes `bytes` to `target` whole or not at all.
pub fn write(target: &Path, bytes: &[u8]) -> Result<(), String> {
    write_with(target, |w| w.write_all(bytes))
}

/// An RGB buffer of `size` for plotters' `BitMapBackend::with_buffer`.
pub fn blank_rgb((w, h): (u32, u32)) -> Vec<u8> {
    vec![0u8; w as usize * h as usize * 3]
}

/// Writes the RGB pixels `rgb` of `size` as a PNG to `target`, whole or not at all
/// (plotters' own PNG writer would write the target in place).
pub fn write_png(target: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<(), String> {
    use image::ImageEncoder;
    write_with(target, |out| {
        image::codecs::png::PngEncoder::new(out)
            .write_image(rgb, w, h, image::ColorType::Rgb8)
            .map_err(|e| match e {
                image::ImageError::IoError(e) => e,
                e => std::io::Error::other(e),
            })
    })
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
    }

    #[test]
    fn a_file_appears_whole_on_commit_and_its_temporary_is_hidden_and_locked() {
        let dir = tempfile::tempdir().expect("a folder");
        let target = dir.path().join("out.txt");
        std::fs::write(&target, b"old").expect("old content");
        let (partial, mut file) = Partial::create(&target).expect("created");
        file.write_all(b"whole").expect("written");
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .expect("listed")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        let tmp = names
            .iter()
            .find(|n| n.starts_with(".out.txt.tmp"))
            .expect("a hidden temporary");
        assert_eq!(
            tmp.len(),
            ".out.txt.tmp".len() + 6 + leftovers::SUFFIX.len(),
            "{tmp}"
        );
        assert!(tmp.ends_with(".tensegrity-fmu"), "{tmp}");
        let other = File::open(dir.path().join(tmp)).expect("opened");
        assert_eq!(
            leftovers::try_lock(&other).expect("flock"),
            leftovers::Lock::Busy
        );
        assert_eq!(std::fs::read(&target).expect("read"), b"old");
        partial.commit().expect("committed");
        assert_eq!(std::fs::read(&target).expect("read back"), b"whole");
        assert_eq!(std::fs::read_dir(dir.path()).expect("listed").count(), 1);
        assert!(live().is_empty());
    }

    #[test]
    fn a_dropped_file_leaves_nothing_and_the_target_alone() {
        let dir = tempfile::tempdir().expect("a folder");
        let target = dir.path().join("out.txt");
        std::fs::write(&target, b"old").expect("old content");
        let err = write_with(&target, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        })
        .expect_err("fails");
        assert_eq!(err, format!("cannot write {}: disk full", target.display()));
        assert_eq!(std::fs::read(&target).expect("read"), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).expect("listed").count(), 1);
    }
}

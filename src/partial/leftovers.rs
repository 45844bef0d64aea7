//! What killed runs left: hidden `.NAME.tmpXXXXXX.tensegrity-fmu` files and folders that no
//! live process holds locked (the suffix keeps other programs' temporaries out of reach). A process writing one holds an exclusive `flock` on it from creation to
//! the end, so whatever can be locked here has no writer left.

use std::fs::File;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::os::unix::io::AsRawFd;
use std::path::Path;

/// Removes the leftovers in `dir`; one that cannot be removed is left as it is.
pub fn remove(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        if !is_leftover_name(entry.file_name().as_bytes()) {
            continue;
        }
        let path = entry.path();
        // O_NOFOLLOW: a symlink of that name is not ours, and is never followed.
        let Ok(file) = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
        else {
            continue;
        };
        if !matches!(try_lock(&file), Ok(Lock::Taken))
            || !matches!(same_file(&file, &path), Ok(true))
        {
            continue;
        }
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        if removed.is_ok() {
            eprintln!(
                "note: removed {}, left by a run that was killed",
                path.display()
            );
        }
    }
}

/// The end of every temporary's name: only names of this program's are ever removed.
pub const SUFFIX: &str = ".tensegrity-fmu";

/// `.NAME.tmpXXXXXX.tensegrity-fmu`: a dot, a name, `.tmp`, six letters or digits and
/// [`SUFFIX`].
fn is_leftover_name(name: &[u8]) -> bool {
    let Some(name) = name.strip_suffix(SUFFIX.as_bytes()) else {
        return false;
    };
    let n = name.len();
    n >= ".x.tmp".len() + 6
        && name[0] == b'.'
        && &name[n - 10..n - 6] == b".tmp"
        && name[n - 6..].iter().all(u8::is_ascii_alphanumeric)
}

/// What an attempt to lock a file found.
#[derive(Debug, PartialEq, Eq)]
pub enum Lock {
    /// This open file now holds the exclusive lock.
    Taken,
    /// Another open file (of this process or another) holds one.
    Busy,
    /// The filesystem has no locks (some network mounts): nothing can prove there that a
    /// temporary is dead, so none is taken for a leftover, and writing goes on unlocked.
    Unsupported,
}

/// Takes an exclusive advisory lock on `file` without waiting.
pub fn try_lock(file: &File) -> std::io::Result<Lock> {
    // SAFETY: flock on a descriptor that `file` keeps open.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
        return Ok(Lock::Taken);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(Lock::Busy),
        Some(libc::ENOLCK | libc::EOPNOTSUPP) => Ok(Lock::Unsupported),
        _ => Err(e),
    }
}

/// Whether `path` (not followed if a symlink) names the open `file`.
pub fn same_file(file: &File, path: &Path) -> std::io::Result<bool> {
    let open = file.metadata()?;
    Ok(match std::fs::symlink_metadata(path) {
        Ok(named) => named.dev() == open.dev() && named.ino() == open.ino(),
        Err(_) => false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_hidden_temporaries_of_this_program_are_leftovers() {
        for name in [".out.csv.tmpA1b2C3", ".x_vtp.tmp000000", ".a.tmpzzzzzz"] {
            let ours = format!("{name}{SUFFIX}");
            assert!(is_leftover_name(ours.as_bytes()), "{ours}");
            // Another program's temporary of the same shape is not ours to remove.
            assert!(!is_leftover_name(name.as_bytes()), "{name}");
        }
        for name in [
            "out.csv.tmpA1b2C3",
            ".out.csv.tmpA1b2C",
            ".out.csv.tmpA1b2C!",
            ".out.csv.partial-12",
            ".tmpA1b2C3",
            ".out.csv",
        ] {
            let ours = format!("{name}{SUFFIX}");
            assert!(!is_leftover_name(ours.as_bytes()), "{ours}");
        }
    }
}

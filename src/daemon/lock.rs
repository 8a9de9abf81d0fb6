//! One owner per data directory: an advisory lock (`flock`, through std's `File::try_lock`) on
//! `<dir>/bearingd.lock`, taken before anything in the directory is opened.
//!
//! Why: start-up recovery rewrites every unfinished log file it finds, and the open file of a
//! running daemon *is* unfinished; a second daemon on the same directory would "recover" it
//! under the first one's feet, and both would overwrite the state files. The lock makes the
//! second one stop before it touches anything, naming the holder.
//!
//! The file holds who took it (pid, host, start time in UTC). The kernel drops a `flock` when
//! its holder dies, so a lock file whose text is left but whose lock is free belongs to a
//! process that did not stop cleanly (a `kill -9`, a power cut): it is taken over, and the
//! caller is told whose it was. A clean stop empties the file, so the next start says nothing.
//!
//! The lock file is opened without following a link (`O_NOFOLLOW`) and must be this user's
//! regular file: a link named `bearingd.lock` planted to another file is refused, never
//! truncated, and nothing of another file is read into a message (issue 32). Only the first
//! line, at most [`MAX_HOLDER_BYTES`], of our own lock file is ever read.

use crate::clock::wall_clock_now_ns;
use crate::fsafe::{check_own_regular, no_follow, NotOwnFile};
use crate::mcap_log::files::utc_text;
use crate::sinks::mcap::metadata::host_name;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The lock file's name inside each locked directory.
pub const LOCK_FILE: &str = "bearingd.lock";
/// What is read of a lock file to name its holder, at most.
pub const MAX_HOLDER_BYTES: u64 = 256;

/// Why a directory could not be locked.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    #[error(
        "{dir}: in use by another bearingd ({holder}); stop it first, or give this one its own \
         directory (outputs.mcap_dir / outputs.state_dir, or --data-dir)"
    )]
    Held { dir: PathBuf, holder: String },
    #[error("{path}: cannot {op} the lock file: {source}; check the directory's permissions")]
    Io {
        path: PathBuf,
        op: &'static str,
        source: std::io::Error,
    },
    #[error("lock file: {0}")]
    NotOwnFile(#[from] NotOwnFile),
}

/// A held lock on a directory; released (and the file emptied) when dropped.
#[derive(Debug)]
pub struct DirLock {
    file: File,
    path: PathBuf,
    /// What the lock file said when it was taken: a previous owner that did not stop cleanly.
    pub taken_over_from: Option<String>,
}

impl DirLock {
    /// Locks `dir` (which must exist) for this process, or says who holds it.
    pub fn acquire(dir: &Path) -> Result<DirLock, LockError> {
        let path = dir.join(LOCK_FILE);
        let io = |op| {
            let path = path.clone();
            move |source| LockError::Io { path, op, source }
        };
        let opened = no_follow(
            OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false),
        )
        .open(&path);
        let mut file = match opened {
            Err(e) if e.raw_os_error() == Some(libc::ELOOP) => {
                return Err(LockError::NotOwnFile(NotOwnFile::NotRegular {
                    path,
                    kind: "a symbolic link",
                }))
            }
            other => other.map_err(io("open"))?,
        };
        check_own_regular(&path, file.metadata().map_err(io("stat"))?)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                // The holder may be writing its line right now; what is there names it.
                return Err(LockError::Held {
                    dir: dir.to_path_buf(),
                    holder: holder_text(&first_line(&mut file).unwrap_or_default()),
                });
            }
            Err(TryLockError::Error(e)) => return Err(io("lock")(e)),
        }
        let previous = first_line(&mut file).map_err(io("read"))?;
        let line = format!(
            "pid={} host={} started={}\n",
            std::process::id(),
            host_name(),
            utc_text(wall_clock_now_ns())
        );
        file.set_len(0).map_err(io("write"))?;
        file.seek(SeekFrom::Start(0)).map_err(io("write"))?;
        file.write_all(line.as_bytes()).map_err(io("write"))?;
        file.sync_all().map_err(io("write"))?;
        let previous = previous.trim();
        Ok(DirLock {
            file,
            path,
            taken_over_from: (!previous.is_empty()).then(|| previous.to_string()),
        })
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Empty means "released cleanly"; the kernel drops the flock when the file closes.
        let _ = self.file.set_len(0);
        let _ = self.file.sync_all();
    }
}

/// The first line of the lock file, read from its start, at most [`MAX_HOLDER_BYTES`].
fn first_line(file: &mut File) -> std::io::Result<String> {
    let mut bytes = Vec::new();
    (&mut *file)
        .take(MAX_HOLDER_BYTES)
        .read_to_end(&mut bytes)?;
    let text = String::from_utf8_lossy(&bytes);
    Ok(text.lines().next().unwrap_or_default().to_string())
}

fn holder_text(text: &str) -> String {
    match text.trim() {
        "" => "its pid is not written yet".to_string(),
        line => line.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bearingd-lock-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_second_lock_on_the_same_directory_is_refused_and_names_the_holder() {
        let dir = scratch("twice");
        let first = DirLock::acquire(&dir).unwrap();
        assert!(first.taken_over_from.is_none());
        let err = DirLock::acquire(&dir).unwrap_err().to_string();
        assert!(
            err.contains(&format!("pid={}", std::process::id())) && err.contains("host="),
            "{err}"
        );
        drop(first);
        let again = DirLock::acquire(&dir).unwrap();
        assert!(
            again.taken_over_from.is_none(),
            "a clean release is not stale"
        );
    }

    #[test]
    fn a_lock_file_left_by_a_dead_process_is_taken_over_and_said() {
        let dir = scratch("stale");
        std::fs::write(dir.join(LOCK_FILE), "pid=999999 host=old started=x\n").unwrap();
        let lock = DirLock::acquire(&dir).unwrap();
        assert_eq!(
            lock.taken_over_from.as_deref(),
            Some("pid=999999 host=old started=x")
        );
        drop(lock);
        // A link in its place is refused: its target neither truncated nor read.
        let victim = dir.join("victim");
        std::fs::write(&victim, "secret\n").unwrap();
        std::fs::remove_file(dir.join(LOCK_FILE)).unwrap();
        std::os::unix::fs::symlink(&victim, dir.join(LOCK_FILE)).unwrap();
        let err = DirLock::acquire(&dir).unwrap_err().to_string();
        assert!(
            err.contains("symbolic link") && !err.contains("secret"),
            "{err}"
        );
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "secret\n");
        std::fs::remove_file(dir.join(LOCK_FILE)).unwrap();
        let lock = DirLock::acquire(&dir).unwrap();
        let text = std::fs::read_to_string(lock.path()).unwrap();
        assert!(
            text.starts_with(&format!("pid={} ", std::process::id())),
            "{text}"
        );
    }
}

//! Safe file creation where others may have planted names: every file bearingd writes in its
//! data directories goes through here.
//!
//! Why: the daemon writes in directories (`outputs.state_dir`, `outputs.mcap_dir`, a replay's
//! `--out`) where a careless or hostile neighbour can leave a symbolic link named like one of
//! its files. Following it would overwrite (or truncate, or copy out) whatever the link points
//! at, with the daemon's rights. So (issue 32):
//!
//! - a file is never opened for writing through a link: new files are created with
//!   `O_CREAT|O_EXCL` ([`create_new`]), existing ones opened with `O_NOFOLLOW` ([`no_follow`]);
//!   a whole file is replaced by writing a new one beside it and renaming it over
//!   ([`replace`]), which replaces a link by a file and never writes through it;
//! - what the daemon reads back, recovers, moves or deletes must be a regular file owned by
//!   its user ([`own_regular_file`]); anything else is left alone and reported;
//! - modes do not follow the caller's umask: directories are created `0750`, files `0640`
//!   ([`DIR_MODE`], [`FILE_MODE`]), and the daemon sets its umask to `027` ([`restrict_umask`]);
//! - a data directory others can write into is refused at start, as ssh's `StrictModes` does
//!   ([`check_private_dir`]).

use std::fs::{File, Metadata, OpenOptions};
use std::io::Write;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// Mode of the directories bearingd creates: the group (e.g. a log reader) may list them.
pub const DIR_MODE: u32 = 0o750;
/// Mode of the files bearingd creates: the group may read them, nobody else.
pub const FILE_MODE: u32 = 0o640;
/// The daemon's umask: whatever it creates without a mode of its own (a library's file) is at
/// most `0750`/`0640` too.
pub const UMASK: u32 = 0o027;

/// Sets the process's umask to [`UMASK`] (for the daemon's commands, at their start).
pub fn restrict_umask() {
    #[allow(unsafe_code)]
    // SAFETY: umask(2) only replaces the process's file-mode creation mask; it cannot fail and
    // touches no memory of this program.
    unsafe {
        libc::umask(UMASK as libc::mode_t);
    }
}

/// The effective user id: who owns what this process creates.
pub fn effective_uid() -> u32 {
    #[allow(unsafe_code)]
    // SAFETY: geteuid(2) has no arguments, cannot fail and touches no memory of this program.
    unsafe {
        libc::geteuid()
    }
}

/// Creates `dir` and any missing parents with [`DIR_MODE`] (existing ones are left as they are).
pub fn create_dir_all(dir: &Path) -> std::io::Result<()> {
    std::fs::DirBuilder::new()
        .recursive(true)
        .mode(DIR_MODE)
        .create(dir)
}

/// `options` made to refuse a symbolic link as the last component (`ELOOP`) and to create with
/// [`FILE_MODE`].
pub fn no_follow(options: &mut OpenOptions) -> &mut OpenOptions {
    options.custom_flags(libc::O_NOFOLLOW).mode(FILE_MODE)
}

/// Creates `path`, which must not exist (not even as a link), for writing, with `mode`.
pub fn create_new_with_mode(path: &Path, mode: u32) -> std::io::Result<File> {
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .custom_flags(libc::O_NOFOLLOW)
        .mode(mode)
        .open(path)
}

/// Creates `path`, which must not exist (not even as a link), for writing, with [`FILE_MODE`].
pub fn create_new(path: &Path) -> std::io::Result<File> {
    create_new_with_mode(path, FILE_MODE)
}

/// Replaces `path` with a file holding `bytes`, atomically and durably: written to
/// `<path>.new` (a leftover of that name, link or file, is removed first, never followed),
/// fsynced, renamed over `path` (a link there is replaced, its target untouched), and the
/// directory fsynced. A crash leaves the old content or the new, never half a file.
pub fn replace(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut temporary = path.as_os_str().to_owned();
    temporary.push(".new");
    let temporary = PathBuf::from(temporary);
    let file = match create_new(&temporary) {
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            std::fs::remove_file(&temporary)?;
            create_new(&temporary)
        }
        other => other,
    };
    let write = |mut file: File| -> std::io::Result<()> {
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&temporary, path)
    };
    if let Err(e) = file.and_then(write) {
        let _ = std::fs::remove_file(&temporary);
        return Err(e);
    }
    sync_dir(parent_dir(path));
    Ok(())
}

/// `path`'s directory (`.` for a bare name).
pub fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Makes the names in `dir` durable (after a create or a rename); a directory that cannot be
/// opened for fsync is not fatal.
pub fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

/// Why a name bearingd would touch is not its own regular file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NotOwnFile {
    #[error("{path}: is {kind}, not a regular file; bearingd does not follow or touch it (remove it, or move it out of the directory)")]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error("{path}: belongs to uid {owner}, not to bearingd's uid {uid}; bearingd does not touch it (remove it, or move it out of the directory)")]
    Foreign { path: PathBuf, owner: u32, uid: u32 },
    #[error("{path}: cannot be looked at: {reason}")]
    Unreadable { path: PathBuf, reason: String },
}

impl NotOwnFile {
    /// The name that was refused.
    pub fn path(&self) -> &Path {
        match self {
            NotOwnFile::NotRegular { path, .. }
            | NotOwnFile::Foreign { path, .. }
            | NotOwnFile::Unreadable { path, .. } => path,
        }
    }
}

/// `path`'s own metadata (a link is not followed) if it is a regular file owned by this
/// process's user; else why not.
pub fn own_regular_file(path: &Path) -> Result<Metadata, NotOwnFile> {
    let meta = std::fs::symlink_metadata(path).map_err(|e| NotOwnFile::Unreadable {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    check_own_regular(path, meta)
}

/// [`own_regular_file`] for metadata already at hand (an open file's, a directory entry's).
pub fn check_own_regular(path: &Path, meta: Metadata) -> Result<Metadata, NotOwnFile> {
    let file_type = meta.file_type();
    if !file_type.is_file() {
        let kind = if file_type.is_symlink() {
            "a symbolic link"
        } else if file_type.is_dir() {
            "a directory"
        } else {
            "a special file (device, FIFO or socket)"
        };
        return Err(NotOwnFile::NotRegular {
            path: path.to_path_buf(),
            kind,
        });
    }
    let uid = effective_uid();
    if meta.uid() != uid {
        return Err(NotOwnFile::Foreign {
            path: path.to_path_buf(),
            owner: meta.uid(),
            uid,
        });
    }
    Ok(meta)
}

/// Opens `path` for reading only if it is this user's regular file (a link is refused by the
/// open itself, `O_NOFOLLOW`, and the open file is checked, so a swap in between is caught).
pub fn open_own_file(path: &Path) -> Result<File, NotOwnFile> {
    let unreadable = |e: std::io::Error| NotOwnFile::Unreadable {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let file = match OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
        .open(path)
    {
        Ok(file) => file,
        Err(e) if e.raw_os_error() == Some(libc::ELOOP) => {
            return Err(NotOwnFile::NotRegular {
                path: path.to_path_buf(),
                kind: "a symbolic link",
            })
        }
        Err(e) => return Err(unreadable(e)),
    };
    check_own_regular(path, file.metadata().map_err(unreadable)?)?;
    Ok(file)
}

/// Why a data directory is refused at start.
#[derive(Debug, thiserror::Error)]
pub enum UnsafeDir {
    #[error("{path}: mode {mode:04o} lets other users write in it (they could plant links where bearingd writes); fix: chmod o-w {path}")]
    WorldWritable { path: PathBuf, mode: u32 },
    #[error("{path}: owned by uid {owner}, not by bearingd's uid {uid} or root (its owner could plant links where bearingd writes); fix: chown {uid} {path}, or give bearingd a directory of its own")]
    Foreign { path: PathBuf, owner: u32, uid: u32 },
    #[error("{path}: cannot be looked at: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Refuses a data directory other users could write into (as ssh's `StrictModes`): `dir` must
/// be owned by this user or root and not writable by others; its parent must not be writable
/// by others either, unless sticky (`/tmp`: others cannot rename `dir` away there).
pub fn check_private_dir(dir: &Path) -> Result<(), UnsafeDir> {
    let stat = |path: &Path| {
        std::fs::metadata(path).map_err(|source| UnsafeDir::Io {
            path: path.to_path_buf(),
            source,
        })
    };
    let meta = stat(dir)?;
    let uid = effective_uid();
    if meta.uid() != uid && meta.uid() != 0 {
        return Err(UnsafeDir::Foreign {
            path: dir.to_path_buf(),
            owner: meta.uid(),
            uid,
        });
    }
    let writable_by_others = |meta: &Metadata| meta.permissions().mode() & 0o002 != 0;
    if writable_by_others(&meta) {
        return Err(UnsafeDir::WorldWritable {
            path: dir.to_path_buf(),
            mode: meta.permissions().mode() & 0o7777,
        });
    }
    let parent = match dir.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => Some(parent.to_path_buf()),
        _ => std::fs::canonicalize(dir)
            .ok()
            .and_then(|d| d.parent().map(Path::to_path_buf)),
    };
    if let Some(parent) = parent {
        let meta = stat(&parent)?;
        let sticky = meta.permissions().mode() & 0o1000 != 0;
        if writable_by_others(&meta) && !sticky {
            return Err(UnsafeDir::WorldWritable {
                path: parent,
                mode: meta.permissions().mode() & 0o7777,
            });
        }
    }
    Ok(())
}

/// Creates `dir` (with [`create_dir_all`]) and checks it with [`check_private_dir`]; the error
/// names the directory.
pub fn prepare_private_dir(dir: &Path) -> Result<(), UnsafeDir> {
    create_dir_all(dir).map_err(|source| UnsafeDir::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    check_private_dir(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("bearingd-fsafe-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn replace_puts_a_file_in_place_of_a_link_and_leaves_its_target_alone() {
        let dir = scratch("replace");
        let victim = dir.join("victim");
        std::fs::write(&victim, "victim").unwrap();
        std::os::unix::fs::symlink(&victim, dir.join("x.json")).unwrap();
        std::os::unix::fs::symlink(&victim, dir.join("x.json.new")).unwrap();
        replace(&dir.join("x.json"), b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "victim");
        assert_eq!(std::fs::read_to_string(dir.join("x.json")).unwrap(), "new");
        assert!(own_regular_file(&dir.join("x.json")).is_ok());
        assert!(!dir.join("x.json.new").exists());
        let mode = std::fs::metadata(dir.join("x.json"))
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, FILE_MODE & !current_umask());
    }

    #[test]
    fn a_link_is_not_an_own_regular_file_nor_opened() {
        let dir = scratch("link");
        std::fs::write(dir.join("file"), "x").unwrap();
        std::os::unix::fs::symlink(dir.join("file"), dir.join("link")).unwrap();
        assert!(own_regular_file(&dir.join("file")).is_ok());
        let err = own_regular_file(&dir.join("link")).unwrap_err();
        assert!(
            matches!(
                err,
                NotOwnFile::NotRegular {
                    kind: "a symbolic link",
                    ..
                }
            ),
            "{err}"
        );
        let err = open_own_file(&dir.join("link")).unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
        assert!(create_new(&dir.join("link")).is_err());
        assert!(own_regular_file(&dir).is_err());
    }

    #[test]
    fn a_world_writable_dir_is_refused_with_the_fix() {
        let dir = scratch("modes");
        let open = dir.join("open");
        create_dir_all(&open).unwrap();
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
        let err = check_private_dir(&open).unwrap_err().to_string();
        assert!(
            err.contains("0777") && err.contains(&format!("chmod o-w {}", open.display())),
            "{err}"
        );
        let inner = open.join("inner");
        create_dir_all(&inner).unwrap();
        assert!(check_private_dir(&inner)
            .unwrap_err()
            .to_string()
            .contains("chmod o-w"));
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o1777)).unwrap();
        check_private_dir(&inner).unwrap();
    }

    fn current_umask() -> u32 {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        status
            .lines()
            .find_map(|l| l.strip_prefix("Umask:"))
            .map_or(0o022, |m| u32::from_str_radix(m.trim(), 8).unwrap())
    }
}

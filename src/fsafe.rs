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
    #[error("iceoryx2 root {path}: is a symbolic link; bearingd does not follow it (someone may point it at a directory of theirs); fix: rm {path}")]
    Symlink { path: PathBuf },
    #[error("iceoryx2 root {path}: is not a directory; fix: rm {path} (after looking at what it is), or set outputs.iceoryx2_root")]
    NotDir { path: PathBuf },
    #[error("iceoryx2 root {path}: owned by uid {owner}, not by bearingd's uid {uid}; another user may have made it to read or forge alerts; fix: rm -r {path} as root, or set outputs.iceoryx2_root")]
    ForeignRoot { path: PathBuf, owner: u32, uid: u32 },
    #[error("iceoryx2 root {path}: mode {mode:04o} lets other users write in it (they may have planted services); fix: check `ls -lnR {path}`, then rm -r {path}")]
    TooOpen { path: PathBuf, mode: u32 },
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
    if writable_by_others(&meta) {
        return Err(UnsafeDir::WorldWritable {
            path: dir.to_path_buf(),
            mode: meta.permissions().mode() & 0o7777,
        });
    }
    match parent_of(dir) {
        Some(parent) => check_parent(&parent, &stat(&parent)?),
        None => Ok(()),
    }
}

fn writable_by_others(meta: &Metadata) -> bool {
    meta.permissions().mode() & 0o002 != 0
}

/// `dir`'s parent directory (through the current directory for a bare name).
fn parent_of(dir: &Path) -> Option<PathBuf> {
    match dir.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => Some(parent.to_path_buf()),
        _ => std::fs::canonicalize(dir)
            .ok()
            .and_then(|d| d.parent().map(Path::to_path_buf)),
    }
}

/// The parent rule: others must not be able to rename a directory away (and put their own in
/// its place), so its parent is not writable by others unless sticky (`/tmp`, `/dev/shm`).
fn check_parent(parent: &Path, meta: &Metadata) -> Result<(), UnsafeDir> {
    let sticky = meta.permissions().mode() & 0o1000 != 0;
    if writable_by_others(meta) && !sticky {
        return Err(UnsafeDir::WorldWritable {
            path: parent.to_path_buf(),
            mode: meta.permissions().mode() & 0o7777,
        });
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

/// Mode of the iceoryx2 root: iceoryx2 0.10 creates its files owner-only anyway, so nobody
/// else has any business in it (issue 32).
pub const PRIVATE_ROOT_MODE: u32 = 0o700;

/// What [`prepare_private_root`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RootPrepared {
    /// The root did not exist: made, [`PRIVATE_ROOT_MODE`].
    Created,
    /// Ours already, [`PRIVATE_ROOT_MODE`].
    Ready,
    /// Ours with group or other read bits (made by an earlier bearingd, or by iceoryx2 itself,
    /// `0750`): tightened to [`PRIVATE_ROOT_MODE`].
    Tightened { from: u32 },
}

/// Makes `root` the daemon's private iceoryx2 root, or says why it cannot be trusted (issue 32:
/// another user who creates a predictable root first could read or forge every alert).
///
/// Its parent (created `0750` if missing) must pass [`check_private_dir`]'s parent rule and
/// be owned by this user or root. `root` itself is created [`PRIVATE_ROOT_MODE`] when missing.
/// An existing one is refused when it is a link (never followed), not a directory, owned by
/// another user, or writable by group or others; this user's looser directory is tightened.
/// The checks are made again on the directory opened without following a link, so a swap in
/// between is caught.
pub fn prepare_private_root(root: &Path) -> Result<RootPrepared, UnsafeDir> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| UnsafeDir::Io { path, source }
    };
    let uid = effective_uid();
    if let Some(parent) = parent_of(root) {
        create_dir_all(&parent).map_err(io(&parent))?;
        let meta = std::fs::metadata(&parent).map_err(io(&parent))?;
        if meta.uid() != uid && meta.uid() != 0 {
            return Err(UnsafeDir::Foreign {
                path: parent,
                owner: meta.uid(),
                uid,
            });
        }
        check_parent(&parent, &meta)?;
    }
    let created = match std::fs::symlink_metadata(root) {
        Ok(meta) => {
            root_kind(root, &meta)?;
            false
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::DirBuilder::new()
                .mode(PRIVATE_ROOT_MODE)
                .create(root)
                .map_err(io(root))?;
            true
        }
        Err(e) => return Err(io(root)(e)),
    };
    let opened = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_DIRECTORY | libc::O_NOFOLLOW)
        .open(root)
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ELOOP) => UnsafeDir::Symlink {
                path: root.to_path_buf(),
            },
            Some(libc::ENOTDIR) => UnsafeDir::NotDir {
                path: root.to_path_buf(),
            },
            _ => io(root)(e),
        })?;
    let meta = opened.metadata().map_err(io(root))?;
    check_root_owner_and_mode(root, &meta, uid)?;
    let mode = meta.permissions().mode() & 0o7777;
    if mode == PRIVATE_ROOT_MODE {
        return Ok(if created {
            RootPrepared::Created
        } else {
            RootPrepared::Ready
        });
    }
    opened
        .set_permissions(std::fs::Permissions::from_mode(PRIVATE_ROOT_MODE))
        .map_err(io(root))?;
    Ok(RootPrepared::Tightened { from: mode })
}

/// Checks, without changing anything, that `root` is a directory (not a link) owned by `uid`
/// and not writable by group or others: what a subscriber expects of the daemon's root.
pub fn check_private_root(root: &Path, uid: u32) -> Result<(), UnsafeDir> {
    let meta = std::fs::symlink_metadata(root).map_err(|source| UnsafeDir::Io {
        path: root.to_path_buf(),
        source,
    })?;
    root_kind(root, &meta)?;
    check_root_owner_and_mode(root, &meta, uid)
}

/// A link or a non-directory at the root's path is refused.
fn root_kind(root: &Path, meta: &Metadata) -> Result<(), UnsafeDir> {
    let path = root.to_path_buf();
    if meta.file_type().is_symlink() {
        Err(UnsafeDir::Symlink { path })
    } else if !meta.is_dir() {
        Err(UnsafeDir::NotDir { path })
    } else {
        Ok(())
    }
}

/// The root must be `uid`'s and not writable by group or others.
fn check_root_owner_and_mode(root: &Path, meta: &Metadata, uid: u32) -> Result<(), UnsafeDir> {
    if meta.uid() != uid {
        return Err(UnsafeDir::ForeignRoot {
            path: root.to_path_buf(),
            owner: meta.uid(),
            uid,
        });
    }
    let mode = meta.permissions().mode() & 0o7777;
    if mode & 0o022 != 0 {
        return Err(UnsafeDir::TooOpen {
            path: root.to_path_buf(),
            mode,
        });
    }
    Ok(())
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

    #[test]
    fn a_private_root_is_made_0700_and_an_own_looser_one_tightened() {
        let dir = scratch("root");
        let root = dir.join("iox");
        assert_eq!(prepare_private_root(&root).unwrap(), RootPrepared::Created);
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o7777;
        assert_eq!(mode(&root), 0o700);
        assert_eq!(prepare_private_root(&root).unwrap(), RootPrepared::Ready);
        std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o750)).unwrap();
        assert_eq!(
            prepare_private_root(&root).unwrap(),
            RootPrepared::Tightened { from: 0o750 }
        );
        assert_eq!(mode(&root), 0o700);
        check_private_root(&root, effective_uid()).unwrap();
        assert!(check_private_root(&root, effective_uid() + 1).is_err());
    }

    #[test]
    fn a_root_that_is_a_link_a_file_or_open_to_others_is_refused_with_the_fix() {
        let dir = scratch("badroot");
        let victim = dir.join("victim");
        create_dir_all(&victim).unwrap();
        let link = dir.join("link");
        std::os::unix::fs::symlink(&victim, &link).unwrap();
        let err = prepare_private_root(&link).unwrap_err();
        assert!(matches!(err, UnsafeDir::Symlink { .. }), "{err}");
        assert!(err.to_string().contains(&format!("rm {}", link.display())));
        assert_eq!(std::fs::read_dir(&victim).unwrap().count(), 0);
        let file = dir.join("file");
        std::fs::write(&file, "x").unwrap();
        let err = prepare_private_root(&file).unwrap_err();
        assert!(matches!(err, UnsafeDir::NotDir { .. }), "{err}");
        let open = dir.join("open");
        create_dir_all(&open).unwrap();
        for bad in [0o777, 0o770] {
            std::fs::set_permissions(&open, std::fs::Permissions::from_mode(bad)).unwrap();
            let err = prepare_private_root(&open).unwrap_err();
            assert!(
                matches!(err, UnsafeDir::TooOpen { mode, .. } if mode == bad),
                "{err}"
            );
            assert!(err.to_string().contains("rm -r"), "{err}");
            assert!(check_private_root(&open, effective_uid()).is_err());
        }
    }

    #[test]
    fn a_root_below_a_parent_others_can_write_is_refused() {
        let dir = scratch("rootparent");
        let parent = dir.join("parent");
        create_dir_all(&parent).unwrap();
        std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o777)).unwrap();
        let err = prepare_private_root(&parent.join("iox")).unwrap_err();
        assert!(matches!(err, UnsafeDir::WorldWritable { .. }), "{err}");
        assert!(!parent.join("iox").exists());
        std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o1777)).unwrap();
        prepare_private_root(&parent.join("iox")).unwrap();
    }

    #[test]
    fn a_root_of_another_user_is_refused_with_the_fix() {
        if effective_uid() != 0 {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "this test needs root to give a directory to another uid"
            );
            eprintln!("skipped: not root, cannot chown a directory to another uid");
            return;
        }
        let dir = scratch("foreignroot");
        let root = dir.join("iox");
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&root)
            .unwrap();
        std::os::unix::fs::chown(&root, Some(61032), Some(61032)).unwrap();
        let err = prepare_private_root(&root).unwrap_err();
        assert!(
            matches!(err, UnsafeDir::ForeignRoot { owner: 61032, .. }),
            "{err}"
        );
        assert!(err.to_string().contains("outputs.iceoryx2_root"), "{err}");
    }

    fn current_umask() -> u32 {
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        status
            .lines()
            .find_map(|l| l.strip_prefix("Umask:"))
            .map_or(0o022, |m| u32::from_str_radix(m.trim(), 8).unwrap())
    }
}

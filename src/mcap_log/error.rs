//! One error type for the log: every variant names the file and, where it applies, the byte
//! offset in it, so that a message in the daemon's journal points at the exact place.

use std::path::PathBuf;

/// Errors of the MCAP log (writing, reading, recovery).
#[derive(Debug, thiserror::Error)]
pub enum McapLogError {
    /// An operating-system call on a file or directory failed.
    #[error("{path}: {op}: {source}")]
    Io {
        path: PathBuf,
        op: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The `mcap` crate refused a write (or the writer failed earlier and stays failed).
    #[error("{path}: MCAP write: {source}")]
    Write {
        path: PathBuf,
        #[source]
        source: mcap::McapError,
    },
    /// A message could not be decoded into its pipeline type.
    #[error("{path}: message at byte {offset} on {topic}: {reason}")]
    Decode {
        path: PathBuf,
        offset: u64,
        topic: String,
        reason: String,
    },
    /// The file is not a readable MCAP from its first bytes (nothing at all could be read).
    #[error("{path}: at byte {offset}: {reason}")]
    Corrupt {
        path: PathBuf,
        offset: u64,
        reason: String,
    },
    /// A log-named entry is not this user's regular file (a link, a directory, another user's
    /// file): it is not read, rewritten or deleted.
    #[error(transparent)]
    NotOwnFile(#[from] crate::fsafe::NotOwnFile),
    /// A logger setting is unusable.
    #[error("MCAP logger config: {0}")]
    Config(String),
}

/// Result alias of the log module.
pub type Result<T, E = McapLogError> = std::result::Result<T, E>;

pub(crate) fn io_err(
    path: impl Into<PathBuf>,
    op: &'static str,
) -> impl FnOnce(std::io::Error) -> McapLogError {
    let path = path.into();
    move |source| McapLogError::Io { path, op, source }
}

//! What the daemon keeps across restarts in `outputs.state_dir`: the health baselines of every
//! channel (`baselines.json`), so that a restart does not send the bearings back to learning.
//!
//! Saved every `outputs.state_save_interval_s` while running and at every stop, each time
//! atomically (write a temporary file, fsync it, rename it over the old one, fsync the
//! directory): a `kill -9` or a power cut finds either the previous save or the new one, never
//! half a file, and loses at most one period of learning. The save never writes through a
//! link planted in the directory ([`crate::fsafe::replace`]), and a `baselines.json` that is
//! not this user's regular file is not read.

use crate::analysis::health::{baselines_from_json, baselines_to_json, Baseline};
use crate::messages::ChannelId;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

const BASELINES_FILE: &str = "baselines.json";

/// Why the baselines file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error("{path}: unreadable ({detail})")]
    Unreadable { path: PathBuf, detail: String },
    #[error("{path}: cannot save the health baselines: {source}")]
    NotSaved {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What was loaded at start, for the operator: which file, how many channels, saved when.
#[derive(Debug, Clone)]
pub struct StateLoaded {
    pub path: PathBuf,
    pub channels: usize,
    /// The file's modification time, ns since the epoch (0 when unknown).
    pub saved_at_ns: u64,
}

/// The baselines kept in `state_dir`: none when there is no file yet; an error (and none) when
/// the file cannot be read, so the caller can say that the baselines are learned again.
pub fn load_baselines(
    state_dir: &Path,
) -> (
    BTreeMap<ChannelId, Baseline>,
    Result<Option<StateLoaded>, StateError>,
) {
    let path = state_dir.join(BASELINES_FILE);
    if std::fs::symlink_metadata(&path).is_err() {
        return (BTreeMap::new(), Ok(None));
    }
    let mut text = String::new();
    let read = crate::fsafe::open_own_file(&path)
        .map_err(|e| e.to_string())
        .and_then(|mut file| file.read_to_string(&mut text).map_err(|e| e.to_string()));
    if let Err(detail) = read {
        return (
            BTreeMap::new(),
            Err(StateError::Unreadable { path, detail }),
        );
    }
    let saved_at_ns = std::fs::metadata(&path)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    match baselines_from_json(&text) {
        Ok(baselines) => {
            let loaded = StateLoaded {
                path,
                channels: baselines.len(),
                saved_at_ns,
            };
            (baselines, Ok(Some(loaded)))
        }
        Err(e) => (
            BTreeMap::new(),
            Err(StateError::Unreadable {
                path,
                detail: e.to_string(),
            }),
        ),
    }
}

/// Writes the baselines to `state_dir` atomically (see the module docs).
pub fn save_baselines(
    state_dir: &Path,
    baselines: &BTreeMap<ChannelId, Baseline>,
) -> Result<(), StateError> {
    let path = state_dir.join(BASELINES_FILE);
    let write = || -> std::io::Result<()> {
        let text = baselines_to_json(baselines).map_err(std::io::Error::other)?;
        crate::fsafe::replace(&path, text.as_bytes())
    };
    write().map_err(|source| StateError::NotSaved { path, source })
}

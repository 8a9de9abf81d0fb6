//! What the daemon keeps across restarts in `outputs.state_dir`: the health baselines of every
//! channel (`baselines.json`), so that a restart does not send the bearings back to learning.

use crate::analysis::health::Baseline;
use crate::messages::ChannelId;
use std::collections::BTreeMap;
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

/// The baselines kept in `state_dir`: none when there is no file yet; an error (and none) when
/// the file cannot be read, so the caller can say that the baselines are learned again.
pub fn load_baselines(state_dir: &Path) -> (BTreeMap<ChannelId, Baseline>, Option<StateError>) {
    let path = state_dir.join(BASELINES_FILE);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return (BTreeMap::new(), None);
    };
    match serde_json::from_str::<Vec<(ChannelId, Baseline)>>(&text) {
        Ok(list) => (list.into_iter().collect(), None),
        Err(e) => (
            BTreeMap::new(),
            Some(StateError::Unreadable {
                path,
                detail: e.to_string(),
            }),
        ),
    }
}

/// Writes the baselines to `state_dir` (a temporary file renamed over the old one, so a crash
/// never leaves half a file).
pub fn save_baselines(
    state_dir: &Path,
    baselines: &BTreeMap<ChannelId, Baseline>,
) -> Result<(), StateError> {
    let path = state_dir.join(BASELINES_FILE);
    let temporary = state_dir.join(format!("{BASELINES_FILE}.new"));
    let list: Vec<_> = baselines.iter().collect();
    serde_json::to_string_pretty(&list)
        .map_err(std::io::Error::other)
        .and_then(|text| std::fs::write(&temporary, text))
        .and_then(|_| std::fs::rename(&temporary, &path))
        .map_err(|source| StateError::NotSaved { path, source })
}

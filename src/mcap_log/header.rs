//! What a log file says about itself before its first message: the metadata records the
//! writer puts at the start of every file (names and keys below; what they mean:
//! `docs/MCAP.md`). Replay reads them to order files by run and sequence, to find run
//! boundaries, and to analyse with the settings the log was recorded with, not today's.
//!
//! Reading stops at the first message, so a header costs at most one chunk; a file without
//! these records (an older bearingd) gives an empty header, not an error.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::Result;
use super::scan::{ScannedRecord, Scanner};

/// The run's record: version, host, run id, log-time origin.
pub const RUN_RECORD: &str = "bearingd.run";
/// The resolved configuration, as JSON (`json`).
pub const CONFIG_RECORD: &str = "bearingd.config";
/// One per sensor axis: rate, unit, scale, bearing.
pub const CHANNEL_RECORD: &str = "bearingd.channel";
/// The file's place in its run (`sequence`, from 1).
pub const FILE_RECORD: &str = "bearingd.file";
/// The learned state the run started with (`baselines_json`: the health baselines the daemon
/// loaded from `baselines.json`), so that a replay starts each run from the same state.
pub const STATE_RECORD: &str = "bearingd.state";
/// A log made by `bearingd import`: the recording it came from (`source`) and where its date
/// came from (`time_source`).
pub const IMPORT_RECORD: &str = "bearingd.import";

/// What one file's metadata records say (each `None` when absent or unparsable).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LogHeader {
    pub path: PathBuf,
    /// The file's size in bytes.
    pub bytes: u64,
    /// The run's id: the same in every file of one run of the daemon, another after a restart.
    pub run_id: Option<u64>,
    /// Wall-clock time of sample 0, ns since the Unix epoch.
    pub origin_ns: Option<u64>,
    /// 1 for a run's first file, then one more per rotation.
    pub sequence: Option<u64>,
    /// The resolved configuration the run used, as JSON.
    pub config_json: Option<String>,
    /// The bearingd version that wrote it.
    pub version: Option<String>,
    /// The health baselines the run started with, as JSON (`bearingd.state`).
    pub start_baselines_json: Option<String>,
    /// At least one message could be read (reading stops at the first).
    pub holds_a_message: bool,
    /// Where and why reading stopped, or first skipped something, before the first message.
    pub problem: Option<(u64, String)>,
}

impl LogHeader {
    /// Why not one message could be read, when reading stopped on a defect before the first
    /// ([`super::reader::no_message_reason`]); `None` for a file with messages or a complete
    /// log that holds none.
    pub fn no_message_reason(&self) -> Option<String> {
        self.problem
            .as_ref()
            .filter(|_| !self.holds_a_message)
            .map(super::reader::no_message_reason)
    }

    /// Does the file carry the run's metadata (run id and config)?
    pub fn is_self_describing(&self) -> bool {
        self.run_id.is_some() && self.config_json.is_some()
    }
}

/// Reads the metadata records of `path` up to its first message.
pub fn read_header(path: &Path) -> Result<LogHeader> {
    let mut scanner = Scanner::open(path)?;
    let mut header = LogHeader {
        path: path.to_path_buf(),
        bytes: scanner.file_len(),
        ..LogHeader::default()
    };
    while let Some(record) = scanner.next_record()? {
        match record {
            ScannedRecord::Metadata { name, metadata } => header.take(&name, &metadata),
            ScannedRecord::Message { .. } => {
                header.holds_a_message = true;
                break;
            }
            ScannedRecord::Schema { .. } | ScannedRecord::Channel { .. } => {}
        }
    }
    header.problem = scanner.outcome().first_problem.clone();
    Ok(header)
}

impl LogHeader {
    fn take(&mut self, name: &str, pairs: &BTreeMap<String, String>) {
        let number = |key: &str| pairs.get(key).and_then(|v| v.parse::<u64>().ok());
        match name {
            RUN_RECORD => {
                self.run_id = number("run_id");
                self.origin_ns = number("log_time_origin_ns");
                self.version = pairs.get("version").cloned();
            }
            CONFIG_RECORD => self.config_json = pairs.get("json").cloned(),
            FILE_RECORD => self.sequence = number("sequence"),
            STATE_RECORD => self.start_baselines_json = pairs.get("baselines_json").cloned(),
            _ => {}
        }
    }
}

//! The MCAP log: every raw block and every result the pipeline emits, in files that standard
//! tools read (Python `mcap` with its protobuf and JSON decoders, Foxglove / Lichtblick) and
//! that `bearingd replay` feeds back through the same pipeline.
//!
//! Why it is built this way (topics, schemas, time fields, rotation, retention, recovery and
//! how to read the files: `docs/MCAP.md`):
//!
//! - raw samples are the ground truth of a replay, so they are stored losslessly: the sensor's
//!   integer counts plus the scale, as protobuf (`schema.rs`); results are low-rate JSON.
//! - a crash must lose at most the open chunk and leave a file that can be made whole again:
//!   the writer is chunked and flushed by the daemon (`writer.rs`), start-up recovery rewrites
//!   unfinished files from their complete chunks (`recover.rs`).
//! - replay must read whatever survived, never panic, and say what it could not read: one
//!   bounded scanner (`scan.rs`) under both the reader (`reader.rs`) and the recovery.
//! - no clock inside: the caller passes every timestamp, so tests and replays are
//!   deterministic (one named helper, [`wall_clock_now_ns`], is for the daemon's edge).

mod error;
pub mod reader;
pub mod recover;
pub mod scan;
pub mod schema;
pub mod writer;

pub use error::{McapLogError, Result};
pub use reader::{
    read_messages, read_raw_blocks, FileReadReport, LogReader, LoggedMessage, RawBlocks,
    ReadSummary,
};
pub use recover::{is_finished, recover_directory, recover_file, RecoveryReport};
pub use scan::ScanOutcome;
pub use writer::{
    enforce_budget, file_name, wall_clock_now_ns, LogStats, LoggerConfig, McapLogger,
    RetentionReport, TopicStats,
};

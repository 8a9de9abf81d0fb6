//! The MCAP log's format: topics, schemas, file names, and reading the files back. The writer
//! that makes them is a sink ([`crate::sinks::mcap`]); the replay that feeds them through the
//! pipeline again is a source ([`crate::sources::replay`]); both stand on this room, and so can
//! any later reader of recordings (`analyze` of a log), without an arrow back up.
//!
//! Why it is built this way (topics, schemas, time fields, rotation, retention, recovery and
//! how to read the files: `docs/MCAP.md`):
//!
//! - raw samples are the ground truth of a replay, so they are stored losslessly: the sensor's
//!   integer counts plus the scale, as protobuf (`schema.rs`); results are low-rate JSON. The
//!   encoding of every message and its decoding live side by side (`schema.rs`, `reader.rs`).
//! - replay must read whatever survived, never panic, and say what it could not read: one
//!   bounded scanner (`scan.rs`) under both the reader (`reader.rs`) and the sink's start-up
//!   recovery. No declared length is allocated before it is known to fit in the file and in
//!   its record (`bounds.rs`, used by every reader: a hostile file must not abort the daemon).
//! - no clock inside: the caller passes every timestamp, so tests and replays are
//!   deterministic.
//! - a file that replaces another (recovery) must first pass a strict read by the `mcap`
//!   crate's own reader (`verify.rs`), independent of the scanner that produced it.

pub mod bounds;
pub(crate) mod error;
pub mod files;
pub mod header;
pub mod reader;
pub mod scan;
pub mod schema;
pub mod verify;

pub use error::{McapLogError, Result};
pub use files::{file_name, is_log_file_name};
pub use header::{read_header, LogHeader};
pub use reader::{
    no_message_reason, read_messages, read_raw_blocks, FileReadReport, LogReader, LoggedMessage,
    RawBlocks, ReadSummary,
};
pub use scan::ScanOutcome;
pub use verify::{read_back_strictly, StrictRead};

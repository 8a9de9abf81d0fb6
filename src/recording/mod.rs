//! Readers for recorded vibration data: the readers of the data sets' formats (MATLAB, CSV,
//! IMS, WAV) live in the `bearing-signal` crate, shared with the sensor simulator; this module
//! re-exports them and adds the reader of bearingd's own MCAP logs ([`mcap`]), whose format is
//! the daemon's, so that `analyze`, `trend` and `import` read a log as any other recording.

mod mcap;

pub use mcap::{LogPlacement, LoggedHwFit, Segment};

pub use bearing_signal::recording::{
    detect_format, ixml_track_names, time_from_name, LogReader, NamedTime, NamedTimeKind,
    ReadOptions, Recording, RecordingError, RecordingFormat, SampleUnit, StatedUnit, MCAP_MAGIC,
    PRONOSTIA_PERIOD_S,
};

use std::cell::RefCell;
use std::path::Path;

/// Reads bearingd's MCAP logs as recordings (one channel of raw samples, the stated speed).
pub struct McapLogs;

impl LogReader for McapLogs {
    fn read(&self, path: &Path, selector: Option<&str>) -> Result<Recording, RecordingError> {
        mcap::read(path, selector)
    }
    fn channels(&self, path: &Path) -> Result<Vec<String>, RecordingError> {
        mcap::channels(path)
    }
}

/// Reads one channel of a recording, bearingd's MCAP logs included.
pub fn read_recording(path: &Path, options: &ReadOptions) -> Result<Recording, RecordingError> {
    bearing_signal::recording::read_recording_with(path, options, &McapLogs)
}

/// The channels a file offers, bearingd's MCAP logs included.
pub fn list_channels(path: &Path) -> Result<Vec<String>, RecordingError> {
    bearing_signal::recording::list_channels_with(path, &McapLogs)
}

/// [`read_recording`], and for a bearingd log what places its samples in time (its anchor,
/// its runs of contiguous samples, the HW fits the daemon logged); `None` for other formats.
pub fn read_recording_placed(
    path: &Path,
    options: &ReadOptions,
) -> Result<(Recording, Option<LogPlacement>), RecordingError> {
    /// Keeps the placement of the log it read.
    struct Placing(RefCell<Option<LogPlacement>>);
    impl LogReader for Placing {
        fn read(&self, path: &Path, selector: Option<&str>) -> Result<Recording, RecordingError> {
            let (recording, placement) = mcap::read_log(path, selector)?;
            *self.0.borrow_mut() = Some(placement);
            Ok(recording)
        }
        fn channels(&self, path: &Path) -> Result<Vec<String>, RecordingError> {
            mcap::channels(path)
        }
    }
    let logs = Placing(RefCell::new(None));
    let recording = bearing_signal::recording::read_recording_with(path, options, &logs)?;
    Ok((recording, logs.0.into_inner()))
}

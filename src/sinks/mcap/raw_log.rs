//! A recording written as a raw MCAP log that describes itself as the daemon's logs do: the
//! settings to replay it with, the bearing, the rate, the speed and a date. `bearingd import`,
//! `bearingd dataset` and `bearingd evaluate --recordings` all write through here, so that a
//! recording reaches the daemon's pipeline the same way whoever converts it.

use crate::bearing::BearingGeometry;
use crate::config::ConfigError;
use crate::mcap_log::header::IMPORT_RECORD;
use crate::mcap_log::McapLogError;
use crate::messages::{ChannelId, PipelineMessage, RawBlock, SpeedMessage, SpeedSource};
use crate::recording::{time_from_name, NamedTimeKind};
use crate::sinks::mcap::metadata::{run_records, MetadataRecord};
use crate::sinks::mcap::{LoggerConfig, McapLogger};
use std::path::{Path, PathBuf};

/// Counts of full scale: the largest sample maps to this, leaving headroom below i16::MAX.
const FULL_SCALE_COUNTS: f64 = 30_000.0;
/// Seconds of signal per raw block.
const BLOCK_S: f64 = 0.1;

/// The samples of a raw log, what they were taken under, and where the log goes.
#[derive(Debug, Clone, Copy)]
pub struct LogSignal<'a> {
    /// The directory of the log and its `replay.toml`.
    pub out: &'a Path,
    pub sensor: &'a str,
    pub samples: &'a [f64],
    pub fs_hz: f64,
    pub rpm: f64,
    pub bearing: &'a BearingGeometry,
}

/// A recording to write as a raw log.
pub struct RawLog<'a> {
    pub signal: LogSignal<'a>,
    /// Wall-clock time of sample 0, ns since the epoch.
    pub origin_ns: u64,
    /// A metadata record saying where the recording came from.
    pub about: MetadataRecord,
    /// The recording, for the settings file's first line.
    pub what: &'a str,
}

/// What [`write_raw_log`] wrote.
#[derive(Debug, Clone)]
pub struct WrittenLog {
    /// The last file of the log (a long recording may rotate into several).
    pub path: Option<PathBuf>,
    pub config_path: PathBuf,
    pub scale: f64,
}

/// Why a raw log could not be written.
#[derive(Debug, thiserror::Error)]
pub enum RawLogError {
    #[error("the settings of the log are refused: {0}")]
    Settings(#[source] ConfigError),
    #[error("{0}")]
    Open(#[source] McapLogError),
    #[error("{0}")]
    Write(#[source] McapLogError),
    #[error("{path}: cannot write: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Writes `log` into `log.out` as a raw MCAP log that describes itself as the daemon's logs do
/// (the settings to replay it with, short band period and delays since recordings are short),
/// plus the same settings as `replay.toml`.
pub fn write_raw_log(log: &RawLog) -> Result<WrittenLog, RawLogError> {
    let signal = &log.signal;
    let (fs, rpm, b) = (signal.fs_hz, signal.rpm, signal.bearing);
    let bearing_spec = b.spec();
    let peak = signal.samples.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = if peak > 0.0 {
        peak / FULL_SCALE_COUNTS
    } else {
        1e-6
    };
    let channel = ChannelId {
        sensor: signal.sensor.to_string(),
        axis: "radial".into(),
    };
    let config_text = format!(
        "# Replays {what}: bearingd replay {out}/*.mcap (the log carries these settings; give \
         --config {out}/replay.toml after editing it)\n\
         [[sensors]]\nid = \"{sensor}\"\ntransport = \"shm\"\nsample_rate_hz = {fs}\nscale_g_per_count = {scale:e}\naxes = [\"radial\"]\nbearing = \"{bearing_spec}\"\n\
         [sensors.speed]\nsource = \"fixed\"\nrpm = {rpm}\n\n\
         # A recording is one piece of evidence: the verdict rests on all of it so far (up to\n\
         # 600 s), as `bearingd analyze`'s does on the whole, and is decided again every 3 s\n\
         # and at its end; flags rise and fall on 1 s of evidence.\n\
         [analysis]\nband_period_s = 3.0\nevidence_horizon_s = {horizon}\n\n[thresholds]\non_delay_s = 1.0\noff_delay_s = 1.0\nbaseline_windows = 5\n\n\
         [outputs]\nstate_dir = \"{out}/state\"\nmcap_dir = \"{out}/replay\"\n",
        what = log.what,
        horizon = evidence_horizon_s(signal.samples.len(), fs),
        out = signal.out.display(),
        sensor = signal.sensor,
    );
    let config_path = signal.out.join("replay.toml");
    let config = crate::config::parse(&config_text, &config_path.display().to_string())
        .map_err(RawLogError::Settings)?;
    let mut metadata = run_records(&config, log.origin_ns, log.origin_ns, &Default::default());
    metadata.push(log.about.clone());
    let logger_config = LoggerConfig {
        metadata,
        ..LoggerConfig::new(signal.out)
    };
    let mut logger = McapLogger::create(logger_config, log.origin_ns).map_err(RawLogError::Open)?;
    // The speed the record was taken at, stated in the log itself, so that `analyze` reads it
    // from there (a replay scores with the config's fixed speed and passes this one over).
    let speed = PipelineMessage::Speed(SpeedMessage {
        channel: channel.clone(),
        end_sample: 0,
        source: SpeedSource::Fixed,
        given_rpm: Some(rpm),
        rpm: Some(rpm),
    });
    logger
        .log(&speed, log.origin_ns, log.origin_ns)
        .map_err(RawLogError::Write)?;
    let block = ((fs * BLOCK_S).round() as usize).max(1);
    for (i, chunk) in signal.samples.chunks(block).enumerate() {
        let first_sample = (i * block) as u64;
        let message = PipelineMessage::Raw(RawBlock {
            channel: channel.clone(),
            first_sample,
            sample_rate_hz: fs,
            scale_g_per_count: scale,
            counts: chunk.iter().map(|x| (x / scale).round() as i32).collect(),
        });
        let time = log.origin_ns + (first_sample as f64 / fs * 1e9) as u64;
        logger
            .log(&message, time, time)
            .map_err(RawLogError::Write)?;
    }
    let path = logger.current_path().map(|p| p.to_path_buf());
    logger.finish().map_err(RawLogError::Write)?;
    // Replaced, not written through: a link named replay.toml is not followed.
    crate::fsafe::replace(&config_path, config_text.as_bytes()).map_err(|source| {
        RawLogError::Io {
            path: config_path.clone(),
            source,
        }
    })?;
    Ok(WrittenLog {
        path,
        config_path,
        scale,
    })
}

/// A recording file to import: what `bearingd import FILE` writes, given the file's samples
/// and the conditions resolved for them.
pub struct Import<'a> {
    pub file: &'a Path,
    pub signal: LogSignal<'a>,
}

/// What [`import_recording`] wrote, and the date it gave the log.
#[derive(Debug, Clone)]
pub struct Imported {
    pub written: WrittenLog,
    pub origin_ns: u64,
    /// Where that date came from.
    pub time_source: &'static str,
}

/// Writes a recording file as a raw log dated by [`recording_date`], with a
/// `bearingd.import` record naming the file and where its date came from.
pub fn import_recording(import: &Import) -> Result<Imported, RawLogError> {
    let (origin_ns, time_source) = recording_date(import.file);
    let written = write_raw_log(&RawLog {
        signal: import.signal,
        origin_ns,
        about: (
            IMPORT_RECORD.to_string(),
            [
                ("source".to_string(), import.file.display().to_string()),
                ("time_source".to_string(), time_source.to_string()),
            ]
            .into(),
        ),
        what: &format!("{} (bearingd import)", import.file.display()),
    })?;
    Ok(Imported {
        written,
        origin_ns,
        time_source,
    })
}

/// When the recording began, ns since the Unix epoch, and where that came from: the date an IMS
/// file's name states, else the file's modification time (the best a .mat or CSV file says),
/// else the epoch.
pub fn recording_date(file: &Path) -> (u64, &'static str) {
    if let Some(named) = time_from_name(file).filter(|t| t.kind == NamedTimeKind::ImsDate) {
        return (
            (named.seconds.max(0.0) * 1e9) as u64,
            "file name (IMS date)",
        );
    }
    let modified = std::fs::metadata(file)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok());
    match modified {
        Some(since_epoch) => (since_epoch.as_nanos() as u64, "file modification time"),
        None => (
            0,
            "nothing (no date in the name, no modification time): the Unix epoch",
        ),
    }
}

/// The evidence horizon a recording is replayed with: its whole length, so that its last
/// verdict rests on all of it (up to the longest horizon the config allows); written with
/// enough digits to hold every sample.
fn evidence_horizon_s(samples: usize, fs_hz: f64) -> String {
    let seconds = (samples as f64 / fs_hz).clamp(1e-3, MAX_HORIZON_S);
    format!("{:.6}", (seconds * 1e6).ceil() / 1e6)
}

/// The longest evidence horizon `[analysis] evidence_horizon_s` accepts.
const MAX_HORIZON_S: f64 = 600.0;

//! `bearingd import FILE --out DIR`: a recording (.mat, .csv, WAV) as a raw MCAP log that
//! describes itself as the daemon's logs do (the settings to replay it with, the bearing, the
//! rate, and a real date: an IMS file's name, else the file's modification time), so that
//! recorded data goes through the daemon's pipeline with `bearingd replay DIR/*.mcap`. The
//! same settings are also written as `DIR/replay.toml`, a starting point for `--config`.

use super::{CliError, RecordingArgs};
use crate::bearing::BearingGeometry;
use crate::mcap_log::header::IMPORT_RECORD;
use crate::messages::{ChannelId, PipelineMessage, RawBlock, SpeedMessage, SpeedSource};
use crate::offline::{resolve_conditions, AnalyzeRequest};
use crate::recording::{read_recording, time_from_name, NamedTimeKind};
use crate::sinks::mcap::metadata::{run_records, MetadataRecord};
use crate::sinks::mcap::{LoggerConfig, McapLogger};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ImportArgs {
    /// The recording: CWRU .mat, PRONOSTIA/IMS/plain CSV, WAV.
    file: PathBuf,
    /// Directory for the MCAP log and replay.toml.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    recording: RecordingArgs,
    /// Sensor id in the log.
    #[arg(long, default_value = "imported")]
    sensor: String,
}

/// Counts of full scale: the largest sample maps to this, leaving headroom below i16::MAX.
const FULL_SCALE_COUNTS: f64 = 30_000.0;
/// Seconds of signal per raw block.
const BLOCK_S: f64 = 0.1;

pub fn run(args: &ImportArgs) -> Result<(), CliError> {
    let recording =
        read_recording(&args.file, &args.recording.read_options()).map_err(CliError::input)?;
    let request = AnalyzeRequest {
        fs_hz: args.recording.fs,
        rpm: args.recording.rpm,
        bearing: args.recording.bearing.clone(),
        ..Default::default()
    };
    let conditions = resolve_conditions(&recording, &request, false).map_err(CliError::input)?;
    for warning in &conditions.warnings {
        eprintln!("bearingd: import: {warning}");
    }
    let fs = conditions.fs_hz;
    let (origin_ns, time_source) = recording_date(&args.file);
    let written = write_raw_log(&RawLog {
        out: &args.out,
        sensor: &args.sensor,
        samples: &recording.samples,
        fs_hz: fs,
        rpm: conditions.rpm,
        bearing: &conditions.bearing,
        origin_ns,
        about: (
            IMPORT_RECORD.to_string(),
            [
                ("source".to_string(), args.file.display().to_string()),
                ("time_source".to_string(), time_source.to_string()),
            ]
            .into(),
        ),
        what: &format!("{} (bearingd import)", args.file.display()),
    })?;
    let path = written
        .path
        .as_ref()
        .map_or("?".into(), |p| p.display().to_string());
    println!(
        "imported {} samples ({:.2} s at {fs} Hz, {:.3e} g per count, dated {} from the {time_source}) into {path}; replay with: bearingd replay {path} (its settings are also in {})",
        recording.samples.len(),
        recording.samples.len() as f64 / fs,
        written.scale,
        crate::mcap_log::files::utc_text(origin_ns),
        written.config_path.display()
    );
    Ok(())
}

/// A recording to write as a raw log.
pub(super) struct RawLog<'a> {
    pub out: &'a Path,
    pub sensor: &'a str,
    pub samples: &'a [f64],
    pub fs_hz: f64,
    pub rpm: f64,
    pub bearing: &'a BearingGeometry,
    /// Wall-clock time of sample 0, ns since the epoch.
    pub origin_ns: u64,
    /// A metadata record saying where the recording came from.
    pub about: MetadataRecord,
    /// The recording, for the settings file's first line.
    pub what: &'a str,
}

/// What [`write_raw_log`] wrote.
pub(super) struct WrittenLog {
    pub path: Option<PathBuf>,
    pub config_path: PathBuf,
    pub scale: f64,
}

/// Writes `log` into `log.out` as a raw MCAP log that describes itself as the daemon's logs do
/// (the settings to replay it with, short band period and delays since recordings are short),
/// plus the same settings as `replay.toml`.
pub(super) fn write_raw_log(log: &RawLog) -> Result<WrittenLog, CliError> {
    let (fs, rpm, b) = (log.fs_hz, log.rpm, log.bearing);
    let bearing_spec = b.spec();
    let peak = log.samples.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = if peak > 0.0 {
        peak / FULL_SCALE_COUNTS
    } else {
        1e-6
    };
    let channel = ChannelId {
        sensor: log.sensor.to_string(),
        axis: "radial".into(),
    };
    let config_text = format!(
        "# Replays {what}: bearingd replay {out}/*.mcap (the log carries these settings; give \
         --config {out}/replay.toml after editing it)\n\
         [[sensors]]\nid = \"{sensor}\"\ntransport = \"shm\"\nsample_rate_hz = {fs}\nscale_g_per_count = {scale:e}\naxes = [\"radial\"]\nbearing = \"{bearing_spec}\"\n\
         [sensors.speed]\nsource = \"fixed\"\nrpm = {rpm}\n\n\
         # A recording is one piece of evidence: the verdict rests on all of it (up to 600 s), as\n\
         # `bearingd analyze`'s does, decided at its end; flags rise on 1 s of evidence.\n\
         [analysis]\nband_period_s = {horizon}\nevidence_horizon_s = {horizon}\n\n[thresholds]\non_delay_s = 1.0\noff_delay_s = 5.0\nbaseline_windows = 5\n\n\
         [outputs]\nstate_dir = \"{out}/state\"\nmcap_dir = \"{out}/replay\"\n",
        what = log.what,
        horizon = evidence_horizon_s(log.samples.len(), fs),
        out = log.out.display(),
        sensor = log.sensor,
    );
    let config_path = log.out.join("replay.toml");
    let config = crate::config::parse(&config_text, &config_path.display().to_string())
        .map_err(|e| CliError::input(format!("the settings of the log are refused: {e}")))?;
    let mut metadata = run_records(&config, log.origin_ns, log.origin_ns, &Default::default());
    metadata.push(log.about.clone());
    let logger_config = LoggerConfig {
        metadata,
        ..LoggerConfig::new(log.out)
    };
    let mut logger = McapLogger::create(logger_config, log.origin_ns).map_err(CliError::input)?;
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
        .map_err(CliError::failure)?;
    let block = ((fs * BLOCK_S).round() as usize).max(1);
    for (i, chunk) in log.samples.chunks(block).enumerate() {
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
            .map_err(CliError::failure)?;
    }
    let path = logger.current_path().map(|p| p.to_path_buf());
    logger.finish().map_err(CliError::failure)?;
    std::fs::write(&config_path, config_text)
        .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", config_path.display())))?;
    Ok(WrittenLog {
        path,
        config_path,
        scale,
    })
}

/// The evidence horizon (and band period) an imported recording is replayed with: its whole
/// length, so that its verdict is decided once, on all of it, up to the longest horizon the
/// config allows; written with enough digits to hold every sample.
fn evidence_horizon_s(samples: usize, fs_hz: f64) -> String {
    let seconds = (samples as f64 / fs_hz).clamp(1e-3, MAX_HORIZON_S);
    format!("{:.6}", (seconds * 1e6).ceil() / 1e6)
}

/// The longest evidence horizon `[analysis] evidence_horizon_s` accepts.
const MAX_HORIZON_S: f64 = 600.0;

/// When the recording began, ns since the Unix epoch, and where that came from: the date an IMS
/// file's name states, else the file's modification time (the best a .mat or CSV file says),
/// else the epoch.
fn recording_date(file: &Path) -> (u64, &'static str) {
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

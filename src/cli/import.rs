//! `bearingd import FILE --out DIR`: a recording (.mat, .csv, WAV) as a raw MCAP log, plus the
//! configuration to replay it with, so that recorded data goes through the daemon's pipeline
//! (`bearingd replay DIR/*.mcap --config DIR/replay.toml`).

use super::{CliError, RecordingArgs};
use crate::messages::{ChannelId, PipelineMessage, RawBlock};
use crate::offline::{resolve_conditions, AnalyzeRequest};
use crate::recording::read_recording;
use crate::sinks::mcap::{LoggerConfig, McapLogger};
use clap::Args;
use std::path::PathBuf;

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
    let (fs, rpm) = (conditions.fs_hz, conditions.rpm);
    let bearing = &conditions.bearing;
    let bearing_spec = format!(
        "z={},d={}mm,D={}mm,alpha={}",
        bearing.rolling_elements,
        bearing.element_diameter_mm,
        bearing.pitch_diameter_mm,
        bearing.contact_angle_deg
    );
    let file = args.file.display();
    let peak = recording.samples.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = if peak > 0.0 {
        peak / FULL_SCALE_COUNTS
    } else {
        1e-6
    };
    let channel = ChannelId {
        sensor: args.sensor.clone(),
        axis: "radial".into(),
    };
    let mut logger =
        McapLogger::create(LoggerConfig::new(&args.out), 0).map_err(CliError::input)?;
    let block = ((fs * BLOCK_S).round() as usize).max(1);
    for (i, chunk) in recording.samples.chunks(block).enumerate() {
        let first_sample = (i * block) as u64;
        let message = PipelineMessage::Raw(RawBlock {
            channel: channel.clone(),
            first_sample,
            sample_rate_hz: fs,
            scale_g_per_count: scale,
            counts: chunk.iter().map(|x| (x / scale).round() as i32).collect(),
        });
        let time = (first_sample as f64 / fs * 1e9) as u64;
        logger
            .log(&message, time, time)
            .map_err(CliError::failure)?;
    }
    let path = logger.current_path().map(|p| p.to_path_buf());
    logger.finish().map_err(CliError::failure)?;
    let config = format!(
        "# Replays {file} (bearingd import): bearingd replay {out}/*.mcap --config {out}/replay.toml\n\
         [[sensors]]\nid = \"{sensor}\"\ntransport = \"shm\"\nsample_rate_hz = {fs}\nscale_g_per_count = {scale:e}\naxes = [\"radial\"]\nbearing = \"{bearing_spec}\"\n\
         [sensors.speed]\nsource = \"fixed\"\nrpm = {rpm}\n\n\
         # A recording is short: choose bands every 3 s and raise flags after 1 s.\n\
         [analysis]\nband_period_s = 3.0\n\n[thresholds]\non_delay_s = 1.0\noff_delay_s = 5.0\nbaseline_windows = 5\n\n\
         [outputs]\nstate_dir = \"{out}/state\"\nmcap_dir = \"{out}/replay\"\n",
        out = args.out.display(),
        sensor = args.sensor,
    );
    let config_path = args.out.join("replay.toml");
    std::fs::write(&config_path, config)
        .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", config_path.display())))?;
    println!(
        "imported {} samples ({:.2} s at {fs} Hz, {:.3e} g per count) into {}; replay with: bearingd replay {} --config {}",
        recording.samples.len(),
        recording.samples.len() as f64 / fs,
        scale,
        path.as_ref().map_or("?".into(), |p| p.display().to_string()),
        path.as_ref().map_or("?".into(), |p| p.display().to_string()),
        config_path.display()
    );
    Ok(())
}

//! `bearingd import FILE --out DIR`: a recording (.mat, .csv, WAV) as a raw MCAP log that
//! describes itself as the daemon's logs do (the settings to replay it with, the bearing, the
//! rate, and a real date: an IMS file's name, else the file's modification time), so that
//! recorded data goes through the daemon's pipeline with `bearingd replay DIR/*.mcap`. The
//! same settings are also written as `DIR/replay.toml`, a starting point for `--config`.

use super::format::{FormatArg, Remarks};
use super::{CliError, RecordingArgs};
use crate::offline::{resolve_conditions, AnalyzeRequest};
use crate::recording::{read_recording, SampleUnit};
use crate::sinks::mcap::raw_log::{import_recording, Import, LogSignal, RawLogError};
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
    #[command(flatten)]
    format: FormatArg,
}

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
    let mut remarks = Remarks::new("bearingd: import", args.format.json());
    remarks.extend(&conditions.notes, &conditions.warnings);
    if recording.unit == SampleUnit::FullScale {
        remarks.warning("the log states its samples in g, so these fractions of full scale will be read as g (thresholds, velocity); give --unit g or --unit m/s2 if the recorder's full scale is known");
    }
    let fs = conditions.fs_hz;
    let imported = import_recording(&Import {
        file: &args.file,
        signal: LogSignal {
            out: &args.out,
            sensor: &args.sensor,
            samples: &recording.samples,
            fs_hz: fs,
            rpm: conditions.rpm,
            bearing: &conditions.bearing,
        },
    })
    .map_err(raw_log_error)?;
    let (written, origin_ns, time_source) =
        (&imported.written, imported.origin_ns, imported.time_source);
    let path = written
        .path
        .as_ref()
        .map_or("?".into(), |p| p.display().to_string());
    let seconds = recording.samples.len() as f64 / fs;
    let dated = crate::mcap_log::files::utc_text(origin_ns);
    if args.format.json() {
        println!(
            "{}",
            serde_json::json!({
                "samples": recording.samples.len(),
                "seconds": seconds,
                "fs_hz": fs,
                "g_per_count": written.scale,
                "dated": dated,
                "origin_ns": origin_ns,
                "time_source": time_source.to_string(),
                "log": path,
                "config": written.config_path.display().to_string(),
                "notes": remarks.notes,
                "warnings": remarks.warnings,
            })
        );
        return Ok(());
    }
    println!(
        "imported {} samples ({:.2} s at {fs} Hz, {:.3e} g per count, dated {} from the {time_source}) into {path}; replay with: bearingd replay {path} (its settings are also in {})",
        recording.samples.len(),
        seconds,
        written.scale,
        dated,
        written.config_path.display()
    );
    Ok(())
}

/// A refused setting or a log that cannot be opened is the input's (exit 2); a failed write is
/// not.
pub fn raw_log_error(error: RawLogError) -> CliError {
    match error {
        RawLogError::Settings(_) | RawLogError::Open(_) => CliError::input(error),
        RawLogError::Write(_) | RawLogError::Io { .. } => CliError::failure(error),
    }
}

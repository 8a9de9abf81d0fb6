//! `bearingd analyze FILE`: diagnose one recording and show the evidence.

use super::CliError;
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::{AnalysisSettings, BandSelection};
use crate::bearing::BearingGeometry;
use crate::recording::{read_recording, ReadOptions, Recording, RecordingFormat};
use crate::report::{analysis_figure, render_text, AnalyzeReport, RecordContext, SpeedSource};
use crate::twin::{SimulatedFault, SimulationParams, Simulator};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum OutputFormat {
    Text,
    Json,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum BandMethod {
    Kurtogram,
    Gk,
    Fixed,
}

#[derive(Args)]
pub struct AnalyzeArgs {
    /// The recording: CWRU .mat, PRONOSTIA acc_*.csv, IMS text file, plain CSV or WAV.
    #[arg(required_unless_present = "demo")]
    file: Option<PathBuf>,
    /// Analyse a built-in simulated record (outer-race fault, SKF 6205-2RS, 1772 rpm, 12 kHz).
    #[arg(long, conflicts_with = "file")]
    demo: bool,
    /// Channel: DE, FE, BA or a variable (.mat); horizontal/vertical (PRONOSTIA); B1x…B4y (IMS).
    #[arg(long)]
    channel: Option<String>,
    /// Column of a CSV table: header name or 1-based index.
    #[arg(long)]
    column: Option<String>,
    /// Sample rate in Hz (overrides what the file says).
    #[arg(long)]
    fs: Option<f64>,
    /// Shaft speed in rpm (overrides what the file says).
    #[arg(long)]
    rpm: Option<f64>,
    /// Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia,
    /// rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0".
    #[arg(long)]
    bearing: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: OutputFormat,
    /// Draw the envelope spectrum and the kurtogram to this file (.png or .svg).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Take the analysis settings from this configuration file's [analysis] section.
    #[arg(long)]
    config: Option<PathBuf>,
    /// How to choose the resonance band.
    #[arg(long, value_enum)]
    band_selection: Option<BandMethod>,
    /// The band for --band-selection fixed, as LO-HI in Hz, e.g. 2000-4000.
    #[arg(long)]
    band: Option<String>,
    /// Do not refine the band per fault hypothesis by its fault-band SNR.
    #[arg(long)]
    no_refine: bool,
    /// Envelope-spectrum window length in seconds (rounded to a power of two samples).
    #[arg(long)]
    window: Option<f64>,
}

pub fn run(args: &AnalyzeArgs) -> Result<(), CliError> {
    let settings = settings_from(args)?;
    let (recording, context_defaults) = if args.demo {
        demo_recording()
    } else {
        load(args)?
    };
    let fs_hz = args.fs.or(recording.fs_hz).ok_or_else(|| {
        CliError::input(format!(
            "{}: the sample rate is unknown ({} files do not state it); give it with --fs, e.g. --fs 12000",
            recording.path.display(),
            recording.format
        ))
    })?;
    let (rpm, rpm_source) = match (args.rpm, recording.rpm, context_defaults.rpm) {
        (Some(rpm), _, _) => (rpm, SpeedSource::Given),
        (None, Some(rpm), _) => (rpm, if args.demo { SpeedSource::Simulation } else { SpeedSource::File }),
        (None, None, Some(rpm)) => (rpm, SpeedSource::DataSetDefault),
        (None, None, None) => {
            return Err(CliError::input(format!(
                "{}: the shaft speed is unknown (the file does not state it); give it with --rpm, e.g. --rpm 1797",
                recording.path.display()
            )))
        }
    };
    if !(rpm.is_finite() && rpm > 0.0) {
        return Err(CliError::input(format!(
            "--rpm {rpm} is not a shaft speed; give it in rpm, e.g. --rpm 1797"
        )));
    }
    let (bearing, bearing_note) = match (&args.bearing, context_defaults.bearing) {
        (Some(text), _) => (BearingGeometry::parse(text).map_err(CliError::input)?, None),
        (None, Some((name, note))) => (BearingGeometry::from_catalog(name).map_err(CliError::failure)?, Some(note)),
        (None, None) => {
            return Err(CliError::input(format!(
                "{}: which bearing is it? give --bearing with a catalog name ({}) or custom geometry \"z=8,d=5.97mm,D=31.62mm,alpha=0\"",
                recording.path.display(),
                BearingGeometry::catalog_names().join(", ")
            )))
        }
    };
    let freqs = bearing.fault_frequencies(rpm / 60.0);
    let samples: Vec<f32> = recording.samples.iter().map(|&x| x as f32).collect();
    let analysis = RecordAnalyzer::default()
        .analyze(&samples, fs_hz, &freqs, &settings)
        .map_err(|e| CliError::input(format!("{}: {e}", recording.path.display())))?;
    let mut warnings = recording.warnings.clone();
    if let Some(note) = &bearing_note {
        warnings.push(format!(
            "bearing not given: assumed {} ({note}); give --bearing to change",
            bearing.name
        ));
    }
    let context = RecordContext {
        file: recording.path.display().to_string(),
        channel: recording.channel.clone(),
        rpm,
        rpm_source,
        bearing,
        bearing_note,
        selection: settings.band_selection,
        warnings,
    };
    let report = AnalyzeReport::new(&context, &analysis, &settings);
    if let Some(path) = &args.plot {
        crate::plot::save(&analysis_figure(&report, &analysis), path).map_err(CliError::input)?;
    }
    match args.format {
        OutputFormat::Text => print!("{}", render_text(&report)),
        OutputFormat::Json => println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(CliError::failure)?
        ),
    }
    Ok(())
}

/// What a data set's documentation says when the file itself does not.
#[derive(Default)]
struct FormatDefaults {
    rpm: Option<f64>,
    bearing: Option<(&'static str, String)>,
}

fn format_defaults(recording: &Recording) -> FormatDefaults {
    match recording.format {
        RecordingFormat::CwruMat => {
            let fan_end = recording.channel.contains("_FE_");
            FormatDefaults {
                rpm: None,
                bearing: Some(if fan_end {
                    ("skf-6203-2rs", "the CWRU fan-end bearing".to_string())
                } else {
                    ("skf-6205-2rs", "the CWRU drive-end bearing".to_string())
                }),
            }
        }
        RecordingFormat::PronostiaCsv => FormatDefaults {
            rpm: None,
            bearing: Some(("pronostia", "the PRONOSTIA test bearing".to_string())),
        },
        RecordingFormat::ImsText => FormatDefaults {
            rpm: Some(2000.0),
            bearing: Some(("rexnord-za-2115", "the IMS test rig's bearing".to_string())),
        },
        RecordingFormat::PlainCsv | RecordingFormat::Wav => FormatDefaults::default(),
    }
}

fn load(args: &AnalyzeArgs) -> Result<(Recording, FormatDefaults), CliError> {
    let Some(path) = &args.file else {
        return Err(CliError::input("give a recording to analyse, or --demo"));
    };
    let options = ReadOptions {
        channel: args.channel.clone(),
        column: args.column.clone(),
    };
    let recording = read_recording(path, &options).map_err(CliError::input)?;
    let defaults = format_defaults(&recording);
    Ok((recording, defaults))
}

/// Ten seconds of the twin's outer-race fault: needs no data and no hardware.
fn demo_recording() -> (Recording, FormatDefaults) {
    let params = SimulationParams::example(SimulatedFault::OuterRace);
    let samples = Simulator::record(params.clone(), 10.0)
        .into_iter()
        .map(f64::from)
        .collect();
    let recording = Recording {
        path: PathBuf::from(format!("demo:outer_race(seed {})", params.seed)),
        format: RecordingFormat::Wav,
        channel: "simulated".into(),
        fs_hz: Some(params.fs_hz),
        rpm: Some(params.rpm),
        samples,
        warnings: vec![format!(
            "simulated record: outer-race fault, resonance {:.0} Hz, noise {} g, seed {}",
            params.resonance_hz, params.noise_g, params.seed
        )],
    };
    (
        recording,
        FormatDefaults {
            rpm: None,
            bearing: Some(("skf-6205-2rs", "the simulated bearing".into())),
        },
    )
}

fn settings_from(args: &AnalyzeArgs) -> Result<AnalysisSettings, CliError> {
    let mut settings = match &args.config {
        Some(path) => crate::config::load(path).map_err(CliError::input)?.analysis,
        None => AnalysisSettings::default(),
    };
    if let Some(window) = args.window {
        if !(window.is_finite() && window > 0.01 && window <= 10.0) {
            return Err(CliError::input(format!(
                "--window {window} is not usable; give seconds in (0.01, 10], e.g. --window 1"
            )));
        }
        settings.window_s = window;
    }
    if args.no_refine {
        settings.refine_band_by_snr = false;
    }
    match (args.band_selection, &args.band) {
        (Some(BandMethod::Kurtogram), None) => settings.band_selection = BandSelection::Kurtogram,
        (Some(BandMethod::Gk), None) => settings.band_selection = BandSelection::GiniKurtosis,
        (Some(BandMethod::Fixed) | None, Some(text)) => {
            let parsed = text
                .split_once('-')
                .and_then(|(lo, hi)| {
                    Some((
                        lo.trim().parse::<f64>().ok()?,
                        hi.trim().parse::<f64>().ok()?,
                    ))
                })
                .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && *lo >= 0.0 && lo < hi);
            let Some((lo_hz, hi_hz)) = parsed else {
                return Err(CliError::input(format!("--band {text} is not a band; give LO-HI in Hz with LO < HI, e.g. --band 2000-4000")));
            };
            settings.band_selection = BandSelection::Fixed { lo_hz, hi_hz };
        }
        (Some(BandMethod::Fixed), None) => {
            return Err(CliError::input(
                "--band-selection fixed needs --band LO-HI, e.g. --band 2000-4000",
            ))
        }
        (Some(_), Some(_)) => {
            return Err(CliError::input(
                "--band is only for --band-selection fixed; drop one of them",
            ))
        }
        (None, None) => {}
    }
    Ok(settings)
}

//! `bearingd analyze FILE...`: diagnose recordings and show the evidence. The text, JSON and
//! table are the service's; `--plot` is drawn by the lab (`bearingd-lab analyze`, which runs
//! this same command through [`run_with`] and adds the figure of each record), so that the
//! service links no drawing code.

use super::format::ReportFormat;
use super::{CliError, RecordingArgs};
use crate::analysis::iso::{Foundation, MachineGroup, SeveritySettings};
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::{AnalysisSettings, BandSelection};
use crate::offline::{analyze, AnalyzeOutcome, AnalyzeRequest};
use crate::report::{render_text, AnalyzeReport};
use crate::twin::hw::StateFilter;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, ValueEnum)]
pub enum BandMethod {
    Kurtogram,
    Gk,
    Fixed,
}

#[derive(Args)]
pub struct AnalyzeArgs {
    /// Recordings: MATLAB .mat (CWRU, structs such as MFPT's), PRONOSTIA acc_*.csv, IMS text
    /// files, plain CSV, WAV, or an MCAP log of bearingd run.
    #[arg(required_unless_present = "demo")]
    files: Vec<PathBuf>,
    /// Analyse a built-in simulated record (outer-race fault, SKF 6205-2RS, 1772 rpm, 12 kHz).
    #[arg(long, conflicts_with = "files")]
    demo: bool,
    #[command(flatten)]
    recording: RecordingArgs,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: ReportFormat,
    /// Draw the envelope spectrum and the kurtogram to this file (.png or .svg); with several
    /// records, the record's file name is added before the extension. Runs in bearingd-lab.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Take the analysis settings from this configuration file's [analysis] section, and its
    /// twin.learned_model unless --learned is given: the daemon's decision, offline.
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
    /// Also fit the signal-model twin for each fault hypothesis (adds `twin` to the JSON, the
    /// twin's spectrum to the text and the plot).
    #[arg(long)]
    twin: bool,
    /// Add a learned model's opinion: a .safetensors file of `bearingd train`, or a directory
    /// of them, one per bearing (the shipped ones: models/, one for each catalog bearing). It
    /// may settle what the envelope leaves open, never overrule it; the JSON gains `learned`.
    #[arg(long, conflicts_with = "hw")]
    learned: Option<PathBuf>,
    /// ISO 10816-3 machine group for the velocity zones: 1 (above 300 kW, or shaft height
    /// from 315 mm) or 2 (15 to 300 kW, shaft height 160 to 315 mm).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u8).range(1..=2))]
    machine_group: u8,
    /// Foundation for the velocity zones: rigid or flexible.
    #[arg(long, value_enum, default_value = "rigid")]
    foundation: FoundationArg,
    /// Instead of the diagnosis: identify the Hammerstein–Wiener model (seed 003) for state
    /// orders 0…9 on each record and print its accuracy and time per order, and the mean per
    /// directory (bearing).
    #[arg(long, conflicts_with_all = ["demo", "twin", "plot"])]
    hw: bool,
    /// With --hw: where the median filter sits in the virtual states' chain of differences,
    /// raw_once (the raw signal, once: the seed's reading) or each_order (every order's
    /// output on its own); docs/HW.md compares them.
    #[arg(long, value_enum, default_value = "raw-once", requires = "hw")]
    hw_states: HwStatesArg,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum HwStatesArg {
    RawOnce,
    EachOrder,
}

impl From<HwStatesArg> for StateFilter {
    fn from(arg: HwStatesArg) -> Self {
        match arg {
            HwStatesArg::RawOnce => StateFilter::RawOnce,
            HwStatesArg::EachOrder => StateFilter::EachOrder,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum FoundationArg {
    Rigid,
    Flexible,
}

fn severity_from(args: &AnalyzeArgs) -> SeveritySettings {
    SeveritySettings {
        group: if args.machine_group == 1 {
            MachineGroup::Large
        } else {
            MachineGroup::Medium
        },
        foundation: match args.foundation {
            FoundationArg::Rigid => Foundation::Rigid,
            FoundationArg::Flexible => Foundation::Flexible,
        },
    }
}

/// What a caller adds for each analysed record (the lab: its figure), with the number of
/// records asked for.
pub type OnRecord<'a> = dyn FnMut(&AnalyzeOutcome, usize) -> Result<(), CliError> + 'a;

/// `bearingd analyze`: with `--plot`, handed to `bearingd-lab` (this process is replaced).
pub fn run(args: &AnalyzeArgs) -> Result<(), CliError> {
    if args.plot.is_some() {
        return Err(super::lab::exec_lab("analyze --plot"));
    }
    run_with(args, &mut |_, _| Ok(()))
}

/// The analysis of every record asked for, printed as `--format` says; `on_record` sees each
/// record's outcome before it is printed.
pub fn run_with(args: &AnalyzeArgs, on_record: &mut OnRecord) -> Result<(), CliError> {
    if args.hw {
        return super::hw_table::run(
            &args.files,
            &args.recording,
            args.hw_states.into(),
            args.format == ReportFormat::Json,
        );
    }
    let config = match &args.config {
        Some(path) => Some(crate::config::load(path).map_err(CliError::input)?),
        None => None,
    };
    let settings = settings_from(args, config.as_ref())?;
    let files: Vec<Option<PathBuf>> = if args.demo {
        vec![None]
    } else {
        args.files.iter().cloned().map(Some).collect()
    };
    let learned_path = args
        .learned
        .as_ref()
        .or(config.as_ref().and_then(|c| c.twin.learned_model.as_ref()));
    let learned = match learned_path {
        Some(path) => Some(std::sync::Arc::new(
            crate::learned::ModelSet::load(path).map_err(CliError::input)?,
        )),
        None => None,
    };
    let mut analyzer = RecordAnalyzer::default();
    let mut reports = Vec::new();
    let mut failures = Vec::new();
    if args.format == ReportFormat::Table {
        println!("{}", table_header());
    }
    for file in &files {
        let request = AnalyzeRequest {
            file: file.clone(),
            read: args.recording.read_options(),
            fs_hz: args.recording.fs,
            rpm: args.recording.rpm,
            bearing: args.recording.bearing.clone(),
            settings: settings.clone(),
            twin: args.twin,
            severity: severity_from(args),
            learned: learned.clone(),
        };
        let outcome = match analyze(&request, &mut analyzer) {
            Ok(outcome) => outcome,
            Err(error) if files.len() > 1 => {
                eprintln!("bearingd: error: {error}");
                failures.push(error.to_string());
                continue;
            }
            Err(error) => return Err(CliError::input(error)),
        };
        on_record(&outcome, files.len())?;
        match args.format {
            ReportFormat::Text => print!("{}", render_text(&outcome.report)),
            ReportFormat::Table => println!("{}", table_row(&outcome.report)),
            ReportFormat::Json => {}
        }
        reports.push(outcome.report);
    }
    if args.format == ReportFormat::Json {
        let json = if reports.len() == 1 {
            serde_json::to_string_pretty(&reports[0])
        } else {
            serde_json::to_string_pretty(&reports)
        };
        println!("{}", json.map_err(CliError::failure)?);
    }
    match failures.len() {
        0 => Ok(()),
        n => Err(CliError::input(format!(
            "{n} of {} recordings could not be analysed (see above)",
            files.len()
        ))),
    }
}

fn table_header() -> String {
    "| file | channel | rpm | band (Hz) | BPFO | BPFI | 2BSF | FTF | diagnosis | confidence |\n|---|---|---|---|---|---|---|---|---|---|".into()
}

fn table_row(r: &AnalyzeReport) -> String {
    let name = Path::new(&r.file)
        .file_name()
        .map_or(r.file.clone(), |n| n.to_string_lossy().into_owned());
    format!(
        "| {name} | {} | {:.0} | {:.0}–{:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {:.2} |",
        r.channel,
        r.rpm,
        r.band_hz[0],
        r.band_hz[1],
        r.scores.outer_race,
        r.scores.inner_race,
        r.scores.ball,
        r.scores.cage,
        r.diagnosis,
        r.confidence
    )
}

fn settings_from(
    args: &AnalyzeArgs,
    config: Option<&crate::config::Config>,
) -> Result<AnalysisSettings, CliError> {
    let mut settings = config.map_or_else(AnalysisSettings::default, |c| c.analysis.clone());
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

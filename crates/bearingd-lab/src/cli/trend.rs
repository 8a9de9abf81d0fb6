//! `bearingd trend DIR`: a bearing's life from a directory of snapshots, in time order, through
//! the daemon's health tracker (stages healthy → degrading → failing) with RMS, kurtosis, the HW
//! residual and the envelope fault score, and the RMS trend with its time to the failure limit.
//!
//! A command of its own rather than `analyze --trend`: `analyze` judges each record on its own,
//! `trend` carries state from one snapshot to the next (baselines, stages, the trend), so its
//! options (baseline, smoothing, threshold) and its output (a timeline) are different.
//!
//! Reading and timing files happens here; the life itself is sans-IO ([`LifeTracker`]).

use crate::analysis::health::CONFIRM_WINDOWS;
use crate::life::{hindsight, LifeSettings, LifeTracker};
use crate::offline::{resolve_conditions, AnalyzeRequest, OfflineError};
use crate::recording::{read_recording, time_from_name};
use crate::report::{life_figure, render_life_text, LifeReport, LifeSettingsReport, SkippedFile};
use bearingd::cli::{CliError, RecordingArgs};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TrendFormat {
    /// The stage timeline and the trend, for people.
    Text,
    /// Everything, per snapshot, as one JSON document.
    Json,
    /// One Markdown table row per snapshot.
    Table,
}

#[derive(Args)]
pub struct TrendArgs {
    /// A directory of snapshots (PRONOSTIA acc_NNNNN.csv, IMS files named like
    /// 2003.10.22.12.14.13, bearingd-*.mcap logs), or one MCAP log.
    path: PathBuf,
    #[command(flatten)]
    recording: RecordingArgs,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: TrendFormat,
    /// Draw the stage timeline (RMS with the trend, kurtosis, HW residual, fault score) to
    /// this file (.png or .svg).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Snapshots that form the healthy baseline (and the aging baseline of RMS).
    #[arg(long, default_value_t = 15)]
    baseline: u64,
    /// Running median over this many snapshots before the tracker (1: none).
    #[arg(long, default_value_t = 3)]
    smoothing: usize,
    /// Standard deviations above a baseline that change the stage.
    #[arg(long, default_value_t = 3.0)]
    sigma: f64,
    /// Snapshots in the sliding window of the RMS trend.
    #[arg(long, default_value_t = 12)]
    trend_window: usize,
    /// RMS threshold in g for the time-to-threshold (default: the failure limit the tracker
    /// learns at the start of degradation).
    #[arg(long)]
    threshold_g: Option<f64>,
    /// Seconds between snapshots whose names state no time (e.g. other .mcap files), placed in
    /// name order.
    #[arg(long)]
    interval: Option<f64>,
    /// Records longer than 1.5 windows (IMS, MCAP logs) are cut into windows of this many
    /// seconds, each one snapshot.
    #[arg(long, default_value_t = 1.0)]
    window: f64,
    /// Do not identify the HW model per snapshot.
    #[arg(long)]
    no_hw: bool,
}

/// A file to read, placed in time.
struct Placed {
    path: PathBuf,
    seconds: f64,
}

/// What a directory holds: snapshots in time order, files that could not be placed, files
/// that are not snapshots.
struct Listing {
    placed: Vec<Placed>,
    skipped: Vec<SkippedFile>,
    ignored: Vec<String>,
}

pub fn run(args: &TrendArgs) -> Result<(), CliError> {
    let settings = settings_from(args)?;
    let Listing {
        placed,
        mut skipped,
        ignored,
    } = list_snapshots(args)?;
    let first_s = placed.first().map_or(0.0, |p| p.seconds);
    let mut life = LifeTracker::new(settings.clone());
    let mut points = Vec::new();
    let mut notes: BTreeSet<String> = BTreeSet::new();
    let mut channel = None;
    let progress = ProgressBar::with_draw_target(
        Some(placed.len() as u64),
        ProgressDrawTarget::stderr_with_hz(4),
    );
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} snapshots, {eta} left") {
        progress.set_style(style);
    }
    for file in &placed {
        progress.inc(1);
        let name = file_label(&file.path);
        let recording = match read_recording(&file.path, &args.recording.read_options()) {
            Ok(r) => r,
            Err(e) => {
                skipped.push(SkippedFile {
                    file: name,
                    error: e.to_string(),
                });
                continue;
            }
        };
        let request = AnalyzeRequest {
            file: Some(file.path.clone()),
            read: args.recording.read_options(),
            fs_hz: args.recording.fs,
            rpm: args.recording.rpm,
            bearing: args.recording.bearing.clone(),
            ..AnalyzeRequest::default()
        };
        let (fs_hz, freqs) = match resolve_conditions(&recording, &request, false) {
            Ok(c) => {
                // The recording's own warnings are among them.
                notes.extend(c.notes);
                notes.extend(c.warnings);
                (c.fs_hz, Some(c.bearing.fault_frequencies(c.rpm / 60.0)))
            }
            Err(OfflineError::UnknownSpeed { .. } | OfflineError::UnknownBearing { .. }) => {
                notes.extend(recording.warnings.iter().cloned());
                notes.insert("no shaft speed or bearing known for some snapshots: no envelope fault score for them; give --rpm (and --bearing) to score the fault bands".into());
                match args.recording.fs.or(recording.fs_hz) {
                    Some(fs) => (fs, None),
                    None => {
                        skipped.push(SkippedFile {
                            file: name.clone(),
                            error: format!("{name}: the sample rate is unknown; give it with --fs, e.g. --fs 25600"),
                        });
                        continue;
                    }
                }
            }
            Err(e @ OfflineError::BadOverride { .. }) => return Err(CliError::input(e)),
            Err(e) => {
                skipped.push(SkippedFile {
                    file: name,
                    error: e.to_string(),
                });
                continue;
            }
        };
        channel.get_or_insert_with(|| recording.channel.clone());
        let window = ((args.window * fs_hz).round() as usize).max(1);
        let pieces: Vec<&[f64]> = if recording.samples.len() * 2 > window * 3 {
            recording
                .samples
                .chunks(window)
                .filter(|c| c.len() * 2 >= window)
                .collect()
        } else {
            vec![&recording.samples[..]]
        };
        let several = pieces.len() > 1;
        for (k, piece) in pieces.into_iter().enumerate() {
            let source = if several {
                format!("{name}#{k}")
            } else {
                name.clone()
            };
            let time_s = file.seconds - first_s + k as f64 * window as f64 / fs_hz;
            match life.push(&source, time_s, piece, fs_hz, freqs.as_ref()) {
                Ok(point) => points.push(point),
                Err(e) => skipped.push(SkippedFile {
                    file: source,
                    error: e.to_string(),
                }),
            }
        }
    }
    progress.finish_and_clear();
    if points.is_empty() {
        let mut message = format!("{}: no usable snapshot", args.path.display());
        for s in &skipped {
            message.push_str(&format!("\n  {}", s.error));
        }
        if skipped.is_empty() {
            message.push_str("; give a directory of PRONOSTIA acc_NNNNN.csv files, IMS files named like 2003.10.22.12.14.13, or bearingd MCAP logs");
        }
        return Err(CliError::input(message));
    }
    let report = LifeReport {
        path: args.path.display().to_string(),
        channel: channel.unwrap_or_default(),
        settings: LifeSettingsReport {
            baseline_snapshots: settings.baseline_snapshots,
            sigma: settings.sigma,
            confirm_snapshots: CONFIRM_WINDOWS,
            smoothing: settings.smoothing,
            trend_window: settings.trend_window,
            confidence: settings.confidence,
            threshold_rms: settings.threshold_rms,
        },
        events: life.events().to_vec(),
        hindsight: hindsight(&points),
        points,
        skipped,
        ignored,
        notes: notes.into_iter().collect(),
    };
    if let Some(plot) = &args.plot {
        crate::plot::save(&life_figure(&report), plot).map_err(CliError::input)?;
    }
    match args.format {
        TrendFormat::Text => print!("{}", render_life_text(&report)),
        TrendFormat::Json => println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(CliError::failure)?
        ),
        TrendFormat::Table => print!("{}", table(&report)),
    }
    if !report.skipped.is_empty() && args.format != TrendFormat::Text {
        eprintln!(
            "bearingd: warning: skipped {} file(s) that could not be used:",
            report.skipped.len()
        );
        for s in &report.skipped {
            eprintln!("  {}", s.error);
        }
    }
    Ok(())
}

fn settings_from(args: &TrendArgs) -> Result<LifeSettings, CliError> {
    let mut problems = Vec::new();
    if args.baseline < 2 {
        problems.push(format!(
            "--baseline {} is too few; give at least 2 snapshots, e.g. --baseline 15",
            args.baseline
        ));
    }
    if args.smoothing == 0 {
        problems.push("--smoothing 0 is not usable; give 1 for none, e.g. --smoothing 3".into());
    }
    if !(args.sigma.is_finite() && args.sigma > 0.0) {
        problems.push(format!(
            "--sigma {} is not usable; give a number above 0, e.g. --sigma 3",
            args.sigma
        ));
    }
    if args.trend_window < 4 {
        problems.push(format!(
            "--trend-window {} is too short; give at least 4 snapshots, e.g. --trend-window 12",
            args.trend_window
        ));
    }
    if let Some(g) = args.threshold_g.filter(|g| !(g.is_finite() && *g > 0.0)) {
        problems.push(format!(
            "--threshold-g {g} is not usable; give an RMS in g above 0, e.g. --threshold-g 2"
        ));
    }
    if let Some(s) = args.interval.filter(|s| !(s.is_finite() && *s > 0.0)) {
        problems.push(format!(
            "--interval {s} is not usable; give seconds above 0, e.g. --interval 10"
        ));
    }
    if !(args.window.is_finite() && args.window >= 0.01) {
        problems.push(format!(
            "--window {} is not usable; give seconds, at least 0.01, e.g. --window 1",
            args.window
        ));
    }
    if !problems.is_empty() {
        return Err(CliError::input(problems.join("\n")));
    }
    Ok(LifeSettings {
        baseline_snapshots: args.baseline,
        sigma: args.sigma,
        smoothing: args.smoothing,
        trend_window: args.trend_window,
        threshold_rms: args.threshold_g,
        hw: (!args.no_hw).then(Default::default),
        ..LifeSettings::default()
    })
}

/// The snapshots under `args.path` in time order, the files that could not be placed, and the
/// files that are not snapshots at all.
fn list_snapshots(args: &TrendArgs) -> Result<Listing, CliError> {
    let path = &args.path;
    let files: Vec<PathBuf> = if path.is_dir() {
        let entries = std::fs::read_dir(path).map_err(|e| {
            CliError::input(format!(
                "{}: cannot list the directory: {e}; check that it exists and is readable",
                path.display()
            ))
        })?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file())
            .filter(|p| !file_label(p).starts_with('.'))
            .collect();
        files.sort();
        files
    } else if path.is_file() {
        vec![path.clone()]
    } else {
        return Err(CliError::input(format!(
            "{}: not found; give a directory of snapshots or an MCAP log",
            path.display()
        )));
    };
    let mut placed = Vec::new();
    let mut unplaced = Vec::new();
    let mut ignored = Vec::new();
    for file in files {
        if let Some(t) = time_from_name(&file) {
            placed.push(Placed {
                path: file,
                seconds: t.seconds,
            });
        } else if is_mcap(&file) || path.is_file() {
            unplaced.push(file);
        } else {
            ignored.push(file_label(&file));
        }
    }
    let mut skipped = Vec::new();
    match args.interval {
        Some(interval) => {
            // Name order, after the snapshots that state their time.
            let start = placed
                .iter()
                .map(|p| p.seconds)
                .fold(f64::NEG_INFINITY, f64::max);
            let start = if start.is_finite() { start + interval } else { 0.0 };
            placed.extend(unplaced.into_iter().enumerate().map(|(i, path)| Placed {
                path,
                seconds: start + i as f64 * interval,
            }));
        }
        None if path.is_file() && unplaced.len() == 1 => {
            placed.extend(unplaced.into_iter().map(|path| Placed { path, seconds: 0.0 }));
        }
        None => skipped.extend(unplaced.into_iter().map(|f| SkippedFile {
            file: file_label(&f),
            error: format!(
                "{}: its name states no time (bearingd logs are named bearingd-YYYYMMDDTHHMMSSZ-NNNNNN.mcap); give --interval SECONDS to place such files in name order",
                f.display()
            ),
        })),
    }
    placed.sort_by(|a, b| a.seconds.total_cmp(&b.seconds).then(a.path.cmp(&b.path)));
    Ok(Listing {
        placed,
        skipped,
        ignored,
    })
}

fn is_mcap(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn table(report: &LifeReport) -> String {
    let mut out = String::from(
        "| snapshot | time (s) | life % | RMS (g) | kurtosis | HW residual % | fault score | stage |\n|---|---|---|---|---|---|---|---|\n",
    );
    for p in &report.points {
        out.push_str(&format!(
            "| {} | {:.1} | {:.1} | {:.3} | {:.2} | {} | {} | {} |\n",
            p.source,
            p.time_s,
            100.0 * report.life_fraction(p.time_s),
            p.rms,
            p.kurtosis,
            p.hw_residual_percent
                .map_or("–".into(), |r| format!("{r:.1}")),
            p.fault_score.map_or("–".into(), |s| format!("{s:.1}")),
            p.stage.name()
        ));
    }
    out
}

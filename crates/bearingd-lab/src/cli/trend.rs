//! `bearingd trend DIR`: a bearing's life from a directory of snapshots, in time order, through
//! the daemon's health tracker (stages healthy → degrading → failing) with RMS, kurtosis, the HW
//! residual and the envelope fault score, and the RMS trend with its time to the failure limit.
//!
//! A command of its own rather than `analyze --trend`: `analyze` judges each record on its own,
//! `trend` carries state from one snapshot to the next (baselines, stages, the trend), so its
//! options (baseline, smoothing, threshold) and its output (a timeline) are different.
//!
//! Reading and timing files happens here; the life itself is sans-IO ([`LifeTracker`]).

use super::progress::Progress;
use crate::analysis::health::CONFIRM_WINDOWS;
use crate::evaluate::recordings::Manifest;
use crate::life::{hindsight, HwFrom, LifeSettings, LifeTracker, SnapshotHw};
use crate::offline::{resolve_conditions, AnalyzeRequest, OfflineError};
use crate::recording::{
    read_recording_placed, time_from_name, LogPlacement, LoggedHwFit, SampleUnit, Segment,
};
use crate::report::{
    life_figure, render_life_text, LifeGap, LifeReport, LifeSettingsReport, SkippedFile,
};
use bearingd::cli::format::ReportFormat;
use bearingd::cli::{CliError, RecordingArgs};
use bearingd::mcap_log::read_header;
use clap::Args;
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct TrendArgs {
    /// A directory of snapshots (PRONOSTIA acc_NNNNN.csv, IMS files named like
    /// 2003.10.22.12.14.13, bearingd-*.mcap logs), or one MCAP log.
    path: PathBuf,
    #[command(flatten)]
    recording: RecordingArgs,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: ReportFormat,
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
    /// Seconds between snapshots whose names state no time (.mcap and .wav files; given this,
    /// any other file too, e.g. CSV tables), placed in name order.
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
    /// Seconds: a log's wall-clock anchor (its sample 0), else the time its name states.
    seconds: f64,
    /// A log's place in its run (1, 2, … after each rotation); 0 for other files.
    sequence: u64,
}

/// What a directory holds: snapshots in time order, files that could not be placed, files
/// that are not snapshots.
struct Listing {
    placed: Vec<Placed>,
    skipped: Vec<SkippedFile>,
    ignored: Vec<String>,
}

/// One snapshot cut from a file: its samples and where they sit.
struct Piece<'a> {
    samples: &'a [f64],
    /// Seconds after the start of the file's segment (`segment`), or of the file.
    offset_s: f64,
    /// Index of the log's segment it lies in.
    segment: usize,
    /// A log's samples `[from, to)` in its own count.
    log_samples: Option<(u64, u64)>,
}

pub fn run(args: &TrendArgs) -> Result<(), CliError> {
    let settings = settings_from(args)?;
    let Listing {
        placed,
        mut skipped,
        ignored,
    } = list_snapshots(args)?;
    let mut life = LifeTracker::new(settings.clone());
    let mut points = Vec::new();
    let mut notes: BTreeSet<String> = BTreeSet::new();
    let mut channel = None;
    let mut clock = LogClock::default();
    let mut hw_note = HwNote::default();
    let manifest = ManifestSpeeds::find(&args.path);
    notes.extend(manifest.unreadable.iter().cloned());
    let progress = Progress::start("trend", "files", placed.len() as u64);
    for (done, file) in placed.iter().enumerate() {
        progress.set(done as u64, &format!("{} snapshots", points.len()));
        let name = file_label(&file.path);
        let (recording, placement) =
            match read_recording_placed(&file.path, &args.recording.read_options()) {
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
            rpm: args
                .recording
                .rpm
                .or_else(|| manifest.rpm_of(&file.path, &mut notes)),
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
                notes.extend(recording.notes.iter().cloned());
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
        if recording.unit == SampleUnit::FullScale {
            notes.insert("some snapshots are in fractions of full scale, not g: their RMS is relative and the failure threshold in g does not apply to them; give --unit g or --unit m/s2 if the recorder's full scale is known".into());
        }
        channel.get_or_insert_with(|| recording.channel.clone());
        let window = ((args.window * fs_hz).round() as usize).max(1);
        let pieces = cut(&recording.samples, placement.as_ref(), window, fs_hz);
        let logged_hw = match &placement {
            Some(p) if settings.hw.is_some() => hw_note.choose(&name, p),
            _ => None,
        };
        let several = pieces.len() > 1;
        for (k, piece) in pieces.into_iter().enumerate() {
            let source = if several {
                format!("{name}#{k}")
            } else {
                name.clone()
            };
            let time_s = match &placement {
                Some(p) => clock.place(file, p, piece.segment, fs_hz, &source),
                None => clock.relative(file.seconds),
            } + piece.offset_s;
            let hw = match (logged_hw, piece.log_samples) {
                (Some(fits), Some(span)) => SnapshotHw::Logged(residual_in(fits, span)),
                _ => SnapshotHw::Identify,
            };
            match life.push_with_hw(&source, time_s, piece.samples, fs_hz, freqs.as_ref(), hw) {
                Ok(point) => points.push(point),
                Err(e) => skipped.push(SkippedFile {
                    file: source,
                    error: e.to_string(),
                }),
            }
        }
    }
    let snapshots = format!("{} snapshots", points.len());
    progress.set(placed.len() as u64, &snapshots);
    progress.finish(&snapshots);
    if points.is_empty() {
        let mut message = format!("{}: no usable snapshot", args.path.display());
        for s in &skipped {
            message.push_str(&format!("\n  {}", s.error));
        }
        if skipped.is_empty() {
            message.push_str("; give a directory of PRONOSTIA acc_NNNNN.csv files, IMS files named like 2003.10.22.12.14.13, or bearingd MCAP logs; other recordings (WAV, CSV tables) with --interval SECONDS");
        }
        return Err(CliError::input(message));
    }
    notes.extend(hw_note.notes(channel.as_deref().unwrap_or_default(), &points));
    notes.extend(clock.notes());
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
        gaps: clock.gaps,
        points,
        skipped,
        ignored,
        notes: notes.into_iter().collect(),
    };
    if let Some(plot) = &args.plot {
        crate::plot::save(&life_figure(&report), plot).map_err(CliError::input)?;
    }
    match args.format {
        ReportFormat::Text => print!("{}", render_life_text(&report)),
        ReportFormat::Json => println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(CliError::failure)?
        ),
        ReportFormat::Table => print!("{}", table(&report)),
    }
    if !report.skipped.is_empty() && args.format != ReportFormat::Text {
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

/// The snapshots of one file: the whole file when it is at most 1.5 windows long, else
/// windows of `window` samples (a last one shorter than half a window is left out), cut
/// inside each run of contiguous samples of a log so that no window spans a gap.
fn cut<'a>(
    samples: &'a [f64],
    placement: Option<&LogPlacement>,
    window: usize,
    fs_hz: f64,
) -> Vec<Piece<'a>> {
    let whole = [Segment {
        offset: 0,
        first_sample: 0,
        len: samples.len(),
    }];
    let segments = match placement {
        Some(p) if !p.segments.is_empty() => &p.segments[..],
        _ => &whole[..],
    };
    let logged = placement.is_some();
    if samples.len() * 2 <= window * 3 {
        let first = segments[0].first_sample;
        return vec![Piece {
            samples,
            offset_s: 0.0,
            segment: 0,
            log_samples: logged.then_some((first, first + samples.len() as u64)),
        }];
    }
    let mut pieces = Vec::new();
    for (index, segment) in segments.iter().enumerate() {
        let Some(part) = samples.get(segment.offset..segment.offset + segment.len) else {
            continue;
        };
        for (k, chunk) in part.chunks(window).enumerate() {
            if chunk.len() * 2 < window {
                continue;
            }
            let from = segment.first_sample + (k * window) as u64;
            pieces.push(Piece {
                samples: chunk,
                offset_s: (k * window) as f64 / fs_hz,
                segment: index,
                log_samples: logged.then_some((from, from + chunk.len() as u64)),
            });
        }
    }
    pieces
}

/// The residual (%) of the last HW fit the daemon logged whose signal ends in `(from, to]`.
fn residual_in(fits: &[LoggedHwFit], (from, to): (u64, u64)) -> Option<f64> {
    fits.iter()
        .rfind(|f| f.end_sample > from && f.end_sample <= to)
        .and_then(|f| f.accuracy_simulation)
        .map(|accuracy| 100.0 - accuracy)
}

/// The shaft speeds a data set's `manifest.csv` gives its files (FEMTO: 1800 rpm for
/// Bearing1_2), in the snapshots' folder or the one above it: used when `--rpm` is not given,
/// so that the fault score is computed whenever the speed is known.
#[derive(Default)]
struct ManifestSpeeds {
    path: PathBuf,
    rpm: HashMap<PathBuf, f64>,
    /// A `manifest.csv` found but not readable as a data set's manifest, and why: said in a
    /// note, never skipped in silence (the speeds it would have given are missing).
    unreadable: Vec<String>,
}

impl ManifestSpeeds {
    fn find(path: &Path) -> Self {
        let dir = if path.is_dir() {
            Some(path)
        } else {
            path.parent()
        };
        let candidates = dir
            .into_iter()
            .flat_map(|d| [Some(d), d.parent()])
            .flatten()
            .map(|d| d.join("manifest.csv"));
        let mut unreadable = Vec::new();
        for candidate in candidates.filter(|c| c.is_file()) {
            let manifest = match Manifest::read(&candidate) {
                Ok(manifest) => manifest,
                Err(e) => {
                    unreadable.push(format!(
                        "no speed taken from a manifest that is not a readable data set manifest: {e}; mend it, or give --rpm"
                    ));
                    continue;
                }
            };
            let rpm: HashMap<PathBuf, f64> = manifest
                .records
                .iter()
                .filter_map(|r| Some((r.file.canonicalize().ok()?, r.rpm?)))
                .collect();
            if !rpm.is_empty() {
                return ManifestSpeeds {
                    path: candidate,
                    rpm,
                    unreadable,
                };
            }
        }
        ManifestSpeeds {
            unreadable,
            ..ManifestSpeeds::default()
        }
    }

    /// The manifest's speed of `file`, said in a note.
    fn rpm_of(&self, file: &Path, notes: &mut BTreeSet<String>) -> Option<f64> {
        let rpm = *self.rpm.get(&file.canonicalize().ok()?)?;
        notes.insert(format!(
            "speed from {} (the data set's manifest: {rpm} rpm for its files); --rpm overrides it",
            self.path.display()
        ));
        Some(rpm)
    }
}

/// Which HW residuals a life over logs uses, and what to say about it once.
#[derive(Default)]
struct HwNote {
    /// Logs whose HW fits were used, and logs that had none (so the model was identified).
    logged: usize,
    identified: Vec<String>,
}

impl HwNote {
    /// The fits of a log to use (maybe none yet, when its configuration says the daemon fits
    /// the model), or `None` (identify the model) when it logged none and says nothing or that
    /// HW was off.
    fn choose<'a>(&mut self, name: &str, log: &'a LogPlacement) -> Option<&'a [LoggedHwFit]> {
        if log.hw_fits.is_empty() && log.hw_enabled != Some(true) {
            self.identified.push(name.to_string());
            None
        } else {
            self.logged += 1;
            Some(&log.hw_fits)
        }
    }

    fn notes(&self, channel: &str, points: &[crate::life::LifePoint]) -> Vec<String> {
        let mut notes = Vec::new();
        if self.logged > 0 {
            let with = points
                .iter()
                .filter(|p| p.hw_from == Some(HwFrom::Log))
                .count();
            notes.push(format!(
                "HW residual: the daemon's own fits, read from /hw/{channel} ({with} of {} snapshots hold one: the daemon fits once per twin re-fit, twin.refit_period_s), not identified again",
                points.len()
            ));
        }
        if let Some(first) = self.identified.first() {
            notes.push(format!(
                "HW residual: {} log(s) hold no HW fit (/hw/{channel}: HW off, or a log of an older bearingd; the first: {first}): the model was identified on each of their snapshots instead (slow: about 0.8 s of CPU per 1 s window; --no-hw skips it)",
                self.identified.len()
            ));
        }
        notes
    }
}

/// Places the snapshots of logs in time: each log at its wall-clock anchor plus its sample
/// index over the sample rate; a run that starts before the previous one ends (runs made
/// with `run --fast` are dated in sample time, so they overlap in wall-clock time; or a sensor
/// restart) is moved to start where the previous ended; a jump forward longer than half a
/// window is a gap.
#[derive(Default)]
struct LogClock {
    /// Absolute seconds of the first snapshot: the life's time 0.
    first_s: Option<f64>,
    /// The run (anchor) being placed, and how far its samples were moved (s).
    run: Option<(Option<u64>, u64)>,
    shift_s: f64,
    /// End of the last segment placed (absolute s) and the snapshot before it.
    last_end_s: Option<f64>,
    last_source: String,
    /// The segment placed last: (file, segment index).
    placed_segment: Option<(PathBuf, usize)>,
    moved: usize,
    gaps: Vec<LifeGap>,
}

impl LogClock {
    /// Seconds since the first snapshot of a file placed at `absolute_s`.
    fn relative(&mut self, absolute_s: f64) -> f64 {
        absolute_s - *self.first_s.get_or_insert(absolute_s)
    }

    /// Time (s since the first snapshot) of the start of `segment` of the log `file`, and
    /// `source` is its snapshot (a gap before it names it).
    fn place(
        &mut self,
        file: &Placed,
        placement: &LogPlacement,
        segment: usize,
        fs_hz: f64,
        source: &str,
    ) -> f64 {
        let Some(seg) = placement.segments.get(segment) else {
            return self.relative(file.seconds);
        };
        let anchor_s = placement
            .origin_ns
            .map_or(file.seconds, |ns| ns as f64 / 1e9);
        let run = (placement.run_id, placement.origin_ns.unwrap_or_default());
        if self.run != Some(run) {
            self.run = Some(run);
            self.shift_s = 0.0;
        }
        let key = (file.path.clone(), segment);
        let mut start_s = anchor_s + seg.first_sample as f64 / fs_hz + self.shift_s;
        if self.placed_segment.as_ref() != Some(&key) {
            // A new segment: check it against the end of the one before.
            if let Some(end_s) = self.last_end_s {
                let tolerance = 1e-3 + 1.0 / fs_hz;
                if start_s < end_s - tolerance {
                    self.shift_s += end_s - start_s;
                    start_s = end_s;
                    self.moved += 1;
                } else if start_s > end_s + tolerance.max(0.5) {
                    let first = *self.first_s.get_or_insert(start_s);
                    self.gaps.push(LifeGap {
                        after: self.last_source.clone(),
                        before: source.to_string(),
                        from_s: end_s - first,
                        to_s: start_s - first,
                    });
                }
            }
            self.last_end_s = Some(start_s + seg.len as f64 / fs_hz);
            self.placed_segment = Some(key);
        }
        self.last_source = source.to_string();
        self.relative(start_s)
    }

    fn notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.moved > 0 {
            notes.push(format!(
                "{} run(s) or file(s) of logs start before the previous one ends (logs made with bearingd run --fast are dated in sample time; or a sensor restart): each was placed right after the one before, so times after them are not wall-clock times",
                self.moved
            ));
        }
        if !self.gaps.is_empty() {
            notes.push(format!(
                "{} gap(s) in the logs (no samples for longer than half a window, e.g. between runs): shown as gaps, the lines break there",
                self.gaps.len()
            ));
        }
        notes
    }
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
        if let Some((seconds, sequence)) = log_anchor(&file) {
            placed.push(Placed {
                path: file,
                seconds,
                sequence,
            });
        } else if let Some(t) = time_from_name(&file) {
            placed.push(Placed {
                path: file,
                seconds: t.seconds,
                sequence: 0,
            });
        } else if is_mcap(&file) || has_extension(&file, "wav") || path.is_file() {
            // Recordings whose name states no time: placed by --interval or skipped, named.
            unplaced.push(file);
        } else if args.interval.is_some() {
            // Given an interval, any file is a snapshot in name order (CSV tables included);
            // one that does not read is skipped with its reason.
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
                sequence: 0,
            }));
        }
        None if path.is_file() && unplaced.len() == 1 => {
            placed.extend(unplaced.into_iter().map(|path| Placed {
                path,
                seconds: 0.0,
                sequence: 0,
            }));
        }
        None => skipped.extend(unplaced.into_iter().map(|f| SkippedFile {
            file: file_label(&f),
            error: format!(
                "{}: its name states no time (bearingd logs are named bearingd-YYYYMMDDTHHMMSSZ-NNNNNN.mcap, IMS snapshots YYYY.MM.DD.hh.mm.ss, PRONOSTIA ones acc_NNNNN.csv); give --interval SECONDS to place such files in name order",
                f.display()
            ),
        })),
    }
    // Logs by their anchor, then their place in the run: not by name (a log's name is the
    // time it was opened, in sample time for `run --fast`).
    placed.sort_by(|a, b| {
        a.seconds
            .total_cmp(&b.seconds)
            .then(a.sequence.cmp(&b.sequence))
            .then(a.path.cmp(&b.path))
    });
    Ok(Listing {
        placed,
        skipped,
        ignored,
    })
}

/// A bearingd log's wall-clock anchor (s since the epoch of its sample 0,
/// `log_time_origin_ns`) and its sequence in its run; `None` for other files and for logs
/// that state no anchor (placed by their name).
fn log_anchor(path: &Path) -> Option<(f64, u64)> {
    if !is_mcap(path) {
        return None;
    }
    let header = read_header(path).ok()?;
    let origin_ns = header.origin_ns?;
    Some((origin_ns as f64 / 1e9, header.sequence.unwrap_or_default()))
}

fn is_mcap(path: &Path) -> bool {
    has_extension(path, "mcap")
}

fn has_extension(path: &Path, extension: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
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
    let mut gaps = report.gaps.iter().peekable();
    for p in &report.points {
        while let Some(gap) = gaps.next_if(|g| g.to_s <= p.time_s) {
            out.push_str(&format!(
                "| (gap) | {:.1} to {:.1} | | | | | | no samples for {} |\n",
                gap.from_s,
                gap.to_s,
                crate::report::duration_text(gap.to_s - gap.from_s)
            ));
        }
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

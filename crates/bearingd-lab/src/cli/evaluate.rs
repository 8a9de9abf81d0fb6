//! `bearingd-lab evaluate`: sweep the simulator through the real pipeline and report how well the
//! detector does; with `--recordings`, real recordings of a manifest through `analyze` and
//! through the daemon's replay; with `--false-alarm-hours`, hours of healthy signal through the
//! daemon's channel monitor (see `crate::evaluate` and docs/DIAGNOSIS.md).

use super::progress::Progress;
use crate::evaluate::false_alarms::{
    render_false_alarms, stream_run, summarize_false_alarms, FalseAlarmPlan, FalseAlarmSummary,
    RunResult,
};
use crate::evaluate::recordings::{
    evaluate_recordings, plan, render_recordings, tally, Entry, Manifest, RecordingsAgreement,
    RecordingsOptions, RecordingsReport, Said,
};
use crate::evaluate::{
    in_order, pd_figure, render_csv, render_tables, run_sweep, summarize, Bench,
    Path as JudgedPath, Summary, Sweep,
};
use crate::twin::Nuisance;
use bearingd::cli::format::FormatArg;
use bearingd::cli::CliError;
use clap::Args;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct EvaluateArgs {
    /// Instead of the simulator: every record of this manifest (CSV with a header: `file`
    /// relative to its folder, and `fault`, `note` or `life_frac` for the truth; `channel_var`,
    /// `fs_hz`, `rpm`, `bearing_geometry` where the file does not say) through `bearingd analyze` and through
    /// `bearingd import` + `replay`; writes recordings.json. May be given several times.
    #[arg(long, value_name = "MANIFEST", conflicts_with_all = ["quick", "no_nuisance"])]
    recordings: Vec<PathBuf>,
    /// Instead of the sweep: H hours of healthy simulated signal per machine (the full sweep's
    /// three machines at 0.6 and 1 × nominal speed, four noise levels, with the nuisance)
    /// streamed through the daemon's channel monitor; counts the fault flags that rise (false
    /// alarms) per hour of operation; writes false_alarms.json and false_alarms.txt. Without
    /// a value: 2 h per machine (about 2.5 min of CPU).
    #[arg(
        long,
        value_name = "H",
        num_args = 0..=1,
        default_missing_value = "2",
        conflicts_with_all = ["recordings", "quick"]
    )]
    false_alarm_hours: Option<f64>,
    /// With --recordings: also the other channels of each record (CWRU fan end and base,
    /// every axis of other files; IMS snapshots are always evaluated on all eight).
    #[arg(long, requires = "recordings")]
    all_channels: bool,
    /// With --recordings: exit 1 if any answer is confident and wrong, the paths disagree on
    /// any record, or any record fails (CI).
    #[arg(long, requires = "recordings")]
    strict: bool,
    /// The small sweep CI runs (both bearings at nominal speed, default severity, the
    /// simulator's default noise and 0 dB SNR, healthy records) instead of the full one.
    #[arg(long)]
    quick: bool,
    /// Directory for results.json, results.csv, table.txt and pd_vs_snr.svg (with
    /// --recordings: recordings.json and recordings.txt) (created).
    #[arg(long, default_value = "evaluate-results")]
    out: PathBuf,
    /// Seed of the sweep: the same seed gives the same records and results.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (default: the machine's cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Take the analysis and threshold settings from this config file instead of the
    /// embedded default (to evaluate a tuned configuration). With `twin.learned_model` the
    /// sweep's record path also writes agreement_grid.txt (the learned model's agreement
    /// decided at every point of a parameter grid); with --recordings only its agreement_*
    /// keys and model are used, by both paths.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Leave out the machine's nuisance (shaft harmonics, modulated noise, random impulses,
    /// gear and electrical tones): bearing, 1× tone and white noise only.
    #[arg(long)]
    no_nuisance: bool,
    // With json, the summary and the files written as one JSON document on stdout instead of
    // the tables.
    #[command(flatten)]
    format: FormatArg,
}

/// What results.json holds.
#[derive(Serialize)]
struct ResultsFile<'a> {
    sweep: &'a Sweep,
    summary: &'a Summary,
    runs: &'a [crate::evaluate::CaseResult],
}

pub fn run(args: &EvaluateArgs) -> Result<(), CliError> {
    if !args.recordings.is_empty() {
        return run_recordings(args);
    }
    let bench = bench(args)?;
    if let Some(hours) = args.false_alarm_hours {
        return run_false_alarms(args, &bench, hours);
    }
    let mut sweep = if args.quick {
        Sweep::quick(args.seed)
    } else {
        Sweep::full(args.seed)
    };
    if args.no_nuisance {
        sweep.nuisance = Nuisance::none();
    }
    create_out(&args.out)?;
    let threads = threads(args)?;

    let total = sweep.cases().len();
    eprintln!(
        "evaluate: {} sweep, {total} simulated records ({} s each), seed {}, {threads} threads",
        sweep.name, sweep.monitor_s, sweep.seed
    );
    let started = Instant::now();
    let progress = Progress::start("evaluate", "runs", total as u64);
    let step = |done: usize, _total: usize| progress.set(done as u64, "");
    let results = run_sweep(&bench, &sweep, threads, &step);
    progress.finish("");
    let summary = summarize(&results);
    let tables = render_tables(&summary);
    let text = !args.format.json();
    if text {
        print!("{tables}");
    }

    let write = |name: &str, bytes: &[u8]| write_out(&args.out, name, bytes);
    let json = serde_json::to_vec_pretty(&ResultsFile {
        sweep: &sweep,
        summary: &summary,
        runs: &results,
    })
    .map_err(|e| CliError::failure(format!("cannot encode the results as JSON: {e}")))?;
    let mut written = vec![
        write("results.json", &json)?,
        write("results.csv", render_csv(&results).as_bytes())?,
        write("table.txt", tables.as_bytes())?,
    ];
    if bench.witness.is_some() {
        let grid = crate::evaluate::agreement::render(&results);
        if text {
            print!("\n{grid}");
        }
        written.push(write("agreement_grid.txt", grid.as_bytes())?);
    }
    let plot_path = args.out.join("pd_vs_snr.svg");
    crate::plot::save(&pd_figure(&summary, &sweep.name), &plot_path)
        .map_err(|e| CliError::failure(e.to_string()))?;
    if !text {
        written.push(plot_path);
        return print_json(&sweep.name, &summary, started, &written);
    }
    eprintln!(
        "evaluate: {} runs in {:.1} s; wrote {}, {}",
        results.len(),
        started.elapsed().as_secs_f64(),
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        display(&plot_path)
    );
    Ok(())
}

/// The embedded default config, or `--config`'s.
fn bench(args: &EvaluateArgs) -> Result<Bench, CliError> {
    match &args.config {
        Some(path) => {
            Bench::new(crate::config::load(path).map_err(CliError::input)?).map_err(CliError::input)
        }
        None => Bench::embedded().map_err(CliError::failure),
    }
}

/// `evaluate --format json`: what the tables say, as one JSON document on stdout.
fn print_json(
    kind: &str,
    summary: &impl Serialize,
    started: Instant,
    written: &[PathBuf],
) -> Result<(), CliError> {
    let json = serde_json::json!({
        "evaluation": kind,
        "seconds": started.elapsed().as_secs_f64(),
        "summary": summary,
        "written": written,
    });
    println!("{json}");
    Ok(())
}

/// What false_alarms.json holds.
#[derive(Serialize)]
struct FalseAlarmsFile<'a> {
    plan: &'a FalseAlarmPlan,
    summary: &'a FalseAlarmSummary,
    /// CPU time of the whole process (every thread), s; `None` if it cannot be read.
    cpu_s: Option<f64>,
    wall_s: f64,
    runs: &'a [RunResult],
}

/// `evaluate --false-alarm-hours H`: hours of healthy signal through the monitor path.
fn run_false_alarms(args: &EvaluateArgs, bench: &Bench, hours: f64) -> Result<(), CliError> {
    if !(hours.is_finite() && hours > 0.0 && hours <= 10_000.0) {
        return Err(CliError::input(format!(
            "--false-alarm-hours {hours}: give the hours of healthy signal per machine, above 0 \
             and at most 10000, e.g. --false-alarm-hours 2"
        )));
    }
    let mut plan = FalseAlarmPlan::new(hours, args.seed);
    if args.no_nuisance {
        plan.nuisance = Nuisance::none();
    }
    create_out(&args.out)?;
    let threads = threads(args)?;
    let runs = plan.runs();
    eprintln!(
        "evaluate: false alarms, {hours} h of healthy signal on each of {} machines ({:.1} h in \
         {} runs of {:.0} s), seed {}, {threads} threads",
        plan.machines.len(),
        plan.total_hours(),
        runs.len(),
        runs.first().map_or(0.0, |r| r.seconds),
        plan.seed
    );
    let started = Instant::now();
    let cpu_at_start = process_cpu_s();
    let bar = Progress::start("evaluate", "runs", runs.len() as u64);
    let simulated = std::sync::Mutex::new((0.0f64, 0usize));
    let progress = |done: usize, _total: usize, result: &RunResult| {
        let (hours, rises) = {
            let mut seen = simulated.lock().unwrap_or_else(|e| e.into_inner());
            seen.0 += result.run.seconds / 3600.0;
            seen.1 += result.rises.len();
            *seen
        };
        bar.set(
            done as u64,
            &format!("{hours:.1} h simulated, {rises} flag rise(s)"),
        );
    };
    let results = in_order(
        &runs,
        threads,
        || (),
        |(), run| stream_run(bench, &plan, run),
        &progress,
    );
    bar.finish("");
    let wall_s = started.elapsed().as_secs_f64();
    let cpu_s = process_cpu_s()
        .zip(cpu_at_start)
        .map(|(end, start)| end - start);
    let summary = summarize_false_alarms(&results);
    let mut table = render_false_alarms(&summary);
    let _ = writeln!(
        table,
        "{:.1} h simulated in {wall_s:.0} s of wall time{}",
        summary.all.hours,
        cpu_s.map_or(String::new(), |cpu| format!(
            ", {cpu:.0} s of CPU: {:.1} simulated h per CPU minute",
            summary.all.hours / (cpu / 60.0).max(1e-9)
        ))
    );
    if !args.format.json() {
        print!("{table}");
    }
    let json = serde_json::to_vec_pretty(&FalseAlarmsFile {
        plan: &plan,
        summary: &summary,
        cpu_s,
        wall_s,
        runs: &results,
    })
    .map_err(|e| CliError::failure(format!("cannot encode the results as JSON: {e}")))?;
    let written = [
        write_out(&args.out, "false_alarms.json", &json)?,
        write_out(&args.out, "false_alarms.txt", table.as_bytes())?,
    ];
    if args.format.json() {
        return print_json("false alarms", &summary, started, &written);
    }
    eprintln!(
        "evaluate: wrote {} and {}",
        display(&written[0]),
        display(&written[1])
    );
    Ok(())
}

/// CPU time used so far by the whole process (every thread, user and system), s.
fn process_cpu_s() -> Option<f64> {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::uninit();
    // SAFETY: getrusage writes the struct it is given before returning 0; it is read only
    // then.
    #[allow(unsafe_code)]
    let usage = unsafe {
        if libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) != 0 {
            return None;
        }
        usage.assume_init()
    };
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Some(seconds(usage.ru_utime) + seconds(usage.ru_stime))
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

fn create_out(out: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(out).map_err(|e| {
        CliError::input(format!(
            "{}: cannot create the output directory: {e}; give a writable --out DIR",
            out.display()
        ))
    })
}

fn write_out(out: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf, CliError> {
    let path = out.join(name);
    std::fs::write(&path, bytes)
        .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", path.display())))?;
    Ok(path)
}

fn threads(args: &EvaluateArgs) -> Result<usize, CliError> {
    match args.jobs {
        Some(0) => Err(CliError::input(
            "--jobs 0: give at least one thread, e.g. --jobs 2",
        )),
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)),
    }
}

/// `evaluate --recordings`: every record of the manifests through both paths.
fn run_recordings(args: &EvaluateArgs) -> Result<(), CliError> {
    let manifests = args
        .recordings
        .iter()
        .map(|path| Manifest::read(path).map_err(CliError::input))
        .collect::<Result<Vec<_>, _>>()?;
    create_out(&args.out)?;
    let agreement = match &args.config {
        Some(path) => RecordingsAgreement::of(&crate::config::load(path).map_err(CliError::input)?)
            .map_err(CliError::input)?,
        None => None,
    };
    let options = RecordingsOptions {
        all_channels: args.all_channels,
        jobs: threads(args)?,
        scratch: args.out.clone(),
        agreement,
    };
    let tasks = plan(&manifests, options.all_channels);
    eprintln!(
        "evaluate: {} records of {} manifest(s), {} record·channel runs{}, {} threads",
        manifests.iter().map(|m| m.records.len()).sum::<usize>(),
        manifests.len(),
        tasks.len(),
        if args.all_channels {
            " (all channels)"
        } else {
            ""
        },
        options.jobs
    );
    let started = Instant::now();
    let bar = Progress::start("evaluate", "record·channel runs", tasks.len() as u64);
    let progress = |done: usize, _total: usize, entry: &Entry| {
        let said = |path| Said::of(path, entry).name();
        let line = format!(
            "{}: analyze {}, daemon {}",
            entry.label(),
            said(JudgedPath::Record),
            said(JudgedPath::Monitor)
        );
        bar.set(done as u64, &line);
    };
    let entries = evaluate_recordings(&tasks, &options, &progress);
    bar.finish("");
    let counted = tally(&entries);
    let table = render_recordings(&counted);
    if !args.format.json() {
        print!("{table}");
    }
    let json = RecordingsReport {
        manifests: &args.recordings,
        all_channels: args.all_channels,
        summary: &counted,
        entries: &entries,
    }
    .json()
    .map_err(|e| CliError::failure(format!("cannot encode the results as JSON: {e}")))?;
    let written = [
        write_out(&args.out, "recordings.json", &json)?,
        write_out(&args.out, "recordings.txt", table.as_bytes())?,
    ];
    if args.format.json() {
        print_json("recordings", &counted, started, &written)?;
    } else {
        eprintln!(
            "evaluate: {} record·channel runs in {:.1} s; wrote {} and {}",
            entries.len(),
            started.elapsed().as_secs_f64(),
            display(&written[0]),
            display(&written[1])
        );
    }
    if args.strict && counted.problems() > 0 {
        return Err(CliError::failure(format!(
            "--strict: {} confident-wrong answer(s) (analyze {}, daemon {}), {} disagreement(s), \
             {} failed record(s)",
            counted.record.confident_wrong + counted.daemon.confident_wrong,
            counted.record.confident_wrong,
            counted.daemon.confident_wrong,
            counted.disagreements.len(),
            counted.failures.len()
        )));
    }
    Ok(())
}

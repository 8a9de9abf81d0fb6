//! `bearingd evaluate`: sweep the simulator through the real pipeline and report how well the
//! detector does; with `--recordings`, real recordings of a manifest through `analyze` and
//! through the daemon's replay (see `crate::evaluate` and docs/DIAGNOSIS.md).

use super::CliError;
use crate::evaluate::recordings::{
    evaluate_recordings, plan, render_recordings, tally, Entry, Manifest, RecordingsOptions,
    RecordingsReport, Said,
};
use crate::evaluate::{
    pd_figure, render_csv, render_tables, run_sweep, summarize, Bench, Path as JudgedPath, Summary,
    Sweep,
};
use crate::twin::Nuisance;
use clap::Args;
use serde::Serialize;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct EvaluateArgs {
    /// Instead of the simulator: every record of this manifest (CSV with a header: `file`
    /// relative to its folder, and `fault`, `note` or `life_frac` for the truth; `channel_var`,
    /// `fs_hz`, `rpm` where the file does not say) through `bearingd analyze` and through
    /// `bearingd import` + `replay`; writes recordings.json. May be given several times.
    #[arg(long, value_name = "MANIFEST", conflicts_with_all = ["quick", "config", "no_nuisance"])]
    recordings: Vec<PathBuf>,
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
    /// embedded default (to evaluate a tuned configuration).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Leave out the machine's nuisance (shaft harmonics, modulated noise, random impulses,
    /// gear and electrical tones): bearing, 1× tone and white noise only.
    #[arg(long)]
    no_nuisance: bool,
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
    let bench = match &args.config {
        Some(path) => Bench {
            config: crate::config::load(path).map_err(CliError::input)?,
        },
        None => Bench::embedded().map_err(CliError::failure)?,
    };
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
    let terminal = std::io::stderr().is_terminal();
    let progress = |done: usize, total: usize| {
        let elapsed = started.elapsed().as_secs_f64();
        if terminal {
            let left = elapsed / done as f64 * (total - done) as f64;
            eprint!(
                "\revaluate: {done}/{total} runs ({:.0} %), {elapsed:.0} s, ~{left:.0} s left   ",
                100.0 * done as f64 / total as f64
            );
            let _ = std::io::stderr().flush();
        } else if done == total || (done * 4 / total) != ((done - 1) * 4 / total) {
            eprintln!("evaluate: {done}/{total} runs, {elapsed:.0} s");
        }
    };
    let results = run_sweep(&bench, &sweep, threads, &progress);
    if terminal {
        eprintln!();
    }
    let summary = summarize(&results);
    let tables = render_tables(&summary);
    print!("{tables}");

    let write = |name: &str, bytes: &[u8]| write_out(&args.out, name, bytes);
    let json = serde_json::to_vec_pretty(&ResultsFile {
        sweep: &sweep,
        summary: &summary,
        runs: &results,
    })
    .map_err(|e| CliError::failure(format!("cannot encode the results as JSON: {e}")))?;
    let written = [
        write("results.json", &json)?,
        write("results.csv", render_csv(&results).as_bytes())?,
        write("table.txt", tables.as_bytes())?,
    ];
    let plot_path = args.out.join("pd_vs_snr.svg");
    crate::plot::save(&pd_figure(&summary, &sweep.name), &plot_path)
        .map_err(|e| CliError::failure(e.to_string()))?;
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
    let options = RecordingsOptions {
        all_channels: args.all_channels,
        jobs: threads(args)?,
        scratch: args.out.clone(),
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
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(tasks.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "evaluate {bar:20} {pos}/{len} ({eta}) {wide_msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let progress = |done: usize, total: usize, entry: &Entry| {
        let said = |path| Said::of(path, entry).name();
        let line = format!(
            "{}: analyze {}, daemon {}",
            entry.label(),
            said(JudgedPath::Record),
            said(JudgedPath::Monitor)
        );
        match &bar {
            Some(bar) => {
                bar.set_position(done as u64);
                bar.set_message(line);
            }
            None => eprintln!("evaluate: {done}/{total} {line}"),
        }
    };
    let entries = evaluate_recordings(&tasks, &options, &progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let counted = tally(&entries);
    let table = render_recordings(&counted);
    print!("{table}");
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
    eprintln!(
        "evaluate: {} record·channel runs in {:.1} s; wrote {} and {}",
        entries.len(),
        started.elapsed().as_secs_f64(),
        display(&written[0]),
        display(&written[1])
    );
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

//! `bearingd evaluate`: sweep the simulator through the real pipeline and report how well the
//! detector does (see `crate::evaluate` and docs/DIAGNOSIS.md).

use super::CliError;
use crate::evaluate::{
    pd_figure, render_csv, render_tables, run_sweep, summarize, Bench, Summary, Sweep,
};
use crate::twin::Nuisance;
use clap::Args;
use serde::Serialize;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct EvaluateArgs {
    /// The small sweep CI runs (both bearings at nominal speed, default severity, the
    /// simulator's default noise and 0 dB SNR, healthy records) instead of the full one.
    #[arg(long)]
    quick: bool,
    /// Directory for results.json, results.csv, table.txt and pd_vs_snr.svg (created).
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
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::input(format!(
            "{}: cannot create the output directory: {e}; give a writable --out DIR",
            args.out.display()
        ))
    })?;
    let threads = args.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    if threads == 0 {
        return Err(CliError::input(
            "--jobs 0: give at least one thread, e.g. --jobs 2",
        ));
    }

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

    let write = |name: &str, bytes: &[u8]| -> Result<PathBuf, CliError> {
        let path = args.out.join(name);
        std::fs::write(&path, bytes)
            .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", path.display())))?;
        Ok(path)
    };
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

//! `bearingd analyze --hw FILE...`: the Hammerstein–Wiener model of seed 003 identified on each
//! record for the state orders 0…9, its accuracy and identification time per order, and per
//! directory (one bearing) the mean over its records: the layout of the seed's Table A1, for
//! comparison with the seed's numbers (docs/HW.md).
//!
//! The identification itself is sans-IO (`twin::hw`); the clock that times it lives here.

use super::{CliError, RecordingArgs};
use crate::recording::read_recording;
use crate::twin::hw::{identify_record, HwConfig, StateFilter};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// State orders of the seed's tables.
const ORDERS: std::ops::RangeInclusive<usize> = 0..=9;

/// One record: per order, (simulation accuracy %, one-step accuracy %, milliseconds,
/// simulation accuracy from rest %).
type RecordResult = Vec<(f64, f64, f64, f64)>;

pub fn run(
    files: &[PathBuf],
    recording: &RecordingArgs,
    states: StateFilter,
) -> Result<(), CliError> {
    let mut by_bearing: BTreeMap<String, Vec<RecordResult>> = BTreeMap::new();
    let mut failures = 0;
    println!(
        "| record | {} |",
        ORDERS
            .map(|n| format!("n={n}"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    println!("|---|{}", "---|".repeat(ORDERS.count()));
    for (done, file) in files.iter().enumerate() {
        match record(file, recording, states) {
            Ok(result) => {
                println!(
                    "| {} | {} |",
                    file.display(),
                    result
                        .iter()
                        .map(|(sim, _, ms, _)| format!("{sim:.1} % {ms:.0} ms"))
                        .collect::<Vec<_>>()
                        .join(" | ")
                );
                by_bearing.entry(bearing_of(file)).or_default().push(result);
            }
            Err(error) => {
                failures += 1;
                eprintln!("bearingd: error: {error}");
            }
        }
        eprint!("\r{}/{} records", done + 1, files.len());
    }
    eprintln!();
    println!();
    println!("Virtual states: median filter {}.", states.name());
    println!();
    println!("Mean per bearing (simulation accuracy 100·(1 − NRMSE) % from the estimated initial state, as MATLAB's compare; one-step in brackets; the mean from rest; mean identification time):");
    println!();
    println!(
        "| bearing | records | {} | mean | mean from rest | ms per identification |",
        ORDERS
            .map(|n| format!("n={n}"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    println!("|---|---|{}---|---|---|", "---|".repeat(ORDERS.count()));
    for (bearing, results) in &by_bearing {
        let count = results.len() as f64;
        let mean_of = |n: usize, pick: fn(&(f64, f64, f64, f64)) -> f64| {
            results.iter().map(|r| pick(&r[n])).sum::<f64>() / count
        };
        let cells: Vec<String> = ORDERS
            .map(|n| format!("{:.1} ({:.1})", mean_of(n, |r| r.0), mean_of(n, |r| r.1)))
            .collect();
        let overall = ORDERS.map(|n| mean_of(n, |r| r.0)).sum::<f64>() / ORDERS.count() as f64;
        let from_rest = ORDERS.map(|n| mean_of(n, |r| r.3)).sum::<f64>() / ORDERS.count() as f64;
        let ms = ORDERS.map(|n| mean_of(n, |r| r.2)).sum::<f64>() / ORDERS.count() as f64;
        println!(
            "| {bearing} | {} | {} | {overall:.1} | {from_rest:.1} | {ms:.0} |",
            results.len(),
            cells.join(" | ")
        );
    }
    match failures {
        0 => Ok(()),
        n => Err(CliError::input(format!(
            "{n} of {} recordings could not be identified (see above)",
            files.len()
        ))),
    }
}

/// Identifies every order on one record, timing each identification.
fn record(file: &Path, args: &RecordingArgs, states: StateFilter) -> Result<RecordResult, String> {
    let recording = read_recording(file, &args.read_options()).map_err(|e| e.to_string())?;
    let fs_hz = args.fs.or(recording.fs_hz).ok_or_else(|| {
        format!(
            "{}: the file does not state its sample rate; give it with --fs HZ",
            file.display()
        )
    })?;
    ORDERS
        .map(|order| {
            let started = Instant::now();
            let config = HwConfig {
                states,
                ..HwConfig::for_order(order)
            };
            let fit = identify_record(&recording.samples, fs_hz, &config, None)
                .map_err(|e| format!("{}: order {order}: {e}", file.display()))?;
            let ms = started.elapsed().as_secs_f64() * 1e3;
            Ok((
                fit.accuracy.simulation,
                fit.accuracy.one_step,
                ms,
                fit.accuracy.simulation_zero_state,
            ))
        })
        .collect()
}

/// The directory a record lies in (one bearing for FEMTO), else the file itself.
fn bearing_of(file: &Path) -> String {
    file.parent().and_then(|p| p.file_name()).map_or_else(
        || file.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

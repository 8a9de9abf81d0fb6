//! `bearingd analyze --hw FILE...`: the Hammerstein–Wiener model of seed 003 identified on each
//! record for the state orders 0…9, its accuracy and identification time per order, and per
//! directory (one bearing) the mean over its records: the layout of the seed's Table A1, for
//! comparison with the seed's numbers (docs/HW.md).
//!
//! The identification itself is sans-IO (`twin::hw`); the clock that times it lives here.

use super::{CliError, RecordingArgs};
use crate::recording::read_recording;
use crate::twin::hw::{identify_record, HwConfig, StateFilter};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// State orders of the seed's tables.
const ORDERS: std::ops::RangeInclusive<usize> = 0..=9;

/// One identification: one record at one state order.
#[derive(Debug, Clone, Copy, Serialize)]
struct OrderResult {
    order: usize,
    /// 100·(1 − NRMSE) % of the simulation from the estimated initial state.
    simulation_accuracy_pct: f64,
    one_step_accuracy_pct: f64,
    /// The simulation's accuracy from rest (zero initial state), for comparison.
    simulation_accuracy_from_rest_pct: f64,
    identification_ms: f64,
}

#[derive(Debug, Serialize)]
struct RecordResult {
    file: PathBuf,
    /// The directory the record lies in (one bearing for FEMTO).
    bearing: String,
    orders: Vec<OrderResult>,
}

/// Per bearing, the means over its records.
#[derive(Debug, Serialize)]
struct BearingMeans {
    bearing: String,
    records: usize,
    /// Per order: the mean simulation and one-step accuracies.
    orders: Vec<OrderResult>,
    /// Over every order.
    simulation_accuracy_pct: f64,
    simulation_accuracy_from_rest_pct: f64,
    identification_ms: f64,
}

/// What `--format json` prints.
#[derive(Debug, Serialize)]
struct HwTable {
    /// Where the median filter of the virtual states sits.
    states: &'static str,
    records: Vec<RecordResult>,
    bearings: Vec<BearingMeans>,
    /// The records that could not be identified, each with why.
    failures: Vec<String>,
}

/// The Markdown tables (`--format text` and `table`), or with `json` one document with the
/// same numbers. Progress goes to stderr: redrawn in place on a terminal, one line per record in a
/// pipe.
pub fn run(
    files: &[PathBuf],
    recording: &RecordingArgs,
    states: StateFilter,
    json: bool,
) -> Result<(), CliError> {
    let terminal = std::io::stderr().is_terminal();
    let mut records = Vec::new();
    let mut failures = Vec::new();
    for (done, file) in files.iter().enumerate() {
        match record(file, recording, states) {
            Ok(orders) => records.push(RecordResult {
                file: file.clone(),
                bearing: bearing_of(file),
                orders,
            }),
            Err(error) => {
                if terminal {
                    eprintln!();
                }
                eprintln!("bearingd: error: {error}");
                failures.push(error);
            }
        }
        let line = format!("analyze --hw: {}/{} records", done + 1, files.len());
        if terminal {
            eprint!("\r{line}");
        } else {
            eprintln!("{line} ({})", file.display());
        }
    }
    if terminal {
        eprintln!();
    }
    let table = HwTable {
        states: states.name(),
        bearings: means_per_bearing(&records),
        records,
        failures,
    };
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&table).map_err(CliError::input)?
        );
    } else {
        print_markdown(&table);
    }
    match table.failures.len() {
        0 => Ok(()),
        n => Err(CliError::input(format!(
            "{n} of {} recordings could not be identified (see above)",
            files.len()
        ))),
    }
}

fn means_per_bearing(records: &[RecordResult]) -> Vec<BearingMeans> {
    let mut by_bearing: BTreeMap<&str, Vec<&RecordResult>> = BTreeMap::new();
    for r in records {
        by_bearing.entry(&r.bearing).or_default().push(r);
    }
    by_bearing
        .into_iter()
        .map(|(bearing, results)| {
            let count = results.len() as f64;
            let orders: Vec<OrderResult> = ORDERS
                .map(|n| {
                    let mean = |pick: fn(&OrderResult) -> f64| {
                        results.iter().map(|r| pick(&r.orders[n])).sum::<f64>() / count
                    };
                    OrderResult {
                        order: n,
                        simulation_accuracy_pct: mean(|o| o.simulation_accuracy_pct),
                        one_step_accuracy_pct: mean(|o| o.one_step_accuracy_pct),
                        simulation_accuracy_from_rest_pct: mean(|o| {
                            o.simulation_accuracy_from_rest_pct
                        }),
                        identification_ms: mean(|o| o.identification_ms),
                    }
                })
                .collect();
            let over_orders = |pick: fn(&OrderResult) -> f64| {
                orders.iter().map(pick).sum::<f64>() / orders.len() as f64
            };
            BearingMeans {
                bearing: bearing.to_string(),
                records: results.len(),
                simulation_accuracy_pct: over_orders(|o| o.simulation_accuracy_pct),
                simulation_accuracy_from_rest_pct: over_orders(|o| {
                    o.simulation_accuracy_from_rest_pct
                }),
                identification_ms: over_orders(|o| o.identification_ms),
                orders,
            }
        })
        .collect()
}

/// The layout of the seed's Table A1: a row per record, then the means per bearing.
fn print_markdown(table: &HwTable) {
    let order_columns = ORDERS
        .map(|n| format!("n={n}"))
        .collect::<Vec<_>>()
        .join(" | ");
    println!("| record | {order_columns} |");
    println!("|---|{}", "---|".repeat(ORDERS.count()));
    for r in &table.records {
        println!(
            "| {} | {} |",
            r.file.display(),
            r.orders
                .iter()
                .map(|o| format!(
                    "{:.1} % {:.0} ms",
                    o.simulation_accuracy_pct, o.identification_ms
                ))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    println!();
    println!("Virtual states: median filter {}.", table.states);
    println!();
    println!("Mean per bearing (simulation accuracy 100·(1 − NRMSE) % from the estimated initial state, as MATLAB's compare; one-step in brackets; the mean from rest; mean identification time):");
    println!();
    println!(
        "| bearing | records | {order_columns} | mean | mean from rest | ms per identification |"
    );
    println!("|---|---|{}---|---|---|", "---|".repeat(ORDERS.count()));
    for b in &table.bearings {
        let cells: Vec<String> = b
            .orders
            .iter()
            .map(|o| {
                format!(
                    "{:.1} ({:.1})",
                    o.simulation_accuracy_pct, o.one_step_accuracy_pct
                )
            })
            .collect();
        println!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.0} |",
            b.bearing,
            b.records,
            cells.join(" | "),
            b.simulation_accuracy_pct,
            b.simulation_accuracy_from_rest_pct,
            b.identification_ms
        );
    }
}

/// Identifies every order on one record, timing each identification.
fn record(
    file: &Path,
    args: &RecordingArgs,
    states: StateFilter,
) -> Result<Vec<OrderResult>, String> {
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
            Ok(OrderResult {
                order,
                simulation_accuracy_pct: fit.accuracy.simulation,
                one_step_accuracy_pct: fit.accuracy.one_step,
                simulation_accuracy_from_rest_pct: fit.accuracy.simulation_zero_state,
                identification_ms: ms,
            })
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

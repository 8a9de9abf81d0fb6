//! The defect-size estimator over the physics twin's full grid (docs/DIAGNOSIS.md §5):
//! outer and inner race, widths 0.1–1 mm, 1200 and 1797 rpm, 500 and 2000 N, resonance 3 and
//! 15 kHz, 48 kHz, 2 s per record; one table per noise level.
//!
//!     cargo run --release -p bearingd-lab --example defect_size_grid            # noise 0.05 g and 0.2 g
//!     cargo run --release -p bearingd-lab --example defect_size_grid -- 0.1      # another noise level, g
//!
//! Prints a Markdown table (true width, estimate ± uncertainty or why none, the verdict) and
//! the summary; the time to simulate and size the records is measured here, outside the
//! library (the library has no clock).

use bearingd::analysis::defect_size::NotMeasured;
use bearingd::bearing::FaultKind;
use bearingd_lab::twin::defect_size::{full_grid, summarize, SizingOutcome, WIDTHS_MM};
use rayon::prelude::*;
use std::time::Instant;

fn cell(outcome: &SizingOutcome) -> String {
    let named = if outcome.named() { "" } else { " †" };
    match (&outcome.size, outcome.relative_error()) {
        (Ok(size), Some(error)) => format!(
            "{:.2} ± {:.2} ({:+.0} %){named}",
            size.value_mm,
            size.uncertainty_mm,
            100.0 * error
        ),
        _ => format!("—{named}"),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let noises: Vec<f64> = match std::env::args().skip(1).map(|a| a.parse()).collect() {
        Ok(list) if !Vec::is_empty(&list) => list,
        Ok(_) => vec![0.05, 0.2],
        Err(e) => return Err(format!("give noise levels in g, e.g. 0.05 0.2: {e}").into()),
    };
    for noise in noises {
        let cases = full_grid(noise);
        let started = Instant::now();
        let outcomes: Vec<SizingOutcome> = cases
            .par_iter()
            .map(|case| case.run())
            .collect::<Result<_, _>>()?;
        let wall = started.elapsed().as_secs_f64();
        println!(
            "\n### Noise {noise} g ({} records, {wall:.1} s wall on {} threads)\n",
            cases.len(),
            rayon::current_num_threads()
        );
        let header: Vec<String> = WIDTHS_MM.iter().map(|w| format!("{w} mm")).collect();
        println!("| race | resonance | rpm | load | {} |", header.join(" | "));
        println!("|---|---|---|---|{}", "---|".repeat(WIDTHS_MM.len()));
        for row in outcomes.chunks(WIDTHS_MM.len()) {
            let c = row[0].case;
            let race = if c.fault == FaultKind::OuterRace {
                "outer"
            } else {
                "inner"
            };
            let cells: Vec<String> = row.iter().map(cell).collect();
            println!(
                "| {race} | {:.0} kHz | {:.0} | {:.0} N | {} |",
                c.resonance_hz / 1e3,
                c.rpm,
                c.load_n,
                cells.join(" | ")
            );
        }
        let s = summarize(&outcomes);
        println!(
            "\nsized {} of {}; |error| max {:.0} %, mean {:.1} %; within 2σ: {} of {}",
            s.sized,
            s.cases,
            100.0 * s.max_abs_error,
            100.0 * s.mean_abs_error,
            s.within_two_sigma,
            s.sized
        );
        for width in WIDTHS_MM {
            let of_width: Vec<SizingOutcome> = outcomes
                .iter()
                .filter(|o| o.case.width_mm == width)
                .cloned()
                .collect();
            let s = summarize(&of_width);
            println!(
                "  {width} mm: sized {} of {}, |error| max {:.0} %, mean {:.1} %",
                s.sized,
                s.cases,
                100.0 * s.max_abs_error,
                100.0 * s.mean_abs_error
            );
        }
        let mut reasons: std::collections::BTreeMap<String, usize> = Default::default();
        for why in outcomes.iter().filter_map(|o| o.size.as_ref().err()) {
            let text = match why {
                NotMeasured::NotResolved(detail) => detail.clone(),
                other => other.to_string(),
            };
            let short = text
                .split(['(', ':'])
                .next()
                .unwrap_or_default()
                .trim()
                .to_string();
            *reasons.entry(short).or_default() += 1;
        }
        let reasons: Vec<String> = reasons
            .iter()
            .map(|(why, n)| format!("{why} ({n})"))
            .collect();
        println!("  why none: {}", reasons.join("; "));
        let named = outcomes
            .iter()
            .filter(|o| o.size.is_ok() && o.named())
            .count();
        println!(
            "  sized and named by the verdict (what analyze reports): {named} of {}",
            s.sized
        );
        println!("  † the verdict does not name the simulated fault: analyze would report no size");
    }
    Ok(())
}

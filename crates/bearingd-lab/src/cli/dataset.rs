//! `bearingd dataset --spec FILE --out DIR`: a labelled synthetic data set for learned
//! diagnosis (see [`crate::twin::dataset`]): `dataset.npz` (NumPy: `x` records × samples in
//! g, `y` labels, and the drawn conditions), `manifest.csv` (one row per record, with its class
//! name), a copy of the spec, and with `--mcap` each record as a self-describing raw MCAP log
//! that `bearingd replay` reads as the daemon's own. Records are made on all cores, with
//! progress on stderr ([`Progress`]).

use super::progress::Progress;
use crate::sinks::mcap::raw_log::{write_raw_log, LogSignal, RawLog};
use crate::twin::dataset::{DatasetRecord, DatasetSpec};
use bearingd::cli::format::FormatArg;
use bearingd::cli::import::raw_log_error;
use bearingd::cli::CliError;
use clap::Args;
use ndarray::{Array1, Array2};
use rayon::prelude::*;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct DatasetArgs {
    /// The spec (TOML): faults, records per fault, model and ranges; an example with every
    /// key: config/dataset.toml.
    #[arg(long)]
    spec: PathBuf,
    /// Output directory (created): dataset.npz, manifest.csv, spec.toml, and mcap/NNNNN/.
    #[arg(long)]
    out: PathBuf,
    /// Also write each record as a raw MCAP log (mcap/NNNNN/), replayable without a config.
    #[arg(long)]
    mcap: bool,
    /// Simulate this bearing instead of the spec's `bearing`: a catalog name (skf-6205-2rs,
    /// skf-6203-2rs, skf-61804, pronostia, mfpt, rexnord-za-2115) or a custom geometry. One
    /// spec makes the training set of every bearing's model; the spec.toml written beside the
    /// set says the bearing used.
    #[arg(long)]
    bearing: Option<String>,
    #[command(flatten)]
    format: FormatArg,
}

pub fn run(args: &DatasetArgs) -> Result<(), CliError> {
    let text = std::fs::read_to_string(&args.spec)
        .map_err(|e| CliError::input(format!("{}: cannot read: {e}", args.spec.display())))?;
    let parse = |text: &str| {
        DatasetSpec::parse(text).map_err(|problems| {
            CliError::input(format!(
                "{}{}: {} problem(s): {}",
                args.spec.display(),
                match &args.bearing {
                    Some(b) => format!(" with --bearing {b:?}"),
                    None => String::new(),
                },
                problems.len(),
                problems.join("; ")
            ))
        })
    };
    let mut spec = parse(&text)?;
    // The spec as used: with another bearing, the spec rewritten (and checked again).
    let text = match &args.bearing {
        Some(bearing) => {
            spec.bearing = bearing.clone();
            let rewritten = toml::to_string(&spec)
                .map_err(|e| CliError::failure(format!("the spec with --bearing: {e}")))?;
            spec = parse(&rewritten)?;
            rewritten
        }
        None => text,
    };
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::input(format!("{}: cannot create: {e}", args.out.display())))?;
    let records = spec.records();
    let progress = Progress::start("dataset", "records", records.len() as u64);
    let started = std::time::Instant::now();
    let made: Vec<Vec<f32>> = records
        .par_iter()
        .map(|record| {
            let samples = spec.generate(record);
            progress.inc("");
            samples.map_err(|e| {
                CliError::input(format!(
                    "record {} ({}): {e}",
                    record.index,
                    record.fault.name()
                ))
            })
        })
        .collect::<Result<_, _>>()?;
    progress.finish("");
    let generated_s = started.elapsed().as_secs_f64();
    write_npz(&args.out.join("dataset.npz"), &records, &made, &spec)?;
    write_manifest(&args.out.join("manifest.csv"), &records, args.mcap)?;
    let copy = args.out.join("spec.toml");
    std::fs::write(&copy, &text)
        .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", copy.display())))?;
    if args.mcap {
        write_logs(&args.out, &spec, &records, &made)?;
    }
    if args.format.json() {
        println!(
            "{}",
            serde_json::json!({
                "records": records.len(),
                "classes": spec.faults.len(),
                "records_per_class": spec.records_per_fault,
                "duration_s": spec.duration_s,
                "fs_hz": spec.fs_hz,
                "model": spec.model.name(),
                "generated_s": generated_s,
                "threads": rayon::current_num_threads(),
                "out": args.out.display().to_string(),
                "mcap": args.mcap,
            })
        );
        return Ok(());
    }
    eprintln!(
        "bearingd: dataset: {} records ({} classes × {}, {} s at {} Hz, {} model) made in {generated_s:.1} s on {} threads; wrote {}/dataset.npz and manifest.csv{}",
        records.len(),
        spec.faults.len(),
        spec.records_per_fault,
        spec.duration_s,
        spec.fs_hz,
        spec.model.name(),
        rayon::current_num_threads(),
        args.out.display(),
        if args.mcap { " and mcap/" } else { "" }
    );
    Ok(())
}

/// `x` (records × samples, float32 g), `y` (labels, int64), and per record `rpm`, `noise_g`,
/// `severity`, `load_n`, `resonance_hz` (float64); `fs_hz` as a 0-d array.
fn write_npz(
    path: &Path,
    records: &[DatasetRecord],
    made: &[Vec<f32>],
    spec: &DatasetSpec,
) -> Result<(), CliError> {
    let fail = |e: &dyn std::fmt::Display| {
        CliError::failure(format!("{}: cannot write: {e}", path.display()))
    };
    let width = made.iter().map(Vec::len).min().unwrap_or(0);
    let flat: Vec<f32> = made
        .iter()
        .flat_map(|r| r[..width].iter().copied())
        .collect();
    let x = Array2::from_shape_vec((made.len(), width), flat).map_err(|e| fail(&e))?;
    let column = |f: fn(&DatasetRecord) -> f64| records.iter().map(f).collect::<Array1<f64>>();
    let y: Array1<i64> = records.iter().map(|r| r.label as i64).collect();
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut npz = ndarray_npy::NpzWriter::new(std::io::BufWriter::new(file));
    npz.add_array("x", &x).map_err(|e| fail(&e))?;
    npz.add_array("y", &y).map_err(|e| fail(&e))?;
    npz.add_array("rpm", &column(|r| r.rpm))
        .map_err(|e| fail(&e))?;
    npz.add_array("noise_g", &column(|r| r.noise_g))
        .map_err(|e| fail(&e))?;
    npz.add_array("severity", &column(|r| r.severity))
        .map_err(|e| fail(&e))?;
    npz.add_array("load_n", &column(|r| r.load_n))
        .map_err(|e| fail(&e))?;
    npz.add_array("resonance_hz", &column(|r| r.resonance_hz))
        .map_err(|e| fail(&e))?;
    npz.add_array("fs_hz", &ndarray::arr0(spec.fs_hz))
        .map_err(|e| fail(&e))?;
    npz.finish().map_err(|e| fail(&e))?;
    Ok(())
}

/// One row per record: its index (the row of `x`), label, class name and conditions.
fn write_manifest(path: &Path, records: &[DatasetRecord], mcap: bool) -> Result<(), CliError> {
    let fail =
        |e: std::io::Error| CliError::failure(format!("{}: cannot write: {e}", path.display()));
    let file = std::fs::File::create(path).map_err(fail)?;
    let mut out = std::io::BufWriter::new(file);
    writeln!(
        out,
        "index,label,fault,model,rpm,noise_g,severity,load_n,resonance_hz,seed,mcap,bearing"
    )
    .map_err(fail)?;
    for r in records {
        writeln!(
            out,
            "{},{},{},{},{:.3},{:.5},{:.5},{:.1},{:.1},{},{},\"{}\"",
            r.index,
            r.label,
            r.fault.name(),
            r.model.name(),
            r.rpm,
            r.noise_g,
            r.severity,
            r.load_n,
            r.resonance_hz,
            r.seed,
            if mcap {
                log_dir(r).display().to_string()
            } else {
                String::new()
            },
            r.bearing
        )
        .map_err(fail)?;
    }
    out.flush().map_err(fail)
}

fn log_dir(record: &DatasetRecord) -> PathBuf {
    PathBuf::from("mcap").join(format!("{:05}", record.index))
}

/// Each record as a raw MCAP log in `out/mcap/NNNNN/`, dated now, with a `bearingd.dataset`
/// record (spec seed, index, label, fault).
fn write_logs(
    out: &Path,
    spec: &DatasetSpec,
    records: &[DatasetRecord],
    made: &[Vec<f32>],
) -> Result<(), CliError> {
    let origin_ns = crate::clock::wall_clock_now_ns();
    records
        .par_iter()
        .zip(made)
        .try_for_each(|(record, samples)| {
            let bearing = record.geometry().map_err(CliError::input)?;
            let samples: Vec<f64> = samples.iter().map(|&x| f64::from(x)).collect();
            write_raw_log(&RawLog {
                signal: LogSignal {
                    out: &out.join(log_dir(record)),
                    sensor: "dataset",
                    samples: &samples,
                    fs_hz: spec.fs_hz,
                    rpm: record.rpm,
                    bearing: &bearing,
                },
                origin_ns,
                about: (
                    "bearingd.dataset".to_string(),
                    [
                        ("seed".to_string(), spec.seed.to_string()),
                        ("index".to_string(), record.index.to_string()),
                        ("label".to_string(), record.label.to_string()),
                        ("fault".to_string(), record.fault.name().to_string()),
                    ]
                    .into(),
                ),
                what: &format!("record {} of a bearingd dataset", record.index),
            })
            .map(|_| ())
            .map_err(raw_log_error)
        })
}

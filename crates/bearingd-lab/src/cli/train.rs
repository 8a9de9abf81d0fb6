//! `bearingd train --dataset DIR --out MODEL.safetensors`: trains the learned diagnosis (see
//! [`crate::learned`]) on a `bearingd dataset` output, printing each epoch's loss and
//! accuracies, and writes the model file (weights and model card).

use crate::learned::{train, FeatureSettings, TrainingSet, TrainingSettings};
use bearingd::cli::format::FormatArg;
use bearingd::cli::CliError;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct TrainArgs {
    /// A directory written by `bearingd dataset` (dataset.npz and spec.toml); repeat it to
    /// train on several (same classes, and same bearing on shaft orders), e.g. a signal-model
    /// and a physics set.
    #[arg(long, required = true)]
    dataset: Vec<PathBuf>,
    /// The model file to write (.safetensors).
    #[arg(long)]
    out: PathBuf,
    /// Passes over the training segments.
    #[arg(long, default_value_t = TrainingSettings::default().epochs)]
    epochs: usize,
    /// The seed of the initial weights, the corruption noise and the batch order.
    #[arg(long, default_value_t = TrainingSettings::default().seed)]
    seed: u64,
    /// The input's axis: `shaft` orders (the model knows the data set's one bearing) or
    /// `fault-relative` orders (each fault's own; the model serves any bearing, best trained
    /// on data sets of many, e.g. `bearing = "random"`).
    #[arg(long, value_enum, default_value_t = Axis::Shaft)]
    axis: Axis,
    // With json, the summary and every epoch as one JSON document on stdout (the epochs are
    // still printed on stderr as they end).
    #[command(flatten)]
    format: FormatArg,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Axis {
    Shaft,
    FaultRelative,
}

pub fn run(args: &TrainArgs) -> Result<(), CliError> {
    if args.epochs == 0 {
        return Err(CliError::input(
            "--epochs 0: give at least 1, e.g. --epochs 40",
        ));
    }
    let started = std::time::Instant::now();
    let features = match args.axis {
        Axis::Shaft => FeatureSettings::default(),
        Axis::FaultRelative => FeatureSettings::fault_relative(),
    };
    let set = TrainingSet::read_all(&args.dataset, features).map_err(CliError::input)?;
    eprintln!(
        "bearingd: train: {} records → {} segments of {} revolutions ({} classes: {}), inputs made in {:.1} s; every fifth record held out",
        set.records,
        set.segments(),
        set.features.segment_revolutions,
        set.spec.faults.len(),
        set.spec.faults.iter().map(|f| f.name()).collect::<Vec<_>>().join(", "),
        started.elapsed().as_secs_f64()
    );
    let settings = TrainingSettings {
        epochs: args.epochs,
        seed: args.seed,
        ..TrainingSettings::default()
    };
    let mut epochs = Vec::new();
    let trained = train(&set, &settings, |epoch| {
        epochs.push(serde_json::json!({
            "epoch": epoch.epoch,
            "loss": epoch.loss,
            "train_accuracy": epoch.train_accuracy,
            "validation_accuracy": epoch.validation_accuracy,
        }));
        eprintln!(
            "epoch {:>3}/{}: loss {:.4}, training accuracy {:.3}, held-out accuracy {:.3} ({:.0} s)",
            epoch.epoch,
            settings.epochs,
            epoch.loss,
            epoch.train_accuracy,
            epoch.validation_accuracy,
            started.elapsed().as_secs_f64()
        );
    })
    .map_err(CliError::failure)?;
    trained.save(&args.out).map_err(CliError::failure)?;
    if args.format.json() {
        println!(
            "{}",
            serde_json::json!({
                "records": set.records,
                "segments": set.segments(),
                "classes": set.spec.faults.iter().map(|f| f.name()).collect::<Vec<_>>(),
                "epochs": epochs,
                "validation_accuracy": trained.last_epoch.validation_accuracy,
                "seconds": started.elapsed().as_secs_f64(),
                "out": args.out.display().to_string(),
            })
        );
        return Ok(());
    }
    eprintln!(
        "bearingd: train: held-out accuracy {:.3} after {} epochs in {:.0} s; wrote {}",
        trained.last_epoch.validation_accuracy,
        settings.epochs,
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

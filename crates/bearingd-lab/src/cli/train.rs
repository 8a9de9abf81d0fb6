//! `bearingd train --dataset DIR --out MODEL.safetensors`: trains the learned diagnosis (see
//! [`crate::learned`]) on a `bearingd dataset` output, printing each epoch's loss and
//! accuracies, and writes the model file (weights and model card).

use crate::learned::{train, FeatureSettings, TrainingSet, TrainingSettings};
use bearingd::cli::CliError;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct TrainArgs {
    /// A directory written by `bearingd dataset` (dataset.npz and spec.toml); repeat it to
    /// train on several (same classes and bearing), e.g. a signal-model and a physics set.
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
}

pub fn run(args: &TrainArgs) -> Result<(), CliError> {
    if args.epochs == 0 {
        return Err(CliError::input(
            "--epochs 0: give at least 1, e.g. --epochs 40",
        ));
    }
    let started = std::time::Instant::now();
    let set = TrainingSet::read_all(&args.dataset, FeatureSettings::default())
        .map_err(CliError::input)?;
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
    let trained = train(&set, &settings, |epoch| {
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
    eprintln!(
        "bearingd: train: held-out accuracy {:.3} after {} epochs in {:.0} s; wrote {}",
        trained.last_epoch.validation_accuracy,
        settings.epochs,
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

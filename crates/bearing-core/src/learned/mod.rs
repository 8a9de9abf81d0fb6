//! Learned diagnosis trained only on synthetic data (seed 001, issue 14 item 4): a denoising
//! autoencoder + 1-D CNN that reads a record's envelope spectrum on the shaft-order axis and
//! gives class probabilities, trained on `bearingd dataset` output by `bearingd train` (with
//! candle) and run by a plain f32 forward pass (no training library in the service). It is an
//! extra opinion: the second witness of
//! [`crate::analysis::agreement::decide`], which may let the envelope name its first-ranked
//! fault on less evidence but never overrules or replaces it.
//!
//! - [`features`]: the input (order spectrum of a segment), the same in training and use;
//! - `bearingd_lab::learned::network`: the autoencoder and the classifier, trainable (candle,
//!   in the lab crate);
//! - [`infer`]: the same network's forward pass in plain f32, what a trained model runs;
//! - [`file`]: reading a model file (safetensors layout), bounded, every flaw a clear error;
//! - [`model`]: a trained model (weights + model card) and its opinion of a record;
//! - `bearingd_lab::learned::train`: training on a data set, seeded, and writing the model file
//!   (the lab crate: the service never trains);
//! - [`set`]: the models to pick from, one per bearing (`twin.learned_model` as a directory);
//! - [`combine`]: the model as that witness, and what the report says of the outcome.

pub mod combine;
pub mod features;
pub mod file;
pub mod infer;
pub mod model;
pub mod set;

pub use combine::{combined, Basis, Combined};
pub use features::FeatureSettings;
pub use model::{LearnedModel, LearnedOpinion, ModelCard, ModelError, TrainingSummary};
pub use set::ModelSet;

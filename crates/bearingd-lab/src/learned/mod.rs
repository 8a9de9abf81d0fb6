//! The learned diagnosis's training half (the service's `bearingd::learned` runs a trained
//! model without any of it): the candle network that can learn, and training on a data set.
//! The service's modules are re-exported so that both halves read as one `learned` room.
//!
//! - [`network`]: the autoencoder and the classifier, trainable (candle);
//! - [`train`]: training on a data set, seeded, and writing the model file.

pub mod network;
pub mod train;

pub use bearingd::learned::*;
pub use train::{train, EpochReport, Trained, TrainingError, TrainingSet, TrainingSettings};

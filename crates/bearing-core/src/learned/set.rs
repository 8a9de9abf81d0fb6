//! The learned models a daemon or an analysis picks from, by bearing: `twin.learned_model`
//! (or `analyze --learned`) names one model file, or a directory of them, one per bearing
//! (the repository's `models/` has one for each catalog bearing).
//!
//! A model on shaft orders knows one geometry's fault orders, so each channel is judged by the
//! model of its own bearing; a model on fault-relative orders serves any bearing that has no
//! model of its own. Two models for the same bearing in one directory are refused at load:
//! which one judges a channel must never depend on the order files are listed in.

use super::model::{LearnedModel, LearnedOpinion, ModelError};
use crate::analysis::agreement::{Witness, WitnessOpinion};
use crate::bearing::{BearingGeometry, FaultFrequencies};
use std::path::Path;

/// At most this many model files in a directory (a model is about 0.5 MB; a catalog has six).
pub const MAX_MODELS: usize = 64;

/// One or more learned models, each for its own bearing.
#[derive(Debug)]
pub struct ModelSet {
    /// The file or directory they were read from.
    pub source: String,
    /// Read from a directory (a missing bearing is then the directory's problem, not the
    /// one model's).
    directory: bool,
    models: Vec<LearnedModel>,
}

impl ModelSet {
    /// A set of one model (a model file, or a model fresh from training).
    pub fn single(model: LearnedModel) -> Self {
        ModelSet {
            source: model.file.clone(),
            directory: false,
            models: vec![model],
        }
    }

    /// The model file at `path`, or every `*.safetensors` file in the directory at `path`
    /// (in name order). Any file that is not a model, an empty directory, and two models for
    /// the same bearing are errors that name the file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let source = path.display().to_string();
        if !path.is_dir() {
            return LearnedModel::load(path).map(Self::single);
        }
        let unreadable = |e: std::io::Error| ModelError::Read {
            file: source.clone(),
            source: e,
        };
        let mut files = Vec::new();
        for entry in std::fs::read_dir(path).map_err(unreadable)? {
            let file = entry.map_err(unreadable)?.path();
            if file.extension().is_some_and(|e| e == "safetensors") {
                files.push(file);
            }
            if files.len() > MAX_MODELS {
                break;
            }
        }
        files.sort();
        if files.is_empty() || files.len() > MAX_MODELS {
            return Err(ModelError::NotAModelSet {
                dir: source,
                why: match files.len() {
                    0 => "it holds no *.safetensors file".to_string(),
                    _ => format!("it holds more than {MAX_MODELS} *.safetensors files"),
                },
            });
        }
        let models = files
            .iter()
            .map(|file| LearnedModel::load(file))
            .collect::<Result<Vec<_>, _>>()?;
        let set = ModelSet {
            source,
            directory: true,
            models,
        };
        set.refuse_twins()?;
        Ok(set)
    }

    pub fn models(&self) -> &[LearnedModel] {
        &self.models
    }

    /// The model that judges signals of `bearing`: its own (shaft orders), else one on
    /// fault-relative orders; an error that lists the bearings the set knows when none does.
    pub fn for_bearing(&self, bearing: &BearingGeometry) -> Result<&LearnedModel, ModelError> {
        match self.for_frequencies(&bearing.fault_frequencies(1.0)) {
            Some(model) => Ok(model),
            None if !self.directory => {
                // One model file: its own error says what to train.
                self.models[0]
                    .check_bearing(bearing)
                    .map(|()| &self.models[0])
            }
            None => Err(ModelError::NoModelFor {
                set: self.source.clone(),
                given: bearing.spec(),
                known: self.bearings().join(", "),
            }),
        }
    }

    /// The model whose bearing has the fault frequencies `freqs` (at any shaft speed), as in
    /// [`Self::for_bearing`].
    pub fn for_frequencies(&self, freqs: &FaultFrequencies) -> Option<&LearnedModel> {
        let shaft = |m: &&LearnedModel| m.card.features.axis.is_shaft();
        self.models
            .iter()
            .find(|m| shaft(m) && m.knows_orders(freqs))
            .or_else(|| self.models.iter().find(|m| !shaft(m)))
    }

    /// The opinion of `samples` (at `fs_hz`) by the model of the bearing whose frequencies
    /// are `freqs` (a caller that checked each channel's bearing with [`Self::for_bearing`]).
    pub fn opinion_of(
        &self,
        samples: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
    ) -> Result<LearnedOpinion, ModelError> {
        let model = self
            .for_frequencies(freqs)
            .ok_or_else(|| ModelError::NoModelFor {
                set: self.source.clone(),
                given: format!(
                    "with fault orders BPFO {:.3}, BPFI {:.3}, BSF {:.3}",
                    freqs.bpfo / freqs.shaft,
                    freqs.bpfi / freqs.shaft,
                    freqs.bsf / freqs.shaft
                ),
                known: self.bearings().join(", "),
            })?;
        model.opinion_of_checked(samples, fs_hz, freqs)
    }

    /// The bearing each model was trained for, in the set's order.
    pub fn bearings(&self) -> Vec<String> {
        self.models
            .iter()
            .map(|m| match m.card.features.axis.is_shaft() {
                true => m.card.bearing.clone(),
                false => format!("any ({})", m.card.bearing),
            })
            .collect()
    }

    /// Two models for one bearing (or two for any bearing) are refused.
    fn refuse_twins(&self) -> Result<(), ModelError> {
        for (i, first) in self.models.iter().enumerate() {
            for second in &self.models[i + 1..] {
                let same = match (
                    first.card.features.axis.is_shaft(),
                    second.card.features.axis.is_shaft(),
                ) {
                    (true, true) => BearingGeometry::parse(&second.card.bearing)
                        .ok()
                        .is_some_and(|b| first.check_bearing(&b).is_ok()),
                    (false, false) => true,
                    _ => false,
                };
                if same {
                    return Err(ModelError::NotAModelSet {
                        dir: self.source.clone(),
                        why: format!(
                            "{} and {} are both for bearing {}; keep one of them",
                            first.file, second.file, first.card.bearing
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

/// The set as the verdicts' second witness: each signal is judged by the model of its
/// bearing, found by its fault frequencies.
impl Witness for ModelSet {
    fn witness(
        &self,
        signal: &[f32],
        fs_hz: f64,
        freqs: &FaultFrequencies,
    ) -> Result<Option<WitnessOpinion>, String> {
        self.opinion_of(signal, fs_hz, freqs)
            .map(|opinion| opinion.as_witness())
            .map_err(|e| e.to_string())
    }

    fn knows(&self, bearing: &BearingGeometry) -> bool {
        self.for_bearing(bearing).is_ok()
    }
}

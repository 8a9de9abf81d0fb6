//! Training on a synthetic data set (`bearingd dataset`): every record cut into segments,
//! each segment's order spectrum an example; every fifth record held out for validation (its
//! segments never seen in training, so neighbouring segments of one record cannot leak).
//!
//! Reproducible: the initial weights, the corruption noise and the batch order all come from
//! the seeded generator, so the same data set, settings and seed give the same model (to the
//! last bits of the floating-point sums, which the matrix kernels may order differently across
//! thread counts).

use super::features::FeatureSettings;
use super::file::FileError;
use super::model::{LearnedModel, ModelCard, ModelError, TrainingSummary, CARD_FORMAT, CARD_KEY};
use super::network::Network;
use crate::analysis::envelope::FftPlans;
use crate::random::Rng;
use crate::twin::dataset::{DatasetSpec, RANDOM_BEARING};
use crate::twin::SimulatedFault;
use candle_core::{DType, Device, Tensor, D};
use candle_nn::{loss, AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// How to train (`bearingd train` options).
#[derive(Debug, Clone, Copy)]
pub struct TrainingSettings {
    pub epochs: usize,
    pub batch: usize,
    pub learning_rate: f64,
    pub seed: u64,
    /// The autoencoder's corruption: Gaussian noise of this standard deviation added to the
    /// (log) input.
    pub corruption: f32,
    /// Weight of the autoencoder's reconstruction error against the classification loss.
    pub reconstruction_weight: f64,
}

impl Default for TrainingSettings {
    fn default() -> Self {
        TrainingSettings {
            epochs: 30,
            batch: 32,
            learning_rate: 2e-3,
            seed: 1,
            corruption: 0.5,
            reconstruction_weight: 0.5,
        }
    }
}

/// The examples of a data set: one order spectrum per segment.
pub struct TrainingSet {
    pub spec: DatasetSpec,
    pub spec_text: String,
    pub features: FeatureSettings,
    pub records: usize,
    /// `order_bins` values per segment.
    pub inputs: Vec<f32>,
    pub labels: Vec<u32>,
    /// Whether each segment belongs to a held-out record.
    pub held_out: Vec<bool>,
    /// The specs' bearings (`random` for sets that draw one per record), each once.
    pub bearings: Vec<String>,
}

/// Why a data set cannot be trained on.
#[derive(Debug, thiserror::Error)]
pub enum TrainingError {
    #[error("{file}: {why}; make the data set with `bearingd dataset --spec SPEC --out DIR`")]
    DataSet { file: String, why: String },
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("the network failed: {0}")]
    Network(#[from] candle_core::Error),
}

/// One epoch's numbers, for progress.
#[derive(Debug, Clone, Copy)]
pub struct EpochReport {
    pub epoch: usize,
    pub loss: f64,
    pub train_accuracy: f64,
    pub validation_accuracy: f64,
}

impl TrainingSet {
    /// Reads several data sets of the same classes and bearing (for example one made by the
    /// signal model and one by the physics twin) as one.
    pub fn read_all(
        dirs: &[std::path::PathBuf],
        features: FeatureSettings,
    ) -> Result<Self, TrainingError> {
        let mut sets = dirs.iter().map(|dir| Self::read(dir, features));
        let Some(first) = sets.next() else {
            return Err(TrainingError::DataSet {
                file: "(none)".into(),
                why: "no data set given".into(),
            });
        };
        let mut all = first?;
        for (dir, set) in dirs.iter().skip(1).zip(sets) {
            let set = set?;
            // On shaft orders a model knows one bearing; on fault-relative orders any.
            let same_bearing = set.spec.bearing == all.spec.bearing || !features.axis.is_shaft();
            if set.spec.faults != all.spec.faults || !same_bearing {
                return Err(TrainingError::DataSet {
                    file: dir.join("spec.toml").display().to_string(),
                    why: format!(
                        "its classes ({:?}) and bearing ({}) must be those of the first data set ({:?}, {}){}",
                        set.spec.faults,
                        set.spec.bearing,
                        all.spec.faults,
                        all.spec.bearing,
                        if same_bearing { "" } else { " (or train on fault-relative orders: --axis fault-relative)" }
                    ),
                });
            }
            if !all.bearings.contains(&set.spec.bearing) {
                all.bearings.push(set.spec.bearing.clone());
            }
            all.records += set.records;
            all.inputs.extend(set.inputs);
            all.labels.extend(set.labels);
            all.held_out.extend(set.held_out);
            all.spec_text = format!(
                "{}\n# --- next data set ---\n{}",
                all.spec_text, set.spec_text
            );
        }
        Ok(all)
    }

    /// Reads `dataset.npz` and `spec.toml` of a `bearingd dataset` output directory and turns
    /// every record into segments (on all cores).
    pub fn read(dir: &Path, features: FeatureSettings) -> Result<Self, TrainingError> {
        let spec_path = dir.join("spec.toml");
        let problem = |file: &Path, why: String| TrainingError::DataSet {
            file: file.display().to_string(),
            why,
        };
        let spec_text = std::fs::read_to_string(&spec_path)
            .map_err(|e| problem(&spec_path, format!("cannot read: {e}")))?;
        let spec = DatasetSpec::parse(&spec_text)
            .map_err(|problems| problem(&spec_path, problems.join("; ")))?;
        let npz_path = dir.join("dataset.npz");
        let npz_problem = |why: String| problem(&npz_path, why);
        let file =
            std::fs::File::open(&npz_path).map_err(|e| npz_problem(format!("cannot read: {e}")))?;
        let mut npz = ndarray_npy::NpzReader::new(file)
            .map_err(|e| npz_problem(format!("not a NumPy .npz file: {e}")))?;
        let x: ndarray::Array2<f32> = npz
            .by_name("x")
            .map_err(|e| npz_problem(format!("array x: {e}")))?;
        let y: ndarray::Array1<i64> = npz
            .by_name("y")
            .map_err(|e| npz_problem(format!("array y: {e}")))?;
        let rpm: ndarray::Array1<f64> = npz
            .by_name("rpm")
            .map_err(|e| npz_problem(format!("array rpm: {e}")))?;
        if x.nrows() != y.len() || y.len() != rpm.len() {
            return Err(npz_problem(format!(
                "x has {} rows, y {} and rpm {}: they must match",
                x.nrows(),
                y.len(),
                rpm.len()
            )));
        }
        if let Some(bad) = y
            .iter()
            .find(|&&l| l < 0 || l as usize >= spec.faults.len())
        {
            return Err(npz_problem(format!(
                "label {bad} is not one of the spec's {} classes",
                spec.faults.len()
            )));
        }
        if features.axis.is_shaft() && spec.bearing == RANDOM_BEARING {
            return Err(problem(
                &spec_path,
                "its records each have their own bearing (bearing = \"random\"), which a model on shaft orders cannot learn; train on fault-relative orders (--axis fault-relative)".into(),
            ));
        }
        // Each record's bearing is the spec's draw for it: the rows of x are the spec's
        // records, in order.
        let records = spec.records();
        if records.len() != x.nrows() {
            return Err(npz_problem(format!(
                "x has {} rows, but the spec makes {} records",
                x.nrows(),
                records.len()
            )));
        }
        let geometries = records
            .iter()
            .map(|record| record.geometry())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|why| problem(&spec_path, why))?;
        let fs_hz = spec.fs_hz;
        let per_record: Vec<Vec<f32>> = x
            .outer_iter()
            .collect::<Vec<_>>()
            .par_iter()
            .zip(rpm.to_vec().par_iter())
            .zip(geometries.par_iter())
            .map(|((row, &rpm), geometry)| {
                let samples: Vec<f32> = row.iter().copied().collect();
                let freqs = geometry.fault_frequencies(rpm / 60.0);
                features.record_inputs(&mut FftPlans::default(), &samples, fs_hz, &freqs)
            })
            .collect();
        let bins = features.order_bins;
        let mut set = TrainingSet {
            spec_text,
            features,
            records: x.nrows(),
            inputs: Vec::new(),
            labels: Vec::new(),
            held_out: Vec::new(),
            bearings: vec![spec.bearing.clone()],
            spec,
        };
        for (index, (inputs, &label)) in per_record.iter().zip(&y).enumerate() {
            let segments = inputs.len() / bins;
            set.inputs.extend_from_slice(inputs);
            set.labels
                .extend(std::iter::repeat_n(label as u32, segments));
            set.held_out
                .extend(std::iter::repeat_n(index % 5 == 4, segments));
        }
        if set.labels.is_empty() {
            return Err(problem(
                &npz_path,
                format!(
                    "no record holds a whole segment ({} revolutions); make the records longer (duration_s)",
                    features.segment_revolutions
                ),
            ));
        }
        Ok(set)
    }

    pub fn segments(&self) -> usize {
        self.labels.len()
    }

    fn classes(&self) -> Vec<SimulatedFault> {
        self.spec.faults.clone()
    }
}

/// A trained model, its weights by name (to save) and its last epoch's numbers.
pub struct Trained {
    pub model: LearnedModel,
    weights: BTreeMap<String, PlainTensor>,
    pub last_epoch: EpochReport,
}

/// A tensor's shape and values, out of candle.
struct PlainTensor {
    shape: Vec<usize>,
    values: Vec<f32>,
}

impl Trained {
    /// Writes the model file (weights and card) in the layout [`super::file`] reads.
    pub fn save(&self, path: &Path) -> Result<(), ModelError> {
        let file = path.display().to_string();
        let write = |why: String| ModelError::Write {
            file: file.clone(),
            why,
        };
        let bytes: Vec<(&String, &PlainTensor, Vec<u8>)> = self
            .weights
            .iter()
            .map(|(name, tensor)| {
                let bytes = tensor.values.iter().flat_map(|v| v.to_le_bytes()).collect();
                (name, tensor, bytes)
            })
            .collect();
        let views = bytes
            .iter()
            .map(|(name, tensor, bytes)| {
                safetensors::tensor::TensorView::new(
                    safetensors::Dtype::F32,
                    tensor.shape.clone(),
                    bytes,
                )
                .map(|view| (name.to_string(), view))
                .map_err(|e| write(e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let card_json =
            serde_json::to_string(&self.model.card).map_err(|e| write(e.to_string()))?;
        let metadata = HashMap::from([(CARD_KEY.to_string(), card_json)]);
        safetensors::serialize_to_file(views, Some(metadata), path)
            .map_err(|e| write(e.to_string()))
    }
}

/// Trains a model on `set`, calling `progress` after every epoch.
pub fn train(
    set: &TrainingSet,
    settings: &TrainingSettings,
    mut progress: impl FnMut(&EpochReport),
) -> Result<Trained, TrainingError> {
    let device = Device::Cpu;
    let bins = set.features.order_bins;
    let classes = set.classes();
    let varmap = VarMap::new();
    let vb = VarBuilder::from_varmap(&varmap, DType::F32, &device);
    let network = Network::new(vb, bins, classes.len())?;
    let mut rng = Rng::new(settings.seed);
    seed_weights(&varmap, &mut rng)?;
    let mut optimizer = AdamW::new(
        varmap.all_vars(),
        ParamsAdamW {
            lr: settings.learning_rate,
            weight_decay: 1e-4,
            ..ParamsAdamW::default()
        },
    )?;
    let train_rows: Vec<usize> = (0..set.segments()).filter(|&i| !set.held_out[i]).collect();
    let held_rows: Vec<usize> = (0..set.segments()).filter(|&i| set.held_out[i]).collect();
    let mut report = EpochReport {
        epoch: 0,
        loss: f64::NAN,
        train_accuracy: 0.0,
        validation_accuracy: 0.0,
    };
    let mut order = train_rows.clone();
    for epoch in 1..=settings.epochs {
        shuffle(&mut order, &mut rng);
        let (mut loss_sum, mut batches, mut right) = (0.0, 0usize, 0usize);
        for batch in order.chunks(settings.batch.max(1)) {
            let (clean, labels) = gather(set, batch, &device)?;
            let noise: Vec<f32> = (0..batch.len() * bins)
                .map(|_| settings.corruption * rng.normal() as f32)
                .collect();
            let corrupted = (&clean + Tensor::from_vec(noise, (batch.len(), bins), &device)?)?;
            let out = network.forward(&corrupted)?;
            let classification = loss::cross_entropy(&out.logits, &labels)?;
            let reconstruction = loss::mse(&out.denoised, &clean)?;
            let total = (classification + (reconstruction * settings.reconstruction_weight)?)?;
            optimizer.backward_step(&total)?;
            loss_sum += f64::from(total.to_scalar::<f32>()?);
            batches += 1;
            right += correct(&out.logits, &labels)?;
        }
        report = EpochReport {
            epoch,
            loss: loss_sum / batches.max(1) as f64,
            train_accuracy: right as f64 / train_rows.len().max(1) as f64,
            validation_accuracy: accuracy(&network, set, &held_rows, &device)?,
        };
        progress(&report);
    }
    let card = ModelCard {
        format: CARD_FORMAT,
        classes,
        bearing: if set.features.axis.is_shaft() {
            set.spec.bearing.clone()
        } else {
            format!("any (trained on {})", set.bearings.join(", "))
        },
        features: set.features,
        training: TrainingSummary {
            dataset_spec: set.spec_text.clone(),
            records: set.records,
            segments: set.segments(),
            epochs: settings.epochs,
            seed: settings.seed,
            validation_accuracy: report.validation_accuracy,
        },
    };
    let weights = varmap
        .data()
        .lock()
        .map_err(|_| candle_core::Error::Msg("the weights' lock is poisoned".into()))?
        .iter()
        .map(|(name, var)| {
            let tensor = PlainTensor {
                shape: var.dims().to_vec(),
                values: var.as_tensor().flatten_all()?.to_vec1()?,
            };
            Ok((name.clone(), tensor))
        })
        .collect::<candle_core::Result<BTreeMap<_, _>>>()?;
    let model = LearnedModel::from_tensors(card, "trained".into(), |name, shape| {
        match weights.get(name) {
            Some(tensor) if tensor.shape == shape => Ok(tensor.values.clone()),
            _ => Err(FileError::Malformed(format!(
                "training made no tensor {name:?} of shape {shape:?}"
            ))),
        }
    })?;
    Ok(Trained {
        model,
        weights,
        last_epoch: report,
    })
}

/// Kaiming-normal weights and zero biases, from the seeded generator.
fn seed_weights(varmap: &VarMap, rng: &mut Rng) -> candle_core::Result<()> {
    let vars = varmap
        .data()
        .lock()
        .map_err(|_| candle_core::Error::Msg("the weights' lock is poisoned".into()))?;
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    for name in names {
        let var = &vars[name];
        let dims = var.dims().to_vec();
        let count: usize = dims.iter().product();
        let values: Vec<f32> = if name.ends_with("bias") {
            vec![0.0; count]
        } else {
            let fan_in: usize = dims.iter().skip(1).product::<usize>().max(1);
            let std = (2.0 / fan_in as f64).sqrt();
            (0..count).map(|_| (std * rng.normal()) as f32).collect()
        };
        var.set(&Tensor::from_vec(values, dims, var.device())?)?;
    }
    Ok(())
}

fn shuffle(rows: &mut [usize], rng: &mut Rng) {
    for i in (1..rows.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        rows.swap(i, j);
    }
}

fn gather(
    set: &TrainingSet,
    rows: &[usize],
    device: &Device,
) -> candle_core::Result<(Tensor, Tensor)> {
    let bins = set.features.order_bins;
    let inputs: Vec<f32> = rows
        .iter()
        .flat_map(|&r| set.inputs[r * bins..(r + 1) * bins].iter().copied())
        .collect();
    let labels: Vec<u32> = rows.iter().map(|&r| set.labels[r]).collect();
    Ok((
        Tensor::from_vec(inputs, (rows.len(), bins), device)?,
        Tensor::from_vec(labels, rows.len(), device)?,
    ))
}

fn correct(logits: &Tensor, labels: &Tensor) -> candle_core::Result<usize> {
    let predicted = logits.argmax(D::Minus1)?;
    let same: Vec<u8> = predicted.eq(labels)?.to_vec1()?;
    Ok(same.iter().filter(|&&s| s != 0).count())
}

fn accuracy(
    network: &Network,
    set: &TrainingSet,
    rows: &[usize],
    device: &Device,
) -> candle_core::Result<f64> {
    let mut right = 0;
    for chunk in rows.chunks(256) {
        let (inputs, labels) = gather(set, chunk, device)?;
        right += correct(&network.forward(&inputs)?.logits, &labels)?;
    }
    Ok(right as f64 / rows.len().max(1) as f64)
}

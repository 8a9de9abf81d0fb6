//! The network, after seed 001: a denoising autoencoder whose output a small 1-D CNN
//! classifies. Both halves are trained together: the autoencoder to give back the clean input
//! from a corrupted one, the CNN to name the class from the autoencoder's output.
//!
//! Sizes (choice): three 9-tap convolutions for the autoencoder (1 → 8 → 8 → 1 channels), two
//! convolutions with 2× pooling and a 32-unit hidden layer for the classifier: about 27,000
//! weights, 105 KiB, a fraction of a millisecond per segment on one core. The sizes and tensor
//! names are [`super::infer`]'s, whose plain forward pass is what a trained model runs.
//!
//! This candle network is for training only (it can learn); a test holds its forward pass and
//! [`super::infer`]'s to the same probabilities.

use super::infer::{
    self, ConvShape, CLASSES, CNN_FIRST, CNN_SECOND, DAE_IN, DAE_MID, DAE_OUT, HIDDEN, HIDDEN_UNITS,
};
use candle_core::{Module, Result, Tensor};
use candle_nn::{conv1d, linear, Conv1d, Conv1dConfig, Linear, VarBuilder};

pub struct Network {
    dae_in: Conv1d,
    dae_mid: Conv1d,
    dae_out: Conv1d,
    cnn_first: Conv1d,
    cnn_second: Conv1d,
    hidden: Linear,
    classes: Linear,
}

/// What one forward pass gives for a batch.
pub struct Forward {
    /// The autoencoder's output, `[batch, bins]`.
    pub denoised: Tensor,
    /// Unnormalised class scores, `[batch, classes]`.
    pub logits: Tensor,
}

impl Network {
    /// `bins` must be a multiple of 4 (two 2× poolings).
    pub fn new(vb: VarBuilder, bins: usize, classes: usize) -> Result<Self> {
        let hidden_inputs = infer::hidden_inputs(bins).ok_or_else(|| {
            candle_core::Error::Msg(format!("{bins} bins: not a positive multiple of 4"))
        })?;
        let conv = |shape: ConvShape| {
            let same = Conv1dConfig {
                padding: shape.kernel / 2,
                ..Conv1dConfig::default()
            };
            conv1d(
                shape.inputs,
                shape.outputs,
                shape.kernel,
                same,
                vb.pp(shape.name),
            )
        };
        Ok(Network {
            dae_in: conv(DAE_IN)?,
            dae_mid: conv(DAE_MID)?,
            dae_out: conv(DAE_OUT)?,
            cnn_first: conv(CNN_FIRST)?,
            cnn_second: conv(CNN_SECOND)?,
            hidden: linear(hidden_inputs, HIDDEN_UNITS, vb.pp(HIDDEN))?,
            classes: linear(HIDDEN_UNITS, classes, vb.pp(CLASSES))?,
        })
    }

    /// `input`: `[batch, bins]`.
    pub fn forward(&self, input: &Tensor) -> Result<Forward> {
        let x = input.unsqueeze(1)?;
        let h = self.dae_in.forward(&x)?.relu()?;
        let h = self.dae_mid.forward(&h)?.relu()?;
        let denoised = self.dae_out.forward(&h)?;
        let c = pool2(&self.cnn_first.forward(&denoised)?.relu()?)?;
        let c = pool2(&self.cnn_second.forward(&c)?.relu()?)?;
        let c = c.flatten_from(1)?;
        let c = self.hidden.forward(&c)?.relu()?;
        Ok(Forward {
            denoised: denoised.squeeze(1)?,
            logits: self.classes.forward(&c)?,
        })
    }
}

/// Max over neighbouring pairs along the last axis: `[b, c, l]` → `[b, c, l / 2]`.
fn pool2(x: &Tensor) -> Result<Tensor> {
    let (b, c, l) = x.dims3()?;
    x.reshape((b, c, l / 2, 2))?.max(3)
}

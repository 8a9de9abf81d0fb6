//! The network, after seed 001: a denoising autoencoder whose output a small 1-D CNN
//! classifies. Both halves are trained together: the autoencoder to give back the clean input
//! from a corrupted one, the CNN to name the class from the autoencoder's output.
//!
//! Sizes (choice): three 9-tap convolutions for the autoencoder (1 → 8 → 8 → 1 channels), two
//! convolutions with 2× pooling and a 32-unit hidden layer for the classifier: about 27,000
//! weights, 105 KiB, a fraction of a millisecond per segment on one core.

use candle_core::{Module, Result, Tensor};
use candle_nn::{conv1d, linear, Conv1d, Conv1dConfig, Linear, VarBuilder};

/// Kernel of the autoencoder's convolutions.
const DAE_KERNEL: usize = 9;
const DAE_CHANNELS: usize = 8;
const CNN_CHANNELS: usize = 16;
const HIDDEN: usize = 32;

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
        let same = |kernel: usize| Conv1dConfig {
            padding: kernel / 2,
            ..Conv1dConfig::default()
        };
        Ok(Network {
            dae_in: conv1d(
                1,
                DAE_CHANNELS,
                DAE_KERNEL,
                same(DAE_KERNEL),
                vb.pp("dae_in"),
            )?,
            dae_mid: conv1d(
                DAE_CHANNELS,
                DAE_CHANNELS,
                DAE_KERNEL,
                same(DAE_KERNEL),
                vb.pp("dae_mid"),
            )?,
            dae_out: conv1d(
                DAE_CHANNELS,
                1,
                DAE_KERNEL,
                same(DAE_KERNEL),
                vb.pp("dae_out"),
            )?,
            cnn_first: conv1d(1, CNN_CHANNELS, 7, same(7), vb.pp("cnn_first"))?,
            cnn_second: conv1d(CNN_CHANNELS, CNN_CHANNELS, 5, same(5), vb.pp("cnn_second"))?,
            hidden: linear(CNN_CHANNELS * (bins / 4), HIDDEN, vb.pp("hidden"))?,
            classes: linear(HIDDEN, classes, vb.pp("classes"))?,
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

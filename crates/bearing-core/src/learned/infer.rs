//! The network's forward pass in plain f32, for using a trained model: the service needs only
//! this (about 27,000 multiply-adds per output bin of the autoencoder, a fraction of a
//! millisecond per segment), so it does not link the training library. Training keeps its own
//! forward (`bearingd_lab::learned::network`, candle), and a test holds the two to the same probabilities.
//!
//! The layers, after seed 001: the denoising autoencoder (three 9-tap "same" convolutions,
//! 1 → 8 → 8 → 1 channels, ReLU between), then the classifier (a 7-tap convolution to 16
//! channels, ReLU, 2× max-pool; a 5-tap convolution 16 → 16, ReLU, 2× max-pool; a linear layer
//! to 32 units, ReLU; a linear layer to the classes), then softmax.
//!
//! The sizes are defined here once; `bearingd_lab::learned::network` builds the trainable network from them,
//! so a model file's tensor names and shapes are the same for both.

/// One convolution of the network: the name of its tensors (`NAME.weight` `[outputs, inputs,
/// kernel]`, `NAME.bias` `[outputs]`), its channels and taps. "Same" padding: `kernel / 2`
/// zeros on each side, so the output is as long as the input.
#[derive(Debug, Clone, Copy)]
pub struct ConvShape {
    pub name: &'static str,
    pub inputs: usize,
    pub outputs: usize,
    pub kernel: usize,
}

const DAE_KERNEL: usize = 9;
const DAE_CHANNELS: usize = 8;
const CNN_CHANNELS: usize = 16;

pub const DAE_IN: ConvShape = ConvShape {
    name: "dae_in",
    inputs: 1,
    outputs: DAE_CHANNELS,
    kernel: DAE_KERNEL,
};
pub const DAE_MID: ConvShape = ConvShape {
    name: "dae_mid",
    inputs: DAE_CHANNELS,
    outputs: DAE_CHANNELS,
    kernel: DAE_KERNEL,
};
pub const DAE_OUT: ConvShape = ConvShape {
    name: "dae_out",
    inputs: DAE_CHANNELS,
    outputs: 1,
    kernel: DAE_KERNEL,
};
pub const CNN_FIRST: ConvShape = ConvShape {
    name: "cnn_first",
    inputs: 1,
    outputs: CNN_CHANNELS,
    kernel: 7,
};
pub const CNN_SECOND: ConvShape = ConvShape {
    name: "cnn_second",
    inputs: CNN_CHANNELS,
    outputs: CNN_CHANNELS,
    kernel: 5,
};
/// The linear layers' tensor names (`NAME.weight` `[outputs, inputs]`, `NAME.bias`).
pub const HIDDEN: &str = "hidden";
pub const CLASSES: &str = "classes";
pub const HIDDEN_UNITS: usize = 32;

/// The inputs of the hidden layer: the second convolution's channels after two 2× poolings.
/// `None` when `bins` is not a positive multiple of 4 (or absurdly large).
pub fn hidden_inputs(bins: usize) -> Option<usize> {
    if bins == 0 || !bins.is_multiple_of(4) {
        return None;
    }
    CNN_CHANNELS.checked_mul(bins / 4)
}

/// A convolution's weights, `[outputs][inputs][kernel]`, and biases.
#[derive(Debug, Clone)]
struct Conv {
    shape: ConvShape,
    weight: Vec<f32>,
    bias: Vec<f32>,
}

/// A linear layer's weights, `[outputs][inputs]`, and biases.
#[derive(Debug, Clone)]
struct Linear {
    inputs: usize,
    outputs: usize,
    weight: Vec<f32>,
    bias: Vec<f32>,
}

/// The trained weights of the whole network, for inputs of `bins` values.
#[derive(Debug, Clone)]
pub struct Weights {
    bins: usize,
    dae_in: Conv,
    dae_mid: Conv,
    dae_out: Conv,
    cnn_first: Conv,
    cnn_second: Conv,
    hidden: Linear,
    classes: Linear,
}

/// Working memory of the forward pass, kept between segments so that a warm pass allocates
/// nothing.
#[derive(Debug, Default)]
pub struct Scratch {
    a: Vec<f32>,
    b: Vec<f32>,
}

impl Weights {
    /// The weights for inputs of `bins` values and `classes` outputs, each tensor asked of
    /// `tensor(name, shape)` (a model file, or a network fresh from training). Fails with the
    /// first tensor `tensor` refuses, or when `bins` is not a positive multiple of 4.
    pub fn from_tensors<E>(
        bins: usize,
        classes: usize,
        mut tensor: impl FnMut(&str, &[usize]) -> Result<Vec<f32>, E>,
        bad_bins: impl FnOnce() -> E,
    ) -> Result<Self, E> {
        let Some(hidden_inputs) = hidden_inputs(bins) else {
            return Err(bad_bins());
        };
        let mut conv = |shape: ConvShape| -> Result<Conv, E> {
            Ok(Conv {
                weight: tensor(
                    &format!("{}.weight", shape.name),
                    &[shape.outputs, shape.inputs, shape.kernel],
                )?,
                bias: tensor(&format!("{}.bias", shape.name), &[shape.outputs])?,
                shape,
            })
        };
        let (dae_in, dae_mid, dae_out) = (conv(DAE_IN)?, conv(DAE_MID)?, conv(DAE_OUT)?);
        let (cnn_first, cnn_second) = (conv(CNN_FIRST)?, conv(CNN_SECOND)?);
        let mut linear = |name: &str, inputs: usize, outputs: usize| -> Result<Linear, E> {
            Ok(Linear {
                inputs,
                outputs,
                weight: tensor(&format!("{name}.weight"), &[outputs, inputs])?,
                bias: tensor(&format!("{name}.bias"), &[outputs])?,
            })
        };
        Ok(Weights {
            bins,
            dae_in,
            dae_mid,
            dae_out,
            cnn_first,
            cnn_second,
            hidden: linear(HIDDEN, hidden_inputs, HIDDEN_UNITS)?,
            classes: linear(CLASSES, HIDDEN_UNITS, classes)?,
        })
    }

    /// Values per input.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// Number of outputs.
    pub fn classes(&self) -> usize {
        self.classes.outputs
    }

    /// The class probabilities of one input of [`Self::bins`] values into `probabilities`
    /// ([`Self::classes`] values). Extra input values or output slots are ignored; missing input
    /// values count as zero (callers pass whole segments).
    pub fn probabilities(&self, input: &[f32], scratch: &mut Scratch, probabilities: &mut [f32]) {
        let bins = self.bins;
        let Scratch { a, b } = scratch;
        a.clear();
        a.extend(input.iter().take(bins));
        a.resize(bins, 0.0);
        // The autoencoder: a → b → a → b (the denoised input, one channel).
        self.dae_in.forward(a, bins, b, true);
        self.dae_mid.forward(b, bins, a, true);
        self.dae_out.forward(a, bins, b, false);
        // The classifier.
        self.cnn_first.forward(b, bins, a, true);
        max_pool2(a, b);
        self.cnn_second.forward(b, bins / 2, a, true);
        max_pool2(a, b);
        self.hidden.forward(b, a, true);
        self.classes.forward(a, b, false);
        softmax(b);
        for (p, v) in probabilities.iter_mut().zip(b.iter()) {
            *p = *v;
        }
    }
}

impl Conv {
    /// `x`: `[inputs][len]` → `y`: `[outputs][len]`, zero-padded "same" cross-correlation (as
    /// the training library computes it), plus bias, then ReLU if `relu`.
    fn forward(&self, x: &[f32], len: usize, y: &mut Vec<f32>, relu: bool) {
        let ConvShape {
            inputs,
            outputs,
            kernel,
            ..
        } = self.shape;
        let pad = kernel / 2;
        y.clear();
        y.resize(outputs * len, 0.0);
        for (o, out) in y.chunks_exact_mut(len).enumerate() {
            for (i, row) in x.chunks_exact(len).take(inputs).enumerate() {
                let taps = &self.weight[(o * inputs + i) * kernel..][..kernel];
                for (j, &w) in taps.iter().enumerate() {
                    // out[t] += w · row[t + j − pad] where 0 ≤ t + j − pad < len.
                    let first = pad.saturating_sub(j);
                    let end = (len + pad).saturating_sub(j).min(len);
                    if first >= end {
                        continue;
                    }
                    let source = &row[first + j - pad..end + j - pad];
                    for (o_t, &x_t) in out[first..end].iter_mut().zip(source) {
                        *o_t += w * x_t;
                    }
                }
            }
            let bias = self.bias[o];
            for v in out.iter_mut() {
                *v = activate(*v + bias, relu);
            }
        }
    }
}

impl Linear {
    /// `y = W x + b`, then ReLU if `relu`.
    fn forward(&self, x: &[f32], y: &mut Vec<f32>, relu: bool) {
        y.clear();
        y.extend(
            self.weight
                .chunks_exact(self.inputs)
                .zip(&self.bias)
                .map(|(row, &bias)| {
                    let sum: f32 = row.iter().zip(x).map(|(w, v)| w * v).sum();
                    activate(sum + bias, relu)
                }),
        );
    }
}

fn activate(v: f32, relu: bool) -> f32 {
    if relu {
        v.max(0.0)
    } else {
        v
    }
}

/// Max over neighbouring pairs: `x` `[channels][len]` → `y` `[channels][len / 2]` (`len` even,
/// so the pairs never straddle two channels).
fn max_pool2(x: &[f32], y: &mut Vec<f32>) {
    y.clear();
    y.extend(x.chunks_exact(2).map(|pair| pair[0].max(pair[1])));
}

/// In place: `exp(v − max) / Σ exp(v − max)`.
fn softmax(values: &mut [f32]) {
    let max = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mut sum = 0.0;
    for v in values.iter_mut() {
        *v = (*v - max).exp();
        sum += *v;
    }
    for v in values.iter_mut() {
        *v /= sum;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Weights whose every tensor is `fill(name, index)`.
    fn weights(bins: usize, classes: usize, fill: impl Fn(&str, usize) -> f32) -> Weights {
        Weights::from_tensors(
            bins,
            classes,
            |name, shape| -> Result<Vec<f32>, String> {
                let count: usize = shape.iter().product();
                Ok((0..count).map(|i| fill(name, i)).collect())
            },
            || "bad bins".to_string(),
        )
        .unwrap()
    }

    #[test]
    fn a_convolution_is_a_zero_padded_cross_correlation() {
        // One channel, taps [1, 2, 3] (kernel 3, pad 1): y[t] = x[t−1] + 2 x[t] + 3 x[t+1].
        let conv = Conv {
            shape: ConvShape {
                name: "c",
                inputs: 1,
                outputs: 1,
                kernel: 3,
            },
            weight: vec![1.0, 2.0, 3.0],
            bias: vec![0.5],
        };
        let mut y = Vec::new();
        conv.forward(&[1.0, 10.0, 100.0, -1000.0], 4, &mut y, false);
        assert_eq!(y, [32.5, 321.5, -2789.5, -1899.5]);
        conv.forward(&[1.0, 10.0, 100.0, -1000.0], 4, &mut y, true);
        assert_eq!(y, [32.5, 321.5, 0.0, 0.0]);
    }

    #[test]
    fn pooling_softmax_and_linear_do_what_they_say() {
        let mut y = Vec::new();
        max_pool2(&[1.0, 3.0, -2.0, -5.0, 0.0, 0.0], &mut y);
        assert_eq!(y, [3.0, -2.0, 0.0]);
        let mut p = [1.0f32, 2.0, 3.0];
        softmax(&mut p);
        let e = [(-2f32).exp(), (-1f32).exp(), 1.0];
        let sum: f32 = e.iter().sum();
        for (p, e) in p.iter().zip(e) {
            assert!((p - e / sum).abs() < 1e-7);
        }
        let linear = Linear {
            inputs: 2,
            outputs: 2,
            weight: vec![1.0, 2.0, -3.0, 4.0],
            bias: vec![0.5, -100.0],
        };
        linear.forward(&[1.0, 1.0], &mut y, true);
        assert_eq!(y, [3.5, 0.0]);
    }

    #[test]
    fn probabilities_sum_to_one_and_a_warm_pass_keeps_its_buffers() {
        let w = weights(16, 3, |name, i| {
            let sign = if i % 3 == 0 { -1.0 } else { 1.0 };
            sign * (0.05 + 0.01 * (i % 7) as f32) * if name.ends_with("bias") { 0.1 } else { 1.0 }
        });
        let input: Vec<f32> = (0..16).map(|i| (i as f32 * 0.7).sin()).collect();
        let mut scratch = Scratch::default();
        let mut p = [0f32; 3];
        w.probabilities(&input, &mut scratch, &mut p);
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{p:?}");
        assert!(p.iter().all(|&v| v > 0.0 && v < 1.0), "{p:?}");
        let capacities = (scratch.a.capacity(), scratch.b.capacity());
        let mut again = [0f32; 3];
        w.probabilities(&input, &mut scratch, &mut again);
        assert_eq!(p, again);
        assert_eq!(capacities, (scratch.a.capacity(), scratch.b.capacity()));
    }

    #[test]
    fn bins_must_be_a_positive_multiple_of_four() {
        for bins in [0, 6, usize::MAX] {
            let refused = Weights::from_tensors(
                bins,
                2,
                |_, _| -> Result<Vec<f32>, String> { Ok(Vec::new()) },
                || "bad bins".to_string(),
            );
            assert_eq!(refused.unwrap_err(), "bad bins", "{bins}");
        }
    }
}

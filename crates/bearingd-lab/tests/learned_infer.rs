//! The plain-f32 forward pass a model runs with ([`bearingd::learned::infer`]) against the
//! candle network it was trained as ([`bearingd_lab::learned::network`]), on the shipped model:
//! the same probabilities (within 1e-5) and the same most probable class, segment by segment,
//! on simulated records of every class and on the real CWRU records.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::analysis::envelope::FftPlans;
use bearingd::bearing::BearingGeometry;
use bearingd::learned::LearnedModel;
use bearingd::recording::{read_recording, ReadOptions};
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};
use bearingd_lab::learned::network::Network;
use bearingd_testdata::{read_manifest, repo_root, shared_data_dir};
use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;

/// Largest difference of a probability allowed between the two forward passes.
const TOLERANCE: f32 = 1e-5;

struct Both {
    plain: LearnedModel,
    candle: Network,
}

impl Both {
    fn shipped() -> Self {
        let path = repo_root().join("models/skf-6205-2rs.safetensors");
        let plain = LearnedModel::load(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let vb = VarBuilder::from_buffered_safetensors(bytes, DType::F32, &Device::Cpu).unwrap();
        let candle =
            Network::new(vb, plain.card.features.order_bins, plain.card.classes.len()).unwrap();
        Both { plain, candle }
    }

    /// Compares the two on every segment of a record; returns the number of segments.
    fn compare(&self, what: &str, samples: &[f32], fs_hz: f64, shaft_hz: f64) -> usize {
        let features = self.plain.card.features;
        let bins = features.order_bins;
        let freqs = BearingGeometry::parse(&self.plain.card.bearing)
            .unwrap()
            .fault_frequencies(shaft_hz);
        let inputs = features.record_inputs(&mut FftPlans::default(), samples, fs_hz, &freqs);
        let segments = inputs.len() / bins;
        assert!(segments > 0, "{what}: no whole segment");
        let plain = self.plain.classify(&inputs);
        let batch = Tensor::from_slice(&inputs, (segments, bins), &Device::Cpu).unwrap();
        let logits = self.candle.forward(&batch).unwrap().logits;
        let candle: Vec<Vec<f32>> = candle_nn::ops::softmax(&logits, 1)
            .unwrap()
            .to_vec2()
            .unwrap();
        assert_eq!(plain.len(), segments, "{what}");
        for (segment, (p, c)) in plain.iter().zip(&candle).enumerate() {
            let largest = p
                .iter()
                .zip(c)
                .map(|(p, c)| (p - c).abs())
                .fold(0f32, f32::max);
            assert!(
                largest <= TOLERANCE,
                "{what}, segment {segment}: |Δp| {largest:e} > {TOLERANCE:e}: plain {p:?}, candle {c:?}"
            );
            assert_eq!(
                argmax(p),
                argmax(c),
                "{what}, segment {segment}: plain {p:?}, candle {c:?}"
            );
        }
        segments
    }
}

fn argmax(p: &[f32]) -> usize {
    p.iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i)
}

#[test]
fn the_plain_forward_pass_gives_candles_probabilities_on_simulated_records() {
    let both = Both::shipped();
    let mut segments = 0;
    for fault in [
        SimulatedFault::None,
        SimulatedFault::OuterRace,
        SimulatedFault::InnerRace,
        SimulatedFault::Ball,
    ] {
        for (rpm, seed) in [(1500.0, 3), (1797.0, 11)] {
            let params = SimulationParams {
                rpm,
                seed,
                ..SimulationParams::example(fault)
            };
            let samples = Simulator::record(params.clone(), 4.0);
            segments += both.compare(
                &format!("{} at {rpm} rpm", fault.name()),
                &samples,
                params.fs_hz,
                rpm / 60.0,
            );
        }
    }
    assert!(segments >= 40, "{segments} segments compared");
}

#[test]
fn the_plain_forward_pass_gives_candles_probabilities_on_cwru() {
    let Some(dir) = shared_data_dir("cwru") else {
        return;
    };
    let both = Both::shipped();
    let (mut records, mut segments) = (0, 0);
    for row in read_manifest(&dir) {
        let recording = read_recording(&dir.join(&row["file"]), &ReadOptions::default()).unwrap();
        let fs_hz: f64 = row["fs_hz"].parse().unwrap();
        let rpm: f64 = row["rpm"].parse().unwrap();
        let samples: Vec<f32> = recording.samples.iter().map(|&v| v as f32).collect();
        segments += both.compare(&row["file"], &samples, fs_hz, rpm / 60.0);
        records += 1;
    }
    assert!(records >= 19, "{records} CWRU records compared");
    assert!(segments >= 19 * 10, "{segments} segments compared");
}

//! The in-process simulated sensor node (`transport = "sim"`): the twin's signal model, one
//! simulator per axis, quantised to the counts a real node would send. It makes
//! `bearingd run` show the whole loop on a machine with no sensor.

use crate::config::{SensorConfig, SimConfig, SimFault};
use crate::messages::ChannelId;
use crate::pipeline::Input;
use crate::twin::{SimulatedFault, SimulationParams, Simulator};

/// Produces a sensor's blocks, axis by axis, in sample time.
pub struct SimSource {
    sensor: String,
    scale_g_per_count: f64,
    axes: Vec<(String, Simulator)>,
    block: usize,
}

impl SimSource {
    /// `block_s`: length of each block in seconds of sample time.
    pub fn new(sensor: &SensorConfig, sim: &SimConfig, block_s: f64) -> Self {
        let fault = match sim.fault {
            SimFault::None => SimulatedFault::None,
            SimFault::Outer => SimulatedFault::OuterRace,
            SimFault::Inner => SimulatedFault::InnerRace,
            SimFault::Ball => SimulatedFault::Ball,
        };
        let axes = sensor
            .axes
            .iter()
            .enumerate()
            .map(|(i, axis)| {
                let params = SimulationParams {
                    fault,
                    rpm: sensor
                        .speed
                        .initial_rpm()
                        .unwrap_or_else(|| sensor.speed.max_rpm()),
                    bearing: sensor.bearing.clone(),
                    fs_hz: sensor.sample_rate_hz,
                    amplitude_g: sim.severity,
                    noise_g: sim.noise_g,
                    shaft_tone_g: sim.imbalance_g,
                    onset_s: sim.onset_s,
                    ramp_s: 10.0,
                    resonance_hz: (sensor.sample_rate_hz * 0.12).min(3_000.0),
                    seed: sim.seed.wrapping_add(i as u64 * 7919),
                    ..SimulationParams::example(fault)
                };
                (axis.clone(), Simulator::new(params))
            })
            .collect();
        SimSource {
            sensor: sensor.id.clone(),
            scale_g_per_count: sensor.scale_g_per_count,
            axes,
            block: ((sensor.sample_rate_hz * block_s).round() as usize).max(1),
        }
    }

    pub fn sample_rate_hz(&self) -> f64 {
        self.axes.first().map_or(1.0, |(_, s)| s.params().fs_hz)
    }

    /// Sample index of the next block.
    pub fn next_sample(&self) -> u64 {
        self.axes.first().map_or(0, |(_, s)| s.next_sample())
    }

    /// The next block of every axis.
    pub fn next_blocks(&mut self) -> Vec<Input> {
        let mut g = vec![0f32; self.block];
        let scale = self.scale_g_per_count;
        self.axes
            .iter_mut()
            .map(|(axis, sim)| {
                let first_sample = sim.next_sample();
                sim.fill(&mut g);
                let counts = g
                    .iter()
                    .map(|&x| {
                        (f64::from(x) / scale)
                            .round()
                            .clamp(f64::from(i16::MIN), f64::from(i16::MAX))
                            as i16
                    })
                    .collect();
                Input::Samples {
                    channel: ChannelId {
                        sensor: self.sensor.clone(),
                        axis: axis.clone(),
                    },
                    first_sample,
                    scale_g_per_count: scale,
                    counts,
                }
            })
            .collect()
    }
}

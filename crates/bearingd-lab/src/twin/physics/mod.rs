//! The physics twin (seed 001, MODELS.md §5): a lumped 6-DOF model of the bearing with Hertz
//! contacts, clearance, ball passage and a localized defect, integrated in time; and its
//! calibration to a measured record. The signal-model twin (`twin::simulate`) draws the
//! vibration a defect makes; this one computes it from masses, stiffnesses and the contact
//! geometry, so it can show faults a machine has never had, for the bearing it actually has.
//!
//! # API (sans-IO: no file, no clock, no printing)
//!
//! ```no_run
//! use bearingd::bearing::BearingGeometry;
//! use bearingd_lab::twin::physics::{simulate, PhysicsModel, PhysicsParams};
//! use bearingd::twin::SimulatedFault;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let bearing = BearingGeometry::from_catalog("skf-6205-2rs")?;
//! let mut params = PhysicsParams::new(bearing, 1797.0, SimulatedFault::InnerRace);
//! params.defect_width_mm = 0.356; // CWRU's 0.014 in
//! params.load_n = 1500.0;
//! params.fs_hz = 12_000.0;
//! params.duration_s = 2.0;
//! params.noise_g = 0.05;
//! params.seed = 7;
//! let record: Vec<f32> = simulate(&params)?; // 24 000 samples, g
//!
//! // Or streaming, block by block (same samples for the same parameters):
//! let mut model = PhysicsModel::new(params)?;
//! let mut block = [0f32; 1024];
//! model.fill(&mut block)?;
//! # Ok(()) }
//! ```
//!
//! - [`PhysicsParams`]: bearing geometry ([`crate::bearing::BearingGeometry`]), shaft speed
//!   (rpm), radial load (N), fault ([`crate::twin::SimulatedFault`]: none, outer race, inner
//!   race, ball), defect width and depth (mm) and its angle from the load line, the structure
//!   ([`Structure`]: masses, stiffnesses, dampings, contact stiffness `k_b`, clearance; defaults
//!   from the literature and Hertz theory), [`Dof`] (six, or seed 003's five), sample rate,
//!   duration, cage slip, noise (g), seed and the integrator's tolerance.
//!   `PhysicsParams::new(bearing, rpm, fault)` gives the defaults; `PhysicsParams::cwru(fault)`
//!   the CWRU drive end at 1797 rpm.
//! - [`simulate`]`(&params) -> Result<Vec<f32>, PhysicsError>`: `round(duration·fs)` samples of
//!   the sensor signal in g: the resonator's vertical acceleration, low-pass filtered and
//!   sampled like a real acquisition chain, plus white noise of `noise_g`. The record starts at
//!   t = 0 from the static equilibrium under the load (no start-up transient). Deterministic
//!   for a seed.
//! - [`PhysicsModel`]: the same, streaming (`fill` block by block), with integration counters.
//! - [`PhysicsError`]: every unusable parameter is named with its fix (`Invalid`); a model
//!   that cannot be integrated says when and why (`Integration`). No panic on any input.
//! - [`calibrate`]: fits `k_r`, `c_r`, `k_b` and the defect width to a measured record, by
//!   [`evolve::differential_evolution`] (parallel, rayon).
//!
//! The model, the integrator and its accuracy, the calibration and the measured speed:
//! docs/PHYSICS.md.

mod calibrate;
mod dynamics;
pub mod evolve;
mod model;
mod params;

pub use calibrate::{calibrate, Calibration, CalibrationSettings, SPECTRUM_WINDOW};
pub use model::{simulate, IntegrationStats, PhysicsModel};
pub use params::{hertz_contact_stiffness, Dof, PhysicsError, PhysicsParams, Structure};

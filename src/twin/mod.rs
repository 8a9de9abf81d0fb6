//! The signal-model digital twin of the bearing (MODELS.md §4): a simulator of a localized
//! defect's vibration, shared by every part that needs a synthetic signal.

pub mod rng;
pub mod simulate;

pub use simulate::{SimulatedFault, SimulationParams, Simulator};

//! The signal-model digital twin of the bearing (MODELS.md §4): a simulator of a localized
//! defect's vibration, shared by every part that needs a synthetic signal; the same model's
//! envelope spectrum in closed form; and its fit to measured spectra, per fault hypothesis.
//! The physics twin (MODELS.md §5: the 6-DOF contact model and its calibration), the labelled
//! data sets and the defect-size check on the physics twin are the lab's
//! (`bearingd_lab::twin`): the service never integrates an ODE.

pub mod diagnose;
pub mod fit;
pub mod hw;
pub mod model;
pub mod optimize;
pub use bearing_signal::simulate;

pub use fit::{FitBounds, HypothesisFit, TwinFitter, TwinParams};
pub use simulate::{Nuisance, SimulatedFault, SimulationParams, Simulator};

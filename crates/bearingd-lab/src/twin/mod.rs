//! The lab's twins: the physics twin ([`physics`]: the 6-DOF contact model, its calibration),
//! labelled synthetic data sets made with either twin ([`dataset`]), and the defect-size
//! estimator checked against the physics twin ([`defect_size`]). The service's signal-model
//! twin (`bearingd::twin`: simulator, fits, the HW identification) is re-exported, so both read
//! as one `twin` room.

pub mod dataset;
pub mod defect_size;
pub mod physics;

pub use bearingd::twin::*;

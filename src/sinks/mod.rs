//! Sinks: where the pipeline's results leave it (DESIGN.md, "The house").
//!
//! - [`fleet`]: the fleet bridge, MQTT Sparkplug B with store-and-forward.
//!
//! (The MCAP log and the iceoryx2 alerts still live in `daemon/` and `alerts/`; the module
//! reorganisation moves them here.)

pub mod fleet;

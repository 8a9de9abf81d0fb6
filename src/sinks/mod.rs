//! Sinks: where the pipeline's messages go.
//!
//! - [`mcap`]: the MCAP log (writer, rotation, disk budget, crash recovery) as a [`Sink`].
//! - [`alerts`]: flag changes → alerts on the iceoryx2 service `outputs.alerts_service`; also
//!   the subscriber that `bearingd alerts` uses.
//! - [`systemd`]: the notify protocol (READY, STATUS, WATCHDOG, STOPPING) and the one-line
//!   `STATUS=`.
//! - [`fleet`]: the fleet bridge, MQTT Sparkplug B with store-and-forward, as a [`Sink`] whose
//!   network and fsyncs run on a thread of their own.
//!
//! Every sink is blocking by design (files, compression, iceoryx2 ports) and runs on a thread of
//! its own behind a bounded queue; the daemon decides which thread (`crate::daemon`).
//!
//! [`Sink`]: crate::pipeline::Sink

pub mod alerts;
pub mod fleet;
pub mod mcap;
pub mod systemd;

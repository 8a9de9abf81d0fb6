//! The fleet bridge: a node's alerts and indicators over MQTT with the Sparkplug B payload and
//! topic rules, so that SCADA, historians and dashboards (Ignition, HiveMQ, EMQX, …) see every
//! bearingd of a plant. Design, numbers and the plan beyond one broker: `docs/FLEET.md`.
//!
//! Inside the daemon, as a sink on its own thread: it sees every pipeline message directly (no
//! second process, no new iceoryx2 service), and a stalled network never reaches the analysis
//! (the disk queue takes the records meanwhile).
//!
//! - [`sparkplug`]: the Sparkplug B payload as prost structs (`proto/sparkplug_b.proto`).
//! - [`metrics`]: the metric catalog per device (one per channel) and when records are made
//!   (sans-IO, on the observations' own clock).
//! - [`node`]: the edge node's session: topics, births and deaths, `bdSeq`, `seq`, rebirth
//!   (sans-IO).
//! - [`primary`]: the Sparkplug 3.0 primary host's STATE and whether to publish now (sans-IO).
//! - [`queue`]: the bounded on-disk store-and-forward queue.
//! - [`bridge`]: the I/O around them: the MQTT 5 client (rumqttc, rustls), reconnects, acks.
//! - `tls`: the bridge's TLS client setup (rustls; with the cargo feature `tls`).
//! - [`adapter`]: the one place that knows the daemon's message types and its `Sink` trait.
//! - [`decode`]: payloads back to text, for `bearingd fleet-decode`.

pub mod adapter;
pub mod bridge;
pub mod decode;
pub mod metrics;
pub mod node;
pub mod primary;
pub mod queue;
pub mod sparkplug;
#[cfg(feature = "tls")]
mod tls;

pub use adapter::FleetSink;

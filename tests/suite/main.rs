//! The integration-test suite: one binary, one module per part (ripgrep's layout), so that the
//! suite links once.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod alerts;
mod cli;
mod daemon;
mod dataset;
mod defect_size;
mod developer_set;
mod envelope;
// Against a real mosquitto over TLS (mqtts://): needs the `tls` feature (a default one).
#[cfg(feature = "tls")]
mod fleet;
mod formats;
mod foxglove;
mod hostile_alerts;
mod hostile_files;
mod hostile_logs;
mod kinematics;
mod learned;
mod learned_models;
mod machine;
mod monitor;
mod replay;
mod rolling_element;
mod severity;
mod speed;
mod twin;

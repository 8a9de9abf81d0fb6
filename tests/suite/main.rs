//! The integration-test suite: one binary, one module per part (ripgrep's layout), so that the
//! suite links once.

mod alerts;
mod cli;
mod daemon;
mod developer_set;
mod envelope;
mod kinematics;
mod monitor;
mod physics;
mod speed;
mod twin;

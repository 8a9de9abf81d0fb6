//! The integration-test suite: one binary, one module per part (ripgrep's layout), so that the
//! suite links once.

mod envelope;
mod kinematics;

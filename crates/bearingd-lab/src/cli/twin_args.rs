//! The twin's command-line choices shared by `bearingd simulate` and `bearingd calibrate`: the
//! defect, the machine fault and the physics model's degrees of freedom. They live here, not in either command, so
//! that neither command imports the other.

use crate::machine_fault::MachineFaultKind;
use crate::twin::physics::Dof;
use crate::twin::SimulatedFault;
use clap::ValueEnum;

#[derive(Clone, Copy, ValueEnum)]
pub enum FaultArg {
    None,
    Outer,
    Inner,
    Ball,
    Cage,
}

impl From<FaultArg> for SimulatedFault {
    fn from(fault: FaultArg) -> Self {
        match fault {
            FaultArg::None => SimulatedFault::None,
            FaultArg::Outer => SimulatedFault::OuterRace,
            FaultArg::Inner => SimulatedFault::InnerRace,
            FaultArg::Ball => SimulatedFault::Ball,
            FaultArg::Cage => SimulatedFault::Cage,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum DofArg {
    /// Seed 001: shaft, housing and a resonator, each in x and y.
    Six,
    /// Seed 003: the resonator in y only.
    Five,
}

impl From<DofArg> for Dof {
    fn from(dof: DofArg) -> Self {
        match dof {
            DofArg::Six => Dof::Six,
            DofArg::Five => Dof::Five,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum MachineFaultArg {
    /// A 1× line (once per revolution).
    Unbalance,
    /// 2× stronger than 1×, some 3×.
    Misalignment,
    /// Many running-speed harmonics and half orders.
    Looseness,
}

impl From<MachineFaultArg> for MachineFaultKind {
    fn from(kind: MachineFaultArg) -> Self {
        match kind {
            MachineFaultArg::Unbalance => MachineFaultKind::Unbalance,
            MachineFaultArg::Misalignment => MachineFaultKind::Misalignment,
            MachineFaultArg::Looseness => MachineFaultKind::Looseness,
        }
    }
}

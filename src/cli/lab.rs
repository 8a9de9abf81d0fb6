//! The lab commands seen from the service binary. Training, simulation, the physics twin, the
//! evaluation, a bearing's life (`trend`) and every picture (`analyze --plot`) live in a second
//! binary, `bearingd-lab` (crates/bearingd-lab), so that the service a box runs does not link
//! candle, the ODE solver or a rasterizer. A user still types
//! `bearingd train ...`: the service replaces itself with `bearingd-lab` and the same arguments
//! (`exec`, so the exit code and signals are the lab's own).

use super::CliError;
use clap::Args;
use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::Command;

/// The lab binary's name, looked up beside the running `bearingd`, then on PATH.
pub const LAB_BINARY: &str = "bearingd-lab";

/// The commands `bearingd-lab` runs. (`analyze` runs there too when it is asked for `--plot`:
/// [`super::analyze::run`] hands it over once its arguments are parsed.)
pub const LAB_COMMANDS: &[&str] = &[
    "simulate",
    "dataset",
    "train",
    "calibrate",
    "evaluate",
    "trend",
];

/// The lab command `args` (without the program name) asks for, if it asks for one.
pub fn lab_command<S: AsRef<str>>(args: &[S]) -> Option<&'static str> {
    let first = args.first()?.as_ref();
    LAB_COMMANDS.iter().find(|c| **c == first).copied()
}

/// A lab command's arguments, handed to `bearingd-lab` unparsed (its `--help` included).
#[derive(Args)]
#[command(disable_help_flag = true)]
pub struct LabArgs {
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
    args: Vec<OsString>,
}

/// Replaces this process with `bearingd-lab` and this process's own arguments. Returns only if
/// that fails: an absent lab binary is a usage error (exit 2) that says how to get it.
pub fn exec_lab(command: &str) -> CliError {
    let argv: Vec<OsString> = std::env::args_os().skip(1).collect();
    let error = Command::new(lab_binary()).args(argv).exec();
    if error.kind() == std::io::ErrorKind::NotFound {
        CliError::input(format!(
            "`{command}` is a lab command: install {LAB_BINARY} (`make install` installs both) or run `{LAB_BINARY} {command}`"
        ))
    } else {
        CliError::failure(format!(
            "cannot start {LAB_BINARY} for `{command}`: {error}"
        ))
    }
}

/// `bearingd-lab` beside the running executable if it is there, else the bare name (PATH).
fn lab_binary() -> PathBuf {
    std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(|dir| dir.join(LAB_BINARY)))
        .filter(|beside| beside.is_file())
        .unwrap_or_else(|| PathBuf::from(LAB_BINARY))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lab_commands_go_to_the_lab_the_rest_stays() {
        assert_eq!(lab_command(&["train", "--help"]), Some("train"));
        assert_eq!(
            lab_command(&["simulate", "--out", "x.csv"]),
            Some("simulate")
        );
        assert_eq!(
            lab_command(&["evaluate", "--recordings", "m.csv"]),
            Some("evaluate")
        );
        assert_eq!(
            lab_command(&["trend", "life/", "--plot", "x.svg"]),
            Some("trend")
        );
        assert_eq!(lab_command(&["analyze", "a.mat", "--plot", "x.png"]), None);
        assert_eq!(lab_command(&["run", "--config", "train"]), None);
        assert_eq!(lab_command::<&str>(&[]), None);
    }
}

//! `bearingd completions SHELL`: the shell completion script, printed on stdout.
//!
//! Why the scripts are embedded text and not generated here: clap_complete would add crates to
//! the service binary, whose normal dependency tree is held at 180 (issue 31, a ratchet that may
//! only fall). The lab links clap_complete and renders the scripts from the service's own clap
//! command into docs/cli/completions (`make cli-docs`); a test of the lab
//! (crates/bearingd-lab/tests/cli_docs.rs) fails when a committed script is not what the current
//! command line gives, so the text embedded here cannot drift from the flags it completes. The
//! service keeps the command on a box where only it is installed (`make install-service`).

use super::CliError;
use clap::ValueEnum;
use std::io::Write;

/// A shell that `completions` writes a script for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Shell {
    Bash,
    Zsh,
    Fish,
    Elvish,
    Powershell,
}

impl Shell {
    /// Every shell, in the order the lab writes them.
    pub const ALL: [Shell; 5] = [
        Shell::Bash,
        Shell::Zsh,
        Shell::Fish,
        Shell::Elvish,
        Shell::Powershell,
    ];

    /// The script's file name under docs/cli/completions for `program`, the name each shell
    /// looks a completion up by where it has such a convention (bash: the command's name, zsh:
    /// `_command`, fish: `command.fish`).
    pub fn file_name(self, program: &str) -> String {
        match self {
            Shell::Bash => program.to_string(),
            Shell::Zsh => format!("_{program}"),
            Shell::Fish => format!("{program}.fish"),
            Shell::Elvish => format!("{program}.elv"),
            Shell::Powershell => format!("_{program}.ps1"),
        }
    }

    /// The service's script for this shell.
    pub fn script(self) -> &'static str {
        match self {
            Shell::Bash => include_str!("../../docs/cli/completions/bearingd"),
            Shell::Zsh => include_str!("../../docs/cli/completions/_bearingd"),
            Shell::Fish => include_str!("../../docs/cli/completions/bearingd.fish"),
            Shell::Elvish => include_str!("../../docs/cli/completions/bearingd.elv"),
            Shell::Powershell => include_str!("../../docs/cli/completions/_bearingd.ps1"),
        }
    }
}

/// Prints the script for `shell` on stdout.
pub fn run(shell: Shell) -> Result<(), CliError> {
    std::io::stdout()
        .write_all(shell.script().as_bytes())
        .map_err(|error| CliError::failure(format!("cannot write the completion script: {error}")))
}

//! `bearingd-lab completions` and `bearingd-lab man`: shell completion scripts and man pages of
//! both command lines, `bearingd` and `bearingd-lab`.
//!
//! Why here: clap_complete and clap_mangen would add crates to the service binary, whose
//! dependency tree is held at 180 crates (issue 31). The lab links them and renders the service's
//! clap command, which `bearingd::cli::command` hands out; the service prints the scripts the lab
//! wrote into docs/cli/completions (embedded at build time), and `make install-service` installs
//! the committed scripts and pages, so an edge box needs neither the lab nor a generator.
//!
//! The service's lab commands take their arguments unparsed (they are handed to this binary), so
//! their clap definitions say nothing of their options. For the pages and scripts, the service's
//! command gets the lab's real definition of each one, with the service's own description: `man
//! bearingd-train` and `bearingd train --<TAB>` show train's options.

use super::{Cli, CliError};
use bearingd::cli::completions::Shell;
use clap::{CommandFactory, ValueEnum};
use std::path::{Path, PathBuf};

/// The two programs whose pages and scripts the lab writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Program {
    /// The service, `bearingd`.
    Bearingd,
    /// The lab, `bearingd-lab`.
    BearingdLab,
}

impl Program {
    pub const ALL: [Program; 2] = [Program::Bearingd, Program::BearingdLab];

    /// The program's clap command, as the pages and scripts describe it.
    pub fn command(self) -> clap::Command {
        match self {
            Program::Bearingd => service_command(),
            Program::BearingdLab => Cli::command(),
        }
    }
}

/// `bearingd-lab completions`: the script for one shell on stdout, or with --out every shell's
/// script of both programs into a directory.
#[derive(clap::Args)]
pub struct CompletionsArgs {
    /// The shell to complete in (not with --out, which writes them all).
    #[arg(value_enum, required_unless_present = "out", conflicts_with = "out")]
    shell: Option<Shell>,
    /// Whose command line: bearingd (the service) or bearingd-lab.
    #[arg(long, value_enum, default_value = "bearingd-lab")]
    program: Program,
    /// Write every shell's script of both programs into this directory (docs/cli/completions
    /// is where the service's scripts are taken from; `make cli-docs` writes it).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// `bearingd-lab man`: the man pages (section 1) of both programs and each of their subcommands.
#[derive(clap::Args)]
pub struct ManArgs {
    /// The directory to write the pages into (created if absent): bearingd.1,
    /// bearingd-analyze.1, ..., bearingd-lab.1, bearingd-lab-train.1, ...
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// The service's command line with the lab's definition of each command it hands to the lab.
pub fn service_command() -> clap::Command {
    let lab = Cli::command();
    let mut service = bearingd::cli::command();
    for name in bearingd::cli::lab::LAB_COMMANDS {
        let Some(definition) = lab.find_subcommand(name).cloned() else {
            continue;
        };
        service = service.mut_subcommand(name, |handed| {
            let mut real = definition;
            if let Some(about) = handed.get_about() {
                real = real.about(about.clone());
            }
            if let Some(long_about) = handed.get_long_about() {
                real = real.long_about(long_about.clone());
            }
            real
        });
    }
    service
}

/// The completion script of `program` for `shell`.
pub fn completion_script(program: Program, shell: Shell) -> Vec<u8> {
    let mut command = program.command();
    let name = command.get_name().to_string();
    let mut script = Vec::new();
    let generator = match shell {
        Shell::Bash => clap_complete::Shell::Bash,
        Shell::Zsh => clap_complete::Shell::Zsh,
        Shell::Fish => clap_complete::Shell::Fish,
        Shell::Elvish => clap_complete::Shell::Elvish,
        Shell::Powershell => clap_complete::Shell::PowerShell,
    };
    clap_complete::generate(generator, &mut command, name, &mut script);
    script
}

/// Every man page of `program`: (file name, roff), the program's own first, then each subcommand
/// (and theirs) as `program-sub.1`. Hidden commands and clap's `help` get none.
pub fn man_pages(program: Program) -> Result<Vec<(String, Vec<u8>)>, std::io::Error> {
    let mut command = program.command().disable_help_subcommand(true);
    command.build();
    let mut pages = Vec::new();
    add_pages(command, &mut pages)?;
    Ok(pages)
}

fn add_pages(
    command: clap::Command,
    pages: &mut Vec<(String, Vec<u8>)>,
) -> Result<(), std::io::Error> {
    let man = clap_mangen::Man::new(command.clone());
    let mut roff = Vec::new();
    man.render(&mut roff)?;
    pages.push((man.get_filename(), roff));
    for sub in command.get_subcommands().filter(|sub| !sub.is_hide_set()) {
        add_pages(sub.clone(), pages)?;
    }
    Ok(())
}

pub fn run_completions(args: &CompletionsArgs) -> Result<(), CliError> {
    match (&args.out, args.shell) {
        (Some(dir), _) => {
            create_dir(dir)?;
            for program in Program::ALL {
                let name = program.command().get_name().to_string();
                for shell in Shell::ALL {
                    write_file(
                        &dir.join(shell.file_name(&name)),
                        &completion_script(program, shell),
                    )?;
                }
            }
            Ok(())
        }
        (None, Some(shell)) => {
            use std::io::Write;
            std::io::stdout()
                .write_all(&completion_script(args.program, shell))
                .map_err(|error| {
                    CliError::failure(format!("cannot write the completion script: {error}"))
                })
        }
        // clap requires one of the two; said again here rather than panicking.
        (None, None) => Err(CliError::input(
            "completions: name a shell (bash, zsh, fish, elvish, powershell) or give --out DIR",
        )),
    }
}

pub fn run_man(args: &ManArgs) -> Result<(), CliError> {
    create_dir(&args.out)?;
    for program in Program::ALL {
        let pages = man_pages(program)
            .map_err(|error| CliError::failure(format!("cannot render the man pages: {error}")))?;
        for (name, roff) in pages {
            write_file(&args.out.join(name), &roff)?;
        }
    }
    Ok(())
}

fn create_dir(dir: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|error| {
        CliError::input(format!(
            "--out {}: cannot create the directory ({error}): choose a writable directory",
            dir.display()
        ))
    })
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    std::fs::write(path, bytes).map_err(|error| {
        CliError::input(format!(
            "cannot write {} ({error}): choose a writable directory with --out",
            path.display()
        ))
    })
}

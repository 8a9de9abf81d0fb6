//! The `bearingd-lab` command line: the lab commands, also reached as `bearingd <command>`
//! (the service binary hands them over unparsed). Errors, exit codes (0 success, 2 bad input,
//! 1 anything else) and the shared arguments are the service's own ([`bearingd::cli`]).

mod analyze;
mod calibrate;
mod dataset;
pub mod docs;
mod evaluate;
mod progress;
mod simulate;
mod train;
mod trend;
mod twin_args;

use bearingd::cli::{end_quietly_on_a_closed_pipe, exit_code, CliError};
use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "bearingd-lab",
    version,
    about = "The bearingd laboratory: training, simulation, the physics twin, evaluation and pictures."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV.
    Simulate(simulate::SimulateArgs),
    /// Generate a labelled synthetic data set (signal model or physics twin) for learned
    /// diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log.
    Dataset(dataset::DatasetArgs),
    /// Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of
    /// `bearingd dataset`; writes a model file for `analyze --learned`.
    Train(train::TrainArgs),
    /// Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width)
    /// to a measured record; prints the parameters and the fit error, plots the spectra.
    Calibrate(calibrate::CalibrateArgs),
    /// Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records)
    /// through the real pipeline: detection probability, false alarms, confusion matrix, plot;
    /// or real recordings of a manifest through `analyze` and through the daemon.
    Evaluate(evaluate::EvaluateArgs),
    /// Follow a bearing's life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV
    /// and CSV with --interval):
    /// health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its
    /// time to the failure limit; text, JSON or a table, and a plot.
    Trend(trend::TrendArgs),
    /// Diagnose a recording as `bearingd analyze` does, and draw the envelope spectrum and the
    /// kurtogram with --plot (`bearingd analyze --plot` runs this).
    Analyze(bearingd::cli::analyze::AnalyzeArgs),
    /// Print the shell completion script of bearingd-lab (or, with --program bearingd, of the
    /// service) for bash, zsh, fish, elvish or powershell; with --out DIR write them all.
    Completions(docs::CompletionsArgs),
    /// Write the man pages of bearingd and bearingd-lab and of each of their commands into a
    /// directory (`make install` installs the committed ones, docs/cli/man).
    Man(docs::ManArgs),
}

/// The lab's command line as clap sees it (the lab's tests compare the pages and scripts with it).
pub fn command() -> clap::Command {
    use clap::CommandFactory;
    Cli::command()
}

/// Parses the command line, runs the command, prints errors, returns the exit code. Every lab
/// command is a report or a batch job: a closed pipe ends it quietly, as any Unix tool.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    end_quietly_on_a_closed_pipe();
    let result: Result<(), CliError> = match cli.command {
        Command::Simulate(args) => simulate::run(&args),
        Command::Dataset(args) => dataset::run(&args),
        Command::Train(args) => train::run(&args),
        Command::Calibrate(args) => calibrate::run(&args),
        Command::Evaluate(args) => evaluate::run(&args),
        Command::Trend(args) => trend::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Completions(args) => docs::run_completions(&args),
        Command::Man(args) => docs::run_man(&args),
    };
    exit_code("bearingd-lab", result)
}

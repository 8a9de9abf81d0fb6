//! The `bearingd` command line. The only place that prints, chooses exit codes, or turns
//! typed errors into messages for people (DESIGN.md "Errors": that handling lives only at this
//! edge; the library returns typed errors).
//!
//! Exit codes: 0 success, 2 bad input (a file, an option or a config that cannot be used; the
//! message names it and says how to fix it), 1 anything else.

#[cfg(feature = "shm")]
mod alerts;
pub mod analyze;
pub mod completions;
mod config_cmd;
mod fleet_decode;
pub mod format;
mod hw_table;
pub mod import;
mod ingest;
pub mod lab;
mod progress;
mod replay;
mod run;

use clap::{Args, CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

/// How to read a recording and what it was taken under: shared by `analyze` and `import`.
#[derive(Args)]
pub struct RecordingArgs {
    /// Channel: DE, FE, BA, a variable or a field path such as bearing.gs (.mat);
    /// horizontal/vertical (PRONOSTIA); B1x…B4y (IMS); sensor/axis (MCAP log).
    #[arg(long)]
    pub channel: Option<String>,
    /// Column of a CSV table: header name or 1-based index.
    #[arg(long)]
    pub column: Option<String>,
    /// Sample rate in Hz (overrides what the file says).
    #[arg(long)]
    pub fs: Option<f64>,
    /// Shaft speed in rpm (overrides what the file says).
    #[arg(long)]
    pub rpm: Option<f64>,
    /// Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt,
    /// rexnord-za-2115) or custom geometry "z=8,d=5.97mm,D=31.62mm,alpha=0".
    #[arg(long)]
    pub bearing: Option<String>,
    /// Unit of the file's values, for WAV, plain CSV and .mat files (default: g; for an
    /// integer WAV, fractions of full scale). m/s2 is converted to g; full-scale gives no
    /// velocity in mm/s.
    #[arg(long, value_enum)]
    pub unit: Option<UnitArg>,
}

/// The values `--unit` takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum UnitArg {
    /// Acceleration in g.
    G,
    /// Acceleration in m/s².
    #[value(name = "m/s2")]
    MetresPerSecondSquared,
    /// Relative amplitudes (fractions of a recorder's full scale).
    FullScale,
}

impl RecordingArgs {
    pub fn read_options(&self) -> crate::recording::ReadOptions {
        use crate::recording::StatedUnit;
        crate::recording::ReadOptions {
            channel: self.channel.clone(),
            column: self.column.clone(),
            unit: self.unit.map(|unit| match unit {
                UnitArg::G => StatedUnit::G,
                UnitArg::MetresPerSecondSquared => StatedUnit::MetresPerSecondSquared,
                UnitArg::FullScale => StatedUnit::FullScale,
            }),
        }
    }
}

/// An error on its way to the user: the message and the exit code.
#[derive(Debug)]
pub struct CliError {
    pub message: String,
    pub code: u8,
}

impl CliError {
    pub fn input(message: impl std::fmt::Display) -> Self {
        CliError {
            message: message.to_string(),
            code: 2,
        }
    }

    pub fn failure(message: impl std::fmt::Display) -> Self {
        CliError {
            message: message.to_string(),
            code: 1,
        }
    }
}

#[derive(Parser)]
#[command(
    name = "bearingd",
    version,
    about = "Watches a rolling-element bearing from its vibration: envelope spectrum, fault scores, diagnosis."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Diagnose a recording (CWRU .mat, PRONOSTIA/IMS/plain CSV, WAV) or the built-in demo.
    Analyze(analyze::AnalyzeArgs),
    /// Run the service: sources → analysis → logs and alerts. Without --config, the embedded
    /// default: a simulated sensor that develops an outer-race fault after 30 s.
    Run(run::RunArgs),
    /// Convert a recording (.mat, .csv, WAV) into a raw MCAP log and a config to replay it with.
    Import(import::ImportArgs),
    /// Replay MCAP logs' raw samples through the same pipeline, as fast as possible or at --speed.
    Replay(replay::ReplayArgs),
    /// Sweep simulated faults (type × severity × SNR × speed × bearing, and healthy records)
    /// through the real pipeline: detection probability, false alarms, confusion matrix, plot.
    /// Runs in bearingd-lab.
    Evaluate(lab::LabArgs),
    /// Follow a bearing's life through a directory of snapshots (PRONOSTIA, IMS, MCAP logs; WAV
    /// and CSV with --interval):
    /// health stages, RMS, kurtosis, HW residual, fault score, the RMS trend and its
    /// time to the failure limit; text, JSON or a table, and a plot. Runs in bearingd-lab.
    Trend(lab::LabArgs),
    /// Write a synthetic record of a bearing fault (signal model or physics twin) as CSV or WAV.
    /// Runs in bearingd-lab.
    Simulate(lab::LabArgs),
    /// Generate a labelled synthetic data set (signal model or physics twin) for learned
    /// diagnosis: NumPy .npz, a manifest, and optionally each record as an MCAP log. Runs in bearingd-lab.
    Dataset(lab::LabArgs),
    /// Train the learned diagnosis (denoising autoencoder + 1-D CNN) on a data set of
    /// `bearingd dataset`; writes a model file for `analyze --learned`. Runs in bearingd-lab.
    Train(lab::LabArgs),
    /// Fit the physics twin (resonator stiffness and damping, contact stiffness, defect width)
    /// to a measured record; prints the parameters and the fit error, plots the spectra. Runs in bearingd-lab.
    Calibrate(lab::LabArgs),
    /// Check a configuration file; lists every problem with its key and how to fix it.
    Validate {
        /// The TOML file to check.
        file: std::path::PathBuf,
        #[command(flatten)]
        format: format::FormatArg,
    },
    /// Run one source (SocketCAN or iceoryx2) alone and report what arrived.
    Ingest(ingest::IngestArgs),
    /// Print the daemon's active alerts, then each alert as it comes (iceoryx2).
    #[cfg(feature = "shm")]
    Alerts(alerts::AlertsArgs),
    /// Decode Sparkplug B messages of the fleet bridge: reads `TOPIC HEX` lines as printed by
    /// `mosquitto_sub -v -F '%t %x' -t 'spBv1.0/#'` and prints one JSON object per message.
    FleetDecode(fleet_decode::FleetDecodeArgs),
    /// Configuration helpers.
    Config {
        #[command(subcommand)]
        action: config_cmd::ConfigAction,
    },
    /// Print the shell completion script for bash, zsh, fish, elvish or powershell on stdout
    /// (docs/OPERATIONS.md "Completions and man pages" says where each shell reads it).
    Completions {
        /// The shell to complete in.
        #[arg(value_enum)]
        shell: completions::Shell,
    },
}

/// The service's command line as clap sees it: what the lab renders the completion scripts and
/// the man pages from (the service links neither generator, see [`completions`]).
pub fn command() -> clap::Command {
    Cli::command()
}

/// Parses the command line, runs the command, prints errors, returns the exit code.
/// A report command whose reader went away (`bearingd analyze ... | head`) ends as any Unix
/// tool does, by SIGPIPE, instead of panicking in `println!`: Rust ignores SIGPIPE, so a write
/// to a closed pipe is an error that `println!` turns into a panic. The daemon (`run`) keeps the
/// error: its stdout may be a journal that restarts, and it must not die of that.
pub fn end_quietly_on_a_closed_pipe() {
    #[allow(unsafe_code)]
    // SAFETY: setting a signal's disposition to its default is async-signal-safe and is done
    // before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

pub fn main() -> ExitCode {
    let args: Vec<String> = std::env::args_os()
        .skip(1)
        .map(|arg| arg.to_string_lossy().into_owned())
        .collect();
    if let Some(command) = lab::lab_command(&args) {
        return exit_code("bearingd", Err(lab::exec_lab(command)));
    }
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Run(_)) {
        end_quietly_on_a_closed_pipe();
    }
    let result = match cli.command {
        Command::Analyze(args) => analyze::run(&args),
        Command::Run(args) => run::run_command(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Import(args) => import::run(&args),
        Command::Simulate(_) => Err(lab::exec_lab("simulate")),
        Command::Dataset(_) => Err(lab::exec_lab("dataset")),
        Command::Train(_) => Err(lab::exec_lab("train")),
        Command::Trend(_) => Err(lab::exec_lab("trend")),
        Command::Evaluate(_) => Err(lab::exec_lab("evaluate")),
        Command::Calibrate(_) => Err(lab::exec_lab("calibrate")),
        Command::Validate { file, format } => config_cmd::validate(&file, format),
        Command::Config { action } => config_cmd::run(&action),
        Command::Ingest(args) => ingest::run(&args),
        Command::FleetDecode(args) => fleet_decode::run(&args),
        Command::Completions { shell } => completions::run(shell),
        #[cfg(feature = "shm")]
        Command::Alerts(args) => alerts::run(&args),
    };
    exit_code("bearingd", result)
}

/// Prints a command's error as `PROGRAM: error: ...` and gives its exit code (both binaries).
pub fn exit_code(program: &str, result: Result<(), CliError>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("{program}: error: {}", error.message);
            ExitCode::from(error.code)
        }
    }
}

//! `bearingd replay LOG.mcap...`: logged raw samples through the same pipeline, into a new log.

use super::run::print_events;
use super::CliError;
use crate::config::{self, Config};
use crate::daemon::lock::DirLock;
use crate::daemon::{replay, ReplayOptions};
use crate::pipeline::Sink;
use crate::sinks::mcap::McapSink;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ReplayArgs {
    /// MCAP logs written by `bearingd run` (or `bearingd import`), replayed in the given order.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The configuration to analyse with (default: the embedded default's).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Replay speed: 1 = real time; default: as fast as possible.
    #[arg(long)]
    speed: Option<f64>,
    /// Directory of the replay's own MCAP log.
    #[arg(long, default_value = "bearingd-replay")]
    out: PathBuf,
    /// No progress lines.
    #[arg(long)]
    quiet: bool,
    /// Print the summary as JSON (flags with their sample times).
    #[arg(long)]
    json: bool,
}

pub fn run(args: &ReplayArgs) -> Result<(), CliError> {
    let mut config = match &args.config {
        Some(path) => config::load(path).map_err(CliError::input)?,
        None => Config::default_embedded().map_err(CliError::failure)?,
    };
    if let Some(speed) = args.speed {
        if !(speed.is_finite() && speed > 0.0) {
            return Err(CliError::input(format!(
                "--speed {speed} is not a speed; give a factor of real time, e.g. --speed 1"
            )));
        }
    }
    for file in &args.files {
        if !file.is_file() {
            return Err(CliError::input(format!(
                "{}: not found; give the path of an MCAP log",
                file.display()
            )));
        }
        check_mcap_magic(file)?;
    }
    config.outputs.mcap_dir = args.out.clone();
    // The output directory has one owner too: recovery at open would otherwise rewrite the
    // open file of a daemon (or another replay) writing there.
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::input(format!("{}: cannot create: {e}", args.out.display())))?;
    let _lock = DirLock::acquire(&args.out).map_err(CliError::input)?;
    let (sink, _) = McapSink::for_config(&config, 0).map_err(CliError::input)?;
    let mut sinks: Vec<Box<dyn Sink>> = vec![Box::new(sink)];
    let options = ReplayOptions {
        speed: args.speed,
        progress: !args.quiet,
    };
    let summary = replay(&args.files, &config, &options, &mut sinks, &print_events())
        .map_err(CliError::failure)?;
    let read = &summary.read;
    if args.json {
        let flags: Vec<_> = summary.flags.iter().collect();
        let json = serde_json::json!({
            "raw_blocks": summary.raw_blocks,
            "samples": summary.samples,
            "sample_seconds": summary.sample_seconds,
            "elapsed_s": summary.elapsed.as_secs_f64(),
            "unreadable_bytes": read.unreadable_bytes(),
            "unfinished_files": read.unfinished_files(),
            "unknown_channels": summary.unknown_channels,
            "flags": flags,
        });
        println!("{json}");
    } else {
        for flag in &summary.flags {
            println!(
                "flag {}: {} {} -> {} at sample {} (score {:.1})",
                flag.channel, flag.fault, flag.from, flag.to, flag.end_sample, flag.score
            );
        }
        println!(
            "replayed {} blocks, {} samples ({:.1} s of signal) in {:.2} s ({:.0}× real time); output in {}",
            summary.raw_blocks,
            summary.samples,
            summary.sample_seconds,
            summary.elapsed.as_secs_f64(),
            summary.sample_seconds / summary.elapsed.as_secs_f64().max(1e-9),
            args.out.display()
        );
    }
    if read.unreadable_bytes() > 0 || read.unfinished_files() > 0 {
        eprintln!(
            "bearingd: replay: {} unfinished file(s); {} bytes could not be read (read up to the last complete chunk)",
            read.unfinished_files(),
            read.unreadable_bytes()
        );
    }
    if !summary.unknown_channels.is_empty() {
        eprintln!(
            "bearingd: replay: channels not in the config were skipped: {}; give --config with these sensors",
            summary.unknown_channels.join(", ")
        );
    }
    Ok(())
}

/// Refuses a file that does not start with the MCAP magic: replaying it would read nothing and
/// succeed, which looks like an empty log rather than the wrong file.
fn check_mcap_magic(file: &Path) -> Result<(), CliError> {
    use std::io::Read;
    let mut magic = [0u8; 8];
    let read = std::fs::File::open(file).and_then(|mut f| f.read_exact(&mut magic));
    match read {
        Ok(()) if magic == *mcap::MAGIC => Ok(()),
        Ok(()) | Err(_) => Err(CliError::input(format!(
            "{}: not an MCAP log (it does not start with the MCAP magic bytes); give a log \
             written by `bearingd run` or `bearingd import` (a .mcap file)",
            file.display()
        ))),
    }
}

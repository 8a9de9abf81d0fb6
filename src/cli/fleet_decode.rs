//! `bearingd fleet-decode`: Sparkplug B messages from any MQTT client's output as JSON lines.
//!
//! ```text
//! mosquitto_sub -h BROKER -t 'spBv1.0/#' -F '%t %x' | bearingd fleet-decode
//! ```
//!
//! DDATA names its metrics by alias: started after a node's births, it prints `#<alias>` until
//! the next rebirth declares the names.

use super::CliError;
use crate::sinks::fleet::decode::Decoder;
use clap::Args;
use std::io::{BufRead, Write};

#[derive(Args)]
pub struct FleetDecodeArgs {
    /// Indent the JSON (one object over several lines).
    #[arg(long)]
    pretty: bool,
}

pub fn run(args: &FleetDecodeArgs) -> Result<(), CliError> {
    let stdin = std::io::stdin();
    let mut stdout = std::io::stdout().lock();
    let mut bad = 0u64;
    let mut decoder = Decoder::new();
    for (n, line) in stdin.lock().lines().enumerate() {
        let line = line.map_err(|e| CliError::failure(format!("stdin: {e}")))?;
        if line.trim().is_empty() {
            continue;
        }
        match decoder.decode_line(&line) {
            Ok(json) => {
                let text = if args.pretty {
                    serde_json::to_string_pretty(&json)
                } else {
                    serde_json::to_string(&json)
                }
                .unwrap_or_default();
                if writeln!(stdout, "{text}")
                    .and_then(|_| stdout.flush())
                    .is_err()
                {
                    return Ok(()); // the reader went away (e.g. `| head`)
                }
            }
            Err(e) => {
                bad += 1;
                eprintln!("bearingd: fleet-decode: line {}: {e}", n + 1);
            }
        }
    }
    if bad > 0 {
        return Err(CliError::input(format!(
            "{bad} line(s) could not be decoded; feed it `mosquitto_sub -F '%t %x'` output"
        )));
    }
    Ok(())
}

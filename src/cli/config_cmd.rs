//! `bearingd validate FILE` and `bearingd config default`.

use super::format::FormatArg;
use super::CliError;
use crate::config;
use clap::Subcommand;
use std::path::Path;

#[derive(Subcommand)]
pub enum ConfigAction {
    /// Print the documented default configuration (the embedded default: a simulated sensor);
    /// with --format json, the same settings as one JSON document (without the comments).
    Default {
        #[command(flatten)]
        format: FormatArg,
    },
}

pub fn run(action: &ConfigAction) -> Result<(), CliError> {
    match action {
        ConfigAction::Default { format } => {
            if format.json() {
                println!("{}", default_as_json()?);
            } else {
                print!("{}", config::DEFAULT_TOML);
            }
            Ok(())
        }
    }
}

/// The embedded default's settings as pretty JSON (the TOML's tables and values, no comments).
fn default_as_json() -> Result<String, CliError> {
    let value: toml::Value = toml::from_str(config::DEFAULT_TOML)
        .map_err(|e| CliError::failure(format!("the embedded default is not TOML: {e}")))?;
    serde_json::to_string_pretty(&value)
        .map_err(|e| CliError::failure(format!("the embedded default has no JSON form: {e}")))
}

/// Checks `file`; with --format json prints `{"file", "ok", "sensors", "problems": [{"key",
/// "message"}]}` on stdout, and exits 2 on problems as the text form does.
pub fn validate(file: &Path, format: FormatArg) -> Result<(), CliError> {
    let loaded = config::load(file);
    if format.json() {
        let (sensors, problems) = match &loaded {
            Ok(config) => (Some(config.sensors.len()), Vec::new()),
            Err(error) => (
                None,
                error
                    .problems
                    .iter()
                    .map(|p| serde_json::json!({"key": p.key, "message": p.message}))
                    .collect(),
            ),
        };
        println!(
            "{}",
            serde_json::json!({
                "file": file.display().to_string(),
                "ok": loaded.is_ok(),
                "sensors": sensors,
                "problems": problems,
            })
        );
    }
    let config = loaded.map_err(CliError::input)?;
    if !format.json() {
        println!(
            "{}: ok ({} sensor{})",
            file.display(),
            config.sensors.len(),
            if config.sensors.len() == 1 { "" } else { "s" }
        );
    }
    Ok(())
}

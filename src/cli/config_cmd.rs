//! `bearingd validate FILE` and `bearingd config default`.

use super::CliError;
use crate::config;
use clap::Subcommand;
use std::path::Path;

#[derive(Subcommand)]
pub enum ConfigAction {
    /// Print the documented default configuration (the embedded default: a simulated sensor).
    Default,
}

pub fn run(action: &ConfigAction) -> Result<(), CliError> {
    match action {
        ConfigAction::Default => {
            print!("{}", config::DEFAULT_TOML);
            Ok(())
        }
    }
}

pub fn validate(file: &Path) -> Result<(), CliError> {
    let config = config::load(file).map_err(CliError::input)?;
    println!(
        "{}: ok ({} sensor{})",
        file.display(),
        config.sensors.len(),
        if config.sensors.len() == 1 { "" } else { "s" }
    );
    Ok(())
}

//! The TOML configuration (DESIGN.md "Config"): read into a raw form, then validated into a
//! typed [`Config`], with every problem reported at once.
//!
//! # Why two types, raw and validated
//!
//! The raw form (the private `raw` module) mirrors the file: every key optional, every
//! leaf "the value, or a note that it had the wrong type". serde fills it and judges nothing
//! beyond the shape of the tables and which keys exist. The validated form ([`Config`] and
//! the types it holds) is what the rest of bearingd uses: defaults applied, ranges checked,
//! names resolved (a bearing name becomes a [`BearingGeometry`](crate::bearing::BearingGeometry),
//! `band_selection` a [`BandSelection`](crate::analysis::BandSelection)), impossible
//! combinations made unrepresentable (a CAN sensor's bus settings live inside
//! [`Transport::Can`]). Keeping them apart means:
//!
//! - serde never stops at a bad value: a type error or an out-of-range number becomes one
//!   entry in a list, and the validator goes on, so a user fixes a file in one round instead
//!   of one round per mistake;
//! - checks that span keys (band edge against each sensor's Nyquist frequency, disk budget
//!   against file size, unique sensor ids) see the whole file;
//! - consumers never re-check or re-parse: if they hold a [`Config`], it is valid.
//!
//! # What is reported, and how
//!
//! [`ConfigError`] lists [`ConfigProblem`]s, one per line as `FILE: KEY: MESSAGE`, where KEY
//! is a key path (`sensors[1].sample_rate_hz`). Every message reads
//! `<what is wrong>; <what to do>`: the part after its last `"; "` starts with an imperative
//! verb (`add`, `fix`, `give`, `leave`, `lower`, `move`, `raise`, `remove`, `rename`, `set`,
//! `use`, `write`), usually with an example (`e.g. rpm = 1772`). A test holds every message to
//! that rule.
//!
//! Stages, each reporting all it finds:
//!
//! 1. TOML syntax (toml's recovering parser). Syntax errors end the reading; their KEY is the
//!    position, `line L, column C`.
//! 2. Shape: unknown keys (with the known keys of that table and the likeliest intended one)
//!    and tables of the wrong type. serde stops at the first, so each is removed from the parsed
//!    document and the document read again (see `document.rs`).
//! 3. Values: types, ranges, choices, and checks across keys.
//!
//! # Defaults
//!
//! Every section and most keys are optional; defaults live in code (`Default` impls of the
//! section types and [`AnalysisSettings::default`](crate::analysis::AnalysisSettings)) and are
//! restated, with a comment on every key, in `config/bearingd.toml`, which is also the
//! embedded default ([`DEFAULT_TOML`]). A test checks the two agree. Per sensor, `id`,
//! `transport`, `sample_rate_hz`, `bearing`, `speed.rpm` and, for CAN, `can.node_id` have no
//! default: a guessed value there would produce plausible but wrong diagnoses.

mod document;
mod error;
mod logged;
mod raw;
mod types;
mod validate;

use std::path::Path;

pub use error::{ConfigError, ConfigProblem};
pub use logged::config_from_log;
pub use types::{
    Broker, CanConfig, Config, FleetConfig, OutputConfig, SensorConfig, ShmConfig, SimConfig,
    SimFault, Speed, ThresholdConfig, Transport, TwinConfig,
};
pub use validate::{MAX_ID_LEN, MAX_IOX_ROOT_LEN, TLS_BUILT, TLS_NOT_BUILT};

/// The embedded default configuration: one simulated sensor on an SKF 6205-2RS at 1772 rpm,
/// sampled at 25.6 kHz, whose outer race develops a fault after 30 s. Also the documented
/// reference of every key.
pub const DEFAULT_TOML: &str = include_str!("../../config/bearingd.toml");

/// How [`Config::default_embedded`] names its origin in messages.
pub const EMBEDDED_ORIGIN: &str = "<embedded default config>";

/// Reads and validates the config file at `path`.
pub fn load(path: &Path) -> Result<Config, ConfigError> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, &file),
        Err(error) => {
            let message = if error.kind() == std::io::ErrorKind::InvalidData {
                "the file is not UTF-8 text; save it as UTF-8".to_string()
            } else {
                format!(
                    "cannot read the file: {error}; give the path of a readable TOML file, e.g. \
                     /etc/bearingd/bearingd.toml"
                )
            };
            Err(ConfigError {
                file,
                problems: vec![ConfigProblem::new("", message)],
            })
        }
    }
}

/// Parses and validates config text; `origin` names it in messages (usually the file path).
pub fn parse(text: &str, origin: &str) -> Result<Config, ConfigError> {
    let reading = document::read(text);
    let mut problems = reading.problems.clone();
    let config = match &reading.raw {
        Some(raw) => match validate::validate(raw) {
            Ok(config) => Some(config),
            Err(found) => {
                problems.extend(found.into_iter().filter(|p| !reading.shadows(&p.key)));
                None
            }
        },
        None => None,
    };
    match config {
        Some(config) if problems.is_empty() => Ok(config),
        _ => {
            if problems.is_empty() {
                problems.push(ConfigProblem::new(
                    "",
                    "the configuration was refused without a recorded reason (a bug in \
                     bearingd); report it with this file",
                ));
            }
            Err(ConfigError {
                file: origin.to_string(),
                problems,
            })
        }
    }
}

impl Config {
    /// The embedded default ([`DEFAULT_TOML`]), for `bearingd run` without a config file.
    /// A test checks that it validates, so the error is not expected in practice.
    pub fn default_embedded() -> Result<Config, ConfigError> {
        parse(DEFAULT_TOML, EMBEDDED_ORIGIN)
    }

    /// The embedded default with its state and MCAP logs under `data_dir`, and an iceoryx2
    /// root of its own, so that a user without root can run it and `bearingd alerts
    /// --data-dir` finds the same root.
    ///
    /// The root is private to the user (issue 32: a predictable root another user could
    /// create first would let them read or forge alerts): `$XDG_RUNTIME_DIR/bearingd-iox-<hash
    /// of the absolute data directory>` when that variable is set to an absolute path (a
    /// login's own `0700` runtime directory), else `/run/bearingd/iox-<hash>` (the systemd
    /// unit's `RuntimeDirectory=`; root creates it when missing). The daemon creates the root
    /// `0700` and refuses one it does not own ([`crate::fsafe::prepare_private_root`]). Not
    /// inside the data directory: iceoryx2's socket paths below the root must fit in 108
    /// bytes, which a deep working directory would exceed ([`MAX_IOX_ROOT_LEN`]; a longer
    /// `$XDG_RUNTIME_DIR` falls back to /run/bearingd).
    pub fn embedded_in(data_dir: &Path) -> Result<Config, String> {
        let mut config = Config::default_embedded().map_err(|e| e.to_string())?;
        let absolute = std::path::absolute(data_dir).map_err(|e| {
            format!(
                "{}: cannot make the data directory absolute: {e}; give it as an absolute path",
                data_dir.display()
            )
        })?;
        config.outputs.state_dir = data_dir.join("state");
        config.outputs.mcap_dir = data_dir.join("mcap");
        let hash = fnv1a(absolute.as_os_str().as_encoded_bytes());
        let runtime_dir = std::env::var_os("XDG_RUNTIME_DIR").map(std::path::PathBuf::from);
        config.outputs.iceoryx2_root = default_iox_root(runtime_dir.as_deref(), hash);
        Ok(config)
    }
}

/// The embedded default's iceoryx2 root for the data directory's `hash`: under the user's
/// runtime directory when it is absolute and short enough, else under /run/bearingd.
fn default_iox_root(runtime_dir: Option<&Path>, hash: u64) -> std::path::PathBuf {
    let per_user = runtime_dir
        .filter(|dir| dir.is_absolute())
        .map(|dir| dir.join(format!("bearingd-iox-{hash:016x}")))
        .filter(|root| root.as_os_str().len() <= MAX_IOX_ROOT_LEN);
    per_user.unwrap_or_else(|| std::path::PathBuf::from(format!("/run/bearingd/iox-{hash:016x}")))
}

/// FNV-1a, 64 bits: a short name that is the same for the same input in every run and every
/// build (std's hasher makes no such promise).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, &b| {
        (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_iox_root_is_under_the_users_runtime_dir_or_run_bearingd() {
        let root = default_iox_root(Some(Path::new("/run/user/1000")), 0xab);
        assert_eq!(
            root,
            Path::new("/run/user/1000/bearingd-iox-00000000000000ab")
        );
        let fallback = Path::new("/run/bearingd/iox-00000000000000ab");
        assert_eq!(default_iox_root(None, 0xab), fallback);
        assert_eq!(
            default_iox_root(Some(Path::new("relative")), 0xab),
            fallback
        );
        let deep = Path::new("/run/user/1000/a/very/deep/runtime/directory/here");
        assert_eq!(default_iox_root(Some(deep), 0xab), fallback);
        assert!(fallback.as_os_str().len() <= MAX_IOX_ROOT_LEN);
    }
}

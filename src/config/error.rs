//! The one error type of the config module: every problem found in one file.

use std::fmt;

/// One thing wrong with a config file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigProblem {
    /// Where: a key path such as `sensors[1].sample_rate_hz`; for a TOML syntax error, the
    /// position (`line 3, column 7`); empty when the problem concerns the whole file (it could
    /// not be read).
    pub key: String,
    /// What is wrong and how to fix it: `<what is wrong>; <what to do>`, the part after the last
    /// `"; "` starting with an imperative verb (`give`, `use`, `remove`, …).
    pub message: String,
}

impl ConfigProblem {
    pub(crate) fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        ConfigProblem {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ConfigProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.key, self.message)
        }
    }
}

/// A config file that cannot be used, with every problem found in it (never only the first).
///
/// Displayed one problem per line as `FILE: KEY: MESSAGE` (`FILE: MESSAGE` when the problem has
/// no key), so that editors and `grep` can jump to it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", render(.file, .problems))]
pub struct ConfigError {
    /// The file's path, or the origin given to [`parse`](super::parse).
    pub file: String,
    /// Never empty.
    pub problems: Vec<ConfigProblem>,
}

fn render(file: &str, problems: &[ConfigProblem]) -> String {
    problems
        .iter()
        .map(|problem| format!("{file}: {problem}"))
        .collect::<Vec<_>>()
        .join("\n")
}

//! `--format`: how a command prints its result, the same choices and the same words in every
//! command of both programs (the lab uses these too). Text for people is always the default.

use clap::{Args, ValueEnum};

/// The values `--format` takes on a command with one result (or one line per event).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Lines for people.
    Text,
    /// JSON on stdout: one document, or one object per line for a stream of events; notes and
    /// warnings are in the object.
    Json,
}

/// The values `--format` takes on a command that reports on many records (`analyze`, `trend`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReportFormat {
    /// Lines for people.
    Text,
    /// JSON on stdout: one document (`analyze` of several records: an array of them).
    Json,
    /// One Markdown table row per record (per snapshot for `trend`).
    Table,
}

/// `--format text|json`, flattened into a command's arguments.
#[derive(Args, Debug, Clone, Copy)]
pub struct FormatArg {
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
}

impl FormatArg {
    pub fn json(&self) -> bool {
        self.format == Format::Json
    }
}

/// `--format text|json` with the older `--json` kept as its alias (`alerts`, `replay`).
#[derive(Args, Debug, Clone, Copy)]
pub struct FormatOrJsonArg {
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
    /// The same as --format json.
    #[arg(long)]
    pub json: bool,
}

impl FormatOrJsonArg {
    pub fn json(&self) -> bool {
        self.json || self.format == Format::Json
    }
}

/// Notes and warnings of a command gathered for its JSON object, or printed on stderr as
/// `PROGRAM: COMMAND: note: ...` in text.
#[derive(Debug, Default, Clone, serde::Serialize)]
pub struct Remarks {
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
    #[serde(skip)]
    prefix: String,
    #[serde(skip)]
    json: bool,
}

impl Remarks {
    /// `prefix` such as `bearingd: import`; with `json` the remarks are kept for the object.
    pub fn new(prefix: &str, json: bool) -> Self {
        Remarks {
            prefix: prefix.to_string(),
            json,
            ..Default::default()
        }
    }

    pub fn note(&mut self, text: impl Into<String>) {
        let text = text.into();
        if !self.json {
            eprintln!("{}: note: {text}", self.prefix);
        }
        self.notes.push(text);
    }

    /// The notes and warnings of resolved conditions (speed, bearing, unit), in that order.
    pub fn extend(&mut self, notes: &[String], warnings: &[String]) {
        notes.iter().for_each(|n| self.note(n.as_str()));
        warnings.iter().for_each(|w| self.warning(w.as_str()));
    }

    pub fn warning(&mut self, text: impl Into<String>) {
        let text = text.into();
        if !self.json {
            eprintln!("{}: warning: {text}", self.prefix);
        }
        self.warnings.push(text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remarks_in_json_are_kept_for_the_object_and_serialize_as_two_lists() {
        let mut remarks = Remarks::new("bearingd: import", true);
        remarks.note("rpm from the file");
        remarks.warning("no bearing");
        let value = serde_json::to_value(&remarks).unwrap();
        assert_eq!(
            value,
            serde_json::json!({"notes": ["rpm from the file"], "warnings": ["no bearing"]})
        );
    }
}

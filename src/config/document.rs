//! From text to the raw form: TOML syntax, unknown keys, tables of the wrong shape.
//!
//! serde with `deny_unknown_fields` stops at the first unknown key. To still report every
//! unknown key at once, the document is parsed into toml's spanned tree first; after each serde
//! error the offending key is found by its span, reported with its key path and position,
//! removed from the tree, and the raw form is read again. Each round removes one entry, so the
//! loop ends. Syntax errors are reported (all that toml's recovering parser finds) and end the
//! reading: a half-understood file is not validated further.
//!
//! Not `serde_ignored`: it gives an ignored key's path but not its table's known keys, which
//! every unknown-key message lists (and the nearest of them, by strsim); serde's error has both.

use std::ops::Range;

use serde::Deserialize;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::error::ConfigProblem;
use super::raw::RawConfig;

/// What reading the text produced.
pub(crate) struct Reading {
    /// `None` after a syntax error.
    pub raw: Option<RawConfig>,
    /// Syntax errors, unknown keys, misshapen tables.
    pub problems: Vec<ConfigProblem>,
    /// Key paths removed because their shape was wrong; later problems under them are
    /// consequences (e.g. "no sensor" after a misshapen `sensors`) and are not reported again.
    pub removed: Vec<String>,
}

impl Reading {
    /// Whether a validation problem at `key` is only a consequence of a removed entry.
    pub fn shadows(&self, key: &str) -> bool {
        self.removed.iter().any(|removed| {
            key.strip_prefix(removed.as_str())
                .is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))
        })
    }
}

/// One step of a key path.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

pub(crate) fn read(text: &str) -> Reading {
    let (mut document, errors) = DeTable::parse_recoverable(text);
    if !errors.is_empty() {
        let mut problems: Vec<(usize, ConfigProblem)> = Vec::new();
        for error in &errors {
            let offset = error.span().map_or(usize::MAX, |span| span.start);
            let problem = syntax_problem(text, error);
            if !problems.iter().any(|(_, seen)| *seen == problem) {
                problems.push((offset, problem));
            }
        }
        return Reading {
            raw: None,
            problems: in_file_order(problems),
            removed: Vec::new(),
        };
    }

    // (offset in the text, problem): reported in the order of the file, not of serde's visits.
    let mut problems: Vec<(usize, ConfigProblem)> = Vec::new();
    let mut removed = Vec::new();
    // Each round removes one entry, so the number of entries bounds the rounds; the cap is a
    // second guard.
    for _ in 0..=count_entries(document.get_ref()).saturating_add(1) {
        let error = match RawConfig::deserialize(toml::de::Deserializer::from(document.clone())) {
            Ok(raw) => {
                return Reading {
                    raw: Some(raw),
                    problems: in_file_order(problems),
                    removed,
                }
            }
            Err(error) => error,
        };
        let located = error
            .span()
            .and_then(|span| locate(document.get_ref(), &span).map(|hit| (span, hit)));
        let Some((span, (path, found))) = located else {
            let offset = error.span().map_or(usize::MAX, |span| span.start);
            problems.push((offset, unplaced_problem(text, &error)));
            break;
        };
        let key = render_path(&path);
        let position = position(text, span.start);
        if let Some((unknown, known)) = parse_unknown_field(error.message()) {
            problems.push((
                span.start,
                unknown_key_problem(&key, &unknown, &known, &position),
            ));
        } else {
            problems.push((span.start, shape_problem(&key, &path, found, &position)));
            removed.push(key);
        }
        if !remove(document.get_mut(), &path) {
            break;
        }
    }
    Reading {
        raw: None,
        problems: in_file_order(problems),
        removed,
    }
}

fn in_file_order(mut problems: Vec<(usize, ConfigProblem)>) -> Vec<ConfigProblem> {
    problems.sort_by_key(|(offset, _)| *offset);
    problems.into_iter().map(|(_, problem)| problem).collect()
}

fn syntax_problem(text: &str, error: &toml::de::Error) -> ConfigProblem {
    let what = one_line(error.message());
    let fix = if what.contains("duplicate key") {
        "remove or rename one of the two definitions (a [table] may appear only once)"
    } else if what.contains("quote") || what.contains("string") {
        "fix the quoting: text values go in double quotes, e.g. transport = \"can\""
    } else if what.contains("unclosed") || what.contains('[') || what.contains(']') {
        "fix the brackets: close each [ with ], e.g. [analysis], [[sensors]] or \
         axes = [\"radial\"]"
    } else {
        "fix the TOML syntax there (see https://toml.io), e.g. rpm = 1772"
    };
    let key = match error.span() {
        Some(span) => position(text, span.start),
        None => "TOML syntax".to_string(),
    };
    ConfigProblem::new(key, format!("{what}; {fix}"))
}

fn unplaced_problem(text: &str, error: &toml::de::Error) -> ConfigProblem {
    let key = match error.span() {
        Some(span) => position(text, span.start),
        None => String::new(),
    };
    ConfigProblem::new(
        key,
        format!(
            "{}; fix this entry so that it matches config/bearingd.toml",
            one_line(error.message())
        ),
    )
}

fn unknown_key_problem(
    key: &str,
    unknown: &str,
    known: &[String],
    position: &str,
) -> ConfigProblem {
    let known_list = if known.is_empty() {
        "none".to_string()
    } else {
        known.join(", ")
    };
    let fix = match closest(unknown, known) {
        Some(near) => format!("rename it to `{near}` if that is what you meant, or remove it"),
        None => "remove it, or move it to the table where it belongs".to_string(),
    };
    ConfigProblem::new(
        key,
        format!("unknown key `{unknown}` at {position}; known keys here: {known_list}; {fix}"),
    )
}

fn shape_problem(key: &str, path: &[Step], found: &str, position: &str) -> ConfigProblem {
    let message = match path.last() {
        Some(Step::Key(name)) if name == "sensors" && path.len() == 1 => format!(
            "expected a list of [[sensors]] tables, found {} at {position}; write each sensor \
             as its own [[sensors]] section (double brackets)",
            article(found)
        ),
        Some(Step::Index(_)) => format!(
            "expected a table, found {} at {position}; write each sensor as its own \
             [[sensors]] section with key = value lines",
            article(found)
        ),
        _ => format!(
            "expected a table, found {} at {position}; write it as a [{}] section with \
             key = value lines",
            article(found),
            header(path)
        ),
    };
    ConfigProblem::new(key, message)
}

fn article(type_name: &str) -> String {
    match type_name {
        "integer" | "array" => format!("an {type_name}"),
        other => format!("a {other}"),
    }
}

/// `sensors[0].speed` → `sensors.speed`, the table header that defines it.
fn header(path: &[Step]) -> String {
    path.iter()
        .filter_map(|step| match step {
            Step::Key(k) => Some(k.as_str()),
            Step::Index(_) => None,
        })
        .collect::<Vec<_>>()
        .join(".")
}

fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|line| !line.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// serde's wording: "unknown field `x`, expected one of `a`, `b`" (or "expected `a`", or
/// "there are no fields"). Returns the unknown key and the known ones.
fn parse_unknown_field(message: &str) -> Option<(String, Vec<String>)> {
    if !message.starts_with("unknown field") {
        return None;
    }
    let mut quoted = message.split('`').skip(1).step_by(2).map(str::to_string);
    let unknown = quoted.next()?;
    Some((unknown, quoted.collect()))
}

/// The known key nearest to a misspelt one, if it is near enough to be a likely typo. The
/// distance is strsim's optimal string alignment: a swap of two neighbours is one edit, so that
/// `fualt` is one edit from `fault`.
fn closest<'a>(unknown: &str, known: &'a [String]) -> Option<&'a str> {
    known
        .iter()
        .map(|k| (strsim::osa_distance(unknown, k), k))
        .filter(|(distance, k)| *distance <= (k.chars().count() / 3).max(1))
        .min_by_key(|(distance, _)| *distance)
        .map(|(_, k)| k.as_str())
        .or_else(|| {
            // A word left out, e.g. a unit: `sample_rate` for `sample_rate_hz`, `refit_s` for
            // `refit_period_s`. Only when exactly one key fits.
            let words: Vec<&str> = unknown.split('_').collect();
            if !words.iter().any(|w| w.len() >= 3) {
                return None;
            }
            let mut fitting = known.iter().filter(|k| {
                let theirs: Vec<&str> = k.split('_').collect();
                words.iter().all(|w| theirs.contains(w))
            });
            match (fitting.next(), fitting.next()) {
                (Some(only), None) => Some(only.as_str()),
                _ => None,
            }
        })
}

/// `line L, column C` of a byte offset (1-based; columns count characters).
fn position(text: &str, offset: usize) -> String {
    let bytes = text.as_bytes();
    let before = &bytes[..offset.min(bytes.len())];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |newline| newline + 1);
    let column = before[line_start..]
        .iter()
        .filter(|&&b| (b & 0xC0) != 0x80)
        .count()
        + 1;
    format!("line {line}, column {column}")
}

fn render_path(path: &[Step]) -> String {
    let mut out = String::new();
    for step in path {
        match step {
            Step::Key(k) => {
                if !out.is_empty() {
                    out.push('.');
                }
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if bare {
                    out.push_str(k);
                } else {
                    out.push_str(&format!("{k:?}"));
                }
            }
            Step::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

fn count_entries(table: &DeTable<'_>) -> usize {
    table
        .values()
        .map(|value| 1 + count_value_entries(value.get_ref()))
        .sum()
}

fn count_value_entries(value: &DeValue<'_>) -> usize {
    match value {
        DeValue::Table(t) => count_entries(t),
        DeValue::Array(a) => a
            .iter()
            .map(|item| 1 + count_value_entries(item.get_ref()))
            .sum(),
        _ => 0,
    }
}

/// A candidate for the entry an error points at.
struct Hit {
    path: Vec<Step>,
    found: &'static str,
    /// The error points into the key itself (unknown keys do).
    on_key: bool,
    /// Length of the matching span: the smallest is the most specific.
    width: usize,
}

/// The entry an error span points at: its key path and the TOML type it holds.
///
/// Header tables (`[analysis]`) have spans covering only their header, so the whole tree is
/// searched rather than descending by span containment.
fn locate(table: &DeTable<'_>, span: &Range<usize>) -> Option<(Vec<Step>, &'static str)> {
    let mut hits = Vec::new();
    let mut path = Vec::new();
    collect_table(table, span, &mut path, &mut hits);
    hits.into_iter()
        .min_by_key(|hit| (!hit.on_key, hit.width, usize::MAX - hit.path.len()))
        .map(|hit| (hit.path, hit.found))
}

fn covers(outer: &Range<usize>, inner: &Range<usize>) -> bool {
    if inner.is_empty() {
        outer.start <= inner.start && inner.start < outer.end.max(outer.start + 1)
    } else {
        outer.start <= inner.start && inner.end <= outer.end
    }
}

fn collect_table(
    table: &DeTable<'_>,
    span: &Range<usize>,
    path: &mut Vec<Step>,
    hits: &mut Vec<Hit>,
) {
    for (key, value) in table.iter() {
        path.push(Step::Key(key.get_ref().to_string()));
        let key_span = key.span();
        if covers(&key_span, span) {
            hits.push(Hit {
                path: path.clone(),
                found: value.get_ref().type_str(),
                on_key: true,
                width: key_span.len(),
            });
        }
        collect_value(value, span, path, hits);
        path.pop();
    }
}

fn collect_value(
    value: &Spanned<DeValue<'_>>,
    span: &Range<usize>,
    path: &mut Vec<Step>,
    hits: &mut Vec<Hit>,
) {
    let value_span = value.span();
    if covers(&value_span, span) {
        hits.push(Hit {
            path: path.clone(),
            found: value.get_ref().type_str(),
            on_key: false,
            width: value_span.len(),
        });
    }
    match value.get_ref() {
        DeValue::Table(t) => collect_table(t, span, path, hits),
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                path.push(Step::Index(i));
                collect_value(item, span, path, hits);
                path.pop();
            }
        }
        _ => {}
    }
}

/// Removes the entry at `path`. A list item is replaced by an empty table instead, so that
/// the indices of its siblings, and the key paths in later messages, stay true.
fn remove(table: &mut DeTable<'_>, path: &[Step]) -> bool {
    match path {
        [Step::Key(k)] => table.remove(k.as_str()).is_some(),
        [Step::Key(k), rest @ ..] => table
            .get_mut(k.as_str())
            .is_some_and(|value| remove_in(value.get_mut(), rest)),
        _ => false,
    }
}

fn remove_in(value: &mut DeValue<'_>, path: &[Step]) -> bool {
    match (value, path) {
        (DeValue::Table(t), _) => remove(t, path),
        (DeValue::Array(items), [Step::Index(i)]) => match items.get_mut(*i) {
            Some(item) if !matches!(item.get_ref(), DeValue::Table(t) if t.is_empty()) => {
                *item = Spanned::new(item.span(), DeValue::Table(DeTable::new()));
                true
            }
            _ => false,
        },
        (DeValue::Array(items), [Step::Index(i), rest @ ..]) => items
            .get_mut(*i)
            .is_some_and(|item| remove_in(item.get_mut(), rest)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_lines_and_characters() {
        assert_eq!(position("a\nbé = 1", 5), "line 2, column 3");
        assert_eq!(position("", 10), "line 1, column 1");
    }

    #[test]
    fn typos_find_their_key() {
        let known: Vec<String> = ["fault", "onset_s", "sample_rate_hz", "window_s", "sigma"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(closest("fualt", &known), Some("fault"));
        assert_eq!(closest("sample_rate", &known), Some("sample_rate_hz"));
        assert_eq!(closest("banana", &known), None);
        assert_eq!(closest("window", &known), Some("window_s"));
        assert_eq!(closest("s", &known), None);
    }
}

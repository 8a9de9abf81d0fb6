//! The numeric-table reader shared by the text formats (plain CSV, PRONOSTIA, IMS).
//!
//! One pass, no regex, no allocation per row: each line is split lazily and only the chosen
//! column is parsed; every row is checked for its field count so a damaged row is reported with
//! its line number. A last line without a final newline that does not parse is the mark of a
//! file cut mid-row (a copy interrupted, a logger killed): it is dropped with a warning and the
//! rows before it are kept.
//!
//! Ours stays, not the `csv` crate: one reader serves `,`/`;`/tab tables and the
//! whitespace-aligned IMS files alike (csv covers only the delimited ones and would sit beside
//! it), numeric tables need no quoted separators, and the cut-last-row rule needs line ends.

use super::RecordingError;
use std::path::Path;

/// How fields are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Sep {
    Char(char),
    Whitespace,
}

impl Sep {
    /// From a sample line: `;` beats tab beats `,` (so `1,5;2,5` is seen as `;`-separated and
    /// its decimal commas are then reported), otherwise runs of spaces.
    pub(super) fn detect(line: &str) -> Sep {
        for c in [';', '\t', ','] {
            if line.contains(c) {
                return Sep::Char(c);
            }
        }
        Sep::Whitespace
    }

    pub(super) fn fields<'a>(self, line: &'a str) -> Fields<'a> {
        match self {
            Sep::Char(c) => Fields::Split(line.split(c)),
            Sep::Whitespace => Fields::Whitespace(line.split_ascii_whitespace()),
        }
    }
}

/// The fields of one line, trimmed and with one pair of surrounding double quotes removed.
pub(super) enum Fields<'a> {
    Split(std::str::Split<'a, char>),
    Whitespace(std::str::SplitAsciiWhitespace<'a>),
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a str;
    fn next(&mut self) -> Option<&'a str> {
        let raw = match self {
            Fields::Split(s) => s.next()?,
            Fields::Whitespace(s) => s.next()?,
        };
        let t = raw.trim();
        Some(
            t.strip_prefix('"')
                .and_then(|u| u.strip_suffix('"'))
                .unwrap_or(t),
        )
    }
}

/// One non-blank line of the file.
#[derive(Debug, Clone, Copy)]
pub(super) struct Line<'a> {
    /// 1-based line number in the file.
    pub number: usize,
    pub text: &'a str,
    /// The last line, and the file does not end with a newline.
    pub unterminated: bool,
}

/// Decodes the file as UTF-8 text (a leading byte-order mark is skipped).
pub(super) fn as_text<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str, RecordingError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let valid = &bytes[..e.valid_up_to()];
        RecordingError::MalformedRow {
            path: path.to_path_buf(),
            line: 1 + valid.iter().filter(|&&b| b == b'\n').count(),
            problem: "not text (invalid UTF-8); is this really a text table?".to_string(),
        }
    })
}

/// The non-blank lines, with their numbers; `\r\n` endings are accepted.
pub(super) fn lines(text: &str) -> impl Iterator<Item = Line<'_>> {
    let terminated = text.ends_with('\n');
    let body = if terminated {
        &text[..text.len() - 1]
    } else {
        text
    };
    let count = body.split('\n').count();
    body.split('\n').enumerate().filter_map(move |(i, raw)| {
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        (!line.trim().is_empty()).then_some(Line {
            number: i + 1,
            text: line,
            unterminated: !terminated && i + 1 == count,
        })
    })
}

/// The shape of a table, taken from its first non-blank line.
#[derive(Debug, Clone)]
pub(super) struct Layout {
    pub sep: Sep,
    /// Header names, or `column 1`, `column 2`, … when there is no header.
    pub names: Vec<String>,
    /// Line number of the header row, if the first line is one.
    pub header_line: Option<usize>,
    /// Line number of the first line.
    pub first_line: usize,
}

/// Reads the layout. The first line is a header when none of its fields is a number.
/// `sep` forces a separator; `None` detects it from the first line.
pub(super) fn layout(path: &Path, text: &str, sep: Option<Sep>) -> Result<Layout, RecordingError> {
    let Some(first) = lines(text).next() else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
            detail: "the file holds only blank lines".to_string(),
        });
    };
    let sep = sep.unwrap_or_else(|| Sep::detect(first.text));
    let fields: Vec<&str> = sep.fields(first.text).collect();
    let is_header = fields.iter().all(|f| f.parse::<f64>().is_err());
    let names = fields
        .iter()
        .enumerate()
        .map(|(i, f)| {
            if is_header && !f.is_empty() {
                f.to_string()
            } else {
                format!("column {}", i + 1)
            }
        })
        .collect();
    Ok(Layout {
        sep,
        names,
        header_line: is_header.then_some(first.number),
        first_line: first.number,
    })
}

/// One column of a table, read.
#[derive(Debug)]
pub(super) struct Column {
    pub samples: Vec<f64>,
    pub warnings: Vec<String>,
}

/// Reads column `col` (0-based) of every data row, checking every row's field count.
/// NaN and infinite values are refused with the line of the first one.
pub(super) fn read_column(
    path: &Path,
    text: &str,
    layout: &Layout,
    col: usize,
) -> Result<Column, RecordingError> {
    let n_fields = layout.names.len();
    let name = layout.names.get(col).cloned().unwrap_or_default();
    let mut samples = Vec::new();
    let mut warnings = Vec::new();
    let mut bad: Option<(usize, usize)> = None; // (sample index, line)
    let mut bad_count = 0usize;
    for line in lines(text) {
        if Some(line.number) == layout.header_line {
            continue;
        }
        let mut count = 0usize;
        let mut field = "";
        for (i, f) in layout.sep.fields(line.text).enumerate() {
            if i == col {
                field = f;
            }
            count = i + 1;
        }
        let problem = if count != n_fields {
            Some(format!(
                "{count} field(s) where line {} has {n_fields}",
                layout.first_line
            ))
        } else {
            match field.parse::<f64>() {
                Ok(v) => {
                    if !v.is_finite() {
                        bad_count += 1;
                        bad.get_or_insert((samples.len(), line.number));
                    }
                    samples.push(v);
                    None
                }
                Err(_) if field.is_empty() => Some(format!("column '{name}' is empty")),
                Err(_) => Some(format!("column '{name}': '{field}' is not a number")),
            }
        };
        if let Some(problem) = problem {
            if line.unterminated {
                warnings.push(format!(
                    "line {} is incomplete (the file ends mid-row, without a final newline); dropped it and kept the {} row(s) before it",
                    line.number,
                    samples.len()
                ));
                break;
            }
            return Err(RecordingError::MalformedRow {
                path: path.to_path_buf(),
                line: line.number,
                problem,
            });
        }
    }
    if let Some((index, line)) = bad {
        return Err(RecordingError::NonFinite {
            path: path.to_path_buf(),
            channel: name,
            index,
            count: bad_count,
            at: format!(" (line {line})"),
        });
    }
    if samples.is_empty() {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
            detail: "the table has no data rows".to_string(),
        });
    }
    Ok(Column { samples, warnings })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separators_and_quotes() {
        assert_eq!(Sep::detect("1;2,5"), Sep::Char(';'));
        assert_eq!(Sep::detect("1\t2"), Sep::Char('\t'));
        assert_eq!(Sep::detect("1, 2"), Sep::Char(','));
        assert_eq!(Sep::detect(" 1  2 "), Sep::Whitespace);
        let f: Vec<_> = Sep::Char(',').fields(" \"a\" , 2,").collect();
        assert_eq!(f, ["a", "2", ""]);
    }

    #[test]
    fn lines_skip_blanks_and_mark_the_unterminated_last() {
        let l: Vec<_> = lines("a\r\n\n b\nc")
            .map(|l| (l.number, l.text, l.unterminated))
            .collect();
        assert_eq!(l, [(1, "a", false), (3, " b", false), (4, "c", true)]);
        assert!(lines("a\n").all(|l| !l.unterminated));
    }

    #[test]
    fn header_detection() {
        let p = Path::new("t.csv");
        let l = layout(p, "time,x\n1,2\n", None).unwrap();
        assert_eq!(l.names, ["time", "x"]);
        assert_eq!(l.header_line, Some(1));
        let l = layout(p, "\n1 2\n", None).unwrap();
        assert_eq!(l.names, ["column 1", "column 2"]);
        assert_eq!((l.header_line, l.first_line), (None, 2));
    }
}

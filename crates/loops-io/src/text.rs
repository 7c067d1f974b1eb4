//! Text files as numbered data lines and fields: what the line-based readers share.

use std::path::Path;
use std::str::SplitAsciiWhitespace;

use crate::error::{IoError, Result};

/// The whole file as text, read at once (pose files are at most tens of MB).
///
/// Bytes that are not UTF-8 become U+FFFD instead of failing the whole file: in a comment they
/// do no harm, and in a data line they fail that line's number parsing with its line number.
/// A leading byte-order mark is dropped.
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|error| IoError::Open { path: path.to_path_buf(), error })?;
    let mut text =
        String::from_utf8(bytes).unwrap_or_else(|error| String::from_utf8_lossy(error.as_bytes()).into_owned());
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// The data lines of `text` with their 1-based line numbers, trimmed; blank lines and `#`
/// comment lines left out. `\n` and `\r\n` both end a line.
pub(crate) fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(index, line)| (index + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'))
}

/// How the fields of a line are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Delimiter {
    /// One character; fields are trimmed and may be quoted (`"x"`), and may be empty.
    Char(char),
    /// Runs of spaces and tabs; fields are never empty.
    Whitespace,
}

impl Delimiter {
    /// The fields of `line`.
    pub(crate) fn split(self, line: &str) -> Fields<'_> {
        match self {
            Self::Char(delimiter) => Fields::Char(line.split(delimiter)),
            Self::Whitespace => Fields::Whitespace(line.split_ascii_whitespace()),
        }
    }
}

/// The fields of one line (see [`Delimiter::split`]).
#[derive(Debug)]
pub(crate) enum Fields<'a> {
    Char(std::str::Split<'a, char>),
    Whitespace(SplitAsciiWhitespace<'a>),
}

impl<'a> Iterator for Fields<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        match self {
            Self::Char(split) => split.next().map(unquote),
            Self::Whitespace(split) => split.next(),
        }
    }
}

/// A delimited field without surrounding whitespace and one pair of double quotes.
fn unquote(field: &str) -> &str {
    let field = field.trim();
    field.strip_prefix('"').and_then(|inner| inner.strip_suffix('"')).unwrap_or(field)
}

/// Whether `field` reads as a number (finite or not): tells data rows from header rows.
pub(crate) fn is_number(field: &str) -> bool {
    field.parse::<f64>().is_ok()
}

/// A header row: a row none of whose fields is a number. A row mixing numbers and words is a
/// data row with a bad field, and fails as such.
pub(crate) fn is_header<'a>(mut fields: impl Iterator<Item = &'a str>) -> bool {
    !fields.any(is_number)
}

/// The finite number in `field`, which is column `column` (1-based); or what is wrong with it.
pub(crate) fn parse_finite(field: &str, column: usize) -> Result<f64, String> {
    match field.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(value),
        Ok(_) => Err(format!("column {column} ({}) is not finite", quoted(field))),
        Err(_) if field.is_empty() => Err(format!("column {column} is empty")),
        Err(_) => Err(format!("column {column} ({}) is not a number", quoted(field))),
    }
}

/// `field` quoted and escaped for a message, cut short when long (garbage can be long).
fn quoted(field: &str) -> String {
    const MAX_CHARS: usize = 40;
    match field.char_indices().nth(MAX_CHARS) {
        Some((end, _)) => format!("{:?}…", &field[..end]),
        None => format!("{field:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_lines_are_numbered_from_one_and_skip_comments_and_blanks() {
        let text = "# header\r\n1 2\r\n\r\n  \t\n  # indented comment\n3 4";
        let lines: Vec<_> = data_lines(text).collect();
        assert_eq!(lines, [(2, "1 2"), (6, "3 4")]);
    }

    #[test]
    fn fields_split_and_unquote() {
        let fields: Vec<_> = Delimiter::Char(',').split(" \"t\" , x,,y ").collect();
        assert_eq!(fields, ["t", "x", "", "y"]);
        let fields: Vec<_> = Delimiter::Whitespace.split("1\t 2  3").collect();
        assert_eq!(fields, ["1", "2", "3"]);
    }

    #[test]
    fn numbers_must_be_finite_and_errors_name_the_column() {
        assert_eq!(parse_finite("-1.5e3", 1), Ok(-1500.0));
        assert_eq!(parse_finite("abc", 3).unwrap_err(), r#"column 3 ("abc") is not a number"#);
        assert_eq!(parse_finite("NaN", 2).unwrap_err(), r#"column 2 ("NaN") is not finite"#);
        assert_eq!(parse_finite("-inf", 2).unwrap_err(), r#"column 2 ("-inf") is not finite"#);
        assert_eq!(parse_finite("", 4).unwrap_err(), "column 4 is empty");
        let long = "é".repeat(100);
        let expected = format!("column 1 (\"{}\"…) is not a number", "é".repeat(40));
        assert_eq!(parse_finite(&long, 1).unwrap_err(), expected);
    }

    #[test]
    fn a_header_has_no_number() {
        assert!(is_header(["t", "x", "y"].into_iter()));
        assert!(!is_header(["t", "1.0", "y"].into_iter()));
        assert!(!is_header(["nan", "x"].into_iter()));
    }
}

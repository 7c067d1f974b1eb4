//! Text files as numbered data lines and fields: what the line-based readers share.
//!
//! A file is read as a stream, one line at a time ([`Lines`]): memory holds one line, never the
//! file, and a line longer than [`MAX_LINE_BYTES`] is an error naming it, so a file with no line
//! breaks (`/dev/zero`, a binary file named as text) fails after 1 MiB instead of filling the
//! memory.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::str::SplitAsciiWhitespace;

use crate::error::{IoError, Result};

/// Longest line a text reader takes: 1 MiB. Pose, graph and detection lines are a few hundred
/// bytes (a g2o 3-D edge with its information matrix, ~500); a longer line means the file is
/// not text of a format read here.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The data lines of a text file, read one at a time: each with its 1-based line number,
/// trimmed; blank lines and `#` comment lines left out. `\n` and `\r\n` both end a line.
///
/// Bytes that are not UTF-8 become U+FFFD instead of failing the whole file: in a comment they
/// do no harm, and in a data line they fail that line's number parsing with its line number.
/// A leading byte-order mark is dropped.
#[derive(Debug)]
pub(crate) struct Lines<R> {
    path: PathBuf,
    reader: R,
    /// The number of the last line read.
    number: usize,
    bytes: Vec<u8>,
    line: String,
    /// Whether the last data line read is to be returned again (see [`Lines::peek`]).
    pending: bool,
}

/// The data lines of the file at `path`.
///
/// # Errors
/// [`IoError::Open`] when the file cannot be opened.
pub(crate) fn open_lines(path: &Path) -> Result<Lines<BufReader<File>>> {
    let file = File::open(path).map_err(|error| IoError::Open { path: path.to_path_buf(), error })?;
    Ok(Lines::new(path, BufReader::with_capacity(1 << 16, file)))
}

impl<R: BufRead> Lines<R> {
    /// The data lines `reader` holds, as the contents of `path`.
    pub(crate) fn new(path: &Path, reader: R) -> Self {
        Self { path: path.to_path_buf(), reader, number: 0, bytes: Vec::new(), line: String::new(), pending: false }
    }

    /// The next data line and its number, or `None` at the end of the file.
    ///
    /// # Errors
    /// [`IoError::Open`] when the file cannot be read; [`IoError::Parse`] for a line longer
    /// than [`MAX_LINE_BYTES`].
    pub(crate) fn next_data(&mut self) -> Result<Option<(usize, &str)>> {
        if self.pending {
            self.pending = false;
            return Ok(Some((self.number, self.line.trim())));
        }
        loop {
            self.bytes.clear();
            let limit = MAX_LINE_BYTES as u64 + 2;
            let read = (&mut self.reader)
                .take(limit)
                .read_until(b'\n', &mut self.bytes)
                .map_err(|error| IoError::Open { path: self.path.clone(), error })?;
            if read == 0 {
                return Ok(None);
            }
            self.number += 1;
            if self.bytes.last() == Some(&b'\n') {
                self.bytes.pop();
            }
            if self.bytes.last() == Some(&b'\r') {
                self.bytes.pop();
            }
            if self.bytes.len() > MAX_LINE_BYTES {
                return Err(IoError::parse(
                    &self.path,
                    self.number,
                    format!(
                        "the line is longer than {} MiB, the limit for one line: the file is not text of this format",
                        MAX_LINE_BYTES >> 20
                    ),
                ));
            }
            self.line.clear();
            match std::str::from_utf8(&self.bytes) {
                Ok(text) => self.line.push_str(text),
                Err(_) => self.line.push_str(&String::from_utf8_lossy(&self.bytes)),
            }
            if self.number == 1 && self.line.starts_with('\u{feff}') {
                self.line.drain(..'\u{feff}'.len_utf8());
            }
            let trimmed = self.line.trim();
            if !trimmed.is_empty() && !trimmed.starts_with('#') {
                return Ok(Some((self.number, self.line.trim())));
            }
        }
    }

    /// The next data line, which the next call to [`next_data`](Self::next_data) returns again.
    ///
    /// # Errors
    /// As [`next_data`](Self::next_data).
    pub(crate) fn peek(&mut self) -> Result<Option<(usize, &str)>> {
        if !self.pending && self.next_data()?.is_none() {
            return Ok(None);
        }
        self.pending = true;
        Ok(Some((self.number, self.line.trim())))
    }
}

/// The first `count` data lines of the file at `path` (fewer if it has fewer): what the
/// format sniffing looks at.
///
/// # Errors
/// As [`Lines::next_data`].
pub(crate) fn first_data_lines(path: &Path, count: usize) -> Result<Vec<String>> {
    let mut lines = open_lines(path)?;
    let mut out = Vec::new();
    while out.len() < count {
        match lines.next_data()? {
            Some((_, line)) => out.push(line.to_owned()),
            None => break,
        }
    }
    Ok(out)
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

/// How many fields a record of a format takes: what [`record`] checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Takes {
    /// Exactly this many (every line of a file of columns has the count of its first).
    Exactly(usize),
    /// The first count, or the second: a record whose trailing fields are optional, as a whole
    /// (an information matrix, a covariance, a score).
    Either(usize, usize),
    /// This many or more: a first line with further columns the format allows (EuRoC's
    /// velocities and biases); the lines after it take [`Takes::Exactly`] its count.
    AtLeast(usize),
}

impl Takes {
    fn allows(self, count: usize) -> bool {
        match self {
            Self::Exactly(n) => count == n,
            Self::Either(a, b) => count == a || count == b,
            Self::AtLeast(n) => count >= n,
        }
    }

    /// The most fields a record takes, if there is a most.
    fn most(self) -> Option<usize> {
        match self {
            Self::Exactly(n) => Some(n),
            Self::Either(a, b) => Some(a.max(b)),
            Self::AtLeast(_) => None,
        }
    }
}

impl std::fmt::Display for Takes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Exactly(n) => write!(f, "{n}"),
            Self::Either(a, b) => write!(f, "{a} or {b}"),
            Self::AtLeast(n) => write!(f, "at least {n}"),
        }
    }
}

/// The fields of one record: `fields` (one data line's, split), when there are as many as
/// `takes` allows. This is the one rule of every text reader for how long a record is: a line
/// with more fields than its record takes is not read for its first fields with the rest
/// dropped (two lines run together would lose the second pose without a word), and one with
/// fewer is not padded.
///
/// # Errors
/// What is wrong, for the line's error: `expected N columns{layout}, found M`, then the first
/// field past the record's end (named, with its column) or the last field of a line that ends
/// early. `layout` (called only then) says what a record looks like: ` (timestamp tx ty tz
/// ...)`, ` as on line 1`.
pub(crate) fn record<'a>(
    fields: impl Iterator<Item = &'a str>,
    takes: Takes,
    layout: impl FnOnce() -> String,
) -> Result<Vec<&'a str>, String> {
    let fields: Vec<&str> = fields.collect();
    let found = fields.len();
    if takes.allows(found) {
        return Ok(fields);
    }
    let detail = match (takes.most(), fields.last()) {
        (Some(most), _) if found > most => format!(
            ": column {} ({}) is past the end of the record, at column {most} (two records run together on one \
             line?)",
            most + 1,
            quoted(fields[most])
        ),
        (_, Some(last)) => format!(": the line ends after column {found} ({})", quoted(last)),
        (_, None) => String::new(),
    };
    let columns = if takes == Takes::Exactly(1) { "column" } else { "columns" };
    Err(format!("expected {takes} {columns}{}, found {found}{detail}", layout()))
}

/// Checks that a record a reader skips (a type of its format that holds no pose) does not hold
/// another record after its own: none of `fields` (one line's, its tag first) but the first is
/// a tag of the format (`is_tag`). A skipped line that two records were run into would
/// otherwise take the second, a pose, with it.
///
/// # Errors
/// The column and the tag of the second record, for the line's error.
pub(crate) fn check_one_record<'a>(
    fields: impl Iterator<Item = &'a str>,
    is_tag: impl Fn(&str) -> bool,
) -> Result<(), String> {
    match fields.enumerate().skip(1).find(|(_, field)| is_tag(field)) {
        Some((k, tag)) => Err(format!(
            "column {} ({}) starts another record in a line of a record this reader skips (two records run \
             together on one line?)",
            k + 1,
            quoted(tag)
        )),
        None => Ok(()),
    }
}

/// Checks that each of `fields`, which start at column `first_column` (1-based), is a number
/// (finite or not): the further columns a reader ignores (a covariance, EuRoC's velocities) are
/// still the record's, and a word among them is a defect of the line, not data to skip.
pub(crate) fn check_numbers(fields: &[&str], first_column: usize) -> Result<(), String> {
    match fields.iter().position(|field| !is_number(field)) {
        Some(k) => Err(format!("column {} ({}) is not a number", first_column + k, quoted(fields[k]))),
        None => Ok(()),
    }
}

/// Whether `field` reads as a number (finite or not): tells data rows from header rows.
pub(crate) fn is_number(field: &str) -> bool {
    field.parse::<f64>().is_ok()
}

/// A header row: a row none of whose fields is a number, or holds one among its words. A row
/// mixing numbers and words is a data row with a bad field, and fails as such; so does a row of
/// records run together by another delimiter (`0.25 0 0 0 0 0 0 1,1.25 1 2 ...` has fields
/// that are no numbers, but hold them), which is no header to skip.
pub(crate) fn is_header<'a>(mut fields: impl Iterator<Item = &'a str>) -> bool {
    !fields.any(|field| field.split_ascii_whitespace().any(is_number))
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

    /// Every data line of `text`.
    fn data_lines(text: &str) -> Vec<(usize, String)> {
        let mut lines = Lines::new(Path::new("t.txt"), text.as_bytes());
        let mut out = Vec::new();
        while let Some((number, line)) = lines.next_data().unwrap() {
            out.push((number, line.to_owned()));
        }
        out
    }

    #[test]
    fn data_lines_are_numbered_from_one_and_skip_comments_and_blanks() {
        let text = "\u{feff}# header\r\n1 2\r\n\r\n  \t\n  # indented comment\n3 4";
        assert_eq!(data_lines(text), [(2, "1 2".to_owned()), (6, "3 4".to_owned())]);
        assert_eq!(data_lines("\u{feff}5 6\n"), [(1, "5 6".to_owned())]);
        let mut lines = Lines::new(Path::new("t.txt"), &b"a\0b\xff"[..]);
        assert_eq!(lines.next_data().unwrap(), Some((1, "a\u{0}b\u{fffd}")));
        let mut lines = Lines::new(Path::new("t.txt"), &b"# c\n1\n2\n"[..]);
        assert_eq!(lines.peek().unwrap(), Some((2, "1")));
        assert_eq!(lines.peek().unwrap(), Some((2, "1")));
        assert_eq!(lines.next_data().unwrap(), Some((2, "1")));
        assert_eq!(lines.next_data().unwrap(), Some((3, "2")));
        assert_eq!(lines.peek().unwrap(), None);
        assert_eq!(lines.next_data().unwrap(), None);
    }

    #[test]
    fn a_line_longer_than_the_limit_is_an_error_naming_it() {
        let mut text = "1 2\n".to_owned();
        text.push_str(&"7".repeat(MAX_LINE_BYTES));
        text.push_str("\r\n3 4\n");
        assert_eq!(data_lines(&text).len(), 3, "a line of exactly the limit reads");
        text.insert(5, '7');
        let mut lines = Lines::new(Path::new("t.txt"), text.as_bytes());
        assert!(lines.next_data().unwrap().is_some());
        let error = lines.next_data().unwrap_err();
        assert_eq!(
            error.to_string(),
            "t.txt line 2: the line is longer than 1 MiB, the limit for one line: the file is not text of this format"
        );
        let zeros = std::io::repeat(0).take(1 << 40);
        let error = Lines::new(Path::new("zero"), BufReader::new(zeros)).next_data().unwrap_err();
        assert_eq!(error.line(), Some(1));
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
    fn a_record_takes_its_count_of_fields_and_errors_name_the_field() {
        let layout = || " (VERTEX_SE2 id x y theta)".to_owned();
        let line = "VERTEX_SE2 1 1 0 0 VERTEX_SE2 2 2 0 0";
        let error = record(line.split_ascii_whitespace(), Takes::Exactly(5), layout).unwrap_err();
        assert_eq!(
            error,
            r#"expected 5 columns (VERTEX_SE2 id x y theta), found 10: column 6 ("VERTEX_SE2") is past the end of the record, at column 5 (two records run together on one line?)"#
        );
        let error = record("VERTEX_SE2 1 1 0".split_ascii_whitespace(), Takes::Exactly(5), layout).unwrap_err();
        assert_eq!(
            error,
            r#"expected 5 columns (VERTEX_SE2 id x y theta), found 4: the line ends after column 4 ("0")"#
        );
        assert_eq!(record("a b c d".split(' '), Takes::Either(4, 8), String::new).unwrap().len(), 4);
        let error = record("a b c d e".split(' '), Takes::Either(4, 8), String::new).unwrap_err();
        assert_eq!(error, r#"expected 4 or 8 columns, found 5: the line ends after column 5 ("e")"#);
        let error = record("1 2 3 4 5 6 7 8 9".split(' '), Takes::Either(4, 8), String::new).unwrap_err();
        assert!(error.contains(r#"column 9 ("9") is past the end"#), "{error}");
        assert_eq!(record("1 2 3".split(' '), Takes::AtLeast(2), String::new).unwrap(), ["1", "2", "3"]);
        let error = record("1".split(' '), Takes::AtLeast(2), || " (t, t')".to_owned()).unwrap_err();
        assert_eq!(error, r#"expected at least 2 columns (t, t'), found 1: the line ends after column 1 ("1")"#);
        let tags = |field: &str| field == "loop";
        assert_eq!(check_one_record("odom2 0 0 0".split(' '), tags), Ok(()));
        let error = check_one_record("odom2 0 0 loop 1 2".split(' '), tags).unwrap_err();
        assert!(error.starts_with(r#"column 4 ("loop") starts another record"#), "{error}");
        assert_eq!(check_numbers(&["1", "nan"], 9), Ok(()));
        assert_eq!(check_numbers(&["1", "x"], 9).unwrap_err(), r#"column 10 ("x") is not a number"#);
    }

    #[test]
    fn a_header_has_no_number() {
        assert!(is_header(["t", "x", "y"].into_iter()));
        assert!(!is_header(["t", "1.0", "y"].into_iter()));
        assert!(!is_header(["nan", "x"].into_iter()));
        assert!(is_header(["p_x [m]", "time"].into_iter()));
        assert!(!is_header(["0.25 0 0 1", "1.25 1 2 1"].into_iter()), "records run together");
        assert!(!is_header(["loop 2.25 0.25 0.5", "loop 3.25 1.25 0.5"].into_iter()));
    }
}

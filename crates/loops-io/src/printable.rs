//! Text read from a file, made fit for a one-line message: names (topics, frames, schema
//! names) and libraries' messages. A leaf module: the error types and the modules that
//! format names (`topic`) both use it.

use std::fmt;

/// `text` with its control characters escaped (`\n`, `\u{1b}`): names read from a file (topics,
/// frames, schema names) go into one-line messages and onto terminals as they are otherwise.
pub(crate) fn printable(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A library's message (SQLite, a YAML parser, a codec) on one line: its line breaks and runs
/// of white space become one space, its other control characters are escaped.
pub(crate) fn one_line(message: &dyn fmt::Display) -> String {
    let text = message.to_string();
    printable(&text.split_whitespace().collect::<Vec<_>>().join(" ")).into_owned()
}

//! The one error type of the readers: every error names the file, and the line where there is one.

use std::path::{Path, PathBuf};

use crate::format::Format;

/// `Result` with [`IoError`] as the default error type.
pub type Result<T, E = IoError> = std::result::Result<T, E>;

/// Everything that can go wrong reading a pose file. The message always starts with the file's
/// path, then `line N` where a line is to blame: `drive.tum line 12: column 3 ("abc") is not a
/// number`.
///
/// Each message is complete on its own, so the wrapped errors (`error` fields) are public fields
/// to match on and are not repeated as [`source`](std::error::Error::source): a report that
/// walks the source chain (`anyhow`'s `{:#}`) prints every cause once.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be read: missing, a directory, no permission.
    #[error("{}: cannot read the file: {error}", .path.display())]
    Open {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// A line that does not fit the format.
    #[error("{} line {line}: {message}", .path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong, naming the 1-based column and the offending text where there is one:
        /// `column 3 ("abc") is not a number`.
        message: String,
    },
    /// A file with no data lines (only blank lines, comments or a header).
    #[error("{}: no poses: the file has no data lines", .path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// Poses that the core rejects as a trajectory (duplicate timestamps, too few poses, ...),
    /// located in the file.
    #[error("{}", trajectory_message(.path, *.line, *.previous_line, .error))]
    Trajectory {
        /// The file.
        path: PathBuf,
        /// The line of the pose the core names, when it names one.
        line: Option<usize>,
        /// For timestamps out of order: the line of the pose before (comments and blank lines
        /// may lie between the two).
        previous_line: Option<usize>,
        /// What the core said, with pose indices rather than lines.
        error: loops_core::Error,
    },
    /// No format was given and the file's extension does not tell it.
    #[error("{}: {}", .path.display(), unknown_format_message(.extension.as_deref()))]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The file's extension, if it has one.
        extension: Option<String>,
    },
}

impl IoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Open { path, .. }
            | Self::Parse { path, .. }
            | Self::Empty { path }
            | Self::Trajectory { path, .. }
            | Self::UnknownFormat { path, .. } => path,
        }
    }

    /// The 1-based line the error is about, when there is one.
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Parse { line, .. } => Some(*line),
            Self::Trajectory { line, .. } => *line,
            Self::Open { .. } | Self::Empty { .. } | Self::UnknownFormat { .. } => None,
        }
    }

    pub(crate) fn parse(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Self::Parse {
            path: path.to_path_buf(),
            line,
            message: message.into(),
        }
    }
}

/// The core's message in terms of the file: lines instead of pose indices.
fn trajectory_message(
    path: &Path,
    line: Option<usize>,
    previous_line: Option<usize>,
    error: &loops_core::Error,
) -> String {
    use loops_core::Error;

    let location = match line {
        Some(line) => format!("{} line {line}", path.display()),
        None => path.display().to_string(),
    };
    let what = match (line, error) {
        (
            Some(_),
            Error::TimestampsNotIncreasing {
                previous_s,
                value_s,
                ..
            },
        ) => {
            let previous = previous_line
                .map(|p| format!(" (line {p})"))
                .unwrap_or_default();
            format!(
                "timestamps must strictly increase: {value_s} s is not after {previous_s} s{previous}"
            )
        }
        (Some(_), Error::NonFiniteTimestamp { value, .. }) => {
            format!("the timestamp is not finite ({value})")
        }
        (Some(_), Error::NonFiniteCoordinate { axis, value, .. }) => {
            format!("coordinate {axis} of the position is not finite ({value})")
        }
        _ => error.to_string(),
    };
    format!("{location}: {what}")
}

fn unknown_format_message(extension: Option<&str>) -> String {
    let known: Vec<String> = Format::ALL
        .iter()
        .map(|format| {
            let extensions: Vec<String> = format
                .extensions()
                .iter()
                .map(|e| format!(".{e}"))
                .collect();
            format!("{} for {}", extensions.join(" or "), format.name())
        })
        .collect();
    let names: Vec<&str> = Format::ALL.iter().map(|format| format.name()).collect();
    let given = match extension {
        Some(extension) => format!("the extension {:?}", format!(".{extension}")),
        None => "a file without an extension".to_owned(),
    };
    format!(
        "cannot tell the file format from {given}: expected {}, or name the format ({})",
        known.join(", "),
        names.join(", ")
    )
}

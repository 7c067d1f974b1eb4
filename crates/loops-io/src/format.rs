//! File formats by name and extension, and the reader that picks one.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use crate::csv::parse_csv;
use crate::error::{IoError, Result};
use crate::table::PoseTable;
use crate::text::{self, Delimiter};
use crate::tum::parse_tum;

/// A pose file format this crate reads.
///
/// Names (for [`FromStr`] and [`Display`](fmt::Display)) are lower case: `tum`, `csv`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Format {
    /// TUM RGB-D: `timestamp tx ty tz qx qy qz qw` a line ([`read_tum`](crate::read_tum)).
    Tum,
    /// Delimited `t,x,y[,z]` with an optional header ([`read_csv`](crate::read_csv)).
    Csv,
}

/// The names [`Format::from_str`] accepts, as the error lists them.
const NAMES: &str = "tum, csv";

impl Format {
    /// Every format, in the order error messages list them.
    pub const ALL: [Format; 2] = [Format::Tum, Format::Csv];

    /// The format's name: `tum`, `csv`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tum => "tum",
            Self::Csv => "csv",
        }
    }

    /// The file extensions (without the dot, lower case) that [`from_path`](Self::from_path)
    /// takes for this format.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::Tum => &["tum", "txt"],
            Self::Csv => &["csv"],
        }
    }

    /// The format a file's extension suggests, in any case: `.tum` and `.txt` are TUM, `.csv`
    /// is CSV. `None` for other extensions and none. Only the name is looked at, not the
    /// contents (but see [`read_trajectory`]).
    ///
    /// # Examples
    /// ```
    /// use loops_io::Format;
    /// assert_eq!(Format::from_path("runs/fr2_desk_groundtruth.TXT"), Some(Format::Tum));
    /// assert_eq!(Format::from_path("drive.csv"), Some(Format::Csv));
    /// assert_eq!(Format::from_path("drive.bag"), None);
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Option<Format> {
        let extension = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|format| format.extensions().contains(&extension.as_str()))
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Format {
    type Err = loops_core::Error;

    /// The format named `name`, in any case.
    ///
    /// # Errors
    /// [`loops_core::Error::UnknownName`] listing the names, for any other name.
    fn from_str(name: &str) -> std::result::Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|format| format.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| loops_core::Error::UnknownName {
                kind: "file format",
                name: name.to_owned(),
                expected: NAMES,
            })
    }
}

/// Reads a pose file in `format`, or when `None` in the format its extension suggests
/// ([`Format::from_path`]).
///
/// One exception to the extension: a `.csv` file whose first data line has no `,` `;` or tab
/// but 8 numbers separated by spaces is read as TUM. Such files are common (the UrbanNav
/// ground truth `gt_slam_*.csv` is TUM), and as CSV they would fail.
///
/// # Errors
/// [`IoError::UnknownFormat`] when `format` is `None` and the extension does not tell it;
/// otherwise as [`read_tum`](crate::read_tum) or [`read_csv`](crate::read_csv).
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{Format, read_trajectory};
///
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}.log", std::process::id()));
/// std::fs::write(&path, "t,x,y\n0,0,0\n1,1,0\n")?;
/// assert!(read_trajectory(&path, None).is_err()); // .log: no format known
/// let traj = read_trajectory(&path, Some("csv".parse()?))?.to_trajectory()?;
/// assert_eq!((traj.len(), traj.dim()), (2, 2));
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_trajectory(path: impl AsRef<Path>, format: Option<Format>) -> Result<PoseTable> {
    let path = path.as_ref();
    let format = match format {
        Some(format) => format,
        None => Format::from_path(path).ok_or_else(|| IoError::UnknownFormat {
            path: path.to_path_buf(),
            extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
        })?,
    };
    let text = text::read_text(path)?;
    match format {
        Format::Csv if looks_like_tum(&text) => parse_tum(path, &text),
        Format::Csv => parse_csv(path, &text),
        Format::Tum => parse_tum(path, &text),
    }
}

/// Whether the first data line is 8 space-separated numbers with no CSV delimiter.
fn looks_like_tum(text: &str) -> bool {
    text::data_lines(text).next().is_some_and(|(_, line)| {
        !line.contains([',', ';', '\t'])
            && Delimiter::Whitespace.split(line).count() == 8
            && Delimiter::Whitespace.split(line).all(text::is_number)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_the_error_lists_them_all() {
        for format in Format::ALL {
            assert_eq!(format.name().parse::<Format>(), Ok(format));
            assert_eq!(format.name().to_uppercase().parse::<Format>(), Ok(format));
            assert_eq!(format.to_string(), format.name());
        }
        let names: Vec<&str> = Format::ALL.iter().map(|format| format.name()).collect();
        assert_eq!(NAMES, names.join(", "));
    }

    #[test]
    fn extensions_belong_to_one_format() {
        let mut extensions: Vec<&str> = Format::ALL
            .iter()
            .flat_map(|format| format.extensions())
            .copied()
            .collect();
        let count = extensions.len();
        extensions.sort_unstable();
        extensions.dedup();
        assert_eq!(extensions.len(), count);
    }

    #[test]
    fn tum_in_a_csv_is_recognised() {
        assert!(looks_like_tum("# c\n1 0 0 0 0 0 -0 1\n"));
        assert!(!looks_like_tum("1,0,0,0,0,0,0,1\n"));
        assert!(!looks_like_tum("1 0 0\n"));
        assert!(!looks_like_tum("t x y z qx qy qz qw\n1 0 0 0 0 0 0 1\n"));
    }
}

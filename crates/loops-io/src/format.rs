//! File formats by name and extension, and the reader that picks one.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use crate::csv::parse_csv;
use crate::error::{IoError, Result};
use crate::euroc::{looks_like_euroc, parse_euroc};
use crate::graph::{looks_like_graph, parse_pose_graph};
use crate::kitti::parse_kitti;
use crate::mcap::{McapOptions, read_mcap};
use crate::table::PoseTable;
use crate::text::{self, Delimiter};
use crate::timing::Timing;
use crate::tuc::{looks_like_tuc, parse_tuc};
use crate::tum::parse_tum;

/// A pose file format this crate reads.
///
/// Names (for [`FromStr`] and [`Display`](fmt::Display)) are lower case: `tum`, `csv`, `kitti`,
/// `euroc`, `g2o`, `tuc`, `mcap`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Format {
    /// TUM RGB-D: `timestamp tx ty tz qx qy qz qw` a line ([`read_tum`](crate::read_tum)).
    Tum,
    /// Delimited `t,x,y[,z]` with an optional header ([`read_csv`](crate::read_csv)).
    Csv,
    /// KITTI: `[time] r00 r01 r02 tx r10 ... tz` a line ([`read_kitti`](crate::read_kitti)).
    Kitti,
    /// EuRoC ground truth: `timestamp [ns], p_xyz, q_wxyz, ...` ([`read_euroc`](crate::read_euroc)).
    Euroc,
    /// g2o or TORO pose graph: its vertices ([`read_pose_graph`](crate::read_pose_graph)).
    G2o,
    /// libRSF (TU Chemnitz) ground truth: `point2` / `point3` lines ([`read_tuc`](crate::read_tuc)).
    Tuc,
    /// MCAP, from ROS 2 or Foxglove ([`read_mcap`](crate::read_mcap)).
    Mcap,
}

/// The names [`Format::from_str`] accepts, as the error lists them.
const NAMES: &str = "tum, csv, kitti, euroc, g2o, tuc, mcap";

impl Format {
    /// Every format, in the order error messages list them.
    pub const ALL: [Format; 7] =
        [Format::Tum, Format::Csv, Format::Kitti, Format::Euroc, Format::G2o, Format::Tuc, Format::Mcap];

    /// The format's name: `tum`, `csv`, ...
    pub fn name(self) -> &'static str {
        match self {
            Self::Tum => "tum",
            Self::Csv => "csv",
            Self::Kitti => "kitti",
            Self::Euroc => "euroc",
            Self::G2o => "g2o",
            Self::Tuc => "tuc",
            Self::Mcap => "mcap",
        }
    }

    /// The file extensions (without the dot, lower case) that [`from_path`](Self::from_path)
    /// takes for this format. KITTI, EuRoC and libRSF files have the extensions of TUM and CSV
    /// (`.txt`, `.csv`) and none of their own: [`read_trajectory`] tells them by their first
    /// line.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::Tum => &["tum", "txt"],
            Self::Csv => &["csv"],
            Self::G2o => &["g2o", "graph"],
            Self::Mcap => &["mcap"],
            Self::Kitti | Self::Euroc | Self::Tuc => &[],
        }
    }

    /// The format a file's extension suggests, in any case: `.tum` and `.txt` are TUM, `.csv`
    /// is CSV, `.g2o` and `.graph` are pose graphs, `.mcap` is MCAP. `None` for other extensions
    /// and none. Only the name is looked at, not the contents (but see [`read_trajectory`]).
    ///
    /// # Examples
    /// ```
    /// use loops_io::Format;
    /// assert_eq!(Format::from_path("runs/fr2_desk_groundtruth.TXT"), Some(Format::Tum));
    /// assert_eq!(Format::from_path("drive.csv"), Some(Format::Csv));
    /// assert_eq!(Format::from_path("drive.mcap"), Some(Format::Mcap));
    /// assert_eq!(Format::from_path("drive.bag"), None);
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Option<Format> {
        let extension = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Self::ALL.into_iter().find(|format| format.extensions().contains(&extension.as_str()))
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
        Self::ALL.into_iter().find(|format| format.name().eq_ignore_ascii_case(name)).ok_or_else(|| {
            loops_core::Error::UnknownName { kind: "file format", name: name.to_owned(), expected: NAMES }
        })
    }
}

/// How [`read_trajectory_with`] reads a file: the format, and what the formats that need more
/// than the file take.
///
/// # Examples
/// ```
/// use loops_io::{Format, McapOptions, ReadOptions, Timing};
/// let mulran = ReadOptions::default().format(Format::Kitti).timing(Timing::RateHz(10.0));
/// let odometry = ReadOptions::default().mcap(McapOptions::default().topic("/odom"));
/// # let _ = (mulran, odometry);
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub struct ReadOptions {
    /// The format; `None` tells it from the extension and the first line (see
    /// [`read_trajectory`]).
    pub format: Option<Format>,
    /// For MCAP: topic, time source, frame pair.
    pub mcap: McapOptions,
    /// For KITTI and pose graphs: a rate or a times file instead of the file's times.
    pub timing: Timing,
}

impl ReadOptions {
    /// Reads `format`.
    pub fn format(mut self, format: Format) -> Self {
        self.format = Some(format);
        self
    }

    /// Reads MCAP files with `mcap`.
    pub fn mcap(mut self, mcap: McapOptions) -> Self {
        self.mcap = mcap;
        self
    }

    /// Times poses by `timing`.
    pub fn timing(mut self, timing: Timing) -> Self {
        self.timing = timing;
        self
    }
}

/// Reads a pose file in `format`, or when `None` in the format its extension and first line
/// suggest; the other options at their defaults. See [`read_trajectory_with`].
///
/// # Errors
/// As [`read_trajectory_with`].
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
    read_trajectory_with(path, &ReadOptions { format, ..ReadOptions::default() })
}

/// Reads a pose file as `options` say: in `options.format`, or when `None` in the format its
/// extension ([`Format::from_path`]) and its first data line suggest.
///
/// The first line overrides the extension where the extension is shared: a `.txt` file whose
/// first data line is 12 or 13 numbers is KITTI, `point2` / `point3` / `angle` is libRSF (TUC),
/// `VERTEX...` / `EDGE...` is a pose graph; a `.csv` file whose first data line is 8
/// space-separated numbers is TUM (the UrbanNav ground truth `gt_slam_*.csv`), and at least 8
/// comma-separated numbers starting with a nanosecond integer is EuRoC. A pose graph gives its
/// vertices ([`read_pose_graph`](crate::read_pose_graph) gives the edges too).
///
/// # Errors
/// [`IoError::UnknownFormat`] when `format` is `None` and the extension does not tell it;
/// otherwise as the format's reader.
pub fn read_trajectory_with(path: impl AsRef<Path>, options: &ReadOptions) -> Result<PoseTable> {
    let path = path.as_ref();
    let format = match options.format {
        Some(format) => format,
        None => Format::from_path(path).ok_or_else(|| IoError::UnknownFormat {
            path: path.to_path_buf(),
            extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
        })?,
    };
    if format == Format::Mcap {
        return read_mcap(path, &options.mcap);
    }
    let text = text::read_text(path)?;
    let sniffed = match (options.format, format) {
        (Some(_), _) => format,
        (None, Format::Tum) if looks_like_kitti(&text) => Format::Kitti,
        (None, Format::Tum) if looks_like_tuc(&text) => Format::Tuc,
        (None, Format::Tum) if looks_like_graph(&text) => Format::G2o,
        (None, Format::Csv) if looks_like_tum(&text) => Format::Tum,
        (None, Format::Csv) if looks_like_euroc(&text) => Format::Euroc,
        (None, format) => format,
    };
    match sniffed {
        Format::Tum => parse_tum(path, &text),
        Format::Csv => parse_csv(path, &text),
        Format::Kitti => parse_kitti(path, &text, &options.timing),
        Format::Euroc => parse_euroc(path, &text),
        Format::G2o => parse_pose_graph(path, &text, &options.timing).map(|graph| graph.vertices),
        Format::Tuc => parse_tuc(path, &text),
        Format::Mcap => unreachable!("MCAP is read above"),
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

/// Whether the first data line is 12 or 13 space-separated numbers.
fn looks_like_kitti(text: &str) -> bool {
    text::data_lines(text).next().is_some_and(|(_, line)| {
        let fields = || line.split_ascii_whitespace();
        matches!(fields().count(), 12 | 13) && fields().all(text::is_number)
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
        let mut extensions: Vec<&str> = Format::ALL.iter().flat_map(|format| format.extensions()).copied().collect();
        let count = extensions.len();
        extensions.sort_unstable();
        extensions.dedup();
        assert_eq!(extensions.len(), count);
    }

    #[test]
    fn kitti_is_recognised() {
        assert!(looks_like_kitti("# c\n0 1 0 0 0 0 1 0 0 0 0 1 0\n"));
        assert!(looks_like_kitti("1 0 0 0 0 1 0 0 0 0 1 0\n"));
        assert!(!looks_like_kitti("1 0 0 0 0 0 0 1\n"));
    }

    #[test]
    fn tum_in_a_csv_is_recognised() {
        assert!(looks_like_tum("# c\n1 0 0 0 0 0 -0 1\n"));
        assert!(!looks_like_tum("1,0,0,0,0,0,0,1\n"));
        assert!(!looks_like_tum("1 0 0\n"));
        assert!(!looks_like_tum("t x y z qx qy qz qw\n1 0 0 0 0 0 0 1\n"));
    }
}

//! The pose file formats by name and extension.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// A pose file format this crate reads.
///
/// Names (for [`FromStr`] and [`Display`](fmt::Display)) are lower case: `tum`, `csv`, `kitti`,
/// `euroc`, `g2o`, `tuc`, `mcap`, `rosbag2`, `ros1`.
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
    /// A rosbag2 bag: its folder, its `metadata.yaml`, or one of its files, sqlite3 (`.db3`) or
    /// MCAP, compressed or not ([`read_rosbag2`](crate::read_rosbag2)).
    Rosbag2,
    /// A ROS 1 bag, format 2.0 (`.bag`; [`read_ros1`](crate::read_ros1)).
    Ros1,
}

/// The names [`Format::from_str`] accepts, as the error lists them.
const NAMES: &str = "tum, csv, kitti, euroc, g2o, tuc, mcap, rosbag2, ros1";

impl Format {
    /// Every format, in the order error messages list them.
    pub const ALL: [Format; 9] = [
        Format::Tum,
        Format::Csv,
        Format::Kitti,
        Format::Euroc,
        Format::G2o,
        Format::Tuc,
        Format::Mcap,
        Format::Rosbag2,
        Format::Ros1,
    ];

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
            Self::Rosbag2 => "rosbag2",
            Self::Ros1 => "ros1",
        }
    }

    /// The file extensions (without the dot, lower case) that [`from_path`](Self::from_path)
    /// takes for this format. KITTI files are `.kitti` as evo writes them, or `.txt`; EuRoC and
    /// libRSF files have the extensions of TUM and CSV (`.txt`, `.csv`) and none of their own: [`read_trajectory`](crate::read_trajectory) tells them by
    /// their first line.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::Tum => &["tum", "txt"],
            Self::Csv => &["csv"],
            Self::G2o => &["g2o", "graph"],
            Self::Mcap => &["mcap"],
            Self::Rosbag2 => &["db3", "yaml", "zstd", "lz4"],
            Self::Ros1 => &["bag"],
            Self::Kitti => &["kitti"],
            Self::Euroc | Self::Tuc => &[],
        }
    }

    /// The format a file's extension suggests, in any case: `.tum` and `.txt` are TUM, `.csv`
    /// is CSV, `.g2o` and `.graph` are pose graphs, `.mcap` is MCAP, `.db3`, `.yaml` (a bag's
    /// `metadata.yaml`) and the file-compressed `.zstd` and `.lz4` are rosbag2, `.bag` is ROS 1.
    /// `None` for other extensions and none. Only the name is looked at, not the contents (but
    /// see [`detect`](Self::detect) and [`read_trajectory`](crate::read_trajectory)).
    ///
    /// # Examples
    /// ```
    /// use loops_io::Format;
    /// assert_eq!(Format::from_path("runs/fr2_desk_groundtruth.TXT"), Some(Format::Tum));
    /// assert_eq!(Format::from_path("drive.csv"), Some(Format::Csv));
    /// assert_eq!(Format::from_path("drive.mcap"), Some(Format::Mcap));
    /// assert_eq!(Format::from_path("drive.bag"), Some(Format::Ros1));
    /// assert_eq!(Format::from_path("bag/rosbag2_0.db3.zstd"), Some(Format::Rosbag2));
    /// assert_eq!(Format::from_path("drive.log"), None);
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Option<Format> {
        let extension = path.as_ref().extension()?.to_str()?.to_ascii_lowercase();
        Self::ALL.into_iter().find(|format| format.extensions().contains(&extension.as_str()))
    }
}

impl Format {
    /// The format of `path` as [`read_trajectory`](crate::read_trajectory) tells it without
    /// being told: a folder is a rosbag2 bag, a file goes by its extension
    /// ([`from_path`](Self::from_path)).
    pub fn detect(path: impl AsRef<Path>) -> Option<Format> {
        let path = path.as_ref();
        if path.is_dir() { Some(Format::Rosbag2) } else { Self::from_path(path) }
    }

    /// Whether files of this format hold topics ([`list_topics`](crate::list_topics) lists
    /// them): MCAP, rosbag2 and ROS 1.
    pub fn has_topics(self) -> bool {
        matches!(self, Self::Mcap | Self::Rosbag2 | Self::Ros1)
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
}

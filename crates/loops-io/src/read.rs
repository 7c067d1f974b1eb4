//! Reading a pose file in the format it names, or that its extension and first line suggest.

use std::path::Path;

use loops_core::{MetricSpec, Trajectory};

use crate::bag::{read_ros1, read_rosbag2};
use crate::csv::parse_csv;
use crate::dropped::Dropped;
use crate::error::{IoError, Result};
use crate::euroc::{looks_like_euroc, parse_euroc};
use crate::format::Format;
use crate::graph::{EdgeChain, PoseGraph, SkippedRecords, looks_like_graph, parse_pose_graph};
use crate::kitti::parse_kitti;
use crate::mcap::{McapOptions, read_mcap, read_mcap_files};
use crate::table::PoseTable;
use crate::text::{self, Delimiter};
use crate::timing::Timing;
use crate::tuc::{looks_like_tuc, parse_tuc};
use crate::tum::parse_tum;

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
    /// For pose graphs without vertices (a list of edges): chain the odometry edges (vertex
    /// `k` to `k + 1`) into a trajectory, from the first vertex at the origin. That trajectory
    /// is dead reckoning; [`read_pose_graph_with`] says whether a file was chained
    /// ([`PoseGraph::chain`]). Without it such a file is an error that names this option.
    pub chain_edges: bool,
    /// For [`read_trajectories`]: drop the poses whose timestamp repeats the one before
    /// (keeping the first of each, [`PoseTable::drop_duplicate_stamps`]); without it they are
    /// an error naming the line.
    pub drop_duplicate_stamps: bool,
    /// For [`read_trajectories`]: normalise quaternions within this distance of unit length
    /// ([`PoseTable::normalize_orientations`]); `None` leaves the trajectory's own tolerance
    /// ([`FILE_QUATERNION_TOLERANCE`](loops_core::FILE_QUATERNION_TOLERANCE)).
    pub quaternion_tolerance: Option<f64>,
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

    /// Chains the odometry edges of a pose graph without vertices ([`chain_edges`](Self::chain_edges)).
    pub fn chain_edges(mut self, chain_edges: bool) -> Self {
        self.chain_edges = chain_edges;
        self
    }

    /// Drops repeated timestamps ([`drop_duplicate_stamps`](Self::drop_duplicate_stamps)).
    pub fn drop_duplicate_stamps(mut self, drop: bool) -> Self {
        self.drop_duplicate_stamps = drop;
        self
    }

    /// Normalises quaternions within `tolerance` of unit length
    /// ([`quaternion_tolerance`](Self::quaternion_tolerance)).
    pub fn quaternion_tolerance(mut self, tolerance: Option<f64>) -> Self {
        self.quaternion_tolerance = tolerance;
        self
    }
}

/// What [`read_trajectories`] read: the files' poses joined, the trajectory the metric takes
/// from them, and what the caller should warn about.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ReadPoses {
    /// The poses of every file, joined in time order (orientations included).
    pub table: PoseTable,
    /// The trajectory the metric takes from [`table`](Self::table).
    pub trajectory: Trajectory,
    /// Each file's notes (dead reckoning, skipped records), in the order the files were given.
    pub notes: Vec<ReadNotes>,
    /// With [`ReadOptions::drop_duplicate_stamps`]: what was dropped of each table (empty ones
    /// too), in the order they were read.
    pub dropped: Vec<Dropped>,
}

/// Reads `paths` as one trajectory for `metric`, on the plane `axes` when given: the one read
/// pipeline of the command line and the Python API.
///
/// Several MCAP files are merged by time ([`read_mcap_files`]: a recording split in parts);
/// other files are read one by one ([`read_trajectory_chaining`], the format of each from
/// `options.format` or its extension and first lines) and must follow one another in time
/// ([`PoseTable::join`]). Each table then has its repeated stamps dropped
/// (`options.drop_duplicate_stamps`) and its quaternions normalised
/// (`options.quaternion_tolerance`); with several files each is converted first, so that an
/// error names its file and line, then the joined table
/// ([`PoseTable::to_trajectory_for`]).
///
/// # Errors
/// As [`read_trajectory_chaining`], [`read_mcap_files`], [`PoseTable::normalize_orientations`],
/// [`PoseTable::join`] (also for an empty `paths`) and [`PoseTable::to_trajectory_for`].
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_core::MetricSpec;
/// use loops_io::{ReadOptions, read_trajectories};
///
/// let dir = std::env::temp_dir().join(format!("loops-io-doc-{}-many", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
/// std::fs::write(&a, "t,x,y\n0,0,0\n1,1,0\n1,1,0\n")?;
/// std::fs::write(&b, "t,x,y\n2,2,0\n3,3,0\n")?;
/// let options = ReadOptions::default().drop_duplicate_stamps(true);
/// let read = read_trajectories(&[&b, &a], &options, &MetricSpec::Euclidean, None)?;
/// assert_eq!(read.trajectory.len(), 4);
/// assert_eq!(read.dropped.iter().map(|d| d.count).sum::<usize>(), 1);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn read_trajectories<P: AsRef<Path>>(
    paths: &[P],
    options: &ReadOptions,
    metric: &MetricSpec,
    axes: Option<[usize; 2]>,
) -> Result<ReadPoses> {
    let is_mcap = |path: &P| options.format.or_else(|| Format::detect(path.as_ref())) == Some(Format::Mcap);
    let mut notes = Vec::new();
    let mut tables = if paths.len() > 1 && paths.iter().all(is_mcap) {
        vec![read_mcap_files(paths, &options.mcap)?]
    } else {
        let mut tables = Vec::with_capacity(paths.len());
        for path in paths {
            let (table, note) = read_trajectory_chaining(path, options)?;
            notes.push(note);
            tables.push(table);
        }
        tables
    };
    let mut dropped = Vec::new();
    for table in &mut tables {
        if options.drop_duplicate_stamps {
            dropped.push(table.drop_duplicate_stamps());
        }
        if let Some(tolerance) = options.quaternion_tolerance {
            table.normalize_orientations(tolerance)?;
        }
    }
    if tables.len() > 1 {
        for table in &tables {
            table.to_trajectory_for(metric, axes)?;
        }
    }
    let table = PoseTable::join(tables)?;
    let trajectory = table.to_trajectory_for(metric, axes)?;
    Ok(ReadPoses { table, trajectory, notes, dropped })
}

/// Reads a pose graph as [`read_pose_graph`](crate::read_pose_graph) does, with the times of
/// `options.timing` and, with `options.chain_edges`, a file of edges without vertices chained
/// from its odometry edges ([`PoseGraph::chain`] says how; the format and MCAP options are not
/// used).
///
/// # Errors
/// As [`read_pose_graph`](crate::read_pose_graph); with `chain_edges`, [`IoError::PoseGraph`]
/// naming the first vertex that no odometry edge reaches, and [`IoError::Parse`] for an edge
/// whose quaternion is zero.
///
/// # Examples
/// An `EDGE2` list (TORO): one step forward, a quarter turn, one step forward.
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{ReadOptions, read_pose_graph_with};
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-chain.graph", std::process::id()));
/// std::fs::write(&path, "EDGE2 0 1 1 0 1.5707963267948966\nEDGE2 1 2 1 0 0\nEDGE2 2 0 -1 1 -1.5707963267948966\n")?;
/// assert!(read_pose_graph_with(&path, &ReadOptions::default()).is_err()); // no vertex
/// let graph = read_pose_graph_with(&path, &ReadOptions::default().chain_edges(true))?;
/// let last = graph.vertices.positions[2];
/// assert!((last[0] - 1.0).abs() < 1e-12 && (last[1] - 1.0).abs() < 1e-12);
/// assert_eq!(graph.chain.map(|chain| chain.poses()), Some(3));
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_pose_graph_with(path: impl AsRef<Path>, options: &ReadOptions) -> Result<PoseGraph> {
    let path = path.as_ref();
    parse_pose_graph(path, &mut text::open_lines(path)?, &options.timing, options.chain_edges)
}

/// What reading a pose file has to say beside its poses ([`read_trajectory_chaining`]): each a
/// warning the caller gives, one line each ([`warnings`](Self::warnings)).
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub struct ReadNotes {
    /// How a pose graph's poses were chained from its edges (dead reckoning), when
    /// `chain_edges` chained them.
    pub chain: Option<EdgeChain>,
    /// The lines of a pose graph that were not poses or edges between them, when it had some.
    pub skipped: Option<SkippedRecords>,
}

impl ReadNotes {
    /// The notes as one-line sentences, dead reckoning first.
    pub fn warnings(&self) -> Vec<String> {
        self.chain.iter().map(ToString::to_string).chain(self.skipped.iter().map(ToString::to_string)).collect()
    }
}

/// Reads a pose file as [`read_trajectory_with`], and says what the caller should warn about
/// ([`ReadNotes`]): how a pose graph's poses were chained from its edges when
/// `options.chain_edges` chained them (dead reckoning), and the lines of a pose graph that
/// were skipped (landmarks, `EQUIV`, ...).
///
/// # Errors
/// As [`read_trajectory_with`].
pub fn read_trajectory_chaining(path: impl AsRef<Path>, options: &ReadOptions) -> Result<(PoseTable, ReadNotes)> {
    let path = path.as_ref();
    let format = match options.format {
        Some(format) => format,
        None => detect(path)?,
    };
    match format {
        Format::Mcap => return Ok((read_mcap(path, &options.mcap)?, ReadNotes::default())),
        Format::Rosbag2 => return Ok((read_rosbag2(path, &options.mcap)?, ReadNotes::default())),
        Format::Ros1 => return Ok((read_ros1(path, &options.mcap)?, ReadNotes::default())),
        _ => {}
    }
    let sniffed = match options.format {
        Some(_) => format,
        None => sniff(format, &text::first_data_lines(path, SNIFFED_LINES)?),
    };
    let lines = &mut text::open_lines(path)?;
    let table = match sniffed {
        Format::Tum => parse_tum(path, lines),
        Format::Csv => parse_csv(path, lines),
        Format::Kitti => parse_kitti(path, lines, &options.timing),
        Format::Euroc => parse_euroc(path, lines),
        Format::G2o => {
            let graph = parse_pose_graph(path, lines, &options.timing, options.chain_edges)?;
            return Ok((graph.vertices, ReadNotes { chain: graph.chain, skipped: graph.skipped }));
        }
        Format::Tuc => parse_tuc(path, lines),
        Format::Mcap | Format::Rosbag2 | Format::Ros1 => unreachable!("logs with topics are read above"),
    }?;
    Ok((table, ReadNotes::default()))
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
/// extension ([`Format::from_path`]) and its first data line suggest; a folder is a rosbag2 bag
/// ([`Format::detect`]). MCAP files and bags take `options.mcap` (topic, time, frame pair).
///
/// The first line overrides the extension where the extension is shared: a `.txt` file whose
/// first data line is 12 or 13 numbers is KITTI, `point2` / `point3` / `angle` is libRSF (TUC),
/// `VERTEX...` / `EDGE...` is a pose graph; a `.csv` file whose first data line is 8
/// space-separated numbers is TUM (the UrbanNav ground truth `gt_slam_*.csv`), and at least 8
/// comma-separated numbers starting with a nanosecond integer is EuRoC. A pose graph gives its
/// vertices ([`read_pose_graph`](crate::read_pose_graph) gives the edges too).
///
/// A pose graph without vertices is chained from its odometry edges with `options.chain_edges`
/// (dead reckoning, which [`read_trajectory_chaining`] reports), and an error without.
///
/// # Errors
/// [`IoError::UnknownFormat`] when `format` is `None` and the extension does not tell it;
/// otherwise as the format's reader.
pub fn read_trajectory_with(path: impl AsRef<Path>, options: &ReadOptions) -> Result<PoseTable> {
    read_trajectory_chaining(path, options).map(|(table, _)| table)
}

/// The format [`read_trajectory`] reads `path` in when none is given: from the extension
/// ([`Format::detect`]), then, for the extensions several formats share (`.txt`, `.csv`), from
/// the first data line as [`read_trajectory_with`] describes. What `loops info` prints.
///
/// Time O(1): at most the first two data lines of a `.txt` or `.csv` file are read.
///
/// # Errors
/// [`IoError::UnknownFormat`] when the extension does not tell it; [`IoError::Open`] when a
/// text file whose first line is needed cannot be read.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{Format, format_of};
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-format.txt", std::process::id()));
/// std::fs::write(&path, "0 1 0 0 0 0 1 0 0 0 0 1 0\n")?; // a time and a 3×4 pose
/// assert_eq!(format_of(&path)?, Format::Kitti);
/// std::fs::write(&path, "0 0 0 0 0 0 0 1\n")?;
/// assert_eq!(format_of(&path)?, Format::Tum);
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn format_of(path: impl AsRef<Path>) -> Result<Format> {
    let path = path.as_ref();
    let format = detect(path)?;
    match format {
        Format::Tum | Format::Csv => Ok(sniff(format, &text::first_data_lines(path, SNIFFED_LINES)?)),
        _ => Ok(format),
    }
}

/// The format of `path`'s extension, or the error saying it does not tell one.
fn detect(path: &Path) -> Result<Format> {
    Format::detect(path).ok_or_else(|| IoError::UnknownFormat {
        path: path.to_path_buf(),
        extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
    })
}

/// The data lines the format sniffing looks at: the first, or the second after a header row.
const SNIFFED_LINES: usize = 2;

/// The format the first data lines of a file tell, for a file whose extension says `format`.
fn sniff(format: Format, text: &[String]) -> Format {
    match format {
        Format::Tum if looks_like_kitti(text) => Format::Kitti,
        Format::Tum if looks_like_tuc(text) => Format::Tuc,
        Format::Tum if looks_like_graph(text) => Format::G2o,
        Format::Csv if looks_like_tum(text) => Format::Tum,
        Format::Csv if looks_like_euroc(text) => Format::Euroc,
        format => format,
    }
}

/// Whether the first data line is 8 space-separated numbers with no CSV delimiter.
fn looks_like_tum(first_lines: &[String]) -> bool {
    first_lines.first().is_some_and(|line| {
        !line.contains([',', ';', '\t'])
            && Delimiter::Whitespace.split(line).count() == 8
            && Delimiter::Whitespace.split(line).all(text::is_number)
    })
}

/// Whether the first data line is 12 or 13 space-separated numbers.
fn looks_like_kitti(first_lines: &[String]) -> bool {
    first_lines.first().is_some_and(|line| {
        let fields = || line.split_ascii_whitespace();
        matches!(fields().count(), 12 | 13) && fields().all(text::is_number)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first data lines of `text`, as the sniffing sees them.
    fn first(text: &str) -> Vec<String> {
        let mut lines = text::Lines::new(Path::new("t.txt"), text.as_bytes());
        let mut out = Vec::new();
        while let Some((_, line)) = lines.next_data().unwrap().filter(|_| out.len() < SNIFFED_LINES) {
            out.push(line.to_owned());
        }
        out
    }

    #[test]
    fn kitti_is_recognised() {
        assert!(looks_like_kitti(&first("# c\n0 1 0 0 0 0 1 0 0 0 0 1 0\n")));
        assert!(looks_like_kitti(&first("1 0 0 0 0 1 0 0 0 0 1 0\n")));
        assert!(!looks_like_kitti(&first("1 0 0 0 0 0 0 1\n")));
    }

    #[test]
    fn tum_in_a_csv_is_recognised() {
        assert!(looks_like_tum(&first("# c\n1 0 0 0 0 0 -0 1\n")));
        assert!(!looks_like_tum(&first("1,0,0,0,0,0,0,1\n")));
        assert!(!looks_like_tum(&first("1 0 0\n")));
        assert!(!looks_like_tum(&first("t x y z qx qy qz qw\n1 0 0 0 0 0 0 1\n")));
    }
}

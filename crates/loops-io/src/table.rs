//! Pose tables: what a reader returns, and the trajectory made from one.

use std::path::{Path, PathBuf};

use loops_core::{Error, FILE_QUATERNION_TOLERANCE, Trajectory};

use crate::dropped::Dropped;
use crate::error::{IoError, MessageLocation, Result, TrajectoryMessages};

/// The poses of one file, as read: one row per data line, in file order, not validated as a
/// trajectory yet (see [`to_trajectory`](Self::to_trajectory)).
///
/// All vectors have one entry per pose. Positions are in the file's units (metres for TUM).
/// Poses come from lines of a text file ([`source_lines`](Self::source_lines)) or from messages
/// of MCAP files ([`messages`](Self::messages)).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoseTable {
    /// The file read (the first one, for several MCAP files).
    pub path: PathBuf,
    /// Timestamps, seconds, as read (not checked for order).
    pub timestamps_s: Vec<f64>,
    /// The same timestamps as integer nanoseconds, exactly as the file gives them, when it gives
    /// integers (MCAP stamps and log times, EuRoC); `timestamps_s` is then
    /// [`seconds_of_ns`](crate::seconds_of_ns) of each.
    pub timestamps_ns: Option<Vec<i64>>,
    /// Positions `[x, y, z]`; `z = 0` for 2-D files.
    pub positions: Vec<[f64; 3]>,
    /// Orientations as unit quaternions `[qx, qy, qz, qw]`, stored as read (not normalised),
    /// when the format has them (TUM does, CSV does not).
    pub orientations_xyzw: Option<Vec<[f64; 4]>>,
    /// Coordinates the file gives per position: 2 (`x, y`) or 3 (`x, y, z`).
    pub dim: usize,
    /// The 1-based line number in the file of each pose; empty for poses from MCAP messages.
    pub source_lines: Vec<usize>,
    /// For poses from MCAP files: the topic, and the message each pose came from.
    pub messages: Option<MessageSources>,
}

/// Seconds from integer nanoseconds, as close as an `f64` gets: whole seconds plus the
/// nanoseconds divided by 10⁹ (two roundings at most, where `ns as f64 / 1e9` has two as well but
/// loses the nanoseconds of an epoch stamp first).
///
/// # Examples
/// ```
/// assert_eq!(loops_io::seconds_of_ns(1_700_000_000_250_000_000), 1_700_000_000.25);
/// assert_eq!(loops_io::seconds_of_ns(-1), -1e-9);
/// ```
pub fn seconds_of_ns(ns: i64) -> f64 {
    const NS_PER_S: i64 = 1_000_000_000;
    (ns / NS_PER_S) as f64 + (ns % NS_PER_S) as f64 / 1e9
}

/// Nanoseconds as exact decimal seconds, as the writers print them: `1.000000002`,
/// `-0.000000001`.
pub(crate) fn exact_seconds(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let abs = ns.unsigned_abs();
    format!("{sign}{}.{:09}", abs / 1_000_000_000, abs % 1_000_000_000)
}

/// Where the poses of a [`PoseTable`] read from MCAP files came from.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct MessageSources {
    /// The files read, in the order given.
    pub files: Vec<PathBuf>,
    /// The topic read.
    pub topic: String,
    /// The topic's schema name: `geometry_msgs/msg/PoseStamped`, `foxglove.PoseInFrame`, ...
    pub schema_name: String,
    /// For transform topics: the `(parent, child)` frame pair read.
    pub frames: Option<(String, String)>,
    /// The message of each pose, one per pose (a message holding several poses appears once for
    /// each).
    pub messages: Vec<MessageRef>,
}

/// One message in one of the files of [`MessageSources`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct MessageRef {
    /// Index into [`MessageSources::files`].
    pub file: usize,
    /// Byte offset in the file of the message record, or of the chunk record holding it.
    pub offset: u64,
    /// For a message in a chunk: its byte offset in the chunk's decompressed records.
    pub offset_in_chunk: Option<u64>,
}

impl MessageSources {
    /// Where the message of pose `index` lies, or `None` for an index out of range.
    pub fn location(&self, index: usize) -> Option<MessageLocation> {
        let message = self.messages.get(index)?;
        Some(MessageLocation {
            path: self.files.get(message.file)?.clone(),
            topic: self.topic.clone(),
            offset: message.offset,
            offset_in_chunk: message.offset_in_chunk,
        })
    }
}

/// Whether the trajectory `metric` needs from a pose table can be read on a plane of its
/// positions ([`PoseTable::to_trajectory_for`] with `axes`): `euclidean` (the plane's two
/// coordinates) and `se2` (those and the heading in the plane). `se3`, `se3_rotation` and `so3`
/// measure whole poses, and the other metrics' points are not poses.
///
/// # Examples
/// ```
/// use loops_io::metric_takes_plane;
/// assert!(metric_takes_plane(&"se2(rotation_weight_m_per_rad=5)".parse()?));
/// assert!(!metric_takes_plane(&"so3".parse()?));
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn metric_takes_plane(metric: &loops_core::MetricSpec) -> bool {
    matches!(metric, loops_core::MetricSpec::Euclidean | loops_core::MetricSpec::Se2(_))
}

impl PoseTable {
    /// A table with no poses yet, for the readers to fill.
    pub(crate) fn empty(path: &Path, dim: usize) -> Self {
        Self {
            path: path.to_path_buf(),
            timestamps_s: Vec::new(),
            timestamps_ns: None,
            positions: Vec::new(),
            orientations_xyzw: None,
            dim,
            source_lines: Vec::new(),
            messages: None,
        }
    }

    /// The number of poses.
    pub fn len(&self) -> usize {
        self.timestamps_s.len()
    }

    /// Whether the table has no pose.
    pub fn is_empty(&self) -> bool {
        self.timestamps_s.is_empty()
    }

    /// Drops the poses whose timestamp equals the one before (recorders that stamp twice at one
    /// instant: TUM's `fr2_desk` ground truth, line 10863), keeping the first pose of each
    /// stamp, and says which it dropped. Timestamps out of order stay for
    /// [`to_trajectory`](Self::to_trajectory) to report: only repeats are dropped, and a table
    /// without any is unchanged. Reading is strict by default; this is the lenient option
    /// (`--drop-duplicate-stamps`, `drop_duplicate_stamps=True`), and its callers say how many
    /// it dropped.
    ///
    /// Time O(n).
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-dups.tum", std::process::id()));
    /// std::fs::write(&path, "0.0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n0.1 2 0 0 0 0 0 1\n0.2 3 0 0 0 0 0 1\n")?;
    /// let mut table = loops_io::read_tum(&path)?;
    /// assert!(table.to_trajectory().is_err()); // strict: 0.1 s twice
    /// let dropped = table.drop_duplicate_stamps();
    /// assert_eq!((dropped.count, dropped.lines.as_slice()), (1, &[3][..]));
    /// assert_eq!(table.positions[1], [1.0, 0.0, 0.0]); // the first pose of the stamp is kept
    /// assert_eq!(table.to_trajectory()?.len(), 3);
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn drop_duplicate_stamps(&mut self) -> Dropped {
        let n = self.len();
        let keep: Vec<bool> = (0..n).map(|i| i == 0 || self.timestamps_s[i] != self.timestamps_s[i - 1]).collect();
        let mut dropped =
            Dropped { path: self.path.clone(), count: keep.iter().filter(|k| !**k).count(), lines: Vec::new() };
        if dropped.count == 0 {
            return dropped;
        }
        if self.source_lines.len() == n {
            dropped.lines = (0..n).filter(|&i| !keep[i]).map(|i| self.source_lines[i]).collect();
        }
        fn retain<T>(rows: &mut Vec<T>, keep: &[bool]) {
            if rows.len() == keep.len() {
                let mut index = 0;
                rows.retain(|_| {
                    index += 1;
                    keep[index - 1]
                });
            }
        }
        retain(&mut self.timestamps_s, &keep);
        retain(&mut self.positions, &keep);
        retain(&mut self.source_lines, &keep);
        if let Some(ns) = &mut self.timestamps_ns {
            retain(ns, &keep);
        }
        if let Some(orientations) = &mut self.orientations_xyzw {
            retain(orientations, &keep);
        }
        if let Some(messages) = &mut self.messages {
            retain(&mut messages.messages, &keep);
        }
        dropped
    }

    /// Normalises the orientations within `tolerance` of unit length, in place, so that the
    /// trajectory constructors ([`to_trajectory_for`](Self::to_trajectory_for), which allows
    /// [`FILE_QUATERNION_TOLERANCE`]) accept them: `quaternion_tolerance` of the CLI
    /// (`--quaternion-tolerance`) and of Python's `read_trajectory`. Rows with a non-finite
    /// value are left for the constructors to report; a table without orientations is
    /// unchanged.
    ///
    /// # Errors
    /// [`IoError::Trajectory`] holding [`Error::NonUnitQuaternion`] at the line (or message) of
    /// the first quaternion farther than `tolerance` from unit length, or zero; holding
    /// [`Error::InvalidParameter`] for a negative or NaN `tolerance`.
    pub fn normalize_orientations(&mut self, tolerance: f64) -> Result<()> {
        if tolerance.is_nan() || tolerance < 0.0 {
            return Err(self.locate(Error::InvalidParameter {
                name: "quaternion_tolerance",
                value: tolerance,
                expected: "a number ≥ 0: how far a quaternion's norm may be from 1",
            }));
        }
        let Some(orientations) = &self.orientations_xyzw else { return Ok(()) };
        let mut normalized = orientations.clone();
        for (index, q) in normalized.iter_mut().enumerate() {
            if !q.iter().all(|v| v.is_finite()) {
                continue;
            }
            let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 || (norm - 1.0).abs() > tolerance {
                return Err(self.locate(Error::NonUnitQuaternion { index, norm }));
            }
            *q = q.map(|v| v / norm);
        }
        self.orientations_xyzw = Some(normalized);
        Ok(())
    }

    /// The tables of files that follow one another in time (a recording split in parts, one
    /// file per session) as one table: sorted by their first timestamp and concatenated.
    ///
    /// The files must not overlap in time: each one's poses all come before the next one's.
    /// Check each table first ([`to_trajectory_for`](Self::to_trajectory_for)) so that an error
    /// inside a file names its line: the joined table keeps the path of the earliest file, and
    /// no lines or messages (they would name the wrong file). It keeps orientations and integer
    /// stamps when every table has them. MCAP files of one recording are better read together
    /// by [`read_mcap_files`](crate::read_mcap_files), which merges their messages by time.
    ///
    /// Time O(total poses).
    ///
    /// # Errors
    /// [`IoError::Join`] when two files overlap in time (naming both, and the stamp and line of
    /// each side), when they differ in dimension, or when no table is given.
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let dir = std::env::temp_dir();
    /// let [a, b] = ["a", "b"].map(|n| dir.join(format!("loops-io-doc-{}-join-{n}.csv", std::process::id())));
    /// std::fs::write(&a, "t,x,y\n10,0,0\n11,1,0\n")?;
    /// std::fs::write(&b, "t,x,y\n0,5,5\n1,6,5\n")?;
    /// let tables = vec![loops_io::read_csv(&a)?, loops_io::read_csv(&b)?];
    /// let joined = loops_io::PoseTable::join(tables)?;
    /// assert_eq!(joined.timestamps_s, [0.0, 1.0, 10.0, 11.0]); // b first: it starts earlier
    /// std::fs::write(&b, "t,x,y\n0,5,5\n10.5,6,5\n")?;
    /// let error = loops_io::PoseTable::join(vec![loops_io::read_csv(&a)?, loops_io::read_csv(&b)?]).unwrap_err();
    /// assert!(error.to_string().contains("overlaps"), "{error}");
    /// # for path in [a, b] { std::fs::remove_file(path)?; }
    /// # Ok(())
    /// # }
    /// ```
    pub fn join(mut tables: Vec<PoseTable>) -> Result<PoseTable> {
        let span = |table: &PoseTable| {
            let t = &table.timestamps_s;
            let first = (0..t.len()).min_by(|&a, &b| t[a].total_cmp(&t[b]));
            let last = (0..t.len()).max_by(|&a, &b| t[a].total_cmp(&t[b]));
            first.zip(last)
        };
        if tables.is_empty() {
            return Err(IoError::Join { path: PathBuf::new(), message: "no file to read".to_owned() });
        }
        if let Some(empty) = tables.iter().find(|table| table.is_empty()) {
            return Err(IoError::Empty { path: empty.path.clone() });
        }
        tables.sort_by(|a, b| {
            let first = |table: &PoseTable| span(table).map_or(f64::NAN, |(i, _)| table.timestamps_s[i]);
            first(a).total_cmp(&first(b))
        });
        let where_ = |table: &PoseTable, index: usize| match table.source_lines.get(index) {
            Some(line) => format!("line {line}, {} s", table.timestamps_s[index]),
            None => format!("{} s", table.timestamps_s[index]),
        };
        for pair in tables.windows(2) {
            let (before, after) = (&pair[0], &pair[1]);
            if before.dim != after.dim {
                return Err(IoError::Join {
                    path: after.path.clone(),
                    message: format!(
                        "{} coordinates a pose, and {} has {}: files read as one trajectory must have the same",
                        after.dim,
                        before.path.display(),
                        before.dim
                    ),
                });
            }
            let (Some((_, last)), Some((first, _))) = (span(before), span(after)) else { continue };
            if after.timestamps_s[first] <= before.timestamps_s[last] {
                return Err(IoError::Join {
                    path: after.path.clone(),
                    message: format!(
                        "overlaps {} in time: its first pose ({}) is not after the last pose of {} ({}); \
                         files read as one trajectory must follow one another",
                        before.path.display(),
                        where_(after, first),
                        before.path.display(),
                        where_(before, last)
                    ),
                });
            }
        }
        let mut tables = tables.into_iter();
        let Some(mut joined) = tables.next() else { unreachable!("checked non-empty above") };
        if tables.len() == 0 {
            return Ok(joined);
        }
        joined.source_lines.clear();
        joined.messages = None;
        for table in tables {
            joined.timestamps_s.extend(table.timestamps_s);
            joined.positions.extend(table.positions);
            joined.timestamps_ns = joined.timestamps_ns.zip(table.timestamps_ns).map(|(mut a, b)| {
                a.extend(b);
                a
            });
            joined.orientations_xyzw = joined.orientations_xyzw.zip(table.orientations_xyzw).map(|(mut a, b)| {
                a.extend(b);
                a
            });
        }
        Ok(joined)
    }

    /// The positions as a trajectory: `[x, y]` or `[x, y, z]`, as many coordinates as the file
    /// gives ([`dim`](Self::dim)).
    ///
    /// # Errors
    /// [`IoError::Trajectory`] when the core rejects the poses, located at the line of the pose
    /// the core names: timestamps not strictly increasing (unsorted or duplicate) name the
    /// line and the line before; fewer than 2 poses names no line. Also when `dim` is not 2 or
    /// 3 (possible only in a table built by hand).
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-dup.tum", std::process::id()));
    /// std::fs::write(&path, "# t tx ty tz qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n0.1 2 0 0 0 0 0 1\n")?;
    /// let table = loops_io::read_tum(&path)?;
    /// let error = table.to_trajectory().unwrap_err();
    /// assert_eq!(error.line(), Some(4));
    /// assert!(error.to_string().contains("line 4: timestamps must strictly increase: 0.1 s is not after 0.1 s (line 3)"));
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn to_trajectory(&self) -> Result<Trajectory> {
        self.trajectory_of_axes(self.axes_given()?)
    }

    /// The positions projected on a plane of two position axes (0 = x, 1 = y, 2 = z), as a 2-D
    /// trajectory: `[0, 1]` for x-y, `[0, 2]` for KITTI's x-z ground plane.
    ///
    /// # Errors
    /// As [`to_trajectory`](Self::to_trajectory); also [`IoError::Trajectory`] holding
    /// [`loops_core::Error::InvalidParameter`] when an axis is not one the file gives (2 for a
    /// 2-D file, or 3 and more) or both axes are the same.
    pub fn to_trajectory_plane(&self, axes: [usize; 2]) -> Result<Trajectory> {
        self.check_plane(axes)?;
        self.trajectory_of_axes(&axes)
    }

    /// Checks that `axes` name a plane of this table's positions: two different axes the file
    /// gives (0 = x, 1 = y, and 2 = z for a 3-D file).
    ///
    /// # Errors
    /// As [`to_trajectory_plane`](Self::to_trajectory_plane).
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-plane.csv", std::process::id()));
    /// std::fs::write(&path, "t,x,y\n0,0,0\n1,1,0\n")?;
    /// let table = loops_io::read_trajectory(&path, None)?;
    /// assert!(table.check_plane([1, 0]).is_ok());
    /// let error = table.check_plane([0, 2]).unwrap_err();
    /// assert!(error.to_string().contains("a position axis of a 2-D file: 0 (x) or 1 (y)"), "{error}");
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn check_plane(&self, axes: [usize; 2]) -> Result<()> {
        let given = self.axes_given()?;
        if let Some(&axis) = axes.iter().find(|axis| !given.contains(axis)) {
            let expected = match given.len() {
                2 => "a position axis of a 2-D file: 0 (x) or 1 (y)",
                _ => "a position axis: 0 (x), 1 (y) or 2 (z)",
            };
            return Err(self.locate(Error::InvalidParameter { name: "plane axis", value: axis as f64, expected }));
        }
        if axes[0] == axes[1] {
            return Err(self.locate(Error::InvalidParameter {
                name: "plane axes",
                value: axes[1] as f64,
                expected: "two different axes",
            }));
        }
        Ok(())
    }

    /// The trajectory a metric needs from this table: positions for `euclidean` (all axes, or
    /// the plane `axes`), positions and orientations for `se3` / `se3_rotation`, orientations
    /// for `so3`, and for `se2` the two coordinates of the plane `axes` (default x, y) with the
    /// heading in that plane, the rotation about its normal
    /// ([`heading_in_plane`](Self::heading_in_plane)): yaw about z on x-y; on KITTI's x-z
    /// ground plane the rotation about its y axis (which points down).
    ///
    /// # Errors
    /// As [`to_trajectory`](Self::to_trajectory); also [`IoError::Trajectory`] holding
    /// [`IoError::Parse`] when the metric needs orientations the file does not have;
    /// [`Error::MetricMismatch`] when the metric's points cannot come from a pose file (torus,
    /// sphere, haversine, angular) or do not take `axes` (see [`metric_takes_plane`]); bad `axes`
    /// as [`to_trajectory_plane`](Self::to_trajectory_plane); quaternions farther than
    /// [`FILE_QUATERNION_TOLERANCE`] from unit length name their line (closer ones are
    /// normalised: files often print 4 decimals).
    pub fn to_trajectory_for(&self, metric: &loops_core::MetricSpec, axes: Option<[usize; 2]>) -> Result<Trajectory> {
        use loops_core::MetricSpec as M;
        let unsupported =
            |expected: &'static str| self.locate(Error::MetricMismatch { metric: metric.to_string(), expected });
        match (metric, axes) {
            (M::Euclidean, None) => self.to_trajectory(),
            (M::Euclidean, Some(axes)) => self.to_trajectory_plane(axes),
            (M::Se2(_), axes) => {
                let axes = axes.unwrap_or([0, 1]);
                self.check_plane(axes)?;
                let headings = self.heading_in_plane(axes)?;
                let poses: Vec<[f64; 3]> =
                    self.positions.iter().zip(headings).map(|(p, theta)| [p[axes[0]], p[axes[1]], theta]).collect();
                Trajectory::se2(self.timestamps_s.clone(), &poses).map_err(|error| self.locate(error))
            }
            (_, Some(_)) => Err(unsupported(
                "axes (a plane) go with the euclidean and se2 metrics; se3, se3_rotation and so3 measure whole poses",
            )),
            (M::Se3(_) | M::Se3Rotation(_), None) => {
                let orientations = self.orientations("se3")?;
                Trajectory::se3_with_tolerance(
                    self.timestamps_s.clone(),
                    &self.positions,
                    orientations,
                    FILE_QUATERNION_TOLERANCE,
                )
                .map_err(|error| self.locate(error))
            }
            (M::So3(_), None) => {
                let orientations = self.orientations("so3")?;
                Trajectory::so3_with_tolerance(self.timestamps_s.clone(), orientations, FILE_QUATERNION_TOLERANCE)
                    .map_err(|error| self.locate(error))
            }
            _ => Err(unsupported("a metric for poses: euclidean, se3, se3_rotation, so3 or se2")),
        }
    }

    /// The heading of every pose in the plane of the position axes `axes`, radians in (-π, π]:
    /// the rotated axis `axes[0]` projected on the plane, measured from `axes[0]` towards
    /// `axes[1]`, which is the rotation about the plane's normal `e_a × e_b` (the first angle of
    /// the intrinsic Euler sequence normal, `axes[1]`, `axes[0]`). On x-y it is the yaw about z
    /// (the first of the intrinsic Z-Y-X angles); on x-z, the ground plane of KITTI's camera
    /// frame (x right, y down, z forward), it is the rotation about −y, which points up: minus
    /// the first intrinsic Y-Z-X angle. The SE(2) poses of [`to_trajectory_for`](Self::to_trajectory_for)
    /// take it. Quaternions are checked and normalised as for `se3`. O(n).
    ///
    /// # Errors
    /// Bad `axes` as [`to_trajectory_plane`](Self::to_trajectory_plane); [`IoError::Parse`]
    /// when the file has no orientations; a quaternion farther than
    /// [`FILE_QUATERNION_TOLERANCE`] from unit length names its line.
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// // KITTI: a camera turned by 0.5 rad about its y axis (which points down).
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-heading.txt", std::process::id()));
    /// let (c, s) = (0.5_f64.cos(), 0.5_f64.sin());
    /// std::fs::write(&path, format!("0 1 0 0 0 0 1 0 0 0 0 1 0\n0.1 {c} 0 {s} 3 0 1 0 0 {} 0 {c} 4\n", -s))?;
    /// let table = loops_io::read_trajectory(&path, Some(loops_io::Format::Kitti))?;
    /// let theta = table.heading_in_plane([0, 2])?;
    /// assert!((theta[1] + 0.5).abs() < 1e-12); // about −y, up: a right turn seen from above
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn heading_in_plane(&self, axes: [usize; 2]) -> Result<Vec<f64>> {
        self.check_plane(axes)?;
        let orientations = self.orientations("se2")?;
        // The core's check of unit quaternions (the error names the pose, placed on its line),
        // and its normalised quaternions.
        let rotations =
            Trajectory::so3_with_tolerance(self.timestamps_s.clone(), orientations, FILE_QUATERNION_TOLERANCE)
                .map_err(|error| self.locate(error))?;
        Ok(rotations
            .coords()
            .chunks_exact(4)
            .map(|q| crate::rotation::heading_in_plane([q[0], q[1], q[2], q[3]], axes))
            .collect())
    }

    fn orientations(&self, metric: &str) -> Result<&[[f64; 4]]> {
        self.orientations_xyzw.as_deref().ok_or_else(|| IoError::Parse {
            path: self.path.clone(),
            line: self.source_lines.first().copied().unwrap_or(1),
            message: format!("the {metric} metric needs orientations, and this file has positions only"),
        })
    }

    /// The position axes the file gives: `[0, 1]` or `[0, 1, 2]`.
    fn axes_given(&self) -> Result<&'static [usize]> {
        match self.dim {
            2 => Ok(&[0, 1]),
            3 => Ok(&[0, 1, 2]),
            dim => Err(self.locate(Error::InvalidParameter {
                name: "dim",
                value: dim as f64,
                expected: "2 or 3 coordinates per position",
            })),
        }
    }

    fn trajectory_of_axes(&self, axes: &[usize]) -> Result<Trajectory> {
        let coords = self.positions.iter().flat_map(|position| axes.iter().map(|&axis| position[axis])).collect();
        Trajectory::new(self.timestamps_s.clone(), coords, axes.len()).map_err(|error| self.locate(error))
    }

    /// A core error placed in the file: the pose index it names becomes a line, or a message.
    pub(crate) fn locate(&self, error: Error) -> IoError {
        let (index, previous) = match error {
            Error::TimestampsNotIncreasing { index, .. } => (Some(index), index.checked_sub(1)),
            Error::NonFiniteTimestamp { index, .. }
            | Error::NonFiniteCoordinate { index, .. }
            | Error::NonUnitQuaternion { index, .. } => (Some(index), None),
            _ => (None, None),
        };
        let line_of = |index: Option<usize>| index.and_then(|index| self.source_lines.get(index).copied());
        let message_of = |index: Option<usize>| Some(self.messages.as_ref()?.location(index?)).flatten();
        let messages =
            message_of(index).map(|message| Box::new(TrajectoryMessages { message, previous: message_of(previous) }));
        IoError::Trajectory {
            path: messages.as_ref().map_or_else(|| self.path.as_path(), |m| m.message.path.as_path()).into(),
            line: line_of(index),
            previous_line: line_of(previous),
            messages,
            error,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn table(timestamps_s: Vec<f64>, dim: usize) -> PoseTable {
        let count = timestamps_s.len();
        PoseTable {
            path: PathBuf::from("drive.csv"),
            positions: (0..count).map(|i| [i as f64, 10.0 * i as f64, 100.0 * i as f64]).collect(),
            timestamps_s,
            timestamps_ns: None,
            orientations_xyzw: None,
            dim,
            source_lines: (0..count).map(|i| 2 * i + 3).collect(),
            messages: None,
        }
    }

    #[test]
    fn trajectory_has_the_dimension_read() {
        let traj = table(vec![0.0, 1.0], 2).to_trajectory().unwrap();
        assert_eq!(traj.coords(), &[0.0, 0.0, 1.0, 10.0]);
        let traj = table(vec![0.0, 1.0], 3).to_trajectory().unwrap();
        assert_eq!(traj.point(1), &[1.0, 10.0, 100.0]);
    }

    #[test]
    fn each_metric_gets_points_of_its_manifold_never_quaternions_as_a_vector() {
        use loops_core::{Manifold, MetricSpec};
        let mut poses = table(vec![0.0, 1.0], 3);
        poses.orientations_xyzw = Some(vec![[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0]]);
        for (text, manifold, dim) in [
            ("euclidean", Manifold::Euclidean, 3),
            ("se3(rotation_weight_m_per_rad=1)", Manifold::Se3, 7),
            ("se3_rotation", Manifold::Se3, 7),
            ("so3", Manifold::So3, 4),
            ("se2(rotation_weight_m_per_rad=1)", Manifold::Se2, 3),
        ] {
            let spec: MetricSpec = text.parse().unwrap();
            let traj = poses.to_trajectory_for(&spec, None).unwrap();
            assert_eq!((traj.manifold(), traj.dim()), (manifold, dim), "{text}");
            assert!(spec.validate(&traj).is_ok(), "{text}");
        }
        // The default reads positions only: the file's quaternions are no coordinates.
        let positions = poses.to_trajectory_for(&MetricSpec::default(), None).unwrap();
        assert_eq!(positions.coords(), &[0.0, 0.0, 0.0, 1.0, 10.0, 100.0]);
    }

    #[test]
    fn plane_picks_the_axes_in_order() {
        let traj = table(vec![0.0, 1.0], 3).to_trajectory_plane([2, 0]).unwrap();
        assert_eq!(traj.point(1), &[100.0, 1.0]);
    }

    #[test]
    fn bad_axes_are_errors_not_panics() {
        for (dim, axes) in [(3, [0, 3]), (2, [0, 2]), (3, [1, 1]), (3, [usize::MAX, 0])] {
            let error = table(vec![0.0, 1.0], dim).to_trajectory_plane(axes).unwrap_err();
            assert!(
                matches!(error, IoError::Trajectory { line: None, error: Error::InvalidParameter { .. }, .. }),
                "{error:?}"
            );
        }
        let expected = "drive.csv: dim = 4 is invalid: 2 or 3 coordinates per position";
        let error = table(vec![0.0, 1.0], 4).to_trajectory().unwrap_err();
        assert_eq!(error.to_string(), expected);
        let error = table(vec![0.0, 1.0], 4).to_trajectory_plane([0, 1]).unwrap_err();
        assert_eq!(error.to_string(), expected);
    }

    /// A table of poses turning by `heading_rad[i]` about `axis`, at the positions of `table`.
    fn turning(heading_rad: &[f64], axis: usize) -> PoseTable {
        let mut poses = table((0..heading_rad.len()).map(|i| i as f64).collect(), 3);
        let quaternion = |angle: f64| {
            let mut q = [0.0, 0.0, 0.0, (0.5 * angle).cos()];
            q[axis] = (0.5 * angle).sin();
            q
        };
        poses.orientations_xyzw = Some(heading_rad.iter().map(|&angle| quaternion(angle)).collect());
        poses
    }

    #[test]
    fn se2_on_a_plane_takes_its_coordinates_and_the_rotation_about_its_normal() {
        let se2: loops_core::MetricSpec = "se2(rotation_weight_m_per_rad=1)".parse().unwrap();
        let angles = [0.0, 0.5, -2.0, 3.0];
        // KITTI's camera frame: turning about y (down); on x-z the heading is about -y (up).
        let traj = turning(&angles, 1).to_trajectory_for(&se2, Some([0, 2])).unwrap();
        for (i, angle) in angles.iter().enumerate() {
            let [x, y, theta] = [traj.point(i)[0], traj.point(i)[1], traj.point(i)[2]];
            assert_eq!([x, y], [i as f64, 100.0 * i as f64]);
            assert!((theta + angle).abs() < 1e-12, "{theta} for {angle}");
        }
        let swapped = turning(&angles, 1).to_trajectory_for(&se2, Some([2, 0])).unwrap();
        assert_eq!(&swapped.point(3)[..2], &[300.0, 3.0]);
        assert!((swapped.point(3)[2] - 3.0).abs() < 1e-12);
        // Without axes: x, y and the yaw about z, as before; a turn about y has none (x still
        // points ahead up to a quarter turn, and back beyond).
        let flat = turning(&angles, 2).to_trajectory_for(&se2, None).unwrap();
        assert!((flat.point(1)[2] - 0.5).abs() < 1e-12 && flat.point(1)[..2] == [1.0, 10.0]);
        let tilted = turning(&angles, 1).to_trajectory_for(&se2, None).unwrap();
        let yaw: Vec<f64> = tilted.coords().chunks(3).map(|p| p[2].abs()).collect();
        assert!(yaw[0] < 1e-12 && yaw[1] < 1e-12 && (yaw[2] - PI).abs() < 1e-12, "{yaw:?}");
    }

    #[test]
    fn se2_on_a_plane_refuses_bad_axes_and_quaternions() {
        let se2: loops_core::MetricSpec = "se2(rotation_weight_m_per_rad=1)".parse().unwrap();
        for axes in [[0, 3], [2, 2]] {
            let error = turning(&[0.0, 1.0], 1).to_trajectory_for(&se2, Some(axes)).unwrap_err();
            assert!(matches!(error, IoError::Trajectory { error: Error::InvalidParameter { .. }, .. }), "{error:?}");
        }
        let mut zero = turning(&[0.0, 1.0, 2.0], 1);
        zero.orientations_xyzw.as_mut().unwrap()[2] = [0.0; 4];
        let error = zero.to_trajectory_for(&se2, Some([0, 2])).unwrap_err();
        assert!(error.to_string().starts_with("drive.csv line 7: "), "{error}");
        let error = table(vec![0.0, 1.0], 3).to_trajectory_for(&se2, Some([0, 2])).unwrap_err();
        assert!(error.to_string().contains("the se2 metric needs orientations"), "{error}");
        // se3 and so3 measure whole poses: a plane is refused, naming what takes one.
        for metric in ["se3(rotation_weight_m_per_rad=1)", "so3"] {
            let spec: loops_core::MetricSpec = metric.parse().unwrap();
            assert!(!metric_takes_plane(&spec));
            let error = turning(&[0.0, 1.0], 1).to_trajectory_for(&spec, Some([0, 2])).unwrap_err();
            assert!(error.to_string().contains("euclidean and se2"), "{error}");
        }
        assert!(metric_takes_plane(&se2) && metric_takes_plane(&loops_core::MetricSpec::Euclidean));
    }

    #[test]
    fn core_errors_name_lines() {
        let error = table(vec![0.0, 2.0, 1.0], 2).to_trajectory().unwrap_err();
        assert_eq!(
            error.to_string(),
            "drive.csv line 7: timestamps must strictly increase: 1 s is not after 2 s (line 5)"
        );
        let mut bad = table(vec![0.0, 1.0, 2.0], 3);
        bad.positions[2][1] = f64::NAN;
        let error = bad.to_trajectory().unwrap_err();
        assert_eq!(error.to_string(), "drive.csv line 7: coordinate 1 of the position is not finite (NaN)");
        let error = table(vec![0.0], 2).to_trajectory().unwrap_err();
        assert_eq!(error.to_string(), "drive.csv: a trajectory needs at least 2 poses, got 1");
    }

    #[test]
    fn missing_source_lines_fall_back_to_the_core_message() {
        let mut bad = table(vec![0.0, 1.0, 1.0], 2);
        bad.source_lines.clear();
        let error = bad.to_trajectory().unwrap_err();
        assert!(error.to_string().starts_with("drive.csv: timestamps must strictly increase: index 2"), "{error}");
    }

    #[test]
    fn exact_seconds_are_exact() {
        assert_eq!(exact_seconds(1_403_715_524_912_143_104), "1403715524.912143104");
        assert_eq!(exact_seconds(5), "0.000000005");
        assert_eq!(exact_seconds(-1_500_000_000), "-1.500000000");
        assert_eq!(exact_seconds(i64::MIN), "-9223372036.854775808");
    }
}

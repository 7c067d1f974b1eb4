//! Writers: trajectories as TUM, and candidate loop-closure edges as g2o. Every write is atomic
//! ([`write_atomically`]: a temporary file beside the target, then a rename) and does not
//! replace an existing file unless asked.

use std::io::{BufWriter, Write};
use std::path::Path;

use loops_core::Error;

use crate::atomic::write_atomically;
use crate::error::{IoError, Result, WriteError};
use crate::rotation::{normalized, yaw_of};
use crate::table::{PoseTable, exact_seconds};

/// Writes `table` as a TUM trajectory: a `# timestamp tx ty tz qx qy qz qw` header, then one
/// pose a line.
///
/// Numbers are printed in the shortest form that reads back as the same `f64` (so
/// [`read_tum`](crate::read_tum) gives the table back); timestamps known as integer nanoseconds
/// ([`PoseTable::timestamps_ns`]) are printed exactly, `1403715524.912143104`. A 2-D table gets
/// `z = 0`; a table without orientations gets the identity `0 0 0 1`.
///
/// Time O(n). The file is written to a temporary file beside it, then moved in place; an
/// existing file is replaced only with `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{read_tum, write_tum};
/// let dir = std::env::temp_dir().join(format!("loops-io-doc-{}-write", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let source = dir.join("in.tum");
/// std::fs::write(&source, "0.1 1 2 3 0 0 0 1\n0.2 1.5 2 3 0 0 0.6 0.8\n")?;
/// let table = read_tum(&source)?;
/// let copy = dir.join("out.tum");
/// write_tum(&copy, &table, false)?;
/// assert_eq!(read_tum(&copy)?.positions, table.positions);
/// assert!(write_tum(&copy, &table, false).is_err()); // not overwritten
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn write_tum(path: impl AsRef<Path>, table: &PoseTable, overwrite: bool) -> Result<(), WriteError> {
    write_atomically(path.as_ref(), overwrite, |file| {
        let mut out = BufWriter::new(file);
        writeln!(out, "# timestamp tx ty tz qx qy qz qw")?;
        for (i, position) in table.positions.iter().enumerate() {
            match table.timestamps_ns.as_ref().and_then(|ns| ns.get(i)) {
                Some(&ns) => write!(out, "{}", exact_seconds(ns))?,
                None => write!(out, "{}", table.timestamps_s[i])?,
            }
            let [x, y, z] = position;
            let [qx, qy, qz, qw] = table.orientations_xyzw.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |q| q[i]);
            writeln!(out, " {x} {y} {z} {qx} {qy} {qz} {qw}")?;
        }
        out.flush()
    })
}

/// Which g2o edge type [`write_g2o_edges`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum EdgeKind {
    /// `EDGE_SE2 i j dx dy dθ` and the 6 upper-triangular entries of the information matrix.
    Se2,
    /// `EDGE_SE3:QUAT i j x y z qx qy qz qw` and the 21 upper-triangular entries.
    Se3,
}

/// How [`write_g2o_edges`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct G2oOptions {
    /// The edge type; `None` picks [`EdgeKind::Se2`] for a 2-D table and [`EdgeKind::Se3`] for a
    /// 3-D one.
    pub kind: Option<EdgeKind>,
    /// Whether to write the vertices too (`VERTEX_SE2` / `VERTEX_SE3:QUAT`, one per pose, id =
    /// row), making a graph g2o can load alone. Off by default: a back end adds the edges to
    /// its own graph, whose vertex ids are the pose indices.
    pub with_vertices: bool,
    /// Whether to replace an existing file.
    pub overwrite: bool,
}

impl G2oOptions {
    /// Writes edges of `kind`.
    pub fn kind(mut self, kind: EdgeKind) -> Self {
        self.kind = Some(kind);
        self
    }

    /// Writes the vertices too.
    pub fn with_vertices(mut self, with_vertices: bool) -> Self {
        self.with_vertices = with_vertices;
        self
    }

    /// Replaces an existing file, or not.
    pub fn overwrite(mut self, overwrite: bool) -> Self {
        self.overwrite = overwrite;
        self
    }
}

/// Writes candidate loop-closure edges for the pose pairs `pairs` (rows of `table`) as g2o
/// edges whose measurement is the relative pose from pose `i` to pose `j` in the table: an
/// initial guess for scan matching, with an identity information matrix (the back end sets its
/// own after matching).
///
/// - [`EdgeKind::Se3`]: `EDGE_SE3:QUAT i j x y z qx qy qz qw` + 21 entries, the pose of `j` in
///   the frame of `i` (`T_i⁻¹ T_j`), quaternions normalised first.
/// - [`EdgeKind::Se2`]: `EDGE_SE2 i j dx dy dθ` + 6 entries, from `x`, `y` and the heading
///   (yaw) of each pose, `dθ` in (-π, π].
///
/// Vertex ids are row indices. A table without orientations has identity rotations: the
/// measurement is then the difference of positions. Numbers are printed to round-trip exactly.
///
/// Time O(n + pairs). The file is written to a temporary file beside it, then moved in place.
///
/// # Errors
/// [`IoError::Trajectory`] holding [`loops_core::Error::IndexOutOfRange`] for a pair with a row
/// the table does not have, or [`loops_core::Error::NonUnitQuaternion`] for a zero or
/// non-finite quaternion in a pair; [`IoError::Write`] holding a [`WriteError`] as
/// [`write_tum`].
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{G2oOptions, read_pose_graph, write_g2o_edges};
/// let dir = std::env::temp_dir().join(format!("loops-io-doc-{}-g2o", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let source = dir.join("in.tum");
/// std::fs::write(&source, "0 0 0 0 0 0 0 1\n1 10 0 0 0 0 0.7071067811865476 0.7071067811865476\n")?;
/// let table = loops_io::read_tum(&source)?;
/// let out = dir.join("candidates.g2o");
/// write_g2o_edges(&out, &table, &[(0, 1)], &G2oOptions::default().with_vertices(true))?;
/// let text = std::fs::read_to_string(&out)?;
/// assert!(text.contains("EDGE_SE3:QUAT 0 1 10 0 0 0 0 0.7071067811865476 0.7071067811865476 1 0 0 0 0 0 1"));
/// let graph = read_pose_graph(&out, &Default::default())?;
/// assert_eq!((graph.vertex_ids.len(), graph.edges.len()), (2, 1));
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn write_g2o_edges(
    path: impl AsRef<Path>,
    table: &PoseTable,
    pairs: &[(usize, usize)],
    options: &G2oOptions,
) -> Result<()> {
    let lines = g2o_edges_text(table, pairs, options)?;
    write_atomically(path.as_ref(), options.overwrite, |file| file.write_all(lines.as_bytes())).map_err(IoError::Write)
}

/// The text [`write_g2o_edges`] writes (its `overwrite` option aside): for a command that writes
/// several files all or none ([`StagedFiles`](crate::StagedFiles)). O(n + pairs).
///
/// # Errors
/// As [`write_g2o_edges`], but for writing.
pub fn g2o_edges_text(table: &PoseTable, pairs: &[(usize, usize)], options: &G2oOptions) -> Result<String> {
    let len = table.len();
    if let Some(&index) = pairs.iter().flat_map(|(i, j)| [i, j]).find(|&&index| index >= len) {
        return Err(table.locate(Error::IndexOutOfRange { index, len }));
    }
    let pose = |index: usize| pose_of(table, index);
    let kind = options.kind.unwrap_or(if table.dim == 2 { EdgeKind::Se2 } else { EdgeKind::Se3 });
    let mut lines = String::new();
    if options.with_vertices {
        for index in 0..len {
            lines += &vertex_line(kind, index as u64, pose(index)?);
        }
    }
    for &(i, j) in pairs {
        lines += &edge_line(kind, [i as u64, j as u64], pose(i)?, pose(j)?);
    }
    Ok(lines)
}

/// The relative pose from row `i` to row `j` of `table` that a g2o edge of [`write_g2o_edges`]
/// measures ([`loops_core::se3_between`], or [`loops_core::se2_between`] on the headings for a
/// 2-D table), for the samples' files to give the same guess as the edges. `None` for a table
/// without orientations (the trajectory's own guess then holds) or a quaternion that does not
/// normalise.
pub fn table_relative_pose(table: &PoseTable, i: usize, j: usize) -> Option<loops_core::RelativePose> {
    table.orientations_xyzw.as_ref()?;
    let (a, b) = (pose_of(table, i).ok()?, pose_of(table, j).ok()?);
    if table.dim == 2 {
        let ([dx, dy], dtheta) = loops_core::se2_between([a.0[0], a.0[1], yaw_of(a.1)], [b.0[0], b.0[1], yaw_of(b.1)]);
        let (s, c) = (0.5 * dtheta).sin_cos();
        return Some(loops_core::RelativePose {
            translation: [dx, dy, 0.0],
            rotation_xyzw: Some([0.0, 0.0, s, c]),
            rotation_rad: Some(dtheta),
        });
    }
    let (translation, rotation) = loops_core::se3_between(a, b);
    Some(loops_core::RelativePose { translation, rotation_xyzw: Some(rotation), rotation_rad: None })
}

/// A pose of a table for g2o: its position and its unit quaternion (normalised; the identity
/// for a table without orientations).
///
/// # Errors
/// [`IoError::Trajectory`] holding [`Error::NonUnitQuaternion`] for a zero or non-finite
/// quaternion. `index` must be a row of the table.
pub(crate) fn pose_of(table: &PoseTable, index: usize) -> Result<([f64; 3], [f64; 4])> {
    let q = table.orientations_xyzw.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |q| q[index]);
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let q = normalized(q).ok_or_else(|| table.locate(Error::NonUnitQuaternion { index, norm }))?;
    Ok((table.positions[index], q))
}

/// A g2o vertex line of `kind` with id `id` at `pose`.
pub(crate) fn vertex_line(kind: EdgeKind, id: u64, ([x, y, z], q): ([f64; 3], [f64; 4])) -> String {
    match kind {
        EdgeKind::Se2 => format!("VERTEX_SE2 {id} {x} {y} {}\n", yaw_of(q)),
        EdgeKind::Se3 => format!("VERTEX_SE3:QUAT {id} {x} {y} {z} {} {} {} {}\n", q[0], q[1], q[2], q[3]),
    }
}

/// A g2o edge line of `kind` between the vertices `[i, j]`, measuring the pose `b` in the frame
/// of the pose `a`, with an identity information matrix.
pub(crate) fn edge_line(kind: EdgeKind, [i, j]: [u64; 2], a: ([f64; 3], [f64; 4]), b: ([f64; 3], [f64; 4])) -> String {
    match kind {
        EdgeKind::Se2 => {
            let ([dx, dy], dtheta) =
                loops_core::se2_between([a.0[0], a.0[1], yaw_of(a.1)], [b.0[0], b.0[1], yaw_of(b.1)]);
            format!("EDGE_SE2 {i} {j} {dx} {dy} {dtheta} 1 0 0 1 0 1\n")
        }
        EdgeKind::Se3 => {
            let ([x, y, z], [qx, qy, qz, qw]) = loops_core::se3_between(a, b);
            format!("EDGE_SE3:QUAT {i} {j} {x} {y} {z} {qx} {qy} {qz} {qw} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n")
        }
    }
}

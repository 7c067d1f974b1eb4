//! Edge-only pose graphs as trajectories: the odometry edges (vertex `k` to `k + 1`) composed
//! from the first vertex, dead reckoning. Relative poses are composed as nalgebra's
//! `Isometry2` (2-D edges) and `Isometry3` (3-D edges).

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry2, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector2, Vector4};

use super::{GraphEdge, RelativePose};
use crate::error::{IoError, Result};
use crate::rotation::{normalized, quaternion_from_yaw};

/// How the vertices of an edge-only pose graph were made: by composing its odometry edges from
/// the first vertex at the origin. Such a trajectory is dead reckoning: its error grows along
/// the path, and loops that the loop-closure edges close may not close in it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct EdgeChain {
    /// The file.
    pub path: PathBuf,
    /// The first vertex id of the chain (at the origin, unrotated).
    pub first_id: u64,
    /// The last vertex id of the chain.
    pub last_id: u64,
    /// The odometry edges composed: one per pose after the first.
    pub odometry_edges: usize,
    /// The other edges between consecutive vertices (a second measurement of the same step),
    /// which the chain does not use: the first edge of each step in the file is composed.
    pub unused_odometry_edges: usize,
}

impl EdgeChain {
    /// The number of poses chained.
    pub fn poses(&self) -> usize {
        self.odometry_edges + 1
    }
}

impl fmt::Display for EdgeChain {
    /// `drive.g2o: 1228 poses (vertices 0 to 1227) chained from the odometry edges, ...`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} poses (vertices {} to {}) chained from the odometry edges i -> i+1: dead reckoning, whose \
             error grows along the path, not a measured trajectory",
            self.path.display(),
            self.poses(),
            self.first_id,
            self.last_id
        )?;
        if self.unused_odometry_edges > 0 {
            write!(
                f,
                " ({} repeated odometry edge(s) not used: the first of each step is)",
                self.unused_odometry_edges
            )?;
        }
        Ok(())
    }
}

/// A pose of the chain: the vertex `id`, and the line of the edge that placed it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ChainedPose {
    pub id: u64,
    pub position: [f64; 3],
    pub orientation_xyzw: [f64; 4],
    pub line: usize,
}

/// A pose of the chain while it is composed.
#[derive(Debug, Clone, Copy)]
enum Pose {
    Se2(Isometry2<f64>),
    Se3(Isometry3<f64>),
}

impl Pose {
    /// The pose after the step `edge` (taken backwards when it runs from `k + 1` to `k`).
    fn then(self, edge: &GraphEdge, backwards: bool, path: &Path) -> Result<Self> {
        let mismatch =
            || IoError::parse(path, edge.line, "a 2-D and a 3-D edge in one chain: one graph has one dimension");
        match (self, edge.measurement) {
            (Self::Se2(pose), RelativePose::Se2 { translation, rotation_rad }) => {
                let step = Isometry2::new(Vector2::from(translation), rotation_rad);
                Ok(Self::Se2(pose * if backwards { step.inverse() } else { step }))
            }
            (Self::Se3(pose), RelativePose::Se3 { translation, rotation_xyzw }) => {
                let Some(q) = normalized(rotation_xyzw) else {
                    return Err(IoError::parse(
                        path,
                        edge.line,
                        format!("the edge's quaternion {rotation_xyzw:?} is zero: it is no rotation"),
                    ));
                };
                let rotation = UnitQuaternion::new_unchecked(Quaternion::from_vector(Vector4::from(q)));
                let step = Isometry3::from_parts(Translation3::from(translation), rotation);
                Ok(Self::Se3(pose * if backwards { step.inverse() } else { step }))
            }
            _ => Err(mismatch()),
        }
    }

    /// Position `[x, y, z]` (`z = 0` in 2-D) and orientation `[qx, qy, qz, qw]`.
    fn parts(self) -> ([f64; 3], [f64; 4]) {
        match self {
            Self::Se2(pose) => {
                let t = pose.translation.vector;
                ([t.x, t.y, 0.0], quaternion_from_yaw(pose.rotation.angle()))
            }
            Self::Se3(pose) => {
                let t = pose.translation.vector;
                ([t.x, t.y, t.z], pose.rotation.into_inner().coords.into())
            }
        }
    }
}

/// The trajectory of the odometry edges of `edges` (non-empty): vertex `first` at the origin,
/// then each vertex `k + 1` as vertex `k` composed with the edge `k → k + 1` (or the inverse of
/// an edge `k + 1 → k`), up to the largest id any edge names. Where a step has several edges the
/// first in the file is composed. Each pose's line is that of the edge that placed it (the first
/// vertex: the edge leaving it). Time O(edges + poses).
///
/// # Errors
/// [`IoError::PoseGraph`] naming the first vertex that no odometry edge reaches (a gap in the
/// chain); [`IoError::Parse`] for a zero quaternion or 2-D and 3-D edges in one chain.
pub(crate) fn chain_odometry(path: &Path, edges: &[GraphEdge]) -> Result<(Vec<ChainedPose>, EdgeChain)> {
    let ids = edges.iter().flat_map(|edge| [edge.from, edge.to]);
    let (Some(first_id), Some(last_id)) = (ids.clone().min(), ids.max()) else {
        return Err(IoError::Empty { path: path.to_path_buf() });
    };
    // The first edge of each step k → k + 1, by k.
    let mut steps: HashMap<u64, &GraphEdge> = HashMap::new();
    let mut repeated = 0;
    for edge in edges.iter().filter(|edge| edge.from.abs_diff(edge.to) == 1) {
        let k = edge.from.min(edge.to);
        match steps.entry(k) {
            std::collections::hash_map::Entry::Occupied(_) => repeated += 1,
            std::collections::hash_map::Entry::Vacant(slot) => {
                slot.insert(edge);
            }
        }
    }
    let Some(first_step) = steps.get(&first_id) else {
        return Err(gap(path, first_id, first_id, last_id));
    };
    let mut pose = match first_step.measurement {
        RelativePose::Se2 { .. } => Pose::Se2(Isometry2::identity()),
        RelativePose::Se3 { .. } => Pose::Se3(Isometry3::identity()),
    };
    let capacity = usize::try_from(last_id - first_id).map_or(0, |steps| steps.min(edges.len()) + 1);
    let mut poses = Vec::with_capacity(capacity);
    let (position, orientation_xyzw) = pose.parts();
    poses.push(ChainedPose { id: first_id, position, orientation_xyzw, line: first_step.line });
    for k in first_id..last_id {
        let Some(&edge) = steps.get(&k) else {
            return Err(gap(path, k, first_id, last_id));
        };
        pose = pose.then(edge, edge.from > edge.to, path)?;
        let (position, orientation_xyzw) = pose.parts();
        poses.push(ChainedPose { id: k + 1, position, orientation_xyzw, line: edge.line });
    }
    let chain = EdgeChain {
        path: path.to_path_buf(),
        first_id,
        last_id,
        odometry_edges: poses.len() - 1,
        unused_odometry_edges: repeated,
    };
    Ok((poses, chain))
}

/// The error of a file of `edges` (at least one) without vertices, read without chaining.
pub(super) fn no_vertices(path: &Path, edges: &[GraphEdge]) -> IoError {
    IoError::PoseGraph {
        path: path.to_path_buf(),
        message: format!(
            "no poses: the pose graph has {} edge(s) (the first on line {}) but no vertex; chain_edges=True \
             (--chain-edges) chains its odometry edges (i -> i+1) into a trajectory, by dead reckoning",
            edges.len(),
            edges.first().map_or(0, |edge| edge.line)
        ),
    }
}

/// The error of a chain with no odometry edge between vertices `k` and `k + 1`.
fn gap(path: &Path, k: u64, first_id: u64, last_id: u64) -> IoError {
    IoError::PoseGraph {
        path: path.to_path_buf(),
        message: format!(
            "cannot chain the odometry edges: no edge joins vertex {k} and vertex {} (the edges name vertices \
             {first_id} to {last_id}; chaining needs an edge between every two consecutive ids)",
            k + 1
        ),
    }
}

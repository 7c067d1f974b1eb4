//! Far-field pruning: a binary hierarchy of bounding balls over time-consecutive stretches of
//! the path, under the trajectory's own metric.
//!
//! Consecutive poses stay close, so a stretch of the path fits in a small ball around its middle
//! pose. A row scan asks for the stretches that may hold a pose within `reach` of `x_i`; a ball
//! with `δ(x_i, centre) − radius > reach` holds none (triangle inequality), and neither do its
//! children. Only δ and the triangle inequality are used, so every [`Metric`] gets it.

use crate::metric::Metric;
use crate::trajectory::Trajectory;

const LEAF: u32 = u32::MAX;

#[derive(Debug, Clone, Copy)]
struct Node {
    /// First pose, inclusive.
    lo: u32,
    /// Last pose, exclusive.
    hi: u32,
    /// Pose at the centre of the ball.
    centre: u32,
    /// Upper bound of δ(centre, x_k) over the stretch.
    radius: f64,
    /// Index of the left child (the right one follows it), or `LEAF`.
    left: u32,
}

/// A leaf of the hierarchy: poses `lo..hi` within `radius` of pose `centre`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Leaf {
    pub lo: u32,
    pub hi: u32,
    pub centre: u32,
    pub radius: f64,
}

/// The ball hierarchy over a trajectory's poses; leaves hold `leaf_size` consecutive poses.
#[derive(Debug, Clone)]
pub(crate) struct BallTree {
    nodes: Vec<Node>,
    /// The coordinates of each node's centre pose, in node order: a walk reads them next to the
    /// nodes (siblings are adjacent) instead of at random places of the trajectory, which
    /// matters once the trajectory outgrows the caches.
    centres: Vec<f64>,
    dim: usize,
}

impl BallTree {
    /// Builds the hierarchy: exact radii at the leaves (one δ per pose), bounds above them
    /// (`δ(centre, child centre) + child radius`). O(n) metric evaluations; memory about
    /// `(48 + 16 · dim) / leaf_size` bytes a pose.
    pub(crate) fn new<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, leaf_size: usize) -> Self {
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * traj.len().div_ceil(leaf_size)),
            centres: Vec::new(),
            dim: traj.dim(),
        };
        tree.nodes.push(Node { lo: 0, hi: 0, centre: 0, radius: 0.0, left: LEAF });
        tree.build(0, 0, traj.len(), traj, metric, leaf_size.max(1));
        tree.centres = tree.nodes.iter().flat_map(|node| traj.point(node.centre as usize)).copied().collect();
        tree
    }

    fn build<M: Metric + ?Sized>(
        &mut self,
        slot: usize,
        lo: usize,
        hi: usize,
        traj: &Trajectory,
        metric: &M,
        leaf_size: usize,
    ) {
        let centre = lo + (hi - lo) / 2;
        let x_c = traj.point(centre);
        if hi - lo <= leaf_size {
            let radius = (lo..hi).map(|k| metric.distance(x_c, traj.point(k))).fold(0.0, f64::max);
            self.nodes[slot] = Node { lo: lo as u32, hi: hi as u32, centre: centre as u32, radius, left: LEAF };
            return;
        }
        let left = self.nodes.len();
        let placeholder = self.nodes[slot];
        self.nodes.push(placeholder);
        self.nodes.push(placeholder);
        let middle = lo + (hi - lo) / 2;
        self.build(left, lo, middle, traj, metric, leaf_size);
        self.build(left + 1, middle, hi, traj, metric, leaf_size);
        let radius = [self.nodes[left], self.nodes[left + 1]]
            .iter()
            .map(|child| metric.distance(x_c, traj.point(child.centre as usize)) + child.radius)
            .fold(0.0, f64::max);
        self.nodes[slot] = Node { lo: lo as u32, hi: hi as u32, centre: centre as u32, radius, left: left as u32 };
    }

    /// The leaves, in increasing order, that end after `from` and whose ball reaches within
    /// `reach` of `x` (appended to `out`, cleared first). Poses in other leaves are all farther
    /// than `reach` from `x`.
    pub(crate) fn near_leaves<M: Metric + ?Sized>(
        &self,
        metric: &M,
        x: &[f64],
        from: usize,
        reach: f64,
        out: &mut Vec<Leaf>,
    ) {
        out.clear();
        self.for_each_near_node(metric, x, from, reach, |node| {
            out.push(Leaf { lo: node.lo, hi: node.hi, centre: node.centre, radius: node.radius });
        });
    }

    /// Calls `visit(lo, hi)` for every leaf stretch, in increasing order, that ends after
    /// `from` and whose ball reaches within `reach` of `x`; `lo` is clipped to `from`. Poses in
    /// the stretches not visited are all farther than `reach` from `x`.
    pub(crate) fn for_each_near_leaf<M: Metric + ?Sized>(
        &self,
        metric: &M,
        x: &[f64],
        from: usize,
        reach: f64,
        mut visit: impl FnMut(usize, usize),
    ) {
        self.for_each_near_node(metric, x, from, reach, |node| {
            visit((node.lo as usize).max(from), node.hi as usize);
        });
    }

    fn for_each_near_node<M: Metric + ?Sized>(
        &self,
        metric: &M,
        x: &[f64],
        from: usize,
        reach: f64,
        mut visit: impl FnMut(&Node),
    ) {
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if (node.hi as usize) <= from {
                continue;
            }
            let centre = &self.centres[index as usize * self.dim..(index as usize + 1) * self.dim];
            if metric.distance(x, centre) - node.radius > reach {
                continue;
            }
            if node.left == LEAF {
                visit(&node);
            } else {
                stack.push(node.left + 1);
                stack.push(node.left);
            }
        }
    }
}

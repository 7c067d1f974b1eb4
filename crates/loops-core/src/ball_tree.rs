//! Far-field pruning: a binary hierarchy of bounding balls over time-consecutive stretches of
//! the path, under the trajectory's own metric.
//!
//! Consecutive poses stay close, so a stretch of the path fits in a small ball around its middle
//! pose. A row scan asks for the stretches that may hold a pose within `reach` of `x_i`; a ball
//! with `δ(x_i, centre) − radius > reach` holds none (triangle inequality), and neither do its
//! children. Only δ and the triangle inequality are used, so every [`Metric`] gets it.
//!
//! Built whole, it is one tree. Grown leaf by leaf ([`BallTree::push_leaf`], for the online
//! engine), it is a forest of perfect binary trees like the digits of a binary counter: a new
//! leaf joins the last tree when they are the same size, and so on up, so a pose costs O(1)
//! amortised metric evaluations and the forest has at most log₂(n / leaf) + 1 trees.
//!
//! A node whose poses are all one point, bit for bit (a robot parked, reporting one pose), is
//! marked `uniform`: δ from any x to each of its poses is then one number, so a walk hands the
//! node over whole and a scan decides all of its poses with one distance, exactly, whatever that
//! distance is. Without it, two stops at nearly one place cost n² (each row of one stop ranks
//! every pose of the other, all at one distance above 0, and, at γ give or take the rounding
//! margin, measures each of them: the path length within a stop is 0, so the arc-length bounds
//! jump over none).

use crate::error::Result;
use crate::memory::{try_filled, try_reserve, try_with_capacity};
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
    /// Index of the left child, or `LEAF`.
    left: u32,
    /// Index of the right child (when `left` is not `LEAF`).
    right: u32,
    /// Every pose of the stretch has the centre's coordinates, bit for bit.
    uniform: bool,
}

/// The ball of poses `lo..hi` of `traj` (not empty): its centre, the middle pose `lo + (hi −
/// lo)/2`, and its radius, the largest distance from there to a pose of the range. The one
/// rule for the hierarchy's leaves, a tile's chunks and a session's blocks
/// ([`SessionBlocks`](crate::tile::SessionBlocks)).
pub(crate) fn pose_ball<M: Metric + ?Sized>(traj: &Trajectory, lo: usize, hi: usize, metric: &M) -> (usize, f64) {
    let centre = lo + (hi - lo) / 2;
    let radius = (lo..hi).map(|k| metric.distance(traj.point(centre), traj.point(k))).fold(0.0, f64::max);
    (centre, radius)
}

/// The radius of a ball centred on `centre` that holds the balls `parts` ((centre, radius)
/// each): the largest distance from `centre` to a part's centre plus its radius, so every point
/// of the parts lies within it (triangle inequality). The one rule for the hierarchy's inner
/// nodes, a tile's groups of chunks and
/// [`SessionBlocks::coarsened`](crate::tile::SessionBlocks::coarsened).
pub(crate) fn joined_radius<'a, M: Metric + ?Sized>(
    centre: &[f64],
    parts: impl IntoIterator<Item = (&'a [f64], f64)>,
    metric: &M,
) -> f64 {
    parts.into_iter().map(|(c, r)| metric.distance(centre, c) + r).fold(0.0, f64::max)
}

impl Node {
    /// A leaf over poses `lo..hi` of `traj`: its centre the middle pose, its radius exact
    /// ([`pose_ball`]).
    fn leaf<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, lo: usize, hi: usize) -> Self {
        let (centre, radius) = pose_ball(traj, lo, hi, metric);
        let uniform = (lo..hi).all(|k| traj.same_point(k, centre));
        Node { lo: lo as u32, hi: hi as u32, centre: centre as u32, radius, left: LEAF, right: LEAF, uniform }
    }

    /// The node over poses `a.lo..b.hi` whose children are `a` (at index `left`) and `b` (at
    /// `right`): its centre the middle pose, its radius bounded from the children's
    /// ([`joined_radius`]).
    fn joined<M: Metric + ?Sized>(
        traj: &Trajectory,
        metric: &M,
        (a, left): (&Node, u32),
        (b, right): (&Node, u32),
    ) -> Self {
        let (lo, hi) = (a.lo as usize, b.hi as usize);
        let centre = lo + (hi - lo) / 2;
        let children = [a, b].map(|child| (traj.point(child.centre as usize), child.radius));
        let radius = joined_radius(traj.point(centre), children, metric);
        let uniform = a.uniform && b.uniform && traj.same_point(a.centre as usize, b.centre as usize);
        Node { lo: lo as u32, hi: hi as u32, centre: centre as u32, radius, left, right, uniform }
    }
}

/// A stretch of the path that a query could not rule out: poses `lo..hi` within `radius` of pose
/// `centre`. Either a leaf of the hierarchy, or a whole subtree taken without visiting its
/// leaves: one that lies within the query's inner reach (`inside`), or one whose poses are all
/// the centre's point (`uniform`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Leaf {
    pub lo: u32,
    pub hi: u32,
    pub centre: u32,
    pub radius: f64,
    pub inside: bool,
    pub uniform: bool,
}

impl Leaf {
    fn of(node: &Node, inside: bool) -> Self {
        Leaf { lo: node.lo, hi: node.hi, centre: node.centre, radius: node.radius, inside, uniform: node.uniform }
    }

    /// Grows this stretch by `next` when both are inside stretches and `next` starts where this
    /// one ends (the one rule that merges adjacent inside stretches); true when it did.
    pub(crate) fn absorb(&mut self, next: &Leaf) -> bool {
        let adjacent = self.inside && next.inside && self.hi == next.lo;
        if adjacent {
            self.hi = next.hi;
            self.uniform = false;
        }
        adjacent
    }
}

/// A node of the hierarchy that a spatial index holds ([`BallTree::chunks`]): poses up to `hi`
/// (exclusive) within `radius` of pose `centre`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Chunk {
    pub node: u32,
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
    /// The roots of its trees, in pose order: one for a hierarchy built whole.
    roots: Vec<u32>,
}

impl BallTree {
    /// Builds the hierarchy: exact radii at the leaves (one δ per pose), bounds above them
    /// (`δ(centre, child centre) + child radius`). O(n) metric evaluations; memory about
    /// `(48 + 16 · dim) / leaf_size` bytes a pose.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory).
    pub(crate) fn new<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, leaf_size: usize) -> Result<Self> {
        Self::with_sessions(traj, metric, leaf_size, &[0])
    }

    /// An empty hierarchy over points of `dim` coordinates, to grow by
    /// [`push_leaf`](Self::push_leaf).
    pub(crate) fn growing(dim: usize) -> Self {
        Self { nodes: Vec::new(), centres: Vec::new(), dim, roots: Vec::new() }
    }

    /// Poses `0..covered()` are in its trees (all of them for a hierarchy built whole).
    pub(crate) fn covered(&self) -> usize {
        self.roots.last().map_or(0, |&root| self.nodes[root as usize].hi as usize)
    }

    /// Adds the leaf of poses `covered()..hi` of `traj` (the poses after the last leaf) and joins
    /// it with the last tree while the two are the same size, as a binary counter carries: the
    /// joined node is the one [`new`](Self::new) builds over the same poses (centre at the middle
    /// pose, radius bounded from the children's). O(1) metric evaluations amortised per pose.
    /// Returns the leaf's node, for [`near_spans_under`](Self::near_spans_under).
    pub(crate) fn push_leaf<M: Metric + ?Sized>(&mut self, traj: &Trajectory, metric: &M, hi: usize) -> u32 {
        let lo = self.covered();
        debug_assert!(lo < hi && hi <= traj.len());
        let leaf = self.nodes.len() as u32;
        self.push_node(traj, Node::leaf(traj, metric, lo, hi));
        while let [.., left, right] = self.roots[..] {
            let (a, b) = (self.nodes[left as usize], self.nodes[right as usize]);
            if a.hi - a.lo != b.hi - b.lo {
                break;
            }
            self.roots.truncate(self.roots.len() - 2);
            self.push_node(traj, Node::joined(traj, metric, (&a, left), (&b, right)));
        }
        leaf
    }

    /// Appends `node` as the last root, with its centre's coordinates.
    fn push_node(&mut self, traj: &Trajectory, node: Node) {
        self.roots.push(self.nodes.len() as u32);
        self.centres.extend_from_slice(traj.point(node.centre as usize));
        self.nodes.push(node);
    }

    /// The hierarchy over a fleet's concatenated sessions (`starts`: the first pose of each
    /// session, the first being 0): its top levels split the sessions in halves, so every node
    /// below them, and every leaf, holds poses of one session only. A single session (`starts`
    /// = `[0]`) gives [`new`](Self::new)'s hierarchy.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory).
    pub(crate) fn with_sessions<M: Metric + ?Sized>(
        traj: &Trajectory,
        metric: &M,
        leaf_size: usize,
        starts: &[usize],
    ) -> Result<Self> {
        let leaf_size = leaf_size.max(1);
        let mut bounds = try_with_capacity(starts.len() + 1, "the ball hierarchy")?;
        bounds.extend_from_slice(starts);
        bounds.push(traj.len());
        let capacity = sessions_tree_size(&bounds, leaf_size);
        let placeholder = Node { lo: 0, hi: 0, centre: 0, radius: 0.0, left: LEAF, right: LEAF, uniform: false };
        let mut tree = Self {
            nodes: try_filled(capacity, placeholder, "the ball hierarchy")?,
            centres: Vec::new(),
            dim: traj.dim(),
            roots: vec![0],
        };
        let build = Build { traj, metric, leaf_size };
        let (root, below) = tree.nodes.split_first_mut().expect("a hierarchy has a root");
        *root = build.sessions(&bounds, 1, below);
        let mut centres = try_with_capacity(tree.nodes.len() * traj.dim(), "the ball hierarchy")?;
        centres.extend(tree.nodes.iter().flat_map(|node| traj.point(node.centre as usize)));
        tree.centres = centres;
        Ok(tree)
    }

    /// The chunks a spatial index holds: the largest nodes that lie in one session (`starts` as
    /// for [`with_sessions`](Self::with_sessions)) with a radius of at most `max_radius`, and
    /// the leaves whose radius is larger. Each pose is in exactly one chunk; a parked session
    /// is one chunk.
    pub(crate) fn chunks(&self, starts: &[usize], max_radius: f64) -> Vec<Chunk> {
        let session_of = |pose: u32| starts.partition_point(|&s| s <= pose as usize);
        let mut chunks = Vec::new();
        let mut stack: Vec<u32> = self.roots.iter().rev().copied().collect();
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            let one_session = session_of(node.lo) == session_of(node.hi - 1);
            if node.left == LEAF || (one_session && node.radius <= max_radius) {
                chunks.push(Chunk { node: index, hi: node.hi, centre: node.centre, radius: node.radius });
            } else {
                stack.push(node.right);
                stack.push(node.left);
            }
        }
        chunks
    }

    /// [`near_spans`](Self::near_spans) under the node `root` only, appended to `out` (not
    /// cleared, not merged with what `out` holds).
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) when the stretches do not fit in memory.
    pub(crate) fn near_spans_under<M: Metric + ?Sized>(
        &self,
        root: u32,
        metric: &M,
        x: &[f64],
        from: usize,
        reach: (f64, f64),
        out: &mut Vec<Leaf>,
    ) -> Result<()> {
        let mut grown = Ok(());
        self.walk_from(root, metric, x, from, reach, |node, inside| {
            if grown.is_ok() {
                grown = try_reserve(out, 1, "the stretches of a row scan").map(|()| out.push(Leaf::of(node, inside)));
            }
        });
        grown
    }

    /// The stretches, in increasing order, that end after `from` and whose ball reaches within
    /// `reach` of `x` (appended to `out`, cleared first): leaves, whole subtrees whose ball lies
    /// within `inside_reach` of `x` (`δ(x, centre) + radius ≤ inside_reach`), marked `inside`,
    /// and whole subtrees of one point (`uniform`), neither descended into. Poses outside every
    /// stretch are all farther than `reach` from `x`. Adjacent inside stretches are merged, so a
    /// parked robot's whole past is one stretch: the walk costs O(stretches · log n), not
    /// O(leaves).
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) when the stretches do not fit in memory.
    pub(crate) fn near_spans<M: Metric + ?Sized>(
        &self,
        metric: &M,
        x: &[f64],
        from: usize,
        (reach, inside_reach): (f64, f64),
        out: &mut Vec<Leaf>,
    ) -> Result<()> {
        out.clear();
        let mut grown = Ok(());
        self.walk(metric, x, from, (reach, inside_reach), |node, inside| push_merged(out, node, inside, &mut grown));
        grown
    }

    /// [`near_spans`](Self::near_spans) under the node `root` only (the leaf just pushed, say),
    /// appended to `out` after the stretches it holds, which end by `root`'s first pose, and
    /// merged with them as `near_spans` merges.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) when the stretches do not fit in memory.
    pub(crate) fn append_near_spans<M: Metric + ?Sized>(
        &self,
        root: u32,
        metric: &M,
        x: &[f64],
        reach: (f64, f64),
        out: &mut Vec<Leaf>,
    ) -> Result<()> {
        debug_assert!(out.last().is_none_or(|last| last.hi <= self.nodes[root as usize].lo));
        let mut grown = Ok(());
        self.walk_from(root, metric, x, 0, reach, |node, inside| push_merged(out, node, inside, &mut grown));
        grown
    }

    /// The pose of `lo..=hi` closest to `x` under the metric's
    /// [`distance_rank`](Metric::distance_rank), the earliest on ties: the same answer as
    /// [`Metric::closest_in`] over the stretch. Branch and bound over the hierarchy, in index
    /// order: a ball whose nearest possible pose is farther than the best so far by more than
    /// `margin` (the rounding allowance of δ) is skipped, a ball of one point (`uniform`) is
    /// ranked once, at its first pose in the range, and a rank of 0 ends the search. A parked
    /// robot's run of a million identical poses costs O(log n), not a million ranks, at whatever
    /// distance from `x` it is parked.
    pub(crate) fn closest_in_range<M: Metric + ?Sized>(
        &self,
        metric: &M,
        traj: &Trajectory,
        x: &[f64],
        (lo, hi): (usize, usize),
        margin: f64,
    ) -> usize {
        self.closest_in_range_within(metric, traj, x, (lo, hi), margin, f64::INFINITY)
    }

    /// [`closest_in_range`](Self::closest_in_range) knowing that some pose of `lo..=hi` lies
    /// `within` of `x` (as the metric measures δ): balls farther than that by more than `margin`
    /// are skipped from the start, before any pose is ranked.
    pub(crate) fn closest_in_range_within<M: Metric + ?Sized>(
        &self,
        metric: &M,
        traj: &Trajectory,
        x: &[f64],
        (lo, hi): (usize, usize),
        margin: f64,
        within: f64,
    ) -> usize {
        let dim = traj.dim();
        // (rank, distance, pose) of the best so far.
        let mut best = (f64::INFINITY, within, lo);
        let mut stack = NodeStack::default();
        self.roots.iter().rev().for_each(|&root| stack.push(root));
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            let (a, b) = ((node.lo as usize).max(lo), (node.hi as usize).min(hi + 1));
            if a >= b {
                continue;
            }
            if metric.distance(x, self.centre(index)) - node.radius > best.1 + margin {
                continue;
            }
            if node.uniform {
                // Every pose of the range ranks as pose `a`: the earliest of them is the one.
                let rank = metric.distance_rank(x, traj.point(a));
                if rank < best.0 {
                    best = (rank, metric.distance(x, traj.point(a)).min(best.1), a);
                    if rank <= 0.0 {
                        return a;
                    }
                }
                continue;
            }
            if node.left != LEAF {
                stack.push(node.right);
                stack.push(node.left);
                continue;
            }
            let k = a + metric.closest_in(x, &traj.coords()[a * dim..b * dim]);
            let rank = metric.distance_rank(x, traj.point(k));
            if rank < best.0 {
                best = (rank, metric.distance(x, traj.point(k)).min(best.1), k);
                if rank <= 0.0 {
                    return k;
                }
            }
        }
        // A growing forest's last poses, not yet in a leaf, come last in index order.
        let a = lo.max(self.covered());
        if a <= hi {
            let k = a + metric.closest_in(x, &traj.coords()[a * dim..(hi + 1) * dim]);
            if metric.distance_rank(x, traj.point(k)) < best.0 {
                return k;
            }
        }
        best.2
    }

    fn centre(&self, index: u32) -> &[f64] {
        &self.centres[index as usize * self.dim..(index as usize + 1) * self.dim]
    }

    /// Calls `visit(lo, hi)` for every stretch (a leaf, or a subtree of one point), in
    /// increasing order, that ends after `from` and whose ball reaches within `reach` of `x`;
    /// `lo` is clipped to `from`. Poses in the stretches not visited are all farther than `reach`
    /// from `x`.
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
        self.walk(metric, x, from, (reach, f64::NEG_INFINITY), |node, _| visit(node));
    }

    /// The walk of the hierarchy, in increasing order of poses: nodes ending by `from`, or
    /// whose ball stays farther than `reach` from `x`, are skipped; a node whose ball lies within
    /// `inside_reach` of `x` is visited whole (`inside`), and so is a node of one point
    /// (`uniform`) and every other leaf.
    fn walk<M: Metric + ?Sized>(
        &self,
        metric: &M,
        x: &[f64],
        from: usize,
        reach: (f64, f64),
        mut visit: impl FnMut(&Node, bool),
    ) {
        for &root in &self.roots {
            self.walk_from(root, metric, x, from, reach, &mut visit);
        }
    }

    /// [`walk`](Self::walk) of the subtree under `root`.
    fn walk_from<M: Metric + ?Sized>(
        &self,
        root: u32,
        metric: &M,
        x: &[f64],
        from: usize,
        (reach, inside_reach): (f64, f64),
        mut visit: impl FnMut(&Node, bool),
    ) {
        let mut stack = NodeStack::default();
        stack.push(root);
        while let Some(index) = stack.pop() {
            let node = self.nodes[index as usize];
            if (node.hi as usize) <= from {
                continue;
            }
            let d = metric.distance(x, self.centre(index));
            if d - node.radius > reach {
                continue;
            }
            let inside = d + node.radius <= inside_reach;
            if inside || node.uniform || node.left == LEAF {
                visit(&node, inside);
            } else {
                stack.push(node.right);
                stack.push(node.left);
            }
        }
    }
}

/// The nodes a depth-first walk has still to visit, held in place rather than on the heap: a
/// walk runs for every block of rows, and must not abort where memory runs out. A walk holds at
/// most its roots still to walk and one node per level of the tree it is in: a forest grown
/// leaf by leaf has at most 33 trees over fewer than 2³² poses, and a tree fewer than 64
/// levels (32 splitting sessions, 32 splitting poses).
#[derive(Debug)]
struct NodeStack {
    nodes: [u32; 128],
    len: usize,
}

impl Default for NodeStack {
    fn default() -> Self {
        Self { nodes: [0; 128], len: 0 }
    }
}

impl NodeStack {
    fn push(&mut self, node: u32) {
        self.nodes[self.len] = node;
        self.len += 1;
    }

    fn pop(&mut self) -> Option<u32> {
        self.len = self.len.checked_sub(1)?;
        Some(self.nodes[self.len])
    }
}

/// Appends the stretch of `node` to `out`, merged into the last one when both are inside
/// stretches that meet ([`Leaf::absorb`]); `grown` keeps the first failure to make room.
fn push_merged(out: &mut Vec<Leaf>, node: &Node, inside: bool, grown: &mut Result<()>) {
    let leaf = Leaf::of(node, inside);
    if out.last_mut().is_none_or(|last| !last.absorb(&leaf)) && grown.is_ok() {
        *grown = try_reserve(out, 1, "the stretches of a row scan").map(|()| out.push(leaf));
    }
}

/// The number of nodes [`Build::poses`] makes over `poses` poses (at least 1) in leaves of
/// at most `leaf_size`: the halves of a level differ in size by at most one, so each level
/// holds at most two sizes. O(log poses).
fn tree_size(poses: usize, leaf_size: usize) -> usize {
    // The sizes of one level's nodes differ by at most one: (size, how many) for both.
    let mut level = [(poses, 1_usize), (poses + 1, 0)];
    let mut nodes = 0;
    while level[0].1 + level[1].1 > 0 {
        let mut next = [(level[0].0 / 2, 0), (level[0].0 / 2 + 1, 0)];
        for (size, count) in level {
            nodes += count;
            if size > leaf_size && count > 0 {
                for half in [size / 2, size - size / 2] {
                    next[half - next[0].0].1 += count;
                }
            }
        }
        level = next;
    }
    nodes
}

/// The number of nodes over the sessions between consecutive `bounds` (at least two): each
/// session's tree ([`tree_size`]) and the nodes that join the sessions' trees in halves.
fn sessions_tree_size(bounds: &[usize], leaf_size: usize) -> usize {
    bounds.len() - 2 + bounds.windows(2).map(|pair| tree_size(pair[1] - pair[0], leaf_size)).sum::<usize>()
}

/// Poses from which the two halves of a node are built on two threads.
const PARALLEL_BUILD_POSES: usize = 1 << 13;

/// What building a hierarchy reads: the poses, the metric and the leaf size.
struct Build<'a, M: ?Sized> {
    traj: &'a Trajectory,
    metric: &'a M,
    leaf_size: usize,
}

impl<M: Metric + ?Sized> Build<'_, M> {
    /// The node over the sessions between `bounds[0]` and `bounds[last]`, its descendants written
    /// to `below` (exactly their number of nodes, the first at index `base`), in the order of a
    /// depth-first build: a node's two children side by side, then the first one's descendants,
    /// then the second one's. The top levels split the sessions in halves.
    fn sessions(&self, bounds: &[usize], base: usize, below: &mut [Node]) -> Node {
        let (lo, hi) = (bounds[0], bounds[bounds.len() - 1]);
        if bounds.len() <= 2 {
            return self.poses(lo, hi, base, below);
        }
        let middle = (bounds.len() - 1) / 2;
        let (first, second) = (&bounds[..=middle], &bounds[middle..]);
        let first_size = sessions_tree_size(first, self.leaf_size);
        let [pair, first_below, second_below] = halves(below, first_size);
        let a = self.sessions(first, base + 2, first_below);
        let b = self.sessions(second, base + 1 + first_size, second_below);
        self.join(pair, base, a, b)
    }

    /// The node over poses `lo..hi` of one session, its descendants written to `below` as
    /// [`sessions`](Self::sessions) writes them; the halves of a large node on two threads.
    fn poses(&self, lo: usize, hi: usize, base: usize, below: &mut [Node]) -> Node {
        if hi - lo <= self.leaf_size {
            return Node::leaf(self.traj, self.metric, lo, hi);
        }
        let middle = lo + (hi - lo) / 2;
        let first_size = tree_size(middle - lo, self.leaf_size);
        let [pair, first_below, second_below] = halves(below, first_size);
        let mut first = || self.poses(lo, middle, base + 2, first_below);
        let mut second = || self.poses(middle, hi, base + 1 + first_size, second_below);
        let (a, b) = if hi - lo >= PARALLEL_BUILD_POSES { rayon::join(first, second) } else { (first(), second()) };
        self.join(pair, base, a, b)
    }

    /// Writes the children `a` and `b` to `pair` (at index `base`) and returns their parent.
    fn join(&self, pair: &mut [Node], base: usize, a: Node, b: Node) -> Node {
        pair[0] = a;
        pair[1] = b;
        Node::joined(self.traj, self.metric, (&a, base as u32), (&b, base as u32 + 1))
    }
}

/// A node's descendants (`below`, as [`Build::sessions`] writes them) cut into its two
/// children, the first child's descendants (`first_size` − 1 nodes: its tree less itself) and
/// the second child's.
fn halves(below: &mut [Node], first_size: usize) -> [&mut [Node]; 3] {
    let (pair, rest) = below.split_at_mut(2);
    let (first, second) = rest.split_at_mut(first_size - 1);
    [pair, first, second]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;

    /// The tree of a wandering path, in sessions, built on one thread and on four: the same
    /// nodes bit for bit, as many as `tree_size` says, each node's children where the serial
    /// depth-first order puts them (side by side, first one's descendants before the second's).
    #[test]
    fn built_alike_on_any_number_of_threads() {
        let n = 3 * PARALLEL_BUILD_POSES + 17;
        let points: Vec<[f64; 3]> =
            (0..n).map(|k| k as f64 * 0.01).map(|t| [t.sin() * 50.0, (0.7 * t).cos() * 30.0, t * 0.1]).collect();
        let times: Vec<f64> = (0..n).map(|k| k as f64 * 0.1).collect();
        let traj = Trajectory::from_points(times, &points).expect("valid");
        for starts in [vec![0], vec![0, 5, PARALLEL_BUILD_POSES + 3, n - 1], vec![0, n / 2]] {
            let build = |threads| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
                pool.install(|| BallTree::with_sessions(&traj, &Euclidean, 16, &starts).expect("fits"))
            };
            let (one, four) = (build(1), build(4));
            let ends = starts.iter().skip(1).copied().chain([n]);
            let sizes: usize = starts.iter().zip(ends).map(|(&lo, hi)| tree_size(hi - lo, 16)).sum();
            assert_eq!(one.nodes.len(), starts.len() - 1 + sizes);
            let same = |a: &Node, b: &Node| {
                (a.lo, a.hi, a.centre, a.radius.to_bits(), a.left, a.right, a.uniform)
                    == (b.lo, b.hi, b.centre, b.radius.to_bits(), b.left, b.right, b.uniform)
            };
            assert!(one.nodes.iter().zip(&four.nodes).all(|(a, b)| same(a, b)), "sessions {starts:?}");
            for (k, node) in one.nodes.iter().enumerate().filter(|(_, node)| node.left != LEAF) {
                let (left, right) = (&one.nodes[node.left as usize], &one.nodes[node.right as usize]);
                assert!(node.left as usize > k && node.right == node.left + 1, "node {k}");
                assert!(left.lo == node.lo && left.hi == right.lo && right.hi == node.hi, "node {k}");
            }
        }
    }

    /// `tree_size` against the sizes of the halving it counts, for every size up to 2,000.
    #[test]
    fn tree_size_counts_the_halving() {
        fn count(poses: usize, leaf: usize) -> usize {
            if poses <= leaf { 1 } else { 1 + count(poses / 2, leaf) + count(poses - poses / 2, leaf) }
        }
        for leaf in [1, 3, 16] {
            for poses in 1..2000 {
                assert_eq!(tree_size(poses, leaf), count(poses, leaf), "{poses} poses, leaves of {leaf}");
            }
        }
    }

    /// Poses on a 3 × 3 lattice (many identical, many ties) and on a line, at random.
    fn tied_trajectory(n: usize, seed: u64) -> Trajectory {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let points: Vec<[f64; 2]> = (0..n)
            .map(|k| if k % 97 < 60 { [(next() % 3) as f64, (next() % 3) as f64] } else { [k as f64 * 0.01, 0.0] })
            .collect();
        Trajectory::from_points((0..n).map(|i| i as f64).collect(), &points).unwrap()
    }

    #[test]
    fn closest_in_range_is_the_linear_scan_ties_included() {
        for seed in 0..20 {
            let traj = tied_trajectory(1500, seed);
            let tree = BallTree::new(&traj, &Euclidean, 16).unwrap();
            for (k, lo) in (0..traj.len()).step_by(37).enumerate() {
                let hi = (lo + 40 + 97 * k).min(traj.len() - 1);
                for x in [traj.point((lo * 7 + 3) % traj.len()), &[0.5, 0.5][..], &[1.0, 1.0][..]] {
                    let expected = lo + Euclidean.closest_in(x, &traj.coords()[2 * lo..2 * (hi + 1)]);
                    let found = tree.closest_in_range(&Euclidean, &traj, x, (lo, hi), 1e-12);
                    assert_eq!(found, expected, "seed {seed}, range {lo}..={hi}, x {x:?}");
                }
            }
        }
    }

    /// Knowing a pose's δ from the start: that of any pose of the range, the least one exactly
    /// (every other pose at it is a tie that only its index decides), or the least one lowered
    /// by the margin it is allowed to be off by.
    #[test]
    fn closest_in_range_within_a_known_distance_is_the_linear_scan() {
        let margin = 1e-12;
        for seed in 0..20 {
            let traj = tied_trajectory(1500, seed);
            let tree = BallTree::new(&traj, &Euclidean, 16).unwrap();
            for (k, lo) in (0..traj.len()).step_by(37).enumerate() {
                let hi = (lo + 40 + 97 * k).min(traj.len() - 1);
                for x in [traj.point((lo * 7 + 3) % traj.len()), &[0.5, 0.5][..], &[1.0, 1.0][..]] {
                    let expected = lo + Euclidean.closest_in(x, &traj.coords()[2 * lo..2 * (hi + 1)]);
                    let least = Euclidean.distance(x, traj.point(expected));
                    let other = Euclidean.distance(x, traj.point(lo + (hi - lo) * (seed as usize % 7) / 6));
                    for within in [other, least, least - 0.5 * margin] {
                        let found = tree.closest_in_range_within(&Euclidean, &traj, x, (lo, hi), margin, within);
                        assert_eq!(found, expected, "seed {seed}, range {lo}..={hi}, x {x:?}, within {within}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_growing_forest_answers_as_the_linear_scan() {
        let traj = tied_trajectory(1000, 3);
        let mut forest = BallTree::growing(2);
        let mut spans = Vec::new();
        for n in 1..=traj.len() {
            if n - forest.covered() == 16 {
                forest.push_leaf(&traj, &Euclidean, n);
            }
            // A binary counter: at most one tree per size, largest first.
            let sizes: Vec<u32> =
                forest.roots.iter().map(|&r| forest.nodes[r as usize].hi - forest.nodes[r as usize].lo).collect();
            assert!(sizes.windows(2).all(|w| w[0] > w[1]), "{sizes:?}");
            assert_eq!(sizes.iter().sum::<u32>() as usize, forest.covered());
            if n % 61 != 0 {
                continue;
            }
            let x = traj.point((n * 7) % traj.len());
            let (lo, hi) = (n / 5, n - 1);
            let expected = lo + Euclidean.closest_in(x, &traj.coords()[2 * lo..2 * n]);
            assert_eq!(forest.closest_in_range(&Euclidean, &traj, x, (lo, hi), 1e-12), expected, "{n} poses");
            forest.near_spans(&Euclidean, x, 0, (1.0, 0.5), &mut spans).unwrap();
            for k in 0..forest.covered() {
                match spans.iter().find(|s| (s.lo as usize..s.hi as usize).contains(&k)) {
                    Some(span) if span.inside => assert!(Euclidean.distance(x, traj.point(k)) <= 0.5),
                    Some(_) => {}
                    None => assert!(Euclidean.distance(x, traj.point(k)) > 1.0, "pose {k} pruned but near"),
                }
            }
        }
    }

    #[test]
    fn inside_spans_are_within_reach_and_pruned_poses_beyond() {
        let traj = tied_trajectory(3000, 7);
        let tree = BallTree::new(&traj, &Euclidean, 16).unwrap();
        let mut spans = Vec::new();
        for (q, from) in [(0, 0), (100, 50), (2000, 1990)] {
            let x = traj.point(q);
            tree.near_spans(&Euclidean, x, from, (1.0, 0.5), &mut spans).unwrap();
            let span_of = |k: usize| spans.iter().find(|s| (s.lo as usize..s.hi as usize).contains(&k));
            for k in from..traj.len() {
                match span_of(k) {
                    Some(span) if span.inside => {
                        assert!(Euclidean.distance(x, traj.point(k)) <= 0.5, "pose {k} of an inside span");
                    }
                    Some(_) => {}
                    None => assert!(Euclidean.distance(x, traj.point(k)) > 1.0, "pose {k} pruned but near"),
                }
            }
            assert!(spans.windows(2).all(|w| w[0].hi <= w[1].lo), "spans in order, disjoint");
        }
    }
}

//! The ε graph of detections (paper, Sec. 5.3) and its connected components, exactly, without
//! enumerating the ε-pairs.

use std::f64::consts::SQRT_2;

use rayon::prelude::*;

use crate::detection::Detections;
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::union_find::MinRootForest;

mod grid;
mod sort;

use grid::{Grid, Scratch};
use sort::SortedPoints;

/// The ε of the paper's experiment, seconds: the default detection-graph radius and P2 radius.
pub const DEFAULT_EPSILON_S: f64 = 30.0;

/// Checks an ε in seconds (detection-graph radius, P2 radius): positive and finite. Front ends
/// call it to refuse a bad ε before any work.
///
/// # Errors
/// [`Error::InvalidParameter`] otherwise.
pub fn check_epsilon_s(epsilon_s: f64) -> Result<()> {
    if epsilon_s.is_finite() && epsilon_s > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: "epsilon_s",
            value: epsilon_s,
            expected: "a positive finite duration, seconds",
        })
    }
}

/// One connected component of the ε graph of detections: an approximation of a loop component.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionCluster {
    /// Index in [`DetectionClusters::clusters`]. Clusters are numbered in lexicographic order
    /// of their smallest point (t, t′), so ids do not depend on the order of the detections.
    pub id: usize,
    /// Number of detections.
    pub size: usize,
    /// Smallest and largest t, seconds.
    pub t_s: [f64; 2],
    /// Smallest and largest t′, seconds.
    pub t_prime_s: [f64; 2],
    /// Number of grid cells (side [`DetectionClusters::cell_side_s`]) holding its detections.
    pub cells: usize,
    /// Area proxy, s²: `cells` × side², the area of the grid cells the cluster covers. For dense
    /// detections it approaches the area of the loop component at the resolution of ε.
    pub area_proxy_s2: f64,
    /// Index of its smallest detection in (t, t′) order (the earliest index on ties): the
    /// anchor of the id.
    pub anchor: usize,
}

/// The connected components of the ε graph of a detection set, with the detections.
///
/// Build with [`cluster_detections`].
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "DetectionClustersState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionClusters {
    epsilon_s: f64,
    cell_side_s: f64,
    detections: Detections,
    labels: Vec<u32>,
    clusters: Vec<DetectionCluster>,
}

impl DetectionClusters {
    /// The threshold ε, seconds.
    pub fn epsilon_s(&self) -> f64 {
        self.epsilon_s
    }

    /// Side of the grid cells, seconds: ε/√2, shrunk by 2⁻¹⁸ so that floating-point rounding
    /// cannot put two points more than ε apart into one cell.
    pub fn cell_side_s(&self) -> f64 {
        self.cell_side_s
    }

    /// The detections that were clustered.
    pub fn detections(&self) -> &Detections {
        &self.detections
    }

    /// The cluster id of each detection, in the order of the detections.
    pub fn labels(&self) -> &[u32] {
        &self.labels
    }

    /// The clusters, by id.
    pub fn clusters(&self) -> &[DetectionCluster] {
        &self.clusters
    }

    /// Number of clusters (at least 1).
    pub fn len(&self) -> usize {
        self.clusters.len()
    }

    /// Never: a detection set is never empty, so it has at least one cluster.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// A point (t, t′) of the plane, seconds.
pub(super) type Point = [f64; 2];

/// The edge predicate of the ε graph, exactly as evaluated: `(t₁ − t₂)² + (t′₁ − t′₂)² ≤ ε²`
/// in f64 (the same test as scikit-learn's `DBSCAN(eps, min_samples=1)` with a tree index).
#[inline]
pub(super) fn within(a: Point, b: Point, epsilon2: f64) -> bool {
    distance2(a, b) <= epsilon2
}

/// The squared distance, as [`within`] evaluates it.
#[inline]
pub(super) fn distance2(a: Point, b: Point) -> f64 {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    dx * dx + dy * dy
}

/// An axis-aligned bounding box of points, with corners that are point coordinates.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bbox {
    pub(super) x: [f64; 2],
    pub(super) y: [f64; 2],
}

impl Bbox {
    pub(super) fn of(points: &[Point]) -> Self {
        let mut b = Self { x: [f64::INFINITY, f64::NEG_INFINITY], y: [f64::INFINITY, f64::NEG_INFINITY] };
        for p in points {
            b.x = [b.x[0].min(p[0]), b.x[1].max(p[0])];
            b.y = [b.y[0].min(p[1]), b.y[1].max(p[1])];
        }
        b
    }

    /// A lower bound, as evaluated by [`within`], of the squared distance of any pair across
    /// the two boxes (rounding is monotone, so each pair's evaluated value is at least this).
    pub(super) fn min_gap2(&self, other: &Self) -> f64 {
        let gap = |a: [f64; 2], b: [f64; 2]| {
            if b[0] > a[1] {
                b[0] - a[1]
            } else if a[0] > b[1] {
                a[0] - b[1]
            } else {
                0.0
            }
        };
        let (gx, gy) = (gap(self.x, other.x), gap(self.y, other.y));
        gx * gx + gy * gy
    }

    /// An upper bound, as evaluated, of the squared distance of any pair across the boxes.
    pub(super) fn max_gap2(&self, other: &Self) -> f64 {
        let span = |a: [f64; 2], b: [f64; 2]| (b[1] - a[0]).max(a[1] - b[0]);
        let (sx, sy) = (span(self.x, other.x), span(self.y, other.y));
        sx * sx + sy * sy
    }

    /// A lower bound of the squared distance from `p` to any point in the box.
    pub(super) fn point_gap2(&self, p: Point) -> f64 {
        let gap = |v: f64, a: [f64; 2]| {
            if v < a[0] {
                a[0] - v
            } else if v > a[1] {
                v - a[1]
            } else {
                0.0
            }
        };
        let (gx, gy) = (gap(p[0], self.x), gap(p[1], self.y));
        gx * gx + gy * gy
    }

    /// The squared diagonal, as evaluated: no pair inside is farther apart.
    pub(super) fn diagonal2(&self) -> f64 {
        let (w, h) = (self.x[1] - self.x[0], self.y[1] - self.y[0]);
        w * w + h * h
    }
}

/// Cells along a side of the grid up to which the cell index is exact enough (≤ 0.25 cell).
const MAX_CELLS_PER_SIDE: f64 = (1u64 << 49) as f64;

/// Clusters the detections: the connected components of the graph with an edge between every
/// two detections within `epsilon_s` seconds of each other (Euclidean in the (t, t′) plane,
/// `≤ ε`; DBSCAN with `min_samples = 1`). The partition is exact: the same as a union-find over
/// all pairs within ε.
///
/// The ε-pairs are never enumerated (there can be 1e8 and more). The plane is cut into square
/// cells of side ε/√2 (a little less), keyed by `(⌊t/side⌋, ⌊t′/side⌋)`, and the points are
/// sorted by cell: a counting sort when the grid over the detections has at most about 2n cells
/// (detections that fill their time range), otherwise a radix sort of 64-bit cell keys. Two
/// points of one cell are within ε, so a cell is one node, checked from its bounding box (a cell
/// that fails the check in a floating-point corner case becomes one node per point). Two
/// neighbouring cells (offsets up to 2 in each direction, the only ones whose closest points can
/// be within ε) are joined when any cross pair is within ε, unless union-find already joins
/// them; touching cells are linked first, over the whole grid, so that most farther pairs are
/// joined already. That test stops at the first pair found: bounding boxes first (all pairs
/// apart, or all within), a few probe pairs, each side's point nearest to the other side's box
/// and the other side's point nearest to it, then a recursive search that drops the points
/// farther than ε from the other side's box and halves the larger side. Union-find is the
/// crate's one (smallest-id roots).
///
/// Time: O(n) to sort the points by cell (O(n log n) by comparison when the grid has over 2³²
/// cells), then O(cells) neighbour look-ups, each a box test, a few linear passes, or a search
/// that stops at the first pair within ε (worst case quadratic in the points of the two cells
/// only when they face each other at just over ε). Memory: the copy of the detections that the
/// result holds, the labels, and 4 bytes per detection while clustering (20 when the
/// detections are far from time order and the grid is sparse). The result does not depend on
/// the order of the detections (ids follow the smallest point of each cluster) nor on the
/// number of threads.
///
/// # Errors
/// [`Error::InvalidParameter`] unless `epsilon_s` is positive and finite, or when ε is below the
/// floating-point resolution of the detections' time range (range / ε > 2⁴⁸);
/// [`Error::Interrupted`] when an [`Interrupt`] installed on this thread is interrupted (checked
/// between its phases).
///
/// # Examples
/// ```
/// use loops_core::{Detections, cluster_detections};
/// // Three points in a chain 30 s apart, and one far away.
/// let det = Detections::new(vec![0.0, 30.0, 60.0, 500.0], vec![1000.0, 1000.0, 1000.0, 900.0])?;
/// let clusters = cluster_detections(&det, 30.0)?;
/// assert_eq!(clusters.len(), 2);
/// assert_eq!(clusters.labels(), &[0, 0, 0, 1]);
/// assert_eq!(clusters.clusters()[0].size, 3);
/// assert_eq!(clusters.clusters()[0].t_s, [0.0, 60.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn cluster_detections(detections: &Detections, epsilon_s: f64) -> Result<DetectionClusters> {
    check_epsilon_s(epsilon_s)?;
    let (xs, ys) = (detections.t_s(), detections.t_prime_s());
    let min_max = |v: &[f64]| v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    let ((x_min, x_max), (y_min, y_max)) = (min_max(xs), min_max(ys));
    let side = epsilon_s / SQRT_2 * (1.0 - f64::powi(2.0, -18));
    if ((x_max - x_min).max(y_max - y_min) / side).partial_cmp(&MAX_CELLS_PER_SIDE) != Some(std::cmp::Ordering::Less) {
        return Err(Error::InvalidParameter {
            name: "epsilon_s",
            value: epsilon_s,
            expected: "at least 2^-48 of the time range of the detections (floating-point resolution)",
        });
    }
    let epsilon2 = epsilon_s * epsilon_s;

    // Checked between the phases (each O(n log n)).
    let interrupt = Interrupt::current();
    let components = || -> Result<_> {
        let sorted = SortedPoints::new(xs, ys, [x_min, y_min], [x_max, y_max], side);
        interrupt.check()?;
        let (grid, node_roots) = link(&sorted, epsilon2);
        interrupt.check()?;
        Ok(number_clusters(&sorted, &grid, &node_roots, side))
    };
    // The copy of the detections that the result owns is made while the clusters are computed.
    let (detections, components) = if xs.len() <= SMALL {
        (detections.clone(), components())
    } else {
        rayon::join(|| detections.clone(), components)
    };
    let (labels, clusters) = components?;
    Ok(DetectionClusters { epsilon_s, cell_side_s: side, detections, labels, clusters })
}

/// The label of each detection and the clusters, numbered by their smallest point (then
/// smallest detection index), so that ids do not depend on the input order.
fn number_clusters(
    sorted: &SortedPoints,
    grid: &Grid,
    node_roots: &[u32],
    side: f64,
) -> (Vec<u32>, Vec<DetectionCluster>) {
    let order = &sorted.order;
    let candidate = |p: u32| {
        let point = sorted.point(p);
        (point[0], point[1], order[p as usize])
    };
    // The smallest point of each root's cluster, as a position in the sorted points.
    let mut anchor = vec![u32::MAX; grid.nodes.len()];
    for (node, &root) in grid.nodes.iter().zip(node_roots) {
        let slot = &mut anchor[root as usize];
        if *slot == u32::MAX || candidate(node.anchor) < candidate(*slot) {
            *slot = node.anchor;
        }
    }
    let mut roots: Vec<(f64, f64, u32, u32)> = anchor
        .iter()
        .enumerate()
        .filter(|&(_, &a)| a != u32::MAX)
        .map(|(v, &a)| {
            let (x, y, k) = candidate(a);
            (x, y, k, v as u32)
        })
        .collect();
    roots.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut id_of_root = anchor; // reused: every slot read below is overwritten first
    for (id, root) in roots.iter().enumerate() {
        id_of_root[root.3 as usize] = id as u32;
    }

    let mut labels = vec![0u32; order.len()];
    let mut clusters: Vec<DetectionCluster> = roots
        .iter()
        .enumerate()
        .map(|(id, root)| DetectionCluster {
            id,
            size: 0,
            t_s: [f64::INFINITY, f64::NEG_INFINITY],
            t_prime_s: [f64::INFINITY, f64::NEG_INFINITY],
            cells: 0,
            area_proxy_s2: 0.0,
            anchor: root.2 as usize,
        })
        .collect();
    let mut seen_in_cell: Vec<u32> = Vec::new();
    for cell in &grid.cells {
        seen_in_cell.clear();
        for v in cell.nodes.0..cell.nodes.1 {
            let id = id_of_root[node_roots[v as usize] as usize];
            if cell.nodes.1 - cell.nodes.0 == 1 {
                clusters[id as usize].cells += 1;
            } else if !seen_in_cell.contains(&id) {
                seen_in_cell.push(id);
                clusters[id as usize].cells += 1;
            }
            let node = &grid.nodes[v as usize];
            let cluster = &mut clusters[id as usize];
            cluster.size += (node.end - node.start) as usize;
            cluster.t_s = [cluster.t_s[0].min(node.bbox.x[0]), cluster.t_s[1].max(node.bbox.x[1])];
            cluster.t_prime_s = [cluster.t_prime_s[0].min(node.bbox.y[0]), cluster.t_prime_s[1].max(node.bbox.y[1])];
            for &k in &order[node.start as usize..node.end as usize] {
                labels[k as usize] = id;
            }
        }
    }
    for cluster in &mut clusters {
        cluster.area_proxy_s2 = cluster.cells as f64 * side * side;
    }
    (labels, clusters)
}

/// The grid over the sorted points, and the union-find root of each of its nodes.
fn link(sorted: &SortedPoints, epsilon2: f64) -> (Grid, Vec<u32>) {
    let grid = Grid::new(sorted, epsilon2);
    let mut parent: Vec<u32> = (0..grid.nodes.len() as u32).collect();
    let mut union_find = MinRootForest::new(&mut parent, 0);
    let mut scratch = Scratch::default();
    grid.link_within_cells(sorted, epsilon2, &mut union_find);
    grid.link_neighbours(sorted, epsilon2, &mut union_find, &mut scratch);
    let node_roots = (0..grid.nodes.len()).map(|v| union_find.find(v) as u32).collect();
    (grid, node_roots)
}

/// Up to this many points, all work is done on the calling thread, and cell keys that do not
/// go to the counting sort are sorted by comparison.
pub(super) const SMALL: usize = 1 << 12;

/// What a serialised [`DetectionClusters`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct DetectionClustersState {
    epsilon_s: f64,
    cell_side_s: f64,
    detections: Detections,
    labels: Vec<u32>,
    clusters: Vec<DetectionCluster>,
}

#[cfg(feature = "serde")]
impl TryFrom<DetectionClustersState> for DetectionClusters {
    type Error = Error;

    /// Checks ε, one label per detection naming a cluster, and the clusters' ids and anchors.
    fn try_from(state: DetectionClustersState) -> Result<Self> {
        check_epsilon_s(state.epsilon_s)?;
        let invalid = |reason: String| Error::InvalidState { what: "DetectionClusters", reason };
        let (n, count) = (state.detections.len(), state.clusters.len());
        if !(state.cell_side_s.is_finite() && state.cell_side_s > 0.0) || state.labels.len() != n {
            return Err(invalid(format!(
                "cell side {} s and {} labels for {n} detections",
                state.cell_side_s,
                state.labels.len()
            )));
        }
        if let Some(k) = state.labels.iter().position(|&c| c as usize >= count) {
            return Err(invalid(format!("detection {k} is in cluster {}, of {count}", state.labels[k])));
        }
        if let Some(k) = state.clusters.iter().enumerate().position(|(k, c)| c.id != k || c.anchor >= n) {
            let c = &state.clusters[k];
            return Err(invalid(format!("cluster {k} has id {} and anchor {}, of {n} detections", c.id, c.anchor)));
        }
        let DetectionClustersState { epsilon_s, cell_side_s, detections, labels, clusters } = state;
        Ok(Self { epsilon_s, cell_side_s, detections, labels, clusters })
    }
}

#[cfg(test)]
mod tests {
    use super::sort::CellRange;
    use super::*;
    use petgraph::unionfind::UnionFind;

    /// Labels by petgraph's union-find over every pair within ε: independent of ours.
    fn brute_labels(xs: &[f64], ys: &[f64], epsilon: f64) -> Vec<usize> {
        let n = xs.len();
        let mut union_find = UnionFind::<usize>::new(n);
        for a in 0..n {
            for b in a + 1..n {
                if within([xs[a], ys[a]], [xs[b], ys[b]], epsilon * epsilon) {
                    union_find.union(a, b);
                }
            }
        }
        union_find.into_labeling()
    }

    fn same_partition(a: &[u32], b: &[usize]) -> bool {
        (0..a.len()).all(|p| (0..a.len()).all(|q| (a[p] == a[q]) == (b[p] == b[q])))
    }

    #[test]
    fn chain_and_exact_epsilon() {
        // Points exactly ε apart on a line are joined; ε(1 + 1e-12) apart are not.
        let eps = 30.0;
        let xs = vec![0.0, 30.0, 60.0, 90.0 + 30.0 * 1e-12 + 60.0 * 1e-12, 200.0];
        let ys = [0.0; 5];
        let det = Detections::new(xs.clone(), ys.iter().map(|y| y + 1000.0).collect()).unwrap();
        let clusters = cluster_detections(&det, eps).unwrap();
        assert_eq!(clusters.labels(), &[0, 0, 0, 1, 2]);
        assert!(same_partition(clusters.labels(), &brute_labels(det.t_s(), det.t_prime_s(), eps)));
    }

    #[test]
    fn dense_cells_and_far_cells() {
        // Two dense blobs 2.5ε apart (neighbouring cells never join), one blob spanning many cells.
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            xs.push(100.0 + 20.0 * next());
            ys.push(500.0 + 20.0 * next());
            xs.push(145.0 + 20.0 * next());
            ys.push(500.0 + 20.0 * next());
            xs.push(300.0 + 200.0 * next());
            ys.push(800.0 + 10.0 * next());
        }
        let det = Detections::new(xs, ys).unwrap();
        let clusters = cluster_detections(&det, 10.0).unwrap();
        assert!(same_partition(clusters.labels(), &brute_labels(det.t_s(), det.t_prime_s(), 10.0)));
    }

    #[test]
    fn cells_failing_the_diameter_check_fall_back_to_points() {
        // Keys as rounding could make them: points up to 4ε apart share cell (0, 0). The cell
        // becomes one node per point, joined pairwise; its neighbour (1, 0) is checked per node.
        let eps = 1.0;
        let points: Vec<Point> = vec![[0.0, 0.0], [0.9, 0.0], [1.8, 0.0], [4.0, 0.0], [4.9, 0.0], [5.85, 0.0]];
        let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p[0], p[1])).unzip();
        let mut cells = vec![CellRange::new(0, 0, 0, 4), CellRange::new(1, 0, 4, 6)];
        for cell in &mut cells {
            (cell.start..cell.end).for_each(|p| cell.summary.add(points[p as usize], p));
        }
        let sorted = SortedPoints { xs: &xs, ys: &ys, order: (0..6).collect(), cells, copy: None };
        let (grid, roots) = link(&sorted, eps * eps);
        assert_eq!(grid.nodes.len(), 5); // a node per point of (0, 0); (1, 0) is 0.95ε wide
        let node_of =
            |p: usize| grid.nodes.iter().position(|n| (n.start as usize..n.end as usize).contains(&p)).unwrap();
        let same = |a: usize, b: usize| roots[node_of(a)] == roots[node_of(b)];
        assert!(same(0, 1) && same(1, 2) && !same(2, 3));
        assert!(same(3, 4) && same(4, 5));
        let expected = brute_labels(&xs, &ys, eps);
        assert!((0..6).all(|a| (0..6).all(|b| same(a, b) == (expected[a] == expected[b]))));
    }

    #[test]
    fn bad_epsilon() {
        let det = Detections::new(vec![0.0, 1e9], vec![0.0, 1e9]).unwrap();
        for eps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(cluster_detections(&det, eps), Err(Error::InvalidParameter { name: "epsilon_s", .. })));
        }
        assert!(cluster_detections(&det, 1e-9).is_err()); // below the resolution of a 1e9 s range
        assert_eq!(cluster_detections(&det, 1e-3).unwrap().len(), 2);
    }
}

//! The ε graph of detections (paper, Sec. 5.3) and its connected components, exactly, without
//! enumerating the ε-pairs (DESIGN §4.4).

use std::f64::consts::SQRT_2;

use petgraph::unionfind::UnionFind;
use rayon::prelude::*;

use crate::detection::Detections;
use crate::error::{Error, Result};

/// One connected component of the ε graph of detections: an approximation of a loop component.
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
type Point = [f64; 2];

/// The edge predicate of the ε graph, exactly as evaluated: `(t₁ − t₂)² + (t′₁ − t′₂)² ≤ ε²`
/// in f64 (the same test as scikit-learn's `DBSCAN(eps, min_samples=1)` with a tree index).
#[inline]
fn within(a: Point, b: Point, epsilon2: f64) -> bool {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    dx * dx + dy * dy <= epsilon2
}

/// Pairs of points compared one by one below this many.
const BRUTE_PAIRS: usize = 64;
/// Pairs tried before the recursive search when linking two groups.
const PROBE: usize = 8;
/// Cells along a side of the grid up to which the cell index is exact enough (≤ 0.25 cell).
const MAX_CELLS_PER_SIDE: f64 = (1u64 << 49) as f64;

/// Clusters the detections: the connected components of the graph with an edge between every
/// two detections within `epsilon_s` seconds of each other (Euclidean in the (t, t′) plane,
/// `≤ ε`; DBSCAN with `min_samples = 1`). The partition is exact: the same as a union-find over
/// all pairs within ε.
///
/// The ε-pairs are never enumerated (there can be 1e8 and more). The plane is cut into square
/// cells of side ε/√2 (a little less), keyed by `(⌊t/side⌋, ⌊t′/side⌋)` and sorted. Two points
/// of one cell are within ε, so a cell is one node, checked from its bounding box (a cell that
/// fails the check in a floating-point corner case becomes one node per point). Two neighbouring
/// cells (offsets up to 2 in each direction, the only ones whose closest points can be within ε)
/// are joined when any cross pair is within ε, unless union-find already joins them. That test
/// stops at the first pair found: bounding boxes first (all pairs apart, or all within), a few
/// probe pairs, then a recursive search that drops the points farther than ε from the other
/// side's box and halves the larger side. Union-find is `petgraph`'s.
///
/// Time: a parallel sort of the n points, then O(cells) neighbour look-ups, each a box test or a
/// search that stops at the first pair within ε (worst case quadratic in the points of the two
/// cells only when they face each other at just over ε). Memory O(n). The result does not
/// depend on the order of the detections (ids follow the smallest point of each cluster) nor on
/// the number of threads.
///
/// # Errors
/// [`Error::InvalidParameter`] unless `epsilon_s` is positive and finite, or when ε is below the
/// floating-point resolution of the detections' time range (range / ε > 2⁴⁸).
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
    if !(epsilon_s.is_finite() && epsilon_s > 0.0) {
        return Err(Error::InvalidParameter {
            name: "epsilon_s",
            value: epsilon_s,
            expected: "a positive finite duration, seconds",
        });
    }
    let (xs, ys) = (detections.t_s(), detections.t_prime_s());
    let n = xs.len();
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

    let keys = sorted_cell_keys(xs, ys, [x_min, y_min], side);
    let points: Vec<Point> = keys.par_iter().map(|&(_, _, k)| [xs[k as usize], ys[k as usize]]).collect();

    let (grid, node_roots) = link(&keys, &points, epsilon2);

    // Roots → clusters, numbered by their smallest point (then smallest detection index), so
    // that ids do not depend on the input order. Points are read in cell order.
    let mut anchor: Vec<Option<(f64, f64, u32)>> = vec![None; grid.nodes.len()];
    for (v, node) in grid.nodes.iter().enumerate() {
        let slot = &mut anchor[node_roots[v] as usize];
        for p in node.start as usize..node.end as usize {
            let candidate = (points[p][0], points[p][1], keys[p].2);
            if slot.is_none_or(|a| candidate < a) {
                *slot = Some(candidate);
            }
        }
    }
    let mut roots: Vec<(f64, f64, u32, u32)> =
        anchor.iter().enumerate().filter_map(|(v, a)| a.map(|(x, y, k)| (x, y, k, v as u32))).collect();
    roots.par_sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut id_of_root = vec![u32::MAX; grid.nodes.len()];
    for (id, root) in roots.iter().enumerate() {
        id_of_root[root.3 as usize] = id as u32;
    }

    let mut labels = vec![0u32; n];
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
            for key in &keys[node.start as usize..node.end as usize] {
                labels[key.2 as usize] = id;
            }
        }
    }
    for cluster in &mut clusters {
        cluster.area_proxy_s2 = cluster.cells as f64 * side * side;
    }
    Ok(DetectionClusters { epsilon_s, cell_side_s: side, detections: detections.clone(), labels, clusters })
}

/// The grid over points sorted by cell key, and the union-find root of each of its nodes.
fn link(keys: &[(i64, i64, u32)], points: &[Point], epsilon2: f64) -> (Grid, Vec<u32>) {
    let grid = Grid::new(keys, points, epsilon2);
    let mut union_find = UnionFind::<u32>::new(grid.nodes.len());
    let mut scratch = Scratch::default();
    grid.link_within_cells(points, epsilon2, &mut union_find);
    grid.link_neighbours(points, epsilon2, &mut union_find, &mut scratch);
    let node_roots = (0..grid.nodes.len() as u32).map(|v| union_find.find_mut(v)).collect();
    (grid, node_roots)
}

/// Cell keys `(cx, cy, detection)` of every point, sorted (unique, so the order is
/// deterministic). A counting sort by column, then the columns sorted in parallel; a plain
/// parallel sort when the columns far outnumber the points.
fn sorted_cell_keys(xs: &[f64], ys: &[f64], origin: [f64; 2], side: f64) -> Vec<(i64, i64, u32)> {
    let n = xs.len();
    let cell = |v: f64, lo: f64| ((v - lo) / side).floor() as i64;
    let columns: Vec<i64> = xs.par_iter().map(|&x| cell(x, origin[0])).collect();
    let width = columns.par_iter().copied().max().unwrap_or(0) as u64 + 1;
    if width > 4 * n as u64 + 1024 {
        let mut keys: Vec<(i64, i64, u32)> =
            (0..n).into_par_iter().map(|k| (columns[k], cell(ys[k], origin[1]), k as u32)).collect();
        keys.par_sort_unstable();
        return keys;
    }
    let width = width as usize;
    let mut starts = vec![0usize; width + 1];
    for &c in &columns {
        starts[c as usize + 1] += 1;
    }
    for c in 0..width {
        starts[c + 1] += starts[c];
    }
    let mut keys = vec![(0i64, 0i64, 0u32); n];
    let mut next = starts.clone();
    for (k, &c) in columns.iter().enumerate() {
        keys[next[c as usize]] = (c, cell(ys[k], origin[1]), k as u32);
        next[c as usize] += 1;
    }
    let mut slices = Vec::with_capacity(width);
    let mut rest = keys.as_mut_slice();
    for c in 0..width {
        let (column, tail) = rest.split_at_mut(starts[c + 1] - starts[c]);
        slices.push(column);
        rest = tail;
    }
    slices.into_par_iter().for_each(|column| column.sort_unstable());
    keys
}

/// An axis-aligned bounding box of points, with corners that are point coordinates.
#[derive(Debug, Clone, Copy)]
struct Bbox {
    x: [f64; 2],
    y: [f64; 2],
}

impl Bbox {
    fn of(points: &[Point]) -> Self {
        let mut b = Self { x: [f64::INFINITY, f64::NEG_INFINITY], y: [f64::INFINITY, f64::NEG_INFINITY] };
        for p in points {
            b.x = [b.x[0].min(p[0]), b.x[1].max(p[0])];
            b.y = [b.y[0].min(p[1]), b.y[1].max(p[1])];
        }
        b
    }

    /// A lower bound, as evaluated by [`within`], of the squared distance of any pair across
    /// the two boxes (rounding is monotone, so each pair's evaluated value is at least this).
    fn min_gap2(&self, other: &Self) -> f64 {
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
    fn max_gap2(&self, other: &Self) -> f64 {
        let span = |a: [f64; 2], b: [f64; 2]| (b[1] - a[0]).max(a[1] - b[0]);
        let (sx, sy) = (span(self.x, other.x), span(self.y, other.y));
        sx * sx + sy * sy
    }

    /// A lower bound of the squared distance from `p` to any point in the box.
    fn point_gap2(&self, p: Point) -> f64 {
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
    fn diagonal2(&self) -> f64 {
        let (w, h) = (self.x[1] - self.x[0], self.y[1] - self.y[0]);
        w * w + h * h
    }
}

/// A set of points known to be connected: a whole cell, or one point of a cell that failed the
/// diameter check.
#[derive(Debug, Clone, Copy)]
struct Node {
    /// Range in the sorted points.
    start: u32,
    end: u32,
    bbox: Bbox,
}

#[derive(Debug, Clone, Copy)]
struct Cell {
    cx: i64,
    cy: i64,
    /// Range of its nodes.
    nodes: (u32, u32),
}

struct Grid {
    cells: Vec<Cell>,
    nodes: Vec<Node>,
}

/// Forward neighbour offsets (dx, dy): the half of the 5 × 5 block after (0, 0) in key order,
/// nearest first so that the near unions make the far checks unnecessary.
const FORWARD: [(i64, i64); 12] =
    [(0, 1), (1, 0), (1, 1), (1, -1), (0, 2), (2, 0), (1, 2), (1, -2), (2, 1), (2, -1), (2, 2), (2, -2)];

/// `RANK[dx][dy + 2]`: the position of (dx, dy) in [`FORWARD`] (12 for offsets not in it).
const RANK: [[u8; 5]; 3] = {
    let mut rank = [[12u8; 5]; 3];
    let mut k = 0;
    while k < FORWARD.len() {
        rank[FORWARD[k].0 as usize][(FORWARD[k].1 + 2) as usize] = k as u8;
        k += 1;
    }
    rank
};

impl Grid {
    fn new(keys: &[(i64, i64, u32)], points: &[Point], epsilon2: f64) -> Self {
        let mut ranges = Vec::new();
        let mut start = 0;
        for p in 1..=keys.len() {
            if p == keys.len() || (keys[p].0, keys[p].1) != (keys[start].0, keys[start].1) {
                ranges.push((start, p));
                start = p;
            }
        }
        let boxes: Vec<Bbox> = ranges.par_iter().map(|&(a, b)| Bbox::of(&points[a..b])).collect();
        let mut cells = Vec::with_capacity(ranges.len());
        let mut nodes = Vec::with_capacity(ranges.len());
        for (&(a, b), bbox) in ranges.iter().zip(boxes) {
            let first = nodes.len() as u32;
            if bbox.diagonal2() <= epsilon2 {
                nodes.push(Node { start: a as u32, end: b as u32, bbox });
            } else {
                // Rounding put points more than ε apart into one cell: one node per point.
                nodes.extend((a..b).map(|p| Node {
                    start: p as u32,
                    end: p as u32 + 1,
                    bbox: Bbox::of(&points[p..=p]),
                }));
            }
            cells.push(Cell { cx: keys[a].0, cy: keys[a].1, nodes: (first, nodes.len() as u32) });
        }
        Self { cells, nodes }
    }

    /// Joins the single-point nodes of cells that failed the diameter check.
    fn link_within_cells(&self, points: &[Point], epsilon2: f64, union_find: &mut UnionFind<u32>) {
        for cell in self.cells.iter().filter(|c| c.nodes.1 - c.nodes.0 > 1) {
            for a in cell.nodes.0..cell.nodes.1 {
                for b in a + 1..cell.nodes.1 {
                    let (pa, pb) = (self.nodes[a as usize].start, self.nodes[b as usize].start);
                    if !union_find.equiv(a, b) && within(points[pa as usize], points[pb as usize], epsilon2) {
                        union_find.union(a, b);
                    }
                }
            }
        }
    }

    /// Joins nodes of neighbouring cells that have a pair within ε.
    fn link_neighbours(&self, points: &[Point], epsilon2: f64, union_find: &mut UnionFind<u32>, scratch: &mut Scratch) {
        let cells = &self.cells;
        let key = |c: &Cell| (c.cx, c.cy);
        // pointer[dx]: first cell with key ≥ (cx + dx, cy − 2); it only moves forward.
        let mut pointer = [0usize; 3];
        let mut neighbours: Vec<(u8, usize)> = Vec::with_capacity(12);
        for (ci, cell) in cells.iter().enumerate() {
            neighbours.clear();
            for (dx, slot) in pointer.iter_mut().enumerate() {
                let dx = dx as i64;
                let lo = if dx == 0 { (cell.cx, cell.cy + 1) } else { (cell.cx + dx, cell.cy - 2) };
                let hi = (cell.cx + dx, cell.cy + 2);
                if dx == 0 {
                    *slot = ci + 1;
                }
                while *slot < cells.len() && key(&cells[*slot]) < lo {
                    *slot += 1;
                }
                let mut d = *slot;
                while d < cells.len() && key(&cells[d]) <= hi {
                    let dy = cells[d].cy - cell.cy;
                    neighbours.push((RANK[dx as usize][(dy + 2) as usize], d));
                    d += 1;
                }
            }
            if neighbours.len() > 1 {
                neighbours.sort_unstable();
            }
            for &(_, d) in &neighbours {
                self.link_cells(cell, &cells[d], points, epsilon2, union_find, scratch);
            }
        }
    }

    fn link_cells(
        &self,
        a: &Cell,
        b: &Cell,
        points: &[Point],
        epsilon2: f64,
        union_find: &mut UnionFind<u32>,
        scratch: &mut Scratch,
    ) {
        for u in a.nodes.0..a.nodes.1 {
            for v in b.nodes.0..b.nodes.1 {
                if union_find.equiv(u, v) {
                    continue;
                }
                let (nu, nv) = (&self.nodes[u as usize], &self.nodes[v as usize]);
                let pu = &points[nu.start as usize..nu.end as usize];
                let pv = &points[nv.start as usize..nv.end as usize];
                if any_within(pu, &nu.bbox, pv, &nv.bbox, epsilon2, scratch) {
                    union_find.union(u, v);
                }
            }
        }
    }
}

#[derive(Default)]
struct Scratch {
    a: Vec<Point>,
    b: Vec<Point>,
}

/// Whether some pair across `a` and `b` is within ε; stops at the first one found.
fn any_within(a: &[Point], box_a: &Bbox, b: &[Point], box_b: &Bbox, epsilon2: f64, scratch: &mut Scratch) -> bool {
    if box_a.min_gap2(box_b) > epsilon2 {
        return false;
    }
    if box_a.max_gap2(box_b) <= epsilon2 {
        return true;
    }
    if (0..a.len().min(b.len()).min(PROBE)).any(|k| within(a[k], b[k], epsilon2)) {
        return true;
    }
    if a.len() * b.len() <= BRUTE_PAIRS {
        return brute(a, b, epsilon2);
    }
    let (mut sa, mut sb) = (std::mem::take(&mut scratch.a), std::mem::take(&mut scratch.b));
    sa.clear();
    sa.extend_from_slice(a);
    sb.clear();
    sb.extend_from_slice(b);
    let found = search(&mut sa, &mut sb, epsilon2);
    (scratch.a, scratch.b) = (sa, sb);
    found
}

fn brute(a: &[Point], b: &[Point], epsilon2: f64) -> bool {
    a.iter().any(|&p| b.iter().any(|&q| within(p, q, epsilon2)))
}

/// Moves the points of `points` that satisfy `keep` to the front; returns how many there are.
fn partition_in_place(points: &mut [Point], keep: impl Fn(Point) -> bool) -> usize {
    let mut kept = 0;
    for k in 0..points.len() {
        if keep(points[k]) {
            points.swap(kept, k);
            kept += 1;
        }
    }
    kept
}

/// Bichromatic search for a pair within ε: prune each side to the points within ε of the other
/// side's box, then split the larger side at its median along its longer axis, nearer half first.
/// Reorders both slices.
fn search(a: &mut [Point], b: &mut [Point], epsilon2: f64) -> bool {
    let box_b = Bbox::of(b);
    let kept = partition_in_place(a, |p| box_b.point_gap2(p) <= epsilon2);
    if kept == 0 {
        return false;
    }
    let a = &mut a[..kept];
    let box_a = Bbox::of(a);
    let kept = partition_in_place(b, |p| box_a.point_gap2(p) <= epsilon2);
    if kept == 0 {
        return false;
    }
    let b = &mut b[..kept];
    let box_b = Bbox::of(b);
    if box_a.max_gap2(&box_b) <= epsilon2 {
        return true;
    }
    if a.len() * b.len() <= BRUTE_PAIRS {
        return brute(a, b, epsilon2);
    }
    let (big, small, box_big) = if a.len() >= b.len() { (a, b, box_a) } else { (b, a, box_b) };
    let axis = usize::from(box_big.y[1] - box_big.y[0] > box_big.x[1] - box_big.x[0]);
    let middle = big.len() / 2;
    big.select_nth_unstable_by(middle, |p, q| p[axis].total_cmp(&q[axis]));
    let (low, high) = big.split_at_mut(middle);
    let box_small = Bbox::of(small);
    let (first, second) = if Bbox::of(low).min_gap2(&box_small) <= Bbox::of(high).min_gap2(&box_small) {
        (low, high)
    } else {
        (high, low)
    };
    search(first, small, epsilon2) || search(second, small, epsilon2)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let keys: Vec<(i64, i64, u32)> = vec![(0, 0, 0), (0, 0, 1), (0, 0, 2), (0, 0, 3), (1, 0, 4), (1, 0, 5)];
        let (grid, roots) = link(&keys, &points, eps * eps);
        assert_eq!(grid.nodes.len(), 5); // a node per point of (0, 0); (1, 0) is 0.95ε wide
        let node_of =
            |p: usize| grid.nodes.iter().position(|n| (n.start as usize..n.end as usize).contains(&p)).unwrap();
        let same = |a: usize, b: usize| roots[node_of(a)] == roots[node_of(b)];
        assert!(same(0, 1) && same(1, 2) && !same(2, 3));
        assert!(same(3, 4) && same(4, 5));
        let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p[0], p[1])).unzip();
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

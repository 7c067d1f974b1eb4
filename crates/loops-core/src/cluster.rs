//! The ε graph of detections (paper, Sec. 5.3) and its connected components, exactly, without
//! enumerating the ε-pairs (DESIGN §4.4).

use std::f64::consts::SQRT_2;

use rayon::prelude::*;

use crate::detection::Detections;
use crate::error::{Error, Result};
use crate::quality::check_epsilon_s;
use crate::union_find::MinRootForest;

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
    distance2(a, b) <= epsilon2
}

/// The squared distance, as [`within`] evaluates it.
#[inline]
fn distance2(a: Point, b: Point) -> f64 {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    dx * dx + dy * dy
}

/// Pairs of points compared one by one below this many.
const BRUTE_PAIRS: usize = 64;
/// Pairs tried before the recursive search when linking two groups.
const PROBE: u32 = 8;
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

    let components = || {
        let sorted = SortedPoints::new(xs, ys, [x_min, y_min], [x_max, y_max], side);
        let (grid, node_roots) = link(&sorted, epsilon2);
        number_clusters(&sorted, &grid, &node_roots, side)
    };
    // The copy of the detections that the result owns is made while the clusters are computed.
    let (detections, (labels, clusters)) = if xs.len() <= SMALL {
        (detections.clone(), components())
    } else {
        rayon::join(|| detections.clone(), components)
    };
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
const SMALL: usize = 1 << 12;
/// Points are sorted by a counting sort over the whole grid when it has at most this many cells
/// per point (plus [`COUNTING_SORT_MIN_CELLS`]).
const COUNTING_SORT_CELLS_PER_POINT: u64 = 2;
/// Grids of up to this many cells always go to the counting sort.
const COUNTING_SORT_MIN_CELLS: u64 = 1024;
/// Largest digit of the radix sort of cell keys, bits (8192 buckets: two passes up to 2²⁶ cells).
const DIGIT_BITS: u32 = 13;
/// Points sorted by keys are copied in sorted order when the detection indices in a cell span
/// more than this on average (their coordinates, 16 bytes each, then stop fitting in a core's
/// cache).
const COPY_MEAN_SPAN: u64 = 1 << 15;

/// The points sorted by grid cell, and the cells.
///
/// The points are read through `order`: a copy in sorted order would be 16 bytes per point of
/// memory touched for the first time, which costs more than the reads when the detection
/// indices in a cell are close together (detections in time order, the usual case) or when the
/// points are read only at the borders of clusters (the counting sort summarises the cells in
/// input order). Points sorted otherwise, with scattered indices, are copied.
#[derive(Debug)]
struct SortedPoints<'a> {
    xs: &'a [f64],
    ys: &'a [f64],
    /// The detection index of each sorted point, ascending within a cell.
    order: Vec<u32>,
    /// The non-empty cells in key order `(cx, cy)`.
    cells: Vec<CellRange>,
    /// The points in sorted order, when copied.
    copy: Option<Vec<Point>>,
}

/// A non-empty cell: its column and row, its range in [`SortedPoints`] and its points' summary.
#[derive(Debug, Clone, Copy)]
struct CellRange {
    cx: i64,
    cy: i64,
    start: u32,
    end: u32,
    summary: Summary,
}

impl CellRange {
    fn new(cx: u64, cy: u64, start: usize, end: usize) -> Self {
        Self { cx: cx as i64, cy: cy as i64, start: start as u32, end: end as u32, summary: Summary::EMPTY }
    }
}

impl<'a> SortedPoints<'a> {
    /// Sorts the points by cell `(⌊(t − t_min)/side⌋, ⌊(t′ − t′_min)/side⌋)`, then by detection
    /// index, with cells numbered `cx · rows + cy` over the grid of the points' bounding box:
    /// - a counting sort by cell when the grid has few cells for the points (the usual case:
    ///   the detections of a drive fill their time range);
    /// - otherwise, up to 2³² cells, a stable LSD radix sort of the keys `cell << 32 | detection`
    ///   on the bits of the cell (a comparison sort up to [`SMALL`] points);
    /// - beyond, a parallel comparison sort of `(cx, cy, detection)`.
    fn new(xs: &'a [f64], ys: &'a [f64], origin: [f64; 2], corner: [f64; 2], side: f64) -> Self {
        let n = xs.len();
        // Offsets from the minimum are ≥ 0 (and below 2⁴⁹ cells), so truncation is the floor.
        // (A multiplication by 1/side, checked against cell borders, measured slower.)
        let cell = |v: f64, lo: f64| ((v - lo) / side) as i64 as u64;
        let (columns, rows) = (cell(corner[0], origin[0]) + 1, cell(corner[1], origin[1]) + 1);
        let cell_of = |k: usize| cell(xs[k], origin[0]) * rows + cell(ys[k], origin[1]);
        let counting_sort_cells = COUNTING_SORT_CELLS_PER_POINT * n as u64 + COUNTING_SORT_MIN_CELLS;
        let (order, cells) = match columns.checked_mul(rows).filter(|&cells| cells <= 1 << 32) {
            Some(cells) if cells <= counting_sort_cells => {
                // The summaries are made in input order: the points are only read again at the
                // borders of clusters, too few reads to pay for a copy.
                let (order, cells) = counting_sort(xs, ys, cells as usize, rows, cell_of);
                return Self { xs, ys, order, cells, copy: None };
            }
            Some(cells) => {
                let key = |k: usize| cell_of(k) << 32 | k as u64;
                let mut keys: Vec<u64> =
                    if n <= SMALL { (0..n).map(key).collect() } else { (0..n).into_par_iter().map(key).collect() };
                if n <= SMALL {
                    keys.sort_unstable();
                } else {
                    keys = radix_sort_high(keys, u64::BITS - (cells - 1).leading_zeros());
                }
                let mut ranges = Vec::new();
                let mut start = 0;
                for p in 1..=n {
                    if p == n || keys[p] >> 32 != keys[start] >> 32 {
                        let id = keys[start] >> 32;
                        ranges.push(CellRange::new(id / rows, id % rows, start, p));
                        start = p;
                    }
                }
                (keys.iter().map(|&key| key as u32).collect::<Vec<u32>>(), ranges)
            }
            None => {
                let key = |k: usize| (cell(xs[k], origin[0]), cell(ys[k], origin[1]), k as u32);
                let mut keys: Vec<(u64, u64, u32)>;
                if n <= SMALL {
                    keys = (0..n).map(key).collect();
                    keys.sort_unstable();
                } else {
                    keys = (0..n).into_par_iter().map(key).collect();
                    keys.par_sort_unstable();
                }
                let mut ranges = Vec::new();
                let mut start = 0;
                for p in 1..=n {
                    if p == n || keys[p].0 != keys[start].0 || keys[p].1 != keys[start].1 {
                        ranges.push(CellRange::new(keys[start].0, keys[start].1, start, p));
                        start = p;
                    }
                }
                (keys.iter().map(|key| key.2).collect(), ranges)
            }
        };
        let mut sorted = Self { xs, ys, order, cells, copy: None }.with_copy_if_scattered();
        let mut cells = std::mem::take(&mut sorted.cells);
        let summarise = |range: &mut CellRange| {
            for p in range.start..range.end {
                range.summary.add(sorted.point(p), p);
            }
        };
        if n <= SMALL {
            cells.iter_mut().for_each(summarise);
        } else {
            cells.par_iter_mut().for_each(summarise);
        }
        Self { cells, ..sorted }
    }

    /// Copies the points in sorted order if the detection indices in a cell span more than
    /// [`COPY_MEAN_SPAN`] on average.
    fn with_copy_if_scattered(mut self) -> Self {
        let span: u64 =
            self.cells.iter().map(|c| u64::from(self.order[c.end as usize - 1] - self.order[c.start as usize])).sum();
        if span > COPY_MEAN_SPAN * self.cells.len() as u64 {
            let point = |&k: &u32| [self.xs[k as usize], self.ys[k as usize]];
            self.copy = Some(if self.order.len() <= SMALL {
                self.order.iter().map(point).collect()
            } else {
                self.order.par_iter().map(point).collect()
            });
        }
        self
    }

    /// The point at sorted position `p`.
    #[inline]
    fn point(&self, p: u32) -> Point {
        match &self.copy {
            Some(copy) => copy[p as usize],
            None => {
                let k = self.order[p as usize] as usize;
                [self.xs[k], self.ys[k]]
            }
        }
    }

    /// Replaces the contents of `points` with the points at sorted positions `range`.
    fn points_into(&self, range: std::ops::Range<u32>, points: &mut Vec<Point>) {
        let range = range.start as usize..range.end as usize;
        points.clear();
        match &self.copy {
            Some(copy) => points.extend_from_slice(&copy[range]),
            None => points.extend(self.order[range].iter().map(|&k| [self.xs[k as usize], self.ys[k as usize]])),
        }
    }
}

/// A stable counting sort of the points by cell over a grid of `grid_cells` cells: the
/// detection index at each sorted position, and the non-empty cells with their summaries.
///
/// One thread: the two passes are bound by memory, and splitting them between threads (each
/// reading all points, writing the cells of its own range) measured no faster. Cells are
/// computed again in the second pass rather than stored: memory touched for the first time
/// costs more than the arithmetic.
fn counting_sort(
    xs: &[f64],
    ys: &[f64],
    grid_cells: usize,
    rows: u64,
    cell_of: impl Fn(usize) -> u64,
) -> (Vec<u32>, Vec<CellRange>) {
    let n = xs.len();
    // Per grid cell: the number of points, then the next free position and the index of the
    // cell among the non-empty ones.
    let mut table = vec![[0u32; 2]; grid_cells];
    for k in 0..n {
        table[cell_of(k) as usize][0] += 1;
    }
    let mut ranges = Vec::new();
    let mut start = 0;
    for (id, entry) in table.iter_mut().enumerate() {
        let count = entry[0] as usize;
        if count > 0 {
            *entry = [start as u32, ranges.len() as u32];
            ranges.push(CellRange::new(id as u64 / rows, id as u64 % rows, start, start + count));
            start += count;
        }
    }
    let mut order = vec![0u32; n];
    for k in 0..n {
        let entry = &mut table[cell_of(k) as usize];
        let slot = entry[0];
        entry[0] += 1;
        order[slot as usize] = k as u32;
        ranges[entry[1] as usize].summary.add([xs[k], ys[k]], slot);
    }
    (order, ranges)
}

/// Sorts `keys` stably by their bits 32 to 32 + `bits` (the bits above are zero): an LSD radix
/// sort with digits of at most [`DIGIT_BITS`] bits, skipping digits that all keys share.
fn radix_sort_high(keys: Vec<u64>, bits: u32) -> Vec<u64> {
    let n = keys.len();
    if bits == 0 {
        return keys;
    }
    let passes = bits.div_ceil(DIGIT_BITS);
    let digit_bits = bits.div_ceil(passes);
    let buckets = 1usize << digit_bits;
    let mask = buckets as u64 - 1;
    let digit = |key: u64, pass: u32| ((key >> (32 + digit_bits * pass)) & mask) as usize;
    let histogram = |keys: &[u64], pass: u32| {
        let mut counts = vec![0usize; buckets];
        for &key in keys {
            counts[digit(key, pass)] += 1;
        }
        counts
    };
    let mut counts = keys
        .par_chunks(1 << 16)
        .map(|chunk| histogram(chunk, 0))
        .reduce_with(|mut a, b| {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
            a
        })
        .unwrap_or_default();
    let (mut src, mut dst) = (keys, Vec::new());
    for pass in 0..passes {
        let last = pass + 1 == passes;
        if counts.contains(&n) {
            // One digit for all: already in order.
            if !last {
                counts = histogram(&src, pass + 1);
            }
            continue;
        }
        let mut next = Vec::with_capacity(buckets);
        let mut sum = 0;
        for &count in &counts {
            next.push(sum);
            sum += count;
        }
        if dst.is_empty() {
            dst = vec![0; n];
        }
        counts.fill(0);
        for &key in &src {
            let slot = &mut next[digit(key, pass)];
            dst[*slot] = key;
            *slot += 1;
            if !last {
                counts[digit(key, pass + 1)] += 1;
            }
        }
        std::mem::swap(&mut src, &mut dst);
    }
    src
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
    /// Position of its smallest point in (t, t′) order (the first in the range on ties).
    anchor: u32,
}

/// The bounding box of the points of a cell and the position of its smallest point in
/// (t, t′) order (the first one on ties), built point by point in sorted order.
#[derive(Debug, Clone, Copy)]
struct Summary {
    bbox: Bbox,
    smallest: Point,
    /// Position of `smallest` in the sorted points.
    anchor: u32,
}

impl Summary {
    const EMPTY: Self = Self {
        bbox: Bbox { x: [f64::INFINITY, f64::NEG_INFINITY], y: [f64::INFINITY, f64::NEG_INFINITY] },
        smallest: [f64::INFINITY, f64::INFINITY],
        anchor: u32::MAX,
    };

    /// Adds the point at `position`, after those before it in its cell.
    #[inline]
    fn add(&mut self, p: Point, position: u32) {
        self.bbox.x = [self.bbox.x[0].min(p[0]), self.bbox.x[1].max(p[0])];
        self.bbox.y = [self.bbox.y[0].min(p[1]), self.bbox.y[1].max(p[1])];
        if (p[0], p[1]) < (self.smallest[0], self.smallest[1]) {
            (self.smallest, self.anchor) = (p, position);
        }
    }
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

/// The first this many offsets of [`FORWARD`] are the cells that touch (0, 0).
const TOUCHING: u8 = 4;

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
    fn new(sorted: &SortedPoints, epsilon2: f64) -> Self {
        let mut cells = Vec::with_capacity(sorted.cells.len());
        let mut nodes = Vec::with_capacity(sorted.cells.len());
        for range in &sorted.cells {
            let first = nodes.len() as u32;
            let (a, b, summary) = (range.start, range.end, range.summary);
            if summary.bbox.diagonal2() <= epsilon2 {
                nodes.push(Node { start: a, end: b, bbox: summary.bbox, anchor: summary.anchor });
            } else {
                // Rounding put points more than ε apart into one cell: one node per point.
                nodes.extend((a..b).map(|p| Node {
                    start: p,
                    end: p + 1,
                    bbox: Bbox::of(&[sorted.point(p)]),
                    anchor: p,
                }));
            }
            cells.push(Cell { cx: range.cx, cy: range.cy, nodes: (first, nodes.len() as u32) });
        }
        Self { cells, nodes }
    }

    /// Joins the single-point nodes of cells that failed the diameter check.
    fn link_within_cells(&self, sorted: &SortedPoints, epsilon2: f64, union_find: &mut MinRootForest) {
        for cell in self.cells.iter().filter(|c| c.nodes.1 - c.nodes.0 > 1) {
            for a in cell.nodes.0..cell.nodes.1 {
                for b in a + 1..cell.nodes.1 {
                    let (pa, pb) = (self.nodes[a as usize].start, self.nodes[b as usize].start);
                    if !union_find.equiv(a as usize, b as usize) && within(sorted.point(pa), sorted.point(pb), epsilon2)
                    {
                        union_find.union(a as usize, b as usize);
                    }
                }
            }
        }
    }

    /// Joins nodes of neighbouring cells that have a pair within ε.
    fn link_neighbours(
        &self,
        sorted: &SortedPoints,
        epsilon2: f64,
        union_find: &mut MinRootForest,
        scratch: &mut Scratch,
    ) {
        // Touching cells first, over the whole grid: most of the farther pairs are then joined
        // already, through touching ones, and need no test.
        for ranks in [0..TOUCHING, TOUCHING..FORWARD.len() as u8] {
            self.for_each_neighbour(ranks, |a, b| self.link_cells(a, b, sorted, epsilon2, union_find, scratch));
        }
    }

    /// Calls `f(cell, neighbour)` for every cell and each of its forward neighbours whose rank in
    /// [`FORWARD`] is in `ranks`, nearest first.
    fn for_each_neighbour(&self, ranks: std::ops::Range<u8>, mut f: impl FnMut(&Cell, &Cell)) {
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
                    let rank = RANK[dx as usize][(cells[d].cy - cell.cy + 2) as usize];
                    if ranks.contains(&rank) {
                        neighbours.push((rank, d));
                    }
                    d += 1;
                }
            }
            if neighbours.len() > 1 {
                neighbours.sort_unstable();
            }
            for &(_, d) in &neighbours {
                f(cell, &cells[d]);
            }
        }
    }

    fn link_cells(
        &self,
        a: &Cell,
        b: &Cell,
        sorted: &SortedPoints,
        epsilon2: f64,
        union_find: &mut MinRootForest,
        scratch: &mut Scratch,
    ) {
        for u in a.nodes.0..a.nodes.1 {
            for v in b.nodes.0..b.nodes.1 {
                if !union_find.equiv(u as usize, v as usize)
                    && any_within(sorted, &self.nodes[u as usize], &self.nodes[v as usize], epsilon2, scratch)
                {
                    union_find.union(u as usize, v as usize);
                }
            }
        }
    }
}

/// Buffers for the points of the two nodes being compared.
#[derive(Default)]
struct Scratch {
    a: Vec<Point>,
    b: Vec<Point>,
}

/// Whether some pair across nodes `a` and `b` is within ε; stops at the first one found.
fn any_within(sorted: &SortedPoints, a: &Node, b: &Node, epsilon2: f64, scratch: &mut Scratch) -> bool {
    let (box_a, box_b) = (&a.bbox, &b.bbox);
    if box_a.min_gap2(box_b) > epsilon2 {
        return false;
    }
    if box_a.max_gap2(box_b) <= epsilon2 {
        return true;
    }
    let probes = (a.end - a.start).min(b.end - b.start).min(PROBE);
    if (0..probes).any(|k| within(sorted.point(a.start + k), sorted.point(b.start + k), epsilon2)) {
        return true;
    }
    sorted.points_into(a.start..a.end, &mut scratch.a);
    sorted.points_into(b.start..b.end, &mut scratch.b);
    let (a, b) = (scratch.a.as_mut_slice(), scratch.b.as_mut_slice());
    // Each side's point nearest to the other side's box, and the other side's point nearest to
    // it: a pair found at the cost of two passes when the sides overlap at all, and a proof that
    // there is none when one side has no point within ε of the other's box.
    for (near, box_far, far) in [(&*a, box_b, &*b), (&*b, box_a, &*a)] {
        let (gap2, p) = nearest(near, |p| box_far.point_gap2(p));
        if gap2 > epsilon2 {
            return false;
        }
        if nearest(far, |q| distance2(p, q)).0 <= epsilon2 {
            return true;
        }
    }
    if a.len() * b.len() <= BRUTE_PAIRS {
        return brute(a, b, epsilon2);
    }
    search(a, b, epsilon2)
}

/// The smallest `cost` over `points` (not empty) and the point that has it (the first on ties).
fn nearest(points: &[Point], cost: impl Fn(Point) -> f64) -> (f64, Point) {
    let mut best = (cost(points[0]), points[0]);
    for &p in &points[1..] {
        let c = cost(p);
        if c < best.0 {
            best = (c, p);
        }
    }
    best
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

//! The detections sorted by grid cell: a counting sort when the grid is small for the points, a
//! radix sort of cell keys otherwise; each cell with the summary of its points.

use rayon::prelude::*;

use super::{Bbox, Point, SMALL};

/// Points are sorted by a counting sort over the whole grid when it has at most this many cells
/// per point (plus [`COUNTING_SORT_MIN_CELLS`]).
pub(super) const COUNTING_SORT_CELLS_PER_POINT: u64 = 2;
/// Grids of up to this many cells always go to the counting sort.
pub(super) const COUNTING_SORT_MIN_CELLS: u64 = 1024;
/// Largest digit of the radix sort of cell keys, bits (8192 buckets: two passes up to 2²⁶ cells).
pub(super) const DIGIT_BITS: u32 = 13;
/// Points sorted by keys are copied in sorted order when the detection indices in a cell span
/// more than this on average (their coordinates, 16 bytes each, then stop fitting in a core's
/// cache).
pub(super) const COPY_MEAN_SPAN: u64 = 1 << 15;

/// The points sorted by grid cell, and the cells.
///
/// The points are read through `order`: a copy in sorted order would be 16 bytes per point of
/// memory touched for the first time, which costs more than the reads when the detection
/// indices in a cell are close together (detections in time order, the usual case) or when the
/// points are read only at the borders of clusters (the counting sort summarises the cells in
/// input order). Points sorted otherwise, with scattered indices, are copied.
#[derive(Debug)]
pub(super) struct SortedPoints<'a> {
    pub(super) xs: &'a [f64],
    pub(super) ys: &'a [f64],
    /// The detection index of each sorted point, ascending within a cell.
    pub(super) order: Vec<u32>,
    /// The non-empty cells in key order `(cx, cy)`.
    pub(super) cells: Vec<CellRange>,
    /// The points in sorted order, when copied.
    pub(super) copy: Option<Vec<Point>>,
}

/// A non-empty cell: its column and row, its range in [`SortedPoints`] and its points' summary.
#[derive(Debug, Clone, Copy)]
pub(super) struct CellRange {
    pub(super) cx: i64,
    pub(super) cy: i64,
    pub(super) start: u32,
    pub(super) end: u32,
    pub(super) summary: Summary,
}

impl CellRange {
    pub(super) fn new(cx: u64, cy: u64, start: usize, end: usize) -> Self {
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
    pub(super) fn new(xs: &'a [f64], ys: &'a [f64], origin: [f64; 2], corner: [f64; 2], side: f64) -> Self {
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
    pub(super) fn with_copy_if_scattered(mut self) -> Self {
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
    pub(super) fn point(&self, p: u32) -> Point {
        match &self.copy {
            Some(copy) => copy[p as usize],
            None => {
                let k = self.order[p as usize] as usize;
                [self.xs[k], self.ys[k]]
            }
        }
    }

    /// Replaces the contents of `points` with the points at sorted positions `range`.
    pub(super) fn points_into(&self, range: std::ops::Range<u32>, points: &mut Vec<Point>) {
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
pub(super) fn counting_sort(
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
pub(super) fn radix_sort_high(keys: Vec<u64>, bits: u32) -> Vec<u64> {
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

/// The bounding box of the points of a cell and the position of its smallest point in
/// (t, t′) order (the first one on ties), built point by point in sorted order.
#[derive(Debug, Clone, Copy)]
pub(super) struct Summary {
    pub(super) bbox: Bbox,
    pub(super) smallest: Point,
    /// Position of `smallest` in the sorted points.
    pub(super) anchor: u32,
}

impl Summary {
    const EMPTY: Self = Self {
        bbox: Bbox { x: [f64::INFINITY, f64::NEG_INFINITY], y: [f64::INFINITY, f64::NEG_INFINITY] },
        smallest: [f64::INFINITY, f64::INFINITY],
        anchor: u32::MAX,
    };

    /// Adds the point at `position`, after those before it in its cell.
    #[inline]
    pub(super) fn add(&mut self, p: Point, position: u32) {
        self.bbox.x = [self.bbox.x[0].min(p[0]), self.bbox.x[1].max(p[0])];
        self.bbox.y = [self.bbox.y[0].min(p[1]), self.bbox.y[1].max(p[1])];
        if (p[0], p[1]) < (self.smallest[0], self.smallest[1]) {
            (self.smallest, self.anchor) = (p, position);
        }
    }
}

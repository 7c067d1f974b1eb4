//! The grid of cells over the sorted detections, and the linking of neighbouring cells that
//! have a pair within ε (bounding boxes, probes, then a bichromatic search).

use super::sort::SortedPoints;
use super::{Bbox, Point, distance2, within};
use crate::union_find::MinRootForest;

/// Pairs of points compared one by one below this many.
pub(super) const BRUTE_PAIRS: usize = 64;
/// Pairs tried before the recursive search when linking two groups.
pub(super) const PROBE: u32 = 8;

/// A set of points known to be connected: a whole cell, or one point of a cell that failed the
/// diameter check.
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    /// Range in the sorted points.
    pub(super) start: u32,
    pub(super) end: u32,
    pub(super) bbox: Bbox,
    /// Position of its smallest point in (t, t′) order (the first in the range on ties).
    pub(super) anchor: u32,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Cell {
    pub(super) cx: i64,
    pub(super) cy: i64,
    /// Range of its nodes.
    pub(super) nodes: (u32, u32),
}

pub(super) struct Grid {
    pub(super) cells: Vec<Cell>,
    pub(super) nodes: Vec<Node>,
}

/// Forward neighbour offsets (dx, dy): the half of the 5 × 5 block after (0, 0) in key order,
/// nearest first so that the near unions make the far checks unnecessary.
pub(super) const FORWARD: [(i64, i64); 12] =
    [(0, 1), (1, 0), (1, 1), (1, -1), (0, 2), (2, 0), (1, 2), (1, -2), (2, 1), (2, -1), (2, 2), (2, -2)];

/// The first this many offsets of [`FORWARD`] are the cells that touch (0, 0).
pub(super) const TOUCHING: u8 = 4;

/// `RANK[dx][dy + 2]`: the position of (dx, dy) in [`FORWARD`] (12 for offsets not in it).
pub(super) const RANK: [[u8; 5]; 3] = {
    let mut rank = [[12u8; 5]; 3];
    let mut k = 0;
    while k < FORWARD.len() {
        rank[FORWARD[k].0 as usize][(FORWARD[k].1 + 2) as usize] = k as u8;
        k += 1;
    }
    rank
};

impl Grid {
    pub(super) fn new(sorted: &SortedPoints, epsilon2: f64) -> Self {
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
    pub(super) fn link_within_cells(&self, sorted: &SortedPoints, epsilon2: f64, union_find: &mut MinRootForest) {
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
    pub(super) fn link_neighbours(
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
    pub(super) fn for_each_neighbour(&self, ranks: std::ops::Range<u8>, mut f: impl FnMut(&Cell, &Cell)) {
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

    pub(super) fn link_cells(
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
pub(super) struct Scratch {
    pub(super) a: Vec<Point>,
    pub(super) b: Vec<Point>,
}

/// Whether some pair across nodes `a` and `b` is within ε; stops at the first one found.
pub(super) fn any_within(sorted: &SortedPoints, a: &Node, b: &Node, epsilon2: f64, scratch: &mut Scratch) -> bool {
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
pub(super) fn nearest(points: &[Point], cost: impl Fn(Point) -> f64) -> (f64, Point) {
    let mut best = (cost(points[0]), points[0]);
    for &p in &points[1..] {
        let c = cost(p);
        if c < best.0 {
            best = (c, p);
        }
    }
    best
}

pub(super) fn brute(a: &[Point], b: &[Point], epsilon2: f64) -> bool {
    a.iter().any(|&p| b.iter().any(|&q| within(p, q, epsilon2)))
}

/// Moves the points of `points` that satisfy `keep` to the front; returns how many there are.
pub(super) fn partition_in_place(points: &mut [Point], keep: impl Fn(Point) -> bool) -> usize {
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
pub(super) fn search(a: &mut [Point], b: &mut [Point], epsilon2: f64) -> bool {
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

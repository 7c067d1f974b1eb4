//! Tiles of a fleet's plane: blocks of rows × blocks of columns of one session pair, computed
//! apart (on other machines) and merged into the fleet's loop components (DESIGN §9).
//!
//! A tile is scanned by the same engine as the whole fleet, on the tile's poses only, and
//! returns a [`TileSummary`]: the statistics of each of its provisional components (cells, area,
//! runs, overlapping run pairs, diagonal cells and links, extents, closest pair, first cell) and
//! only the runs on its edges (its first and last rows, its first and last columns), with their
//! provisional labels. [`merge_tiles`] joins provisional components whose edge runs touch: a run
//! of a tile's last row that shares a column with a run of the first row of the tile below, and
//! the two halves of a run cut by a column boundary (the run in row i ending at the boundary and
//! the one starting there). Statistics add up, with three corrections for what a cut counts
//! twice or not at all: a run cut in two is one run; two cut runs in consecutive rows overlap
//! once, not once on each side of the cut; and a diagonal run cut right after its diagonal cell
//! still links (i, i + 1). Holes then follow from the Euler number as for one trajectory.
//!
//! Exactness: the components, their cells, runs, holes, extents, closest pairs and first cells
//! are those of [`find_fleet_loops`](crate::find_fleet_loops) for any tiling. Areas are sums of
//! floating-point products taken in another order (and over runs cut in pieces), so they agree
//! to rounding (a relative 10⁻¹², checked by the tests), not bit for bit.

use std::collections::HashMap;

use crate::ball_tree::BallTree;
use crate::component::{LoopComponent, ROWS_PER_LABEL_TASK, for_each_overlap, label_runs};
use crate::error::{Error, Result};
use crate::fleet::Fleet;
use crate::metric::Metric;
use crate::separation::Separation;
use crate::sublevel::{ArcLength, Pruner, SublevelSet, check_gamma, path_length};
use crate::trajectory::{Trajectory, prefix_sums_by_session};
use crate::union_find::MinRootForest;

/// Maps an index of a tile's piece to its fleet index.
type ToFleet<'a> = Box<dyn Fn(usize) -> usize + 'a>;

/// The rows of the runs cut at each column boundary of a session pair, with a global label.
type CutRows = HashMap<([usize; 2], usize), Vec<(usize, usize)>>;

/// Poses per leaf of a tile's ball hierarchy.
const LEAF_SIZE: usize = 16;

/// Rows `rows` of session `sessions[0]` against columns `columns` of session `sessions[1]`,
/// both ranges of fleet indices within their sessions; `sessions[0] ≤ sessions[1]`, and within
/// one session the tile lies on or above the diagonal (`columns.end > rows.start`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Tile {
    /// The session pair (a, b), a ≤ b.
    pub sessions: [usize; 2],
    /// Fleet indices of the rows (poses of session a).
    pub rows: std::ops::Range<usize>,
    /// Fleet indices of the columns (poses of session b).
    pub columns: std::ops::Range<usize>,
}

/// The tiles of a fleet cut into blocks of at most `block` poses per session (from each
/// session's first pose), keeping only the block pairs whose bounding balls come within γ:
/// a tile whose row block and column block cannot hold a pair within γ is not made. For a
/// session with itself, only the blocks on or above the diagonal.
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidParameter`] for a block of 0 poses.
pub fn plan_tiles<M: Metric + ?Sized>(fleet: &Fleet, metric: &M, gamma: f64, block: usize) -> Result<Vec<Tile>> {
    check_gamma(gamma)?;
    if block == 0 {
        return Err(Error::InvalidParameter { name: "block", value: 0.0, expected: "at least 1 pose" });
    }
    let joint = fleet.joint();
    // (session, range, centre, radius) of every block.
    let mut blocks = Vec::new();
    for a in 0..fleet.len() {
        let start = fleet.starts()[a];
        let end = start + fleet.session(a).len();
        for lo in (start..end).step_by(block) {
            let hi = (lo + block).min(end);
            let centre = lo + (hi - lo) / 2;
            let radius = (lo..hi).map(|k| metric.distance(joint.point(centre), joint.point(k))).fold(0.0, f64::max);
            blocks.push((a, lo..hi, centre, radius));
        }
    }
    let mut tiles = Vec::new();
    for (p, (a, rows, c_r, r_r)) in blocks.iter().enumerate() {
        for (b, columns, c_c, r_c) in &blocks[p..] {
            let reach = gamma + r_r + r_c;
            // The rounding of three distances: a relative 10⁻⁹ is far above it.
            if metric.distance(joint.point(*c_r), joint.point(*c_c)) <= reach * (1.0 + 1e-9) + 1e-9 {
                tiles.push(Tile { sessions: [*a, *b], rows: rows.clone(), columns: columns.clone() });
            }
        }
    }
    Ok(tiles)
}

/// A provisional component of one tile: the sums and extremes that merge.
#[derive(Debug, Clone, PartialEq)]
pub struct TileComponent {
    /// Holds a diagonal cell.
    pub trivial: bool,
    /// Runs (pieces of runs, where a column boundary cuts one).
    pub runs: u64,
    /// Pairs of its runs in consecutive rows of the tile that share a column.
    pub overlaps: u64,
    /// Cells.
    pub pairs: u64,
    /// Σ w_i w_j over its cells, s².
    pub area_s2: f64,
    /// Diagonal cells (i, i).
    pub diagonal_cells: u64,
    /// Diagonal links: rows i whose diagonal run reaches column i + 1.
    pub diagonal_links: u64,
    /// Σ w_i² over its diagonal cells.
    pub diagonal_area_s2: f64,
    /// First and last row (fleet indices).
    pub rows: [usize; 2],
    /// First and last column (fleet indices).
    pub columns: [usize; 2],
    /// The closest pair (fleet indices), its rank and distance.
    pub closest: [usize; 2],
    /// The metric's rank of the closest pair.
    pub closest_rank: f64,
    /// δ of the closest pair.
    pub closest_distance: f64,
    /// The first cell in row-major order (fleet indices).
    pub first: [usize; 2],
}

/// A run on a tile's edge, with its provisional component.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeRun {
    /// Fleet index of the row.
    pub row: usize,
    /// First column (fleet index), inclusive.
    pub start: usize,
    /// Last column, inclusive.
    pub end: usize,
    /// Index in [`TileSummary::components`].
    pub label: u32,
}

/// What a tile returns: its provisional components and the runs on its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct TileSummary {
    /// The tile.
    pub tile: Tile,
    /// Provisional components, numbered by first appearance in the tile.
    pub components: Vec<TileComponent>,
    /// Runs in the tile's first or last row, or touching its first or last column.
    pub edges: Vec<EdgeRun>,
}

/// Scans one tile of `fleet`: the same cells as [`find_fleet_loops`](crate::find_fleet_loops)
/// gives in the tile's rows and columns, summarised (see the module docs). Reads only the
/// tile's poses, plus the row session's path length and clock when a separation is given
/// (so that separated columns are those of the whole session, whatever the tiling).
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidSeparation`]; [`Error::InvalidParameter`] for a
/// tile that does not lie in its sessions, or below the diagonal.
pub fn scan_tile<M: Metric + ?Sized>(
    fleet: &Fleet,
    metric: &M,
    gamma: f64,
    separation: Separation,
    tile: &Tile,
) -> Result<TileSummary> {
    check_gamma(gamma)?;
    separation.check()?;
    let [a, b] = tile.sessions;
    let within = |s: usize, r: &std::ops::Range<usize>| {
        s < fleet.len()
            && r.start < r.end
            && r.start >= fleet.starts()[s]
            && r.end <= fleet.starts()[s] + fleet.session(s).len()
    };
    if a > b || !within(a, &tile.rows) || !within(b, &tile.columns) || (a == b && tile.columns.end <= tile.rows.start) {
        return Err(Error::InvalidParameter {
            name: "tile",
            value: tile.rows.start as f64,
            expected: "rows and columns within their sessions (a ≤ b), on or above the diagonal",
        });
    }
    let session_a = fleet.session(a);
    let start_a = fleet.starts()[a];
    let (r0, r1) = (tile.rows.start - start_a, tile.rows.end - start_a);
    let rows = r1 - r0;
    // The tile's poses as one small trajectory: the rows, then the columns (a ≠ b), or the
    // stretch of the session from the first row to the last column (a = b).
    let (piece, starts, to_fleet): (Trajectory, Vec<usize>, ToFleet<'_>) = if a == b {
        let c1 = tile.columns.end - start_a;
        (session_a.piece(r0..c1), vec![0], Box::new(move |k| tile.rows.start + k))
    } else {
        let start_b = fleet.starts()[b];
        let (c0, c1) = (tile.columns.start - start_b, tile.columns.end - start_b);
        let parts = [session_a.piece(r0..r1), fleet.session(b).piece(c0..c1)];
        let (joint, _) = Trajectory::concatenate(&[&parts[0], &parts[1]], 1.0)?;
        let columns_start = tile.columns.start;
        (joint, vec![0, rows], Box::new(move |k| if k < rows { tile.rows.start + k } else { columns_start + k - rows }))
    };
    let first_columns: Vec<u32> = if a == b {
        let local_c0 = tile.columns.start - tile.rows.start;
        let separated = if separation.is_none() {
            None
        } else {
            Some(separation.first_columns(&path_length(session_a, metric), session_a.timestamps_s()))
        };
        (0..piece.len())
            .map(|k| {
                let own = separated.as_ref().map_or(r0 + k, |f| f[r0 + k] as usize) - r0;
                own.max(local_c0).max(k) as u32
            })
            .collect()
    } else {
        (0..piece.len()).map(|k| if k < rows { rows as u32 } else { k as u32 }).collect()
    };
    let (arc, balls) = rayon::join(
        || ArcLength::new(&piece, metric, false),
        || BallTree::with_sessions(&piece, metric, LEAF_SIZE, &starts),
    );
    let set = SublevelSet::scan(
        &piece,
        metric,
        gamma,
        separation,
        &arc,
        Pruner::Hierarchy(&balls),
        &first_columns,
        &starts,
        rows,
    )?;
    Ok(summarise(tile, &piece, metric, &set, &starts, rows, &*to_fleet))
}

/// The provisional components of a tile's set and its edge runs.
fn summarise<M: Metric + ?Sized>(
    tile: &Tile,
    piece: &Trajectory,
    metric: &M,
    set: &SublevelSet,
    starts: &[usize],
    rows: usize,
    to_fleet: &dyn Fn(usize) -> usize,
) -> TileSummary {
    let (labels, count) = label_runs(set, ROWS_PER_LABEL_TASK);
    let widths = piece.cell_widths_s();
    let breaks: Vec<u32> = starts[1..].iter().map(|&s| s as u32).collect();
    let prefix = prefix_sums_by_session(widths, &breaks);
    let mut components = vec![
        TileComponent {
            trivial: false,
            runs: 0,
            overlaps: 0,
            pairs: 0,
            area_s2: 0.0,
            diagonal_cells: 0,
            diagonal_links: 0,
            diagonal_area_s2: 0.0,
            rows: [usize::MAX, 0],
            columns: [usize::MAX, 0],
            closest: [0, 0],
            closest_rank: f64::INFINITY,
            closest_distance: f64::INFINITY,
            first: [usize::MAX, usize::MAX],
        };
        count as usize
    ];
    let mut edges = Vec::new();
    let (first_column, last_column) = (tile.columns.start, tile.columns.end - 1);
    for i in 0..rows {
        if i + 1 < rows {
            for_each_overlap(set, i..i + 1, |x, _| components[labels[x] as usize].overlaps += 1);
        }
        let offset = set.row_offset(i);
        let (w_i, fleet_i) = (widths[i], to_fleet(i));
        for (k, run) in set.row(i).iter().enumerate() {
            let r = offset + k;
            let label = labels[r];
            let c = &mut components[label as usize];
            let (x, y) = (run.start as usize, run.end as usize);
            let (start, end) = (to_fleet(x), to_fleet(y));
            c.runs += 1;
            c.pairs += run.len() as u64;
            c.area_s2 += w_i * ((prefix[y] + widths[y]) - prefix[x]);
            c.rows = [c.rows[0].min(fleet_i), c.rows[1].max(fleet_i)];
            c.columns = [c.columns[0].min(start), c.columns[1].max(end)];
            if c.first[0] == usize::MAX {
                c.first = [fleet_i, start];
            }
            if start == fleet_i {
                c.trivial = true;
                c.diagonal_cells += 1;
                c.diagonal_area_s2 += w_i * w_i;
                if end > fleet_i {
                    c.diagonal_links += 1;
                }
            }
            let j = set.closest_columns()[r] as usize;
            let rank = metric.distance_rank(piece.point(i), piece.point(j));
            if rank < c.closest_rank {
                c.closest_rank = rank;
                c.closest = [fleet_i, to_fleet(j)];
                c.closest_distance = metric.distance(piece.point(i), piece.point(j));
            }
            if i == 0 || i + 1 == rows || start == first_column || end == last_column {
                edges.push(EdgeRun { row: fleet_i, start, end, label });
            }
        }
    }
    TileSummary { tile: tile.clone(), components, edges }
}

/// Merges the summaries of tiles that cover a fleet's plane (every tile [`plan_tiles`] makes,
/// scanned by [`scan_tile`], in any order) into the fleet's loop components, numbered as
/// [`find_fleet_loops`](crate::find_fleet_loops) numbers them (by first cell, row-major).
///
/// The merge is a union-find over the provisional components, O(components + edge runs).
///
/// # Errors
/// [`Error::InvalidParameter`] for two summaries of one tile.
pub fn merge_tiles(summaries: &[TileSummary]) -> Result<Vec<LoopComponent>> {
    let mut base = Vec::with_capacity(summaries.len());
    let mut total = 0_usize;
    let mut by_corner: HashMap<([usize; 2], usize, usize), usize> = HashMap::new();
    for (t, s) in summaries.iter().enumerate() {
        base.push(total);
        total += s.components.len();
        if by_corner.insert((s.tile.sessions, s.tile.rows.start, s.tile.columns.start), t).is_some() {
            return Err(Error::InvalidParameter {
                name: "tile",
                value: s.tile.rows.start as f64,
                expected: "each tile summarised once",
            });
        }
    }
    let mut parent: Vec<u32> = (0..total as u32).collect();
    let mut forest = MinRootForest::new(&mut parent, 0);
    // Corrections: (global label, Δruns, Δoverlaps, Δlinks), applied to roots after the joins.
    let mut corrections: Vec<(usize, i64, i64, i64)> = Vec::new();
    // The rows (and a global label) of the runs cut at each column boundary of a session pair.
    let mut cut_rows: CutRows = HashMap::new();
    for (t, s) in summaries.iter().enumerate() {
        let tile = &s.tile;
        // The tile below: its first row after this tile's last, same columns.
        if let Some(&u) = by_corner.get(&(tile.sessions, tile.rows.end, tile.columns.start)) {
            let below = &summaries[u];
            let last: Vec<&EdgeRun> = s.edges.iter().filter(|e| e.row + 1 == tile.rows.end).collect();
            let first: Vec<&EdgeRun> = below.edges.iter().filter(|e| e.row == below.tile.rows.start).collect();
            let (mut p, mut q) = (0, 0);
            while p < last.len() && q < first.len() {
                let (x, y) = (last[p], first[q]);
                if x.start.max(y.start) <= x.end.min(y.end) {
                    let (gx, gy) = (base[t] + x.label as usize, base[u] + y.label as usize);
                    forest.union(gx, gy);
                    corrections.push((gx, 0, 1, 0));
                }
                if x.end <= y.end {
                    p += 1;
                }
                if y.end <= x.end {
                    q += 1;
                }
            }
        }
        // The tile to the right: same rows, its first column after this tile's last.
        if let Some(&u) = by_corner.get(&(tile.sessions, tile.rows.start, tile.columns.end)) {
            let right = &summaries[u];
            let boundary = tile.columns.end;
            let ending: HashMap<usize, &EdgeRun> =
                s.edges.iter().filter(|e| e.end + 1 == boundary).map(|e| (e.row, e)).collect();
            for y in right.edges.iter().filter(|e| e.start == boundary) {
                if let Some(x) = ending.get(&y.row) {
                    let (gx, gy) = (base[t] + x.label as usize, base[u] + y.label as usize);
                    forest.union(gx, gy);
                    // One run, not two; a diagonal cell followed by the cut still links.
                    let link = i64::from(x.start == x.row && boundary == x.row + 1);
                    corrections.push((gx, -1, 0, link));
                    cut_rows.entry((tile.sessions, boundary)).or_default().push((y.row, gx));
                }
            }
        }
    }
    // Cut runs in consecutive rows (of one tile or of two tiles one above the other) overlap
    // once in the plane, but once on each side of the cut in the tiles.
    for rows in cut_rows.values_mut() {
        rows.sort_unstable();
        for w in rows.windows(2) {
            if w[1].0 == w[0].0 + 1 {
                corrections.push((w[0].1, 0, -1, 0));
            }
        }
    }
    // Roots, numbered later by first cell; statistics added to each root.
    let mut merged: HashMap<usize, (TileComponent, i64, i64, i64)> = HashMap::new();
    for (t, s) in summaries.iter().enumerate() {
        for (k, c) in s.components.iter().enumerate() {
            let root = forest.find(base[t] + k);
            merged
                .entry(root)
                .and_modify(|(m, _, _, _)| {
                    m.trivial |= c.trivial;
                    m.runs += c.runs;
                    m.overlaps += c.overlaps;
                    m.pairs += c.pairs;
                    m.area_s2 += c.area_s2;
                    m.diagonal_cells += c.diagonal_cells;
                    m.diagonal_links += c.diagonal_links;
                    m.diagonal_area_s2 += c.diagonal_area_s2;
                    m.rows = [m.rows[0].min(c.rows[0]), m.rows[1].max(c.rows[1])];
                    m.columns = [m.columns[0].min(c.columns[0]), m.columns[1].max(c.columns[1])];
                    let (mine, theirs) = ((m.closest_rank, m.closest), (c.closest_rank, c.closest));
                    if theirs.0 < mine.0 || (theirs.0 == mine.0 && theirs.1 < mine.1) {
                        m.closest_rank = c.closest_rank;
                        m.closest = c.closest;
                        m.closest_distance = c.closest_distance;
                    }
                    m.first = m.first.min(c.first);
                })
                .or_insert((c.clone(), 0, 0, 0));
        }
    }
    for (label, runs, overlaps, links) in corrections {
        let root = forest.find(label);
        let entry = merged.get_mut(&root).expect("every label has a root");
        entry.1 += runs;
        entry.2 += overlaps;
        entry.3 += links;
    }
    let mut components: Vec<(TileComponent, i64, i64, i64)> = merged.into_values().collect();
    components.sort_unstable_by_key(|(c, ..)| c.first);
    Ok(components
        .into_iter()
        .enumerate()
        .map(|(id, (c, d_runs, d_overlaps, d_links))| {
            let runs = c.runs as i64 + d_runs;
            let euler_half = runs - (c.overlaps as i64 + d_overlaps);
            let links = c.diagonal_links as i64 + d_links;
            let (area_s2, pairs, euler, rows, columns): (f64, u64, i64, [usize; 2], [usize; 2]) = if c.trivial {
                let euler = 2 * euler_half - c.diagonal_cells as i64 + links;
                let extent = [c.rows[0], c.columns[1]];
                (2.0 * c.area_s2 - c.diagonal_area_s2, 2 * c.pairs - c.diagonal_cells, euler, extent, extent)
            } else {
                (c.area_s2, c.pairs, euler_half, c.rows, c.columns)
            };
            debug_assert!(euler <= 1, "a connected set has Euler number ≤ 1");
            LoopComponent {
                id,
                trivial: c.trivial,
                area_s2,
                pair_count: pairs,
                run_count: runs as usize,
                holes: (1 - euler) as u64,
                i_range: rows,
                j_range: columns,
                closest_pair: c.closest,
                closest_distance: c.closest_distance,
            }
        })
        .collect())
}

//! Tiles of a fleet's plane: blocks of rows × blocks of columns of one session pair, computed
//! apart (on other machines) and merged into the fleet's loop components.
//!
//! A tile is scanned by the same engine as the whole fleet, on the tile's poses only, and
//! returns a [`TileSummary`]: the statistics of each of its provisional components (cells, area,
//! runs, overlapping run pairs, diagonal cells and links, extents and their times, closest pair,
//! first cell) and only the runs on its edges (its first and last rows, its first and last
//! columns), with their provisional labels. The merge joins provisional components whose edge
//! runs touch: a run of a tile's last row that shares a column with a run of the first row of
//! the tile below, and the two halves of a run cut by a column boundary (the run in row i ending
//! at the boundary and the one starting there). Statistics add up, with three corrections for
//! what a cut counts twice or not at all: a run cut in two is one run; two cut runs in
//! consecutive rows overlap once, not once on each side of the cut; and a diagonal run cut right
//! after its diagonal cell still links (i, i + 1). Holes then follow from the Euler number as for
//! one trajectory.
//!
//! For a cluster, every step has a form that needs no [`Fleet`]:
//! - **Plan** from what each session's reader learns alone: [`SessionBlocks`] (pose count, span,
//!   the bounding balls of its blocks), then [`plan_session_tiles`]. [`plan_tiles`] is the same
//!   plan from a fleet in memory.
//! - **Scan** a tile from its two sessions' trajectories and their first fleet indices:
//!   [`scan_session_tile`], which also keeps, as [`TileKeep`] asks, the tile's share of τ and its
//!   runs for the draws (see [`draw_session_tile`]). [`scan_tile`] is the same scan of a fleet in memory.
//! - **Merge** in a tree: a [`TileMerge`] is a partial merge of any set of tiles (one tile's
//!   summary, or a merge of merges), keeping the statistics of its components with the joins
//!   made so far and only the edge runs that face a tile it does not hold yet; merging merges
//!   joins across them. The order and grouping do not matter. [`TileMerge::finish`] gives the
//!   fleet's components with their session pairs ([`MergedLoops`]: the overlap matrix, the
//!   components in session poses); [`merge_tiles`] is the one-step merge of summaries.
//! - **Ship** as bytes: `TileSummary::to_bytes`, `TileMerge::to_bytes` and
//!   `SessionBlocks::to_bytes`, with the `serde` feature (MessagePack, as the Python bindings
//!   pickle results, after a 4-byte tag and a format version; decoding checks the tag, the
//!   version, that every byte is used and that labels and tiles refer to what exists, and says
//!   which of these failed).
//!
//! Exactness: the components, their cells, runs, holes, extents, closest pairs and first cells
//! are those of [`find_fleet_loops`](crate::fleet::find_fleet_loops) for any tiling and any merge tree.
//! Areas are sums of floating-point products taken in another order (and over runs cut in
//! pieces), so they agree to rounding (a relative 10⁻¹², checked by the tests), not bit for bit.
//!
//! # Examples
//! ```
//! use loops_core::tile::{SessionBlocks, TileKeep, TileMerge, plan_session_tiles, scan_session_tile};
//! use loops_core::{Euclidean, Separation, Trajectory};
//! let out = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
//! let back = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
//! // Each reader describes its session; the plan needs nothing else.
//! let blocks = [SessionBlocks::new(&out, &Euclidean, 2)?, SessionBlocks::new(&back, &Euclidean, 2)?];
//! let tiles = plan_session_tiles(&blocks, &Euclidean, 1.0)?;
//! let sessions = [&out, &back];
//! let starts = [0, 3]; // the sessions' first fleet indices: 3 poses, then 2
//! let mut parts = Vec::new();
//! for tile in &tiles {
//!     let [a, b] = tile.sessions;
//!     let pair = [sessions[a], sessions[b]];
//!     let summary =
//!         scan_session_tile(pair, [starts[a], starts[b]], &Euclidean, 1.0, Separation::NONE, tile, TileKeep::SUMMARY)?
//!             .summary;
//!     // What a worker ships back, and the merge reads.
//!     parts.push(TileMerge::new(loops_core::tile::TileSummary::from_bytes(&summary.to_bytes())?)?);
//! }
//! let merged = TileMerge::merge(parts)?.finish()?;
//! let between: Vec<_> = merged.components().iter().filter(|c| c.sessions == [0, 1]).collect();
//! assert_eq!(between.len(), 2); // Tuesday passes Monday's poses twice
//! let overlap = merged.session_pairs(&[2.0, 1.0])?;
//! assert_eq!(overlap.iter().map(|p| p.sessions).collect::<Vec<_>>(), [[0, 0], [0, 1], [1, 1]]);
//! # Ok::<(), loops_core::Error>(())
//! ```

pub(crate) mod draw;
mod piece;

use std::collections::HashMap;

use self::draw::duration_of;
pub use self::draw::{TileDuration, TileRuns, draw_session_tile, draw_tile_runs, session_loop_duration, tile_requests};
use self::piece::{SideBalls, live_stretches};

use crate::ball_tree::BallTree;
use crate::component::{LoopComponent, ROWS_PER_LABEL_TASK, Tally, closer, for_each_overlap, label_runs};
use crate::error::{Error, Result};
use crate::fleet::{Fleet, FleetComponent, SessionPair, localize, session_pairs_of};
use crate::metric::Metric;
use crate::sample::DrawStats;
use crate::separation::Separation;
use crate::spec::{MetricSpec, with_metric};
use crate::sublevel::{ArcLength, Pruner, SublevelSet, check_gamma, try_path_length};
use crate::trajectory::{Trajectory, prefix_sums_by_session};
use crate::union_find::{MinRootForest, number_sets};

/// Poses per leaf of a tile's ball hierarchy.
const LEAF_SIZE: usize = 16;

/// The version of the byte format of `TileSummary::to_bytes`, `TileMerge::to_bytes`,
/// `SessionBlocks::to_bytes` and the other tile types (with the `serde` feature): bytes of a
/// version from [`OLDEST_TILE_FORMAT_VERSION`] on are read, others refused. Version 3 keeps a
/// tile's share of τ on the stretches its scan read ([`TileDuration`], tag `ILtt`), where
/// version 2 kept a value for every row and column (`ILtd`, still read); the other types are
/// the same in both. Version 4 packs long arrays of numbers (runs, labels, components, shares)
/// as little-endian values in one MessagePack `bin` each; versions 2 and 3 wrote each number on
/// its own, and are read as they are. Version 5 packs a merge's components too (a fixed-width
/// record each, [`MergedLoops::to_bytes`]), where version 4 wrote each field on its own (still
/// read).
pub const TILE_FORMAT_VERSION: u16 = 5;

/// The oldest version of the byte format ([`TILE_FORMAT_VERSION`]) this build reads.
pub const OLDEST_TILE_FORMAT_VERSION: u16 = 2;

/// Rows `rows` of session `sessions[0]` against columns `columns` of session `sessions[1]`,
/// both ranges of fleet indices within their sessions; `sessions[0] ≤ sessions[1]`, and within
/// one session the tile lies on or above the diagonal (`columns.end > rows.start`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Tile {
    /// The session pair (a, b), a ≤ b.
    pub sessions: [usize; 2],
    /// Fleet indices of the rows (poses of session a).
    pub rows: std::ops::Range<usize>,
    /// Fleet indices of the columns (poses of session b).
    pub columns: std::ops::Range<usize>,
}

impl Tile {
    /// Non-empty ranges, a ≤ b, on or above the diagonal within one session.
    pub(crate) fn is_well_formed(&self) -> bool {
        let [a, b] = self.sessions;
        a <= b
            && self.rows.start < self.rows.end
            && self.columns.start < self.columns.end
            && (a != b || self.columns.end > self.rows.start)
    }

    /// The tile of sessions `sessions`, its rows and columns moved by `shifts` (fleet
    /// indices): where a tile lies once the fleet's sessions are renumbered.
    pub(crate) fn moved(&self, sessions: [usize; 2], shifts: [isize; 2]) -> Tile {
        let at = |x: usize, side: usize| x.wrapping_add_signed(shifts[side]);
        Tile {
            sessions,
            rows: at(self.rows.start, 0)..at(self.rows.end, 0),
            columns: at(self.columns.start, 1)..at(self.columns.end, 1),
        }
    }
}

/// What planning tiles needs of one session, learnt by whoever reads it: its pose count, its
/// span and the bounding balls of its blocks of `block` consecutive poses (from its first pose).
/// A ball is centred on the block's middle pose, with the largest distance from it to a pose of
/// the block as radius.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SessionBlocks {
    /// Number of poses.
    pub poses: usize,
    /// t_{n−1} − t_0, seconds (the span that [`SessionPair::density`] divides by).
    pub span_s: f64,
    /// Poses per block (the last block may hold fewer).
    pub block: usize,
    /// Coordinates per pose.
    pub dim: usize,
    /// The centre pose of each block, `dim` coordinates per block.
    pub centres: Vec<f64>,
    /// The radius of each block's ball, in the metric's unit.
    pub radii: Vec<f64>,
}

impl SessionBlocks {
    /// The blocks of `session` under `metric`: O(poses) distance evaluations.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a block of 0 poses.
    pub fn new<M: Metric + ?Sized>(session: &Trajectory, metric: &M, block: usize) -> Result<Self> {
        if block == 0 {
            return Err(Error::InvalidParameter { name: "block", value: 0.0, expected: "at least 1 pose" });
        }
        let (mut centres, mut radii) = (Vec::new(), Vec::new());
        for lo in (0..session.len()).step_by(block) {
            let hi = (lo + block).min(session.len());
            let (centre, radius) = piece::pose_ball(session, lo, hi, metric);
            centres.extend_from_slice(session.point(centre));
            radii.push(radius);
        }
        Ok(Self { poses: session.len(), span_s: session.span_s(), block, dim: session.dim(), centres, radii })
    }

    /// The same session in blocks `factor` times larger (the last may hold fewer poses), each
    /// bounded from the balls of the blocks it joins: centred on its middle block's centre, with
    /// radius the largest distance from there to a joined block's centre plus that block's
    /// radius (by the triangle inequality, every pose of the block lies within it). Lets a planner
    /// choose the tiles' size after learning every session's length, without reading the
    /// sessions again. O(blocks) distance evaluations.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a factor of 0, or blocks of more than `usize::MAX` poses.
    ///
    /// # Example
    /// ```
    /// use loops_core::tile::SessionBlocks;
    /// use loops_core::{Euclidean, Trajectory};
    /// let x: Vec<f64> = (0..10).map(f64::from).collect();
    /// let drive = Trajectory::new(x.clone(), x.iter().flat_map(|&x| [x, 0.0]).collect(), 2).unwrap();
    /// let fine = SessionBlocks::new(&drive, &Euclidean, 2).unwrap();
    /// let coarse = fine.coarsened(3, &Euclidean).unwrap();
    /// assert_eq!((coarse.block, coarse.len()), (6, 2));
    /// // Poses 0..6 around pose 3's centre (block 1 of 2): 2 + 1 from pose 1's block.
    /// assert_eq!((&coarse.centres[..2], coarse.radii[0]), (&[3.0, 0.0][..], 3.0));
    /// ```
    pub fn coarsened<M: Metric + ?Sized>(&self, factor: usize, metric: &M) -> Result<Self> {
        let block = self.block.checked_mul(factor).filter(|_| factor > 0).ok_or(Error::InvalidParameter {
            name: "factor",
            value: factor as f64,
            expected: "at least 1, with blocks of at most usize::MAX poses",
        })?;
        let centre = |k: usize| &self.centres[k * self.dim..(k + 1) * self.dim];
        let (mut centres, mut radii) = (Vec::new(), Vec::new());
        for lo in (0..self.len()).step_by(factor) {
            let hi = (lo + factor).min(self.len());
            let middle = centre(lo + (hi - lo) / 2);
            let radius = piece::joined_radius(middle, (lo..hi).map(|k| (centre(k), self.radii[k])), metric);
            centres.extend_from_slice(middle);
            radii.push(radius);
        }
        Ok(Self { poses: self.poses, span_s: self.span_s, block, dim: self.dim, centres, radii })
    }

    /// Number of blocks.
    pub fn len(&self) -> usize {
        self.radii.len()
    }

    /// No blocks (a session of no poses; never one made by [`new`](Self::new)).
    pub fn is_empty(&self) -> bool {
        self.radii.is_empty()
    }

    /// The fields agree with each other.
    pub(crate) fn check(&self) -> std::result::Result<(), String> {
        if self.block == 0 || self.dim == 0 {
            return Err(format!("block {} and dimension {} must be at least 1", self.block, self.dim));
        }
        if self.radii.len() != self.poses.div_ceil(self.block) || self.centres.len() != self.radii.len() * self.dim {
            return Err(format!(
                "{} poses in blocks of {} make {} blocks, but there are {} radii and {} centre coordinates \
                 (dimension {})",
                self.poses,
                self.block,
                self.poses.div_ceil(self.block),
                self.radii.len(),
                self.centres.len(),
                self.dim
            ));
        }
        if let Some(k) = self.radii.iter().position(|r| !(r.is_finite() && *r >= 0.0)) {
            return Err(format!("radius {} of block {k} is not a finite distance ≥ 0", self.radii[k]));
        }
        Ok(())
    }

    /// The blocks as bytes: a 4-byte tag, [`TILE_FORMAT_VERSION`], then MessagePack.
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        encode(*b"ILsb", self)
    }

    /// The blocks from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    /// [`Error::InvalidState`]: other bytes, another version, or fields that disagree.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let blocks: Self = decode(*b"ILsb", "session blocks", bytes)?;
        blocks.check().map_err(|problem| Error::InvalidState { what: "session blocks", reason: problem })?;
        Ok(blocks)
    }
}

/// The tiles of a fleet cut into blocks of at most `block` poses per session (from each
/// session's first pose), keeping only the block pairs whose bounding balls come within γ:
/// a tile whose row block and column block cannot hold a pair within γ is not made. For a
/// session with itself, only the blocks on or above the diagonal. The same plan as
/// [`plan_session_tiles`] of each session's [`SessionBlocks`].
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidParameter`] for a block of 0 poses.
pub fn plan_tiles<M: Metric + ?Sized>(fleet: &Fleet, metric: &M, gamma: f64, block: usize) -> Result<Vec<Tile>> {
    check_gamma(gamma)?;
    let sessions =
        (0..fleet.len()).map(|a| SessionBlocks::new(fleet.session(a), metric, block)).collect::<Result<Vec<_>>>()?;
    plan_session_tiles(&sessions, metric, gamma)
}

/// The tiles of the fleet whose sessions, in fleet order, have these blocks (see
/// [`plan_tiles`]): fleet indices number the sessions' poses one session after another.
/// For metrics that are the Euclidean distance of 1 to 3 coordinates, a KD-tree over the
/// blocks' centres finds the candidates (O(blocks log blocks + candidates)); for any other
/// metric every two blocks are compared (O(blocks²) distance evaluations).
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidParameter`] for no sessions, or sessions cut into
/// blocks of different sizes or of points of different dimensions; [`Error::InconsistentTiles`]
/// for blocks whose fields disagree.
pub fn plan_session_tiles<M: Metric + ?Sized>(sessions: &[SessionBlocks], metric: &M, gamma: f64) -> Result<Vec<Tile>> {
    plan_blocks(sessions, metric, gamma, None)
}

/// The tiles of [`plan_session_tiles`] that hold a session marked in `touched` (one flag per
/// session) as their rows or their columns: what an update of those sessions must scan
/// anew, the plan of every other session pair being unchanged (a tile depends on its two
/// sessions' blocks alone). The same tiles, in the same order, as filtering the whole plan;
/// the candidates are searched from the marked sessions' blocks only.
///
/// # Errors
/// As [`plan_session_tiles`]; [`Error::InvalidParameter`] for a number of flags other than
/// the number of sessions.
///
/// # Examples
/// ```
/// use loops_core::tile::{SessionBlocks, plan_session_tiles, plan_session_tiles_touching};
/// use loops_core::{Euclidean, Trajectory};
/// let line = |t0: f64, y: f64| Trajectory::from_points(vec![t0, t0 + 1.0], &[[0.0, y], [1.0, y]]);
/// let blocks: Vec<SessionBlocks> =
///     [line(0.0, 0.0)?, line(10.0, 0.5)?, line(20.0, 9.0)?].iter().map(|s| SessionBlocks::new(s, &Euclidean, 2)).collect::<Result<_, _>>()?;
/// let all = plan_session_tiles(&blocks, &Euclidean, 1.0)?;
/// let touched = plan_session_tiles_touching(&blocks, &Euclidean, 1.0, &[false, true, false])?;
/// let expected: Vec<_> = all.into_iter().filter(|t| t.sessions.contains(&1)).collect();
/// assert_eq!(touched, expected); // session 1 with itself and with session 0
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn plan_session_tiles_touching<M: Metric + ?Sized>(
    sessions: &[SessionBlocks],
    metric: &M,
    gamma: f64,
    touched: &[bool],
) -> Result<Vec<Tile>> {
    if touched.len() != sessions.len() {
        return Err(Error::InvalidParameter {
            name: "touched",
            value: touched.len() as f64,
            expected: "one flag per session",
        });
    }
    plan_blocks(sessions, metric, gamma, Some(touched))
}

/// [`plan_session_tiles`], keeping only the tiles of a session marked in `touched` when given.
fn plan_blocks<M: Metric + ?Sized>(
    sessions: &[SessionBlocks],
    metric: &M,
    gamma: f64,
    touched: Option<&[bool]>,
) -> Result<Vec<Tile>> {
    check_gamma(gamma)?;
    let Some(first) = sessions.first() else {
        return Err(Error::InvalidParameter { name: "sessions", value: 0.0, expected: "at least one session" });
    };
    for s in sessions {
        s.check().map_err(|problem| Error::InconsistentTiles { problem: format!("session blocks: {problem}") })?;
        if s.block != first.block {
            return Err(Error::InvalidParameter {
                name: "block",
                value: s.block as f64,
                expected: "the same block size for every session",
            });
        }
        if s.dim != first.dim {
            return Err(Error::InvalidParameter {
                name: "dimension",
                value: s.dim as f64,
                expected: "the same dimension for every session",
            });
        }
    }
    // (session, range, centre, radius) of every block.
    let mut blocks = Vec::new();
    let mut start = 0;
    for (a, s) in sessions.iter().enumerate() {
        for (k, radius) in s.radii.iter().enumerate() {
            let lo = start + k * s.block;
            let hi = (lo + s.block).min(start + s.poses);
            blocks.push((a, lo..hi, &s.centres[k * s.dim..(k + 1) * s.dim], *radius));
        }
        start += s.poses;
    }
    // The rounding of three distances: a relative 10⁻⁹ is far above it.
    let meets = |p: usize, q: usize| {
        let ((_, _, c_r, r_r), (_, _, c_c, r_c)) = (&blocks[p], &blocks[q]);
        metric.distance(c_r, c_c) <= (gamma + r_r + r_c) * (1.0 + 1e-9) + 1e-9
    };
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    let centres: Vec<&[f64]> = blocks.iter().map(|b| b.2).collect();
    let index = if metric.is_coordinate_euclidean() { crate::spatial::Kd::new(&centres) } else { None };
    match index {
        // Euclidean coordinates (1 to 3): each block asks a KD-tree over the centres for those
        // within its reach plus the largest radius, O(blocks log blocks + candidates).
        Some(index) => {
            let largest = blocks.iter().map(|b| b.3).fold(0.0, f64::max);
            // With `touched`, only the marked blocks ask, for partners on either side; each
            // pair is measured as (lower, higher) block, as the whole plan measures it.
            for (p, block) in blocks.iter().enumerate() {
                if touched.is_some_and(|t| !t[block.0]) {
                    continue;
                }
                let reach = (gamma + block.3 + largest) * (1.0 + 1e-6) + 1e-6;
                index.within(block.2, reach, |q| {
                    let (lo, hi) = (p.min(q), p.max(q));
                    if (q >= p || touched.is_some()) && meets(lo, hi) {
                        pairs.push((lo, hi));
                    }
                });
            }
            pairs.sort_unstable();
            pairs.dedup();
        }
        // Any other metric: every two blocks, O(blocks²).
        None => {
            let kept = |p: usize, q: usize| touched.is_none_or(|t| t[blocks[p].0] || t[blocks[q].0]);
            for p in 0..blocks.len() {
                pairs.extend((p..blocks.len()).filter(|&q| kept(p, q) && meets(p, q)).map(|q| (p, q)));
            }
        }
    }
    let tiles = pairs
        .into_iter()
        .map(|(p, q)| Tile {
            sessions: [blocks[p].0, blocks[q].0],
            rows: blocks[p].1.clone(),
            columns: blocks[q].1.clone(),
        })
        .collect();
    Ok(tiles)
}

impl MetricSpec {
    /// [`SessionBlocks::new`] under this metric.
    ///
    /// # Errors
    /// As [`SessionBlocks::new`].
    pub fn session_blocks(&self, session: &Trajectory, block: usize) -> Result<SessionBlocks> {
        with_metric!(self, m => SessionBlocks::new(session, m, block))
    }

    /// [`SessionBlocks::coarsened`] under this metric.
    ///
    /// # Errors
    /// As [`SessionBlocks::coarsened`].
    pub fn coarsened_blocks(&self, blocks: &SessionBlocks, factor: usize) -> Result<SessionBlocks> {
        with_metric!(self, m => blocks.coarsened(factor, m))
    }

    /// [`plan_session_tiles`] under this metric.
    ///
    /// # Errors
    /// As [`plan_session_tiles`].
    pub fn plan_session_tiles(&self, sessions: &[SessionBlocks], gamma: f64) -> Result<Vec<Tile>> {
        with_metric!(self, m => plan_session_tiles(sessions, m, gamma))
    }

    /// [`scan_session_tiles`] under this metric.
    ///
    /// # Errors
    /// As [`scan_session_tiles`].
    pub fn scan_session_tiles(
        &self,
        jobs: &[(&Tile, [&Trajectory; 2], [usize; 2])],
        gamma: f64,
        separation: Separation,
        keep: TileKeep,
    ) -> Result<Vec<TileScan>> {
        with_metric!(self, m => scan_session_tiles(jobs, m, gamma, separation, keep))
    }

    /// [`scan_session_tile`] under this metric.
    ///
    /// # Errors
    /// As [`scan_session_tile`].
    pub fn scan_session_tile(
        &self,
        sessions: [&Trajectory; 2],
        starts: [usize; 2],
        gamma: f64,
        separation: Separation,
        tile: &Tile,
        keep: TileKeep,
    ) -> Result<TileScan> {
        with_metric!(self, m => scan_session_tile(sessions, starts, m, gamma, separation, tile, keep))
    }
}

/// A provisional component of one tile: the sums and extremes that merge.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// The times of the first and last row, and of the first and last column, seconds, each on
    /// its session's own clock.
    pub times_s: [[f64; 2]; 2],
    /// The closest pair (fleet indices), its rank and distance.
    pub closest: [usize; 2],
    /// The metric's rank of the closest pair.
    pub closest_rank: f64,
    /// δ of the closest pair.
    pub closest_distance: f64,
    /// The first cell in row-major order (fleet indices).
    pub first: [usize; 2],
}

impl TileComponent {
    /// The tally of the counts, extents and closest pair ([`Tally`]).
    fn tally(&self) -> Tally {
        Tally {
            trivial: self.trivial,
            runs: self.runs,
            overlaps: self.overlaps,
            pairs: self.pairs,
            area_s2: self.area_s2,
            diagonal_cells: self.diagonal_cells,
            diagonal_links: self.diagonal_links,
            diagonal_area_s2: self.diagonal_area_s2,
            rows: self.rows,
            columns: self.columns,
            closest: (self.closest_rank, self.closest),
        }
    }

    /// A provisional component from its tally, first cell and closest pair's distance; the times
    /// of its extents are filled in later.
    fn from_tally(tally: Tally, first: [usize; 2], closest_distance: f64) -> Self {
        let mut component = Self {
            trivial: false,
            runs: 0,
            overlaps: 0,
            pairs: 0,
            area_s2: 0.0,
            diagonal_cells: 0,
            diagonal_links: 0,
            diagonal_area_s2: 0.0,
            rows: [0; 2],
            columns: [0; 2],
            times_s: [[0.0; 2]; 2],
            closest: [0; 2],
            closest_rank: f64::INFINITY,
            closest_distance,
            first,
        };
        component.set_tally(tally);
        component
    }

    /// Sets the counts, extents and closest pair from `tally`.
    fn set_tally(&mut self, tally: Tally) {
        let Tally {
            trivial,
            runs,
            overlaps,
            pairs,
            area_s2,
            diagonal_cells,
            diagonal_links,
            diagonal_area_s2,
            rows,
            columns,
            closest,
        } = tally;
        (self.trivial, self.runs, self.overlaps, self.pairs, self.area_s2) = (trivial, runs, overlaps, pairs, area_s2);
        (self.diagonal_cells, self.diagonal_links, self.diagonal_area_s2) =
            (diagonal_cells, diagonal_links, diagonal_area_s2);
        (self.rows, self.columns, (self.closest_rank, self.closest)) = (rows, columns, closest);
    }

    /// Adds the statistics of `other`, a provisional component of the same final component: the
    /// tallies merge by [`Tally::absorb`]; each extreme keeps its time, and the closest pair its
    /// distance.
    fn absorb(&mut self, other: &Self) {
        let mut tally = self.tally();
        tally.absorb(&other.tally());
        // Within a session, times grow with the index: an extreme `other` moved takes its time.
        for axis in 0..2 {
            let (mine, theirs) = if axis == 0 { (self.rows, other.rows) } else { (self.columns, other.columns) };
            if theirs[0] < mine[0] {
                self.times_s[axis][0] = other.times_s[axis][0];
            }
            if theirs[1] > mine[1] {
                self.times_s[axis][1] = other.times_s[axis][1];
            }
        }
        if closer((other.closest_rank, other.closest), (self.closest_rank, self.closest)) {
            self.closest_distance = other.closest_distance;
        }
        self.set_tally(tally);
        self.first = self.first.min(other.first);
    }
}

/// A run on a tile's edge, with its provisional component.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TileSummary {
    /// The tile.
    pub tile: Tile,
    /// Provisional components, numbered by first appearance in the tile.
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    pub components: Vec<TileComponent>,
    /// Runs in the tile's first or last row, or touching its first or last column.
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    pub edges: Vec<EdgeRun>,
}

#[cfg(feature = "serde")]
crate::packed::packed_record!(EdgeRun { row: usize, start: usize, end: usize, label: u32 });

#[cfg(feature = "serde")]
crate::packed::packed_record!(TileComponent {
    trivial: bool,
    runs: u64,
    overlaps: u64,
    pairs: u64,
    area_s2: f64,
    diagonal_cells: u64,
    diagonal_links: u64,
    diagonal_area_s2: f64,
    rows: [usize; 2],
    columns: [usize; 2],
    times_s: [[f64; 2]; 2],
    closest: [usize; 2],
    closest_rank: f64,
    closest_distance: f64,
    first: [usize; 2],
});

// The sizes `TileSummary::to_bytes` documents.
#[cfg(feature = "serde")]
const _: () =
    assert!(<TileComponent as crate::packed::Packed>::WIDTH == 169 && <EdgeRun as crate::packed::Packed>::WIDTH == 28);

impl TileSummary {
    /// The summary as bytes, to ship from the machine that scanned the tile: a 4-byte tag,
    /// [`TILE_FORMAT_VERSION`] (2 bytes, little-endian), then the fields in MessagePack (structs
    /// as arrays, floats bit for bit), its components and edge runs packed as little-endian
    /// records: 169 bytes per component and 28 per edge run.
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        encode(*b"ILts", self)
    }

    /// The summary from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    /// [`Error::InvalidState`]: bytes of something else (the message names what the tag
    /// says), of another format version, cut short or too long, or whose tile, runs or labels
    /// do not fit together.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let summary: Self = decode(*b"ILts", "tile summary", bytes)?;
        summary.check().map_err(|problem| Error::InvalidState { what: "tile summary", reason: problem })?;
        Ok(summary)
    }

    /// The tile is well formed, every edge run lies in it and every label names a component.
    pub(crate) fn check(&self) -> std::result::Result<(), String> {
        let tile = &self.tile;
        if !tile.is_well_formed() {
            return Err(format!("tile {tile:?} is empty, below the diagonal or has sessions a > b"));
        }
        let within = |r: &std::ops::Range<usize>, x: [usize; 2]| r.contains(&x[0]) && r.contains(&x[1]) && x[0] <= x[1];
        let area = (tile.rows.len() as u128) * (tile.columns.len() as u128);
        for (k, c) in self.components.iter().enumerate() {
            let fits = within(&tile.rows, c.rows)
                && within(&tile.columns, c.columns)
                && tile.rows.contains(&c.first[0])
                && tile.columns.contains(&c.first[1])
                && tile.rows.contains(&c.closest[0])
                && tile.columns.contains(&c.closest[1]);
            let counts = c.runs >= 1
                && c.pairs >= c.runs
                && u128::from(c.pairs) <= area
                && c.diagonal_cells <= c.pairs
                && c.diagonal_links <= c.diagonal_cells;
            if !(fits && counts && c.area_s2.is_finite() && c.area_s2 >= 0.0) {
                return Err(format!("component {k} does not fit tile {tile:?}: {c:?}"));
            }
        }
        for (k, e) in self.edges.iter().enumerate() {
            if e.label as usize >= self.components.len() {
                return Err(format!(
                    "edge run {k} has label {}, but there are {} components",
                    e.label,
                    self.components.len()
                ));
            }
            if !tile.rows.contains(&e.row)
                || !tile.columns.contains(&e.start)
                || !tile.columns.contains(&e.end)
                || e.start > e.end
            {
                return Err(format!(
                    "edge run {k} (row {}, columns {}..={}) lies outside tile {tile:?}",
                    e.row, e.start, e.end
                ));
            }
        }
        Ok(())
    }
}

/// Scans one tile of `fleet`: the same cells as [`find_fleet_loops`](crate::fleet::find_fleet_loops)
/// gives in the tile's rows and columns, summarised (see the module docs). Reads only the
/// tile's poses, plus the row session's path length and clock when a separation is given
/// (so that separated columns are those of the whole session, whatever the tiling). The same
/// scan as [`scan_session_tile`] of the tile's sessions.
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
    let [a, b] = tile.sessions;
    if a > b || b >= fleet.len() {
        return Err(bad_tile(tile));
    }
    let starts = [fleet.starts()[a], fleet.starts()[b]];
    let sessions = [fleet.session(a), fleet.session(b)];
    Ok(scan_session_tile(sessions, starts, metric, gamma, separation, tile, TileKeep::SUMMARY)?.summary)
}

/// The error of a tile that does not lie in its sessions.
fn bad_tile(tile: &Tile) -> Error {
    Error::InvalidParameter {
        name: "tile",
        value: tile.rows.start as f64,
        expected: "rows and columns within their sessions (a ≤ b), on or above the diagonal",
    }
}

/// What a tile scan keeps besides the tile's summary ([`scan_session_tile`]): nothing more by
/// default ([`TileKeep::SUMMARY`]).
///
/// # Examples
/// ```
/// use loops_core::tile::TileKeep;
/// let keep = TileKeep::SUMMARY.with_duration().with_runs();
/// assert!(keep.duration && keep.runs);
/// assert_eq!(TileKeep::asking(true, false), TileKeep::SUMMARY.with_duration());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct TileKeep {
    /// The tile's share of the loop duration τ ([`TileDuration`]).
    pub duration: bool,
    /// The tile's runs with their provisional labels ([`TileRuns`]), for
    /// [`draw_tile_runs`] to draw from without a rescan.
    pub runs: bool,
}

impl TileKeep {
    /// The summary only.
    pub const SUMMARY: Self = Self { duration: false, runs: false };

    /// The summary, with the tile's share of τ when `duration` and its runs when `runs`.
    #[must_use]
    pub const fn asking(duration: bool, runs: bool) -> Self {
        Self { duration, runs }
    }

    /// Also the tile's share of τ.
    #[must_use]
    pub const fn with_duration(self) -> Self {
        Self { duration: true, ..self }
    }

    /// Also the tile's runs.
    #[must_use]
    pub const fn with_runs(self) -> Self {
        Self { runs: true, ..self }
    }
}

/// One tile's scan ([`scan_session_tile`]): its summary, and what [`TileKeep`] asked for
/// (`None` otherwise).
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct TileScan {
    /// The statistics of the tile's provisional components and its edge runs.
    pub summary: TileSummary,
    /// The tile's share of τ, when [`TileKeep::duration`].
    pub duration: Option<TileDuration>,
    /// The tile's runs, when [`TileKeep::runs`].
    pub runs: Option<TileRuns>,
}

/// Scans one tile from its two sessions alone: `sessions` are the trajectories of sessions a
/// and b of `tile.sessions` (for a tile within one session, that session twice), `starts` their
/// first fleet indices (the poses of the sessions before them in the fleet). What a worker that
/// read only those two sessions needs; the summary is [`scan_tile`]'s on the whole fleet.
/// `keep` says what else to return from the same scan: the tile's share of τ, its runs.
///
/// Time O(the tile's runs and its poses' passes near each other), as the fleet engine, plus
/// O(the tile's rows and columns) for τ; memory O(the tile's poses and runs); rows in parallel.
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidSeparation`]; [`Error::InvalidParameter`] for a
/// tile that does not lie in its sessions, or below the diagonal, or sessions whose fleet
/// indices overlap; [`Error::SessionMismatch`] for sessions of different dimensions or
/// manifolds; the metric's errors on the tile's poses.
pub fn scan_session_tile<M: Metric + ?Sized>(
    sessions: [&Trajectory; 2],
    starts: [usize; 2],
    metric: &M,
    gamma: f64,
    separation: Separation,
    tile: &Tile,
    keep: TileKeep,
) -> Result<TileScan> {
    scan_shared(sessions, starts, metric, gamma, separation, tile, keep, None)
}

/// [`scan_session_tile`] of many tiles, in parallel: each job is a tile with its two sessions
/// and their first fleet indices, as [`scan_session_tile`] takes them; the scans come in the
/// order of `jobs`, each the one [`scan_session_tile`] makes. The balls that bound a side of a
/// tile (one distance a pose, to find the stretches that come near the other side) are made
/// once per block and shared by the tiles that read it: a session met by many tiles (a new
/// day's against a fleet) is bounded once, not once a tile.
///
/// Time: the tiles' scans, rows and tiles in parallel, plus O(poses) distance evaluations for
/// the balls of the distinct sides (instead of O(poses) a tile).
///
/// # Errors
/// As [`scan_session_tile`], the first in the order of `jobs`.
pub fn scan_session_tiles<M: Metric + ?Sized>(
    jobs: &[(&Tile, [&Trajectory; 2], [usize; 2])],
    metric: &M,
    gamma: f64,
    separation: Separation,
    keep: TileKeep,
) -> Result<Vec<TileScan>> {
    use rayon::prelude::*;
    // Each side of a tile off the diagonal, by its fleet range and the poses given for it (the
    // address of its trajectory): (key, session, its first fleet index). Ranges outside their
    // session are left to the scan, which refuses them.
    type Key = (usize, usize, usize);
    let key = |range: &std::ops::Range<usize>, session: &Trajectory| {
        (range.start, range.end, std::ptr::from_ref(session) as usize)
    };
    let mut sides: Vec<(Key, &Trajectory, usize)> = Vec::new();
    for (tile, sessions, starts) in jobs {
        let on_diagonal = tile.sessions[0] == tile.sessions[1] && tile.columns.start < tile.rows.end;
        for (side, range) in [&tile.rows, &tile.columns].into_iter().enumerate() {
            let fits = range.start >= starts[side] && range.end <= starts[side] + sessions[side].len();
            if !on_diagonal && fits {
                sides.push((key(range, sessions[side]), sessions[side], starts[side]));
            }
        }
    }
    sides.sort_unstable_by_key(|side| side.0);
    sides.dedup_by_key(|side| side.0);
    let balls: Vec<SideBalls> = sides
        .par_iter()
        .map(|&((lo, hi, _), session, start)| SideBalls::new(session, lo - start..hi - start, metric))
        .collect();
    let ball_of = |range: &std::ops::Range<usize>, session: &Trajectory| {
        sides.binary_search_by_key(&key(range, session), |side| side.0).ok().map(|k| &balls[k])
    };
    let scans: Vec<Result<TileScan>> = jobs
        .par_iter()
        .map(|(tile, sessions, starts)| {
            let shared = ball_of(&tile.rows, sessions[0]).zip(ball_of(&tile.columns, sessions[1])).map(|(r, c)| [r, c]);
            scan_shared(*sessions, *starts, metric, gamma, separation, tile, keep, shared)
        })
        .collect();
    scans.into_iter().collect()
}

/// [`scan_session_tile`], with the balls of the tile's two sides when they are made already.
#[allow(clippy::too_many_arguments)]
fn scan_shared<M: Metric + ?Sized>(
    sessions: [&Trajectory; 2],
    starts: [usize; 2],
    metric: &M,
    gamma: f64,
    separation: Separation,
    tile: &Tile,
    keep: TileKeep,
    sides: Option<[&SideBalls; 2]>,
) -> Result<TileScan> {
    let scanned = scan_piece(sessions, starts, metric, gamma, separation, tile, sides)?;
    let prefix = scanned.prefix_sums()?;
    let summary = summary_of(&scanned, &prefix, metric, tile);
    let duration = keep.duration.then(|| duration_of(&scanned, &prefix, tile));
    let runs = keep.runs.then(|| TileRuns::new(scanned, tile, starts, gamma, separation));
    Ok(TileScan { summary, duration, runs })
}

/// The summary of a scanned tile, `prefix` its [`ScannedTile::prefix_sums`].
fn summary_of<M: Metric + ?Sized>(scanned: &ScannedTile<'_>, prefix: &[f64], metric: &M, tile: &Tile) -> TileSummary {
    let mut summary = summarise(tile, metric, scanned, prefix);
    for c in &mut summary.components {
        c.times_s = [
            [scanned.time_s(0, c.rows[0]), scanned.time_s(0, c.rows[1])],
            [scanned.time_s(1, c.columns[0]), scanned.time_s(1, c.columns[1])],
        ];
    }
    summary
}

/// A tile's poses as one small trajectory and its cells of S_γ. On the diagonal of a session,
/// the piece is the tile's stretch of the session; otherwise it is the live stretches of the
/// rows, then those of the columns ([`live_stretches`]): every cell of the tile lies in them.
/// Piece rows are the first [`rows`](Self::rows) poses; each stretch is a session of the piece,
/// so that runs and components never cross from one stretch to the next.
pub(crate) struct ScannedTile<'a> {
    pub(crate) piece: Trajectory,
    pub(crate) piece_starts: Vec<usize>,
    pub(crate) rows: usize,
    pub(crate) set: SublevelSet,
    /// The provisional component of each run of `set` ([`label_runs`]), and their number.
    pub(crate) labels: (Vec<u32>, u32),
    /// The fleet index of the first pose of each stretch (one per `piece_starts`).
    pub(crate) fleet_starts: Vec<usize>,
    /// The row and column sessions' clocks and first fleet indices.
    times_s: [&'a [f64]; 2],
    session_starts: [usize; 2],
}

impl ScannedTile<'_> {
    /// The fleet index of pose `k` of the piece.
    pub(crate) fn to_fleet(&self, k: usize) -> usize {
        fleet_index(&self.piece_starts, &self.fleet_starts, k)
    }

    /// The time of fleet index `f` of the row (`side` 0) or column (1) session.
    pub(crate) fn time_s(&self, side: usize, f: usize) -> f64 {
        self.times_s[side][f - self.session_starts[side]]
    }

    /// The prefix sums of the piece's cell widths, restarting at each stretch
    /// ([`prefix_sums_by_session`]).
    ///
    /// # Errors
    /// [`Error::OutOfMemory`].
    pub(crate) fn prefix_sums(&self) -> Result<Vec<f64>> {
        let breaks: Vec<u32> = self.piece_starts[1..].iter().map(|&s| s as u32).collect();
        prefix_sums_by_session(self.piece.cell_widths_s(), &breaks)
    }
}

/// The fleet index of pose `k` of a piece whose stretches start at `piece_starts` (piece
/// indices) and `fleet_starts` (fleet indices).
pub(crate) fn fleet_index(piece_starts: &[usize], fleet_starts: &[usize], k: usize) -> usize {
    let s = piece_starts.partition_point(|&p| p <= k) - 1;
    fleet_starts[s] + k - piece_starts[s]
}

/// The piece row of fleet row `f` in a piece of `len` poses whose first `rows` are rows (its
/// stretches as [`fleet_index`]), or `None` when the row was left out (it holds no cell).
pub(crate) fn piece_row(
    piece_starts: &[usize],
    fleet_starts: &[usize],
    rows: usize,
    len: usize,
    f: usize,
) -> Option<usize> {
    let row_stretches = piece_starts.partition_point(|&p| p < rows);
    let s = fleet_starts[..row_stretches].partition_point(|&g| g <= f).checked_sub(1)?;
    let k = piece_starts[s] + f - fleet_starts[s];
    let end = piece_starts.get(s + 1).copied().unwrap_or(len).min(rows);
    (k < end).then_some(k)
}

/// Checks a tile against its sessions and scans its cells (see [`scan_session_tile`]).
/// `sides`, when given, are the balls of the tile's rows and columns ([`SideBalls`]).
pub(crate) fn scan_piece<'a, M: Metric + ?Sized>(
    sessions: [&'a Trajectory; 2],
    starts: [usize; 2],
    metric: &M,
    gamma: f64,
    separation: Separation,
    tile: &Tile,
    sides: Option<[&SideBalls; 2]>,
) -> Result<ScannedTile<'a>> {
    check_gamma(gamma)?;
    separation.check()?;
    let [a, b] = tile.sessions;
    let [session_a, session_b] = sessions;
    let within = |start: usize, len: usize, r: &std::ops::Range<usize>| r.start >= start && r.end <= start + len;
    let apart = if a == b { starts[0] == starts[1] } else { starts[0] + session_a.len() <= starts[1] };
    if !tile.is_well_formed()
        || !apart
        || !within(starts[0], session_a.len(), &tile.rows)
        || !within(starts[1], session_b.len(), &tile.columns)
    {
        return Err(bad_tile(tile));
    }
    if a != b {
        let mismatch = |problem: String, what| Error::SessionMismatch { session: format!("{b}"), problem, what };
        if session_b.dim() != session_a.dim() {
            let problem = format!("has {} coordinates, session {a} has {}", session_b.dim(), session_a.dim());
            return Err(mismatch(problem, "dimension"));
        }
        if session_b.manifold() != session_a.manifold() {
            let problem =
                format!("lies on {}, session {a} on {}", session_b.manifold().name(), session_a.manifold().name());
            return Err(mismatch(problem, "manifold"));
        }
    }
    // Within one session, the column session is the row session.
    let session_b = if a == b { session_a } else { session_b };
    let start_a = starts[0];
    let (r0, r1) = (tile.rows.start - start_a, tile.rows.end - start_a);
    let (c0, c1) = (tile.columns.start - starts[1], tile.columns.end - starts[1]);
    let diagonal = a == b && c0 < r1;
    // Within one session, each row's first column (an index of the session) under the separation.
    let separated = if a == b && !separation.is_none() {
        Some(separation.first_columns(&try_path_length(session_a, metric)?, session_a.timestamps_s())?)
    } else {
        None
    };
    let (piece, piece_starts, fleet_starts, rows, first_columns) = if diagonal {
        // The stretch of the session from the first row to the last column.
        let piece = session_a.piece(r0..c1)?;
        piece.check_metric(metric)?;
        let local_c0 = c0 - r0;
        let first_columns: Vec<u32> = (0..piece.len())
            .map(|k| {
                let own = separated.as_ref().map_or(r0 + k, |f| f[r0 + k] as usize) - r0;
                own.max(local_c0).max(k) as u32
            })
            .collect();
        (piece, vec![0], vec![tile.rows.start], r1 - r0, first_columns)
    } else {
        let made;
        let [rows, columns] = match sides {
            Some(sides) if *sides[0].range() == (r0..r1) && *sides[1].range() == (c0..c1) => sides,
            _ => {
                made = [SideBalls::new(session_a, r0..r1, metric), SideBalls::new(session_b, c0..c1, metric)];
                [&made[0], &made[1]]
            }
        };
        let [mut live_rows, mut live_columns] = live_stretches(session_a, rows, session_b, columns, metric, gamma);
        if live_rows.is_empty() || live_columns.is_empty() {
            // No pair within γ: one chunk of each side, which holds no cell either.
            live_rows = std::iter::once(r0..(r0 + piece::CHUNK).min(r1)).collect();
            live_columns = std::iter::once(c0..(c0 + piece::CHUNK).min(c1)).collect();
        }
        let parts: Vec<(&Trajectory, std::ops::Range<usize>)> = live_rows
            .iter()
            .map(|r| (session_a, r.clone()))
            .chain(live_columns.iter().map(|c| (session_b, c.clone())))
            .collect();
        let (piece, _) = Trajectory::concatenate_pieces(&parts, 1.0)?;
        piece.check_metric(metric)?;
        let (mut piece_starts, mut fleet_starts, mut next) = (Vec::new(), Vec::new(), 0);
        for (side, stretches) in [(0, &live_rows), (1, &live_columns)] {
            for s in stretches {
                piece_starts.push(next);
                fleet_starts.push(starts[side] + s.start);
                next += s.len();
            }
        }
        let rows: usize = live_rows.iter().map(|r| r.len()).sum();
        let column_stretches = live_rows.len();
        // The first piece column at or after column `c` of the session.
        let column_at = |c: usize| -> usize {
            let s = live_columns.partition_point(|r| r.end <= c);
            match live_columns.get(s) {
                Some(r) => piece_starts[column_stretches + s] + c.saturating_sub(r.start),
                None => piece.len(),
            }
        };
        let first_columns: Vec<u32> = (0..piece.len())
            .map(|k| {
                if k >= rows {
                    k as u32
                } else if let Some(f) = &separated {
                    let s = piece_starts.partition_point(|&p| p <= k) - 1;
                    let row = fleet_starts[s] + k - piece_starts[s] - start_a;
                    column_at(f[row] as usize).max(rows) as u32
                } else {
                    rows as u32
                }
            })
            .collect();
        (piece, piece_starts, fleet_starts, rows, first_columns)
    };
    let (arc, balls) = rayon::join(
        || ArcLength::new(&piece, metric, false),
        || BallTree::with_sessions(&piece, metric, LEAF_SIZE, &piece_starts),
    );
    let (arc, balls) = (arc?, balls?);
    let set = SublevelSet::scan(
        &piece,
        metric,
        gamma,
        separation,
        &arc,
        Pruner::Hierarchy(&balls),
        &first_columns,
        &piece_starts,
        rows,
    )?;
    let labels = label_runs(&set, ROWS_PER_LABEL_TASK);
    Ok(ScannedTile {
        piece,
        piece_starts,
        rows,
        set,
        labels,
        fleet_starts,
        times_s: [session_a.timestamps_s(), session_b.timestamps_s()],
        session_starts: starts,
    })
}

/// The provisional components of a tile's set and its edge runs.
fn summarise<M: Metric + ?Sized>(tile: &Tile, metric: &M, scanned: &ScannedTile<'_>, prefix: &[f64]) -> TileSummary {
    let ScannedTile { piece, rows, set, labels: (labels, count), .. } = scanned;
    let (rows, count) = (*rows, *count);
    let to_fleet = |k: usize| scanned.to_fleet(k);
    let widths = piece.cell_widths_s();
    // The tallies, with the first cell and the closest pair's distance of each.
    let mut tallies = vec![(Tally::empty(), [usize::MAX; 2], f64::INFINITY); count as usize];
    let mut edges = Vec::new();
    let (first_column, last_column) = (tile.columns.start, tile.columns.end - 1);
    for i in 0..rows {
        if i + 1 < rows {
            for_each_overlap(set, i..i + 1, |x, _| tallies[labels[x] as usize].0.overlaps += 1);
        }
        let offset = set.row_offset(i);
        let (w_i, fleet_i) = (widths[i], to_fleet(i));
        for (k, run) in set.row(i).iter().enumerate() {
            let r = offset + k;
            let label = labels[r];
            let (tally, first, closest_distance) = &mut tallies[label as usize];
            let (x, y) = (run.start as usize, run.end as usize);
            let (start, end) = (to_fleet(x), to_fleet(y));
            tally.add_run(fleet_i, [start, end], w_i * ((prefix[y] + widths[y]) - prefix[x]), w_i);
            if first[0] == usize::MAX {
                *first = [fleet_i, start];
            }
            let j = set.closest_columns()[r] as usize;
            if tally.offer_closest(metric.distance_rank(piece.point(i), piece.point(j)), [fleet_i, to_fleet(j)]) {
                *closest_distance = metric.distance(piece.point(i), piece.point(j));
            }
            if fleet_i == tile.rows.start || fleet_i + 1 == tile.rows.end || start == first_column || end == last_column
            {
                edges.push(EdgeRun { row: fleet_i, start, end, label });
            }
        }
    }
    let components = tallies
        .into_iter()
        .map(|(tally, first, closest_distance)| TileComponent::from_tally(tally, first, closest_distance))
        .collect();
    TileSummary { tile: tile.clone(), components, edges }
}

/// A component of a partial merge: its session pair and the statistics of its pieces, with the
/// joins made so far folded in.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct MergeComponent {
    sessions: [usize; 2],
    stats: TileComponent,
}

/// An edge run still open in a partial merge: its tile (an index in [`TileMerge::tiles`]) and
/// the run, labelled by the merge's component.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct OpenEdge {
    tile: u32,
    run: EdgeRun,
}

/// A run cut by a column boundary and joined, in the first or last row of its tiles: kept while
/// the row next to it across the tiles' row boundary may still be cut there and joined, because
/// two cut runs in consecutive rows overlap once, not once on each side of the cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Cut {
    /// The tile left of the boundary.
    tile: u32,
    row: usize,
    label: u32,
}

/// A partial merge of tiles: the statistics of the components of the tiles it holds, with every
/// join between them made, and only the edge runs that face a tile it does not hold (plus the
/// few cut runs a later join still needs). Merging partial merges of disjoint sets of tiles, in
/// any grouping and order, then [`finish`](Self::finish)ing the merge of all the tiles of a
/// plan, gives the fleet's components: a tree of reductions, each step O(its components + open
/// edge runs + tiles).
///
/// The tiles must come from one plan ([`plan_tiles`] or [`plan_session_tiles`]); a tile the plan
/// leaves out holds no pair within γ, so nothing waits for it.
///
/// # Examples
/// ```
/// use loops_core::fleet::Fleet;
/// use loops_core::tile::{TileMerge, merge_tiles, plan_tiles, scan_tile};
/// use loops_core::{Euclidean, Separation, Trajectory};
/// let xs: Vec<[f64; 2]> = (0..40).map(|k| [(k as f64 * 0.3).sin() * 3.0, (k as f64 * 0.2).cos() * 3.0]).collect();
/// let fleet = Fleet::new(vec![("a".into(), Trajectory::from_points((0..40).map(f64::from).collect(), &xs)?)])?;
/// let tiles = plan_tiles(&fleet, &Euclidean, 1.0, 7)?;
/// let summaries: Vec<_> =
///     tiles.iter().map(|t| scan_tile(&fleet, &Euclidean, 1.0, Separation::NONE, t)).collect::<Result<_, _>>()?;
/// // Merge pairs of tiles, then pairs of those merges, and so on.
/// let mut level: Vec<TileMerge> = summaries.iter().cloned().map(TileMerge::new).collect::<Result<_, _>>()?;
/// while level.len() > 1 {
///     let mut next = Vec::new();
///     let mut parts = level.into_iter();
///     while let Some(first) = parts.next() {
///         next.push(TileMerge::merge([first].into_iter().chain(parts.next()).collect())?);
///     }
///     level = next;
/// }
/// let tree = level.remove(0).finish()?;
/// let flat = merge_tiles(&summaries)?;
/// assert_eq!(tree.components().len(), flat.len());
/// assert!(tree.components().iter().zip(&flat).all(|(t, f)| t.component.pair_count == f.pair_count));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TileMerge {
    tiles: Vec<Tile>,
    /// Per tile, the merge's component of each of its provisional components.
    labels: Vec<Vec<u32>>,
    components: Vec<MergeComponent>,
    edges: Vec<OpenEdge>,
    cuts: Vec<Cut>,
}

/// The cuts at each column boundary of each session pair: (row, the part that made the cut or
/// `None` for the merge under way, label).
type CutsAt = HashMap<([usize; 2], usize), Vec<(usize, Option<usize>, u32)>>;

/// Tiles by (sessions, a row bound, a column bound).
type TileKey = ([usize; 2], usize, usize);

/// `count + delta`, which must not go below 0.
fn corrected(count: u64, delta: i64, what: &str, first: [usize; 2]) -> Result<u64> {
    u64::try_from(count as i128 + i128::from(delta)).map_err(|_| Error::InconsistentTiles {
        problem: format!("the component with first cell {first:?} would have {count} {delta:+} {what}"),
    })
}

impl TileMerge {
    /// The merge of one tile: its summary, every edge run open.
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a summary whose tile is not well formed, or whose edge
    /// runs lie outside it or name no component.
    pub fn new(summary: TileSummary) -> Result<Self> {
        summary.check().map_err(|problem| Error::InconsistentTiles { problem })?;
        let sessions = summary.tile.sessions;
        Ok(Self {
            labels: vec![(0..summary.components.len() as u32).collect()],
            edges: summary.edges.into_iter().map(|run| OpenEdge { tile: 0, run }).collect(),
            components: summary.components.into_iter().map(|stats| MergeComponent { sessions, stats }).collect(),
            tiles: vec![summary.tile],
            cuts: Vec::new(),
        })
    }

    /// The tiles merged.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// Number of components (final ones and those that may still grow).
    pub fn component_count(&self) -> usize {
        self.components.len()
    }

    /// Number of edge runs still open: those facing a tile not merged yet.
    pub fn open_edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Indices and labels refer to what exists.
    fn check(&self) -> std::result::Result<(), String> {
        let (tiles, labels) = (self.tiles.len(), self.components.len());
        if self.labels.len() != tiles || self.labels.iter().flatten().any(|&l| l as usize >= labels) {
            return Err(format!("the labels of {} tiles name {labels} components", self.labels.len()));
        }
        if let Some(t) = self.tiles.iter().position(|t| !t.is_well_formed()) {
            return Err(format!("tile {:?} is empty, below the diagonal or has sessions a > b", self.tiles[t]));
        }
        if let Some(c) = self.components.iter().find(|c| c.sessions[0] > c.sessions[1]) {
            return Err(format!("a component has sessions {:?}, a > b", c.sessions));
        }
        for e in &self.edges {
            let Some(tile) = self.tiles.get(e.tile as usize) else {
                return Err(format!("an edge run names tile {}, but there are {tiles}", e.tile));
            };
            let r = &e.run;
            if r.label as usize >= labels {
                return Err(format!("an edge run has label {}, but there are {labels} components", r.label));
            }
            if !tile.rows.contains(&r.row) || !tile.columns.contains(&r.start) || !tile.columns.contains(&r.end) {
                return Err(format!(
                    "edge run (row {}, columns {}..={}) lies outside tile {tile:?}",
                    r.row, r.start, r.end
                ));
            }
        }
        for c in &self.cuts {
            if c.tile as usize >= tiles || c.label as usize >= labels {
                return Err(format!(
                    "a cut names tile {} and label {} of {tiles} tiles, {labels} components",
                    c.tile, c.label
                ));
            }
        }
        Ok(())
    }

    /// Merges partial merges of disjoint sets of tiles of one plan: joins the components whose
    /// open edge runs touch across the parts (see the module docs), adds their statistics and
    /// keeps the edge runs that still face a tile none of the parts holds. Components are
    /// renumbered; the result does not depend on the order of the parts.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a tile in two parts; [`Error::InconsistentTiles`] for
    /// parts whose labels or tiles do not fit, or whose counts a join would make negative.
    pub fn merge(parts: Vec<Self>) -> Result<Self> {
        let inconsistent = |problem: String| Error::InconsistentTiles { problem };
        let (mut tiles, mut origin, mut components) = (Vec::new(), Vec::new(), Vec::new());
        let mut tile_labels: Vec<Vec<u32>> = Vec::new();
        let mut edges = Vec::new();
        // Cuts with the part that made them (None: this merge).
        let mut cuts: Vec<(Cut, Option<usize>)> = Vec::new();
        for (p, part) in parts.into_iter().enumerate() {
            part.check().map_err(|problem| inconsistent(format!("part {p}: {problem}")))?;
            let (tile_base, label_base) = (tiles.len(), components.len());
            if tile_base + part.tiles.len() > u32::MAX as usize
                || label_base + part.components.len() > u32::MAX as usize
            {
                return Err(inconsistent("more than 2³² tiles or components in one merge".to_owned()));
            }
            let (tb, lb) = (tile_base as u32, label_base as u32);
            origin.extend(std::iter::repeat_n(p, part.tiles.len()));
            tiles.extend(part.tiles);
            tile_labels.extend(part.labels.into_iter().map(|map| map.into_iter().map(|l| l + lb).collect()));
            components.extend(part.components);
            edges.extend(
                part.edges
                    .into_iter()
                    .map(|e| OpenEdge { tile: e.tile + tb, run: EdgeRun { label: e.run.label + lb, ..e.run } }),
            );
            cuts.extend(
                part.cuts.into_iter().map(|c| (Cut { tile: c.tile + tb, row: c.row, label: c.label + lb }, Some(p))),
            );
        }
        let mut by_start: HashMap<TileKey, usize> = HashMap::with_capacity(tiles.len());
        let mut by_rows_end: HashMap<TileKey, usize> = HashMap::with_capacity(tiles.len());
        let mut by_columns_end: HashMap<TileKey, usize> = HashMap::with_capacity(tiles.len());
        for (t, tile) in tiles.iter().enumerate() {
            if by_start.insert((tile.sessions, tile.rows.start, tile.columns.start), t).is_some() {
                return Err(Error::InvalidParameter {
                    name: "tile",
                    value: tile.rows.start as f64,
                    expected: "each tile summarised once",
                });
            }
            by_rows_end.insert((tile.sessions, tile.rows.end, tile.columns.start), t);
            by_columns_end.insert((tile.sessions, tile.rows.start, tile.columns.end), t);
        }
        let below = |t: usize| by_start.get(&(tiles[t].sessions, tiles[t].rows.end, tiles[t].columns.start)).copied();
        let right = |t: usize| by_start.get(&(tiles[t].sessions, tiles[t].rows.start, tiles[t].columns.end)).copied();
        let above =
            |t: usize| by_rows_end.get(&(tiles[t].sessions, tiles[t].rows.start, tiles[t].columns.start)).copied();
        let left =
            |t: usize| by_columns_end.get(&(tiles[t].sessions, tiles[t].rows.start, tiles[t].columns.start)).copied();
        let mut of_tile: Vec<Vec<EdgeRun>> = vec![Vec::new(); tiles.len()];
        for e in edges {
            of_tile[e.tile as usize].push(e.run);
        }
        for runs in &mut of_tile {
            runs.sort_unstable_by_key(|r| (r.row, r.start));
        }
        let mut parent: Vec<u32> = (0..components.len() as u32).collect();
        // Corrections: (label, Δruns, Δoverlaps, Δlinks), added to the sets' sums after the joins.
        let mut deltas: Vec<(u32, i64, i64, i64)> = Vec::new();
        {
            let mut forest = MinRootForest::new(&mut parent, 0);
            for t in 0..tiles.len() {
                // The tile below, from another part: its first row against this tile's last.
                if let Some(u) = below(t).filter(|&u| origin[u] != origin[t]) {
                    let last: Vec<&EdgeRun> = of_tile[t].iter().filter(|e| e.row + 1 == tiles[t].rows.end).collect();
                    let first: Vec<&EdgeRun> = of_tile[u].iter().filter(|e| e.row == tiles[u].rows.start).collect();
                    let (mut p, mut q) = (0, 0);
                    while p < last.len() && q < first.len() {
                        let (x, y) = (last[p], first[q]);
                        if x.start.max(y.start) <= x.end.min(y.end) {
                            forest.union(x.label as usize, y.label as usize);
                            deltas.push((x.label, 0, 1, 0));
                        }
                        if x.end <= y.end {
                            p += 1;
                        }
                        if y.end <= x.end {
                            q += 1;
                        }
                    }
                }
                // The tile to the right, from another part: the runs cut at the boundary.
                if let Some(r) = right(t).filter(|&r| origin[r] != origin[t]) {
                    let boundary = tiles[t].columns.end;
                    let ending: HashMap<usize, &EdgeRun> =
                        of_tile[t].iter().filter(|e| e.end + 1 == boundary).map(|e| (e.row, e)).collect();
                    for y in of_tile[r].iter().filter(|e| e.start == boundary) {
                        if let Some(x) = ending.get(&y.row) {
                            forest.union(x.label as usize, y.label as usize);
                            // One run, not two; a diagonal cell followed by the cut still links.
                            let link = i64::from(x.start == x.row && boundary == x.row + 1);
                            deltas.push((x.label, -1, 0, link));
                            cuts.push((Cut { tile: t as u32, row: y.row, label: x.label }, None));
                        }
                    }
                }
            }
        }
        // Cut runs in consecutive rows overlap once in the plane, but once on each side of the
        // cut in the tiles: counted when both cuts first meet (made here, or in different parts).
        let mut at_boundary: CutsAt = HashMap::new();
        for (c, from) in &cuts {
            let tile = &tiles[c.tile as usize];
            at_boundary.entry((tile.sessions, tile.columns.end)).or_default().push((c.row, *from, c.label));
        }
        for rows in at_boundary.values_mut() {
            rows.sort_unstable_by_key(|&(row, ..)| row);
            for w in rows.windows(2) {
                let ((r0, o0, label), (r1, o1, _)) = (w[0], w[1]);
                if r1 == r0 + 1 && !(o0.is_some() && o0 == o1) {
                    deltas.push((label, 0, -1, 0));
                }
            }
        }
        // One component per set, numbered by its smallest label.
        let count = number_sets(&mut parent) as usize;
        let mut merged: Vec<Option<MergeComponent>> = vec![None; count];
        for (k, c) in components.into_iter().enumerate() {
            match &mut merged[parent[k] as usize] {
                slot @ None => *slot = Some(c),
                Some(m) if m.sessions == c.sessions => m.stats.absorb(&c.stats),
                Some(m) => {
                    return Err(inconsistent(format!(
                        "a run of sessions {:?} touches a run of sessions {:?}",
                        m.sessions, c.sessions
                    )));
                }
            }
        }
        let mut sums = vec![(0_i64, 0_i64, 0_i64); count];
        for (label, runs, overlaps, links) in deltas {
            let s = &mut sums[parent[label as usize] as usize];
            (s.0, s.1, s.2) = (s.0 + runs, s.1 + overlaps, s.2 + links);
        }
        let components = merged
            .into_iter()
            .zip(sums)
            .map(|(m, (runs, overlaps, links))| {
                let mut m = m.expect("every set has a member");
                let c = &mut m.stats;
                c.runs = corrected(c.runs, runs, "runs", c.first)?;
                c.overlaps = corrected(c.overlaps, overlaps, "overlaps", c.first)?;
                c.diagonal_links = corrected(c.diagonal_links, links, "diagonal links", c.first)?;
                Ok(m)
            })
            .collect::<Result<Vec<_>>>()?;
        // The edge runs that still face a tile no part holds.
        let mut open = Vec::new();
        for (t, runs) in of_tile.into_iter().enumerate() {
            let tile = &tiles[t];
            let sides = [above(t).is_none(), below(t).is_none(), left(t).is_none(), right(t).is_none()];
            for run in runs {
                let faces = [
                    run.row == tile.rows.start,
                    run.row + 1 == tile.rows.end,
                    run.start == tile.columns.start,
                    run.end + 1 == tile.columns.end,
                ];
                if sides.iter().zip(faces).any(|(&side, face)| side && face) {
                    open.push(OpenEdge { tile: t as u32, run: EdgeRun { label: parent[run.label as usize], ..run } });
                }
            }
        }
        // The cuts in a tile's first (last) row, while the tiles above (below) both sides of the
        // boundary are not both merged: a cut in the next row may still come.
        let kept = cuts
            .into_iter()
            .filter_map(|(c, _)| {
                let t = c.tile as usize;
                let tile = &tiles[t];
                let pair = right(t);
                let both = |near: &dyn Fn(usize) -> Option<usize>| near(t).is_some() && pair.and_then(near).is_some();
                let keep = (c.row == tile.rows.start && !both(&above)) || (c.row + 1 == tile.rows.end && !both(&below));
                keep.then(|| Cut { label: parent[c.label as usize], ..c })
            })
            .collect();
        for map in &mut tile_labels {
            map.iter_mut().for_each(|l| *l = parent[*l as usize]);
        }
        Ok(Self { tiles, labels: tile_labels, components, edges: open, cuts: kept })
    }

    /// The fleet's components from the merge of every tile of a plan, numbered as
    /// [`find_fleet_loops`](crate::fleet::find_fleet_loops) numbers them (by first cell, row-major),
    /// with their session pairs. Edge runs still open (facing tiles the plan left out) are
    /// ignored. O(components log components).
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for counts no set of cells has (an Euler number above 1:
    /// summaries that do not belong together).
    pub fn finish(&self) -> Result<MergedLoops> {
        let mut order: Vec<usize> = (0..self.components.len()).collect();
        order.sort_unstable_by_key(|&k| self.components[k].stats.first);
        let mut ids = vec![0u32; order.len()];
        for (id, &k) in order.iter().enumerate() {
            ids[k] = id as u32;
        }
        let components = order
            .into_iter()
            .map(|k| &self.components[k])
            .enumerate()
            .map(|(id, m)| {
                let c = &m.stats;
                let inconsistent = |what: &str| Error::InconsistentTiles {
                    problem: format!("the component with first cell {:?} has {what}", c.first),
                };
                let tally = c.tally();
                tally.check().map_err(|problem| inconsistent(&problem))?;
                // The extents' times follow the extents (a trivial component's are mirrored).
                let times_s = if c.trivial {
                    let times = [c.times_s[0][0], c.times_s[1][1]];
                    [times, times]
                } else {
                    c.times_s
                };
                let component = tally.loop_component(id, c.closest_distance);
                let draw = DrawStats {
                    trivial: c.trivial,
                    rows: c.rows,
                    pairs: c.pairs.saturating_sub(c.diagonal_cells),
                    closest_pair: c.closest,
                };
                Ok(MergedComponent { component, sessions: m.sessions, times_s, draw })
            })
            .collect::<Result<Vec<_>>>()?;
        let labels = self.labels.iter().map(|map| map.iter().map(|&l| ids[l as usize]).collect::<Vec<u32>>()).collect();
        let mut firsts: Vec<[usize; 2]> = self.components.iter().map(|m| m.stats.first).collect();
        firsts.sort_unstable();
        Ok(MergedLoops { components, tiles: self.tiles.clone(), labels, firsts })
    }

    /// The partial merge as bytes (as [`TileSummary::to_bytes`], another tag).
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        encode(*b"ILtm", self)
    }

    /// The partial merge from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    /// [`Error::InvalidState`], as [`TileSummary::from_bytes`].
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let merge: Self = decode(*b"ILtm", "tile merge", bytes)?;
        merge.check().map_err(|problem| Error::InvalidState { what: "tile merge", reason: problem })?;
        Ok(merge)
    }
}

/// A fleet's loop component from merged tiles.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MergedComponent {
    /// The component in fleet indices: the component of
    /// [`FleetLoops::loops`](crate::fleet::FleetLoops::loops) with this id.
    pub component: LoopComponent,
    /// Its block (a, b), a ≤ b.
    pub sessions: [usize; 2],
    /// The times of its extents: `[[t(i_range[0]), t(i_range[1])], [t′(j_range[0]),
    /// t′(j_range[1])]]`, seconds, each on its session's own clock.
    pub times_s: [[f64; 2]; 2],
    /// What a keyed draw of samples needs of it ([`KeyedDraw`](crate::sample::KeyedDraw)).
    pub draw: DrawStats,
}

#[cfg(feature = "serde")]
crate::packed::packed_record!(MergedComponent {
    component: LoopComponent,
    sessions: [usize; 2],
    times_s: [[f64; 2]; 2],
    draw: DrawStats,
});

/// The fleet's loop components from merged tiles ([`TileMerge::finish`]), by id.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MergedLoops {
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    components: Vec<MergedComponent>,
    tiles: Vec<Tile>,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed::lists"))]
    labels: Vec<Vec<u32>>,
    /// The first cell (row-major, fleet indices) of each component, by id.
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    firsts: Vec<[usize; 2]>,
}

impl MergedLoops {
    /// The merge as bytes (a tag, [`TILE_FORMAT_VERSION`], MessagePack): what a fleet store
    /// saves of each session pair, so that a store read back need not merge again.
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        encode(*b"ILml", self)
    }

    /// The merge from [`to_bytes`](Self::to_bytes), checked to fit together (a label list a
    /// tile, labels of its components, a first cell a component).
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"merged loops"`) for other bytes or parts that do not
    /// fit.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let merged: Self = decode(*b"ILml", "merged loops", bytes)?;
        let n = merged.components.len();
        let problem = if merged.labels.len() != merged.tiles.len() {
            Some(format!("{} label lists for {} tiles", merged.labels.len(), merged.tiles.len()))
        } else if merged.firsts.len() != n {
            Some(format!("{} first cells for {n} components", merged.firsts.len()))
        } else {
            merged.labels.iter().flatten().find(|&&c| c as usize >= n).map(|c| format!("label {c} of {n} components"))
        };
        match problem {
            Some(reason) => Err(Error::InvalidState { what: "merged loops", reason }),
            None => Ok(merged),
        }
    }

    /// The merge of one session pair's tiles as a fleet of those two sessions alone holds it,
    /// each from pose 0 (sessions `[0, 0]` within one session, else `[0, 1]`), given where
    /// its sessions start in the store's fleet: what stays the same while other sessions come
    /// and go, and what a store saves of a merge, as it saves its tiles
    /// ([`StoredTile::local`](crate::store::StoredTile::local)). [`placed`](Self::placed)
    /// puts it back. O(components + tiles).
    pub fn local(&self, starts: [usize; 2]) -> Self {
        let pair = self.tiles.first().map_or([0, 0], |t| t.sessions);
        let mut local = self.clone();
        local.move_to([0, usize::from(pair[0] != pair[1])], [-(starts[0] as isize), -(starts[1] as isize)]);
        local
    }

    /// A merge of [`local`](Self::local) form placed as the merge of the store's sessions
    /// `sessions`, which start at `starts` in its fleet. O(components + tiles).
    pub fn placed(mut self, sessions: [usize; 2], starts: [usize; 2]) -> Self {
        self.move_to(sessions, [starts[0] as isize, starts[1] as isize]);
        self
    }

    /// Renumbers the merge's session pair `sessions` and moves its rows and columns by
    /// `shifts` (fleet indices): what merging the moved tiles gives, for a merge of the tiles
    /// of one session pair. O(components + tiles).
    pub(crate) fn move_to(&mut self, sessions: [usize; 2], shifts: [isize; 2]) {
        let at = |x: usize, side: usize| x.wrapping_add_signed(shifts[side]);
        let pair = |x: [usize; 2]| [at(x[0], 0), at(x[1], 1)];
        for m in &mut self.components {
            let c = &mut m.component;
            c.i_range = [at(c.i_range[0], 0), at(c.i_range[1], 0)];
            c.j_range = [at(c.j_range[0], 1), at(c.j_range[1], 1)];
            c.closest_pair = pair(c.closest_pair);
            m.draw.rows = [at(m.draw.rows[0], 0), at(m.draw.rows[1], 0)];
            m.draw.closest_pair = pair(m.draw.closest_pair);
            m.sessions = sessions;
        }
        for t in &mut self.tiles {
            *t = t.moved(sessions, shifts);
        }
        self.firsts.iter_mut().for_each(|f| *f = pair(*f));
    }

    /// The tiles merged, in the merge's order.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// The component id of each provisional component of tile `t` (an index in
    /// [`tiles`](Self::tiles)), as the tile's summary numbered them: what a tile's keyed draw
    /// needs to name its runs' components.
    ///
    /// # Panics
    /// If `t` is not a tile of the merge.
    pub fn tile_labels(&self, t: usize) -> &[u32] {
        &self.labels[t]
    }

    /// The keyed draws' statistics of every component, by id.
    pub fn draw_stats(&self) -> Vec<DrawStats> {
        self.components.iter().map(|m| m.draw).collect()
    }

    /// The components, by id.
    pub fn components(&self) -> &[MergedComponent] {
        &self.components
    }

    /// The components in the poses of their sessions, as
    /// [`FleetLoops::components`](crate::fleet::FleetLoops::components) gives them; `starts` are
    /// the sessions' first fleet indices.
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a component of a session `starts` does not reach.
    pub fn fleet_components(&self, starts: &[usize]) -> Result<Vec<FleetComponent>> {
        use rayon::prelude::*;
        if let Some(k) = self.components.par_iter().position_first(|m| !fits_starts(m, starts)) {
            let m = &self.components[k];
            return Err(Error::InconsistentTiles {
                problem: format!(
                    "component {} of sessions {:?} does not lie at the starts given",
                    m.component.id, m.sessions
                ),
            });
        }
        Ok(self.components.par_iter().map(|m| localize(&m.component, m.sessions, starts)).collect())
    }

    /// The sparse overlap matrix, as [`FleetLoops::session_pairs`](crate::fleet::FleetLoops::session_pairs)
    /// gives it; `spans_s` are the sessions' spans ([`SessionBlocks::span_s`]).
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a component of a session beyond `spans_s`.
    pub fn session_pairs(&self, spans_s: &[f64]) -> Result<Vec<SessionPair>> {
        if let Some(m) = self.components.iter().find(|m| m.sessions[1] >= spans_s.len()) {
            return Err(Error::InconsistentTiles {
                problem: format!("a component of sessions {:?}, but {} spans", m.sessions, spans_s.len()),
            });
        }
        Ok(session_pairs_of(self.components.iter().map(|m| (&m.component, m.sessions)), spans_s))
    }
}

/// The merges of the tiles of distinct session pairs as one merge of all their tiles, without
/// copying their components: components never join across session pairs, so this is what
/// [`TileMerge::merge`] and [`TileMerge::finish`] of all the tiles give, with the components
/// numbered by first cell (each id names its part and its place there) and the tiles in the
/// order of the parts. A fleet store's merges, one a session pair, read as its fleet's loops.
#[derive(Debug, Clone)]
pub(crate) struct JoinedMerges {
    parts: Vec<std::sync::Arc<MergedLoops>>,
    /// Each component's part and index there, by id.
    order: Vec<(u32, u32)>,
    tiles: Vec<Tile>,
    /// Each tile's labels, as ids.
    labels: Vec<Vec<u32>>,
}

impl JoinedMerges {
    /// The merges `parts` (of distinct session pairs) joined. O(components log components +
    /// tiles' labels).
    pub(crate) fn new(parts: Vec<std::sync::Arc<MergedLoops>>) -> Self {
        use rayon::prelude::*;
        // Each component's first cell, with where it is: a direct key (no lookup through the
        // parts while sorting). First cells are apart, so the order is that of any sort.
        // (Each vector made at its length: grown, they would be copied as they grow.)
        let mut order: Vec<([usize; 2], u32, u32)> = Vec::with_capacity(parts.iter().map(|m| m.firsts.len()).sum());
        for (p, m) in parts.iter().enumerate() {
            order.extend(m.firsts.iter().enumerate().map(|(k, &first)| (first, p as u32, k as u32)));
        }
        order.par_sort_unstable_by_key(|&(first, _, _)| first);
        let mut ids: Vec<Vec<u32>> = parts.iter().map(|m| vec![0; m.components.len()]).collect();
        for (id, &(_, p, k)) in order.iter().enumerate() {
            ids[p as usize][k as usize] = id as u32;
        }
        let mut tiles = Vec::with_capacity(parts.iter().map(|m| m.tiles.len()).sum());
        parts.iter().for_each(|m| tiles.extend_from_slice(&m.tiles));
        let mut labels: Vec<Vec<u32>> = Vec::with_capacity(tiles.len());
        labels.par_extend(parts.par_iter().zip(ids.par_iter()).flat_map_iter(|(m, ids)| {
            m.labels.iter().map(|map| map.iter().map(|&l| ids[l as usize]).collect::<Vec<u32>>())
        }));
        let order = order.into_iter().map(|(_, p, k)| (p, k)).collect();
        Self { parts, order, tiles, labels }
    }

    /// The number of components.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// The components, by id, as their parts hold them (a `component.id` is the part's own).
    pub fn components(&self) -> impl ExactSizeIterator<Item = &MergedComponent> + '_ {
        self.order.iter().map(|&(p, k)| &self.parts[p as usize].components[k as usize])
    }

    /// The tiles merged, in the parts' order.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// The component id of each provisional component of tile `t` (an index in
    /// [`tiles`](Self::tiles)), as [`MergedLoops::tile_labels`] gives it.
    ///
    /// # Panics
    /// If `t` is not a tile of the merge.
    pub fn tile_labels(&self, t: usize) -> &[u32] {
        &self.labels[t]
    }

    /// The keyed draws' statistics of every component, by id.
    pub fn draw_stats(&self) -> Vec<DrawStats> {
        self.components().map(|m| m.draw).collect()
    }

    /// The components in the poses of their sessions, as [`MergedLoops::fleet_components`]
    /// gives them; `starts` are the sessions' first fleet indices.
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a component of a session `starts` does not reach.
    pub fn fleet_components(&self, starts: &[usize]) -> Result<Vec<FleetComponent>> {
        use rayon::prelude::*;
        if let Some(m) = self.parts.iter().flat_map(|m| &m.components).find(|m| !fits_starts(m, starts)) {
            return Err(Error::InconsistentTiles {
                problem: format!("a component of sessions {:?} does not lie at the starts given", m.sessions),
            });
        }
        Ok(self
            .order
            .par_iter()
            .enumerate()
            .map(|(id, &(p, k))| {
                let m = &self.parts[p as usize].components[k as usize];
                FleetComponent { id, ..localize(&m.component, m.sessions, starts) }
            })
            .collect())
    }

    /// The sparse overlap matrix, as [`MergedLoops::session_pairs`] gives it; `spans_s` are
    /// the sessions' spans. Each part is one session pair, its components in id order.
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a component of a session beyond `spans_s`.
    pub fn session_pairs(&self, spans_s: &[f64]) -> Result<Vec<SessionPair>> {
        use rayon::prelude::*;
        let parts: Vec<Vec<SessionPair>> =
            self.parts.par_iter().map(|m| m.session_pairs(spans_s)).collect::<Result<_>>()?;
        let mut pairs: Vec<SessionPair> = parts.into_iter().flatten().collect();
        pairs.sort_by_key(|p| p.sessions);
        Ok(pairs)
    }

    /// The times of each component's extents, by id ([`MergedComponent::times_s`]).
    pub fn times_s(&self) -> Vec<[[f64; 2]; 2]> {
        self.components().map(|m| m.times_s).collect()
    }
}

/// Whether merged component `m` lies at or after the first fleet indices of its sessions.
fn fits_starts(m: &MergedComponent, starts: &[usize]) -> bool {
    let ([a, b], c) = (m.sessions, &m.component);
    b < starts.len()
        && starts[a] <= c.i_range[0].min(c.i_range[1]).min(c.closest_pair[0])
        && starts[b] <= c.j_range[0].min(c.j_range[1]).min(c.closest_pair[1])
}

/// Merges the summaries of tiles that cover a fleet's plane (every tile [`plan_tiles`] makes,
/// scanned by [`scan_tile`], in any order) into the fleet's loop components, numbered as
/// [`find_fleet_loops`](crate::fleet::find_fleet_loops) numbers them (by first cell, row-major): the
/// merge of all of them in one [`TileMerge::merge`].
///
/// The merge is a union-find over the provisional components, O(components + edge runs).
///
/// # Errors
/// [`Error::InvalidParameter`] for two summaries of one tile; [`Error::InconsistentTiles`] as
/// [`TileMerge::merge`].
pub fn merge_tiles(summaries: &[TileSummary]) -> Result<Vec<LoopComponent>> {
    let parts = summaries.iter().cloned().map(TileMerge::new).collect::<Result<Vec<_>>>()?;
    Ok(TileMerge::merge(parts)?.finish()?.components.into_iter().map(|m| m.component).collect())
}

/// The tags of the byte formats, and what each holds.
#[cfg(feature = "serde")]
const TAGS: [([u8; 4], &str); 6] = [
    (*b"ILsb", "session blocks"),
    (*b"ILts", "tile summary"),
    (*b"ILtt", "tile duration"),
    (*b"ILtm", "tile merge"),
    (*b"ILtr", "tile runs"),
    (*b"ILml", "merged loops"),
];

/// `value` after its tag and the format version.
#[cfg(feature = "serde")]
pub(crate) fn encode<T: serde::Serialize>(tag: [u8; 4], value: &T) -> Vec<u8> {
    let mut bytes = tag.to_vec();
    bytes.extend_from_slice(&TILE_FORMAT_VERSION.to_le_bytes());
    let body = rmp_serde::to_vec(value).expect("MessagePack writes the tile types to a Vec");
    bytes.extend_from_slice(&body);
    bytes
}

/// The value of [`encode`]'s bytes, checking the tag, the version and that every byte is used.
#[cfg(feature = "serde")]
pub(crate) fn decode<T: serde::de::DeserializeOwned>(tag: [u8; 4], what: &'static str, bytes: &[u8]) -> Result<T> {
    let corrupt = |reason: String| Error::InvalidState { what, reason };
    if bytes.len() < 6 {
        return Err(corrupt(format!("{} bytes, fewer than the 6 of its tag and version", bytes.len())));
    }
    if bytes[..4] != tag {
        let problem = match TAGS.iter().find(|(t, _)| bytes[..4] == *t) {
            Some((_, other)) => format!("these are the bytes of a {other}"),
            None => format!(
                "the bytes start with {:?}, not the tag {:?}",
                String::from_utf8_lossy(&bytes[..4]),
                String::from_utf8_lossy(&tag)
            ),
        };
        return Err(corrupt(problem));
    }
    let version = u16::from_le_bytes([bytes[4], bytes[5]]);
    if !(OLDEST_TILE_FORMAT_VERSION..=TILE_FORMAT_VERSION).contains(&version) {
        return Err(corrupt(format!(
            "format version {version}; this build reads versions {OLDEST_TILE_FORMAT_VERSION} to {TILE_FORMAT_VERSION}"
        )));
    }
    let body = &bytes[6..];
    // Read in place (packed values straight from the bytes); a value that is the whole body
    // leaves nothing for a next one to read. Anything else is read again through a cursor to
    // name what is wrong.
    let mut de = rmp_serde::Deserializer::from_read_ref(body);
    if let Ok(value) = <T as serde::Deserialize>::deserialize(&mut de)
        && matches!(
            <serde::de::IgnoredAny as serde::Deserialize>::deserialize(&mut de),
            Err(rmp_serde::decode::Error::InvalidMarkerRead(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof
        )
    {
        return Ok(value);
    }
    let mut reader = std::io::Cursor::new(body);
    let value: T = rmp_serde::from_read(&mut reader).map_err(|e| corrupt(format!("{e} (in {} bytes)", bytes.len())))?;
    let used = reader.position() as usize;
    if used != body.len() {
        return Err(corrupt(format!("{} bytes left over after the {} it holds", body.len() - used, used + 6)));
    }
    Ok(value)
}

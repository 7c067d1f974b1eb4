//! What tiles give besides components: keyed draws of samples and the loop duration τ, each
//! from one tile's rescan or scan, equal to the fleet's in memory.
//!
//! - **Samples.** After the merge, a [`KeyedDraw`](crate::sample::KeyedDraw) over the merged statistics
//!   ([`MergedLoops::draw_stats`]) asks for a few pairs per component; [`tile_requests`] cuts the
//!   request into what each tile holds ([`MergedLoops::tile_labels`] names its provisional
//!   components), and [`draw_session_tile`] rescans a tile and offers its pairs: the keyed pairs
//!   below a threshold and the closest pair of requested rows. The draw takes the offers of every
//!   tile and gives the samples of [`sample_fleet`](crate::fleet::sample_fleet), pair for pair.
//! - **τ.** [`scan_session_tile`](crate::tile::scan_session_tile), kept with its duration
//!   ([`TileKeep::duration`](crate::tile::TileKeep::duration)), also returns the tile's share of τ
//!   ([`TileDuration`]: what its runs add to each of its rows and columns), and
//!   [`session_loop_duration`] adds up the shares of one session: `own` from the tiles within it,
//!   `other` from the tiles with another session, as
//!   [`FleetLoops::loop_duration`](crate::fleet::FleetLoops::loop_duration) gives them (to
//!   rounding: the same widths, added in another order).

use std::collections::HashSet;

use crate::error::{Error, Result};
use crate::metric::Metric;
use crate::sample::{DrawCandidates, DrawRequest, DrawRun, RunHolder, draw_candidates};
use crate::separation::Separation;
use crate::spec::{MetricSpec, with_metric};
use crate::tile::{MergedLoops, ScannedTile, Tile, fleet_index, piece_row, scan_piece};
use crate::trajectory::Trajectory;

/// The part of `request` each tile of `merged` must answer (by tile, as
/// [`MergedLoops::tiles`]); `None` for a tile asked nothing. O(the tiles' provisional
/// components + the request).
pub fn tile_requests(merged: &MergedLoops, request: &DrawRequest) -> Vec<Option<DrawRequest>> {
    merged
        .tiles()
        .iter()
        .enumerate()
        .map(|(t, tile)| {
            let ids: HashSet<usize> = merged.tile_labels(t).iter().map(|&c| c as usize).collect();
            let part = request.restricted(&ids, tile.rows.clone(), tile.sessions);
            (!part.is_empty()).then_some(part)
        })
        .collect()
}

/// A tile's runs as its scan made them, with their provisional labels: what a keyed draw of the
/// tile reads ([`draw_tile_runs`]), kept where the tile was scanned
/// ([`scan_session_tile`](crate::tile::scan_session_tile) with [`TileKeep::runs`](crate::tile::TileKeep::runs))
/// so that the draw need not rescan it. Owns its runs (16 bytes a run), not the tile's poses.
/// A fleet store saves them beside its tiles ([`to_bytes`](Self::to_bytes)).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TileRuns {
    tile: Tile,
    starts: [usize; 2],
    gamma: f64,
    separation: Separation,
    set: crate::sublevel::SublevelSet,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    piece_starts: Vec<usize>,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    fleet_starts: Vec<usize>,
    rows: usize,
    piece_len: usize,
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    provisional: Vec<u32>,
    components: u32,
    /// The first and last piece row of each provisional component.
    #[cfg_attr(feature = "serde", serde(with = "crate::packed"))]
    spans: Vec<[u32; 2]>,
}

impl TileRuns {
    pub(super) fn new(
        scanned: ScannedTile<'_>,
        tile: &Tile,
        starts: [usize; 2],
        gamma: f64,
        separation: Separation,
    ) -> Self {
        let piece_len = scanned.piece.len();
        let ScannedTile { piece_starts, rows, set, labels: (provisional, components), fleet_starts, .. } = scanned;
        let mut spans = vec![[u32::MAX, 0]; components as usize];
        for k in 0..set.rows().min(rows) {
            for &p in &provisional[set.row_offset(k)..set.row_offset(k + 1)] {
                let span = &mut spans[p as usize];
                *span = [span[0].min(k as u32), span[1].max(k as u32)];
            }
        }
        Self {
            tile: tile.clone(),
            starts,
            gamma,
            separation,
            set,
            piece_starts,
            fleet_starts,
            rows,
            piece_len,
            provisional,
            components,
            spans,
        }
    }

    /// The rows (fleet indices, sorted, apart) where the provisional components that `wanted`
    /// accepts have runs: the rows a draw asking about them reads. O(components).
    fn rows_of(&self, wanted: impl Fn(usize) -> bool) -> Vec<std::ops::Range<usize>> {
        let mut spans: Vec<[u32; 2]> = (0..self.spans.len())
            .filter(|&p| wanted(p) && self.spans[p][0] <= self.spans[p][1])
            .map(|p| self.spans[p])
            .collect();
        spans.sort_unstable();
        let mut rows: Vec<std::ops::Range<usize>> = Vec::new();
        for [first, last] in spans {
            let range = self.to_fleet(first as usize)..self.to_fleet(last as usize) + 1;
            match rows.last_mut() {
                Some(r) if range.start <= r.end => r.end = r.end.max(range.end),
                _ => rows.push(range),
            }
        }
        rows
    }

    /// The tile.
    pub fn tile(&self) -> &Tile {
        &self.tile
    }

    /// γ and the separation it was scanned with.
    pub(crate) fn scanned_with(&self) -> (f64, Separation) {
        (self.gamma, self.separation)
    }

    /// The first fleet index of its two sessions.
    pub(crate) fn starts(&self) -> [usize; 2] {
        self.starts
    }

    /// Its runs.
    pub fn run_count(&self) -> usize {
        self.provisional.len()
    }

    /// The bytes it holds: its runs (16 bytes each with their closest column and label) and its
    /// rows' offsets (8 bytes a row).
    pub fn heap_bytes(&self) -> usize {
        let runs = self.run_count() * (std::mem::size_of::<crate::sublevel::Run>() + 8);
        let rows = (self.set.rows() + 1 + self.piece_starts.len() + self.fleet_starts.len()) * 8;
        runs + rows
    }

    fn to_fleet(&self, k: usize) -> usize {
        fleet_index(&self.piece_starts, &self.fleet_starts, k)
    }

    /// The runs as bytes (a tag, [`TILE_FORMAT_VERSION`](crate::TILE_FORMAT_VERSION),
    /// MessagePack): 16 bytes a run and 8 a row, about [`heap_bytes`](Self::heap_bytes).
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        crate::tile::encode(*b"ILtr", self)
    }

    /// The runs from [`to_bytes`](Self::to_bytes), checked to fit together (labels of its
    /// components, each run's label, the stretches of rows within its piece).
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"tile runs"`) for other bytes or parts that do not fit.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let runs: Self = crate::tile::decode(*b"ILtr", "tile runs", bytes)?;
        runs.check().map_err(|reason| Error::InvalidState { what: "tile runs", reason })?;
        Ok(runs)
    }

    /// Its parts fit together: what a draw indexes by is in range.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self) -> std::result::Result<(), String> {
        let set = &self.set;
        let runs = set.row_offset(set.rows());
        if self.provisional.len() != runs {
            return Err(format!("{} labels for {runs} runs", self.provisional.len()));
        }
        if self.spans.len() != self.components as usize {
            return Err(format!("{} spans for {} components", self.spans.len(), self.components));
        }
        if let Some(p) = self.provisional.iter().find(|&&p| p >= self.components) {
            return Err(format!("label {p} of {} components", self.components));
        }
        if let Some(s) = self.spans.iter().find(|s| s[0] <= s[1] && s[1] as usize >= set.rows()) {
            return Err(format!("a component spans rows {s:?} of {} rows", set.rows()));
        }
        let starts = &self.piece_starts;
        if starts.len() != self.fleet_starts.len()
            || starts.first().is_some_and(|&s| s != 0)
            || starts.windows(2).any(|w| w[0] >= w[1])
            || starts.last().is_some_and(|&s| s >= self.piece_len.max(1))
        {
            return Err(format!("stretches {starts:?} of a piece of {} poses", self.piece_len));
        }
        if self.rows > self.piece_len || set.rows() > self.piece_len {
            return Err(format!(
                "{} rows ({} in its set) of a piece of {} poses",
                self.rows,
                set.rows(),
                self.piece_len
            ));
        }
        if let Some(k) = (0..set.rows()).find(|&k| set.row(k).iter().any(|r| r.end as usize >= self.piece_len)) {
            return Err(format!("row {k} has a run beyond the piece's {} poses", self.piece_len));
        }
        Ok(())
    }

    /// The runs as a fleet of the tile's two sessions alone holds them, each from pose 0, as
    /// [`StoredTile::local`](crate::store::StoredTile::local) holds the tile; `placed` puts
    /// them back. O(the tile's stretches).
    pub fn local(&self) -> Self {
        let [a, b] = self.tile.sessions;
        let mut local = self.clone();
        local.move_to([0, usize::from(a != b)], [-(self.starts[0] as isize), -(self.starts[1] as isize)]);
        local
    }

    /// Runs of [`local`](Self::local) form placed as those of the tile of the store's sessions
    /// `sessions`, which start at `starts` in its fleet. O(the tile's stretches).
    pub fn placed(mut self, sessions: [usize; 2], starts: [usize; 2]) -> Self {
        self.move_to(sessions, [starts[0] as isize, starts[1] as isize]);
        self
    }

    /// Renumbers the tile's sessions `sessions` and moves its rows and columns by `shifts`
    /// (fleet indices): what a rescan at the new place keeps, since a tile reads its two
    /// sessions alone. O(the tile's stretches).
    pub(crate) fn move_to(&mut self, sessions: [usize; 2], shifts: [isize; 2]) {
        let at = |x: usize, side: usize| x.wrapping_add_signed(shifts[side]);
        self.tile = self.tile.moved(sessions, shifts);
        self.starts = [at(self.starts[0], 0), at(self.starts[1], 1)];
        // The stretches of rows come first; within one session both sides move alike.
        for (p, f) in self.piece_starts.iter().zip(&mut self.fleet_starts) {
            *f = at(*f, usize::from(*p >= self.rows));
        }
    }
}

/// A tile's runs, for a keyed draw.
struct TileHolder<'a, M: Metric + ?Sized> {
    sessions: [&'a Trajectory; 2],
    starts: [usize; 2],
    metric: &'a M,
    gamma: f64,
    diagonal: bool,
    tile: &'a Tile,
    runs: &'a TileRuns,
    labels: &'a [u32],
    /// The rows offered (those of the tile, or fewer), in stretches sorted and apart.
    rows: Vec<std::ops::Range<usize>>,
}

impl<M: Metric + ?Sized> TileHolder<'_, M> {
    fn point(&self, f: usize, side: usize) -> &[f64] {
        self.sessions[side].point(f - self.starts[side])
    }

    /// δ(x_i, x_j) ≤ γ for a pair of the row session (within one session).
    fn within(&self, i: usize, j: usize) -> bool {
        self.metric.distance(self.point(i, 0), self.point(j, 0)) <= self.gamma
    }
}

impl<M: Metric + ?Sized> RunHolder for TileHolder<'_, M> {
    fn rows(&self) -> Vec<std::ops::Range<usize>> {
        self.rows.clone()
    }

    fn for_each_run(&self, i: usize, f: &mut dyn FnMut(DrawRun)) {
        let runs = self.runs;
        let set = &runs.set;
        let Some(k) = piece_row(&runs.piece_starts, &runs.fleet_starts, runs.rows, runs.piece_len, i) else {
            return;
        };
        let offset = set.row_offset(k);
        let to_fleet = |k: usize| runs.to_fleet(k);
        for (r, run) in set.row(k).iter().enumerate() {
            let provisional = runs.provisional[offset + r] as usize;
            f(DrawRun {
                start: to_fleet(run.start as usize),
                end: to_fleet(run.end as usize),
                component: self.labels[provisional] as usize,
                closest: to_fleet(set.closest_columns()[offset + r] as usize),
            });
        }
    }

    fn measure(&self, i: usize, j: usize) -> (f64, f64) {
        let (x, y) = (self.point(i, 0), self.point(j, 1));
        (self.metric.distance(x, y), self.metric.distance_rank(x, y))
    }

    fn times_s(&self, i: usize, j: usize) -> [f64; 2] {
        [self.sessions[0].timestamps_s()[i - self.starts[0]], self.sessions[1].timestamps_s()[j - self.starts[1]]]
    }

    fn diagonal_end(&self, i: usize, end: usize) -> usize {
        if !self.diagonal || end + 1 != self.tile.columns.end {
            return end;
        }
        // The run reaches the tile's last column: read on in the session.
        let last = self.starts[1] + self.sessions[1].len() - 1;
        let mut j = end;
        while j < last && self.within(i, j + 1) {
            j += 1;
        }
        j
    }

    fn continues_diagonal(&self, i: usize, start: usize) -> bool {
        self.diagonal && start == self.tile.columns.start && start > i && (i + 1..start).all(|j| self.within(i, j))
    }
}

/// Rescans one tile (as [`scan_session_tile`](crate::tile::scan_session_tile)) and offers its
/// pairs to a keyed draw: `labels` are the component ids of its provisional components
/// ([`MergedLoops::tile_labels`]), `request` the part of the draw's request for this tile
/// ([`tile_requests`]). A run on the diagonal that reaches the tile's last column is read on in
/// the session, so that its return column is that of the whole run; the piece that continues it
/// in the next tile offers nothing.
/// [`draw_tile_runs`] offers the same pairs from the runs its scan kept.
///
/// Time: the tile's scan, plus O(offered pairs) and the diagonal runs of requested rows.
///
/// # Errors
/// As [`scan_session_tile`](crate::tile::scan_session_tile); [`Error::InconsistentTiles`] for labels of another tile.
#[allow(clippy::too_many_arguments)]
pub fn draw_session_tile<M: Metric + ?Sized>(
    sessions: [&Trajectory; 2],
    starts: [usize; 2],
    metric: &M,
    gamma: f64,
    separation: Separation,
    tile: &Tile,
    labels: &[u32],
    request: &DrawRequest,
) -> Result<DrawCandidates> {
    let scanned = scan_piece(sessions, starts, metric, gamma, separation, tile, None)?;
    let runs = TileRuns::new(scanned, tile, starts, gamma, separation);
    draw_tile_runs(sessions, starts, metric, &runs, labels, request)
}

/// [`draw_session_tile`] without the rescan: the pairs offered from `runs`, which
/// [`scan_session_tile`](crate::tile::scan_session_tile) kept of the same tile with the same sessions,
/// metric, γ and separation. The same offers as [`draw_session_tile`].
///
/// Time: O(offered pairs) and the diagonal runs of requested rows.
///
/// # Errors
/// [`Error::InconsistentTiles`] for labels of another tile, or runs of another tile or
/// other sessions' starts than the request's; [`Error::Interrupted`] when an
/// [`Interrupt`](crate::Interrupt) installed on this thread is interrupted.
pub fn draw_tile_runs<M: Metric + ?Sized>(
    sessions: [&Trajectory; 2],
    starts: [usize; 2],
    metric: &M,
    runs: &TileRuns,
    labels: &[u32],
    request: &DrawRequest,
) -> Result<DrawCandidates> {
    let tile = &runs.tile;
    if runs.components as usize != labels.len() {
        return Err(Error::InconsistentTiles {
            problem: format!(
                "tile {tile:?} has {} components, but {} labels were given",
                runs.components,
                labels.len()
            ),
        });
    }
    let fits = |side: usize, range: &std::ops::Range<usize>| {
        range.start >= starts[side] && range.end <= starts[side] + sessions[side].len()
    };
    if runs.starts != starts || !fits(0, &tile.rows) || !fits(1, &tile.columns) {
        return Err(Error::InconsistentTiles {
            problem: format!(
                "the runs of tile {tile:?} were scanned with sessions at {:?}, not {starts:?}",
                runs.starts
            ),
        });
    }
    let diagonal = tile.sessions[0] == tile.sessions[1] && runs.separation.is_none();
    // Only the rows where the components asked about have runs can offer anything.
    let asked: HashSet<usize> = request.components.iter().map(|c| c.id).collect();
    // One pass over all of them: one index of the request, one set of tasks.
    let rows = runs.rows_of(|p| asked.contains(&(labels[p] as usize)));
    let holder = TileHolder { sessions, starts, metric, gamma: runs.gamma, diagonal, tile, runs, labels, rows };
    draw_candidates(&holder, request)
}

/// What one tile's runs add to the loop duration τ (Side both, seconds) of its rows and of its
/// columns, on the stretches of each that its scan read (the rows and columns that can hold a
/// cell; the others add nothing): each stretch is `(offset, seconds)`, `seconds[k]` added to
/// fleet index `tile.rows.start + offset + k` (of `rows`) or `tile.columns.start + offset + k`
/// (of `columns`). Within one session both are that session's own τ; between two, each its τ
/// with others. O(those stretches) in memory, not O(the tile's rows and columns).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TileDuration {
    /// The tile.
    pub tile: Tile,
    /// Stretches of rows: (offset from the tile's first row, seconds per row).
    #[cfg_attr(feature = "serde", serde(with = "crate::packed::stretches"))]
    pub rows: Vec<(usize, Vec<f64>)>,
    /// Stretches of columns: (offset from the tile's first column, seconds per column).
    #[cfg_attr(feature = "serde", serde(with = "crate::packed::stretches"))]
    pub columns: Vec<(usize, Vec<f64>)>,
}

/// [`TileDuration`] as the stores of layout 2 saved it: a value for every row and column of the
/// tile (tag `ILtd`), read as one stretch a side.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct DenseDuration {
    tile: Tile,
    rows: Vec<f64>,
    columns: Vec<f64>,
}

impl TileDuration {
    /// As bytes (a tag, [`TILE_FORMAT_VERSION`](crate::tile::TILE_FORMAT_VERSION), MessagePack).
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        crate::tile::encode(*b"ILtt", self)
    }

    /// From [`to_bytes`](Self::to_bytes), or from the bytes of the dense shares that earlier
    /// versions wrote (a value for every row and column of the tile).
    ///
    /// # Errors
    /// [`Error::InvalidState`] for other bytes, or stretches that do not fit the tile.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let d: Self = if bytes.starts_with(b"ILtd") {
            let DenseDuration { tile, rows, columns } = crate::tile::decode(*b"ILtd", "tile duration", bytes)?;
            Self { tile, rows: vec![(0, rows)], columns: vec![(0, columns)] }
        } else {
            crate::tile::decode(*b"ILtt", "tile duration", bytes)?
        };
        if !d.fits_tile() {
            return Err(Error::InvalidState {
                what: "tile duration",
                reason: format!("a stretch of rows or columns leaves tile {:?}", d.tile),
            });
        }
        Ok(d)
    }

    /// Every stretch lies within its side of the tile.
    pub(crate) fn fits_tile(&self) -> bool {
        let fits = |stretches: &[(usize, Vec<f64>)], side: &std::ops::Range<usize>| {
            stretches
                .iter()
                .all(|(offset, values)| offset.checked_add(values.len()).is_some_and(|end| end <= side.len()))
        };
        fits(&self.rows, &self.tile.rows) && fits(&self.columns, &self.tile.columns)
    }
}

/// `to_bytes` and `from_bytes` of a draw's message: a tag, the tile format version, MessagePack.
macro_rules! draw_bytes {
    ($type:ty, $tag:literal, $what:literal) => {
        #[cfg(feature = "serde")]
        impl $type {
            #[doc = concat!("The ", $what, " as bytes (a tag, the tile format version, MessagePack).")]
            pub fn to_bytes(&self) -> Vec<u8> {
                crate::tile::encode(*$tag, self)
            }

            #[doc = concat!("The ", $what, " from [`to_bytes`](Self::to_bytes).")]
            ///
            /// # Errors
            /// [`Error::InvalidState`] for other bytes.
            pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
                crate::tile::decode(*$tag, $what, bytes)
            }
        }
    };
}

draw_bytes!(DrawRequest, b"ILdr", "draw request");
draw_bytes!(DrawCandidates, b"ILdc", "draw candidates");

/// The share of τ of a scanned tile, `prefix` its [`ScannedTile::prefix_sums`]: one pass over
/// its runs, on the piece's stretches.
pub(super) fn duration_of(scanned: &ScannedTile<'_>, prefix: &[f64], tile: &Tile) -> TileDuration {
    let widths = scanned.piece.cell_widths_s();
    let width = |a: usize, b: usize| (prefix[b] + widths[b]) - prefix[a];
    let (len, rows, set) = (scanned.piece.len(), scanned.rows, &scanned.set);
    // The piece's stretches: (first piece index, end, first fleet index).
    let starts = &scanned.piece_starts;
    let stretches: Vec<(usize, usize, usize)> = (0..starts.len())
        .map(|s| (starts[s], starts.get(s + 1).copied().unwrap_or(len), scanned.fleet_starts[s]))
        .collect();
    let mut ends = vec![false; len + 1];
    stretches.iter().for_each(|&(_, end, _)| ends[end] = true);
    // Each row's share, and the columns' as differences: a run's weight enters at its first
    // column and leaves after its last, unless that ends its stretch (summed from 0 in each).
    let mut row_share = vec![0.0; rows];
    let mut diff = vec![0.0; len + 1];
    for (k, &w_k) in widths[..rows].iter().enumerate() {
        for run in set.row(k) {
            let (a, b) = (run.start as usize, run.end as usize);
            row_share[k] += width(a, b);
            // The diagonal cell (k, k) adds to its row only.
            let first = if a == k { a + 1 } else { a };
            if first <= b {
                diff[first] += w_k;
                if !ends[b + 1] {
                    diff[b + 1] -= w_k;
                }
            }
        }
    }
    // The part of each stretch within `side` (fleet indices): (piece range, offset in side).
    let within = |(p0, p1, f0): (usize, usize, usize), side: &std::ops::Range<usize>| {
        let (lo, hi) = (f0.max(side.start), (f0 + p1 - p0).min(side.end));
        (lo < hi).then(|| (p0 + lo - f0..p0 + hi - f0, lo - side.start))
    };
    let row_stretches = stretches
        .iter()
        .filter(|&&(p0, _, _)| p0 < rows)
        .filter_map(|&(p0, p1, f0)| within((p0, p1.min(rows), f0), &tile.rows))
        .map(|(piece, offset)| (offset, row_share[piece].to_vec()))
        .collect();
    let column_stretches = stretches
        .iter()
        .filter_map(|&stretch| within(stretch, &tile.columns))
        .map(|(piece, offset)| {
            let mut running = 0.0;
            let values = diff[piece]
                .iter()
                .map(|d| {
                    running += d;
                    running
                })
                .collect();
            (offset, values)
        })
        .collect();
    TileDuration { tile: tile.clone(), rows: row_stretches, columns: column_stretches }
}

/// τ of session `session` (its first fleet index `start`, `poses` poses) from the shares of
/// every tile that holds its rows or columns ([`scan_session_tile`](crate::tile::scan_session_tile) with
/// its duration), in any order: `(own, other)` per pose, seconds, as
/// [`FleetLoops::loop_duration`](crate::fleet::FleetLoops::loop_duration) splits them. Shares
/// of tiles without the session are ignored.
///
/// # Errors
/// [`Error::InconsistentTiles`] for a share whose rows or columns lie outside the session.
pub fn session_loop_duration<'a>(
    session: usize,
    start: usize,
    poses: usize,
    parts: impl IntoIterator<Item = &'a TileDuration>,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let (mut own, mut other) = (vec![0.0; poses], vec![0.0; poses]);
    let mut ordered: Vec<&TileDuration> = parts.into_iter().collect();
    ordered.sort_by_key(|p| (p.tile.sessions, p.tile.rows.start, p.tile.columns.start));
    for part in ordered {
        let t = &part.tile;
        for (side, range, stretches) in [(0, &t.rows, &part.rows), (1, &t.columns, &part.columns)] {
            if t.sessions[side] != session {
                continue;
            }
            let fits = |(offset, values): &(usize, Vec<f64>)| offset + values.len() <= range.len();
            if range.start < start || range.end > start + poses || !stretches.iter().all(fits) {
                return Err(Error::InconsistentTiles {
                    problem: format!("tile {t:?} does not lie in session {session} (poses {start}..{})", start + poses),
                });
            }
            let target = if t.sessions[0] == t.sessions[1] { &mut own } else { &mut other };
            for (offset, values) in stretches {
                let first = range.start - start + offset;
                target[first..first + values.len()].iter_mut().zip(values).for_each(|(y, v)| *y += v);
            }
        }
    }
    Ok((own, other))
}

impl MetricSpec {
    /// [`draw_session_tile`] under this metric.
    ///
    /// # Errors
    /// As [`draw_session_tile`].
    #[allow(clippy::too_many_arguments)]
    pub fn draw_session_tile(
        &self,
        sessions: [&Trajectory; 2],
        starts: [usize; 2],
        gamma: f64,
        separation: Separation,
        tile: &Tile,
        labels: &[u32],
        request: &DrawRequest,
    ) -> Result<DrawCandidates> {
        with_metric!(self, m => draw_session_tile(sessions, starts, m, gamma, separation, tile, labels, request))
    }

    /// [`draw_tile_runs`] under this metric.
    ///
    /// # Errors
    /// As [`draw_tile_runs`].
    pub fn draw_tile_runs(
        &self,
        sessions: [&Trajectory; 2],
        starts: [usize; 2],
        runs: &TileRuns,
        labels: &[u32],
        request: &DrawRequest,
    ) -> Result<DrawCandidates> {
        with_metric!(self, m => draw_tile_runs(sessions, starts, m, runs, labels, request))
    }
}

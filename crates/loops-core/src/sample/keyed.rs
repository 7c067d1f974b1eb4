//! Keyed draws from the exact loop components: samples that depend on the seed, the sampler
//! and the cells of S_γ alone — not on how the plane is cut into tiles, nor on the threads.
//!
//! Every pair (i, j) off the diagonal has a 64-bit *key*, a uniform random number taken from a
//! stream keyed by (seed, i, ⌊j / 64⌋) (SplitMix64, bit-sliced over the 64 columns of the block,
//! so that the keys at most a threshold come out of a few words per block without visiting
//! every cell). Whoever holds a run of a component — the whole trajectory in memory, or one tile
//! of a fleet on another machine — finds the same keys for its cells. In a fleet the indices are
//! each session's own, salted by a hash of its name ([`KeyLayout`]): a pair keeps its key when
//! sessions are added or removed around it, so that a fleet store can keep what a draw found in
//! the tiles an update leaves alone. From the keys:
//!
//! - **Quotas** per component come from statistics that merge from tiles: the number of pairs
//!   off the diagonal, the first and last row, the closest pair (σ_1: 1 each; σ_ρ and the
//!   dispersed samplers: the rows, `last − first + 1`, which is every row of a 4-connected
//!   component; nearest-then-uniform: the rows, then the pairs). They are rounded at random by
//!   numbers of their own ([`Numbers`]): a rate by each component's permanent random number, a
//!   hash of the cell that names it (its closest pair) under the seed; a budget's extra picks
//!   by each session pair's numbers, to the pairs by order sampling and within a pair
//!   systematically along its components in id order (in time), so that a small budget is
//!   spread along a drive and a pair keeps its picks when sessions come or go: a fleet store's
//!   next draw asks again only where quotas moved.
//! - **Uniform picks** (σ_1, σ_ρ, the rest of the dispersed samplers) are the `q` pairs of the
//!   component with the smallest keys: a uniform draw without replacement. Each holder returns
//!   the `q` smallest of its pairs with a key at most a threshold that leaves a few more than
//!   `q` in expectation (the component's `q` smallest are among them); should fewer come back
//!   in all, the threshold grows and the holders are asked again (the answer does not depend
//!   on the threshold). σ_α takes the smallest keys over all components (a
//!   budget), or every pair with a key below `p · 2⁶⁴` (a rate).
//! - **Row picks** (the dispersed σ_ρ, closest-first, closest-then-spread and the first picks of
//!   nearest-then-uniform, whose others are uniform picks) are the closest pair of chosen rows
//!   (stratified with an offset drawn from the component's own word, as its permanent number):
//!   each holder returns the closest pair of its runs in those rows, and the closest of them
//!   wins (by the metric's rank, then the column). A run on the diagonal offers the closest column after its farthest point
//!   (a return along the same way); a tile reads past its last column to find the run's end.

use std::collections::{BTreeMap, HashMap, HashSet};

use rayon::prelude::*;

use super::SamplerKind;
use super::nearest::nearest_then_uniform_quotas;
use crate::draw::{Numbers, SAMPLE_BYTES, SampleSize, SampleWarning, check_count};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::sample::Sampler;

/// Columns per key stream.
const KEY_BLOCK: usize = 64;

/// Rows per task of the in-memory draw.
const ROWS_PER_TASK: usize = 4096;

/// SplitMix64's output function.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// The stream of components' own words ([`KeyLayout::component_word`]), apart from the keys'.
const COMPONENT_TAG: u64 = 0x636F_6D70_6F6E_656E;

/// The stream of the strata's numbers ([`KeyLayout::numbers`]).
const STRATUM_TAG: u64 = 0x7374_7261_7475_6D31;

/// The stream of the stratification offsets, drawn from the components' words.
const OFFSET_TAG: u64 = 0x6F66_6673_6574_7321;

/// A word as a uniform number in [0, 1) (its top 53 bits).
fn unit(word: u64) -> f64 {
    (word >> 11) as f64 / (1u64 << 53) as f64
}

/// The stream of the keys of row `row`, columns `64 · block ..`, under `seed` (row and block as
/// [`KeyLayout`] names them).
struct KeyStream(u64);

impl KeyStream {
    fn new(seed: u64, row: u64, block: u64) -> Self {
        let s = mix(mix(seed.wrapping_add(GOLDEN)) ^ row.wrapping_mul(GOLDEN));
        Self(mix(s ^ block.wrapping_add(0x6B65_7965_645F_6472)))
    }

    fn next_word(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix(self.0)
    }
}

/// Calls `out(column, key)` for every column of `lo..=hi` (one block of 64, in the columns'
/// own indices) of row `row` whose key is at most `threshold`, in increasing column order; the
/// block's stream is that of `salt + block`. The key's bit 63 − ℓ is bit `column mod 64` of the
/// stream's ℓ-th word.
fn keys_at_most(
    seed: u64,
    row: u64,
    salt: u64,
    lo: usize,
    hi: usize,
    threshold: u64,
    out: &mut impl FnMut(usize, u64),
) {
    let block = lo / KEY_BLOCK;
    debug_assert!(hi / KEY_BLOCK == block && lo <= hi);
    let base = block * KEY_BLOCK;
    let width = hi - lo + 1;
    let mask = if width == 64 { u64::MAX } else { ((1u64 << width) - 1) << (lo - base) };
    let block = salt.wrapping_add(block as u64);
    let mut stream = KeyStream::new(seed, row, block);
    let (mut less, mut equal) = (0u64, mask);
    let mut level = 0;
    while level < 64 && equal != 0 {
        let w = stream.next_word();
        if (threshold >> (63 - level)) & 1 == 1 {
            less |= equal & !w;
            equal &= w;
        } else {
            equal &= !w;
        }
        level += 1;
    }
    let mut hits = less | equal;
    if hits == 0 {
        return;
    }
    // Few blocks have a key below a threshold: their words are drawn again, in full.
    let mut stream = KeyStream::new(seed, row, block);
    let words: [u64; 64] = std::array::from_fn(|_| stream.next_word());
    while hits != 0 {
        let p = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        let key = words.iter().enumerate().fold(0u64, |key, (l, w)| key | (((w >> p) & 1) << (63 - l)));
        out(base + p, key);
    }
}

/// Calls `out(column, key)` for the columns `start..=end` of row `row` with a key at most
/// `threshold`, indices as `layout` keys them.
fn run_keys(
    seed: u64,
    layout: &KeyLayout,
    row: usize,
    start: usize,
    end: usize,
    threshold: u64,
    out: &mut impl FnMut(usize, u64),
) {
    let ((row_key, _), _, _) = layout.origin(row);
    let mut from = start;
    while from <= end {
        // The columns of one session at a time: each has its own blocks.
        let ((_, salt), first, next) = layout.origin(from);
        let to = next.map_or(end, |n| end.min(n - 1));
        let (mut lo, last) = (from - first, to - first);
        while lo <= last {
            let hi = last.min((lo / KEY_BLOCK + 1) * KEY_BLOCK - 1);
            keys_at_most(seed, row_key, salt, lo, hi, threshold, &mut |j, key| out(first + j, key));
            lo = hi + 1;
        }
        from = to + 1;
    }
}

/// The key of pair (i, j) of one trajectory under `seed` (for tests and checks: O(1) per pair).
pub fn pair_key(seed: u64, i: usize, j: usize) -> u64 {
    KeyLayout::default().pair_key(seed, i, j)
}

/// How the indices of pairs are keyed: those of one trajectory as they are, or a fleet's by
/// session, each session's own indices salted by a hash of its name, so that adding or
/// removing sessions (which moves the fleet indices of the sessions after them) leaves every
/// other pair's key as it was. A fleet of one session keys its pairs by its name too, so its
/// uniform picks are not those of the session alone.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct KeyLayout {
    /// Per session (in fleet order): its first fleet index and its salt. Empty: one
    /// trajectory, unsalted.
    sessions: Vec<(usize, u64)>,
}

impl KeyLayout {
    /// The keys of a fleet whose sessions start at `starts` (fleet indices, increasing) and are
    /// named `names`.
    ///
    /// # Panics
    /// When `starts` and `names` differ in length (a caller's bug).
    pub fn sessions<S: AsRef<str>>(starts: &[usize], names: &[S]) -> Self {
        assert_eq!(starts.len(), names.len(), "one name per session");
        Self { sessions: starts.iter().zip(names).map(|(&s, n)| (s, Self::salt(n.as_ref()))).collect() }
    }

    /// The salt of a session's indices: a 64-bit hash of its name (FNV-1a, then SplitMix64's
    /// output function) with its low 32 bits clear, so that a session's rows and blocks (up to
    /// 2³² poses) are apart from every other session's.
    pub fn salt(name: &str) -> u64 {
        let fnv = name.bytes().fold(0xCBF2_9CE4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01B3));
        mix(fnv) & !0xFFFF_FFFF
    }

    /// The part for a tile of sessions `sessions` (indices into this layout): those two only.
    pub fn narrowed(&self, sessions: [usize; 2]) -> Self {
        if self.sessions.is_empty() {
            return Self::default();
        }
        let [a, b] = sessions;
        let mut kept = vec![self.sessions[a]];
        if b != a {
            kept.push(self.sessions[b]);
        }
        kept.sort_unstable();
        Self { sessions: kept }
    }

    /// The key of pair (i, j) under `seed` (O(1)).
    pub fn pair_key(&self, seed: u64, i: usize, j: usize) -> u64 {
        let mut key = 0;
        run_keys(seed, self, i, j, j, u64::MAX, &mut |_, k| key = k);
        key
    }

    /// A component's own random word under `seed`: a hash (another stream than the pairs'
    /// keys) of the cell that names it — its closest pair, or the diagonal cell of its first
    /// row for a trivial component (whose closest pair a tile does not know) — in its sessions'
    /// own indices, with the two sessions' salts combined (XOR: none within one session, so
    /// that a fleet of one session rounds and spreads as the session alone). The same for any
    /// holder, any order of the sessions and any other components.
    fn component_word(&self, seed: u64, s: &DrawStats) -> u64 {
        let [i, j] = if s.trivial { [s.rows[0]; 2] } else { s.closest_pair };
        let ((row, row_salt), _, _) = self.origin(i);
        let ((column, column_salt), _, _) = self.origin(j);
        let local = |key: u64, salt: u64| key.wrapping_sub(salt);
        let h = mix(mix(seed ^ COMPONENT_TAG) ^ (row_salt ^ column_salt));
        let h = mix(h.wrapping_add(local(row, row_salt).wrapping_mul(GOLDEN)));
        mix(h ^ local(column, column_salt).wrapping_mul(0xD6E8_FEB8_6659_FD93))
    }

    /// What rounds the quotas of the components `stats` (in id order, with their own words
    /// `words`) under `seed`: each one's permanent random number (its word), and their session
    /// pairs as strata (a trajectory is one), so that a budget's picks are spread along each
    /// pair's components in id order (in time) and a pair keeps its picks when sessions come
    /// or go around it ([`Numbers`]). A pair's rank number is hashed from its two sessions'
    /// salts, its offset from their XOR (none within one session, so that a fleet of one
    /// session spreads its picks as the session alone).
    fn numbers<'a>(&self, seed: u64, stats: impl Iterator<Item = &'a DrawStats>, words: &[u64]) -> Numbers {
        let mut strata: HashMap<[u64; 2], u32> = HashMap::new();
        let mut pairs = Vec::new();
        let stratum = stats
            .map(|s| {
                let [i, j] = if s.trivial { [s.rows[0]; 2] } else { s.closest_pair };
                let ((_, row_salt), _, _) = self.origin(i);
                let ((_, column_salt), _, _) = self.origin(j);
                *strata.entry([row_salt, column_salt]).or_insert_with(|| {
                    pairs.push([row_salt, column_salt]);
                    (pairs.len() - 1) as u32
                })
            })
            .collect();
        let stream = mix(seed ^ STRATUM_TAG);
        let rank = |[a, b]: [u64; 2]| unit(mix(mix(stream ^ a).wrapping_add(b.wrapping_mul(GOLDEN))));
        let offset = |[a, b]: [u64; 2]| unit(mix(mix(stream.wrapping_add(GOLDEN)) ^ a ^ b));
        let strata = pairs.iter().map(|&pair| [rank(pair), offset(pair)]).collect();
        Numbers::stratified(words.iter().map(|&w| unit(w)).collect(), stratum, strata)
    }

    /// Index `f` as keyed: (the row key of `f`, the salt of its session), the first fleet index
    /// of its session, and the first of the next one, if any.
    fn origin(&self, f: usize) -> ((u64, u64), usize, Option<usize>) {
        if self.sessions.is_empty() {
            return ((f as u64, 0), 0, None);
        }
        let k = self.sessions.partition_point(|&(s, _)| s <= f).max(1) - 1;
        let (start, salt) = self.sessions[k];
        let local = f.saturating_sub(start) as u64;
        ((salt.wrapping_add(local), salt), start, self.sessions.get(k + 1).map(|&(s, _)| s))
    }
}

/// What a keyed draw needs of one loop component: statistics that merge from tiles.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DrawStats {
    /// Holds a diagonal cell.
    pub trivial: bool,
    /// First and last row with a cell of the component (upper half).
    pub rows: [usize; 2],
    /// Pairs (i, j) with j > i: the candidates of the samplers.
    pub pairs: u64,
    /// The closest pair (row, column); that of a trivial component is not used.
    pub closest_pair: [usize; 2],
}

#[cfg(feature = "serde")]
crate::packed::packed_record!(DrawStats { trivial: bool, rows: [usize; 2], pairs: u64, closest_pair: [usize; 2] });

impl DrawStats {
    /// Rows from the first to the last.
    fn row_count(&self) -> usize {
        self.rows[1] - self.rows[0] + 1
    }
}

/// What one pass of a keyed draw asks of one component.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ComponentRequest {
    /// The component.
    pub id: usize,
    /// Every pair off the diagonal with a key at most this.
    pub pool: Option<u64>,
    /// Of the pool, the pairs with the smallest keys a holder need offer: the component's
    /// quota (its smallest keys over all holders are among those of each), or `u64::MAX`
    /// (σ_α, which takes the smallest over all components).
    pub keep: u64,
    /// The closest pair of each of these rows (sorted).
    pub rows: Vec<usize>,
    /// The closest pair over all its rows.
    pub best: bool,
}

/// What one pass of a keyed draw asks of whoever holds runs: per component, sorted by id.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DrawRequest {
    /// The sampler's seed.
    pub seed: u64,
    /// How the pairs' indices are keyed.
    pub keys: KeyLayout,
    /// The components asked about, by id.
    pub components: Vec<ComponentRequest>,
}

impl DrawRequest {
    /// The part of the request about these components, and rows in `rows` only, for a tile of
    /// sessions `sessions` (its keys narrowed to those: [`KeyLayout::narrowed`]).
    pub fn restricted(&self, ids: &HashSet<usize>, rows: std::ops::Range<usize>, sessions: [usize; 2]) -> Self {
        let components = self
            .components
            .iter()
            .filter(|c| ids.contains(&c.id))
            .map(|c| {
                let lo = c.rows.partition_point(|&r| r < rows.start);
                let hi = c.rows.partition_point(|&r| r < rows.end);
                ComponentRequest { id: c.id, pool: c.pool, keep: c.keep, rows: c.rows[lo..hi].to_vec(), best: c.best }
            })
            .filter(|c| c.pool.is_some() || c.best || !c.rows.is_empty())
            .collect();
        Self { seed: self.seed, keys: self.keys.narrowed(sessions), components }
    }

    /// Nothing is asked.
    pub fn is_empty(&self) -> bool {
        self.components.is_empty()
    }
}

/// A pair offered to a keyed draw.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DrawCandidate {
    /// Its component.
    pub component: usize,
    /// The pair (row, column), in the indices of the runs (fleet indices for a fleet).
    pub pair: [usize; 2],
    /// Its key (uniform picks), or 0.
    pub key: u64,
    /// The metric's rank of the pair (row picks), or 0.
    pub rank: f64,
    /// δ of the pair.
    pub distance: f64,
    /// Its two times, seconds (each on its session's clock, from tiles).
    pub times_s: [f64; 2],
}

impl DrawCandidate {
    /// Closer first, then the earlier pair.
    fn closer(&self, other: &Self) -> bool {
        self.rank.total_cmp(&other.rank).then(self.pair.cmp(&other.pair)).is_lt()
    }
}

/// What one holder of runs offers a pass of a keyed draw.
#[derive(Debug, Clone, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DrawCandidates {
    /// Pairs with a key at most their component's threshold.
    pub pool: Vec<DrawCandidate>,
    /// The closest pair of each requested row of each component (among the holder's runs).
    pub rows: Vec<DrawCandidate>,
    /// The closest pair of each component that asked for it (among the holder's runs).
    pub best: Vec<DrawCandidate>,
}

impl DrawCandidates {
    /// Adds `other`'s offers (the closer of two offers for one row or component is kept when
    /// the draw reads them).
    pub fn absorb(&mut self, other: Self) {
        self.pool.extend(other.pool);
        self.rows.extend(other.rows);
        self.best.extend(other.best);
    }

    /// Of the pool (reduced), the `keep(component)` smallest keys of each component.
    pub(crate) fn keep_smallest(&mut self, keep: &dyn Fn(usize) -> u64) {
        let mut run: (usize, u64) = (usize::MAX, 0);
        self.pool.retain(|o| {
            if run.0 != o.component {
                run = (o.component, 0);
            }
            run.1 += 1;
            run.1 <= keep(o.component)
        });
    }

    /// One offer per (component, row) and per component; the pool sorted by (component, key).
    fn reduce(&mut self) {
        let keep_closest = |list: &mut Vec<DrawCandidate>, key: &dyn Fn(&DrawCandidate) -> (usize, usize)| {
            list.sort_by(|a, b| key(a).cmp(&key(b)).then(a.rank.total_cmp(&b.rank)).then(a.pair.cmp(&b.pair)));
            list.dedup_by(|later, first| key(later) == key(first));
        };
        keep_closest(&mut self.rows, &|c| (c.component, c.pair[0]));
        keep_closest(&mut self.best, &|c| (c.component, 0));
        self.pool.sort_by_key(|a| (a.component, a.key, a.pair));
        self.pool.dedup_by(|a, b| a.component == b.component && a.pair == b.pair);
    }
}

/// A run as a keyed draw sees it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DrawRun {
    pub start: usize,
    pub end: usize,
    pub component: usize,
    /// The run's closest column (among its cells here).
    pub closest: usize,
}

/// Whoever holds runs: the whole trajectory in memory, or one tile.
pub(crate) trait RunHolder: Sync {
    /// The rows held (indices of the runs), in stretches, sorted and apart.
    fn rows(&self) -> Vec<std::ops::Range<usize>>;
    /// The runs of row `i`, in column order.
    fn for_each_run(&self, i: usize, f: &mut dyn FnMut(DrawRun));
    /// δ and the metric's rank of pair (i, j).
    fn measure(&self, i: usize, j: usize) -> (f64, f64);
    /// The times of pair (i, j).
    fn times_s(&self, i: usize, j: usize) -> [f64; 2];
    /// The last column of the whole run of row `i` that starts on the diagonal and ends here at
    /// `end` (a tile reads past its last column).
    fn diagonal_end(&self, i: usize, end: usize) -> usize;
    /// Whether the run of row `i` starting here at `start` continues a run that starts on the
    /// diagonal elsewhere (whose holder offers it).
    fn continues_diagonal(&self, i: usize, start: usize) -> bool;
}

/// The closest column after the farthest point of a diagonal run `start..=end` (by δ, the
/// earliest of equals): where the path comes back along the same way, or the last column.
fn return_column(holder: &dyn RunHolder, i: usize, start: usize, end: usize) -> usize {
    let distances: Vec<f64> = (start..=end).map(|j| holder.measure(i, j).0).collect();
    let farthest = distances.iter().enumerate().fold(0, |best, (k, &d)| if d > distances[best] { k } else { best });
    let back = distances[farthest..]
        .iter()
        .enumerate()
        .fold(farthest, |best, (k, &d)| if d < distances[best] { farthest + k } else { best });
    start + back
}

/// The offers of `holder` to a pass: O(its runs + the pairs offered, + the length of each
/// diagonal run asked for its return column), rows in parallel.
///
/// # Errors
/// [`Error::Interrupted`] when the [`Interrupt`] installed on this thread is interrupted: it is
/// looked at before every row.
pub(crate) fn draw_candidates(holder: &dyn RunHolder, request: &DrawRequest) -> Result<DrawCandidates> {
    // The request by component id, looked up once a run.
    let mut index: Vec<&ComponentRequest> = request.components.iter().collect();
    index.sort_unstable_by_key(|c| c.id);
    let find = |id: usize| index.binary_search_by_key(&id, |c| c.id).ok().map(|k| index[k]);
    let chunks: Vec<std::ops::Range<usize>> = holder
        .rows()
        .into_iter()
        .flat_map(|rows| {
            (rows.start..rows.end).step_by(ROWS_PER_TASK).map(move |s| s..(s + ROWS_PER_TASK).min(rows.end))
        })
        .collect();
    let interrupt = Interrupt::current();
    let parts: Vec<DrawCandidates> = chunks
        .into_par_iter()
        .map(|chunk| {
            let mut out = DrawCandidates::default();
            let mut best: BTreeMap<usize, DrawCandidate> = BTreeMap::new();
            for i in chunk {
                // One row costs its runs, its pairs offered and, on the diagonal, the run's
                // length: a parked robot's rows span the whole stop.
                interrupt.check()?;
                let mut row_best: BTreeMap<usize, DrawCandidate> = BTreeMap::new();
                holder.for_each_run(i, &mut |run| {
                    let Some(req) = find(run.component) else { return };
                    let c = run.component;
                    if let Some(threshold) = req.pool {
                        let first = run.start.max(i + 1);
                        if first <= run.end {
                            run_keys(request.seed, &request.keys, i, first, run.end, threshold, &mut |j, key| {
                                let (distance, _) = holder.measure(i, j);
                                let times_s = holder.times_s(i, j);
                                out.pool.push(DrawCandidate {
                                    component: c,
                                    pair: [i, j],
                                    key,
                                    rank: 0.0,
                                    distance,
                                    times_s,
                                });
                            });
                        }
                    }
                    let wants_row = req.rows.binary_search(&i).is_ok();
                    if !(wants_row || req.best) {
                        return;
                    }
                    let column = if run.start == i {
                        let end = holder.diagonal_end(i, run.end);
                        (end > i).then(|| return_column(holder, i, i + 1, end))
                    } else if holder.continues_diagonal(i, run.start) {
                        None
                    } else {
                        Some(run.closest)
                    };
                    let Some(j) = column else { return };
                    let (distance, rank) = holder.measure(i, j);
                    let offer = DrawCandidate {
                        component: c,
                        pair: [i, j],
                        key: 0,
                        rank,
                        distance,
                        times_s: holder.times_s(i, j),
                    };
                    if wants_row {
                        let slot = row_best.entry(c).or_insert(offer);
                        if offer.closer(slot) {
                            *slot = offer;
                        }
                    }
                    if req.best {
                        let slot = best.entry(c).or_insert(offer);
                        if offer.closer(slot) {
                            *slot = offer;
                        }
                    }
                });
                out.rows.extend(row_best.into_values());
            }
            out.best.extend(best.into_values());
            Ok(out)
        })
        .collect::<Result<_>>()?;
    let mut all = DrawCandidates::default();
    for part in parts {
        all.pool.extend(part.pool);
        all.rows.extend(part.rows);
        all.best.extend(part.best);
    }
    all.reduce();
    all.keep_smallest(&|id| find(id).map_or(u64::MAX, |c| c.keep));
    Ok(all)
}

/// A pair a keyed draw chose.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DrawnPair {
    /// Its component.
    pub component: usize,
    /// The pair (row, column).
    pub pair: [usize; 2],
    /// δ of the pair.
    pub distance: f64,
    /// Its times, seconds (each on its session's clock, from tiles).
    pub times_s: [f64; 2],
}

/// A component of a keyed draw.
#[derive(Debug, Clone)]
struct Group {
    id: usize,
    quota: u64,
    /// Of the quota, the closest pairs of rows (nearest-then-uniform; the quota for the others).
    near: u64,
    /// The stratification offset (dispersed samplers; 0 for a group without picks).
    offset: f64,
    /// The pool threshold asked last.
    pool: Option<u64>,
    /// The rows whose closest pair is asked (the dispersed samplers).
    rows: Vec<usize>,
    /// Whether the closest pair over all rows is asked (closest-first, trivial components).
    best: bool,
}

/// A draw of samples from loop components by keys (see the module docs): plan, passes over
/// whoever holds the runs, and the samples, the same for any holders.
///
/// # Examples
/// ```
/// use loops_core::sample::KeyedDraw;
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, UrbanDrive, find_loops, sample_loops};
/// let drive = UrbanDrive { duration_s: 600.0, ..UrbanDrive::default() }.generate()?;
/// let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
/// let sampler = Sampler::new(SamplerKind::Rho, SampleSize::Budget(50), 3);
/// // sample_loops runs the passes over the loops in memory; tiles of a fleet run the same.
/// let draw = KeyedDraw::new(&sampler, &loops_core::sample::draw_stats(&loops), &|_| true)?;
/// assert_eq!(draw.groups(), sample_loops(&drive.trajectory, &Euclidean, &loops, &sampler)?.groups());
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct KeyedDraw {
    kind: SamplerKind,
    size: SampleSize,
    seed: u64,
    keys: KeyLayout,
    stats: Vec<DrawStats>,
    groups: Vec<Group>,
    /// σ_α's threshold (all groups share it).
    alpha: Option<u64>,
    available: u64,
    warnings: Vec<SampleWarning>,
    candidates: DrawCandidates,
    /// The request still to answer (none after the last pass).
    pending: Option<DrawRequest>,
    picks: Option<Vec<DrawnPair>>,
}

/// The threshold leaving `need` of `total` keys below it with a margin: ≥ need with
/// overwhelming probability.
fn threshold_for(need: u64, total: u64) -> u64 {
    let n = need as f64;
    let fraction = (n + 4.0 * n.sqrt() + 8.0) / total.max(1) as f64;
    threshold_of_fraction(fraction)
}

fn threshold_of_fraction(fraction: f64) -> u64 {
    if fraction >= 1.0 { u64::MAX } else { (fraction * 18_446_744_073_709_551_616.0) as u64 }
}

fn fraction_of(threshold: u64) -> f64 {
    (threshold as f64 + 1.0) / 18_446_744_073_709_551_616.0
}

impl KeyedDraw {
    /// The draw of `sampler` over the components with these statistics (by id) that `keep`
    /// accepts: quotas and the first pass's request.
    ///
    /// # Errors
    /// As [`sample_loops`](crate::sample_loops) for the samplers of components (`one`, `rho`,
    /// `rho-dispersed`, `alpha`, `closest-first`, `closest-then-spread`, `nearest-then-uniform`);
    /// [`Error::NotApplicable`] for a baseline.
    pub fn new(sampler: &Sampler, stats: &[DrawStats], keep: &dyn Fn(usize) -> bool) -> Result<Self> {
        Self::with_keys(sampler, stats, keep, KeyLayout::default())
    }

    /// As [`new`](Self::new), with pairs and components keyed by `keys` (a fleet's sessions:
    /// [`KeyLayout::sessions`]).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_keys(
        sampler: &Sampler,
        stats: &[DrawStats],
        keep: &dyn Fn(usize) -> bool,
        keys: KeyLayout,
    ) -> Result<Self> {
        let kind = sampler.kind;
        if kind.is_baseline() {
            return Err(Error::NotApplicable {
                option: "a keyed draw",
                to: format!("the {kind} baseline"),
                reason: "a baseline's rule runs over the whole trajectory; use nearest-then-uniform (the default), \
                         one, rho, rho-dispersed, alpha, closest-first or closest-then-spread",
            });
        }
        sampler.size.validate(kind)?;
        sampler.check_applicable()?;
        let wanted = |c: usize| keep(c) && !(sampler.skip_trivial && stats[c].trivial) && stats[c].pairs > 0;
        let ids: Vec<usize> = (0..stats.len()).filter(|&c| wanted(c)).collect();
        let caps: Vec<u64> = ids.iter().map(|&c| stats[c].pairs).collect();
        let available: u64 = caps.iter().sum();
        let mut warnings = Vec::new();
        // Each component's own word (its permanent random number, rounding a rate's quota, and
        // its rows' stratification offset) and its session pair's numbers (a budget's picks),
        // whatever else the draw holds.
        let words: Vec<u64> = ids.iter().map(|&c| keys.component_word(sampler.seed, &stats[c])).collect();
        let numbers = keys.numbers(sampler.seed, ids.iter().map(|&c| &stats[c]), &words);
        let (groups, alpha) = if kind == SamplerKind::Alpha {
            let (count, threshold) = match sampler.size {
                SampleSize::Rate(rate) => {
                    let t = if rate >= 1.0 {
                        u64::MAX
                    } else {
                        ((rate * 18_446_744_073_709_551_616.0) as u64).saturating_sub(1)
                    };
                    (rate * available as f64, t)
                }
                SampleSize::Budget(budget) => {
                    if budget as u64 > available {
                        warnings.push(SampleWarning::BudgetAboveAvailable { budget, available });
                    }
                    let need = (budget as u64).min(available);
                    (need as f64, if need == available { u64::MAX } else { threshold_for(need, available) })
                }
            };
            check_count("samples", sampler.size, count, SAMPLE_BYTES)?;
            let groups = ids
                .iter()
                .map(|&id| Group {
                    id,
                    quota: 0,
                    near: 0,
                    offset: 0.0,
                    pool: Some(threshold),
                    rows: Vec::new(),
                    best: false,
                })
                .collect();
            (groups, Some(threshold))
        } else {
            // (all picks, of which rows' closest pairs) per group.
            let quotas: Vec<(u64, u64)> = if kind == SamplerKind::NearestThenUniform {
                let rows: Vec<u64> = ids.iter().map(|&c| stats[c].row_count() as u64).collect();
                let splits = nearest_then_uniform_quotas(&rows, &caps, sampler.size, &numbers, &mut warnings);
                let total = splits.iter().map(|s| s.total()).sum::<u64>();
                check_count("samples", sampler.size, total as f64, SAMPLE_BYTES)?;
                splits.into_iter().map(|s| (s.total(), s.near)).collect()
            } else {
                let rows = || ids.iter().map(|&c| stats[c].row_count() as f64).collect();
                let quotas = sampler.group_quotas(rows, &caps, &numbers, &mut warnings)?;
                quotas.into_iter().map(|q| (q, q)).collect()
            };
            let groups = ids
                .iter()
                .zip(quotas)
                .zip(&words)
                .map(|((&id, (quota, near)), &word)| {
                    let s = &stats[id];
                    let mut group = Group { id, quota, near, offset: 0.0, pool: None, rows: Vec::new(), best: false };
                    if quota == 0 {
                        return group;
                    }
                    let offset = unit(mix(word ^ OFFSET_TAG));
                    group.offset = offset;
                    let r0 = s.rows[0];
                    let count = s.row_count();
                    match kind {
                        SamplerKind::One | SamplerKind::Rho => group.pool = Some(threshold_for(quota, s.pairs)),
                        SamplerKind::NearestThenUniform => {
                            (group.rows, group.best) = closest_then_stratified(s, near as usize, offset);
                            if quota > near {
                                group.pool = Some(threshold_for(quota, s.pairs));
                            }
                        }
                        _ if quota as usize > count => {
                            group.rows = (s.rows[0]..=s.rows[1]).collect();
                            group.pool = Some(threshold_for(quota - count as u64, s.pairs));
                        }
                        SamplerKind::RhoDispersed => {
                            let mut rows = BTreeMap::new();
                            for idx in stratified(quota as usize, count, offset) {
                                let r = r0 + idx;
                                rows.insert(r, ());
                                if s.trivial && r > r0 {
                                    rows.insert(r - 1, ());
                                }
                            }
                            group.rows = rows.into_keys().collect();
                        }
                        _ => {
                            // Closest-first and closest-then-spread.
                            (group.rows, group.best) = closest_then_stratified(s, quota as usize, offset);
                        }
                    }
                    group
                })
                .collect();
            (groups, None)
        };
        let mut draw = Self {
            kind,
            size: sampler.size,
            seed: sampler.seed,
            keys,
            stats: stats.to_vec(),
            groups,
            alpha,
            available,
            warnings,
            candidates: DrawCandidates::default(),
            pending: None,
            picks: None,
        };
        draw.pending = Some(draw.request_all());
        Ok(draw)
    }

    /// How many of a group's pool a holder need offer.
    fn keep(&self, g: &Group) -> u64 {
        if self.alpha.is_some() { u64::MAX } else { g.quota }
    }

    /// Every group's current request.
    fn request_all(&self) -> DrawRequest {
        let components = self
            .groups
            .iter()
            .filter(|g| g.pool.is_some() || g.best || !g.rows.is_empty())
            .map(|g| ComponentRequest {
                id: g.id,
                pool: g.pool,
                keep: self.keep(g),
                rows: g.rows.clone(),
                best: g.best,
            })
            .collect();
        DrawRequest { seed: self.seed, keys: self.keys.clone(), components }
    }

    /// The sampler.
    pub fn sampler(&self) -> SamplerKind {
        self.kind
    }

    /// Number of groups (components with a pair to sample; 0 for σ_α).
    pub fn groups(&self) -> usize {
        if self.alpha.is_some() { 0 } else { self.groups.len() }
    }

    /// Number of candidate pairs.
    pub fn available(&self) -> u64 {
        self.available
    }

    /// Warnings of the quotas (a budget below the groups, or above the pairs).
    pub fn warnings(&self) -> &[SampleWarning] {
        &self.warnings
    }

    /// What the next pass must offer ([`absorb`](Self::absorb)), or `None` when the draw is
    /// done.
    pub fn request(&self) -> Option<&DrawRequest> {
        self.pending.as_ref()
    }

    /// Takes the offers of every holder of runs to the pending request (together, or one
    /// holder at a time), then, once all of them are in ([`complete`](Self::complete)), works
    /// out the samples or the next request.
    pub fn absorb(&mut self, offers: DrawCandidates) {
        self.candidates.absorb(offers);
    }

    /// Ends the pending pass: the samples, or a next request for components whose pool came
    /// back short (rare: the thresholds leave a margin of four standard deviations).
    pub fn complete(&mut self) {
        if self.pending.take().is_none() {
            return;
        }
        self.candidates.reduce();
        match self.finish() {
            Ok(picks) => self.picks = Some(picks),
            Err(short) => {
                // Grow the thresholds of the short groups; drop their pools (the next pass
                // offers a superset).
                let short: HashSet<usize> = short.into_iter().collect();
                if let Some(t) = self.alpha {
                    let grown = threshold_of_fraction(4.0 * fraction_of(t));
                    self.alpha = Some(grown);
                    self.groups.iter_mut().for_each(|g| g.pool = Some(grown));
                    self.candidates.pool.clear();
                } else {
                    for g in self.groups.iter_mut().filter(|g| short.contains(&g.id)) {
                        let s = &self.stats[g.id];
                        g.pool = Some(match g.pool {
                            Some(t) => threshold_of_fraction(4.0 * fraction_of(t)),
                            None => threshold_for(g.quota, s.pairs),
                        });
                    }
                    self.candidates.pool.retain(|c| !short.contains(&c.component));
                }
                let components = self
                    .groups
                    .iter()
                    .filter(|g| short.contains(&g.id) || self.alpha.is_some())
                    .map(|g| ComponentRequest {
                        id: g.id,
                        pool: g.pool,
                        keep: self.keep(g),
                        rows: Vec::new(),
                        best: false,
                    })
                    .collect();
                self.pending = Some(DrawRequest { seed: self.seed, keys: self.keys.clone(), components });
            }
        }
    }

    /// The chosen pairs, by pair, once the draw is done.
    pub fn picks(&self) -> Option<&[DrawnPair]> {
        self.picks.as_deref()
    }

    /// The picks, or the groups whose pool is short.
    fn finish(&self) -> std::result::Result<Vec<DrawnPair>, Vec<usize>> {
        let c = &self.candidates;
        let drawn = |o: &DrawCandidate| DrawnPair {
            component: o.component,
            pair: o.pair,
            distance: o.distance,
            times_s: o.times_s,
        };
        if let Some(threshold) = self.alpha {
            let mut all: Vec<&DrawCandidate> = c.pool.iter().collect();
            all.sort_by_key(|a| (a.key, a.pair));
            let picks: Vec<DrawnPair> = match self.size {
                SampleSize::Rate(_) => all.into_iter().map(drawn).collect(),
                SampleSize::Budget(budget) => {
                    let need = (budget as u64).min(self.available) as usize;
                    if all.len() < need && threshold != u64::MAX {
                        return Err(Vec::new());
                    }
                    all.into_iter().take(need).map(drawn).collect()
                }
            };
            return Ok(sorted(picks));
        }
        let pool_of = |id: usize| {
            let lo = c.pool.partition_point(|o| o.component < id);
            let hi = c.pool.partition_point(|o| o.component <= id);
            &c.pool[lo..hi]
        };
        let row_pick = |id: usize, row: usize| {
            c.rows.binary_search_by(|o| (o.component, o.pair[0]).cmp(&(id, row))).ok().map(|k| &c.rows[k])
        };
        let mut picks = Vec::new();
        let mut short = Vec::new();
        for g in &self.groups {
            let s = &self.stats[g.id];
            let q = g.quota as usize;
            if q == 0 {
                continue;
            }
            // A row with no pair off the diagonal (the last row of a trivial component) gives
            // its place to the row before, which always has one.
            let offer_of = |row: usize| {
                row_pick(g.id, row)
                    .or_else(|| (s.trivial && row > s.rows[0]).then(|| row_pick(g.id, row - 1)).flatten())
            };
            let mut chosen: Vec<DrawCandidate> = Vec::with_capacity(q);
            let mut seen: HashSet<[usize; 2]> = HashSet::new();
            let count = s.row_count();
            // The component's closest pair, then `n` − 1 other rows stratified around its row.
            let closest_then_rows = |chosen: &mut Vec<DrawCandidate>, seen: &mut HashSet<[usize; 2]>, n: usize| {
                let best = if s.trivial {
                    c.best.iter().find(|o| o.component == g.id)
                } else {
                    row_pick(g.id, s.closest_pair[0])
                };
                if let Some(best) = best {
                    push(chosen, seen, Some(best));
                    let b = best.pair[0];
                    for idx in stratified(n - 1, count - 1, g.offset) {
                        let r = s.rows[0] + idx;
                        push(chosen, seen, offer_of(if r >= b { r + 1 } else { r }));
                    }
                }
            };
            match self.kind {
                SamplerKind::One | SamplerKind::Rho => {}
                SamplerKind::NearestThenUniform => closest_then_rows(&mut chosen, &mut seen, g.near as usize),
                _ if q > count => {
                    for row in s.rows[0]..=s.rows[1] {
                        push(&mut chosen, &mut seen, offer_of(row));
                    }
                }
                SamplerKind::RhoDispersed => {
                    for idx in stratified(q, count, g.offset) {
                        push(&mut chosen, &mut seen, offer_of(s.rows[0] + idx));
                    }
                }
                // Closest-first and closest-then-spread.
                _ => closest_then_rows(&mut chosen, &mut seen, q),
            }
            // The rest from the pool, smallest keys first.
            for o in pool_of(g.id) {
                if chosen.len() >= q {
                    break;
                }
                push(&mut chosen, &mut seen, Some(o));
            }
            if chosen.len() < q && g.pool != Some(u64::MAX) {
                short.push(g.id);
                continue;
            }
            picks.extend(chosen.iter().map(drawn));
        }
        if short.is_empty() { Ok(sorted(picks)) } else { Err(short) }
    }
}

/// The rows whose closest pairs closest-first, closest-then-spread and nearest-then-uniform
/// ask of component `s` for `n` (≥ 1, at most its rows) such picks: its closest pair's row (for
/// a trivial component, the closest pair over all rows: the returned flag), then `n` − 1 rows
/// stratified around it (a trivial component's neighbours too, which stand in for a row with no
/// pair off the diagonal).
fn closest_then_stratified(s: &DrawStats, n: usize, offset: f64) -> (Vec<usize>, bool) {
    let r0 = s.rows[0];
    let mut rows = BTreeMap::new();
    if !s.trivial {
        rows.insert(s.closest_pair[0], ());
    }
    for idx in stratified(n - 1, s.row_count() - 1, offset) {
        let r = r0 + idx;
        if s.trivial {
            for row in [r.saturating_sub(1).max(r0), r, r + 1] {
                rows.insert(row, ());
            }
        } else {
            rows.insert(if r >= s.closest_pair[0] { r + 1 } else { r }, ());
        }
    }
    (rows.into_keys().collect(), s.trivial)
}

/// Takes `offer` unless that pair is taken already.
fn push(chosen: &mut Vec<DrawCandidate>, seen: &mut HashSet<[usize; 2]>, offer: Option<&DrawCandidate>) {
    if let Some(o) = offer
        && seen.insert(o.pair)
    {
        chosen.push(*o);
    }
}

fn sorted(mut picks: Vec<DrawnPair>) -> Vec<DrawnPair> {
    picks.sort_by_key(|a| a.pair);
    picks
}

/// `q` row indices of `rows`, stratified: ⌊(k + offset) · rows / q⌋.
fn stratified(q: usize, rows: usize, offset: f64) -> impl Iterator<Item = usize> {
    (0..q).map(move |k| (((k as f64 + offset) * rows as f64 / q as f64) as usize).min(rows.saturating_sub(1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key of (row, column) as the module defines it, word by word: bit 63 − ℓ is bit
    /// `column mod 64` of the ℓ-th word of the block's stream.
    fn key_by_definition(seed: u64, row: usize, column: usize) -> u64 {
        let mut stream = KeyStream::new(seed, row as u64, (column / KEY_BLOCK) as u64);
        (0..64).fold(0u64, |key, l| key | (((stream.next_word() >> (column % KEY_BLOCK)) & 1) << (63 - l)))
    }

    #[test]
    fn run_keys_are_the_keys_at_most_the_threshold() {
        let mut hits = 0;
        for (seed, row, start, end) in [(1, 0, 1, 1), (7, 5, 3, 200), (9, 1000, 60, 70), (3, 42, 128, 255)] {
            let keys: Vec<u64> = (start..=end).map(|j| key_by_definition(seed, row, j)).collect();
            let mut sorted = keys.clone();
            sorted.sort_unstable();
            // Thresholds at, between and around the keys themselves, and the extremes.
            let mut thresholds = vec![0, 1, u64::MAX / 1000, u64::MAX / 3, u64::MAX];
            thresholds.extend([sorted[0], sorted[sorted.len() / 2], sorted[sorted.len() - 1].saturating_sub(1)]);
            for threshold in thresholds {
                let want: Vec<(usize, u64)> =
                    (start..=end).zip(keys.iter().copied()).filter(|&(_, k)| k <= threshold).collect();
                let mut got = Vec::new();
                run_keys(seed, &KeyLayout::default(), row, start, end, threshold, &mut |j, k| got.push((j, k)));
                assert_eq!(got, want, "seed {seed} row {row} {start}..={end} threshold {threshold:#x}");
                hits += got.len();
            }
            assert_eq!(pair_key(seed, row, end), keys[keys.len() - 1]);
        }
        assert!(hits > 100, "{hits}");
    }
}

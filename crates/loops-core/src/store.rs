//! A fleet's loops kept up to date as sessions come, are corrected and go: [`FleetStore`], the
//! state of a fleet's tiles (see [`tile`](crate::tile::TileSummary)) that an update changes at the
//! cost of the sessions it changes.
//!
//! The store holds its sessions (name, content fingerprint, blocks: what planning needs) in
//! name order, and the summary and share of τ of every tile of their plan, in fleet indices of
//! that order. An update ([`FleetStore::update`]: sessions added or replaced by name, others
//! removed) keeps the tiles of every pair of unchanged sessions (moved to the new fleet
//! indices: a tile depends on its two sessions alone), drops those of replaced and removed
//! sessions, and scans only the tiles that hold a new or replaced session (new × old, new ×
//! new). The answer follows from what the store keeps besides: the merge of each session
//! pair's tiles (components never join across pairs, so an update merges the pairs it scanned
//! and moves the others; [`FleetStore::loops`] puts them together), τ of each session (the new
//! tiles' shares added), and the runs of the tiles it scanned, from which samples are drawn by
//! keys ([`FleetStore::samples`]) without a rescan.
//!
//! **Same answer as from scratch.** After any sequence of updates, the components, the overlap
//! matrix, τ and the samples are those of [`find_fleet_loops`](crate::fleet::find_fleet_loops) and
//! [`sample_fleet`](crate::fleet::sample_fleet) over the store's sessions in name order (areas to
//! rounding, as for any tiling; everything else exactly), and the store itself (its tiles,
//! bit for bit) does not depend on the order of the updates.
//!
//! **Queries.** Which sessions pass within a radius of a place, and when
//! ([`FleetStore::near`], a [`Place`] in the map plane); which sessions revisit a session
//! ([`StoreLoops::revisits`], from the overlap matrix); the components the last update added
//! ([`FleetStore::added_components`]).
//!
//! The store holds no poses: an update and a draw ask a *source* for the stored sessions they
//! read (`FnMut(&StoreSession) -> Result<Trajectory>`), and check what comes back against the
//! session's pose count and fingerprint. Where the poses live (a folder of tables, a cluster's
//! storage) is the caller's: `loops_io::store` keeps them beside the tables.
//!
//! # Examples
//! ```
//! use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops};
//! use loops_core::store::{FleetStore, StoreSession, StoreSettings};
//! use loops_core::{Euclidean, Trajectory};
//! let line = |t0: f64, y: f64| Trajectory::from_points(vec![t0, t0 + 1.0, t0 + 2.0], &[[0.0, y], [5.0, y], [10.0, y]]);
//! let (monday, tuesday) = (line(0.0, 0.0)?, line(100.0, 0.5)?);
//! let mut store = FleetStore::new(StoreSettings { block: 2, ..StoreSettings::new(1.0) })?;
//! let mut no_poses = |s: &StoreSession| -> loops_core::Result<Trajectory> { unreachable!("{}", s.name) };
//! store.update(vec![("monday".into(), monday.clone())], &[], &mut no_poses)?;
//! // Tuesday's tiles with Monday need Monday's poses: the source gives them.
//! let mut source = |s: &StoreSession| -> loops_core::Result<Trajectory> {
//!     assert_eq!(s.name, "monday");
//!     Ok(monday.clone())
//! };
//! let update = store.update(vec![("tuesday".into(), tuesday.clone())], &[], &mut source)?;
//! assert_eq!(update.added, ["tuesday"]);
//! let loops = store.loops()?;
//! let fleet = Fleet::new(vec![("monday".into(), monday), ("tuesday".into(), tuesday)])?;
//! let scratch = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
//! assert_eq!(loops.components().len(), scratch.components().len());
//! # Ok::<(), loops_core::Error>(())
//! ```

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::{Arc, Mutex, OnceLock};

use rayon::prelude::*;

use crate::draw::SampleWarning;
use crate::error::{Error, Result};
use crate::fleet::{FleetComponent, FleetSample, SessionPair};
use crate::place::{Pass, Place, check_plane, check_radius, passes_within};
use crate::sample::{
    ComponentRequest, DrawCandidate, DrawCandidates, DrawRequest, KeyLayout, KeyedDraw, Sampler, SamplerKind,
};
use crate::separation::Separation;
use crate::spec::{MetricSpec, with_metric};
use crate::sublevel::check_gamma;
use crate::tile::draw::{TileDuration, TileRuns, draw_session_tile, draw_tile_runs};
use crate::tile::{
    JoinedMerges, MergedComponent, MergedLoops, SessionBlocks, Tile, TileKeep, TileMerge, TileSummary,
    plan_session_tiles_touching,
};
use crate::trajectory::{Manifold, Trajectory};

/// The version of a store's layout (its tables and their meaning). Version 2 adds what a
/// store keeps of its answer (the merge of each session pair's tiles, the runs of each tile);
/// version 3 keeps its tiles by part, each tile in its sessions' own indices
/// ([`StoredTile::local`]), so that an update writes only the parts that change; version 4
/// keeps the merges of its session pairs by part too, each in its sessions' own indices
/// ([`MergedLoops::local`]); version 5 keeps the sessions' pose files in one folder beside
/// the states, each written once, so that an update touches only the pose files of the
/// sessions it adds, replaces or removes. Stores of versions 1 to 4 read back (version 1
/// without what it keeps of its answer); one of a later version is refused.
pub const STORE_FORMAT_VERSION: u16 = 5;

/// What a store's answer depends on, fixed when the store is made.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreSettings {
    /// The metric δ (in serde, by its text form).
    #[cfg_attr(feature = "serde", serde(with = "metric_text"))]
    pub metric: MetricSpec,
    /// γ, in the metric's unit.
    pub gamma: f64,
    /// The revisit separation within a session.
    pub separation: Separation,
    /// Poses per block of a session: tiles are blocks × blocks.
    pub block: usize,
}

impl StoreSettings {
    /// Poses per block when none is chosen: the unit the Dask runner cuts sessions into.
    pub const DEFAULT_BLOCK: usize = 50_000;

    /// γ with the Euclidean metric, no separation and [`DEFAULT_BLOCK`](Self::DEFAULT_BLOCK).
    pub fn new(gamma: f64) -> Self {
        Self { metric: MetricSpec::Euclidean, gamma, separation: Separation::NONE, block: Self::DEFAULT_BLOCK }
    }

    /// γ, the separation and the block are valid.
    ///
    /// # Errors
    /// [`Error::InvalidGamma`]; [`Error::InvalidSeparation`]; [`Error::InvalidParameter`] for a
    /// block of 0 poses.
    pub fn check(&self) -> Result<()> {
        check_gamma(self.gamma)?;
        self.separation.check()?;
        if self.block == 0 {
            return Err(Error::InvalidParameter { name: "block", value: 0.0, expected: "at least 1 pose" });
        }
        Ok(())
    }
}

/// One session of a store: what planning and checking it need, not its poses.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreSession {
    /// Its name (sessions are kept in name order).
    pub name: String,
    /// [`session_fingerprint`] of its trajectory.
    pub fingerprint: u64,
    /// What its points are.
    pub manifold: Manifold,
    /// The times of its first and last pose, seconds, on its own clock.
    pub times_s: [f64; 2],
    /// Its blocks (pose count, span, dimension, bounding balls).
    pub blocks: SessionBlocks,
}

impl StoreSession {
    /// The session of `trajectory` under `settings`: O(poses).
    ///
    /// # Errors
    /// The metric's errors on the trajectory; [`Error::InvalidParameter`] for a block of 0.
    pub fn new(name: String, trajectory: &Trajectory, settings: &StoreSettings) -> Result<Self> {
        with_metric!(&settings.metric, m => trajectory.check_metric(m))?;
        let blocks = with_metric!(&settings.metric, m => SessionBlocks::new(trajectory, m, settings.block))?;
        let times = trajectory.timestamps_s();
        Ok(Self {
            name,
            fingerprint: session_fingerprint(trajectory),
            manifold: trajectory.manifold(),
            times_s: [times[0], times[times.len() - 1]],
            blocks,
        })
    }

    /// Number of poses.
    pub fn poses(&self) -> usize {
        self.blocks.poses
    }
}

/// A 64-bit fingerprint of a trajectory's content: its manifold, dimension, times and
/// coordinates, bit for bit. Two trajectories with the same fingerprint are taken as the same
/// session (an update that gives a session again unchanged scans nothing). O(poses).
///
/// # Examples
/// ```
/// use loops_core::store::session_fingerprint;
/// use loops_core::Trajectory;
/// let a = Trajectory::from_points(vec![0.0, 1.0], &[[0.0, 0.0], [1.0, 0.0]])?;
/// let b = Trajectory::from_points(vec![0.0, 1.0], &[[0.0, 0.0], [1.0, 1e-12]])?;
/// assert_eq!(session_fingerprint(&a), session_fingerprint(&a.clone()));
/// assert_ne!(session_fingerprint(&a), session_fingerprint(&b));
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn session_fingerprint(trajectory: &Trajectory) -> u64 {
    let mut h = Fingerprint::new(0x6c6f_6f70_732d_7374);
    trajectory.manifold().name().bytes().for_each(|b| h.eat(u64::from(b)));
    h.eat(trajectory.dim() as u64);
    h.eat(trajectory.len() as u64);
    trajectory.timestamps_s().iter().for_each(|t| h.eat(t.to_bits()));
    trajectory.coords().iter().for_each(|x| h.eat(x.to_bits()));
    h.finish()
}

/// A 64-bit fingerprint of a sequence of words: SplitMix64's finaliser over each, chained.
struct Fingerprint(u64);

impl Fingerprint {
    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn new(seed: u64) -> Self {
        Self(Self::mix(seed))
    }

    fn eat(&mut self, word: u64) {
        self.0 = Self::mix(self.0 ^ word).wrapping_add(0x9E37_79B9_7F4A_7C15);
    }

    /// The settings' metric (by its text form), γ, separation and block.
    fn eat_settings(&mut self, settings: &StoreSettings) {
        settings.metric.to_string().bytes().for_each(|b| self.eat(u64::from(b)));
        self.eat(settings.gamma.to_bits());
        self.eat(settings.separation.path.to_bits());
        self.eat(settings.separation.time_s.to_bits());
        self.eat(settings.block as u64);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

/// A tile of a store: its summary and its share of τ, in the store's fleet indices.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoredTile {
    /// What the merge reads.
    pub summary: TileSummary,
    /// What τ adds up.
    pub duration: TileDuration,
}

impl StoredTile {
    /// The tile.
    pub fn tile(&self) -> &Tile {
        &self.summary.tile
    }

    /// The tile as a fleet of its two sessions alone holds it, each from pose 0 (sessions
    /// `[0, 0]` within one session, else `[0, 1]`), given where its sessions start in the
    /// store's fleet: what stays the same while other sessions come and go, and what a store
    /// saves of a tile. [`placed`](Self::placed) puts it back. O(its components and edge runs).
    pub fn local(&self, starts: [usize; 2]) -> Self {
        let [a, b] = self.tile().sessions;
        let mut local = self.clone();
        local.move_to([0, usize::from(a != b)], [-(starts[0] as isize), -(starts[1] as isize)]);
        local
    }

    /// A tile of [`local`](Self::local) form placed as the tile of the store's sessions
    /// `sessions`, which start at `starts` in its fleet. O(its components and edge runs).
    pub fn placed(mut self, sessions: [usize; 2], starts: [usize; 2]) -> Self {
        self.move_to(sessions, [starts[0] as isize, starts[1] as isize]);
        self
    }

    /// Renumbers the tile's sessions `sessions` and moves its rows and columns by `shifts`
    /// (fleet indices): what a rescan at the new place gives, since a tile reads its two
    /// sessions alone. O(its components and edge runs).
    fn move_to(&mut self, sessions: [usize; 2], shifts: [isize; 2]) {
        let at = |x: usize, side: usize| x.wrapping_add_signed(shifts[side]);
        let pair = |x: [usize; 2]| [at(x[0], 0), at(x[1], 1)];
        let tile = self.summary.tile.moved(sessions, shifts);
        for c in &mut self.summary.components {
            c.rows = [at(c.rows[0], 0), at(c.rows[1], 0)];
            c.columns = [at(c.columns[0], 1), at(c.columns[1], 1)];
            (c.closest, c.first) = (pair(c.closest), pair(c.first));
        }
        for e in &mut self.summary.edges {
            (e.row, e.start, e.end) = (at(e.row, 0), at(e.start, 1), at(e.end, 1));
        }
        self.summary.tile = tile.clone();
        self.duration.tile = tile;
    }
}

/// A tile as a store saved it, in its sessions' own indices ([`StoredTile::local`],
/// [`TileRuns::local`]), read when an update or a draw first needs it: what a store read back
/// lazily ([`FleetStore::from_saved_lazily`]) holds of a tile until then. Whoever reads the
/// saved form implements it (`loops_io::store` reads the bytes of a tile part).
pub trait SavedTile: Send + Sync + std::fmt::Debug {
    /// Its summary and share of τ, in its sessions' own indices.
    ///
    /// # Errors
    /// What cannot be read back.
    fn stored(&self) -> Result<StoredTile>;

    /// Its runs in its sessions' own indices, where it was saved with them.
    ///
    /// # Errors
    /// What cannot be read back.
    fn runs(&self) -> Result<Option<TileRuns>>;
}

/// One of a store's tiles ([`FleetStore::tiles`]): where it lies, and its summary, share of τ
/// and runs, as scanned, or read from where they were saved the first time they are asked (a
/// store read back lazily: an update that adds sessions reads none of its old tiles, a draw
/// the runs of the tiles it asks). What is read is checked to be of the tile.
#[derive(Debug, Clone)]
pub struct KeptTile {
    /// The tile, in the store's fleet indices.
    tile: Tile,
    /// Where the rest is read from, until it is.
    saved: Option<Arc<dyn SavedTile>>,
    stored: OnceLock<std::result::Result<StoredTile, String>>,
    runs: OnceLock<std::result::Result<Option<Arc<TileRuns>>, String>>,
}

impl KeptTile {
    /// A tile as scanned (or read back whole), with its runs where kept.
    fn ready(stored: StoredTile, runs: Option<Arc<TileRuns>>) -> Self {
        let tile = stored.tile().clone();
        Self { tile, saved: None, stored: OnceLock::from(Ok(stored)), runs: OnceLock::from(Ok(runs)) }
    }

    /// The tile `tile`, the rest read from `saved` when asked.
    fn saved(tile: Tile, saved: Arc<dyn SavedTile>) -> Self {
        Self { tile, saved: Some(saved), stored: OnceLock::new(), runs: OnceLock::new() }
    }

    /// The tile (its sessions, rows and columns in the store's fleet indices).
    pub fn tile(&self) -> &Tile {
        &self.tile
    }

    /// Whether its summary and share of τ have been read (scanned, or read from where they
    /// were saved).
    pub fn is_read(&self) -> bool {
        self.stored.get().is_some()
    }

    /// Where the sessions of a tile read back in their own indices as `local` start in the
    /// store's fleet, `local` checked to be of this tile's size and shape.
    fn place_of(&self, local: &Tile) -> std::result::Result<[usize; 2], String> {
        let [a, b] = self.tile.sessions;
        let fits = local.sessions == [0, usize::from(a != b)]
            && local.rows.len() == self.tile.rows.len()
            && local.columns.len() == self.tile.columns.len()
            && local.rows.start <= self.tile.rows.start
            && local.columns.start <= self.tile.columns.start;
        if !fits {
            return Err(format!("it was saved as tile {local:?}"));
        }
        Ok([self.tile.rows.start - local.rows.start, self.tile.columns.start - local.columns.start])
    }

    /// Its summary and share of τ, read where they were saved the first time.
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"fleet store"`) naming the tile, for what cannot be
    /// read back or is not of this tile (the same error each time it is asked).
    pub fn stored(&self) -> Result<&StoredTile> {
        let read = self.stored.get_or_init(|| {
            let saved = self.saved.as_ref().ok_or("it was kept without its summary")?;
            let local = saved.stored().map_err(|e| e.to_string())?;
            local.summary.check()?;
            let d = &local.duration;
            if d.tile != local.summary.tile || !d.fits_tile() {
                return Err(format!("its share of τ is not of tile {:?}", local.summary.tile));
            }
            let place = self.place_of(local.tile())?;
            Ok(local.placed(self.tile.sessions, place))
        });
        read.as_ref().map_err(|reason| self.corrupt(reason))
    }

    /// Its runs (`None` for a tile kept without them, which a draw scans again), read where
    /// they were saved the first time.
    ///
    /// # Errors
    /// As [`stored`](Self::stored).
    pub fn runs(&self) -> Result<Option<&TileRuns>> {
        let read = self.runs.get_or_init(|| {
            let Some(saved) = &self.saved else { return Ok(None) };
            let Some(local) = saved.runs().map_err(|e| e.to_string())? else { return Ok(None) };
            let place = self.place_of(local.tile())?;
            let runs = local.placed(self.tile.sessions, place);
            Ok(Some(Arc::new(runs)))
        });
        read.as_ref().map(Option::as_deref).map_err(|reason| self.corrupt(reason))
    }

    fn corrupt(&self, reason: &str) -> Error {
        Error::InvalidState { what: "fleet store", reason: format!("tile {:?}: {reason}", self.tile) }
    }

    /// Renumbers its sessions and moves it by `shifts` ([`StoredTile::move_to`]): what is read
    /// moves with it, what is not yet read is placed where the tile then is.
    fn move_to(&mut self, sessions: [usize; 2], shifts: [isize; 2]) {
        self.tile = self.tile.moved(sessions, shifts);
        if let Some(Ok(stored)) = self.stored.get_mut() {
            stored.move_to(sessions, shifts);
        }
        if let Some(Ok(Some(runs))) = self.runs.get_mut() {
            Arc::make_mut(runs).move_to(sessions, shifts);
        }
    }
}

/// Two tiles are equal when they lie alike and their summaries and shares of τ are (each read
/// where it is not yet); runs follow from the tile.
impl PartialEq for KeptTile {
    fn eq(&self, other: &Self) -> bool {
        self.tile == other.tile && matches!((self.stored(), other.stored()), (Ok(a), Ok(b)) if a == b)
    }
}

/// What an update did, by session name (each list in name order), and its tiles.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StoreUpdate {
    /// Sessions new to the store.
    pub added: Vec<String>,
    /// Sessions given anew with other content.
    pub replaced: Vec<String>,
    /// Sessions given anew with the same content (nothing to do).
    pub unchanged: Vec<String>,
    /// Sessions removed.
    pub removed: Vec<String>,
    /// Tiles scanned.
    pub tiles_scanned: usize,
    /// Tiles kept from before.
    pub tiles_kept: usize,
    /// Tiles of replaced or removed sessions dropped.
    pub tiles_dropped: usize,
}

impl StoreUpdate {
    /// Whether the update adds, replaces and removes nothing (every session given is stored
    /// with that content, and none is removed): it leaves the store exactly as it was, its
    /// [`FleetStore::last_update`] included, and a store on disk writes nothing for it.
    ///
    /// # Examples
    /// ```
    /// use loops_core::store::StoreUpdate;
    /// assert!(StoreUpdate { unchanged: vec!["monday".into()], ..StoreUpdate::default() }.changes_nothing());
    /// assert!(!StoreUpdate { removed: vec!["monday".into()], ..StoreUpdate::default() }.changes_nothing());
    /// ```
    pub fn changes_nothing(&self) -> bool {
        self.added.is_empty() && self.replaced.is_empty() && self.removed.is_empty()
    }

    /// The sessions whose tiles the update scanned: added and replaced, in name order.
    pub fn changed(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.added.iter().chain(&self.replaced).map(String::as_str).collect();
        names.sort_unstable();
        names
    }
}

/// The plan of a store's update ([`FleetStore::plan_update`]): the sessions after it, where
/// each was before, and the tiles to scan, each of which [`scan_tile`](Self::scan_tile) scans
/// on its own (on any machine that reads its two sessions), for
/// [`FleetStore::apply_update`] to put together. It holds no poses and no stored tile:
/// O(sessions + blocks + the tiles to scan), what a cluster ships to its workers (with the
/// `serde` feature).
///
/// # Examples
/// ```
/// use loops_core::store::{FleetStore, StoreSession, StoreSettings};
/// use loops_core::Trajectory;
/// let line = |t0: f64, y: f64| Trajectory::from_points(vec![t0, t0 + 1.0, t0 + 2.0], &[[0.0, y], [5.0, y], [10.0, y]]);
/// let (monday, tuesday) = (line(0.0, 0.0)?, line(100.0, 0.5)?);
/// let settings = StoreSettings { block: 2, ..StoreSettings::new(1.0) };
/// let mut store = FleetStore::new(settings)?;
/// let mut no_poses = |s: &StoreSession| -> loops_core::Result<Trajectory> { unreachable!("{}", s.name) };
/// store.update(vec![("monday".into(), monday.clone())], &[], &mut no_poses)?;
/// // Tuesday, step by step: plan, scan each tile (anywhere), apply.
/// let plan = store.plan_update(vec![StoreSession::new("tuesday".into(), &tuesday, &settings)?], &[])?;
/// let poses = |s: usize| if plan.sessions()[s].name == "monday" { &monday } else { &tuesday };
/// let scanned = (0..plan.tiles().len())
///     .map(|k| {
///         let [a, b] = plan.tiles()[k].sessions;
///         plan.scan_tile(k, [poses(a), poses(b)])
///     })
///     .collect::<loops_core::Result<Vec<_>>>()?;
/// assert_eq!(store.apply_update(&plan, scanned)?.added, ["tuesday"]);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "PlanFields"))]
pub struct UpdatePlan {
    id: u64,
    settings: StoreSettings,
    put: Vec<StoreSession>,
    remove: Vec<String>,
    sessions: Vec<StoreSession>,
    starts: Vec<usize>,
    before: Vec<Option<usize>>,
    report: StoreUpdate,
    tiles: Vec<Tile>,
}

/// A saved [`UpdatePlan`] as read, before [`UpdatePlan::check_shape`].
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct PlanFields {
    id: u64,
    settings: StoreSettings,
    put: Vec<StoreSession>,
    remove: Vec<String>,
    sessions: Vec<StoreSession>,
    starts: Vec<usize>,
    before: Vec<Option<usize>>,
    report: StoreUpdate,
    tiles: Vec<Tile>,
}

#[cfg(feature = "serde")]
impl TryFrom<PlanFields> for UpdatePlan {
    type Error = Error;

    /// Checked by [`UpdatePlan::check_shape`]: a plan shipped between machines, or forged,
    /// cannot make a scan read past its sessions.
    fn try_from(f: PlanFields) -> Result<Self> {
        let plan = Self {
            id: f.id,
            settings: f.settings,
            put: f.put,
            remove: f.remove,
            sessions: f.sessions,
            starts: f.starts,
            before: f.before,
            report: f.report,
            tiles: f.tiles,
        };
        plan.check_shape()?;
        Ok(plan)
    }
}

impl UpdatePlan {
    /// The plan of an update of a store with the settings `settings` and the sessions
    /// `stored` (in name order, as [`FleetStore::sessions`]): [`FleetStore::plan_update`], from
    /// a store's small tables alone (a cluster plans without reading its tiles).
    ///
    /// # Errors
    /// As [`FleetStore::plan_update`]; [`Error::InvalidState`] for stored sessions out of name
    /// order or with blocks that do not fit the settings.
    pub fn new(
        settings: StoreSettings,
        stored: &[StoreSession],
        put: Vec<StoreSession>,
        remove: &[String],
    ) -> Result<Self> {
        check_sessions(&settings, stored)?;
        let index = |name: &str| stored.binary_search_by(|s| s.name.as_str().cmp(name)).ok();
        let mut given: BTreeMap<String, StoreSession> = BTreeMap::new();
        for session in put {
            if given.contains_key(&session.name) {
                return Err(Error::DuplicateSession { name: session.name });
            }
            if session.blocks.block != settings.block {
                return Err(Error::InvalidParameter {
                    name: "block",
                    value: session.blocks.block as f64,
                    expected: "the store's poses per block",
                });
            }
            given.insert(session.name.clone(), session);
        }
        let mut removed = BTreeMap::new();
        for name in remove {
            let Some(k) = index(name) else {
                return Err(Error::StoreSession { name: name.clone(), problem: "is not in the store (to remove)" });
            };
            if given.contains_key(name) {
                return Err(Error::StoreSession { name: name.clone(), problem: "is both given and removed" });
            }
            removed.insert(name.clone(), k);
        }
        let mut report = StoreUpdate::default();
        let mut changed: BTreeMap<&str, &StoreSession> = BTreeMap::new();
        for (name, session) in &given {
            match index(name).map(|k| &stored[k]) {
                Some(old) if old.fingerprint == session.fingerprint && old.poses() == session.poses() => {
                    report.unchanged.push(name.clone());
                }
                Some(_) => {
                    report.replaced.push(name.clone());
                    changed.insert(name, session);
                }
                None => {
                    report.added.push(name.clone());
                    changed.insert(name, session);
                }
            }
        }
        report.removed = removed.keys().cloned().collect();
        // The new sessions in name order, with where each was before (unchanged ones).
        let mut next: BTreeMap<&str, (StoreSession, Option<usize>)> = BTreeMap::new();
        for (k, s) in stored.iter().enumerate() {
            if !removed.contains_key(&s.name) && !changed.contains_key(s.name.as_str()) {
                next.insert(&s.name, (s.clone(), Some(k)));
            }
        }
        for (name, session) in &changed {
            next.insert(name, ((*session).clone(), None));
        }
        let (sessions, before): (Vec<StoreSession>, Vec<Option<usize>>) = next.into_values().unzip();
        if let Some(first) = sessions.first() {
            for s in &sessions {
                let mismatch =
                    |problem: String, what| Error::SessionMismatch { session: s.name.clone(), problem, what };
                if s.blocks.dim != first.blocks.dim {
                    let problem =
                        format!("has {} coordinates, session {:?} has {}", s.blocks.dim, first.name, first.blocks.dim);
                    return Err(mismatch(problem, "dimension"));
                }
                if s.manifold != first.manifold {
                    let problem =
                        format!("lies on {}, session {:?} on {}", s.manifold.name(), first.name, first.manifold.name());
                    return Err(mismatch(problem, "manifold"));
                }
            }
        }
        let touched: Vec<bool> = before.iter().map(Option::is_none).collect();
        let tiles = if sessions.is_empty() {
            Vec::new()
        } else {
            let blocks: Vec<SessionBlocks> = sessions.iter().map(|s| s.blocks.clone()).collect();
            with_metric!(&settings.metric, m => plan_session_tiles_touching(&blocks, m, settings.gamma, &touched))?
        };
        report.tiles_scanned = tiles.len();
        // What the plan is of: the store's sessions, what is given and removed.
        let mut id = Fingerprint::new(0x706c_616e_2d73_7473);
        id.eat_settings(&settings);
        for s in stored.iter().chain(given.values()) {
            s.name.bytes().for_each(|b| id.eat(u64::from(b)));
            id.eat(0xff);
            id.eat(s.fingerprint);
            id.eat(s.poses() as u64);
        }
        id.eat(u64::MAX);
        for name in &report.removed {
            name.bytes().for_each(|b| id.eat(u64::from(b)));
            id.eat(0xff);
        }
        let starts = starts_of(&sessions);
        Ok(Self {
            id: id.finish(),
            settings,
            put: given.into_values().collect(),
            remove: report.removed.clone(),
            sessions,
            starts,
            before,
            report,
            tiles,
        })
    }

    /// The plan holds together: one start and one origin per session, the starts the sessions'
    /// running pose counts, and every tile well formed on poses of its two sessions. O(sessions
    /// + tiles).
    ///
    /// # Errors
    /// [`Error::InvalidState`] naming the first part that does not fit.
    #[cfg(feature = "serde")]
    fn check_shape(&self) -> Result<()> {
        let fail = |reason: String| Err(Error::InvalidState { what: "store update plan", reason });
        let n = self.sessions.len();
        if self.starts.len() != n || self.before.len() != n {
            return fail(format!("{n} sessions but {} starts and {} origins", self.starts.len(), self.before.len()));
        }
        let mut start = 0usize;
        for (s, session) in self.sessions.iter().enumerate() {
            if self.starts[s] != start {
                return fail(format!("session {s} starts at pose {}, not {start}", self.starts[s]));
            }
            start = start.saturating_add(session.poses());
        }
        let span = |s: usize| self.starts[s]..self.starts[s] + self.sessions[s].poses();
        for (k, tile) in self.tiles.iter().enumerate() {
            let [a, b] = tile.sessions;
            let fits = b < n
                && tile.is_well_formed()
                && span(a).start <= tile.rows.start
                && tile.rows.end <= span(a).end
                && span(b).start <= tile.columns.start
                && tile.columns.end <= span(b).end;
            if !fits {
                return fail(format!("tile {k} ({tile:?}) does not lie on the poses of its sessions"));
            }
        }
        Ok(())
    }

    /// A fingerprint of what the plan is of (the store's settings and sessions, what is given
    /// and removed): the tiles scanned for it carry it.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The store's settings.
    pub fn settings(&self) -> &StoreSettings {
        &self.settings
    }

    /// The sessions after the update, in name order (the indices of [`tiles`](Self::tiles)).
    pub fn sessions(&self) -> &[StoreSession] {
        &self.sessions
    }

    /// Whether session `s` (an index of [`sessions`](Self::sessions)) is added or replaced
    /// (its poses are those given), rather than read from the store.
    pub fn is_new(&self, s: usize) -> bool {
        self.before[s].is_none()
    }

    /// The tiles to scan, in plan order.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// What the update will do, by name (its tile counts but the scanned one are set when it
    /// is applied).
    pub fn report(&self) -> &StoreUpdate {
        &self.report
    }

    /// Whether the update changes nothing ([`StoreUpdate::changes_nothing`]): it has no tile
    /// to scan, and [`FleetStore::apply_update`] leaves the store as it was.
    pub fn changes_nothing(&self) -> bool {
        self.report.changes_nothing()
    }

    /// Checks that `trajectory` is session `s`'s (its pose count and fingerprint): what a
    /// worker that read it from a file checks before scanning. O(poses).
    ///
    /// # Errors
    /// [`Error::InvalidState`] for other poses.
    pub fn check_session(&self, s: usize, trajectory: &Trajectory) -> Result<()> {
        check_read(&self.sessions[s], trajectory)
    }

    /// Scans tile `k` of the plan from the poses of its two sessions (`sessions`: those of
    /// `tiles()[k].sessions`, in that order; the same for a tile of one session): its summary,
    /// its share of τ and its runs, as the store keeps them. Independent of every other tile;
    /// the scan [`FleetStore::update`] makes. Time: that of
    /// [`scan_session_tile`](crate::tile::scan_session_tile).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for `k` out of range; [`Error::InvalidState`] for poses of
    /// another count than the sessions'; the scan's errors.
    pub fn scan_tile(&self, k: usize, sessions: [&Trajectory; 2]) -> Result<ScannedTile> {
        let mut scanned = self.scan_tiles(&[k], |_| Ok(sessions))?;
        Ok(scanned.remove(0))
    }

    /// [`scan_tile`](Self::scan_tile) of each tile `ks` of the plan, in parallel, the scans in
    /// the order of `ks`: `sessions(k)` gives the poses of tile k's two sessions. What
    /// [`FleetStore::update`] scans; a worker given a group of tiles scans them so too. The
    /// balls that bound each side of a tile are made once per session block and shared by the
    /// tiles of the group that read it ([`scan_session_tile`](crate::tile::scan_session_tile)
    /// makes them for its tile alone): the scans are those of [`scan_tile`](Self::scan_tile).
    ///
    /// # Errors
    /// As [`scan_tile`](Self::scan_tile), the first in the order of `ks`; `sessions`' errors.
    pub fn scan_tiles<'a>(
        &self,
        ks: &[usize],
        mut sessions: impl FnMut(usize) -> Result<[&'a Trajectory; 2]>,
    ) -> Result<Vec<ScannedTile>> {
        let mut jobs = Vec::with_capacity(ks.len());
        for &k in ks {
            let Some(tile) = self.tiles.get(k) else {
                return Err(Error::InvalidParameter { name: "tile", value: k as f64, expected: "a tile of the plan" });
            };
            let [a, b] = tile.sessions;
            let given = sessions(k)?;
            for (s, t) in [a, b].into_iter().zip(given) {
                if t.len() != self.sessions[s].poses() {
                    return Err(Error::InvalidState {
                        what: "store update",
                        reason: format!(
                            "{} poses given for session {:?}, which has {}",
                            t.len(),
                            self.sessions[s].name,
                            self.sessions[s].poses()
                        ),
                    });
                }
            }
            jobs.push((tile, given, [self.starts[a], self.starts[b]]));
        }
        let settings = &self.settings;
        let keep = TileKeep::SUMMARY.with_duration().with_runs();
        let scans = settings.metric.scan_session_tiles(&jobs, settings.gamma, settings.separation, keep)?;
        Ok(ks
            .iter()
            .zip(scans)
            .map(|(&k, scan)| {
                let duration = scan.duration.expect("kept with its duration");
                let runs = scan.runs.expect("kept with its runs");
                ScannedTile { plan: self.id, index: k, tile: StoredTile { summary: scan.summary, duration }, runs }
            })
            .collect())
    }
}

/// A tile of an [`UpdatePlan`], scanned ([`UpdatePlan::scan_tile`]): what
/// [`FleetStore::apply_update`] takes, bytes to ship between machines with the `serde`
/// feature ([`to_bytes`](Self::to_bytes)).
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ScannedTile {
    plan: u64,
    index: usize,
    tile: StoredTile,
    runs: TileRuns,
}

impl ScannedTile {
    /// Its index in the plan's tiles.
    pub fn index(&self) -> usize {
        self.index
    }

    /// The scanned tile as bytes (a tag, the tile format version, MessagePack): its plan's
    /// id, its index, its summary, share of τ and runs; about their sizes together.
    #[cfg(feature = "serde")]
    pub fn to_bytes(&self) -> Vec<u8> {
        crate::tile::encode(*b"ILsc", self)
    }

    /// From [`to_bytes`](Self::to_bytes), checked to fit together.
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"scanned tile"`) for other bytes or parts that do not fit.
    #[cfg(feature = "serde")]
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let scanned: Self = crate::tile::decode(*b"ILsc", "scanned tile", bytes)?;
        let corrupt = |reason: String| Error::InvalidState { what: "scanned tile", reason };
        scanned.tile.summary.check().map_err(corrupt)?;
        scanned.runs.check().map_err(corrupt)?;
        let d = &scanned.tile.duration;
        if d.tile != scanned.tile.summary.tile || !d.fits_tile() {
            return Err(corrupt(format!("its share of τ is not of tile {:?}", d.tile)));
        }
        Ok(scanned)
    }
}

/// A metric in serde by its text form ([`MetricSpec`]'s `Display` and `FromStr`).
#[cfg(feature = "serde")]
mod metric_text {
    use crate::spec::MetricSpec;

    pub(super) fn serialize<S: serde::Serializer>(metric: &MetricSpec, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(metric)
    }

    pub(super) fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<MetricSpec, D::Error> {
        let text = <String as serde::Deserialize>::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// A fleet's loops kept up to date by session (see the module docs).
///
/// Besides its state (settings, sessions, tiles, the last update), a store keeps what its
/// answer is made of, so that the answer after an update costs what the update changed: the
/// merge of each session pair's tiles, τ of each session, and the runs of each tile it scanned
/// (16 bytes a run, [`TileRuns::heap_bytes`]), which its draws read instead of rescanning. A
/// store read back with them ([`from_saved`](Self::from_saved)) only adds τ up again; one
/// read back lazily ([`from_saved_lazily`](Self::from_saved_lazily)) takes τ as saved and
/// reads each tile where it was saved when an update or a draw first needs it
/// ([`KeptTile`]); one read back from its state alone ([`from_parts`](Self::from_parts))
/// merges again, and rescans the tiles a draw asks until an update scans them.
#[derive(Debug, Clone)]
pub struct FleetStore {
    settings: StoreSettings,
    sessions: Vec<StoreSession>,
    tiles: Vec<KeptTile>,
    last_update: StoreUpdate,
    kept: Kept,
}

/// Two stores are equal when their states are: what each keeps of its answer follows from it.
impl PartialEq for FleetStore {
    fn eq(&self, other: &Self) -> bool {
        (&self.settings, &self.sessions, &self.tiles, &self.last_update)
            == (&other.settings, &other.sessions, &other.tiles, &other.last_update)
    }
}

/// What a store keeps of its answer between updates, in the store's fleet indices.
#[derive(Debug, Clone, Default)]
struct Kept {
    /// The merge of the tiles of each session pair with tiles, by pair (a, b).
    merges: BTreeMap<[usize; 2], Arc<MergedLoops>>,
    /// τ of each session, `(own, other)` per pose, seconds.
    duration: Vec<(Vec<f64>, Vec<f64>)>,
    /// What the last draws found of uniform and row picks, by tile and component: those of the
    /// last draw of each of the last [`POOL_SEEDS`] seeds, most recent last.
    pools: Arc<Mutex<Vec<(u64, Pools)>>>,
}

/// What one draw found in the tiles, by tile and component.
type Pools = HashMap<PoolKey, Found>;

/// A tile's part of a draw's pass, and for each component it asks (in the same order) what the
/// cache did not answer: the key its answer is kept under and, where the tile is asked a pool
/// (with a slack), the threshold and count the draw asked.
type TilePart = (usize, DrawRequest, Vec<(PoolKey, Option<(u64, u64)>)>);

/// The tag of a store's saved draws ([`FleetStore::kept_draws`]).
#[cfg(feature = "serde")]
const DRAWS_TAG: [u8; 4] = *b"ILdr";

/// The tag of saved draws that held pools only, before rows' closest pairs were kept too.
#[cfg(feature = "serde")]
const POOLS_ONLY_TAG: &[u8; 4] = b"ILdw";

/// Seeds whose draws a store keeps what they found in its tiles.
const POOL_SEEDS: usize = 4;

/// A checksum of saved bytes (the store's fingerprint mixing, eight bytes a word).
#[cfg(feature = "serde")]
fn checksum(bytes: &[u8]) -> u64 {
    let mut f = Fingerprint::new(bytes.len() as u64);
    for chunk in bytes.chunks(8) {
        let mut word = [0u8; 8];
        word[..chunk.len()].copy_from_slice(chunk);
        f.eat(u64::from_le_bytes(word));
    }
    f.finish()
}

/// A component's pairs in one tile with a key at most a threshold, as a draw found them: the
/// next draw (after an update, which moves fleet indices but not the sessions' own) answers
/// from it every tile of two sessions it left alone. Keyed by content, never by place: the
/// seed, the store's settings, the tile's sessions (salt of the name and fingerprint of the
/// poses) and first row and column in their own indices, and the component's first and last row
/// and closest pair in them, with its number of pairs.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct PoolKey {
    seed: u64,
    /// The store's settings (metric, γ, separation, block), mixed into one word.
    settings: u64,
    sessions: [(u64, u64); 2],
    tile: [usize; 2],
    component: ([usize; 2], [usize; 2], u64),
    /// The fields mixed into one word: what the map hashes (a draw looks up every tile of
    /// every component it asks).
    digest: u64,
}

impl PoolKey {
    fn new(
        (seed, settings): (u64, u64),
        sessions: [(u64, u64); 2],
        tile: [usize; 2],
        component: ([usize; 2], [usize; 2], u64),
    ) -> Self {
        let (rows, closest, pairs) = component;
        let words = [seed, settings, sessions[0].0, sessions[0].1, sessions[1].0, sessions[1].1]
            .into_iter()
            .chain([tile[0] as u64, tile[1] as u64, rows[0] as u64, rows[1] as u64])
            .chain([closest[0] as u64, closest[1] as u64, pairs]);
        let mut digest = Fingerprint::new(0x706F_6F6C);
        words.for_each(|w| digest.eat(w));
        Self { seed, settings, sessions, tile, component, digest: digest.finish() }
    }
}

impl std::hash::Hash for PoolKey {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        state.write_u64(self.digest);
    }
}

/// What draws found of one component in one tile (pairs in the tile's sessions' own indices):
/// its pool, the closest pair of the rows they asked (none where the tile has no pair in that
/// row), and its closest pair over all rows, where asked. Each answers the next draw that asks
/// the same: a component's rows and offset follow from its own cells, so a draw after an
/// update asks the same rows of a component it left alone.
#[derive(Debug, Clone, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Found {
    pool: Option<PoolEntry>,
    rows: BTreeMap<usize, Option<DrawCandidate>>,
    best: Option<Option<DrawCandidate>>,
}

/// Of the pairs (in the tile's sessions' own indices) with a key at most `threshold`, the `keep`
/// smallest (all of them when fewer), by key.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct PoolEntry {
    threshold: u64,
    keep: u64,
    pairs: Vec<DrawCandidate>,
}

impl PoolEntry {
    /// Whether it holds the `keep` smallest keys at most `threshold`.
    fn answers(&self, threshold: u64, keep: u64) -> bool {
        self.threshold >= threshold && (self.keep >= keep || (self.pairs.len() as u64) < self.keep)
    }
}

/// The threshold and count a tile's pairs are looked up with when a draw asks `(threshold,
/// keep)`: twice as many expected pairs, so that a quota grown by a later update still reads
/// them from the cache.
fn pool_slack(threshold: u64, keep: u64) -> (u64, u64) {
    (threshold.saturating_mul(2), keep.saturating_mul(2).saturating_add(2))
}

/// Where a store reads a stored session's poses.
pub type SessionSource<'a> = dyn FnMut(&StoreSession) -> Result<Trajectory> + 'a;

impl FleetStore {
    /// An empty store.
    ///
    /// # Errors
    /// As [`StoreSettings::check`].
    pub fn new(settings: StoreSettings) -> Result<Self> {
        settings.check()?;
        Ok(Self {
            settings,
            sessions: Vec::new(),
            tiles: Vec::new(),
            last_update: StoreUpdate::default(),
            kept: Kept::default(),
        })
    }

    /// A store from its parts as saved (sessions in name order, tiles in plan order), checked:
    /// the settings, each session's blocks, and that the tiles are exactly the plan of the
    /// sessions (O(blocks log blocks)), each lying in its sessions with a share of τ of its
    /// size.
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"fleet store"`) naming the first part that does not
    /// fit; the settings' errors.
    pub fn from_parts(
        settings: StoreSettings,
        sessions: Vec<StoreSession>,
        tiles: Vec<StoredTile>,
        last_update: StoreUpdate,
    ) -> Result<Self> {
        let runs = vec![None; tiles.len()];
        let mut store = Self::read_whole(settings, sessions, tiles, runs, last_update)?;
        let read: Vec<&StoredTile> = store.tiles.iter().map(KeptTile::stored).collect::<Result<_>>()?;
        store.kept.merges = merges_of(read.into_iter())?;
        Ok(store)
    }

    /// A store from its parts and what it keeps of its answer as saved
    /// ([`kept_merges`](Self::kept_merges), [`kept_runs`](Self::kept_runs)): as
    /// [`from_parts`](Self::from_parts), but it neither merges again nor rescans a tile that
    /// has its runs to draw. Checks, besides, that the merges are those of the session pairs
    /// of the tiles (each over its pair's tiles in plan order), and each tile's runs are of
    /// that tile, scanned with the store's γ and separation from its sessions' places.
    /// O(blocks log blocks + tiles + components).
    ///
    /// # Errors
    /// As [`from_parts`](Self::from_parts), [`Error::InvalidState`] naming the merge or runs
    /// that do not fit.
    pub fn from_saved(
        settings: StoreSettings,
        sessions: Vec<StoreSession>,
        tiles: Vec<StoredTile>,
        last_update: StoreUpdate,
        merges: Vec<([usize; 2], MergedLoops)>,
        runs: Vec<Option<TileRuns>>,
    ) -> Result<Self> {
        let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
        if runs.len() != tiles.len() {
            return Err(corrupt(format!("runs of {} tiles for {} tiles", runs.len(), tiles.len())));
        }
        let mut store = Self::read_whole(settings, sessions, tiles, runs, last_update)?;
        let starts = store.starts();
        for k in 0..store.tiles.len() {
            store.checked_runs(k, &starts)?;
        }
        store.kept.merges = checked_merges(&store.sessions, &store.tiles, merges)?;
        Ok(store)
    }

    /// A store from its parts as saved, read lazily: its tiles (in plan order) where they lie
    /// in the fleet of `sessions`, each read from where it was saved ([`SavedTile`]) when an
    /// update or a draw first needs it ([`KeptTile`]), with the merges it keeps
    /// ([`kept_merges`](Self::kept_merges)) and τ of each session (`(own, other)` per pose,
    /// as [`loop_duration`](Self::loop_duration) gives them, by session). Checks what
    /// [`from_saved`](Self::from_saved) checks but the tiles' contents, which are checked when
    /// read, and that τ has a finite, non-negative value for every pose. O(blocks log blocks +
    /// tiles + components + poses): no tile is read. An update that adds sessions then reads
    /// none of the old tiles (τ adds the new shares to what is given); one that replaces or
    /// removes a session reads the kept tiles of the sessions that lost one; a draw reads the
    /// runs of the tiles it asks.
    ///
    /// # Errors
    /// As [`from_saved`](Self::from_saved), and for τ of another length than a session's poses.
    pub fn from_saved_lazily(
        settings: StoreSettings,
        sessions: Vec<StoreSession>,
        tiles: Vec<(Tile, Arc<dyn SavedTile>)>,
        last_update: StoreUpdate,
        merges: Vec<([usize; 2], MergedLoops)>,
        duration: Vec<(Vec<f64>, Vec<f64>)>,
    ) -> Result<Self> {
        let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
        let tiles = tiles.into_iter().map(|(tile, saved)| KeptTile::saved(tile, saved)).collect();
        let mut store = Self::checked(settings, sessions, tiles, last_update)?;
        if duration.len() != store.sessions.len() {
            return Err(corrupt(format!("τ of {} sessions for {} sessions", duration.len(), store.sessions.len())));
        }
        // Sessions in parallel; the first misfit in session order.
        let misfit = duration.par_iter().enumerate().find_map_first(|(s, (own, other))| {
            let (poses, name) = (store.sessions[s].poses(), &store.sessions[s].name);
            if own.len() != poses || other.len() != poses {
                return Some(format!(
                    "τ of {} and {} poses for session {s} {name:?} of {poses} poses",
                    own.len(),
                    other.len()
                ));
            }
            (0..poses)
                .find(|&k| !(own[k] >= 0.0 && other[k] >= 0.0 && (own[k] + other[k]).is_finite()))
                .map(|k| format!("τ of pose {k} of session {s} {name:?} is ({}, {}) s", own[k], other[k]))
        });
        if let Some(reason) = misfit {
            return Err(corrupt(reason));
        }
        store.kept.merges = checked_merges(&store.sessions, &store.tiles, merges)?;
        store.kept.duration = duration;
        Ok(store)
    }

    /// A store of tiles read back whole, each checked to lie in its sessions with a share of τ
    /// of its size, and τ added up; without its merges.
    fn read_whole(
        settings: StoreSettings,
        sessions: Vec<StoreSession>,
        tiles: Vec<StoredTile>,
        runs: Vec<Option<TileRuns>>,
        last_update: StoreUpdate,
    ) -> Result<Self> {
        let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
        for (k, t) in tiles.iter().enumerate() {
            t.summary.check().map_err(|p| corrupt(format!("tile {k}: {p}")))?;
            let d = &t.duration;
            if d.tile != t.summary.tile || !d.fits_tile() {
                return Err(corrupt(format!("tile {k}: its share of τ is not of tile {:?}", t.summary.tile)));
            }
        }
        let tiles = tiles.into_iter().zip(runs).map(|(t, r)| KeptTile::ready(t, r.map(Arc::new))).collect();
        let mut store = Self::checked(settings, sessions, tiles, last_update)?;
        let all: Vec<usize> = (0..store.sessions.len()).collect();
        let read: Vec<&StoredTile> = store.tiles.iter().map(KeptTile::stored).collect::<Result<_>>()?;
        store.kept.duration = durations_of(&read, &store.starts(), &store.sessions, &all)?;
        Ok(store)
    }

    /// What is checked of a store's parts as saved but its tiles' contents: the settings, the
    /// sessions, and that the tiles are the plan of the sessions. Without its merges or τ.
    fn checked(
        settings: StoreSettings,
        sessions: Vec<StoreSession>,
        tiles: Vec<KeptTile>,
        last_update: StoreUpdate,
    ) -> Result<Self> {
        check_sessions(&settings, &sessions)?;
        let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
        let store = Self { settings, sessions, tiles, last_update, kept: Kept::default() };
        let plan = store.plan(&vec![true; store.sessions.len()])?;
        if let Some(k) =
            (0..plan.len().max(store.tiles.len())).find(|&k| plan.get(k) != store.tiles.get(k).map(KeptTile::tile))
        {
            return Err(corrupt(format!(
                "tile {k} is {:?}, but the plan of the sessions has {:?} there ({} tiles in all, {} stored)",
                store.tiles.get(k).map(KeptTile::tile),
                plan.get(k),
                plan.len(),
                store.tiles.len()
            )));
        }
        Ok(store)
    }

    /// The runs of tile `k` where it has them, checked to be of that tile under this store
    /// (scanned with its γ and separation from its sessions' places, `starts`).
    fn checked_runs(&self, k: usize, starts: &[usize]) -> Result<Option<&TileRuns>> {
        let t = &self.tiles[k];
        let Some(r) = t.runs()? else { return Ok(None) };
        let [a, b] = t.tile().sessions;
        let wanted = (self.settings.gamma, self.settings.separation);
        if r.tile() != t.tile() || r.scanned_with() != wanted || r.starts() != [starts[a], starts[b]] {
            return Err(Error::InvalidState {
                what: "fleet store",
                reason: format!("the runs of tile {k} are not of tile {:?} under this store", t.tile()),
            });
        }
        Ok(Some(r))
    }

    /// The merge of each session pair's tiles that the store keeps, by pair (a, b), a ≤ b:
    /// what [`from_saved`](Self::from_saved) takes back.
    pub fn kept_merges(&self) -> impl Iterator<Item = ([usize; 2], &MergedLoops)> {
        self.kept.merges.iter().map(|(pair, m)| (*pair, m.as_ref()))
    }

    /// The runs of each tile the store keeps, by tile (as [`tiles`](Self::tiles)), each read
    /// where it was saved if not yet; `None` for a tile it would rescan to draw (a store read
    /// back without them): what [`from_saved`](Self::from_saved) takes back.
    ///
    /// # Errors
    /// As [`KeptTile::runs`].
    pub fn kept_runs(&self) -> Result<Vec<Option<&TileRuns>>> {
        self.tiles.iter().map(KeptTile::runs).collect()
    }

    /// The summary and share of τ of each tile, as [`from_parts`](Self::from_parts) takes
    /// them, each read where it was saved if not yet. O(tiles' components, edge runs and
    /// shares).
    ///
    /// # Errors
    /// As [`KeptTile::stored`].
    pub fn stored_tiles(&self) -> Result<Vec<StoredTile>> {
        self.tiles.par_iter().map(|t| t.stored().cloned()).collect()
    }

    /// What the store keeps of its last draws ([`samples`](Self::samples)), as bytes to save
    /// beside its tiles: per seed (oldest first), what the draw found in the tiles, tagged,
    /// versioned and ending in a checksum. [`keep_draws`](Self::keep_draws) takes them back.
    #[cfg(feature = "serde")]
    pub fn kept_draws(&self) -> Vec<(u64, Vec<u8>)> {
        let pools = self.kept.pools.lock().unwrap_or_else(|e| e.into_inner());
        pools
            .iter()
            .map(|(seed, found)| {
                let mut entries: Vec<(&PoolKey, &Found)> = found.iter().collect();
                entries.sort_by_key(|(k, _)| (k.sessions, k.tile, k.component));
                let mut bytes = crate::tile::encode(DRAWS_TAG, &entries);
                let check = checksum(&bytes);
                bytes.extend_from_slice(&check.to_le_bytes());
                (*seed, bytes)
            })
            .collect()
    }

    /// Takes back what [`kept_draws`](Self::kept_draws) gave (a store read back): its next
    /// draws of those seeds read again only the tiles these do not answer. What they hold is
    /// keyed by content, so draws of another store's sessions are never taken for this one's.
    ///
    /// A draw saved by a build that kept pools only (tag `ILdw`) is passed over: draws are what
    /// a store may find again, and the next draw of that seed reads its tiles as a store
    /// without them does.
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"fleet store draws"`) for bytes that are not such a
    /// draw, or whose checksum does not match; nothing is kept then.
    #[cfg(feature = "serde")]
    pub fn keep_draws(&self, draws: &[(u64, &[u8])]) -> Result<()> {
        let what = "fleet store draws";
        let mut kept = Vec::with_capacity(draws.len());
        for (k, &(seed, bytes)) in draws.iter().enumerate() {
            let corrupt = |reason: String| Error::InvalidState { what, reason: format!("draw {k}: {reason}") };
            let Some((body, check)) = bytes.split_last_chunk::<8>() else {
                return Err(corrupt(format!("{} bytes, fewer than its checksum", bytes.len())));
            };
            if checksum(body) != u64::from_le_bytes(*check) {
                return Err(corrupt("its checksum does not match its bytes".into()));
            }
            if body.starts_with(POOLS_ONLY_TAG) {
                continue;
            }
            let entries: Vec<(PoolKey, Found)> =
                crate::tile::decode(DRAWS_TAG, what, body).map_err(|e| corrupt(e.to_string()))?;
            let found: Pools = entries
                .into_iter()
                .map(|(key, entry)| {
                    (PoolKey::new((key.seed, key.settings), key.sessions, key.tile, key.component), entry)
                })
                .collect();
            if found.keys().any(|key| key.seed != seed) {
                return Err(corrupt(format!("it holds pools of another seed than {seed}")));
            }
            kept.push((seed, found));
        }
        let over = kept.len().saturating_sub(POOL_SEEDS);
        kept.drain(..over);
        *self.kept.pools.lock().unwrap_or_else(|e| e.into_inner()) = kept;
        Ok(())
    }

    /// The settings.
    pub fn settings(&self) -> &StoreSettings {
        &self.settings
    }

    /// The sessions, in name order (their fleet order).
    pub fn sessions(&self) -> &[StoreSession] {
        &self.sessions
    }

    /// The tiles, in plan order.
    pub fn tiles(&self) -> &[KeptTile] {
        &self.tiles
    }

    /// What the last update that changed the store did (one that changes nothing leaves it).
    pub fn last_update(&self) -> &StoreUpdate {
        &self.last_update
    }

    /// The index of the session named `name`.
    pub fn session_index(&self, name: &str) -> Option<usize> {
        self.sessions.binary_search_by(|s| s.name.as_str().cmp(name)).ok()
    }

    /// The first fleet index of each session.
    pub fn starts(&self) -> Vec<usize> {
        starts_of(&self.sessions)
    }

    /// The tiles of the sessions marked in `touched`, as the whole plan has them.
    fn plan(&self, touched: &[bool]) -> Result<Vec<Tile>> {
        if self.sessions.is_empty() {
            return Ok(Vec::new());
        }
        let blocks: Vec<SessionBlocks> = self.sessions.iter().map(|s| s.blocks.clone()).collect();
        with_metric!(&self.settings.metric, m => plan_session_tiles_touching(&blocks, m, self.settings.gamma, touched))
    }

    /// Adds or replaces the sessions `put` (by name) and removes the sessions `remove`, in one
    /// update: scans only the tiles that hold an added or replaced session (reading the stored
    /// sessions they meet from `source`, each once), keeps the tiles of every other pair, and
    /// drops those of replaced and removed sessions. A session given with the content it has
    /// in the store (same fingerprint) changes nothing; an update that changes nothing
    /// ([`StoreUpdate::changes_nothing`]) leaves the store exactly as it was, its
    /// [`last_update`](Self::last_update) included. Returns what the update did. On an error
    /// the store is unchanged.
    ///
    /// The update is its three steps, here in one process: [`plan_update`](Self::plan_update),
    /// [`UpdatePlan::scan_tile`] of each planned tile (in parallel), and
    /// [`apply_update`](Self::apply_update); a cluster runs the same steps on its workers.
    ///
    /// Time: the scans of the new tiles (rows in parallel, tiles in parallel), plus O(stored
    /// tiles) to move them when a new name sorts before stored ones, plus O(blocks log blocks)
    /// to plan.
    ///
    /// # Errors
    /// [`Error::DuplicateSession`] for a name given twice; [`Error::StoreSession`] for a
    /// removed name not in the store or also given; [`Error::SessionMismatch`] for a session
    /// whose dimension or manifold differs from the others'; the metric's errors on a session;
    /// [`Error::InvalidState`] for a stored session that `source` gives with another pose
    /// count or content; `source`'s errors.
    pub fn update(
        &mut self,
        put: Vec<(String, Trajectory)>,
        remove: &[String],
        source: &mut SessionSource<'_>,
    ) -> Result<StoreUpdate> {
        // In parallel; the first error in the order given.
        let sessions: Vec<Result<StoreSession>> = put
            .par_iter()
            .map(|(name, trajectory)| StoreSession::new(name.clone(), trajectory, &self.settings))
            .collect();
        let sessions = sessions.into_iter().collect::<Result<Vec<_>>>()?;
        let plan = self.plan_update(sessions, remove)?;
        let given: HashMap<&str, &Trajectory> = put.iter().map(|(name, t)| (name.as_str(), t)).collect();
        let mut stored: Vec<usize> =
            plan.tiles.iter().flat_map(|t| t.sessions).filter(|&s| plan.before[s].is_some()).collect();
        stored.sort_unstable();
        stored.dedup();
        let read: HashMap<usize, Trajectory> =
            stored.iter().copied().zip(read_sessions(&plan.sessions, &stored, source)?).collect();
        let trajectory = |s: usize| -> &Trajectory {
            match plan.before[s] {
                Some(_) => &read[&s],
                None => given[plan.sessions[s].name.as_str()],
            }
        };
        let all: Vec<usize> = (0..plan.tiles.len()).collect();
        let scanned = plan.scan_tiles(&all, |k| {
            let [a, b] = plan.tiles[k].sessions;
            Ok([trajectory(a), trajectory(b)])
        })?;
        // Planned from this state just now: no need to plan again to check it.
        self.apply_planned(&plan, scanned)
    }

    /// The plan of an update that adds or replaces the sessions `put` (by name; each
    /// [`StoreSession::new`] of its trajectory) and removes the sessions `remove`: the
    /// sessions after it, and the tiles it must scan ([`UpdatePlan::tiles`]), each of which
    /// [`UpdatePlan::scan_tile`] scans on its own. Reads the store's sessions alone:
    /// O(sessions + blocks log blocks); the plan is as small (no poses, no tiles kept).
    ///
    /// # Errors
    /// As [`update`](Self::update), but for the reading of sessions.
    pub fn plan_update(&self, put: Vec<StoreSession>, remove: &[String]) -> Result<UpdatePlan> {
        UpdatePlan::new(self.settings, &self.sessions, put, remove)
    }

    /// Applies the update that `plan` (this store's [`plan_update`](Self::plan_update)) plans,
    /// with `scanned` its tiles ([`UpdatePlan::scan_tile`] of each, in any order): keeps the
    /// tiles of every pair of unchanged sessions, moved to their new fleet indices, drops those
    /// of replaced and removed sessions, merges the session pairs of the new tiles, and adds
    /// their shares of τ; a plan that changes nothing ([`UpdatePlan::changes_nothing`]) leaves
    /// the store exactly as it was. Returns what the update did (then also
    /// [`last_update`](Self::last_update) but for a plan that changes nothing). On an error the
    /// store is unchanged. Time: O(the new tiles'
    /// components and edge runs + stored tiles + poses of the sessions that lost a tile), plus
    /// O(blocks log blocks) to check the plan.
    ///
    /// # Errors
    /// [`Error::InvalidState`] (`what`: `"store update"`) for a plan that is not this store's
    /// (made from another state, or altered) and for scanned tiles that are not exactly the
    /// plan's (one missing, twice, of another plan, or not of its tile); as
    /// [`plan_update`](Self::plan_update).
    pub fn apply_update(&mut self, plan: &UpdatePlan, scanned: Vec<ScannedTile>) -> Result<StoreUpdate> {
        if self.plan_update(plan.put.clone(), &plan.remove)? != *plan {
            return Err(Error::InvalidState {
                what: "store update",
                reason: format!("plan {:016x} is not of this store's state (planned from another)", plan.id),
            });
        }
        self.apply_planned(plan, scanned)
    }

    /// [`apply_update`](Self::apply_update) of a plan known to be of this store's state (made
    /// from it, and the store not changed since): the scans are checked against it, the plan
    /// is not made again. O(the new tiles' components and edge runs + stored tiles + poses of
    /// the sessions that lost a tile).
    fn apply_planned(&mut self, plan: &UpdatePlan, scanned: Vec<ScannedTile>) -> Result<StoreUpdate> {
        let wrong = |reason: String| Error::InvalidState { what: "store update", reason };
        let mut slots: Vec<Option<ScannedTile>> = vec![None; plan.tiles.len()];
        for s in scanned {
            if s.plan != plan.id {
                return Err(wrong(format!(
                    "tile {} was scanned for plan {:016x}, not {:016x}",
                    s.index, s.plan, plan.id
                )));
            }
            let k = s.index;
            let Some(tile) = plan.tiles.get(k) else {
                return Err(wrong(format!("tile {k} scanned, of {} tiles planned", plan.tiles.len())));
            };
            let [a, b] = tile.sessions;
            let fits = s.tile.tile() == tile
                && s.tile.duration.tile == *tile
                && s.runs.tile() == tile
                && s.runs.scanned_with() == (plan.settings.gamma, plan.settings.separation)
                && s.runs.starts() == [plan.starts[a], plan.starts[b]];
            if !fits {
                return Err(wrong(format!("the scan of tile {k} is not of tile {tile:?} under this store")));
            }
            if slots[k].replace(s).is_some() {
                return Err(wrong(format!("tile {k} scanned twice")));
            }
        }
        if let Some(k) = slots.iter().position(Option::is_none) {
            return Err(wrong(format!(
                "tile {k} of the {} planned ({:?}) was not scanned",
                plan.tiles.len(),
                plan.tiles[k]
            )));
        }
        let mut report = plan.report.clone();
        if plan.changes_nothing() {
            report.tiles_kept = self.tiles.len();
            return Ok(report);
        }
        let scanned: Vec<(StoredTile, Arc<TileRuns>)> =
            slots.into_iter().flatten().map(|s| (s.tile, Arc::new(s.runs))).collect();
        let (starts, old_starts, before) = (&plan.starts, self.starts(), &plan.before);
        let mut now = vec![None; self.sessions.len()];
        for (k, b) in before.iter().enumerate() {
            if let Some(b) = *b {
                now[b] = Some(k);
            }
        }
        // Stored tiles of two unchanged sessions are kept; the others are dropped, and their
        // unchanged sessions lose a tile.
        let mut lost = vec![false; self.sessions.len()];
        for t in &self.tiles {
            let [a, b] = t.tile().sessions;
            if now[a].is_none() || now[b].is_none() {
                report.tiles_dropped += 1;
                (lost[a], lost[b]) = (true, true);
            }
        }
        report.tiles_kept = self.tiles.len() - report.tiles_dropped;
        // The kept tiles of a session that lost one: its τ is added up again from them (read
        // here, in parallel, where a store read back lazily has not yet).
        let relost: Vec<&StoredTile> = self
            .tiles
            .par_iter()
            .filter(|t| {
                let [a, b] = t.tile().sessions;
                now[a].is_some() && now[b].is_some() && (lost[a] || lost[b])
            })
            .map(KeptTile::stored)
            .collect::<Result<_>>()?;
        let mut kept_of: Vec<Vec<&TileDuration>> = vec![Vec::new(); self.sessions.len()];
        for t in &relost {
            let [a, b] = t.tile().sessions;
            kept_of[a].push(&t.duration);
            if b != a {
                kept_of[b].push(&t.duration);
            }
        }
        // The merges of the session pairs of changed sessions: all their tiles are new.
        let new_merges = merges_of(scanned.iter().map(|(t, _)| t))?;
        // τ: what the new tiles add to each session, and what a session that lost a tile keeps.
        let mut new_of: Vec<Vec<&TileDuration>> = vec![Vec::new(); plan.sessions.len()];
        for (t, _) in &scanned {
            let [a, b] = t.tile().sessions;
            new_of[a].push(&t.duration);
            if b != a {
                new_of[b].push(&t.duration);
            }
        }
        let shares = |k: usize| -> Result<Option<(Vec<f64>, Vec<f64>)>> {
            let poses = plan.sessions[k].poses();
            let new = || crate::tile::draw::session_loop_duration(k, starts[k], poses, new_of[k].iter().copied());
            match before[k] {
                Some(b) if lost[b] => {
                    let (mut own, mut other) = new()?;
                    let (o, x) =
                        crate::tile::draw::session_loop_duration(b, old_starts[b], poses, kept_of[b].iter().copied())?;
                    own.iter_mut().zip(o).for_each(|(y, v)| *y += v);
                    other.iter_mut().zip(x).for_each(|(y, v)| *y += v);
                    Ok(Some((own, other)))
                }
                Some(_) if new_of[k].is_empty() => Ok(None),
                _ => new().map(Some),
            }
        };
        let shares: Vec<Option<(Vec<f64>, Vec<f64>)>> =
            (0..plan.sessions.len()).into_par_iter().map(shares).collect::<Result<_>>()?;
        drop((kept_of, new_of, relost));

        // Nothing fails from here: the kept state moves to the new fleet indices.
        let shifts_of = |[a, b]: [usize; 2], [na, nb]: [usize; 2]| {
            let shift = |new: usize, old: usize| new as isize - old as isize;
            [shift(starts[na], old_starts[a]), shift(starts[nb], old_starts[b])]
        };
        let old = std::mem::take(&mut self.kept);
        let mut tiles: Vec<KeptTile> = Vec::with_capacity(report.tiles_kept + scanned.len());
        for mut t in std::mem::take(&mut self.tiles) {
            let [a, b] = t.tile().sessions;
            let (Some(na), Some(nb)) = (now[a], now[b]) else { continue };
            let shifts = shifts_of([a, b], [na, nb]);
            if shifts != [0, 0] || [na, nb] != [a, b] {
                t.move_to([na, nb], shifts);
            }
            tiles.push(t);
        }
        tiles.extend(scanned.into_iter().map(|(t, r)| KeptTile::ready(t, Some(r))));
        // Plan order: by row block, then column block (fleet indices order both).
        tiles.sort_by_key(|t| (t.tile().rows.start, t.tile().columns.start));
        let mut merges = new_merges;
        for ([a, b], mut merge) in old.merges {
            let (Some(na), Some(nb)) = (now[a], now[b]) else { continue };
            let shifts = shifts_of([a, b], [na, nb]);
            if shifts != [0, 0] || [na, nb] != [a, b] {
                Arc::make_mut(&mut merge).move_to([na, nb], shifts);
            }
            merges.insert([na, nb], merge);
        }
        let mut old_duration: Vec<Option<(Vec<f64>, Vec<f64>)>> = old.duration.into_iter().map(Some).collect();
        let duration = shares
            .into_iter()
            .zip(before)
            .map(|(share, b)| match (share, b.filter(|&b| !lost[b])) {
                (Some(add), Some(b)) => {
                    let (mut own, mut other) = old_duration[b].take().unwrap_or_default();
                    own.iter_mut().zip(add.0).for_each(|(y, v)| *y += v);
                    other.iter_mut().zip(add.1).for_each(|(y, v)| *y += v);
                    (own, other)
                }
                (Some(whole), None) => whole,
                (None, b) => b.and_then(|b| old_duration[b].take()).unwrap_or_default(),
            })
            .collect();
        self.kept = Kept { merges, duration, pools: old.pools };
        self.sessions = plan.sessions.clone();
        self.tiles = tiles;
        self.last_update = report.clone();
        Ok(report)
    }

    /// Adds new sessions ([`update`](Self::update)).
    ///
    /// # Errors
    /// [`Error::StoreSession`] for a name already in the store; as [`update`](Self::update).
    pub fn add(&mut self, sessions: Vec<(String, Trajectory)>, source: &mut SessionSource<'_>) -> Result<StoreUpdate> {
        if let Some((name, _)) = sessions.iter().find(|(name, _)| self.session_index(name).is_some()) {
            return Err(Error::StoreSession { name: name.clone(), problem: "is already in the store (replace it)" });
        }
        self.update(sessions, &[], source)
    }

    /// Replaces sessions of the store by name ([`update`](Self::update)).
    ///
    /// # Errors
    /// [`Error::StoreSession`] for a name not in the store; as [`update`](Self::update).
    pub fn replace(
        &mut self,
        sessions: Vec<(String, Trajectory)>,
        source: &mut SessionSource<'_>,
    ) -> Result<StoreUpdate> {
        if let Some((name, _)) = sessions.iter().find(|(name, _)| self.session_index(name).is_none()) {
            return Err(Error::StoreSession { name: name.clone(), problem: "is not in the store (add it)" });
        }
        self.update(sessions, &[], source)
    }

    /// Removes sessions by name ([`update`](Self::update)): no scan.
    ///
    /// # Errors
    /// As [`update`](Self::update).
    pub fn remove(&mut self, names: &[String]) -> Result<StoreUpdate> {
        let mut unread = |s: &StoreSession| -> Result<Trajectory> {
            Err(Error::StoreSession { name: s.name.clone(), problem: "was read by a removal" })
        };
        self.update(Vec::new(), names, &mut unread)
    }

    /// The ids of the components of `loops` (this store's [`loops`](Self::loops)) that hold a
    /// session the last update added or replaced, with itself or another: the components the
    /// update added. O(components).
    pub fn added_components(&self, loops: &StoreLoops) -> Vec<usize> {
        let changed: HashSet<usize> =
            self.last_update.changed().into_iter().filter_map(|name| self.session_index(name)).collect();
        loops.components_of(&changed)
    }

    /// The passes of the stored sessions within `radius` of `place` (γ when `None`), in
    /// session order and time order within a session, as [`passes_near`](crate::passes_near)
    /// finds them in each session's poses, read from `source` one session at a time.
    ///
    /// Under the Euclidean metric, whose distance bounds the distance in the map plane, the
    /// stored blocks' bounding balls rule out the blocks far from the place: a session with no
    /// block near is not read, and only the poses of the blocks near are looked at. Time:
    /// O(blocks × the place's vertices + the poses of the blocks near × the place's vertices).
    ///
    /// # Errors
    /// As [`passes_near`](crate::passes_near); [`Error::InvalidState`] for a session that
    /// `source` gives with another content; `source`'s errors.
    pub fn near(&self, place: &Place, radius: Option<f64>, source: &mut SessionSource<'_>) -> Result<Vec<StorePass>> {
        let radius = radius.unwrap_or(self.settings.gamma);
        check_radius(radius)?;
        let mut passes = Vec::new();
        for (session, s) in self.sessions.iter().enumerate() {
            check_plane(s.manifold, s.blocks.dim)?;
            let near = self.blocks_near(s, place, radius);
            if !near.iter().any(|&n| n) {
                continue;
            }
            let trajectory = read_session(s, source)?;
            let mut found = Vec::new();
            let mut k = 0;
            while k < near.len() {
                if !near[k] {
                    k += 1;
                    continue;
                }
                let first = k;
                while k < near.len() && near[k] {
                    k += 1;
                }
                let block = s.blocks.block;
                passes_within(&trajectory, place, radius, first * block..(k * block).min(s.poses()), &mut found);
            }
            passes.extend(found.into_iter().map(|pass| StorePass { session, pass }));
        }
        Ok(passes)
    }

    /// Whether each block of `session` may hold a pose within `radius` of `place` in the map
    /// plane: every block under the Euclidean metric (which bounds the plane's distance) whose
    /// ball reaches the place, every block under the others.
    fn blocks_near(&self, session: &StoreSession, place: &Place, radius: f64) -> Vec<bool> {
        let blocks = &session.blocks;
        if !matches!(self.settings.metric, MetricSpec::Euclidean) {
            return vec![true; blocks.len()];
        }
        (0..blocks.len())
            .map(|k| {
                let centre = &blocks.centres[k * blocks.dim..];
                // A pose within `radius` lies within radius + r of the centre; the slack covers
                // the rounding of both distances.
                let reach = (radius + blocks.radii[k]) * (1.0 + 1e-9) + 1e-9;
                place.distance([centre[0], centre[1]]) <= reach
            })
            .collect()
    }

    /// The fleet's loops, from the merges of each session pair's tiles that the store keeps (an
    /// update merges the pairs it scanned): O(components log components + tiles).
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for summaries that do not fit together (a corrupt store).
    pub fn loops(&self) -> Result<StoreLoops> {
        let starts = self.starts();
        if self.tiles.is_empty() {
            return Ok(StoreLoops { merged: None, components: Vec::new(), session_pairs: Vec::new(), starts });
        }
        let merged = JoinedMerges::new(self.kept.merges.values().cloned().collect());
        let components = merged.fleet_components(&starts)?;
        let spans: Vec<f64> = self.sessions.iter().map(|s| s.blocks.span_s).collect();
        let session_pairs = merged.session_pairs(&spans)?;
        Ok(StoreLoops { merged: Some(merged), components, session_pairs, starts })
    }

    /// τ of every pose, split as [`FleetLoops::loop_duration`](crate::fleet::FleetLoops::loop_duration)
    /// splits it: `(own, other)`, seconds, by fleet index, as the store keeps it (an update adds
    /// the shares of its new tiles, and adds up again the sessions that lost a tile): O(poses).
    ///
    /// # Errors
    /// [`Error::InconsistentTiles`] for a share outside its session (a corrupt store).
    pub fn loop_duration(&self) -> Result<(Vec<f64>, Vec<f64>)> {
        let poses = self.sessions.iter().map(StoreSession::poses).sum();
        let (mut own, mut other) = (Vec::with_capacity(poses), Vec::with_capacity(poses));
        for (o, x) in &self.kept.duration {
            own.extend_from_slice(o);
            other.extend_from_slice(x);
        }
        Ok((own, other))
    }

    /// The samples of `sampler` (a sampler of components) over `loops` (this store's
    /// [`loops`](Self::loops)), by keyed draws: those of [`sample_fleet`](crate::fleet::sample_fleet)
    /// over the store's sessions, with `between_only` as there. Reads the tiles each pass asks
    /// from the runs kept by the update that scanned them, or rescans those it has none of
    /// (a store read back), reading their stored sessions from `source` (each once).
    ///
    /// The store keeps what the draws of its last few seeds found, per tile and component, in
    /// the sessions' own indices (pairs are keyed by session: [`KeyLayout`]): the uniform
    /// picks' pools and the closest pairs of the rows asked. A draw after an update reads a tile
    /// again only for the components it lacks an answer of (those of the new tiles, those whose
    /// quota grew past what was kept, those whose quota or rows moved), and does not read the
    /// sessions of the tiles it needs nothing more from. Quotas and rows follow from each
    /// component's own cells and its session pair's numbers, so a day's sessions move few of
    /// them. The samples are the same with or without it; σ_α keeps nothing (it asks a share of
    /// every component).
    ///
    /// # Errors
    /// As [`KeyedDraw::with_keys`]; the scans' errors; [`Error::InvalidState`] for a session that
    /// `source` gives with another content; `source`'s errors.
    pub fn samples(
        &self,
        loops: &StoreLoops,
        sampler: &Sampler,
        between_only: bool,
        source: &mut SessionSource<'_>,
    ) -> Result<StoreSamples> {
        let Some(merged) = &loops.merged else {
            let draw = KeyedDraw::new(sampler, &[], &|_| true)?;
            let warnings = draw.warnings().to_vec();
            return Ok(StoreSamples {
                rows: Vec::new(),
                groups: 0,
                available: 0,
                warnings,
                tiles_rescanned: 0,
                tiles_read: 0,
                tiles_asked: 0,
            });
        };
        let blocks: Vec<[usize; 2]> = merged.components().map(|m| m.sessions).collect();
        let keep = |c: usize| !between_only || blocks[c][0] != blocks[c][1];
        let names: Vec<&str> = self.sessions.iter().map(|s| s.name.as_str()).collect();
        let keys = KeyLayout::sessions(&loops.starts, &names);
        let stats = merged.draw_stats();
        let mut draw = KeyedDraw::with_keys(sampler, &stats, &keep, keys)?;
        let mut read: HashMap<usize, Trajectory> = HashMap::new();
        let (mut tiles_rescanned, mut tiles_read, mut tiles_asked) = (0, 0, 0);
        let settings = self.settings;
        let starts = &loops.starts;
        // The stored tile of a tile of the merge: the stored tiles are in plan order, by first
        // row, then first column.
        let stored = |tile: &Tile| {
            let key = |t: &KeptTile| (t.tile().rows.start, t.tile().columns.start);
            let k = self.tiles.binary_search_by_key(&(tile.rows.start, tile.columns.start), key).ok()?;
            (self.tiles[k].tile() == tile).then_some(k)
        };
        let holders = Holders::of(merged);
        // What the last draw of this seed found, and what this one finds (kept after it).
        let identity: Vec<(u64, u64)> =
            self.sessions.iter().map(|s| (KeyLayout::salt(&s.name), s.fingerprint)).collect();
        let settings_word = {
            let mut f = Fingerprint::new(0x7365_7474);
            f.eat_settings(&self.settings);
            f.finish()
        };
        let pool_key = |k: usize, c: usize| {
            let tile = &merged.tiles()[k];
            let [a, b] = tile.sessions;
            let s = &stats[c];
            PoolKey::new(
                (sampler.seed, settings_word),
                [identity[a], identity[b]],
                [tile.rows.start - starts[a], tile.columns.start - starts[b]],
                // (A trivial component's closest pair is not its own: any word will do.)
                (
                    [s.rows[0].wrapping_sub(starts[a]), s.rows[1].wrapping_sub(starts[a])],
                    [s.closest_pair[0].wrapping_sub(starts[a]), s.closest_pair[1].wrapping_sub(starts[b])],
                    s.pairs,
                ),
            )
        };
        // σ_α asks every component for a share of its pairs: a cache would hold that share of
        // them all, so it reads the tiles each time.
        let caching = sampler.kind != SamplerKind::Alpha;
        let mut last = {
            let mut pools = self.kept.pools.lock().unwrap_or_else(|e| e.into_inner());
            pools.iter().position(|(seed, _)| *seed == sampler.seed).map(|k| pools.remove(k).1).unwrap_or_default()
        };
        let mut found = Pools::new();
        while let Some(request) = draw.request().cloned() {
            // Each tile's part: what the cache holds is answered here; the rest (the rows and
            // pools it lacks, pools looked up with a slack) by the tile's runs.
            let mut cached = DrawCandidates::default();
            let mut asked: Vec<TilePart> = Vec::new();
            let parts = tile_parts(merged, &holders, &request);
            tiles_asked += parts.len();
            for (k, mut part) in parts {
                let [a, b] = merged.tiles()[k].sessions;
                let mut missed = Vec::new();
                // A cached offer as this draw has it: its fleet indices, this draw's component id.
                let global = |p: &DrawCandidate, component: usize| DrawCandidate {
                    component,
                    pair: [p.pair[0] + starts[a], p.pair[1] + starts[b]],
                    ..*p
                };
                part.components.retain_mut(|c| {
                    if !caching {
                        return true;
                    }
                    let key = pool_key(k, c.id);
                    // An entry moves from the last draw's to this one's the first time it is read.
                    if !found.contains_key(&key)
                        && let Some((key, entry)) = last.remove_entry(&key)
                    {
                        found.insert(key, entry);
                    }
                    let entry = found.get(&key);
                    let mut asked_pool = None;
                    if let Some(threshold) = c.pool {
                        match entry.and_then(|e| e.pool.as_ref()).filter(|e| e.answers(threshold, c.keep)) {
                            Some(pool) => {
                                let below = pool.pairs.iter().filter(|p| p.key <= threshold).take(c.keep as usize);
                                cached.pool.extend(below.map(|p| global(p, c.id)));
                                c.pool = None;
                            }
                            None => {
                                asked_pool = Some((threshold, c.keep));
                                let wider = pool_slack(threshold, c.keep);
                                (c.pool, c.keep) = (Some(wider.0), wider.1);
                            }
                        }
                    }
                    c.rows.retain(|&r| match entry.and_then(|e| e.rows.get(&(r - starts[a]))) {
                        Some(answer) => {
                            cached.rows.extend(answer.iter().map(|p| global(p, c.id)));
                            false
                        }
                        None => true,
                    });
                    if c.best
                        && let Some(answer) = entry.and_then(|e| e.best)
                    {
                        cached.best.extend(answer.iter().map(|p| global(p, c.id)));
                        c.best = false;
                    }
                    let ask = c.pool.is_some() || c.best || !c.rows.is_empty();
                    if ask {
                        missed.push((key, asked_pool));
                    }
                    ask
                });
                if !part.components.is_empty() {
                    asked.push((k, part, missed));
                }
            }
            let mut unread: Vec<usize> = asked
                .iter()
                .flat_map(|(k, _, _)| merged.tiles()[*k].sessions)
                .filter(|s| !read.contains_key(s))
                .collect();
            unread.sort_unstable();
            unread.dedup();
            let trajectories = read_sessions(&self.sessions, &unread, source)?;
            read.extend(unread.into_iter().zip(trajectories));
            // The runs kept of each tile asked (read, in parallel, where not yet).
            let runs: Vec<Option<&TileRuns>> = asked
                .par_iter()
                .map(|(k, _, _)| stored(&merged.tiles()[*k]).map_or(Ok(None), |t| self.checked_runs(t, starts)))
                .collect::<Result<_>>()?;
            tiles_rescanned += runs.iter().filter(|r| r.is_none()).count();
            tiles_read += asked.len();
            let offers = asked
                .par_iter()
                .zip(&runs)
                .map(|((k, part, _), runs)| {
                    let k = *k;
                    let tile = &merged.tiles()[k];
                    let [a, b] = tile.sessions;
                    let (sessions, at) = ([&read[&a], &read[&b]], [starts[a], starts[b]]);
                    match runs {
                        Some(runs) => with_metric!(&settings.metric, m => draw_tile_runs(
                            sessions, at, m, runs, merged.tile_labels(k), part,
                        )),
                        None => with_metric!(&settings.metric, m => draw_session_tile(
                            sessions,
                            at,
                            m,
                            settings.gamma,
                            settings.separation,
                            tile,
                            merged.tile_labels(k),
                            part,
                        )),
                    }
                })
                .collect::<Result<Vec<DrawCandidates>>>()?;
            draw.absorb(cached);
            for ((k, part, missed), mut offer) in asked.into_iter().zip(offers) {
                let [a, b] = merged.tiles()[k].sessions;
                if caching {
                    // The offers as the cache keeps them: pools by component (sorted by key),
                    // rows by component and row, in the sessions' own indices.
                    let local = |p: &DrawCandidate| DrawCandidate {
                        pair: [p.pair[0] - starts[a], p.pair[1] - starts[b]],
                        ..*p
                    };
                    let mut pools: HashMap<usize, Vec<DrawCandidate>> = HashMap::new();
                    for p in &offer.pool {
                        pools.entry(p.component).or_default().push(local(p));
                    }
                    let rows: HashMap<(usize, usize), DrawCandidate> =
                        offer.rows.iter().map(|p| ((p.component, p.pair[0]), local(p))).collect();
                    let best: HashMap<usize, DrawCandidate> =
                        offer.best.iter().map(|p| (p.component, local(p))).collect();
                    // What the tile was asked (pools with their slack) is what the cache keeps.
                    let mut asked_at: HashMap<usize, (u64, u64)> = HashMap::new();
                    for (request, (key, asked_pool)) in part.components.iter().zip(missed) {
                        let c = request.id;
                        let entry = found.entry(key).or_default();
                        if let (Some(threshold), Some(asked)) = (request.pool, asked_pool) {
                            let pairs = pools.remove(&c).unwrap_or_default();
                            entry.pool = Some(PoolEntry { threshold, keep: request.keep, pairs });
                            asked_at.insert(c, asked);
                        }
                        for &r in &request.rows {
                            entry.rows.insert(r - starts[a], rows.get(&(c, r)).copied());
                        }
                        if request.best {
                            entry.best = Some(best.get(&c).copied());
                        }
                    }
                    // The draw gets what it asked: at most its threshold, its count.
                    offer.pool.retain(|p| p.key <= asked_at[&p.component].0);
                    offer.keep_smallest(&|c| asked_at[&c].1);
                }
                draw.absorb(offer);
            }
            draw.complete();
        }
        if caching {
            // What earlier draws of the seed found and this one did not read stays while its
            // two sessions do (another sampler or budget may ask it again); what a session
            // replaced or removed held goes. The entries are what draws asked, never all pairs.
            let live: HashSet<(u64, u64)> = identity.iter().copied().collect();
            for (key, entry) in last {
                if key.sessions.iter().all(|s| live.contains(s)) {
                    found.entry(key).or_insert(entry);
                }
            }
            let mut pools = self.kept.pools.lock().unwrap_or_else(|e| e.into_inner());
            pools.push((sampler.seed, found));
            let over = pools.len().saturating_sub(POOL_SEEDS);
            pools.drain(..over);
        }
        let rows = draw
            .picks()
            .unwrap_or_default()
            .iter()
            .map(|p| {
                let (a, pa) = locate(starts, p.pair[0]);
                let (b, pb) = locate(starts, p.pair[1]);
                FleetSample {
                    sessions: [a, b],
                    poses: [pa, pb],
                    times_s: p.times_s,
                    component: Some(p.component),
                    distance: Some(p.distance),
                }
            })
            .collect();
        Ok(StoreSamples {
            rows,
            groups: draw.groups(),
            available: draw.available(),
            warnings: draw.warnings().to_vec(),
            tiles_rescanned,
            tiles_read,
            tiles_asked,
        })
    }
}

/// The settings are valid, and `sessions` in name order with blocks of the settings' size.
fn check_sessions(settings: &StoreSettings, sessions: &[StoreSession]) -> Result<()> {
    settings.check()?;
    let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
    for (k, s) in sessions.iter().enumerate() {
        if k > 0 && sessions[k - 1].name >= s.name {
            return Err(corrupt(format!(
                "session {k} {:?} is not after {:?} in name order",
                s.name,
                sessions[k - 1].name
            )));
        }
        s.blocks.check().map_err(|p| corrupt(format!("session {k} {:?}: {p}", s.name)))?;
        if s.blocks.block != settings.block {
            return Err(corrupt(format!(
                "session {k} {:?} is cut into blocks of {} poses, the store into blocks of {}",
                s.name, s.blocks.block, settings.block
            )));
        }
    }
    Ok(())
}

/// The merges saved of a store's session pairs, checked to be those of its `tiles`: one for
/// each session pair with tiles, over its tiles in plan order. O(tiles + components).
fn checked_merges(
    sessions: &[StoreSession],
    tiles: &[KeptTile],
    merges: Vec<([usize; 2], MergedLoops)>,
) -> Result<BTreeMap<[usize; 2], Arc<MergedLoops>>> {
    let starts = starts_of(sessions);
    let corrupt = |reason: String| Error::InvalidState { what: "fleet store", reason };
    let mut of_pair: BTreeMap<[usize; 2], Vec<&Tile>> = BTreeMap::new();
    for t in tiles {
        of_pair.entry(t.tile().sessions).or_default().push(t.tile());
    }
    if merges.len() != of_pair.len() {
        return Err(corrupt(format!("{} merges for the {} session pairs with tiles", merges.len(), of_pair.len())));
    }
    // Each merge against its pair's tiles, in parallel; the first misfit in the order given.
    let misfit = merges.par_iter().find_map_first(|(pair, merge)| {
        let Some(tiles) = of_pair.get(pair) else {
            return Some(format!("a merge of sessions {pair:?}, which have no tiles"));
        };
        let fits =
            merge.tiles().iter().eq(tiles.iter().copied()) && merge.components().iter().all(|c| c.sessions == *pair);
        if !fits {
            return Some(format!("the merge of sessions {pair:?} is not of their {} tiles", tiles.len()));
        }
        let sides = pair.map(|s| starts[s]..starts[s] + sessions[s].poses());
        merge.components().iter().enumerate().find_map(|(k, c)| {
            component_misfit(c, &sides).map(|what| format!("component {k} of the merge of sessions {pair:?}: {what}"))
        })
    });
    if let Some(reason) = misfit {
        return Err(corrupt(reason));
    }
    let mut kept = BTreeMap::new();
    for (pair, merge) in merges {
        if kept.insert(pair, Arc::new(merge)).is_some() {
            return Err(corrupt(format!("two merges of sessions {pair:?}")));
        }
    }
    Ok(kept)
}

/// What is wrong with a merged component's numbers for a component of its session pair, whose
/// rows and columns are `sides` (fleet indices), if anything: its extents, rows and closest
/// pairs within them and in order, its pair count within its rows and columns, its measures
/// finite, a trivial one within one session. What a damaged or altered file would get wrong,
/// found when the store opens rather than in a wrong answer.
fn component_misfit(c: &MergedComponent, sides: &[std::ops::Range<usize>; 2]) -> Option<String> {
    let (lc, draw) = (&c.component, &c.draw);
    let span =
        |r: [usize; 2], side: &std::ops::Range<usize>| r[0] <= r[1] && side.contains(&r[0]) && side.contains(&r[1]);
    let cell = |p: [usize; 2]| sides[0].contains(&p[0]) && sides[1].contains(&p[1]);
    let rows = draw.rows[1].wrapping_sub(draw.rows[0]) as u128 + 1;
    let (rows_of, columns_of) = (&sides[0], &sides[1]);
    if !span(lc.i_range, rows_of) || !span(lc.j_range, columns_of) || !span(draw.rows, rows_of) {
        return Some(format!(
            "rows {:?}, columns {:?} and rows drawn {:?}, outside rows {rows_of:?} and columns {columns_of:?}",
            lc.i_range, lc.j_range, draw.rows
        ));
    }
    if !cell(lc.closest_pair) || !(draw.trivial || cell(draw.closest_pair)) {
        return Some(format!("closest pairs {:?} and {:?} outside its sessions", lc.closest_pair, draw.closest_pair));
    }
    if draw.trivial != lc.trivial || (lc.trivial && c.sessions[0] != c.sessions[1]) {
        return Some(format!("trivial {} and {} between sessions {:?}", lc.trivial, draw.trivial, c.sessions));
    }
    if u128::from(draw.pairs) > rows * columns_of.len() as u128 {
        return Some(format!("{} pairs in rows {:?}", draw.pairs, draw.rows));
    }
    let finite = |x: f64| x >= 0.0 && x.is_finite();
    if !finite(lc.area_s2) || !finite(lc.closest_distance) || !c.times_s.iter().flatten().all(|t| t.is_finite()) {
        return Some(format!(
            "area {} s², closest distance {}, times {:?}",
            lc.area_s2, lc.closest_distance, c.times_s
        ));
    }
    None
}

/// The merges of the tiles of each session pair among `tiles` (all the tiles of each pair),
/// by pair: pairs in parallel, each pair's tiles in plan order. O(their components and edge
/// runs).
fn merges_of<'a>(tiles: impl Iterator<Item = &'a StoredTile>) -> Result<BTreeMap<[usize; 2], Arc<MergedLoops>>> {
    let mut of_pair: BTreeMap<[usize; 2], Vec<&StoredTile>> = BTreeMap::new();
    for t in tiles {
        of_pair.entry(t.tile().sessions).or_default().push(t);
    }
    of_pair
        .into_par_iter()
        .map(|(pair, mut tiles)| {
            tiles.sort_by_key(|t| (t.tile().rows.start, t.tile().columns.start));
            let parts = tiles.iter().map(|t| TileMerge::new(t.summary.clone())).collect::<Result<Vec<_>>>()?;
            Ok((pair, Arc::new(TileMerge::merge(parts)?.finish()?)))
        })
        .collect()
}

/// τ of the sessions `which` (indices), `(own, other)` per pose, from all their tiles, in the
/// order of `which`. O(their tiles' rows and columns).
fn durations_of(
    tiles: &[&StoredTile],
    starts: &[usize],
    sessions: &[StoreSession],
    which: &[usize],
) -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
    let wanted: HashSet<usize> = which.iter().copied().collect();
    let mut of_session: HashMap<usize, Vec<&TileDuration>> = HashMap::new();
    for t in tiles {
        let [a, b] = t.tile().sessions;
        for s in if a == b { vec![a] } else { vec![a, b] } {
            if wanted.contains(&s) {
                of_session.entry(s).or_default().push(&t.duration);
            }
        }
    }
    which
        .par_iter()
        .map(|&s| {
            let parts = of_session.get(&s).into_iter().flatten().copied();
            crate::tile::draw::session_loop_duration(s, starts[s], sessions[s].poses(), parts)
        })
        .collect()
}

/// The tiles of a merge that hold each of its components, in tile order: one list of tiles
/// cut by component (a vector each would be hundreds of thousands of small allocations).
struct Holders {
    /// Where each component's tiles start in `tiles`, and where the last one's end.
    starts: Vec<usize>,
    tiles: Vec<usize>,
}

impl Holders {
    /// The holders of `merged`'s components, from its tiles' labels. O(labels).
    fn of(merged: &JoinedMerges) -> Self {
        let n = merged.len();
        // Each (component, tile) once, in tile order, however many of the tile's labels name
        // the component.
        let each_holding = |f: &mut dyn FnMut(usize, usize)| {
            let mut last = vec![usize::MAX; n];
            for k in 0..merged.tiles().len() {
                for &c in merged.tile_labels(k) {
                    if std::mem::replace(&mut last[c as usize], k) != k {
                        f(c as usize, k);
                    }
                }
            }
        };
        let mut starts = vec![0usize; n + 1];
        each_holding(&mut |c, _| starts[c + 1] += 1);
        for c in 0..n {
            starts[c + 1] += starts[c];
        }
        let mut next = starts.clone();
        let mut tiles = vec![0; starts[n]];
        each_holding(&mut |c, k| {
            tiles[next[c]] = k;
            next[c] += 1;
        });
        Holders { starts, tiles }
    }

    /// The tiles that hold component `c`, in tile order.
    fn of_component(&self, c: usize) -> &[usize] {
        &self.tiles[self.starts[c]..self.starts[c + 1]]
    }
}

/// The part of `request` each tile of `merged` that holds a component asked about must answer
/// (by the merge's tile index, in tile order): what [`tile_requests`](crate::tile::tile_requests)
/// gives for the tiles it asks something, found from `holders` (the tiles of each component)
/// rather than by going through every tile. O(the tiles of the components asked).
fn tile_parts(merged: &JoinedMerges, holders: &Holders, request: &DrawRequest) -> Vec<(usize, DrawRequest)> {
    let mut parts: BTreeMap<usize, Vec<ComponentRequest>> = BTreeMap::new();
    for c in &request.components {
        for &k in holders.of_component(c.id) {
            let rows = &merged.tiles()[k].rows;
            let lo = c.rows.partition_point(|&r| r < rows.start);
            let hi = c.rows.partition_point(|&r| r < rows.end);
            let part =
                ComponentRequest { id: c.id, pool: c.pool, keep: c.keep, rows: c.rows[lo..hi].to_vec(), best: c.best };
            if part.pool.is_some() || part.best || !part.rows.is_empty() {
                parts.entry(k).or_default().push(part);
            }
        }
    }
    parts
        .into_iter()
        .map(|(k, components)| {
            let keys = request.keys.narrowed(merged.tiles()[k].sessions);
            (k, DrawRequest { seed: request.seed, keys, components })
        })
        .collect()
}

/// A stored session's poses from `source`, checked against what the store knows of it.
fn read_session(session: &StoreSession, source: &mut SessionSource<'_>) -> Result<Trajectory> {
    let trajectory = source(session)?;
    check_read(session, &trajectory)?;
    Ok(trajectory)
}

/// `trajectory` has the pose count and fingerprint of `session`.
fn check_read(session: &StoreSession, trajectory: &Trajectory) -> Result<()> {
    if trajectory.len() != session.poses() || session_fingerprint(trajectory) != session.fingerprint {
        return Err(Error::InvalidState {
            what: "fleet store",
            reason: format!(
                "the poses read for session {:?} ({} poses) are not those stored ({} poses, fingerprint {:016x})",
                session.name,
                trajectory.len(),
                session.poses(),
                session.fingerprint
            ),
        });
    }
    Ok(())
}

/// The poses of `sessions[s]` for each `s` of `which`, from `source` (called in that order),
/// each checked as [`read_session`] checks it, the checks in parallel; the first that fails,
/// in that order, is the error.
fn read_sessions(
    sessions: &[StoreSession],
    which: &[usize],
    source: &mut SessionSource<'_>,
) -> Result<Vec<Trajectory>> {
    let mut read = Vec::with_capacity(which.len());
    for &s in which {
        read.push(source(&sessions[s])?);
    }
    let checks: Vec<Result<()>> = which.par_iter().zip(&read).map(|(&s, t)| check_read(&sessions[s], t)).collect();
    checks.into_iter().collect::<Result<()>>()?;
    Ok(read)
}

/// The first fleet index of each of `sessions` (in the store's order): where
/// [`StoredTile::placed`] puts a tile of theirs.
pub fn starts_of(sessions: &[StoreSession]) -> Vec<usize> {
    let mut next = 0;
    sessions
        .iter()
        .map(|s| {
            let start = next;
            next += s.poses();
            start
        })
        .collect()
}

/// (session, pose) of fleet index `f`.
fn locate(starts: &[usize], f: usize) -> (usize, usize) {
    let a = starts.partition_point(|&s| s <= f) - 1;
    (a, f - starts[a])
}

/// A store's loops ([`FleetStore::loops`]).
#[derive(Debug, Clone)]
pub struct StoreLoops {
    merged: Option<JoinedMerges>,
    components: Vec<FleetComponent>,
    session_pairs: Vec<SessionPair>,
    starts: Vec<usize>,
}

impl StoreLoops {
    /// The components in their sessions' poses, by id (as
    /// [`FleetLoops::components`](crate::fleet::FleetLoops::components)).
    pub fn components(&self) -> &[FleetComponent] {
        &self.components
    }

    /// The sparse overlap matrix (as [`FleetLoops::session_pairs`](crate::fleet::FleetLoops::session_pairs)).
    pub fn session_pairs(&self) -> &[SessionPair] {
        &self.session_pairs
    }

    /// The times of each component's extents (`[[t(i0), t(i1)], [t′(j0), t′(j1)]]`, seconds,
    /// each on its session's clock), by id.
    pub fn component_times_s(&self) -> Vec<[[f64; 2]; 2]> {
        self.merged.as_ref().map_or_else(Vec::new, JoinedMerges::times_s)
    }

    /// The sessions that revisit session `session` (an index): those sharing at least one loop
    /// component with it, other than itself, in session order, read from the overlap matrix.
    /// O(session pairs).
    pub fn revisits(&self, session: usize) -> Vec<Revisit> {
        let mut revisits: Vec<Revisit> = self
            .session_pairs
            .iter()
            .filter(|p| p.sessions[0] != p.sessions[1] && p.components > 0 && p.sessions.contains(&session))
            .map(|p| Revisit {
                session: p.sessions[0] + p.sessions[1] - session,
                components: p.components,
                pair_count: p.pair_count,
                area_s2: p.area_s2,
                density: p.density,
            })
            .collect();
        revisits.sort_by_key(|r| r.session);
        revisits
    }

    /// The ids of the components of a session in `sessions` (indices), with itself or another:
    /// after an update, with the sessions it changed, the components it added.
    pub fn components_of(&self, sessions: &HashSet<usize>) -> Vec<usize> {
        // A flag per session: a lookup in a vector, not a hash, for each component.
        let mut named = vec![false; self.starts.len()];
        for &s in sessions {
            if let Some(flag) = named.get_mut(s) {
                *flag = true;
            }
        }
        let of = |s: usize| named.get(s).copied().unwrap_or(false);
        self.components.iter().filter(|c| of(c.sessions[0]) || of(c.sessions[1])).map(|c| c.id).collect()
    }
}

/// A pass of a stored session near a place ([`FleetStore::near`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StorePass {
    /// The session's index (name order).
    pub session: usize,
    /// Its poses and times.
    pub pass: Pass,
}

/// A session that revisits another ([`StoreLoops::revisits`]): their block of the overlap
/// matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Revisit {
    /// The revisiting session's index.
    pub session: usize,
    /// Loop components the two share.
    pub components: usize,
    /// Pose pairs within γ between the two.
    pub pair_count: u64,
    /// Loop area α between the two, s².
    pub area_s2: f64,
    /// Loop density ρ between the two.
    pub density: f64,
}

/// The samples of a store ([`FleetStore::samples`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StoreSamples {
    /// The samples, ordered by pair (fleet order), in their sessions' poses and clocks.
    pub rows: Vec<FleetSample>,
    /// Components with a pair to sample (0 for σ_α).
    pub groups: usize,
    /// Candidate pairs.
    pub available: u64,
    /// Warnings of the quotas.
    pub warnings: Vec<SampleWarning>,
    /// Tiles the draw scanned again, having no runs of them (tile passes, counted once per
    /// pass that asked): 0 where every tile asked has its runs kept.
    pub tiles_rescanned: usize,
    /// Tiles the draw read (from their kept runs or a rescan), counted once per pass that
    /// asked; the others it asked were answered by what an earlier draw with the seed found
    /// in them.
    pub tiles_read: usize,
    /// Tiles the draw asked (once per pass).
    pub tiles_asked: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(threshold: u64, keep: u64, pairs: usize) -> PoolEntry {
        let pair = DrawCandidate { component: 0, pair: [0, 1], key: 0, rank: 0.0, distance: 0.0, times_s: [0.0; 2] };
        PoolEntry { threshold, keep, pairs: vec![pair; pairs] }
    }

    /// Draws saved when a store kept pools only are passed over, not refused: the store reads
    /// back and keeps nothing of them; bytes of that tag with a bad checksum are still refused.
    #[cfg(feature = "serde")]
    #[test]
    fn draws_saved_with_pools_only_are_passed_over() {
        let store = FleetStore::new(StoreSettings::new(5.0)).unwrap();
        let mut old = POOLS_ONLY_TAG.to_vec();
        old.extend_from_slice(&[2, 0, 0x90]);
        old.extend_from_slice(&checksum(&old).to_le_bytes());
        store.keep_draws(&[(7, old.as_slice())]).unwrap();
        assert!(store.kept_draws().is_empty());
        let last = old.len() - 1;
        old[last] ^= 1;
        assert!(store.keep_draws(&[(7, old.as_slice())]).is_err());
    }

    /// An entry answers a lower threshold for as many pairs as it kept; more only when it kept
    /// all it found; never a higher threshold.
    #[test]
    fn a_pool_entry_answers_what_it_holds_only() {
        let full = entry(1000, 4, 4);
        assert!(full.answers(1000, 4) && full.answers(10, 1));
        assert!(!full.answers(1000, 5), "it may have left out smaller keys than a fifth");
        assert!(!full.answers(1001, 1));
        let all = entry(1000, 4, 3);
        assert!(all.answers(500, 40), "it holds every key at most its threshold");
        assert_eq!(pool_slack(100, 3), (200, 8));
        assert_eq!(pool_slack(u64::MAX, u64::MAX), (u64::MAX, u64::MAX));
    }
}

//! A fleet store on disk: a [`FleetStore`] and its answer as a folder of Parquet tables that
//! pandas, pyarrow and DuckDB read, updated atomically.
//!
//! ```text
//! DIR/
//!   loops-store.json      the ownership marker (out_dir::STORE)
//!   store.json            {"format": "inexact-loops fleet store", "version": 5, "state": "state-000003"}
//!   poses/FINGERPRINT.parquet  pose, t_s, cell_s, then one column per coordinate, manifold
//!                         (version 5; before: state-NNNNNN/poses/)
//!   state-000003/         the current state, complete
//!     settings.json       metric, gamma, separation, block, sampler, what the last update did
//!     sessions.parquet    session, name, fingerprint, poses, t_first_s, t_last_s, span_s, dim, manifold, blocks
//!     tiles/GENERATION.parquet  session_a, session_b, fingerprint_a, fingerprint_b, rows_start, rows_end,
//!                         columns_start, columns_end, components, run_count, summary, duration, runs
//!                                                          (version 3; before: tiles.parquet, tile_runs.parquet)
//!     merges/GENERATION.parquet  session_a, session_b, fingerprint_a, fingerprint_b, tiles, components, merge
//!                                                          (version 4; before: merges.parquet, version 2)
//!     draws.parquet       seed, draw                           (version 2, optional)
//!     components.parquet  id, session_a, session_b, a, b, trivial, area_s2, pair_count, run_count, holes,
//!                         i_min, i_max, j_min, j_max, t_min_s, t_max_s, t_prime_min_s, t_prime_max_s,
//!                         closest_i, closest_j, closest_distance, added
//!     session_pairs.parquet  session_a, session_b, a, b, components, pair_count, area_s2, density
//!     loop_duration.parquet  session, pose, own_s, other_s
//!     samples.parquet     session_a, session_b, a, b, i, j, t_s, t_prime_s, component, distance
//! ```
//!
//! Indices `a`, `b` are sessions in name order; `i`, `j` poses within them; times on each
//! session's own clock. `summary`, `duration` and `blocks` are the bytes the tiles ship as
//! ([`loops_core::tile::TileSummary::to_bytes`]). `added` marks the components of the sessions the
//! last update added or replaced.
//!
//! **Tiles by part** (version 3). The folder `tiles` holds the store's tiles in parts, each
//! tile once, with its summary, its share of τ and its runs
//! ([`loops_core::tile::TileRuns::to_bytes`], about 16 bytes a run; `runs` empty and
//! `run_count` −1 where a tile keeps none), each in its two sessions' own indices
//! ([`StoredTile::local`]: as a fleet of those two sessions alone, each from pose 0) and named
//! by its sessions' names and fingerprints, so that a tile's bytes do not change when other
//! sessions come and go. An update links every part of the old state whose tiles are all
//! still the store's and writes the rest (the tiles it scanned, and those of parts that held a
//! replaced or removed session's tiles) as one new part named by the new state's generation:
//! adding a day writes that day's tiles, not the fleet's. A part holds its tiles in row groups
//! of 128 (LZ4 blobs without statistics), and is read lazily: opening a store reads each part's
//! columns that name and place the tiles, holding the file open, and reads a row group's blobs the
//! first time the store needs a tile of it ([`loops_core::store::KeptTile`]): an update that
//! adds sessions reads no old tile (τ starts from `loop_duration.parquet`), one that replaces
//! or removes a session the kept tiles of the sessions that lose one, a draw the runs of the
//! tiles it asks; a part written again copies the bytes of the old tiles it keeps. A damaged
//! blob is named (file and row) when it is read. Stores of version 2 kept the tiles
//! in `tiles.parquet` and their runs in `tile_runs.parquet` (`tile` its row in `tiles.parquet`),
//! in fleet indices; they still read, and their next update writes version 3.
//!
//! **Merges by part** (version 4). The folder `merges` holds the merge of each session pair's
//! tiles ([`loops_core::tile::MergedLoops::to_bytes`]) in parts, as `tiles` holds the tiles:
//! each in its two sessions' own indices ([`loops_core::tile::MergedLoops::local`]), named by
//! their names and fingerprints, the parts whose merges are all still the store's linked, the
//! others written as one new part (at most [`MAX_TILE_PARTS`] parts): adding a day writes the
//! merges of that day's session pairs. Opening a store decodes every merge (in parallel): the
//! components table and the draw need them all. Stores of version 3 kept them in
//! `merges.parquet`, in fleet indices; they still read, and their next update writes version 4.
//!
//! **What the answer is made of** (version 2). Each tile's runs (above), and the merge of each
//! session pair's tiles (`merges.parquet` until version 3)
//! ([`loops_core::tile::MergedLoops::to_bytes`]). A store read back with them draws its samples and
//! makes its next update without scanning a stored tile or merging a stored pair again
//! ([`FleetStore::from_saved_lazily`]; [`FleetStore::from_saved`] for version 2). A store of version 1 (without them) still reads: it merges
//! again on reading and rescans the tiles its first draw asks; its next update writes version 2.
//! `draws.parquet` holds what the last draws found in the tiles (uniform picks' pools, rows'
//! closest pairs), per seed
//! ([`FleetStore::kept_draws`]; the seed as the INT64 of its bits): the next update's draw of a
//! seed there reads again only the tiles and components they do not answer. A state without it
//! (written before it) draws as before.
//!
//! **Pose files beside the states** (version 5). The folder `poses` holds one file a session,
//! named by its fingerprint, shared by the states: an update writes the files of the sessions
//! it adds or replaces (each filled in the scratch folder and then moved to its name, so that a
//! file under a session's name is whole) before the new state is pointed at, and removes, after,
//! those no session of the new state has. An update touches only the pose files of the
//! sessions it changes; until version 4 each state held a hard link to every session's file,
//! made and removed again at every update. Stores of version 4 still read, and their next
//! update moves their pose files into `poses` (links).
//!
//! **Atomic.** An update reads the current state, builds the whole new state in the store's
//! scratch folder, moves it into place under a new name, then replaces `store.json` in one
//! rename, then removes the old state and the pose files it alone had. A run killed at any
//! moment leaves `store.json` naming the old state or the new one, each complete with its pose
//! files; the next update removes what the killed one left.

use std::collections::{HashMap, HashSet};
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use loops_core::{
    MetricSpec, SampleSize, Sampler, SamplerKind, Separation, Trajectory,
    fleet::FleetSample,
    store::{
        FleetStore, SavedTile, ScannedTile, StoreLoops, StoreSamples, StoreSession, StoreSettings, StoreUpdate,
        StoredTile, UpdatePlan,
    },
    tile::{MergedLoops, SessionBlocks, Tile, TileDuration, TileRuns, TileSummary},
};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use serde::{Deserialize, Serialize};

use crate::out_dir::{OutDir, OutDirError, STORE};

/// What `store.json` says a store is.
pub const STORE_FORMAT: &str = "inexact-loops fleet store";

/// Why a store could not be read or updated: one line naming the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// The folder could not be taken or written ([`OutDir`]'s rules).
    #[error(transparent)]
    OutDir(#[from] OutDirError),
    /// A file could not be read or written.
    #[error("{what} {}: {error}", .path.display())]
    Io {
        /// What was being done.
        what: &'static str,
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// A file of the store is not what the store wrote.
    #[error("{}: {reason}", .path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
    /// The core refused the update or the state read back.
    #[error(transparent)]
    Core(#[from] loops_core::Error),
    /// Settings given for an existing store that differ from its own.
    #[error("fleet store {}: {what} is {stored} in the store, not {given}; a store keeps the settings it was made with", .path.display())]
    Settings {
        /// The store.
        path: PathBuf,
        /// The setting.
        what: &'static str,
        /// The store's.
        stored: String,
        /// The one given.
        given: String,
    },
    /// No store in the folder (to read).
    #[error("{}: no fleet store here (no store.json)", .path.display())]
    NotAStore {
        /// The folder.
        path: PathBuf,
    },
}

type Result<T> = std::result::Result<T, StoreError>;

/// A store's settings and sampler, fixed when it is made.
#[derive(Debug, Clone, PartialEq)]
pub struct StoreConfig {
    /// What the answer depends on.
    pub settings: StoreSettings,
    /// The sampler of `samples.parquet`, if any, and whether it samples between sessions only.
    pub sampler: Option<(Sampler, bool)>,
}

/// A store read from its folder.
#[derive(Debug, Clone)]
pub struct StoredFleet {
    /// The folder.
    pub dir: PathBuf,
    /// The current state's folder (a name in `dir`).
    pub state: String,
    /// The store.
    pub store: FleetStore,
    /// Its sampler.
    pub config: StoreConfig,
    /// The files of its state's `tiles/` folder, with the tiles each holds (none for a state
    /// of layout 1 or 2, whose tiles are in one table).
    parts: Vec<TilePart>,
    /// The files of its state's `merges/` folder, with the merges each holds (none for a
    /// state of layout 3 or before, whose merges are in one table).
    merge_parts: Vec<MergePart>,
    /// The folder of its sessions' pose files ([`pose_folder`]).
    pose_dir: PathBuf,
}

/// A session pair's name in a store's folder: its sessions' names and fingerprints (a replaced
/// session's tiles and merges are not its new ones). What names a merge.
#[derive(Debug, Clone, PartialEq, Eq)]
struct PairKey {
    names: [Arc<str>; 2],
    fingerprints: [u64; 2],
}

/// Hashed by the fingerprints alone (equal keys have equal fingerprints, and a fingerprint is
/// already a hash of its session): an update hashes every pair's key to link the parts it keeps.
impl std::hash::Hash for PairKey {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.fingerprints.hash(state);
    }
}

impl PairKey {
    /// The name of the store's session pair `[a, b]`.
    fn of(store: &FleetStore, [a, b]: [usize; 2]) -> Self {
        let s = store.sessions();
        PairKey {
            names: [s[a].name.as_str().into(), s[b].name.as_str().into()],
            fingerprints: [s[a].fingerprint, s[b].fingerprint],
        }
    }
}

/// The columns that name the session pairs `keys`, a row each: the first four columns of a
/// part (`session_a`, `session_b`, `fingerprint_a`, `fingerprint_b`), which [`Names::pair`]
/// reads.
fn pair_columns<'a>(keys: impl Iterator<Item = &'a PairKey>) -> Vec<(&'static str, Column)> {
    let mut columns: [Vec<String>; 4] = Default::default();
    for key in keys {
        for side in 0..2 {
            columns[side].push(key.names[side].to_string());
            columns[2 + side].push(fingerprint_text(key.fingerprints[side]));
        }
    }
    ["session_a", "session_b", "fingerprint_a", "fingerprint_b"].into_iter().zip(columns.map(Column::Text)).collect()
}

/// A tile's name in a store's folder: its session pair and its first row and column in their
/// own indices.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct TileKey {
    pair: PairKey,
    at: [usize; 2],
}

impl TileKey {
    /// The name of the store's tile `k`.
    fn of(store: &FleetStore, starts: &[usize], k: usize) -> Self {
        let tile = store.tiles()[k].tile();
        let [a, b] = tile.sessions;
        TileKey { pair: PairKey::of(store, [a, b]), at: [tile.rows.start - starts[a], tile.columns.start - starts[b]] }
    }
}

/// A file of one of a state's folders of parts (`tiles`, `merges`) and what it holds, by key
/// (row by row), with the file as read back where the rows' bytes are read lazily (tiles).
#[derive(Debug, Clone)]
struct Part<K> {
    file: String,
    keys: Vec<K>,
    read: Option<Arc<PartFile>>,
}

/// A part of a state's folder `tiles`.
type TilePart = Part<TileKey>;

/// A part of a state's folder `merges`.
type MergePart = Part<PairKey>;

/// The columns of a part of a state's folder `merges`: each merge in its sessions' own
/// indices ([`MergedLoops::local`]).
const MERGE_COLUMNS: [&str; 7] =
    ["session_a", "session_b", "fingerprint_a", "fingerprint_b", "tiles", "components", "merge"];

/// Tiles a row group of a tile part holds: a reader decodes the blobs of the groups whose
/// tiles it reads, alone.
const PART_GROUP_ROWS: usize = 128;

/// The first of a tile part's blob columns (`summary`, `duration`, `runs`); those before it
/// name and place each tile.
const PART_BLOBS: usize = 10;

/// A tile part read back: its open file, whose first columns are read with the store and
/// whose blobs (each tile's summary, share of τ and runs), a row group at a time, when a tile
/// of that group is first read ([`PartTile`]). The file is held open, so a later state's
/// update may remove its name: it is read until the part is dropped.
struct PartFile {
    path: PathBuf,
    reader: SerializedFileReader<AtFile>,
    /// The first row of each row group.
    groups: Vec<usize>,
    /// Each row group's blob columns, where read.
    blobs: Vec<[OnceLock<GroupBlobs>; 3]>,
    /// Each tile's components and runs (-1 where saved without them), as the file has them.
    counts: Vec<[i64; 2]>,
}

/// One blob column of a row group of a tile part, as read (or why it could not be).
type GroupBlobs = std::result::Result<Vec<ByteArray>, String>;

/// A file that Parquet reads by byte ranges at their offsets (`pread`): the row groups of a
/// part are decoded by several threads at once, and the readers that `File`'s own
/// `ChunkReader` makes share one file position (they are clones of one handle). Written here:
/// the two calls it needs are the standard library's.
struct AtFile {
    file: Arc<File>,
    len: u64,
}

impl AtFile {
    fn open(path: &Path) -> std::io::Result<Self> {
        let file = File::open(path)?;
        let len = file.metadata()?.len();
        Ok(AtFile { file: Arc::new(file), len })
    }
}

/// Reads `buf.len()` bytes or fewer of `file` at `offset`.
fn read_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<usize> {
    #[cfg(unix)]
    return std::os::unix::fs::FileExt::read_at(file, buf, offset);
    #[cfg(windows)]
    return std::os::windows::fs::FileExt::seek_read(file, buf, offset);
}

impl parquet::file::reader::Length for AtFile {
    fn len(&self) -> u64 {
        self.len
    }
}

/// [`AtFile`] read on from an offset.
struct AtRead {
    file: Arc<File>,
    at: u64,
}

impl std::io::Read for AtRead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = read_at(&self.file, buf, self.at)?;
        self.at += n as u64;
        Ok(n)
    }
}

impl parquet::file::reader::ChunkReader for AtFile {
    /// Buffered: a page header is read a few bytes at a time.
    type T = std::io::BufReader<AtRead>;

    fn get_read(&self, start: u64) -> parquet::errors::Result<Self::T> {
        Ok(std::io::BufReader::with_capacity(4096, AtRead { file: self.file.clone(), at: start }))
    }

    fn get_bytes(&self, start: u64, length: usize) -> parquet::errors::Result<bytes::Bytes> {
        let mut buffer = vec![0; length];
        let mut done = 0;
        while done < length {
            match read_at(&self.file, &mut buffer[done..], start + done as u64) {
                Ok(0) => {
                    return Err(parquet::errors::ParquetError::EOF(format!(
                        "{length} bytes at {start}: the file ends after {done}"
                    )));
                }
                Ok(n) => done += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e.into()),
            }
        }
        Ok(buffer.into())
    }
}

impl std::fmt::Debug for PartFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PartFile").field("path", &self.path).field("groups", &self.groups).finish_non_exhaustive()
    }
}

impl PartFile {
    /// The bytes of blob `which` (0: summary, 1: share of τ, 2: runs) of the tile in `row`,
    /// its row group decoded the first time.
    fn blob(&self, which: usize, row: usize) -> std::result::Result<&[u8], String> {
        let g = self.groups.partition_point(|&first| first <= row).saturating_sub(1);
        let read = self.blobs[g][which].get_or_init(|| {
            let mut column = Column::Blobs(Vec::new());
            read_chunk(&self.reader, &self.path, g, PART_BLOBS + which, usize::MAX, &mut column)
                .map_err(|e| e.to_string())?;
            match column {
                Column::Blobs(values) => Ok(values),
                _ => unreachable!("read as blobs"),
            }
        });
        let values = read.as_ref().map_err(Clone::clone)?;
        values.get(row - self.groups[g]).map(ByteArray::data).ok_or_else(|| format!("no row {row}"))
    }
}

/// A tile of a part read back, read when the store first needs it ([`SavedTile`]): row `row`
/// of `part`, which starts at `at` in its sessions' own indices.
#[derive(Debug)]
struct PartTile {
    part: Arc<PartFile>,
    row: usize,
    at: [usize; 2],
}

impl PartTile {
    fn corrupt(&self, reason: String) -> loops_core::Error {
        let path = self.part.path.display();
        loops_core::Error::InvalidState { what: "fleet store", reason: format!("{path}: row {}: {reason}", self.row) }
    }

    /// `tile` starts where the part's columns say.
    fn check_at(&self, tile: &loops_core::tile::Tile) -> std::result::Result<(), String> {
        if [tile.rows.start, tile.columns.start] != self.at {
            return Err(format!("its blobs are of tile {tile:?}, which does not start at {:?}", self.at));
        }
        Ok(())
    }
}

impl SavedTile for PartTile {
    fn stored(&self) -> loops_core::Result<StoredTile> {
        let read = || -> std::result::Result<StoredTile, String> {
            let summary = TileSummary::from_bytes(self.part.blob(0, self.row)?).map_err(|e| e.to_string())?;
            let duration = TileDuration::from_bytes(self.part.blob(1, self.row)?).map_err(|e| e.to_string())?;
            self.check_at(&summary.tile)?;
            Ok(StoredTile { summary, duration })
        };
        read().map_err(|reason| self.corrupt(reason))
    }

    fn runs(&self) -> loops_core::Result<Option<TileRuns>> {
        let read = || -> std::result::Result<Option<TileRuns>, String> {
            let bytes = self.part.blob(2, self.row)?;
            if bytes.is_empty() {
                return Ok(None);
            }
            let runs = TileRuns::from_bytes(bytes).map_err(|e| e.to_string())?;
            self.check_at(runs.tile())?;
            Ok(Some(runs))
        };
        read().map_err(|reason| self.corrupt(reason))
    }
}

impl StoredFleet {
    /// The poses of a stored session, from its pose file.
    ///
    /// # Errors
    /// [`StoreError::Io`] or [`StoreError::Corrupt`] for a pose file that cannot be read back.
    pub fn poses(&self, session: &StoreSession) -> Result<Trajectory> {
        read_poses(&self.pose_dir.join(pose_file(session)))
    }

    /// The path of one of the current state's tables (`components.parquet`, ...).
    pub fn table(&self, name: &str) -> PathBuf {
        self.dir.join(&self.state).join(name)
    }

    /// The passes of the stored sessions within `radius` of `place` (γ when `None`), their
    /// poses read from the pose files ([`FleetStore::near`]).
    ///
    /// # Errors
    /// The core's errors on the place and radius, or on a pose file that cannot be read back.
    pub fn near(&self, place: &loops_core::Place, radius: Option<f64>) -> Result<Vec<loops_core::store::StorePass>> {
        let mut source = |s: &StoreSession| -> loops_core::Result<Trajectory> {
            self.poses(s).map_err(|e| loops_core::Error::InvalidState { what: "fleet store", reason: e.to_string() })
        };
        Ok(self.store.near(place, radius, &mut source)?)
    }

    /// The sessions' names, in the store's order.
    pub fn names(&self) -> Vec<&str> {
        self.store.sessions().iter().map(|s| s.name.as_str()).collect()
    }
}

/// `store.json`.
#[derive(Debug, Serialize, Deserialize)]
struct Pointer {
    format: String,
    version: u16,
    state: String,
}

/// `settings.json` of a state.
#[derive(Debug, Serialize, Deserialize)]
struct SettingsFile {
    version: u16,
    metric: String,
    gamma: f64,
    separation_path: f64,
    separation_time_s: f64,
    block: usize,
    sampler: Option<SamplerFile>,
    last_update: UpdateFile,
}

#[derive(Debug, Serialize, Deserialize)]
struct SamplerFile {
    kind: String,
    budget: Option<usize>,
    rate: Option<f64>,
    seed: u64,
    skip_trivial: bool,
    between_only: bool,
}

#[derive(Debug, Default, Serialize, Deserialize)]
struct UpdateFile {
    added: Vec<String>,
    replaced: Vec<String>,
    unchanged: Vec<String>,
    removed: Vec<String>,
    tiles_scanned: usize,
    tiles_kept: usize,
    tiles_dropped: usize,
}

impl From<&StoreUpdate> for UpdateFile {
    fn from(u: &StoreUpdate) -> Self {
        Self {
            added: u.added.clone(),
            replaced: u.replaced.clone(),
            unchanged: u.unchanged.clone(),
            removed: u.removed.clone(),
            tiles_scanned: u.tiles_scanned,
            tiles_kept: u.tiles_kept,
            tiles_dropped: u.tiles_dropped,
        }
    }
}

impl From<UpdateFile> for StoreUpdate {
    fn from(u: UpdateFile) -> Self {
        StoreUpdate {
            added: u.added,
            replaced: u.replaced,
            unchanged: u.unchanged,
            removed: u.removed,
            tiles_scanned: u.tiles_scanned,
            tiles_kept: u.tiles_kept,
            tiles_dropped: u.tiles_dropped,
        }
    }
}

fn settings_file(config: &StoreConfig, update: &StoreUpdate) -> SettingsFile {
    let s = &config.settings;
    SettingsFile {
        version: loops_core::store::STORE_FORMAT_VERSION,
        metric: s.metric.name(),
        gamma: s.gamma,
        separation_path: s.separation.path,
        separation_time_s: s.separation.time_s,
        block: s.block,
        sampler: config.sampler.as_ref().map(|(sampler, between_only)| SamplerFile {
            kind: sampler.kind.name().to_owned(),
            budget: match sampler.size {
                SampleSize::Budget(b) => Some(b),
                _ => None,
            },
            rate: match sampler.size {
                SampleSize::Rate(r) => Some(r),
                _ => None,
            },
            seed: sampler.seed,
            skip_trivial: sampler.skip_trivial,
            between_only: *between_only,
        }),
        last_update: update.into(),
    }
}

fn config_of(file: &SettingsFile, path: &Path) -> Result<StoreConfig> {
    let corrupt = |reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    if !READABLE_VERSIONS.contains(&file.version) {
        return Err(corrupt(format!(
            "store format version {}; this build reads versions {} to {}",
            file.version,
            READABLE_VERSIONS.start(),
            READABLE_VERSIONS.end()
        )));
    }
    let metric: MetricSpec = file.metric.parse().map_err(|e| corrupt(format!("metric: {e}")))?;
    let separation = Separation { path: file.separation_path, time_s: file.separation_time_s };
    let settings = StoreSettings { metric, gamma: file.gamma, separation, block: file.block };
    let sampler = match &file.sampler {
        None => None,
        Some(s) => {
            let kind: SamplerKind = s.kind.parse().map_err(|e| corrupt(format!("sampler: {e}")))?;
            let size = match (s.budget, s.rate) {
                (Some(b), None) => SampleSize::Budget(b),
                (None, Some(r)) => SampleSize::Rate(r),
                _ => return Err(corrupt("the sampler needs a budget or a rate".to_owned())),
            };
            let sampler = Sampler { skip_trivial: s.skip_trivial, ..Sampler::new(kind, size, s.seed) };
            Some((sampler, s.between_only))
        }
    };
    Ok(StoreConfig { settings, sampler })
}

/// The pose file of a session: named by its fingerprint.
fn pose_file(session: &StoreSession) -> String {
    format!("{}.parquet", fingerprint_text(session.fingerprint))
}

/// The folder of a store's pose files (version 5 on), beside its states: each session's file
/// is written once, by the update that adds the session, and removed by the update that
/// replaces or removes it, once the new state is pointed at, so that an update touches only
/// the pose files of the sessions it changes (before, each state held a link to every
/// session's file).
const POSES: &str = "poses";

/// Whether `name` is that of a pose file ([`pose_file`]): 16 hexadecimal digits and `.parquet`.
fn is_pose_file_name(name: &str) -> bool {
    name.strip_suffix(".parquet").is_some_and(|n| n.len() == 16 && n.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// Where the pose files of the state `pointer` names are, in the store `dir`: [`POSES`], or
/// the state's own `poses` folder before version 5.
fn pose_folder(dir: &Path, pointer: &Pointer) -> PathBuf {
    if pointer.version >= 5 { dir.join(POSES) } else { dir.join(&pointer.state).join(POSES) }
}

/// A session's fingerprint as the tables and pose files name it: 16 hexadecimal digits.
fn fingerprint_text(fingerprint: u64) -> String {
    format!("{fingerprint:016x}")
}

/// The fingerprint of [`fingerprint_text`].
fn fingerprint_of(text: &str) -> std::result::Result<u64, String> {
    u64::from_str_radix(text, 16).map_err(|e| format!("fingerprint {text:?}: {e}"))
}

/// Reads the store in `dir`: its current state.
///
/// # Errors
/// [`StoreError::NotAStore`]; [`StoreError::Io`] or [`StoreError::Corrupt`] naming the file
/// that cannot be read back; [`StoreError::Core`] for tables that do not fit together.
pub fn read_store(dir: &Path) -> Result<StoredFleet> {
    let Head { pointer, file, config, sessions } = read_head(dir)?;
    let state = dir.join(&pointer.state);
    let pose_dir = pose_folder(dir, &pointer);
    let last_update = file.last_update.into();
    if file.version >= 3 {
        // The tiles, the merges and τ side by side; the first failure in that order.
        let (tiles, (merges, duration)) = rayon::join(
            || read_parts(&state.join("tiles"), &sessions),
            || {
                rayon::join(
                    || match file.version {
                        4.. => read_merge_parts(&state.join("merges"), &sessions),
                        _ => Ok((read_merges(&state.join("merges.parquet"))?, Vec::new())),
                    },
                    || read_duration(&state.join("loop_duration.parquet"), &sessions),
                )
            },
        );
        let ((tiles, parts), (merges, merge_parts), duration) = (tiles?, merges?, duration?);
        let store = FleetStore::from_saved_lazily(config.settings, sessions, tiles, last_update, merges, duration)?;
        read_draws(&state.join("draws.parquet"), &store)?;
        return Ok(StoredFleet {
            dir: dir.to_path_buf(),
            state: pointer.state,
            store,
            config,
            parts,
            merge_parts,
            pose_dir,
        });
    }
    let corrupt = |path: &Path, reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    let tiles_path = state.join("tiles.parquet");
    let table = read_table(&tiles_path)?;
    let tiles = (0..table.rows)
        .map(|k| -> std::result::Result<StoredTile, String> {
            let summary = TileSummary::from_bytes(table.bytes(7, k)?).map_err(|e| format!("row {k}: {e}"))?;
            let duration = TileDuration::from_bytes(table.bytes(8, k)?).map_err(|e| format!("row {k}: {e}"))?;
            Ok(StoredTile { summary, duration })
        })
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|reason| corrupt(&tiles_path, reason))?;
    let store = if file.version < 2 {
        FleetStore::from_parts(config.settings, sessions, tiles, last_update)?
    } else {
        let (merges, runs) = read_kept(&state, tiles.len())?;
        let store = FleetStore::from_saved(config.settings, sessions, tiles, last_update, merges, runs)?;
        read_draws(&state.join("draws.parquet"), &store)?;
        store
    };
    Ok(StoredFleet {
        dir: dir.to_path_buf(),
        state: pointer.state,
        store,
        config,
        parts: Vec::new(),
        merge_parts: Vec::new(),
        pose_dir,
    })
}

/// A state's tiles, each placed in the store's fleet and read from its part when first needed,
/// and the parts that hold them.
type StoredParts = (Vec<(Tile, Arc<dyn SavedTile>)>, Vec<TilePart>);

/// The tiles of a state of layout 3 (the parts in its folder `tiles`), placed in the fleet of
/// `sessions`, in plan order, and the parts that hold them. Reads each part's columns that
/// name and place the tiles, holding the file open; their blobs are read when the
/// store needs them. O(tiles).
fn read_parts(folder: &Path, sessions: &[StoreSession]) -> Result<StoredParts> {
    use rayon::prelude::*;
    let names = Names::of(sessions);
    let starts = loops_core::store::starts_of(sessions);
    let mut tiles: Vec<(Tile, Arc<dyn SavedTile>)> = Vec::new();
    let mut parts = Vec::new();
    for file in part_files(folder)? {
        let path = folder.join(&file);
        let opened =
            AtFile::open(&path).map_err(|error| StoreError::Io { what: "reading", path: path.clone(), error })?;
        let reader = SerializedFileReader::new(opened).map_err(|e| parquet_corrupt(&path, e))?;
        let corrupt = |reason: String| StoreError::Corrupt { path: path.clone(), reason };
        let table = read_columns(&reader, &path, &|c| c < PART_BLOBS)?;
        if table.names.get(PART_BLOBS..) != Some(&["summary", "duration", "runs"].map(String::from)[..]) {
            return Err(corrupt(format!("columns {:?}, not those of a tile part", table.names)));
        }
        // Each row's tile, key and counts, in parallel; the first bad row in order.
        let row = |k: usize| -> Result<_> {
            let row_of = |e: String| corrupt(format!("row {k}: {e}"));
            let (pair, key) = names.pair(&table, k, "tile").map_err(row_of)?;
            let cell = |c: usize| table.index(c, k).map_err(row_of);
            let (at, ends) = ([cell(4)?, cell(6)?], [cell(5)?, cell(7)?]);
            let side = |s: usize| {
                let (first, end) = (starts[pair[s]] + at[s], starts[pair[s]] + ends[s]);
                (at[s] <= ends[s] && ends[s] <= sessions[pair[s]].poses()).then_some(first..end).ok_or_else(|| {
                    row_of(format!("poses {}..{} of session {:?}", at[s], ends[s], sessions[pair[s]].name))
                })
            };
            let tile = Tile { sessions: pair, rows: side(0)?, columns: side(1)? };
            let counts = [table.int(8, k).map_err(row_of)?, table.int(9, k).map_err(row_of)?];
            Ok((TileKey { pair: key, at }, (tile, k, at), counts))
        };
        let rows: Vec<Result<_>> = (0..table.rows).into_par_iter().map(row).collect();
        let mut keys = Vec::with_capacity(table.rows);
        let mut placed = Vec::with_capacity(table.rows);
        let mut counts = Vec::with_capacity(table.rows);
        for read in rows {
            let (key, tile, count) = read?;
            keys.push(key);
            placed.push(tile);
            counts.push(count);
        }
        let metadata = reader.metadata();
        let mut groups = Vec::with_capacity(metadata.num_row_groups());
        let mut first = 0;
        for g in metadata.row_groups() {
            groups.push(first);
            first += usize::try_from(g.num_rows()).unwrap_or(0);
        }
        let blobs = groups.iter().map(|_| Default::default()).collect();
        let part = Arc::new(PartFile { path: path.clone(), reader, groups, blobs, counts });
        for (tile, row, at) in placed {
            tiles.push((tile, Arc::new(PartTile { part: part.clone(), row, at })));
        }
        parts.push(TilePart { file, keys, read: Some(part) });
    }
    // Plan order: by row block, then column block (fleet indices order both).
    tiles.sort_by_key(|(t, _)| (t.rows.start, t.columns.start));
    Ok((tiles, parts))
}

/// The Parquet files of a folder of parts, in name order.
fn part_files(folder: &Path) -> Result<Vec<String>> {
    let mut files: Vec<String> = std::fs::read_dir(folder)
        .and_then(|list| list.map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned())).collect())
        .map_err(|error| StoreError::Io { what: "listing", path: folder.to_path_buf(), error })?;
    files.retain(|f| f.ends_with(".parquet"));
    files.sort_unstable();
    Ok(files)
}

/// A state's sessions by name: what a part's first four columns (`session_a`, `session_b`,
/// `fingerprint_a`, `fingerprint_b`) name. A part names the same few sessions in row after
/// row, so each session's name is shared by the keys made here, and its fingerprint's text is
/// made once, to compare a row's with before reading its number.
struct Names<'a> {
    sessions: &'a [StoreSession],
    index: HashMap<&'a [u8], usize>,
    names: Vec<Arc<str>>,
    fingerprints: Vec<String>,
}

impl<'a> Names<'a> {
    fn of(sessions: &'a [StoreSession]) -> Self {
        Names {
            sessions,
            index: sessions.iter().enumerate().map(|(k, s)| (s.name.as_bytes(), k)).collect(),
            names: sessions.iter().map(|s| Arc::from(s.name.as_str())).collect(),
            fingerprints: sessions.iter().map(|s| fingerprint_text(s.fingerprint)).collect(),
        }
    }

    /// The session pair that row `k` of a part's `table` names, as indices and as its key:
    /// sessions of the state, as they are now (a `what` of a session as it was before is not
    /// the state's).
    fn pair(&self, table: &Table, k: usize, what: &str) -> std::result::Result<([usize; 2], PairKey), String> {
        let (mut pair, mut fingerprints) = ([0; 2], [0; 2]);
        for side in 0..2 {
            let (name, text) = (table.bytes(side, k)?, table.bytes(2 + side, k)?);
            let Some(&s) = self.index.get(name) else {
                return Err(format!("session {:?} is not in the store", table.text(side, k)?));
            };
            if text != self.fingerprints[s].as_bytes() {
                let (name, text) = (table.text(side, k)?, table.text(2 + side, k)?);
                if self.sessions[s].fingerprint != fingerprint_of(text)? {
                    return Err(format!("a {what} of session {name:?} as it was before (fingerprint {text})"));
                }
            }
            (pair[side], fingerprints[side]) = (s, self.sessions[s].fingerprint);
        }
        let names = pair.map(|s| self.names[s].clone());
        Ok((pair, PairKey { names, fingerprints }))
    }
}

/// The merges of a state of layout 4 (the parts in its folder `merges`), each decoded and
/// placed in the fleet of `sessions` (in parallel), and the parts that hold them. O(merges'
/// bytes).
fn read_merge_parts(folder: &Path, sessions: &[StoreSession]) -> Result<(Merges, Vec<MergePart>)> {
    use rayon::prelude::*;
    let names = Names::of(sessions);
    let starts = loops_core::store::starts_of(sessions);
    let mut merges = Vec::new();
    let mut parts = Vec::new();
    for file in part_files(folder)? {
        let path = folder.join(&file);
        let corrupt = |reason: String| StoreError::Corrupt { path: path.clone(), reason };
        let table = read_table(&path)?;
        if table.names != MERGE_COLUMNS {
            return Err(corrupt(format!("columns {:?}, not those of a merge part", table.names)));
        }
        let rows = (0..table.rows)
            .into_par_iter()
            .map(|k| names.pair(&table, k, "merge").map_err(|e| corrupt(format!("row {k}: {e}"))))
            .collect::<Vec<Result<_>>>()
            .into_iter()
            .collect::<Result<Vec<_>>>()?;
        let decoded = rows
            .par_iter()
            .enumerate()
            .map(|(k, &([a, b], _))| {
                let merge =
                    table.bytes(6, k).and_then(|bytes| MergedLoops::from_bytes(bytes).map_err(|e| e.to_string()));
                merge
                    .map(|m| ([a, b], m.placed([a, b], [starts[a], starts[b]])))
                    .map_err(|e| corrupt(format!("row {k}: {e}")))
            })
            .collect::<Vec<Result<_>>>();
        for merge in decoded {
            merges.push(merge?);
        }
        parts.push(MergePart { file, keys: rows.into_iter().map(|(_, key)| key).collect(), read: None });
    }
    Ok((merges, parts))
}

/// Merges by session pair, in fleet indices, as [`FleetStore::from_saved_lazily`] takes them.
type Merges = Vec<([usize; 2], MergedLoops)>;

/// τ of each session as a state keeps it (`loop_duration.parquet`: a row per pose of each
/// session, in order), by session.
fn read_duration(path: &Path, sessions: &[StoreSession]) -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
    let table = read_table(path)?;
    let corrupt = |reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    let poses: usize = sessions.iter().map(StoreSession::poses).sum();
    if table.rows != poses {
        return Err(corrupt(format!("{} rows for the {poses} poses of the store's sessions", table.rows)));
    }
    let (own, other) = (table.floats(2).map_err(corrupt)?, table.floats(3).map_err(corrupt)?);
    let (at, pose) = (table.ints(0).map_err(corrupt)?, table.ints(1).map_err(corrupt)?);
    let mut first = 0;
    let mut duration = Vec::with_capacity(sessions.len());
    for (s, session) in sessions.iter().enumerate() {
        let end = first + session.poses();
        let rows = at[first..end].iter().zip(&pose[first..end]);
        if let Some((k, (a, p))) = rows.enumerate().find(|&(k, (&a, &p))| (a, p) != (s as i64, k as i64)) {
            return Err(corrupt(format!("row {} is of pose {p} of session {a}, not pose {k} of {s}", first + k)));
        }
        duration.push((own[first..end].to_vec(), other[first..end].to_vec()));
        first = end;
    }
    Ok(duration)
}

/// What a state's small files say: `store.json`, `settings.json` and `sessions.parquet`.
struct Head {
    pointer: Pointer,
    file: SettingsFile,
    config: StoreConfig,
    sessions: Vec<StoreSession>,
}

/// Reads the store's pointer, its current state's settings and sessions: O(sessions + blocks).
fn read_head(dir: &Path) -> Result<Head> {
    let pointer_path = dir.join("store.json");
    if !pointer_path.is_file() {
        return Err(StoreError::NotAStore { path: dir.to_path_buf() });
    }
    let pointer: Pointer = read_json(&pointer_path)?;
    let corrupt = |path: &Path, reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    if pointer.format != STORE_FORMAT || !READABLE_VERSIONS.contains(&pointer.version) {
        return Err(corrupt(
            &pointer_path,
            format!(
                "format {:?} version {}, not {STORE_FORMAT:?} version {}",
                pointer.format,
                pointer.version,
                loops_core::store::STORE_FORMAT_VERSION
            ),
        ));
    }
    if !is_state_name(&pointer.state) {
        return Err(corrupt(&pointer_path, format!("state {:?} is not a state folder's name", pointer.state)));
    }
    let state = dir.join(&pointer.state);
    let settings_path = state.join("settings.json");
    let file: SettingsFile = read_json(&settings_path)?;
    let config = config_of(&file, &settings_path)?;
    let sessions_path = state.join("sessions.parquet");
    let table = read_table(&sessions_path)?;
    let sessions = (0..table.rows)
        .map(|k| -> std::result::Result<StoreSession, String> {
            let blocks = SessionBlocks::from_bytes(table.bytes(9, k)?).map_err(|e| e.to_string())?;
            let fingerprint = fingerprint_of(table.text(2, k)?)?;
            let manifold = table.text(8, k)?;
            let manifold = manifold_of(manifold).ok_or_else(|| format!("manifold {manifold:?} is unknown"))?;
            Ok(StoreSession {
                name: table.text(1, k)?.to_owned(),
                fingerprint,
                manifold,
                times_s: [table.float(4, k)?, table.float(5, k)?],
                blocks,
            })
            .map_err(|e: String| format!("row {k}: {e}"))
        })
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|reason| corrupt(&sessions_path, reason))?;
    Ok(Head { pointer, file, config, sessions })
}

/// The versions of the layout this build reads: those without what the answer is made of
/// (1), and the current one.
const READABLE_VERSIONS: std::ops::RangeInclusive<u16> = 1..=loops_core::store::STORE_FORMAT_VERSION;

/// What a state keeps of its answer: the merges (`merges.parquet`) and the runs of each of its
/// `tiles` tiles (`tile_runs.parquet`).
fn read_kept(state: &Path, tiles: usize) -> Result<KeptParts> {
    let merges = read_merges(&state.join("merges.parquet"))?;
    let runs_path = state.join("tile_runs.parquet");
    let mut runs: Vec<Option<TileRuns>> = vec![None; tiles];
    let table = read_table(&runs_path)?;
    for k in 0..table.rows {
        let corrupt =
            |reason: String| StoreError::Corrupt { path: runs_path.clone(), reason: format!("row {k}: {reason}") };
        let tile = table.index(0, k).map_err(corrupt)?;
        let parsed = TileRuns::from_bytes(table.bytes(4, k).map_err(corrupt)?).map_err(|e| corrupt(e.to_string()))?;
        match runs.get_mut(tile) {
            Some(slot @ None) => *slot = Some(parsed),
            Some(Some(_)) => return Err(corrupt(format!("tile {tile} has runs twice"))),
            None => return Err(corrupt(format!("tile {tile} of {tiles} tiles"))),
        }
    }
    Ok((merges, runs))
}

/// The merge of each session pair's tiles (`merges.parquet`).
fn read_merges(path: &Path) -> Result<Vec<([usize; 2], MergedLoops)>> {
    let table = read_table(path)?;
    (0..table.rows)
        .map(|k| -> std::result::Result<([usize; 2], MergedLoops), String> {
            let row_of = |e: String| format!("row {k}: {e}");
            let pair = [table.index(0, k).map_err(row_of)?, table.index(1, k).map_err(row_of)?];
            let merge =
                MergedLoops::from_bytes(table.bytes(4, k).map_err(row_of)?).map_err(|e| row_of(e.to_string()))?;
            Ok((pair, merge))
        })
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|reason| StoreError::Corrupt { path: path.to_path_buf(), reason })
}

/// What the last draws of a state found (`draws.parquet`, where there is one), given to `store`.
fn read_draws(path: &Path, store: &FleetStore) -> Result<()> {
    if !path.exists() {
        return Ok(());
    }
    let corrupt = |reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    let table = read_table(path)?;
    let mut draws = Vec::with_capacity(table.rows);
    for k in 0..table.rows {
        let seed = table.int(0, k).map_err(|e| corrupt(format!("row {k}: {e}")))? as u64;
        draws.push((seed, table.bytes(1, k).map_err(|e| corrupt(format!("row {k}: {e}")))?));
    }
    store.keep_draws(&draws).map_err(|e| corrupt(e.to_string()))
}

/// The merges and runs a state keeps ([`FleetStore::from_saved`]).
type KeptParts = (Vec<([usize; 2], MergedLoops)>, Vec<Option<TileRuns>>);

/// The samples of the store's current state (`samples.parquet`), in its order: those
/// [`update_store`] drew, read back.
///
/// # Errors
/// [`StoreError::Io`] or [`StoreError::Corrupt`] for a table that cannot be read back.
pub fn read_samples(stored: &StoredFleet) -> Result<Vec<FleetSample>> {
    let path = stored.table("samples.parquet");
    let table = read_table(&path)?;
    (0..table.rows)
        .map(|k| -> std::result::Result<FleetSample, String> {
            let component = table.int(8, k)?;
            let distance = table.float(9, k)?;
            Ok(FleetSample {
                sessions: [table.index(2, k)?, table.index(3, k)?],
                poses: [table.index(4, k)?, table.index(5, k)?],
                times_s: [table.float(6, k)?, table.float(7, k)?],
                component: usize::try_from(component).ok(),
                distance: (!distance.is_nan()).then_some(distance),
            })
            .map_err(|e: String| format!("row {k}: {e}"))
        })
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|reason| StoreError::Corrupt { path, reason })
}

/// What [`update_store`] did.
#[derive(Debug, Clone)]
pub struct StoreReport {
    /// What this update did. When it changes nothing ([`StoreUpdate::changes_nothing`]),
    /// nothing was written: the folder, its files and their times are as they were, and the
    /// store's own `last_update` is still that of the last update that changed it.
    pub update: StoreUpdate,
    /// The store as it now is.
    pub stored: StoredFleet,
    /// Components in all, and those the update added.
    pub components: usize,
    /// Components of the sessions the update added or replaced.
    pub added_components: usize,
    /// The loops written (`components.parquet`, `session_pairs.parquet`).
    pub loops: StoreLoops,
    /// The samples written (`samples.parquet`), if the store has a sampler; `None` too when
    /// nothing was written (they are then the table's, [`read_samples`]).
    pub samples: Option<StoreSamples>,
}

/// Adds or replaces the sessions `put` (by name) and removes `remove` in the store in `dir`,
/// making the store when the folder is missing or empty (with `config`, which must then be
/// given; for an existing store, `config` when given must be the store's own). Scans only the
/// new tiles ([`FleetStore::update`]), then writes the new state atomically (see the module
/// docs). An update of an existing store that changes nothing
/// ([`StoreUpdate::changes_nothing`]: nothing given or removed, or every session given stored
/// with the same content) writes nothing: no new state, no file or time of the folder touched
/// ([`StoreReport::update`] says so).
///
/// # Errors
/// [`StoreError::OutDir`] for a folder that holds anything but a store, or a store in use;
/// [`StoreError::Settings`] for a `config` other than the store's; the core's errors on the
/// update (the store is then unchanged); [`StoreError::Io`] when a file cannot be written.
pub fn update_store(
    dir: &Path,
    config: Option<&StoreConfig>,
    put: Vec<(String, Trajectory)>,
    remove: &[String],
) -> Result<StoreReport> {
    update_with(dir, config, put, remove, None, None)
}

/// [`update_store`] (with `scanned`: [`update_store_scanned`]) of the store that `opened` was
/// read from ([`read_store`], or the [`StoreReport::stored`] of its last update): where the
/// folder still holds the state it was read from (that state folder, with the same sessions,
/// settings and last update: a state is never changed once written), the update starts from
/// `opened` instead of reading every table again; otherwise it reads the folder, as
/// [`update_store`] does. What is written and returned is the same either way.
///
/// # Errors
/// As [`update_store`] and [`update_store_scanned`].
pub fn update_opened_store(
    opened: StoredFleet,
    config: Option<&StoreConfig>,
    put: Vec<(String, Trajectory)>,
    remove: &[String],
    scanned: Option<Vec<ScannedTile>>,
) -> Result<StoreReport> {
    let dir = opened.dir.clone();
    update_with(&dir, config, put, remove, scanned, Some(opened))
}

/// The store's current state in `dir`: `opened` where it is what the folder holds (see
/// [`update_opened_store`]: O(sessions + blocks) to check), else read from the folder.
fn current_state(dir: &Path, opened: Option<StoredFleet>) -> Result<StoredFleet> {
    if let Some(opened) = opened.filter(|o| o.dir == dir) {
        let head = read_head(dir)?;
        let last_update: StoreUpdate = head.file.last_update.into();
        if head.pointer.state == opened.state
            && head.config == opened.config
            && head.sessions == opened.store.sessions()
            && &last_update == opened.store.last_update()
        {
            return Ok(opened);
        }
    }
    read_store(dir)
}

/// An update of the store in a folder, planned ([`plan_store_update`]) from its small tables:
/// the core's plan and where the stored sessions' poses are. O(sessions + blocks + the tiles
/// to scan); it ships between machines with serde.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StorePlan {
    /// What the update will do and the tiles it scans.
    pub plan: UpdatePlan,
    /// The pose files of the state it was planned from (`None` for a store not yet made).
    pub poses: Option<PathBuf>,
}

/// The plan of the update that [`update_store`] makes with the same arguments, from the
/// store's pointer, settings and sessions alone (no tile is read): what a cluster plans
/// first, then scans tile by tile ([`scan_store_tiles`]) and applies
/// ([`update_store_scanned`]). O(poses given + sessions + blocks log blocks).
///
/// # Errors
/// As [`update_store`], but for those of the scans and the writing.
pub fn plan_store_update(
    dir: &Path,
    config: Option<&StoreConfig>,
    put: &[(String, Trajectory)],
    remove: &[String],
) -> Result<StorePlan> {
    let (settings, stored, poses) = if dir.join("store.json").is_file() {
        let head = read_head(dir)?;
        if let Some(given) = config {
            check_same(dir, &head.config, given)?;
        }
        (head.config.settings, head.sessions, Some(pose_folder(dir, &head.pointer)))
    } else {
        let Some(given) = config else { return Err(StoreError::NotAStore { path: dir.to_path_buf() }) };
        given.settings.check()?;
        (given.settings, Vec::new(), None)
    };
    let sessions = put
        .iter()
        .map(|(name, t)| StoreSession::new(name.clone(), t, &settings))
        .collect::<loops_core::Result<Vec<_>>>()?;
    Ok(StorePlan { plan: UpdatePlan::new(settings, &stored, sessions, remove)?, poses })
}

/// Scans the tiles `tiles` (indices of the plan's tiles) of a planned update, each read
/// session once: a session the update adds or replaces from `put` (those of the plan's
/// update; others may be left out), a stored one from the pose files of the state planned
/// from (in parallel); each checked against the plan before it is scanned. Tiles in parallel.
///
/// # Errors
/// [`StoreError::Core`] for a tile out of range, a session missing from `put`, or poses that
/// are not the planned session's; [`StoreError::Io`] or [`StoreError::Corrupt`] for a pose
/// file that cannot be read back.
pub fn scan_store_tiles(
    planned: &StorePlan,
    tiles: &[usize],
    put: &[(String, Trajectory)],
) -> Result<Vec<ScannedTile>> {
    scan_reading(planned, tiles, put).map(|(scanned, _)| scanned)
}

/// [`scan_store_tiles`], with the sessions it read, by index of the plan's sessions.
fn scan_reading(
    planned: &StorePlan,
    tiles: &[usize],
    put: &[(String, Trajectory)],
) -> Result<(Vec<ScannedTile>, std::collections::BTreeMap<usize, Trajectory>)> {
    let plan = &planned.plan;
    if let Some(&k) = tiles.iter().find(|&&k| k >= plan.tiles().len()) {
        return Err(loops_core::Error::InvalidParameter {
            name: "tile",
            value: k as f64,
            expected: "a tile of the plan",
        }
        .into());
    }
    let mut sessions: Vec<usize> = tiles.iter().flat_map(|&k| plan.tiles()[k].sessions).collect();
    sessions.sort_unstable();
    sessions.dedup();
    let mut read: std::collections::BTreeMap<usize, Trajectory> = std::collections::BTreeMap::new();
    for &s in sessions.iter().filter(|&&s| plan.is_new(s)) {
        let session = &plan.sessions()[s];
        let Some((_, t)) = put.iter().find(|(name, _)| *name == session.name) else {
            return Err(loops_core::Error::StoreSession {
                name: session.name.clone(),
                problem: "is not given to scan",
            }
            .into());
        };
        plan.check_session(s, t)?;
        read.insert(s, t.clone());
    }
    let stored: Vec<usize> = sessions.into_iter().filter(|&s| !plan.is_new(s)).collect();
    let folder = planned.poses.clone().unwrap_or_default();
    read.extend(stored.iter().copied().zip(read_stored(plan, &folder, &stored)?));
    let scanned = plan.scan_tiles(tiles, |k| {
        let [a, b] = plan.tiles()[k].sessions;
        Ok([&read[&a], &read[&b]])
    })?;
    Ok((scanned, read))
}

/// The stored sessions `which` (indices of the plan's sessions) from their pose files in
/// `folder`, in parallel, each checked to be the planned session's; the first failure in the
/// order of `which`.
fn read_stored(plan: &UpdatePlan, folder: &Path, which: &[usize]) -> Result<Vec<Trajectory>> {
    use rayon::prelude::*;
    let read: Vec<Result<Trajectory>> = which
        .par_iter()
        .map(|&s| {
            let trajectory = read_poses(&folder.join(pose_file(&plan.sessions()[s])))?;
            plan.check_session(s, &trajectory)?;
            Ok(trajectory)
        })
        .collect();
    read.into_iter().collect()
}

/// [`update_store`] with the tiles of its plan scanned elsewhere ([`scan_store_tiles`] of
/// every tile of [`plan_store_update`] with the same arguments): plans again (checking that
/// the scans are of this plan, from this state), applies them ([`FleetStore::apply_update`]),
/// draws and writes the new state atomically, as [`update_store`] does.
///
/// # Errors
/// As [`update_store`]; [`StoreError::Core`] for scans of another plan or state, or not
/// every tile of the plan's (the store is then unchanged).
pub fn update_store_scanned(
    dir: &Path,
    config: Option<&StoreConfig>,
    put: Vec<(String, Trajectory)>,
    remove: &[String],
    scanned: Vec<ScannedTile>,
) -> Result<StoreReport> {
    update_with(dir, config, put, remove, Some(scanned), None)
}

/// [`update_store`], with the new tiles scanned here (`None`) or given, from the store as
/// `opened` where it is current ([`current_state`]).
fn update_with(
    dir: &Path,
    config: Option<&StoreConfig>,
    put: Vec<(String, Trajectory)>,
    remove: &[String],
    scanned: Option<Vec<ScannedTile>>,
    mut opened: Option<StoredFleet>,
) -> Result<StoreReport> {
    if let Some(report) = unchanged(dir, config, &put, remove, scanned.as_ref(), &mut opened)? {
        return Ok(report);
    }
    let exists = dir.join(STORE.marker).is_file();
    if !exists {
        crate::out_dir::refuse_non_empty(dir, false, STORE)?;
        std::fs::create_dir_all(dir).map_err(|error| StoreError::Io {
            what: "creating",
            path: dir.to_path_buf(),
            error,
        })?;
    }
    let out = OutDir::take(dir, exists, STORE)?;
    let current = if dir.join("store.json").is_file() { Some(current_state(dir, opened)?) } else { None };
    // States a killed update left (not the one store.json names).
    for name in out.entries() {
        if is_state_name(&name) && current.as_ref().is_none_or(|c| c.state != name) {
            out.remove(&name)?;
        }
    }
    let (mut store, config, old_state, old_parts, old_merge_parts, poses_dir) = match (current, config) {
        (Some(c), Some(given)) => {
            check_same(dir, &c.config, given)?;
            (c.store, c.config, Some(c.state), c.parts, c.merge_parts, Some(c.pose_dir))
        }
        (Some(c), None) => (c.store, c.config, Some(c.state), c.parts, c.merge_parts, Some(c.pose_dir)),
        (None, Some(given)) => (FleetStore::new(given.settings)?, given.clone(), None, Vec::new(), Vec::new(), None),
        (None, None) => {
            return Err(StoreError::NotAStore { path: dir.to_path_buf() });
        }
    };
    // The update's steps ([`FleetStore::update`]), with the stored sessions its tiles meet read
    // in parallel, and kept for the draw, which reads most of them again.
    let sessions: Vec<loops_core::Result<StoreSession>> = {
        use rayon::prelude::*;
        put.par_iter().map(|(name, t)| StoreSession::new(name.clone(), t, store.settings())).collect()
    };
    let plan = store.plan_update(sessions.into_iter().collect::<loops_core::Result<Vec<_>>>()?, remove)?;
    let planned = StorePlan { plan, poses: poses_dir.clone() };
    let (scanned, read) = match scanned {
        Some(scanned) => (scanned, std::collections::BTreeMap::new()),
        None => scan_reading(&planned, &(0..planned.plan.tiles().len()).collect::<Vec<_>>(), &put)?,
    };
    // What the store holds that does not read back (a stored tile decoded now, a pose file) is
    // a damaged file of its state, not a bad argument.
    let state_dir = old_state.as_ref().map_or_else(|| dir.to_path_buf(), |s| dir.join(s));
    let damaged = |error: StoreError| match error {
        StoreError::Core(loops_core::Error::InvalidState { what: "fleet store", reason }) => {
            StoreError::Corrupt { path: state_dir.clone(), reason }
        }
        error => error,
    };
    let update = store.apply_update(&planned.plan, scanned).map_err(|e| damaged(e.into()))?;
    // The stored sessions read, by name and fingerprint (the update moved their indices).
    let mut kept_poses: HashMap<(String, u64), Trajectory> = read
        .into_iter()
        .filter(|(s, _)| !planned.plan.is_new(*s))
        .map(|(s, t)| {
            let session = &planned.plan.sessions()[s];
            ((session.name.clone(), session.fingerprint), t)
        })
        .collect();
    let new_poses: Vec<(String, Trajectory)> = put;
    // A session given now from what was given (the core checks its fingerprint), else as the
    // update read it, else from the current state's pose file.
    let mut source = |s: &StoreSession| -> loops_core::Result<Trajectory> {
        if let Some((_, trajectory)) = new_poses.iter().find(|(name, _)| *name == s.name) {
            return Ok(trajectory.clone());
        }
        if let Some(trajectory) = kept_poses.remove(&(s.name.clone(), s.fingerprint)) {
            return Ok(trajectory);
        }
        let path = poses_dir.as_ref().map(|p| p.join(pose_file(s))).unwrap_or_default();
        read_poses(&path).map_err(|e| loops_core::Error::InvalidState { what: "fleet store", reason: e.to_string() })
    };
    // The new state, complete, in the scratch folder.
    let staged = out.staging_path();
    let io = |what: &'static str, path: &Path| {
        let path = path.to_path_buf();
        move |error| StoreError::Io { what, path, error }
    };
    std::fs::create_dir(&staged).map_err(io("creating", &staged))?;
    let pool = dir.join(POSES);
    if !out.owns(POSES) {
        if pool.symlink_metadata().is_ok() {
            return Err(crate::out_dir::OutDirError::NotAnOutput { path: pool, command: STORE.command }.into());
        }
        out.claim(POSES)?;
    }
    if !pool.is_dir() {
        std::fs::create_dir(&pool).map_err(io("creating", &pool))?;
    }
    let changed: HashSet<&str> = store.last_update().changed().into_iter().collect();
    let names: Vec<&str> = store.sessions().iter().map(|s| s.name.as_str()).collect();
    let generation = old_state.as_deref().and_then(|s| s["state-".len()..].parse::<u64>().ok()).unwrap_or(0) + 1;
    let old_tiles = old_state.as_ref().map(|s| dir.join(s).join("tiles"));
    let old = old_tiles.as_deref().map(|folder| (folder, old_parts.as_slice()));
    let old_merges = old_state.as_ref().map(|s| dir.join(s).join("merges"));
    let old_merges = old_merges.as_deref().map(|folder| (folder, old_merge_parts.as_slice()));
    // The pose file of each session the folder of pose files lacks: a session this update adds
    // or replaces (from what was given), or a stored one of a state of layout 4 or before
    // (linked from that state's folder, else copied). Each is filled under another name and
    // then moved to its own, so that a file there under a session's name is always whole.
    let poses = || -> Result<()> {
        let mut added = false;
        for s in store.sessions() {
            let target = pool.join(pose_file(s));
            if target.exists() {
                continue;
            }
            let filled = out.staging_path();
            let given = new_poses.iter().find(|(n, _)| *n == s.name && changed.contains(n.as_str()));
            match (given, &poses_dir) {
                (Some((_, trajectory)), _) => write_poses(&filled, trajectory)?,
                (None, Some(old)) => {
                    let from = old.join(pose_file(s));
                    if std::fs::hard_link(&from, &target).is_ok() {
                        added = true;
                        continue;
                    }
                    std::fs::copy(&from, &filled)
                        .and_then(|_| File::open(&filled)?.sync_all())
                        .map_err(io("copying", &from))?;
                }
                (None, None) => unreachable!("a stored session without a state"),
            }
            std::fs::rename(&filled, &target).map_err(io("placing", &target))?;
            added = true;
        }
        if added {
            crate::atomic::sync_directory(&pool).map_err(io("syncing", &pool))?;
        }
        Ok(())
    };
    let settings = || {
        let json =
            serde_json::to_string_pretty(&settings_file(&config, store.last_update())).map_err(std::io::Error::other);
        write_synced(&staged.join("settings.json"), json.map(String::into_bytes))
    };
    // What the components and the draw are not needed for (τ, the tile and merge parts, the
    // pose files, the sessions, the settings) is written while they are made; then their
    // tables, in parallel. Each file on its own; the first failure in the order: the draw, the
    // parts, the other files.
    use rayon::prelude::*;
    let (kept, answer) = rayon::join(
        || {
            let duration = || write_loop_duration(&staged.join("loop_duration.parquet"), &store);
            let files: [&(dyn Fn() -> Result<()> + Sync); 4] =
                [&duration, &poses, &|| write_sessions(&staged.join("sessions.parquet"), &store), &settings];
            let (written, parts) = rayon::join(
                || files.par_iter().map(|write| write()).collect::<Vec<Result<()>>>(),
                || {
                    rayon::join(
                        || write_parts(&staged.join("tiles"), old, &store, generation),
                        || write_merge_parts(&staged.join("merges"), old_merges, &store, generation),
                    )
                },
            );
            (parts, written)
        },
        || -> Result<_> {
            let loops = store.loops()?;
            let added = store.added_components(&loops);
            // The components' tables are written while the draw runs; the draw's after it.
            let (drawn, [components, pairs]) = rayon::join(
                || -> Result<_> {
                    let samples = match &config.sampler {
                        Some((sampler, between_only)) => Some(
                            store
                                .samples(&loops, sampler, *between_only, &mut source)
                                .map_err(|e| damaged(e.into()))?,
                        ),
                        None => None,
                    };
                    let (draws, written) = rayon::join(
                        || write_draws(&staged.join("draws.parquet"), &store),
                        || write_samples(&staged.join("samples.parquet"), samples.as_ref(), &names),
                    );
                    Ok((samples, [draws, written]))
                },
                || {
                    let (components, pairs) = rayon::join(
                        || write_components(&staged.join("components.parquet"), &loops, &names, &added),
                        || write_session_pairs(&staged.join("session_pairs.parquet"), &loops, &names),
                    );
                    [components, pairs]
                },
            );
            let (samples, [draws, written]) = drawn?;
            Ok((loops, samples, added, [draws, components, pairs, written]))
        },
    );
    let (loops, samples, added, tables) = answer?;
    let ((parts, merge_parts), files) = kept;
    let parts = parts.map_err(damaged)?;
    let merge_parts = merge_parts?;
    files.into_iter().chain(tables).collect::<Result<()>>()?;
    crate::atomic::sync_directory(&staged).map_err(io("syncing", &staged))?;

    // Placed under a new name, then pointed at in one rename, then the old state removed.
    let state = format!("state-{generation:06}");
    out.place(&staged, &state, true)?;
    let pointer = Pointer {
        format: STORE_FORMAT.to_owned(),
        version: loops_core::store::STORE_FORMAT_VERSION,
        state: state.clone(),
    };
    let pointer_staged = out.staging_path();
    let json = serde_json::to_string_pretty(&pointer).map_err(std::io::Error::other).map(|j| (j + "\n").into_bytes());
    write_synced(&pointer_staged, json)?;
    out.swap_file(&pointer_staged, "store.json")?;
    if let Some(old) = old_state {
        out.remove(&old)?;
    }
    // The pose files no session of the new state has: those of the sessions this update
    // replaced or removed, and any that a killed update left. One listing of the folder; what
    // is not named as a pose file is left alone.
    let kept: HashSet<String> = store.sessions().iter().map(pose_file).collect();
    let listed = std::fs::read_dir(&pool).and_then(|list| list.collect::<std::io::Result<Vec<_>>>());
    for entry in listed.map_err(io("listing", &pool))? {
        let name = entry.file_name().into_string().unwrap_or_default();
        if is_pose_file_name(&name) && !kept.contains(&name) {
            std::fs::remove_file(entry.path()).map_err(io("removing", &entry.path()))?;
        }
    }
    let report = StoreReport {
        update,
        components: loops.components().len(),
        added_components: added.len(),
        samples,
        loops,
        stored: StoredFleet { dir: dir.to_path_buf(), state, store, config, parts, merge_parts, pose_dir: pool },
    };
    Ok(report)
}

/// The report of an update of the existing store in `dir` that changes nothing (planned from
/// its small tables under the folder's lock, which writes nothing), the store read as it is;
/// `None` for one that changes something, a store not yet made, or a folder that a killed
/// update left pieces in (the update that writes tidies it). The plan is checked as
/// [`update_store`] checks it (a `config` other than the store's, a name given twice or
/// removed but not stored are errors), and so are scans given for it: it has none.
fn unchanged(
    dir: &Path,
    config: Option<&StoreConfig>,
    put: &[(String, Trajectory)],
    remove: &[String],
    scanned: Option<&Vec<ScannedTile>>,
    opened: &mut Option<StoredFleet>,
) -> Result<Option<StoreReport>> {
    if !dir.join(STORE.marker).is_file() || !dir.join("store.json").is_file() {
        return Ok(None);
    }
    let _lock = crate::out_dir::lock(dir, STORE)?;
    let planned = plan_store_update(dir, config, put, remove)?;
    if !planned.plan.changes_nothing() {
        return Ok(None);
    }
    let mut stored = current_state(dir, opened.take())?;
    // What a killed update left (a scratch folder, another state) is tidied by writing.
    let mut entries: Vec<String> = std::fs::read_dir(dir)
        .and_then(|list| list.map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned())).collect())
        .map_err(|error| StoreError::Io { what: "listing", path: dir.to_path_buf(), error })?;
    entries.sort_unstable();
    let mut clean = vec![STORE.marker.to_owned(), stored.state.clone(), "store.json".to_owned()];
    if stored.pose_dir == dir.join(POSES) {
        clean.push(POSES.to_owned());
    }
    clean.sort_unstable();
    if entries != clean {
        *opened = Some(stored);
        return Ok(None);
    }
    let update = stored.store.apply_update(&planned.plan, scanned.cloned().unwrap_or_default())?;
    let loops = stored.store.loops()?;
    Ok(Some(StoreReport {
        update,
        components: loops.components().len(),
        added_components: stored.store.added_components(&loops).len(),
        samples: None,
        loops,
        stored,
    }))
}

/// A state folder's name: `state-` and digits.
fn is_state_name(name: &str) -> bool {
    name.strip_prefix("state-").is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

fn check_same(dir: &Path, stored: &StoreConfig, given: &StoreConfig) -> Result<()> {
    let (s, g) = (&stored.settings, &given.settings);
    let differs = |what: &'static str, stored: String, given: String| {
        Err(StoreError::Settings { path: dir.to_path_buf(), what, stored, given })
    };
    if s.metric != g.metric {
        return differs("the metric", s.metric.name(), g.metric.name());
    }
    if s.gamma != g.gamma {
        return differs("gamma", s.gamma.to_string(), g.gamma.to_string());
    }
    if s.separation != g.separation {
        return differs("the separation", format!("{:?}", s.separation), format!("{:?}", g.separation));
    }
    if s.block != g.block {
        return differs("the block", s.block.to_string(), g.block.to_string());
    }
    if stored.sampler != given.sampler {
        let text = |c: &StoreConfig| {
            c.sampler.as_ref().map_or("none".to_owned(), |(s, b)| {
                format!("{} {:?} seed {}{}", s.kind, s.size, s.seed, if *b { " between only" } else { "" })
            })
        };
        return differs("the sampler", text(stored), text(given));
    }
    Ok(())
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|error| StoreError::Io {
        what: "reading",
        path: path.to_path_buf(),
        error,
    })?;
    serde_json::from_str(&text).map_err(|e| StoreError::Corrupt { path: path.to_path_buf(), reason: e.to_string() })
}

fn write_synced(path: &Path, bytes: std::io::Result<Vec<u8>>) -> Result<()> {
    let written = bytes.and_then(|bytes| {
        use std::io::Write;
        let mut file = File::create_new(path)?;
        file.write_all(&bytes)?;
        file.sync_all()
    });
    written.map_err(|error| StoreError::Io { what: "writing", path: path.to_path_buf(), error })
}

/// One column of a table: written from the first six, read back as the first three and
/// [`Blobs`](Column::Blobs).
enum Column {
    Int(Vec<i64>),
    Float(Vec<f64>),
    Bool(Vec<bool>),
    Text(Vec<String>),
    /// Text of few values repeated row by row (session names, a manifold): each value's bytes
    /// held once and shared by its rows ([`repeated`]); written as [`Text`](Column::Text).
    Repeated(Vec<ByteArray>),
    Bytes(Vec<Vec<u8>>),
    /// Text or bytes as read back.
    Blobs(Vec<ByteArray>),
}

/// The [`Column::Repeated`] of `values[k]` for each `k` of `rows`: a table of hundreds of
/// thousands of components names its sessions without a string of its own each.
fn repeated(values: &[&str], rows: impl Iterator<Item = usize>) -> Column {
    let shared = shared_values(values);
    Column::Repeated(rows.map(|k| shared[k].clone()).collect())
}

/// Each of `values` as bytes that the rows of a [`Column::Repeated`] share.
fn shared_values(values: &[&str]) -> Vec<ByteArray> {
    values.iter().map(|v| ByteArray::from(v.as_bytes().to_vec())).collect()
}

impl Column {
    /// Its number of values.
    fn len(&self) -> usize {
        match self {
            Column::Int(v) => v.len(),
            Column::Float(v) => v.len(),
            Column::Bool(v) => v.len(),
            Column::Text(v) => v.len(),
            Column::Repeated(v) => v.len(),
            Column::Bytes(v) => v.len(),
            Column::Blobs(v) => v.len(),
        }
    }

    /// An empty column of the kind that holds `column`'s values.
    fn empty_like(column: &parquet::schema::types::ColumnDescriptor) -> Self {
        use parquet::basic::Type;
        match column.physical_type() {
            Type::INT64 => Column::Int(Vec::new()),
            Type::DOUBLE => Column::Float(Vec::new()),
            Type::BOOLEAN => Column::Bool(Vec::new()),
            _ => Column::Blobs(Vec::new()),
        }
    }
}

/// Writes `columns` as a Parquet file of one row group (required columns, uncompressed but
/// blobs), synced.
fn write_table(path: &Path, columns: Vec<(&str, Column)>) -> Result<()> {
    write_groups(path, columns, usize::MAX)
}

/// [`write_table`] in row groups of at most `group_rows` rows: a reader may then decode the
/// groups it needs alone.
fn write_groups(path: &Path, columns: Vec<(&str, Column)>, group_rows: usize) -> Result<()> {
    let fields: Vec<String> = columns
        .iter()
        .map(|(name, c)| match c {
            Column::Int(_) => format!("REQUIRED INT64 {name};"),
            Column::Float(_) => format!("REQUIRED DOUBLE {name};"),
            Column::Bool(_) => format!("REQUIRED BOOLEAN {name};"),
            Column::Text(_) | Column::Repeated(_) => format!("REQUIRED BYTE_ARRAY {name} (STRING);"),
            Column::Bytes(_) | Column::Blobs(_) => format!("REQUIRED BYTE_ARRAY {name};"),
        })
        .collect();
    let schema = format!("message table {{ {} }}", fields.join(" "));
    let failed = |e: parquet::errors::ParquetError| StoreError::Io {
        what: "writing",
        path: path.to_path_buf(),
        error: std::io::Error::other(e),
    };
    let schema = Arc::new(parquet::schema::parser::parse_message_type(&schema).map_err(failed)?);
    let file =
        File::create_new(path).map_err(|error| StoreError::Io { what: "creating", path: path.to_path_buf(), error })?;
    // Only names (text) are worth a dictionary: hashing every number or blob for one costs more
    // than writing it, and finds few repeats. Integers (indices, counts, mostly increasing) are
    // delta-coded, floats and blobs written plain, blobs compressed. Statistics are kept only
    // where a table has several row groups, for a reader to skip some; with one they skip
    // nothing.
    use parquet::basic::{Compression, Encoding};
    use parquet::file::properties::{EnabledStatistics, WriterPropertiesBuilder};
    let one_group = columns.first().is_none_or(|(_, c)| c.len() <= group_rows);
    let properties = columns.iter().fold(WriterProperties::builder(), |p, (name, column)| {
        let path = parquet::schema::types::ColumnPath::from(*name);
        let plain = |p: WriterPropertiesBuilder| p.set_column_dictionary_enabled(path.clone(), false);
        let p = match column {
            Column::Text(_) | Column::Repeated(_) | Column::Bool(_) => p,
            Column::Int(_) => plain(p).set_column_encoding(path.clone(), Encoding::DELTA_BINARY_PACKED),
            Column::Float(_) => plain(p),
            Column::Bytes(_) | Column::Blobs(_) => plain(p)
                .set_column_statistics_enabled(path.clone(), EnabledStatistics::None)
                .set_column_compression(path.clone(), Compression::LZ4_RAW),
        };
        if one_group { p.set_column_statistics_enabled(path, EnabledStatistics::None) } else { p }
    });
    let mut writer = SerializedFileWriter::new(file, schema, Arc::new(properties.build())).map_err(failed)?;
    let columns: Vec<Column> = columns
        .into_iter()
        .map(|(_, column)| match column {
            Column::Text(v) => Column::Blobs(v.into_iter().map(|s| ByteArray::from(s.into_bytes())).collect()),
            Column::Repeated(v) => Column::Blobs(v),
            Column::Bytes(v) => Column::Blobs(v.into_iter().map(ByteArray::from).collect()),
            other => other,
        })
        .collect();
    let rows = columns.first().map_or(0, Column::len);
    // One group for a table without rows too.
    for g in 0..rows.div_ceil(group_rows).max(1) {
        let (first, end) = (g * group_rows, (g + 1).saturating_mul(group_rows).min(rows));
        let mut group = writer.next_row_group().map_err(failed)?;
        for column in &columns {
            let mut out = group.next_column().map_err(failed)?.expect("one writer per column of the schema");
            match column {
                Column::Int(v) => out.typed::<Int64Type>().write_batch(&v[first..end], None, None),
                Column::Float(v) => out.typed::<DoubleType>().write_batch(&v[first..end], None, None),
                Column::Bool(v) => out.typed::<BoolType>().write_batch(&v[first..end], None, None),
                Column::Blobs(v) => out.typed::<ByteArrayType>().write_batch(&v[first..end], None, None),
                Column::Text(_) | Column::Repeated(_) | Column::Bytes(_) => unreachable!("made blobs above"),
            }
            .map_err(failed)?;
            out.close().map_err(failed)?;
        }
        group.close().map_err(failed)?;
    }
    let file = writer.into_inner().map_err(failed)?;
    file.sync_all().map_err(|error| StoreError::Io { what: "syncing", path: path.to_path_buf(), error })
}

/// A Parquet table read column by column (the tables [`write_table`] writes: required columns
/// of the five kinds of [`Column`]), whole or the columns asked. Read with the column readers
/// rather than the record API, which builds a row of named fields for every row: for the
/// tiles' blobs and the pose files that costs more than decoding them.
struct Table {
    names: Vec<String>,
    /// Each column, where read.
    columns: Vec<Option<Column>>,
    rows: usize,
}

/// Reads the Parquet file at `path` whole.
fn read_table(path: &Path) -> Result<Table> {
    let reader = open_table(path)?;
    read_columns(&reader, path, &|_| true)
}

/// The Parquet file at `path`, read into memory in one read (a store's tables are read whole,
/// and a reader of the file itself reads each page with a few calls).
fn open_table(path: &Path) -> Result<SerializedFileReader<bytes::Bytes>> {
    let bytes =
        std::fs::read(path).map_err(|error| StoreError::Io { what: "reading", path: path.to_path_buf(), error })?;
    SerializedFileReader::new(bytes::Bytes::from(bytes)).map_err(|e| parquet_corrupt(path, e))
}

fn parquet_corrupt(path: &Path, e: parquet::errors::ParquetError) -> StoreError {
    StoreError::Corrupt { path: path.to_path_buf(), reason: e.to_string() }
}

/// The columns `wanted` (by index) of the table `reader` reads from `path`, every row group;
/// the others are left unread.
fn read_columns<R: parquet::file::reader::ChunkReader + 'static>(
    reader: &SerializedFileReader<R>,
    path: &Path,
    wanted: &dyn Fn(usize) -> bool,
) -> Result<Table> {
    let metadata = reader.metadata();
    let schema = metadata.file_metadata().schema_descr();
    let names: Vec<String> = schema.columns().iter().map(|c| c.name().to_owned()).collect();
    let rows = usize::try_from(metadata.file_metadata().num_rows()).unwrap_or(0);
    let mut columns: Vec<Option<Column>> = (0..names.len()).map(|_| None).collect();
    for g in 0..metadata.num_row_groups() {
        for (c, column) in columns.iter_mut().enumerate().filter(|(c, _)| wanted(*c)) {
            let column = column.get_or_insert_with(|| Column::empty_like(&schema.column(c)));
            read_chunk(reader, path, g, c, usize::MAX, column)?;
        }
    }
    // The row count the file states is the one every column read holds, or the file is not one.
    if let Some((c, column)) =
        columns.iter().enumerate().find_map(|(c, k)| k.as_ref().filter(|k| k.len() != rows).map(|k| (c, k)))
    {
        let reason = format!("column {} holds {} values of the {rows} rows the file states", names[c], column.len());
        return Err(StoreError::Corrupt { path: path.to_path_buf(), reason });
    }
    Ok(Table { names, columns, rows })
}

/// Appends the values of column `c` in row group `g` of the table `reader` reads from `path`
/// to `into` (a column of its kind), those of its first `most` rows.
fn read_chunk<R: parquet::file::reader::ChunkReader + 'static>(
    reader: &SerializedFileReader<R>,
    path: &Path,
    g: usize,
    c: usize,
    most: usize,
    into: &mut Column,
) -> Result<()> {
    use parquet::column::reader::ColumnReader;
    // Reads `count` values of a required column into `values`, or says what is wrong.
    fn all<T: parquet::data_type::DataType>(
        mut r: parquet::column::reader::ColumnReaderImpl<T>,
        count: usize,
        values: &mut Vec<T::T>,
    ) -> std::result::Result<(), String> {
        let before = values.len();
        // Room for all of them at once where it can be had (the reader grows the vector batch by
        // batch otherwise); a count no file holds is found by the read.
        let _ = values.try_reserve(count);
        let (records, _, _) = r.read_records(count, None, None, values).map_err(|e| e.to_string())?;
        if records != count || values.len() != before + count {
            return Err(format!("{} values of {count} rows", values.len() - before));
        }
        Ok(())
    }
    let group = reader.get_row_group(g).map_err(|e| parquet_corrupt(path, e))?;
    let count = usize::try_from(group.metadata().num_rows()).unwrap_or(0).min(most);
    let read = match (group.get_column_reader(c).map_err(|e| parquet_corrupt(path, e))?, into) {
        (ColumnReader::Int64ColumnReader(r), Column::Int(v)) => all(r, count, v),
        (ColumnReader::DoubleColumnReader(r), Column::Float(v)) => all(r, count, v),
        (ColumnReader::BoolColumnReader(r), Column::Bool(v)) => all(r, count, v),
        (ColumnReader::ByteArrayColumnReader(r), Column::Blobs(v)) => all(r, count, v),
        _ => Err("a column of a kind this store does not write".to_owned()),
    };
    let name = reader.metadata().file_metadata().schema_descr().column(c).name().to_owned();
    read.map_err(|reason| StoreError::Corrupt { path: path.to_path_buf(), reason: format!("column {name}: {reason}") })
}

impl Table {
    fn column(&self, i: usize) -> std::result::Result<&Column, String> {
        match self.columns.get(i) {
            Some(Some(column)) => Ok(column),
            Some(None) => Err(format!("column {} ({i}) was not read", self.names[i])),
            None => Err(format!("no column {i} (the table has {})", self.columns.len())),
        }
    }
    fn wrong(&self, i: usize, kind: &str) -> String {
        format!("column {} ({i}) is not {kind}", self.names[i])
    }
    fn int(&self, i: usize, k: usize) -> std::result::Result<i64, String> {
        match self.column(i)? {
            Column::Int(v) => Ok(v[k]),
            _ => Err(self.wrong(i, "INT64")),
        }
    }
    /// Cell (`k`, `i`) as an index (a non-negative INT64).
    fn index(&self, i: usize, k: usize) -> std::result::Result<usize, String> {
        let value = self.int(i, k)?;
        usize::try_from(value).map_err(|_| format!("column {}: {value} is not an index", self.names[i]))
    }
    fn float(&self, i: usize, k: usize) -> std::result::Result<f64, String> {
        match self.column(i)? {
            Column::Float(v) => Ok(v[k]),
            _ => Err(self.wrong(i, "DOUBLE")),
        }
    }
    /// The values of an INT64 column.
    fn ints(&self, i: usize) -> std::result::Result<&[i64], String> {
        match self.column(i)? {
            Column::Int(v) => Ok(v),
            _ => Err(self.wrong(i, "INT64")),
        }
    }
    /// The values of a DOUBLE column.
    fn floats(&self, i: usize) -> std::result::Result<&[f64], String> {
        match self.column(i)? {
            Column::Float(v) => Ok(v),
            _ => Err(self.wrong(i, "DOUBLE")),
        }
    }
    fn bytes(&self, i: usize, k: usize) -> std::result::Result<&[u8], String> {
        match self.column(i)? {
            Column::Blobs(v) => Ok(v[k].data()),
            _ => Err(self.wrong(i, "BYTE_ARRAY")),
        }
    }
    fn text(&self, i: usize, k: usize) -> std::result::Result<&str, String> {
        std::str::from_utf8(self.bytes(i, k)?).map_err(|e| format!("column {}: {e}", self.names[i]))
    }
}

/// The manifold of its variant's name (as `settings` and the tables write it).
fn manifold_of(name: &str) -> Option<loops_core::Manifold> {
    serde_json::from_value(serde_json::Value::String(name.to_owned())).ok()
}

/// A column's name for coordinate `k` of `names` (the manifold's), or `x{k}` where a name is
/// not a plain identifier.
fn coordinate_names(t: &Trajectory) -> Vec<String> {
    let dim = t.dim();
    let names: Vec<String> = t.manifold().columns(dim).split_whitespace().map(str::to_owned).collect();
    let plain = |n: &String| n.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') && n != "pose" && n != "t_s";
    if names.len() == dim && names.iter().all(plain) { names } else { (0..dim).map(|k| format!("x{k}")).collect() }
}

fn ints(values: impl IntoIterator<Item = usize>) -> Column {
    Column::Int(values.into_iter().map(|v| v as i64).collect())
}

fn write_poses(path: &Path, t: &Trajectory) -> Result<()> {
    let dim = t.dim();
    let names = coordinate_names(t);
    let mut columns = vec![
        ("pose", ints(0..t.len())),
        ("t_s", Column::Float(t.timestamps_s().to_vec())),
        ("cell_s", Column::Float(t.cell_widths_s().to_vec())),
    ];
    let coords: Vec<Column> =
        (0..dim).map(|k| Column::Float(t.coords().iter().skip(k).step_by(dim).copied().collect())).collect();
    columns.extend(names.iter().map(String::as_str).zip(coords));
    // The manifold, as its variant's name (a trajectory read back is on it).
    columns.push(("manifold", repeated(&[&format!("{:?}", t.manifold())], std::iter::repeat_n(0, t.len()))));
    write_table(path, columns)
}

/// The trajectory of a pose file ([`write_poses`]): its times, cell widths and coordinates,
/// and the manifold of its first row (the column repeats it; the pose numbers are the rows').
fn read_poses(path: &Path) -> Result<Trajectory> {
    let reader = open_table(path)?;
    let corrupt = |reason: String| StoreError::Corrupt { path: path.to_path_buf(), reason };
    let width = reader.metadata().file_metadata().schema_descr().num_columns();
    let dim = width.checked_sub(4).filter(|&d| d > 0).ok_or_else(|| corrupt(format!("{width} columns")))?;
    let mut table = read_columns(&reader, path, &|c| (1..3 + dim).contains(&c))?;
    if table.rows == 0 {
        return Err(corrupt("no poses".to_owned()));
    }
    let mut manifold = Column::Blobs(Vec::new());
    read_chunk(&reader, path, 0, 3 + dim, 1, &mut manifold)?;
    table.columns[3 + dim] = Some(manifold);
    let manifold = table.text(3 + dim, 0).map_err(corrupt)?;
    let manifold = manifold_of(manifold).ok_or_else(|| corrupt(format!("manifold {manifold:?} is unknown")))?;
    let axes =
        (0..dim).map(|c| table.floats(3 + c)).collect::<std::result::Result<Vec<_>, String>>().map_err(corrupt)?;
    let mut coords: Vec<f64> = vec![0.0; table.rows * dim];
    for (c, axis) in axes.iter().enumerate() {
        coords[c..].iter_mut().step_by(dim).zip(axis.iter()).for_each(|(x, &a)| *x = a);
    }
    let mut take = |c: usize| match table.columns[c].take() {
        Some(Column::Float(values)) => Ok(values),
        _ => Err(corrupt(format!("column {} ({c}) is not DOUBLE", table.names[c]))),
    };
    let (times, cells) = (take(1)?, take(2)?);
    Trajectory::from_saved(times, coords, dim, cells, manifold)
        .map_err(|e| corrupt(format!("the poses do not make a trajectory: {e}")))
}

fn write_sessions(path: &Path, store: &FleetStore) -> Result<()> {
    let s = store.sessions();
    write_table(
        path,
        vec![
            ("session", ints(0..s.len())),
            ("name", Column::Text(s.iter().map(|s| s.name.clone()).collect())),
            ("fingerprint", Column::Text(s.iter().map(|s| fingerprint_text(s.fingerprint)).collect())),
            ("poses", ints(s.iter().map(StoreSession::poses))),
            ("t_first_s", Column::Float(s.iter().map(|s| s.times_s[0]).collect())),
            ("t_last_s", Column::Float(s.iter().map(|s| s.times_s[1]).collect())),
            ("span_s", Column::Float(s.iter().map(|s| s.blocks.span_s).collect())),
            ("dim", ints(s.iter().map(|s| s.blocks.dim))),
            ("manifold", Column::Text(s.iter().map(|s| format!("{:?}", s.manifold)).collect())),
            ("blocks", Column::Bytes(s.iter().map(|s| s.blocks.to_bytes()).collect())),
        ],
    )
}

/// The most parts a state's folder `tiles` holds: beyond it, an update writes the tiles of its
/// smallest kept parts again, with its own, so that a store updated every day for years reads
/// a bounded number of files.
const MAX_TILE_PARTS: usize = 32;

/// Links into `folder` (created here) each part of an old state's folder of parts (`old`)
/// whose rows are all among `keys` (the new state's), the largest first, at most
/// [`MAX_TILE_PARTS`] − 1 of them (the part written next makes one more), copying where a link
/// cannot be made. Returns the parts linked, in name order, and the keys no linked part holds
/// (indices into `keys`, in order): those to write.
fn link_parts<K: Eq + std::hash::Hash + Clone>(
    folder: &Path,
    old: Option<(&Path, &[Part<K>])>,
    keys: &[K],
) -> Result<(Vec<Part<K>>, Vec<usize>)> {
    std::fs::create_dir_all(folder).map_err(|error| StoreError::Io {
        what: "creating",
        path: folder.to_path_buf(),
        error,
    })?;
    let mut unwritten: HashMap<&K, usize> = keys.iter().enumerate().map(|(k, key)| (key, k)).collect();
    let (old, old_parts) = old.unwrap_or((folder, &[])); // no parts: the folder is not read
    let mut kept: Vec<&Part<K>> =
        old_parts.iter().filter(|p| p.keys.iter().all(|key| unwritten.contains_key(key))).collect();
    // The largest first; the new part makes one more.
    kept.sort_by_key(|p| std::cmp::Reverse(p.keys.len()));
    kept.truncate(MAX_TILE_PARTS - 1);
    let mut parts = Vec::new();
    for part in kept {
        let (from, to) = (old.join(&part.file), folder.join(&part.file));
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(|error| StoreError::Io { what: "copying", path: from.clone(), error })?;
        }
        for key in &part.keys {
            unwritten.remove(key);
        }
        parts.push(part.clone());
    }
    parts.sort_by(|a, b| a.file.cmp(&b.file));
    let mut new: Vec<usize> = unwritten.into_values().collect();
    new.sort_unstable();
    Ok((parts, new))
}

/// Syncs a folder of parts, written.
fn sync_parts(folder: &Path) -> Result<()> {
    crate::atomic::sync_directory(folder).map_err(|error| StoreError::Io {
        what: "syncing",
        path: folder.to_path_buf(),
        error,
    })
}

/// The store's tiles as the parts of a state's folder `tiles` (created here): each part of
/// the old state (in `old`) whose tiles are all still the store's is linked ([`link_parts`]),
/// the other tiles written anew, each in its sessions' own indices ([`StoredTile::local`]), as
/// one part named by the state's `generation`. An update that adds sessions writes only the
/// tiles it scanned; one that replaces or removes a session also writes again the other tiles
/// of the parts that held that session's tiles; and where more than [`MAX_TILE_PARTS`] would
/// be left, the smallest kept parts are written again too. Returns the parts.
fn write_parts(
    folder: &Path,
    old: Option<(&Path, &[TilePart])>,
    store: &FleetStore,
    generation: u64,
) -> Result<Vec<TilePart>> {
    let starts = store.starts();
    let keys: Vec<TileKey> = (0..store.tiles().len()).map(|k| TileKey::of(store, &starts, k)).collect();
    let (mut parts, new) = link_parts(folder, old, &keys)?;
    if !new.is_empty() {
        // Where an old part not linked, read back, holds a tile written again: its bytes are
        // copied.
        let linked: HashSet<&str> = parts.iter().map(|p| p.file.as_str()).collect();
        let mut rows: HashMap<&TileKey, (&PartFile, usize)> = HashMap::new();
        for part in old.map_or(&[][..], |(_, p)| p).iter().filter(|p| !linked.contains(p.file.as_str())) {
            if let Some(read) = &part.read {
                rows.extend(part.keys.iter().enumerate().map(|(row, key)| (key, (read.as_ref(), row))));
            }
        }
        let file = format!("{generation:06}.parquet");
        parts.push(write_part(folder, &file, store, &starts, &keys, new, &rows)?);
    }
    sync_parts(folder)?;
    Ok(parts)
}

/// The merges of the store's session pairs as the parts of a state's folder `merges`
/// (created here), as [`write_parts`] writes the tiles: the old parts whose merges are all
/// still the store's linked, the others (the pairs of the sessions an update added or
/// replaced, and those of the parts written again) written as one part named by the state's
/// `generation`, each in its sessions' own indices ([`MergedLoops::local`]). Returns the parts.
fn write_merge_parts(
    folder: &Path,
    old: Option<(&Path, &[MergePart])>,
    store: &FleetStore,
    generation: u64,
) -> Result<Vec<MergePart>> {
    use rayon::prelude::*;
    let starts = store.starts();
    let merges: Vec<([usize; 2], &MergedLoops)> = store.kept_merges().collect();
    let keys: Vec<PairKey> = merges.iter().map(|&(pair, _)| PairKey::of(store, pair)).collect();
    let (mut parts, new) = link_parts(folder, old, &keys)?;
    if !new.is_empty() {
        let blobs: Vec<Vec<u8>> = new
            .par_iter()
            .map(|&k| {
                let ([a, b], merge) = merges[k];
                merge.local([starts[a], starts[b]]).to_bytes()
            })
            .collect();
        let file = format!("{generation:06}.parquet");
        let mut columns = pair_columns(new.iter().map(|&k| &keys[k]));
        columns.extend([
            (MERGE_COLUMNS[4], ints(new.iter().map(|&k| merges[k].1.tiles().len()))),
            (MERGE_COLUMNS[5], ints(new.iter().map(|&k| merges[k].1.components().len()))),
            (MERGE_COLUMNS[6], Column::Bytes(blobs)),
        ]);
        write_table(&folder.join(&file), columns)?;
        parts.push(MergePart { file, keys: new.into_iter().map(|k| keys[k].clone()).collect(), read: None });
    }
    sync_parts(folder)?;
    Ok(parts)
}

/// Writes the store's tiles `new` (indices, named `keys`) as the part `file` of `folder`, each
/// in its sessions' own indices (`starts`: the sessions' first fleet indices): the bytes of
/// a tile an old part holds (`rows`) copied, those of others encoded (the tiles an update
/// scanned), in row groups of [`PART_GROUP_ROWS`] tiles.
fn write_part(
    folder: &Path,
    file: &str,
    store: &FleetStore,
    starts: &[usize],
    keys: &[TileKey],
    new: Vec<usize>,
    rows: &HashMap<&TileKey, (&PartFile, usize)>,
) -> Result<TilePart> {
    use rayon::prelude::*;
    // Each new tile's blobs in its sessions' own indices, with its components and runs, in
    // parallel; the first failure in order.
    type Written = ([Vec<u8>; 3], [i64; 2]);
    let written: Vec<Result<Written>> = new
        .par_iter()
        .map(|&k| {
            if let Some(&(part, row)) = rows.get(&keys[k]) {
                let blob = |which: usize| {
                    part.blob(which, row)
                        .map(<[u8]>::to_vec)
                        .map_err(|reason| StoreError::Corrupt { path: part.path.clone(), reason })
                };
                return Ok(([blob(0)?, blob(1)?, blob(2)?], part.counts[row]));
            }
            let t = &store.tiles()[k];
            let [a, b] = t.tile().sessions;
            let local = t.stored()?.local([starts[a], starts[b]]);
            let runs = t.runs()?;
            let counts = [local.summary.components.len() as i64, runs.map_or(-1, |r| r.run_count() as i64)];
            let runs = runs.map_or_else(Vec::new, |r| r.local().to_bytes());
            Ok(([local.summary.to_bytes(), local.duration.to_bytes(), runs], counts))
        })
        .collect();
    let tile = |k: usize| store.tiles()[k].tile();
    let local = |f: &dyn Fn(usize) -> usize| ints(new.iter().map(|&k| f(k)));
    let (mut summaries, mut durations, mut all_runs, mut components, mut run_counts) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for written in written {
        let ([summary, duration, runs], [c, r]) = written?;
        summaries.push(summary);
        durations.push(duration);
        all_runs.push(runs);
        components.push(c);
        run_counts.push(r);
    }
    let mut columns = pair_columns(new.iter().map(|&k| &keys[k].pair));
    columns.extend([
        ("rows_start", local(&|k| keys[k].at[0])),
        ("rows_end", local(&|k| keys[k].at[0] + tile(k).rows.len())),
        ("columns_start", local(&|k| keys[k].at[1])),
        ("columns_end", local(&|k| keys[k].at[1] + tile(k).columns.len())),
        ("components", Column::Int(components)),
        ("run_count", Column::Int(run_counts)),
        ("summary", Column::Bytes(summaries)),
        ("duration", Column::Bytes(durations)),
        ("runs", Column::Bytes(all_runs)),
    ]);
    write_groups(&folder.join(file), columns, PART_GROUP_ROWS)?;
    let keys = new.into_iter().map(|k| keys[k].clone()).collect();
    Ok(TilePart { file: file.to_owned(), keys, read: None })
}

/// `draws.parquet`: what the store's last draws found in its tiles, by seed.
fn write_draws(path: &Path, store: &FleetStore) -> Result<()> {
    let draws = store.kept_draws();
    write_table(
        path,
        vec![
            ("seed", Column::Int(draws.iter().map(|(seed, _)| *seed as i64).collect())),
            ("draw", Column::Bytes(draws.into_iter().map(|(_, bytes)| bytes).collect())),
        ],
    )
}

fn write_components(path: &Path, loops: &loops_core::store::StoreLoops, names: &[&str], added: &[usize]) -> Result<()> {
    let c = loops.components();
    let mut is_added = vec![false; c.len()];
    added.iter().for_each(|&id| is_added[id] = true);
    let times = loops.component_times_s();
    // Every column filled in one pass over the components (a pass a column would read them
    // all again for each of its 21 columns).
    let n = c.len();
    let shared = shared_values(names);
    let mut text: [Vec<ByteArray>; 2] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut int: [Vec<i64>; 11] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut float: [Vec<f64>; 6] = std::array::from_fn(|_| Vec::with_capacity(n));
    let mut flag: [Vec<bool>; 2] = std::array::from_fn(|_| Vec::with_capacity(n));
    for (c, t) in c.iter().zip(&times) {
        let [a, b] = c.sessions;
        text[0].push(shared[a].clone());
        text[1].push(shared[b].clone());
        let ints = [
            c.id as i64,
            a as i64,
            b as i64,
            c.pair_count as i64,
            c.holes as i64,
            c.poses[0][0] as i64,
            c.poses[0][1] as i64,
            c.poses[1][0] as i64,
            c.poses[1][1] as i64,
            c.closest_pair[0] as i64,
            c.closest_pair[1] as i64,
        ];
        int.iter_mut().zip(ints).for_each(|(column, value)| column.push(value));
        let floats = [c.area_s2, t[0][0], t[0][1], t[1][0], t[1][1], c.closest_distance];
        float.iter_mut().zip(floats).for_each(|(column, value)| column.push(value));
        flag[0].push(c.trivial);
        flag[1].push(is_added[c.id]);
    }
    let [session_a, session_b] = text.map(Column::Repeated);
    let [id, a, b, pair_count, holes, i_min, i_max, j_min, j_max, closest_i, closest_j] = int.map(Column::Int);
    let [area, t_min, t_max, t_prime_min, t_prime_max, closest_distance] = float.map(Column::Float);
    let [trivial, added] = flag.map(Column::Bool);
    write_table(
        path,
        vec![
            ("id", id),
            ("session_a", session_a),
            ("session_b", session_b),
            ("a", a),
            ("b", b),
            ("trivial", trivial),
            ("area_s2", area),
            ("pair_count", pair_count),
            ("holes", holes),
            ("i_min", i_min),
            ("i_max", i_max),
            ("j_min", j_min),
            ("j_max", j_max),
            ("t_min_s", t_min),
            ("t_max_s", t_max),
            ("t_prime_min_s", t_prime_min),
            ("t_prime_max_s", t_prime_max),
            ("closest_i", closest_i),
            ("closest_j", closest_j),
            ("closest_distance", closest_distance),
            ("added", added),
        ],
    )
}

fn write_session_pairs(path: &Path, loops: &loops_core::store::StoreLoops, names: &[&str]) -> Result<()> {
    let p = loops.session_pairs();
    write_table(
        path,
        vec![
            ("session_a", repeated(names, p.iter().map(|p| p.sessions[0]))),
            ("session_b", repeated(names, p.iter().map(|p| p.sessions[1]))),
            ("a", ints(p.iter().map(|p| p.sessions[0]))),
            ("b", ints(p.iter().map(|p| p.sessions[1]))),
            ("components", ints(p.iter().map(|p| p.components))),
            ("pair_count", Column::Int(p.iter().map(|p| p.pair_count as i64).collect())),
            ("area_s2", Column::Float(p.iter().map(|p| p.area_s2).collect())),
            ("density", Column::Float(p.iter().map(|p| p.density).collect())),
        ],
    )
}

/// `loop_duration.parquet`: τ of every pose of the store, own and other, a row a pose.
fn write_loop_duration(path: &Path, store: &FleetStore) -> Result<()> {
    let (own, other) = store.loop_duration()?;
    let (mut session, mut pose) = (Vec::new(), Vec::new());
    for (a, s) in store.sessions().iter().enumerate() {
        session.extend(std::iter::repeat_n(a, s.poses()));
        pose.extend(0..s.poses());
    }
    write_table(
        path,
        vec![
            ("session", ints(session)),
            ("pose", ints(pose)),
            ("own_s", Column::Float(own)),
            ("other_s", Column::Float(other)),
        ],
    )
}

fn write_samples(path: &Path, samples: Option<&StoreSamples>, names: &[&str]) -> Result<()> {
    let rows = samples.map_or(&[][..], |s| &s.rows[..]);
    let f = |g: &dyn Fn(&loops_core::fleet::FleetSample) -> f64| Column::Float(rows.iter().map(g).collect());
    let u = |g: &dyn Fn(&loops_core::fleet::FleetSample) -> usize| ints(rows.iter().map(g));
    write_table(
        path,
        vec![
            ("session_a", repeated(names, rows.iter().map(|s| s.sessions[0]))),
            ("session_b", repeated(names, rows.iter().map(|s| s.sessions[1]))),
            ("a", u(&|s| s.sessions[0])),
            ("b", u(&|s| s.sessions[1])),
            ("i", u(&|s| s.poses[0])),
            ("j", u(&|s| s.poses[1])),
            ("t_s", f(&|s| s.times_s[0])),
            ("t_prime_s", f(&|s| s.times_s[1])),
            ("component", u(&|s| s.component.unwrap_or(usize::MAX))),
            ("distance", f(&|s| s.distance.unwrap_or(f64::NAN))),
        ],
    )
}

/// The columns of the passes near a place ([`FleetStore::near`](loops_core::store::FleetStore::near)),
/// a pass a row: the session's index and name, its first and last pose, their times.
pub const PASS_COLUMNS: [&str; 6] = ["session", "name", "i_start", "i_end", "t_start_s", "t_end_s"];

/// The columns of the sessions that revisit a session
/// ([`StoreLoops::revisits`](loops_core::store::StoreLoops::revisits)), one a row.
pub const REVISIT_COLUMNS: [&str; 6] = ["session", "name", "components", "pair_count", "area_s2", "density"];

/// The columns of a list of a store's components (the components the last update added): as
/// `components.parquet` names them.
pub const STORE_COMPONENT_COLUMNS: [&str; 12] =
    ["id", "session_a", "session_b", "a", "b", "trivial", "area_s2", "pair_count", "i_min", "i_max", "j_min", "j_max"];

#[derive(Serialize)]
struct PassRow<'a> {
    session: usize,
    name: &'a str,
    i_start: usize,
    i_end: usize,
    t_start_s: f64,
    t_end_s: f64,
}

#[derive(Serialize)]
struct RevisitRow<'a> {
    session: usize,
    name: &'a str,
    components: usize,
    pair_count: u64,
    area_s2: f64,
    density: f64,
}

#[derive(Serialize)]
struct ComponentRow<'a> {
    id: usize,
    session_a: &'a str,
    session_b: &'a str,
    a: usize,
    b: usize,
    trivial: bool,
    area_s2: f64,
    pair_count: u64,
    i_min: usize,
    i_max: usize,
    j_min: usize,
    j_max: usize,
}

/// The name of session `k`, or an `InvalidData` error for an index beyond `names`.
fn name_of<'a>(names: &[&'a str], k: usize) -> std::io::Result<&'a str> {
    names.get(k).copied().ok_or_else(|| {
        std::io::Error::new(std::io::ErrorKind::InvalidData, format!("session {k} of {} sessions", names.len()))
    })
}

/// Writes passes near a place as CSV ([`PASS_COLUMNS`]); `names` are the store's sessions'.
///
/// # Errors
/// What `out` returns; `InvalidData` for a session beyond `names`.
pub fn passes_to_csv<W: std::io::Write>(
    passes: &[loops_core::store::StorePass],
    names: &[&str],
    out: W,
) -> std::io::Result<()> {
    let rows = passes
        .iter()
        .map(|p| {
            Ok(PassRow {
                session: p.session,
                name: name_of(names, p.session)?,
                i_start: p.pass.poses[0],
                i_end: p.pass.poses[1],
                t_start_s: p.pass.times_s[0],
                t_end_s: p.pass.times_s[1],
            })
        })
        .collect::<std::io::Result<Vec<_>>>()?;
    crate::csv_rows::write_csv(out, &PASS_COLUMNS, rows)
}

/// Writes the sessions that revisit a session as CSV ([`REVISIT_COLUMNS`]).
///
/// # Errors
/// What `out` returns; `InvalidData` for a session beyond `names`.
pub fn revisits_to_csv<W: std::io::Write>(
    revisits: &[loops_core::store::Revisit],
    names: &[&str],
    out: W,
) -> std::io::Result<()> {
    let rows = revisits
        .iter()
        .map(|r| {
            Ok(RevisitRow {
                session: r.session,
                name: name_of(names, r.session)?,
                components: r.components,
                pair_count: r.pair_count,
                area_s2: r.area_s2,
                density: r.density,
            })
        })
        .collect::<std::io::Result<Vec<_>>>()?;
    crate::csv_rows::write_csv(out, &REVISIT_COLUMNS, rows)
}

/// Writes the components `ids` of `loops` as CSV ([`STORE_COMPONENT_COLUMNS`], poses within
/// their sessions).
///
/// # Errors
/// What `out` returns; `InvalidData` for an id beyond the components or a session beyond
/// `names`.
pub fn store_components_to_csv<W: std::io::Write>(
    loops: &StoreLoops,
    ids: &[usize],
    names: &[&str],
    out: W,
) -> std::io::Result<()> {
    let rows = ids
        .iter()
        .map(|&id| {
            let c = loops.components().get(id).ok_or_else(|| {
                std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("component {id} of {}", loops.components().len()),
                )
            })?;
            let [a, b] = c.sessions;
            Ok(ComponentRow {
                id,
                session_a: name_of(names, a)?,
                session_b: name_of(names, b)?,
                a,
                b,
                trivial: c.trivial,
                area_s2: c.area_s2,
                pair_count: c.pair_count,
                i_min: c.poses[0][0],
                i_max: c.poses[0][1],
                j_min: c.poses[1][0],
                j_max: c.poses[1][1],
            })
        })
        .collect::<std::io::Result<Vec<_>>>()?;
    crate::csv_rows::write_csv(out, &STORE_COMPONENT_COLUMNS, rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A store in `dir` of a small city's fleet: 2 vehicles, `days` drives each of `duration_s`
    /// seconds. Returns the fleet and the report of the update that stored it.
    fn small_store(
        dir: &Path,
        days: usize,
        duration_s: f64,
        settings: StoreSettings,
    ) -> (loops_core::fleet::Fleet, StoreReport) {
        let fleet = loops_core::UrbanFleet {
            vehicles: 2,
            days,
            drive: loops_core::UrbanDrive { duration_s, rate_hz: 4.0, city_size_m: 300.0, ..Default::default() },
            start_spread_s: 600.0,
        }
        .generate()
        .unwrap();
        let put = (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect();
        let config = StoreConfig { settings, sampler: None };
        let report = update_store(dir, Some(&config), put, &[]).unwrap();
        (fleet, report)
    }

    /// Writes the table at `path` again with `edit` made to its columns, in row groups of
    /// `group_rows` rows.
    fn rewrite(path: &Path, group_rows: usize, edit: impl FnOnce(&mut [(&str, Column)])) {
        let Table { names, columns, .. } = read_table(path).unwrap();
        let mut columns: Vec<(&str, Column)> =
            names.iter().map(String::as_str).zip(columns.into_iter().map(Option::unwrap)).collect();
        edit(&mut columns);
        std::fs::remove_file(path).unwrap();
        write_groups(path, columns, group_rows).unwrap();
    }

    /// Every kind of column reads back as written, in one row group and in several: integers
    /// delta-coded across the extremes of i64 (the deltas wrap), floats plain with NaN, ±∞ and
    /// −0, names with their dictionary, blobs compressed.
    #[test]
    fn columns_read_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let ints = vec![0, -1, i64::MAX, i64::MIN, 1, i64::MIN, i64::MAX, 7, 7, 7, -5];
        let floats = vec![0.5, f64::NAN, f64::INFINITY, -0.0, f64::NEG_INFINITY, 1e-300, 3.0, 3.0, 2.0, -1.5, 9.0];
        let texts: Vec<String> = (0..ints.len()).map(|k| ["a", "bb", ""][k % 3].to_owned()).collect();
        let blobs: Vec<Vec<u8>> = (0..ints.len()).map(|k| vec![k as u8; k * 40]).collect();
        let bools: Vec<bool> = (0..ints.len()).map(|k| k % 4 == 1).collect();
        for (k, group_rows) in [usize::MAX, 4, 1].into_iter().enumerate() {
            let path = dir.path().join(format!("t{k}.parquet"));
            let columns = vec![
                ("i", Column::Int(ints.clone())),
                ("f", Column::Float(floats.clone())),
                ("t", Column::Text(texts.clone())),
                ("b", Column::Bytes(blobs.clone())),
                ("o", Column::Bool(bools.clone())),
            ];
            write_groups(&path, columns, group_rows).unwrap();
            let table = read_table(&path).unwrap();
            assert_eq!(table.rows, ints.len());
            assert_eq!(table.ints(0).unwrap(), &ints[..], "groups of {group_rows}");
            let read = table.floats(1).unwrap();
            assert!(read.iter().zip(&floats).all(|(a, b)| a.to_bits() == b.to_bits()), "{read:?}");
            for row in 0..ints.len() {
                assert_eq!(table.text(2, row).unwrap(), texts[row]);
                assert_eq!(table.bytes(3, row).unwrap(), &blobs[row][..]);
            }
            let Some(Column::Bool(read)) = &table.columns[4] else { panic!("a BOOLEAN column") };
            assert_eq!(read, &bools);
        }
    }

    /// τ's rows are each session's poses in order: a row out of place is named, in one line.
    #[test]
    fn a_duration_row_out_of_place_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let (_, report) = small_store(dir.path(), 1, 20.0, StoreSettings::new(8.0));
        let path = dir.path().join(&report.stored.state).join("loop_duration.parquet");
        let sessions = report.stored.store.sessions();
        assert!(read_duration(&path, sessions).is_ok());
        let row = sessions[0].poses() + 3;
        rewrite(&path, usize::MAX, |columns| {
            let Column::Int(poses) = &mut columns[1].1 else { panic!("poses are INT64") };
            poses.swap(row, row + 1);
        });
        let error = read_duration(&path, sessions).unwrap_err().to_string();
        let named = error.contains(&path.display().to_string())
            && error.contains(&format!("row {row} is of pose 4 of session 1, not pose 3 of 1"));
        assert!(named && !error.contains('\n'), "{error}");
    }

    /// A part with one damaged blob still opens (no blob is read then); reading that tile names
    /// the file and the row in one line, and the others read.
    #[test]
    fn a_damaged_tile_is_named_when_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let settings = StoreSettings { block: 50, ..StoreSettings::new(8.0) };
        let (fleet, report) = small_store(dir.path(), 2, 40.0, settings);
        let part = dir.path().join(&report.stored.state).join("tiles").join("000001.parquet");
        let tiles = read_table(&part).unwrap().rows;
        assert!(tiles > 2, "{tiles} tiles");
        rewrite(&part, 2, |columns| {
            let Column::Blobs(summaries) = &mut columns[PART_BLOBS].1 else { panic!("summaries are blobs") };
            summaries[0] = ByteArray::from(b"ILts not a summary".to_vec());
        });

        let read = read_store(dir.path()).unwrap();
        let error = read.store.stored_tiles().unwrap_err().to_string();
        let named = error.contains(&part.display().to_string()) && error.contains("row 0:");
        assert!(named && !error.contains('\n'), "{error}");
        let fine = read.store.tiles().iter().filter(|t| t.stored().is_ok()).count();
        assert_eq!(fine, read.store.tiles().len() - 1);

        // Every summary damaged: replacing a session reads the kept tiles of its neighbours,
        // and fails as a damaged file of the store, naming the part; the store is unchanged.
        rewrite(&part, PART_GROUP_ROWS, |columns| {
            let Column::Blobs(summaries) = &mut columns[PART_BLOBS].1 else { panic!("summaries are blobs") };
            summaries.iter_mut().for_each(|s| *s = ByteArray::from(b"ILts not a summary".to_vec()));
        });
        let t = fleet.session(0);
        let moved: Vec<f64> = t.coords().iter().map(|x| x + 0.25).collect();
        let moved = Trajectory::new(t.timestamps_s().to_vec(), moved, t.dim()).unwrap();
        let error = update_store(dir.path(), None, vec![(fleet.names()[0].clone(), moved)], &[]).unwrap_err();
        assert!(matches!(error, StoreError::Corrupt { .. }), "{error:?}");
        let error = error.to_string();
        assert!(error.contains("000001.parquet: row ") && !error.contains('\n'), "{error}");
        assert_eq!(read_store(dir.path()).unwrap().state, report.stored.state, "the store is unchanged");
    }

    /// A part's rows name their sessions by name and fingerprint: a fingerprint written in
    /// capitals is the same number and opens; one of another number, an unknown name, or a
    /// fingerprint that is not hex is named with the file and row, in one line.
    #[test]
    fn a_part_row_names_its_sessions_as_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let (_, report) = small_store(dir.path(), 2, 40.0, StoreSettings::new(8.0));
        let state = dir.path().join(&report.stored.state);
        let merges = state.join("merges").join("000001.parquet");
        let row = read_table(&merges).unwrap().rows - 1;
        let edit = |column: usize, value: &dyn Fn(&str) -> String| {
            rewrite(&merges, usize::MAX, |columns| {
                let Column::Blobs(texts) = &mut columns[column].1 else { panic!("names are byte arrays") };
                let was = std::str::from_utf8(texts[row].data()).unwrap().to_owned();
                texts[row] = ByteArray::from(value(&was).into_bytes());
            });
        };
        let opened = |dir: &Path| read_store(dir).map(|r| r.store.loops().unwrap().components().len());
        let components = opened(dir.path()).unwrap();
        edit(3, &|was| was.to_uppercase());
        assert_eq!(opened(dir.path()).unwrap(), components);
        type Edit<'a> = &'a dyn Fn(&str) -> String;
        let wrong: [(usize, Edit, &str); 3] = [
            (3, &|was| format!("{:016x}", u64::from_str_radix(was, 16).unwrap() ^ 1), "as it was before"),
            (1, &|_| "nobody".to_owned(), "session \"nobody\" is not in the store"),
            (2, &|_| "0x12".to_owned(), "fingerprint \"0x12\""),
        ];
        let kept = dir.path().join("merges-kept.parquet");
        std::fs::copy(&merges, &kept).unwrap();
        for (column, value, says) in wrong {
            edit(column, value);
            let error = read_store(dir.path()).unwrap_err().to_string();
            let named = error.contains(&merges.display().to_string()) && error.contains(&format!("row {row}:"));
            assert!(named && error.contains(says) && !error.contains('\n'), "{error}");
            std::fs::copy(&kept, &merges).unwrap();
        }
    }
}

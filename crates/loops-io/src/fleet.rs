//! Fleet results out: the loop components of a fleet with both sessions ([`FleetComponentRow`],
//! the fleet's `components.csv`), the sparse session-overlap matrix ([`SessionPairRow`],
//! `session_pairs.csv`), the sampled pairs with both sessions ([`FleetSampleRow`], CSV or JSON),
//! and those pairs as g2o edges between the sessions' poses, keyed as GTSAM `Symbol`s
//! ([`gtsam_symbol_key`]: one robot letter per session).
//!
//! Poses are named in their sessions: `i` is a pose of session `a` (the rows, t), `j` a pose of
//! session `b` (the columns, t′), `a ≤ b`; times are each session's own clock. The tables share
//! their column names with the single-trajectory files (`components.csv`, `samples.csv`) where
//! the meaning is the same, and go through the same CSV rows and atomic writer.

use std::io::{self, Write};
use std::path::Path;

use loops_core::{
    Error, Samples,
    fleet::{Fleet, FleetLoops, FleetSample},
};

use crate::atomic::write_atomically;
use crate::components::{
    CLOSEST_POSITION_COLUMNS, ClosestPositions, ComponentExtent, ComponentMeasures, ComponentRow, EXTENT_COLUMNS,
    MEASURE_COLUMNS, columns,
};
use crate::csv_rows::write_csv;
use crate::error::{IoError, Result, WriteError};
use crate::json::write_json;
use crate::samples::SamplesFormat;
use crate::table::PoseTable;
use crate::write::{EdgeKind, G2oOptions, edge_line, pose_of, vertex_line};

/// The columns of a fleet's `components.csv`, without the optional `samples`: the block (both
/// sessions by index, `session_a` and `session_b`, then by name, `name_a` and `name_b`), then
/// the columns of `components.csv` but `id` (see
/// [`COMPONENT_COLUMNS`](crate::COMPONENT_COLUMNS)), with `i` indexing poses of session `a` and
/// `j` poses of session `b` (the closest pair's positions: pose `closest_i` of session `a`,
/// pose `closest_j` of session `b`).
pub const FLEET_COMPONENT_COLUMNS: [&str; 28] = columns(&[
    &["id", "session_a", "session_b", "name_a", "name_b"],
    &MEASURE_COLUMNS,
    &EXTENT_COLUMNS,
    &CLOSEST_POSITION_COLUMNS,
]);

/// One row of a fleet's `components.csv`: a [`FleetComponent`](loops_core::fleet::FleetComponent) with
/// the names of its sessions and the times of its pose ranges, each on its session's clock: in
/// its [`extent`](ComponentRow::extent), `i` indexes the poses of session `a` (the rows, t) and
/// `j` those of session `b` (the columns, t′); its [`measures`](ComponentRow::measures) are the
/// block's (trivial: it holds diagonal cells, within one session only); its
/// [`positions`](ComponentRow::positions) are those of pose `closest_i` of session `a` and pose
/// `closest_j` of session `b`.
pub type FleetComponentRow = ComponentRow<SessionBlock>;

/// Where fleet component `component`'s closest pair is: pose `closest_pair[0]` of session `a`
/// and pose `closest_pair[1]` of session `b`, among `positions`, one list per session (each
/// session's [`point_positions`](crate::point_positions), or its log's own); unknown without
/// them. O(1).
///
/// # Panics
/// When a session or pose is outside `positions`.
pub fn fleet_closest_positions(
    component: &loops_core::fleet::FleetComponent,
    positions: Option<&[Vec<[f64; 3]>]>,
) -> ClosestPositions {
    let Some(positions) = positions else { return ClosestPositions::default() };
    closest_positions_by(component, |a, i| positions[a][i])
}

/// Where fleet component `component`'s closest pair is, read from the sessions of `fleet`
/// ([`point_position`](crate::point_position) of its two poses), without every session's
/// positions. O(1).
///
/// # Panics
/// When a session or pose is not `fleet`'s (a component of another fleet).
pub fn fleet_closest_positions_in(
    component: &loops_core::fleet::FleetComponent,
    fleet: &loops_core::fleet::Fleet,
) -> ClosestPositions {
    closest_positions_by(component, |a, i| crate::point_position(fleet.session(a), i))
}

/// Pose `closest_pair[0]` of session `a` and pose `closest_pair[1]` of session `b`, placed by
/// `position(session, pose)`: the one rule of [`fleet_closest_positions`] and
/// [`fleet_closest_positions_in`].
fn closest_positions_by(
    component: &loops_core::fleet::FleetComponent,
    position: impl Fn(usize, usize) -> [f64; 3],
) -> ClosestPositions {
    let [a, b] = component.sessions;
    let [i, j] = component.closest_pair;
    ClosestPositions::of_poses([Some(position(a, i)), Some(position(b, j))])
}

/// The block of a fleet's component: its two sessions, by index and name. `session_a` and
/// `session_b` are indices in the fleet everywhere (these files, the Python tables, the Parquet
/// tables); `name_a` and `name_b` their names.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub struct SessionBlock {
    /// Session `a`'s index in the fleet (the rows, t).
    pub session_a: usize,
    /// Session `b`'s index in the fleet (the columns, t′; `a ≤ b`, `a = b` within one session).
    pub session_b: usize,
    /// The name of session `a`.
    pub name_a: String,
    /// The name of session `b`.
    pub name_b: String,
}

/// The rows of a fleet's `components.csv`: one per component of `loops` (found on `fleet`), in
/// id order, with the closest pair's `positions` ([`fleet_closest_positions`]; one list per
/// session, or unknown). With `samples_per_component` (by component id, as
/// [`SampleQuality::per_component`](loops_core::SampleQuality::per_component) of the joint
/// result), each row has its number of samples (0 for an id past its end). O(components).
///
/// # Panics
/// When `loops` were found on another fleet (a session or pose `fleet` or `positions` does not
/// have).
pub fn fleet_component_rows(
    fleet: &Fleet,
    loops: &FleetLoops,
    positions: Option<&[Vec<[f64; 3]>]>,
    samples_per_component: Option<&[u64]>,
) -> Vec<FleetComponentRow> {
    let joint = loops.loops().components();
    loops
        .components()
        .into_iter()
        .map(|c| {
            let [a, b] = c.sessions;
            let times = [fleet.session(a).timestamps_s(), fleet.session(b).timestamps_s()];
            let (name_a, name_b) = (fleet.names()[a].clone(), fleet.names()[b].clone());
            FleetComponentRow {
                id: c.id,
                block: SessionBlock { session_a: a, session_b: b, name_a, name_b },
                // The joint component's measures are the block's (a fleet component is the joint
                // one in its sessions' poses).
                measures: ComponentMeasures::new(&joint[c.id]),
                extent: ComponentExtent::new(c.poses, c.closest_pair, c.closest_distance, times),
                positions: fleet_closest_positions(&c, positions),
                samples: samples_per_component.map(|s| s.get(c.id).copied().unwrap_or(0)),
            }
        })
        .collect()
}

/// Writes a fleet's `components.csv` to `out`: a header of [`FLEET_COMPONENT_COLUMNS`] (and
/// `samples` with `samples_per_component`), then the [`fleet_component_rows`] (the closest
/// pair's positions among `positions`, one list per session; empty fields without). Numbers
/// are printed as in `components.csv`. O(components).
///
/// # Errors
/// What `out` returns.
///
/// # Panics
/// As [`fleet_component_rows`].
///
/// # Examples
/// ```
/// use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops};
/// use loops_core::{Euclidean, Trajectory};
/// let monday = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
/// let tuesday = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
/// let fleet = Fleet::new(vec![("monday".into(), monday), ("tuesday".into(), tuesday)])?;
/// let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
/// let mut text = Vec::new();
/// let positions: Vec<_> = (0..fleet.len()).map(|a| loops_io::point_positions(fleet.session(a))).collect();
/// loops_io::fleet_components_to_csv(&fleet, &loops, Some(&positions), None, &mut text).unwrap();
/// let text = String::from_utf8(text).unwrap();
/// assert!(text.starts_with("id,session_a,session_b,name_a,name_b,trivial,area_s2,"));
/// // Tuesday's pose 1 (t = 101 s on its clock, at (0, 0.5)) passes Monday's pose 0, 0.5 away.
/// assert!(
///     text.lines().any(|line| line.ends_with(",0,1,monday,tuesday,false,0.25,1,1,1,0,0,0,1,1,0,0,101,101,0,1,0.5,0,0,0,0,0.5,0"))
/// );
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn fleet_components_to_csv<W: Write>(
    fleet: &Fleet,
    loops: &FleetLoops,
    positions: Option<&[Vec<[f64; 3]>]>,
    samples_per_component: Option<&[u64]>,
    out: W,
) -> io::Result<()> {
    let mut columns = FLEET_COMPONENT_COLUMNS.to_vec();
    if samples_per_component.is_some() {
        columns.push("samples");
    }
    write_csv(out, &columns, fleet_component_rows(fleet, loops, positions, samples_per_component))
}

/// Writes a fleet's `components.csv` ([`fleet_components_to_csv`]) to the file `path`,
/// atomically ([`write_atomically`](crate::write_atomically)); an existing file is replaced only
/// with `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
///
/// # Panics
/// As [`fleet_component_rows`].
pub fn write_fleet_components(
    path: impl AsRef<Path>,
    fleet: &Fleet,
    loops: &FleetLoops,
    positions: Option<&[Vec<[f64; 3]>]>,
    samples_per_component: Option<&[u64]>,
    overwrite: bool,
) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |file| {
        fleet_components_to_csv(fleet, loops, positions, samples_per_component, file)
    })
}

/// The columns of `session_pairs.csv`.
pub const SESSION_PAIR_COLUMNS: [&str; 8] =
    ["session_a", "session_b", "name_a", "name_b", "components", "pair_count", "area_s2", "density"];

/// One row of `session_pairs.csv`, one entry of the sparse session-overlap matrix: a
/// [`SessionPair`](loops_core::fleet::SessionPair) with its sessions' names.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct SessionPairRow {
    /// Session `a`'s index in the fleet.
    pub session_a: usize,
    /// Session `b`'s index in the fleet (`a ≤ b`; `a = b`: the session alone).
    pub session_b: usize,
    /// The name of session `a`.
    pub name_a: String,
    /// The name of session `b`.
    pub name_b: String,
    /// Loop components in the block.
    pub components: usize,
    /// Pose pairs in the block (for `a = b`, both halves of the square, the diagonal once).
    pub pair_count: u64,
    /// Loop area α of the block, s² (for `a = b`, the whole square); α(b, a) = α(a, b).
    pub area_s2: f64,
    /// Loop density ρ = α / (T_a T_b), T the sessions' spans: the share of the block's
    /// rectangle within γ.
    pub density: f64,
}

/// The rows of `session_pairs.csv`: every session pair (a, b), a ≤ b, with at least one loop
/// component, in order of (a, b) ([`FleetLoops::session_pairs`]). O(components).
///
/// # Panics
/// When `loops` were found on another fleet (a session `fleet` does not have).
pub fn session_pair_rows(fleet: &Fleet, loops: &FleetLoops) -> Vec<SessionPairRow> {
    loops.session_pairs().iter().map(|pair| SessionPairRow::new(pair, fleet.names())).collect()
}

impl SessionPairRow {
    /// The row of `pair`, its sessions named by `names` (the fleet's, in fleet order).
    ///
    /// # Panics
    /// When `names` has no name for a session of `pair`.
    pub fn new(pair: &loops_core::fleet::SessionPair, names: &[String]) -> Self {
        let [a, b] = pair.sessions;
        Self {
            session_a: a,
            session_b: b,
            name_a: names[a].clone(),
            name_b: names[b].clone(),
            components: pair.components,
            pair_count: pair.pair_count,
            area_s2: pair.area_s2,
            density: pair.density,
        }
    }
}

/// Writes `session_pairs.csv` to `out`: a header of [`SESSION_PAIR_COLUMNS`], then the
/// [`session_pair_rows`]. O(components).
///
/// # Errors
/// What `out` returns.
///
/// # Panics
/// As [`session_pair_rows`].
///
/// # Examples
/// ```
/// use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops};
/// use loops_core::{Euclidean, Trajectory};
/// let monday = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
/// let tuesday = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
/// let fleet = Fleet::new(vec![("monday".into(), monday), ("tuesday".into(), tuesday)])?;
/// let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
/// let mut text = Vec::new();
/// loops_io::session_pairs_to_csv(&fleet, &loops, &mut text).unwrap();
/// let text = String::from_utf8(text).unwrap();
/// assert_eq!(text.lines().next(), Some("session_a,session_b,name_a,name_b,components,pair_count,area_s2,density"));
/// // Two places where the sessions meet, one cell each: 1 s × 1 s of 2 s × 1 s of spans.
/// assert_eq!(text.lines().nth(2), Some("0,1,monday,tuesday,2,2,0.5,0.25"));
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn session_pairs_to_csv<W: Write>(fleet: &Fleet, loops: &FleetLoops, out: W) -> io::Result<()> {
    write_csv(out, &SESSION_PAIR_COLUMNS, session_pair_rows(fleet, loops))
}

/// Writes `session_pairs.csv` ([`session_pairs_to_csv`]) to the file `path`, atomically; an
/// existing file is replaced only with `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written.
///
/// # Panics
/// As [`session_pair_rows`].
pub fn write_session_pairs(
    path: impl AsRef<Path>,
    fleet: &Fleet,
    loops: &FleetLoops,
    overwrite: bool,
) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |file| session_pairs_to_csv(fleet, loops, file))
}

/// The columns of a fleet's samples, as the CSV header names them.
pub const FLEET_SAMPLE_COLUMNS: [&str; 11] =
    ["session_a", "session_b", "name_a", "name_b", "i", "j", "t_s", "t_prime_s", "component", "distance", "sampler"];

/// One row of a fleet's samples file: a [`FleetSample`] with its sessions' names. `None` is
/// unknown: an empty CSV field, `null` in JSON.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct FleetSampleRow {
    /// The index in the fleet of the session of the earlier pose (in fleet order).
    pub session_a: usize,
    /// The index of the session of the later pose (`a ≤ b`).
    pub session_b: usize,
    /// The name of session `a`.
    pub name_a: String,
    /// The name of session `b`.
    pub name_b: String,
    /// The pose of session `a`.
    pub i: usize,
    /// The pose of session `b`.
    pub j: usize,
    /// Time of pose `i`, seconds on session `a`'s clock.
    pub t_s: f64,
    /// Time of pose `j`, seconds on session `b`'s clock.
    pub t_prime_s: f64,
    /// The loop component of the pair (its id in the fleet's `components.csv`), when known.
    pub component: Option<usize>,
    /// δ between the two poses, in the metric's unit, when known.
    pub distance: Option<f64>,
    /// The sampler's name.
    pub sampler: &'static str,
}

/// The rows of a fleet's samples: `samples` of [`sample_fleet`](loops_core::fleet::sample_fleet) on
/// `fleet` ([`Fleet::localize`]), in the samples' order. O(samples · log sessions).
///
/// # Errors
/// [`Error::IndexOutOfRange`] for samples of another fleet.
pub fn fleet_sample_rows(fleet: &Fleet, samples: &Samples) -> loops_core::Result<Vec<FleetSampleRow>> {
    let sampler = samples.sampler().name();
    Ok(fleet.localize(samples)?.into_iter().map(|s| sample_row(fleet, &s, sampler)).collect())
}

fn sample_row(fleet: &Fleet, s: &FleetSample, sampler: &'static str) -> FleetSampleRow {
    FleetSampleRow {
        session_a: s.sessions[0],
        session_b: s.sessions[1],
        name_a: fleet.names()[s.sessions[0]].clone(),
        name_b: fleet.names()[s.sessions[1]].clone(),
        i: s.poses[0],
        j: s.poses[1],
        t_s: s.times_s[0],
        t_prime_s: s.times_s[1],
        component: s.component,
        distance: s.distance,
        sampler,
    }
}

/// An error of the core as the writers' `io::Error`.
fn invalid(error: Error) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, error)
}

/// Writes a fleet's samples as CSV: a header of [`FLEET_SAMPLE_COLUMNS`], then one line a
/// sample ([`fleet_sample_rows`]). O(samples · log sessions).
///
/// # Errors
/// What `out` returns; an `InvalidInput` error holding [`Error::IndexOutOfRange`] for samples of
/// another fleet (nothing is written then).
///
/// # Examples
/// ```
/// use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops, sample_fleet};
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, Trajectory};
/// let monday = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
/// let tuesday = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
/// let fleet = Fleet::new(vec![("monday".into(), monday), ("tuesday".into(), tuesday)])?;
/// let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
/// let sampler = Sampler::new(SamplerKind::One, SampleSize::Budget(2), 0);
/// let samples = sample_fleet(&fleet, &Euclidean, &loops, &sampler, true)?;
/// let mut text = Vec::new();
/// loops_io::fleet_samples_to_csv(&fleet, &samples, &mut text).unwrap();
/// let text = String::from_utf8(text).unwrap();
/// let first = text.lines().nth(1).unwrap();
/// assert!(first.starts_with("0,1,monday,tuesday,0,1,0,101,") && first.ends_with(",0.5,one"), "{first}");
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn fleet_samples_to_csv<W: Write>(fleet: &Fleet, samples: &Samples, out: W) -> io::Result<()> {
    let rows = fleet_sample_rows(fleet, samples).map_err(invalid)?;
    write_csv(out, &FLEET_SAMPLE_COLUMNS, rows)
}

/// The whole file in JSON.
#[derive(serde::Serialize)]
struct JsonFleetSamples<'a> {
    sampler: &'static str,
    count: usize,
    groups: usize,
    available: u64,
    sessions: &'a [String],
    warnings: Vec<String>,
    samples: Vec<FleetSampleRow>,
}

/// Writes a fleet's samples as one JSON object: `sampler` (its name), `count`, `groups`
/// (components sampled from), `available` (candidates chosen from), `sessions` (the names, in
/// fleet order), `warnings` (sentences) and `samples`, a list of objects with the columns of
/// [`FLEET_SAMPLE_COLUMNS`] (`null` for unknown values). O(samples · log sessions).
///
/// # Errors
/// As [`fleet_samples_to_csv`].
pub fn fleet_samples_to_json<W: Write>(fleet: &Fleet, samples: &Samples, out: W) -> io::Result<()> {
    let document = JsonFleetSamples {
        sampler: samples.sampler().name(),
        count: samples.len(),
        groups: samples.groups(),
        available: samples.available(),
        sessions: fleet.names(),
        warnings: samples.warnings().iter().map(ToString::to_string).collect(),
        samples: fleet_sample_rows(fleet, samples).map_err(invalid)?,
    };
    write_json(&document, out)
}

/// Writes a fleet's samples to the file `path` in `format` ([`fleet_samples_to_csv`],
/// [`fleet_samples_to_json`]), atomically; an existing file is replaced only with `overwrite`.
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written, or for samples of another fleet.
pub fn write_fleet_samples(
    path: impl AsRef<Path>,
    fleet: &Fleet,
    samples: &Samples,
    format: SamplesFormat,
    overwrite: bool,
) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |out| match format {
        SamplesFormat::Csv => fleet_samples_to_csv(fleet, samples, out),
        SamplesFormat::Json => fleet_samples_to_json(fleet, samples, out),
    })
}

/// The robot letters of [`gtsam_symbol_key`], one per session in fleet order: session 0 is `a`,
/// session 25 is `z`. A fleet of more sessions has no g2o file with these keys.
pub const GTSAM_ROBOT_LETTERS: &str = "abcdefghijklmnopqrstuvwxyz";

/// Bits of the index in a GTSAM `Symbol` key (64-bit keys, 8 bits of character).
const SYMBOL_INDEX_BITS: u32 = 56;

/// The GTSAM `Symbol` key of pose `pose` of session `session`: the session's robot letter c (the
/// `session`-th of [`GTSAM_ROBOT_LETTERS`]: `a`, `b`, …, `z`) and the pose index j, as
/// `key = (c << 56) | j`, GTSAM's `Symbol::key()` (`gtsam/inference/Symbol.cpp`: `Key key =
/// (Key(c_) << indexBits) | j_`, `indexBits` = 64 − 8 bits) and Python's `gtsam.symbol(c, j)`;
/// `gtsam.Symbol(key)` gives the letter and index back (`.chr()`, `.index()`). A robot letter
/// per session, in order, is the multi-robot convention of Kimera-Multi (Kimera-PGMO's
/// `robot_id_to_prefix`: robot 0 is `a`, robot 1 is `b`, …).
///
/// # Errors
/// [`Error::InvalidParameter`] for a session past the 26 letters (`sessions = 27 is invalid`,
/// naming the limit), or a pose index that does not fit GTSAM's 56 index bits.
///
/// # Examples
/// ```
/// use loops_io::gtsam_symbol_key;
/// // gtsam.symbol('a', 5) and gtsam.symbol('b', 0) in GTSAM's Python bindings.
/// assert_eq!(gtsam_symbol_key(0, 5)?, 6_989_586_621_679_009_797);
/// assert_eq!(gtsam_symbol_key(1, 0)?, (u64::from(b'b') << 56));
/// assert!(gtsam_symbol_key(26, 0).is_err());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn gtsam_symbol_key(session: usize, pose: usize) -> loops_core::Result<u64> {
    let letter = GTSAM_ROBOT_LETTERS.as_bytes().get(session).ok_or(Error::InvalidParameter {
        name: "sessions",
        value: (session + 1) as f64,
        expected: "at most 26 for g2o with GTSAM Symbol keys (one robot letter a-z per session)",
    })?;
    let index = pose as u64;
    if index >> SYMBOL_INDEX_BITS != 0 {
        return Err(Error::InvalidParameter {
            name: "pose index",
            value: pose as f64,
            expected: "below 2^56, the index bits of a GTSAM Symbol key",
        });
    }
    Ok(u64::from(*letter) << SYMBOL_INDEX_BITS | index)
}

/// The text of [`write_fleet_g2o_edges`] (its `overwrite` option aside): for a command that
/// writes several files all or none. O(poses written + samples).
///
/// # Errors
/// As [`write_fleet_g2o_edges`], but for writing.
pub fn fleet_g2o_edges_text(tables: &[&PoseTable], samples: &[FleetSample], options: &G2oOptions) -> Result<String> {
    if let Some(table) = tables.get(GTSAM_ROBOT_LETTERS.len()) {
        let error = gtsam_symbol_key(tables.len() - 1, 0).expect_err("past the letters");
        return Err(table.locate(error));
    }
    for s in samples {
        for (&session, &pose) in s.sessions.iter().zip(&s.poses) {
            let Some(table) = tables.get(session) else {
                let at = tables.last().map_or_else(|| Path::new("").into(), |t| t.path.as_path().into());
                let error = Error::IndexOutOfRange { index: session, len: tables.len() };
                return Err(IoError::Trajectory { path: at, line: None, previous_line: None, messages: None, error });
            };
            if pose >= table.len() {
                return Err(table.locate(Error::IndexOutOfRange { index: pose, len: table.len() }));
            }
        }
    }
    let kind = options.kind.unwrap_or(if tables.iter().all(|t| t.dim == 2) { EdgeKind::Se2 } else { EdgeKind::Se3 });
    let key = |session: usize, pose: usize, table: &PoseTable| {
        gtsam_symbol_key(session, pose).map_err(|error| table.locate(error))
    };
    let mut lines = String::new();
    if options.with_vertices {
        for (session, table) in tables.iter().enumerate() {
            for pose in 0..table.len() {
                lines += &vertex_line(kind, key(session, pose, table)?, pose_of(table, pose)?);
            }
        }
    }
    for s in samples {
        let ([a, b], [i, j]) = (s.sessions, s.poses);
        let (ta, tb) = (tables[a], tables[b]);
        lines += &edge_line(kind, [key(a, i, ta)?, key(b, j, tb)?], pose_of(ta, i)?, pose_of(tb, j)?);
    }
    Ok(lines)
}

/// Writes candidate loop-closure edges between the sessions of a fleet as g2o: for each sample
/// ([`Fleet::localize`]d), an edge from pose `i` of session `a` to pose `j` of session `b`
/// whose measurement is the relative pose between them in the tables (one frame for all
/// sessions), as [`write_g2o_edges`](crate::write_g2o_edges) writes it for one trajectory.
/// Vertex ids are GTSAM `Symbol` keys ([`gtsam_symbol_key`]): session `a`'s letter and the
/// pose's index in its session, so `gtsam.readG2o` reads them as `Symbol('a', i)`, ….
///
/// `tables[k]` are the poses of session `k` as read (orientations where the files have them);
/// the edge type is [`EdgeKind::Se2`] when every table is 2-D, else [`EdgeKind::Se3`], unless
/// `options` names one. Time O(poses written + samples). The file is written atomically.
///
/// # Errors
/// [`IoError::Trajectory`] holding [`Error::InvalidParameter`] for more than 26 sessions
/// (naming the limit, at the first session past it), [`Error::IndexOutOfRange`] for a sample of
/// another fleet, or [`Error::NonUnitQuaternion`] for a zero or non-finite quaternion;
/// [`IoError::Write`] holding a [`WriteError`] as [`write_tum`](crate::write_tum).
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops, sample_fleet};
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind};
/// use loops_io::{G2oOptions, read_tum, write_fleet_g2o_edges};
/// let dir = std::env::temp_dir().join(format!("loops-io-doc-{}-fleet-g2o", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// std::fs::write(dir.join("monday.tum"), "0 0 0 0 0 0 0 1\n1 5 0 0 0 0 0 1\n2 10 0 0 0 0 0 1\n")?;
/// std::fs::write(dir.join("tuesday.tum"), "100 10 0.5 0 0 0 0 1\n101 0 0.5 0 0 0 1 0\n")?;
/// let tables = [read_tum(dir.join("monday.tum"))?, read_tum(dir.join("tuesday.tum"))?];
/// let fleet = Fleet::new(vec![
///     ("monday".into(), tables[0].to_trajectory()?),
///     ("tuesday".into(), tables[1].to_trajectory()?),
/// ])?;
/// let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
/// let sampler = Sampler::new(SamplerKind::One, SampleSize::Budget(2), 0);
/// let samples = fleet.localize(&sample_fleet(&fleet, &Euclidean, &loops, &sampler, true)?)?;
/// let out = dir.join("candidates.g2o");
/// write_fleet_g2o_edges(&out, &[&tables[0], &tables[1]], &samples, &G2oOptions::default())?;
/// let text = std::fs::read_to_string(&out)?;
/// // Monday's pose 0 (a0) and Tuesday's pose 1 (b1), which faces back along x.
/// let (a0, b1) = ((u64::from(b'a') << 56), (u64::from(b'b') << 56) | 1);
/// assert!(text.starts_with(&format!("EDGE_SE3:QUAT {a0} {b1} 0 0.5 0 0 0 1 0 ")), "{text}");
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn write_fleet_g2o_edges(
    path: impl AsRef<Path>,
    tables: &[&PoseTable],
    samples: &[FleetSample],
    options: &G2oOptions,
) -> Result<()> {
    let lines = fleet_g2o_edges_text(tables, samples, options)?;
    write_atomically(path.as_ref(), options.overwrite, |file| file.write_all(lines.as_bytes())).map_err(IoError::Write)
}

#[cfg(test)]
mod tests {
    use loops_core::{
        Euclidean, Metric, SampleSize, Sampler, SamplerKind, Trajectory,
        fleet::{FleetOptions, find_fleet_loops, sample_fleet},
    };

    use super::*;
    use crate::components::COMPONENT_COLUMNS;

    const GAMMA: f64 = 0.5;

    /// Three sessions on a line: out along x, back 0.2 beside it on another clock, and one far
    /// away; poses 0.25 apart, so the way back meets the way out in one band.
    fn fleet() -> (Fleet, FleetLoops) {
        let line = |t0: f64, xs: &[f64], y: f64| {
            let points: Vec<[f64; 2]> = xs.iter().map(|&x| [x, y]).collect();
            Trajectory::from_points((0..xs.len()).map(|i| t0 + i as f64).collect(), &points).unwrap()
        };
        let out: Vec<f64> = (0..=16).map(|k| 0.25 * f64::from(k)).collect();
        let back: Vec<f64> = (0..=12).map(|k| 4.0 - 0.25 * f64::from(k)).collect();
        let fleet = Fleet::new(vec![
            ("out".into(), line(0.0, &out, 0.0)),
            ("back, \"quoted\"".into(), line(500.0, &back, 0.2)),
            ("far".into(), line(7.0, &[100.0, 101.0], 0.0)),
        ])
        .unwrap();
        let loops = find_fleet_loops(&fleet, &Euclidean, GAMMA, &FleetOptions::default()).unwrap();
        (fleet, loops)
    }

    /// The pairs of sessions 0 and 1 within γ, every pair measured.
    fn cross_pairs(fleet: &Fleet) -> Vec<[usize; 2]> {
        let (a, b) = (fleet.session(0), fleet.session(1));
        let mut pairs = Vec::new();
        for i in 0..a.len() {
            for j in 0..b.len() {
                if Euclidean.distance(a.point(i), b.point(j)) <= GAMMA {
                    pairs.push([i, j]);
                }
            }
        }
        pairs
    }

    #[test]
    fn component_columns_follow_components_csv() {
        // A log's columns after the block, the closest pair's positions included.
        assert_eq!(FLEET_COMPONENT_COLUMNS[5..], COMPONENT_COLUMNS[1..]);
        let (fleet, loops) = fleet();
        let rows = fleet_component_rows(&fleet, &loops, None, Some(&[4]));
        let mut expected = FLEET_COMPONENT_COLUMNS.to_vec();
        expected.push("samples");
        assert_eq!(crate::csv_rows::inferred_columns(&rows[0]), expected);
        assert_eq!((rows[0].samples, rows.last().unwrap().samples), (Some(4), Some(0)));
    }

    #[test]
    fn closest_positions_read_from_the_fleet_are_those_of_every_position() {
        let (fleet, loops) = fleet();
        let positions: Vec<_> = (0..fleet.len()).map(|a| crate::point_positions(fleet.session(a))).collect();
        let components = loops.components();
        assert!(components.iter().any(|c| c.sessions[0] != c.sessions[1]));
        for c in &components {
            let [a, b] = c.sessions;
            let [i, j] = c.closest_pair;
            let read = fleet_closest_positions_in(c, &fleet);
            assert_eq!(read, fleet_closest_positions(c, Some(&positions)));
            assert_eq!(read.closest_i_x, Some(fleet.session(a).point(i)[0]));
            assert_eq!(read.closest_j_y, Some(fleet.session(b).point(j)[1]));
        }
    }

    #[test]
    fn rows_name_sessions_and_their_own_clocks() {
        let (fleet, loops) = fleet();
        let positions: Vec<_> = (0..fleet.len()).map(|a| crate::point_positions(fleet.session(a))).collect();
        let rows = fleet_component_rows(&fleet, &loops, Some(&positions), None);
        assert_eq!(rows.len(), loops.loops().components().len());
        for row in &rows {
            let c = &loops.components()[row.id];
            let block = &row.block;
            assert_eq!([block.session_a, block.session_b], c.sessions);
            assert_eq!(
                [&block.name_a, &block.name_b],
                [&fleet.names()[block.session_a], &fleet.names()[block.session_b]]
            );
            assert_eq!(row.extent.t_min_s, fleet.session(block.session_a).timestamps_s()[row.extent.i_min]);
            assert_eq!(row.extent.t_prime_max_s, fleet.session(block.session_b).timestamps_s()[row.extent.j_max]);
            assert_eq!(row.measures.run_count, loops.loops().components()[row.id].run_count);
            // The closest pair's positions: pose closest_i of session a, closest_j of session b.
            let [a, b] = [block.session_a, block.session_b].map(|s| fleet.session(s));
            let (i, j) = (a.point(row.extent.closest_i), b.point(row.extent.closest_j));
            let p = &row.positions;
            assert_eq!([p.closest_i_x, p.closest_i_y, p.closest_i_z], [Some(i[0]), Some(i[1]), Some(0.0)]);
            assert_eq!([p.closest_j_x, p.closest_j_y, p.closest_j_z], [Some(j[0]), Some(j[1]), Some(0.0)]);
        }
        // The way back meets the way out in one band: every pair within γ, every pose of the
        // way back, on its own clock from 500 s.
        let between: Vec<_> = rows.iter().filter(|r| r.block.session_a != r.block.session_b).collect();
        assert_eq!(between.len(), 1);
        let pairs = cross_pairs(&fleet);
        assert_eq!(
            (between[0].block.session_a, between[0].block.session_b, between[0].measures.pair_count),
            (0, 1, pairs.len() as u64)
        );
        assert_eq!((between[0].extent.t_prime_min_s, between[0].extent.t_prime_max_s), (500.0, 512.0));
        let i_max = pairs.iter().map(|p| p[0]).max().unwrap();
        assert_eq!((between[0].extent.i_max, between[0].extent.t_max_s), (i_max, i_max as f64));
        let mut text = Vec::new();
        fleet_components_to_csv(&fleet, &loops, Some(&positions), None, &mut text).unwrap();
        let text = String::from_utf8(text).unwrap();
        assert_eq!(text.lines().count(), 1 + rows.len());
        // The way back's closest pose (4 - 0.25 j, 0.2) lies on the way out's (0.25 i, 0).
        let row = between[0];
        let [i, j] = [row.extent.closest_i as f64, row.extent.closest_j as f64];
        assert_eq!(row.positions.closest_i_x, Some(0.25 * i));
        assert_eq!((row.positions.closest_j_x, row.positions.closest_j_y), (Some(4.0 - 0.25 * j), Some(0.2)));
        assert!(text.contains(",0,1,out,\"back, \"\"quoted\"\"\",false,"), "{text}");
    }

    #[test]
    fn session_pairs_are_the_sparse_matrix() {
        let (fleet, loops) = fleet();
        let rows = session_pair_rows(&fleet, &loops);
        let blocks: Vec<[usize; 2]> = rows.iter().map(|r| [r.session_a, r.session_b]).collect();
        assert_eq!(blocks, [[0, 0], [0, 1], [1, 1], [2, 2]], "far never meets the others");
        let between = &rows[1];
        let c = loops.components().into_iter().find(|c| c.sessions == [0, 1]).unwrap();
        let pairs = cross_pairs(&fleet).len() as u64;
        assert_eq!((between.components, between.pair_count, between.area_s2), (1, pairs, c.area_s2));
        let spans = fleet.session(0).span_s() * fleet.session(1).span_s();
        assert_eq!((spans, between.density), (16.0 * 12.0, c.area_s2 / spans));
        let mut text = Vec::new();
        session_pairs_to_csv(&fleet, &loops, &mut text).unwrap();
        assert_eq!(String::from_utf8(text).unwrap().lines().next().unwrap(), SESSION_PAIR_COLUMNS.join(","));
    }

    #[test]
    fn samples_name_both_sessions() {
        let (fleet, loops) = fleet();
        let sampler = Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0);
        let samples = sample_fleet(&fleet, &Euclidean, &loops, &sampler, true).unwrap();
        let rows = fleet_sample_rows(&fleet, &samples).unwrap();
        assert_eq!(rows.len(), cross_pairs(&fleet).len(), "every pair between the sessions");
        assert_eq!(crate::csv_rows::inferred_columns(&rows[0]), FLEET_SAMPLE_COLUMNS);
        for row in &rows {
            assert_eq!((row.session_a, row.session_b, row.name_b.as_str()), (0, 1, "back, \"quoted\""));
            assert_eq!(row.t_s, fleet.session(0).timestamps_s()[row.i]);
            assert_eq!(row.t_prime_s, fleet.session(1).timestamps_s()[row.j]);
            let (pa, pb) = (fleet.session(0).point(row.i), fleet.session(1).point(row.j));
            assert_eq!(row.distance, Some(Euclidean.distance(pa, pb)));
        }
        let mut json = Vec::new();
        fleet_samples_to_json(&fleet, &samples, &mut json).unwrap();
        let value: serde_json::Value = serde_json::from_slice(&json).unwrap();
        assert_eq!(value["count"], rows.len());
        assert_eq!(value["sessions"][2], "far");
        assert_eq!(value["samples"][0]["name_a"], "out");
        // Samples of another fleet are refused, not written.
        let other = Fleet::new(vec![("x".into(), fleet.session(2).clone())]).unwrap();
        let error = fleet_samples_to_csv(&other, &samples, Vec::new()).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::InvalidInput);
    }

    /// A table of `positions` with identity orientations, from `path`.
    fn table(path: &str, positions: &[[f64; 3]]) -> PoseTable {
        PoseTable {
            path: path.into(),
            timestamps_s: (0..positions.len()).map(|i| i as f64).collect(),
            timestamps_ns: None,
            positions: positions.to_vec(),
            orientations_xyzw: Some(vec![[0.0, 0.0, 0.0, 1.0]; positions.len()]),
            dim: 3,
            source_lines: (1..=positions.len()).collect(),
            messages: None,
        }
    }

    #[test]
    fn symbol_keys_are_gtsams() {
        // gtsam.symbol(c, j) printed by GTSAM 4.3's Python bindings.
        assert_eq!(gtsam_symbol_key(0, 5).unwrap(), 6_989_586_621_679_009_797);
        assert_eq!(gtsam_symbol_key(25, 0).unwrap(), 8_791_026_472_627_208_192);
        assert_eq!(gtsam_symbol_key(0, (1 << 56) - 1).unwrap(), 7_061_644_215_716_937_727);
        let error = gtsam_symbol_key(26, 0).unwrap_err();
        assert!(error.to_string().starts_with("sessions = 27 is invalid: at most 26"), "{error}");
        assert!(gtsam_symbol_key(0, 1 << 56).is_err());
    }

    #[test]
    fn g2o_edges_join_the_sessions_poses() {
        let a = table("a.tum", &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        let b = table("b.tum", &[[5.0, 0.0, 0.0], [1.0, 2.0, 0.0], [9.0, 9.0, 0.0]]);
        let samples = [FleetSample {
            sessions: [0, 1],
            poses: [1, 1],
            times_s: [1.0, 1.0],
            component: Some(0),
            distance: Some(2.0),
        }];
        let options = G2oOptions::default().with_vertices(true);
        let text = fleet_g2o_edges_text(&[&a, &b], &samples, &options).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 5 + 1);
        let (a1, b1) = (gtsam_symbol_key(0, 1).unwrap(), gtsam_symbol_key(1, 1).unwrap());
        assert_eq!(lines[1], format!("VERTEX_SE3:QUAT {a1} 1 0 0 0 0 0 1"));
        assert!(lines[5].starts_with(&format!("EDGE_SE3:QUAT {a1} {b1} 0 2 0 0 0 0 1 ")), "{}", lines[5]);
        // The same edge as the single-trajectory writer gives for the two poses in one table.
        let joined = table("ab.tum", &[[1.0, 0.0, 0.0], [1.0, 2.0, 0.0]]);
        let single = crate::g2o_edges_text(&joined, &[(0, 1)], &G2oOptions::default()).unwrap();
        assert_eq!(
            single.split_whitespace().skip(3).collect::<Vec<_>>(),
            lines[5].split_whitespace().skip(3).collect::<Vec<_>>()
        );
        // 2-D tables give EDGE_SE2.
        let flat = |t: &PoseTable| PoseTable { dim: 2, ..t.clone() };
        let (a2, b2) = (flat(&a), flat(&b));
        let text = fleet_g2o_edges_text(&[&a2, &b2], &samples, &G2oOptions::default()).unwrap();
        assert_eq!(text, format!("EDGE_SE2 {a1} {b1} 0 2 0 1 0 0 1 0 1\n"));
        // A pose or session the tables do not have, and a 27th session, are errors naming them.
        let bad = [FleetSample { poses: [1, 3], ..samples[0] }];
        let error = fleet_g2o_edges_text(&[&a, &b], &bad, &options).unwrap_err();
        assert!(error.to_string().starts_with("b.tum: pose index 3 is out of range"), "{error}");
        let bad = [FleetSample { sessions: [0, 2], ..samples[0] }];
        assert!(fleet_g2o_edges_text(&[&a, &b], &bad, &options).is_err());
        let many: Vec<PoseTable> = (0..27).map(|k| table(&format!("s{k}.tum"), &[[0.0; 3]; 2])).collect();
        let refs: Vec<&PoseTable> = many.iter().collect();
        let error = fleet_g2o_edges_text(&refs, &[], &options).unwrap_err();
        assert!(error.to_string().starts_with("s26.tum: sessions = 27 is invalid: at most 26"), "{error}");
        assert!(fleet_g2o_edges_text(&refs[..26], &[], &options).is_ok());
    }
}

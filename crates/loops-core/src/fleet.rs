//! Fleets: loops within and between sessions (vehicles, days, robots) in one frame.
//!
//! A [`Fleet`] is several trajectories, each with a name and its own clock. S_γ over a fleet is,
//! for every pair of sessions (a, b) with a ≤ b, the pairs (t_a, t′_b) within γ: a *block* of
//! the plane. Loop components are 4-connected on each block's own lattice, never across
//! sessions. An intra-session block (a, a) is the analysis of session a alone (with the revisit
//! separation, if any); an inter-session block (a, b), a < b, has no diagonal, and each of its
//! components is one place where the two sessions overlap.
//!
//! The engine is the single-trajectory engine: the sessions are laid one after
//! another as one trajectory (each keeping its own time cells, half cells at its ends), the path
//! length runs on across a break with the jump between the sessions (the triangle inequality
//! still bounds the scan), runs are cut where a session starts, and rows of different sessions
//! are not 4-adjacent. Every block is then scanned at once, rows in parallel. What does not carry
//! over is the far-field pruning: poses of unrelated sessions share no time order, so for
//! Euclidean positions the stretches are found by a KD-tree over chunk balls
//! ([`Pruning::KdTree`], see the `spatial` module) rather than by the time-ordered hierarchy, and
//! session pairs whose paths never come within γ cost no distance evaluation at all.
//!
//! Indices: [`FleetLoops::loops`] is the result over the joint trajectory ([`Fleet::joint`]),
//! in *fleet indices* (0 ‥ total poses) on the *fleet clock* (sessions one after another, an
//! hour apart). [`Fleet::locate`] turns a fleet index into (session, pose); the fleet's own
//! types ([`FleetComponent`], [`FleetSample`], [`SessionPair`]) already name sessions and poses.

use crate::ball_tree::BallTree;
use crate::component::LoopComponent;
use crate::error::{Error, Result};
use crate::loops::Loops;
use crate::measure::{Scale, Selection, Side};
use crate::memory::{try_collect, try_with_capacity};
use crate::metric::Metric;
use crate::sample::{KeyLayout, Sampler, Samples, sample_loops_where};
use crate::separation::Separation;
use crate::spatial::ChunkIndex;
use crate::spec::{MetricSpec, with_metric};
use crate::sublevel::{ArcLength, Pruner, SublevelSet, check_gamma, try_path_length};
use crate::trajectory::Trajectory;

/// Seconds between the end of one session and the start of the next on the fleet clock: more
/// than any time gap a baseline waits for, so a baseline sees other sessions as long past.
pub const FLEET_CLOCK_GAP_S: f64 = 3600.0;

/// Poses per leaf of the ball hierarchy (as for one trajectory).
const LEAF_SIZE: usize = 16;

/// Sessions (trajectories with names and their own clocks) in one frame.
///
/// # Examples
/// ```
/// use loops_core::fleet::{Fleet, FleetOptions, find_fleet_loops};
/// use loops_core::{Euclidean, Trajectory};
/// let out = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
/// let back = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
/// let fleet = Fleet::new(vec![("monday".into(), out), ("tuesday".into(), back)])?;
/// let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
/// let between: Vec<_> = loops.components().into_iter().filter(|c| c.sessions[0] != c.sessions[1]).collect();
/// assert_eq!(between.len(), 2); // the two places where Tuesday passes Monday's poses
/// assert_eq!(between[0].poses, [[0, 0], [1, 1]]); // Monday's pose 0 with Tuesday's pose 1
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Fleet {
    names: Vec<String>,
    sessions: Vec<Trajectory>,
    /// The first fleet index of each session.
    starts: Vec<usize>,
    joint: Trajectory,
    clock_offsets: Vec<f64>,
}

impl Fleet {
    /// A fleet of named sessions, in the order given (which orders the blocks: a ≤ b).
    ///
    /// # Errors
    /// [`Error::EmptyFleet`]; [`Error::DuplicateSession`]; [`Error::SessionMismatch`] for a
    /// session whose dimension or manifold differs from the first's; [`Error::TooManyPoses`]
    /// for more poses in all than one trajectory may hold; [`Error::OutOfMemory`].
    pub fn new(sessions: Vec<(String, Trajectory)>) -> Result<Self> {
        let Some((_, first)) = sessions.first() else { return Err(Error::EmptyFleet) };
        let (dim, manifold) = (first.dim(), first.manifold());
        let what = "the sessions of a fleet";
        let mut seen = std::collections::HashSet::new();
        seen.try_reserve(sessions.len())
            .map_err(|_| Error::OutOfMemory { what, bytes: (sessions.len() * 2 * size_of::<&str>()) as u64 })?;
        for (name, traj) in &sessions {
            if !seen.insert(name.as_str()) {
                return Err(Error::DuplicateSession { name: name.clone() });
            }
            if traj.dim() != dim {
                let problem = format!("has {} coordinates, the first has {dim}", traj.dim());
                return Err(Error::SessionMismatch { session: name.clone(), problem, what: "dimension" });
            }
            if traj.manifold() != manifold {
                let problem = format!("lies on {}, the first on {}", traj.manifold().name(), manifold.name());
                return Err(Error::SessionMismatch { session: name.clone(), problem, what: "manifold" });
            }
        }
        drop(seen);
        let parts: Vec<&Trajectory> = try_collect(sessions.iter().map(|(_, t)| t), what)?;
        let (joint, clock_offsets) = Trajectory::concatenate(&parts, FLEET_CLOCK_GAP_S)?;
        drop(parts);
        let mut starts = try_with_capacity(sessions.len(), what)?;
        let mut next = 0;
        for (_, traj) in &sessions {
            starts.push(next);
            next += traj.len();
        }
        let (mut names, mut trajectories) =
            (try_with_capacity(sessions.len(), what)?, try_with_capacity(sessions.len(), what)?);
        for (name, traj) in sessions {
            names.push(name);
            trajectories.push(traj);
        }
        Ok(Self { names, sessions: trajectories, starts, joint, clock_offsets })
    }

    /// Number of sessions.
    #[allow(clippy::len_without_is_empty)] // a fleet is never empty
    pub fn len(&self) -> usize {
        self.sessions.len()
    }

    /// The sessions' names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The session `a`'s trajectory, on its own clock.
    ///
    /// # Panics
    /// If `a >= len()`.
    pub fn session(&self, a: usize) -> &Trajectory {
        &self.sessions[a]
    }

    /// The first fleet index of each session.
    pub fn starts(&self) -> &[usize] {
        &self.starts
    }

    /// Number of poses in all sessions.
    pub fn poses(&self) -> usize {
        self.joint.len()
    }

    /// The sessions one after another as one trajectory, on the fleet clock (each session
    /// starts [`FLEET_CLOCK_GAP_S`] after the previous one ends), each with its own time cells.
    pub fn joint(&self) -> &Trajectory {
        &self.joint
    }

    /// Fleet clock − session clock, per session.
    pub fn clock_offsets(&self) -> &[f64] {
        &self.clock_offsets
    }

    /// The (session, pose) of a fleet index.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] beyond the last pose.
    pub fn locate(&self, index: usize) -> Result<(usize, usize)> {
        if index >= self.poses() {
            return Err(Error::IndexOutOfRange { index, len: self.poses() });
        }
        let a = self.starts.partition_point(|&s| s <= index) - 1;
        Ok((a, index - self.starts[a]))
    }

    /// The session holding a fleet index (which must exist).
    fn session_of(&self, index: usize) -> usize {
        self.starts.partition_point(|&s| s <= index) - 1
    }

    /// The fleet index of pose `pose` of session `a`.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a session or pose that does not exist.
    pub fn index(&self, a: usize, pose: usize) -> Result<usize> {
        let len = self.sessions.len();
        let traj = self.sessions.get(a).ok_or(Error::IndexOutOfRange { index: a, len })?;
        if pose >= traj.len() {
            return Err(Error::IndexOutOfRange { index: pose, len: traj.len() });
        }
        Ok(self.starts[a] + pose)
    }
}

/// How a fleet's scan prunes the far field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Pruning {
    /// [`KdTree`](Self::KdTree) where it applies (a metric that is the Euclidean distance of
    /// 1 to 3 coordinates, and more than one session), else [`Hierarchy`](Self::Hierarchy).
    #[default]
    Auto,
    /// The time-ordered ball hierarchy of one trajectory, with sessions split at its top:
    /// every metric.
    Hierarchy,
    /// A KD-tree (kiddo) over the centres of chunk balls: Euclidean positions of 1 to 3
    /// coordinates only.
    KdTree,
}

impl Pruning {
    /// The accepted names.
    pub const NAMES: &'static str = "auto, hierarchy, kd-tree";

    /// The name, as parsed.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Hierarchy => "hierarchy",
            Self::KdTree => "kd-tree",
        }
    }
}

impl std::str::FromStr for Pruning {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        match name {
            "auto" => Ok(Self::Auto),
            "hierarchy" => Ok(Self::Hierarchy),
            "kd-tree" => Ok(Self::KdTree),
            _ => Err(Error::UnknownName { kind: "pruning", name: name.to_owned(), expected: Self::NAMES }),
        }
    }
}

/// Options of [`find_fleet_loops`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FleetOptions {
    /// The revisit separation within a session (pairs of different sessions are always kept).
    pub separation: Separation,
    /// The far-field pruning.
    pub pruning: Pruning,
    /// The largest radius of a chunk ball in the KD-tree, in the metric's unit; `None`: γ.
    pub chunk_radius: Option<f64>,
}

impl Default for FleetOptions {
    /// No separation, [`Pruning::Auto`], chunks of radius γ.
    fn default() -> Self {
        Self { separation: Separation::NONE, pruning: Pruning::Auto, chunk_radius: None }
    }
}

/// A loop component of a fleet: within one session, or where two sessions overlap.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct FleetComponent {
    /// Index in [`FleetLoops::components`] (and in the joint [`Loops::components`]).
    pub id: usize,
    /// Its block (a, b), a ≤ b: rows (t) in session a, columns (t′) in session b.
    pub sessions: [usize; 2],
    /// Contains diagonal cells (a = b only); see [`LoopComponent::trivial`].
    pub trivial: bool,
    /// Area in the block, s² (the sessions' own time cells); a trivial component whole.
    pub area_s2: f64,
    /// Number of lattice cells.
    pub pair_count: u64,
    /// Number of holes.
    pub holes: u64,
    /// First and last pose of session a (rows), and of session b (columns): `[[i0, i1], [j0, j1]]`.
    pub poses: [[usize; 2]; 2],
    /// The closest pair: pose of session a, pose of session b.
    pub closest_pair: [usize; 2],
    /// δ at the closest pair.
    pub closest_distance: f64,
}

/// What two sessions share (or one session alone, a = b): one entry of the sparse overlap
/// matrix.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionPair {
    /// The sessions, a ≤ b.
    pub sessions: [usize; 2],
    /// Number of loop components in the block.
    pub components: usize,
    /// Number of lattice cells in the block (for a = b, the whole square: both halves, the
    /// diagonal once).
    pub pair_count: u64,
    /// Loop area α of the block, s² (for a = b, the whole square).
    pub area_s2: f64,
    /// Loop density ρ = α / (T_a T_b), T the sessions' spans: the share of the block's
    /// rectangle that lies within γ.
    pub density: f64,
}

/// Checks a fleet's tables read back from a saved result that holds no loops (a cluster's
/// merged tiles): for `sessions` sessions, components numbered in order in blocks (a, b),
/// a ≤ b < `sessions`, with finite areas and closest distances of at least 0 and a time extent
/// `[[t_min, t_max], [t′_min, t′_max]]` each (seconds, finite, ordered); session pairs within
/// the sessions, with finite measures of at least 0.
///
/// # Errors
/// [`Error::InvalidState`] naming the first entry that does not fit (`what`: `"fleet tables"`).
pub fn check_fleet_tables(
    sessions: usize,
    components: &[FleetComponent],
    times_s: &[[[f64; 2]; 2]],
    pairs: &[SessionPair],
) -> Result<()> {
    let invalid = |reason: String| Error::InvalidState { what: "fleet tables", reason };
    let fits = |[a, b]: [usize; 2]| a <= b && b < sessions;
    let measure = |value: f64| value.is_finite() && value >= 0.0;
    if times_s.len() != components.len() {
        return Err(invalid(format!("{} components but {} time extents", components.len(), times_s.len())));
    }
    for (k, (c, times)) in components.iter().zip(times_s).enumerate() {
        let ordered = times.iter().all(|[lo, hi]| lo.is_finite() && hi.is_finite() && lo <= hi);
        if c.id != k || !fits(c.sessions) || !measure(c.area_s2) || !measure(c.closest_distance) || !ordered {
            return Err(invalid(format!(
                "component {k} has id {}, sessions {:?} of {sessions}, area {} s^2, closest distance {} and \
                 times {times:?} s",
                c.id, c.sessions, c.area_s2, c.closest_distance
            )));
        }
    }
    if let Some((k, p)) =
        pairs.iter().enumerate().find(|(_, p)| !(fits(p.sessions) && measure(p.area_s2) && measure(p.density)))
    {
        return Err(invalid(format!(
            "session pair {k} has sessions {:?} of {sessions}, area {} s^2 and density {}",
            p.sessions, p.area_s2, p.density
        )));
    }
    Ok(())
}

/// S_γ over a fleet, its loop components per block, and the measures per session pair.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetLoops {
    loops: Loops,
    starts: Vec<usize>,
    spans_s: Vec<f64>,
    blocks: Vec<[usize; 2]>,
    pruning: Pruning,
}

/// Loop components of every block of a fleet (see the module docs), exactly, with the same
/// engine as [`find_loops`](crate::find_loops): time and memory follow the runs of S_γ over the
/// fleet, and session pairs that never come within γ cost nothing beyond the pruning.
///
/// # Errors
/// [`Error::InvalidGamma`]; [`Error::InvalidSeparation`]; the metric's errors on any session;
/// [`Error::NotApplicable`] for [`Pruning::KdTree`] with a metric it does not serve.
pub fn find_fleet_loops<M: Metric + ?Sized>(
    fleet: &Fleet,
    metric: &M,
    gamma: f64,
    options: &FleetOptions,
) -> Result<FleetLoops> {
    check_gamma(gamma)?;
    options.separation.check()?;
    let joint = fleet.joint();
    joint.check_metric(metric)?;
    let separation = options.separation;
    // Each session's first separated columns, from its own path length and clock, so that an
    // intra-session block is exactly that session's own result.
    let mut first_columns = try_with_capacity(joint.len(), "the first columns of the rows")?;
    for (a, traj) in fleet.sessions.iter().enumerate() {
        let start = fleet.starts[a] as u32;
        if separation.is_none() {
            first_columns.extend((0..traj.len() as u32).map(|i| start + i));
        } else {
            let local = separation.first_columns(&try_path_length(traj, metric)?, traj.timestamps_s())?;
            first_columns.extend(local.into_iter().map(|j| start + j));
        }
    }
    let usable = metric.is_coordinate_euclidean() && (1..=3).contains(&joint.dim());
    let pruning = match options.pruning {
        Pruning::Auto if usable && fleet.len() > 1 => Pruning::KdTree,
        Pruning::Auto => Pruning::Hierarchy,
        Pruning::KdTree if !usable => {
            return Err(Error::NotApplicable {
                option: "kd-tree pruning",
                to: format!("the {} metric on {} coordinates", metric.name(), joint.dim()),
                reason: "it serves the Euclidean distance of 1 to 3 coordinates; use the hierarchy",
            });
        }
        other => other,
    };
    let (arc, balls) = rayon::join(
        || ArcLength::new(joint, metric, false),
        || BallTree::with_sessions(joint, metric, LEAF_SIZE, &fleet.starts),
    );
    let (arc, balls) = (arc?, balls?);
    let index = match pruning {
        Pruning::KdTree => {
            let radius = options.chunk_radius.filter(|r| *r > 0.0 && r.is_finite()).unwrap_or(gamma);
            ChunkIndex::new(joint, &balls, &fleet.starts, radius)
        }
        _ => None,
    };
    let pruner = match &index {
        Some(index) => Pruner::Chunks(&balls, index),
        None => Pruner::Hierarchy(&balls),
    };
    let set =
        SublevelSet::scan(joint, metric, gamma, separation, &arc, pruner, &first_columns, &fleet.starts, joint.len())?;
    drop(index);
    let loops = Loops::try_from_set(joint, metric, set)?;
    let blocks =
        loops.components().iter().map(|c| [fleet.session_of(c.i_range[0]), fleet.session_of(c.j_range[0])]).collect();
    let spans_s = fleet.sessions.iter().map(Trajectory::span_s).collect();
    Ok(FleetLoops { loops, starts: fleet.starts.clone(), spans_s, blocks, pruning })
}

impl MetricSpec {
    /// [`find_fleet_loops`] under this metric.
    ///
    /// # Errors
    /// As [`find_fleet_loops`].
    pub fn find_fleet_loops(&self, fleet: &Fleet, gamma: f64, options: &FleetOptions) -> Result<FleetLoops> {
        with_metric!(self, m => find_fleet_loops(fleet, m, gamma, options))
    }

    /// [`sample_fleet`] under this metric.
    ///
    /// # Errors
    /// As [`sample_fleet`].
    pub fn sample_fleet(
        &self,
        fleet: &Fleet,
        loops: &FleetLoops,
        sampler: &Sampler,
        between_only: bool,
    ) -> Result<Samples> {
        with_metric!(self, m => sample_fleet(fleet, m, loops, sampler, between_only))
    }
}

impl FleetLoops {
    /// The result over the joint trajectory ([`Fleet::joint`]): fleet indices, fleet clock.
    pub fn loops(&self) -> &Loops {
        &self.loops
    }

    /// The pruning the scan used ([`Pruning::Auto`] resolved).
    pub fn pruning(&self) -> Pruning {
        self.pruning
    }

    /// Number of sessions.
    pub fn sessions(&self) -> usize {
        self.starts.len()
    }

    /// The block (a, b) of each component, in component order.
    pub fn component_sessions(&self) -> &[[usize; 2]] {
        &self.blocks
    }

    /// Every component, with its sessions and poses.
    pub fn components(&self) -> Vec<FleetComponent> {
        self.loops.components().iter().zip(&self.blocks).map(|(c, &sessions)| self.localize(c, sessions)).collect()
    }

    fn localize(&self, c: &LoopComponent, sessions: [usize; 2]) -> FleetComponent {
        localize(c, sessions, &self.starts)
    }

    /// The sparse overlap matrix: every session pair (a, b), a ≤ b, with at least one loop
    /// component, in order of (a, b). α(b, a) = α(a, b).
    pub fn session_pairs(&self) -> Vec<SessionPair> {
        session_pairs_of(self.loops.components().iter().zip(self.blocks.iter().copied()), &self.spans_s)
    }

    /// Loop duration τ per fleet index, split: `own`, within the pose's session (that session's
    /// own τ), and `other`, with the poses of every other session. Seconds; `own + other` is τ
    /// over the whole fleet.
    pub fn loop_duration(&self) -> (Vec<f64>, Vec<f64>) {
        let (own, other): (Vec<usize>, Vec<usize>) =
            (0..self.blocks.len()).partition(|&c| self.blocks[c][0] == self.blocks[c][1]);
        let tau = |ids: &[usize]| {
            self.loops
                .loop_duration(Selection::Components(ids), Side::Both, Scale::Seconds)
                .expect("component ids of this result")
        };
        (tau(&own), tau(&other))
    }

    /// The component ids between two different sessions.
    pub fn between_sessions(&self) -> Vec<usize> {
        (0..self.blocks.len()).filter(|&c| self.blocks[c][0] != self.blocks[c][1]).collect()
    }

    /// The fleet result of `loops`, found over `fleet`'s joint trajectory by
    /// [`find_fleet_loops`] with `pruning` (as [`FleetLoops::pruning`] gives it): what a
    /// [`FleetLoops`] saved as its [`Loops`] (with the `serde` feature) and its fleet reads back
    /// as. O(poses + runs).
    ///
    /// # Errors
    /// [`Error::InvalidState`] when they do not fit together: loops of another trajectory
    /// (pose count or times), a component or a run that spans two sessions, a component's
    /// closest pair outside its block, or [`Pruning::Auto`] (never the pruning of a scan).
    ///
    /// # Examples
    /// ```
    /// use loops_core::fleet::{Fleet, FleetLoops, FleetOptions, find_fleet_loops};
    /// use loops_core::{Euclidean, Trajectory};
    /// let out = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])?;
    /// let back = Trajectory::from_points(vec![100.0, 101.0], &[[10.0, 0.5], [0.0, 0.5]])?;
    /// let fleet = Fleet::new(vec![("monday".into(), out), ("tuesday".into(), back)])?;
    /// let found = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default())?;
    /// let again = FleetLoops::from_loops(&fleet, found.loops().clone(), found.pruning())?;
    /// assert_eq!(again, found);
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn from_loops(fleet: &Fleet, loops: Loops, pruning: Pruning) -> Result<Self> {
        let invalid = |reason: String| Error::InvalidState { what: "FleetLoops", reason };
        if pruning == Pruning::Auto {
            return Err(invalid("its pruning is auto, which no scan leaves unresolved".to_owned()));
        }
        loops.check_trajectory(fleet.joint()).map_err(|e| invalid(e.to_string()))?;
        let session = |index: usize| fleet.session_of(index);
        let mut blocks = Vec::with_capacity(loops.components().len());
        for c in loops.components() {
            let [a, b] = [session(c.i_range[0]), session(c.j_range[0])];
            let fits = a <= b
                && session(c.i_range[1]) == a
                && session(c.j_range[1]) == b
                && session(c.closest_pair[0]) == a
                && session(c.closest_pair[1]) == b;
            if !fits {
                return Err(invalid(format!(
                    "component {} (rows {:?}, columns {:?}, closest pair {:?}) does not lie in one block of sessions",
                    c.id, c.i_range, c.j_range, c.closest_pair
                )));
            }
            blocks.push([a, b]);
        }
        if let Some(run) = loops.runs().find(|r| session(r.start) != session(r.end)) {
            return Err(invalid(format!(
                "the run of row {} from column {} to {} spans two sessions",
                run.row, run.start, run.end
            )));
        }
        let spans_s = fleet.sessions.iter().map(Trajectory::span_s).collect();
        Ok(Self { loops, starts: fleet.starts.clone(), spans_s, blocks, pruning })
    }
}

/// A component of the joint result in its sessions' poses; `starts`: the sessions' first fleet
/// indices.
pub(crate) fn localize(c: &LoopComponent, [a, b]: [usize; 2], starts: &[usize]) -> FleetComponent {
    let (sa, sb) = (starts[a], starts[b]);
    FleetComponent {
        id: c.id,
        sessions: [a, b],
        trivial: c.trivial,
        area_s2: c.area_s2,
        pair_count: c.pair_count,
        holes: c.holes,
        poses: [[c.i_range[0] - sa, c.i_range[1] - sa], [c.j_range[0] - sb, c.j_range[1] - sb]],
        closest_pair: [c.closest_pair[0] - sa, c.closest_pair[1] - sb],
        closest_distance: c.closest_distance,
    }
}

/// The sparse overlap matrix of components with their blocks (in id order), the sessions'
/// spans giving ρ: one entry per block with a component, in order of (a, b).
pub(crate) fn session_pairs_of<'a>(
    components: impl Iterator<Item = (&'a LoopComponent, [usize; 2])>,
    spans_s: &[f64],
) -> Vec<SessionPair> {
    let mut pairs: std::collections::BTreeMap<[usize; 2], SessionPair> = std::collections::BTreeMap::new();
    for (c, sessions) in components {
        let entry = pairs.entry(sessions).or_insert(SessionPair {
            sessions,
            components: 0,
            pair_count: 0,
            area_s2: 0.0,
            density: 0.0,
        });
        // Within a session, a non-trivial component is one half of its mirror pair.
        let mirrored = if sessions[0] == sessions[1] && !c.trivial { 2 } else { 1 };
        entry.components += 1;
        entry.pair_count = entry.pair_count.saturating_add(c.pair_count.saturating_mul(mirrored));
        entry.area_s2 += mirrored as f64 * c.area_s2;
    }
    pairs
        .into_values()
        .map(|mut p| {
            p.density = p.area_s2 / (spans_s[p.sessions[0]] * spans_s[p.sessions[1]]);
            p
        })
        .collect()
}

/// A sampled pair of a fleet: which sessions, which poses, when on each session's clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FleetSample {
    /// The sessions of the earlier and the later pose (by fleet index), a ≤ b.
    pub sessions: [usize; 2],
    /// The poses, in their sessions.
    pub poses: [usize; 2],
    /// Their times, seconds, each on its session's clock.
    pub times_s: [f64; 2],
    /// The component.
    pub component: Option<usize>,
    /// δ between the two poses.
    pub distance: Option<f64>,
}

impl Fleet {
    /// The samples of [`sample_fleet`] with sessions, poses and session clocks.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for samples of another fleet.
    pub fn localize(&self, samples: &Samples) -> Result<Vec<FleetSample>> {
        samples
            .rows()
            .iter()
            .filter_map(|s| s.pair.map(|pair| (s, pair)))
            .map(|(s, [i, j])| {
                let ((a, pi), (b, pj)) = (self.locate(i)?, self.locate(j)?);
                // The session's own timestamp, not the fleet clock's minus the offset (which
                // rounds).
                let time = |session: usize, pose: usize| self.sessions[session].timestamps_s()[pose];
                Ok(FleetSample {
                    sessions: [a, b],
                    poses: [pi, pj],
                    times_s: [time(a, pi), time(b, pj)],
                    component: s.component,
                    distance: s.distance,
                })
            })
            .collect()
    }
}

/// One budget over all components of all blocks of a fleet (σ_1, σ_ρ, the dispersed σ_ρ, σ_α),
/// or a baseline rule run over the joint trajectory; with `between_only`, over the components
/// between different sessions only (map merging). P1–P3 hold across the fleet as they hold
/// for one trajectory. Sample pairs are fleet indices on the fleet clock; see
/// [`Fleet::localize`].
///
/// # Errors
/// As [`sample_loops`](crate::sample_loops); [`Error::NotApplicable`] for `between_only` with
/// a baseline.
pub fn sample_fleet<M: Metric + ?Sized>(
    fleet: &Fleet,
    metric: &M,
    loops: &FleetLoops,
    sampler: &Sampler,
    between_only: bool,
) -> Result<Samples> {
    if between_only && sampler.kind.is_baseline() {
        return Err(Error::NotApplicable {
            option: "sampling between sessions only",
            to: format!("the {} baseline", sampler.kind.name()),
            reason: "a baseline's rule knows no components; use nearest-then-uniform (the default), one, rho, \
                     rho-dispersed, alpha, closest-first or closest-then-spread",
        });
    }
    let blocks = &loops.blocks;
    let keep = move |c: usize| !between_only || blocks[c][0] != blocks[c][1];
    let keys = KeyLayout::sessions(fleet.starts(), fleet.names());
    sample_loops_where(fleet.joint(), metric, &loops.loops, sampler, &keep, keys)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;

    fn line(t0: f64, xs: &[f64], y: f64) -> Trajectory {
        let points: Vec<[f64; 2]> = xs.iter().map(|&x| [x, y]).collect();
        Trajectory::from_points((0..xs.len()).map(|i| t0 + i as f64).collect(), &points).unwrap()
    }

    #[test]
    fn a_fleet_checks_its_sessions() {
        assert!(matches!(Fleet::new(vec![]), Err(Error::EmptyFleet)));
        let a = line(0.0, &[0.0, 1.0], 0.0);
        let twice = Fleet::new(vec![("a".into(), a.clone()), ("a".into(), a.clone())]);
        assert!(matches!(twice, Err(Error::DuplicateSession { .. })));
        let flat = Trajectory::new(vec![0.0, 1.0], vec![0.0, 1.0], 1).unwrap();
        let err = Fleet::new(vec![("a".into(), a), ("b".into(), flat)]).unwrap_err();
        assert!(err.to_string().contains("session \"b\" has 1 coordinates, the first has 2"), "{err}");
    }

    #[test]
    fn locate_and_index_are_inverse() {
        let fleet =
            Fleet::new(vec![("a".into(), line(5.0, &[0.0, 1.0, 2.0], 0.0)), ("b".into(), line(0.0, &[0.0, 1.0], 0.0))])
                .unwrap();
        for k in 0..fleet.poses() {
            let (a, pose) = fleet.locate(k).unwrap();
            assert_eq!(fleet.index(a, pose).unwrap(), k);
        }
        assert!(fleet.locate(5).is_err() && fleet.index(1, 2).is_err());
        // Each session keeps its own clock behind the fleet clock.
        let t = fleet.joint().timestamps_s();
        assert_eq!(t[3] - fleet.clock_offsets()[1], 0.0);
        assert_eq!(t[3] - t[2], FLEET_CLOCK_GAP_S);
    }

    #[test]
    fn samples_have_their_poses_own_times() {
        // The second session's clock (from 1000 s) lies higher on the fleet clock (from 3620 s),
        // where an f64 keeps fewer bits: there t + offset − offset is not always t again.
        let times = |start: f64| (0..200).map(|k| start + 0.1 * f64::from(k)).collect::<Vec<_>>();
        let points: Vec<[f64; 1]> = (0..200).map(|k| [f64::from(k % 10)]).collect();
        let sessions = [0.0, 1_000.123_456_789]
            .iter()
            .enumerate()
            .map(|(k, &t0)| (format!("s{k}"), Trajectory::from_points(times(t0), &points).unwrap()))
            .collect();
        let fleet = Fleet::new(sessions).unwrap();
        let loops = find_fleet_loops(&fleet, &Euclidean, 0.5, &FleetOptions::default()).unwrap();
        let all = Sampler::new(crate::SamplerKind::Alpha, crate::SampleSize::Rate(1.0), 0);
        let samples = fleet.localize(&sample_fleet(&fleet, &Euclidean, &loops, &all, false).unwrap()).unwrap();
        assert!(samples.len() > 100);
        for s in &samples {
            for k in 0..2 {
                assert_eq!(s.times_s[k], fleet.session(s.sessions[k]).timestamps_s()[s.poses[k]], "{s:?}");
            }
        }
    }

    #[test]
    fn a_session_is_measured_in_a_fleet_as_alone_bit_for_bit() {
        // Sessions of 1,300 and 1,700 poses: the second one's rows start at a joint row that is
        // not a multiple of the tally's stretches, and its components span several of them.
        let drive = |seed, duration_s| {
            crate::UrbanDrive { duration_s, city_size_m: 300.0, seed, ..crate::UrbanDrive::default() }
                .generate()
                .unwrap()
                .trajectory
        };
        let (a, b) = (drive(3, 130.0), drive(4, 170.0));
        let fleet = Fleet::new(vec![("a".into(), a.clone()), ("b".into(), b.clone())]).unwrap();
        let loops = find_fleet_loops(&fleet, &Euclidean, 25.0, &FleetOptions::default()).unwrap();
        let components = loops.components();
        for (s, session) in [a, b].iter().enumerate() {
            let alone = crate::find_loops(session, &Euclidean, 25.0).unwrap();
            let own: Vec<_> = components.iter().filter(|c| c.sessions == [s, s]).collect();
            assert_eq!(own.len(), alone.components().len(), "session {s}");
            assert!(alone.components().iter().any(|c| c.i_range[1] - c.i_range[0] > 600), "session {s}");
            for (c, single) in own.iter().zip(alone.components()) {
                assert_eq!(c.area_s2.to_bits(), single.area_s2.to_bits(), "session {s}: {c:?}");
                assert_eq!((c.pair_count, c.poses), (single.pair_count, [single.i_range, single.j_range]));
            }
        }
    }

    #[test]
    fn runs_are_cut_and_rows_not_joined_across_sessions() {
        // Two identical sessions: the intra blocks are each session's own, and the inter block
        // is the full square of one session against itself, without a diagonal.
        let a = line(0.0, &[0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 0.0], 0.0);
        let fleet = Fleet::new(vec![("a".into(), a.clone()), ("b".into(), a.clone())]).unwrap();
        let alone = crate::find_loops(&a, &Euclidean, 1.0).unwrap();
        for pruning in [Pruning::Hierarchy, Pruning::KdTree] {
            let options = FleetOptions { pruning, ..FleetOptions::default() };
            let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &options).unwrap();
            assert_eq!(loops.pruning(), pruning);
            let comps = loops.components();
            for s in 0..2 {
                let own: Vec<_> = comps.iter().filter(|c| c.sessions == [s, s]).collect();
                assert_eq!(own.len(), alone.components().len());
                for (c, single) in own.iter().zip(alone.components()) {
                    assert_eq!(
                        (c.pair_count, c.area_s2, c.trivial),
                        (single.pair_count, single.area_s2, single.trivial)
                    );
                    assert_eq!(c.poses, [single.i_range, single.j_range]);
                }
            }
            let between: Vec<_> = comps.iter().filter(|c| c.sessions == [0, 1]).collect();
            // The square's cells within γ: the mirror of the trivial component, whole, is one
            // component; the two return legs' components and their mirrors are others.
            let cells: u64 = between.iter().map(|c| c.pair_count).sum();
            assert_eq!(cells, alone.pair_count());
            assert!(loops.loops().warnings().is_empty(), "{:?}", loops.loops().warnings());
        }
    }
}

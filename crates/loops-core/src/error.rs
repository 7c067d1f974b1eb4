//! The one error type of the core.

/// `Result` with the core's [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the core: all of it is bad input, named with the index and
/// value that make it bad. Invariant violations are bugs and use `debug_assert!` instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Tile summaries or partial merges that do not fit together (a tile merged twice, a
    /// label without a component, counts a cut cannot explain).
    #[error("tile summaries do not fit together: {problem}")]
    InconsistentTiles {
        /// What does not fit, naming the tile or label.
        problem: String,
    },
    /// A fleet without sessions.
    #[error("a fleet needs at least one session")]
    EmptyFleet,
    /// Two sessions of a fleet with the same name.
    #[error("two sessions are named {name:?}: session names must be unique")]
    DuplicateSession {
        /// The name.
        name: String,
    },
    /// A session a fleet store's update names that it cannot take: one not in the store
    /// (removing it), or one both given and removed.
    #[error("session {name:?} {problem}")]
    StoreSession {
        /// The session's name.
        name: String,
        /// What is wrong, in words.
        problem: &'static str,
    },
    /// A session that does not fit the fleet's first session.
    #[error("session {session:?} {problem}: every session of a fleet must have the first session's {what}")]
    SessionMismatch {
        /// The session's name.
        session: String,
        /// What differs, with both values (e.g. "has 3 coordinates, the first has 2").
        problem: String,
        /// The property ("dimension", "manifold").
        what: &'static str,
    },
    /// A trajectory with fewer than two poses: time cells (and so durations and areas) need two.
    #[error("a trajectory needs at least 2 poses, got {count}")]
    TooFewPoses {
        /// How many poses were given.
        count: usize,
    },
    /// The number of timestamps differs from the number of poses.
    #[error("{timestamps} timestamps but {poses} poses")]
    LengthMismatch {
        /// Number of timestamps.
        timestamps: usize,
        /// Number of poses.
        poses: usize,
    },
    /// Two inputs that must have one row per pose have different numbers of rows.
    #[error("{first_rows} {first} but {second_rows} {second}: one of each per pose")]
    RowCountMismatch {
        /// The first input.
        first: &'static str,
        /// Its rows.
        first_rows: usize,
        /// The second input.
        second: &'static str,
        /// Its rows.
        second_rows: usize,
    },
    /// Points of dimension zero.
    #[error("points must have at least one coordinate, got dimension 0")]
    ZeroDimension,
    /// A flat coordinate buffer whose length is not a multiple of the dimension.
    #[error("{len} coordinates do not split into points of dimension {dim}")]
    RaggedCoordinates {
        /// Length of the buffer.
        len: usize,
        /// Dimension of one point.
        dim: usize,
    },
    /// A timestamp that is NaN or infinite.
    #[error("timestamp at index {index} is not finite ({value})")]
    NonFiniteTimestamp {
        /// Pose index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A timestamp beyond [`MAX_MAGNITUDE`](crate::MAX_MAGNITUDE) seconds.
    #[error("timestamp at index {index} is {value:e} s, beyond ±{max:e}: spans and areas would overflow")]
    TimestampTooLarge {
        /// Pose index.
        index: usize,
        /// The offending value, seconds.
        value: f64,
        /// The largest magnitude accepted.
        max: f64,
    },
    /// A coordinate beyond [`MAX_MAGNITUDE`](crate::MAX_MAGNITUDE).
    #[error("coordinate {axis} of pose {index} is {value:e}, beyond ±{max:e}: distances would overflow")]
    CoordinateTooLarge {
        /// Pose index.
        index: usize,
        /// Coordinate (column) index within the pose.
        axis: usize,
        /// The offending value.
        value: f64,
        /// The largest magnitude accepted.
        max: f64,
    },
    /// A coordinate that is NaN or infinite.
    #[error("coordinate {axis} of pose {index} is not finite ({value})")]
    NonFiniteCoordinate {
        /// Pose index.
        index: usize,
        /// Coordinate (column) index within the pose.
        axis: usize,
        /// The offending value.
        value: f64,
    },
    /// Timestamps that do not strictly increase (unsorted or duplicate).
    #[error(
        "timestamps must strictly increase: index {index} has {value_s} s, not after {previous_s} s at index {}",
        index - 1
    )]
    TimestampsNotIncreasing {
        /// Index of the first timestamp that is not after its predecessor.
        index: usize,
        /// The predecessor's value, seconds.
        previous_s: f64,
        /// The offending value, seconds.
        value_s: f64,
    },
    /// More poses than the engine indexes (2³² − 1).
    #[error("{count} poses is more than the {max} the engine indexes")]
    TooManyPoses {
        /// How many poses were given.
        count: usize,
        /// The largest supported count.
        max: usize,
    },
    /// Points of more coordinates than an online engine takes
    /// ([`OnlineLoops::MAX_DIM`](crate::online::OnlineLoops::MAX_DIM)).
    #[error("dim = {dim} is invalid: an online engine takes points of at most {max} coordinates")]
    DimensionTooLarge {
        /// The dimension given.
        dim: usize,
        /// The largest accepted.
        max: usize,
    },
    /// An update offered to a sampler that is not its engine's last push: an older one, another
    /// engine's, one from before a rebuild or clear, or one that names no engine.
    #[error(
        "the update of poses {first_pose}..={pose} is not the last push of this engine: offer each push's \
         update once, in order, with the engine that made it"
    )]
    UpdateNotLatest {
        /// Its first pose.
        first_pose: usize,
        /// Its last pose.
        pose: usize,
    },
    /// An update offered to a sampler twice.
    #[error("the update of poses {first_pose}..={pose} was already offered to this sampler")]
    UpdateAlreadyOffered {
        /// Its first pose.
        first_pose: usize,
        /// Its last pose.
        pose: usize,
    },
    /// γ must be a positive, finite distance.
    #[error("gamma must be a positive finite distance, got {0}")]
    InvalidGamma(f64),
    /// A separation bound (path length or time) must be finite and not negative.
    #[error("the {what} separation must be a finite distance of at least 0, got {value}")]
    InvalidSeparation {
        /// `path` or `time`.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A metric that cannot measure points of this dimension.
    #[error("metric {metric} needs points of dimension {expected}, got dimension {found}")]
    DimensionMismatch {
        /// The metric's name.
        metric: String,
        /// What the metric needs.
        expected: String,
        /// What the trajectory has.
        found: usize,
    },
    /// A time interval [a, b] with a ≥ b or a non-finite end.
    #[error("time interval [{a}, {b}] is empty or not finite: need finite a < b")]
    InvalidInterval {
        /// Start of the interval.
        a: f64,
        /// End of the interval.
        b: f64,
    },
    /// A pose index past the end of the trajectory.
    #[error("pose index {index} is out of range: the trajectory has {len} poses")]
    IndexOutOfRange {
        /// The index given.
        index: usize,
        /// The number of poses.
        len: usize,
    },
    /// A component id that does not exist.
    #[error("no loop component with id {id}: there are {count}")]
    UnknownComponent {
        /// The id asked for.
        id: usize,
        /// The number of components.
        count: usize,
    },
    /// A named numeric parameter out of its allowed range.
    #[error("{name} = {value} is invalid: {expected}")]
    InvalidParameter {
        /// Parameter name, with its unit.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// A quaternion whose norm is not 1 (within 1e-6 for constructors, 1e-9 for metrics). The
    /// message names the option that accepts quaternions printed with few decimals.
    #[error(
        "quaternion of pose {index} has norm {norm}, not 1: zero, or farther from unit length than \
         quaternion_tolerance (quaternions within it are normalised; 1e-3 accepts files that print \
         4 decimals, as TUM ground truth does)"
    )]
    NonUnitQuaternion {
        /// Pose index.
        index: usize,
        /// Its norm.
        norm: f64,
    },
    /// A vector that should be of unit length (sphere points, normalised descriptors), or a zero
    /// vector that cannot be normalised.
    #[error("vector of pose {index} has norm {norm}, not 1 (zero or not normalised)")]
    NonUnitVector {
        /// Pose index.
        index: usize,
        /// Its norm.
        norm: f64,
    },
    /// A latitude outside [−90°, 90°].
    #[error("latitude of pose {index} is {value_deg}°, outside [-90°, 90°]")]
    LatitudeOutOfRange {
        /// Pose index.
        index: usize,
        /// The latitude, degrees.
        value_deg: f64,
    },
    /// A metric given as text that does not parse.
    #[error("invalid metric {spec:?}: {reason}")]
    InvalidMetricSpec {
        /// The text given.
        spec: String,
        /// What is wrong.
        reason: String,
    },
    /// A sample size given as both a rate and a budget, or as neither.
    #[error("{}", match (rate, budget) {
        (Some(rate), Some(budget)) => format!("give rate or budget, not both (got rate={rate}, budget={budget})"),
        _ => "give rate or budget: how many to draw".to_owned(),
    })]
    SampleSizeChoice {
        /// The rate given, if any.
        rate: Option<f64>,
        /// The budget given, if any.
        budget: Option<usize>,
    },
    /// A metric that cannot be used the way it was asked for, e.g. on the points of a pose
    /// file (a torus or sphere metric) or with position axes (anything but Euclidean).
    #[error("metric {metric:?} does not fit here: {expected}")]
    MetricMismatch {
        /// The metric, as its text spec.
        metric: String,
        /// What would fit.
        expected: &'static str,
    },
    /// A metric that does not measure the points of the trajectory's manifold, e.g. the
    /// Euclidean metric on SE(3) poses (it would take a quaternion's components for
    /// coordinates). See [`Metric::fits`](crate::Metric::fits). Boxed, so that errors stay small.
    #[error("{0}")]
    MetricDoesNotFit(Box<MetricMisfit>),
    /// A name (of a side, a metric, ...) that is not one of the known ones.
    #[error("unknown {kind} {name:?}: expected one of {expected}")]
    UnknownName {
        /// What kind of name.
        kind: &'static str,
        /// The name given.
        name: String,
        /// The names allowed, comma separated.
        expected: &'static str,
    },
    /// An option that does not apply where it was given, e.g. skipping the trivial components
    /// when sampling detection clusters, which do not know them.
    #[error("{option} does not apply to {to}: {reason}")]
    NotApplicable {
        /// The option.
        option: &'static str,
        /// What it was given to.
        to: String,
        /// Why not, and what would do.
        reason: &'static str,
    },
    /// An empty set of detections: clustering and sampling need at least one pair.
    #[error("no detections: at least one pair (t, t') is needed")]
    NoDetections,
    /// Two columns of one table (t and t′, indices i and j, scores) of different lengths.
    #[error("{column} has {len} values, but {expected} are needed (one per detection)")]
    ColumnLengthMismatch {
        /// The column that is off.
        column: &'static str,
        /// Its length.
        len: usize,
        /// The number of detections.
        expected: usize,
    },
    /// A detection time or score that is NaN or infinite.
    #[error("{column} of detection {index} is not finite ({value})")]
    NonFiniteDetection {
        /// The column (`t_s`, `t_prime_s`, `score`).
        column: &'static str,
        /// Detection index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A detection time outside the time span of the trajectory it is placed on.
    #[error("detection {index} at {time_s} s lies outside the trajectory's time span [{start_s}, {end_s}] s")]
    DetectionOutsideSpan {
        /// Detection index.
        index: usize,
        /// The offending time, seconds.
        time_s: f64,
        /// First timestamp of the trajectory, seconds.
        start_s: f64,
        /// Last timestamp of the trajectory, seconds.
        end_s: f64,
    },
    /// A time to place on a trajectory that lies outside its time span.
    #[error("time {index} ({time_s} s) lies outside the trajectory's time span [{start_s}, {end_s}] s")]
    TimeOutsideSpan {
        /// Index of the time in its list.
        index: usize,
        /// The offending time, seconds.
        time_s: f64,
        /// First timestamp of the trajectory, seconds.
        start_s: f64,
        /// Last timestamp of the trajectory, seconds.
        end_s: f64,
    },
    /// A time window of the (t, t′) plane with no pose in it.
    #[error("no pose with {axis} in [{start_s}, {end_s}] s (from the first pose)")]
    EmptyWindow {
        /// The axis: `t` or `t′`.
        axis: &'static str,
        /// Start of the window, seconds from the first pose.
        start_s: f64,
        /// End of the window, seconds from the first pose.
        end_s: f64,
    },
    /// A [`PlaneGrid`](crate::plane::PlaneGrid) used with a trajectory (or loops) other than its own.
    #[error("the plane grid was made for {grid_poses} poses, not {poses}")]
    PlaneGridMismatch {
        /// Poses of the trajectory the grid was made for.
        grid_poses: usize,
        /// Poses of the trajectory given.
        poses: usize,
    },
    /// An image whose number of values is not its width times its height.
    #[error("{len} values do not make an image of {width} × {height} pixels")]
    ImageSizeMismatch {
        /// The number of values given.
        len: usize,
        /// Width, pixels.
        width: usize,
        /// Height, pixels.
        height: usize,
    },
    /// A pose index past the end of the trajectory.
    #[error("detection {index} refers to pose {pose}, but the trajectory has {poses} poses")]
    PoseIndexOutOfRange {
        /// Detection index.
        index: usize,
        /// The offending pose index.
        pose: usize,
        /// Number of poses.
        poses: usize,
    },
    /// Memory for a result could not be had: the allocator refused a buffer of `bytes` bytes
    /// for `what` (the answer is too big for this machine, or for a limit such as `ulimit -v`).
    /// Nothing is left half-built; the inputs are untouched.
    #[error(
        "out of memory: {} ({bytes} bytes) for {what} could not be allocated; a smaller answer (a \
         smaller gamma, a separation, fewer poses, a smaller budget or image) needs less",
        size_text(*bytes)
    )]
    OutOfMemory {
        /// What the memory was for (`the runs of S_gamma`, `the samples`, ...).
        what: &'static str,
        /// The size of the buffer that could not be allocated, bytes.
        bytes: u64,
    },
    /// A sample (or a draw of detections) larger than one call returns
    /// ([`MAX_SAMPLES`](crate::MAX_SAMPLES)), refused before anything is drawn. Boxed, so that
    /// errors stay small.
    #[error("{0}")]
    TooManySamples(Box<TooManySamples>),
    /// The computation was stopped by an [`Interrupt`](crate::Interrupt) (Ctrl-C in Python)
    /// before it finished; nothing was returned.
    #[error("interrupted")]
    Interrupted,
    /// A saved (deserialised) result whose parts do not fit together: corrupt, or made by hand.
    #[error("invalid saved {what}: {reason}")]
    InvalidState {
        /// The type (`Loops`, `Samples`, ...).
        what: &'static str,
        /// What does not fit, naming the index.
        reason: String,
    },
    /// A place on the map (a point or a polygon of a store's query) that is not one.
    #[error("invalid place: {problem}")]
    InvalidPlace {
        /// What is wrong, naming the vertex and the value.
        problem: String,
    },
    /// Inputs that must come from one trajectory come from two (pose counts or timestamps differ).
    #[error(
        "the {what} and the loops come from different trajectories ({poses} and {loops_poses} poses; first difference at pose {index})"
    )]
    TrajectoryMismatch {
        /// What does not match the loops (`trajectory`, `samples`, ...).
        what: &'static str,
        /// First pose index at which they differ.
        index: usize,
        /// Poses of that input's trajectory.
        poses: usize,
        /// Poses of the loops' trajectory.
        loops_poses: usize,
    },
}

/// The kind of an [`Error`], as the adapters report it: Python raises one exception class per
/// kind, the C API returns one status per kind. Decided here, once, so that the two cannot drift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorClass {
    /// A trajectory (or pose) the core refuses: too few poses, lengths that differ, a
    /// coordinate or time that is not finite or too large, times not increasing, a quaternion
    /// or vector that is not unit, a latitude out of range.
    InvalidTrajectory,
    /// A pose index past the last pose.
    IndexOutOfRange,
    /// Memory could not be had.
    OutOfMemory,
    /// The computation was interrupted.
    Interrupted,
    /// Any other bad input: a parameter out of range or unknown, inputs that do not fit together.
    InvalidParameter,
}

impl Error {
    /// The kind of this error.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Error, ErrorClass};
    /// assert_eq!(Error::ZeroDimension.class(), ErrorClass::InvalidTrajectory);
    /// assert_eq!(Error::InvalidGamma(-1.0).class(), ErrorClass::InvalidParameter);
    /// ```
    pub fn class(&self) -> ErrorClass {
        use Error as E;
        match self {
            E::TooFewPoses { .. }
            | E::LengthMismatch { .. }
            | E::RowCountMismatch { .. }
            | E::ZeroDimension
            | E::RaggedCoordinates { .. }
            | E::NonFiniteTimestamp { .. }
            | E::NonFiniteCoordinate { .. }
            | E::TimestampTooLarge { .. }
            | E::CoordinateTooLarge { .. }
            | E::TimestampsNotIncreasing { .. }
            | E::TooManyPoses { .. }
            | E::NonUnitQuaternion { .. }
            | E::NonUnitVector { .. }
            | E::LatitudeOutOfRange { .. } => ErrorClass::InvalidTrajectory,
            E::IndexOutOfRange { .. } | E::PoseIndexOutOfRange { .. } => ErrorClass::IndexOutOfRange,
            E::OutOfMemory { .. } => ErrorClass::OutOfMemory,
            E::Interrupted => ErrorClass::Interrupted,
            _ => ErrorClass::InvalidParameter,
        }
    }
}

/// A size in bytes for a message: `812 bytes`, `3.1 MiB`, `7.4 GiB`.
pub(crate) fn size_text(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", UNITS[unit])
}

/// What [`Error::TooManySamples`] says: what was asked for, how many that makes, what it would
/// cost.
#[derive(Debug, Clone, PartialEq)]
pub struct TooManySamples {
    /// `samples` or `detections`.
    pub what: &'static str,
    /// The budget asked for, if a budget was.
    pub budget: Option<usize>,
    /// The rate asked for, if a rate was.
    pub rate: Option<f64>,
    /// How many that makes (the expected count for a rate).
    pub count: u64,
    /// The memory they would take, bytes (an estimate).
    pub bytes: u64,
    /// The most one call returns ([`MAX_SAMPLES`](crate::MAX_SAMPLES)).
    pub max: usize,
}

impl std::fmt::Display for TooManySamples {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Self { what, budget, rate, count, bytes, max } = self;
        match (budget, rate) {
            (Some(budget), _) => write!(f, "budget {budget}")?,
            (None, Some(rate)) => write!(f, "rate {rate}")?,
            (None, None) => write!(f, "the sample")?,
        }
        write!(
            f,
            " asks for {count} {what} (about {} of memory); one call returns at most {max} \
             (loops_core::MAX_SAMPLES): give a budget of at most {max}, or a smaller rate",
            size_text(*bytes)
        )
    }
}

/// What [`Error::MetricDoesNotFit`] says: a metric, and the trajectory it does not fit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MetricMisfit {
    /// The metric, by name.
    pub metric: String,
    /// The trajectory, by its manifold (`an se3 trajectory`).
    pub trajectory: &'static str,
    /// Coordinates per point.
    pub dim: usize,
    /// What the columns hold.
    pub columns: String,
    /// The metrics that fit.
    pub fitting: &'static str,
    /// The trajectory's default metric, by name.
    pub default: String,
}

impl std::fmt::Display for MetricMisfit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Self { metric, trajectory, dim, columns, fitting, default } = self;
        write!(
            f,
            "metric {metric} does not fit {trajectory} ({dim} columns: {columns}): measure it with {fitting}, \
             or give no metric for its default, {default}"
        )
    }
}

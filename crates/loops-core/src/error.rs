//! The one error type of the core.

/// `Result` with the core's [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the core: all of it is bad input, named with the index and
/// value that make it bad. Invariant violations are bugs and use `debug_assert!` instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
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
    /// γ must be a positive, finite distance.
    #[error("gamma must be a positive finite distance, got {0}")]
    InvalidGamma(f64),
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
}

//! Trajectories: strictly increasing timestamps and one point per timestamp.

use crate::error::{Error, Result};
use crate::memory::{try_collect, try_copy, try_with_capacity};

/// A sampled trajectory ξ: timestamps in seconds, strictly increasing, and one point of a fixed
/// dimension per timestamp, stored row-major in one flat buffer.
///
/// The points are coordinates on the trajectory's [`Manifold`]: Rⁿ positions for
/// [`Trajectory::new`], the layout of a manifold's metric for its constructors
/// ([`Trajectory::se3`] and friends), which record the manifold so that the engine measures the
/// points with a metric that fits them ([`Trajectory::default_metric`] when none is chosen).
/// Sample `i` stands for its *time cell*
/// `[m_{i-1}, m_i]` with `m_i = (t_i + t_{i+1}) / 2` (clipped to `[t_0, t_{n-1}]` at the ends),
/// of width `w_i = (t_{i+1} − t_{i−1}) / 2` (half cells at the ends). The cells tile the time
/// span exactly, so durations and areas computed from them are in seconds and s², and stay right
/// when sampling is uneven.
///
/// # Examples
/// ```
/// use loops_core::Trajectory;
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 3.0], &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])?;
/// assert_eq!(traj.len(), 3);
/// assert_eq!(traj.cell_widths_s(), &[0.5, 1.5, 1.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "TrajectoryState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    timestamps_s: Vec<f64>,
    coords: Vec<f64>,
    dim: usize,
    cell_widths_s: Vec<f64>,
    manifold: Manifold,
}

/// What a trajectory's points are: the manifold its constructor built them on, and so which
/// metrics can measure them and which one does when none is chosen
/// ([`Manifold::default_metric`]).
///
/// | manifold | constructor | columns | default metric |
/// |---|---|---|---|
/// | `Euclidean` | [`Trajectory::new`], [`gnss_ecef`](Trajectory::gnss_ecef), [`descriptors`](Trajectory::descriptors) unnormalised | Rⁿ, as given | `euclidean` |
/// | `Se3` | [`se3`](Trajectory::se3) | `x y z qx qy qz qw` | `se3(rotation_weight_m_per_rad=0)`: the translation, metres |
/// | `So3` | [`so3`](Trajectory::so3), [`so3_from_rotation_vectors`](Trajectory::so3_from_rotation_vectors) | `qx qy qz qw` | `so3` (geodesic angle) |
/// | `Se2` | [`se2`](Trajectory::se2) | `x y theta` | `se2(rotation_weight_m_per_rad=0)`: the translation, metres |
/// | `Torus` | [`torus`](Trajectory::torus) | k angles | `torus` |
/// | `Sphere` | [`sphere`](Trajectory::sphere), [`sphere_from_lat_lon`](Trajectory::sphere_from_lat_lon) | unit `x y z` | `sphere(radius=1)` |
/// | `Gnss` | [`gnss`](Trajectory::gnss) | `ux uy uz height_m` | `haversine` (metres) |
/// | `Descriptors` | [`descriptors`](Trajectory::descriptors) normalised | unit vectors | `angular` |
///
/// SE(3) and SE(2) count no rotation by default: the weight of a radian in metres has no
/// universal value (it is the user's choice, as in `se3(rotation_weight_m_per_rad=10)`), and
/// loop-closure candidates of deployed SLAM systems are chosen by position. A Euclidean
/// trajectory's coordinates may also be measured by any metric whose layout they have (checked
/// as that metric requires); a manifold's points only by the metrics of that manifold
/// ([`Metric::fits`](crate::Metric::fits)), so no quaternion is ever measured as a vector.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Manifold {
    /// Rⁿ: coordinates as given (positions, raw descriptors, ECEF).
    #[default]
    Euclidean,
    /// SE(3) poses `[x, y, z, qx, qy, qz, qw]`, unit quaternions.
    Se3,
    /// SO(3) rotations `[qx, qy, qz, qw]`, unit quaternions.
    So3,
    /// SE(2) poses `[x, y, θ]`, θ in radians wrapped to (−π, π].
    Se2,
    /// The torus (S¹)ᵏ: k angles, radians, wrapped to (−π, π].
    Torus,
    /// The sphere S²: unit vectors `[x, y, z]`.
    Sphere,
    /// GNSS fixes `[ux, uy, uz, height_m]`: the fix's direction from the Earth's centre and its
    /// height, metres.
    Gnss,
    /// Descriptors normalised to unit length (place recognition).
    Descriptors,
}

impl Manifold {
    /// Every manifold, in the order of the table above.
    pub const ALL: [Self; 8] =
        [Self::Euclidean, Self::Se3, Self::So3, Self::Se2, Self::Torus, Self::Sphere, Self::Gnss, Self::Descriptors];

    /// Its name, lower case: `euclidean`, `se3`, `so3`, `se2`, `torus`, `sphere`, `gnss`,
    /// `descriptors`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Euclidean => "euclidean",
            Self::Se3 => "se3",
            Self::So3 => "so3",
            Self::Se2 => "se2",
            Self::Torus => "torus",
            Self::Sphere => "sphere",
            Self::Gnss => "gnss",
            Self::Descriptors => "descriptors",
        }
    }

    /// What the columns of its points of dimension `dim` hold, e.g. `"x y z qx qy qz qw"`.
    pub fn columns(self, dim: usize) -> String {
        match self {
            Self::Euclidean => format!("{dim} coordinate{}", if dim == 1 { "" } else { "s" }),
            Self::Se3 => "x y z qx qy qz qw".to_owned(),
            Self::So3 => "qx qy qz qw".to_owned(),
            Self::Se2 => "x y theta".to_owned(),
            Self::Torus => format!("{dim} angle{}", if dim == 1 { "" } else { "s" }),
            Self::Sphere => "unit vector x y z".to_owned(),
            Self::Gnss => "ux uy uz height_m".to_owned(),
            Self::Descriptors => format!("unit vector of {dim}"),
        }
    }

    /// "a(n) … trajectory", for messages.
    pub(crate) fn a_trajectory(self) -> &'static str {
        match self {
            Self::Euclidean => "a euclidean trajectory",
            Self::Se3 => "an se3 trajectory",
            Self::So3 => "an so3 trajectory",
            Self::Se2 => "an se2 trajectory",
            Self::Torus => "a torus trajectory",
            Self::Sphere => "a sphere trajectory",
            Self::Gnss => "a gnss trajectory",
            Self::Descriptors => "a descriptors trajectory",
        }
    }

    /// The metrics that measure its points, as text (for messages).
    pub fn metrics(self) -> &'static str {
        match self {
            Self::Euclidean => "euclidean, or any metric whose layout the coordinates have",
            Self::Se3 => "se3(rotation_weight_m_per_rad=W) or se3_rotation",
            Self::So3 => "so3",
            Self::Se2 => "se2(rotation_weight_m_per_rad=W)",
            Self::Torus => "torus",
            Self::Sphere => "sphere(radius=R) or angular",
            Self::Gnss => "haversine(radius_m=R)",
            Self::Descriptors => "angular or euclidean",
        }
    }
}

impl std::fmt::Display for Manifold {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

pub(crate) mod sealed {
    /// Implemented by the types whose timestamps are known to be valid.
    pub trait Sealed {}
}

/// Something that carries the timestamps of a trajectory's poses: a [`Trajectory`], or the
/// [`Loops`](crate::Loops) found on one. Detections given by times are placed on its poses,
/// detections given by pose indices take their times from it, and a
/// [`PlaneGrid`](crate::plane::PlaneGrid) picks its poses.
///
/// Sealed: the timestamps are known to be finite, strictly increasing and at least two.
pub trait Timeline: sealed::Sealed {
    /// Timestamps of the poses, seconds, strictly increasing.
    fn pose_times_s(&self) -> &[f64];
}

impl sealed::Sealed for Trajectory {}

impl Timeline for Trajectory {
    fn pose_times_s(&self) -> &[f64] {
        self.timestamps_s()
    }
}

/// The largest number of poses the engine indexes (it stores columns as `u32`).
pub const MAX_POSES: usize = u32::MAX as usize - 1;

/// The largest magnitude of a timestamp (seconds) or a coordinate that a trajectory accepts:
/// 1e150. Beyond it the engine's arithmetic cannot hold the answer — squared distances
/// overflow to infinity near 1e154, and spans, time cells and areas (s²) of timestamps near
/// f64's limit become infinite or NaN — so such values are refused, naming pose and value,
/// instead of giving a wrong answer.
pub const MAX_MAGNITUDE: f64 = 1e150;

impl Trajectory {
    /// A trajectory from timestamps (seconds) and a flat row-major buffer of `dim` coordinates
    /// per pose.
    ///
    /// # Errors
    /// [`Error::ZeroDimension`], [`Error::RaggedCoordinates`], [`Error::LengthMismatch`],
    /// [`Error::TooFewPoses`] (fewer than 2), [`Error::TooManyPoses`],
    /// [`Error::NonFiniteTimestamp`], [`Error::TimestampsNotIncreasing`] (unsorted or
    /// duplicate) and [`Error::NonFiniteCoordinate`], each naming the first offending index;
    /// [`Error::OutOfMemory`] when the time cells do not fit in memory.
    pub fn new(timestamps_s: Vec<f64>, coords: Vec<f64>, dim: usize) -> Result<Self> {
        Self::check_poses(&timestamps_s, &coords, dim)?;
        let cell_widths_s = cell_widths(&timestamps_s)?;
        Ok(Self { timestamps_s, coords, dim, cell_widths_s, manifold: Manifold::Euclidean })
    }

    /// The checks of [`new`](Self::new) on timestamps and coordinates, before its time cells.
    fn check_poses(timestamps_s: &[f64], coords: &[f64], dim: usize) -> Result<()> {
        if dim == 0 {
            return Err(Error::ZeroDimension);
        }
        if !coords.len().is_multiple_of(dim) {
            return Err(Error::RaggedCoordinates { len: coords.len(), dim });
        }
        let poses = coords.len() / dim;
        if timestamps_s.len() != poses {
            return Err(Error::LengthMismatch { timestamps: timestamps_s.len(), poses });
        }
        if poses < 2 {
            return Err(Error::TooFewPoses { count: poses });
        }
        if poses > MAX_POSES {
            return Err(Error::TooManyPoses { count: poses, max: MAX_POSES });
        }
        validate_timestamps(timestamps_s)?;
        validate_coordinates(coords, dim, 0)
    }

    /// Checked trajectories one after another, on one clock (each shifted to start `gap_s`
    /// after the previous one ends), each keeping its own time cells (half cells at its ends):
    /// a fleet's sessions as one trajectory. Returns it with each part's clock offset (time on
    /// the joint clock − time on the part's clock). The parts share a dimension and manifold.
    ///
    /// # Errors
    /// [`Error::TooManyPoses`]; [`Error::OutOfMemory`].
    pub(crate) fn concatenate(parts: &[&Trajectory], gap_s: f64) -> Result<(Self, Vec<f64>)> {
        let whole: Vec<(&Trajectory, std::ops::Range<usize>)> = parts.iter().map(|&p| (p, 0..p.len())).collect();
        Self::concatenate_pieces(&whole, gap_s)
    }

    /// [`concatenate`](Self::concatenate) of the pieces `range` of each trajectory
    /// ([`piece`](Self::piece)s, each with its own time cells), copied once: a tile's stretches.
    ///
    /// # Errors
    /// [`Error::TooManyPoses`]; [`Error::OutOfMemory`].
    pub(crate) fn concatenate_pieces(
        parts: &[(&Trajectory, std::ops::Range<usize>)],
        gap_s: f64,
    ) -> Result<(Self, Vec<f64>)> {
        let poses: usize = parts.iter().map(|(_, r)| r.len()).sum();
        if poses > MAX_POSES {
            return Err(Error::TooManyPoses { count: poses, max: MAX_POSES });
        }
        let first = parts[0].0;
        let what = "the joint trajectory of a fleet";
        let mut joint = Self {
            timestamps_s: try_with_capacity(poses, what)?,
            coords: try_with_capacity(poses * first.dim, what)?,
            dim: first.dim,
            cell_widths_s: try_with_capacity(poses, what)?,
            manifold: first.manifold,
        };
        let mut offsets = try_with_capacity(parts.len(), what)?;
        let mut next_start = 0.0;
        for (part, range) in parts {
            let offset = next_start - part.timestamps_s[range.start];
            offsets.push(offset);
            joint.timestamps_s.extend(part.timestamps_s[range.clone()].iter().map(|t| t + offset));
            joint.coords.extend_from_slice(&part.coords[range.start * part.dim..range.end * part.dim]);
            joint.cell_widths_s.extend_from_slice(&part.cell_widths_s[range.clone()]);
            next_start = joint.timestamps_s[joint.timestamps_s.len() - 1] + gap_s;
        }
        Ok((joint, offsets))
    }

    /// The poses `range` with their own time cells (not half cells at the cut): a piece of a
    /// session for a tile. May hold a single pose.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`].
    pub(crate) fn piece(&self, range: std::ops::Range<usize>) -> Result<Self> {
        let what = "a piece of a session";
        Ok(Self {
            timestamps_s: try_copy(&self.timestamps_s[range.clone()], what)?,
            coords: try_copy(&self.coords[range.start * self.dim..range.end * self.dim], what)?,
            dim: self.dim,
            cell_widths_s: try_copy(&self.cell_widths_s[range], what)?,
            manifold: self.manifold,
        })
    }

    /// The timestamps and the coordinates, moved out.
    pub(crate) fn into_parts(self) -> (Vec<f64>, Vec<f64>) {
        (self.timestamps_s, self.coords)
    }

    /// No pose yet, `dim` coordinates a point on `manifold`: the online engine's trajectory,
    /// grown by [`push_pose`](Self::push_pose). Not a valid public trajectory before its second
    /// pose.
    pub(crate) fn growing(dim: usize, manifold: Manifold) -> Self {
        Self { timestamps_s: Vec::new(), coords: Vec::new(), dim, cell_widths_s: Vec::new(), manifold }
    }

    /// Appends a pose already checked (time after the last, `dim` finite coordinates): the last
    /// cell becomes whole and the new one is a half cell, as [`new`](Self::new) makes them.
    pub(crate) fn push_pose(&mut self, t_s: f64, point: &[f64]) {
        debug_assert_eq!(point.len(), self.dim);
        self.timestamps_s.push(t_s);
        self.coords.extend_from_slice(point);
        let n = self.timestamps_s.len();
        if n >= 2 {
            self.cell_widths_s[n - 2] = cell_width(&self.timestamps_s, n - 2);
        }
        self.cell_widths_s.push(cell_width(&self.timestamps_s, n - 1));
    }

    /// The same points, declared to lie on `manifold`: for the constructors of
    /// [`pose`](crate::Trajectory::se3), which lay the points out as the manifold's metrics expect.
    pub(crate) fn on(mut self, manifold: Manifold) -> Self {
        self.manifold = manifold;
        self
    }

    /// A trajectory from timestamps and fixed-size points (`[x, y]`, `[x, y, z]`, ...).
    ///
    /// # Errors
    /// As [`Trajectory::new`].
    pub fn from_points<const D: usize>(timestamps_s: Vec<f64>, points: &[[f64; D]]) -> Result<Self> {
        Self::new(timestamps_s, points.iter().flatten().copied().collect(), D)
    }

    /// Number of poses `n` (at least 2).
    #[allow(clippy::len_without_is_empty)] // a trajectory is never empty
    pub fn len(&self) -> usize {
        self.timestamps_s.len()
    }

    /// Coordinates per point.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The manifold of the points: [`Manifold::Euclidean`] for [`Trajectory::new`], the
    /// constructor's for [`Trajectory::se3`] and friends.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Manifold, Trajectory};
    /// let poses = Trajectory::se3(vec![0.0, 1.0], &[[0.0; 3]; 2], &[[0.0, 0.0, 0.0, 1.0]; 2])?;
    /// assert_eq!(poses.manifold(), Manifold::Se3);
    /// assert_eq!(poses.default_metric().to_string(), "se3(rotation_weight_m_per_rad=0, rotation=geodesic)");
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn manifold(&self) -> Manifold {
        self.manifold
    }

    /// Timestamps, seconds, strictly increasing.
    pub fn timestamps_s(&self) -> &[f64] {
        &self.timestamps_s
    }

    /// All coordinates, row-major, `len() * dim()` values.
    pub fn coords(&self) -> &[f64] {
        &self.coords
    }

    /// The coordinates of point `i`.
    ///
    /// # Panics
    /// If `i >= len()`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.coords[i * self.dim..(i + 1) * self.dim]
    }

    /// Whether poses `i` and `j` have the same coordinates bit for bit, so that every metric
    /// measures the same distance from anything to either (`-0.0` and `0.0` differ: an angle's
    /// sign may matter).
    pub(crate) fn same_point(&self, i: usize, j: usize) -> bool {
        self.point(i).iter().zip(self.point(j)).all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// Time-cell widths `w_i`, seconds; they sum to [`span_s`](Self::span_s).
    pub fn cell_widths_s(&self) -> &[f64] {
        &self.cell_widths_s
    }

    /// The time cell `[start, end]` of sample `i`, seconds.
    ///
    /// # Panics
    /// If `i >= len()`.
    pub fn cell_s(&self, i: usize) -> (f64, f64) {
        cell_of(&self.timestamps_s, i)
    }

    /// `t_{n−1} − t_0`, seconds (positive).
    pub fn span_s(&self) -> f64 {
        self.timestamps_s[self.len() - 1] - self.timestamps_s[0]
    }

    /// The pose nearest each time (seconds, on the clock of the timestamps): the pose whose
    /// time cell holds it, ties to the earlier pose. O(times · log n).
    ///
    /// # Errors
    /// [`Error::TimeOutsideSpan`] for a time before the first or after the last timestamp (or
    /// NaN), naming its index in `times_s`.
    ///
    /// # Examples
    /// ```
    /// use loops_core::Trajectory;
    /// let traj = Trajectory::from_points(vec![0.0, 1.0, 3.0], &[[0.0], [1.0], [2.0]])?;
    /// assert_eq!(traj.nearest_poses(&[0.4, 0.5, 2.1, 3.0])?, [0, 0, 2, 2]);
    /// assert!(traj.nearest_poses(&[3.5]).is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn nearest_poses(&self, times_s: &[f64]) -> Result<Vec<usize>> {
        let times = &self.timestamps_s;
        times_s
            .iter()
            .enumerate()
            .map(|(index, &t)| {
                nearest_pose(times, t).ok_or(Error::TimeOutsideSpan {
                    index,
                    time_s: t,
                    start_s: times[0],
                    end_s: times[times.len() - 1],
                })
            })
            .collect()
    }

    /// A copy whose points are `f(point)`: same timestamps, new dimension, Euclidean.
    ///
    /// # Errors
    /// As [`Trajectory::new`], for the new points (e.g. a NaN produced by `f`).
    pub fn map_points(&self, dim: usize, mut f: impl FnMut(&[f64], &mut Vec<f64>)) -> Result<Self> {
        let mut coords = Vec::with_capacity(self.len() * dim);
        for i in 0..self.len() {
            f(self.point(i), &mut coords);
        }
        Self::new(self.timestamps_s.clone(), coords, dim)
    }
}

/// Checks points of `dim` coordinates, the first being pose `first`: finite, within
/// [`MAX_MAGNITUDE`].
pub(crate) fn validate_coordinates(coords: &[f64], dim: usize, first: usize) -> Result<()> {
    if all_within_magnitude(coords) {
        return Ok(());
    }
    if let Some(k) = coords.iter().position(|c| !c.is_finite()) {
        return Err(Error::NonFiniteCoordinate { index: first + k / dim, axis: k % dim, value: coords[k] });
    }
    if let Some(k) = coords.iter().position(|c| c.abs() > MAX_MAGNITUDE) {
        let (index, axis, value) = (first + k / dim, k % dim, coords[k]);
        return Err(Error::CoordinateTooLarge { index, axis, value, max: MAX_MAGNITUDE });
    }
    Ok(())
}

/// Whether every value is finite and at most [`MAX_MAGNITUDE`] in size: the checks' common
/// case, in one pass the compiler vectorises (a NaN fails the comparison too); the checks find
/// the first value at fault only when this says there is one.
fn all_within_magnitude(values: &[f64]) -> bool {
    values.chunks(64).all(|chunk| chunk.iter().fold(true, |ok, v| ok & (v.abs() <= MAX_MAGNITUDE)))
}

pub(crate) fn validate_timestamps(timestamps_s: &[f64]) -> Result<()> {
    if all_within_magnitude(timestamps_s) && timestamps_s.windows(2).all(|w| w[1] > w[0]) {
        return Ok(());
    }
    if let Some(index) = timestamps_s.iter().position(|t| !t.is_finite()) {
        return Err(Error::NonFiniteTimestamp { index, value: timestamps_s[index] });
    }
    if let Some(index) = timestamps_s.iter().position(|t| t.abs() > MAX_MAGNITUDE) {
        return Err(Error::TimestampTooLarge { index, value: timestamps_s[index], max: MAX_MAGNITUDE });
    }
    if let Some(k) = timestamps_s.windows(2).position(|w| w[1] <= w[0]) {
        return Err(Error::TimestampsNotIncreasing {
            index: k + 1,
            previous_s: timestamps_s[k],
            value_s: timestamps_s[k + 1],
        });
    }
    Ok(())
}

/// The pose whose time cell holds `t` (the nearest timestamp, ties to the earlier one), `None`
/// outside `[times[0], times[n − 1]]` or for NaN. O(log n).
pub(crate) fn nearest_pose(times: &[f64], t: f64) -> Option<usize> {
    if !(t >= times[0] && t <= times[times.len() - 1]) {
        return None;
    }
    let k = times.partition_point(|&x| x < t);
    Some(if k == 0 || t - times[k - 1] > times[k] - t { k } else { k - 1 })
}

/// The one time-weight rule: cell `i` is `[m_{i−1}, m_i]`, midpoints between samples, clipped to
/// the span at the ends.
pub(crate) fn cell_of(timestamps_s: &[f64], i: usize) -> (f64, f64) {
    let n = timestamps_s.len();
    let start = if i == 0 { timestamps_s[0] } else { 0.5 * (timestamps_s[i - 1] + timestamps_s[i]) };
    let end = if i + 1 == n { timestamps_s[n - 1] } else { 0.5 * (timestamps_s[i] + timestamps_s[i + 1]) };
    (start, end)
}

/// Running sums `P = [0, w_0, w_0 + w_1, …]` of cell widths, restarting at 0 at each session
/// start in `breaks` (sorted; empty for one trajectory): `P[k]` sums the
/// widths from the start of k's session to k − 1. The width of cells `a..=b` of one session is
/// `(P[b] + w_b) − P[a]`, bit for bit what the session alone would give (and, without breaks,
/// `P[b + 1] − P[a]`).
///
/// # Errors
/// [`Error::OutOfMemory`].
pub(crate) fn prefix_sums_by_session(cell_widths_s: &[f64], breaks: &[u32]) -> Result<Vec<f64>> {
    let mut prefix = try_with_capacity(cell_widths_s.len() + 1, "the running sums of the time cells")?;
    prefix.push(0.0);
    let mut acc = 0.0;
    let mut next_break = breaks.iter().peekable();
    for (k, w) in cell_widths_s.iter().enumerate() {
        if next_break.peek().is_some_and(|&&b| b as usize == k) {
            next_break.next();
            acc = 0.0;
            *prefix.last_mut().expect("pushed") = 0.0;
        }
        acc += w;
        prefix.push(acc);
    }
    Ok(prefix)
}

/// Widths `(t_{i+1} − t_{i−1}) / 2` (half cells at the ends), from differences of neighbouring
/// timestamps, which are exact even on an epoch clock (differences of midpoints are not).
fn cell_widths(timestamps_s: &[f64]) -> Result<Vec<f64>> {
    try_collect((0..timestamps_s.len()).map(|i| cell_width(timestamps_s, i)), "the time cells of a trajectory")
}

/// The width of cell `i` of [`cell_widths`] (a half cell when `i` is the last).
pub(crate) fn cell_width(timestamps_s: &[f64], i: usize) -> f64 {
    let n = timestamps_s.len();
    let before = if i == 0 { 0.0 } else { timestamps_s[i] - timestamps_s[i - 1] };
    let after = if i + 1 == n { 0.0 } else { timestamps_s[i + 1] - timestamps_s[i] };
    0.5 * (before + after)
}

/// What a serialised [`Trajectory`] holds. The time cells are kept, not derived again: a
/// fleet's joint trajectory has half cells at every session's ends.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct TrajectoryState {
    timestamps_s: Vec<f64>,
    coords: Vec<f64>,
    dim: usize,
    cell_widths_s: Vec<f64>,
    manifold: Manifold,
}

#[cfg(feature = "serde")]
impl TryFrom<TrajectoryState> for Trajectory {
    type Error = Error;

    /// Validated as [`Trajectory::new`] and, for a manifold, as its default metric validates
    /// its points (unit quaternions, latitudes, ...); time cells as [`checked_cell_widths`].
    fn try_from(state: TrajectoryState) -> Result<Self> {
        Self::from_saved(state.timestamps_s, state.coords, state.dim, state.cell_widths_s, state.manifold)
    }
}

#[cfg(feature = "serde")]
impl Trajectory {
    /// A trajectory as saved with its time cells ([`cell_widths_s`](Self::cell_widths_s): a
    /// fleet's joint trajectory has half cells at every session's ends) and manifold: what a
    /// serialised trajectory and a store's pose file hold.
    ///
    /// # Errors
    /// As [`Trajectory::new`]; the manifold's default metric's errors on its points (unit
    /// quaternions, latitudes, ...); [`Error::InvalidState`] for time cells that are not one
    /// a pose, each from 0 s to its timestamps' cell.
    pub fn from_saved(
        timestamps_s: Vec<f64>,
        coords: Vec<f64>,
        dim: usize,
        cell_widths_s: Vec<f64>,
        manifold: Manifold,
    ) -> Result<Self> {
        // Checked as `new` checks, with the saved time cells rather than ones derived again
        // (the manifold's checks, of the points alone, before theirs).
        Self::check_poses(&timestamps_s, &coords, dim)?;
        let mut traj = Self { timestamps_s, coords, dim, cell_widths_s, manifold };
        traj.default_metric().validate(&traj)?;
        traj.cell_widths_s =
            checked_cell_widths("Trajectory", std::mem::take(&mut traj.cell_widths_s), &traj.timestamps_s)?;
        Ok(traj)
    }
}

/// Time cells read from a saved `what` with these (checked) timestamps: one a pose, each at
/// least 0 s and at most the pose's whole cell, `(t_{i+1} − t_{i−1}) / 2` (a session's end in a
/// fleet keeps a half cell), with a few roundings of the timestamps to spare (a fleet's are
/// shifted onto one clock). So no area or duration summed from them can overflow.
#[cfg(feature = "serde")]
pub(crate) fn checked_cell_widths(what: &'static str, widths: Vec<f64>, timestamps_s: &[f64]) -> Result<Vec<f64>> {
    let poses = timestamps_s.len();
    if widths.len() != poses {
        let reason = format!("{} time cells for {poses} poses", widths.len());
        return Err(Error::InvalidState { what, reason });
    }
    // A cell fits within its timestamps' cell, with an allowance of a few roundings of the
    // timestamps around it (`near`: the sum of their magnitudes).
    let within = |w: f64, cell: f64, near: f64| w >= 0.0 && w <= cell + 4.0 * f64::EPSILON * near;
    let fits = |i: usize| {
        let near = timestamps_s[i.saturating_sub(1)..(i + 2).min(poses)].iter().map(|t| t.abs()).sum::<f64>();
        within(widths[i], cell_width(timestamps_s, i), near)
    };
    // The interior poses in one pass without bounds checks (the same sums in the same order as
    // `fits`: each decided alike), the ends and any pose at fault by `fits`.
    let interior_fits = widths
        .get(1..poses.saturating_sub(1))
        .unwrap_or_default()
        .iter()
        .zip(timestamps_s.windows(3))
        .all(|(&w, t)| within(w, 0.5 * ((t[1] - t[0]) + (t[2] - t[1])), t[0].abs() + t[1].abs() + t[2].abs()));
    if interior_fits && (poses == 0 || (fits(0) && fits(poses - 1))) {
        return Ok(widths);
    }
    if let Some(i) = (0..poses).find(|&i| !fits(i)) {
        let reason = format!(
            "the time cell of pose {i} is {:?} s, outside 0 to {:?} s (its timestamps' cell)",
            widths[i],
            cell_width(timestamps_s, i)
        );
        return Err(Error::InvalidState { what, reason });
    }
    Ok(widths)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each saved time cell at its bound is taken and one step above it refused, naming its
    /// pose, for the ends and the interior alike (the one-pass check decides as the pose by
    /// pose one), on timestamps far from 0 where the rounding allowance matters.
    #[cfg(feature = "serde")]
    #[test]
    fn saved_cells_are_checked_at_their_bounds() {
        let times: Vec<f64> = (0..40).map(|i| 1.7e9 + 0.1 * i as f64 + 0.013 * ((i * 7) % 5) as f64).collect();
        let poses = times.len();
        let most = |i: usize| {
            let near = times[i.saturating_sub(1)..(i + 2).min(poses)].iter().map(|t| t.abs()).sum::<f64>();
            cell_width(&times, i) + 4.0 * f64::EPSILON * near
        };
        let bounds: Vec<f64> = (0..poses).map(most).collect();
        assert!(checked_cell_widths("t", bounds.clone(), &times).is_ok());
        for i in 0..poses {
            let mut widths = bounds.clone();
            widths[i] = f64::from_bits(widths[i].to_bits() + 1);
            let error = checked_cell_widths("t", widths.clone(), &times).unwrap_err().to_string();
            assert!(error.contains(&format!("the time cell of pose {i} is")), "{i}: {error}");
            widths[i] = -1e-300;
            assert!(checked_cell_widths("t", widths, &times).is_err(), "{i}");
        }
    }

    #[test]
    fn values_at_fault_are_found_past_the_fast_check() {
        for at in [0, 63, 64, 130] {
            for bad in [f64::NAN, f64::INFINITY, -2e150] {
                let mut coords = vec![1.0; 200];
                coords[at] = bad;
                let error = validate_coordinates(&coords, 2, 10).unwrap_err().to_string();
                assert!(error.contains(&format!("of pose {} is", 10 + at / 2)), "{at} {bad}: {error}");
                let mut times: Vec<f64> = (0..200).map(f64::from).collect();
                times[at] = bad;
                assert!(validate_timestamps(&times).is_err(), "{at} {bad}");
            }
        }
        assert!(validate_coordinates(&[1e150, -1e150], 2, 0).is_ok());
    }

    #[test]
    fn cells_tile_the_span() {
        let t = vec![0.0, 0.1, 0.5, 0.6, 2.0];
        let traj = Trajectory::new(t, vec![0.0; 5], 1).unwrap();
        let total: f64 = traj.cell_widths_s().iter().sum();
        assert!((total - traj.span_s()).abs() < 1e-12);
        assert_eq!(traj.cell_s(0), (0.0, 0.05));
        assert_eq!(traj.cell_s(4), (1.3, 2.0));
    }

    #[test]
    fn bad_input_names_the_index() {
        let err = Trajectory::new(vec![0.0, 1.0, 1.0], vec![0.0; 3], 1).unwrap_err();
        assert_eq!(err, Error::TimestampsNotIncreasing { index: 2, previous_s: 1.0, value_s: 1.0 });
        assert!(err.to_string().contains("index 2"), "{err}");
        let err = Trajectory::new(vec![0.0, 1.0], vec![0.0, 0.0, f64::NAN, 1.0], 2).unwrap_err();
        assert_eq!(err.to_string(), "coordinate 0 of pose 1 is not finite (NaN)");
        let err = Trajectory::new(vec![0.0, f64::INFINITY], vec![0.0; 2], 1).unwrap_err();
        assert!(matches!(err, Error::NonFiniteTimestamp { index: 1, .. }));
        assert_eq!(Trajectory::new(vec![], vec![], 3).unwrap_err(), Error::TooFewPoses { count: 0 });
        assert_eq!(Trajectory::new(vec![1.0], vec![0.0; 3], 3).unwrap_err(), Error::TooFewPoses { count: 1 });
        assert_eq!(
            Trajectory::new(vec![0.0, 1.0], vec![0.0; 5], 2).unwrap_err(),
            Error::RaggedCoordinates { len: 5, dim: 2 }
        );
        assert_eq!(
            Trajectory::new(vec![0.0, 1.0], vec![0.0; 6], 2).unwrap_err(),
            Error::LengthMismatch { timestamps: 2, poses: 3 }
        );
        assert_eq!(Trajectory::new(vec![0.0, 1.0], vec![], 0).unwrap_err(), Error::ZeroDimension);
    }
}

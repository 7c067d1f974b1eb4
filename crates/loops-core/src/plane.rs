//! Derived results on the (t, t′) plane, for figures and reports: the pairwise
//! distance π_ξ(t, t′) = δ(ξ(t), ξ(t′)) sampled on a grid of poses, the loop component of every
//! pixel, the outlines ∂Ω of the components, and isocontours of π_ξ.
//!
//! Everything here works on a [`PlaneGrid`]: one pose per image column (time t) and one per
//! image row (time t′). Images are row-major `Vec`s of `width × height` values, row 0 first (the
//! earliest t′: the bottom row of a plot whose t′ axis points up). Geometry (outlines, contours)
//! is in pixel units: column a spans x ∈ [a, a + 1], row b spans y ∈ [b, b + 1], and the pixel's
//! centre (a + ½, b + ½) stands for the pair (`columns[a]`, `rows[b]`).
//!
//! One rule for every surface: a pixel shows the pair of poses its column and row stand for, its
//! distance is that pair's δ and its label that pair's component. So the labels and the image
//! agree exactly (a pixel is labelled if and only if its δ ≤ γ, S_γ being exact), and with a grid
//! of every pose the label image is the lattice of the components itself. When the grid
//! downsamples, a component smaller than a pixel may hold none of the pixels' pairs: it then has
//! no outline, and a figure can mark it at its [`closest_pair`](crate::LoopComponent::closest_pair).

use std::collections::BTreeMap;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::memory::try_filled;
use crate::metric::Metric;
use crate::spec::{MetricSpec, with_metric};
use crate::trajectory::{Timeline, Trajectory};

/// The poses an image of the (t, t′) plane shows: the pose index of each column (time t) and of
/// each row (time t′), both increasing.
///
/// Along each axis: every pose whose time lies in the window when there are at most
/// `max_pixels` of them; otherwise `max_pixels` pixels evenly spaced in time over the window,
/// each showing the pose of the window nearest its centre time (ties to the earlier pose; a pose
/// may show in two neighbouring pixels when poses are sparser than pixels there).
///
/// Each pixel stands for a stretch of time, its *edges* ([`column_edges_s`](Self::column_edges_s),
/// [`row_edges_s`](Self::row_edges_s)): on a downsampled axis the even steps over the window, so
/// pixel units map to seconds affinely; on an axis of every pose the midpoints between the
/// poses' times, half a step beyond the first and the last (the window itself for a single pose).
///
/// # Examples
/// ```
/// use loops_core::plane::PlaneGrid;
/// use loops_core::Trajectory;
/// let traj = Trajectory::from_points((0..10).map(f64::from).collect(), &[[0.0]; 10])?;
/// let all = PlaneGrid::new(&traj, None, 100)?;
/// assert_eq!(all.columns(), &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
/// let coarse = PlaneGrid::new(&traj, None, 3)?; // pixel centres at 1.5, 4.5 and 7.5 s
/// assert_eq!(coarse.columns(), &[1, 4, 7]);
/// let zoom = PlaneGrid::new(&traj, Some(([2.0, 4.0], [6.5, 9.0])), 100)?;
/// assert_eq!((zoom.columns(), zoom.rows()), (&[2, 3, 4][..], &[7, 8, 9][..]));
/// assert_eq!(coarse.column_edges_s(), &[0.0, 3.0, 6.0, 9.0]);
/// assert_eq!(zoom.column_edges_s(), &[1.5, 2.5, 3.5, 4.5]);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(try_from = "PlaneGridState"))]
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneGrid {
    columns: Vec<usize>,
    rows: Vec<usize>,
    column_edges_s: Vec<f64>,
    row_edges_s: Vec<f64>,
    poses: usize,
}

impl PlaneGrid {
    /// The grid of a trajectory (or of the [`Loops`] found on one) over a window
    /// `([t_min, t_max], [t′_min, t′_max])`, seconds from the first pose (`None`: the whole
    /// plane), with at most `max_pixels` pixels a side. O(min(n, max_pixels) · log n).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for `max_pixels` = 0; [`Error::InvalidInterval`] for a window
    /// side that is not finite with min < max; [`Error::EmptyWindow`] when no pose lies in one.
    pub fn new<T: Timeline + ?Sized>(
        timeline: &T,
        window_s: Option<([f64; 2], [f64; 2])>,
        max_pixels: usize,
    ) -> Result<Self> {
        if max_pixels == 0 {
            return Err(Error::InvalidParameter {
                name: "max_pixels",
                value: 0.0,
                expected: "at least 1 pixel a side",
            });
        }
        let times = timeline.pose_times_s();
        let span_s = times[times.len() - 1] - times[0];
        let (t_window, t_prime_window) = window_s.unwrap_or(([0.0, span_s], [0.0, span_s]));
        let (columns, column_edges_s) = axis_poses(times, t_window, max_pixels, "t")?;
        let (rows, row_edges_s) = if t_prime_window == t_window {
            (columns.clone(), column_edges_s.clone())
        } else {
            axis_poses(times, t_prime_window, max_pixels, "t′")?
        };
        Ok(Self { columns, rows, column_edges_s, row_edges_s, poses: times.len() })
    }

    /// The pose index i of each image column (time t), increasing.
    pub fn columns(&self) -> &[usize] {
        &self.columns
    }

    /// The pose index j of each image row (time t′), increasing: row 0 is the earliest t′.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// The time each column stands for: `width + 1` increasing boundaries, seconds from the
    /// first pose (column a spans `[edges[a], edges[a + 1]]`; see [`PlaneGrid`]).
    pub fn column_edges_s(&self) -> &[f64] {
        &self.column_edges_s
    }

    /// The time each row stands for: `height + 1` increasing boundaries, seconds from the first
    /// pose, as [`column_edges_s`](Self::column_edges_s).
    pub fn row_edges_s(&self) -> &[f64] {
        &self.row_edges_s
    }

    /// Number of columns (at least 1).
    pub fn width(&self) -> usize {
        self.columns.len()
    }

    /// Number of rows (at least 1).
    pub fn height(&self) -> usize {
        self.rows.len()
    }

    /// Number of poses of the trajectory the grid was made for.
    pub fn poses(&self) -> usize {
        self.poses
    }

    /// Errors unless the grid was made for a trajectory of `poses` poses.
    fn check_poses(&self, poses: usize) -> Result<()> {
        if self.poses == poses { Ok(()) } else { Err(Error::PlaneGridMismatch { grid_poses: self.poses, poses }) }
    }
}

/// The poses along one axis of the grid and the pixels' edges (see [`PlaneGrid`]).
fn axis_poses(
    times: &[f64],
    window_s: [f64; 2],
    max_pixels: usize,
    axis: &'static str,
) -> Result<(Vec<usize>, Vec<f64>)> {
    let [a, b] = window_s;
    if !(a.is_finite() && b.is_finite() && a < b) {
        return Err(Error::InvalidInterval { a, b });
    }
    // Times from the first pose, as the window is given.
    let t0 = times[0];
    let lo = times.partition_point(|&t| t - t0 < a);
    let hi = times.partition_point(|&t| t - t0 <= b);
    if hi <= lo {
        return Err(Error::EmptyWindow { axis, start_s: a, end_s: b });
    }
    if hi - lo <= max_pixels {
        return Ok(((lo..hi).collect(), pose_edges(&times[lo..hi], t0, window_s)));
    }
    let inside = &times[lo..hi];
    let step = (b - a) / max_pixels as f64;
    let edges = (0..=max_pixels).map(|k| if k == max_pixels { b } else { a + k as f64 * step }).collect();
    let poses = (0..max_pixels)
        .map(|k| {
            let centre = a + (k as f64 + 0.5) * step;
            let after = inside.partition_point(|&t| t - t0 < centre).min(inside.len() - 1);
            let nearest = if after > 0 && centre - (inside[after - 1] - t0) <= (inside[after] - t0) - centre {
                after - 1
            } else {
                after
            };
            lo + nearest
        })
        .collect();
    Ok((poses, edges))
}

/// The edges of pixels that show one pose each (`inside`, times on the clock of `t0`): the
/// midpoints between neighbours, half a step beyond the ends; the window for a single pose.
fn pose_edges(inside: &[f64], t0: f64, [a, b]: [f64; 2]) -> Vec<f64> {
    let relative: Vec<f64> = inside.iter().map(|t| t - t0).collect();
    let [first, .., last] = relative[..] else { return vec![a, b] };
    let mids = relative.windows(2).map(|w| (w[0] + w[1]) / 2.0);
    let (after_first, before_last) = ((relative[0] + relative[1]) / 2.0, (relative[relative.len() - 2] + last) / 2.0);
    std::iter::once(first - (after_first - first))
        .chain(mids)
        .chain(std::iter::once(last + (last - before_last)))
        .collect()
}

/// The pairwise distance π_ξ on a grid: δ(x_i, x_j) for column pose i and row pose j, row-major
/// (`rows × columns`, row 0 first), in the metric's unit. For any [`Metric`]; by name with
/// [`MetricSpec::distance_image`].
///
/// O(n) to validate the trajectory, then one δ per pixel, rows in parallel; memory one `f64` per
/// pixel.
///
/// # Errors
/// [`Error::PlaneGridMismatch`] when `grid` was made for another number of poses; the metric's
/// validation error (dimension, unit quaternions, ...); [`Error::OutOfMemory`] for an image too
/// big for memory; [`Error::Interrupted`] (checked every row) when an
/// [`Interrupt`] installed on this thread is interrupted.
///
/// # Examples
/// ```
/// use loops_core::plane::{PlaneGrid, distance_image};
/// use loops_core::{Euclidean, Trajectory};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0], [3.0], [1.0]])?;
/// let grid = PlaneGrid::new(&traj, None, 10)?;
/// let image = distance_image(&traj, &Euclidean, &grid)?;
/// assert_eq!(image, [0.0, 3.0, 1.0, 3.0, 0.0, 2.0, 1.0, 2.0, 0.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn distance_image<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, grid: &PlaneGrid) -> Result<Vec<f64>> {
    grid.check_poses(traj.len())?;
    traj.check_metric(metric)?;
    let mut image = try_filled(grid.width() * grid.height(), 0.0, "the distance image")?;
    let interrupt = Interrupt::current();
    image.par_chunks_mut(grid.width()).zip(grid.rows.par_iter()).try_for_each(|(row, &j)| {
        interrupt.check()?;
        let x_j = traj.point(j);
        for (value, &i) in row.iter_mut().zip(&grid.columns) {
            *value = metric.distance(traj.point(i), x_j);
        }
        Ok(())
    })?;
    Ok(image)
}

impl MetricSpec {
    /// [`distance_image`] under this metric (dispatched once: the per-pixel loop stays
    /// monomorphic).
    ///
    /// # Errors
    /// As [`distance_image`].
    ///
    /// # Examples
    /// ```
    /// use loops_core::plane::PlaneGrid;
    /// use loops_core::{MetricSpec, Trajectory};
    /// // Rotations about z by 0, 90° and 180°.
    /// let s = std::f64::consts::FRAC_1_SQRT_2;
    /// let traj = Trajectory::so3(vec![0.0, 1.0, 2.0], &[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, s, s], [0.0, 0.0, 1.0, 0.0]])?;
    /// let spec: MetricSpec = "so3".parse()?;
    /// let image = spec.distance_image(&traj, &PlaneGrid::new(&traj, None, 8)?)?;
    /// assert!((image[2] - std::f64::consts::PI).abs() < 1e-12); // δ(x_2, x_0): radians
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn distance_image(&self, traj: &Trajectory, grid: &PlaneGrid) -> Result<Vec<f64>> {
        with_metric!(self, m => distance_image(traj, m, grid))
    }
}

impl Loops {
    /// The loop component of every pixel of `grid`: the component holding the pair (column
    /// pose i, row pose j), either order (so the image is mirrored across the diagonal), `None`
    /// outside S_γ. Row-major like [`distance_image`]: `None` exactly where its δ > γ.
    ///
    /// O(pixels · log runs of a row), rows in parallel; memory 8 bytes a pixel.
    ///
    /// # Errors
    /// [`Error::PlaneGridMismatch`] when `grid` was made for another number of poses;
    /// [`Error::OutOfMemory`], [`Error::Interrupted`] as [`distance_image`].
    ///
    /// # Examples
    /// ```
    /// use loops_core::plane::PlaneGrid;
    /// use loops_core::{Euclidean, Trajectory, find_loops};
    /// // Out and back on a line: the end comes back to the start.
    /// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &[[0.0], [5.0], [5.0], [0.0]])?;
    /// let loops = find_loops(&traj, &Euclidean, 1.0)?;
    /// let labels = loops.label_image(&PlaneGrid::new(&loops, None, 10)?)?;
    /// let loop_id = loops.component_of(0, 3).map(|c| c as u32);
    /// assert!(loop_id.is_some());
    /// assert_eq!((labels[3], labels[3 * 4]), (loop_id, loop_id)); // (t_3, t′_0) and its mirror
    /// assert_eq!(labels[1], None); // (t_1, t′_0): 5 m apart
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn label_image(&self, grid: &PlaneGrid) -> Result<Vec<Option<u32>>> {
        grid.check_poses(self.len())?;
        let (set, components) = (self.sublevel_set(), self.run_components());
        let mut labels = try_filled(grid.width() * grid.height(), None, "the label image")?;
        let interrupt = Interrupt::current();
        labels.par_chunks_mut(grid.width()).zip(grid.rows.par_iter()).try_for_each(|(row, &j)| {
            interrupt.check()?;
            for (label, &i) in row.iter_mut().zip(&grid.columns) {
                *label = set.run_index(i, j).map(|r| components[r]);
            }
            Ok::<(), Error>(())
        })?;
        Ok(labels)
    }

    /// The component holding each pair (i, j) (either order), `None` outside S_γ: a binary
    /// search over the runs of row min(i, j). O(pairs · log runs of a row).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a pose index past the last pose.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Euclidean, Trajectory, find_loops};
    /// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0], [5.0], [0.0]])?;
    /// let loops = find_loops(&traj, &Euclidean, 1.0)?;
    /// let ids = loops.components_of_pairs(&[[0, 2], [2, 0], [0, 1]])?;
    /// assert_eq!(ids[0], ids[1]);
    /// assert!(ids[0].is_some() && ids[2].is_none());
    /// assert!(loops.components_of_pairs(&[[0, 3]]).is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn components_of_pairs(&self, pairs: &[[usize; 2]]) -> Result<Vec<Option<usize>>> {
        if let Some(&index) = pairs.iter().flatten().find(|&&p| p >= self.len()) {
            return Err(Error::IndexOutOfRange { index, len: self.len() });
        }
        Ok(pairs.par_iter().map(|&[i, j]| self.component_of(i, j)).collect())
    }

    /// How many of `pairs` each component holds (pairs outside S_γ are not counted), by
    /// component id. O(pairs · log runs of a row + components).
    ///
    /// # Errors
    /// As [`components_of_pairs`](Self::components_of_pairs).
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Euclidean, Trajectory, find_loops};
    /// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0], [5.0], [0.0]])?;
    /// let loops = find_loops(&traj, &Euclidean, 1.0)?;
    /// let counts = loops.pair_counts_per_component(&[[0, 2], [2, 0], [0, 1], [1, 1]])?;
    /// assert_eq!(counts.iter().sum::<u64>(), 3);
    /// assert_eq!(counts[loops.component_of(0, 2).unwrap()], 2);
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn pair_counts_per_component(&self, pairs: &[[usize; 2]]) -> Result<Vec<u64>> {
        let mut counts = vec![0; self.components().len()];
        for c in self.components_of_pairs(pairs)?.into_iter().flatten() {
            counts[c] += 1;
        }
        Ok(counts)
    }
}

/// How [`outline_segments`] treats the border of the image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Border {
    /// Outside the image lies no component: a component that touches the border is closed
    /// along it, so every outline is a closed line (for filled outlines).
    #[default]
    Closed,
    /// The image continues its outermost pixels: no edge along the border, so a component cut
    /// by a zoom window stays open there.
    Open,
}

impl Border {
    /// The accepted names.
    pub const NAMES: &'static str = "closed, open";
}

impl std::str::FromStr for Border {
    type Err = Error;

    /// `"closed"` or `"open"`.
    ///
    /// # Examples
    /// ```
    /// use loops_core::plane::Border;
    /// assert_eq!("open".parse::<Border>()?, Border::Open);
    /// assert!("ajar".parse::<Border>().is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    fn from_str(name: &str) -> Result<Self> {
        match name {
            "closed" => Ok(Self::Closed),
            "open" => Ok(Self::Open),
            _ => Err(Error::UnknownName { kind: "border", name: name.to_owned(), expected: Self::NAMES }),
        }
    }
}

/// One unit edge of the pixel lattice with different labels on its two sides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PixelEdge {
    /// Its first vertex `[x, y]`, a pixel corner in pixel units (x ∈ 0..=width, y ∈ 0..=height).
    pub start: [u32; 2],
    /// Its second vertex: one up from `start` (a vertical edge) or one to the right (horizontal).
    pub end: [u32; 2],
    /// The labels on its two sides: left and right of a vertical edge, below and above a
    /// horizontal one (`None`: no component, or outside a [`Border::Closed`] image).
    pub sides: [Option<u32>; 2],
}

/// Checks that an image of `len` values is `width × height`.
fn check_image(len: usize, width: usize, height: usize) -> Result<()> {
    if width.checked_mul(height) == Some(len) { Ok(()) } else { Err(Error::ImageSizeMismatch { len, width, height }) }
}

/// The edges of the pixel lattice where the label changes: the outlines ∂Ω of the components of
/// a label image (as [`Loops::label_image`] gives), vertical edges first (row by row, left to
/// right), then horizontal ones (bottom to top). Join them with [`chain_polylines`], or per
/// component with [`component_outlines`]. O(width · height).
///
/// # Errors
/// [`Error::ImageSizeMismatch`] unless `labels` has `width × height` values.
///
/// # Examples
/// ```
/// use loops_core::plane::{Border, outline_segments};
/// // One labelled pixel in the middle of a 3 × 3 image: its four sides.
/// let mut labels = vec![None; 9];
/// labels[4] = Some(7);
/// let edges = outline_segments(&labels, 3, 3, Border::Closed)?;
/// assert_eq!(edges.len(), 4);
/// assert!(edges.iter().all(|e| e.sides.contains(&Some(7)) && e.sides.contains(&None)));
/// // Labelled everywhere: edges only along a closed border.
/// assert_eq!(outline_segments(&[Some(1); 4], 2, 2, Border::Closed)?.len(), 8);
/// assert!(outline_segments(&[Some(1); 4], 2, 2, Border::Open)?.is_empty());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn outline_segments(labels: &[Option<u32>], width: usize, height: usize, border: Border) -> Result<Vec<PixelEdge>> {
    check_image(labels.len(), width, height)?;
    let label = |a: usize, b: usize| labels[b * width + a];
    // The label beyond the border next to pixel (a, b): none, or the pixel's own.
    let outside = |a: usize, b: usize| match border {
        Border::Closed => None,
        Border::Open => label(a, b),
    };
    let mut edges = Vec::new();
    for b in 0..height {
        for a in 0..=width {
            let left = if a > 0 { label(a - 1, b) } else { outside(a, b) };
            let right = if a < width { label(a, b) } else { outside(a - 1, b) };
            if left != right {
                let (x, y) = (a as u32, b as u32);
                edges.push(PixelEdge { start: [x, y], end: [x, y + 1], sides: [left, right] });
            }
        }
    }
    for b in 0..=height {
        for a in 0..width {
            let below = if b > 0 { label(a, b - 1) } else { outside(a, b) };
            let above = if b < height { label(a, b) } else { outside(a, b - 1) };
            if below != above {
                let (x, y) = (a as u32, b as u32);
                edges.push(PixelEdge { start: [x, y], end: [x + 1, y], sides: [below, above] });
            }
        }
    }
    Ok(edges)
}

/// The outline of each component of a label image, as closed polylines of lattice vertices
/// `[x, y]` (pixel corners, pixel units), by component id: the edges of
/// [`outline_segments`] with that id on either side, chained by [`chain_polylines`]. With
/// [`Border::Closed`] every polyline is closed (it ends where it starts), so the outlines can be
/// filled (even-odd: holes stay empty). O(width · height · log).
///
/// # Errors
/// As [`outline_segments`].
///
/// # Examples
/// ```
/// use loops_core::plane::{Border, component_outlines};
/// // A 2 × 1 component in a 3 × 2 image.
/// let labels = [Some(4), Some(4), None, None, None, None];
/// let outlines = component_outlines(&labels, 3, 2, Border::Closed)?;
/// assert_eq!(outlines[&4], [vec![[0, 0], [0, 1], [1, 1], [2, 1], [2, 0], [1, 0], [0, 0]]]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn component_outlines(
    labels: &[Option<u32>],
    width: usize,
    height: usize,
    border: Border,
) -> Result<BTreeMap<u32, Vec<Vec<[u32; 2]>>>> {
    let mut edges: BTreeMap<u32, Vec<[[u32; 2]; 2]>> = BTreeMap::new();
    for edge in outline_segments(labels, width, height, border)? {
        for c in edge.sides.into_iter().flatten() {
            edges.entry(c).or_default().push([edge.start, edge.end]);
        }
    }
    Ok(edges.into_iter().map(|(c, edges)| (c, chain_polylines(&edges))).collect())
}

/// Joins edges (pairs of vertices, either direction) into polylines, each a list of vertices; a
/// closed polyline ends with its first vertex. Every edge is used once. Deterministic: a
/// polyline starts at the first unused edge in input order, is extended forwards, then
/// backwards, each time along the first unused edge (in input order) at its end.
/// O(edges · log edges).
///
/// # Examples
/// ```
/// use loops_core::plane::chain_polylines;
/// // A unit square given out of order, and an open path.
/// let square = chain_polylines(&[[0, 1], [2, 3], [1, 2], [3, 0]]);
/// assert_eq!(square, [vec![0, 1, 2, 3, 0]]);
/// assert_eq!(chain_polylines(&[[5, 6], [7, 8], [6, 7]]), [vec![5, 6, 7, 8]]);
/// ```
pub fn chain_polylines<V: Copy + Ord>(edges: &[[V; 2]]) -> Vec<Vec<V>> {
    let mut ends: Vec<(V, usize)> = edges.iter().enumerate().flat_map(|(k, &[a, b])| [(a, k), (b, k)]).collect();
    ends.sort_unstable();
    let mut used = vec![false; edges.len()];
    let next = |vertex: V, used: &[bool]| -> Option<usize> {
        let first = ends.partition_point(|e| e.0 < vertex);
        ends[first..].iter().take_while(|e| e.0 == vertex).map(|e| e.1).find(|&k| !used[k])
    };
    let extend = |line: &mut Vec<V>, used: &mut Vec<bool>| {
        while let Some(&end) = line.last() {
            let Some(k) = next(end, used) else { break };
            used[k] = true;
            let [a, b] = edges[k];
            line.push(if a == end { b } else { a });
        }
    };
    let mut result = Vec::new();
    for k in 0..edges.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let [a, b] = edges[k];
        let mut forward = vec![a, b];
        extend(&mut forward, &mut used);
        let mut backward = vec![a];
        if forward.last() != Some(&a) {
            extend(&mut backward, &mut used);
        }
        backward.reverse();
        backward.pop();
        backward.extend(forward);
        result.push(backward);
    }
    result
}

/// The `level` isocontour of an image (`width × height` values, row-major, pixel centres at
/// (a + ½, b + ½)) by marching squares, as polylines of points `[x, y]` in pixel units, each
/// crossing placed by linear interpolation along its edge. Saddle cells are resolved by the
/// mean of their four corners. NaN counts as above the level. O(width · height · log).
///
/// For the γ isocontour of π_ξ, pass a [`distance_image`] and γ.
///
/// # Errors
/// [`Error::ImageSizeMismatch`] unless `values` has `width × height` values.
///
/// # Examples
/// ```
/// use loops_core::plane::isocontour;
/// // A cone of height 0 at (4.5, 4.5) in a 9 × 9 image: its level-2.5 contour is one circle.
/// let values: Vec<f64> = (0..81).map(|k| ((k % 9) as f64 - 4.0).hypot((k / 9) as f64 - 4.0)).collect();
/// let lines = isocontour(&values, 9, 9, 2.5)?;
/// assert_eq!(lines.len(), 1);
/// assert_eq!(lines[0].first(), lines[0].last());
/// assert!(lines[0].iter().all(|p| ((p[0] - 4.5).hypot(p[1] - 4.5) - 2.5).abs() < 0.3));
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn isocontour(values: &[f64], width: usize, height: usize, level: f64) -> Result<Vec<Vec<[f64; 2]>>> {
    check_image(values.len(), width, height)?;
    let v = |a: usize, b: usize| values[b * width + a] - level;
    let inside = |x: f64| x <= 0.0;
    // Edges between pixel centres: 2(b·width + a) to the right of (a, b), + 1 above it.
    let right = |a: usize, b: usize| 2 * (b * width + a);
    let up = |a: usize, b: usize| 2 * (b * width + a) + 1;
    let mut segments: Vec<[usize; 2]> = Vec::new();
    for b in 0..height.saturating_sub(1) {
        for a in 0..width.saturating_sub(1) {
            let corners = [v(a, b), v(a + 1, b), v(a + 1, b + 1), v(a, b + 1)];
            let case = corners.iter().enumerate().fold(0, |acc, (k, &c)| acc | (usize::from(inside(c)) << k));
            let (bottom, east, top, west) = (right(a, b), up(a + 1, b), right(a, b + 1), up(a, b));
            let centre_inside = inside(corners.iter().sum::<f64>());
            let pairs: &[[usize; 2]] = match case {
                0 | 15 => &[],
                1 | 14 => &[[west, bottom]],
                2 | 13 => &[[bottom, east]],
                3 | 12 => &[[west, east]],
                4 | 11 => &[[east, top]],
                6 | 9 => &[[bottom, top]],
                7 | 8 => &[[west, top]],
                5 if centre_inside => &[[bottom, east], [top, west]],
                5 => &[[west, bottom], [east, top]],
                10 if centre_inside => &[[west, bottom], [east, top]],
                _ => &[[bottom, east], [top, west]],
            };
            segments.extend_from_slice(pairs);
        }
    }
    let point = |edge: usize| {
        let (cell, vertical) = (edge / 2, edge % 2 == 1);
        let (a, b) = (cell % width, cell / width);
        let (v0, v1) = if vertical { (v(a, b), v(a, b + 1)) } else { (v(a, b), v(a + 1, b)) };
        let f = if v0 == v1 { 0.5 } else { (v0 / (v0 - v1)).clamp(0.0, 1.0) };
        let f = if f.is_nan() { 0.5 } else { f };
        let (x, y) = (a as f64 + 0.5, b as f64 + 0.5);
        if vertical { [x, y + f] } else { [x + f, y] }
    };
    Ok(chain_polylines(&segments).into_iter().map(|line| line.into_iter().map(point).collect()).collect())
}

/// What a serialised [`PlaneGrid`] holds.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct PlaneGridState {
    columns: Vec<usize>,
    rows: Vec<usize>,
    column_edges_s: Vec<f64>,
    row_edges_s: Vec<f64>,
    poses: usize,
}

#[cfg(feature = "serde")]
impl TryFrom<PlaneGridState> for PlaneGrid {
    type Error = Error;

    /// Checks that every pixel is a pose and has its two edges.
    fn try_from(state: PlaneGridState) -> Result<Self> {
        let PlaneGridState { columns, rows, column_edges_s, row_edges_s, poses } = state;
        let fits = |axis: &[usize], edges: &[f64]| {
            !axis.is_empty() && axis.iter().all(|&i| i < poses) && edges.len() == axis.len() + 1
        };
        if !(fits(&columns, &column_edges_s) && fits(&rows, &row_edges_s)) {
            return Err(Error::InvalidState {
                what: "PlaneGrid",
                reason: format!(
                    "{} columns with {} edges and {} rows with {} edges do not index {poses} poses",
                    columns.len(),
                    column_edges_s.len(),
                    rows.len(),
                    row_edges_s.len()
                ),
            });
        }
        Ok(Self { columns, rows, column_edges_s, row_edges_s, poses })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coarse_axes_take_the_nearest_pose() {
        let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 10.0], &[[0.0]; 4]).unwrap();
        // Three pixels (the four poses do not fit): centres at 1.67, 5 and 8.33 s; a sparse
        // stretch shows one pose twice.
        assert_eq!(PlaneGrid::new(&traj, None, 3).unwrap().columns(), [2, 2, 3]);
        assert_eq!(PlaneGrid::new(&traj, None, 1).unwrap().columns(), [2]);
        let err = PlaneGrid::new(&traj, Some(([3.0, 9.0], [0.0, 10.0])), 5).unwrap_err();
        assert_eq!(err, Error::EmptyWindow { axis: "t", start_s: 3.0, end_s: 9.0 });
        assert!(matches!(PlaneGrid::new(&traj, Some(([3.0, 3.0], [0.0, 1.0])), 5), Err(Error::InvalidInterval { .. })));
        assert!(matches!(PlaneGrid::new(&traj, None, 0), Err(Error::InvalidParameter { name: "max_pixels", .. })));
    }

    #[test]
    fn edges_are_even_steps_or_midpoints() {
        let traj = Trajectory::from_points(vec![5.0, 6.0, 7.0, 15.0], &[[0.0]; 4]).unwrap();
        let coarse = PlaneGrid::new(&traj, None, 3).unwrap();
        assert_eq!(coarse.column_edges_s(), [0.0, 10.0 / 3.0, 20.0 / 3.0, 10.0]);
        assert_eq!(coarse.row_edges_s(), coarse.column_edges_s());
        let all = PlaneGrid::new(&traj, None, 4).unwrap();
        assert_eq!(all.column_edges_s(), [-0.5, 0.5, 1.5, 6.0, 14.0]);
        let zoom = PlaneGrid::new(&traj, Some(([9.5, 10.0], [0.5, 2.5])), 4).unwrap();
        assert_eq!((zoom.columns(), zoom.column_edges_s()), (&[3][..], &[9.5, 10.0][..]));
        assert_eq!((zoom.rows(), zoom.row_edges_s()), (&[1, 2][..], &[0.5, 1.5, 2.5][..]));
    }

    #[test]
    fn sizes_are_checked() {
        assert_eq!(
            outline_segments(&[None; 5], 2, 3, Border::Open).unwrap_err(),
            Error::ImageSizeMismatch { len: 5, width: 2, height: 3 }
        );
        assert!(isocontour(&[0.0; 4], 3, 1, 1.0).is_err());
        assert!(isocontour(&[0.0], 1, 1, 1.0).unwrap().is_empty());
        let traj = Trajectory::from_points(vec![0.0, 1.0], &[[0.0]; 2]).unwrap();
        let other = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0]; 3]).unwrap();
        let grid = PlaneGrid::new(&other, None, 8).unwrap();
        assert_eq!(
            distance_image(&traj, &crate::metric::Euclidean, &grid).unwrap_err(),
            Error::PlaneGridMismatch { grid_poses: 3, poses: 2 }
        );
    }

    #[test]
    fn open_contours_end_at_the_border() {
        // A ramp in x: the level crosses every row once, a straight open line.
        let values: Vec<f64> = (0..20).map(|k| (k % 5) as f64).collect();
        let lines = isocontour(&values, 5, 4, 1.5).unwrap();
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].len(), 4);
        assert!(lines[0].iter().all(|p| p[0] == 2.0), "{lines:?}");
    }
}

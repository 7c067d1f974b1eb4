//! Places on the map and the passes of a trajectory near them: which poses of a session lie
//! within a radius of a point or a polygon, as maximal runs of consecutive poses ([`Pass`]).
//!
//! A place lies in the map plane: the first two coordinates of the positions (`x`, `y` of a
//! Euclidean trajectory of at least two coordinates, of SE(2) and of SE(3) poses), measured
//! with the plane's Euclidean distance. A pose is within radius r of a polygon when it lies
//! inside it (even-odd rule) or within r of its boundary.

use crate::error::{Error, Result};
use crate::trajectory::{Manifold, Trajectory};

/// A place in the map plane (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum Place {
    /// A point `[x, y]`.
    Point([f64; 2]),
    /// A polygon by its vertices `[x, y]` in order (closed: the last joins the first); at least
    /// three.
    Polygon(Vec<[f64; 2]>),
}

impl Place {
    /// The point `[x, y]`, checked.
    ///
    /// # Errors
    /// [`Error::InvalidPlace`] for a coordinate that is not finite.
    pub fn point(xy: [f64; 2]) -> Result<Self> {
        check_vertex("point", None, xy)?;
        Ok(Self::Point(xy))
    }

    /// The polygon of `vertices`, checked.
    ///
    /// # Errors
    /// [`Error::InvalidPlace`] for fewer than three vertices or a coordinate that is not
    /// finite.
    pub fn polygon(vertices: Vec<[f64; 2]>) -> Result<Self> {
        if vertices.len() < 3 {
            return Err(Error::InvalidPlace {
                problem: format!("a polygon needs at least 3 vertices, got {}", vertices.len()),
            });
        }
        for (k, &v) in vertices.iter().enumerate() {
            check_vertex("polygon vertex", Some(k), v)?;
        }
        Ok(Self::Polygon(vertices))
    }

    /// The distance from `xy` to the place in the plane: 0 inside a polygon. O(vertices).
    ///
    /// # Examples
    /// ```
    /// use loops_core::Place;
    /// let square = Place::polygon(vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])?;
    /// assert_eq!(square.distance([1.0, 1.0]), 0.0);
    /// assert_eq!(square.distance([5.0, 2.0]), 3.0);
    /// assert_eq!(Place::point([0.0, 0.0])?.distance([3.0, 4.0]), 5.0);
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn distance(&self, xy: [f64; 2]) -> f64 {
        match self {
            Self::Point(p) => (xy[0] - p[0]).hypot(xy[1] - p[1]),
            Self::Polygon(vertices) => {
                let mut inside = false;
                let mut nearest = f64::INFINITY;
                let mut previous = vertices[vertices.len() - 1];
                for &v in vertices {
                    // Even-odd rule: a ray to +x crosses edges whose ends lie on both sides of y.
                    if (v[1] > xy[1]) != (previous[1] > xy[1]) {
                        let x = v[0] + (xy[1] - v[1]) / (previous[1] - v[1]) * (previous[0] - v[0]);
                        if xy[0] < x {
                            inside = !inside;
                        }
                    }
                    nearest = nearest.min(segment_distance(xy, previous, v));
                    previous = v;
                }
                if inside { 0.0 } else { nearest }
            }
        }
    }

    /// Whether the place is within `radius` of the plane point `xy`.
    fn is_near(&self, xy: [f64; 2], radius: f64) -> bool {
        self.distance(xy) <= radius
    }
}

/// A pass of a trajectory near a place: a maximal run of consecutive poses within the radius.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pass {
    /// Its first and last pose (both within the radius).
    pub poses: [usize; 2],
    /// The times of those poses, seconds, on the trajectory's clock.
    pub times_s: [f64; 2],
}

/// The passes of `trajectory` within `radius` of `place`, in time order. O(poses × vertices).
///
/// # Errors
/// [`Error::InvalidParameter`] for a radius that is negative or not finite;
/// [`Error::InvalidPlace`] for a trajectory whose points have no map plane (see the module
/// docs).
///
/// # Examples
/// ```
/// use loops_core::{Place, Trajectory, passes_near};
/// // Out along the x axis and back: two passes within 1 of (4, 0).
/// let xs = [0.0, 2.0, 4.0, 6.0, 4.0, 2.0, 0.0];
/// let points: Vec<[f64; 2]> = xs.iter().map(|&x| [x, 0.0]).collect();
/// let drive = Trajectory::from_points((0..7).map(f64::from).collect(), &points)?;
/// let passes = passes_near(&drive, &Place::point([4.0, 0.0])?, 1.0)?;
/// assert_eq!(passes.iter().map(|p| p.poses).collect::<Vec<_>>(), [[2, 2], [4, 4]]);
/// assert_eq!(passes[1].times_s, [4.0, 4.0]);
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn passes_near(trajectory: &Trajectory, place: &Place, radius: f64) -> Result<Vec<Pass>> {
    check_radius(radius)?;
    check_plane(trajectory.manifold(), trajectory.dim())?;
    let mut passes = Vec::new();
    passes_within(trajectory, place, radius, 0..trajectory.len(), &mut passes);
    Ok(passes)
}

/// Appends to `passes` the maximal runs of poses within `radius` of `place` among the poses
/// `range` of `trajectory` (checked as [`passes_near`] checks them): the passes of the whole
/// trajectory that lie in `range`, when the poses just outside it are not near.
pub(crate) fn passes_within(
    trajectory: &Trajectory,
    place: &Place,
    radius: f64,
    range: std::ops::Range<usize>,
    passes: &mut Vec<Pass>,
) {
    let times = trajectory.timestamps_s();
    let mut open: Option<usize> = None;
    for i in range.clone() {
        let p = trajectory.point(i);
        let near = place.is_near([p[0], p[1]], radius);
        match (near, open) {
            (true, None) => open = Some(i),
            (false, Some(start)) => {
                passes.push(Pass { poses: [start, i - 1], times_s: [times[start], times[i - 1]] });
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        let last = range.end - 1;
        passes.push(Pass { poses: [start, last], times_s: [times[start], times[last]] });
    }
}

/// A radius is a finite distance of at least 0.
///
/// # Errors
/// [`Error::InvalidParameter`] otherwise.
pub fn check_radius(radius: f64) -> Result<()> {
    if radius.is_finite() && radius >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name: "radius", value: radius, expected: "a finite distance of at least 0" })
    }
}

/// Points of `manifold` and `dim` coordinates have a map plane (their first two coordinates).
pub(crate) fn check_plane(manifold: Manifold, dim: usize) -> Result<()> {
    let planar = match manifold {
        Manifold::Euclidean => dim >= 2,
        Manifold::Se2 | Manifold::Se3 => true,
        _ => false,
    };
    if planar {
        return Ok(());
    }
    Err(Error::InvalidPlace {
        problem: format!(
            "points on {} of dimension {dim} have no map plane: places need positions (euclidean of at least \
             2 coordinates, se2, se3)",
            manifold.name()
        ),
    })
}

/// A finite `[x, y]`, or an error naming it (`what`, vertex `index`).
fn check_vertex(what: &str, index: Option<usize>, xy: [f64; 2]) -> Result<()> {
    for (axis, value) in ["x", "y"].into_iter().zip(xy) {
        if !value.is_finite() {
            let at = index.map_or_else(String::new, |k| format!(" {k}"));
            return Err(Error::InvalidPlace {
                problem: format!("{what}{at} has {axis} = {value}: need finite coordinates"),
            });
        }
    }
    Ok(())
}

/// The distance from `p` to the segment from `a` to `b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let u = if length2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - u * dx).hypot(p[1] - a[1] - u * dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_polygon_holds_its_inside_and_measures_its_boundary() {
        let l_shape =
            Place::polygon(vec![[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0], [1.0, 4.0], [0.0, 4.0]]).unwrap();
        assert_eq!(l_shape.distance([0.5, 3.0]), 0.0);
        assert_eq!(l_shape.distance([3.0, 0.5]), 0.0);
        assert!((l_shape.distance([3.0, 3.0]) - 2.0).abs() < 1e-12);
        assert_eq!(l_shape.distance([4.0, 0.5]), 0.0);
    }

    #[test]
    fn bad_places_and_radii_are_named() {
        let short = Place::polygon(vec![[0.0, 0.0], [1.0, 0.0]]).unwrap_err().to_string();
        assert!(short.contains("at least 3 vertices, got 2"), "{short}");
        let nan = Place::polygon(vec![[0.0, 0.0], [1.0, 0.0], [1.0, f64::NAN]]).unwrap_err().to_string();
        assert!(nan.contains("vertex 2 has y = NaN"), "{nan}");
        assert!(check_radius(-1.0).unwrap_err().to_string().contains("radius = -1"));
        let angles = Trajectory::new(vec![0.0, 1.0], vec![0.0, 1.0], 1).unwrap();
        let flat = passes_near(&angles, &Place::point([0.0, 0.0]).unwrap(), 1.0).unwrap_err().to_string();
        assert!(flat.contains("no map plane"), "{flat}");
    }
}

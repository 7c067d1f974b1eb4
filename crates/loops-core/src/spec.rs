//! Metrics by name: [`MetricSpec`], the registry of the metrics of [`metric`](crate::Metric)
//! and the manifolds, parsed from and printed as text (for Python and the command line).

use crate::error::{Error, MetricMisfit, Result};
use crate::manifold::RotationDistance;
use crate::metric::Metric;
use crate::trajectory::{Manifold, Trajectory};

/// A metric chosen by name at run time (from Python or the command line), dispatched once to
/// the statically typed engine, so the hot loops stay monomorphic.
///
/// The text form is `name` or `name(key=value, ...)`; [`FromStr`](std::str::FromStr) parses it
/// and [`Display`](std::fmt::Display) writes it back:
///
/// | name | parameters | points |
/// |---|---|---|
/// | `euclidean` | | Rⁿ |
/// | `so3` | `rotation=geodesic\|chordal` (default geodesic) | `[qx, qy, qz, qw]` |
/// | `se3` | `rotation_weight_m_per_rad=W` (required), `rotation=...` | `[x, y, z, qx, qy, qz, qw]` |
/// | `se3_rotation` | `rotation=...` | as `se3` |
/// | `se2` | `rotation_weight_m_per_rad=W` (required) | `[x, y, θ]` |
/// | `torus` | | angles |
/// | `sphere` | `radius=R` (default 1) | unit vectors `[x, y, z]` |
/// | `haversine` | `radius_m=R` (default the mean Earth radius) | `[ux, uy, uz, height_m]` |
/// | `angular` | | unit vectors |
///
/// # Examples
/// ```
/// use loops_core::MetricSpec;
/// let spec: MetricSpec = "se3(rotation_weight_m_per_rad=10)".parse()?;
/// assert_eq!(spec.to_string(), "se3(rotation_weight_m_per_rad=10, rotation=geodesic)");
/// assert!("se3".parse::<MetricSpec>().is_err()); // the weight has no universal default
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[non_exhaustive]
pub enum MetricSpec {
    /// [`Euclidean`](crate::metric::Euclidean).
    #[default]
    Euclidean,
    /// [`So3`](crate::manifold::So3).
    So3(crate::manifold::So3),
    /// [`Se3`](crate::manifold::Se3).
    Se3(crate::manifold::Se3),
    /// [`Se3Rotation`](crate::manifold::Se3Rotation).
    Se3Rotation(crate::manifold::Se3Rotation),
    /// [`Se2`](crate::manifold::Se2).
    Se2(crate::manifold::Se2),
    /// [`Torus`](crate::manifold::Torus).
    Torus,
    /// [`Sphere`](crate::manifold::Sphere).
    Sphere(crate::manifold::Sphere),
    /// [`Haversine`](crate::manifold::Haversine).
    Haversine(crate::manifold::Haversine),
    /// [`Angular`](crate::manifold::Angular).
    Angular,
}

/// Calls `$body` with `$m` bound to the concrete metric of a [`MetricSpec`], so that code
/// generic over [`Metric`] is instantiated once per metric. Each engine module adds its own
/// `MetricSpec` entry point with it (`find_loops`, `sample_loops`, `distance_image`).
macro_rules! with_metric {
    ($spec:expr, $m:ident => $body:expr) => {
        match $spec {
            $crate::spec::MetricSpec::Euclidean => {
                let $m = &$crate::metric::Euclidean;
                $body
            }
            $crate::spec::MetricSpec::So3(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Se3(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Se3Rotation(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Se2(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Torus => {
                let $m = &$crate::manifold::Torus;
                $body
            }
            $crate::spec::MetricSpec::Sphere(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Haversine(metric) => {
                let $m = metric;
                $body
            }
            $crate::spec::MetricSpec::Angular => {
                let $m = &$crate::manifold::Angular;
                $body
            }
        }
    };
}
pub(crate) use with_metric;

/// The name a result records for `metric` ([`Loops::metric_name`](crate::Loops::metric_name)):
/// [`Metric::name`] when it is a [`MetricSpec`]'s (parsing it back gives the same text), or
/// else `custom(NAME)`, a metric of the caller's own (a Python callable, a type of your own),
/// which no spec parses as. A saved result read back can so tell a metric it can rebuild by
/// name from one it cannot, and a name that is neither is refused as corrupt
/// (`check_recorded_metric_name`, inside the crate).
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, MetricSpec, recorded_metric_name};
/// assert_eq!(recorded_metric_name(&Euclidean), "euclidean");
/// let se3: MetricSpec = "se3(rotation_weight_m_per_rad=2)".parse()?;
/// assert_eq!(recorded_metric_name(se3.as_metric()), se3.name());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn recorded_metric_name<M: Metric + ?Sized>(metric: &M) -> String {
    let name = metric.name();
    match name.parse::<MetricSpec>() {
        Ok(spec) if spec.name() == name => name,
        _ => format!("custom({name})"),
    }
}

/// Checks a metric's name read from a saved result: one that [`recorded_metric_name`] gives.
///
/// # Errors
/// What is wrong with it, in words.
#[cfg(feature = "serde")]
pub(crate) fn check_recorded_metric_name(name: &str) -> std::result::Result<(), String> {
    let custom = name.strip_prefix("custom(").and_then(|rest| rest.strip_suffix(')'));
    match name.parse::<MetricSpec>() {
        Ok(spec) if spec.name() == name => Ok(()),
        _ if custom.is_some() => Ok(()),
        Ok(spec) => Err(format!("its metric {name:?} is not written as the metric {spec} is")),
        Err(error) => Err(format!("its metric {name:?} is neither a metric's name ({error}) nor custom(NAME)")),
    }
}

impl MetricSpec {
    /// The accepted names.
    pub const NAMES: &'static str = "euclidean, so3, se3, se3_rotation, se2, torus, sphere, haversine, angular";

    /// The canonical text form, as [`FromStr`](std::str::FromStr) accepts it.
    pub fn name(&self) -> String {
        with_metric!(self, m => m.name())
    }

    /// The metric as a trait object, for code that takes `&dyn Metric` (dispatched per call;
    /// [`find_loops`](Self::find_loops) keeps the engine's loops monomorphic instead).
    pub fn as_metric(&self) -> &dyn Metric {
        with_metric!(self, m => m as &dyn Metric)
    }

    /// δ between two points under this metric (dispatched per call: for tests and small jobs).
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        with_metric!(self, m => m.distance(a, b))
    }

    /// Checks that this metric fits `traj`'s manifold and validates the points for it (see
    /// [`Trajectory::check_metric`]).
    ///
    /// # Errors
    /// As [`Trajectory::check_metric`].
    pub fn validate(&self, traj: &Trajectory) -> Result<()> {
        with_metric!(self, m => traj.check_metric(m))
    }
}

impl Manifold {
    /// The metric that measures its points when none is chosen (see the table of
    /// [`Manifold`]): the one every entry point uses without a metric — Python's
    /// `find_loops(traj, gamma=...)`, `sample`, `distance_image`.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Manifold, MetricSpec};
    /// assert_eq!(Manifold::Euclidean.default_metric(), MetricSpec::Euclidean);
    /// assert_eq!(Manifold::So3.default_metric().to_string(), "so3(rotation=geodesic)");
    /// assert_eq!(Manifold::Gnss.default_metric().to_string(), "haversine(radius_m=6371008.8)");
    /// ```
    pub fn default_metric(self) -> MetricSpec {
        use crate::manifold::{EARTH_RADIUS_M, Haversine, RotationDistance, Se2, Se3, So3, Sphere};
        match self {
            Self::Euclidean => MetricSpec::Euclidean,
            Self::Se3 => MetricSpec::Se3(Se3 { rotation_weight_m_per_rad: 0.0, rotation: RotationDistance::Geodesic }),
            Self::So3 => MetricSpec::So3(So3 { rotation: RotationDistance::Geodesic }),
            Self::Se2 => MetricSpec::Se2(Se2 { rotation_weight_m_per_rad: 0.0 }),
            Self::Torus => MetricSpec::Torus,
            Self::Sphere => MetricSpec::Sphere(Sphere { radius: 1.0 }),
            Self::Gnss => MetricSpec::Haversine(Haversine { radius_m: EARTH_RADIUS_M }),
            Self::Descriptors => MetricSpec::Angular,
        }
    }
}

impl Trajectory {
    /// The metric that measures the points when none is chosen: its
    /// [`manifold`](Trajectory::manifold)'s [`default_metric`](Manifold::default_metric).
    pub fn default_metric(&self) -> MetricSpec {
        self.manifold().default_metric()
    }

    /// Checks that `metric` measures these points — it fits the trajectory's manifold
    /// ([`Metric::fits`]) — and validates them for it ([`Metric::validate`]): what the engine
    /// checks before it measures anything.
    ///
    /// # Errors
    /// [`Error::MetricDoesNotFit`], naming the metric, the manifold, its columns and the
    /// metrics that fit; then the metric's own errors (dimension, unit quaternions, ...).
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Euclidean, Se3, RotationDistance, Trajectory};
    /// let poses = Trajectory::se3(vec![0.0, 1.0], &[[0.0; 3], [1.0, 0.0, 0.0]], &[[0.0, 0.0, 0.0, 1.0]; 2])?;
    /// let error = poses.check_metric(&Euclidean).unwrap_err().to_string();
    /// assert!(error.starts_with("metric euclidean does not fit an se3 trajectory (7 columns: x y z qx qy qz qw)"));
    /// assert!(poses.check_metric(&Se3 { rotation_weight_m_per_rad: 2.0, rotation: RotationDistance::Geodesic }).is_ok());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn check_metric<M: Metric + ?Sized>(&self, metric: &M) -> Result<()> {
        check_fits(metric, self)?;
        metric.validate(self)
    }
}

/// [`Error::MetricDoesNotFit`] unless `metric` fits `traj`'s manifold (no pass over the points).
pub(crate) fn check_fits<M: Metric + ?Sized>(metric: &M, traj: &Trajectory) -> Result<()> {
    let manifold = traj.manifold();
    if metric.fits(manifold) {
        return Ok(());
    }
    Err(Error::MetricDoesNotFit(Box::new(MetricMisfit {
        metric: metric.name(),
        trajectory: manifold.a_trajectory(),
        dim: traj.dim(),
        columns: manifold.columns(traj.dim()),
        fitting: manifold.metrics(),
        default: manifold.default_metric().name(),
    })))
}

impl std::fmt::Display for MetricSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

impl std::str::FromStr for MetricSpec {
    type Err = Error;

    fn from_str(spec: &str) -> Result<Self> {
        let invalid = |reason: String| Error::InvalidMetricSpec { spec: spec.to_owned(), reason };
        let text = spec.trim();
        let (name, args) = match text.split_once('(') {
            None => (text, ""),
            Some((name, rest)) => {
                let args = rest.strip_suffix(')').ok_or_else(|| invalid("missing the closing ')'".into()))?;
                (name.trim(), args)
            }
        };
        let mut params: Vec<(String, String)> = Vec::new();
        for item in args.split(',').map(str::trim).filter(|item| !item.is_empty()) {
            let (key, value) = item.split_once('=').ok_or_else(|| invalid(format!("{item:?} is not key=value")))?;
            let key = key.trim();
            if params.iter().any(|(k, _)| k == key) {
                return Err(invalid(format!("repeated parameter '{key}'")));
            }
            params.push((key.to_owned(), value.trim().to_owned()));
        }
        let mut take = |key: &str| -> Option<String> {
            let at = params.iter().position(|(k, _)| k == key)?;
            Some(params.remove(at).1)
        };
        let number = |key: &str, value: Option<String>| -> Result<Option<f64>> {
            value.map(|v| v.parse::<f64>().map_err(|_| invalid(format!("{key}={v} is not a number")))).transpose()
        };
        let rotation = |value: Option<String>| -> Result<RotationDistance> {
            value.map_or(Ok(RotationDistance::default()), |v| v.parse())
        };
        let required = |key: &'static str, value: Option<f64>| {
            value.ok_or_else(|| invalid(format!("{key} is required, e.g. {name}({key}=10)")))
        };
        let parsed = match name.to_ascii_lowercase().as_str() {
            "euclidean" | "l2" => Self::Euclidean,
            "so3" => Self::So3(crate::manifold::So3 { rotation: rotation(take("rotation"))? }),
            "se3" => {
                let weight = number("rotation_weight_m_per_rad", take("rotation_weight_m_per_rad"))?;
                let rotation = rotation(take("rotation"))?;
                Self::Se3(crate::manifold::Se3 {
                    rotation_weight_m_per_rad: required("rotation_weight_m_per_rad", weight)?,
                    rotation,
                })
            }
            "se3_rotation" => Self::Se3Rotation(crate::manifold::Se3Rotation { rotation: rotation(take("rotation"))? }),
            "se2" => {
                let weight = number("rotation_weight_m_per_rad", take("rotation_weight_m_per_rad"))?;
                Self::Se2(crate::manifold::Se2 {
                    rotation_weight_m_per_rad: required("rotation_weight_m_per_rad", weight)?,
                })
            }
            "torus" => Self::Torus,
            "sphere" => {
                Self::Sphere(crate::manifold::Sphere { radius: number("radius", take("radius"))?.unwrap_or(1.0) })
            }
            "haversine" => Self::Haversine(crate::manifold::Haversine {
                radius_m: number("radius_m", take("radius_m"))?.unwrap_or(crate::manifold::EARTH_RADIUS_M),
            }),
            "angular" => Self::Angular,
            _ => return Err(Error::UnknownName { kind: "metric", name: name.to_owned(), expected: Self::NAMES }),
        };
        if let Some((key, _)) = params.first() {
            return Err(invalid(format!("{name} takes no parameter {key:?}")));
        }
        // Weights and radii are checked here too, so a bad spec fails before any data is read.
        match parsed {
            MetricSpec::Se3(m) if !(m.rotation_weight_m_per_rad.is_finite() && m.rotation_weight_m_per_rad >= 0.0) => {
                Err(invalid(format!(
                    "rotation_weight_m_per_rad must be finite and ≥ 0, got {}",
                    m.rotation_weight_m_per_rad
                )))
            }
            MetricSpec::Se2(m) if !(m.rotation_weight_m_per_rad.is_finite() && m.rotation_weight_m_per_rad >= 0.0) => {
                Err(invalid(format!(
                    "rotation_weight_m_per_rad must be finite and ≥ 0, got {}",
                    m.rotation_weight_m_per_rad
                )))
            }
            MetricSpec::Sphere(m) if !(m.radius.is_finite() && m.radius > 0.0) => {
                Err(invalid(format!("radius must be positive and finite, got {}", m.radius)))
            }
            MetricSpec::Haversine(m) if !(m.radius_m.is_finite() && m.radius_m > 0.0) => {
                Err(invalid(format!("radius_m must be positive and finite, got {}", m.radius_m)))
            }
            _ => Ok(parsed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metric_specs_round_trip_and_reject_bad_text() {
        for text in [
            "euclidean",
            "so3(rotation=chordal)",
            "se3(rotation_weight_m_per_rad=2.5, rotation=geodesic)",
            "se3_rotation(rotation=geodesic)",
            "se2(rotation_weight_m_per_rad=4)",
            "torus",
            "sphere(radius=2)",
            "haversine(radius_m=6371008.8)",
            "angular",
        ] {
            let spec: MetricSpec = text.parse().unwrap();
            assert_eq!(spec.to_string(), text);
            assert_eq!(spec.to_string().parse::<MetricSpec>().unwrap(), spec);
        }
        assert_eq!("L2".parse::<MetricSpec>().unwrap(), MetricSpec::Euclidean);
        for bad in [
            "manhattan",
            "se3",
            "se3(rotation_weight_m_per_rad=-1)",
            "se3(rotation_weight_m_per_rad=x)",
            "se3(rotation_weight_m_per_rad=1",
            "se2(weight=1)",
            "so3(rotation=euler)",
            "sphere(radius=0)",
            "torus(radius=1)",
        ] {
            assert!(bad.parse::<MetricSpec>().is_err(), "{bad}");
        }
        // A key given twice is refused as such, not as a parameter the metric lacks.
        for repeated in
            ["so3(rotation=chordal,rotation=geodesic)", "se3(rotation_weight_m_per_rad=1, rotation_weight_m_per_rad=2)"]
        {
            let error = repeated.parse::<MetricSpec>().unwrap_err().to_string();
            assert!(
                error.ends_with("repeated parameter 'rotation'")
                    || error.ends_with("repeated parameter 'rotation_weight_m_per_rad'"),
                "{error}"
            );
        }
    }
}

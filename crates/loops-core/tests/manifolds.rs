//! Metrics on manifolds: the metric axioms on random and adversarial points, values
//! against formulas written here from textbooks (rotation matrices, haversine, ellipsoid radii),
//! the engine against the brute force under every metric, bad input, the paper's Fig. 4, and
//! the manifold every constructor records (its default metric, and the metrics refused).
//!
//! Points are always built through the `Trajectory` constructors, as a user builds them.

mod support;

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, SQRT_2, TAU};

use loops_core::{
    Angular, EARTH_RADIUS_M, Error, Euclidean, Haversine, Loops, Manifold, Metric, MetricSpec, RotationDistance,
    SampleSize, Sampler, SamplerKind, Se2, Se3, Se3Rotation, Separation, So3, Sphere, SublevelSet, Torus, Trajectory,
    find_loops,
    plane::{PlaneGrid, distance_image},
    sample_loops,
};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use support::config;

// =============================================================================================
// Independent reference formulas
// =============================================================================================

/// A quaternion `[x, y, z, w]` (the ROS and scipy order).
type Quat = [f64; 4];
type Mat3 = [[f64; 3]; 3];

/// The rotation matrix of a unit quaternion (the standard formula).
fn rotation_matrix([x, y, z, w]: Quat) -> Mat3 {
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
        [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
        [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// tr(Aᵀ B) = Σ A_ij B_ij.
fn trace_of_at_b(a: &Mat3, b: &Mat3) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(p, q)| p * q).sum()
}

/// cos θ of the rotation R_aᵀ R_b: (tr(R_aᵀ R_b) − 1) / 2.
fn cos_angle_between(a: &Mat3, b: &Mat3) -> f64 {
    (trace_of_at_b(a, b) - 1.0) / 2.0
}

/// ‖R_a − R_b‖_F from the matrices.
fn frobenius(a: &Mat3, b: &Mat3) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt()
}

/// The Hamilton product a ⊗ b.
fn quat_mul([ax, ay, az, aw]: Quat, [bx, by, bz, bw]: Quat) -> Quat {
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

fn quat_conj([x, y, z, w]: Quat) -> Quat {
    [-x, -y, -z, w]
}

/// The quaternion of a rotation vector (axis × angle, radians).
fn quat_exp(v: [f64; 3]) -> Quat {
    let angle = norm(&v);
    if angle == 0.0 {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let k = (0.5 * angle).sin() / angle;
    [k * v[0], k * v[1], k * v[2], (0.5 * angle).cos()]
}

/// The rotation about `axis` (any length) by `angle`.
fn axis_angle(axis: [f64; 3], angle: f64) -> Quat {
    let n = norm(&axis);
    quat_exp([axis[0] / n * angle, axis[1] / n * angle, axis[2] / n * angle])
}

/// Rotation angle of q_a⁻¹ q_b from the relative quaternion: 2 atan2(‖v‖, |w|), stable everywhere.
fn relative_angle(a: Quat, b: Quat) -> f64 {
    let [x, y, z, w] = quat_mul(quat_conj(a), b);
    2.0 * norm(&[x, y, z]).atan2(w.abs())
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `v / ‖v‖`, or `None` for a (nearly) zero vector.
fn unit(v: &[f64]) -> Option<Vec<f64>> {
    let n = norm(v);
    (n > 1e-12).then(|| v.iter().map(|x| x / n).collect())
}

/// The textbook haversine (R = 6371008.8 m): a = sin²(Δφ/2) + cos φ₁ cos φ₂ sin²(Δλ/2),
/// d = 2R asin(√a). Degrees in, metres out.
fn haversine_textbook_m(lat1_deg: f64, lon1_deg: f64, lat2_deg: f64, lon2_deg: f64) -> f64 {
    let (phi1, phi2) = (lat1_deg.to_radians(), lat2_deg.to_radians());
    let (d_phi, d_lambda) = ((lat2_deg - lat1_deg).to_radians(), (lon2_deg - lon1_deg).to_radians());
    let a = (d_phi / 2.0).sin().powi(2) + phi1.cos() * phi2.cos() * (d_lambda / 2.0).sin().powi(2);
    2.0 * 6_371_008.8 * a.sqrt().min(1.0).asin()
}

/// The unit vector of a latitude and longitude, degrees.
fn lat_lon_to_unit(lat_deg: f64, lon_deg: f64) -> [f64; 3] {
    let (lat, lon) = (lat_deg.to_radians(), lon_deg.to_radians());
    [lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()]
}

/// The great-circle angle between unit vectors, atan2(‖a × b‖, a · b): well conditioned at 0 and π.
fn great_circle_angle(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    norm(&cross).atan2(dot(a, b))
}

/// The flat-torus distance by brute force: per angle the least |a − b + 2πk| over k, then L2.
fn torus_brute_force(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (-20..=20).map(|k| (x - y + TAU * f64::from(k)).abs()).fold(f64::INFINITY, f64::min).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn times(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64).collect()
}

// =============================================================================================
// Spaces: raw constructor input, random points and geodesic steps
// =============================================================================================

/// A manifold, with points as the raw input of its `Trajectory` constructor.
#[derive(Debug, Clone, Copy)]
enum Space {
    /// `[qx, qy, qz, qw]`, through `Trajectory::so3`.
    So3,
    /// `[x, y, z, qx, qy, qz, qw]`, through `Trajectory::se3`; rotation steps of `radians_per_m`
    /// per metre of translation step.
    Se3 { radians_per_m: f64 },
    /// `[x, y, θ]`, through `Trajectory::se2`.
    Se2 { radians_per_m: f64 },
    /// k angles, through `Trajectory::torus`.
    Torus(usize),
    /// Any non-zero `[x, y, z]`, through `Trajectory::sphere`; steps in units of `radius`.
    Sphere { radius: f64 },
    /// `[lat_deg, lon_deg, height_m]`, through `Trajectory::gnss`.
    Gnss,
    /// Non-zero descriptors of dimension d, through `Trajectory::descriptors(normalize = true)`.
    Descriptor(usize),
    /// Rⁿ, through `Trajectory::descriptors(normalize = false)`.
    Euclid(usize),
}

/// Uniform values in [−1, 1] that seed a point or a direction.
type Seed = [f64; 8];

impl Space {
    fn build(self, points: &[Vec<f64>]) -> loops_core::Result<Trajectory> {
        let t = times(points.len());
        let fixed =
            |k: usize| -> Vec<[f64; 4]> { points.iter().map(|p| [p[k], p[k + 1], p[k + 2], p[k + 3]]).collect() };
        let three = |k: usize| -> Vec<[f64; 3]> { points.iter().map(|p| [p[k], p[k + 1], p[k + 2]]).collect() };
        let flat = || -> Vec<f64> { points.iter().flatten().copied().collect() };
        match self {
            Space::So3 => Trajectory::so3(t, &fixed(0)),
            Space::Se3 { .. } => Trajectory::se3(t, &three(0), &fixed(3)),
            Space::Se2 { .. } => Trajectory::se2(t, &three(0)),
            Space::Torus(k) => Trajectory::torus(t, &flat(), k),
            Space::Sphere { .. } => Trajectory::sphere(t, &three(0)),
            Space::Gnss => Trajectory::gnss(t, &three(0)),
            Space::Descriptor(d) => Trajectory::descriptors(t, &flat(), d, true),
            Space::Euclid(d) => Trajectory::descriptors(t, &flat(), d, false),
        }
    }

    /// A point from a seed; `scale` for unbounded coordinates (positions, heights).
    fn random_point(self, seed: &Seed, scale: f64) -> Vec<f64> {
        let quat = || -> Vec<f64> { unit(&seed[0..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]) };
        match self {
            Space::So3 => quat(),
            Space::Se3 { .. } => {
                [seed[4] * scale, seed[5] * scale, seed[6] * scale].into_iter().chain(quat()).collect()
            }
            Space::Se2 { .. } => vec![seed[0] * scale, seed[1] * scale, seed[2] * 3.0 * PI],
            Space::Torus(k) => seed[..k].iter().map(|a| a * 3.0 * PI).collect(),
            Space::Sphere { .. } => unit(&seed[..3]).unwrap_or_else(|| vec![0.0, 0.0, 1.0]),
            Space::Gnss => vec![seed[0] * 90.0, seed[1] * 540.0, seed[2] * scale.min(1e4)],
            Space::Descriptor(d) => {
                let v = unit(&seed[..d]).unwrap_or_else(|| (0..d).map(|i| f64::from(i == 0)).collect());
                v.iter().map(|x| 3.0 * x).collect()
            }
            Space::Euclid(d) => seed[..d].iter().map(|x| x * scale).collect(),
        }
    }

    /// The point `len` (about, in the metric's unit) from `p` along the geodesic with direction
    /// `dir`; points on one geodesic for a fixed `dir` and growing `len`. Quaternions flip sign
    /// when `dir[7] > 0.8`, longitudes jump by ±360° when `|dir[6]| > 0.9`: same points.
    fn step(self, p: &[f64], dir: &Seed, len: f64) -> Vec<f64> {
        let rotate = |q: &[f64], omega: [f64; 3]| -> Vec<f64> {
            let q = quat_mul([q[0], q[1], q[2], q[3]], quat_exp(omega));
            let sign = if dir[7] > 0.8 { -1.0 } else { 1.0 };
            q.iter().map(|v| sign * v).collect()
        };
        match self {
            Space::So3 => {
                let u = unit(&dir[..3]).unwrap_or_else(|| vec![1.0, 0.0, 0.0]);
                rotate(p, [u[0] * len, u[1] * len, u[2] * len])
            }
            Space::Se3 { radians_per_m } => {
                let u = unit(&dir[..6]).unwrap_or_else(|| vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
                let r = len * radians_per_m;
                let position = (0..3).map(|k| p[k] + u[k] * len);
                position.chain(rotate(&p[3..], [u[3] * r, u[4] * r, u[5] * r])).collect()
            }
            Space::Se2 { radians_per_m } => {
                let u = unit(&dir[..3]).unwrap_or_else(|| vec![1.0, 0.0, 0.0]);
                vec![p[0] + u[0] * len, p[1] + u[1] * len, p[2] + u[2] * len * radians_per_m]
            }
            Space::Torus(k) => {
                let u = unit(&dir[..k]).unwrap_or_else(|| (0..k).map(|i| f64::from(i == 0)).collect());
                p.iter().zip(u).map(|(a, du)| a + du * len).collect()
            }
            Space::Sphere { radius } => great_circle_step(p, &dir[..3], len / radius),
            Space::Gnss => {
                // Part along the surface, part up or down (the metric is their L2 combination).
                let tilt = dir[3] * FRAC_PI_4;
                let (surface_m, up_m) = (len * tilt.cos(), len * tilt.sin());
                let n = lat_lon_to_unit(p[0], p[1]);
                let moved = great_circle_step(&n, &dir[..3], surface_m / EARTH_RADIUS_M);
                let lat = moved[2].clamp(-1.0, 1.0).asin().to_degrees();
                let lon = moved[1].atan2(moved[0]).to_degrees();
                // Keep longitudes continuous (beyond ±180°), with the odd jump of a turn.
                let mut lon = p[1] + (lon - p[1] + 180.0).rem_euclid(360.0) - 180.0;
                if dir[6] > 0.9 {
                    lon += 360.0;
                } else if dir[6] < -0.9 {
                    lon -= 360.0;
                }
                vec![lat, lon, p[2] + up_m]
            }
            Space::Descriptor(1) => {
                if (dir[0] * len).abs() > FRAC_PI_2 {
                    vec![-p[0]]
                } else {
                    p.to_vec()
                }
            }
            Space::Descriptor(d) => {
                let moved = great_circle_step(p, &dir[..d], len);
                moved.iter().map(|x| x * (2.0 + dir[0])).collect()
            }
            Space::Euclid(d) => {
                let u = unit(&dir[..d]).unwrap_or_else(|| (0..d).map(|i| f64::from(i == 0)).collect());
                p.iter().zip(u).map(|(x, du)| x + du * len).collect()
            }
        }
    }
}

/// Rotates the direction of `p` by `angle` towards `dir` (its part orthogonal to `p`), on the
/// unit sphere of p's dimension.
fn great_circle_step(p: &[f64], dir: &[f64], angle: f64) -> Vec<f64> {
    let n = unit(p).expect("non-zero point");
    let along = dot(dir, &n);
    let tangent: Vec<f64> = dir.iter().zip(&n).map(|(d, x)| d - along * x).collect();
    let u = unit(&tangent).unwrap_or_else(|| {
        // `dir` parallel to `p`: any orthogonal direction.
        let k = if n[0].abs() < 0.9 { 0 } else { 1 };
        let e: Vec<f64> = (0..n.len()).map(|i| f64::from(i == k)).collect();
        let along = dot(&e, &n);
        unit(&e.iter().zip(&n).map(|(e, x)| e - along * x).collect::<Vec<_>>()).expect("orthogonal")
    });
    n.iter().zip(&u).map(|(x, t)| angle.cos() * x + angle.sin() * t).collect()
}

// =============================================================================================
// 1. Metric axioms
// =============================================================================================

/// A metric under test, with the space its points live in and its diameter (0 if unbounded).
struct Subject {
    metric: Box<dyn Metric>,
    space: Space,
    diameter: f64,
}

fn subject(metric: impl Metric + 'static, space: Space, diameter: f64) -> Subject {
    Subject { metric: Box::new(metric), space, diameter }
}

const CHORDAL_DIAMETER: f64 = 2.0 * SQRT_2;

/// Every metric of the crate, in several parametrisations.
fn subjects() -> Vec<Subject> {
    use RotationDistance::{Chordal, Geodesic};
    let mut all = vec![
        subject(So3 { rotation: Geodesic }, Space::So3, PI),
        subject(So3 { rotation: Chordal }, Space::So3, CHORDAL_DIAMETER),
        subject(Se3Rotation { rotation: Geodesic }, Space::Se3 { radians_per_m: 1.0 }, PI),
        subject(Se3Rotation { rotation: Chordal }, Space::Se3 { radians_per_m: 1.0 }, CHORDAL_DIAMETER),
        subject(Sphere { radius: 1.0 }, Space::Sphere { radius: 1.0 }, PI),
        subject(Sphere { radius: EARTH_RADIUS_M }, Space::Sphere { radius: EARTH_RADIUS_M }, PI * EARTH_RADIUS_M),
        subject(Haversine::default(), Space::Gnss, PI * EARTH_RADIUS_M),
        subject(Haversine { radius_m: 1.0 }, Space::Gnss, PI),
    ];
    for w in [0.0, 1e-3, 1.0, 10.0, 1e3] {
        for (rotation, diameter) in [(Geodesic, PI), (Chordal, CHORDAL_DIAMETER)] {
            let metric = Se3 { rotation_weight_m_per_rad: w, rotation };
            all.push(subject(metric, Space::Se3 { radians_per_m: 1.0 / w.max(0.1) }, w * diameter));
        }
    }
    for w in [0.0, 0.5, 10.0] {
        all.push(subject(Se2 { rotation_weight_m_per_rad: w }, Space::Se2 { radians_per_m: 1.0 / w.max(0.1) }, w * PI));
    }
    for k in 1..=4 {
        all.push(subject(Torus, Space::Torus(k), PI * (k as f64).sqrt()));
    }
    for d in [1, 2, 3, 8] {
        all.push(subject(Angular, Space::Descriptor(d), PI));
        all.push(subject(Euclidean, Space::Euclid(d), 0.0));
    }
    all
}

/// Adversarial points of each space (raw constructor input).
fn adversarial(space: Space) -> Vec<Vec<f64>> {
    let q = |v: Quat| v.to_vec();
    let generic = unit(&[0.1, -0.2, 0.3, 0.9]).unwrap();
    let rotations = || {
        vec![
            q([0.0, 0.0, 0.0, 1.0]),
            q([0.0, 0.0, 0.0, -1.0]),
            q([1.0, 0.0, 0.0, 0.0]),
            q([-1.0, 0.0, 0.0, 0.0]),
            q([0.0, 1.0, 0.0, 0.0]),
            q([0.0, 0.0, 1.0, 0.0]),
            q(axis_angle([1.0, 0.0, 0.0], PI - 1e-9)),
            q(axis_angle([1.0, 0.0, 0.0], PI - 1e-12)),
            q(axis_angle([1.0, 0.0, 0.0], PI + 1e-12)),
            q(axis_angle([1.0, 1.0, 1.0], PI - 1e-9)),
            q(axis_angle([1.0, 1.0, 1.0], PI)),
            q(axis_angle([0.0, 0.0, 1.0], 1e-9)),
            q(axis_angle([0.0, 1.0, 0.0], 1e-12)),
            q(axis_angle([1.0, 0.0, 0.0], 7.0 * PI / 8.0)),
            q(axis_angle([-1.0, 0.0, 0.0], 7.0 * PI / 8.0)),
            q(axis_angle([0.0, 1.0, 0.0], FRAC_PI_2)),
            q(axis_angle([1.0, 0.0, 0.0], TAU - 1e-9)),
            generic.clone(),
            generic.iter().map(|v| -v).collect(),
            vec![generic[0], generic[1], generic[2], -generic[3]],
        ]
    };
    let angles = [
        0.0,
        PI,
        -PI,
        PI - 1e-12,
        -PI + 1e-12,
        PI + 1e-12,
        1e-12,
        -1e-12,
        FRAC_PI_2,
        TAU,
        3.0 * PI,
        0.875 * PI,
        -0.875 * PI,
        1.0,
    ];
    // Deterministic combinations of the angle list for k > 1.
    let combos = |k: usize, count: usize| -> Vec<Vec<f64>> {
        (0..count).map(|i| (0..k).map(|j| angles[(i * (2 * j + 1) + 5 * j) % angles.len()]).collect()).collect()
    };
    match space {
        Space::So3 => rotations(),
        Space::Se3 { .. } => {
            let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1e6, -1e6, 3.0], [1e6, -1e6, 3.0 + 1e-9]];
            let rotations = rotations();
            let picks = [0, 1, 2, 6, 7, 17, 18, 19];
            positions
                .iter()
                .flat_map(|p| picks.iter().map(|&k| p.iter().copied().chain(rotations[k].iter().copied()).collect()))
                .collect()
        }
        Space::Se2 { .. } => {
            let positions = [[0.0, 0.0], [3.0, 4.0], [1e6, 1e6 + 1e-9]];
            positions.iter().flat_map(|p| angles.iter().map(|&a| vec![p[0], p[1], a])).collect()
        }
        Space::Torus(1) => angles.iter().map(|&a| vec![a]).collect(),
        Space::Torus(k) => combos(k, 28),
        Space::Sphere { .. } => {
            let mut points: Vec<Vec<f64>> = [
                [90.0, 0.0],
                [90.0, 123.0],
                [-90.0, 0.0],
                [-90.0, -45.0],
                [0.0, 0.0],
                [0.0, 180.0],
                [0.0, -180.0],
                [0.0, 179.9999],
                [0.0, -179.9999],
                [45.0, 90.0],
                [-45.0, -90.0],
            ]
            .iter()
            .map(|&[lat, lon]| lat_lon_to_unit(lat, lon).to_vec())
            .collect();
            points.extend(
                [
                    [1.0, 0.0, 0.0],
                    [-1.0, 0.0, 0.0],
                    [1.0, 1e-9, 0.0],
                    [-1.0, 1e-9, 0.0],
                    [0.0, 0.0, -1.0],
                    [1e-10, 0.0, 0.0],
                    [3.0, -4.0, 12.0],
                ]
                .map(|v| v.to_vec()),
            );
            points
        }
        Space::Gnss => [
            [90.0, 0.0, 0.0],
            [90.0, 123.0, 0.0],
            [90.0, 0.0, 100.0],
            [-90.0, -45.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 180.0, 0.0],
            [0.0, -180.0, 0.0],
            [0.0, 179.9999, 0.0],
            [0.0, -179.9999, 0.0],
            [0.0, 540.0, 0.0],
            [45.0, 180.0, -50.0],
            [45.0, -180.0, 0.0],
            [-45.0, -179.9999, 10.0],
            [0.0, 90.0, 0.0],
            [89.9999999, 0.0, 0.0],
            [1e-7, 1e-7, 0.0],
        ]
        .map(|v| v.to_vec())
        .to_vec(),
        Space::Descriptor(1) => vec![vec![1.0], vec![-1.0], vec![3.0], vec![-1e-10]],
        Space::Descriptor(d) => {
            let e = |i: usize, scale: f64| -> Vec<f64> { (0..d).map(|k| if k == i { scale } else { 0.0 }).collect() };
            let mut nearly = e(0, 1.0);
            nearly[1] = 1e-9;
            let mut nearly_anti = e(0, -1.0);
            nearly_anti[1] = 1e-9;
            let ones = vec![1.0; d];
            let alternating: Vec<f64> = (0..d).map(|k| if k % 2 == 0 { 1.0 } else { -1.0 }).collect();
            vec![
                e(0, 1.0),
                e(0, -1.0),
                e(0, 2.5),
                e(1, 1.0),
                e(d - 1, -7.0),
                nearly,
                nearly_anti,
                ones.clone(),
                ones.iter().map(|x| -x).collect(),
                alternating,
            ]
        }
        Space::Euclid(d) => {
            let fill = |v: f64| vec![v; d];
            let mut offset = fill(1e8);
            offset[0] += 1e-8;
            vec![fill(0.0), fill(1.0), fill(-1.0), fill(1e8), offset, fill(-1e8), fill(1e-300)]
        }
    }
}

/// Identity, symmetry and the triangle inequality δ(a, c) ≤ δ(a, b) + δ(b, c) + 1e-9 · scale on
/// every ordered triple of the points of `traj`, with scale the metric's diameter or (where
/// unbounded) the size of the coordinates.
fn check_axioms(subject: &Subject, traj: &Trajectory) -> Result<(), String> {
    let n = traj.len();
    let name = subject.metric.name();
    let d: Vec<Vec<f64>> =
        (0..n).map(|i| (0..n).map(|j| subject.metric.distance(traj.point(i), traj.point(j))).collect()).collect();
    let size: Vec<f64> = (0..n).map(|i| traj.point(i).iter().fold(0.0_f64, |m, v| m.max(v.abs()))).collect();
    for (i, row) in d.iter().enumerate() {
        if row[i].is_nan() || row[i].abs() > 1e-12 {
            return Err(format!("{name}: δ(a, a) = {:e} for a = {:?}", row[i], traj.point(i)));
        }
        for (j, &ab) in row.iter().enumerate() {
            let ba = d[j][i];
            if ab.is_nan() || ab < 0.0 || ab.is_infinite() || (ab - ba).abs() > 1e-12 * ab.max(1.0) {
                return Err(format!(
                    "{name}: δ(a, b) = {ab:e}, δ(b, a) = {ba:e} for {:?}, {:?}",
                    traj.point(i),
                    traj.point(j)
                ));
            }
        }
    }
    for a in 0..n {
        for b in 0..n {
            for c in 0..n {
                let scale = subject.diameter.max(1.0 + size[a].max(size[b]).max(size[c]));
                let (ac, ab, bc) = (d[a][c], d[a][b], d[b][c]);
                if ac > ab + bc + 1e-9 * scale {
                    return Err(format!(
                        "{name}: triangle inequality broken by {:e}: δ(a, c) = {ac:e} > δ(a, b) + δ(b, c) = {ab:e} + {bc:e}\n  a = {:?}\n  b = {:?}\n  c = {:?}",
                        ac - ab - bc,
                        traj.point(a),
                        traj.point(b),
                        traj.point(c)
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Every ordered triple of the adversarial points of every metric.
#[test]
fn axioms_hold_on_adversarial_points() {
    for subject in subjects() {
        let raw = adversarial(subject.space);
        let traj = subject.space.build(&raw).unwrap_or_else(|e| panic!("{:?}: {e}", subject.space));
        subject.metric.validate(&traj).unwrap();
        if let Err(message) = check_axioms(&subject, &traj) {
            panic!("{message}");
        }
    }
    // The other constructor routes: rotation vectors (past ±π, 2π, opposite axes) and latitude
    // and longitude on the sphere (poles, the date line).
    let vectors = [
        [0.0, 0.0, 0.0],
        [PI, 0.0, 0.0],
        [-PI, 0.0, 0.0],
        [PI - 1e-9, 0.0, 0.0],
        [PI + 1e-12, 0.0, 0.0],
        [-(PI - 1e-12), 0.0, 0.0],
        [TAU, 0.0, 0.0],
        [TAU - 1e-9, 0.0, 0.0],
        [0.875 * PI, 0.0, 0.0],
        [-0.875 * PI, 0.0, 0.0],
        [0.0, 0.875 * PI, 0.0],
        [1e-12, 0.0, 0.0],
        [0.0, 0.0, 1e-9],
        [1.0, -2.0, 2.0],
    ];
    let rotations = Trajectory::so3_from_rotation_vectors(times(vectors.len()), &vectors).unwrap();
    let lat_lon = [
        [90.0, 0.0],
        [90.0, 123.0],
        [-90.0, 0.0],
        [0.0, 179.9999],
        [0.0, -179.9999],
        [0.0, 0.0],
        [0.0, 180.0],
        [0.0, 540.0],
    ];
    let sphere = Trajectory::sphere_from_lat_lon(times(lat_lon.len()), &lat_lon).unwrap();
    for subject in subjects() {
        let traj = match subject.space {
            Space::So3 => &rotations,
            Space::Sphere { .. } => &sphere,
            _ => continue,
        };
        if let Err(message) = check_axioms(&subject, traj) {
            panic!("{message}");
        }
    }
}

/// Different representations of one point are at distance 0 (within 1e-12 of the diameter).
#[test]
fn one_point_in_two_representations_is_at_distance_zero() {
    use RotationDistance::{Chordal, Geodesic};
    let g = unit(&[0.1, -0.2, 0.3, 0.9]).unwrap();
    let so3 = Trajectory::so3(times(2), &[[g[0], g[1], g[2], g[3]], [-g[0], -g[1], -g[2], -g[3]]]).unwrap();
    let vectors = Trajectory::so3_from_rotation_vectors(
        times(6),
        &[[PI, 0.0, 0.0], [-PI, 0.0, 0.0], [TAU, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 3.0 * PI, 0.0], [0.0, -PI, 0.0]],
    )
    .unwrap();
    for rotation in [Geodesic, Chordal] {
        let metric = So3 { rotation };
        assert_eq!(metric.distance(so3.point(0), so3.point(1)), 0.0, "q and −q");
        for (a, b) in [(0, 1), (2, 3), (4, 5)] {
            let d = metric.distance(vectors.point(a), vectors.point(b));
            assert!(d <= 1e-12, "{rotation:?}: rotation vectors {a} and {b} are one rotation, δ = {d:e}");
        }
    }
    let se2 =
        Trajectory::se2(times(4), &[[1.0, 2.0, PI], [1.0, 2.0, -PI], [1.0, 2.0, 3.0 * PI], [1.0, 2.0, -5.0 * PI]])
            .unwrap();
    let torus =
        Trajectory::torus(times(3), &[PI, -PI, 0.5, -PI, PI, 0.5 + TAU, 3.0 * PI, -3.0 * PI, 0.5 - 4.0 * PI], 3)
            .unwrap();
    for i in 0..4 {
        for j in 0..4 {
            assert!(Se2 { rotation_weight_m_per_rad: 10.0 }.distance(se2.point(i), se2.point(j)) <= 1e-12);
            if i < 3 && j < 3 {
                assert!(Torus.distance(torus.point(i), torus.point(j)) <= 1e-12);
            }
        }
    }
    // The poles at any longitude; one longitude and another a turn away.
    let gnss =
        Trajectory::gnss(times(4), &[[90.0, 0.0, 5.0], [90.0, 123.0, 5.0], [-30.0, 170.0, 0.0], [-30.0, -190.0, 0.0]])
            .unwrap();
    let pole_m = Haversine::default().distance(gnss.point(0), gnss.point(1));
    assert!(pole_m <= 1e-12 * PI * EARTH_RADIUS_M, "north pole at two longitudes: {pole_m:e} m");
    assert!(Haversine::default().distance(gnss.point(2), gnss.point(3)) <= 1e-12 * PI * EARTH_RADIUS_M);
    let sphere =
        Trajectory::sphere_from_lat_lon(times(4), &[[-90.0, 0.0], [-90.0, 77.0], [0.0, 180.0], [0.0, -180.0]]).unwrap();
    assert!(Sphere { radius: 1.0 }.distance(sphere.point(0), sphere.point(1)) <= 1e-12);
    assert!(Sphere { radius: 1.0 }.distance(sphere.point(2), sphere.point(3)) <= 1e-12);
    let descriptors = Trajectory::descriptors(times(2), &[1.0, -2.0, 3.0, 2.5, -5.0, 7.5], 3, true).unwrap();
    assert!(Angular.distance(descriptors.point(0), descriptors.point(1)) <= 1e-12, "a descriptor and 2.5 times it");
}

/// Three points: random, adversarial or on one geodesic (the tight case of the triangle
/// inequality).
#[derive(Debug, Clone)]
struct Triple {
    seeds: [Seed; 3],
    picks: [usize; 3],
    direction: Seed,
    length: f64,
    fraction: f64,
    far: bool,
}

fn seed() -> impl Strategy<Value = Seed> {
    prop::array::uniform8(-1.0..1.0_f64)
}

fn triple() -> impl Strategy<Value = Triple> {
    (
        prop::array::uniform3(seed()),
        prop::array::uniform3(0..64_usize),
        seed(),
        0.0..1.0_f64,
        0.0..1.0_f64,
        any::<bool>(),
    )
        .prop_map(|(seeds, picks, direction, length, fraction, far)| Triple {
            seeds,
            picks,
            direction,
            length,
            fraction,
            far,
        })
}

fn check_random_triples(subject: &Subject, seed: u64) {
    let adversarial = adversarial(subject.space);
    let space = subject.space;
    // Geodesics up to 3.5 half turns long (past the cut locus), or 100 m where unbounded.
    let reach = match space {
        Space::So3 | Space::Torus(_) | Space::Descriptor(_) => 3.5 * PI,
        Space::Sphere { radius } => 3.5 * PI * radius,
        Space::Gnss => 3.5 * PI * EARTH_RADIUS_M,
        Space::Se3 { .. } | Space::Se2 { .. } | Space::Euclid(_) => 100.0,
    };
    let mut runner = TestRunner::new(config(256, seed));
    let result = runner.run(&triple(), |t| {
        let scale = if t.far { 1e6 } else { 10.0 };
        let point = |k: usize| match adversarial.get(t.picks[k]) {
            Some(p) if t.picks[k] % 2 == 0 => p.clone(),
            _ => space.random_point(&t.seeds[k], scale),
        };
        let (a, b, c) = (point(0), point(1), point(2));
        let len = t.length * reach;
        let on_geodesic =
            [a.clone(), space.step(&a, &t.direction, t.fraction * len), space.step(&a, &t.direction, len)];
        let near = [b.clone(), space.step(&b, &t.direction, 1e-9 * len), c.clone()];
        for raw in [vec![a, b, c], on_geodesic.to_vec(), near.to_vec()] {
            let traj = space.build(&raw).map_err(|e| TestCaseError::fail(format!("building {raw:?}: {e}")))?;
            check_axioms(subject, &traj).map_err(TestCaseError::fail)?;
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{}: {e}", subject.metric.name());
    }
}

/// Random triples, each point random or adversarial, and triples on one geodesic.
#[test]
fn axioms_hold_on_random_and_geodesic_triples() {
    for (k, subject) in subjects().iter().enumerate() {
        check_random_triples(subject, 0xA110_0000 + k as u64);
    }
}

// =============================================================================================
// 2. Values against independent formulas
// =============================================================================================

fn so3_pair(a: Quat, b: Quat) -> Trajectory {
    Trajectory::so3(times(2), &[a, b]).unwrap()
}

fn so3_distances(traj: &Trajectory) -> (f64, f64) {
    let geodesic = So3 { rotation: RotationDistance::Geodesic }.distance(traj.point(0), traj.point(1));
    let chordal = So3 { rotation: RotationDistance::Chordal }.distance(traj.point(0), traj.point(1));
    (geodesic, chordal)
}

proptest! {
    #![proptest_config(config(1024, 0x5003_0001))]

    /// Geodesic angle acos((tr(R_aᵀ R_b) − 1) / 2) where acos is well conditioned, and Frobenius
    /// distance ‖R_a − R_b‖_F everywhere, from matrices built by the standard formula.
    #[test]
    fn so3_matches_rotation_matrices(a in seed(), b in seed(), flip in any::<bool>()) {
        let qa = unit(&a[..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
        let qb = unit(&b[..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
        let sign = if flip { -1.0 } else { 1.0 };
        let (qa, qb) = ([qa[0], qa[1], qa[2], qa[3]], [sign * qb[0], sign * qb[1], sign * qb[2], sign * qb[3]]);
        let (ra, rb) = (rotation_matrix(qa), rotation_matrix(qb));
        let (geodesic, chordal) = so3_distances(&so3_pair(qa, qb));
        let cos = cos_angle_between(&ra, &rb);
        if cos.abs() <= 0.9 {
            prop_assert!((geodesic - cos.acos()).abs() <= 1e-9, "geodesic {} vs acos {}", geodesic, cos.acos());
        }
        prop_assert!((geodesic - relative_angle(qa, qb)).abs() <= 1e-12);
        let frob = frobenius(&ra, &rb);
        prop_assert!((chordal - frob).abs() <= 1e-9, "chordal {} vs Frobenius {}", chordal, frob);
        // ‖I − R_a R_bᵀ‖_F, the paper's form, is the same number.
        let rbt = [[rb[0][0], rb[1][0], rb[2][0]], [rb[0][1], rb[1][1], rb[2][1]], [rb[0][2], rb[1][2], rb[2][2]]];
        let product: Mat3 =
            std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| ra[i][k] * rbt[k][j]).sum()));
        let identity: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| f64::from(i == j)));
        prop_assert!((chordal - frobenius(&identity, &product)).abs() <= 1e-9);
    }

    /// Rotations composed with a known relative rotation: the distances are that angle θ and
    /// 2√2 sin(θ/2).
    #[test]
    fn so3_relative_rotation_of_known_angle(base in seed(), axis in seed(), angle in 0.0..PI) {
        let q = unit(&base[..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
        let q = [q[0], q[1], q[2], q[3]];
        let axis = unit(&axis[..3]).unwrap_or_else(|| vec![0.0, 0.0, 1.0]);
        let moved = quat_mul(q, axis_angle([axis[0], axis[1], axis[2]], angle));
        let (geodesic, chordal) = so3_distances(&so3_pair(q, moved));
        prop_assert!((geodesic - angle).abs() <= 1e-12, "{} vs {}", geodesic, angle);
        prop_assert!((chordal - 2.0 * SQRT_2 * (angle / 2.0).sin()).abs() <= 1e-12);
    }
}

/// Near 0 and near π, where acos is useless, against the closed forms.
#[test]
fn so3_near_zero_and_near_pi_closed_forms() {
    let base = unit(&[0.3, -0.5, 0.1, 0.8]).unwrap();
    let base = [base[0], base[1], base[2], base[3]];
    for axis in [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, -2.0, 3.0]] {
        for angle in [0.0, 1e-12, 1e-9, 1e-6, FRAC_PI_2, PI - 1e-6, PI - 1e-9, PI - 1e-12, PI] {
            let relative = axis_angle(axis, angle);
            for (a, b) in [([0.0, 0.0, 0.0, 1.0], relative), (base, quat_mul(base, relative))] {
                let (geodesic, chordal) = so3_distances(&so3_pair(a, b));
                assert!((geodesic - angle).abs() <= 1e-12, "axis {axis:?}, θ = {angle}: geodesic {geodesic}");
                let expected = 2.0 * SQRT_2 * (angle / 2.0).sin();
                assert!(
                    (chordal - expected).abs() <= 1e-12,
                    "axis {axis:?}, θ = {angle}: chordal {chordal} vs {expected}"
                );
                let from_vectors = Trajectory::so3_from_rotation_vectors(
                    times(2),
                    &[[0.0; 3], {
                        let n = norm(&axis);
                        [axis[0] / n * angle, axis[1] / n * angle, axis[2] / n * angle]
                    }],
                )
                .unwrap();
                let (g, _) = so3_distances(&from_vectors);
                assert!((g - angle).abs() <= 1e-12, "rotation vector of length {angle}: {g}");
            }
        }
    }
    // Half turns about orthogonal axes differ by a half turn about the third.
    let (geodesic, chordal) = so3_distances(&so3_pair([1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]));
    assert_eq!(geodesic, PI);
    assert!((chordal - 2.0 * SQRT_2).abs() <= 1e-15, "{chordal}");
    // (x, y, z, −w) is R⁻¹: the angle between R(θ) and R(−θ) is 2θ, or 2π − 2θ past a half turn.
    for angle in [PI / 6.0, PI / 3.0, FRAC_PI_2, 2.0 * PI / 3.0, 5.0 * PI / 6.0, PI - 1e-9] {
        let q = axis_angle([1.0, 2.0, -2.0], angle);
        let (geodesic, _) = so3_distances(&so3_pair(q, [q[0], q[1], q[2], -q[3]]));
        let expected = (2.0 * angle).min(TAU - 2.0 * angle);
        assert!((geodesic - expected).abs() <= 1e-12, "θ = {angle}: {geodesic} vs {expected}");
    }
}

/// The rotation-vector constructor and the quaternion constructor agree.
#[test]
fn rotation_vectors_are_the_quaternions_of_axis_angle() {
    let vectors =
        [[0.0, 0.0, 0.0], [1e-12, 0.0, 0.0], [0.3, -0.4, 1.2], [PI, 0.0, 0.0], [0.0, -2.9, 0.0], [5.0, 5.0, 5.0]];
    let from_vectors = Trajectory::so3_from_rotation_vectors(times(vectors.len()), &vectors).unwrap();
    let from_quaternions = Trajectory::so3(times(vectors.len()), &vectors.map(quat_exp)).unwrap();
    for (i, v) in vectors.iter().enumerate() {
        let d = So3::default().distance(from_vectors.point(i), from_quaternions.point(i));
        assert!(d <= 1e-12, "{v:?}: {d:e}");
    }
}

proptest! {
    #![proptest_config(config(1024, 0x5003_0002))]

    /// Haversine against the textbook formula (away from antipodes, where asin is ill
    /// conditioned) and against the great-circle angle of unit vectors; heights in L2.
    #[test]
    fn haversine_matches_the_textbook(a in seed(), b in seed()) {
        let (lat1, lon1, lat2, lon2) = (a[0] * 90.0, a[1] * 540.0, b[0] * 90.0, b[1] * 540.0);
        let (h1, h2) = (a[2] * 1e4, b[2] * 1e4);
        let traj = Trajectory::gnss(times(2), &[[lat1, lon1, h1], [lat2, lon2, h2]]).unwrap();
        let surface = Trajectory::gnss(times(2), &[[lat1, lon1, 0.0], [lat2, lon2, 0.0]]).unwrap();
        let metric = Haversine::default();
        let d_surface = metric.distance(surface.point(0), surface.point(1));
        let angle = great_circle_angle(&lat_lon_to_unit(lat1, lon1), &lat_lon_to_unit(lat2, lon2));
        prop_assert!((d_surface - EARTH_RADIUS_M * angle).abs() <= 1e-6, "{} vs {}", d_surface, EARTH_RADIUS_M * angle);
        if angle < 0.99 * PI {
            let textbook = haversine_textbook_m(lat1, lon1, lat2, lon2);
            prop_assert!((d_surface - textbook).abs() <= 1e-6, "{} vs textbook {}", d_surface, textbook);
        }
        let d = metric.distance(traj.point(0), traj.point(1));
        prop_assert!((d - d_surface.hypot(h1 - h2)).abs() <= 1e-6);
    }

    /// The torus distance is the brute-force least distance over 2π shifts of every angle.
    #[test]
    fn torus_matches_shifts_by_whole_turns(a in seed(), b in seed(), k in 1..=4_usize, far in any::<bool>()) {
        let spread = if far { 12.0 * PI } else { 1.2 * PI };
        let a: Vec<f64> = a[..k].iter().map(|x| x * spread).collect();
        let b: Vec<f64> = b[..k].iter().map(|x| x * spread).collect();
        let traj = Trajectory::torus(times(2), &[a.clone(), b.clone()].concat(), k).unwrap();
        let d = Torus.distance(traj.point(0), traj.point(1));
        prop_assert!((d - torus_brute_force(&a, &b)).abs() <= 1e-12, "{} vs {}", d, torus_brute_force(&a, &b));
    }

    /// SE(3) and SE(2) are the weighted sums of their definitions; the rotation parts come from
    /// rotation matrices and least angular differences computed here.
    #[test]
    fn se3_and_se2_are_weighted_sums(a in seed(), b in seed(), w in 0.0..20.0_f64) {
        let qa = unit(&a[..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
        let qb = unit(&b[..4]).unwrap_or_else(|| vec![0.0, 0.0, 0.0, 1.0]);
        let (qa, qb) = ([qa[0], qa[1], qa[2], qa[3]], [qb[0], qb[1], qb[2], qb[3]]);
        let (pa, pb) = ([a[4] * 50.0, a[5] * 50.0, a[6] * 50.0], [b[4] * 50.0, b[5] * 50.0, b[6] * 50.0]);
        let traj = Trajectory::se3(times(2), &[pa, pb], &[qa, qb]).unwrap();
        let translation = norm(&[pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]]);
        let frob = frobenius(&rotation_matrix(qa), &rotation_matrix(qb));
        let geodesic = relative_angle(qa, qb);
        let cases = [(RotationDistance::Geodesic, geodesic), (RotationDistance::Chordal, frob)];
        for (rotation, rot) in cases {
            let d = Se3 { rotation_weight_m_per_rad: w, rotation }.distance(traj.point(0), traj.point(1));
            let expected = translation + w * rot;
            prop_assert!((d - expected).abs() <= 1e-9 * (1.0 + d), "{:?}: {} vs {}", rotation, d, expected);
            let d = Se3Rotation { rotation }.distance(traj.point(0), traj.point(1));
            prop_assert!((d - rot).abs() <= 1e-9);
        }
        let (ta, tb) = (a[7] * 4.0 * PI, b[7] * 4.0 * PI);
        let planar = Trajectory::se2(times(2), &[[pa[0], pa[1], ta], [pb[0], pb[1], tb]]).unwrap();
        let expected = (pa[0] - pb[0]).hypot(pa[1] - pb[1]) + w * torus_brute_force(&[ta], &[tb]);
        let d = Se2 { rotation_weight_m_per_rad: w }.distance(planar.point(0), planar.point(1));
        prop_assert!((d - expected).abs() <= 1e-9 * (1.0 + d), "{} vs {}", d, expected);
    }

    /// The angular distance of descriptors is acos of the cosine similarity (where acos is well
    /// conditioned) whatever their lengths.
    #[test]
    fn angular_matches_cosine_similarity(a in seed(), b in seed(), d in 2..=8_usize) {
        let (a, b) = (&a[..d], &b[..d]);
        prop_assume!(norm(a) > 1e-3 && norm(b) > 1e-3);
        let traj = Trajectory::descriptors(times(2), &[a, b].concat(), d, true).unwrap();
        let cos = dot(a, b) / (norm(a) * norm(b));
        let angle = Angular.distance(traj.point(0), traj.point(1));
        if cos.abs() <= 0.9 {
            prop_assert!((angle - cos.acos()).abs() <= 1e-9, "{} vs {}", angle, cos.acos());
        }
        let raw = Trajectory::descriptors(times(2), &[a, b].concat(), d, false).unwrap();
        let l2 = norm(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>());
        prop_assert!((Euclidean.distance(raw.point(0), raw.point(1)) - l2).abs() <= 1e-12);
    }
}

#[test]
fn descriptors_parallel_antiparallel_orthogonal() {
    let rows = [
        [1.0, 2.0, -2.0],
        [2.0, 4.0, -4.0],
        [-0.5, -1.0, 1.0],
        [2.0, 0.0, 1.0],
        [1.0, 1e-9, 0.0],
        [-1.0, 1e-9, 0.0],
        [1.0, 0.0, 0.0],
    ];
    let traj = Trajectory::descriptors(times(rows.len()), rows.as_flattened(), 3, true).unwrap();
    let d = |i: usize, j: usize| Angular.distance(traj.point(i), traj.point(j));
    assert!(d(0, 1) <= 1e-15, "parallel: {}", d(0, 1));
    assert!((d(0, 2) - PI).abs() <= 1e-15, "antiparallel: {}", d(0, 2));
    assert!((d(0, 3) - FRAC_PI_2).abs() <= 1e-15, "orthogonal: {}", d(0, 3));
    assert!((d(4, 6) - 1e-9).abs() <= 1e-20, "nearly parallel: {:e}", d(4, 6));
    assert!((d(5, 6) - (PI - 1e-9)).abs() <= 1e-15, "nearly antiparallel: {}", d(5, 6));
}

/// Known distances: Paris–London, the date line, the poles, a quarter meridian, heights.
#[test]
fn haversine_known_distances() {
    let metric = Haversine::default();
    let d = |a: [f64; 3], b: [f64; 3]| {
        let traj = Trajectory::gnss(times(2), &[a, b]).unwrap();
        metric.distance(traj.point(0), traj.point(1))
    };
    let paris_london = d([48.8566, 2.3522, 0.0], [51.5074, -0.1278, 0.0]);
    assert!((paris_london - 343_500.0).abs() <= 1000.0, "Paris–London {paris_london} m");
    assert!((paris_london - haversine_textbook_m(48.8566, 2.3522, 51.5074, -0.1278)).abs() <= 1e-6);
    // 0.0002° of the equator across the date line, not 359.9998°.
    let date_line = d([0.0, 179.9999, 0.0], [0.0, -179.9999, 0.0]);
    let expected = 6_371_008.8 * 0.0002_f64.to_radians();
    assert!((date_line - expected).abs() <= 1e-6, "date line {date_line} m vs {expected} m");
    assert!((d([0.0, 179.9999, 0.0], [0.0, 180.0001, 0.0]) - expected).abs() <= 1e-6);
    let quarter = 6_371_008.8 * FRAC_PI_2;
    assert!((d([90.0, 0.0, 0.0], [0.0, 37.0, 0.0]) - quarter).abs() <= 1e-6);
    assert!((d([0.0, 0.0, 0.0], [0.0, 90.0, 0.0]) - quarter).abs() <= 1e-6);
    assert!((d([0.0, 0.0, 0.0], [0.0, 180.0, 0.0]) - 2.0 * quarter).abs() <= 1e-6, "exact antipodes");
    assert!((d([90.0, 0.0, 0.0], [-90.0, 10.0, 0.0]) - 2.0 * quarter).abs() <= 1e-6, "pole to pole");
    assert_eq!(d([45.0, 7.0, 0.0], [45.0, 7.0, 100.0]), 100.0);
    let slant = d([45.0, 7.0, 0.0], [45.0, 7.01, 30.0]);
    assert!((slant - haversine_textbook_m(45.0, 7.0, 45.0, 7.01).hypot(30.0)).abs() <= 1e-6);
}

/// ECEF (WGS 84) straight-line distances between fixes 1 km apart: within 0.5% of the haversine
/// away from the equator, and within 1e-4 of the local ellipsoid arc √((M Δφ)² + (N cos φ Δλ)²)
/// everywhere. (Within ±14° of the equator a north–south kilometre on the ellipsoid is 0.56%
/// shorter than on the mean sphere, M(0) = a(1 − e²) = 6335.4 km: a property of the Earth.)
#[test]
fn ecef_agrees_with_haversine_at_one_kilometre() {
    const A: f64 = 6_378_137.0;
    const F: f64 = 1.0 / 298.257_223_563;
    let e2 = F * (2.0 - F);
    let distance_m = 1000.0;
    for lat in (-80..=80).step_by(10).map(f64::from) {
        for bearing in (0..360).step_by(30).map(|b| f64::from(b).to_radians()) {
            let lon = 179.995; // across the date line for eastward bearings
            // Destination on the sphere (textbook): 1 km along `bearing`.
            let (phi1, delta) = (lat.to_radians(), distance_m / EARTH_RADIUS_M);
            let phi2 = (phi1.sin() * delta.cos() + phi1.cos() * delta.sin() * bearing.cos()).asin();
            let dlambda = (bearing.sin() * delta.sin() * phi1.cos()).atan2(delta.cos() - phi1.sin() * phi2.sin());
            let second = [phi2.to_degrees(), lon + dlambda.to_degrees(), 0.0];
            let fixes = [[lat, lon, 0.0], second];
            let haversine = Trajectory::gnss(times(2), &fixes).unwrap();
            let h = Haversine::default().distance(haversine.point(0), haversine.point(1));
            assert!((h - distance_m).abs() <= 1e-6, "destination formula: {h}");
            let ecef = Trajectory::gnss_ecef(times(2), &fixes).unwrap();
            assert_eq!(ecef.point(0), &[0.0, 0.0, 0.0], "relative to the first fix");
            let straight = Euclidean.distance(ecef.point(0), ecef.point(1));
            let phi = 0.5 * (phi1 + phi2);
            let w = (1.0 - e2 * phi.sin().powi(2)).sqrt();
            let (m, n) = (A * (1.0 - e2) / w.powi(3), A / w);
            let local = (m * (phi2 - phi1)).hypot(n * phi.cos() * dlambda);
            assert!(
                (straight - local).abs() <= 1e-4 * local,
                "lat {lat}, bearing {bearing}: {straight} vs ellipsoid {local}"
            );
            if lat.abs() >= 20.0 {
                assert!(
                    (straight - h).abs() <= 0.005 * h,
                    "lat {lat}, bearing {bearing}: ECEF {straight} vs haversine {h}"
                );
            }
        }
    }
    // Absolute: pole to pole is 2b = 2a(1 − f); a height is a height.
    let poles = Trajectory::gnss_ecef(times(3), &[[90.0, 0.0, 0.0], [-90.0, 45.0, 0.0], [-90.0, 45.0, 250.0]]).unwrap();
    assert!((Euclidean.distance(poles.point(0), poles.point(1)) - 2.0 * A * (1.0 - F)).abs() <= 1e-6);
    assert!((Euclidean.distance(poles.point(1), poles.point(2)) - 250.0).abs() <= 1e-6);
}

// =============================================================================================
// 3. The engine equals the brute force under every metric
// =============================================================================================

/// One piece of a random walk.
#[derive(Debug, Clone)]
enum Move {
    /// One sample `size` γ along `direction`.
    Step { direction: Seed, size: f64 },
    /// `count` more samples at the current point, exactly or jittered by ±1e-9 γ.
    Stay { count: usize, jitter: bool, direction: Seed },
    /// One sample exactly at the point `back` samples ago.
    Revisit { back: usize },
}

#[derive(Debug, Clone)]
struct Walk {
    /// Picks the metric's parameters (weights, dimension, ...).
    variant: u8,
    start: Seed,
    /// Coordinates far from the origin (1e6) where the space has unbounded ones.
    far: bool,
    /// Where γ lies in the metric's range, log-uniformly.
    gamma_fraction: f64,
    moves: Vec<Move>,
}

const MAX_POSES: usize = 300;

fn walk() -> impl Strategy<Value = Walk> {
    let one_move = prop_oneof![
        6 => (seed(), 0.0..0.6_f64).prop_map(|(direction, size)| Move::Step { direction, size }),
        2 => (seed(), 1.0..4.0_f64).prop_map(|(direction, size)| Move::Step { direction, size }),
        1 => (1..20_usize, any::<bool>(), seed())
            .prop_map(|(count, jitter, direction)| Move::Stay { count, jitter, direction }),
        1 => (1..MAX_POSES).prop_map(|back| Move::Revisit { back }),
    ];
    (any::<u8>(), seed(), any::<bool>(), 0.0..1.0_f64, prop::collection::vec(one_move, 1..MAX_POSES))
        .prop_map(|(variant, start, far, gamma_fraction, moves)| Walk { variant, start, far, gamma_fraction, moves })
}

/// The raw points of a walk, at most `MAX_POSES` and at least 2.
fn walk_points(space: Space, walk: &Walk, gamma: f64) -> Vec<Vec<f64>> {
    let scale = if walk.far { 1e6 } else { 10.0 * gamma };
    let mut points = vec![space.random_point(&walk.start, scale)];
    for one_move in &walk.moves {
        let last = points[points.len() - 1].clone();
        match one_move {
            Move::Step { direction, size } => points.push(space.step(&last, direction, size * gamma)),
            Move::Stay { count, jitter, direction } => {
                for k in 0..*count {
                    let wiggle = if k % 2 == 0 { 1e-9 * gamma } else { -1e-9 * gamma };
                    points.push(if *jitter { space.step(&last, direction, wiggle) } else { last.clone() });
                }
            }
            Move::Revisit { back } => points.push(points[points.len() - 1 - (*back).min(points.len() - 1)].clone()),
        }
    }
    if points.len() < 2 {
        points.push(space.step(&points[0], &walk.start, 0.3 * gamma));
    }
    points.truncate(MAX_POSES);
    points
}

/// Input that reproduces a failure: γ and the points as stored.
fn describe(traj: &Trajectory, gamma: f64) -> String {
    format!("gamma = {gamma:?}, dim = {}, coords = {:?}", traj.dim(), traj.coords())
}

/// One metric of the engine tests: the space of its points, the metric, the range of γ.
type Setup = (Space, Box<dyn Metric>, (f64, f64));

fn check_engine(setup: &Setup, walk: &Walk) -> Result<(), TestCaseError> {
    let (space, metric, range) = setup;
    let gamma = range.0 * (range.1 / range.0).powf(walk.gamma_fraction);
    let raw = walk_points(*space, walk, gamma);
    let traj = space.build(&raw).map_err(|e| TestCaseError::fail(format!("building the walk: {e}")))?;
    let set = SublevelSet::compute(&traj, metric.as_ref(), gamma)?;
    let brute = SublevelSet::brute_force(&traj, metric.as_ref(), gamma)?;
    if let Some(i) = (0..traj.len()).find(|&i| set.row(i) != brute.row(i)) {
        return Err(TestCaseError::fail(format!(
            "{}: row {i}: engine {:?}, brute force {:?}\n{}",
            metric.name(),
            set.row(i),
            brute.row(i),
            describe(&traj, gamma)
        )));
    }
    prop_assert_eq!(&set, &brute, "{}: closest columns differ\n{}", metric.name(), describe(&traj, gamma));
    // The same metric by name (statically dispatched), components included.
    let spec: MetricSpec = metric.name().parse()?;
    prop_assert_eq!(spec.find_loops(&traj, gamma)?, Loops::from_set(&traj, metric.as_ref(), brute));
    // Revisits under the metric's own path length, 2γ apart (and half the span in time on odd
    // walks).
    let time_s = if walk.variant % 2 == 1 { 0.5 * traj.span_s() } else { 0.0 };
    let separation = Separation { path: 2.0 * gamma, time_s };
    let set = SublevelSet::compute_separated(&traj, metric.as_ref(), gamma, separation)?;
    let brute = SublevelSet::brute_force_separated(&traj, metric.as_ref(), gamma, separation)?;
    prop_assert_eq!(&set, &brute, "{}: separated by {}\n{}", metric.name(), separation, describe(&traj, gamma));
    let loops = spec.find_loops_separated(&traj, gamma, separation)?;
    prop_assert_eq!(loops, Loops::from_set(&traj, metric.as_ref(), brute));
    Ok(())
}

/// Runs 64 random walks, each under the metric `choose` picks from the walk's variant.
fn engine_equals_brute_force(seed: u64, choose: impl Fn(u8) -> Setup) {
    let mut runner = TestRunner::new(config(64, seed));
    if let Err(e) = runner.run(&walk(), |w| check_engine(&choose(w.variant), &w)) {
        panic!("{e}");
    }
}

const ANGLES: (f64, f64) = (0.02, 3.0);
const METRES: (f64, f64) = (0.05, 20.0);

fn rotation_distance(variant: u8) -> RotationDistance {
    if variant.is_multiple_of(2) { RotationDistance::Geodesic } else { RotationDistance::Chordal }
}

#[test]
fn engine_equals_brute_force_so3_geodesic() {
    engine_equals_brute_force(0xE001, |_| (Space::So3, Box::new(So3 { rotation: RotationDistance::Geodesic }), ANGLES));
}

#[test]
fn engine_equals_brute_force_so3_chordal() {
    engine_equals_brute_force(0xE002, |_| (Space::So3, Box::new(So3 { rotation: RotationDistance::Chordal }), ANGLES));
}

/// Weights 0, 0.1, 1 and 10 m/rad; either rotation distance.
#[test]
fn engine_equals_brute_force_se3() {
    engine_equals_brute_force(0xE011, |v| {
        let w: f64 = [0.0, 0.1, 1.0, 10.0][usize::from(v / 2 % 4)];
        let metric = Se3 { rotation_weight_m_per_rad: w, rotation: rotation_distance(v) };
        (Space::Se3 { radians_per_m: 1.0 / w.max(1.0) }, Box::new(metric), METRES)
    });
}

#[test]
fn engine_equals_brute_force_se3_rotation() {
    engine_equals_brute_force(0xE021, |v| {
        (Space::Se3 { radians_per_m: 1.0 }, Box::new(Se3Rotation { rotation: rotation_distance(v) }), ANGLES)
    });
}

#[test]
fn engine_equals_brute_force_se2() {
    engine_equals_brute_force(0xE031, |v| {
        let w: f64 = [0.0, 0.5, 4.0][usize::from(v % 3)];
        (Space::Se2 { radians_per_m: 1.0 / w.max(1.0) }, Box::new(Se2 { rotation_weight_m_per_rad: w }), METRES)
    });
}

/// S¹ to (S¹)⁴.
#[test]
fn engine_equals_brute_force_torus() {
    engine_equals_brute_force(0xE041, |v| (Space::Torus(1 + usize::from(v % 4)), Box::new(Torus), ANGLES));
}

/// Radius 1 (radians) and 1000.
#[test]
fn engine_equals_brute_force_sphere() {
    engine_equals_brute_force(0xE051, |v| {
        if v % 2 == 0 {
            (Space::Sphere { radius: 1.0 }, Box::new(Sphere { radius: 1.0 }), ANGLES)
        } else {
            (Space::Sphere { radius: 1000.0 }, Box::new(Sphere { radius: 1000.0 }), (20.0, 3000.0))
        }
    });
}

/// γ from 1 m to 3000 km; walks over the poles and the date line, longitudes beyond ±180°.
#[test]
fn engine_equals_brute_force_haversine() {
    engine_equals_brute_force(0xE061, |_| (Space::Gnss, Box::new(Haversine::default()), (1.0, 3e6)));
}

/// Descriptors of dimension 1 to 8.
#[test]
fn engine_equals_brute_force_angular() {
    engine_equals_brute_force(0xE071, |v| (Space::Descriptor(1 + usize::from(v % 8)), Box::new(Angular), ANGLES));
}

/// R¹ to R⁸.
#[test]
fn engine_equals_brute_force_euclidean() {
    engine_equals_brute_force(0xE081, |v| (Space::Euclid(1 + usize::from(v % 8)), Box::new(Euclidean), METRES));
}

/// `find_loops` through a metric given as text, as Python and the CLI give it.
#[test]
fn find_loops_through_a_metric_spec() -> loops_core::Result<()> {
    // 100 m out along x, a U-turn on the spot in 60 steps of 3°, and back.
    let (leg, turn) = (100, 60);
    let mut positions = Vec::new();
    let mut quaternions = Vec::new();
    for i in 0..leg {
        positions.push([i as f64, 0.0, 0.0]);
        quaternions.push(axis_angle([0.0, 0.0, 1.0], 0.0));
    }
    for k in 1..=turn {
        positions.push([(leg - 1) as f64, 0.0, 0.0]);
        quaternions.push(axis_angle([0.0, 0.0, 1.0], PI * k as f64 / turn as f64));
    }
    for i in (0..leg - 1).rev() {
        positions.push([i as f64, 0.0, 0.0]);
        quaternions.push(axis_angle([0.0, 0.0, 1.0], PI));
    }
    let n = positions.len();
    let traj = Trajectory::se3(times(n), &positions, &quaternions)?;
    let spec: MetricSpec = "se3(rotation_weight_m_per_rad=10)".parse()?;
    let loops = spec.find_loops(&traj, 5.0)?;
    let metric = Se3 { rotation_weight_m_per_rad: 10.0, rotation: RotationDistance::Geodesic };
    assert_eq!(loops, find_loops(&traj, &metric, 5.0)?);
    assert!(loops.warnings().is_empty(), "steps of 1 m or 10 m × 3° stay within γ");
    // Heading reversed by π costs 10π m > γ: the way back meets the way out nowhere but at the
    // U-turn itself (one trivial component, the start and the end apart) ...
    assert_eq!(loops.components().len(), 1, "{:?}", loops.components());
    assert!(loops.component_of(0, n - 1).is_none());
    // ... while on positions alone, the start and the end are one place.
    let positions_only = "se3(rotation_weight_m_per_rad=0)".parse::<MetricSpec>()?.find_loops(&traj, 5.0)?;
    assert!(positions_only.component_of(0, n - 1).is_some());
    let flat = Trajectory::from_points(times(n), &positions)?;
    assert_eq!(positions_only.sublevel_set(), find_loops(&flat, &Euclidean, 5.0)?.sublevel_set());
    Ok(())
}

// =============================================================================================
// 4. Bad input
// =============================================================================================

#[test]
fn quaternions_near_unit_length_are_normalised_others_rejected() {
    let q = unit(&[0.2, -0.4, 0.1, 0.85]).unwrap();
    let scaled = |s: f64| [q[0] * s, q[1] * s, q[2] * s, q[3] * s];
    for s in [1.0 + 1e-7, 1.0 - 1e-7, 1.0 + 1e-4, 1.0 - 1e-4] {
        let traj = Trajectory::so3(times(2), &[[0.0, 0.0, 0.0, 1.0], scaled(s)]).unwrap();
        assert!((norm(traj.point(1)) - 1.0).abs() <= 1e-15, "normalised");
        assert!(So3::default().validate(&traj).is_ok());
        let se3 = Trajectory::se3(times(2), &[[0.0; 3], [1.0; 3]], &[[0.0, 0.0, 0.0, 1.0], scaled(s)]).unwrap();
        assert!((norm(&se3.point(1)[3..]) - 1.0).abs() <= 1e-15);
    }
    for s in [1.0 + 1e-2, 1.0 - 1e-2, 0.0, 2.0] {
        let quaternions = [[0.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 0.0], scaled(s)];
        let err = Trajectory::so3(times(3), &quaternions).unwrap_err();
        assert!(matches!(err, Error::NonUnitQuaternion { index: 2, norm } if (norm - s).abs() < 1e-12), "{s}: {err:?}");
        assert!(err.to_string().contains("pose 2"), "{err}");
        let err = Trajectory::se3(times(3), &[[0.0; 3]; 3], &quaternions).unwrap_err();
        assert!(matches!(err, Error::NonUnitQuaternion { index: 2, .. }), "{s}: {err:?}");
    }
    // Handed to a metric directly (no constructor), unit length is checked to 1e-9.
    let raw = Trajectory::new(times(3), [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0], scaled(1.0 + 1e-7)].concat(), 4)
        .unwrap();
    assert!(matches!(find_loops(&raw, &So3::default(), 0.1), Err(Error::NonUnitQuaternion { index: 2, .. })));
    let raw = Trajectory::new(times(2), [[0.0; 7], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]].concat(), 7).unwrap();
    for metric in [
        MetricSpec::Se3(Se3 { rotation_weight_m_per_rad: 1.0, rotation: RotationDistance::Geodesic }),
        MetricSpec::Se3Rotation(Se3Rotation::default()),
    ] {
        assert!(matches!(metric.find_loops(&raw, 0.1), Err(Error::NonUnitQuaternion { index: 0, .. })), "{metric}");
    }
    let err = Trajectory::so3(times(2), &[[0.0, 0.0, 0.0, 1.0], [f64::NAN, 0.0, 0.0, 1.0]]).unwrap_err();
    assert!(matches!(err, Error::NonFiniteCoordinate { index: 1, axis: 0, .. }), "{err:?}");
}

#[test]
fn latitudes_beyond_the_poles_are_rejected() {
    for lat in [90.0 + 1e-9, -90.5, 180.0] {
        let fixes = [[0.0, 0.0, 0.0], [10.0, 10.0, 0.0], [lat, 5.0, 0.0]];
        for err in
            [Trajectory::gnss(times(3), &fixes).unwrap_err(), Trajectory::gnss_ecef(times(3), &fixes).unwrap_err()]
        {
            assert_eq!(err, Error::LatitudeOutOfRange { index: 2, value_deg: lat });
        }
        let err = Trajectory::sphere_from_lat_lon(times(3), &[[0.0, 0.0], [10.0, 10.0], [lat, 5.0]]).unwrap_err();
        assert_eq!(err, Error::LatitudeOutOfRange { index: 2, value_deg: lat });
    }
    for lat in [90.0, -90.0] {
        let traj = Trajectory::gnss(times(2), &[[lat, 0.0, 0.0], [0.0, 0.0, 0.0]]).unwrap();
        assert!(find_loops(&traj, &Haversine::default(), 1.0).is_ok(), "latitude {lat} is a pole, not out of range");
    }
    // Handed to the metric directly, points are unit vectors with a height: a non-unit
    // direction is rejected, naming the pose.
    let raw = Trajectory::new(times(2), vec![1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0], 4).unwrap();
    let err = find_loops(&raw, &Haversine::default(), 1.0).unwrap_err();
    assert_eq!(err, Error::NonUnitVector { index: 1, norm: 2.0 });
}

#[test]
fn zero_and_ragged_vectors_are_rejected() {
    let err = Trajectory::descriptors(times(3), &[1.0, 2.0, 0.0, 0.0, 3.0, 4.0], 2, true).unwrap_err();
    assert_eq!(err, Error::NonUnitVector { index: 1, norm: 0.0 });
    // Unnormalised, a zero descriptor is a point like any other.
    assert!(Trajectory::descriptors(times(3), &[1.0, 2.0, 0.0, 0.0, 3.0, 4.0], 2, false).is_ok());
    // Rows of unequal length cannot be flattened into rows of one dimension.
    let err = Trajectory::descriptors(times(2), &[1.0, 2.0, 3.0, 4.0, 5.0], 3, true).unwrap_err();
    assert_eq!(err, Error::RaggedCoordinates { len: 5, dim: 3 });
    let err = Trajectory::sphere(times(2), &[[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]).unwrap_err();
    assert_eq!(err, Error::NonUnitVector { index: 1, norm: 0.0 });
    // Handed to a metric directly, vectors must be unit to 1e-9.
    let raw = Trajectory::new(times(2), vec![1.0, 0.0, 0.0, 0.0, 1.1, 0.0], 3).unwrap();
    assert!(matches!(find_loops(&raw, &Sphere { radius: 1.0 }, 0.1), Err(Error::NonUnitVector { index: 1, .. })));
    assert!(matches!(find_loops(&raw, &Angular, 0.1), Err(Error::NonUnitVector { index: 1, .. })));
}

#[test]
fn negative_or_non_finite_parameters_are_rejected_by_the_engine() {
    use RotationDistance::Geodesic;
    let se3 = Trajectory::se3(times(2), &[[0.0; 3], [1.0; 3]], &[[0.0, 0.0, 0.0, 1.0]; 2]).unwrap();
    let se2 = Trajectory::se2(times(2), &[[0.0; 3], [1.0; 3]]).unwrap();
    let gnss = Trajectory::gnss(times(2), &[[0.0; 3], [1.0; 3]]).unwrap();
    let sphere = Trajectory::sphere(times(2), &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    let invalid = |result: loops_core::Result<Loops>, name: &str| match result {
        Err(Error::InvalidParameter { name: got, .. }) => assert_eq!(got, name),
        other => panic!("{name}: expected InvalidParameter, got {other:?}"),
    };
    for w in [-1.0, -1e-300, f64::NAN, f64::INFINITY] {
        invalid(
            find_loops(&se3, &Se3 { rotation_weight_m_per_rad: w, rotation: Geodesic }, 1.0),
            "rotation_weight_m_per_rad",
        );
        invalid(find_loops(&se2, &Se2 { rotation_weight_m_per_rad: w }, 1.0), "rotation_weight_m_per_rad");
        invalid(find_loops(&gnss, &Haversine { radius_m: w }, 1.0), "radius_m");
        invalid(find_loops(&sphere, &Sphere { radius: w }, 1.0), "radius");
        let brute = SublevelSet::brute_force(&se3, &Se3 { rotation_weight_m_per_rad: w, rotation: Geodesic }, 1.0);
        assert!(matches!(brute, Err(Error::InvalidParameter { .. })));
    }
    invalid(find_loops(&gnss, &Haversine { radius_m: 0.0 }, 1.0), "radius_m");
    invalid(find_loops(&sphere, &Sphere { radius: 0.0 }, 1.0), "radius");
    // Zero weights are allowed: translation only.
    assert!(find_loops(&se3, &Se3 { rotation_weight_m_per_rad: 0.0, rotation: Geodesic }, 1.0).is_ok());
}

#[test]
fn points_of_the_wrong_dimension_are_rejected() {
    let three = Trajectory::from_points(times(2), &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
    let four = Trajectory::from_points(times(2), &[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0]]).unwrap();
    let two = Trajectory::from_points(times(2), &[[0.0, 0.0], [0.0, 1.0]]).unwrap();
    let cases: Vec<(&str, &Trajectory, usize)> = vec![
        ("so3", &three, 3),
        ("so3(rotation=chordal)", &two, 2),
        ("se3(rotation_weight_m_per_rad=1)", &four, 4),
        ("se3_rotation", &three, 3),
        ("se2(rotation_weight_m_per_rad=1)", &two, 2),
        ("se2(rotation_weight_m_per_rad=1)", &four, 4),
        ("sphere", &four, 4),
        ("sphere", &two, 2),
        ("haversine", &two, 2),
        ("haversine", &three, 3),
    ];
    for (text, traj, found) in cases {
        let spec: MetricSpec = text.parse().unwrap();
        match spec.find_loops(traj, 0.5) {
            Err(Error::DimensionMismatch { found: got, .. }) => assert_eq!(got, found, "{text}"),
            other => panic!("{text} on dimension {found}: {other:?}"),
        }
    }
    assert!(matches!(find_loops(&three, &So3::default(), 0.5), Err(Error::DimensionMismatch { found: 3, .. })));
    assert!(matches!(
        SublevelSet::brute_force(&two, &Sphere { radius: 1.0 }, 0.5),
        Err(Error::DimensionMismatch { found: 2, .. })
    ));
}

#[test]
fn metric_specs_that_do_not_parse() {
    for bad in [
        "",
        "manhattan",
        "so4",
        "se3",
        "se2",
        "se3(rotation_weight_m_per_rad=-1)",
        "se3(rotation_weight_m_per_rad=nan)",
        "se3(rotation_weight_m_per_rad=inf)",
        "se3(rotation_weight_m_per_rad=ten)",
        "se3(rotation_weight_m_per_rad=1",
        "se3(rotation_weight_m_per_rad=1))",
        "se3(rotation_weight_m_per_rad=1, rotation_weight_m_per_rad=2)",
        "se3(rotation_weight_m_per_rad=1, rotation=euler)",
        "se3(rotation_weight_m_per_rad)",
        "se3(weight=1)",
        "so3(rotation=)",
        "so3(rotation_weight_m_per_rad=1)",
        "se2(rotation_weight_m_per_rad=-0.5)",
        "torus(dims=2)",
        "sphere(radius=-1)",
        "sphere(radius=0)",
        "haversine(radius_m=0)",
        "haversine(radius=6371000)",
        "angular(dim=3)",
        "euclidean(p=1)",
        "(rotation=geodesic)",
    ] {
        match bad.parse::<MetricSpec>() {
            Err(Error::InvalidMetricSpec { .. } | Error::UnknownName { .. }) => {}
            other => panic!("{bad:?} parsed to {other:?}"),
        }
    }
    for good in [
        "se3(rotation_weight_m_per_rad=10)",
        " SE3 ( rotation_weight_m_per_rad = 10 , ) ",
        "so3(rotation=frobenius)",
        "torus()",
        "l2",
    ] {
        assert!(good.parse::<MetricSpec>().is_ok(), "{good:?}");
    }
}

// =============================================================================================
// 5. The paper's Fig. 4: circles of radius 7π/8 on S¹ × S¹ and in SO(3)
// =============================================================================================

const FIG4_RADIUS: f64 = 7.0 * PI / 8.0;
/// t_i = i / 400: t = 1/4, 1/2, 3/4 fall on samples 100, 200, 300.
const FIG4_SAMPLES: usize = 401;

fn fig4_t(i: usize) -> f64 {
    i as f64 / (FIG4_SAMPLES - 1) as f64
}

/// (7π/8 cos 2πt, 7π/8 sin 2πt).
fn fig4_circle(i: usize) -> [f64; 2] {
    let angle = TAU * fig4_t(i);
    [FIG4_RADIUS * angle.cos(), FIG4_RADIUS * angle.sin()]
}

/// Local minima of δ(t, t′) on the lattice, t < t′: cells no larger than any of their 8
/// neighbours in [0, 1]² (δ is symmetric), by brute force.
fn local_minima(traj: &Trajectory, metric: &dyn Metric) -> Vec<((usize, usize), f64)> {
    let n = traj.len();
    let d: Vec<Vec<f64>> =
        (0..n).map(|i| (0..n).map(|j| metric.distance(traj.point(i), traj.point(j))).collect()).collect();
    let mut minima = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let neighbours = (i.saturating_sub(1)..=(i + 1).min(n - 1))
                .flat_map(|a| (j.saturating_sub(1)..=(j + 1).min(n - 1)).map(move |b| (a, b)));
            if neighbours.clone().all(|(a, b)| d[a][b] >= d[i][j]) {
                minima.push(((i, j), d[i][j]));
            }
        }
    }
    minima
}

/// On the torus the circle (unwrapped: diameter 7π/4 > π) wraps across the seams. Points half a
/// turn apart, at circle angles α and α + π, differ by (2r cos α, 2r sin α), and a difference
/// 2r = 7π/4 wraps to 2π − 7π/4 = π/4. So δ(t, t + ½) = π/4 where the difference lies along an
/// axis, α ∈ {0, π/2, π}: ξ(0) ≈ ξ(½) (across the θ seam) and ξ(¼) ≈ ξ(¾) (across the φ seam) —
/// the two near meetings — while ξ(0) = ξ(1) exactly (the ends meet). In the half t < t′ these
/// are the minima (0, ½), (¼, ¾), (½, 1) at π/4 and (0, 1) at 0. At γ between π/4 and the band
/// they show as four non-trivial components, each around one minimum; below π/4 only the corner.
#[test]
fn fig4_torus_circle_meets_itself_at_its_ends_and_nearly_twice_more() {
    let n = FIG4_SAMPLES;
    let angles: Vec<f64> = (0..n).flat_map(fig4_circle).collect();
    let traj = Trajectory::torus(times(n), &angles, 2).unwrap();
    let near_meeting = TAU - 2.0 * FIG4_RADIUS; // π/4
    assert!((near_meeting - FRAC_PI_4).abs() < 1e-15);
    let (quarter, half) = ((n - 1) / 4, (n - 1) / 2);
    assert!(Torus.distance(traj.point(0), traj.point(n - 1)) <= 1e-12, "the ends meet");

    // Brute-force minima below π/2 are exactly the derived ones.
    let minima = local_minima(&traj, &Torus);
    let low: Vec<_> = minima.iter().filter(|(_, d)| *d < FRAC_PI_2).collect();
    let expected = [
        ((0, half), near_meeting),
        ((0, n - 1), 0.0),
        ((quarter, 3 * quarter), near_meeting),
        ((half, n - 1), near_meeting),
    ];
    assert_eq!(low.len(), expected.len(), "minima below π/2: {low:?}");
    for (cell, value) in expected {
        let found = low.iter().find(|(c, _)| *c == cell).unwrap_or_else(|| panic!("no minimum at {cell:?}: {low:?}"));
        assert!((found.1 - value).abs() <= 1e-12, "{cell:?}: {} vs {value}", found.1);
    }

    let gamma = 1.25 * near_meeting;
    let loops = find_loops(&traj, &Torus, gamma).unwrap();
    assert!(loops.warnings().is_empty());
    let trivial = loops.components().iter().filter(|c| c.trivial).count();
    let others: Vec<_> = loops.components().iter().filter(|c| !c.trivial).collect();
    assert_eq!((trivial, others.len()), (1, 4), "{:?}", loops.components());
    // Non-trivial components exactly around the minima within γ: one each, closest there.
    let within: Vec<_> = minima.iter().filter(|(_, d)| *d <= gamma).collect();
    for component in &others {
        let inside: Vec<_> =
            within.iter().filter(|((i, j), _)| loops.component_of(*i, *j) == Some(component.id)).collect();
        assert_eq!(inside.len(), 1, "component {component:?} holds minima {inside:?}");
        assert_eq!(component.closest_pair, [inside[0].0.0, inside[0].0.1]);
        assert!((component.closest_distance - inside[0].1).abs() <= 1e-12);
    }
    assert_eq!(within.len(), others.len());
    assert!(!loops.is_simple(0, n - 1), "the ends meet outside the trivial component");

    // Below π/4 the near meetings are gone; the ends still meet.
    let loops = find_loops(&traj, &Torus, 0.75 * near_meeting).unwrap();
    let others: Vec<_> = loops.components().iter().filter(|c| !c.trivial).collect();
    assert_eq!(others.len(), 1, "{:?}", loops.components());
    assert_eq!(others[0].closest_pair, [0, n - 1]);
}

/// The relative rotation angle of two rotations by r about unit axes ψ apart, from
/// q_a · q_b = cos²(r/2) + sin²(r/2) cos ψ = 1 − 2 sin²(r/2) sin²(ψ/2) =: c, as
/// θ = 2 atan2(√((1 − c)(1 + c)), |c|) (stable near 0 and π).
fn fig4_so3_angle(psi: f64) -> f64 {
    let one_minus = 2.0 * (FIG4_RADIUS / 2.0).sin().powi(2) * (psi / 2.0).sin().powi(2);
    let c = 1.0 - one_minus;
    2.0 * (one_minus * (1.0 + c)).sqrt().atan2(c.abs())
}

/// In SO(3), v(t) = 7π/8 (cos 2πt, sin 2πt, 0): rotations by 7π/8 about axes turning in a
/// plane. Opposite points of the circle are rotations by 7π/8 about opposite axes, R(−u, r) =
/// R(u, −r), so they differ by a rotation of 2r = 7π/4 ≡ π/4: the circle comes back close to its
/// start and end at their antipodal point t = ½. δ depends on Δt only, rises from 0 to π (at
/// cos ψ = −cot²(r/2), ψ ≈ 92°) and falls to π/4 at Δt = ½: for π/4 < γ < π, S_γ holds a strip
/// along t′ − t = ½, from (0, ½) to (½, 1), apart from the diagonal band and from the corner
/// (0, 1) (the closed circle's ends). In R³ the same vectors are 2r = 7π/4 apart at Δt = ½, so
/// no strip.
#[test]
fn fig4_so3_circle_approaches_its_ends_at_the_antipodal_point() {
    let n = FIG4_SAMPLES;
    let half = (n - 1) / 2;
    let vectors: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let [x, y] = fig4_circle(i);
            [x, y, 0.0]
        })
        .collect();
    let traj = Trajectory::so3_from_rotation_vectors(times(n), &vectors).unwrap();
    let from_quaternions =
        Trajectory::so3(times(n), &vectors.iter().map(|v| quat_exp(*v)).collect::<Vec<_>>()).unwrap();
    let opposite = fig4_so3_angle(PI);
    assert!((opposite - FRAC_PI_4).abs() < 1e-15, "2r mod 2π folded into [0, π]: {opposite}");
    let geodesic = So3 { rotation: RotationDistance::Geodesic };
    let chordal = So3 { rotation: RotationDistance::Chordal };
    for i in (0..n).step_by(7) {
        for j in (0..n).step_by(3) {
            let expected = fig4_so3_angle(TAU * (fig4_t(j) - fig4_t(i)));
            let d = geodesic.distance(traj.point(i), traj.point(j));
            assert!((d - expected).abs() <= 1e-12, "({i}, {j}): {d} vs {expected}");
            let d = chordal.distance(traj.point(i), traj.point(j));
            assert!((d - 2.0 * SQRT_2 * (expected / 2.0).sin()).abs() <= 1e-12);
        }
    }
    // The farthest point between the band and the strip is a half turn: any γ < π separates them.
    let cos_psi: f64 = -1.0 / (FIG4_RADIUS / 2.0).tan().powi(2);
    assert!((fig4_so3_angle(cos_psi.acos()) - PI).abs() < 1e-12);

    let gamma = 1.25 * opposite;
    assert!(gamma < PI);
    for (metric, gamma, below) in [
        (geodesic, gamma, 0.75 * opposite),
        (chordal, 2.0 * SQRT_2 * (gamma / 2.0).sin(), 2.0 * SQRT_2 * (0.75 * opposite / 2.0).sin()),
    ] {
        let loops = find_loops(&traj, &metric, gamma).unwrap();
        assert_eq!(loops.sublevel_set(), find_loops(&from_quaternions, &metric, gamma).unwrap().sublevel_set());
        let others: Vec<_> = loops.components().iter().filter(|c| !c.trivial).collect();
        assert_eq!((loops.components().len(), others.len()), (3, 2), "{}: {:?}", metric.name(), loops.components());
        let strip = loops.component_of(0, half).expect("the start meets the antipodal point");
        assert!(!loops.components()[strip].trivial);
        for i in 0..=half {
            assert_eq!(loops.component_of(i, i + half), Some(strip), "{}: ({i}, {})", metric.name(), i + half);
        }
        assert_eq!(loops.component_of(half, n - 1), Some(strip), "the antipodal point meets the end");
        let corner = loops.component_of(0, n - 1).expect("the ends meet");
        assert_ne!(corner, strip);
        let expected_closest = if metric.rotation == RotationDistance::Geodesic {
            opposite
        } else {
            2.0 * SQRT_2 * (opposite / 2.0).sin()
        };
        assert!((loops.components()[strip].closest_distance - expected_closest).abs() <= 1e-12);
        // Below π/4 the strip is gone.
        let loops = find_loops(&traj, &metric, below).unwrap();
        assert!((0..=half).all(|i| loops.component_of(i, i + half).is_none()));
        assert_eq!(loops.components().len(), 2, "{:?}", loops.components());
    }
    // The chordal distance is a monotone function of the angle: the same set at matching γ.
    let geodesic_set = SublevelSet::compute(&traj, &geodesic, gamma).unwrap();
    let chordal_set = SublevelSet::compute(&traj, &chordal, 2.0 * SQRT_2 * (gamma / 2.0).sin()).unwrap();
    assert_eq!(geodesic_set.runs(), chordal_set.runs());

    // The same vectors in R³: opposite points are 7π/4 apart; no strip, the ends still meet.
    let flat = Trajectory::from_points(times(n), &vectors).unwrap();
    assert!((Euclidean.distance(flat.point(0), flat.point(half)) - 2.0 * FIG4_RADIUS).abs() <= 1e-12);
    let loops = find_loops(&flat, &Euclidean, gamma).unwrap();
    assert!((0..=half).all(|i| loops.component_of(i, i + half).is_none()));
    assert_eq!(loops.components().len(), 2, "{:?}", loops.components());
    assert!(!loops.is_simple(0, n - 1) && loops.component_of(0, n - 1).is_some());
}

// =============================================================================================
// Bugs found (fail until fixed in crates/loops-core/src)
// =============================================================================================

/// Three fixes on the equator's antipode: (0°, 0°), then 1e-8 rad and 3e-8 rad north of
/// (0°, 180°). The textbook haversine rounds h = 1 − 2.5e-17 to 1 for the first pair and reports
/// πR, 6.4 cm more than the truth, breaking the triangle inequality by 6 cm; the metric's
/// angle from unit vectors (2 atan2(‖a − b‖, ‖a + b‖)) has no such loss.
#[test]
fn haversine_near_antipodes_keeps_the_triangle_inequality() {
    let traj = Trajectory::gnss(
        times(3),
        &[[0.0, 0.0, 0.0], [1e-8_f64.to_degrees(), 180.0, 0.0], [3e-8_f64.to_degrees(), 180.0, 0.0]],
    )
    .unwrap();
    let metric = Haversine::default();
    let d = |i: usize, j: usize| metric.distance(traj.point(i), traj.point(j));
    let truth = EARTH_RADIUS_M * (PI - 1e-8);
    assert!(
        d(0, 1) <= d(0, 2) + d(2, 1) + 1e-9 * PI * EARTH_RADIUS_M,
        "δ(0, 1) − δ(0, 2) − δ(2, 1) = {:e} m",
        d(0, 1) - d(0, 2) - d(2, 1)
    );
    assert!(
        (d(0, 1) - truth).abs() <= 1e-3,
        "δ(0, 1) = {} m, truth {truth} m (off by {:e} m)",
        d(0, 1),
        d(0, 1) - truth
    );
}

/// The same three fixes, γ = πR − 0.18 m: the engine's arc-length skip from column 1 (δ = πR,
/// overestimated) jumps over column 2 (δ = πR − 0.19 m ≤ γ), which the brute force keeps.
#[test]
fn haversine_near_antipodes_equals_the_brute_force() {
    let traj = Trajectory::gnss(
        times(3),
        &[[0.0, 0.0, 0.0], [1e-8_f64.to_degrees(), 180.0, 0.0], [3e-8_f64.to_degrees(), 180.0, 0.0]],
    )
    .unwrap();
    let gamma = PI * EARTH_RADIUS_M - 0.18;
    let brute = SublevelSet::brute_force(&traj, &Haversine::default(), gamma).unwrap();
    let set = SublevelSet::compute(&traj, &Haversine::default(), gamma).unwrap();
    assert!(brute.contains(0, 2));
    assert_eq!(set.row(0), brute.row(0), "engine misses (0, 2)");
}

/// Fixes on both sides of the date line, with longitudes as receivers report them (±180°):
/// (0°, 179.9999°), then two fixes 25.7 m away at −179.999869° and one ulp (6 nm) east of it.
/// A haversine of longitude differences (Δλ ≈ −2π + 4.5e-6 rad) rounded by ~6e-9 m there and
/// broke the triangle inequality by more than the engine's margin, which skipped (0, 2). Fixes
/// are now unit vectors (no longitude differences) and the margin is in metres (the radius):
/// the engine must agree with the brute force at every γ around δ(0, 2).
#[test]
fn haversine_across_the_date_line_equals_the_brute_force() {
    let fixes = [
        [0.0, 179.9999, 0.0],
        [4.428571428571428e-6, -179.999869, 0.0],
        [4.428571428571428e-6, -179.99986900000005, 0.0],
    ];
    let traj = Trajectory::gnss(times(3), &fixes).unwrap();
    let metric = Haversine::default();
    let d = |i: usize, j: usize| metric.distance(traj.point(i), traj.point(j));
    let d02 = d(0, 2);
    assert!((d02 - 25.69).abs() < 0.01, "{d02}");
    for gamma in [d02 * (1.0 - 1e-15), d02, d02 * (1.0 + 1e-15), 25.69078341007786] {
        let brute = SublevelSet::brute_force(&traj, &metric, gamma).unwrap();
        let set = SublevelSet::compute(&traj, &metric, gamma).unwrap();
        assert_eq!(set, brute, "gamma {gamma}");
    }
}

/// `Trajectory::sphere` and `Trajectory::descriptors(normalize = true)` normalise any non-zero
/// finite vector: ‖(1e200, 0, 0)‖² would overflow and ‖(1e-170, 0, 0)‖² underflow unscaled.
#[test]
fn huge_and_tiny_vectors_are_normalised() {
    for v in [[1e200, 0.0, 0.0], [1e-170, 0.0, 0.0]] {
        let sphere = Trajectory::sphere(times(2), &[[0.0, 0.0, 1.0], v]);
        assert!(sphere.is_ok(), "{v:?}: {sphere:?}");
        let descriptors = Trajectory::descriptors(times(2), &[[0.0, 0.0, 1.0], v].concat(), 3, true);
        assert!(descriptors.is_ok(), "{v:?}: {descriptors:?}");
    }
}

// =============================================================================================
// 6. A trajectory knows its manifold: every constructor's points are measured by its
//    manifold's metric when none is chosen, and by no metric that does not fit them
// =============================================================================================

/// A small xorshift generator: the same points on every machine.
struct Noise(u64);

impl Noise {
    /// Uniform in [−1, 1].
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// The angle between two non-zero vectors of any dimension, from their unit vectors:
/// atan2(‖a′ − b′‖, ‖a′ + b′‖) · 2.
fn angle_between(a: &[f64], b: &[f64]) -> f64 {
    let (a, b) = (unit(a).unwrap(), unit(b).unwrap());
    let minus: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
    let plus: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
    2.0 * norm(&minus).atan2(norm(&plus))
}

/// ‖a − b‖.
fn l2(a: &[f64], b: &[f64]) -> f64 {
    norm(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>())
}

/// One constructor: the trajectory it builds from raw input, the distance its manifold's
/// metric gives between two raw inputs (written here from the definitions), and the name of
/// the metric it must be measured by when none is chosen.
struct Constructed {
    name: &'static str,
    traj: Trajectory,
    raw: Vec<Vec<f64>>,
    reference: fn(&[f64], &[f64]) -> f64,
    manifold: Manifold,
    default_metric: &'static str,
}

/// Every constructor on a path that goes round twice (so it comes back to itself), with noise;
/// quaternions with random signs, angles unwrapped far beyond ±π, longitudes beyond ±180°.
fn every_constructor(n: usize, seed: u64) -> Vec<Constructed> {
    let mut noise = Noise(seed);
    let u: Vec<f64> = (0..n).map(|i| 2.0 * TAU * i as f64 / n as f64 + 0.05 * noise.next()).collect();
    let t = times(n);
    let mut raw = |f: &mut dyn FnMut(f64, &mut Noise) -> Vec<f64>| -> Vec<Vec<f64>> {
        u.iter().map(|&u| f(u, &mut noise)).collect()
    };
    let rows3 =
        |raw: &[Vec<f64>], k: usize| -> Vec<[f64; 3]> { raw.iter().map(|p| [p[k], p[k + 1], p[k + 2]]).collect() };
    let rows4 = |raw: &[Vec<f64>], k: usize| -> Vec<[f64; 4]> {
        raw.iter().map(|p| [p[k], p[k + 1], p[k + 2], p[k + 3]]).collect()
    };
    let flat = |raw: &[Vec<f64>]| -> Vec<f64> { raw.iter().flatten().copied().collect() };
    let rotation = |u: f64, noise: &mut Noise| -> Vec<f64> {
        let q = quat_exp([0.6 * u.cos() + 0.1 * noise.next(), 0.6 * u.sin(), 1.3 * (2.0 * u).sin()]);
        let sign = if noise.next() > 0.0 { 1.0 } else { -1.0 };
        q.iter().map(|v| sign * v).collect()
    };
    let mut all = Vec::new();

    let points = raw(&mut |u, noise| vec![10.0 * u.cos(), 10.0 * u.sin(), noise.next()]);
    let traj = Trajectory::new(t.clone(), flat(&points), 3).unwrap();
    all.push(Constructed {
        name: "new",
        traj,
        raw: points,
        reference: l2,
        manifold: Manifold::Euclidean,
        default_metric: "euclidean",
    });

    // SE(3): by default the translation only, whatever the rotations.
    let poses = raw(&mut |u, noise| {
        let mut p = vec![10.0 * u.cos(), 10.0 * u.sin(), 0.3 * noise.next()];
        p.extend(rotation(u + 2.0 * noise.next(), noise));
        p
    });
    let traj = Trajectory::se3(t.clone(), &rows3(&poses, 0), &rows4(&poses, 3)).unwrap();
    all.push(Constructed {
        name: "se3",
        traj,
        raw: poses,
        reference: |a, b| l2(&a[..3], &b[..3]),
        manifold: Manifold::Se3,
        default_metric: "se3(rotation_weight_m_per_rad=0, rotation=geodesic)",
    });

    // SO(3): the geodesic angle, here from rotation matrices.
    let geodesic = |a: &[f64], b: &[f64]| {
        let (ra, rb) = (rotation_matrix([a[0], a[1], a[2], a[3]]), rotation_matrix([b[0], b[1], b[2], b[3]]));
        // sin θ from the skew part of Raᵀ Rb, cos θ from its trace: atan2 is stable at 0 and π.
        let m: Vec<[f64; 3]> =
            (0..3).map(|r| [0, 1, 2].map(|c| (0..3).map(|k| ra[k][r] * rb[k][c]).sum::<f64>())).collect();
        let sin = 0.5 * norm(&[m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]]);
        sin.atan2(0.5 * (m[0][0] + m[1][1] + m[2][2] - 1.0))
    };
    let quaternions = raw(&mut |u, noise| rotation(u, noise));
    let traj = Trajectory::so3(t.clone(), &rows4(&quaternions, 0)).unwrap();
    all.push(Constructed {
        name: "so3",
        traj,
        raw: quaternions,
        reference: geodesic,
        manifold: Manifold::So3,
        default_metric: "so3(rotation=geodesic)",
    });
    let vectors = raw(&mut |u, noise| vec![0.6 * u.cos() + 0.1 * noise.next(), 0.6 * u.sin(), 1.3 * (2.0 * u).sin()]);
    let traj = Trajectory::so3_from_rotation_vectors(t.clone(), &rows3(&vectors, 0)).unwrap();
    let as_quaternions: Vec<Vec<f64>> = vectors.iter().map(|v| quat_exp([v[0], v[1], v[2]]).to_vec()).collect();
    all.push(Constructed {
        name: "so3_from_rotation_vectors",
        traj,
        raw: as_quaternions,
        reference: geodesic,
        manifold: Manifold::So3,
        default_metric: "so3(rotation=geodesic)",
    });

    // SE(2): by default the translation only.
    let poses = raw(&mut |u, noise| vec![10.0 * u.cos(), 10.0 * u.sin(), 5.0 * u + 3.0 * noise.next()]);
    let traj = Trajectory::se2(t.clone(), &rows3(&poses, 0)).unwrap();
    all.push(Constructed {
        name: "se2",
        traj,
        raw: poses,
        reference: |a, b| l2(&a[..2], &b[..2]),
        manifold: Manifold::Se2,
        default_metric: "se2(rotation_weight_m_per_rad=0)",
    });

    let angles = raw(&mut |u, noise| vec![u, 3.0 * u + 0.1 * noise.next(), -7.0 + 0.2 * noise.next()]);
    let traj = Trajectory::torus(t.clone(), &flat(&angles), 3).unwrap();
    all.push(Constructed {
        name: "torus",
        traj,
        raw: angles,
        reference: torus_brute_force,
        manifold: Manifold::Torus,
        default_metric: "torus",
    });

    let vectors = raw(&mut |u, noise| vec![5.0 * u.cos(), 5.0 * u.sin(), 2.0 + noise.next()]);
    let traj = Trajectory::sphere(t.clone(), &rows3(&vectors, 0)).unwrap();
    all.push(Constructed {
        name: "sphere",
        traj,
        raw: vectors,
        reference: angle_between,
        manifold: Manifold::Sphere,
        default_metric: "sphere(radius=1)",
    });
    let lat_lon = raw(&mut |u, noise| vec![30.0 + 10.0 * u.sin(), 175.0 + 10.0 * u.cos() + 0.3 * noise.next()]);
    let rows2: Vec<[f64; 2]> = lat_lon.iter().map(|p| [p[0], p[1]]).collect();
    let traj = Trajectory::sphere_from_lat_lon(t.clone(), &rows2).unwrap();
    all.push(Constructed {
        name: "sphere_from_lat_lon",
        traj,
        raw: lat_lon,
        reference: |a, b| haversine_textbook_m(a[0], a[1], b[0], b[1]) / EARTH_RADIUS_M,
        manifold: Manifold::Sphere,
        default_metric: "sphere(radius=1)",
    });

    // GNSS: haversine (metres) combined with the height difference.
    let fixes = raw(&mut |u, noise| vec![48.1 + 1e-3 * u.sin(), 179.999 + 1e-3 * u.cos(), 5.0 * noise.next()]);
    let traj = Trajectory::gnss(t.clone(), &rows3(&fixes, 0)).unwrap();
    all.push(Constructed {
        name: "gnss",
        traj,
        raw: fixes.clone(),
        reference: |a, b| haversine_textbook_m(a[0], a[1], b[0], b[1]).hypot(a[2] - b[2]),
        manifold: Manifold::Gnss,
        default_metric: "haversine(radius_m=6371008.8)",
    });
    // ECEF positions are Rⁿ: measured by the Euclidean metric on what the constructor stored.
    let traj = Trajectory::gnss_ecef(t.clone(), &rows3(&fixes, 0)).unwrap();
    let stored: Vec<Vec<f64>> = (0..n).map(|i| traj.point(i).to_vec()).collect();
    all.push(Constructed {
        name: "gnss_ecef",
        traj,
        raw: stored,
        reference: l2,
        manifold: Manifold::Euclidean,
        default_metric: "euclidean",
    });

    let descriptors = raw(&mut |u, noise| {
        (0..8).map(|k| (u + f64::from(k)).sin() * (2.0 + f64::from(k)) + 0.1 * noise.next()).collect()
    });
    let traj = Trajectory::descriptors(t.clone(), &flat(&descriptors), 8, true).unwrap();
    all.push(Constructed {
        name: "descriptors",
        traj,
        raw: descriptors.clone(),
        reference: angle_between,
        manifold: Manifold::Descriptors,
        default_metric: "angular",
    });
    let traj = Trajectory::descriptors(t, &flat(&descriptors), 8, false).unwrap();
    all.push(Constructed {
        name: "descriptors(normalize=false)",
        traj,
        raw: descriptors,
        reference: l2,
        manifold: Manifold::Euclidean,
        default_metric: "euclidean",
    });
    all
}

/// S_γ as a dense upper-triangular mask, from the runs.
fn mask_of(set: &SublevelSet, n: usize) -> Vec<Vec<bool>> {
    let mut mask = vec![vec![false; n]; n];
    for (i, row) in mask.iter_mut().enumerate() {
        for run in set.row(i) {
            for cell in &mut row[run.start as usize..=run.end as usize] {
                *cell = true;
            }
        }
    }
    mask
}

/// A γ half way between two consecutive reference distances near the given quantile, far
/// (relative to the distances) from every one of them: the mask cannot depend on rounding.
fn gamma_between(distances: &mut [f64], quantile: f64) -> f64 {
    distances.sort_by(f64::total_cmp);
    let scale = distances[distances.len() - 1];
    let start = (quantile * distances.len() as f64) as usize;
    let k = (start..distances.len() - 1)
        .find(|&k| distances[k + 1] - distances[k] > 1e-9 * scale)
        .expect("distinct distances");
    0.5 * (distances[k] + distances[k + 1])
}

#[test]
fn every_constructor_is_measured_by_its_manifolds_metric_by_default() {
    let n = 160;
    for seed in [0x5EED_0001_u64, 0x5EED_0002] {
        for c in every_constructor(n, seed) {
            assert_eq!(c.traj.manifold(), c.manifold, "{}", c.name);
            let spec = c.traj.default_metric();
            assert_eq!(spec.to_string(), c.default_metric, "{}", c.name);
            // δ of every pair (i, j ≥ i), by the definition.
            let reference: Vec<Vec<f64>> = (0..n)
                .map(|i| (0..n).map(|j| if j < i { 0.0 } else { (c.reference)(&c.raw[i], &c.raw[j]) }).collect())
                .collect();
            let mut upper: Vec<f64> = (0..n).flat_map(|i| reference[i][i..].to_vec()).collect();
            for quantile in [0.05, 0.3] {
                let gamma = gamma_between(&mut upper, quantile);
                let loops = spec.find_loops(&c.traj, gamma).unwrap();
                assert_eq!(loops.metric_name(), c.default_metric, "{}", c.name);
                let mask = mask_of(loops.sublevel_set(), n);
                for i in 0..n {
                    for j in i..n {
                        assert_eq!(
                            mask[i][j],
                            reference[i][j] <= gamma,
                            "{} (seed {seed:#x}, gamma {gamma}): pair ({i}, {j}) at {} by the definition",
                            c.name,
                            reference[i][j]
                        );
                    }
                }
                // Revisits (the second lap), not only the diagonal: the test sees loops.
                let revisits = (0..n).flat_map(|i| (i + n / 3..n).map(move |j| (i, j))).filter(|&(i, j)| mask[i][j]);
                assert!(revisits.count() > 0, "{}: no revisit at gamma {gamma}", c.name);
            }
        }
    }
}

#[test]
fn a_metric_that_does_not_fit_the_points_is_refused_naming_both() {
    let n = 40;
    let euclidean = MetricSpec::Euclidean;
    for c in every_constructor(n, 7) {
        let fits = matches!(c.manifold, Manifold::Euclidean | Manifold::Descriptors);
        let found = euclidean.find_loops(&c.traj, 1.0);
        assert_eq!(found.is_ok(), fits, "euclidean on {}: {found:?}", c.name);
        if fits {
            continue;
        }
        let message = found.unwrap_err().to_string();
        let name = c.manifold.name();
        assert!(message.starts_with("metric euclidean does not fit a"), "{message}");
        assert!(message.contains(&format!("{name} trajectory ({} columns: ", c.traj.dim())), "{message}");
        assert!(message.contains(c.default_metric), "{message}");
        // Every entry point that measures refuses it, before measuring anything.
        let refused = |result: loops_core::Result<()>| match result {
            Err(Error::MetricDoesNotFit(misfit)) => assert_eq!(misfit.metric, "euclidean"),
            other => panic!("{}: expected MetricDoesNotFit, got {other:?}", c.name),
        };
        refused(find_loops(&c.traj, &Euclidean, 1.0).map(drop));
        refused(SublevelSet::brute_force(&c.traj, &Euclidean, 1.0).map(drop));
        refused(c.traj.check_metric(&Euclidean));
        let grid = PlaneGrid::new(&c.traj, None, 8).unwrap();
        refused(distance_image(&c.traj, &Euclidean, &grid).map(drop));
        let loops = c.traj.default_metric().find_loops(&c.traj, 1e-3).unwrap();
        let sampler = Sampler::new(SamplerKind::Alpha, SampleSize::Budget(3), 0);
        refused(sample_loops(&c.traj, &Euclidean, &loops, &sampler).map(drop));
        let mut samples = c.traj.default_metric().sample_loops(&c.traj, &loops, &sampler).unwrap();
        refused(samples.measure(&c.traj, &Euclidean));
        assert!(samples.measure(&c.traj, c.traj.default_metric().as_metric()).is_ok());
    }
    // The metrics of one manifold do not fit another's points either (an SO(3) metric on SE(2)
    // poses would take x, y, θ for a quaternion's first three components ...).
    let all = every_constructor(n, 7);
    let by_name = |name: &str| &all.iter().find(|c| c.name == name).unwrap().traj;
    for (text, on) in [
        ("so3", "se2"),
        ("so3", "gnss"),
        ("se3_rotation", "torus"),
        ("torus", "se3"),
        ("torus", "sphere"),
        ("sphere", "gnss"),
        ("haversine", "so3"),
        ("angular", "so3"),
        ("se2(rotation_weight_m_per_rad=1)", "sphere"),
        ("se3(rotation_weight_m_per_rad=1)", "descriptors"),
    ] {
        let spec: MetricSpec = text.parse().unwrap();
        let traj = by_name(on);
        let error = spec.find_loops(traj, 0.5).unwrap_err();
        assert!(matches!(error, Error::MetricDoesNotFit(_)), "{text} on {on}: {error}");
    }
    // ... while the metrics of a manifold measure its points, and plain coordinates take any
    // metric whose layout they have (checked as that metric requires).
    for (text, on) in [
        ("se3(rotation_weight_m_per_rad=10, rotation=chordal)", "se3"),
        ("se3_rotation", "se3"),
        ("so3(rotation=chordal)", "so3_from_rotation_vectors"),
        ("se2(rotation_weight_m_per_rad=2)", "se2"),
        ("sphere(radius=6371000)", "sphere_from_lat_lon"),
        ("angular", "sphere"),
        ("haversine(radius_m=6378137)", "gnss"),
        ("euclidean", "descriptors"),
        ("euclidean", "gnss_ecef"),
    ] {
        let spec: MetricSpec = text.parse().unwrap();
        assert!(spec.find_loops(by_name(on), 0.5).is_ok(), "{text} on {on}");
    }
    let plain = Trajectory::new(times(2), [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]; 2].concat(), 7).unwrap();
    assert_eq!(plain.manifold(), Manifold::Euclidean);
    assert!("se3(rotation_weight_m_per_rad=1)".parse::<MetricSpec>().unwrap().find_loops(&plain, 0.5).is_ok());
}

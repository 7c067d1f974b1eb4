//! Fleets for the fleet and tile tests: random ones from generated cases, and an adversarial one
//! (identical sessions, a time-reversed one, parked ones, one far from the others).

use std::ops::Range;

use loops_core::{Separation, Trajectory};
use proptest::prelude::*;

use super::{Case, any_case};

/// A random fleet: generated cases, each a session in the plane shifted by its shift (in γ), at
/// the first case's γ, with a separation of 2γ along the path or none.
#[derive(Debug, Clone)]
pub struct RandomFleet {
    pub cases: Vec<Case>,
    pub shifts: Vec<(f64, f64)>,
    pub separated: bool,
}

impl RandomFleet {
    pub fn gamma(&self) -> f64 {
        self.cases[0].gamma
    }

    pub fn sessions(&self) -> Vec<Trajectory> {
        let gamma = self.gamma();
        self.cases.iter().zip(&self.shifts).map(|(c, &(x, y))| planar(&c.traj, [x * gamma, y * gamma])).collect()
    }

    pub fn separation(&self) -> Separation {
        if self.separated { Separation { path: 2.0 * self.gamma(), time_s: 0.0 } } else { Separation::NONE }
    }
}

/// Random fleets of `sessions` sessions of at most `n_max` poses, shifted by less than `spread` γ
/// on each axis.
pub fn random_fleet(n_max: usize, sessions: Range<usize>, spread: f64) -> impl Strategy<Value = RandomFleet> {
    let shifts = sessions.end;
    (
        prop::collection::vec(any_case(n_max), sessions),
        prop::collection::vec((-spread..spread, -spread..spread), shifts),
        any::<bool>(),
    )
        .prop_map(|(cases, shifts, separated)| RandomFleet { cases, shifts, separated })
}

/// A session in the plane from a generated case (its first two coordinates, or (x, 0)).
pub fn planar(traj: &Trajectory, shift: [f64; 2]) -> Trajectory {
    let points: Vec<[f64; 2]> = (0..traj.len())
        .map(|i| {
            let p = traj.point(i);
            [p[0] + shift[0], p.get(1).copied().unwrap_or(0.0) + shift[1]]
        })
        .collect();
    Trajectory::from_points(traj.timestamps_s().to_vec(), &points).unwrap()
}

/// A figure-eight-ish loop in the plane, `n` poses, starting at time `t0`.
pub fn tour(n: usize, t0: f64, offset: [f64; 2]) -> Trajectory {
    let points: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let s = k as f64 / n as f64 * std::f64::consts::TAU * 1.5;
            [offset[0] + 10.0 * s.cos(), offset[1] + 6.0 * (2.0 * s).sin()]
        })
        .collect();
    Trajectory::from_points((0..n).map(|k| t0 + 0.5 * k as f64).collect(), &points).unwrap()
}

/// The adversarial fleet: a tour of `tour_n` poses twice, the same path backwards in time, a
/// session parked for `parked_n` poses in it, one parked far away for `far_parked_n` poses, and
/// a tour of `far_n` poses far from all.
pub fn adversarial_fleet(tour_n: usize, parked_n: usize, far_parked_n: usize, far_n: usize) -> [Trajectory; 6] {
    let a = tour(tour_n, 0.0, [0.0, 0.0]);
    // The same path backwards in time.
    let points: Vec<[f64; 2]> = (0..a.len()).rev().map(|k| [a.point(k)[0], a.point(k)[1]]).collect();
    let reversed = Trajectory::from_points((0..a.len()).map(|k| 1e9 + k as f64).collect(), &points).unwrap();
    let parked =
        Trajectory::from_points((0..parked_n).map(|k| k as f64 * 0.1).collect(), &vec![[10.0, 0.0]; parked_n]).unwrap();
    let parked_far =
        Trajectory::from_points((0..far_parked_n).map(|k| k as f64).collect(), &vec![[1e4, 1e4]; far_parked_n])
            .unwrap();
    let far = tour(far_n, 7.0, [5e3, -5e3]);
    [a.clone(), a, reversed, parked, parked_far, far]
}

/// Vehicles that each wander around their own district (centres `spacing` apart on a line) for
/// `n` poses, 0.08 a step with a pull back to the centre, so that neighbours meet only near their
/// border: long sessions whose tiles hold pairs within γ = 1 in a few stretches of their blocks.
pub fn district_walks(vehicles: usize, n: usize, spacing: f64, seed: u64) -> Vec<Trajectory> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..vehicles)
        .map(|v| {
            let centre = spacing * v as f64;
            let (mut p, mut heading) = ([centre, 0.0], rng.random_range(0.0..std::f64::consts::TAU));
            let points: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    heading += rng.random_range(-0.4..0.4);
                    p = [
                        p[0] + 0.08 * heading.cos() + 0.01 * (centre - p[0]),
                        p[1] + 0.08 * heading.sin() - 0.01 * p[1],
                    ];
                    p
                })
                .collect();
            Trajectory::from_points((0..n).map(|k| 1e4 * v as f64 + 0.5 * k as f64).collect(), &points).unwrap()
        })
        .collect()
}

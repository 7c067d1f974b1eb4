//! Shared by the integration tests: trajectory generators built to be nasty, a dense reference
//! for S_γ, its 4-connected components, their holes and the measures τ and α, and an all-pairs
//! partition of detections for the ε graph.
//!
//! The reference is written from the definitions only (a full n × n boolean matrix, breadth-first
//! flood fill, pixel counting, sums over matrix rows) and shares no algorithm with the engine:
//! no runs, no union-find, no arc-length bounds, no prefix sums. The ε-graph reference joins
//! every pair within ε (a plain union-find over all n² pairs; the engine never looks at pairs).
#![allow(dead_code)] // each test crate uses a different part

pub mod fleets;

use std::cmp::Ordering;
use std::collections::VecDeque;
use std::fmt;

use loops_core::{
    Euclidean, Loops, Metric, Run, Scale, Selection, Separation, Side, Trajectory, Warning, find_loops,
    find_loops_separated,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// Proptest settings: `cases` cases from a fixed seed, no regression files (failures found
/// become named tests instead). `PROPTEST_CASES` and `PROPTEST_RNG_SEED` override, for longer
/// hunts.
pub fn config(cases: u32, seed: u64) -> Config {
    let defaults = Config::default();
    let overridden = |name| std::env::var_os(name).is_some();
    Config {
        cases: if overridden("PROPTEST_CASES") { defaults.cases } else { cases },
        rng_seed: if overridden("PROPTEST_RNG_SEED") { defaults.rng_seed } else { RngSeed::Fixed(seed) },
        failure_persistence: None,
        ..defaults
    }
}

// ---------------------------------------------------------------------------------------------
// Partitions of detections
// ---------------------------------------------------------------------------------------------

/// Labels of the connected components of "within ε" over all pairs of detections (t, t′), by
/// first appearance: a union-find over every pair, O(n²), written from the definition.
pub fn brute_force_clusters(t: &[f64], t_prime: &[f64], epsilon: f64) -> Vec<usize> {
    let n = t.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    for a in 0..n {
        for b in a + 1..n {
            let (dx, dy) = (t[a] - t[b], t_prime[a] - t_prime[b]);
            if dx * dx + dy * dy <= epsilon * epsilon {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    canonical(&(0..n).map(|a| root(&mut parent, a)).collect::<Vec<_>>())
}

/// Relabels a partition by order of first appearance.
pub fn canonical<T: Copy + Eq + std::hash::Hash>(labels: &[T]) -> Vec<usize> {
    let mut seen = std::collections::HashMap::new();
    labels
        .iter()
        .map(|l| {
            let next = seen.len();
            *seen.entry(*l).or_insert(next)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------------

/// One piece of a generated path. Displacements are in units of `Recipe::unit`.
#[derive(Debug, Clone)]
pub enum Move {
    /// One sample displaced by this vector.
    Step([f64; 3]),
    /// `count` more samples at the current point, each off by up to `jitter` per axis (metres,
    /// not units), pseudo-randomly from `seed`.
    Stay { count: usize, jitter: f64, seed: u64 },
    /// One sample exactly at the point `back` samples ago (clamped to the first).
    Revisit { back: usize },
    /// `count` samples alternating +step and −step: back and forth.
    Shuttle { step: [f64; 3], count: usize },
}

/// How to build a case: a path from `origin` by `moves`, sampled at `t0 + Σ increments`.
#[derive(Debug, Clone)]
pub struct Recipe {
    pub dim: usize,
    pub gamma: f64,
    /// Length of a unit displacement in `moves`.
    pub unit: f64,
    pub origin: [f64; 3],
    pub moves: Vec<Move>,
    pub t0: f64,
    /// Time steps, seconds, used in turn.
    pub increments: Vec<f64>,
    /// Most poses (at least 2 are made).
    pub n_max: usize,
}

/// A generated input: the trajectory and γ, with the recipe that made it.
#[derive(Clone)]
pub struct Case {
    pub traj: Trajectory,
    pub gamma: f64,
    pub recipe: Recipe,
}

impl fmt::Debug for Case {
    /// Prints a copy-pasteable input (full precision), then the recipe.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "Case {{ n: {}, dim: {}, gamma: {:?},", self.traj.len(), self.traj.dim(), self.gamma)?;
        writeln!(f, "  timestamps_s: {:?},", self.traj.timestamps_s())?;
        writeln!(f, "  coords: {:?},", self.traj.coords())?;
        writeln!(f, "  moves: {:?} }}", self.recipe.moves)
    }
}

/// splitmix64: a tiny seeded generator for jitter, so that shrinking the seed is harmless.
fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

impl Recipe {
    /// The trajectory: at most `n_max` (at least 2) poses.
    pub fn build(self) -> Case {
        let Recipe { dim, gamma, unit, origin, ref moves, t0, ref increments, n_max } = self;
        let add = |p: [f64; 3], v: [f64; 3], scale: f64| [0, 1, 2].map(|k| p[k] + scale * v[k]);
        let mut points: Vec<[f64; 3]> = vec![origin];
        for m in moves {
            if points.len() >= n_max {
                break;
            }
            let last = points[points.len() - 1];
            match *m {
                Move::Step(v) => points.push(add(last, v, unit)),
                Move::Stay { count, jitter, seed } => {
                    let mut state = seed;
                    for _ in 0..count {
                        let noise = [(); 3].map(|()| jitter * (2.0 * splitmix(&mut state) - 1.0));
                        points.push(add(last, noise, 1.0));
                    }
                }
                Move::Revisit { back } => {
                    let k = points.len().saturating_sub(back.max(1));
                    points.push(points[k]);
                }
                Move::Shuttle { step, count } => {
                    for k in 0..count {
                        points.push(add(last, step, if k % 2 == 0 { unit } else { 0.0 }));
                    }
                }
            }
        }
        if points.len() < 2 {
            points.push(points[0]);
        }
        points.truncate(n_max.max(2));
        let timestamps_s = (0..points.len())
            .scan(t0, |t, k| {
                if k > 0 {
                    *t += increments[(k - 1) % increments.len()];
                }
                Some(*t)
            })
            .collect();
        let coords = points.iter().flat_map(|p| p[..dim].to_vec()).collect();
        let traj = Trajectory::new(timestamps_s, coords, dim).expect("generated input is valid");
        Case { traj, gamma, recipe: self }
    }
}

fn direction() -> impl Strategy<Value = [f64; 3]> + Clone {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64].prop_map(|v| {
        let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if norm < 1e-3 { [1.0, 0.0, 0.0] } else { v.map(|c| c / norm) }
    })
}

/// Step lengths in units of γ: inside, around and exactly at γ; when `rough`, also beyond γ
/// and far jumps.
fn length_in_gamma(rough: bool) -> impl Strategy<Value = f64> + Clone {
    let beyond = if rough { 2 } else { 0 };
    prop_oneof![
        6 => 0.0..1.0f64,
        2 => 0.95..1.0f64,
        1 => Just(1.0),
        1 => Just(0.5),
        beyond => 1.0..3.0f64,
        beyond / 2 => 3.0..10.0f64,
    ]
}

fn float_step(rough: bool) -> impl Strategy<Value = [f64; 3]> + Clone {
    (direction(), length_in_gamma(rough)).prop_map(|(d, l)| d.map(|c| c * l))
}

/// Integer steps; when not `rough`, at most one unit per axis.
fn lattice_step(rough: bool) -> impl Strategy<Value = [f64; 3]> + Clone {
    let reach = if rough { 2 } else { 1 };
    [-reach..=reach, -reach..=reach, -reach..=reach].prop_map(|v| v.map(f64::from))
}

/// Paths of up to `count` moves; only `rough` ones jump back to earlier points.
fn moves(step: impl Strategy<Value = [f64; 3]> + Clone, rough: bool, count: usize) -> impl Strategy<Value = Vec<Move>> {
    let one = prop_oneof![
        6 => step.clone().prop_map(Move::Step),
        1 => (1..30usize, prop_oneof![Just(0.0), Just(1e-9)], any::<u64>())
            .prop_map(|(count, jitter, seed)| Move::Stay { count, jitter, seed }),
        u32::from(rough) => (1..60usize).prop_map(|back| Move::Revisit { back }),
        1 => (step, 1..30usize).prop_map(|(step, count)| Move::Shuttle { step, count }),
    ];
    prop::collection::vec(one, 1..count)
}

/// At most `n_max` poses, more often many than few.
fn pose_count(n_max: usize) -> impl Strategy<Value = usize> {
    prop_oneof![1 => 2..=n_max, 2 => n_max / 2..=n_max]
}

fn increments() -> impl Strategy<Value = Vec<f64>> {
    let one = prop_oneof![
        4 => 0.01..2.0f64,
        2 => Just(0.1),
        1 => 1e-6..1e-4f64,
        1 => 2.0..50.0f64,
    ];
    prop::collection::vec(one, 1..64)
}

/// Random walks with real coordinates: random step sizes (some beyond γ), stationary stretches
/// with and without 1e-9 jitter, exact revisits, back and forth; γ random, coordinates sometimes
/// offset far from the origin; uneven timestamps.
pub fn float_case(n_max: usize) -> impl Strategy<Value = Case> {
    (
        1..=3usize,
        prop_oneof![Just(1.0), 0.05..5.0f64],
        prop_oneof![Just([0.0; 3]), Just([1234.5678, -765.4321, 0.1]), Just([3.3e5, 5.6e6, -20.0])],
        prop_oneof![moves(float_step(false), false, n_max / 2 + 8), moves(float_step(true), true, n_max / 2 + 8)],
        -100.0..100.0f64,
        increments(),
        pose_count(n_max),
    )
        .prop_map(|(dim, gamma, origin, moves, t0, increments, n_max)| {
            let unit = gamma;
            Recipe { dim, gamma, unit, origin, moves, t0, increments, n_max }.build()
        })
}

/// Walks on the integer lattice with integer γ, so that many pairs are exactly γ apart.
pub fn lattice_case(n_max: usize) -> impl Strategy<Value = Case> {
    (
        1..=3usize,
        prop_oneof![Just(1.0), Just(2.0), Just(3.0)],
        prop_oneof![Just([0.0; 3]), Just([1e6, -2e6, 7.0])],
        prop_oneof![moves(lattice_step(false), false, n_max / 2 + 8), moves(lattice_step(true), true, n_max / 2 + 8)],
        -100.0..100.0f64,
        increments(),
        pose_count(n_max),
    )
        .prop_map(|(dim, gamma, origin, moves, t0, increments, n_max)| {
            let unit = 1.0;
            Recipe { dim, gamma, unit, origin, moves, t0, increments, n_max }.build()
        })
}

/// Either kind.
pub fn any_case(n_max: usize) -> impl Strategy<Value = Case> {
    prop_oneof![float_case(n_max), lattice_case(n_max)]
}

/// A trajectory in R² sampled at `n` evenly spaced times in [0, 1] from `f(t)`.
pub fn sampled(n: usize, f: impl Fn(f64) -> [f64; 2]) -> Trajectory {
    let times: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
    let points: Vec<[f64; 2]> = times.iter().map(|&t| f(t)).collect();
    Trajectory::from_points(times, &points).expect("valid figure trajectory")
}

// ---------------------------------------------------------------------------------------------
// Dense reference
// ---------------------------------------------------------------------------------------------

pub const OUTSIDE: u32 = u32::MAX;

/// S_γ as a full symmetric n × n matrix, every pair measured.
pub struct DenseSet {
    pub n: usize,
    pub gamma: f64,
    /// δ(x_i, x_j), row-major.
    pub distance: Vec<f64>,
    /// δ(x_i, x_j) ≤ γ, row-major.
    pub inside: Vec<bool>,
}

impl DenseSet {
    pub fn new(traj: &Trajectory, gamma: f64) -> Self {
        Self::separated(traj, gamma, Separation::NONE)
    }

    /// The pairs within γ that are also `separation` apart: path length summed here, pose by
    /// pose, and times subtracted pair by pair.
    pub fn separated(traj: &Trajectory, gamma: f64, separation: Separation) -> Self {
        let n = traj.len();
        let mut path = vec![0.0; n];
        for k in 1..n {
            path[k] = path[k - 1] + Euclidean.distance(traj.point(k - 1), traj.point(k));
        }
        let t = traj.timestamps_s();
        let apart = |i: usize, j: usize| {
            let (a, b) = (i.min(j), i.max(j));
            separation.is_none() || (a < b && path[b] - path[a] >= separation.path && t[b] - t[a] >= separation.time_s)
        };
        let mut distance = vec![0.0; n * n];
        for i in 0..n {
            for j in i..n {
                let d = Euclidean.distance(traj.point(i), traj.point(j));
                distance[i * n + j] = d;
                distance[j * n + i] = d;
            }
        }
        let inside = (0..n * n).map(|k| distance[k] <= gamma && apart(k / n, k % n)).collect();
        Self { n, gamma, distance, inside }
    }

    pub fn at(&self, i: usize, j: usize) -> bool {
        self.inside[i * self.n + j]
    }

    pub fn delta(&self, i: usize, j: usize) -> f64 {
        self.distance[i * self.n + j]
    }

    /// The maximal runs of row `i` over columns j ≥ i, read off the matrix.
    pub fn upper_runs(&self, i: usize) -> Vec<Run> {
        let mut runs = Vec::new();
        let mut j = i;
        while j < self.n {
            if self.at(i, j) {
                let start = j;
                while j + 1 < self.n && self.at(i, j + 1) {
                    j += 1;
                }
                runs.push(Run { start: start as u32, end: j as u32 });
            }
            j += 1;
        }
        runs
    }

    /// Number of cells in the full plane.
    pub fn cells(&self) -> u64 {
        self.inside.iter().filter(|&&b| b).count() as u64
    }
}

/// One 4-connected component of the full symmetric matrix.
#[derive(Debug, Clone)]
pub struct DenseComponent {
    /// Contains a diagonal cell.
    pub trivial: bool,
    /// The component holding the mirror cells (itself when trivial).
    pub mirror: u32,
    pub cells: u64,
    pub area_s2: f64,
    pub rows: [usize; 2],
    pub columns: [usize; 2],
    /// The first cell with j ≥ i in row-major order, if any.
    pub first_upper: Option<(usize, usize)>,
    /// Maximal row intervals over cells with j ≥ i.
    pub upper_runs: usize,
    /// Pixel Euler number, 4-connected foreground: #pixels − #4-adjacent pairs + #full 2×2 blocks.
    pub euler: i64,
    /// Background regions (8-connected) of the padded mask not reaching its border.
    pub holes_by_fill: u64,
    /// min δ over cells with j ≥ i, and the first such cell in row-major order.
    pub closest: (f64, [usize; 2]),
}

/// The components of the dense matrix by breadth-first flood fill.
pub struct DenseLoops {
    pub set: DenseSet,
    pub widths: Vec<f64>,
    /// Component of each cell (full plane), `OUTSIDE` when not in S_γ.
    pub label: Vec<u32>,
    pub components: Vec<DenseComponent>,
    /// Components with cells in the upper half, in order of their first such cell: the order in
    /// which the engine numbers its components.
    pub upper_order: Vec<u32>,
}

impl DenseLoops {
    pub fn new(traj: &Trajectory, gamma: f64) -> Self {
        Self::of(traj, DenseSet::new(traj, gamma))
    }

    pub fn of(traj: &Trajectory, set: DenseSet) -> Self {
        let n = set.n;
        let widths = traj.cell_widths_s().to_vec();

        // Flood fill, 4-connected.
        let mut label = vec![OUTSIDE; n * n];
        let mut count = 0u32;
        let mut queue = VecDeque::new();
        for seed in 0..n * n {
            if !set.inside[seed] || label[seed] != OUTSIDE {
                continue;
            }
            label[seed] = count;
            queue.push_back(seed);
            while let Some(cell) = queue.pop_front() {
                let (i, j) = (cell / n, cell % n);
                let mut visit = |k: usize| {
                    if set.inside[k] && label[k] == OUTSIDE {
                        label[k] = count;
                        queue.push_back(k);
                    }
                };
                if i > 0 {
                    visit(cell - n);
                }
                if i + 1 < n {
                    visit(cell + n);
                }
                if j > 0 {
                    visit(cell - 1);
                }
                if j + 1 < n {
                    visit(cell + 1);
                }
            }
            count += 1;
        }

        let mut components = vec![
            DenseComponent {
                trivial: false,
                mirror: OUTSIDE,
                cells: 0,
                area_s2: 0.0,
                rows: [usize::MAX, 0],
                columns: [usize::MAX, 0],
                first_upper: None,
                upper_runs: 0,
                euler: 0,
                holes_by_fill: 0,
                closest: (f64::INFINITY, [0, 0]),
            };
            count as usize
        ];
        let at = |i: usize, j: usize| label[i * n + j];
        for i in 0..n {
            for j in 0..n {
                let l = at(i, j);
                if l == OUTSIDE {
                    continue;
                }
                let c = &mut components[l as usize];
                c.trivial |= i == j;
                c.mirror = at(j, i);
                c.cells += 1;
                c.area_s2 += widths[i] * widths[j];
                c.rows = [c.rows[0].min(i), c.rows[1].max(i)];
                c.columns = [c.columns[0].min(j), c.columns[1].max(j)];
                // Euler number: this pixel, its right and lower 4-neighbours, the 2×2 block it
                // is the top-left of.
                c.euler += 1;
                let right = j + 1 < n && at(i, j + 1) == l;
                let down = i + 1 < n && at(i + 1, j) == l;
                c.euler -= i64::from(right) + i64::from(down);
                if right && down && at(i + 1, j + 1) == l {
                    c.euler += 1;
                }
                if j >= i {
                    c.first_upper.get_or_insert((i, j));
                    if j == i || !set.at(i, j - 1) {
                        c.upper_runs += 1;
                    }
                    let d = set.delta(i, j);
                    if d < c.closest.0 {
                        c.closest = (d, [i, j]);
                    }
                }
            }
        }
        for (l, c) in components.iter_mut().enumerate() {
            c.holes_by_fill = holes_by_fill(n, &label, l as u32, c.rows, c.columns);
        }
        let mut upper_order: Vec<u32> = (0..count).filter(|&l| components[l as usize].first_upper.is_some()).collect();
        upper_order.sort_by_key(|&l| components[l as usize].first_upper);
        Self { set, widths, label, components, upper_order }
    }

    pub fn label_at(&self, i: usize, j: usize) -> Option<u32> {
        let l = self.label[i * self.set.n + j];
        (l != OUTSIDE).then_some(l)
    }

    /// τ(t_i) of each dense component, for each row i, by summing the full row of the matrix:
    /// `Both` every column, `Begin` j > i, `End` j < i, the diagonal cell half to each of `Begin`
    /// and `End`. Indexed `[label][i]`.
    pub fn tau_by_label(&self, side: Side) -> Vec<Vec<f64>> {
        let n = self.set.n;
        let mut tau = vec![vec![0.0; n]; self.components.len()];
        for (cell, &l) in self.label.iter().enumerate() {
            let (i, j) = (cell / n, cell % n);
            if l != OUTSIDE {
                let w = self.widths[j];
                tau[l as usize][i] += match (side, j.cmp(&i)) {
                    (Side::Both, _) => w,
                    (_, Ordering::Equal) => 0.5 * w,
                    (Side::Begin, Ordering::Greater) | (Side::End, Ordering::Less) => w,
                    _ => 0.0,
                };
            }
        }
        tau
    }

    /// τ of engine component `id` (its upper half and its mirror) from [`tau_by_label`].
    pub fn engine_tau(&self, by_label: &[Vec<f64>], id: usize) -> Vec<f64> {
        let l = self.upper_order[id];
        let mirror = self.components[l as usize].mirror;
        let mut tau = by_label[l as usize].clone();
        if mirror != l {
            tau.iter_mut().zip(&by_label[mirror as usize]).for_each(|(t, x)| *t += x);
        }
        tau
    }

    /// τ over all of S_γ from [`tau_by_label`].
    pub fn total_tau(by_label: &[Vec<f64>], n: usize) -> Vec<f64> {
        let mut tau = vec![0.0; n];
        for row in by_label {
            tau.iter_mut().zip(row).for_each(|(t, x)| *t += x);
        }
        tau
    }
}

/// Holes of the mask `label == l` by flood fill: background 8-connected in the mask's bounding
/// box padded by one cell; regions not reaching the padding are holes.
fn holes_by_fill(n: usize, label: &[u32], l: u32, rows: [usize; 2], columns: [usize; 2]) -> u64 {
    let (h, w) = (rows[1] - rows[0] + 3, columns[1] - columns[0] + 3);
    let foreground = |r: usize, c: usize| {
        (1..h - 1).contains(&r) && (1..w - 1).contains(&c) && label[(rows[0] + r - 1) * n + (columns[0] + c - 1)] == l
    };
    let mut seen = vec![false; h * w];
    let fill = |start: usize, seen: &mut Vec<bool>| {
        let mut queue = VecDeque::from([start]);
        seen[start] = true;
        while let Some(cell) = queue.pop_front() {
            let (r, c) = (cell / w, cell % w);
            for dr in [-1i64, 0, 1] {
                for dc in [-1i64, 0, 1] {
                    let (rr, cc) = (r as i64 + dr, c as i64 + dc);
                    if rr < 0 || cc < 0 || rr >= h as i64 || cc >= w as i64 {
                        continue;
                    }
                    let (rr, cc) = (rr as usize, cc as usize);
                    if !seen[rr * w + cc] && !foreground(rr, cc) {
                        seen[rr * w + cc] = true;
                        queue.push_back(rr * w + cc);
                    }
                }
            }
        }
    };
    fill(0, &mut seen); // the padding corner is background and reaches the whole border
    let mut holes = 0;
    for cell in 0..h * w {
        if !seen[cell] && !foreground(cell / w, cell % w) {
            fill(cell, &mut seen);
            holes += 1;
        }
    }
    holes
}

// ---------------------------------------------------------------------------------------------
// Comparisons
// ---------------------------------------------------------------------------------------------

macro_rules! ensure {
    ($cond:expr, $($fmt:tt)+) => {
        let holds: bool = $cond;
        if !holds {
            return Err(format!($($fmt)+));
        }
    };
}

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-9 * scale.max(f64::MIN_POSITIVE)
}

fn close_all(a: &[f64], b: &[f64], scale: f64) -> Result<(), String> {
    ensure!(a.len() == b.len(), "lengths {} and {}", a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        ensure!(close(*x, *y, scale), "index {i}: {x} vs {y}");
    }
    Ok(())
}

/// Runs the engine on `traj` and compares everything with the dense reference; `interval` is a
/// sub-interval [a, b] of time as fractions of the span (may reach outside it).
pub fn check_against_dense(traj: &Trajectory, gamma: f64, interval: (f64, f64)) -> Result<(), String> {
    let loops = find_loops(traj, &Euclidean, gamma).map_err(|e| e.to_string())?;
    let dense = DenseLoops::new(traj, gamma);
    check_components(traj, &loops, &dense)?;
    check_measures(traj, &loops, &dense, interval)?;
    check_warning(traj, &loops, &dense)
}

/// As [`check_against_dense`], for the revisits `separation` apart.
pub fn check_separated_against_dense(
    traj: &Trajectory,
    gamma: f64,
    separation: Separation,
    interval: (f64, f64),
) -> Result<(), String> {
    let loops = find_loops_separated(traj, &Euclidean, gamma, separation).map_err(|e| e.to_string())?;
    let dense = DenseLoops::of(traj, DenseSet::separated(traj, gamma, separation));
    check_components(traj, &loops, &dense)?;
    check_measures(traj, &loops, &dense, interval)?;
    ensure!(loops.components().iter().all(|c| !c.trivial), "a trivial revisit component");
    match (dense.set.cells(), loops.warnings()) {
        (0, [Warning::NoLoops { separation: s, .. }]) if *s == separation => Ok(()),
        (cells, []) if cells > 0 => Ok(()),
        (cells, warnings) => Err(format!("{cells} cells, warnings {warnings:?}")),
    }
}

/// Partition, count, and every field of every component.
pub fn check_components(traj: &Trajectory, loops: &Loops, dense: &DenseLoops) -> Result<(), String> {
    let n = traj.len();
    let span = traj.span_s();
    ensure!(loops.len() == n, "len");
    ensure!(loops.pair_count() == dense.set.cells(), "pairs {} vs dense {}", loops.pair_count(), dense.set.cells());

    // The same-component relation, both ways: a bijection between engine ids and dense labels
    // of the upper half, respected by every cell.
    let mut dense_of_engine = vec![OUTSIDE; loops.components().len()];
    let mut engine_of_dense = vec![usize::MAX; dense.components.len()];
    for i in 0..n {
        for j in 0..n {
            let (engine, reference) = (loops.component_of(i, j), dense.label_at(i, j));
            ensure!(
                engine.is_some() == reference.is_some(),
                "({i}, {j}): engine {engine:?}, dense inside {}",
                reference.is_some()
            );
            ensure!(engine == loops.component_of(j, i), "({i}, {j}) and ({j}, {i}) differ");
            let (Some(e), Some(l), true) = (engine, reference, j >= i) else {
                continue;
            };
            ensure!(e < dense_of_engine.len(), "({i}, {j}): id {e} out of range");
            ensure!(
                dense_of_engine[e] == OUTSIDE || dense_of_engine[e] == l,
                "engine component {e} holds two dense components (at ({i}, {j}))"
            );
            ensure!(
                engine_of_dense[l as usize] == usize::MAX || engine_of_dense[l as usize] == e,
                "dense component {l} split across engine components (at ({i}, {j}))"
            );
            dense_of_engine[e] = l;
            engine_of_dense[l as usize] = e;
            let simple = dense.components[l as usize].trivial;
            ensure!(loops.is_simple(i, j) == simple, "is_simple({i}, {j})");
        }
    }
    ensure!(
        loops.components().len() == dense.upper_order.len(),
        "{} components, dense {}",
        loops.components().len(),
        dense.upper_order.len()
    );
    // Numbered in order of their first cell, row by row.
    for (id, &l) in dense.upper_order.iter().enumerate() {
        ensure!(dense_of_engine[id] == l, "component {id} is not the {id}-th by first cell");
    }

    for (id, c) in loops.components().iter().enumerate() {
        let d = &dense.components[dense.upper_order[id] as usize];
        let at = format!("component {id} ({c:?}) vs dense {d:?}");
        ensure!(c.id == id, "id: {at}");
        ensure!(c.trivial == d.trivial, "trivial: {at}");
        if !d.trivial {
            // A non-trivial component and its mirror are two dense components.
            ensure!(d.mirror != dense.upper_order[id], "non-trivial mirror: {at}");
        }
        ensure!(c.pair_count == d.cells, "pairs: {at}");
        ensure!(close(c.area_s2, d.area_s2, span * span), "area: {at}");
        ensure!(c.run_count == d.upper_runs, "runs: {at}");
        ensure!(d.euler <= 1, "dense Euler number above 1: {at}");
        ensure!(d.holes_by_fill as i64 == 1 - d.euler, "the two dense hole counts differ: {at}");
        ensure!(c.holes as i64 == 1 - d.euler, "holes: {at}");
        ensure!(c.i_range == d.rows, "rows: {at}");
        ensure!(c.j_range == d.columns, "columns: {at}");
        ensure!(c.closest_distance == d.closest.0, "closest distance: {at}");
        ensure!(!d.trivial || c.closest_distance == 0.0, "trivial closest: {at}");
        let [ci, cj] = c.closest_pair;
        ensure!(ci <= cj && cj < n, "closest pair order: {at}");
        ensure!(loops.component_of(ci, cj) == Some(id), "closest pair outside the component: {at}");
        ensure!(dense.set.delta(ci, cj) == c.closest_distance, "closest pair does not attain the distance: {at}");
        // The documented rule: argmin of the metric's rank (δ² here), earliest in row order. The
        // dense reference ranks by δ, so the two may differ only between cells of equal δ; find
        // the first cell of the component with the smallest δ² independently.
        let rank =
            |i: usize, j: usize| traj.point(i).iter().zip(traj.point(j)).map(|(a, b)| (a - b) * (a - b)).sum::<f64>();
        let mut first_by_rank: Option<(f64, [usize; 2])> = None;
        for i in d.rows[0]..=d.rows[1] {
            for j in i..n {
                if dense.label[i * n + j] == dense.upper_order[id] && first_by_rank.is_none_or(|(r, _)| rank(i, j) < r)
                {
                    first_by_rank = Some((rank(i, j), [i, j]));
                }
            }
        }
        ensure!(
            first_by_rank.map(|(_, pair)| pair) == Some(c.closest_pair),
            "closest pair is not the first smallest δ² in row order: {at}"
        );
    }
    Ok(())
}

/// τ, α, ρ against sums over the dense matrix.
pub fn check_measures(
    traj: &Trajectory,
    loops: &Loops,
    dense: &DenseLoops,
    interval: (f64, f64),
) -> Result<(), String> {
    let n = traj.len();
    let t = traj.timestamps_s();
    let (t0, t_end, span) = (t[0], t[n - 1], traj.span_s());
    let w = traj.cell_widths_s();
    let seconds = |sel: Selection<'_>, side| loops.loop_duration(sel, side, Scale::Seconds).map_err(|e| e.to_string());

    const SIDES: [Side; 3] = [Side::Both, Side::Begin, Side::End];
    let by_label = SIDES.map(|side| dense.tau_by_label(side));
    let [tau, begin, end] = SIDES.map(|side| seconds(Selection::All, side));
    let (tau, begin, end) = (tau?, begin?, end?);
    for (k, engine) in [&tau, &begin, &end].into_iter().enumerate() {
        let reference = DenseLoops::total_tau(&by_label[k], n);
        close_all(engine, &reference, span).map_err(|e| format!("τ {:?}: {e}", SIDES[k]))?;
    }
    let sum: Vec<f64> = begin.iter().zip(&end).map(|(b, e)| b + e).collect();
    close_all(&sum, &tau, span).map_err(|e| format!("begin + end: {e}"))?;

    // Whole span: α = Σ w_i τ_i = Σ trivial areas + 2 Σ non-trivial areas.
    let alpha = loops.loop_area(t0, t_end, Selection::All, Side::Both, Scale::Seconds).map_err(|e| e.to_string())?;
    let weighted: f64 = w.iter().zip(&tau).map(|(w, tau)| w * tau).sum();
    let by_components: f64 =
        loops.components().iter().map(|c| if c.trivial { c.area_s2 } else { 2.0 * c.area_s2 }).sum();
    let dense_area: f64 = dense.components.iter().map(|c| c.area_s2).sum();
    let scale2 = span * span;
    ensure!(close(alpha, weighted, scale2), "α {alpha} vs Σ w τ {weighted}");
    ensure!(close(alpha, by_components, scale2), "α {alpha} vs components {by_components}");
    ensure!(close(alpha, dense_area, scale2), "α {alpha} vs dense {dense_area}");

    // Sub-interval [a, b]: cells [m_{i−1}, m_i] between midpoints, clipped to the span.
    let (a, b) = (t0 + interval.0 * span, t0 + interval.1 * span);
    let midpoint = |i: usize| 0.5 * (t[i] + t[i + 1]);
    let reference: f64 = (0..n)
        .map(|i| {
            let lo = if i == 0 { t0 } else { midpoint(i - 1) };
            let hi = if i + 1 == n { t_end } else { midpoint(i) };
            let overlap = (hi.min(b) - lo.max(a)).max(0.0);
            overlap * tau[i]
        })
        .sum();
    let area = loops.loop_area(a, b, Selection::All, Side::Both, Scale::Seconds).map_err(|e| e.to_string())?;
    ensure!(close(area, reference, scale2), "α[{a}, {b}] = {area}, reference {reference}");
    let density = loops.loop_density(a, b, Selection::All, Side::Both, Scale::Seconds).map_err(|e| e.to_string())?;
    ensure!(close(density, reference / (b - a), span), "ρ[{a}, {b}] = {density}");

    // Normalized units: τ / span, α / span², ρ / span, with a and b mapped to [0, 1].
    let tau_normalized =
        loops.loop_duration(Selection::All, Side::Both, Scale::Normalized).map_err(|e| e.to_string())?;
    let expected: Vec<f64> = tau.iter().map(|x| x / span).collect();
    close_all(&tau_normalized, &expected, 1.0).map_err(|e| format!("normalized τ: {e}"))?;
    let (a_n, b_n) = ((a - t0) / span, (b - t0) / span);
    let area_normalized =
        loops.loop_area(a_n, b_n, Selection::All, Side::Both, Scale::Normalized).map_err(|e| e.to_string())?;
    ensure!(close(area_normalized, area / scale2, 1.0), "normalized α {area_normalized} vs {}", area / scale2);
    let density_normalized =
        loops.loop_density(a_n, b_n, Selection::All, Side::Both, Scale::Normalized).map_err(|e| e.to_string())?;
    ensure!(close(density_normalized, density / span, 1.0), "normalized ρ {density_normalized} vs {}", density / span);

    // Per component: τ against the dense rows restricted to the component and its mirror, and
    // the areas add up to the whole. Begin and End on a spread of components only (cost).
    let count = loops.components().len();
    let mut total_area = 0.0;
    let mut total_tau = vec![0.0; n];
    for id in 0..count {
        let one_side_only = count > 12 && id % (count / 6) != 0 && id + 1 != count;
        for (k, side) in SIDES.into_iter().enumerate().take(if one_side_only { 1 } else { 3 }) {
            let tau_c = seconds(Selection::Components(&[id]), side)?;
            close_all(&tau_c, &dense.engine_tau(&by_label[k], id), span)
                .map_err(|e| format!("τ of component {id}, {side:?}: {e}"))?;
            if side == Side::Both {
                total_tau.iter_mut().zip(&tau_c).for_each(|(s, x)| *s += x);
            }
        }
        let area_c = loops
            .loop_area(t0, t_end, Selection::Components(&[id]), Side::Both, Scale::Seconds)
            .map_err(|e| e.to_string())?;
        let c = &loops.components()[id];
        let expected = if c.trivial { c.area_s2 } else { 2.0 * c.area_s2 };
        ensure!(close(area_c, expected, scale2), "α of component {id}: {area_c} vs {expected}");
        total_area += area_c;
    }
    close_all(&total_tau, &tau, span).map_err(|e| format!("Σ τ over components: {e}"))?;
    ensure!(close(total_area, alpha, scale2), "Σ α over components {total_area} vs {alpha}");
    let all: Vec<usize> = (0..loops.components().len()).collect();
    let area_all =
        loops.loop_area(a, b, Selection::Components(&all), Side::Both, Scale::Seconds).map_err(|e| e.to_string())?;
    ensure!(close(area_all, area, scale2), "all components listed: {area_all} vs {area}");
    Ok(())
}

/// The broken-diagonal warning against the dense consecutive pairs and trivial components.
pub fn check_warning(traj: &Trajectory, loops: &Loops, dense: &DenseLoops) -> Result<(), String> {
    let n = traj.len();
    let gaps: Vec<usize> = (0..n - 1).filter(|&i| !dense.set.at(i, i + 1)).collect();
    let trivial = dense.upper_order.iter().filter(|&&l| dense.components[l as usize].trivial).count();
    ensure!(loops.components().iter().filter(|c| c.trivial).count() == trivial, "trivial components");
    // The diagonal breaks into gaps + 1 stretches; some may reconnect off the diagonal.
    ensure!(trivial >= 1 && trivial <= gaps.len() + 1, "{trivial} trivial, {} gaps", gaps.len());
    match (gaps.first(), loops.warnings()) {
        (None, []) => Ok(()),
        (Some(&first), [Warning::DiagonalBroken { gaps: count, first_gap, largest_step, trivial_components }]) => {
            let largest = gaps.iter().map(|&i| dense.set.delta(i, i + 1)).fold(0.0, f64::max);
            ensure!(*count == gaps.len(), "gaps {count} vs {}", gaps.len());
            ensure!(*first_gap == first, "first gap {first_gap} vs {first}");
            ensure!(*largest_step == largest, "largest step {largest_step} vs {largest}");
            ensure!(largest > dense.set.gamma, "largest step within γ");
            ensure!(*trivial_components == trivial, "trivial components {trivial_components} vs {trivial}");
            Ok(())
        }
        (gap, warnings) => Err(format!("first gap {gap:?}, warnings {warnings:?}")),
    }
}

//! # loops-core
//!
//! Exact *inexact loops* of sampled trajectories, after E. Nelson, "Inexact Loops in Robotics
//! Problems": the places where a trajectory ξ comes back within a distance γ of itself.
//!
//! - The sublevel set S_γ = {(t, t′) : δ(ξ(t), ξ(t′)) ≤ γ} on the sample lattice, exactly (every
//!   pair, nothing subsampled), stored as runs and never as a list of pairs: [`SublevelSet`].
//! - Loop components (4-connected components of S_γ), trivial ones (holding the diagonal, whose
//!   pairs are simple loops), areas in s², holes, closest pairs: [`find_loops`], [`LoopComponent`].
//! - Loop duration τ, loop area α and loop density ρ over S_γ or any set of components:
//!   [`Loops::loop_duration`], [`Loops::loop_area`], [`Loops::loop_density`].
//! - Any [`Metric`] satisfying the triangle inequality: [`Euclidean`] on Rⁿ, [`So3`], [`Se3`],
//!   [`Se2`], [`Torus`], [`Sphere`], [`Haversine`] (GNSS) and [`Angular`] (descriptors); by name
//!   with [`MetricSpec`]. Validated pose constructors: [`Trajectory::se3`] and friends, which
//!   record their [`Manifold`] so that its metric measures them by default and no other does.
//! - A seeded synthetic urban drive for demos and benchmarks: [`UrbanDrive`].
//! - Online, while the robot drives: S_γ, its components and τ updated pose by pose at a cost
//!   that follows the answer ([`online::OnlineLoops`], equal to the batch), and loop-closure
//!   candidates per keyframe with σ_ρ, a cap, P1 online and the revisit separation
//!   ([`online::OnlineSampler`]).
//! - Fleets of sessions in one frame ([`fleet`]), cut into tiles that other machines scan and
//!   a tree of merges joins ([`tile`]), and kept up to date as sessions come and go ([`store`]).
//! - Figures' data on the (t, t′) plane: the pairwise distance π_ξ on a grid of poses for any
//!   metric, the component of every pixel, the outlines ∂Ω and isocontours: [`plane`],
//!   [`Loops::label_image`].
//!
//! What it does not do: read files (that is `loops-io`), talk to Python or a terminal.
//!
//! ## Public surface in two tiers
//! The root holds what a user of one trajectory calls: [`find_loops`] with its options and
//! results, [`Trajectory`] and its poses, the metrics and manifolds, the samplers' entry points
//! ([`sample_loops`], [`sample_clusters`], [`Sampler`], [`SamplerKind`], [`SampleSize`]) and
//! their results, detections, baselines and quality, the synthetic drives, threads, interrupts
//! and [`Error`]. An engine that a user picks on purpose is a public module, and its names are
//! reached through it, never flat from the root: [`fleet`] (several sessions in one frame),
//! [`tile`] (a fleet's plane in tiles: plan, scan, merge, draw, bytes), [`store`] (a fleet kept
//! up to date), [`online`] (pose by pose), [`plane`] (images and outlines of the (t, t′)
//! plane) and [`sample`] (the samplers' keyed draws and their requests, for tiles and
//! clusters). A name belongs to the root when a program on one trajectory needs it (the
//! samplers' entry points are re-exported there from [`sample`]); every other public name is
//! reached through its module only.
//!
//! ## Module order
//! The modules follow the paper, and each uses only modules before it (no cycles):
//! `trajectory` (ξ, time cells, [`Timeline`]) → `metric` (δ) → `manifold` and `pose` (metrics
//! and points on manifolds) → `spec` ([`MetricSpec`]) → `sublevel` (S_γ, [`check_gamma`]) →
//! `component` (Ω) → `measure` (τ, α, ρ) → `loops` ([`find_loops`]) → [`plane`] (π_ξ and ∂Ω on
//! a grid of poses) → `verdict` (where given pairs fall: [`Loops::pair_verdicts`]) → `draw`
//! ([`SampleSize`], uniform draws over S_γ) → `detection` (D) → `cluster` (the ε graph,
//! [`check_epsilon_s`]) → `baseline` ([`Baseline`]) → [`sample`] (σ_1, σ_ρ, σ_α) → `quality`
//! (P1, P2, P3); [`online`] (after `loops` and `draw`); [`fleet`], [`tile`] and [`store`]
//! (after `loops` and `sample`); `synth`, `ball_tree`, `union_find`, `memory` (fallible
//! allocation of the big buffers) and `interrupt` ([`Interrupt`]) are helpers.
//!
//! ## Quickstart
//! ```
//! use loops_core::{Euclidean, Scale, Selection, Side, UrbanDrive, find_loops};
//!
//! let drive = UrbanDrive { duration_s: 600.0, seed: 7, ..UrbanDrive::default() }.generate()?;
//! let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
//! for c in loops.components().iter().filter(|c| !c.trivial).take(3) {
//!     println!("component {}: {:.0} s², {} holes, closest {:.1} m", c.id, c.area_s2, c.holes, c.closest_distance);
//! }
//! let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;
//! let alpha = loops.loop_area(0.0, loops.span_s(), Selection::All, Side::Both, Scale::Seconds)?;
//! let areas: f64 = loops.components().iter().map(|c| if c.trivial { c.area_s2 } else { 2.0 * c.area_s2 }).sum();
//! assert!((alpha - areas).abs() <= 1e-9 * alpha);
//! assert_eq!(tau.len(), drive.trajectory.len());
//! # Ok::<(), loops_core::Error>(())
//! ```
#![warn(missing_docs)]

mod ball_tree;
mod baseline;
mod cluster;
mod component;
mod detection;
mod draw;
mod error;
pub mod fleet;
mod interrupt;
mod loops;
mod manifold;
mod measure;
mod memory;
mod metric;
pub mod online;
#[cfg(feature = "serde")]
mod packed;
mod place;
pub mod plane;
mod pose;
mod quality;
mod relative;
pub mod sample;
mod separation;
mod spatial;
mod spec;
pub mod store;
mod sublevel;
mod synth;
pub mod tile;
mod trajectory;
mod union_find;
mod verdict;

pub use baseline::{Baseline, BaselineParams, Cartographer, HdlGraphSlam, LioSam, TimeGap};
pub use cluster::{DEFAULT_EPSILON_S, DetectionCluster, DetectionClusters, check_epsilon_s, cluster_detections};
pub use component::LoopComponent;
pub use detection::{Detection, Detections};
pub use draw::{MAX_SAMPLES, SampleSize, SampleWarning};
pub use error::{Error, ErrorClass, MetricMisfit, Result, TooManySamples};
pub use interrupt::Interrupt;
pub use loops::{LabelledRun, Loops, Warning, find_loops, find_loops_separated};
pub use manifold::{
    Angular, EARTH_RADIUS_M, Haversine, RotationDistance, Se2, Se3, Se3Rotation, So3, Sphere, Torus, UNIT_TOLERANCE,
    angle_difference, wrap_angle,
};
pub use measure::{Scale, Selection, Side};
pub use metric::{Euclidean, Metric};
pub use place::{Pass, Place, check_radius, passes_near};
pub use pose::{FILE_QUATERNION_TOLERANCE, QUATERNION_TOLERANCE, enu_axes};
pub use quality::{MissedComponent, SampleQuality, sample_quality};
pub use relative::{RelativePose, relative_pose, se2_between, se3_between};
pub use sample::{Sample, Sampler, SamplerKind, Samples, sample_clusters, sample_loops};
pub use separation::Separation;
pub use spec::{MetricSpec, recorded_metric_name};
pub use sublevel::{Run, SublevelSet, check_gamma, path_length};
pub use synth::{Districts, SyntheticDrive, UrbanDrive, UrbanFleet};
pub use trajectory::{MAX_MAGNITUDE, MAX_POSES, Manifold, Timeline, Trajectory};
pub use verdict::{PairVerdict, Verdict};

/// The most worker threads [`with_threads`] starts: far more than any machine has cores (the
/// engine gains nothing past one thread per core), and few enough that a mistyped count is
/// refused at once instead of spending minutes starting threads.
pub const MAX_THREADS: usize = 1024;

/// Checks a thread count before any thread starts: 1 to [`MAX_THREADS`].
///
/// # Errors
/// [`Error::InvalidParameter`] for 0 or more than [`MAX_THREADS`].
pub fn check_threads(threads: usize) -> Result<()> {
    const EXPECTED: &str = "between 1 and 1024 (loops_core::MAX_THREADS)";
    const _: () = assert!(MAX_THREADS == 1024, "EXPECTED names the cap");
    if (1..=MAX_THREADS).contains(&threads) {
        Ok(())
    } else {
        Err(Error::InvalidParameter { name: "threads", value: threads as f64, expected: EXPECTED })
    }
}

/// Runs `f` on a rayon pool of `threads` threads (`None`: the process's default pool, one
/// thread per core).
///
/// Results of this crate do not depend on the thread count. An [`Interrupt`] installed on the
/// calling thread applies inside `f` too.
///
/// The default pool belongs to the process that made it: a child made by `fork` (Python's
/// `multiprocessing` with the `fork` start method, `os.fork`, a pre-forking server) inherits
/// the parent's pool in memory but none of its threads, so work sent there would wait for
/// ever. A call from such a child makes the child a pool of its own, and leaves the parent's
/// alone.
///
/// # Errors
/// [`Error::InvalidParameter`] when `threads` is 0 or more than [`MAX_THREADS`]
/// ([`check_threads`]; no thread is started then), or the pool cannot be built.
///
/// # Examples
/// ```
/// assert_eq!(loops_core::with_threads(Some(2), || 1 + 1)?, 2);
/// assert!(loops_core::with_threads(Some(loops_core::MAX_THREADS + 1), || ()).is_err());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn with_threads<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> Result<R> {
    match threads {
        None => {
            let pool = default_pool()?;
            let interrupt = Interrupt::current();
            Ok(pool.install(|| interrupt.run(f)))
        }
        Some(count) => {
            check_threads(count)?;
            let pool = rayon::ThreadPoolBuilder::new().num_threads(count).build();
            match (count, pool) {
                (1.., Ok(pool)) => {
                    // The pool's threads see the caller's interrupt token.
                    let interrupt = Interrupt::current();
                    Ok(pool.install(|| interrupt.run(f)))
                }
                _ => Err(Error::InvalidParameter {
                    name: "threads",
                    value: count as f64,
                    expected: "a positive number of threads the system can start",
                }),
            }
        }
    }
}

/// The pool of [`with_threads`]`(None, ..)`, made on first use in each process (see there).
fn default_pool() -> Result<std::sync::Arc<rayon::ThreadPool>> {
    use std::sync::{Arc, Mutex, PoisonError};
    static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);
    let pid = std::process::id();
    let mut held = POOL.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some((owner, pool)) = held.as_ref()
        && *owner == pid
    {
        return Ok(Arc::clone(pool));
    }
    // A pool of the parent, whose threads this process does not have: dropping it would signal
    // threads that are not there, so it is left as it is.
    if let Some(inherited) = held.take() {
        std::mem::forget(inherited);
    }
    let pool = rayon::ThreadPoolBuilder::new().build().map_err(|_| Error::InvalidParameter {
        name: "threads",
        value: 0.0,
        expected: "a pool of threads the system can start",
    })?;
    let pool = Arc::new(pool);
    *held = Some((pid, Arc::clone(&pool)));
    Ok(pool)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_counts_past_the_cap_are_refused_before_any_thread_starts() {
        let start = std::time::Instant::now();
        let error = with_threads(Some(1_000_000), || ()).unwrap_err();
        assert!(matches!(error, Error::InvalidParameter { name: "threads", .. }));
        assert!(error.to_string().contains(&format!("between 1 and {MAX_THREADS}")), "{error}");
        assert!(start.elapsed().as_secs() < 5);
        assert!(with_threads(Some(0), || ()).is_err());
        assert_eq!(with_threads(Some(MAX_THREADS.min(4)), || 7).unwrap(), 7);
    }
}

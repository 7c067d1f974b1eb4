//! A parked robot against a moving drive with about as many runs: time and peak memory of
//! `find_loops`: no cost beyond the answer.
//!
//! `cargo run --release -p loops-benches --example stationary -- 1000000 [threads]`
//!
//! The parked robot reports n identical poses at 10 Hz: S_γ is the whole plane, one component
//! in n runs (row i: columns i..n). The moving robot drives a straight road at 10 m/s with the
//! same number of poses: also n runs (row i: the next 40 m), but short ones. Then the urban
//! drive (1 km² city, γ = 40 m), for scale. Prints one line per case: poses, runs,
//! components, seconds, and the process's peak resident set so far (`VmHWM`, so the cases run
//! in increasing order of memory).

use std::time::Instant;

use loops_benches::peak_rss_mb;
use loops_core::{Euclidean, Trajectory, find_loops, with_threads};

fn report(name: &str, traj: &Trajectory, threads: usize) {
    let start = Instant::now();
    let loops = with_threads(Some(threads), || find_loops(traj, &Euclidean, 40.0)).expect("pool").expect("input");
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{name:<8} poses {:>9} runs {:>10} components {:>6} time {:>8.3} s peak {:>7.0} MB",
        traj.len(),
        loops.runs().count(),
        loops.components().len(),
        seconds,
        peak_rss_mb()
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(1_000_000);
    let threads: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1);
    let times: Vec<f64> = (0..n).map(|i| i as f64 * 0.1).collect();
    let parked = Trajectory::from_points(times, &vec![[12.0, -3.0, 0.5]; n]).expect("valid");
    report("parked", &parked, threads);
    drop(parked);
    let road: Vec<[f64; 3]> = (0..n).map(|i| [i as f64, 0.0, 0.0]).collect();
    let straight = Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &road).expect("valid");
    report("straight", &straight, threads);
    drop(straight);
    if args.get(3).is_some_and(|a| a == "urban") {
        report("urban", &loops_benches::urban_drive(n as f64 / 36_000.0), threads);
    }
}

//! Latency of the online engine per pose, and its memory.
//!
//! `cargo run --release -p loops-benches --example online_latency [-- quick]`
//!
//! Pushes every pose of a drive into an `OnlineLoops` one at a time, as a front end would, and
//! offers every update to an `OnlineSampler` (σ_ρ at r = 0.05, a cap of 6 a minute per
//! component, revisits at least 4γ of travel apart). Prints, per drive: the poses, runs and
//! components; p50, p99, p99.9 and the largest latency of a push and of a push with its offer;
//! the total; the peak resident set above the baseline taken once the drive was generated
//! (`VmHWM`, reset through `/proc/self/clear_refs`); and `find_loops` on the whole drive for
//! scale, with a check that the engine's snapshot equals it. `quick` runs 10 min drives only.
//!
//! Drives: the reference 2.1 h urban drive (1 km², 75,600 poses) and the 10⁶-pose drive of the
//! scale benchmark (10 × 10 km worked one 1 km² district at a time), γ = 40 m.

use std::time::Instant;

use loops_core::{
    Euclidean, MetricSpec, Separation, Trajectory, find_loops,
    online::{Cap, OnlineLoops, OnlineSampler, OnlineSamplerOptions},
    with_threads,
};

/// A `/proc/self/status` field, MB.
fn status_mb(field: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with(field)).map(str::to_owned))
        .and_then(|l| l.split_whitespace().nth(1).and_then(|kb| kb.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Resets the peak resident set to the current one; the resident set now, MB.
fn reset_peak() -> f64 {
    // Writing 5 to clear_refs resets VmHWM (Linux ≥ 4.0); harmless where it fails.
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    status_mb("VmRSS:")
}

/// Percentiles of latencies in nanoseconds, as microseconds.
fn percentiles(mut ns: Vec<u64>) -> String {
    ns.sort_unstable();
    let at = |q: f64| ns[((ns.len() - 1) as f64 * q).round() as usize] as f64 / 1000.0;
    format!("p50 {:>6.1} µs  p99 {:>7.1} µs  p99.9 {:>8.1} µs  max {:>9.1} µs", at(0.5), at(0.99), at(0.999), at(1.0))
}

fn report(name: &str, traj: &Trajectory, gamma: f64) {
    let n = traj.len();
    let options = OnlineSamplerOptions {
        rate: 0.05,
        cap: Cap::PerMinute(6.0),
        separation: Separation::for_gamma(gamma),
        ..OnlineSamplerOptions::default()
    };
    let (mut push_ns, mut step_ns) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let baseline_mb = reset_peak();
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, traj.dim(), gamma).expect("valid gamma");
    let mut sampler = OnlineSampler::new(options).expect("valid options");
    let mut candidates = 0;
    let start = Instant::now();
    for k in 0..n {
        let t0 = Instant::now();
        let update = online.push(traj.timestamps_s()[k], traj.point(k)).expect("valid pose");
        let t1 = Instant::now();
        candidates += sampler.offer(&online, &update).expect("the last push, offered once").len();
        let t2 = Instant::now();
        push_ns.push((t1 - t0).as_nanos() as u64);
        step_ns.push((t2 - t0).as_nanos() as u64);
    }
    let total_s = start.elapsed().as_secs_f64();
    let peak_mb = status_mb("VmHWM:") - baseline_mb;
    let components = online.components().count();
    let snapshot = online.to_loops().expect("two poses or more");
    let runs = snapshot.runs().count();
    drop(online);
    let start = Instant::now();
    let batch = with_threads(Some(1), || find_loops(traj, &Euclidean, gamma)).expect("pool").expect("input");
    let batch_s = start.elapsed().as_secs_f64();
    assert!(snapshot == batch, "the online snapshot differs from find_loops");
    println!("{name}: {n} poses, {runs} runs, {components} components, {candidates} candidates");
    println!("  push          {}", percentiles(push_ns));
    println!("  push + offer  {}", percentiles(step_ns));
    println!(
        "  all poses {total_s:.2} s ({:.1} µs a pose); peak {peak_mb:.0} MB above the drive's {baseline_mb:.0} MB; \
         find_loops (1 thread) {batch_s:.2} s; snapshot = find_loops",
        1e6 * total_s / n as f64
    );
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let gamma = 40.0;
    if quick {
        report("urban drive, 10 min", &loops_benches::urban_drive(1.0 / 6.0), gamma);
        return;
    }
    report("urban drive, 2.1 h, 1 km²", &loops_benches::urban_drive(2.1), gamma);
    report("district drive, 28 h (10⁶), 10 × 10 km", &loops_benches::district_drive_1e6(), gamma);
}

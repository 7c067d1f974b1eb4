//! A robot that parks twice at one place against one that parks once: time per run of the
//! batch (`find_loops`, with and without the default separation), the fleet engine (the two
//! stops in two sessions) and the online engine (every pose pushed, with the slowest push).
//!
//! `cargo run --release -p loops-benches --example two_stops -- 1000000 [offset_m ...]`
//!
//! The cases: one stop (every pose the same point), and for each offset (default 0, 10⁻¹⁴ m and
//! 0.5 m) two stops that far apart joined by a 2 km drive ([`loops_benches::parked_twice`]);
//! γ = 40 m, Euclidean, one thread. Prints one line per case and engine: runs, CPU seconds of the
//! engine's thread (and wall-clock seconds), CPU nanoseconds per run and per pose, and for the
//! online engine the 99.9th percentile and the slowest of the pushes (wall-clock). `--skip online` (or batch, separated, fleet) leaves an engine out.

use std::time::Instant;

use loops_benches::thread_cpu_s;
use loops_core::{
    Euclidean, MetricSpec, Separation, Trajectory, find_loops_separated,
    fleet::{Fleet, FleetOptions, find_fleet_loops},
    online::OnlineLoops,
    with_threads,
};

const GAMMA_M: f64 = 40.0;

/// Prints a line: `cpu_s` the engine's CPU time (one thread), `wall_s` its wall-clock time.
fn report(case: &str, engine: &str, traj: &Trajectory, runs: usize, (cpu_s, wall_s): (f64, f64), extra: &str) {
    let per_run_ns = cpu_s * 1e9 / runs as f64;
    let per_pose_ns = cpu_s * 1e9 / traj.len() as f64;
    println!(
        "{case:<14} {engine:<10} runs {runs:>9} cpu {cpu_s:>9.3} s (wall {wall_s:>8.3} s) {per_run_ns:>8.1} ns/run \
         {per_pose_ns:>8.1} ns/pose {extra}"
    );
}

/// A clock of this thread's CPU time and of wall-clock time.
struct Clock(f64, Instant);

impl Clock {
    fn start() -> Self {
        Self(thread_cpu_s(), Instant::now())
    }

    /// (CPU seconds, wall seconds) since the start.
    fn read(&self) -> (f64, f64) {
        (thread_cpu_s() - self.0, self.1.elapsed().as_secs_f64())
    }
}

fn batch(case: &str, traj: &Trajectory, separation: Separation, engine: &str) {
    let clock = Clock::start();
    let loops = find_loops_separated(traj, &Euclidean, GAMMA_M, separation).expect("valid input");
    report(case, engine, traj, loops.sublevel_set().runs().len(), clock.read(), "");
}

fn fleet(case: &str, traj: &Trajectory) {
    // Two sessions, cut halfway.
    let cut = traj.len() / 2;
    let session = |range: std::ops::Range<usize>| {
        Trajectory::new(
            traj.timestamps_s()[range.clone()].to_vec(),
            traj.coords()[range.start * 2..range.end * 2].to_vec(),
            2,
        )
        .expect("valid session")
    };
    let fleet = Fleet::new(vec![("a".into(), session(0..cut)), ("b".into(), session(cut..traj.len()))]).expect("fleet");
    let clock = Clock::start();
    let loops = find_fleet_loops(&fleet, &Euclidean, GAMMA_M, &FleetOptions::default()).expect("valid input");
    report(case, "fleet", traj, loops.loops().sublevel_set().runs().len(), clock.read(), "");
}

fn online(case: &str, traj: &Trajectory) {
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, GAMMA_M).expect("valid gamma");
    let mut runs = 0;
    let mut pushes_s = Vec::with_capacity(traj.len());
    let clock = Clock::start();
    for k in 0..traj.len() {
        let push = Instant::now();
        runs += online.push(traj.timestamps_s()[k], traj.point(k)).expect("valid pose").runs.len();
        pushes_s.push(push.elapsed().as_secs_f64());
    }
    let seconds = clock.read();
    pushes_s.sort_by(f64::total_cmp);
    let p999_ms = pushes_s[(pushes_s.len() - 1) * 999 / 1000] * 1e3;
    let slowest_ms = pushes_s[pushes_s.len() - 1] * 1e3;
    report(case, "online", traj, runs, seconds, &format!("push p99.9 {p999_ms:.3} ms, slowest {slowest_ms:.3} ms"));
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(1_000_000);
    let skip: Vec<&str> = args.windows(2).filter(|w| w[0] == "--skip").map(|w| w[1].as_str()).collect();
    let mut offsets: Vec<f64> = args.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    if offsets.is_empty() {
        offsets = vec![0.0, 1e-14, 0.5];
    }
    let cases = std::iter::once(None).chain(offsets.into_iter().map(Some));
    with_threads(Some(1), || {
        for offset_m in cases {
            let case = offset_m.map_or("one stop".to_owned(), |o| format!("two, {o:e} m"));
            let traj = loops_benches::parked_twice(n, offset_m);
            if !skip.contains(&"batch") {
                batch(&case, &traj, Separation::NONE, "batch");
            }
            if !skip.contains(&"separated") {
                batch(&case, &traj, Separation::for_gamma(GAMMA_M), "separated");
            }
            if !skip.contains(&"fleet") {
                fleet(&case, &traj);
            }
            if !skip.contains(&"online") {
                online(&case, &traj);
            }
        }
    })
    .expect("thread pool");
}

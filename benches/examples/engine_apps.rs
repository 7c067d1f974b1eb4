//! CPU time of the fleet and online engines, for side-by-side runs of two builds.
//!
//! `cargo run --release -p loops-benches --example engine_apps -- fleet CASE VEHICLES MINUTES CITY_M PRUNING [REPS]`
//! `cargo run --release -p loops-benches --example engine_apps -- online HOURS [REPS]`
//!
//! `fleet`: `find_fleet_loops` on the synthetic fleet of `fleet_scale` (CASE `roam` or
//! `districts`, PRUNING `kd-tree` or `hierarchy`, γ = 40 m). `online`: every pose of the urban
//! drive of HOURS pushed into an `OnlineLoops` one at a time (γ = 40 m, Euclidean). Threads from
//! `RAYON_NUM_THREADS` (1 if unset). Prints, per repetition, the CPU time of the engine alone
//! (all threads of the process, `/proc/self/task/*/schedstat`) and its wall time, then what it
//! found, so that two builds can be checked to agree. With `GENERATE_ONLY=1` set it generates
//! the input and stops (for instruction counts by difference, as `benches/callgrind/count.sh`).

use std::time::Instant;

use loops_core::{
    Districts, Euclidean, MetricSpec, UrbanDrive, UrbanFleet,
    fleet::{FleetOptions, Pruning, find_fleet_loops},
    online::OnlineLoops,
    with_threads,
};

/// CPU time of every thread of this process so far, seconds.
fn cpu_s() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else { return f64::NAN };
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        / 1e9
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "engine_apps fleet CASE VEHICLES MINUTES CITY_M PRUNING [REPS] | online HOURS [REPS]";
    let arg = |k: usize| args.get(k).unwrap_or_else(|| panic!("usage: {usage}"));
    let threads: usize = std::env::var("RAYON_NUM_THREADS").ok().and_then(|t| t.parse().ok()).unwrap_or(1);
    let generate_only = std::env::var_os("GENERATE_ONLY").is_some();
    let gamma = 40.0;
    let (reps, work): (usize, Box<dyn Fn() -> String + Send + Sync>) = match arg(1).as_str() {
        "fleet" => {
            let districts = match arg(2).as_str() {
                "roam" => None,
                "districts" => Some(Districts { side_m: 1000.0, dwell_s: 1e9 }),
                _ => panic!("usage: {usage}"),
            };
            let spec = UrbanFleet {
                vehicles: arg(3).parse().expect("vehicles"),
                days: 1,
                drive: UrbanDrive {
                    duration_s: arg(4).parse::<f64>().expect("minutes") * 60.0,
                    city_size_m: arg(5).parse().expect("city side, metres"),
                    districts,
                    ..UrbanDrive::default()
                },
                start_spread_s: 3600.0,
            };
            let fleet = spec.generate().expect("valid fleet");
            let options =
                FleetOptions { pruning: arg(6).parse::<Pruning>().expect("pruning"), ..FleetOptions::default() };
            let reps = args.get(7).and_then(|r| r.parse().ok()).unwrap_or(3);
            (
                reps,
                Box::new(move || {
                    let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).expect("input");
                    format!(
                        "runs {} components {} between {}",
                        loops.loops().runs().count(),
                        loops.components().len(),
                        loops.between_sessions().len()
                    )
                }),
            )
        }
        "online" => {
            let traj = loops_benches::urban_drive(arg(2).parse().expect("hours"));
            let reps = args.get(3).and_then(|r| r.parse().ok()).unwrap_or(3);
            (
                reps,
                Box::new(move || {
                    let mut online = OnlineLoops::new(MetricSpec::Euclidean, traj.dim(), gamma).expect("valid gamma");
                    for k in 0..traj.len() {
                        online.push(traj.timestamps_s()[k], traj.point(k)).expect("valid pose");
                    }
                    let loops = online.to_loops().expect("two poses or more");
                    format!("runs {} components {}", loops.runs().count(), online.components().count())
                }),
            )
        }
        _ => panic!("usage: {usage}"),
    };
    if generate_only {
        return;
    }
    // One pool for every repetition, so that its threads' CPU time is there before and after.
    let found = with_threads(Some(threads), || {
        let mut found = String::new();
        for _ in 0..reps {
            let (cpu0, wall0) = (cpu_s(), Instant::now());
            found = work();
            println!("cpu {:.4} s wall {:.4} s", cpu_s() - cpu0, wall0.elapsed().as_secs_f64());
        }
        found
    })
    .expect("pool");
    println!("{found}");
}

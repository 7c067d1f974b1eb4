//! Fleets at scale: time and peak memory of `find_fleet_loops` on synthetic fleets,
//! with either pruning, against the single-trajectory engine on the same poses.
//!
//! `cargo run --release -p loops-benches --example fleet_scale -- CASE VEHICLES MINUTES CITY_M ENGINE [THREADS]`
//!
//! - CASE: `roam` (every vehicle roams the whole city) or `districts` (each vehicle works its
//!   own 1 km district for the whole drive, so vehicles meet only at district borders);
//! - ENGINE: `kd-tree`, `hierarchy` (the fleet's two prunings) or `single` (`find_loops` on the
//!   fleet's joint trajectory: the same poses as one drive, runs not cut at sessions);
//! - γ = 40 m, no revisit separation, 10 Hz, seed 0.
//!
//! With `FLEET_SCALE_POSES=PATH` set, also writes the fleet's positions (x, y, z as
//! little-endian f64, session after session) to PATH, for `benches/fleet_scale.py`'s
//! `cKDTree.query_pairs` on the same poses.
//!
//! Prints one line: sessions, poses, runs, cells of the upper half (j ≥ i), components, components between sessions, session
//! pairs that meet, seconds of the engine alone (generation excluded), and the peak resident
//! set of the process (`VmHWM`; one case per process).

use std::time::Instant;

use loops_benches::peak_rss_mb;
use loops_core::{
    Districts, Euclidean, UrbanDrive, UrbanFleet, find_loops,
    fleet::{FleetOptions, Pruning, find_fleet_loops},
    with_threads,
};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "fleet_scale CASE(roam|districts) VEHICLES MINUTES CITY_M ENGINE(kd-tree|hierarchy|single) [THREADS]";
    let arg = |k: usize| args.get(k).unwrap_or_else(|| panic!("usage: {usage}"));
    let case = arg(1).as_str();
    let vehicles: usize = arg(2).parse().expect("vehicles");
    let minutes: f64 = arg(3).parse().expect("minutes");
    let city_m: f64 = arg(4).parse().expect("city side, metres");
    let engine = arg(5).as_str();
    let threads: usize = args.get(6).and_then(|a| a.parse().ok()).unwrap_or(1);
    let districts = match case {
        "roam" => None,
        "districts" => Some(Districts { side_m: 1000.0, dwell_s: 1e9 }),
        _ => panic!("usage: {usage}"),
    };
    let spec = UrbanFleet {
        vehicles,
        days: 1,
        drive: UrbanDrive { duration_s: minutes * 60.0, city_size_m: city_m, districts, ..UrbanDrive::default() },
        start_spread_s: 3600.0,
    };
    let fleet = spec.generate().expect("valid fleet");
    if let Ok(path) = std::env::var("FLEET_SCALE_POSES") {
        let bytes: Vec<u8> = fleet.joint().coords().iter().flat_map(|c| c.to_le_bytes()).collect();
        std::fs::write(&path, bytes).expect("writing the poses");
    }
    let gamma = 40.0;
    let start = Instant::now();
    let line = with_threads(Some(threads), || match engine {
        "single" => {
            let loops = find_loops(fleet.joint(), &Euclidean, gamma).expect("input");
            format!(
                "runs {:>11} cells {:>14} components {:>8} between {:>8} meeting {:>7}",
                loops.runs().count(),
                loops.sublevel_set().upper_pairs(),
                loops.components().len(),
                "-",
                "-"
            )
        }
        pruning => {
            let pruning: Pruning = pruning.parse().expect("engine");
            let options = FleetOptions { pruning, ..FleetOptions::default() };
            let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).expect("input");
            let pairs = loops.session_pairs();
            let meeting = pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).count();
            format!(
                "runs {:>11} cells {:>14} components {:>8} between {:>8} meeting {:>7}",
                loops.loops().runs().count(),
                loops.loops().sublevel_set().upper_pairs(),
                loops.components().len(),
                loops.between_sessions().len(),
                meeting
            )
        }
    })
    .expect("thread pool");
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{case} {engine:<9} sessions {:>6} poses {:>9} {line} time {seconds:>8.3} s peak {:>7.0} MB",
        fleet.len(),
        fleet.poses(),
        peak_rss_mb()
    );
}

//! Times the engine as the Scale benchmark uses it (`find_loops`, its components, and τ) on one
//! input, on a pool of the given number of threads, for side-by-side rounds of two builds:
//! `cargo run --release --example engine_rounds -- INPUT THREADS REPEATS`.
//!
//! INPUT is `drive:HOURS` (the urban drive of 1 km², 10 Hz, seed 0, as `drive` generates it) or
//! `skewed:HOURS` (a tenth of the poses spent circling a 200 m square of four blocks first, the
//! rest roaming a 10 km city: dense revisits in one part of the log, few elsewhere). Prints one
//! line: poses, runs, components, and the least wall time of the repeats in seconds.
//! `POINTS_OUT=FILE` writes the positions as little-endian f64 (x, y, z a pose) and stops, for
//! timing other tools on the same input.
use loops_core::{Euclidean, Scale, Selection, Side, Trajectory, UrbanDrive, find_loops};

fn input(spec: &str) -> Result<Trajectory, loops_core::Error> {
    let (kind, hours) = spec.split_once(':').unwrap_or((spec, "2.1"));
    let hours: f64 = hours.parse().unwrap_or(2.1);
    let duration_s = hours * 3600.0;
    match kind {
        "skewed" => {
            let dense = UrbanDrive { duration_s: 0.1 * duration_s, city_size_m: 200.0, ..UrbanDrive::default() }
                .generate()?
                .trajectory;
            let sparse =
                UrbanDrive { duration_s: 0.9 * duration_s, city_size_m: 10_000.0, seed: 1, ..UrbanDrive::default() }
                    .generate()?
                    .trajectory;
            let dim = dense.dim();
            let t0 = dense.timestamps_s()[dense.len() - 1] + 0.1;
            let mut times = dense.timestamps_s().to_vec();
            times.extend(sparse.timestamps_s().iter().map(|t| t0 + t - sparse.timestamps_s()[0]));
            let mut coords = dense.coords().to_vec();
            coords.extend_from_slice(sparse.coords());
            Trajectory::new(times, coords, dim)
        }
        _ => Ok(UrbanDrive { duration_s, ..UrbanDrive::default() }.generate()?.trajectory),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let spec = args.next().unwrap_or_else(|| "drive:2.1".into());
    let threads: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let repeats: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(3);
    let traj = input(&spec)?;
    if let Some(path) = std::env::var_os("POINTS_OUT") {
        let bytes: Vec<u8> = traj.coords().iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(path, bytes)?;
        return Ok(());
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let mut best = f64::INFINITY;
    let mut line = String::new();
    for _ in 0..repeats {
        let (seconds, summary) = pool.install(|| -> Result<_, loops_core::Error> {
            let start = std::time::Instant::now();
            let loops = find_loops(&traj, &Euclidean, 40.0)?;
            let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;
            let seconds = start.elapsed().as_secs_f64();
            let runs = loops.sublevel_set().runs().len();
            Ok((seconds, format!("{} {runs} {} {:.3}", traj.len(), loops.components().len(), tau.iter().sum::<f64>())))
        })?;
        best = best.min(seconds);
        line = summary;
    }
    println!("{line} {best:.6}");
    Ok(())
}

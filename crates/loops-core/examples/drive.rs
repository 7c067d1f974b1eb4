//! Times `find_loops` on the urban drive:
//! `cargo run --release --example drive -- [hours] [gamma_m] [city_size_m]`.
//! `EUCLIDEAN_ONLY=1` skips the SE(3) run; `GENERATE_ONLY=1` stops after generating the drive
//! (the baseline that `benches/callgrind/count.sh` subtracts).
use loops_core::{Euclidean, UrbanDrive, find_loops};

fn main() -> Result<(), loops_core::Error> {
    let mut args = std::env::args().skip(1);
    let hours: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(2.1);
    let gamma: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(40.0);
    let city_size_m: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000.0);
    let drive = UrbanDrive { duration_s: hours * 3600.0, city_size_m, ..UrbanDrive::default() }.generate()?;
    if std::env::var_os("GENERATE_ONLY").is_some() {
        return Ok(()); // the baseline of instruction counts (see benches/callgrind)
    }
    let start = std::time::Instant::now();
    let loops = find_loops(&drive.trajectory, &Euclidean, gamma)?;
    let elapsed = start.elapsed();
    let nontrivial = loops.components().iter().filter(|c| !c.trivial).count();
    println!(
        "{} poses, gamma {gamma} m: {} runs, {} pairs, {} components ({} non-trivial) in {:.3} s",
        drive.trajectory.len(),
        loops.sublevel_set().runs().len(),
        loops.pair_count(),
        loops.components().len(),
        nontrivial,
        elapsed.as_secs_f64()
    );
    if std::env::var_os("EUCLIDEAN_ONLY").is_some() {
        return Ok(());
    }
    let se3_traj = drive.se3_trajectory()?;
    let se3 = loops_core::Se3 { rotation_weight_m_per_rad: 10.0, rotation: loops_core::RotationDistance::Geodesic };
    let start = std::time::Instant::now();
    let loops = find_loops(&se3_traj, &se3, gamma)?;
    println!(
        "se3(10 m/rad): {} runs, {} components in {:.3} s",
        loops.sublevel_set().runs().len(),
        loops.components().len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

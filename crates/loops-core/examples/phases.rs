//! The phases of `find_loops` and τ on the urban drive, on a pool of THREADS threads, with the
//! `phase-times` feature: `cargo run --release --features phase-times --example phases --
//! [hours] [threads] [repeats]`. Writes each phase's wall time to stderr (`phase NAME MS`) and
//! the whole call's to stdout (`total MS`), once per repeat.
use loops_core::{Euclidean, Scale, Selection, Side, UrbanDrive, find_loops};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let hours: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(2.1);
    let threads: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(2);
    let repeats: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(5);
    let traj = UrbanDrive { duration_s: hours * 3600.0, ..UrbanDrive::default() }.generate()?.trajectory;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    for _ in 0..repeats {
        pool.install(|| -> Result<(), loops_core::Error> {
            let start = std::time::Instant::now();
            let loops = find_loops(&traj, &Euclidean, 40.0)?;
            loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;
            eprintln!("total {:.3}", start.elapsed().as_secs_f64() * 1e3);
            Ok(())
        })?;
    }
    Ok(())
}

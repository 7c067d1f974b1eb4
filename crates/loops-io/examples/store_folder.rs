//! A fleet store in a folder from Rust, as `benches/store_disk_update.py` times it from Python:
//! the fleet of `store_days` (4 vehicles × 31 days of 5-minute drives, γ = 10 m, σ_ρ with a
//! budget of 500), days 1 to 30 stored in one update, then, in a fresh copy of that folder each
//! round, the folder opened ([`read_store`]) and day 31 added ([`update_opened_store`]), then
//! all 31 days stored in one update in a new folder. Prints the seconds of each step and the
//! ratio of day 31 (opening and update) to all 31 days (BENCHMARKS.md, "Fleet store"). With
//! `KEEP` set in the environment the store of days 1 to 30 of an earlier run is used again, and
//! with `DAY_ONLY` the rounds store only day 31, so that a profiler sees day 31 alone.
//!
//! ```text
//! cargo run --release -p loops-io --example store_folder -- [ROUNDS] [VEHICLES] [MINUTES]
//! ```
//!
//! `VEHICLES` (4 by default) sizes the fleet: the new tiles of day 31 grow with it, the whole
//! fleet's with its square. `MINUTES` (5 by default) is the length of each drive: with short
//! drives the update's costs per stored session and per file weigh most, longer drives show
//! how it grows with the new tiles.

use std::time::Instant;

use loops_core::{SampleSize, Sampler, SamplerKind, Trajectory, UrbanDrive, UrbanFleet, store::StoreSettings};
use loops_io::store::{StoreConfig, read_store, update_opened_store, update_store};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(3);
    let vehicles: usize = std::env::args().nth(2).and_then(|a| a.parse().ok()).unwrap_or(4);
    let minutes: f64 = std::env::args().nth(3).and_then(|a| a.parse().ok()).unwrap_or(5.0);
    let spec = UrbanFleet {
        vehicles,
        days: 31,
        drive: UrbanDrive {
            duration_s: 60.0 * minutes,
            rate_hz: 5.0,
            city_size_m: 1000.0,
            seed: 1,
            ..UrbanDrive::default()
        },
        start_spread_s: 3600.0,
    };
    let fleet = spec.generate()?;
    let sessions: Vec<(String, Trajectory)> =
        (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect();
    let (last, first): (Vec<_>, Vec<_>) = sessions.into_iter().partition(|(n, _)| n.ends_with("day30"));
    let config = StoreConfig {
        settings: StoreSettings::new(10.0),
        sampler: Some((Sampler::new(SamplerKind::Rho, SampleSize::Budget(500), 7), false)),
    };
    let root = std::env::temp_dir().join("loops-store-folder");
    let stored = root.join(format!("days-1-30-of-{vehicles}x{minutes}"));
    if std::env::var_os("KEEP").is_none() || !stored.is_dir() {
        let _ = std::fs::remove_dir_all(&root);
        let clock = Instant::now();
        update_store(&stored, Some(&config), first.clone(), &[])?;
        println!("days 1-30 in one update: {:.3} s", clock.elapsed().as_secs_f64());
    }
    for k in 0..rounds {
        let copy = root.join(format!("round-{k}"));
        let _ = std::fs::remove_dir_all(&copy);
        copy_dir(&stored, &copy)?;
        let clock = Instant::now();
        let opened = read_store(&copy)?;
        let open = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let report = update_opened_store(opened, None, last.clone(), &[], None)?;
        let update = clock.elapsed().as_secs_f64();
        println!(
            "day 31: opening {open:.3} s, update {update:.3} s ({} tiles scanned, {} kept)",
            report.update.tiles_scanned, report.update.tiles_kept
        );
        std::fs::remove_dir_all(&copy)?;
        if std::env::var_os("DAY_ONLY").is_none() {
            let all = root.join(format!("all-{k}"));
            let clock = Instant::now();
            update_store(&all, Some(&config), first.iter().chain(&last).cloned().collect(), &[])?;
            let at_once = clock.elapsed().as_secs_f64();
            println!("  all 31 days in one update: {at_once:.3} s; day 31 / all: {:.3}", (open + update) / at_once);
            std::fs::remove_dir_all(&all)?;
        }
    }
    Ok(())
}

/// Copies the folder `from` to `to`.
fn copy_dir(from: &std::path::Path, to: &std::path::Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let path = entry?.path();
        let target = to.join(path.file_name().unwrap_or_default());
        if path.is_dir() { copy_dir(&path, &target)? } else { std::fs::copy(&path, &target).map(|_| ())? }
    }
    Ok(())
}

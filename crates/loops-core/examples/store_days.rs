//! A fleet store built day by day, drawn after every day as a daily run does: the cost of
//! adding one more day against computing the whole fleet again, as a store made at once and as
//! `find_fleet_loops` + `sample_fleet`. A budget (500 by default) of σ_ρ, or of the sampler
//! named last (`nearest-then-uniform`, the default of the command line, ...). Prints ratios
//! (BENCHMARKS.md records them).
//!
//! ```text
//! cargo run --release -p loops-core --example store_days -- [VEHICLES] [DAYS] [DURATION_S] [BUDGET] [SAMPLER]
//! ```

use std::collections::HashMap;
use std::time::Instant;

use loops_core::{
    Euclidean, Result, SampleSize, Sampler, SamplerKind, Trajectory, UrbanDrive, UrbanFleet,
    fleet::{Fleet, FleetOptions, find_fleet_loops, sample_fleet},
    store::{FleetStore, StoreSession, StoreSettings},
};

fn main() -> Result<()> {
    let arg = |k: usize, default: f64| std::env::args().nth(k).and_then(|a| a.parse().ok()).unwrap_or(default);
    let (vehicles, days, duration_s) = (arg(1, 4.0) as usize, arg(2, 31.0) as usize, arg(3, 300.0));
    let spec = UrbanFleet {
        vehicles,
        days,
        drive: UrbanDrive { duration_s, rate_hz: 5.0, city_size_m: 1000.0, seed: 1, ..UrbanDrive::default() },
        start_spread_s: 3600.0,
    };
    let fleet = spec.generate()?;
    let gamma = 10.0;
    let settings = StoreSettings { gamma, ..StoreSettings::new(gamma) };
    let budget = std::env::args().nth(4).and_then(|a| a.parse().ok()).unwrap_or(500);
    let kind: SamplerKind = std::env::args().nth(5).map_or(Ok(SamplerKind::Rho), |a| a.parse())?;
    let sampler = Sampler::new(kind, SampleSize::Budget(budget), 7);
    let sessions: Vec<(String, Trajectory)> =
        (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect();
    let all: HashMap<String, Trajectory> = sessions.iter().cloned().collect();
    let mut source = |s: &StoreSession| Ok(all[&s.name].clone());
    let day = |d: usize| -> Vec<(String, Trajectory)> {
        sessions
            .iter()
            .filter(|(n, _)| n.ends_with(&format!("day{d:0width$}", width = (days - 1).to_string().len())))
            .cloned()
            .collect()
    };
    // The answer a store gives after an update: merge, τ and samples (components, and the
    // seconds of each part).
    let answer = |store: &FleetStore,
                  source: &mut dyn FnMut(&StoreSession) -> Result<Trajectory>|
     -> Result<(usize, [f64; 3], [usize; 2])> {
        let clock = Instant::now();
        let loops = store.loops()?;
        let merge = clock.elapsed().as_secs_f64();
        store.loop_duration()?;
        let tau = clock.elapsed().as_secs_f64() - merge;
        let drawn = store.samples(&loops, &sampler, false, source)?;
        let draw = clock.elapsed().as_secs_f64() - merge - tau;
        Ok((loops.components().len(), [merge, tau, draw], [drawn.tiles_read, drawn.tiles_asked]))
    };

    // Days 1 to 30, each drawn after its update as a daily run does: the store keeps what the
    // draw found in the tiles the next update leaves alone.
    let mut store = FleetStore::new(settings)?;
    for d in 0..days - 1 {
        store.update(day(d), &[], &mut source)?;
        store.samples(&store.loops()?, &sampler, false, &mut source)?;
    }
    let clock = Instant::now();
    let update = store.update(day(days - 1), &[], &mut source)?.clone();
    let scanned = clock.elapsed().as_secs_f64();
    let (components, parts, read) = answer(&store, &mut source)?;
    let incremental = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let mut at_once = FleetStore::new(settings)?;
    at_once.update(sessions.clone(), &[], &mut source)?;
    let at_once_scan = clock.elapsed().as_secs_f64();
    assert_eq!(answer(&at_once, &mut source)?.0, components);
    let whole = clock.elapsed().as_secs_f64();
    assert!(at_once.tiles() == store.tiles(), "the day-by-day store differs from the one made at once");

    let clock = Instant::now();
    let named = Fleet::new(sessions.clone())?;
    let loops = find_fleet_loops(&named, &Euclidean, gamma, &FleetOptions::default())?;
    loops.loop_duration();
    sample_fleet(&named, &Euclidean, &loops, &sampler, false)?;
    let in_memory = clock.elapsed().as_secs_f64();

    println!(
        "{} sessions ({vehicles} vehicles x {days} days, {duration_s} s at 5 Hz), {} poses, {} tiles, {components} components",
        fleet.len(),
        fleet.poses(),
        store.tiles().len()
    );
    println!(
        "day {days}: {} tiles scanned, {} kept ({:.1}% of the tiles)",
        update.tiles_scanned,
        update.tiles_kept,
        100.0 * update.tiles_scanned as f64 / store.tiles().len() as f64
    );
    println!(
        "day {days}'s draw read {} of the {} tiles it asked (the others from the draw of day {})",
        read[0],
        read[1],
        days - 1
    );
    println!("scan only:           day {days} / all days at once = {:.3}", scanned / at_once_scan);
    println!("scan+merge+tau+draw: day {days} / all days at once = {:.3}", incremental / whole);
    println!("scan+merge+tau+draw: day {days} / find_fleet_loops+sample_fleet = {:.3}", incremental / in_memory);
    println!(
        "seconds: day {days} {incremental:.3} (scan {scanned:.3}, merge {:.3}, tau {:.3}, draw {:.3}); at once \
         {whole:.3} (scan {at_once_scan:.3}); in memory {in_memory:.3}",
        parts[0], parts[1], parts[2]
    );
    Ok(())
}

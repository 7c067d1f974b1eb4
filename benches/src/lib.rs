//! Shared, seeded inputs of the inexact-loops benchmarks, and what the examples measure.

use loops_core::{Districts, Trajectory, UrbanDrive};

/// The reference urban drive of DESIGN §8 (1 km² city, 10 Hz) lasting `hours`, seed 0.
///
/// # Panics
/// If the generator rejects the parameters (it does not for positive hours).
pub fn urban_drive(hours: f64) -> Trajectory {
    UrbanDrive { duration_s: hours * 3600.0, ..UrbanDrive::default() }
        .generate()
        .expect("valid urban drive parameters")
        .trajectory
}

/// The 10⁶-pose drive of the scale benchmark (`benches/scale.py`, "10 × 10 km, by district,
/// 28 h"): a 10 × 10 km city worked one 1 km² district at a time (2.8 h each, snake order), so
/// that revisits stay bounded as the drive grows, seed 0, 10 Hz.
///
/// # Panics
/// If the generator rejects the parameters (it does not).
pub fn district_drive_1e6() -> Trajectory {
    UrbanDrive {
        duration_s: 100_000.0,
        city_size_m: 10_000.0,
        districts: Some(Districts { side_m: 1_000.0, dwell_s: Districts::DEFAULT_DWELL_S }),
        ..UrbanDrive::default()
    }
    .generate()
    .expect("valid district drive parameters")
    .trajectory
}

/// The peak resident set of this process so far (`VmHWM` of `/proc/self/status`), MB; NaN where
/// it cannot be read.
pub fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM:")).map(str::to_owned))
        .and_then(|l| l.split_whitespace().nth(1).and_then(|kb| kb.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

//! Shared, seeded inputs of the inexact-loops benchmarks, and what the examples measure.

use loops_core::{Districts, Trajectory, UrbanDrive};

/// The reference urban drive (1 km² city, 10 Hz) lasting `hours`, seed 0.
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

/// Poses of the drive between two stops: out 1 km and back at 10 m/s, 10 Hz.
pub const STOP_DRIVE_POSES: usize = 2_000;

/// `n` poses at 10 Hz of a robot that parks twice: half of the rest at (12, −3) m, a drive out
/// 1 km along y and back ([`STOP_DRIVE_POSES`] poses), then the other half `offset_m` further
/// along x, every pose of a stop the same point. With `offset_m` = `None`, one stop: all `n`
/// poses at (12, −3) m. Deterministic (no random choice).
///
/// # Panics
/// If `n` is below [`STOP_DRIVE_POSES`] + 2 for two stops, or below 2.
pub fn parked_twice(n: usize, offset_m: Option<f64>) -> Trajectory {
    let place = [12.0, -3.0];
    let points: Vec<[f64; 2]> = match offset_m {
        None => vec![place; n],
        Some(offset_m) => {
            let first = (n - STOP_DRIVE_POSES) / 2;
            let mut points = vec![place; first];
            points
                .extend((1..=STOP_DRIVE_POSES).map(|k| [place[0], place[1] + k.min(STOP_DRIVE_POSES + 1 - k) as f64]));
            points.extend(std::iter::repeat_n([place[0] + offset_m, place[1]], n - first - STOP_DRIVE_POSES));
            points
        }
    };
    Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &points).expect("valid poses")
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

/// The CPU time this thread has run so far (the first field of `/proc/thread-self/schedstat`),
/// seconds; NaN where it cannot be read. On a loaded machine it counts the work and not the
/// waits, which wall-clock time does.
pub fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|ns| ns.parse::<f64>().ok()))
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

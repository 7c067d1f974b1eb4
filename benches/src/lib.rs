//! Shared, seeded inputs of the inexact-loops benchmarks.

use loops_core::{Trajectory, UrbanDrive};

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

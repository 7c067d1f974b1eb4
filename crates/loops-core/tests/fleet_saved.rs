//! A fleet's loops read back from their joint `Loops` (`FleetLoops::from_loops`, what the Python
//! bindings unpickle through): equal to the result found, and loops that do not fit the fleet
//! are an error naming what is wrong.

use loops_core::{
    Error, Euclidean, Separation, Trajectory, UrbanDrive, UrbanFleet, find_loops,
    fleet::{Fleet, FleetLoops, FleetOptions, Pruning, find_fleet_loops},
};

fn line(t0: f64, from: f64, to: f64, y: f64, n: usize) -> Trajectory {
    let step = (to - from) / (n - 1) as f64;
    let points: Vec<[f64; 2]> = (0..n).map(|k| [from + step * k as f64, y]).collect();
    Trajectory::from_points((0..n).map(|k| t0 + k as f64).collect(), &points).unwrap()
}

fn invalid_reason(error: Error) -> String {
    match error {
        Error::InvalidState { what: "FleetLoops", reason } => reason,
        other => panic!("expected an invalid FleetLoops state, got {other}"),
    }
}

#[test]
fn found_loops_read_back_equal_for_every_pruning_and_separation() {
    let spec = UrbanFleet {
        vehicles: 4,
        days: 1,
        drive: UrbanDrive { duration_s: 300.0, seed: 11, ..UrbanDrive::default() },
        ..UrbanFleet::default()
    };
    let fleet = spec.generate().unwrap();
    for pruning in [Pruning::Hierarchy, Pruning::KdTree] {
        for separation in [Separation::NONE, Separation::for_gamma(30.0)] {
            let options = FleetOptions { separation, pruning, chunk_radius: None };
            let found = find_fleet_loops(&fleet, &Euclidean, 30.0, &options).unwrap();
            assert!(!found.between_sessions().is_empty());
            let again = FleetLoops::from_loops(&fleet, found.loops().clone(), found.pruning()).unwrap();
            assert_eq!(again, found);
            assert_eq!(again.components(), found.components());
            assert_eq!(again.session_pairs(), found.session_pairs());
        }
    }
}

#[test]
fn loops_that_do_not_fit_the_fleet_are_refused() {
    // Tuesday starts where Monday ends and drives back along it.
    let fleet = Fleet::new(vec![
        ("monday".into(), line(0.0, 0.0, 10.0, 0.0, 21)),
        ("tuesday".into(), line(50.0, 10.0, 0.0, 0.2, 21)),
    ])
    .unwrap();
    let found = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default()).unwrap();

    let reason = invalid_reason(FleetLoops::from_loops(&fleet, found.loops().clone(), Pruning::Auto).unwrap_err());
    assert!(reason.contains("pruning is auto"), "{reason}");

    // Loops of another fleet: the pose counts differ.
    let other = Fleet::new(vec![("monday".into(), line(0.0, 0.0, 10.0, 0.0, 21))]).unwrap();
    let reason = invalid_reason(FleetLoops::from_loops(&other, found.loops().clone(), Pruning::KdTree).unwrap_err());
    assert!(reason.contains("different trajectories"), "{reason}");

    // The joint trajectory's own loops (no session cut): components and runs across the break.
    let joint = find_loops(fleet.joint(), &Euclidean, 1.0).unwrap();
    let reason = invalid_reason(FleetLoops::from_loops(&fleet, joint, Pruning::KdTree).unwrap_err());
    assert!(reason.contains("does not lie in one block of sessions"), "{reason}");
}

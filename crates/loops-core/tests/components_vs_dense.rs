//! Loop components, holes, closest pairs, τ, α, ρ and the broken-diagonal warning against a
//! dense reference: the full symmetric boolean matrix of S_γ, labelled by breadth-first flood
//! fill, with holes counted twice (pixel Euler number, and bounded 8-connected background
//! regions) and measures summed over matrix rows.

mod support;

use loops_core::{Euclidean, Separation, Trajectory, Warning, find_loops, find_loops_separated};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use support::{Case, any_case, check_against_dense, check_separated_against_dense, config, lattice_case};

/// A sub-interval of time as fractions of the span, reaching a little outside it.
fn interval() -> impl Strategy<Value = (f64, f64)> {
    (-0.1..1.1f64, -0.1..1.1f64)
        .prop_filter("a non-empty interval", |(a, b)| (a - b).abs() > 1e-3)
        .prop_map(|(a, b)| (a.min(b), a.max(b)))
}

fn check(case: &Case, interval: (f64, f64)) -> Result<(), TestCaseError> {
    check_against_dense(&case.traj, case.gamma, interval).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config(256, 0x5EED_0002))]

    #[test]
    fn components_and_measures_equal_the_dense_reference(
        case in any_case(250),
        interval in interval(),
    ) {
        check(&case, interval)?;
    }

    /// Exact ties at γ make ragged boundaries, holes and broken diagonals.
    #[test]
    fn lattice_components_equal_the_dense_reference(
        case in lattice_case(250),
        interval in interval(),
    ) {
        check(&case, interval)?;
    }
}

fn line(xs: &[f64]) -> Trajectory {
    Trajectory::new((0..xs.len()).map(|i| i as f64).collect(), xs.to_vec(), 1).unwrap()
}

/// Out, back and out again along a line: the three passes enclose the pairs (end of the first
/// pass, start of the third), far apart, in a ring of S_γ attached to the diagonal. One hole in
/// each half of the plane.
#[test]
fn three_passes_make_two_holes() {
    let mut xs: Vec<f64> = (0..=10).map(f64::from).collect();
    xs.extend((0..10).rev().map(f64::from));
    xs.extend((1..=10).map(f64::from));
    let traj = line(&xs);
    check_against_dense(&traj, 1.0, (0.2, 0.7)).unwrap();
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    assert_eq!(loops.components().len(), 1);
    assert!(loops.components()[0].trivial);
    assert_eq!(loops.components()[0].holes, 2);
}

/// Two gaps break the diagonal into three pieces, {0, 1}, {2, 3} and {4, 5}. x_3 lies within γ
/// of x_0, x_1 and x_2, so column 3 joins the first two pieces off the diagonal
/// ((0, 1) → (0, 2) → (0, 3) → (1, 3) → (2, 3)); the third stays apart.
#[test]
fn broken_diagonal_reconnected_off_the_diagonal() {
    let traj = line(&[0.0, 0.9, -0.9, 0.0, 5.0, 5.5]);
    check_against_dense(&traj, 1.0, (0.0, 1.0)).unwrap();
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    let [Warning::DiagonalBroken { gaps, first_gap, trivial_components, .. }] = loops.warnings() else {
        panic!("expected one warning, got {:?}", loops.warnings());
    };
    assert_eq!((*gaps, *first_gap, *trivial_components), (2, 1, 2));
    let trivial: Vec<_> = loops.components().iter().filter(|c| c.trivial).collect();
    assert_eq!(trivial.len(), 2);
    assert_eq!(loops.component_of(0, 0), loops.component_of(2, 2));
    assert_ne!(loops.component_of(0, 0), loops.component_of(4, 4));
}

/// Every consecutive pair farther than γ: each diagonal cell is its own trivial component (its
/// four neighbours are consecutive pairs), and revisits make isolated non-trivial cells.
#[test]
fn fully_broken_diagonal() {
    let traj = line(&[0.0, 2.0, 4.0, 2.5, 0.5, 6.0, 8.0, 0.0]);
    check_against_dense(&traj, 1.0, (0.0, 1.0)).unwrap();
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    let [Warning::DiagonalBroken { gaps, trivial_components, .. }] = loops.warnings() else {
        panic!("expected one warning, got {:?}", loops.warnings());
    };
    assert_eq!((*gaps, *trivial_components), (7, 8));
    // (0, 4), (0, 7), (1, 3) and (4, 7): δ = 0.5, 0, 0.5, 0.5.
    assert_eq!(loops.components().len(), 12);
}

/// No gap, no warning, and one trivial component.
#[test]
fn unbroken_diagonal_has_no_warning() {
    let traj = line(&[0.0, 1.0, 2.0, 1.0, 0.0]);
    check_against_dense(&traj, 1.0, (0.1, 0.9)).unwrap();
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    assert!(loops.warnings().is_empty());
}

/// A separation in path length, in time, or both; sometimes beyond the whole trajectory.
fn separation() -> impl Strategy<Value = Separation> {
    prop_oneof![
        (0.0..30.0f64).prop_map(Separation::path),
        (0.0..30.0f64).prop_map(Separation::time_s),
        (0.0..20.0f64, 0.0..20.0f64).prop_map(|(path, time_s)| Separation { path, time_s }),
        Just(Separation::time_s(1e-9)),
    ]
}

fn check_separated(case: &Case, separation: Separation, interval: (f64, f64)) -> Result<(), TestCaseError> {
    check_separated_against_dense(&case.traj, case.gamma, separation, interval).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config(256, 0x5EED_0014))]

    /// Revisits: components, holes, closest pairs and τ/α/ρ of X = S_γ ∩ {pairs
    /// `separation` apart} equal the dense matrix's.
    #[test]
    fn revisit_components_and_measures_equal_the_dense_reference(
        case in any_case(250),
        separation in separation(),
        interval in interval(),
    ) {
        check_separated(&case, separation, interval)?;
    }

    #[test]
    fn lattice_revisits_equal_the_dense_reference(
        case in lattice_case(250),
        separation in separation(),
        interval in interval(),
    ) {
        check_separated(&case, separation, interval)?;
    }
}

/// Out along a corridor and back: by the paper's topology one trivial component; at least 3
/// apart along the path, the way back is one revisit of the way out, with no diagonal cell.
#[test]
fn out_and_back_is_one_revisit() {
    let mut xs: Vec<f64> = (0..=10).map(f64::from).collect();
    xs.extend((0..10).rev().map(f64::from));
    let traj = line(&xs);
    assert_eq!(find_loops(&traj, &Euclidean, 1.0).unwrap().components().len(), 1);
    let separation = Separation::path(3.0);
    check_separated_against_dense(&traj, 1.0, separation, (0.0, 1.0)).unwrap();
    let revisits = find_loops_separated(&traj, &Euclidean, 1.0, separation).unwrap();
    assert_eq!(revisits.components().len(), 1);
    let c = &revisits.components()[0];
    assert!(!c.trivial && c.closest_distance == 0.0);
    // The turnaround at x = 10 (pose 10) is the nearest the way back comes to the way out.
    assert_eq!(c.i_range, [0, 9]);
    assert_eq!(c.j_range, [11, 20]);
    // Nothing within the separation of the diagonal: (8, 12) is 4 apart, (9, 11) only 2.
    assert!(revisits.component_of(8, 12).is_some() && revisits.component_of(9, 11).is_none());
    // Far beyond the path's length: no revisit, and a warning that says so.
    let none = find_loops_separated(&traj, &Euclidean, 1.0, Separation::path(100.0)).unwrap();
    assert!(none.components().is_empty());
    assert!(matches!(none.warnings(), [Warning::NoLoops { .. }]));
}

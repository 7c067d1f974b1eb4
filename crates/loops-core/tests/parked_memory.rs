//! A parked robot's memory follows its runs: two million identical poses
//! are one component in two million runs (row i: columns i..n), a few tens of megabytes. The
//! engine once held candidate stretches for every near ball of a block and needed 3.3 GB for
//! them; under an address-space limit of 1 GiB that run ended in an allocation failure.
//!
//! The test reruns itself as a child process under `ulimit -v` (the limit must not cap the
//! other tests of this binary), and the child asserts the answer.

#![cfg(target_os = "linux")]

use loops_core::{Euclidean, Run, SublevelSet, Trajectory, find_loops};
use std::process::Command;

/// Set in the child, which runs the engine under the limit.
const CHILD: &str = "LOOPS_PARKED_MEMORY_CHILD";

/// The child's address-space limit, in KiB: 1 GiB, a sixth of the old engine's need and
/// several times the answer's.
const LIMIT_KIB: u64 = 1 << 20;

const POSES: usize = 2_000_000;

#[test]
fn a_parked_robot_fits_in_what_its_runs_need() {
    if std::env::var_os(CHILD).is_some() {
        parked_robot_is_one_component(POSES);
        return;
    }
    let exe = std::env::current_exe().expect("the test binary's path");
    let output = Command::new("sh")
        .arg("-c")
        .arg(format!(
            r#"ulimit -v {LIMIT_KIB} && exec "$0" --exact a_parked_robot_fits_in_what_its_runs_need --test-threads=1"#
        ))
        .arg(&exe)
        .env(CHILD, "1")
        .output()
        .expect("sh runs the test binary");
    assert!(
        output.status.success(),
        "{POSES} identical poses under a {LIMIT_KIB} KiB address limit: {}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
}

fn parked_robot_is_one_component(n: usize) {
    let traj = Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &vec![[1.0, 2.0]; n]).unwrap();
    let set = SublevelSet::compute(&traj, &Euclidean, 1.0).unwrap();
    assert_eq!(set.runs().len(), n);
    assert!((0..n).all(|i| set.row(i) == [Run { start: i as u32, end: (n - 1) as u32 }]));
    drop(set);
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    assert_eq!(loops.components().len(), 1);
}

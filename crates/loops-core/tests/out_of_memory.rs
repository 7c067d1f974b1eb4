//! Inputs too big for memory are errors, not aborts: every buffer that grows with the input on
//! the way through `UrbanFleet::generate`, `Trajectory::new`, `find_loops` (with and without a
//! separation) and `Loops::loop_duration` is allocated fallibly and becomes
//! `Error::OutOfMemory`, which the Python bindings raise as `OutOfMemoryError`. An allocation
//! that fails without it ends the process (and a Python interpreter with it).
//!
//! Each test reruns this binary as a child process under `ulimit -v` (the limit must not cap the
//! other tests), and the child reports what happened; a child killed by a signal is an abort.

#![cfg(target_os = "linux")]

use std::process::{Command, Output};

use loops_core::{
    Error, Euclidean, Scale, Selection, Separation, Side, Trajectory, UrbanDrive, UrbanFleet, find_loops,
    find_loops_separated,
};

/// Set in the child: which case to run.
const CHILD: &str = "LOOPS_OUT_OF_MEMORY_CHILD";

/// 4 GiB, in KiB.
const FOUR_GIB_KIB: u64 = 4 << 20;

/// Runs `test` of this binary in a child under an address-space limit of `limit_kib` (none for
/// `None`), with `case` in the child's environment.
fn child(test: &str, case: &str, limit_kib: Option<u64>) -> Output {
    let exe = std::env::current_exe().expect("the test binary's path");
    let limit = limit_kib.map_or(String::new(), |kib| format!("ulimit -v {kib} && "));
    Command::new("sh")
        .arg("-c")
        .arg(format!(r#"{limit}exec "$0" --exact {test} --test-threads=1 --nocapture"#))
        .arg(&exe)
        .env(CHILD, case)
        // One arena, and every large buffer its own mapping: the address space then follows
        // what the child holds, instead of heaps reserved ahead for each thread.
        .env("GLIBC_TUNABLES", "glibc.malloc.arena_max=1:glibc.malloc.mmap_threshold=131072")
        .output()
        .expect("sh runs the test binary")
}

/// What the child printed after `tag` on each line that holds it (the test harness prints
/// its own words before the first).
fn lines<'a>(output: &'a Output, tag: &str) -> Vec<&'a str> {
    let stdout = std::str::from_utf8(&output.stdout).expect("UTF-8");
    stdout.lines().filter_map(|line| line.find(tag).map(|at| &line[at + tag.len()..])).collect()
}

/// This process's `VmSize` or `VmPeak` (`field`), KiB.
fn vm_kib(field: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let line = status.lines().find(|l| l.starts_with(field)).expect("the field");
    line.split_whitespace().nth(1).and_then(|kib| kib.parse().ok()).expect("KiB")
}

/// Ten million vehicles driving 30 s each (3 × 10⁹ poses, about 120 GB of joint trajectory)
/// under 4 GiB: an `OutOfMemory` error, at once. The generator once collected the sessions in
/// parallel and aborted when memory ran out, some hundred thousand sessions in.
#[test]
fn a_fleet_too_big_for_memory_is_an_error() {
    if let Some(case) = std::env::var_os(CHILD) {
        assert_eq!(case, "fleet");
        let spec = UrbanFleet {
            vehicles: 10_000_000,
            drive: UrbanDrive { duration_s: 30.0, ..UrbanDrive::default() },
            ..UrbanFleet::default()
        };
        match spec.generate() {
            Err(error @ Error::OutOfMemory { .. }) => println!("@error {error}"),
            other => println!("@other {:?}", other.map(|fleet| fleet.len())),
        }
        return;
    }
    let output = child("a_fleet_too_big_for_memory_is_an_error", "fleet", Some(FOUR_GIB_KIB));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the child under 4 GiB: {}\n{stderr}", output.status);
    let errors = lines(&output, "@error ");
    assert_eq!(errors.len(), 1, "{:?}\n{stderr}", lines(&output, "@other "));
    assert!(errors[0].contains("for the joint trajectory of a fleet could not be allocated"), "{}", errors[0]);
}

/// 10⁸ poses under 4 GiB, scaled by four to keep the test short: 2.5 × 10⁷ poses on a line
/// under 1 GiB. The trajectory fits (600 MB), `find_loops` does not, and says so. It once
/// aborted growing the ball hierarchy's nodes past the room it had guessed for them.
#[test]
fn a_find_loops_too_big_for_memory_is_an_error() {
    if let Some(case) = std::env::var_os(CHILD) {
        assert_eq!(case, "line");
        let n = 25_000_000;
        let traj = Trajectory::new((0..n).map(|i| i as f64 * 0.1).collect(), (0..n).map(|i| i as f64).collect(), 1)
            .expect("the trajectory fits");
        match find_loops(&traj, &Euclidean, 0.5) {
            Err(error @ Error::OutOfMemory { .. }) => println!("@error {error}"),
            other => println!("@other {:?}", other.map(|loops| loops.components().len())),
        }
        return;
    }
    let output = child("a_find_loops_too_big_for_memory_is_an_error", "line", Some(FOUR_GIB_KIB / 4));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the child under 1 GiB: {}\n{stderr}", output.status);
    assert_eq!(lines(&output, "@error ").len(), 1, "{:?}\n{stderr}", lines(&output, "@other "));
}

/// A drive back and forth along a line, four passes of 50,000 poses 1 m apart, at γ = 2.5 m
/// (each row meets the later passes: about four runs a row, a band per pair of passes), found
/// with and without a separation and measured; `None`
/// when the inputs themselves do not fit (allocated fallibly: a limit below them is no test of
/// the engine).
fn passes() -> Result<Option<(usize, u64)>, Error> {
    let (n, pass) = (200_000_usize, 50_000_usize);
    let mut times = Vec::new();
    let mut xs = Vec::new();
    if times.try_reserve_exact(n).is_err() || xs.try_reserve_exact(n).is_err() {
        return Ok(None);
    }
    times.extend((0..n).map(|i| i as f64 * 0.1));
    xs.extend((0..n).map(|i| if (i / pass) % 2 == 0 { (i % pass) as f64 } else { (pass - 1 - i % pass) as f64 }));
    let traj = Trajectory::new(times, xs, 1)?;
    let loops = find_loops(&traj, &Euclidean, 2.5)?;
    let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;
    let revisits = find_loops_separated(&traj, &Euclidean, 2.5, Separation::for_gamma(2.5))?;
    let components = loops.components().len() + revisits.components().len();
    Ok(Some((components, tau.len() as u64 + loops.sublevel_set().upper_pairs())))
}

/// [`passes`] under address-space limits from what the child holds before its inputs are made
/// to what the whole computation needs, in twelve steps: each either completes with the answer
/// of an unlimited run or returns `OutOfMemory`; none aborts. Some limit in between must end
/// in `OutOfMemory`, so the steps do reach the engine's buffers.
#[test]
fn every_step_of_find_loops_fails_softly_when_memory_runs_out() {
    const TEST: &str = "every_step_of_find_loops_fails_softly_when_memory_runs_out";
    if std::env::var_os(CHILD).is_some() {
        // Start rayon's pool and the allocator's arenas before the limit matters.
        let warm = Trajectory::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 0.0], 1).expect("valid");
        find_loops(&warm, &Euclidean, 0.5).expect("three poses fit");
        println!("@ready {}", vm_kib("VmSize:"));
        match passes() {
            Ok(Some(answer)) => println!("@answer {answer:?}"),
            Ok(None) => println!("@inputs did not fit"),
            Err(error @ Error::OutOfMemory { .. }) => println!("@error {error}"),
            Err(other) => println!("@other {other}"),
        }
        println!("@peak {}", vm_kib("VmPeak:"));
        return;
    }
    let free = child(TEST, "measure", None);
    assert!(free.status.success(), "{}", String::from_utf8_lossy(&free.stderr));
    let number = |output: &Output, tag: &str| -> u64 { lines(output, tag)[0].parse().expect("KiB") };
    let (ready, peak) = (number(&free, "@ready "), number(&free, "@peak "));
    let answer = lines(&free, "@answer ")[0].to_owned();
    // Twelve steps, or as many as `LOOPS_OUT_OF_MEMORY_STEPS` says, for longer hunts.
    let steps = std::env::var("LOOPS_OUT_OF_MEMORY_STEPS").ok().and_then(|s| s.parse().ok()).unwrap_or(12_u64);
    let mut errors = 0;
    for k in 0..=steps {
        let limit = ready + (peak - ready) * k / steps + 1024;
        let output = child(TEST, "limited", Some(limit));
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "under {limit} KiB: {}\n{stderr}", output.status);
        if lines(&output, "@ready ").is_empty() {
            continue; // the harness itself did not start under this limit
        }
        assert!(lines(&output, "@other ").is_empty(), "under {limit} KiB: {:?}", lines(&output, "@other "));
        for found in lines(&output, "@answer ") {
            assert_eq!(found, answer, "under {limit} KiB");
        }
        for error in lines(&output, "@error ") {
            eprintln!("under {limit} KiB: {error}");
            errors += 1;
        }
    }
    assert!(errors > 0, "no limit between {ready} and {peak} KiB ran out of memory");
}

//! Ctrl-C while `loops` reads a file-compressed rosbag2 bag (`.db3.zstd`) leaves no
//! `loops-bag-*` file in the temporary folder: the decompressed copy has no name (see loops-io's
//! `temp_copy`), and the interrupt handler removes the one it has while SQLite opens it.
//!
//! The bag is written by the Python `rosbags` package (an independent writer: loops-io's
//! `make_bag_fixtures.py --bench`), compressed here with zstd; the test skips, saying why, where
//! Python cannot write it.

#![cfg(target_os = "linux")]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod support;

/// Poses in the bag: about 12 MB of sqlite3, a few seconds of reading in a debug build.
const POSES: usize = 100_000;

/// The bag compressed as a whole (`bench.db3.zstd`), written once per target folder; `None`
/// (with a message) where Python cannot write it.
fn compressed_bag() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("bag-temp-files-{POSES}"));
    let compressed = root.join("bench.db3.zstd");
    if compressed.is_file() {
        return Some(compressed);
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../loops-io/tests/make_bag_fixtures.py");
    let written = Command::new(support::python())
        .arg(&script)
        .args(["--bench", &POSES.to_string()])
        .arg(&root)
        .output()
        .map_err(|error| error.to_string())
        .and_then(|out| if out.status.success() { Ok(()) } else { Err(String::from_utf8_lossy(&out.stderr).into()) });
    if let Err(why) = written {
        support::skip("the interrupted read of a compressed bag", &format!("Python cannot write the bag here ({why})"));
        return None;
    }
    let db3 = std::fs::read(root.join("bench-sqlite3/bench-sqlite3.db3")).expect("the bag's storage file");
    let partial = root.join("bench.db3.zstd.partial");
    std::fs::write(&partial, zstd::bulk::compress(&db3, 3).expect("zstd")).expect("the compressed bag");
    std::fs::rename(&partial, &compressed).expect("the compressed bag");
    Some(compressed)
}

/// The files in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("the temporary folder")
        .map(|entry| entry.expect("an entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Whether process `pid` has a file of `dir` open (the decompressed copy, named or not).
fn holds_a_file_in(pid: u32, dir: &Path) -> bool {
    let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) else { return false };
    fds.filter_map(|fd| std::fs::read_link(fd.ok()?.path()).ok()).any(|target| target.starts_with(dir))
}

#[test]
fn ctrl_c_while_reading_a_compressed_bag_leaves_no_temporary_file() {
    let Some(bag) = compressed_bag() else { return };
    for round in 0..3 {
        let tmp = std::env::temp_dir().join(format!("loops-tmpdir-{}-{round}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        std::fs::create_dir_all(&tmp).expect("a private temporary folder");
        let mut child = Command::new(env!("CARGO_BIN_EXE_loops"))
            .arg("info")
            .arg(&bag)
            .env("TMPDIR", &tmp)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("loops runs");
        // Interrupt once it decompresses into the folder (round 0), or a little later (while it
        // decompresses or walks the copy).
        let start = Instant::now();
        while !holds_a_file_in(child.id(), &tmp) {
            assert!(start.elapsed() < Duration::from_secs(60), "loops never opened a temporary file");
            assert!(child.try_wait().expect("wait").is_none(), "loops ended before it read the bag");
            std::thread::sleep(Duration::from_millis(2));
        }
        std::thread::sleep(Duration::from_millis(150 * round));
        let killed = Command::new("kill").args(["-INT", &child.id().to_string()]).status().expect("kill runs");
        assert!(killed.success());
        let output = child.wait_with_output().expect("loops ends");
        let stderr = String::from_utf8_lossy(&output.stderr);
        // Round 0 is interrupted as soon as the copy is open; the later rounds may find the read
        // finished on a quiet machine, which must leave nothing behind just the same.
        let finished_first = round > 0 && output.status.code() == Some(0);
        assert!(
            output.status.code() == Some(130) || finished_first,
            "round {round}: not interrupted while reading ({:?}): {stderr}",
            output.status.code()
        );
        assert_eq!(names(&tmp), Vec::<String>::new(), "round {round}: left in TMPDIR after Ctrl-C");
        let _ = std::fs::remove_dir_all(&tmp);
    }
}

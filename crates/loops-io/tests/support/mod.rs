//! Shared by the integration tests: byte-string mutations for the fuzz targets, the Python
//! fixture builder of the bag and MCAP tests, the real-data folder, and temp folders.
#![allow(dead_code)] // each test crate uses a different part

pub mod logs;
mod python;

#[allow(unused_imports)] // each test crate uses a different part
pub use python::{python, skip, skipped};

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

use loops_io::PoseType;
use proptest::prelude::*;
use serde_json::Value;

/// The ROS message types that carry a pose.
pub const ROS_TYPES: [PoseType; 5] = [
    PoseType::PoseStamped,
    PoseType::PoseWithCovarianceStamped,
    PoseType::TransformStamped,
    PoseType::Odometry,
    PoseType::TfMessage,
];

/// How the error of a KITTI file read as TUM ends: it says what the file looks like.
pub const KITTI_READ_AS_TUM: &str = "line 1: expected 8 columns (timestamp tx ty tz qx qy qz qw), found 13: a KITTI pose \
                                     line? read the file as kitti (format=\"kitti\", --format kitti)";

/// A mutation of a byte string: truncate, flip a byte, overwrite 4 bytes, insert, remove.
#[derive(Debug, Clone)]
pub enum Mutation {
    Truncate(prop::sample::Index),
    Flip(prop::sample::Index, u8),
    Overwrite(prop::sample::Index, [u8; 4]),
    Insert(prop::sample::Index, Vec<u8>),
    Remove(prop::sample::Index, usize),
}

/// One mutation, any kind, anywhere.
pub fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<prop::sample::Index>().prop_map(Mutation::Truncate),
        (any::<prop::sample::Index>(), 1u8..=255).prop_map(|(i, b)| Mutation::Flip(i, b)),
        (any::<prop::sample::Index>(), any::<[u8; 4]>()).prop_map(|(i, b)| Mutation::Overwrite(i, b)),
        (any::<prop::sample::Index>(), proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        (any::<prop::sample::Index>(), 1usize..64).prop_map(|(i, n)| Mutation::Remove(i, n)),
    ]
}

/// One to three mutations.
pub fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    proptest::collection::vec(mutation(), 1..4)
}

/// `data` with `mutations` applied in order (stopping once it is empty).
pub fn mutate(data: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut data = data.to_vec();
    for mutation in mutations {
        if data.is_empty() {
            break;
        }
        match mutation {
            Mutation::Truncate(i) => data.truncate(i.index(data.len())),
            Mutation::Flip(i, b) => {
                let i = i.index(data.len());
                data[i] ^= b;
            }
            Mutation::Overwrite(i, b) => {
                let i = i.index(data.len());
                for (k, byte) in b.iter().enumerate() {
                    if let Some(slot) = data.get_mut(i + k) {
                        *slot = *byte;
                    }
                }
            }
            Mutation::Insert(i, bytes) => {
                let i = i.index(data.len());
                data.splice(i..i, bytes.iter().copied());
            }
            Mutation::Remove(i, n) => {
                let i = i.index(data.len());
                let end = (i + n).min(data.len());
                data.drain(i..end);
            }
        }
    }
    data
}

/// A name part no other call of this run uses: the process and a counter of calls.
fn unique() -> String {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    format!("{}-{call}", std::process::id())
}

/// Runs the Python fixture `script` (`$PYTHON script ARGS... FOLDER`, the arguments from `args`,
/// called only when it runs) into `dir` unless `dir` holds a `manifest.json` already, and returns
/// `dir`'s manifest. `None` ([`skip`]: a failure under CI) when Python cannot run or the script
/// exits 3 (a missing package); a panic when it fails otherwise.
pub fn python_fixtures(
    what: &str,
    script: &Path,
    dir: PathBuf,
    args: impl FnOnce() -> Vec<OsString>,
) -> Option<(PathBuf, Value)> {
    if !dir.join("manifest.json").is_file() {
        // One folder per call: tests of one process build the same fixtures on several threads.
        let building = dir.with_extension(format!("tmp{}", unique()));
        let _ = std::fs::remove_dir_all(&building);
        let output = match Command::new(python()).arg(script).args(args()).arg(&building).output() {
            Ok(output) => output,
            Err(error) => {
                skip(what, &format!("cannot run {} ({error})", python().to_string_lossy()));
                return None;
            }
        };
        match output.status.code() {
            Some(0) => {}
            Some(3) => {
                skip(what, &String::from_utf8_lossy(&output.stderr));
                return None;
            }
            _ => panic!("{} failed: {}", script.display(), String::from_utf8_lossy(&output.stderr)),
        }
        // Another test process may have won the race; either copy is complete.
        if std::fs::rename(&building, &dir).is_err() {
            let _ = std::fs::remove_dir_all(&building);
        }
    }
    let manifest = std::fs::read_to_string(dir.join("manifest.json")).expect("manifest");
    Some((dir, serde_json::from_str(&manifest).expect("manifest JSON")))
}

/// The MCAP files of the official Python writers (`make_mcap_fixtures.py`), made once per
/// script version (cached in the target folder), and their manifest; `None` when Python
/// cannot make them here.
pub fn mcap_fixtures() -> Option<(PathBuf, Value)> {
    use std::hash::{DefaultHasher, Hash, Hasher};

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/make_mcap_fixtures.py");
    let source = std::fs::read(&script).expect("the fixture script");
    let mut hasher = DefaultHasher::new();
    source.hash(&mut hasher);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mcap-fixtures-{:016x}", hasher.finish()));
    python_fixtures("the MCAP tests", &script, dir, Vec::new)
}

/// One pose of the bag fixtures: stamp (ns), position, orientation.
pub type BagPose = (i64, [f64; 3], [f64; 4]);

/// The bags of `poses` written by Python (`make_bag_fixtures.py`: rosbag2 sqlite3 and MCAP in
/// every compression, split, and ROS 1), once per script version and poses (cached in the
/// target folder), and their manifest; `None` when Python cannot write them here.
pub fn bag_fixtures(name: &str, poses: &[BagPose]) -> Option<(PathBuf, Value)> {
    use std::hash::{DefaultHasher, Hash, Hasher};

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/make_bag_fixtures.py");
    let source = std::fs::read(&script).expect("the fixture script");
    let lines: String = poses
        .iter()
        .map(|(ns, p, q)| {
            format!("{ns} {:?} {:?} {:?} {:?} {:?} {:?} {:?}\n", p[0], p[1], p[2], q[0], q[1], q[2], q[3])
        })
        .collect();
    let mut hasher = DefaultHasher::new();
    source.hash(&mut hasher);
    lines.hash(&mut hasher);
    let root = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let dir = root.join(format!("bag-fixtures-{name}-{:016x}", hasher.finish()));
    let poses_file = root.join(format!("bag-poses-{name}-{}.txt", unique()));
    let fixtures = python_fixtures("the bag tests", &script, dir, || {
        std::fs::write(&poses_file, lines).expect("poses file");
        vec![poses_file.clone().into()]
    });
    let _ = std::fs::remove_file(&poses_file);
    fixtures
}

/// 60 poses with awkward numbers: negative zero, tiny and huge values, stamps near the end of
/// ROS 2's `int32` seconds.
pub fn small_bag_poses() -> Vec<BagPose> {
    (0..60)
        .map(|i| {
            let f = i as f64;
            let ns = 2_000_000_000_000_000_000 + i * 100_000_007;
            let p = [f * 0.1 + 1e-300, -0.0 - f * 1e-7, 1e12 / (f + 3.0)];
            let angle = f * 0.05;
            (ns, p, [0.0, -0.0, (angle / 2.0).sin(), (angle / 2.0).cos()])
        })
        .collect()
}

/// `shared/data` beside the checkout, or `None` (with a message) when it is absent.
pub fn real_data_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if dir.is_dir() {
        Some(dir)
    } else {
        skipped(
            "a test on real data",
            &format!("no real data at {} (it lives beside the checkout in CI)", dir.display()),
        );
        None
    }
}

/// A fresh folder in the temp folder, named after the test crate, removed when dropped.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new() -> Self {
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let count = COUNT.fetch_add(1, Ordering::Relaxed);
        let name = format!("loops-io-{}-{}-{count}", env!("CARGO_CRATE_NAME"), std::process::id());
        let dir = std::env::temp_dir().join(name);
        std::fs::create_dir_all(&dir).expect("temp folder");
        Self(dir)
    }

    /// Writes the file `name` with `contents` in the folder.
    pub fn file(&self, name: &str, contents: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, contents).expect("temp file");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

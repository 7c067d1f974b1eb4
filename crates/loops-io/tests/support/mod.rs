//! Shared by the integration tests: byte-string mutations for the fuzz targets, the Python
//! fixture builder of the bag and MCAP tests, and the real-data folder.
#![allow(dead_code)] // each test crate uses a different part

pub mod logs;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// Runs the Python fixture `script` (`python3 script ARGS... FOLDER`, the arguments from `args`,
/// called only when it runs) into `dir` unless `dir` holds a `manifest.json` already, and returns
/// `dir`'s manifest. `None`, with a message naming `what` is skipped, when python3 cannot run
/// or the script exits 3 (a missing package); a panic when it fails otherwise.
pub fn python_fixtures(
    what: &str,
    script: &Path,
    dir: PathBuf,
    args: impl FnOnce() -> Vec<OsString>,
) -> Option<(PathBuf, Value)> {
    if !dir.join("manifest.json").is_file() {
        let building = dir.with_extension(format!("tmp{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&building);
        let output = match Command::new("python3").arg(script).args(args()).arg(&building).output() {
            Ok(output) => output,
            Err(error) => {
                eprintln!("skipping {what}: cannot run python3 ({error})");
                return None;
            }
        };
        match output.status.code() {
            Some(0) => {}
            Some(3) => {
                eprintln!("skipping {what}: {}", String::from_utf8_lossy(&output.stderr).trim());
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

/// `shared/data` beside the checkout, or `None` (with a message) when it is absent.
pub fn real_data_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: no real data at {} (it lives beside the checkout in CI)", dir.display());
        None
    }
}

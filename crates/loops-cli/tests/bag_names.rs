//! `loops run` names each log's folder after the log: a rosbag2 bag by its folder's name whether
//! it is given as the folder, its `metadata.yaml` or one of its storage files (a split of a bag
//! of several adds its own name), made unique in the batch.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod support;
use support::temp_dir;

fn loops(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loops")).args(args).current_dir(dir).output().expect("the loops binary runs")
}

/// A rosbag2 bag of MCAP storage in `dir/name/`: one split per topic, each a 2-minute synthetic
/// drive written by `loops synth`, and the `metadata.yaml` listing them.
fn bag(dir: &Path, name: &str, topics: &[&str]) -> PathBuf {
    let folder = dir.join(name);
    std::fs::create_dir_all(&folder).expect("bag folder");
    let mut files = Vec::new();
    for (k, topic) in topics.iter().enumerate() {
        let file = format!("{name}_{k}.mcap");
        let output =
            loops(&folder, &["synth", &file, "--duration-s", "120", "--seed", &k.to_string(), "--topic", topic]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        files.push(file);
    }
    let metadata = format!(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths: [{}]\n",
        files.join(", ")
    );
    std::fs::write(folder.join("metadata.yaml"), metadata).expect("metadata.yaml");
    folder
}

fn folders(out: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(out)
        .expect("out")
        .map(|entry| entry.expect("entry").path())
        .filter(|path| path.is_dir())
        .map(|path| path.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_bag_is_named_by_its_folder_however_it_is_given() {
    let dir = temp_dir("one");
    bag(&dir, "drive_2024_05_01", &["/pose"]);
    std::fs::create_dir_all(dir.join("more")).unwrap();
    let output = loops(&dir.join("more"), &["synth", "drive.mcap", "--duration-s", "120", "--seed", "3"]);
    assert!(output.status.success());
    let args = [
        "run",
        "drive_2024_05_01",
        "drive_2024_05_01/metadata.yaml",
        "drive_2024_05_01/drive_2024_05_01_0.mcap",
        "more/drive.mcap",
        "--gamma",
        "40",
        "--quiet",
        "--out",
        "results",
    ];
    let output = loops(&dir, &args);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(
        folders(&dir.join("results")),
        ["drive", "drive_2024_05_01", "drive_2024_05_01-2", "drive_2024_05_01-3"],
        "the bag's folder name for the folder, metadata.yaml and its storage file; unique in the batch"
    );
    // metadata.yaml named from inside the bag's folder, as `.` would be.
    let output = loops(
        &dir.join("drive_2024_05_01"),
        &["run", "metadata.yaml", ".", "--gamma", "40", "--quiet", "--out", "../inside"],
    );
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(folders(&dir.join("inside")), ["drive_2024_05_01", "drive_2024_05_01-2"]);
}

#[test]
fn a_split_of_a_bag_of_several_adds_its_own_name() {
    let dir = temp_dir("splits");
    bag(&dir, "lab", &["/a", "/b"]);
    let output =
        loops(&dir, &["run", "lab/lab_1.mcap", "lab/lab_0.mcap", "--gamma", "40", "--quiet", "--out", "results"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(folders(&dir.join("results")), ["lab-lab_0", "lab-lab_1"]);
}

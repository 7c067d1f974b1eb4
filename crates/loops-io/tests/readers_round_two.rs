//! The reader attacks of the second sweep ("nothing lost, round two"): data dropped without a
//! word by a line holding two records (item 4), by a corrupt message opcode in an MCAP file
//! without a summary (item 5), and by a rosbag2 folder whose metadata leaves out a split or
//! counts more messages than its files hold (item 6). Item 14's test (Ctrl-C leaves no
//! decompressed copy behind) runs the CLI: `crates/loops-cli/tests/bag_temp_files.rs`.
//!
//! Each test builds its input here or from the independent writers' fixtures (the Python
//! `rosbags` package; the `mcap` crate's writer), and checks that the reader refuses it with one
//! line naming the file, the place and the defect.

// The readers' errors (`IoError`) are returned as they are.
#![allow(clippy::result_large_err)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use loops_io::{
    IoError, McapOptions, Timing, list_topics, read_csv, read_detections, read_euroc, read_kitti, read_mcap,
    read_pose_graph, read_rosbag2, read_trajectory, read_tuc, read_tum,
};

mod support;

use support::logs::{self, McapLayout, TOPIC, mcap};

/// A scratch file in the target folder holding `bytes` (one name per test: tests run in
/// parallel).
fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("readers-round-two");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("scratch file");
    path
}

/// A message as the issue wants it: one line, starting with the file.
fn assert_one_line(message: &str, path: &Path) {
    assert!(!message.contains('\n') && !message.contains('\r'), "several lines: {message:?}");
    assert!(message.starts_with(&path.display().to_string()), "does not start with the file: {message:?}");
}

// ---- item 4: two records on one line ---------------------------------------------------------

/// A reader of one text format: the poses (vertices and edges, detections) it reads.
type Reader = fn(&Path) -> Result<usize, IoError>;

#[test]
fn item4_two_records_on_one_line_are_an_error_in_every_text_reader() {
    let euroc_17 = "1403715524907143168,0.5,2,1,0.2,0.8,-0.2,0.5,0,0,0,0,0,0,0,0,0";
    let tum: Reader = |p| Ok(read_tum(p)?.len());
    let kitti: Reader = |p| Ok(read_kitti(p, &Timing::FromFile)?.len());
    let euroc: Reader = |p| Ok(read_euroc(p)?.len());
    let csv: Reader = |p| Ok(read_csv(p)?.len());
    let graph: Reader = |p| {
        let graph = read_pose_graph(p, &Timing::FromFile)?;
        Ok(graph.vertices.len() + graph.edges.len())
    };
    let tuc: Reader = |p| Ok(read_tuc(p)?.len());
    let detections: Reader = |p| Ok(read_detections(p)?.t_s.len());
    // (name, reader, a good first line, the line with two records, what the error names).
    let cases: [(&str, Reader, &str, String, &str); 15] = [
        (
            "m.g2o",
            graph,
            "VERTEX_SE2 0 0 0 0",
            "VERTEX_SE2 1 1 0 0 VERTEX_SE2 2 2 0 0".into(),
            r#"column 6 ("VERTEX_SE2")"#,
        ),
        (
            "m3.g2o",
            graph,
            "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1",
            "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1 VERTEX_SE3:QUAT 2 2 0 0 0 0 0 1".into(),
            r#"column 10 ("VERTEX_SE3:QUAT")"#,
        ),
        ("m.graph", graph, "VERTEX2 0 0 0 0", "VERTEX2 1 1 0 0 VERTEX2 2 2 0 0".into(), r#"column 6 ("VERTEX2")"#),
        (
            "m3.graph",
            graph,
            "VERTEX3 0 0 0 0 0 0 0",
            "VERTEX3 1 1 0 0 0 0 0 VERTEX3 2 2 0 0 0 0 0".into(),
            r#"column 9 ("VERTEX3")"#,
        ),
        (
            "e.g2o",
            graph,
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0",
            "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1 EDGE_SE2 1 2 1 0 0 1 0 0 1 0 1".into(),
            r#"column 13 ("EDGE_SE2")"#,
        ),
        ("m.tum", tum, "0 0 0 0 0 0 0 1", "1 1 0 0 0 0 0 1 2 2 0 0 0 0 0 1".into(), r#"column 9 ("2")"#),
        (
            "m.txt",
            kitti,
            "0 1 0 0 0 0 1 0 0 0 0 1 0",
            "1 1 0 0 1 0 1 0 0 0 0 1 0 2 1 0 0 2 0 1 0 0 0 0 1 0".into(),
            r#"column 14 ("2")"#,
        ),
        (
            "m8.csv",
            euroc,
            "1403715524902143104,0.5,2,1,1,0,0,0",
            "1403715524907143168,0.5,2,1,1,0,0,0,1403715524912143104,0.5,2,1,1,0,0,0".into(),
            r#"column 9 ("1403715524912143104") is past the end"#,
        ),
        (
            "m17.csv",
            euroc,
            "1403715524902143104,0.5,2,1,0.2,0.8,-0.2,0.5,0,0,0,0,0,0,0,0,0",
            format!("{euroc_17},{}", euroc_17.replacen("07143168", "12143104", 1)),
            r#"column 18 ("1403715524912143104")"#,
        ),
        ("xyz.csv", csv, "t,x,y,z\n0,0,0,0", "1,1,0,0,2,2,0,0".into(), r#"column 5 ("2")"#),
        ("p2.txt", tuc, "point2 0 0 0", "point2 1 1 0 point2 2 2 0".into(), r#"column 5 ("point2")"#),
        (
            "p2c.txt",
            tuc,
            "point2 0 0 0 0 0 0 0",
            "point2 1 1 0 0 0 0 0 point2 2 2 0 0 0 0 0".into(),
            r#"column 9 ("point2")"#,
        ),
        (
            "p3.txt",
            tuc,
            "point3 0 4000000 0 0",
            "point3 1 4000001 0 0 point3 2 4000002 0 0".into(),
            r#"column 6 ("point3")"#,
        ),
        ("loops.txt", detections, "loop 5 1 0.5", "loop 6 1 0.5 loop 7 2 0.5".into(), r#"column 5 ("loop")"#),
        ("rows.csv", detections, "t,t_prime,score\n5,1,0.5", "6,1,0.5,7,2,0.5".into(), r#"column 4 ("7")"#),
    ];
    for (name, read, first, merged, named) in cases {
        let good = write(name, format!("{first}\n").as_bytes());
        let read_first = read(&good).unwrap_or_else(|error| panic!("{name}: the good line does not read: {error}"));
        let lines = first.lines().count() + 1;
        let path = write(name, format!("{first}\n{merged}\n").as_bytes());
        let error = match read(&path) {
            Ok(count) => panic!("{name}: the line of two records read as {} record(s)", count - read_first),
            Err(error) => error,
        };
        let message = error.to_string();
        assert_one_line(&message, &path);
        assert_eq!(error.line(), Some(lines), "{name}: {message}");
        assert!(message.contains(named), "{name}: {message}");
    }
    // A EuRoC file of two rows run together into its only line: its further columns would set
    // every line's count, but the ninth is a timestamp.
    let path = write("one.csv", b"1403715524907143168,0.5,2,1,1,0,0,0,1403715524912143104,0.5,2,1,1,0,0,0\n");
    let error = read_euroc(&path).unwrap_err();
    assert!(
        error.to_string().contains(r#"line 1: column 9 ("1403715524912143104") is a timestamp in nanoseconds"#),
        "{error}"
    );
    // A times file (KITTI poses without times) with two times on a line.
    let poses = write("twelve.txt", b"1 0 0 5 0 1 0 6 0 0 1 7\n1 0 0 6 0 1 0 6 0 0 1 7\n");
    let times = write("times.txt", b"0.5\n1.0 1.5\n");
    let error = read_kitti(&poses, &Timing::TimesFile(times.clone())).unwrap_err();
    assert_one_line(&error.to_string(), &times);
    assert!(
        error
            .to_string()
            .contains(r#"line 2: expected 1 column (one time in seconds a line), found 2: column 2 ("1.5")"#),
        "{error}"
    );
}

#[test]
fn item4_records_with_fewer_fields_are_errors_and_optional_blocks_whole() {
    // (name, text, line, what the error says).
    let cases = [
        ("few.g2o", "VERTEX_SE2 0 0 0\n", 1, r#"found 4: the line ends after column 4 ("0")"#),
        (
            "info.g2o",
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0\n",
            3,
            "expected 6 or 12 columns",
        ),
        ("cov.txt", "point2 0 0 0 0 0\n", 1, "expected 4 or 8 columns"),
        ("angle.txt", "point2 0 0 0\nangle 0 1 0 0\n", 2, r#"found 5: column 5 ("0") is past the end"#),
    ];
    for (name, text, line, says) in cases {
        let path = write(name, text.as_bytes());
        let error = read_trajectory(&path, None).unwrap_err();
        assert_one_line(&error.to_string(), &path);
        assert_eq!(error.line(), Some(line), "{name}: {error}");
        assert!(error.to_string().contains(says), "{name}: {error}");
    }
}

#[test]
fn item4_the_real_files_still_read() {
    let Some(dir) = support::real_data_dir() else { return };
    // (file, poses: the counts the data README gives).
    let cases = [
        ("euroc/evo_V102_groundtruth.csv", 16702),
        ("tuc/SLAM/Corridor_GT.txt", 11346),
        ("tuc/Chemnitz_City/Chemnitz_GT.txt", 8571),
        ("tum_rgbd/freiburg1_xyz-groundtruth.txt", 3000),
        ("kitti_odometry/00.txt", 4541),
        ("pose_graphs/input_INTEL_g2o.g2o", 1228),
        ("pose_graphs/FR079_P_toro.graph", 989),
    ];
    for (file, poses) in cases {
        let table = read_trajectory(dir.join(file), None).unwrap_or_else(|error| panic!("{file}: {error}"));
        assert_eq!(table.len(), poses, "{file}");
    }
    let graph = read_pose_graph(dir.join("pose_graphs/input_M3500_g2o.g2o"), &Timing::FromFile).unwrap();
    assert_eq!((graph.vertices.len(), graph.edges.len()), (3500, 5453));
    let detections = read_detections(dir.join("tuc/SLAM/Corridor_Input.txt")).unwrap();
    assert_eq!(detections.t_s.len(), 10019);
}

// ---- item 5: a corrupt message opcode in an MCAP file without a summary ---------------------

#[test]
fn item5_a_corrupt_message_opcode_without_a_summary_is_never_a_silent_loss() {
    // Without CRCs (the issue's file: nothing but the records themselves can tell), and with them.
    for crcs in [false, true] {
        let bytes = mcap(300, McapLayout { summary: false, crcs, ..McapLayout::UNCHUNKED });
        let options = McapOptions::default().topic(TOPIC);
        assert_eq!(read_mcap(write("whole.mcap", &bytes), &options).unwrap().len(), 300);
        let data = logs::cdr_pose_stamped(150);
        let message = bytes.windows(data.len()).position(|window| window == data).expect("pose 150") - 22 - 9;
        assert_eq!(bytes[message], 0x05, "a message record");
        // The issue's case, named where it stands.
        let mut broken = bytes.clone();
        broken[message] = 0x85;
        match read_mcap(write("opcode-0x85.mcap", &broken), &options) {
            Ok(table) => panic!("crcs {crcs}: opcode 0x85: {} of 300 poses read without an error", table.len()),
            Err(error) => {
                assert_eq!(error.offset(), Some(message as u64), "{error}");
                let text = error.to_string();
                assert!(
                    text.contains(&format!("unknown opcode 0x85 reads as a message on channel 1 ({TOPIC})")),
                    "{text}"
                );
            }
        }
        for opcode in (0..=u8::MAX).filter(|&opcode| opcode != 0x05) {
            let mut broken = bytes.clone();
            broken[message] = opcode;
            let path = write("opcode.mcap", &broken);
            match read_mcap(&path, &options) {
                Ok(table) => {
                    panic!("crcs {crcs}: opcode {opcode:#04x}: {} of 300 poses read without an error", table.len())
                }
                Err(error) => {
                    let text = error.to_string();
                    assert_one_line(&text, &path);
                    assert!(error.offset().is_some(), "opcode {opcode:#04x}: no offset: {text}");
                }
            }
            assert!(list_topics(&path).is_err(), "opcode {opcode:#04x}: the topic list walks the file too");
        }
    }
}

#[test]
fn item5_records_of_extensions_that_are_no_message_are_still_skipped() {
    // An extension's record (opcode 0x80 and up) whose first bytes name no channel is skipped,
    // as the format asks: the file reads whole.
    let bytes = mcap(20, McapLayout { summary: false, crcs: false, ..McapLayout::UNCHUNKED });
    let data_end = support::logs::mcap_records(&bytes).iter().find(|record| record.1 == 0x0f).expect("data end").0;
    let mut extended = bytes[..data_end].to_vec();
    extended.push(0x90);
    extended.extend_from_slice(&40u64.to_le_bytes());
    extended.extend_from_slice(&[0xee; 40]);
    extended.extend_from_slice(&bytes[data_end..]);
    let table = read_mcap(write("extension.mcap", &extended), &McapOptions::default().topic(TOPIC)).unwrap();
    assert_eq!(table.len(), 20);
}

// ---- item 6: a rosbag2 folder whose metadata leaves out a split ------------------------------

/// A copy of the Python-written three-split sqlite3 bag of `PoseStamped` in `name`, and its
/// metadata; `None` (with a message) where Python cannot write the fixtures.
fn split_bag(name: &str) -> Option<(PathBuf, serde_yaml_ng::Value)> {
    // Written once per process: the tests run in parallel.
    static FIXTURES: OnceLock<Option<PathBuf>> = OnceLock::new();
    let fixtures = FIXTURES
        .get_or_init(|| support::bag_fixtures("small", &support::small_bag_poses()).map(|(dir, _)| dir))
        .as_ref()?;
    let source = fixtures.join("r2-sqlite3-split3-PoseStamped");
    let folder = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("readers-round-two").join(name);
    let _ = std::fs::remove_dir_all(&folder);
    std::fs::create_dir_all(&folder).expect("scratch folder");
    for entry in std::fs::read_dir(&source).expect("the fixture") {
        let path = entry.expect("an entry").path();
        std::fs::copy(&path, folder.join(path.file_name().expect("a name"))).expect("copy");
    }
    let metadata = serde_yaml_ng::from_str(&std::fs::read_to_string(folder.join("metadata.yaml")).expect("yaml"))
        .expect("the fixture's metadata");
    Some((folder, metadata))
}

fn info(metadata: &mut serde_yaml_ng::Value) -> &mut serde_yaml_ng::Value {
    &mut metadata["rosbag2_bagfile_information"]
}

fn save(folder: &Path, metadata: &serde_yaml_ng::Value) {
    std::fs::write(folder.join("metadata.yaml"), serde_yaml_ng::to_string(metadata).expect("yaml")).expect("save");
}

#[test]
fn item6_a_split_the_metadata_leaves_out_is_an_error() {
    let Some((folder, mut metadata)) = split_bag("unlisted") else { return };
    let options = McapOptions::default().topic("/pose");
    assert_eq!(read_rosbag2(&folder, &options).unwrap().len(), 60, "the whole bag");
    // The issue's case: the metadata lists the first splits and not the last, which is there.
    let files = info(&mut metadata)["relative_file_paths"].as_sequence_mut().expect("a list");
    let left_out = files.pop().expect("three files");
    save(&folder, &metadata);
    for path in [folder.clone(), folder.join("metadata.yaml")] {
        let error = read_rosbag2(&path, &options).unwrap_err();
        assert!(matches!(error, IoError::Bag { .. }), "{error:?}");
        let text = error.to_string();
        assert_one_line(&text, &folder.join("metadata.yaml"));
        assert!(
            text.contains(&format!(
                "the folder holds the storage file {:?}, which the bag does not list (relative_file_paths lists 2)",
                left_out.as_str().expect("a name")
            )),
            "{text}"
        );
        assert!(list_topics(&path).is_err());
    }
    // Listed and missing: an error as before.
    files_of(&mut metadata).push(left_out.clone());
    save(&folder, &metadata);
    std::fs::remove_file(folder.join(left_out.as_str().expect("a name"))).expect("remove");
    let error = read_rosbag2(&folder, &options).unwrap_err();
    assert!(error.to_string().contains("that the bag lists is missing"), "{error}");
}

fn files_of(metadata: &mut serde_yaml_ng::Value) -> &mut Vec<serde_yaml_ng::Value> {
    info(metadata)["relative_file_paths"].as_sequence_mut().expect("a list")
}

#[test]
fn item6_fewer_messages_than_the_metadata_counts_are_an_error() {
    let Some((folder, metadata)) = split_bag("counts") else { return };
    let options = McapOptions::default().topic("/pose");
    let metadata_path = folder.join("metadata.yaml");
    // The last split moved out of the folder and out of the list, the counts left as they were:
    // the bag's poses are 60, the two files hold 40.
    let mut short = metadata.clone();
    let last = files_of(&mut short).pop().expect("three files");
    let last = last.as_str().expect("a name").to_owned();
    info(&mut short)["files"].as_sequence_mut().expect("files").retain(|file| file["path"].as_str() != Some(&last));
    save(&folder, &short);
    std::fs::rename(folder.join(&last), folder.with_file_name(format!("moved-{last}"))).expect("move");
    let error = read_rosbag2(&folder, &options).unwrap_err();
    let text = error.to_string();
    assert_one_line(&text, &metadata_path);
    assert!(
        text.contains(
            "the bag counts 60 messages on topic /pose, but its 2 storage file(s) (r2-sqlite3-split3-PoseStamped_0.db3, \
             r2-sqlite3-split3-PoseStamped_1.db3) hold 40: messages were lost"
        ),
        "{text}"
    );
    // The total alone (a metadata without per-topic counts).
    info(&mut short)["topics_with_message_count"] = serde_yaml_ng::Value::Sequence(Vec::new());
    save(&folder, &short);
    let error = read_rosbag2(&folder, &options).unwrap_err();
    let declared = info(&mut short.clone())["message_count"].as_u64().expect("a count");
    assert!(error.to_string().contains(&format!("the bag counts {declared} messages (message_count)")), "{error}");
    // One storage file's count.
    std::fs::rename(folder.with_file_name(format!("moved-{last}")), folder.join(&last)).expect("move back");
    let mut file_short = metadata.clone();
    let first = &mut info(&mut file_short)["files"][0];
    let count = first["message_count"].as_u64().expect("a count");
    first["message_count"] = (count + 5).into();
    save(&folder, &file_short);
    let error = read_rosbag2(&folder, &options).unwrap_err();
    assert!(
        error.to_string().contains(&format!(
            "the bag counts {} messages in its storage file \"r2-sqlite3-split3-PoseStamped_0.db3\", which holds {count}",
            count + 5
        )),
        "{error}"
    );
    // More messages than counted (metadata written before the recording ended) read.
    let mut stale = metadata.clone();
    info(&mut stale)["message_count"] = 3.into();
    save(&folder, &stale);
    assert_eq!(read_rosbag2(&folder, &options).unwrap().len(), 60);
}

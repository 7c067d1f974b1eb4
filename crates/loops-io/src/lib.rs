//! # loops-io
//!
//! Pose logs in, for [`loops_core`], and results out: a reader returns a [`PoseTable`]
//! (timestamps, positions, orientations when the format has them, and the line or the MCAP
//! message each pose came from), and [`PoseTable::to_trajectory`] (or
//! [`to_trajectory_for`](PoseTable::to_trajectory_for) a metric) turns it into a
//! [`loops_core::Trajectory`], reporting the core's complaints (duplicate timestamps, ...) at
//! their line or message in the file.
//!
//! | format | reader | content | extensions |
//! |---|---|---|---|
//! | MCAP (ROS 2, Foxglove) | [`read_mcap`], [`read_mcap_files`], [`list_topics`], [`list_frame_pairs`] | one topic of [`PoseType`]: ROS 2 CDR `PoseStamped`, `PoseWithCovarianceStamped`, `TransformStamped`, `Odometry`, `TFMessage`; the same in ROS 1 encoding; Foxglove `PoseInFrame`, `PosesInFrame`, `FrameTransform(s)`, `Odometry` in protobuf or JSON | `.mcap` |
//! | rosbag2 (sqlite3, MCAP) | [`read_rosbag2`], [`list_topics`] | the ROS types above; the bag's folder, `metadata.yaml` or a storage file; splits; zstd per message or per file | folder, `.db3`, `.yaml`, `.zstd` |
//! | ROS 1 bag (format 2.0) | [`read_ros1`], [`list_topics`] | the ROS types above and `tf/tfMessage`; chunks uncompressed, bz2 or lz4 | `.bag` |
//! | TUM RGB-D | [`read_tum`] | `timestamp tx ty tz qx qy qz qw` | `.tum`, `.txt` |
//! | CSV | [`read_csv`] | `t,x,y` or `t,x,y,z`, optional header | `.csv` |
//! | KITTI | [`read_kitti`] | `[t] r00 r01 r02 tx ... r22 tz`, times from a rate or file if none | (`.txt`) |
//! | EuRoC | [`read_euroc`] | `timestamp [ns], p_xyz, q_wxyz, ...` | (`.csv`) |
//! | g2o / TORO | [`read_pose_graph`] | `VERTEX_SE2`, `VERTEX2`, `VERTEX_SE3:QUAT`, `VERTEX3` and their edges | `.g2o`, `.graph` |
//! | libRSF (TUC) | [`read_tuc`] | `point2 t x y ...`, `point3 t X Y Z ...` (ECEF → local ENU), `angle t yaw` | (`.txt`) |
//!
//! [`read_trajectory`] and [`read_trajectory_with`] pick the reader by [`Format`], or by
//! extension and first line ([`format_of`] tells which). Writers: [`write_tum`] for
//! trajectories, [`write_g2o_edges`] for candidate loop-closure edges with relative-pose
//! guesses (and [`write_fleet_g2o_edges`] for a fleet's, keyed by [`gtsam_symbol_key`]); a
//! fleet's tables: [`write_fleet_components`], [`write_session_pairs`], [`write_fleet_samples`];
//! the results for robotics viewers: [`Scene`] and [`write_scene_mcap`] (Foxglove's schemas and
//! a ROS 2 `MarkerArray`, on the topics of [`SCENE_TOPICS`], with [`FOXGLOVE_LAYOUT`]), and
//! [`LiveScene`], the same messages keyframe by keyframe for a live stream;
//! all atomic, and never replacing a
//! file unless asked ([`WriteError::Exists`]). [`write_atomically`] is the one atomic writer of
//! the workspace: the CLI writes its files through it too; [`StagedFiles`] writes several files
//! all or none (a command that fails writes nothing). [`out_dir`] is the one rule for an output
//! folder of several results (`loops run`, `loops fleet`, `loops-dask`): locked, marked, filled
//! through a scratch folder, and never removing or replacing what the command did not write;
//! [`out_dir::refuse_output_on_input`] keeps every writer off its inputs.
//!
//! Every error is an [`IoError`] whose message starts with the file and the line, or the topic
//! and byte offset: `drive.tum line 12: column 3 ("abc") is not a number`, `drive.mcap topic
//! /odom, message at byte 96 of the chunk at offset 4242: the CDR message ends at byte 60, but
//! nav_msgs/msg/Odometry needs ...`. No input makes a reader panic or allocate what a corrupt
//! length or a compression bomb declares: text files are read a line at a time (a line holds at
//! most [`MAX_LINE_BYTES`]), logs as streams. Nothing is dropped without an error: a line of an
//! unknown record type is an error, and a log is checked against its own CRCs, indexes and
//! counts, so that messages it says it holds and does not deliver are an error. `tests/attack_sweep.rs` holds the seeded
//! attack sweep that keeps it so (figures in `tests/FUZZ.md`).
//!
//! What it does not do (yet): ROS 1 bags of format 1.x; compose TF trees (one
//! parent-child pair is read as is); read the times of a `PosesInFrame` path pose by pose (all
//! poses of a message get its stamp). Unless asked, it does not normalise quaternions in a
//! table (the trajectory constructors do; [`PoseTable::normalize_orientations`] with a tolerance
//! of your choice), drop duplicate timestamps or detections outside the trajectory's span (they
//! are errors; [`PoseTable::drop_duplicate_stamps`] and [`DetectionTable::drop_outside_span`]
//! drop them and say how many, as [`Dropped`]). Several files read as one trajectory:
//! [`read_mcap_files`] merges MCAP files by time, [`PoseTable::join`] joins files that follow
//! one another; [`read_trajectories`] is the whole pipeline (formats, joining, dropped stamps,
//! quaternion tolerance, the metric's trajectory) that the command line and Python share.
//!
//! ## Quickstart
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use loops_core::{Euclidean, find_loops};
//!
//! // A square driven twice, one pose a second.
//! let path = std::env::temp_dir().join(format!("loops-io-quickstart-{}.tum", std::process::id()));
//! let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
//! for i in 0..8 {
//!     let [x, y] = [[0, 0], [10, 0], [10, 10], [0, 10]][i % 4];
//!     text += &format!("{i}.0 {x} {y} 0 0 0 0 1\n");
//! }
//! std::fs::write(&path, text)?;
//!
//! let table = loops_io::read_tum(&path)?;
//! assert_eq!((table.timestamps_s.len(), table.source_lines[0]), (8, 2));
//! let trajectory = table.to_trajectory_plane([0, 1])?;
//! let loops = find_loops(&trajectory, &Euclidean, 1.0)?;
//! assert!(loops.components().iter().any(|c| !c.trivial)); // the second lap revisits the first
//! # std::fs::remove_file(&path)?;
//! # Ok(())
//! # }
//! ```
//!
//! An MCAP log reads the same way: `read_mcap("drive.mcap", &McapOptions::default())` picks the
//! one topic with poses, or names the candidates; [`McapOptions`] names a topic, a time source
//! and a frame pair.
#![warn(missing_docs)]

// The modules in layers; each uses only modules of the layers above it (no cycles):
// 1. vocabulary and errors: `format`, `pose_type`, `topic`, `dropped`, `error`; the atomic writer
//    `atomic`;
// 2. plumbing: `text` (lines and numbers), `timing`, `table` (`PoseTable`), `rotation`;
// 3. messages: `cdr`, `foxglove`, `message` (decoding), `cdr_write`;
// 4. MCAP: `mcap_records` (the record walker), `mcap` (topics and poses), `mcap_write`;
// 5. readers: `csv`, `euroc`, `graph`, `kitti`, `tuc`, `tum`, `detections`; `read` picks one;
// 6. writers: `csv_rows` (serde rows through the csv crate), the result files `components`,
//    `loop_duration`, `report`, `quality`, `samples`, `edge_verdicts`; and `write` (TUM, g2o);
//    `fleet` (a fleet's tables and g2o edges); `out_dir` (an output folder of several results);
//    `scene` (the results for Foxglove, RViz and Rerun, and its MCAP file); `live_scene` (its
//    messages keyframe by keyframe, from the online engine).
mod atomic;
mod bag;
mod cdr;
mod cdr_write;
mod components;
mod compression;
mod csv;
mod csv_rows;
mod detections;
mod dropped;
mod edge_verdicts;
mod error;
mod euroc;
mod fleet;
mod format;
mod foxglove;
mod frame_tree;
mod graph;
mod json;
mod kitti;
mod live_scene;
mod loop_duration;
mod mcap;
mod mcap_records;
mod mcap_write;
mod message;
pub mod out_dir;
mod pose_type;
mod printable;
mod quality;
mod read;
mod report;
mod ros1_message;
mod rotation;
mod samples;
mod scene;
pub mod store;
mod table;
mod temp_copy;
mod text;
mod timing;
mod topic;
mod tuc;
mod tum;
mod write;

pub use crate::csv::read_csv;
pub use crate::mcap::{McapOptions, TimeSource, read_mcap, read_mcap_files};
pub use atomic::{StagedFiles, write_atomically};
pub use bag::{list_frame_pairs, list_topics, log_name, read_ros1, read_rosbag2};
pub use components::{
    CLOSEST_POSITION_COLUMNS, COMPONENT_COLUMNS, ClosestPositions, ComponentExtent, ComponentMeasures, ComponentRow,
    EXTENT_COLUMNS, MEASURE_COLUMNS, component_rows, component_rows_to_csv, components_to_csv, write_components,
};
pub use detections::{DetectionTable, read_detections};
pub use dropped::Dropped;
pub use edge_verdicts::{EDGE_VERDICT_COLUMNS, EdgeVerdictRow, EdgeVerdicts, VerdictCounts};
pub use error::{IoError, MessageLocation, Result, TrajectoryMessages, WriteError};
pub use euroc::read_euroc;
pub use fleet::{
    FLEET_COMPONENT_COLUMNS, FLEET_SAMPLE_COLUMNS, FleetComponentRow, FleetSampleRow, GTSAM_ROBOT_LETTERS,
    SESSION_PAIR_COLUMNS, SessionBlock, SessionPairRow, fleet_closest_positions, fleet_closest_positions_in,
    fleet_component_rows, fleet_components_to_csv, fleet_g2o_edges_text, fleet_sample_rows, fleet_samples_to_csv,
    fleet_samples_to_json, gtsam_symbol_key, session_pair_rows, session_pairs_to_csv, write_fleet_components,
    write_fleet_g2o_edges, write_fleet_samples, write_session_pairs,
};
pub use format::Format;
pub use graph::{EdgeChain, GraphEdge, PoseGraph, RelativePose, SkippedRecords, read_pose_graph};
pub use kitti::{ROTATION_MATRIX_TOLERANCE, read_kitti};
pub use live_scene::{LIVE_PLANE_POSES, LIVE_TOPICS, LiveChannel, LiveMessage, LiveScene};
pub use loop_duration::{
    LOOP_DURATION_COLUMNS, LoopDurationRow, loop_duration_rows, loop_duration_to_csv, point_position, point_positions,
    write_loop_duration,
};
pub use mcap_write::{McapCompression, McapPoseMessage, McapWriteOptions, write_mcap};
pub use message::{DecodeError, DecodedPose, decode_poses};
pub use pose_type::{MessageEncoding, PoseType};
pub use quality::{COMPARED_SAMPLERS, QualitySummary, compare_samplers};
pub use read::{
    ReadNotes, ReadOptions, ReadPoses, format_of, read_pose_graph_with, read_trajectories, read_trajectory,
    read_trajectory_chaining, read_trajectory_with,
};
pub use report::{ComponentReport, LoopsReport, SeparationReport, loops_report_to_json, write_loops_report};
pub use samples::{
    CSV_HEADER, SAMPLE_POSITION_COLUMNS, SampleRow, SamplesFormat, samples_to_csv, samples_to_json, write_samples,
};
pub use scene::{
    COMPONENT_RGB, FOXGLOVE_LAYOUT, FOXGLOVE_LAYOUT_FILE, PATH_STEP_POSES, PATH_STEPS, PLANE_PIXELS, RgbImage,
    SCENE_FRAME, SCENE_TOPICS, Scene, SceneCandidate, SceneComponent, ScenePath, SceneTopic, TRIVIAL_RGB, path_steps,
    scene_mcap_merged_to, scene_mcap_to, tau_rgba, write_scene_mcap, write_scene_mcap_merged,
};
pub use table::{MessageRef, MessageSources, PoseTable, metric_takes_plane, seconds_of_ns};
pub use temp_copy::remove_temporary_files;
pub use text::MAX_LINE_BYTES;
pub use timing::{Timing, TimingConflict};
pub use topic::{FramePairInfo, TopicInfo};
pub use tuc::{LIBRSF_TAGS, read_tuc};
pub use tum::read_tum;
pub use write::{EdgeKind, G2oOptions, g2o_edges_text, table_relative_pose, write_g2o_edges, write_tum};

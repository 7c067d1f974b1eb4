//! The results as a scene for robotics viewers: Foxglove, RViz (through a ROS 2 bag) and
//! Rerun. A [`Scene`] holds what every viewer draws, computed once here: the paths (one per
//! session), τ along them as a colour, each loop component (the two stretches of path it joins
//! and its closest pair, a colour per component), the sampled candidate pairs, and the (t, t′)
//! plane as an RGB image. [`write_scene_mcap`] writes it as MCAP on the topics of
//! [`SCENE_TOPICS`]; the Python package draws the same [`Scene`] with `rerun-sdk`.
//!
//! The Foxglove messages are the `foxglove` crate's (Foxglove's SDK: its published protobuf
//! schemas, each with its `FileDescriptorSet`, so Foxglove and the `foxglove-schemas-protobuf`
//! package decode them); the file is written with the `mcap` crate, as [`write_mcap`](crate::write_mcap)
//! writes pose logs, rather than with the SDK's writer: the SDK's writer logs through a
//! process-wide context of channels and sinks, where ours writes one file from one value,
//! through [`write_atomically`], with the log times we choose, and reports each error. The ROS
//! 2 `visualization_msgs/msg/MarkerArray` is written in CDR by hand, as the pose messages are
//! (`cdr_write`), with the Humble definition as its `ros2msg` schema.

use std::collections::BTreeMap;
use std::io::{self, BufWriter, Seek, Write};
use std::path::Path;
use std::sync::Arc;

use foxglove::Encode;
use foxglove::messages::{
    Color, KeyValuePair, LinePrimitive, Point3, Pose, PosesInFrame, Quaternion, RawImage, SceneEntity, SceneUpdate,
    Timestamp, Vector3, line_primitive,
};
use loops_core::{
    Loops, Samples, Scale, Selection, Side, Trajectory,
    fleet::{Fleet, FleetLoops},
    plane::PlaneGrid,
};
use mcap::records::MessageHeader;

use crate::atomic::write_atomically;
use crate::cdr_write::{CdrWriter, IDENTITY_XYZW, RosTime};
use crate::error::WriteError;
use crate::loop_duration::point_positions;

/// The most pixels a side of the plane image ([`Scene::plane`]).
pub const PLANE_PIXELS: usize = 512;

/// The most updates of one session's path and τ in the scene's MCAP file ([`path_steps`]).
pub const PATH_STEPS: usize = 100;

/// About the most poses that one session's path updates hold together, past the path's own
/// poses ([`path_steps`]): each update repeats the path so far, so a long path gets fewer
/// updates. About 200 bytes a pose in the three topics (PosesInFrame, τ strip, MarkerArray)
/// before compression: some 40 MB a session at most.
pub const PATH_STEP_POSES: usize = 200_000;

/// The last pose of each update of a path of `n` poses, increasing, the last `n - 1` (none for
/// an empty path): one update every `⌈n / m⌉` poses, for `m` the most updates, at most
/// [`PATH_STEPS`], whose repeated prefixes hold about [`PATH_STEP_POSES`] poses. In all, the
/// updates hold at most `PATH_STEP_POSES + n + PATH_STEPS²` poses. O(updates).
///
/// # Examples
/// ```
/// assert_eq!(loops_io::path_steps(10), [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
/// assert_eq!(loops_io::path_steps(1000).len(), loops_io::PATH_STEPS);
/// assert_eq!(loops_io::path_steps(4_000_000), [3_999_999]); // too long to repeat: whole, once
/// ```
pub fn path_steps(n: usize) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    let most = (2 * PATH_STEP_POSES / n).clamp(1, PATH_STEPS);
    let stride = n.div_ceil(most);
    (1..=n.div_ceil(stride)).map(|m| (m * stride).min(n) - 1).collect()
}

/// The frame every entity is in, unless [`Scene::frame_id`] says otherwise.
pub const SCENE_FRAME: &str = "map";

/// One topic of the scene's MCAP file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct SceneTopic {
    /// The topic.
    pub topic: &'static str,
    /// Its schema (message type).
    pub schema: &'static str,
    /// What its messages hold.
    pub holds: &'static str,
}

/// The topics [`write_scene_mcap`] writes, in the file's channel order.
pub const SCENE_TOPICS: [SceneTopic; 6] = [
    SceneTopic {
        topic: "/loops/trajectory",
        schema: "foxglove.PosesInFrame",
        holds: "the path as the log plays: per session, at most 100 messages (path_steps), each at a pose's time \
                with every pose up to it, position and orientation; the last, at its last pose, the whole path",
    },
    SceneTopic {
        topic: "/loops/tau",
        schema: "foxglove.SceneUpdate",
        holds: "with each message of /loops/trajectory, an entity `tau/<session>`: the path so far as a line \
                strip coloured by τ (red = the longest τ)",
    },
    SceneTopic {
        topic: "/loops/components",
        schema: "foxglove.SceneUpdate",
        holds: "a message per component, when its second stretch begins, with an entity `component/<id>`: \
                its two stretches of path and its closest pair, in its colour; the components.csv values as metadata",
    },
    SceneTopic {
        topic: "/loops/candidates",
        schema: "foxglove.SceneUpdate",
        holds: "a message per sampled pair, at its later pose's time, with an entity `candidate/<k>` \
                (samples.csv's row k): the line between its poses",
    },
    SceneTopic {
        topic: "/loops/plane",
        schema: "foxglove.RawImage",
        holds: "the (t, t′) plane, rgb8: t to the right, t′ up, each component in its colour, candidates white; \
                at the first pose's time",
    },
    SceneTopic {
        topic: "/loops/markers",
        schema: "visualization_msgs/msg/MarkerArray",
        holds: "the same for RViz (ROS 2 CDR), at the same times: namespaces trajectory, tau, \
                components (3 markers each), candidates (id k)",
    },
];

/// The Foxglove layout shipped beside an MCAP file of the scene: a 3D panel with the scene's
/// topics and an Image panel with the plane. Import it in Foxglove (Layouts, Import from file).
pub const FOXGLOVE_LAYOUT: &str = include_str!("scene_layout.json");

/// The name of the layout file beside `results.mcap`.
pub const FOXGLOVE_LAYOUT_FILE: &str = "foxglove-layout.json";

/// One session's path: its poses and their loop duration τ.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ScenePath {
    /// The session's name (the log's, for one trajectory).
    pub name: String,
    /// Each pose's time, seconds (on the session's own clock).
    pub timestamps_s: Vec<f64>,
    /// Each pose's position `[x, y, z]` (0 for the coordinates a 1-D or 2-D path lacks).
    pub positions: Vec<[f64; 3]>,
    /// Each pose's orientation `[x, y, z, w]`, when the log has them.
    pub orientations_xyzw: Option<Vec<[f64; 4]>>,
    /// Each pose's loop duration τ, seconds (over the whole fleet for a fleet's session).
    pub loop_duration_s: Vec<f64>,
}

/// A loop component as the scene draws it.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct SceneComponent {
    /// Its id (`components.csv`'s `id`).
    pub id: usize,
    /// Whether it is trivial.
    pub trivial: bool,
    /// The sessions of its rows (t) and its columns (t′); `[0, 0]` for one trajectory.
    pub sessions: [usize; 2],
    /// Its first and last pose by t in session `sessions[0]`, and by t′ in `sessions[1]`.
    pub poses: [[usize; 2]; 2],
    /// Its closest pair: a pose of each session.
    pub closest_pair: [usize; 2],
    /// δ at the closest pair, in the metric's unit.
    pub closest_distance: f64,
    /// Its area, s².
    pub area_s2: f64,
    /// Its number of pose pairs.
    pub pair_count: u64,
}

impl From<&loops_core::LoopComponent> for SceneComponent {
    /// A component of one trajectory (`sessions` `[0, 0]`).
    fn from(c: &loops_core::LoopComponent) -> Self {
        Self {
            id: c.id,
            trivial: c.trivial,
            sessions: [0, 0],
            poses: [c.i_range, c.j_range],
            closest_pair: c.closest_pair,
            closest_distance: c.closest_distance,
            area_s2: c.area_s2,
            pair_count: c.pair_count,
        }
    }
}

impl From<&loops_core::online::OnlineComponent> for SceneComponent {
    /// A component of the online engine, as it stands (`sessions` `[0, 0]`).
    fn from(c: &loops_core::online::OnlineComponent) -> Self {
        Self {
            id: c.id as usize,
            trivial: c.trivial,
            sessions: [0, 0],
            poses: [c.i_range, c.j_range],
            closest_pair: c.closest_pair,
            closest_distance: c.closest_distance,
            area_s2: c.area_s2,
            pair_count: c.pair_count,
        }
    }
}

/// A sampled candidate pair as the scene draws it.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct SceneCandidate {
    /// The sessions of the earlier and the later pose.
    pub sessions: [usize; 2],
    /// The poses, each in its session.
    pub poses: [usize; 2],
    /// Its component, when known.
    pub component: Option<usize>,
}

/// An RGB image, 8 bits a channel, rows from the top.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct RgbImage {
    /// Pixels a row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width × height × 3` bytes, row by row from the top.
    pub rgb: Vec<u8>,
}

/// What the viewers draw of a result; see the [module](self).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Scene {
    /// The frame of every entity: [`SCENE_FRAME`] unless set.
    pub frame_id: String,
    /// The paths, one per session.
    pub paths: Vec<ScenePath>,
    /// Every loop component, in id order.
    pub components: Vec<SceneComponent>,
    /// Every sampled pair of poses, in the samples' order (samples without a pose pair, drawn
    /// from detections off the trajectory, are left out).
    pub candidates: Vec<SceneCandidate>,
    /// The (t, t′) plane: [`PLANE_PIXELS`] pixels a side at most (see [`SCENE_TOPICS`]).
    pub plane: RgbImage,
}

/// The colour of the plane's pixels outside every component.
const BACKGROUND_RGB: [u8; 3] = [32, 32, 32];
/// The colour of candidate pairs: lines in 3-D, pixels on the plane.
const CANDIDATE_RGBA: [f64; 4] = [1.0, 1.0, 1.0, 0.9];
/// The colour of trivial components (a pose near its own time): [`TRIVIAL_RGB`], translucent.
const TRIVIAL_ALPHA: f64 = 0.35;
/// Colours of non-trivial components, by id modulo six: bright on a dark background and none
/// of them red or white (the colours of samples and candidate pairs). The HTML report, the
/// Foxglove/RViz scene and the live scene all colour component `k` with `COMPONENT_RGB[k % 6]`,
/// so a component looks the same wherever it is seen.
pub const COMPONENT_RGB: [[u8; 3]; 6] = [
    [0xf2, 0x8e, 0x2b],
    [0x8c, 0xd1, 0x7d],
    [0x4f, 0xd1, 0xe8],
    [0xf1, 0xce, 0x63],
    [0xd4, 0xa6, 0xc8],
    [0xb6, 0x99, 0x2d],
];
/// The colour of trivial components, in the report and the scenes.
pub const TRIVIAL_RGB: [u8; 3] = [0xc8, 0xd0, 0xdc];
/// Line widths, in the frame's unit: paths, components, candidates.
const PATH_WIDTH: f64 = 0.5;
const COMPONENT_WIDTH: f64 = 1.5;
const CANDIDATE_WIDTH: f64 = 0.3;

impl SceneComponent {
    /// Its colour, RGBA in [0, 1]: [`COMPONENT_RGB`] by id for a non-trivial component,
    /// [`TRIVIAL_RGB`] translucent for a trivial one.
    pub fn rgba(&self) -> [f64; 4] {
        let ([r, g, b], alpha) = if self.trivial {
            (TRIVIAL_RGB, TRIVIAL_ALPHA)
        } else {
            (COMPONENT_RGB[self.id % COMPONENT_RGB.len()], 1.0)
        };
        [f64::from(r) / 255.0, f64::from(g) / 255.0, f64::from(b) / 255.0, alpha]
    }
}

/// The colour of a pose whose τ is `loop_duration_s`, on a scale whose red end is
/// `max_loop_duration_s`: RGBA `[f, 0.3, 1 − f, 1]`, f = τ / max (blue: no loop; 0 when the
/// max is not positive).
///
/// # Examples
/// ```
/// assert_eq!(loops_io::tau_rgba(5.0, 10.0), [0.5, 0.3, 0.5, 1.0]);
/// assert_eq!(loops_io::tau_rgba(0.0, 0.0), [0.0, 0.3, 1.0, 1.0]);
/// ```
pub fn tau_rgba(loop_duration_s: f64, max_loop_duration_s: f64) -> [f64; 4] {
    let f = if max_loop_duration_s > 0.0 { (loop_duration_s / max_loop_duration_s).clamp(0.0, 1.0) } else { 0.0 };
    [f, 0.3, 1.0 - f, 1.0]
}

impl Scene {
    /// The scene of `loops` found on `traj` (the session `name`), with `samples` drawn from them.
    /// `positions` and `orientations_xyzw` are the poses as the log gave them (a
    /// [`PoseTable`](crate::PoseTable)'s); without them, each point's first three coordinates
    /// ([`point_positions`]) and no orientations. O(n + components + samples + plane pixels).
    ///
    /// # Errors
    /// [`loops_core::Error::RowCountMismatch`] when `positions` or `orientations_xyzw` do not
    /// have one row per pose, [`loops_core::Error::TrajectoryMismatch`] (or another of
    /// [`Loops::check_trajectory`]'s) when `loops` were found on another trajectory, and
    /// [`loops_core::Error::PoseIndexOutOfRange`] for samples of another trajectory.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, Trajectory, find_loops, sample_loops};
    /// let square = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
    /// let points: Vec<[f64; 2]> = (0..8).map(|i| square[i % 4]).collect();
    /// let traj = Trajectory::from_points((0..8).map(f64::from).collect(), &points)?;
    /// let loops = find_loops(&traj, &Euclidean, 1.0)?;
    /// let samples = sample_loops(&traj, &Euclidean, &loops, &Sampler::new(SamplerKind::One, SampleSize::Budget(4), 7))?;
    /// let scene = loops_io::Scene::of_trajectory("square", &traj, None, None, &loops, &samples)?;
    /// assert_eq!((scene.paths[0].positions.len(), scene.components.len()), (8, loops.components().len()));
    /// assert_eq!(scene.candidates.len(), samples.len());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn of_trajectory(
        name: &str,
        traj: &Trajectory,
        positions: Option<&[[f64; 3]]>,
        orientations_xyzw: Option<&[[f64; 4]]>,
        loops: &Loops,
        samples: &Samples,
    ) -> loops_core::Result<Self> {
        loops.check_trajectory(traj)?;
        let n = traj.len();
        for (what, rows) in
            [("positions", positions.map(<[_]>::len)), ("orientations", orientations_xyzw.map(<[_]>::len))]
        {
            if let Some(rows) = rows.filter(|&rows| rows != n) {
                return Err(loops_core::Error::RowCountMismatch {
                    first: "poses",
                    first_rows: n,
                    second: what,
                    second_rows: rows,
                });
            }
        }
        let path = ScenePath {
            name: name.to_owned(),
            timestamps_s: traj.timestamps_s().to_vec(),
            positions: positions.map_or_else(|| point_positions(traj), <[_]>::to_vec),
            orientations_xyzw: orientations_xyzw.map(<[_]>::to_vec),
            loop_duration_s: loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?,
        };
        let components = loops.components().iter().map(SceneComponent::from).collect();
        let mut candidates = Vec::with_capacity(samples.len());
        for sample in samples.rows() {
            if let Some(pair) = sample.pair {
                for index in pair {
                    loops.check_index(index)?;
                }
                candidates.push(SceneCandidate { sessions: [0, 0], poses: pair, component: sample.component });
            }
        }
        let pairs: Vec<[usize; 2]> = candidates.iter().map(|c| c.poses).collect();
        let plane = loops_plane(loops, &pairs)?;
        let frame_id = SCENE_FRAME.to_owned();
        Ok(Self { frame_id, paths: vec![path], components, candidates, plane })
    }

    /// The scene of a fleet's `loops` found on `fleet`, with `samples` drawn from them: a path
    /// per session (each point's first three coordinates, [`point_positions`], or `positions`
    /// per session when given), τ over the whole fleet, every component with its two sessions,
    /// and the plane of the joint trajectory (sessions one after the other).
    ///
    /// # Errors
    /// [`loops_core::Error::RowCountMismatch`] when `positions` do not have one list per session
    /// and one row per pose; what [`Fleet::localize`] returns for samples of another fleet.
    pub fn of_fleet(
        fleet: &Fleet,
        positions: Option<&[Vec<[f64; 3]>]>,
        loops: &FleetLoops,
        samples: &Samples,
    ) -> loops_core::Result<Self> {
        let joint = loops.loops();
        joint.check_trajectory(fleet.joint())?;
        if let Some(positions) = positions.filter(|p| p.len() != fleet.len()) {
            return Err(loops_core::Error::RowCountMismatch {
                first: "sessions",
                first_rows: fleet.len(),
                second: "position lists",
                second_rows: positions.len(),
            });
        }
        let (own, other) = loops.loop_duration();
        let mut paths = Vec::with_capacity(fleet.len());
        for (a, name) in fleet.names().iter().enumerate() {
            let session = fleet.session(a);
            let start = fleet.starts()[a];
            let session_positions = match positions {
                Some(positions) if positions[a].len() != session.len() => {
                    return Err(loops_core::Error::RowCountMismatch {
                        first: "poses",
                        first_rows: session.len(),
                        second: "positions",
                        second_rows: positions[a].len(),
                    });
                }
                Some(positions) => positions[a].clone(),
                None => point_positions(session),
            };
            paths.push(ScenePath {
                name: name.clone(),
                timestamps_s: session.timestamps_s().to_vec(),
                positions: session_positions,
                orientations_xyzw: None,
                loop_duration_s: (start..start + session.len()).map(|k| own[k] + other[k]).collect(),
            });
        }
        let components = loops
            .components()
            .into_iter()
            .map(|c| SceneComponent {
                id: c.id,
                trivial: c.trivial,
                sessions: c.sessions,
                poses: c.poses,
                closest_pair: c.closest_pair,
                closest_distance: c.closest_distance,
                area_s2: c.area_s2,
                pair_count: c.pair_count,
            })
            .collect();
        let candidates = fleet
            .localize(samples)?
            .into_iter()
            .map(|s| SceneCandidate { sessions: s.sessions, poses: s.poses, component: s.component })
            .collect();
        let joint_pairs: Vec<[usize; 2]> = samples.rows().iter().filter_map(|s| s.pair).collect();
        let plane = loops_plane(joint, &joint_pairs)?;
        Ok(Self { frame_id: SCENE_FRAME.to_owned(), paths, components, candidates, plane })
    }

    /// The largest τ of every path, seconds: the red end of [`tau_rgba`]'s scale.
    pub fn max_loop_duration_s(&self) -> f64 {
        self.paths.iter().flat_map(|p| p.loop_duration_s.iter().copied()).fold(0.0, f64::max)
    }

    /// The position of pose `pose` of session `session`.
    fn position(&self, session: usize, pose: usize) -> [f64; 3] {
        self.paths[session].positions[pose]
    }

    /// Why the scene cannot be drawn: an index outside its paths (a scene built by hand).
    fn check(&self) -> Result<(), String> {
        let fits = |session: usize, pose: usize| self.paths.get(session).is_some_and(|p| pose < p.positions.len());
        for c in &self.components {
            let [[i0, i1], [j0, j1]] = c.poses;
            let [a, b] = c.sessions;
            let inside = i0 <= i1 && j0 <= j1 && fits(a, i1) && fits(b, j1);
            if !inside || !fits(a, c.closest_pair[0]) || !fits(b, c.closest_pair[1]) {
                return Err(format!("component {}: a pose outside its sessions' paths", c.id));
            }
        }
        for (k, c) in self.candidates.iter().enumerate() {
            if !fits(c.sessions[0], c.poses[0]) || !fits(c.sessions[1], c.poses[1]) {
                return Err(format!("candidate {k}: a pose outside its sessions' paths"));
            }
        }
        for p in &self.paths {
            let orientations = p.orientations_xyzw.as_ref().map_or(p.positions.len(), Vec::len);
            if p.timestamps_s.len() != p.positions.len()
                || p.loop_duration_s.len() != p.positions.len()
                || orientations != p.positions.len()
            {
                return Err(format!("session {:?}: its columns have different lengths", p.name));
            }
        }
        if self.frame_id.contains('\0') || self.plane.rgb.len() != self.plane.width * self.plane.height * 3 {
            return Err("the frame id has a NUL character, or the plane's pixels do not fill it".to_owned());
        }
        Ok(())
    }
}

/// The (t, t′) plane of `loops` on `grid` as RGB, t′ up: each pixel in its component's colour
/// ([`SceneComponent::rgba`]), [`BACKGROUND_RGB`] outside, and the pixels of `pairs` (and their
/// mirrors) white.
fn plane_image(loops: &Loops, grid: &PlaneGrid, pairs: &[[usize; 2]]) -> loops_core::Result<RgbImage> {
    let labels = loops.label_image(grid)?;
    let (width, height) = (grid.width(), grid.height());
    let colours: Vec<[u8; 3]> = loops
        .components()
        .iter()
        .map(|c| {
            SceneComponent::from(c).rgba().map(|v| (v * 255.0).round() as u8)[..3].try_into().expect("three channels")
        })
        .collect();
    let mut rgb = vec![0; width * height * 3];
    // Row 0 of the labels is the earliest t′: the image's bottom row.
    for (k, label) in labels.iter().enumerate() {
        let (row, column) = (k / width, k % width);
        let colour = label.map_or(BACKGROUND_RGB, |id| colours[id as usize]);
        let at = ((height - 1 - row) * width + column) * 3;
        rgb[at..at + 3].copy_from_slice(&colour);
    }
    let white = CANDIDATE_RGBA.map(|v| (v * 255.0).round() as u8);
    // The pixel of a pose on an axis: the last column (row) whose pose is at or before it.
    let pixel = |axis: &[usize], pose: usize| axis.partition_point(|&p| p <= pose).checked_sub(1);
    for &[i, j] in pairs {
        for (t, t_prime) in [(i, j), (j, i)] {
            if let (Some(column), Some(row)) = (pixel(grid.columns(), t), pixel(grid.rows(), t_prime)) {
                let at = ((height - 1 - row) * width + column) * 3;
                rgb[at..at + 3].copy_from_slice(&white[..3]);
            }
        }
    }
    Ok(RgbImage { width, height, rgb })
}

/// Writes `scene` as an MCAP file on the topics of [`SCENE_TOPICS`]: Foxglove's schemas
/// (protobuf, each with its descriptor set) and a ROS 2 `MarkerArray` (CDR), on a timeline
/// in nanoseconds from the poses' times (each session's own clock; 0 for a time outside 1970
/// to 2038): each session's path and τ as the log plays, in steps ([`path_steps`]: at each
/// step's last pose, the path up to that pose; at most [`PATH_STEPS`] steps a session, the last
/// at its last pose, the whole path), each component at the time its
/// second stretch begins (when the robot comes back), each candidate (entity `candidate/<k>`)
/// at its later pose's time, the plane at the first pose's time; the MarkerArray holds the same
/// markers at the same times. Messages are in time order, with a metadata record `loops`
/// naming the sessions. Every entity lives
/// until replaced (no lifetime). The file is chunked (zstd), indexed and written atomically; an
/// existing file is replaced only with `overwrite`. O(poses + components + candidates + pixels).
///
/// # Errors
/// [`WriteError::Exists`] when `path` exists and `overwrite` is false; [`WriteError::Write`]
/// when it cannot be written, or (an [`io::ErrorKind::InvalidInput`] error) for a scene built by
/// hand whose indices fall outside its paths. Nothing is written then.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, Trajectory, find_loops, sample_loops};
/// let points: Vec<[f64; 2]> = (0..8).map(|i| [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]][i % 4]).collect();
/// let traj = Trajectory::from_points((0..8).map(f64::from).collect(), &points)?;
/// let loops = find_loops(&traj, &Euclidean, 1.0)?;
/// let samples = sample_loops(&traj, &Euclidean, &loops, &Sampler::new(SamplerKind::One, SampleSize::Budget(4), 7))?;
/// let scene = loops_io::Scene::of_trajectory("square", &traj, None, None, &loops, &samples)?;
/// let path = std::env::temp_dir().join(format!("loops-io-scene-{}.mcap", std::process::id()));
/// loops_io::write_scene_mcap(&path, &scene, false)?;
/// assert!(loops_io::write_scene_mcap(&path, &scene, false).is_err()); // not overwritten
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn write_scene_mcap(path: impl AsRef<Path>, scene: &Scene, overwrite: bool) -> Result<(), WriteError> {
    let path = path.as_ref();
    scene.check().map_err(|message| WriteError::Write {
        path: path.to_path_buf(),
        error: io::Error::new(io::ErrorKind::InvalidInput, message),
    })?;
    write_atomically(path, overwrite, |file| scene_mcap_to(file, scene))
}

/// Writes `scene` as [`write_scene_mcap`] does, with the user's MCAP log at `log` merged in
/// ([`scene_mcap_merged_to`]: its schemas, channels and messages as they are), to the file
/// `path`, atomically; an existing file is replaced only with `overwrite`, and never when it is
/// the log itself (or a link to it). The log is read whole into memory.
///
/// # Errors
/// [`WriteError::Exists`] as [`write_scene_mcap`]; [`WriteError::Write`] when `path` is the log
/// ([`io::ErrorKind::InvalidInput`]), when the log cannot be read or is not MCAP
/// ([`io::ErrorKind::InvalidData`], naming it), or when `path` cannot be written. Nothing is
/// written then.
pub fn write_scene_mcap_merged(
    path: impl AsRef<Path>,
    scene: &Scene,
    log: &Path,
    overwrite: bool,
) -> Result<(), WriteError> {
    let path = path.as_ref();
    let failed = |error: io::Error| WriteError::Write { path: path.to_path_buf(), error };
    crate::out_dir::refuse_output_on_input("the results MCAP", path, &[log.to_path_buf()])
        .map_err(|error| failed(io::Error::new(io::ErrorKind::InvalidInput, error.to_string())))?;
    let bytes = std::fs::read(log)
        .map_err(|error| failed(io::Error::new(error.kind(), format!("reading {}: {error}", log.display()))))?;
    // Read before the file is made, so that a bad log leaves nothing behind.
    let merged = MergedLog::read(&bytes).map_err(|error| {
        failed(io::Error::new(io::ErrorKind::InvalidData, format!("merging {}: {error}", log.display())))
    })?;
    scene.check().map_err(|message| failed(io::Error::new(io::ErrorKind::InvalidInput, message)))?;
    let mut merged = Some(merged);
    write_atomically(path, overwrite, |file| {
        write_scene(file, scene, merged.take()).map_err(|error| match error {
            mcap::McapError::Io(error) => error,
            error => io::Error::other(error),
        })
    })
}

/// Writes `scene` as [`write_scene_mcap`] does, into `out` (a file of an output folder that
/// another rule places: [`OutDir::write_file`](crate::out_dir::OutDir::write_file)).
///
/// # Errors
/// What `out` returns; an [`io::ErrorKind::InvalidInput`] error for a scene built by hand whose
/// indices fall outside its paths (nothing is written then).
pub fn scene_mcap_to<W: Write + Seek>(out: W, scene: &Scene) -> io::Result<()> {
    scene_mcap_merged_to(out, scene, None)
}

/// Writes `scene` as [`scene_mcap_to`] does, with the user's MCAP log `log` (its bytes, as read
/// from its file `log.0`) merged in, so that the loops play back over their data: its schemas
/// and channels under their own ids and contents, byte for byte (the scene's take the ids left
/// free), and each of its messages with its data, log time, publish time and sequence, in time
/// order among the scene's; its attachments (name, media type, times, data) and metadata
/// records (name, keys, values) as they are, in the file's order, before the scene's metadata
/// record `loops`. O(the log's bytes + the scene's messages).
///
/// # Errors
/// What `out` returns; an [`io::ErrorKind::InvalidData`] error naming `log.0` when the log is
/// not a readable MCAP file; [`io::ErrorKind::InvalidInput`] as [`scene_mcap_to`].
pub fn scene_mcap_merged_to<W: Write + Seek>(out: W, scene: &Scene, log: Option<(&Path, &[u8])>) -> io::Result<()> {
    scene.check().map_err(|message| io::Error::new(io::ErrorKind::InvalidInput, message))?;
    let merged = match log {
        Some((path, bytes)) => Some(MergedLog::read(bytes).map_err(|error| {
            io::Error::new(io::ErrorKind::InvalidData, format!("merging {}: {error}", path.display()))
        })?),
        None => None,
    };
    write_scene(out, scene, merged).map_err(|error| match error {
        mcap::McapError::Io(error) => error,
        error => io::Error::other(error),
    })
}

/// A user's MCAP log to merge into the scene's file: its schemas and channels by id, its
/// messages (channel id, sequence, log time, publish time, data), attachments and metadata
/// records, each in the file's order.
struct MergedLog<'a> {
    schemas: BTreeMap<u16, Arc<mcap::Schema<'a>>>,
    channels: BTreeMap<u16, Arc<mcap::Channel<'a>>>,
    messages: Vec<mcap::Message<'a>>,
    attachments: Vec<mcap::Attachment<'a>>,
    metadata: Vec<mcap::records::Metadata>,
}

impl<'a> MergedLog<'a> {
    /// Reads `bytes`, an MCAP file: every channel and schema its summary lists (used or not),
    /// and those of its messages.
    fn read(bytes: &'a [u8]) -> mcap::McapResult<Self> {
        let mut log = Self {
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
            messages: Vec::new(),
            attachments: Vec::new(),
            metadata: Vec::new(),
        };
        if let Some(summary) = mcap::Summary::read(bytes)? {
            log.schemas.extend(summary.schemas);
            log.channels.extend(summary.channels);
        }
        for message in mcap::MessageStream::new(bytes)? {
            let message = message?;
            let channel = &message.channel;
            if let Some(schema) = &channel.schema {
                log.schemas.entry(schema.id).or_insert_with(|| Arc::clone(schema));
            }
            log.channels.entry(channel.id).or_insert_with(|| Arc::clone(channel));
            log.messages.push(message);
        }
        // Attachments and metadata are top-level records, never inside a chunk.
        for record in mcap::read::LinearReader::new(bytes)? {
            match record? {
                mcap::records::Record::Attachment { header, data, .. } => log.attachments.push(mcap::Attachment {
                    log_time: header.log_time,
                    create_time: header.create_time,
                    name: header.name,
                    media_type: header.media_type,
                    data,
                }),
                mcap::records::Record::Metadata(metadata) => log.metadata.push(metadata),
                _ => {}
            }
        }
        Ok(log)
    }
}

/// Writes the scene's MCAP file into `out`, with `log` merged in.
fn write_scene<W: Write + Seek>(out: W, scene: &Scene, log: Option<MergedLog<'_>>) -> mcap::McapResult<()> {
    let mut writer = mcap::WriteOptions::new()
        .profile("")
        .library(concat!("loops-io ", env!("CARGO_PKG_VERSION")))
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .create(BufWriter::new(out))?;
    // The log's schemas and channels first, under their own ids.
    if let Some(log) = &log {
        for schema in log.schemas.values() {
            writer.add_schema_with_id(schema.id, &schema.name, &schema.encoding, &schema.data)?;
        }
        for channel in log.channels.values() {
            let schema_id = channel.schema.as_ref().map_or(0, |s| s.id);
            writer.add_channel_with_id(
                channel.id,
                schema_id,
                &channel.topic,
                &channel.message_encoding,
                &channel.metadata,
            )?;
        }
    }
    // Each message at the time its poses were reached, on its session's clock: 0 for a time
    // outside 1970 to 2038.
    let time = |session: usize, pose: usize| {
        scene.paths[session]
            .timestamps_s
            .get(pose)
            .and_then(|&t| RosTime::of_seconds(t))
            .unwrap_or(RosTime { sec: 0, nanosec: 0 })
    };
    let timestamp = |stamp: RosTime| Some(Timestamp::new(stamp.sec.unsigned_abs(), stamp.nanosec));
    let mut channels = Vec::new();
    for topic in &SCENE_TOPICS[..5] {
        let (schema, encoding, data) = match topic.schema {
            "foxglove.PosesInFrame" => foxglove_schema::<PosesInFrame>(),
            "foxglove.RawImage" => foxglove_schema::<RawImage>(),
            _ => foxglove_schema::<SceneUpdate>(),
        };
        let schema_id = writer.add_schema(&schema, &encoding, &data)?;
        channels.push(writer.add_channel(schema_id, topic.topic, "protobuf", &BTreeMap::new())?);
    }
    let schema_id = writer.add_schema(SCENE_TOPICS[5].schema, "ros2msg", MARKER_ARRAY_SCHEMA.as_bytes())?;
    let markers_channel = writer.add_channel(schema_id, SCENE_TOPICS[5].topic, "cdr", &BTreeMap::new())?;

    // Every message with its time and channel, written in time order at the end.
    let mut messages: Vec<(RosTime, u16, Vec<u8>)> = Vec::new();
    let frame_id = &scene.frame_id;
    let update = |entities: Vec<SceneEntity>| SceneUpdate { deletions: Vec::new(), entities };
    let max_tau = scene.max_loop_duration_s();
    let markers = SceneMarkers::new(scene);
    for (k, path) in scene.paths.iter().enumerate() {
        // The path, and its τ, as the log plays: at each step's last pose, the poses so far.
        for last in path_steps(path.positions.len()) {
            let stamp = time(k, last);
            let (positions, tau) = (&path.positions[..=last], &path.loop_duration_s[..=last]);
            let orientations = path.orientations_xyzw.as_deref().map(|q| &q[..=last]);
            let poses = poses_in_frame(frame_id, timestamp(stamp), positions, orientations);
            messages.push((stamp, channels[0], encoded(&poses)?));
            let entity = tau_entity(frame_id, timestamp(stamp), &path.name, positions, tau, max_tau);
            messages.push((stamp, channels[1], encoded(&update(vec![entity]))?));
            messages.push((stamp, markers_channel, markers.path(k, last, stamp)));
        }
    }
    for (k, c) in scene.components.iter().enumerate() {
        // When the robot comes back: the first pose of its second stretch.
        let [a, b] = c.sessions;
        let stamp = time(b, c.poses[1][0]);
        let (paths, names) = ([&scene.paths[a], &scene.paths[b]], [&scene.paths[a].name, &scene.paths[b].name]);
        let positions = paths.map(|p| p.positions.as_slice());
        let entity = component_entity(frame_id, timestamp(stamp), positions, names.map(String::as_str), c);
        messages.push((stamp, channels[2], encoded(&update(vec![entity]))?));
        messages.push((stamp, markers_channel, markers.component(k, stamp)));
    }
    for (k, c) in scene.candidates.iter().enumerate() {
        // At the later pose's time.
        let stamp = time(c.sessions[1], c.poses[1]);
        let points = vec![scene.position(c.sessions[0], c.poses[0]), scene.position(c.sessions[1], c.poses[1])];
        let entity =
            candidates_entity(frame_id, timestamp(stamp), format!("candidate/{k}"), points.clone(), Vec::new());
        messages.push((stamp, channels[3], encoded(&update(vec![entity]))?));
        messages.push((stamp, markers_channel, markers.candidate(k, points, stamp)));
    }
    // The plane sums up the whole run: from the first pose on.
    let stamp = scene.paths.iter().enumerate().map(|(k, _)| time(k, 0)).min_by_key(|t| t.ns());
    let stamp = stamp.unwrap_or(RosTime { sec: 0, nanosec: 0 });
    messages.push((stamp, channels[4], encoded(&plane_raw_image(timestamp(stamp), &scene.plane))?));

    let mut headers: Vec<(MessageHeader, &[u8])> = messages
        .iter()
        .enumerate()
        .map(|(sequence, (stamp, channel_id, data))| {
            let (channel_id, sequence) = (*channel_id, sequence as u32);
            (MessageHeader { channel_id, sequence, log_time: stamp.ns(), publish_time: stamp.ns() }, data.as_slice())
        })
        .collect();
    if let Some(log) = &log {
        headers.extend(log.messages.iter().map(|m| {
            let header = MessageHeader {
                channel_id: m.channel.id,
                sequence: m.sequence,
                log_time: m.log_time,
                publish_time: m.publish_time,
            };
            (header, &*m.data)
        }));
    }
    headers.sort_by_key(|(header, _)| header.log_time); // stable: ties keep the order above
    for (header, data) in headers {
        writer.write_to_known_channel(&header, data)?;
    }

    if let Some(log) = &log {
        for attachment in &log.attachments {
            writer.attach(attachment)?;
        }
        for metadata in &log.metadata {
            writer.write_metadata(metadata)?;
        }
    }
    let names: Vec<&str> = scene.paths.iter().map(|p| p.name.as_str()).collect();
    let metadata = BTreeMap::from([
        ("sessions".to_owned(), serde_json::to_string(&names).expect("strings")),
        ("frame_id".to_owned(), frame_id.clone()),
    ]);
    writer.write_metadata(&mcap::records::Metadata { name: "loops".to_owned(), metadata })?;
    writer.finish()?;
    writer.into_inner().flush()?;
    Ok(())
}

/// The plane image `plane` as a Foxglove `RawImage` (rgb8, frame `plane`).
pub(crate) fn plane_raw_image(timestamp: Option<Timestamp>, plane: &RgbImage) -> RawImage {
    RawImage {
        timestamp,
        frame_id: "plane".to_owned(),
        width: plane.width as u32,
        height: plane.height as u32,
        encoding: "rgb8".to_owned(),
        step: (plane.width * 3) as u32,
        data: plane.rgb.clone().into(),
    }
}

/// The (t, t′) plane image of `loops` ([`Scene::plane`]): at most [`PLANE_PIXELS`] a side,
/// each component in its colour, the pixels of `pairs` white.
///
/// # Errors
/// As [`Loops::label_image`].
pub(crate) fn loops_plane(loops: &Loops, pairs: &[[usize; 2]]) -> loops_core::Result<RgbImage> {
    plane_image(loops, &PlaneGrid::new(loops, None, PLANE_PIXELS)?, pairs)
}

/// `message` in its encoding (protobuf).
fn encoded<T: Encode>(message: &T) -> mcap::McapResult<Vec<u8>> {
    protobuf(message).map_err(mcap::McapError::Io)
}

/// `message` in protobuf.
pub(crate) fn protobuf<T: Encode>(message: &T) -> io::Result<Vec<u8>> {
    let mut data = Vec::new();
    message.encode(&mut data).map_err(|error| io::Error::other(error.to_string()))?;
    Ok(data)
}

/// The schema of a Foxglove message: its name, encoding and descriptor set.
pub(crate) fn foxglove_schema<T: Encode>() -> (String, String, Vec<u8>) {
    let schema = T::get_schema().expect("Foxglove's messages have schemas");
    (schema.name, schema.encoding, schema.data.into_owned())
}

/// The poses of a path as a `PosesInFrame` (identity orientations without `orientations_xyzw`).
pub(crate) fn poses_in_frame(
    frame_id: &str,
    timestamp: Option<Timestamp>,
    positions: &[[f64; 3]],
    orientations_xyzw: Option<&[[f64; 4]]>,
) -> PosesInFrame {
    let poses = positions
        .iter()
        .enumerate()
        .map(|(k, &position)| {
            let [x, y, z, w] = orientations_xyzw.map_or(IDENTITY_XYZW, |q| q[k]);
            Pose { position: Some(vector(position)), orientation: Some(Quaternion { x, y, z, w }) }
        })
        .collect();
    PosesInFrame { timestamp, frame_id: frame_id.to_owned(), poses }
}

/// An entity `id` of `lines`, with `metadata`.
pub(crate) fn entity(
    frame_id: &str,
    timestamp: Option<Timestamp>,
    id: String,
    lines: Vec<LinePrimitive>,
    metadata: Vec<(&str, String)>,
) -> SceneEntity {
    SceneEntity {
        timestamp,
        frame_id: frame_id.to_owned(),
        id,
        lines,
        metadata: metadata.into_iter().map(|(key, value)| KeyValuePair { key: key.to_owned(), value }).collect(),
        ..SceneEntity::default()
    }
}

/// The entity `tau/<name>`: the path through `positions` coloured by τ ([`tau_rgba`]).
pub(crate) fn tau_entity(
    frame_id: &str,
    timestamp: Option<Timestamp>,
    name: &str,
    positions: &[[f64; 3]],
    loop_duration_s: &[f64],
    max_loop_duration_s: f64,
) -> SceneEntity {
    let colors = loop_duration_s.iter().map(|&t| color(tau_rgba(t, max_loop_duration_s))).collect();
    let mut strip = line(line_primitive::Type::LineStrip, positions.to_vec(), None, PATH_WIDTH);
    strip.colors = colors;
    let metadata = vec![("max_loop_duration_s", max_loop_duration_s.to_string())];
    entity(frame_id, timestamp, format!("tau/{name}"), vec![strip], metadata)
}

/// The entity `component/<id>` of `c`: its two stretches of path and its closest pair, in its
/// colour, with `components.csv`'s values as metadata. `positions` and `names` are the paths
/// and names of its two sessions (`c.sessions`).
pub(crate) fn component_entity(
    frame_id: &str,
    timestamp: Option<Timestamp>,
    positions: [&[[f64; 3]]; 2],
    names: [&str; 2],
    c: &SceneComponent,
) -> SceneEntity {
    let rgba = Some(c.rgba());
    let [[i0, i1], [j0, j1]] = c.poses;
    let closest = vec![positions[0][c.closest_pair[0]], positions[1][c.closest_pair[1]]];
    let lines = vec![
        line(line_primitive::Type::LineStrip, positions[0][i0..=i1].to_vec(), rgba, COMPONENT_WIDTH),
        line(line_primitive::Type::LineStrip, positions[1][j0..=j1].to_vec(), rgba, COMPONENT_WIDTH),
        line(line_primitive::Type::LineList, closest, rgba, COMPONENT_WIDTH),
    ];
    entity(frame_id, timestamp, format!("component/{}", c.id), lines, component_metadata(names, c))
}

/// The entity `id`: a line per pair of `points` (two a pair), in the candidates' colour.
pub(crate) fn candidates_entity(
    frame_id: &str,
    timestamp: Option<Timestamp>,
    id: String,
    points: Vec<[f64; 3]>,
    metadata: Vec<(&str, String)>,
) -> SceneEntity {
    let lines = vec![line(line_primitive::Type::LineList, points, Some(CANDIDATE_RGBA), CANDIDATE_WIDTH)];
    entity(frame_id, timestamp, id, lines, metadata)
}

/// The metadata of a component entity: `components.csv`'s columns, numbers as they print there.
fn component_metadata(names: [&str; 2], c: &SceneComponent) -> Vec<(&'static str, String)> {
    let [[i_min, i_max], [j_min, j_max]] = c.poses;
    vec![
        ("id", c.id.to_string()),
        ("trivial", c.trivial.to_string()),
        ("session_a", c.sessions[0].to_string()),
        ("session_b", c.sessions[1].to_string()),
        ("name_a", names[0].to_owned()),
        ("name_b", names[1].to_owned()),
        ("area_s2", c.area_s2.to_string()),
        ("pair_count", c.pair_count.to_string()),
        ("i_min", i_min.to_string()),
        ("i_max", i_max.to_string()),
        ("j_min", j_min.to_string()),
        ("j_max", j_max.to_string()),
        ("closest_i", c.closest_pair[0].to_string()),
        ("closest_j", c.closest_pair[1].to_string()),
        ("closest_distance", c.closest_distance.to_string()),
    ]
}

fn vector([x, y, z]: [f64; 3]) -> Vector3 {
    Vector3 { x, y, z }
}

fn color([r, g, b, a]: [f64; 4]) -> Color {
    Color { r, g, b, a }
}

/// A line primitive through `points` of `kind`, `width` wide, in `rgba` (or per point).
fn line(kind: line_primitive::Type, points: Vec<[f64; 3]>, rgba: Option<[f64; 4]>, width: f64) -> LinePrimitive {
    LinePrimitive {
        r#type: kind as i32,
        pose: Some(Pose {
            position: Some(vector([0.0; 3])),
            orientation: Some(Quaternion { w: 1.0, ..Default::default() }),
        }),
        thickness: width,
        scale_invariant: false,
        points: points.into_iter().map(|[x, y, z]| Point3 { x, y, z }).collect(),
        color: rgba.map(color),
        colors: Vec::new(),
        indices: Vec::new(),
    }
}

/// `visualization_msgs/msg/MarkerArray` (ROS 2 Humble and later, with textures and mesh
/// files), with the definitions it uses.
pub(crate) const MARKER_ARRAY_SCHEMA: &str = "visualization_msgs/Marker[] markers\n\
================================================================================\n\
MSG: visualization_msgs/Marker\n\
int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n\
int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\n\
int32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n\
std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n\
geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\nbool frame_locked\n\
geometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring texture_resource\n\
sensor_msgs/CompressedImage texture\nUVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
MeshFile mesh_file\nbool mesh_use_embedded_materials\n\
================================================================================\n\
MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\n\
MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n\
================================================================================\n\
MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n\
================================================================================\n\
MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n\
================================================================================\n\
MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n\
================================================================================\n\
MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n\
================================================================================\n\
MSG: std_msgs/ColorRGBA\nfloat32 r\nfloat32 g\nfloat32 b\nfloat32 a\n\
================================================================================\n\
MSG: builtin_interfaces/Duration\nint32 sec\nuint32 nanosec\n\
================================================================================\n\
MSG: sensor_msgs/CompressedImage\nstd_msgs/Header header\nstring format\nuint8[] data\n\
================================================================================\n\
MSG: visualization_msgs/UVCoordinate\nfloat32 u\nfloat32 v\n\
================================================================================\n\
MSG: visualization_msgs/MeshFile\nstring filename\nuint8[] data\n";

/// `visualization_msgs/msg/Marker`'s LINE_STRIP and LINE_LIST.
const LINE_STRIP: i32 = 4;
const LINE_LIST: i32 = 5;

/// `visualization_msgs/msg/Marker`'s actions ADD and DELETE.
const ADD: i32 = 0;
const DELETE: i32 = 2;

/// One marker of the array: a line of `kind` through `points`, in `rgba` or per point `colors`
/// (`action` [`DELETE`]: the marker `ns`/`id` removed, its other fields unused).
pub(crate) struct Marker<'a> {
    ns: &'a str,
    id: i32,
    kind: i32,
    action: i32,
    width: f64,
    rgba: [f64; 4],
    points: Vec<[f64; 3]>,
    colors: &'a [[f64; 4]],
}

/// The markers of a path (id `id`: its session) through `points`: namespace `trajectory`,
/// white, and `tau`, a colour per pose (`tau_colors`, [`tau_rgba`]).
pub(crate) fn path_markers<'a>(id: usize, points: &[[f64; 3]], tau_colors: &'a [[f64; 4]]) -> [Marker<'a>; 2] {
    let (id, width, rgba) = (id as i32, PATH_WIDTH, [1.0; 4]);
    let line =
        |ns, colors| Marker { ns, id, kind: LINE_STRIP, action: ADD, width, rgba, points: points.to_vec(), colors };
    [line("trajectory", &[]), line("tau", tau_colors)]
}

/// The markers of component `c` (namespace `components`, ids 3 · id, 3 · id + 1: its two
/// stretches; 3 · id + 2: its closest pair), in its colour; `positions` are the paths of its
/// two sessions (`c.sessions`). Ids past `i32::MAX` wrap (no scene has that many components).
pub(crate) fn component_markers(c: &SceneComponent, positions: [&[[f64; 3]]; 2]) -> [Marker<'static>; 3] {
    let [[i0, i1], [j0, j1]] = c.poses;
    let lines = [
        positions[0][i0..=i1].to_vec(),
        positions[1][j0..=j1].to_vec(),
        vec![positions[0][c.closest_pair[0]], positions[1][c.closest_pair[1]]],
    ];
    let mut part = 0;
    lines.map(|points| {
        let kind = if part == 2 { LINE_LIST } else { LINE_STRIP };
        let id = (3 * c.id + part) as i32;
        part += 1;
        Marker { ns: "components", id, kind, action: ADD, width: COMPONENT_WIDTH, rgba: c.rgba(), points, colors: &[] }
    })
}

/// The deletions of component `id`'s markers ([`component_markers`]): merged into another.
pub(crate) fn component_deletions(id: usize) -> [Marker<'static>; 3] {
    [0, 1, 2].map(|part| Marker {
        ns: "components",
        id: (3 * id + part) as i32,
        kind: LINE_STRIP,
        action: DELETE,
        width: 0.0,
        rgba: [0.0; 4],
        points: Vec::new(),
        colors: &[],
    })
}

/// The marker `id` of namespace `candidates`: a line per pair of `points` (two a pair), in the
/// candidates' colour.
pub(crate) fn candidate_marker(id: usize, points: Vec<[f64; 3]>) -> Marker<'static> {
    let (width, rgba) = (CANDIDATE_WIDTH, CANDIDATE_RGBA);
    Marker { ns: "candidates", id: id as i32, kind: LINE_LIST, action: ADD, width, rgba, points, colors: &[] }
}

/// The scene's markers for RViz, one `MarkerArray` (CDR) a message: namespaces `trajectory`
/// and `tau` (id = session, [`path_markers`]), `components` ([`component_markers`]) and
/// `candidates` (id k: pair k, [`candidate_marker`]).
struct SceneMarkers<'a> {
    scene: &'a Scene,
    tau_colors: Vec<Vec<[f64; 4]>>,
}

impl<'a> SceneMarkers<'a> {
    fn new(scene: &'a Scene) -> Self {
        let max_tau = scene.max_loop_duration_s();
        let tau_colors =
            scene.paths.iter().map(|p| p.loop_duration_s.iter().map(|&t| tau_rgba(t, max_tau)).collect()).collect();
        Self { scene, tau_colors }
    }

    /// Session `k`'s path up to pose `last`, white and coloured by τ.
    fn path(&self, k: usize, last: usize, stamp: RosTime) -> Vec<u8> {
        let markers = path_markers(k, &self.scene.paths[k].positions[..=last], &self.tau_colors[k][..=last]);
        marker_array(&self.scene.frame_id, stamp, &markers)
    }

    /// Component `k`'s two stretches and its closest pair.
    fn component(&self, k: usize, stamp: RosTime) -> Vec<u8> {
        let (scene, c) = (self.scene, &self.scene.components[k]);
        let positions = c.sessions.map(|a| scene.paths[a].positions.as_slice());
        marker_array(&scene.frame_id, stamp, &component_markers(c, positions))
    }

    /// Candidate `k`: the line between its two poses.
    fn candidate(&self, k: usize, points: Vec<[f64; 3]>, stamp: RosTime) -> Vec<u8> {
        marker_array(&self.scene.frame_id, stamp, &[candidate_marker(k, points)])
    }
}

/// `markers` as a `MarkerArray` in CDR, each stamped `stamp` in `frame_id`.
pub(crate) fn marker_array(frame_id: &str, stamp: RosTime, markers: &[Marker<'_>]) -> Vec<u8> {
    let mut data = Vec::new();
    let mut cdr = CdrWriter::new(&mut data);
    cdr.u32(markers.len() as u32);
    for marker in markers {
        cdr.i32(stamp.sec);
        cdr.u32(stamp.nanosec);
        cdr.string(frame_id);
        cdr.string(marker.ns);
        cdr.i32(marker.id);
        cdr.i32(marker.kind);
        cdr.i32(marker.action);
        cdr.f64s(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]); // pose
        cdr.f64s(&[marker.width, 0.0, 0.0]); // scale: x is the line width
        cdr.f32s(&marker.rgba.map(|v| v as f32));
        cdr.i32(0); // lifetime: forever
        cdr.u32(0);
        cdr.bool(false); // frame_locked
        cdr.u32(marker.points.len() as u32);
        for point in &marker.points {
            cdr.f64s(point);
        }
        cdr.u32(marker.colors.len() as u32);
        for rgba in marker.colors {
            cdr.f32s(&rgba.map(|v| v as f32));
        }
        cdr.string(""); // texture_resource
        cdr.i32(0); // texture: an empty sensor_msgs/CompressedImage
        cdr.u32(0);
        cdr.string("");
        cdr.string(""); // its format
        cdr.u32(0); // its data
        cdr.u32(0); // uv_coordinates
        cdr.string(""); // text
        cdr.string(""); // mesh_resource
        cdr.string(""); // mesh_file: no file name
        cdr.u32(0); // and no data
        cdr.bool(false); // mesh_use_embedded_materials
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_steps_grow_to_the_whole_path_within_their_bound() {
        for n in [1, 2, 99, 100, 101, 1000, 1999, 2000, 2001, 4541, 72_000, 399_999, 400_001, 3_000_000] {
            let steps = path_steps(n);
            assert!(!steps.is_empty() && steps.len() <= PATH_STEPS, "{n}: {} steps", steps.len());
            assert_eq!(*steps.last().unwrap(), n - 1, "{n}: the last step holds the whole path");
            // One step every `stride` poses, the last at the path's end.
            let stride = steps[0] + 1;
            assert!(steps[..steps.len() - 1].iter().enumerate().all(|(m, &last)| last + 1 == (m + 1) * stride));
            assert!(n - 1 - steps[steps.len().saturating_sub(2)] <= stride || steps.len() == 1, "{n}");
            let held: usize = steps.iter().map(|&last| last + 1).sum();
            assert!(held <= PATH_STEP_POSES + n + PATH_STEPS * PATH_STEPS, "{n}: {held} poses");
        }
        assert!(path_steps(0).is_empty());
        assert_eq!(path_steps(4541).len(), PATH_STEPS.min(2 * PATH_STEP_POSES / 4541)); // KITTI 00
    }

    /// A small scene: a square driven twice, its loops and four samples.
    fn square() -> Scene {
        use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, find_loops, sample_loops};
        let corners = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let points: Vec<[f64; 2]> = (0..8).map(|i| corners[i % 4]).collect();
        let traj = Trajectory::from_points((0..8).map(|k| 1.7e9 + f64::from(k)).collect(), &points).unwrap();
        let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
        let sampler = Sampler::new(SamplerKind::One, SampleSize::Budget(4), 7);
        let samples = sample_loops(&traj, &Euclidean, &loops, &sampler).unwrap();
        Scene::of_trajectory("square", &traj, None, None, &loops, &samples).unwrap()
    }

    #[test]
    fn a_merged_log_keeps_its_records_and_is_never_written_onto() {
        let dir = std::env::temp_dir().join(format!("loops-io-merge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (log, merged) = (dir.join("log.mcap"), dir.join("merged.mcap"));
        let scene = square();
        write_scene_mcap(&log, &scene, false).unwrap();
        let before = std::fs::read(&log).unwrap();
        // Onto the log itself: refused, whatever `overwrite` says; the log is untouched.
        for overwrite in [false, true] {
            let error = write_scene_mcap_merged(&log, &scene, &log, overwrite).unwrap_err();
            assert!(error.to_string().contains("log.mcap"), "{error}");
        }
        assert_eq!(std::fs::read(&log).unwrap(), before);
        // Merged: the log's channels under their ids, with every message; the scene's too.
        write_scene_mcap_merged(&merged, &scene, &log, false).unwrap();
        let bytes = std::fs::read(&merged).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let original = mcap::Summary::read(&before).unwrap().unwrap();
        for (id, channel) in &original.channels {
            assert_eq!(summary.channels[id].topic, channel.topic);
        }
        let count = |b: &[u8]| mcap::MessageStream::new(b).unwrap().count();
        assert_eq!(count(&bytes), 2 * count(&before), "the log's messages and the scene's, equal here");
        // A log that is not MCAP: a one-line error naming it, and no file.
        let bad = dir.join("bad.mcap");
        std::fs::write(&bad, b"not an mcap file").unwrap();
        let error = write_scene_mcap_merged(dir.join("none.mcap"), &scene, &bad, false).unwrap_err();
        assert!(error.to_string().contains("bad.mcap") && !dir.join("none.mcap").exists(), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_layout_names_every_foxglove_topic() {
        let layout: serde_json::Value = serde_json::from_str(FOXGLOVE_LAYOUT).unwrap();
        let text = layout.to_string();
        for topic in &SCENE_TOPICS[..5] {
            assert!(text.contains(topic.topic), "{}", topic.topic);
        }
    }

    #[test]
    fn tau_runs_from_blue_to_red() {
        assert_eq!(tau_rgba(0.0, 4.0), [0.0, 0.3, 1.0, 1.0]);
        assert_eq!(tau_rgba(4.0, 4.0), [1.0, 0.3, 0.0, 1.0]);
    }
}

//! Pose graphs in g2o and TORO text: vertices (the poses) and edges (the constraints between
//! them, among which the loop closures).

mod chain;

use std::collections::HashMap;
use std::io::BufRead;
use std::path::Path;

pub use chain::EdgeChain;
use chain::{chain_odometry, no_vertices};

use crate::error::{IoError, Result};
use crate::printable::printable;
use crate::rotation::{quaternion_from_roll_pitch_yaw, quaternion_from_yaw, yaw_of};
use crate::table::PoseTable;
use crate::text::{self, Lines, Takes};
use crate::timing::Timing;

/// A pose graph: its pose vertices as a table, and its edges between them.
///
/// It serialises with serde (the Python bindings pickle it); one read back, or built by hand,
/// is not checked: its fields are public.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoseGraph {
    /// The pose vertices, sorted by id: positions, orientations, the line of each, and times
    /// from the ids (see [`read_pose_graph`]).
    pub vertices: PoseTable,
    /// The id of each vertex, one per row of `vertices`, increasing.
    pub vertex_ids: Vec<u64>,
    /// The edges between pose vertices, in file order.
    pub edges: Vec<GraphEdge>,
    /// For a file without vertices read with `chain_edges`
    /// ([`read_pose_graph_with`](crate::read_pose_graph_with)): how its vertices were chained
    /// from its odometry edges (dead reckoning). `None` when the file gave its vertices.
    pub chain: Option<EdgeChain>,
    /// The lines of other record types the file held (landmarks, `FIX`, `EQUIV`, GTSAM's `BR`
    /// bearing-range measurements, ...), which were not read: what a caller says it left out.
    /// `None` when every line was a pose vertex or an edge between them.
    #[serde(default)]
    pub skipped: Option<SkippedRecords>,
}

/// The lines of a pose graph file that were skipped, by tag in order of first appearance:
/// displays as one sentence, `w10000.graph: skipped 5875 EQUIV lines (first on line 10001): only
/// pose vertices and the edges between them are read`.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct SkippedRecords {
    /// The file.
    pub path: std::path::PathBuf,
    /// `(tag, lines, first line)` per tag skipped.
    pub tags: Vec<(String, usize, usize)>,
}

impl SkippedRecords {
    /// Counts a skipped line of `tag` at `line`.
    fn add(&mut self, tag: &str, line: usize) {
        match self.tags.iter_mut().find(|(known, _, _)| known == tag) {
            Some((_, count, _)) => *count += 1,
            None => self.tags.push((tag.to_owned(), 1, line)),
        }
    }
}

impl std::fmt::Display for SkippedRecords {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self
            .tags
            .iter()
            .map(|(tag, count, first)| {
                format!("{count} {} line{} (first on line {first})", printable(tag), if *count == 1 { "" } else { "s" })
            })
            .collect();
        write!(
            f,
            "{}: skipped {}: only pose vertices and the edges between them are read",
            self.path.display(),
            parts.join(", ")
        )
    }
}

/// An edge of a [`PoseGraph`]: a measured relative pose from vertex `from` to vertex `to`, and
/// how much it is trusted (its information matrix).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GraphEdge {
    /// The id of the first vertex.
    pub from: u64,
    /// The id of the second vertex.
    pub to: u64,
    /// The 1-based line of the edge in the file.
    pub line: usize,
    /// The measured pose of vertex `to` in the frame of vertex `from`.
    pub measurement: RelativePose,
    /// The upper triangle of the information matrix, row by row, in g2o's order: 6 values for a
    /// 2-D edge (rows and columns x, y, θ: `xx xy xθ yy yθ θθ`), 21 for a 3-D one (x, y, z and
    /// the rotation: qx, qy, qz for `EDGE_SE3:QUAT`, roll, pitch, yaw for `EDGE3`). TORO's
    /// `EDGE2` lines write theirs as `xx xy yy θθ xθ yθ`; they are reordered. Empty when the
    /// line ends after the measurement.
    pub information: Vec<f64>,
}

/// The measurement of a [`GraphEdge`]: the pose of its second vertex in the frame of its first.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum RelativePose {
    /// A 2-D edge (`EDGE_SE2`, `EDGE2`): `dx dy dθ` as written, metres and radians.
    Se2 {
        /// `[dx, dy]`.
        translation: [f64; 2],
        /// `dθ`, radians, as written (not wrapped).
        rotation_rad: f64,
    },
    /// A 3-D edge (`EDGE_SE3:QUAT`, `EDGE3`): translation and rotation.
    Se3 {
        /// `[x, y, z]`.
        translation: [f64; 3],
        /// The rotation as a quaternion `[qx, qy, qz, qw]`: as written for `EDGE_SE3:QUAT` (not
        /// normalised), from roll, pitch and yaw (`R = Rz(yaw) Ry(pitch) Rx(roll)`) for `EDGE3`.
        rotation_xyzw: [f64; 4],
    },
}

impl GraphEdge {
    /// The edge of a line tagged `tag` (`word` as written): its ids, the numbers after them
    /// (`values`) and the information matrix (`information`: its upper triangle, or none; from
    /// column `column + 1`).
    fn read(
        tag: Tag,
        word: &str,
        ids: [u64; 2],
        values: &[f64; 7],
        information: &[&str],
        column: usize,
        line: usize,
    ) -> std::result::Result<Self, String> {
        let v = values;
        let measurement = match tag {
            Tag::Edge2 => RelativePose::Se2 { translation: [v[0], v[1]], rotation_rad: v[2] },
            Tag::Edge3Quat => {
                RelativePose::Se3 { translation: [v[0], v[1], v[2]], rotation_xyzw: [v[3], v[4], v[5], v[6]] }
            }
            Tag::Edge3Euler => {
                let rotation_xyzw = quaternion_from_roll_pitch_yaw(v[3], v[4], v[5]);
                RelativePose::Se3 { translation: [v[0], v[1], v[2]], rotation_xyzw }
            }
            Tag::Vertex2 | Tag::Vertex3Quat | Tag::Vertex3Euler => unreachable!("a vertex is not an edge"),
        };
        let mut entries = Vec::with_capacity(information.len());
        for (k, field) in information.iter().enumerate() {
            entries.push(text::parse_finite(field, column + 1 + k)?);
        }
        if word == "EDGE2" && !entries.is_empty() {
            // TORO: xx xy yy θθ xθ yθ.
            let t = &entries;
            entries = vec![t[0], t[1], t[4], t[2], t[5], t[3]];
        }
        Ok(Self { from: ids[0], to: ids[1], line, measurement, information: entries })
    }

    /// Whether the edge joins vertices more than one id apart: a loop closure in graphs whose
    /// odometry edges join consecutive ids (all the classic data sets).
    pub fn is_loop_closure(&self) -> bool {
        self.from.abs_diff(self.to) > 1
    }
}

impl PoseGraph {
    /// The edges joining vertices more than one id apart ([`GraphEdge::is_loop_closure`]).
    pub fn loop_closures(&self) -> impl Iterator<Item = &GraphEdge> {
        self.edges.iter().filter(|edge| edge.is_loop_closure())
    }

    /// The row of `vertices` holding vertex `id`, if there is one. Time O(log n).
    pub fn vertex_index(&self, id: u64) -> Option<usize> {
        self.vertex_ids.binary_search(&id).ok()
    }

    /// The rows of `vertices` (pose indices of the trajectory) that `edge` joins: `[from, to]`,
    /// in the edge's order. Every edge of a graph read from a file has both (an edge to a
    /// missing vertex is an error); `None` for an edge of another graph. Time O(log n).
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-rows.g2o", std::process::id()));
    /// std::fs::write(&path, "VERTEX_SE2 10 0 0 0\nVERTEX_SE2 20 1 0 0\nEDGE_SE2 20 10 -1 0 0\n")?;
    /// let graph = loops_io::read_pose_graph(&path, &Default::default())?;
    /// assert_eq!(graph.edge_rows(&graph.edges[0]), Some([1, 0]));
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn edge_rows(&self, edge: &GraphEdge) -> Option<[usize; 2]> {
        Some([self.vertex_index(edge.from)?, self.vertex_index(edge.to)?])
    }

    /// For a 2-D graph, the heading θ of each vertex (radians in (−π, π], as the rotation about
    /// z its orientation holds: the file's θ, wrapped); `None` for a 3-D graph.
    pub fn headings_rad(&self) -> Option<Vec<f64>> {
        let orientations = self.vertices.orientations_xyzw.as_ref()?;
        (self.vertices.dim == 2).then(|| orientations.iter().map(|&q| yaw_of(q)).collect())
    }
}

/// What a line tag is: its dimension, and the numbers after the ids it needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tag {
    /// `VERTEX_SE2 id x y θ`, `VERTEX2 id x y θ`.
    Vertex2,
    /// `VERTEX_SE3:QUAT id x y z qx qy qz qw`.
    Vertex3Quat,
    /// `VERTEX3 id x y z roll pitch yaw` (TORO 3-D).
    Vertex3Euler,
    /// `EDGE_SE2 i j dx dy dθ ...`, `EDGE2 i j dx dy dθ ...`.
    Edge2,
    /// `EDGE_SE3:QUAT i j x y z qx qy qz qw ...`.
    Edge3Quat,
    /// `EDGE3 i j x y z roll pitch yaw ...`.
    Edge3Euler,
}

impl Tag {
    fn of(word: &str) -> Option<Self> {
        match word {
            "VERTEX_SE2" | "VERTEX2" => Some(Self::Vertex2),
            "VERTEX_SE3:QUAT" => Some(Self::Vertex3Quat),
            "VERTEX3" => Some(Self::Vertex3Euler),
            "EDGE_SE2" | "EDGE2" => Some(Self::Edge2),
            "EDGE_SE3:QUAT" => Some(Self::Edge3Quat),
            "EDGE3" => Some(Self::Edge3Euler),
            _ => None,
        }
    }

    /// (ids, numbers after them, entries of the information matrix an edge may end with,
    /// dimension, what a line looks like).
    fn layout(self) -> (usize, usize, usize, usize, &'static str) {
        match self {
            Self::Vertex2 => (1, 3, 0, 2, "id x y theta"),
            Self::Vertex3Quat => (1, 7, 0, 3, "id x y z qx qy qz qw"),
            Self::Vertex3Euler => (1, 6, 0, 3, "id x y z roll pitch yaw"),
            Self::Edge2 => (2, 3, 6, 2, "i j dx dy dtheta, then the information matrix's 6 entries or none"),
            Self::Edge3Quat => (2, 7, 21, 3, "i j x y z qx qy qz qw, then the information matrix's 21 entries or none"),
            Self::Edge3Euler => {
                (2, 6, 21, 3, "i j x y z roll pitch yaw, then the information matrix's 21 entries or none")
            }
        }
    }
}

/// The tags of the g2o and TORO formats that are not pose vertices or edges between them, and
/// are skipped: every type g2o registers (landmarks, parameters, calibration, projections),
/// g2o's `FIX` command, TORO's `EQUIV`, and the switchable and max-mixture constraints of
/// Vertigo (robust back ends' data sets). Any other tag is an error: a misspelled vertex would
/// otherwise vanish without a word.
const OTHER_TAGS: &[&str] = &[
    "FIX",
    "EQUIV",
    "BR",
    "LANDMARK",
    "LANDMARK2",
    "LANDMARK3",
    "CACHE_CAMERA",
    "CACHE_SE2_OFFSET",
    "CACHE_SE3_OFFSET",
    "EDGE_BEARING_SE2_XY",
    "EDGE_CAM",
    "EDGE_LINE2D",
    "EDGE_LINE2D_POINTXY",
    "EDGE_PLANE",
    "EDGE_POINTXY",
    "EDGE_POINTXYZ",
    "EDGE_POINTXYZ_PRIOR",
    "EDGE_PRIOR_SE2",
    "EDGE_PRIOR_SE2_XY",
    "EDGE_PRIOR_XY",
    "EDGE_PROJECT_DEPTH",
    "EDGE_PROJECT_DISPARITY",
    "EDGE_PROJECT_INVERSE_SIM3_XYZ:EXPMAP",
    "EDGE_PROJECT_P2MC",
    "EDGE_PROJECT_P2SC",
    "EDGE_PROJECT_SIM3_XYZ:EXPMAP",
    "EDGE_PROJECT_XYZ2UV:EXPMAP",
    "EDGE_PROJECT_XYZ2UVU:EXPMAP",
    "EDGE_SCALE",
    "EDGE_SE2_CALIB",
    "EDGE_SE2_LINE2D",
    "EDGE_SE2_LOTSOFXY",
    "EDGE_SE2_ODOM_DIFFERENTIAL_CALIB",
    "EDGE_SE2_OFFSET",
    "EDGE_SE2_POINTXY_OFFSET",
    "EDGE_SE2_SEGMENT2D",
    "EDGE_SE2_SEGMENT2D_LINE",
    "EDGE_SE2_SEGMENT2D_POINTLINE",
    "EDGE_SE2_TWOPOINTSXY",
    "EDGE_SE2_XY",
    "EDGE_SE2_XY_CALIB",
    "EDGE_SE3:EXPMAP",
    "EDGE_SE3_CALIB",
    "EDGE_SE3_LINE3D",
    "EDGE_SE3_LOTSOF_XYZ",
    "EDGE_SE3_OFFSET",
    "EDGE_SE3_PLANE_CALIB",
    "EDGE_SE3_PRIOR",
    "EDGE_SE3_PROJECT_XYZ:EXPMAP",
    "EDGE_SE3_PROJECT_XYZONLYPOSE:EXPMAP",
    "EDGE_SE3_TRACKXYZ",
    "EDGE_SE3_XYZ_PRIOR",
    "EDGE_SIM3:EXPMAP",
    "EDGE_STEREO_SE3_PROJECT_XYZ:EXPMAP",
    "EDGE_STEREO_SE3_PROJECT_XYZONLYPOSE:EXPMAP",
    "EDGE_V_V_GICP",
    "PARAMS_CAMERACALIB",
    "PARAMS_CAMERAPARAMETERS",
    "PARAMS_SE2OFFSET",
    "PARAMS_SE3OFFSET",
    "PARAMS_STEREOCAMERACALIB",
    "ROBOTLASER1",
    "VERTEX_CAM",
    "VERTEX_ELLIPSE",
    "VERTEX_INTRINSICS",
    "VERTEX_LINE2D",
    "VERTEX_LINE3D",
    "VERTEX_ODOM_DIFFERENTIAL",
    "VERTEX_PLANE",
    "VERTEX_SE3:EXPMAP",
    "VERTEX_SEGMENT2D",
    "VERTEX_SIM3:EXPMAP",
    "VERTEX_TAG",
    "VERTEX_TRACKXYZ",
    "VERTEX_XY",
    "VERTEX_SWITCH",
    "EDGE_SWITCH_PRIOR",
    "EDGE_SE2_SWITCHABLE",
    "EDGE_SE3_SWITCHABLE",
    "EDGE_SE2_MAXMIX",
    "EDGE_SE3_MAXMIX",
];

/// The message for a line whose first word is no tag of the formats.
fn unknown_tag(word: &str) -> String {
    const SHOWN_CHARS: usize = 40;
    let shown: String = word.chars().take(SHOWN_CHARS).collect();
    let cut = if word.chars().count() > SHOWN_CHARS { "…" } else { "" };
    format!(
        "unknown tag {shown:?}{cut}: expected a g2o or TORO record (VERTEX_SE2, VERTEX2, VERTEX_SE3:QUAT, VERTEX3, \
         EDGE_SE2, EDGE2, EDGE_SE3:QUAT, EDGE3, or another type of g2o, such as FIX, VERTEX_XY, EDGE_SE2_XY, which are \
         skipped)"
    )
}

/// Reads a pose graph in g2o or TORO text: `VERTEX_SE2 id x y θ` / `VERTEX2`,
/// `VERTEX_SE3:QUAT id x y z qx qy qz qw`, `VERTEX3 id x y z roll pitch yaw`, and the edges
/// `EDGE_SE2 i j ...` / `EDGE2`, `EDGE_SE3:QUAT i j ...`, `EDGE3 i j ...`: the measurement
/// ([`GraphEdge::measurement`]), then the upper triangle of the information matrix or nothing
/// ([`GraphEdge::information`]).
///
/// Vertices are sorted by id; each vertex's time is its id in seconds, or `id / rate` or a times
/// file by `timing` ([`Timing`]; a times file gives one time per vertex in id order). 2-D
/// graphs give a 2-D table with headings as rotations about z; 3-D ones a 3-D table. Lines of
/// the other types g2o defines (landmarks `VERTEX_XY`, `EDGE_SE2_XY`, `FIX`, parameters, ...),
/// TORO's `EQUIV`, GTSAM's landmarks and bearing-range measurements (`LANDMARK2`, `BR`) and
/// Vertigo's switchable constraints are skipped, counted in [`PoseGraph::skipped`] for the
/// caller to say so, as are blank lines and `#` comments; a line of any other tag (a misspelled `VERTX2`) is an error. The vertex values of the classic data sets are odometry
/// guesses, not ground truth; their edges with `|i − j| > 1` are the loop closures
/// ([`PoseGraph::loop_closures`]).
///
/// Time O(file size + n log n).
///
/// # Errors
/// - [`IoError::Open`] when a file cannot be read;
/// - [`IoError::Parse`] for a line whose tag is none of the formats' (naming it), a vertex or
///   edge line with another count of columns than its record takes (naming the first column
///   past the record: two records on one line are not read as one), an id that is not a
///   non-negative integer, a field that is not a finite number, 2-D and 3-D poses in one
///   file, an id given twice, or an edge to a vertex the file does not have, naming the line;
/// - [`IoError::PoseGraph`] for a file of edges without vertices, saying that
///   [`read_pose_graph_with`](crate::read_pose_graph_with) with `chain_edges` chains them;
/// - [`IoError::Empty`] without vertices or edges;
/// - as [`Timing`] for a bad rate or times file.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}.g2o", std::process::id()));
/// let text = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 1 1 1.57\n\
///             EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 0 1 1.57 1 0 0 1 0 1\nEDGE_SE2 2 0 -1 1 -1.57 1 0 0 1 0 1\n";
/// std::fs::write(&path, text)?;
/// let graph = loops_io::read_pose_graph(&path, &loops_io::Timing::RateHz(2.0))?;
/// assert_eq!(graph.vertices.timestamps_s, [0.0, 0.5, 1.0]);
/// assert_eq!(graph.loop_closures().map(|e| (e.from, e.to)).collect::<Vec<_>>(), [(2, 0)]);
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_pose_graph(path: impl AsRef<Path>, timing: &Timing) -> Result<PoseGraph> {
    let path = path.as_ref();
    parse_pose_graph(path, &mut text::open_lines(path)?, timing, false)
}

/// One vertex as read.
#[derive(Debug, Clone, Copy)]
struct Vertex {
    id: u64,
    position: [f64; 3],
    orientation: [f64; 4],
    line: usize,
}

/// The pose graph in `lines`, the data lines of `path`; a file without vertices is chained
/// from its odometry edges when `chain_edges` ([`chain_odometry`]).
pub(crate) fn parse_pose_graph(
    path: &Path,
    lines: &mut Lines<impl BufRead>,
    timing: &Timing,
    chain_edges: bool,
) -> Result<PoseGraph> {
    let mut vertices = Vec::new();
    let mut edges = Vec::new();
    let mut dim: Option<(usize, usize)> = None;
    let mut skipped = SkippedRecords { path: path.to_path_buf(), tags: Vec::new() };
    while let Some((line, content)) = lines.next_data()? {
        let parse_error = |message: String| IoError::parse(path, line, message);
        let word = content.split_ascii_whitespace().next().unwrap_or_default();
        let Some(tag) = Tag::of(word) else {
            if OTHER_TAGS.contains(&word) {
                let is_tag = |field: &str| Tag::of(field).is_some() || OTHER_TAGS.contains(&field);
                text::check_one_record(content.split_ascii_whitespace(), is_tag).map_err(parse_error)?;
                skipped.add(word, line);
                continue;
            }
            return Err(parse_error(unknown_tag(word)));
        };
        let (id_count, value_count, information_count, tag_dim, layout) = tag.layout();
        let needed = 1 + id_count + value_count;
        let takes = if information_count == 0 {
            Takes::Exactly(needed)
        } else {
            Takes::Either(needed, needed + information_count)
        };
        let fields = text::record(content.split_ascii_whitespace(), takes, || format!(" ({word} {layout})"))
            .map_err(parse_error)?;
        let mut ids = [0u64; 2];
        for (k, field) in fields[1..=id_count].iter().enumerate() {
            ids[k] = field.parse().map_err(|_| {
                parse_error(format!("column {} ({field:?}) is not a vertex id (a non-negative integer)", k + 2))
            })?;
        }
        let mut values = [0.0; 7];
        for (k, field) in fields[1 + id_count..needed].iter().enumerate() {
            values[k] = text::parse_finite(field, 2 + id_count + k).map_err(parse_error)?;
        }
        match dim {
            Some((first, first_line)) if first != tag_dim => {
                return Err(parse_error(format!(
                    "a {tag_dim}-D pose in a file of {first}-D poses (line {first_line}): one graph has one dimension"
                )));
            }
            Some(_) => {}
            None => dim = Some((tag_dim, line)),
        }
        match tag {
            Tag::Edge2 | Tag::Edge3Quat | Tag::Edge3Euler => {
                let edge = GraphEdge::read(tag, word, ids, &values, &fields[needed..], needed, line);
                edges.push(edge.map_err(parse_error)?);
            }
            Tag::Vertex2 => vertices.push(Vertex {
                id: ids[0],
                position: [values[0], values[1], 0.0],
                orientation: quaternion_from_yaw(values[2]),
                line,
            }),
            Tag::Vertex3Quat => vertices.push(Vertex {
                id: ids[0],
                position: [values[0], values[1], values[2]],
                orientation: [values[3], values[4], values[5], values[6]],
                line,
            }),
            Tag::Vertex3Euler => vertices.push(Vertex {
                id: ids[0],
                position: [values[0], values[1], values[2]],
                orientation: quaternion_from_roll_pitch_yaw(values[3], values[4], values[5]),
                line,
            }),
        }
    }
    let chain = match (vertices.is_empty(), edges.first()) {
        (true, Some(_)) if !chain_edges => return Err(no_vertices(path, &edges)),
        (true, Some(_)) => {
            let (poses, chain) = chain_odometry(path, &edges)?;
            vertices = poses
                .into_iter()
                .map(|pose| Vertex {
                    id: pose.id,
                    position: pose.position,
                    orientation: pose.orientation_xyzw,
                    line: pose.line,
                })
                .collect();
            Some(chain)
        }
        (true, None) => return Err(IoError::Empty { path: path.to_path_buf() }),
        (false, _) => None,
    };
    vertices.sort_by_key(|vertex| vertex.id);
    if let Some(pair) = vertices.windows(2).find(|pair| pair[0].id == pair[1].id) {
        let (first, second) = if pair[0].line < pair[1].line { (pair[0], pair[1]) } else { (pair[1], pair[0]) };
        return Err(IoError::parse(
            path,
            second.line,
            format!("vertex {} is given twice (first on line {})", first.id, first.line),
        ));
    }
    let lines: HashMap<u64, usize> = vertices.iter().map(|vertex| (vertex.id, vertex.line)).collect();
    if let Some((edge, id)) = edges
        .iter()
        .find_map(|edge| [edge.from, edge.to].into_iter().find(|id| !lines.contains_key(id)).map(|id| (edge, id)))
    {
        return Err(IoError::parse(
            path,
            edge.line,
            format!("the edge joins vertex {id}, which the file does not have"),
        ));
    }
    let mut table = PoseTable::empty(path, dim.map_or(3, |(dim, _)| dim));
    let ids: Vec<f64> = vertices.iter().map(|vertex| vertex.id as f64).collect();
    table.timestamps_s = timing.times(path, &ids)?.unwrap_or_else(|| ids.clone());
    table.positions = vertices.iter().map(|vertex| vertex.position).collect();
    table.orientations_xyzw = Some(vertices.iter().map(|vertex| vertex.orientation).collect());
    table.source_lines = vertices.iter().map(|vertex| vertex.line).collect();
    let skipped = (!skipped.tags.is_empty()).then_some(skipped);
    Ok(PoseGraph {
        vertices: table,
        vertex_ids: vertices.iter().map(|vertex| vertex.id).collect(),
        edges,
        chain,
        skipped,
    })
}

/// Whether the first data line is a g2o or TORO vertex or edge.
pub(crate) fn looks_like_graph(first_lines: &[String]) -> bool {
    first_lines.first().is_some_and(|line| {
        let word = line.split_ascii_whitespace().next().unwrap_or_default();
        word.starts_with("VERTEX") || word.starts_with("EDGE")
    })
}

//! The argument groups several commands share: how to read a pose file ([`InputArgs`]), the
//! engine ([`EngineArgs`]), how to sample ([`SamplingArgs`]), the three together
//! ([`AnalysisArgs`]) and what to print or write ([`OutputArgs`]).
//!
//! Each group converts its flags into the type of `loops-core` or `loops-io` that says the same
//! thing, once; defaults come from those types (`default_value_t = ...::default()`), and values
//! are validated where the concept lives, not here. Real-valued flags take any value a float
//! parses from, `-inf` and `NaN` included (`allow_hyphen_values`), so the core's check names
//! what is wrong with it.

use std::ffi::OsStr;
use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use loops_core::{DEFAULT_EPSILON_S, Manifold, MetricSpec, SampleSize, Sampler, SamplerKind, Separation, Trajectory};
use loops_io::PoseTable;

/// The flags that say how to read a pose file, shared by every command that reads one.
#[derive(Debug, Args)]
pub(crate) struct InputArgs {
    /// File format: tum, csv, kitti, euroc, tuc, g2o, mcap, rosbag2, ros1 (default: from the
    /// extension and first line; a folder is a rosbag2 bag).
    #[arg(long)]
    format: Option<String>,
    /// Topic to read from MCAP files and bags (default: the one topic with poses; `loops info`
    /// lists them).
    #[arg(long)]
    topic: Option<String>,
    /// Time of each pose from MCAP files and bags: header (the message stamp), log or publish
    /// (bags record one time: log and publish both take it).
    #[arg(long)]
    time: Option<String>,
    /// Parent and child frame of a transform topic (TF), e.g. odom,base_link. Frames linked
    /// through others (map,velodyne over odom and base_link, /tf_static included) are composed
    /// at the stamps of the moving transform nearest the child.
    #[arg(long, value_delimiter = ',', value_name = "PARENT,CHILD")]
    frames: Option<Vec<String>>,
    /// For files without times (KITTI poses, pose graphs): pose i at i / RATE_HZ seconds.
    #[arg(long, value_name = "RATE_HZ", allow_hyphen_values = true)]
    rate_hz: Option<f64>,
    /// For files without times (KITTI poses, pose graphs): one time a line, seconds, in FILE
    /// (KITTI's sequences/XX/times.txt), one per pose in order.
    #[arg(long, value_name = "FILE", conflicts_with = "rate_hz")]
    times: Option<PathBuf>,
    /// A plane of two position axes (0 = x, 1 = y, 2 = z), e.g. 0,2 for KITTI's ground plane
    /// (x-z): euclidean measures positions in it, se2 takes its coordinates and the rotation
    /// about its normal, and the maps of `loops run` draw it (under se3 and so3, only the maps)
    /// [default: all axes; x-y for se2 and the maps].
    #[arg(long, value_delimiter = ',', value_name = "A,B")]
    axes: Option<Vec<usize>>,
    /// Drop the poses whose timestamp repeats the one before (keeping the first of each),
    /// saying how many on stderr; without it they are an error naming the line.
    #[arg(long)]
    drop_duplicate_stamps: bool,
    /// How far from unit length a quaternion may be and still be normalised [default: 1e-3,
    /// for files that print 4 decimals].
    #[arg(long, value_name = "TOLERANCE", allow_hyphen_values = true)]
    quaternion_tolerance: Option<f64>,
    /// For a pose graph without vertices (a list of edges): chain its odometry edges (vertex i
    /// to i+1) into a trajectory from the first vertex at the origin. That is dead reckoning,
    /// and the command says so; a gap in the chain is an error naming the vertex.
    #[arg(long)]
    chain_edges: bool,
}

impl InputArgs {
    /// The options of `loops_io` these flags ask for: the one place the CLI builds them.
    pub(crate) fn options(&self) -> Result<loops_io::ReadOptions> {
        let mut mcap = loops_io::McapOptions::default();
        if let Some(topic) = &self.topic {
            mcap = mcap.topic(topic.clone());
        }
        if let Some(time) = &self.time {
            mcap = mcap.time(time.parse()?);
        }
        match self.frames.as_deref() {
            None => {}
            Some([parent, child]) => mcap = mcap.frames(parent.clone(), child.clone()),
            Some(other) => bail!("--frames takes a parent and a child frame, got {other:?}"),
        }
        let mut options = loops_io::ReadOptions::default().mcap(mcap);
        if let Some(format) = &self.format {
            options = options.format(format.parse()?);
        }
        options = options.timing(loops_io::Timing::given(self.rate_hz, self.times.clone())?);
        Ok(options
            .chain_edges(self.chain_edges)
            .drop_duplicate_stamps(self.drop_duplicate_stamps)
            .quaternion_tolerance(self.quaternion_tolerance))
    }

    /// Reads `files` as one trajectory: the poses as read (orientations included) and the
    /// trajectory `spec` needs, on the plane of `--axes` when the metric takes one (checked
    /// against the file for the others, which use it for the maps only). Several MCAP files are
    /// merged by time (a recording split in parts); other files must follow one another in
    /// time, and are joined in time order (each checked first, so that an error names its file
    /// and line). Each file's dropped duplicate stamps (--drop-duplicate-stamps) are one line
    /// on stderr, as is each pose graph chained from its edges (--chain-edges: dead reckoning).
    pub(crate) fn read_table(&self, files: &[PathBuf], spec: &MetricSpec) -> Result<(PoseTable, Trajectory)> {
        let plane = self.plane()?;
        // --axes with a metric of whole poses draws the maps only: checked, not measured.
        let takes_plane = loops_io::metric_takes_plane(spec);
        let read = loops_io::read_trajectories(files, &self.options()?, spec, plane.filter(|_| takes_plane))
            .map_err(|error| self.hint(error))?;
        for warning in read.notes.iter().flat_map(loops_io::ReadNotes::warnings) {
            eprintln!("loops: warning: {warning}");
        }
        for dropped in read.dropped.iter().filter(|dropped| !dropped.is_empty()) {
            let lines = dropped.lines_text().map_or(String::new(), |lines| format!(" ({lines})"));
            eprintln!(
                "loops: {}: --drop-duplicate-stamps dropped {} pose(s) whose timestamp repeats the one before{lines}",
                dropped.path.display(),
                dropped.count
            );
        }
        if let Some(plane) = plane.filter(|_| !takes_plane) {
            read.table.check_plane(plane)?;
        }
        Ok((read.table, read.trajectory))
    }

    /// The plane of `--axes`, if given: two position axes.
    pub(crate) fn plane(&self) -> Result<Option<[usize; 2]>> {
        Ok(match self.axes.as_deref() {
            None => None,
            Some(&[a, b]) => Some([a, b]),
            Some(other) => bail!("--axes takes two axis indices, got {other:?}"),
        })
    }

    /// What the metric measures of a pose file, for the headers and the report: the positions
    /// (saying so when the file's orientations are left out), or the poses on their manifold.
    pub(crate) fn measured(&self, table: &PoseTable, traj: &Trajectory) -> String {
        let plane = self.plane().ok().flatten();
        let axes = |axes: &[usize]| -> String {
            axes.iter().map(|&axis| ["x", "y", "z"].get(axis).copied().unwrap_or("?")).collect::<Vec<_>>().join(", ")
        };
        match (traj.manifold(), plane) {
            (Manifold::Euclidean, _) => {
                let positions = match plane {
                    Some(plane) => format!("positions {} (--axes)", axes(&plane)),
                    None => format!("positions {}", axes(&[0, 1, 2][..table.dim.min(3)])),
                };
                if table.orientations_xyzw.is_some() {
                    format!("{positions}; orientations not measured ({ORIENTATION_METRICS} measure them)")
                } else {
                    positions
                }
            }
            (Manifold::Se2, Some(plane)) => {
                format!("se2 points (positions {} and the heading in that plane)", axes(&plane))
            }
            (manifold, _) => format!("{manifold} points ({})", manifold.columns(traj.dim())),
        }
    }

    /// An error about the poses, with the flag that changes what it refuses where the message
    /// names only the option's Python spelling.
    fn hint(&self, error: loops_io::IoError) -> anyhow::Error {
        let flag = match &error {
            loops_io::IoError::Trajectory { error: loops_core::Error::NonUnitQuaternion { .. }, .. } => {
                "; on the command line it is --quaternion-tolerance"
            }
            _ => return error.into(),
        };
        anyhow::anyhow!("{error}{flag}")
    }
}

/// How a command names the trajectory it read from `files`: the file, or the files joined by
/// ` + ` (in the order given).
pub(crate) fn source_name(files: &[PathBuf]) -> String {
    files.iter().map(|file| file.display().to_string()).collect::<Vec<_>>().join(" + ")
}

/// The metrics that measure a pose file's orientations, as `--metric` takes them.
const ORIENTATION_METRICS: &str = "--metric se3(rotation_weight_m_per_rad=W), se3_rotation, so3 or se2";

/// The engine: γ, the metric and the thread pool.
#[derive(Debug, Args)]
pub(crate) struct EngineArgs {
    /// The distance threshold γ, in the metric's unit: metres for euclidean, se3 and se2 (their
    /// rotation weighted in m/rad) and haversine; radians under so3, se3_rotation, torus and
    /// angular; the radius's unit under sphere.
    #[arg(long, value_name = "GAMMA", allow_hyphen_values = true)]
    pub(crate) gamma: f64,
    /// The metric: euclidean, se3(rotation_weight_m_per_rad=W[, rotation=geodesic|chordal]),
    /// se3_rotation, so3, se2(rotation_weight_m_per_rad=W), torus, sphere(radius=R),
    /// haversine(radius_m=R), angular. euclidean (the default) measures the positions only (x,
    /// y, z, or the --axes pair), never a quaternion; se3, se3_rotation, so3 and se2 measure
    /// the file's orientations too. The output's `measured:` line and the report say which.
    #[arg(long, default_value_t = MetricSpec::default().name())]
    pub(crate) metric: String,
    /// Revisits only: pairs at least this path length apart along the trajectory, in the
    /// metric's unit [default: 4 x gamma, or 0 when only --separation-time is given].
    #[arg(long, value_name = "LENGTH", allow_hyphen_values = true)]
    pub(crate) separation_path: Option<f64>,
    /// Revisits only: pairs at least this many seconds apart (LIO-SAM waits 30) [default: 0].
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub(crate) separation_time: Option<f64>,
    /// The paper's S_gamma: no separation, so pairs that odometry ties together count too, as
    /// trivial components and simple loops.
    #[arg(long, conflicts_with_all = ["separation_path", "separation_time"])]
    pub(crate) no_separation: bool,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long)]
    pub(crate) threads: Option<usize>,
}

impl EngineArgs {
    /// The separation the flags ask for, checked: `--no-separation`, the flags given, or the
    /// default [`Separation::for_gamma`].
    pub(crate) fn separation(&self) -> Result<Separation> {
        let separation = match (self.no_separation, self.separation_path, self.separation_time) {
            (true, ..) => Separation::NONE,
            (false, None, None) => Separation::for_gamma(self.gamma),
            (false, path, time_s) => Separation { path: path.unwrap_or(0.0), time_s: time_s.unwrap_or(0.0) },
        };
        separation.check()?;
        Ok(separation)
    }

    /// The metric `--metric` names.
    pub(crate) fn spec(&self) -> Result<MetricSpec> {
        Ok(self.metric.parse()?)
    }
}

/// How a result's separation was chosen, for a run's header: `separation: path >= 24 (the
/// default, 4 x gamma; ...)`.
pub(crate) fn separation_line(separation: Separation, gamma: f64) -> String {
    let how = if separation.is_none() {
        "--no-separation: the paper's S_gamma, trivial components included".to_owned()
    } else if separation == Separation::for_gamma(gamma) {
        format!(
            "the default, {} x gamma; --separation-path/--separation-time to change, --no-separation for the paper's S_gamma",
            Separation::DEFAULT_GAMMAS
        )
    } else {
        "as given".to_owned()
    };
    format!("separation: {separation} ({how})")
}

/// How to sample: the flags `loops sample` and `loops run` share, with the core's defaults.
#[derive(Debug, Args)]
pub(crate) struct SamplingArgs {
    /// The sampler: nearest-then-uniform (each component's closest pair, then rows' closest
    /// pairs up to one row in six, the rest uniform), one (σ_1), rho (σ_ρ), rho-dispersed,
    /// alpha (σ_α), closest-first (each component's closest pair, then as rho-dispersed),
    /// closest-then-spread (σ_ρ's counts, each component's closest pair first, the rest
    /// spread along it), or a SLAM baseline: lio-sam, hdl-graph-slam, cartographer, time-gap.
    #[arg(long, default_value_t = SamplerKind::DEFAULT.name().to_owned())]
    pub(crate) sampler: String,
    /// Exactly this many samples (at least one per component when it allows) [default: 1000
    /// without --rate].
    #[arg(long, conflicts_with = "rate")]
    pub(crate) budget: Option<usize>,
    /// The sampler's rate instead of a budget (per component, per row, or per candidate).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) rate: Option<f64>,
    /// Seed of the random choices.
    #[arg(long, default_value_t = Sampler::DEFAULT_SEED)]
    pub(crate) seed: u64,
    /// Radius of the detection graph and of the P2 redundancy measure, seconds.
    #[arg(
        long = "epsilon-s",
        visible_alias = "epsilon",
        value_name = "EPSILON_S",
        default_value_t = DEFAULT_EPSILON_S,
        allow_hyphen_values = true
    )]
    pub(crate) epsilon_s: f64,
    /// Leave out the trivial loop components (simple loops: the next poses, stops), which
    /// odometry already ties together (not with a baseline or --detections).
    #[arg(long)]
    pub(crate) skip_trivial: bool,
}

impl SamplingArgs {
    /// The sampler these flags ask for, refused by the core when an option does not apply.
    pub(crate) fn sampler(&self) -> Result<Sampler> {
        let kind: SamplerKind = self.sampler.parse()?;
        let size = SampleSize::or_default(self.rate, self.budget)?;
        let sampler = Sampler { skip_trivial: self.skip_trivial, ..Sampler::new(kind, size, self.seed) };
        // Core names the option as in Rust; here it is a flag.
        sampler.check_applicable().map_err(|error| match error {
            loops_core::Error::NotApplicable { option, to, reason } => {
                anyhow::anyhow!("--{} does not apply to {to}: {reason}", option.replace('_', "-"))
            }
            other => other.into(),
        })?;
        Ok(sampler)
    }
}

/// The flags of the commands that find loops and sample them (`sample`, `run`, `fleet`): how to
/// read, the engine, how to sample.
#[derive(Debug, Args)]
pub(crate) struct AnalysisArgs {
    #[command(flatten)]
    pub(crate) input: InputArgs,
    #[command(flatten)]
    pub(crate) engine: EngineArgs,
    #[command(flatten)]
    pub(crate) sampling: SamplingArgs,
}

/// What [`AnalysisArgs`] ask for, checked.
#[derive(Debug)]
pub(crate) struct Analysis {
    pub(crate) spec: MetricSpec,
    pub(crate) sampler: Sampler,
    pub(crate) separation: Separation,
}

impl AnalysisArgs {
    /// The metric, the sampler and the separation the flags ask for, with γ, ε and the thread
    /// count checked by the core: refused once, before any file is read.
    pub(crate) fn checked(&self) -> Result<Analysis> {
        let spec = self.engine.spec()?;
        let sampler = self.sampling.sampler()?;
        loops_core::check_gamma(self.engine.gamma)?;
        let separation = self.engine.separation()?;
        loops_core::check_epsilon_s(self.sampling.epsilon_s)?;
        self.engine.threads.map(loops_core::check_threads).transpose()?;
        Ok(Analysis { spec, sampler, separation })
    }
}

/// Where a `--json FILE` flag sends its JSON: to FILE (written atomically), or to stdout for
/// `-`, instead of the table. Every command spells "JSON on stdout" this way.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum JsonTo {
    /// `-`: stdout, and nothing else there.
    Stdout,
    /// A file.
    File(PathBuf),
}

impl JsonTo {
    /// The file of `--json FILE` (none for `-`, or when the flag is absent).
    pub(crate) fn file(to: &Option<JsonTo>) -> Option<&std::path::Path> {
        match to {
            Some(JsonTo::File(path)) => Some(path),
            _ => None,
        }
    }
}

impl From<&OsStr> for JsonTo {
    fn from(value: &OsStr) -> Self {
        if value == "-" { Self::Stdout } else { Self::File(PathBuf::from(value)) }
    }
}

/// What `loops components` and `loops demo` print and write.
#[derive(Debug, Args)]
pub(crate) struct OutputArgs {
    /// Also write the result as JSON to FILE (atomically); `-` prints it on stdout instead of
    /// the table.
    #[arg(long, value_name = "FILE")]
    pub(crate) json: Option<JsonTo>,
    /// Replace the JSON file if it exists.
    #[arg(long)]
    pub(crate) force: bool,
    /// Show at most this many components, largest area first (0: all).
    #[arg(long, default_value_t = 20)]
    pub(crate) limit: usize,
}

//! `loops`: inexact-loop components of trajectories, on the command line.
//!
//! `main` parses, calls [`run`], prints errors as one line on stderr and exits 2 on error,
//! 0 on success or a closed pipe. Everything else lives in `loops-core` and `loops-io`.

mod guard;
mod html;
mod input;
mod output;
mod progress;
mod report;
mod run;
mod sample;
mod synth;

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use loops_core::{Loops, MetricSpec, Trajectory, UrbanDrive};

/// Find, measure and sample inexact loops (loop closures) in robot trajectories.
#[derive(Debug, Parser)]
#[command(name = "loops", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List the loop components of a trajectory file (TUM or CSV).
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  loops components drive.tum --gamma 40\n  \
        loops components kitti00.txt --format tum --axes 0,2 --gamma 6 --json kitti00.json\n  \
        loops components log.csv --gamma 5 --limit 0    # every component\n  \
        loops components fr2_desk.tum --gamma 0.3 --metric 'se3(rotation_weight_m_per_rad=0.5)'"
    )]
    Components(ComponentsArgs),
    /// Candidate loop-closure pairs for a scan matcher, from the exact loop components or from
    /// clustered detections, with coverage (P1), redundancy (P2) and growth (P3).
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  \
        loops sample drive.tum --gamma 40 --sampler rho --budget 10000 --out pairs.csv\n  \
        loops sample Corridor_GT.tum --gamma 1 --sampler rho --budget 500 --detections Corridor_Input.txt --epsilon-s 5"
    )]
    Sample(sample::SampleArgs),
    /// What a pose file holds: for MCAP, its topics (type, encoding, messages, time span, and
    /// whether poses can be read from it); for text formats, the format, poses and time span.
    #[command(after_help = "Examples:\n  loops info drive.mcap\n  loops info 00.txt --format kitti")]
    Info(InfoArgs),
    /// Run on a built-in synthetic urban drive (2.1 h, 10 Hz, 1 km² city) and print a summary.
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  loops demo\n  loops demo --duration-s 600 --seed 3 --json demo.json"
    )]
    Demo(DemoArgs),
    /// Process many pose logs: per log its components, samples, loop durations, a summary and
    /// an HTML report, in a folder of its own; for the batch an index page and a summary.
    /// Logs run in parallel; one that fails is reported and the others go on (exit code 1).
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  \
        loops run logs/*.mcap --gamma 40 --out results\n  \
        loops run logs/*.mcap --gamma 40 --sampler rho --budget 2000 --out results --force\n  \
        loops run a.mcap b.tum --gamma 0.5 --metric 'se3(rotation_weight_m_per_rad=1)' --out results --json\n  \
        loops run night/*.mcap --topic /odom --gamma 10 --out night-results --quiet\n\n\
        Per log (results/<log>/): components.csv, samples.csv, loop_duration.csv, summary.json,\n\
        report.html. For the batch: results/index.html and results/summary.json. Ctrl-C keeps the\n\
        logs already finished and removes the rest; nothing half-written is left."
    )]
    Run(run::RunArgs),
    /// Write seeded synthetic urban drives (a vehicle on a Manhattan grid) as MCAP or TUM logs.
    #[command(
        allow_negative_numbers = true,
        after_help = "Examples:\n  loops synth drive.mcap\n  \
        loops synth drive.tum --duration-s 600 --seed 7\n  \
        loops synth logs --count 20 --duration-s 900    # logs/urban-drive-0.mcap ... urban-drive-19.mcap\n  \
        loops synth big.mcap --duration-s 100800 --city-size-m 10000"
    )]
    Synth(synth::SynthArgs),
}

#[derive(Debug, Args)]
pub(crate) struct EngineArgs {
    /// The distance threshold γ, in the metric's unit (metres for positions).
    #[arg(long, value_name = "GAMMA_M")]
    pub(crate) gamma: f64,
    /// The metric: euclidean, se3(rotation_weight_m_per_rad=W[, rotation=geodesic|chordal]),
    /// se3_rotation, so3, se2(rotation_weight_m_per_rad=W). SE(3), SO(3) and SE(2) use the file's
    /// orientations.
    #[arg(long, default_value_t = MetricSpec::default().name())]
    pub(crate) metric: String,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long)]
    pub(crate) threads: Option<usize>,
}

#[derive(Debug, Args)]
struct OutputArgs {
    /// Also write the result as JSON to this file (written atomically).
    #[arg(long, value_name = "PATH")]
    json: Option<PathBuf>,
    /// Replace the JSON file if it exists.
    #[arg(long)]
    force: bool,
    /// Show at most this many components, largest area first (0: all).
    #[arg(long, default_value_t = 20)]
    limit: usize,
}

#[derive(Debug, Args)]
struct ComponentsArgs {
    /// The trajectory file.
    file: PathBuf,
    #[command(flatten)]
    input: input::InputArgs,
    #[command(flatten)]
    engine: EngineArgs,
    #[command(flatten)]
    output: OutputArgs,
}

#[derive(Debug, Args)]
struct InfoArgs {
    /// The file.
    file: PathBuf,
    #[command(flatten)]
    input: input::InputArgs,
}

fn info(args: InfoArgs) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    let options = args.input.options()?;
    let is_mcap = options.format == Some(loops_io::Format::Mcap)
        || (options.format.is_none() && loops_io::Format::from_path(&args.file) == Some(loops_io::Format::Mcap));
    writeln!(stdout, "{}", args.file.display())?;
    if is_mcap {
        let topics = loops_io::list_topics(&args.file)?;
        writeln!(
            stdout,
            "{:<28} {:<36} {:<9} {:>9}  {:>10}  poses",
            "topic", "type", "encoding", "messages", "span (s)"
        )?;
        for topic in &topics {
            let span = topic.log_time_span_ns.map_or("-".to_owned(), |(a, b)| format!("{:.1}", (b - a) as f64 * 1e-9));
            let poses = if topic.pose_type.is_some() { "yes" } else { "no" };
            writeln!(
                stdout,
                "{:<28} {:<36} {:<9} {:>9}  {:>10}  {poses}",
                topic.topic, topic.schema_name, topic.message_encoding, topic.message_count, span
            )?;
        }
    } else {
        let table = loops_io::read_trajectory_with(&args.file, &options)?;
        let t = &table.timestamps_s;
        let span =
            t.iter().copied().fold(f64::NEG_INFINITY, f64::max) - t.iter().copied().fold(f64::INFINITY, f64::min);
        writeln!(
            stdout,
            "  {} poses, {} coordinates each, {} orientations, over {:.3} s",
            table.timestamps_s.len(),
            table.dim,
            if table.orientations_xyzw.is_some() { "with" } else { "without" },
            span
        )?;
    }
    Ok(())
}

#[derive(Debug, Args)]
struct DemoArgs {
    /// Length of the drive, seconds.
    #[arg(long, default_value_t = UrbanDrive::default().duration_s)]
    duration_s: f64,
    /// Seed of the drive.
    #[arg(long, default_value_t = UrbanDrive::default().seed)]
    seed: u64,
    /// The distance threshold γ, metres.
    #[arg(long, value_name = "GAMMA_M", default_value_t = 40.0)]
    gamma: f64,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    output: OutputArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(error) = guard::install() {
        eprintln!("loops: error: {error:#}");
        return ExitCode::from(2);
    }
    match run(cli) {
        Ok(code) => code,
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("loops: error: {error:#}");
            ExitCode::from(2)
        }
    }
}

fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Components(args) => components(args),
        Command::Demo(args) => demo(args),
        Command::Sample(args) => sample::sample(args),
        Command::Info(args) => info(args),
        Command::Run(args) => return run::run(args),
        Command::Synth(args) => synth::synth(args),
    }
    .map(|()| ExitCode::SUCCESS)
}

fn components(args: ComponentsArgs) -> Result<()> {
    let source = args.file.display().to_string();
    let spec: MetricSpec = args.engine.metric.parse()?;
    let traj = args.input.read(&args.file, &spec)?;
    let (loops, seconds) = timed(args.engine.threads, || spec.find_loops(&traj, args.engine.gamma))
        .with_context(|| format!("finding loops in {source}"))?;
    report(&source, &traj, &loops, seconds, &args.output)
}

fn demo(args: DemoArgs) -> Result<()> {
    let spec = UrbanDrive { duration_s: args.duration_s, seed: args.seed, ..UrbanDrive::default() };
    let drive = spec.generate().context("generating the urban drive")?;
    let source = format!("urban drive (seed {}, {:.0} s at {} Hz)", spec.seed, spec.duration_s, spec.rate_hz);
    let (loops, seconds) = timed(args.threads, || MetricSpec::Euclidean.find_loops(&drive.trajectory, args.gamma))?;
    report(&source, &drive.trajectory, &loops, seconds, &args.output)
}

fn timed(threads: Option<usize>, f: impl FnOnce() -> loops_core::Result<Loops> + Send) -> Result<(Loops, f64)> {
    let start = Instant::now();
    let loops = loops_core::with_threads(threads, f)??;
    Ok((loops, start.elapsed().as_secs_f64()))
}

fn report(source: &str, traj: &Trajectory, loops: &Loops, seconds: f64, out: &OutputArgs) -> Result<()> {
    for warning in loops.warnings() {
        eprintln!("loops: warning: {warning}");
    }
    let mut stdout = std::io::stdout().lock();
    output::write_table(&mut stdout, source, traj, loops, seconds, out.limit)?;
    stdout.flush()?;
    if let Some(path) = &out.json {
        let json = output::json_report(source, traj, loops)?;
        guard::write_atomically(path, json.as_bytes(), out.force)
            .with_context(|| format!("writing {}", path.display()))?;
        writeln!(stdout, "wrote {}", path.display())?;
    }
    Ok(())
}

//! `loops components`: the loop components of a pose file, as a table on stdout and, on request,
//! a JSON report (loops-io's [`LoopsReport`]). `loops demo` prints the same for its synthetic drive.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use loops_core::{LoopComponent, Loops, MetricSpec, Scale, Selection, Side, Trajectory};
use loops_io::LoopsReport;

use crate::args::{EngineArgs, InputArgs, JsonTo, OutputArgs, separation_line};
use crate::guard;

/// List the loop components of a pose file (MCAP, TUM, CSV, KITTI, EuRoC, TUC or g2o), or of
/// several files read as one trajectory.
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  loops components drive.tum --gamma 40\n  \
    loops components kitti_odometry/00.txt --axes 0,2 --gamma 6 --json kitti00.json\n  \
    loops components poses/00.txt --times sequences/00/times.txt --axes 0,2 --gamma 6    # KITTI without times\n  \
    loops components log.csv --gamma 5 --limit 0    # every component\n  \
    loops components monday.tum tuesday.tum --gamma 5    # one trajectory, in time order\n  \
    loops components drive.mcap --gamma 40 --json - | jq '.components | length'\n  \
    loops components tum_rgbd/fr2_desk_groundtruth.txt --gamma 0.3 --metric 'se3(rotation_weight_m_per_rad=0.5)' \
    --drop-duplicate-stamps\n  \
    loops components pose_graphs/input_INTEL_g2o.g2o --gamma 3 --edges --edges-csv intel_edges.csv\n  \
    loops components edges_only.g2o --chain-edges --gamma 2 --edges    # poses by dead reckoning"
)]
pub(crate) struct ComponentsArgs {
    /// The pose file; several files are read as one trajectory (MCAP files merged by time,
    /// others joined in time order: their times must not overlap).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    engine: EngineArgs,
    #[command(flatten)]
    output: OutputArgs,
    #[command(flatten)]
    edges: EdgesArgs,
}

/// Where the loop-closure edges of a pose graph fall: `--edges` and its files.
#[derive(Debug, Args)]
struct EdgesArgs {
    /// For a pose graph (g2o, TORO): say where each loop-closure edge (vertices more than one
    /// id apart) falls, as counts per verdict: in a loop component (a revisit), in a trivial
    /// component (only with --no-separation), not-separated (within gamma but closer along the
    /// path than the separation: not a revisit), or outside S_gamma (farther than gamma).
    #[arg(long)]
    edges: bool,
    /// Write each loop-closure edge and its verdict as CSV to FILE (atomically; an existing file
    /// is kept unless --force; `-` prints it on stdout instead of the tables). Implies --edges.
    #[arg(long, value_name = "FILE")]
    edges_csv: Option<JsonTo>,
    /// Write the edges' verdicts and counts as JSON to FILE (as --edges-csv). Implies --edges.
    #[arg(long, value_name = "FILE")]
    edges_json: Option<JsonTo>,
}

impl EdgesArgs {
    fn wanted(&self) -> bool {
        self.edges || self.edges_csv.is_some() || self.edges_json.is_some()
    }
}

pub(crate) fn components(args: ComponentsArgs) -> Result<()> {
    let source = crate::args::source_name(&args.files);
    let spec = args.engine.spec()?;
    let stdouts = [&args.output.json, &args.edges.edges_csv, &args.edges.edges_json]
        .iter()
        .filter(|to| **to == &Some(JsonTo::Stdout))
        .count();
    if stdouts > 1 {
        bail!("--json -, --edges-csv - and --edges-json - each take all of stdout: give one of them");
    }
    if args.edges.wanted() && args.files.len() != 1 {
        bail!("--edges reads the edges of one pose graph, and {} files were given", args.files.len());
    }
    crate::out_dir::refuse_outputs_on_inputs(
        [
            ("--json", JsonTo::file(&args.output.json)),
            ("--edges-csv", JsonTo::file(&args.edges.edges_csv)),
            ("--edges-json", JsonTo::file(&args.edges.edges_json)),
        ],
        &args.files,
    )?;
    let (table, traj) = args.input.read_table(&args.files, &spec)?;
    let measured = args.input.measured(&table, &traj);
    loops_core::check_gamma(args.engine.gamma)?;
    let separation = args.engine.separation()?;
    let (loops, seconds) =
        timed(args.engine.threads, || spec.find_loops_separated(&traj, args.engine.gamma, separation))
            .with_context(|| format!("finding loops in {source}"))?;
    if !args.edges.wanted() {
        return print(&source, &measured, &traj, &loops, seconds, &args.output);
    }
    let verdicts = edge_verdicts(&args.files[0], &args.input, &source, &traj, &spec, &loops)?;
    // Every edge file is prepared first and written only when all could be.
    let mut files = loops_io::StagedFiles::new();
    let mut lines = Vec::new();
    if let Some(JsonTo::File(path)) = &args.edges.edges_csv {
        files.stage(path, args.output.force, |file| verdicts.to_csv(file)).map_err(guard::write_error)?;
        lines.push(format!("wrote {} edge verdicts to {}", verdicts.rows.len(), path.display()));
    }
    if let Some(JsonTo::File(path)) = &args.edges.edges_json {
        files.stage(path, args.output.force, |file| verdicts.to_json(file)).map_err(guard::write_error)?;
        lines.push(format!("wrote {} edge verdicts to {}", verdicts.rows.len(), path.display()));
    }
    let mut stdout = std::io::stdout().lock();
    let edges_on_stdout = [&args.edges.edges_csv, &args.edges.edges_json].contains(&&Some(JsonTo::Stdout));
    if edges_on_stdout {
        for warning in loops.warnings() {
            eprintln!("loops: warning: {warning}");
        }
        if let Some(JsonTo::File(path)) = &args.output.json {
            let report = LoopsReport::new(Some(&source), &loops)?;
            files
                .stage(path, args.output.force, |file| loops_io::loops_report_to_json(&report, file))
                .map_err(guard::write_error)?;
        }
        if args.edges.edges_csv == Some(JsonTo::Stdout) {
            verdicts.to_csv(&mut stdout)?;
        } else {
            verdicts.to_json(&mut stdout)?;
        }
        guard::with_writes(|_| files.persist()).map_err(guard::write_error)?;
        return Ok(stdout.flush()?);
    }
    drop(stdout);
    print(&source, &measured, &traj, &loops, seconds, &args.output)?;
    let mut stdout = std::io::stdout().lock();
    guard::with_writes(|_| files.persist()).map_err(guard::write_error)?;
    // With `--json -`, stdout holds the JSON only.
    if args.output.json != Some(JsonTo::Stdout) {
        write_edge_counts(&mut stdout, &verdicts, &loops)?;
        for line in lines {
            writeln!(stdout, "{line}")?;
        }
    }
    Ok(stdout.flush()?)
}

/// The verdicts of the loop-closure edges of the pose graph `file` against `loops`, found on
/// `traj` (its vertices) under `spec`.
fn edge_verdicts(
    file: &std::path::Path,
    input: &InputArgs,
    source: &str,
    traj: &Trajectory,
    spec: &MetricSpec,
    loops: &Loops,
) -> Result<loops_io::EdgeVerdicts> {
    let options = input.options()?;
    let format = match options.format {
        Some(format) => format,
        None => loops_io::format_of(file)?,
    };
    if format != loops_io::Format::G2o {
        bail!("--edges needs a pose graph (g2o or TORO) and its edges; {} is read as {format}", file.display());
    }
    let graph = loops_io::read_pose_graph_with(file, &options)?;
    loops_io::EdgeVerdicts::new(Some(source), &graph, traj, spec.as_metric(), loops)
        .with_context(|| format!("classifying the loop-closure edges of {}", file.display()))
}

/// The counts per verdict of the loop-closure edges, each with what it means, and how many
/// components hold an edge.
fn write_edge_counts(out: &mut impl Write, verdicts: &loops_io::EdgeVerdicts, loops: &Loops) -> Result<()> {
    let separation = loops.separation();
    writeln!(
        out,
        "loop-closure edges: {} of {} edges join vertices more than one id apart; where each falls at gamma {} \
         ({}), separation {separation}:",
        verdicts.loop_closures,
        verdicts.edges,
        loops.gamma(),
        loops.metric_name()
    )?;
    let not_separated = if separation.is_none() {
        "(none without a separation: every pair within gamma is in a component)".to_owned()
    } else {
        format!("within gamma, but closer along the trajectory than the separation ({separation}): not a revisit")
    };
    let meaning = [
        "in a non-trivial loop component: a revisit".to_owned(),
        if separation.is_none() {
            "in a trivial component: a simple loop, which odometry already ties together".to_owned()
        } else {
            "(none with a separation: no component is trivial)".to_owned()
        },
        not_separated,
        "farther apart than gamma: outside S_gamma".to_owned(),
    ];
    for ((name, count), meaning) in verdicts.counts.named().into_iter().zip(meaning) {
        writeln!(out, "  {name:<14} {count:>6}  {meaning}")?;
    }
    let mut holding: Vec<usize> = verdicts.rows.iter().filter_map(|row| row.component).collect();
    holding.sort_unstable();
    holding.dedup();
    let nontrivial = |c: &usize| !loops.components()[*c].trivial;
    writeln!(
        out,
        "  {} of {} non-trivial components hold a loop-closure edge",
        holding.iter().filter(|c| nontrivial(c)).count(),
        loops.components().iter().filter(|c| !c.trivial).count()
    )?;
    Ok(())
}

/// Runs `find` on `threads` threads: its loops and the seconds it took.
pub(crate) fn timed(
    threads: Option<usize>,
    find: impl FnOnce() -> loops_core::Result<Loops> + Send,
) -> Result<(Loops, f64)> {
    let start = Instant::now();
    let loops = loops_core::with_threads(threads, find)??;
    Ok((loops, start.elapsed().as_secs_f64()))
}

/// Prints the warnings (stderr) and the table (stdout), and writes the JSON report if asked;
/// with `--json -` the report is all stdout holds. `measured` says what the metric measured.
pub(crate) fn print(
    source: &str,
    measured: &str,
    traj: &Trajectory,
    loops: &Loops,
    seconds: f64,
    out: &OutputArgs,
) -> Result<()> {
    for warning in loops.warnings() {
        eprintln!("loops: warning: {warning}");
    }
    let mut stdout = std::io::stdout().lock();
    let report = || LoopsReport::new(Some(source), loops);
    if out.json == Some(JsonTo::Stdout) {
        loops_io::loops_report_to_json(&report()?, &mut stdout)?;
        return Ok(stdout.flush()?);
    }
    write_table(&mut stdout, source, measured, traj, loops, seconds, out.limit)?;
    stdout.flush()?;
    if let Some(JsonTo::File(path)) = &out.json {
        let report = report()?;
        guard::with_writes(|_| loops_io::write_loops_report(path, &report, out.force))
            .map_err(guard::write_error)
            .with_context(|| format!("writing {}", path.display()))?;
        writeln!(stdout, "wrote {}", path.display())?;
    }
    Ok(())
}

/// The summary line and the components table, largest area first, at most `limit` rows (0: all).
fn write_table(
    out: &mut impl Write,
    source: &str,
    measured: &str,
    traj: &Trajectory,
    loops: &Loops,
    seconds: f64,
    limit: usize,
) -> Result<()> {
    let components = loops.components();
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let density = loops.loop_density(
        traj.timestamps_s()[0],
        traj.timestamps_s()[traj.len() - 1],
        Selection::All,
        Side::Both,
        Scale::Seconds,
    )?;
    writeln!(out, "{source}")?;
    writeln!(out, "  measured: {measured}")?;
    writeln!(out, "  {}", separation_line(loops.separation(), loops.gamma()))?;
    let t0 = traj.timestamps_s()[0];
    writeln!(
        out,
        "  {} poses over {:.1} s; gamma {} ({}): {} components ({} non-trivial), {} pose pairs (i < j), \
         mean loop duration {:.1} s; {:.3} s",
        traj.len(),
        traj.span_s(),
        loops.gamma(),
        loops.metric_name(),
        components.len(),
        nontrivial,
        loops.pose_pair_count(),
        density,
        seconds
    )?;
    let mut order: Vec<&LoopComponent> = components.iter().collect();
    order.sort_by(|a, b| b.area_s2.total_cmp(&a.area_s2).then(a.id.cmp(&b.id)));
    let shown = if limit == 0 { order.len() } else { limit.min(order.len()) };
    writeln!(out, "  times in seconds from the first pose (t0 = {t0})")?;
    writeln!(
        out,
        "{:>6} {:>7} {:>12} {:>10} {:>5}  {:>21}  {:>21}  {:>10}",
        "id", "trivial", "area_s2", "pose pairs", "holes", "t range (s)", "t' range (s)", "closest"
    )?;
    let t: Vec<f64> = traj.timestamps_s().iter().map(|t| t - t0).collect();
    for c in &order[..shown] {
        writeln!(
            out,
            "{:>6} {:>7} {:>12.1} {:>10} {:>5}  {:>10.1}–{:<10.1}  {:>10.1}–{:<10.1}  {:>10.3}",
            c.id,
            if c.trivial { "yes" } else { "no" },
            c.area_s2,
            c.pose_pair_count,
            c.holes,
            t[c.i_range[0]],
            t[c.i_range[1]],
            t[c.j_range[0]],
            t[c.j_range[1]],
            c.closest_distance
        )?;
    }
    if shown < order.len() {
        writeln!(out, "  ... {} more (--limit 0 shows all)", order.len() - shown)?;
    }
    Ok(())
}

//! `loops components`: the loop components of a pose file, as a table on stdout and, on request,
//! a JSON report (loops-io's [`LoopsReport`]). `loops demo` prints the same for its synthetic drive.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use loops_core::{LoopComponent, Loops, Scale, Selection, Side, Trajectory};
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
    --drop-duplicate-stamps"
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
}

pub(crate) fn components(args: ComponentsArgs) -> Result<()> {
    let source = crate::args::source_name(&args.files);
    let spec = args.engine.spec()?;
    let (table, traj) = args.input.read_table(&args.files, &spec)?;
    let measured = args.input.measured(&table, &traj);
    loops_core::check_gamma(args.engine.gamma)?;
    let separation = args.engine.separation()?;
    let (loops, seconds) =
        timed(args.engine.threads, || spec.find_loops_separated(&traj, args.engine.gamma, separation))
            .with_context(|| format!("finding loops in {source}"))?;
    print(&source, &measured, &traj, &loops, seconds, &args.output)
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
        "  {} poses over {:.1} s; gamma {} ({}): {} components ({} non-trivial), {} pairs, \
         mean loop duration {:.1} s; {:.3} s",
        traj.len(),
        traj.span_s(),
        loops.gamma(),
        loops.metric_name(),
        components.len(),
        nontrivial,
        loops.pair_count(),
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
        "id", "trivial", "area_s2", "pairs", "holes", "t range (s)", "t' range (s)", "closest"
    )?;
    let t: Vec<f64> = traj.timestamps_s().iter().map(|t| t - t0).collect();
    for c in &order[..shown] {
        writeln!(
            out,
            "{:>6} {:>7} {:>12.1} {:>10} {:>5}  {:>10.1}–{:<10.1}  {:>10.1}–{:<10.1}  {:>10.3}",
            c.id,
            if c.trivial { "yes" } else { "no" },
            c.area_s2,
            c.pair_count,
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

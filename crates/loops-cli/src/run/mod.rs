//! `loops run`: many pose logs in one go, each to its own folder of results and a report, with
//! an index page and a summary for the batch.
//!
//! Logs are processed in parallel (and each one's engine in parallel within it) on the
//! `--threads` pool. A log that fails is reported and the others go on; the exit code is 1 when
//! any failed. Each log's files are written into a hidden staging folder that is renamed to the
//! log's name when all are written (see [`crate::guard`]), so a folder is whole or absent.

mod index;

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use loops_core::{
    Loops, MetricSpec, SampleQuality, SampleSize, Sampler, SamplerKind, Samples, Scale, Selection, Side, Trajectory,
    sample_quality,
};
use rayon::prelude::*;
use serde::Serialize;

use crate::args::{EngineArgs, InputArgs, JsonTo, SamplingArgs};
use crate::guard;
use crate::progress::{self, Batch};
use crate::report::{self, ReportInput};

/// The file in each log folder that marks it as written by `loops run` (and replaceable with
/// `--force`).
const MARKER: &str = "summary.json";

/// The samplers of the samples-per-component figure (the run's own is added when not among them).
const COMPARED: [SamplerKind; 3] = [SamplerKind::One, SamplerKind::Rho, SamplerKind::Alpha];

/// Process many pose logs: per log its components, samples, loop durations, a summary and
/// an HTML report, in a folder of its own; for the batch an index page and a summary.
/// Logs run in parallel; one that fails is reported and the others go on (exit code 1).
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
    loops run logs/*.mcap --gamma 40 --out results\n  \
    loops run logs/*.mcap --gamma 40 --sampler rho --budget 2000 --out results --force\n  \
    loops run a.mcap b.tum --gamma 0.5 --metric 'se3(rotation_weight_m_per_rad=1)' --out results --json -\n  \
    loops run night/*.mcap --topic /odom --gamma 10 --out night-results --quiet\n\n\
    Per log (results/<log>/): components.csv, samples.csv, loop_duration.csv, summary.json,\n\
    report.html. For the batch: results/index.html and results/summary.json. Ctrl-C keeps the\n\
    logs already finished and removes the rest; nothing half-written is left."
)]
pub(crate) struct RunArgs {
    /// The pose logs: MCAP, or any format `loops info` reads (TUM, CSV, KITTI, EuRoC, TUC, g2o).
    #[arg(required = true, value_name = "LOG")]
    logs: Vec<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    engine: EngineArgs,
    #[command(flatten)]
    sampling: SamplingArgs,
    /// The folder for the results: a folder per log (components.csv, samples.csv,
    /// loop_duration.csv, summary.json, report.html), index.html and summary.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace the results of an earlier run in --out (only folders and files `loops run` wrote).
    #[arg(long)]
    force: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// Also write the batch summary (summary.json of --out) to FILE; `-` prints it on stdout
    /// instead of the table.
    #[arg(long, value_name = "FILE")]
    json: Option<JsonTo>,
}

/// One log of the batch and the folder its results go to.
#[derive(Debug)]
struct Job {
    path: PathBuf,
    /// The log's folder name in --out: its file stem, made unique in the batch.
    name: String,
}

/// What `loops run` knows after one log: summary.json of its folder.
#[derive(Debug, Serialize)]
pub(crate) struct LogSummary {
    pub(crate) name: String,
    pub(crate) source: String,
    pub(crate) poses: usize,
    pub(crate) t0_s: f64,
    pub(crate) span_s: f64,
    pub(crate) metric: String,
    pub(crate) gamma: f64,
    pub(crate) components: usize,
    pub(crate) nontrivial_components: usize,
    pub(crate) holes: u64,
    pub(crate) pair_count: u64,
    pub(crate) loop_area_s2: f64,
    pub(crate) loop_density_s: f64,
    pub(crate) sampler: String,
    pub(crate) sample_size: String,
    pub(crate) seed: u64,
    pub(crate) skip_trivial: bool,
    pub(crate) epsilon_s: f64,
    pub(crate) samples: usize,
    pub(crate) quality: QualitySummary,
    pub(crate) comparison: Vec<QualitySummary>,
    pub(crate) seconds: Seconds,
    pub(crate) warnings: Vec<String>,
    pub(crate) files: [&'static str; 5],
}

#[derive(Debug, Serialize)]
pub(crate) struct QualitySummary {
    pub(crate) sampler: String,
    pub(crate) samples: usize,
    pub(crate) outside: usize,
    pub(crate) components: usize,
    pub(crate) covered: usize,
    pub(crate) nontrivial_components: usize,
    pub(crate) nontrivial_covered: usize,
    pub(crate) redundant: usize,
    pub(crate) median_spacing_s: Option<f64>,
    pub(crate) p3_slope: Option<f64>,
}

#[derive(Debug, Default, Serialize)]
pub(crate) struct Seconds {
    pub(crate) read: f64,
    pub(crate) find_loops: f64,
    pub(crate) sample: f64,
    pub(crate) write: f64,
    pub(crate) total: f64,
}

/// One line of the batch summary.
#[derive(Debug, Serialize)]
pub(crate) struct LogOutcome {
    pub(crate) name: String,
    pub(crate) source: String,
    pub(crate) ok: bool,
    pub(crate) error: Option<String>,
    pub(crate) summary: Option<LogSummary>,
}

#[derive(Debug, Serialize)]
pub(crate) struct BatchSummary<'a> {
    pub(crate) out: String,
    pub(crate) gamma: f64,
    pub(crate) metric: String,
    pub(crate) sampler: &'a str,
    pub(crate) sample_size: String,
    pub(crate) seed: u64,
    pub(crate) skip_trivial: bool,
    pub(crate) epsilon_s: f64,
    pub(crate) logs: usize,
    pub(crate) succeeded: usize,
    pub(crate) failed: usize,
    pub(crate) seconds: f64,
    pub(crate) results: &'a [LogOutcome],
}

/// The settings every log of the batch shares.
#[derive(Debug)]
struct Settings<'a> {
    args: &'a RunArgs,
    spec: MetricSpec,
    sampler: Sampler,
}

pub(crate) fn run(args: RunArgs) -> Result<ExitCode> {
    let start = Instant::now();
    let spec = args.engine.spec()?;
    let sampler = args.sampling.sampler()?;
    // Refused once, before any log is read, rather than once per log.
    loops_core::check_gamma(args.engine.gamma)?;
    loops_core::check_epsilon_s(args.sampling.epsilon_s)?;
    check_out(&args.out, args.force)?;
    if let Some(JsonTo::File(path)) = &args.json
        && path.exists()
        && !args.force
    {
        bail!("--json {} exists; pass --force to replace it", path.display());
    }
    let jobs = jobs(&args.logs, &args.out)?;
    guard::with_writes(|writes| writes.create_dir(&args.out))?;

    let settings = Settings { args: &args, spec, sampler };
    let batch = Batch::new(progress::Mode::detect(args.quiet), jobs.len());
    batch.println(&format!(
        "loops: {} log(s), gamma {} ({}), sampler {} ({}), results to {}",
        jobs.len(),
        args.engine.gamma,
        settings.spec.name(),
        settings.sampler.kind,
        size_text(settings.sampler.size),
        args.out.display()
    ));
    let outcomes: Vec<LogOutcome> = loops_core::with_threads(args.engine.threads, || {
        jobs.par_iter()
            .map(|job| {
                let log = batch.start(&job.name);
                let source = job.path.display().to_string();
                match process(job, &settings, &log) {
                    Ok(summary) => {
                        log.finish(true, &outcome_line(&summary));
                        LogOutcome { name: job.name.clone(), source, ok: true, error: None, summary: Some(summary) }
                    }
                    Err(error) => {
                        let message = format!("{error:#}");
                        log.finish(false, &message);
                        LogOutcome { name: job.name.clone(), source, ok: false, error: Some(message), summary: None }
                    }
                }
            })
            .collect()
    })?;
    batch.finish();

    let failed = outcomes.iter().filter(|o| !o.ok).count();
    let summary = BatchSummary {
        out: args.out.display().to_string(),
        gamma: args.engine.gamma,
        metric: settings.spec.name(),
        sampler: settings.sampler.kind.name(),
        sample_size: size_text(settings.sampler.size),
        seed: settings.sampler.seed,
        skip_trivial: settings.sampler.skip_trivial,
        epsilon_s: args.sampling.epsilon_s,
        logs: outcomes.len(),
        succeeded: outcomes.len() - failed,
        failed,
        seconds: start.elapsed().as_secs_f64(),
        results: &outcomes,
    };
    let json = serde_json::to_string_pretty(&summary)? + "\n";
    guard::write_atomically(&args.out.join("summary.json"), json.as_bytes(), true)?;
    guard::write_atomically(&args.out.join("index.html"), index::render(&summary).as_bytes(), true)?;

    if let Some(JsonTo::File(path)) = &args.json {
        guard::write_atomically(path, json.as_bytes(), args.force)?;
    }
    let mut stdout = std::io::stdout().lock();
    if args.json == Some(JsonTo::Stdout) {
        stdout.write_all(json.as_bytes())?;
    } else if !args.quiet {
        write_table(&mut stdout, &summary)?;
    }
    stdout.flush()?;
    Ok(if failed == 0 { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// Refuses an --out that holds something other than an earlier run's results, before any work.
fn check_out(out: &Path, force: bool) -> Result<()> {
    if out.exists() && !out.is_dir() {
        bail!("--out {} exists and is not a folder", out.display());
    }
    let has_entries =
        out.is_dir() && std::fs::read_dir(out).with_context(|| format!("reading {}", out.display()))?.next().is_some();
    if has_entries && !force {
        bail!("--out {} exists and is not empty; pass --force to replace the results of an earlier run", out.display());
    }
    Ok(())
}

/// A folder name per log: the file stem, with `-2`, `-3`, ... for repeated stems. Logs inside
/// --out are refused (results must never land on inputs).
fn jobs(logs: &[PathBuf], out: &Path) -> Result<Vec<Job>> {
    let out_abs = std::path::absolute(out).with_context(|| format!("resolving {}", out.display()))?;
    let mut names: Vec<String> = Vec::with_capacity(logs.len());
    let mut jobs = Vec::with_capacity(logs.len());
    for path in logs {
        let abs = std::path::absolute(path).with_context(|| format!("resolving {}", path.display()))?;
        if abs.starts_with(&out_abs) {
            bail!("{} lies inside --out {}; write the results elsewhere", path.display(), out.display());
        }
        let stem = path.file_stem().map_or_else(|| "log".to_owned(), |s| s.to_string_lossy().into_owned());
        let stem: String =
            stem.chars().map(|c| if c.is_control() || c == '/' || c == '\\' { '_' } else { c }).collect();
        let stem = if stem.starts_with('.') || stem.is_empty() { format!("log{stem}") } else { stem };
        let mut name = stem.clone();
        let mut k = 2;
        while names.contains(&name) || name == "index.html" || name == "summary.json" {
            name = format!("{stem}-{k}");
            k += 1;
        }
        names.push(name.clone());
        jobs.push(Job { path: path.clone(), name });
    }
    Ok(jobs)
}

/// Reads, finds, samples and writes one log.
fn process(job: &Job, settings: &Settings<'_>, log: &progress::Log<'_>) -> Result<LogSummary> {
    let args = settings.args;
    let spec = &settings.spec;
    let gamma = args.engine.gamma;
    let epsilon_s = args.sampling.epsilon_s;
    let source = job.path.display().to_string();
    let mut seconds = Seconds::default();
    let start = Instant::now();

    log.stage("reading");
    let (table, traj) = args.input.read_table(&job.path, spec)?;
    seconds.read = start.elapsed().as_secs_f64();

    log.stage(&format!("finding loops in {} poses", traj.len()));
    let clock = Instant::now();
    let loops = spec.find_loops(&traj, gamma).with_context(|| format!("finding loops in {source}"))?;
    seconds.find_loops = clock.elapsed().as_secs_f64();
    let loop_duration_s = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;

    log.stage("sampling");
    let clock = Instant::now();
    let samples = spec.sample_loops(&traj, &loops, &settings.sampler)?;
    let quality = sample_quality(&samples, &loops, epsilon_s)?;
    let comparison = compare_samplers(spec, &traj, &loops, &settings.sampler, samples.len(), epsilon_s)?;
    seconds.sample = clock.elapsed().as_secs_f64();

    log.stage("writing");
    let clock = Instant::now();
    let t = traj.timestamps_s();
    let (a, b) = (t[0], t[t.len() - 1]);
    let components = loops.components();
    let mut summary = LogSummary {
        name: job.name.clone(),
        source: source.clone(),
        poses: traj.len(),
        t0_s: a,
        span_s: traj.span_s(),
        metric: loops.metric_name().to_owned(),
        gamma,
        components: components.len(),
        nontrivial_components: components.iter().filter(|c| !c.trivial).count(),
        holes: components.iter().map(|c| c.holes).sum(),
        pair_count: loops.pair_count(),
        loop_area_s2: loops.loop_area(a, b, Selection::All, Side::Both, Scale::Seconds)?,
        loop_density_s: loops.loop_density(a, b, Selection::All, Side::Both, Scale::Seconds)?,
        sampler: samples.sampler().name().to_owned(),
        sample_size: size_text(settings.sampler.size),
        seed: settings.sampler.seed,
        skip_trivial: settings.sampler.skip_trivial,
        epsilon_s,
        samples: samples.len(),
        quality: quality_summary(samples.sampler(), &quality),
        comparison: comparison.iter().map(|(kind, q)| quality_summary(*kind, q)).collect(),
        seconds: Seconds::default(),
        warnings: loops
            .warnings()
            .iter()
            .map(ToString::to_string)
            .chain(samples.warnings().iter().map(ToString::to_string))
            .collect(),
        files: ["components.csv", "samples.csv", "loop_duration.csv", "summary.json", "report.html"],
    };
    let html = report::render(&ReportInput {
        name: &job.name,
        source: &source,
        table: &table,
        traj: &traj,
        metric: spec,
        loops: &loops,
        loop_duration_s: &loop_duration_s,
        samples: &samples,
        quality: &quality,
        comparison: &comparison,
        epsilon_s,
        skip_trivial: settings.sampler.skip_trivial,
        seconds: seconds.find_loops,
    });
    let files: [(&str, Vec<u8>); 4] = [
        ("components.csv", components_csv(&traj, &loops, &quality).into_bytes()),
        ("samples.csv", samples_csv(&samples)?),
        ("loop_duration.csv", loop_duration_csv(&table, &traj, &loop_duration_s).into_bytes()),
        ("report.html", html.into_bytes()),
    ];
    seconds.write = clock.elapsed().as_secs_f64();
    seconds.total = start.elapsed().as_secs_f64();
    summary.seconds = seconds;
    let json = serde_json::to_string_pretty(&summary)? + "\n";
    write_folder(&args.out, &job.name, &files, json.as_bytes(), args.force)?;
    Ok(summary)
}

/// Every compared sampler at the run's sample count and seed: the samples-per-component figure.
fn compare_samplers(
    spec: &MetricSpec,
    traj: &Trajectory,
    loops: &Loops,
    run: &Sampler,
    count: usize,
    epsilon_s: f64,
) -> Result<Vec<(SamplerKind, SampleQuality)>> {
    let mut kinds: Vec<SamplerKind> = COMPARED.to_vec();
    if !kinds.contains(&run.kind) {
        kinds.push(run.kind);
    }
    kinds
        .into_iter()
        .map(|kind| {
            let sampler = Sampler { kind, size: SampleSize::Budget(count.max(1)), ..run.clone() };
            let samples = spec.sample_loops(traj, loops, &sampler)?;
            Ok((kind, sample_quality(&samples, loops, epsilon_s)?))
        })
        .collect()
}

/// Writes one log's files into a staging folder, then renames it to `out/name`.
fn write_folder(out: &Path, name: &str, files: &[(&str, Vec<u8>)], summary: &[u8], force: bool) -> Result<()> {
    let staged = out.join(format!(".{name}.partial-{}", std::process::id()));
    guard::with_writes(|writes| writes.stage(&staged))?;
    let written = files
        .iter()
        .map(|(file, bytes)| (*file, bytes.as_slice()))
        .chain([(MARKER, summary)])
        .try_for_each(|(file, bytes)| guard::write_atomically(&staged.join(file), bytes, false));
    guard::with_writes(|writes| match written {
        Ok(()) => writes.commit(&staged, &out.join(name), force, MARKER),
        Err(error) => {
            writes.discard(&staged);
            Err(error)
        }
    })
}

fn quality_summary(kind: SamplerKind, q: &SampleQuality) -> QualitySummary {
    QualitySummary {
        sampler: kind.name().to_owned(),
        samples: q.samples,
        outside: q.outside,
        components: q.components,
        covered: q.covered,
        nontrivial_components: q.nontrivial_components,
        nontrivial_covered: q.nontrivial_covered,
        redundant: q.redundant,
        median_spacing_s: q.median_spacing_s,
        p3_slope: q.p3_slope,
    }
}

fn size_text(size: SampleSize) -> String {
    match size {
        SampleSize::Budget(b) => format!("budget {b}"),
        SampleSize::Rate(r) => format!("rate {r}"),
    }
}

/// The header of components.csv.
/// The names are those of the Python API's `Loops.components` columns, plus `samples`.
pub(crate) const COMPONENTS_HEADER: &str = "id,trivial,area_s2,pair_count,run_count,holes,i_min,i_max,j_min,j_max,\
    t_min_s,t_max_s,t_prime_min_s,t_prime_max_s,closest_i,closest_j,closest_distance,samples";

/// components.csv: one row per component in id order; times are the poses' own timestamps.
fn components_csv(traj: &Trajectory, loops: &Loops, quality: &SampleQuality) -> String {
    let t = traj.timestamps_s();
    let mut csv = String::with_capacity(64 * (loops.components().len() + 1));
    csv.push_str(COMPONENTS_HEADER);
    csv.push('\n');
    for c in loops.components() {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.id,
            c.trivial,
            c.area_s2,
            c.pair_count,
            c.run_count,
            c.holes,
            c.i_range[0],
            c.i_range[1],
            c.j_range[0],
            c.j_range[1],
            t[c.i_range[0]],
            t[c.i_range[1]],
            t[c.j_range[0]],
            t[c.j_range[1]],
            c.closest_pair[0],
            c.closest_pair[1],
            c.closest_distance,
            quality.per_component.get(c.id).copied().unwrap_or(0)
        );
    }
    csv
}

/// loop_duration.csv: τ of every pose, with its time and position.
fn loop_duration_csv(table: &loops_io::PoseTable, traj: &Trajectory, loop_duration_s: &[f64]) -> String {
    let mut csv = String::with_capacity(48 * (traj.len() + 1));
    csv.push_str("index,t_s,x,y,z,loop_duration_s\n");
    for (i, (&t, &tau)) in traj.timestamps_s().iter().zip(loop_duration_s).enumerate() {
        let [x, y, z] = table.positions.get(i).copied().unwrap_or([f64::NAN; 3]);
        let _ = writeln!(csv, "{i},{t},{x},{y},{z},{tau}");
    }
    csv
}

fn samples_csv(samples: &Samples) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    loops_io::samples_to_csv(samples, &mut bytes)?;
    Ok(bytes)
}

fn outcome_line(s: &LogSummary) -> String {
    format!(
        "{} poses, {} components ({} non-trivial), {} samples, P1 {}/{}, {:.2} s",
        s.poses,
        s.components,
        s.nontrivial_components,
        s.samples,
        s.quality.nontrivial_covered,
        s.quality.nontrivial_components,
        s.seconds.total
    )
}

/// The batch table on stdout.
fn write_table(out: &mut impl Write, batch: &BatchSummary<'_>) -> Result<()> {
    writeln!(
        out,
        "{} log(s): {} done, {} failed, in {:.2} s; results in {}",
        batch.logs, batch.succeeded, batch.failed, batch.seconds, batch.out
    )?;
    let width = batch.results.iter().map(|r| r.name.chars().count()).max().unwrap_or(3).max(3);
    writeln!(
        out,
        "{:<width$}  {:>9}  {:>9}  {:>10}  {:>11}  {:>8}  {:>9}  {:>8}",
        "log", "poses", "span (s)", "components", "non-trivial", "samples", "P1", "time (s)"
    )?;
    for r in batch.results {
        match &r.summary {
            Some(s) => writeln!(
                out,
                "{:<width$}  {:>9}  {:>9.1}  {:>10}  {:>11}  {:>8}  {:>9}  {:>8.2}",
                r.name,
                s.poses,
                s.span_s,
                s.components,
                s.nontrivial_components,
                s.samples,
                format!("{}/{}", s.quality.nontrivial_covered, s.quality.nontrivial_components),
                s.seconds.total
            )?,
            None => writeln!(out, "{:<width$}  failed: {}", r.name, r.error.as_deref().unwrap_or("unknown error"))?,
        }
    }
    writeln!(out, "wrote {}", Path::new(&batch.out).join("index.html").display())?;
    Ok(())
}

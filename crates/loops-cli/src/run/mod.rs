//! `loops run`: many pose logs in one go, each to its own folder of results and a report, with
//! an index page and a summary for the batch.
//!
//! Logs are processed in parallel (and each one's engine in parallel within it) on the
//! `--threads` pool. A log that fails is reported and the others go on; the exit code is 1 when
//! any failed. Each log's files are written into a hidden staging folder that is renamed to the
//! log's name when all are written (see [`crate::guard`]), so a folder is whole or absent. One
//! run at a time owns `--out`, and `--force` replaces only what `loops run` wrote there (see
//! [`crate::out_dir`]). The files themselves are loops-io's.

mod index;
mod summary;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use loops_core::{MetricSpec, Sampler, Scale, Selection, Separation, Side, Trajectory, sample_quality};
use loops_io::{PoseTable, QualitySummary, SamplesFormat, WriteError};
use rayon::prelude::*;

pub(crate) use summary::{BatchSummary, LogOutcome, LogSummary, Seconds, SettingsSummary, size_text, warnings};

use crate::args::{Analysis, AnalysisArgs, InputArgs, JsonTo};
use crate::guard;
use crate::out_dir::{self, OutDir};
use crate::progress::{self, Batch};
use crate::report::{self, ReportInput};

/// The file each log folder of `loops run` holds (it is replaced with `--force` only when it
/// holds it, and the marker of --out lists it).
const LOG_SUMMARY: &str = "summary.json";

/// The files of each log's folder, and those --mcap adds.
const LOG_FILES: [&str; 5] = ["components.csv", "samples.csv", "loop_duration.csv", "summary.json", "report.html"];
pub(crate) const MCAP_FILES: [&str; 2] = ["results.mcap", loops_io::FOXGLOVE_LAYOUT_FILE];

/// Process many pose logs: per log its components, samples, loop durations, a summary and
/// an HTML report, in a folder of its own; for the batch an index page and a summary.
/// Logs run in parallel; one that fails is reported and the others go on (exit code 1).
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    mut_arg("out", |arg| arg.help(
        "The folder for the results: a folder per log (components.csv, samples.csv, loop_duration.csv, summary.json, \
         report.html), index.html and summary.json"
    )),
    mut_arg("force", |arg| arg.help(
        "Replace the results of an earlier run in --out (only folders and files `loops run` wrote)"
    )),
    mut_arg("json", |arg| arg.help(
        "Also write the batch summary (summary.json of --out) to FILE; `-` prints it on stdout instead of the table"
    )),
    after_help = "Examples:\n  \
    loops run logs/*.mcap --gamma 40 --out results\n  \
    loops run logs/*.mcap --gamma 40 --sampler rho --budget 2000 --out results --force\n  \
    loops run a.mcap b.tum --gamma 0.5 --metric 'se3(rotation_weight_m_per_rad=1)' --out results --json -\n  \
    loops run night/*.mcap --topic /odom --gamma 10 --out night-results --quiet\n  \
    loops run drive.mcap --gamma 40 --out results --mcap   # results/drive/results.mcap for Foxglove\n\n\
    Per log (results/<log>/): components.csv, samples.csv, loop_duration.csv, summary.json,\n\
    report.html; with --mcap also results.mcap and foxglove-layout.json (open both in Foxglove).\n\
    For the batch: results/index.html and results/summary.json. Ctrl-C keeps the logs already\n\
    finished and removes the rest; nothing half-written is left."
)]
pub(crate) struct RunArgs {
    /// The pose logs: MCAP, or any format `loops info` reads (TUM, CSV, KITTI, EuRoC, TUC, g2o).
    #[arg(required = true, value_name = "LOG")]
    logs: Vec<PathBuf>,
    #[command(flatten)]
    analysis: AnalysisArgs,
    #[command(flatten)]
    results: ResultsArgs,
}

/// One log of the batch and the folder its results go to.
#[derive(Debug)]
struct Job {
    path: PathBuf,
    /// The log's folder name in --out: its name (a bag's folder name), made unique in the batch.
    name: String,
}

/// The settings every log of the batch shares (every session's page of `loops fleet`).
#[derive(Debug)]
pub(crate) struct Settings<'a> {
    pub(crate) input: &'a InputArgs,
    pub(crate) gamma: f64,
    pub(crate) epsilon_s: f64,
    pub(crate) spec: MetricSpec,
    pub(crate) sampler: Sampler,
    pub(crate) separation: Separation,
    /// Whether to write results.mcap and foxglove-layout.json (--mcap).
    pub(crate) mcap: bool,
    /// Whether results.mcap holds the log itself too (--merge-log).
    pub(crate) merge_log: bool,
    /// --out, and the folder held (which knows whether --force was given).
    pub(crate) out_path: &'a Path,
    pub(crate) out: &'a OutDir,
}

impl<'a> Settings<'a> {
    /// The settings of the flags `args`, as `checked`, with the results going to `out`.
    pub(crate) fn new(args: &'a AnalysisArgs, checked: Analysis, results: &'a ResultsArgs, out: &'a OutDir) -> Self {
        let Analysis { spec, sampler, separation } = checked;
        Self {
            input: &args.input,
            gamma: args.engine.gamma,
            epsilon_s: args.sampling.epsilon_s,
            spec,
            sampler,
            separation,
            mcap: results.mcap,
            merge_log: results.merge_log,
            out_path: &results.out,
            out,
        }
    }

    /// The settings as summary.json states them, for a result under the metric named `metric`
    /// with `separation`.
    pub(crate) fn summary(&self, metric: String, separation: Separation) -> SettingsSummary {
        SettingsSummary::new(metric, self.gamma, separation, &self.sampler, self.epsilon_s)
    }
}

pub(crate) fn run(args: RunArgs) -> Result<u8> {
    let start = Instant::now();
    // Refused once, before any log is read, rather than once per log.
    let checked = args.analysis.checked()?;
    let results = &args.results;
    results.check(&args.logs)?;
    let jobs = jobs(&args.logs);
    guard::with_writes(|writes| writes.create_dir(&results.out))?;
    let out = out_dir::take(&results.out, results.force, out_dir::RUN)?;

    let settings = Settings::new(&args.analysis, checked, results, &out);
    let batch = Batch::new(progress::Mode::detect(results.quiet), jobs.len());
    batch.println(&format!(
        "loops: {} log(s), gamma {} ({}), sampler {} ({}), results to {}",
        jobs.len(),
        settings.gamma,
        settings.spec.name(),
        settings.sampler.kind,
        size_text(settings.sampler.size),
        results.out.display()
    ));
    batch.println(&format!("loops: {}", crate::args::separation_line(settings.separation, settings.gamma)));
    let outcomes: Vec<LogOutcome> = loops_core::with_threads(args.analysis.engine.threads, || {
        jobs.par_iter()
            .map(|job| {
                let log = batch.start(&job.name);
                let done = process(job, &settings, &log);
                outcome(&job.name, &job.path.display().to_string(), done, log)
            })
            .collect()
    })?;
    batch.finish();

    let failed = outcomes.iter().filter(|o| !o.ok).count();
    let summary = BatchSummary {
        out: results.out.display().to_string(),
        settings: settings.summary(settings.spec.name(), settings.separation),
        logs: outcomes.len(),
        succeeded: outcomes.len() - failed,
        failed,
        seconds: start.elapsed().as_secs_f64(),
        results: &outcomes,
    };
    let json = serde_json::to_string_pretty(&summary)? + "\n";
    results.write(&out, &json, &index::render(&summary), |stdout| write_table(stdout, &summary))?;
    Ok(if failed == 0 { 0 } else { 1 })
}

/// The flags of `loops run` and `loops fleet` about their results: the folder, `--force`,
/// `--quiet` and `--json`. Each command words the help of `--out`, `--force` and `--json` for
/// itself (`mut_arg`); the words here are what they share.
#[derive(Debug, Args)]
pub(crate) struct ResultsArgs {
    /// The folder for the results.
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Replace the results of an earlier run in --out (only what it wrote there).
    #[arg(long)]
    pub(crate) force: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub(crate) quiet: bool,
    /// Also write the summary (summary.json of --out) to FILE; `-` prints it on stdout instead of
    /// the table.
    #[arg(long, value_name = "FILE")]
    pub(crate) json: Option<JsonTo>,
    /// Also write the results for Foxglove and RViz: results.mcap (trajectory, components,
    /// candidates, τ, the (t, t′) plane, a ROS 2 MarkerArray) and foxglove-layout.json beside
    /// each report.
    #[arg(long)]
    pub(crate) mcap: bool,
    /// With --mcap, merge each MCAP log into its own results.mcap (its schemas, channels,
    /// messages, attachments and metadata as they are; a fleet: each session's folder), so that
    /// the loops play back over the recorded data.
    #[arg(long, requires = "mcap")]
    pub(crate) merge_log: bool,
}

impl ResultsArgs {
    /// Refuses, before anything is read: an --out that is a file, a `--json FILE` that exists
    /// without --force, and either of them on one of the `inputs` (or --out inside one, or one
    /// inside --out).
    pub(crate) fn check(&self, inputs: &[PathBuf]) -> Result<()> {
        if self.out.exists() && !self.out.is_dir() {
            bail!("--out {} exists and is not a folder", self.out.display());
        }
        let json = JsonTo::file(&self.json);
        out_dir::refuse_outputs_on_inputs([("--out", Some(self.out.as_path())), ("--json", json)], inputs)?;
        if let Some(JsonTo::File(path)) = &self.json
            && path.exists()
            && !self.force
        {
            bail!("--json {} exists; pass --force to replace it", path.display());
        }
        Ok(())
    }

    /// Writes the command's `summary.json` (`json`) and `index.html` (`html`) at the top of
    /// --out, the `--json FILE` copy, and on stdout the JSON (`--json -`) or, unless --quiet, the
    /// command's table (`table`).
    pub(crate) fn write(
        &self,
        out: &OutDir,
        json: &str,
        html: &str,
        table: impl FnOnce(&mut std::io::StdoutLock<'static>) -> Result<()>,
    ) -> Result<()> {
        // Both are ours (OutDir::take refused a user's): listed, then replaced.
        for (name, bytes) in [("summary.json", json.as_bytes()), ("index.html", html.as_bytes())] {
            out_dir::write_file(out, name, |file| file.write_all(bytes))?;
        }
        if let Some(JsonTo::File(path)) = &self.json {
            write_file(path, json.as_bytes(), self.force)?;
        }
        let mut stdout = std::io::stdout().lock();
        if self.json == Some(JsonTo::Stdout) {
            stdout.write_all(json.as_bytes())?;
        } else if !self.quiet {
            table(&mut stdout)?;
        }
        stdout.flush()?;
        Ok(())
    }
}

/// A folder name per log: its name ([`loops_io::log_name`]: the file stem, or a rosbag2 bag's
/// folder name however the bag is given), with `-2`, `-3`, ... for repeated names and for the
/// names `loops run` keeps for itself ([`out_dir::Tool::reserves`]: `index.html`,
/// `loops-run.json`, ...). (Logs inside --out were refused by [`ResultsArgs::check`].)
fn jobs(logs: &[PathBuf]) -> Vec<Job> {
    let mut names: Vec<String> = Vec::with_capacity(logs.len());
    let mut jobs = Vec::with_capacity(logs.len());
    for path in logs {
        let stem = loops_io::log_name(path);
        let stem: String =
            stem.chars().map(|c| if c.is_control() || c == '/' || c == '\\' { '_' } else { c }).collect();
        let stem = if stem.starts_with('.') || stem.is_empty() { format!("log{stem}") } else { stem };
        let mut name = stem.clone();
        let mut k = 2;
        while names.contains(&name) || out_dir::RUN.reserves(&name) {
            name = format!("{stem}-{k}");
            k += 1;
        }
        names.push(name.clone());
        jobs.push(Job { path: path.clone(), name });
    }
    jobs
}

/// Reads, finds, samples and writes one log.
fn process(job: &Job, settings: &Settings<'_>, log: &progress::Log<'_>) -> Result<LogSummary> {
    let start = Instant::now();
    log.stage("reading");
    let (table, traj) = settings.input.read_table(std::slice::from_ref(&job.path), &settings.spec)?;
    let read_s = start.elapsed().as_secs_f64();
    analyse(&job.name, &job.path.display().to_string(), &table, &traj, read_s, settings, log)
}

/// Finds, samples and writes one trajectory already read (`table` as read, `traj` for the
/// engine; reading took `read_s` seconds): the folder `name` of --out, with the files and the
/// report of one log, and its summary. `source` names the file(s) it was read from.
pub(crate) fn analyse(
    name: &str,
    source: &str,
    table: &PoseTable,
    traj: &Trajectory,
    read_s: f64,
    settings: &Settings<'_>,
    log: &progress::Log<'_>,
) -> Result<LogSummary> {
    let spec = &settings.spec;
    let gamma = settings.gamma;
    let epsilon_s = settings.epsilon_s;
    let mut seconds = Seconds { read: read_s, ..Seconds::default() };
    let start = Instant::now();

    log.stage(&format!("finding loops in {} poses", traj.len()));
    let clock = Instant::now();
    let loops = spec
        .find_loops_separated(traj, gamma, settings.separation)
        .with_context(|| format!("finding loops in {source}"))?;
    seconds.find_loops = clock.elapsed().as_secs_f64();
    let loop_duration_s = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds)?;

    log.stage("sampling");
    let clock = Instant::now();
    let mut samples = spec.sample_loops(traj, &loops, &settings.sampler)?;
    // Where the poses are in the files and the report: the log's own positions, unless reading
    // dropped or merged poses.
    let fits = table.positions.len() == traj.len();
    let positions = if fits { table.positions.clone() } else { loops_io::point_positions(traj) };
    samples.set_positions(|k| positions.get(k).copied());
    let quality = sample_quality(&samples, &loops, epsilon_s)?;
    let comparison = loops_io::compare_samplers(spec, traj, &loops, &settings.sampler, samples.len(), epsilon_s)?;
    seconds.sample = clock.elapsed().as_secs_f64();

    log.stage("writing");
    let clock = Instant::now();
    let t = traj.timestamps_s();
    let (a, b) = (t[0], t[t.len() - 1]);
    let components = loops.components();
    let mut summary = LogSummary {
        name: name.to_owned(),
        source: source.to_owned(),
        poses: traj.len(),
        t0_s: a,
        span_s: traj.span_s(),
        settings: settings.summary(loops.metric_name().to_owned(), loops.separation()),
        components: components.len(),
        nontrivial_components: components.iter().filter(|c| !c.trivial).count(),
        holes: components.iter().map(|c| c.holes).sum(),
        pair_count: loops.pair_count(),
        pose_pair_count: loops.pose_pair_count(),
        loop_area_s2: loops.loop_area(a, b, Selection::All, Side::Both, Scale::Seconds)?,
        loop_density_s: loops.loop_density(a, b, Selection::All, Side::Both, Scale::Seconds)?,
        samples: samples.len(),
        quality: QualitySummary::new(samples.sampler(), &quality),
        comparison: comparison.iter().map(|(kind, q)| QualitySummary::new(*kind, q)).collect(),
        seconds: Seconds::default(),
        warnings: warnings(&loops, &samples),
        files: [&LOG_FILES[..], if settings.mcap { &MCAP_FILES[..] } else { &[] }].concat(),
    };
    let html = report::render(&ReportInput {
        name,
        source,
        table,
        plane: settings.input.plane()?.unwrap_or([0, 1]),
        traj,
        metric: spec,
        measured: &settings.input.measured(table, traj),
        loops: &loops,
        loop_duration_s: &loop_duration_s,
        samples: &samples,
        quality: &quality,
        comparison: &comparison,
        epsilon_s,
        skip_trivial: settings.sampler.skip_trivial,
        seconds: seconds.find_loops,
    });
    seconds.write = clock.elapsed().as_secs_f64();
    seconds.total = read_s + start.elapsed().as_secs_f64();
    summary.seconds = seconds;
    for warning in &summary.warnings {
        log.warn(warning);
    }
    let json = serde_json::to_string_pretty(&summary)? + "\n";
    let scene = if settings.mcap {
        // The log's own positions and orientations, unless reading dropped or merged poses.
        let positions = Some(table.positions.as_slice()).filter(|_| fits);
        let orientations = table.orientations_xyzw.as_deref().filter(|_| fits);
        Some(loops_io::Scene::of_trajectory(name, traj, positions, orientations, &loops, &samples)?)
    } else {
        None
    };
    write_folder(settings, name, |dir| {
        let file = |name: &str| dir.join(name);
        let per_component = Some(quality.per_component.as_slice());
        written(|| loops_io::write_components(file("components.csv"), &loops, Some(&positions), per_component, false))?;
        written(|| loops_io::write_samples(&file("samples.csv"), &samples, SamplesFormat::Csv, false))?;
        written(|| {
            let t = traj.timestamps_s();
            loops_io::write_loop_duration(file("loop_duration.csv"), t, &table.positions, &loop_duration_s, false)
        })?;
        write_file(&file("report.html"), html.as_bytes(), false)?;
        if let Some(scene) = &scene {
            if settings.merge_log {
                let log = Path::new(source);
                if !log.is_file() {
                    bail!("--merge-log merges one MCAP file a log; {source} is not one");
                }
                written(|| loops_io::write_scene_mcap_merged(file(MCAP_FILES[0]), scene, log, false))?;
            } else {
                written(|| loops_io::write_scene_mcap(file(MCAP_FILES[0]), scene, false))?;
            }
            write_file(&file(MCAP_FILES[1]), loops_io::FOXGLOVE_LAYOUT.as_bytes(), false)?;
        }
        write_file(&file(LOG_SUMMARY), json.as_bytes(), false)
    })?;
    Ok(summary)
}

/// The outcome of one log (`done`), said on its progress line `log`.
pub(crate) fn outcome(name: &str, source: &str, done: Result<LogSummary>, log: progress::Log<'_>) -> LogOutcome {
    let (name, source) = (name.to_owned(), source.to_owned());
    match done {
        Ok(summary) => {
            log.finish(true, &outcome_line(&summary));
            LogOutcome { name, source, ok: true, error: None, summary: Some(summary) }
        }
        Err(error) => {
            let message = format!("{error:#}");
            log.finish(false, &message);
            LogOutcome { name, source, ok: false, error: Some(message), summary: None }
        }
    }
}

/// Writes one log's files into a staging folder (`write`), then moves it into place as
/// `out/name` ([`out_dir::write_folder`]). An earlier folder of that name is replaced (with
/// --force) only when the marker of --out lists it and it still holds its `summary.json`.
fn write_folder(settings: &Settings<'_>, name: &str, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let owned = settings.out.owns(name) && settings.out_path.join(name).join(LOG_SUMMARY).is_file();
    out_dir::write_folder(settings.out, name, owned, write)
}

/// Writes `bytes` to `path` atomically ([`loops_io::write_atomically`]), under the write lock of
/// [`guard`]; an existing file is replaced only with `force`.
pub(crate) fn write_file(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    written(|| loops_io::write_atomically(path, force, |file| file.write_all(bytes)))
}

/// Runs one write of loops-io under the write lock of [`guard`], in the CLI's words.
fn written(write: impl FnOnce() -> Result<(), WriteError>) -> Result<()> {
    guard::with_writes(|_| write()).map_err(guard::write_error)
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

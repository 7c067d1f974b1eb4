//! `loops fleet`: several pose logs as one fleet (vehicles, days, robots in one frame): the loops
//! within each session and between every two, the sparse session-overlap matrix, one sampling
//! over all of them, and one report, beside a folder per session as `loops run` writes it.
//!
//! A command of its own rather than `loops run --fleet`: a batch runs its logs independently
//! (one that fails is reported and the others go on, exit code 1), where a fleet is one
//! computation over all of them (a session that cannot be read stops it, exit code 2); its
//! results are the fleet's own files at the top of `--out`, and its flags (`--session`,
//! `--between-only`, `--pruning`) would mean nothing to a batch. What the two share they share
//! in code: the reading, engine and sampling flags (`args`), the output folder's lock and
//! marker (`out_dir`, with the marker `loops-fleet.json`), and each session's folder, which is
//! exactly what `loops run` writes for that log alone (`run::analyse`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, anyhow, bail};
use clap::Args;
use loops_core::{
    SampleQuality, Samples, Trajectory,
    fleet::{Fleet, FleetComponent, FleetLoops, FleetOptions, FleetSample, Pruning},
    sample_quality,
};
use loops_io::{G2oOptions, PoseTable, QualitySummary};
use rayon::prelude::*;
use serde::Serialize;

use crate::args::{AnalysisArgs, source_name};
use crate::guard;
use crate::out_dir::{self, OutDir};
use crate::progress::{self, Batch};
use crate::run::{LogOutcome, ResultsArgs, Seconds, Settings, SettingsSummary};
use page::{FleetReportInput, render};

mod page;

/// `loops fleet` in its output folder: its marker, and the files it writes at the top.
const TOOL: out_dir::Tool = out_dir::FLEET;

/// Find the loops of several pose logs as one fleet: within each session and between every two
/// (where vehicles, days or robots overlap), the session-overlap matrix, one sampling over all,
/// and one report, with a folder per session as `loops run` writes it.
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    group(clap::ArgGroup::new("destination").args(["out", "store"]).required(true)),
    mut_arg("out", |arg| arg
        .help("The folder for the results: the fleet's files and a folder per session")
        .required(false)
        .default_value(".")
        .hide_default_value(true)),
    mut_arg("force", |arg| arg.help(
        "Replace the results of an earlier `loops fleet` in --out (only what it wrote there)"
    )),
    mut_arg("json", |arg| arg.help(
        "Also write the fleet's summary (summary.json of --out) to FILE; `-` prints it on stdout instead of the table"
    )),
    after_help = "Examples:\n  \
    loops synth fleet --vehicles 3 --days 2 --duration-s 900\n  \
    loops fleet fleet/*.mcap --gamma 40 --out fleet-results\n  \
    loops fleet fleet/*.mcap --gamma 40 --between-only --budget 500 --out merge --force\n  \
    loops fleet --session monday=mon_0.mcap,mon_1.mcap --session tuesday=tue.mcap --gamma 40 --out results\n  \
    loops fleet --store city fleet/*day1.mcap --gamma 40 --budget 500 --block 20000\n\n\
    In --out: index.html (the fleet's report), components.csv (every component, both sessions\n\
    by name and index, times on each session's clock), session_pairs.csv (the sparse overlap\n\
    matrix), samples.csv, samples.g2o (GTSAM Symbol keys: robot letter a, b, ... per session, up\n\
    to 26 sessions), summary.json, and a folder per session with what `loops run` writes for it\n\
    alone. Separation applies within a session; pairs of two sessions are all kept."
)]
pub(crate) struct FleetArgs {
    /// The pose logs, one session each, named by the file's stem (a rosbag2 bag by its folder's
    /// name); names must be unique.
    #[arg(value_name = "LOG", required_unless_present_any = ["sessions", "remove"])]
    logs: Vec<PathBuf>,
    /// A session of several files, or a name of your choice: NAME=FILE[,FILE...]. The files are
    /// read as one trajectory, as `loops components A B` reads them (MCAP parts merged by time,
    /// other files joined in time order). Repeat for more; these sessions follow the LOGs.
    #[arg(long = "session", value_name = "NAME=FILE[,FILE...]")]
    sessions: Vec<String>,
    #[command(flatten)]
    analysis: AnalysisArgs,
    /// Sample only pairs of two different sessions (map merging): the budget goes to the places
    /// where sessions overlap (any sampler but the baselines).
    #[arg(long)]
    between_only: bool,
    /// Far-field pruning: auto, hierarchy or kd-tree (auto: a KD-tree over chunk balls for
    /// euclidean positions of 1 to 3 coordinates, else the ball hierarchy). Results do not depend
    /// on it.
    #[arg(long, default_value_t = Pruning::default().name().to_owned())]
    pruning: String,
    /// Keep the fleet in the store DIR instead of --out: add the sessions (replacing those of
    /// the same name), scan only the tiles that hold them, and write the store's Parquet tables
    /// (sessions, tiles, components, session_pairs, loop_duration, samples). A missing or empty
    /// DIR is made with the settings given; later runs must give the same.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["force", "json"])]
    store: Option<PathBuf>,
    /// With --store: remove the session NAME from the store (repeat for more).
    #[arg(long, value_name = "NAME", requires = "store")]
    remove: Vec<String>,
    /// With --store: poses per block of a session (tiles are blocks × blocks), fixed when the
    /// store is made.
    #[arg(
        long,
        value_name = "POSES",
        requires = "store",
        default_value_t = loops_core::store::StoreSettings::DEFAULT_BLOCK
    )]
    block: usize,
    #[command(flatten)]
    results: ResultsArgs,
}

/// A session as given: its name and its file(s).
#[derive(Debug)]
struct SessionSpec {
    name: String,
    files: Vec<PathBuf>,
    /// How it was given, for messages: the file, or `--session NAME=...`.
    given: String,
}

/// One session in summary.json.
#[derive(Debug, Serialize)]
pub(crate) struct SessionSummary {
    pub(crate) name: String,
    pub(crate) source: String,
    pub(crate) poses: usize,
    pub(crate) t0_s: f64,
    pub(crate) span_s: f64,
    /// Loop components within the session (its own).
    pub(crate) within_components: usize,
    /// Loop components between it and another session.
    pub(crate) between_components: usize,
    /// The fleet's samples with a pose in it.
    pub(crate) samples: usize,
}

/// Where the fleet's time went, seconds: the stages of a log's, and the sessions' pages.
#[derive(Debug, Default, Serialize)]
pub(crate) struct FleetSeconds {
    #[serde(flatten)]
    pub(crate) stages: Seconds,
    pub(crate) pages: f64,
}

/// summary.json of the fleet.
#[derive(Debug, Serialize)]
pub(crate) struct FleetSummary<'a> {
    pub(crate) out: String,
    pub(crate) poses: usize,
    #[serde(flatten)]
    pub(crate) settings: SettingsSummary,
    pub(crate) pruning: &'static str,
    pub(crate) components: usize,
    pub(crate) within_components: usize,
    pub(crate) between_components: usize,
    /// Pairs of two different sessions with at least one component between them.
    pub(crate) overlapping_session_pairs: usize,
    pub(crate) between_only: bool,
    pub(crate) samples: usize,
    pub(crate) between_samples: usize,
    /// P1–P3 of the samples against every component of the fleet.
    pub(crate) quality: QualitySummary,
    /// Components between sessions holding a sample (P1 between sessions).
    pub(crate) between_covered: usize,
    pub(crate) sessions: Vec<SessionSummary>,
    pub(crate) warnings: Vec<String>,
    pub(crate) seconds: FleetSeconds,
    pub(crate) files: Vec<&'static str>,
    /// Each session's folder: `loops run`'s summary of the session alone.
    pub(crate) pages: &'a [LogOutcome],
}

pub(crate) fn fleet(args: FleetArgs) -> Result<u8> {
    let start = Instant::now();
    let checked = args.analysis.checked()?;
    let (spec, sampler, separation) = (checked.spec, checked.sampler.clone(), checked.separation);
    let (input, gamma) = (&args.analysis.input, args.analysis.engine.gamma);
    let pruning: Pruning = args.pruning.parse()?;
    if args.between_only && sampler.kind.is_baseline() {
        bail!(
            "--between-only does not apply to the {} baseline: its rule knows no components; use --sampler one, \
             rho, rho-dispersed or alpha",
            sampler.kind
        );
    }
    if let Some(store) = &args.store {
        return fleet_store(&args, store);
    }
    let results = &args.results;
    let specs = sessions(&args)?;
    let inputs: Vec<PathBuf> = specs.iter().flat_map(|s| s.files.iter().cloned()).collect();
    results.check(&inputs)?;
    loops_io::out_dir::refuse_non_empty(&results.out, results.force, TOOL)?;

    let batch = Batch::new(progress::Mode::detect(results.quiet), specs.len() + 1);
    let mut seconds = FleetSeconds::default();
    let result = loops_core::with_threads(args.analysis.engine.threads, || -> Result<u8> {
        // The sessions are read, and fit one fleet, before anything is written or printed: a
        // fleet that cannot be made is one line on stderr, and no --out.
        let log = batch.start("fleet");
        log.stage(&format!("reading {} sessions", specs.len()));
        let clock = Instant::now();
        let read: Vec<(PoseTable, Trajectory)> = specs
            .par_iter()
            .map(|s| input.read_table(&s.files, &spec))
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<_>>()?;
        seconds.stages.read = clock.elapsed().as_secs_f64();
        let sources: Vec<String> = specs.iter().map(|s| source_name(&s.files)).collect();
        let (tables, trajectories): (Vec<PoseTable>, Vec<Trajectory>) = read.into_iter().unzip();
        let fleet = Fleet::new(specs.iter().map(|s| s.name.clone()).zip(trajectories).collect())
            .map_err(|error| mismatch(error, &specs, &sources))?;

        guard::with_writes(|writes| writes.create_dir(&results.out))?;
        let out = out_dir::take(&results.out, results.force, TOOL)?;
        batch.println(&format!(
            "loops: fleet of {} session(s), {} poses, gamma {} ({}), sampler {} ({}{}), results to {}",
            fleet.len(),
            fleet.poses(),
            gamma,
            spec.name(),
            sampler.kind,
            crate::run::size_text(sampler.size),
            if args.between_only { ", between sessions only" } else { "" },
            results.out.display()
        ));
        batch.println(&format!(
            "loops: {} within a session; pairs of two sessions are all kept",
            crate::args::separation_line(separation, gamma)
        ));

        log.stage(&format!("finding loops in {} poses", fleet.poses()));
        let clock = Instant::now();
        let options = FleetOptions { separation, pruning, chunk_radius: None };
        let loops = spec.find_fleet_loops(&fleet, gamma, &options)?;
        seconds.stages.find_loops = clock.elapsed().as_secs_f64();
        batch.println(&format!(
            "loops: pruning {}{}",
            loops.pruning().name(),
            if pruning == Pruning::Auto { " (auto; --pruning to choose)" } else { "" }
        ));

        log.stage("sampling");
        let clock = Instant::now();
        let samples = spec.sample_fleet(&fleet, &loops, &sampler, args.between_only)?;
        let quality = sample_quality(&samples, loops.loops(), args.analysis.sampling.epsilon_s)?;
        let localized = fleet.localize(&samples)?;
        seconds.stages.sample = clock.elapsed().as_secs_f64();

        log.stage("writing");
        let clock = Instant::now();
        let components = loops.components();
        let pairs = loops.session_pairs();
        let positions = session_positions(&fleet, &tables);
        let g2o = write_fleet_files(&out, &fleet, &loops, &samples, &quality, &tables, &positions, &localized)?;
        write_fleet_scene(&out, results.mcap, &fleet, &loops, &samples, &positions)?;
        seconds.stages.write = clock.elapsed().as_secs_f64();
        let between = components.iter().filter(|c| c.sessions[0] != c.sessions[1]).count();
        let between_covered = components
            .iter()
            .filter(|c| c.sessions[0] != c.sessions[1] && quality.per_component.get(c.id).is_some_and(|&k| k > 0))
            .count();
        let between_samples = localized.iter().filter(|s| s.sessions[0] != s.sessions[1]).count();
        log.finish(
            true,
            &format!(
                "{} poses, {} components within sessions, {between} between sessions, {} samples, P1 {between_covered}/{between} between sessions, {:.2} s",
                fleet.poses(),
                components.len() - between,
                samples.len(),
                start.elapsed().as_secs_f64()
            ),
        );
        let warnings = crate::run::warnings(loops.loops(), &samples);
        for warning in &warnings {
            batch.println(&format!("loops: warning: fleet: {warning}"));
        }

        // Each session's folder: `loops run` on the session alone.
        let clock = Instant::now();
        let settings = Settings::new(&args.analysis, checked, results, &out);
        let pages: Vec<LogOutcome> = (0..fleet.len())
            .into_par_iter()
            .map(|a| {
                let name = &fleet.names()[a];
                let log = batch.start(name);
                let analysed =
                    crate::run::analyse(name, &sources[a], &tables[a], fleet.session(a), 0.0, &settings, &log);
                crate::run::outcome(name, &sources[a], analysed, log)
            })
            .collect();
        seconds.pages = clock.elapsed().as_secs_f64();
        batch.finish();

        let sessions = session_summaries(&fleet, &sources, &components, &localized);
        let failed = pages.iter().filter(|p| !p.ok).count();
        let mut summary = FleetSummary {
            out: results.out.display().to_string(),
            poses: fleet.poses(),
            settings: settings.summary(spec.name(), separation),
            pruning: loops.pruning().name(),
            components: components.len(),
            within_components: components.len() - between,
            between_components: between,
            overlapping_session_pairs: pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).count(),
            between_only: args.between_only,
            samples: samples.len(),
            between_samples,
            quality: QualitySummary::new(samples.sampler(), &quality),
            between_covered,
            sessions,
            warnings,
            seconds: FleetSeconds::default(),
            files: TOOL
                .top_files
                .iter()
                .copied()
                .filter(|&f| (f != "samples.g2o" || g2o) && (results.mcap || !crate::run::MCAP_FILES.contains(&f)))
                .collect(),
            pages: &pages,
        };
        let html = render(&FleetReportInput {
            fleet: &fleet,
            tables: &tables,
            plane: input.plane()?.unwrap_or([0, 1]),
            components: &components,
            pairs: &pairs,
            sampler: samples.sampler(),
            quality: &quality,
            summary: &summary,
        });
        seconds.stages.total = start.elapsed().as_secs_f64();
        summary.seconds = seconds;
        let json = serde_json::to_string_pretty(&summary)? + "\n";
        results.write(&out, &json, &html, |stdout| write_table(stdout, &summary))?;
        Ok(if failed == 0 { 0 } else { 1 })
    });
    let result = result.map_err(anyhow::Error::from).and_then(|code| code);
    if result.is_err() {
        batch.finish();
    }
    result
}

/// `loops fleet --store DIR`: the sessions read (every one before the store is touched, so that
/// a log that cannot be read is one line on stderr and the store unchanged), then one update of
/// the store ([`loops_io::store::update_store`]).
fn fleet_store(args: &FleetArgs, dir: &Path) -> Result<u8> {
    let start = Instant::now();
    let checked = args.analysis.checked()?;
    let (spec, sampler, separation) = (checked.spec, checked.sampler.clone(), checked.separation);
    let (input, gamma) = (&args.analysis.input, args.analysis.engine.gamma);
    let specs = sessions(args)?;
    let inputs: Vec<PathBuf> = specs.iter().flat_map(|s| s.files.iter().cloned()).collect();
    if dir.exists() && !dir.is_dir() {
        bail!("--store {} exists and is not a folder", dir.display());
    }
    out_dir::refuse_outputs_on_inputs([("--store", Some(dir))], &inputs)?;
    let config = loops_io::store::StoreConfig {
        settings: loops_core::store::StoreSettings { metric: spec, gamma, separation, block: args.block },
        sampler: Some((sampler, args.between_only)),
    };
    config.settings.check()?;
    let report = loops_core::with_threads(args.analysis.engine.threads, || -> Result<_> {
        let put: Vec<(String, Trajectory)> = specs
            .par_iter()
            .map(|s| input.read_table(&s.files, &spec).map(|(_, trajectory)| (s.name.clone(), trajectory)))
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<_>>()?;
        Ok(loops_io::store::update_store(dir, Some(&config), put, &args.remove)?)
    })??;
    let update = &report.update;
    if update.changes_nothing() {
        if !args.results.quiet {
            println!(
                "loops: store {}: nothing changed, nothing written: {} stored as given ({}); {} sessions, {} \
                 components, {:.2} s",
                dir.display(),
                update.unchanged.len(),
                update.unchanged.join(", "),
                report.stored.store.sessions().len(),
                report.components,
                start.elapsed().as_secs_f64()
            );
        }
        return Ok(0);
    }
    let list = |what: &str, names: &[String]| (!names.is_empty()).then(|| format!("{what} {}", names.join(", ")));
    let done: Vec<String> = [
        list("added", &update.added),
        list("replaced", &update.replaced),
        list("removed", &update.removed),
        list("unchanged", &update.unchanged),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !args.results.quiet {
        println!(
            "loops: store {}: {}; {} tiles scanned, {} kept, {} dropped; {} sessions, {} components ({} of the \
             sessions changed), {} samples, {:.2} s",
            dir.display(),
            done.join("; "),
            update.tiles_scanned,
            update.tiles_kept,
            update.tiles_dropped,
            report.stored.store.sessions().len(),
            report.components,
            report.added_components,
            report.samples.as_ref().map_or(0, |s| s.rows.len()),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(0)
}

/// The sessions as given: each LOG, then each --session, with unique names that can name a
/// folder of --out.
fn sessions(args: &FleetArgs) -> Result<Vec<SessionSpec>> {
    let mut specs: Vec<SessionSpec> = Vec::new();
    for path in &args.logs {
        let given = path.display().to_string();
        specs.push(SessionSpec { name: session_name(path), files: vec![path.clone()], given });
    }
    for text in &args.sessions {
        let Some((name, files)) = text.split_once('=') else {
            bail!("--session {text}: expected NAME=FILE[,FILE...]");
        };
        let files: Vec<PathBuf> = files.split(',').filter(|f| !f.is_empty()).map(PathBuf::from).collect();
        if files.is_empty() {
            bail!("--session {text}: no file given for session {name:?}");
        }
        specs.push(SessionSpec { name: name.to_owned(), files, given: format!("--session {text}") });
    }
    for (k, spec) in specs.iter().enumerate() {
        if let Some(first) = specs[..k].iter().find(|s| s.name == spec.name) {
            bail!(
                "two sessions are named {:?} ({} and {}): session names must be unique; name them with --session \
                 NAME=FILE",
                spec.name,
                first.given,
                spec.given
            );
        }
        // Each session's folder is a `loops run` folder: neither command's own names can name it.
        let reserved = TOOL.reserves(&spec.name) || out_dir::RUN.reserves(&spec.name);
        if spec.name.is_empty()
            || spec.name.starts_with('.')
            || spec.name.contains(['/', '\\'])
            || spec.name.chars().any(char::is_control)
            || reserved
        {
            bail!(
                "session name {:?} ({}) cannot name the session's folder in --out (empty, hidden, a path, or a file \
                 of the fleet's); name it with --session NAME=FILE",
                spec.name,
                spec.given
            );
        }
    }
    Ok(specs)
}

/// A session's name from its log: [`loops_io::log_name`], the file's stem, or a rosbag2 bag's
/// folder name however the bag is given (its folder, its metadata.yaml or a storage file).
fn session_name(path: &Path) -> String {
    loops_io::log_name(path)
}

/// The core's refusal of a session that does not fit the first, with both sessions' files.
fn mismatch(error: loops_core::Error, specs: &[SessionSpec], sources: &[String]) -> anyhow::Error {
    let loops_core::Error::SessionMismatch { session, what, .. } = &error else { return error.into() };
    let source = specs.iter().position(|s| &s.name == session).map_or("?", |k| sources[k].as_str());
    let hint = if *what == "dimension" { "; --axes A,B measures every session in one plane" } else { "" };
    anyhow!("{error} ({session}: {source}; the first: {}){hint}", sources[0])
}

/// Writes the fleet's files into --out (each listed in the marker first, then replaced
/// atomically); samples.g2o only for at most 26 sessions (the letters of its keys), otherwise
/// an earlier one of ours is removed and a line on stderr says why. Returns whether the g2o
/// file was written.
#[allow(clippy::too_many_arguments)]
fn write_fleet_files(
    out: &OutDir,
    fleet: &Fleet,
    loops: &FleetLoops,
    samples: &Samples,
    quality: &SampleQuality,
    tables: &[PoseTable],
    positions: &[Vec<[f64; 3]>],
    localized: &[FleetSample],
) -> Result<bool> {
    let write = |name: &str, fill: &dyn Fn(&mut std::fs::File) -> std::io::Result<()>| -> Result<()> {
        out_dir::write_file(out, name, fill)
    };
    let per_component = Some(quality.per_component.as_slice());
    write("components.csv", &|file| {
        loops_io::fleet_components_to_csv(fleet, loops, Some(positions), per_component, file)
    })?;
    write("session_pairs.csv", &|file| loops_io::session_pairs_to_csv(fleet, loops, file))?;
    write("samples.csv", &|file| loops_io::fleet_samples_to_csv(fleet, samples, file))?;
    if fleet.len() <= loops_io::GTSAM_ROBOT_LETTERS.len() {
        let refs: Vec<&PoseTable> = tables.iter().collect();
        let text = loops_io::fleet_g2o_edges_text(&refs, localized, &G2oOptions::default())?;
        write("samples.g2o", &|file| file.write_all(text.as_bytes()))?;
        Ok(true)
    } else {
        guard::with_writes(|_| out.remove("samples.g2o"))?;
        eprintln!(
            "loops: warning: samples.g2o not written: its GTSAM Symbol keys have one robot letter per session (a-z), for at \
             most {} sessions, and the fleet has {}",
            loops_io::GTSAM_ROBOT_LETTERS.len(),
            fleet.len()
        );
        Ok(false)
    }
}

/// Writes the fleet's results.mcap (every session's path, the components within and between
/// sessions, the samples, the joint (t, t′) plane) and foxglove-layout.json into --out with
/// `mcap` (--mcap); without it, removes those of an earlier run of ours, so that none is left
/// that does not match the other files.
fn write_fleet_scene(
    out: &OutDir,
    mcap: bool,
    fleet: &Fleet,
    loops: &FleetLoops,
    samples: &Samples,
    positions: &[Vec<[f64; 3]>],
) -> Result<()> {
    let [results, layout] = crate::run::MCAP_FILES;
    if !mcap {
        guard::with_writes(|_| out.remove(results).and_then(|_| out.remove(layout)))?;
        return Ok(());
    }
    let scene = loops_io::Scene::of_fleet(fleet, Some(positions), loops, samples)?;
    out_dir::write_file(out, results, |file| loops_io::scene_mcap_to(file, &scene))?;
    out_dir::write_file(out, layout, |file| file.write_all(loops_io::FOXGLOVE_LAYOUT.as_bytes()))
}

/// Where each session's poses are in the files and the scene: its log's own positions, unless
/// reading dropped or merged poses (then its trajectory's points), as for a single log.
fn session_positions(fleet: &Fleet, tables: &[PoseTable]) -> Vec<Vec<[f64; 3]>> {
    tables
        .iter()
        .enumerate()
        .map(|(a, table)| {
            let session = fleet.session(a);
            if table.positions.len() == session.len() {
                table.positions.clone()
            } else {
                loops_io::point_positions(session)
            }
        })
        .collect()
}

/// Per session: its poses, span, components within and between, and the samples touching it.
pub(crate) fn session_summaries(
    fleet: &Fleet,
    sources: &[String],
    components: &[FleetComponent],
    samples: &[FleetSample],
) -> Vec<SessionSummary> {
    let n = fleet.len();
    let (mut within, mut between, mut sampled) = (vec![0; n], vec![0; n], vec![0; n]);
    for c in components {
        let [a, b] = c.sessions;
        if a == b {
            within[a] += 1;
        } else {
            between[a] += 1;
            between[b] += 1;
        }
    }
    for s in samples {
        let [a, b] = s.sessions;
        sampled[a] += 1;
        if b != a {
            sampled[b] += 1;
        }
    }
    (0..n)
        .map(|a| {
            let traj = fleet.session(a);
            SessionSummary {
                name: fleet.names()[a].clone(),
                source: sources[a].clone(),
                poses: traj.len(),
                t0_s: traj.timestamps_s()[0],
                span_s: traj.span_s(),
                within_components: within[a],
                between_components: between[a],
                samples: sampled[a],
            }
        })
        .collect()
}

/// The fleet's table on stdout.
fn write_table(out: &mut impl Write, s: &FleetSummary<'_>) -> Result<()> {
    writeln!(
        out,
        "{} session(s), {} poses: {} components within sessions, {} between sessions in {} session pair(s); {} \
         samples{}, P1 {}/{} between sessions; in {:.2} s; results in {}",
        s.sessions.len(),
        s.poses,
        s.within_components,
        s.between_components,
        s.overlapping_session_pairs,
        s.samples,
        if s.between_only { " (between sessions only)" } else { "" },
        s.between_covered,
        s.between_components,
        s.seconds.stages.total,
        s.out
    )?;
    let width = s.sessions.iter().map(|r| r.name.chars().count()).max().unwrap_or(7).max(7);
    writeln!(
        out,
        "{:<width$}  {:>9}  {:>9}  {:>7}  {:>8}  {:>8}  page",
        "session", "poses", "span (s)", "within", "between", "samples"
    )?;
    for (r, page) in s.sessions.iter().zip(s.pages) {
        let status = if page.ok {
            "ok".to_owned()
        } else {
            format!("failed: {}", page.error.as_deref().unwrap_or("unknown error"))
        };
        writeln!(
            out,
            "{:<width$}  {:>9}  {:>9.1}  {:>7}  {:>8}  {:>8}  {status}",
            r.name, r.poses, r.span_s, r.within_components, r.between_components, r.samples
        )?;
    }
    writeln!(out, "wrote {}", Path::new(&s.out).join("index.html").display())?;
    Ok(())
}

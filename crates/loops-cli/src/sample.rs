//! `loops sample`: candidate loop-closure pairs for a scan matcher, from the exact loop
//! components or from clustered detections, with their quality (P1–P3).

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use loops_core::{Loops, SampleQuality, Samples, Trajectory, cluster_detections, sample_clusters, sample_quality};

use crate::args::{Analysis, AnalysisArgs, JsonTo};
use crate::guard;

/// Candidate loop-closure pairs for a scan matcher, from the exact loop components or from
/// clustered detections, with coverage (P1), redundancy (P2) and growth (P3).
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
    loops sample drive.tum --gamma 40 --sampler rho --budget 10000 --csv pairs.csv --g2o pairs.g2o\n  \
    loops sample tuc/SLAM/Corridor_GT.txt --gamma 1 --sampler rho --budget 500 \
    --detections tuc/SLAM/Corridor_Input.txt --epsilon-s 5 --drop-detections-outside-span"
)]
pub(crate) struct SampleArgs {
    /// The pose file; several files are read as one trajectory (MCAP files merged by time,
    /// others joined in time order: their times must not overlap).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[command(flatten)]
    analysis: AnalysisArgs,
    /// Sample from these detections (`t,t_prime[,score]` rows, or TUC `loop t1 t2 score`
    /// lines), clustered in the (t, t') plane with --epsilon-s; without it, sample from the
    /// exact loop components of S_gamma.
    #[arg(long, value_name = "PATH")]
    detections: Option<PathBuf>,
    /// Drop the detections with a time outside the trajectory's time span, saying how many on
    /// stderr; without it they are an error naming the line.
    #[arg(long, requires = "detections")]
    drop_detections_outside_span: bool,
    /// Write the candidate pairs as CSV to FILE (atomically; kept unless --force).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Write the candidate pairs as JSON to FILE (atomically; kept unless --force); `-` prints
    /// them on stdout instead of the summary.
    #[arg(long, value_name = "FILE")]
    json: Option<JsonTo>,
    /// Write the candidate pairs as g2o edges (EDGE_SE2 or EDGE_SE3:QUAT) to FILE, their
    /// relative pose from the file's poses: initial guesses for a scan matcher.
    #[arg(long, value_name = "FILE")]
    g2o: Option<PathBuf>,
    /// Replace the --csv, --json and --g2o files if they exist.
    #[arg(long)]
    force: bool,
}

pub(crate) fn sample(args: SampleArgs) -> Result<()> {
    let Analysis { spec, sampler, separation } = args.analysis.checked()?;
    let AnalysisArgs { input, engine, sampling } = &args.analysis;
    let (gamma, epsilon_s) = (engine.gamma, sampling.epsilon_s);
    let inputs: Vec<PathBuf> = args.files.iter().chain(&args.detections).cloned().collect();
    crate::out_dir::refuse_outputs_on_inputs(
        [("--csv", args.csv.as_deref()), ("--json", JsonTo::file(&args.json)), ("--g2o", args.g2o.as_deref())],
        &inputs,
    )?;
    let (table, traj) = input.read_table(&args.files, &spec)?;
    let (loops, samples) = loops_core::with_threads(engine.threads, || -> Result<(Loops, Samples)> {
        let loops = spec.find_loops_separated(&traj, gamma, separation)?;
        let samples = match &args.detections {
            None => spec.sample_loops(&traj, &loops, &sampler)?,
            Some(path) => {
                let mut table = loops_io::read_detections(path)?;
                if args.drop_detections_outside_span {
                    let dropped = table.drop_outside_span(&traj);
                    if !dropped.is_empty() {
                        let lines = dropped.lines_text().map_or(String::new(), |lines| format!(" ({lines})"));
                        let t = traj.timestamps_s();
                        eprintln!(
                            "loops: {}: --drop-detections-outside-span dropped {} of {} detection(s) outside \
                             the trajectory's time span [{}, {}] s{lines}",
                            dropped.path.display(),
                            dropped.count,
                            dropped.count + table.t_s.len(),
                            t[0],
                            t[t.len() - 1]
                        );
                    }
                }
                let detections = table.to_detections(&traj)?;
                let clusters = cluster_detections(&detections, epsilon_s)?;
                let mut samples = sample_clusters(&clusters, &sampler)?;
                samples.locate(&loops)?;
                samples
            }
        };
        Ok((loops, samples))
    })??;
    // One guess per pair in every file: the orientations the table holds (as the g2o edges
    // measure them), else the trajectory's own.
    let mut samples = samples;
    if table.orientations_xyzw.is_some() {
        samples.set_relative_poses(|i, j| {
            loops_io::table_relative_pose(&table, i, j).or_else(|| loops_core::relative_pose(&traj, i, j))
        });
    } else {
        samples.set_relative_poses(|i, j| loops_core::relative_pose(&traj, i, j));
    }
    // Where the poses are: the log's own positions, unless reading dropped or merged poses.
    let positions =
        if table.positions.len() == traj.len() { table.positions.clone() } else { loops_io::point_positions(&traj) };
    samples.set_positions(|k| positions.get(k).copied());
    let quality = sample_quality(&samples, &loops, epsilon_s)?;
    for warning in crate::run::warnings(&loops, &samples) {
        eprintln!("loops: warning: {warning}");
    }
    let mut stdout = std::io::stdout().lock();
    if args.json == Some(JsonTo::Stdout) {
        loops_io::samples_to_json(&samples, &mut stdout).context("writing the samples to stdout")?;
    } else {
        let measured = input.measured(&table, &traj);
        write_summary(
            &mut stdout,
            &crate::args::source_name(&args.files),
            &measured,
            &traj,
            &loops,
            &samples,
            &quality,
        )?;
    }
    // Every file is prepared first and written only when all could be: a command that fails
    // writes nothing.
    let mut files = loops_io::StagedFiles::new();
    let mut lines = Vec::new();
    let formats = [
        (args.csv.as_deref(), loops_io::SamplesFormat::Csv),
        (JsonTo::file(&args.json), loops_io::SamplesFormat::Json),
    ];
    for (path, format) in formats {
        if let Some(path) = path {
            files
                .stage(path, args.force, |file| match format {
                    loops_io::SamplesFormat::Csv => loops_io::samples_to_csv(&samples, file),
                    _ => loops_io::samples_to_json(&samples, file),
                })
                .map_err(guard::write_error)?;
            lines.push(format!("wrote {} samples to {}", samples.len(), path.display()));
        }
    }
    if let Some(path) = &args.g2o {
        let pairs: Vec<(usize, usize)> = samples.rows().iter().filter_map(|s| s.pair).map(|[i, j]| (i, j)).collect();
        let edges = loops_io::g2o_edges_text(&table, &pairs, &loops_io::G2oOptions::default())?;
        files.stage(path, args.force, |file| file.write_all(edges.as_bytes())).map_err(guard::write_error)?;
        lines.push(format!("wrote {} g2o edges to {}", pairs.len(), path.display()));
    }
    guard::with_writes(|_| files.persist()).map_err(guard::write_error)?;
    // With `--json -`, stdout holds the JSON only: the lines saying what was written are left out.
    if args.json != Some(JsonTo::Stdout) {
        for line in lines {
            writeln!(stdout, "{line}")?;
        }
    }
    Ok(())
}

fn write_summary(
    out: &mut impl Write,
    source: &str,
    measured: &str,
    traj: &Trajectory,
    loops: &Loops,
    samples: &Samples,
    quality: &SampleQuality,
) -> Result<()> {
    let nontrivial = loops.components().iter().filter(|c| !c.trivial).count();
    writeln!(out, "{source}")?;
    writeln!(out, "  measured: {measured}")?;
    writeln!(out, "  {}", crate::args::separation_line(loops.separation(), loops.gamma()))?;
    writeln!(
        out,
        "  {} poses; gamma {} ({}): {} components ({} non-trivial)",
        traj.len(),
        loops.gamma(),
        loops.metric_name(),
        loops.components().len(),
        nontrivial
    )
    .context("writing the summary")?;
    writeln!(out, "  sampler {}: {} samples from {} groups", samples.sampler(), samples.len(), samples.groups())?;
    writeln!(
        out,
        "  P1 coverage: {}/{} non-trivial components ({} of all {})",
        quality.nontrivial_covered, quality.nontrivial_components, quality.covered, quality.components
    )?;
    let outside = quality.outside_components();
    if outside > 0 {
        let why = if loops.is_separated() {
            "farther than gamma, or within it but not a revisit"
        } else {
            "farther than gamma"
        };
        writeln!(
            out,
            "  {outside} of {} samples lie in no loop component ({why}): the coverage above counts the other {}",
            quality.samples,
            quality.samples - outside
        )?;
    }
    let mut missed: Vec<_> = quality.missed.iter().filter(|m| !m.trivial).collect();
    missed.sort_by(|a, b| b.area_s2.total_cmp(&a.area_s2));
    for m in missed.iter().take(5) {
        writeln!(out, "    missed component {}: {:.1} s², {} pose pairs", m.id, m.area_s2, m.pose_pair_count)?;
    }
    if missed.len() > 5 {
        writeln!(out, "    ... {} more missed", missed.len() - 5)?;
    }
    let spacing = quality.median_spacing_s.map_or("-".to_owned(), |s| format!("{s:.1} s"));
    writeln!(
        out,
        "  P2 redundancy: {} samples have another of their component within {} s; median spacing {spacing}",
        quality.redundant, quality.epsilon_s
    )?;
    let slope = quality.p3_slope.map_or("-".to_owned(), |s| format!("{s:.2}"));
    writeln!(out, "  P3 growth: slope of log samples against log area {slope} (0: σ_1-like, 1: σ_α-like)")?;
    Ok(())
}

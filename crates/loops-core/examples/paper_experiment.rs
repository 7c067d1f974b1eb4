//! The sampling experiment of the paper (Sec. 5.5) on the synthetic urban drive, with the exact
//! components route and the baselines of deployed SLAM systems:
//! `cargo run --release -p loops-core --example paper_experiment -- [budget] [seed]`.
//!
//! 75,600 poses (2.1 h at 10 Hz), γ = 40 m, 1% of S_γ drawn as detections, ε = 30 s, a budget of
//! 1e4 samples per sampler. P1, P2 and P3 are measured against the exact components of S_γ.
use std::time::Instant;

use loops_core::{
    Detections, Euclidean, Loops, SampleQuality, SampleSize, Sampler, SamplerKind, Samples, UrbanDrive,
    cluster_detections, find_loops, sample_clusters, sample_loops, sample_quality,
};

const GAMMA_M: f64 = 40.0;
const EPSILON_S: f64 = 30.0;
const DETECTION_RATE: f64 = 0.01;

fn main() -> Result<(), loops_core::Error> {
    let mut args = std::env::args().skip(1);
    let budget: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(10_000);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(0);

    let drive = UrbanDrive::default().generate()?;
    let traj = &drive.trajectory;
    let start = Instant::now();
    let loops = find_loops(traj, &Euclidean, GAMMA_M)?;
    let nontrivial = loops.components().iter().filter(|c| !c.trivial).count();
    println!(
        "urban drive: {} poses, gamma {GAMMA_M} m: {} pairs of S_gamma, {} components ({} non-trivial), {:.2} s",
        traj.len(),
        loops.pair_count(),
        loops.components().len(),
        nontrivial,
        start.elapsed().as_secs_f64()
    );

    let start = Instant::now();
    let detections = Detections::draw(&loops, SampleSize::Rate(DETECTION_RATE), seed)?;
    let drawn_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let clusters = cluster_detections(&detections, EPSILON_S)?;
    println!(
        "detections: {} ({}% of S_gamma, {drawn_s:.3} s); epsilon {EPSILON_S} s: {} clusters in {:.3} s",
        detections.len(),
        100.0 * DETECTION_RATE,
        clusters.len(),
        start.elapsed().as_secs_f64()
    );

    let big = largest_nontrivial(&loops, 10);
    let area_share = big.iter().map(|&c| loops.components()[c].area_s2).sum::<f64>()
        / loops.components().iter().filter(|c| !c.trivial).map(|c| c.area_s2).sum::<f64>();
    println!(
        "budget {budget}, seed {seed}. P1: components covered (all / non-trivial / smallest half by area); \
         P2: samples with another of their component within {EPSILON_S} s, median spacing to the \
         nearest one (all / non-trivial components); P3: slope of ln samples on ln area; trivial: \
         share of samples in the trivial component; big10: share of non-trivial samples in the 10 \
         largest non-trivial components (their area share: {:.1}%); mean distance: of the sampled \
         pairs in non-trivial components, metres",
        100.0 * area_share
    );
    println!();
    println!(
        "| route | sampler | samples | P1 all | P1 non-trivial | P1 small half | largest missed non-trivial (s²) | P2 redundant | P2 spacing (s) | P2 spacing non-trivial (s) | P3 slope | trivial | big10 | mean distance (m) | time (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let kinds = [SamplerKind::One, SamplerKind::Rho, SamplerKind::RhoDispersed, SamplerKind::Alpha];
    for kind in kinds {
        let start = Instant::now();
        let mut samples = sample_clusters(&clusters, &Sampler::new(kind, SampleSize::Budget(budget), seed))?;
        let elapsed = start.elapsed().as_secs_f64();
        samples.measure(traj, &Euclidean)?;
        row("detections", &samples, &loops, &big, elapsed)?;
    }
    let baselines = [SamplerKind::LioSam, SamplerKind::HdlGraphSlam, SamplerKind::Cartographer, SamplerKind::TimeGap];
    for kind in kinds.into_iter().chain(baselines) {
        let start = Instant::now();
        let samples = sample_loops(traj, &Euclidean, &loops, &Sampler::new(kind, SampleSize::Budget(budget), seed))?;
        let elapsed = start.elapsed().as_secs_f64();
        let route = if kind.is_baseline() { "baseline" } else { "exact components" };
        row(route, &samples, &loops, &big, elapsed)?;
    }
    // Beyond the paper: the budget spent on the revisits only, not on simple loops.
    for kind in kinds {
        let sampler = Sampler { skip_trivial: true, ..Sampler::new(kind, SampleSize::Budget(budget), seed) };
        let start = Instant::now();
        let samples = sample_loops(traj, &Euclidean, &loops, &sampler)?;
        let elapsed = start.elapsed().as_secs_f64();
        row("non-trivial components", &samples, &loops, &big, elapsed)?;
    }
    Ok(())
}

fn largest_nontrivial(loops: &Loops, count: usize) -> Vec<usize> {
    let mut ids: Vec<usize> = loops.components().iter().filter(|c| !c.trivial).map(|c| c.id).collect();
    ids.sort_by(|&a, &b| loops.components()[b].area_s2.total_cmp(&loops.components()[a].area_s2));
    ids.truncate(count);
    ids
}

fn row(route: &str, samples: &Samples, loops: &Loops, big: &[usize], elapsed_s: f64) -> Result<(), loops_core::Error> {
    let quality = sample_quality(samples, loops, EPSILON_S)?;
    let small = small_half_coverage(&quality, loops);
    let nontrivial_samples: u64 =
        loops.components().iter().filter(|c| !c.trivial).map(|c| quality.per_component[c.id]).sum();
    let in_big: u64 = big.iter().map(|&c| quality.per_component[c]).sum();
    let trivial_samples = quality.samples as u64 - nontrivial_samples - quality.outside as u64;
    let mut nontrivial_spacing: Vec<f64> = quality
        .nearest_spacing_s
        .iter()
        .zip(&quality.sample_components)
        .filter(|(_, c)| c.is_some_and(|c| !loops.components()[c].trivial))
        .filter_map(|(s, _)| *s)
        .collect();
    nontrivial_spacing.sort_by(f64::total_cmp);
    let median = nontrivial_spacing.get(nontrivial_spacing.len() / 2);
    let warnings: Vec<String> = samples.warnings().iter().map(ToString::to_string).collect();
    println!(
        "| {route} | {} | {} | {}/{} | {}/{} | {}/{} | {} | {:.1}% | {} | {} | {} | {:.1}% | {:.1}% | {:.1} | {:.3} |{}",
        samples.sampler(),
        quality.samples,
        quality.covered,
        quality.components,
        quality.nontrivial_covered,
        quality.nontrivial_components,
        small.0,
        small.1,
        quality.missed.iter().find(|m| !m.trivial).map_or("-".to_owned(), |m| format!("{:.0}", m.area_s2)),
        100.0 * quality.redundancy(),
        quality.median_spacing_s.map_or("-".to_owned(), |s| format!("{s:.1}")),
        median.map_or("-".to_owned(), |s| format!("{s:.1}")),
        quality.p3_slope.map_or("-".to_owned(), |s| format!("{s:.2}")),
        if quality.samples == 0 { 0.0 } else { 100.0 * trivial_samples as f64 / quality.samples as f64 },
        if nontrivial_samples == 0 { 0.0 } else { 100.0 * in_big as f64 / nontrivial_samples as f64 },
        mean_nontrivial_distance(samples, &quality, loops),
        elapsed_s,
        if warnings.is_empty() { String::new() } else { format!(" {}", warnings.join("; ")) }
    );
    Ok(())
}

fn mean_nontrivial_distance(samples: &Samples, quality: &SampleQuality, loops: &Loops) -> f64 {
    let distances: Vec<f64> = samples
        .rows()
        .iter()
        .zip(&quality.sample_components)
        .filter(|(_, c)| c.is_some_and(|c| !loops.components()[c].trivial))
        .filter_map(|(r, _)| r.distance)
        .collect();
    distances.iter().sum::<f64>() / distances.len().max(1) as f64
}

/// P1 over the smaller half (by area) of the samplable non-trivial components.
fn small_half_coverage(quality: &SampleQuality, loops: &Loops) -> (usize, usize) {
    let missed: std::collections::BTreeSet<usize> = quality.missed.iter().map(|m| m.id).collect();
    let mut ids: Vec<usize> = loops
        .components()
        .iter()
        .filter(|c| !c.trivial && (quality.per_component[c.id] > 0 || missed.contains(&c.id)))
        .map(|c| c.id)
        .collect();
    ids.sort_by(|&a, &b| loops.components()[a].area_s2.total_cmp(&loops.components()[b].area_s2));
    ids.truncate(ids.len() / 2);
    (ids.iter().filter(|c| !missed.contains(c)).count(), ids.len())
}

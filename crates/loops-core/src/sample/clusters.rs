//! Sampling detections by their ε-graph clusters.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::disperse::disperse_detections;
use super::exact::concat;
use super::{Sample, Sampler, SamplerKind, Samples, group_rng};
use crate::cluster::DetectionClusters;
use crate::draw::{Numbers, choose_indices, draw_numbers, uniforms};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::memory::try_collect;

/// Samples detections, grouped by their ε-graph clusters (paper, Sec. 5.3–5.5): σ_1, σ_ρ, the
/// dispersed σ_ρ, σ_α, closest-first (each cluster's best-scored detection first, the middle
/// one of its middle row without scores; the rest as the dispersed σ_ρ), or closest-then-spread
/// (σ_ρ's counts, picked as closest-first; nearest-then-uniform too: detections are a uniform
/// draw already). "Trajectory points" of
/// a cluster (σ_ρ) are its distinct times t.
///
/// Within a group, picks are uniform without replacement (σ_1, σ_ρ) or spread evenly over the
/// group's rows in time order (dispersed σ_ρ: the best-scored detection of a row, or its middle
/// one without scores). Groups are visited in parallel, each with its own ChaCha8 stream, and
/// detections are taken in (cluster, t, t′) order, so the result depends on neither the thread
/// count nor (without duplicates) the order of the detections. O(n log n).
///
/// # Errors
/// [`Error::UnknownName`] for a baseline (they need the trajectory: [`sample_loops`](crate::sample_loops));
/// [`Error::InvalidParameter`] for a budget of 0 or a rate out of range;
/// [`Error::NotApplicable`] for [`Sampler::skip_trivial`] (clusters do not know the trivial
/// components); [`Error::TooManySamples`] for a size that makes more than
/// [`MAX_SAMPLES`](crate::MAX_SAMPLES) samples, before any is drawn; [`Error::OutOfMemory`];
/// [`Error::Interrupted`] when an [`Interrupt`] installed on this thread is interrupted.
///
/// # Examples
/// ```
/// use loops_core::{Detections, SampleSize, Sampler, SamplerKind, cluster_detections, sample_clusters};
/// let det = Detections::new(vec![0.0, 1.0, 2.0, 500.0], vec![100.0, 100.0, 100.0, 900.0])?;
/// let clusters = cluster_detections(&det, 30.0)?;
/// let samples = sample_clusters(&clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(2), 0))?;
/// assert_eq!(samples.len(), 2);
/// assert_eq!(samples.rows()[1].detection, Some(3)); // one per cluster (P1)
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn sample_clusters(clusters: &DetectionClusters, sampler: &Sampler) -> Result<Samples> {
    let kind = sampler.kind;
    if kind.is_baseline() {
        return Err(Error::UnknownName {
            kind: "sampler of detection clusters",
            name: kind.name().to_owned(),
            expected: SamplerKind::CLUSTER_NAMES,
        });
    }
    if sampler.skip_trivial {
        return Err(Error::NotApplicable {
            option: "skip_trivial",
            to: "detection clusters".to_owned(),
            reason: "clusters do not know which loop components are trivial; sample the exact components, \
                     or leave out detections near t′ = t before clustering",
        });
    }
    sampler.size.validate(kind)?;
    let det = clusters.detections();
    let (xs, ys) = (det.t_s(), det.t_prime_s());
    let labels = clusters.labels();
    // Detections in (cluster, t, t′, index) order, and where each cluster starts.
    let mut order: Vec<u32> = (0..det.len() as u32).collect();
    order.par_sort_unstable_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        (labels[a], xs[a], ys[a], a).partial_cmp(&(labels[b], xs[b], ys[b], b)).unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut offsets = vec![0usize; clusters.len() + 1];
    for &label in labels {
        offsets[label as usize + 1] += 1;
    }
    for g in 0..clusters.len() {
        offsets[g + 1] += offsets[g];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(sampler.seed);
    let mut warnings = Vec::new();
    let (chosen, groups): (Vec<u32>, usize) = if kind == SamplerKind::Alpha {
        let n = det.len() as u64;
        let positions = draw_numbers(n, sampler.size, &mut rng, &mut warnings)?;
        (positions.into_iter().map(|p| order[p as usize]).collect(), 0)
    } else {
        let members: Vec<&[u32]> = (0..clusters.len()).map(|g| &order[offsets[g]..offsets[g + 1]]).collect();
        let rows_of = |m: &[u32]| 1 + m.windows(2).filter(|w| xs[w[0] as usize] != xs[w[1] as usize]).count();
        let caps: Vec<u64> = members.iter().map(|m| m.len() as u64).collect();
        let rows = || members.par_iter().map(|m| rows_of(m) as f64).collect();
        // Clusters in time order: a budget's picks spread along them.
        let numbers = Numbers::one_stratum(uniforms(&mut rng, caps.len()), rng.random());
        let quotas = sampler.group_quotas(rows, &caps, &numbers, &mut warnings)?;
        let interrupt = Interrupt::current();
        let scores = det.scores();
        let picks: Vec<Vec<u32>> = members
            .par_iter()
            .zip(&quotas)
            .enumerate()
            .map(|(g, (m, &q))| {
                interrupt.check()?;
                let mut rng = group_rng(sampler.seed, g);
                Ok(
                    if matches!(
                        kind,
                        SamplerKind::RhoDispersed
                            | SamplerKind::ClosestFirst
                            | SamplerKind::ClosestThenSpread
                            | SamplerKind::NearestThenUniform
                    ) {
                        let best_first = kind != SamplerKind::RhoDispersed;
                        disperse_detections(m, q, xs, scores, best_first, &mut rng)
                    } else {
                        choose_indices(m.len() as u64, q, &mut rng).into_iter().map(|p| m[p as usize]).collect()
                    },
                )
            })
            .collect::<Result<_>>()?;
        (concat(picks)?, clusters.len())
    };
    let pairs = det.pairs();
    let rows = chosen.iter().map(|&k| {
        let k = k as usize;
        Sample {
            pair: pairs.map(|p| [p[k][0] as usize, p[k][1] as usize]),
            t_s: xs[k],
            t_prime_s: ys[k],
            component: None,
            cluster: Some(labels[k] as usize),
            detection: Some(k),
            distance: None,
            score: det.scores().map(|s| s[k]),
            relative_pose: None,
            positions: None,
            sampler: kind,
        }
    });
    let mut samples = Samples::new(kind, try_collect(rows, "the samples")?, groups, det.len() as u64, det.poses());
    samples.warnings = warnings;
    Ok(samples)
}

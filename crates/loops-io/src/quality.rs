//! The quality of a sampling in a results summary: [`QualitySummary`], the counts and measures
//! of a [`SampleQuality`] without its per-sample lists; and [`compare_samplers`], the paper's
//! samplers side by side at a run's sample count, which the reports draw.

use loops_core::{
    Loops, MetricSpec, Result, SampleQuality, SampleSize, Sampler, SamplerKind, Trajectory, sample_quality,
};

/// The samplers a report compares at a run's sample count: σ_1, σ_ρ and σ_α (the run's own is
/// added when it is not among them).
pub const COMPARED_SAMPLERS: [SamplerKind; 3] = [SamplerKind::One, SamplerKind::Rho, SamplerKind::Alpha];

/// Each of [`COMPARED_SAMPLERS`], and `run`'s own kind, drawn with `run`'s seed and options at a
/// budget of `count` samples (at least 1), with its quality under the detection window
/// `epsilon_s`: the samples-per-component figure of a report.
///
/// # Errors
/// As [`MetricSpec::sample_loops`] and [`sample_quality`].
pub fn compare_samplers(
    spec: &MetricSpec,
    traj: &Trajectory,
    loops: &Loops,
    run: &Sampler,
    count: usize,
    epsilon_s: f64,
) -> Result<Vec<(SamplerKind, SampleQuality)>> {
    let mut kinds = COMPARED_SAMPLERS.to_vec();
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

/// The counts and measures of a [`SampleQuality`] (P1, P2, P3), named for the sampler, as
/// `summary.json` holds them; the per-component and per-sample lists are left out.
/// Its fields copy [`SampleQuality`]'s on purpose: the core's serde form holds those lists too,
/// and `summary.json` keeps this layout whatever the core adds.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct QualitySummary {
    /// The sampler's name.
    pub sampler: String,
    /// See [`SampleQuality::samples`].
    pub samples: usize,
    /// See [`SampleQuality::outside`].
    pub outside: usize,
    /// See [`SampleQuality::components`].
    pub components: usize,
    /// See [`SampleQuality::covered`].
    pub covered: usize,
    /// See [`SampleQuality::nontrivial_components`].
    pub nontrivial_components: usize,
    /// See [`SampleQuality::nontrivial_covered`].
    pub nontrivial_covered: usize,
    /// See [`SampleQuality::redundant`].
    pub redundant: usize,
    /// See [`SampleQuality::median_spacing_s`].
    pub median_spacing_s: Option<f64>,
    /// See [`SampleQuality::p3_slope`].
    pub p3_slope: Option<f64>,
}

impl QualitySummary {
    /// The summary of `quality`, the quality of a sampling by `sampler`.
    pub fn new(sampler: SamplerKind, quality: &SampleQuality) -> Self {
        Self {
            sampler: sampler.name().to_owned(),
            samples: quality.samples,
            outside: quality.outside,
            components: quality.components,
            covered: quality.covered,
            nontrivial_components: quality.nontrivial_components,
            nontrivial_covered: quality.nontrivial_covered,
            redundant: quality.redundant,
            median_spacing_s: quality.median_spacing_s,
            p3_slope: quality.p3_slope,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loops_core::{Euclidean, Separation, find_loops_separated};

    /// Two laps of a circle: one revisit.
    fn two_laps() -> (Trajectory, Loops) {
        let n = 400;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.1).collect();
        let xy: Vec<[f64; 2]> = t.iter().map(|&s| [10.0 * (s * 0.314).cos(), 10.0 * (s * 0.314).sin()]).collect();
        let traj = Trajectory::from_points(t, &xy).unwrap();
        let loops = find_loops_separated(&traj, &Euclidean, 1.0, Separation::for_gamma(1.0)).unwrap();
        (traj, loops)
    }

    #[test]
    fn the_comparison_holds_the_paper_samplers_and_the_runs_own_at_its_count() {
        let (traj, loops) = two_laps();
        let spec = MetricSpec::Euclidean;
        let run = Sampler::new(SamplerKind::DEFAULT, SampleSize::Budget(7), 3);
        let compared = compare_samplers(&spec, &traj, &loops, &run, 5, 1.0).unwrap();
        let kinds: Vec<SamplerKind> = compared.iter().map(|(kind, _)| *kind).collect();
        assert_eq!(kinds, [SamplerKind::One, SamplerKind::Rho, SamplerKind::Alpha, SamplerKind::DEFAULT]);
        for (kind, quality) in &compared {
            assert_eq!(quality.samples, 5, "{kind:?} drew {} samples, not the run's 5", quality.samples);
        }
        // A run with one of the paper's samplers adds nothing, and no count still draws one.
        let rho = Sampler { kind: SamplerKind::Rho, ..run };
        let compared = compare_samplers(&spec, &traj, &loops, &rho, 0, 1.0).unwrap();
        assert_eq!(compared.len(), COMPARED_SAMPLERS.len());
        assert!(compared.iter().all(|(_, quality)| quality.samples == 1));
    }
}

//! The quality of a sampling in a results summary: [`QualitySummary`], the counts and measures
//! of a [`SampleQuality`] without its per-sample lists.

use loops_core::{SampleQuality, SamplerKind};

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

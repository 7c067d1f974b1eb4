//! The nearest-then-uniform sampler's counts: per component, how many of its picks are the
//! closest pairs of its rows, and how many are uniform over its pairs.
//!
//! Small budgets go to rows' closest pairs, as LIO-SAM's rule matches each keyframe with its
//! nearest revisit: each component's closest pair first (P1), the closest pairs of rows
//! spread along the components in proportion to their rows (as σ_ρ shares its picks), up to one row in
//! [`NEAR_ROW_STRIDE`] (the closest pairs of neighbouring rows are near copies of one scan
//! match). Whatever the budget leaves beyond that is uniform over each component's pairs, in
//! proportion to the pairs it has left, as the time-gap rule draws over all pairs: those
//! spread in time along both poses of the pair, not along rows only.

use crate::draw::{Numbers, SampleSize, SampleWarning, group_quotas, order_sample};

/// One component's counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Split {
    /// Closest pairs of rows (the component's own closest pair first).
    pub near: u64,
    /// Uniform picks over the rest of its pairs.
    pub uniform: u64,
}

impl Split {
    /// All its picks.
    pub fn total(self) -> u64 {
        self.near + self.uniform
    }
}

/// At most one row in this many gives its closest pair before the uniform picks start.
///
/// Chosen on the map evaluation (`benches/eval_grid.py`, KITTI 00/05/08 and MulRan KAIST 01
/// with 2 m keyframes): one row in two left the closest pairs of neighbouring rows, near
/// copies of one constraint, to take the budget that uniform picks used better at 10²; one in
/// six is about the density of LIO-SAM's searches there (one a second at ~10 m/s).
pub(crate) const NEAR_ROW_STRIDE: u64 = 6;

/// Rows' closest pairs a component takes at most: one row in [`NEAR_ROW_STRIDE`] (at least
/// one), no more than its pairs.
pub(crate) fn near_cap(rows: u64, pairs: u64) -> u64 {
    rows.div_ceil(NEAR_ROW_STRIDE).clamp(1, pairs.max(1))
}

/// The counts of each component with `rows` rows and `pairs` pairs (every one ≥ 1).
///
/// Budget `B`: with `N = Σ near_cap`, a budget up to `N` is all closest pairs of rows shared
/// by rows as σ_ρ shares its picks ([`group_quotas`] over the near caps: at least one per
/// component when the budget has one for each, none below that, with a warning), so that a
/// long component may take two or more where short ones take one; beyond `N`, every component
/// takes its near cap and `B − N` is shared in proportion to the pairs left (`pairs − near`),
/// rounded by the components' `numbers` ([`order_shares`]), so that the
/// counts sum to `B` exactly (all pairs, with a warning, for a budget above them). Rate `r`:
/// σ_ρ's counts (`r · rows`, at least 1, at most the pairs), the first up to the near cap
/// closest pairs of rows.
pub(crate) fn nearest_then_uniform_quotas(
    rows: &[u64],
    pairs: &[u64],
    size: SampleSize,
    numbers: &Numbers,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<Split> {
    debug_assert_eq!(rows.len(), pairs.len());
    debug_assert!(pairs.iter().all(|&p| p >= 1));
    let near: Vec<u64> = rows.iter().zip(pairs).map(|(&r, &p)| near_cap(r, p)).collect();
    let weights: Vec<f64> = rows.iter().map(|&r| r as f64).collect();
    match size {
        SampleSize::Rate(_) => group_quotas(&weights, pairs, size, numbers, warnings)
            .into_iter()
            .zip(&near)
            .map(|(q, &n)| Split { near: q.min(n), uniform: q - q.min(n) })
            .collect(),
        SampleSize::Budget(budget) => {
            let budget = budget as u64;
            let near_total: u64 = near.iter().sum();
            if budget <= near_total {
                // All closest pairs of rows, shared by rows as σ_ρ shares its picks: at least
                // one each from a budget of one per component, and a long component may take
                // two or more where short ones take one (none, below one per component).
                return group_quotas(&weights, &near, size, numbers, warnings)
                    .into_iter()
                    .map(|near| Split { near, uniform: 0 })
                    .collect();
            }
            let left: Vec<u64> = pairs.iter().zip(&near).map(|(&p, &n)| p - n).collect();
            let available: u64 = left.iter().sum();
            let rest = budget - near_total;
            if rest >= available {
                if rest > available {
                    warnings.push(SampleWarning::BudgetAboveAvailable {
                        budget: budget as usize,
                        available: pairs.iter().sum(),
                    });
                }
                return near.iter().zip(&left).map(|(&near, &uniform)| Split { near, uniform }).collect();
            }
            let uniform = order_shares(&left, rest, numbers);
            near.iter().zip(uniform).map(|(&near, uniform)| Split { near, uniform }).collect()
        }
    }
}

/// `total` (less than `Σ caps`) shared in proportion to `caps`, each share ⌊e⌋ or ⌈e⌉ of its
/// expectation `e = total · cap / Σ caps` (so at most its cap), summing to `total`: the floors
/// in exact integer arithmetic, then one more for the groups that Pareto order sampling of the
/// fractional parts picks by `numbers` ([`order_sample`]).
fn order_shares(caps: &[u64], total: u64, numbers: &Numbers) -> Vec<u64> {
    let sum: u64 = caps.iter().sum();
    debug_assert!(total < sum);
    let scaled = |cap: u64| u128::from(total) * u128::from(cap);
    let mut shares: Vec<u64> = caps.iter().map(|&cap| (scaled(cap) / u128::from(sum)) as u64).collect();
    let fractions: Vec<f64> = caps.iter().map(|&cap| (scaled(cap) % u128::from(sum)) as f64 / sum as f64).collect();
    // The fractions sum to the integer left over: order sampling picks exactly that many.
    let left = total - shares.iter().sum::<u64>();
    for g in order_sample(&fractions, left, numbers) {
        shares[g] += 1;
    }
    shares
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use crate::draw::uniforms;

    fn quotas(rows: &[u64], pairs: &[u64], size: SampleSize, seed: u64) -> (Vec<Split>, Vec<SampleWarning>) {
        let mut warnings = Vec::new();
        let numbers = Numbers::independent(uniforms(&mut ChaCha8Rng::seed_from_u64(seed), rows.len()));
        let q = nearest_then_uniform_quotas(rows, pairs, size, &numbers, &mut warnings);
        (q, warnings)
    }

    #[test]
    fn small_budgets_are_closest_pairs_of_rows_shared_by_rows_at_least_one_each() {
        // Near caps 50, 5, 1: N = 56.
        let (rows, pairs) = ([300, 30, 1], [1000, 40, 3]);
        for seed in 0..20 {
            let (q, warnings) = quotas(&rows, &pairs, SampleSize::Budget(30), seed);
            assert!(warnings.is_empty());
            assert!(q.iter().all(|s| s.uniform == 0 && s.near >= 1), "{q:?}");
            assert_eq!(q.iter().map(|s| s.near).sum::<u64>(), 30);
            assert!(q[0].near <= 50 && q[1].near <= 5 && q[2].near == 1);
            // max(1, s · rows) as σ_ρ: 330 s + 1 = 30, the long one's share 300 s = 26.4 (one
            // first and then 27 by rows would give it 25.5).
            assert!((q[0].near as f64 - 29.0 * 300.0 / 330.0).abs() < 1.0, "{q:?}");
        }
    }

    #[test]
    fn a_budget_below_the_components_is_shared_by_rows() {
        // Near caps 17, 2, 1, 2; rows 100 : 10 : 1 : 7 of 118.
        let (rows, pairs) = ([100, 10, 1, 7], [1000, 40, 3, 9]);
        let (q, warnings) = quotas(&rows, &pairs, SampleSize::Budget(2), 3);
        assert!(q.iter().all(|s| s.uniform == 0));
        // 2 · 100 / 118 = 1.69: the long component takes one or two, never none.
        assert!(q[0].near >= 1 && q[0].near <= 2, "{q:?}");
        assert_eq!(q.iter().map(|s| s.total()).sum::<u64>(), 2);
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 2, groups: 4 }]));
        // Over seeds the long component's mean is its share, 1.69, where one pick per component
        // would give it at most 1.
        let mean = (0..400).map(|seed| quotas(&rows, &pairs, SampleSize::Budget(2), seed).0[0].near).sum::<u64>()
            as f64
            / 400.0;
        assert!((mean - 200.0 / 118.0).abs() < 0.06, "{mean}");
    }

    #[test]
    fn a_budget_below_the_components_stays_within_the_near_caps() {
        // One long component and thirty one-row ones: 20 picks over 31 components; the long
        // one's share, 20 · 60 / 90 = 13.3, is capped at its near cap, 60 / 6 = 10, and the
        // other 10 go to ten of the one-row components.
        let mut rows = vec![60];
        rows.extend([1; 30]);
        let mut pairs = vec![5000];
        pairs.extend([2; 30]);
        for seed in 0..20 {
            let (q, _) = quotas(&rows, &pairs, SampleSize::Budget(20), seed);
            assert_eq!(q[0].near, 10, "{q:?}");
            assert_eq!(q.iter().map(|s| s.total()).sum::<u64>(), 20);
            assert!(q[1..].iter().all(|s| s.near <= 1 && s.uniform == 0), "{q:?}");
        }
    }

    #[test]
    fn large_budgets_fill_one_row_in_six_then_share_by_the_pairs_left() {
        let (rows, pairs) = ([300, 30, 1], [1000, 40, 3]);
        let left = [950.0, 35.0, 2.0];
        for seed in 0..20 {
            let (q, warnings) = quotas(&rows, &pairs, SampleSize::Budget(456), seed);
            assert!(warnings.is_empty());
            assert_eq!(q.iter().map(|s| s.near).collect::<Vec<_>>(), [50, 5, 1]);
            assert_eq!(q.iter().map(|s| s.total()).sum::<u64>(), 456);
            for (s, l) in q.iter().zip(left) {
                let expected = 400.0 * l / 987.0;
                assert!((s.uniform as f64 - expected).abs() < 1.0, "{q:?}");
            }
        }
    }

    #[test]
    fn a_budget_above_the_pairs_takes_them_all() {
        let (q, warnings) = quotas(&[100, 10], &[1000, 40], SampleSize::Budget(2000), 0);
        assert_eq!(q.iter().map(|s| s.total()).collect::<Vec<_>>(), [1000, 40]);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 2000, available: 1040 }]));
        let (q, warnings) = quotas(&[100, 10], &[1000, 40], SampleSize::Budget(1040), 0);
        assert_eq!(q.iter().map(|s| s.total()).collect::<Vec<_>>(), [1000, 40]);
        assert!(warnings.is_empty());
    }

    #[test]
    fn rate_counts_are_sigma_rho_closest_pairs_first() {
        let (q, _) = quotas(&[300, 30, 1], &[1000, 40, 3], SampleSize::Rate(2.0), 0);
        assert_eq!(q.iter().map(|s| s.near).collect::<Vec<_>>(), [50, 5, 1]);
        assert_eq!(q.iter().map(|s| s.total()).collect::<Vec<_>>(), [600, 40, 2]);
    }

    #[test]
    fn order_shares_sum_and_stay_within_one_of_the_expectation() {
        let caps = [3, 0, 17, 1, 250, 9];
        let mut mean = [0.0; 6];
        for seed in 0..4000 {
            let numbers = Numbers::independent(uniforms(&mut ChaCha8Rng::seed_from_u64(seed), caps.len()));
            let shares = order_shares(&caps, 101, &numbers);
            assert_eq!(shares.iter().sum::<u64>(), 101);
            for (g, (&s, &c)) in shares.iter().zip(&caps).enumerate() {
                assert!(s <= c && (s as f64 - 101.0 * c as f64 / 280.0).abs() < 1.0);
                mean[g] += s as f64 / 4000.0;
            }
        }
        // Over permanent numbers, each share's mean is about its expectation.
        for (g, &c) in caps.iter().enumerate() {
            assert!((mean[g] - 101.0 * c as f64 / 280.0).abs() < 0.03, "{g}: {mean:?}");
        }
    }
}

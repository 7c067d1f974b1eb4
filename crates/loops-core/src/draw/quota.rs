//! Samples per group: quotas proportional to weights, capped, rounded at random to integers
//! that keep the expectation (σ_1 and σ_ρ).
//!
//! The rounding draws on one uniform number per group, its *permanent random number*, rather
//! than on a stream read in group order: a keyed draw takes each component's from a hash of its
//! own cells, so that a component keeps its rounding when others are added or removed around it
//! (order sampling, as survey statistics coordinate samples over time). A fleet store's next
//! draw then asks again only where the quotas moved.

use rand::{Rng, RngExt};

use super::{SampleSize, SampleWarning};

/// `n` uniform numbers in [0, 1) from `rng`: permanent random numbers for groups that have no
/// cells of their own to hash (detection clusters).
pub(crate) fn uniforms<R: Rng + ?Sized>(rng: &mut R, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random::<f64>()).collect()
}

/// Samples per group for σ_1 (`weights` all 1) and σ_ρ (`weights` = rows): quotas
/// `q_g = clamp(s · w_g, lo, cap_g)`, rounded at random to integers with (about) the same
/// expectation, by the groups' permanent random numbers `prn`.
///
/// Rate mode: s is the rate, lo = 1, each group rounded up when its number is below its
/// fractional part. Budget mode: s solves Σ q_g = B exactly (a sweep over the breakpoints of the
/// piecewise linear sum), lo = 1 when B ≥ #groups (P1), else 0 with a warning; then Pareto order
/// sampling of the fractional parts ([`round_to_total`]) gives integers summing to exactly B
/// (all caps when B exceeds them, with a warning).
pub(crate) fn group_quotas(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    prn: &[f64],
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    debug_assert_eq!(prn.len(), weights.len());
    let groups = weights.len();
    match size {
        SampleSize::Rate(rate) => weights
            .iter()
            .zip(caps)
            .zip(prn)
            .map(|((&w, &cap), &u)| round_by(u, (rate * w).clamp(1.0, cap as f64)).min(cap))
            .collect(),
        SampleSize::Budget(budget) => {
            if let Some(all) = every_cap(budget, caps, warnings) {
                return all;
            }
            let lo = if budget >= groups {
                1.0
            } else {
                warnings.push(SampleWarning::BudgetBelowGroups { budget, groups });
                0.0
            };
            let scale = solve_scale(weights, caps, lo, budget as f64);
            let quotas: Vec<f64> =
                weights.iter().zip(caps).map(|(&w, &cap)| (scale * w).clamp(lo, cap as f64)).collect();
            round_to_total(&quotas, caps, budget as u64, prn)
        }
    }
}

/// Samples per group for the closest-first sampler: one per group first (its closest pair),
/// then the rest in proportion to `weights` (the rows, as σ_ρ): `q_g = 1 + clamp(s · w_g, 0,
/// cap_g − 1)`, rounded at random by `prn` as [`group_quotas`] does. Every cap is at least 1.
///
/// Rate mode: `1 + r · w_g` rounded at random, at most the cap. Budget mode: the rest, `B −
/// #groups`, is shared without a floor (every group has its one already); a budget below the
/// number of groups gives one sample to that many groups, chosen ∝ their weight, with a warning;
/// a budget above every cap gives all of them, with a warning.
pub(crate) fn first_then_quotas(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    prn: &[f64],
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    debug_assert!(caps.iter().all(|&cap| cap >= 1));
    match size {
        SampleSize::Rate(rate) => {
            weights.iter().zip(caps).zip(prn).map(|((&w, &cap), &u)| (1 + round_by(u, rate * w)).min(cap)).collect()
        }
        SampleSize::Budget(budget) => {
            if let Some(all) = every_cap(budget, caps, warnings) {
                return all;
            }
            if budget < weights.len() {
                return group_quotas(weights, &vec![1; weights.len()], size, prn, warnings);
            }
            let rest: Vec<u64> = caps.iter().map(|&cap| cap - 1).collect();
            let extra = (budget - weights.len()) as u64;
            let scale = solve_scale(weights, &rest, 0.0, extra as f64);
            let quotas: Vec<f64> =
                weights.iter().zip(&rest).map(|(&w, &cap)| (scale * w).clamp(0.0, cap as f64)).collect();
            round_to_total(&quotas, &rest, extra, prn).into_iter().map(|k| k + 1).collect()
        }
    }
}

/// `q` (≥ 0) rounded up when `u` (uniform in [0, 1)) is below its fractional part, else down:
/// expectation `q`.
fn round_by(u: f64, q: f64) -> u64 {
    let floor = q.floor();
    floor as u64 + u64::from(u < q - floor)
}

/// Every cap, when `budget` reaches their sum (with a warning when it is more); `None` when the
/// budget must be shared.
fn every_cap(budget: usize, caps: &[u64], warnings: &mut Vec<SampleWarning>) -> Option<Vec<u64>> {
    let available: u64 = caps.iter().sum();
    if (budget as u64) < available {
        return None;
    }
    if budget as u64 > available {
        warnings.push(SampleWarning::BudgetAboveAvailable { budget, available });
    }
    Some(caps.to_vec())
}

/// The s ≥ 0 with Σ clamp(s · w_g, lo, cap_g) = total, for lo · #groups ≤ total < Σ cap.
fn solve_scale(weights: &[f64], caps: &[u64], lo: f64, total: f64) -> f64 {
    // F(s) = constant + slope · s between breakpoints: a group enters the linear part at lo / w
    // and leaves it (saturated) at cap / w.
    let mut events: Vec<(f64, bool, usize)> = Vec::with_capacity(2 * weights.len());
    for (g, (&w, &cap)) in weights.iter().zip(caps).enumerate() {
        events.push((lo / w, true, g));
        events.push((cap as f64 / w, false, g));
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    let (mut constant, mut slope) = (lo * weights.len() as f64, 0.0);
    let mut last = 0.0;
    for (s, enter, g) in events {
        let value = constant + slope * s;
        if value >= total {
            // F is continuous and non-decreasing: the crossing is in [last, s].
            return if slope > 0.0 { ((total - constant) / slope).clamp(last, s) } else { last };
        }
        if enter {
            constant -= lo;
            slope += weights[g];
        } else {
            constant += caps[g] as f64;
            slope -= weights[g];
        }
        last = s;
    }
    last
}

/// Integers k_g ∈ [⌊q_g⌋, ⌈q_g⌉] ∩ [0, cap_g] with Σ k_g = total (Σ q_g ≈ total): the floors,
/// then one more for the groups [`order_sample`] picks by their fractional parts.
fn round_to_total(quotas: &[f64], caps: &[u64], total: u64, prn: &[f64]) -> Vec<u64> {
    let mut counts: Vec<u64> = quotas.iter().zip(caps).map(|(&q, &cap)| (q.floor() as u64).min(cap)).collect();
    let assigned: u64 = counts.iter().sum();
    let mut deficit = total.saturating_sub(assigned);
    let fractions: Vec<f64> =
        quotas.iter().zip(&counts).zip(caps).map(|((&q, &k), &cap)| if k < cap { q - k as f64 } else { 0.0 }).collect();
    for g in order_sample(&fractions, deficit, prn) {
        counts[g] += 1;
        deficit -= 1;
    }
    // Rounding left something over: the largest remaining fractions, then any room left.
    if deficit > 0 {
        let mut open: Vec<usize> = (0..counts.len()).filter(|&g| counts[g] < caps[g]).collect();
        open.sort_by(|&a, &b| {
            (quotas[b] - counts[b] as f64).total_cmp(&(quotas[a] - counts[a] as f64)).then(a.cmp(&b))
        });
        for g in open.into_iter().cycle().take(4 * counts.len() + deficit as usize) {
            if deficit == 0 {
                break;
            }
            if counts[g] < caps[g] {
                counts[g] += 1;
                deficit -= 1;
            }
        }
    }
    debug_assert_eq!(counts.iter().sum::<u64>(), total);
    counts
}

/// Pareto order sampling: of the groups with a fraction `f_g` ∈ (0, 1) (Σ f_g ≈ `count`), the
/// `count` (at most that many) with the smallest ranks `u_g (1 − f_g) / ((1 − u_g) f_g)`, ties
/// by index, `u_g` the group's permanent random number. Each is picked with probability close to
/// `f_g`, and a group whose fraction moves a little keeps its pick unless its rank crosses the
/// cut: how the rounding stays put as groups come and go. O(groups).
pub(crate) fn order_sample(fractions: &[f64], count: u64, prn: &[f64]) -> Vec<usize> {
    debug_assert_eq!(fractions.len(), prn.len());
    let mut ranked: Vec<(f64, usize)> = fractions
        .iter()
        .zip(prn)
        .enumerate()
        .filter(|&(_, (&f, _))| f > 0.0)
        .map(|(g, (&f, &u))| (if f >= 1.0 { 0.0 } else { u * (1.0 - f) / ((1.0 - u) * f) }, g))
        .collect();
    let count = (count as usize).min(ranked.len());
    let by_rank = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    if count < ranked.len() && count > 0 {
        ranked.select_nth_unstable_by(count - 1, by_rank);
    }
    ranked.truncate(count);
    ranked.into_iter().map(|(_, g)| g).collect()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn budget_quotas_sum_exactly_and_cover() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let weights: Vec<f64> = (1..=50).map(|k| (k * k) as f64).collect();
        let caps: Vec<u64> = (1..=50).map(|k| 3 * k as u64).collect();
        for budget in [50, 51, 77, 400, 1000, 3824] {
            let mut warnings = Vec::new();
            let q = group_quotas(
                &weights,
                &caps,
                SampleSize::Budget(budget),
                &uniforms(&mut rng, weights.len()),
                &mut warnings,
            );
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        let mut warnings = Vec::new();
        let q =
            group_quotas(&weights, &caps, SampleSize::Budget(20), &uniforms(&mut rng, weights.len()), &mut warnings);
        assert_eq!(q.iter().sum::<u64>(), 20);
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 20, groups: 50 }]));
        let mut warnings = Vec::new();
        let q =
            group_quotas(&weights, &caps, SampleSize::Budget(5000), &uniforms(&mut rng, weights.len()), &mut warnings);
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3825 }]));
    }

    #[test]
    fn first_then_quotas_give_one_each_then_follow_weights() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let weights = [1.0, 2.0, 3.5, 100.0];
        let caps = [1, 1000, 1000, 1000];
        for budget in [4, 5, 17, 300] {
            let mut warnings = Vec::new();
            let q = first_then_quotas(
                &weights,
                &caps,
                SampleSize::Budget(budget),
                &uniforms(&mut rng, weights.len()),
                &mut warnings,
            );
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        // The rest follows the weights with no floor: 1 + 13 · w / Σw for the three open groups.
        let mut mean = [0.0; 3];
        for _ in 0..2000 {
            let q = first_then_quotas(
                &[1.0, 2.0, 3.5],
                &[1000; 3],
                SampleSize::Budget(16),
                &uniforms(&mut rng, 3),
                &mut Vec::new(),
            );
            assert_eq!(q.iter().sum::<u64>(), 16);
            (0..3).for_each(|g| mean[g] += q[g] as f64 / 2000.0);
        }
        for (g, expected) in [3.0, 5.0, 8.0].iter().enumerate() {
            assert!((mean[g] - expected).abs() < 0.05, "{mean:?}");
        }
        let mut warnings = Vec::new();
        let q = first_then_quotas(
            &weights,
            &caps,
            SampleSize::Budget(2),
            &uniforms(&mut rng, weights.len()),
            &mut warnings,
        );
        assert_eq!(q.iter().sum::<u64>(), 2);
        assert!(q.iter().all(|&k| k <= 1));
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 2, groups: 4 }]));
        let mut warnings = Vec::new();
        let q = first_then_quotas(
            &weights,
            &caps,
            SampleSize::Budget(5000),
            &uniforms(&mut rng, weights.len()),
            &mut warnings,
        );
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3001 }]));
        // Rate mode: one, plus r · w rounded at random, capped.
        let q = first_then_quotas(
            &[0.1, 10.0, 4.0],
            &[5, 5, 2],
            SampleSize::Rate(0.5),
            &uniforms(&mut rng, 3),
            &mut Vec::new(),
        );
        assert!(q[0] == 1 || q[0] == 2, "{q:?}");
        assert_eq!(q[1..], [5, 2]);
    }

    #[test]
    fn quotas_follow_weights() {
        // Uncapped: proportional to the weights; randomised rounding keeps the expectation.
        let weights = [1.0, 2.0, 3.5];
        let caps = [1000, 1000, 1000];
        let mut mean = [0.0; 3];
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..2000 {
            let q = group_quotas(
                &weights,
                &caps,
                SampleSize::Budget(13),
                &uniforms(&mut rng, weights.len()),
                &mut Vec::new(),
            );
            assert_eq!(q.iter().sum::<u64>(), 13);
            for g in 0..3 {
                mean[g] += q[g] as f64 / 2000.0;
            }
        }
        for (g, expected) in [2.0, 4.0, 7.0].iter().enumerate() {
            assert!((mean[g] - expected).abs() < 0.05, "{mean:?}");
        }
        // Rate mode: at least one, rounded at random.
        let q = group_quotas(&[0.1, 10.0], &[5, 5], SampleSize::Rate(0.5), &uniforms(&mut rng, 2), &mut Vec::new());
        assert_eq!(q, [1, 5]);
    }

    #[test]
    fn order_sampling_keeps_each_expectation_and_the_total() {
        // Forty groups of uneven weights: over permanent numbers each quota's mean is its share
        // (400 · w / Σw, all above the floor of one), and every draw sums to the budget.
        let weights: Vec<f64> = (0..40).map(|g| 1.0 + (g * 37 % 23) as f64 / 3.0).collect();
        let total: f64 = weights.iter().sum();
        let caps = vec![1000; 40];
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut mean = vec![0.0; 40];
        for _ in 0..4000 {
            let q = group_quotas(&weights, &caps, SampleSize::Budget(400), &uniforms(&mut rng, 40), &mut Vec::new());
            assert_eq!(q.iter().sum::<u64>(), 400);
            for (g, &k) in q.iter().enumerate() {
                let share = 400.0 * weights[g] / total;
                assert!(k == share.floor() as u64 || k == share.ceil() as u64, "{g}: {k} for {share}");
                mean[g] += k as f64 / 4000.0;
            }
        }
        for (g, &w) in weights.iter().enumerate() {
            assert!((mean[g] - 400.0 * w / total).abs() < 0.04, "{g}: {} for {}", mean[g], 400.0 * w / total);
        }
    }

    #[test]
    fn a_group_keeps_its_rounding_when_others_come() {
        // 2,000 groups at about three samples per unit weight, then 100 more with the budget
        // grown to keep that scale: the old groups' quotas are as they were, and their rounding
        // moves for a few only (systematic rounding along the groups would move about half).
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let weights: Vec<f64> = (0..2100).map(|_| rng.random_range(1.0..5.0)).collect();
        let prn = uniforms(&mut rng, 2100);
        let caps = vec![1000; 2100];
        let budget = |n: usize| (3.0 * weights[..n].iter().sum::<f64>()).round() as usize;
        let quotas = |n: usize| {
            group_quotas(&weights[..n], &caps[..n], SampleSize::Budget(budget(n)), &prn[..n], &mut Vec::new())
        };
        let (before, after) = (quotas(2000), quotas(2100));
        let moved = (0..2000).filter(|&g| before[g] != after[g]).count();
        assert!(moved <= 40, "{moved} of 2000 groups moved");
        // The rounding still reads the numbers: others move about half of the groups.
        let other = uniforms(&mut rng, 2100);
        let redrawn = group_quotas(
            &weights[..2000],
            &caps[..2000],
            SampleSize::Budget(budget(2000)),
            &other[..2000],
            &mut Vec::new(),
        );
        let differ = (0..2000).filter(|&g| before[g] != redrawn[g]).count();
        assert!(differ > 500, "{differ}");
    }
}

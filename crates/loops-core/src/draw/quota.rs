//! Samples per group: quotas proportional to weights, capped, rounded at random to integers
//! that keep the expectation (σ_1 and σ_ρ).

use rand::{Rng, RngExt};

use super::{SampleSize, SampleWarning};

/// Samples per group for σ_1 (`weights` all 1) and σ_ρ (`weights` = rows): quotas
/// `q_g = clamp(s · w_g, lo, cap_g)`, rounded at random to integers with the same expectation.
///
/// Rate mode: s is the rate, lo = 1, each group rounded independently. Budget mode: s solves
/// Σ q_g = B exactly (a sweep over the breakpoints of the piecewise linear sum), lo = 1 when
/// B ≥ #groups (P1), else 0 with a warning; then systematic sampling of the fractional parts
/// gives integers summing to exactly B (all caps when B exceeds them, with a warning).
pub(crate) fn group_quotas<R: Rng + ?Sized>(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    rng: &mut R,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    let groups = weights.len();
    match size {
        SampleSize::Rate(rate) => weights
            .iter()
            .zip(caps)
            .map(|(&w, &cap)| round_at_random((rate * w).clamp(1.0, cap as f64), rng).min(cap))
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
            round_to_total(&quotas, caps, budget as u64, rng)
        }
    }
}

/// Samples per group for the closest-first sampler: one per group first (its closest pair),
/// then the rest in proportion to `weights` (the rows, as σ_ρ): `q_g = 1 + clamp(s · w_g, 0,
/// cap_g − 1)`, rounded at random as [`group_quotas`] does. Every cap is at least 1.
///
/// Rate mode: `1 + r · w_g` rounded at random, at most the cap. Budget mode: the rest, `B −
/// #groups`, is shared without a floor (every group has its one already); a budget below the
/// number of groups gives one sample to that many groups, chosen ∝ their weight, with a warning;
/// a budget above every cap gives all of them, with a warning.
pub(crate) fn first_then_quotas<R: Rng + ?Sized>(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    rng: &mut R,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    debug_assert!(caps.iter().all(|&cap| cap >= 1));
    match size {
        SampleSize::Rate(rate) => {
            weights.iter().zip(caps).map(|(&w, &cap)| (1 + round_at_random(rate * w, rng)).min(cap)).collect()
        }
        SampleSize::Budget(budget) => {
            if let Some(all) = every_cap(budget, caps, warnings) {
                return all;
            }
            if budget < weights.len() {
                return group_quotas(weights, &vec![1; weights.len()], size, rng, warnings);
            }
            let rest: Vec<u64> = caps.iter().map(|&cap| cap - 1).collect();
            let extra = (budget - weights.len()) as u64;
            let scale = solve_scale(weights, &rest, 0.0, extra as f64);
            let quotas: Vec<f64> =
                weights.iter().zip(&rest).map(|(&w, &cap)| (scale * w).clamp(0.0, cap as f64)).collect();
            round_to_total(&quotas, &rest, extra, rng).into_iter().map(|k| k + 1).collect()
        }
    }
}

/// `q` rounded at random to one of its two neighbouring integers, with expectation `q` (≥ 0).
fn round_at_random<R: Rng + ?Sized>(q: f64, rng: &mut R) -> u64 {
    let floor = q.floor();
    floor as u64 + u64::from(rng.random::<f64>() < q - floor)
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

/// Integers k_g ∈ [⌊q_g⌋, ⌈q_g⌉] ∩ [0, cap_g] with Σ k_g = total, k_g = ⌈q_g⌉ with probability
/// about the fractional part (systematic sampling); Σ q_g ≈ total.
fn round_to_total<R: Rng + ?Sized>(quotas: &[f64], caps: &[u64], total: u64, rng: &mut R) -> Vec<u64> {
    let mut counts: Vec<u64> = quotas.iter().zip(caps).map(|(&q, &cap)| (q.floor() as u64).min(cap)).collect();
    let assigned: u64 = counts.iter().sum();
    let mut deficit = total.saturating_sub(assigned);
    let fractions: Vec<f64> =
        quotas.iter().zip(&counts).zip(caps).map(|((&q, &k), &cap)| if k < cap { q - k as f64 } else { 0.0 }).collect();
    let sum: f64 = fractions.iter().sum();
    if deficit > 0 && sum > 0.0 {
        let step = sum / deficit as f64;
        let mut point = rng.random::<f64>() * step;
        let mut start = 0.0;
        for (g, &fraction) in fractions.iter().enumerate() {
            let end = start + fraction;
            let mut hit = false;
            while point < end && deficit > 0 {
                hit = true;
                point += step;
            }
            if hit {
                counts[g] += 1;
                deficit -= 1;
            }
            start = end;
        }
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
            let q = group_quotas(&weights, &caps, SampleSize::Budget(budget), &mut rng, &mut warnings);
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        let mut warnings = Vec::new();
        let q = group_quotas(&weights, &caps, SampleSize::Budget(20), &mut rng, &mut warnings);
        assert_eq!(q.iter().sum::<u64>(), 20);
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 20, groups: 50 }]));
        let mut warnings = Vec::new();
        let q = group_quotas(&weights, &caps, SampleSize::Budget(5000), &mut rng, &mut warnings);
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
            let q = first_then_quotas(&weights, &caps, SampleSize::Budget(budget), &mut rng, &mut warnings);
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        // The rest follows the weights with no floor: 1 + 13 · w / Σw for the three open groups.
        let mut mean = [0.0; 3];
        for _ in 0..2000 {
            let q = first_then_quotas(&[1.0, 2.0, 3.5], &[1000; 3], SampleSize::Budget(16), &mut rng, &mut Vec::new());
            assert_eq!(q.iter().sum::<u64>(), 16);
            (0..3).for_each(|g| mean[g] += q[g] as f64 / 2000.0);
        }
        for (g, expected) in [3.0, 5.0, 8.0].iter().enumerate() {
            assert!((mean[g] - expected).abs() < 0.05, "{mean:?}");
        }
        let mut warnings = Vec::new();
        let q = first_then_quotas(&weights, &caps, SampleSize::Budget(2), &mut rng, &mut warnings);
        assert_eq!(q.iter().sum::<u64>(), 2);
        assert!(q.iter().all(|&k| k <= 1));
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 2, groups: 4 }]));
        let mut warnings = Vec::new();
        let q = first_then_quotas(&weights, &caps, SampleSize::Budget(5000), &mut rng, &mut warnings);
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3001 }]));
        // Rate mode: one, plus r · w rounded at random, capped.
        let q = first_then_quotas(&[0.1, 10.0, 4.0], &[5, 5, 2], SampleSize::Rate(0.5), &mut rng, &mut Vec::new());
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
            let q = group_quotas(&weights, &caps, SampleSize::Budget(13), &mut rng, &mut Vec::new());
            assert_eq!(q.iter().sum::<u64>(), 13);
            for g in 0..3 {
                mean[g] += q[g] as f64 / 2000.0;
            }
        }
        for (g, expected) in [2.0, 4.0, 7.0].iter().enumerate() {
            assert!((mean[g] - expected).abs() < 0.05, "{mean:?}");
        }
        // Rate mode: at least one, rounded at random.
        let q = group_quotas(&[0.1, 10.0], &[5, 5], SampleSize::Rate(0.5), &mut rng, &mut Vec::new());
        assert_eq!(q, [1, 5]);
    }
}

//! Samples per group: quotas proportional to weights, capped, rounded at random to integers
//! that keep the expectation (σ_1 and σ_ρ).
//!
//! The rounding draws on numbers that belong to the groups rather than on a stream read in
//! group order ([`Numbers`]): each group's *permanent random number*, and, where the groups
//! fall into strata (a fleet's session pairs), two numbers per stratum. A budget's extra picks
//! go to the strata by Pareto order sampling of their numbers, then, within each stratum, to
//! its groups by systematic sampling in group order from the stratum's offset, so that the
//! picks are spread along the stratum (a trajectory's components in time order: a small budget
//! corrects every stretch of a drive, not a random few) and a stratum keeps its picks when
//! other strata are added or removed (as survey statistics coordinate samples over time). A
//! fleet store's next draw then asks again only where the quotas moved.

use rand::{Rng, RngExt};

use super::{SampleSize, SampleWarning};

/// `n` uniform numbers in [0, 1) from `rng`: permanent random numbers for groups that have no
/// cells of their own to hash (detection clusters).
pub(crate) fn uniforms<R: Rng + ?Sized>(rng: &mut R, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random::<f64>()).collect()
}

/// What rounds the quotas of groups at random: each group's permanent random number (`prn`,
/// uniform in [0, 1)), which rounds a rate's quotas one by one, and the strata that share a
/// budget's extra picks ([`order_sample`]): each group's stratum, in group order within it,
/// and each stratum's two uniform numbers, one that ranks it among the strata (Pareto order
/// sampling) and one that offsets the systematic picks within it.
#[derive(Debug, Clone)]
pub(crate) struct Numbers {
    /// Each group's permanent random number.
    pub(crate) prn: Vec<f64>,
    /// Each group's stratum.
    stratum: Vec<u32>,
    /// Each stratum's rank number and offset.
    strata: Vec<[f64; 2]>,
}

impl Numbers {
    /// Groups each a stratum of its own: a budget's extra picks by Pareto order sampling of
    /// the groups' numbers alone.
    #[cfg(test)]
    pub(crate) fn independent(prn: Vec<f64>) -> Self {
        let stratum = (0..prn.len() as u32).collect();
        let strata = prn.iter().map(|&u| [u, 0.0]).collect();
        Self { prn, stratum, strata }
    }

    /// Groups in strata: group `g` in stratum `stratum[g]`, whose numbers are `strata[k]`
    /// (its rank number, its offset).
    pub(crate) fn stratified(prn: Vec<f64>, stratum: Vec<u32>, strata: Vec<[f64; 2]>) -> Self {
        debug_assert_eq!(prn.len(), stratum.len());
        debug_assert!(stratum.iter().all(|&k| (k as usize) < strata.len()));
        Self { prn, stratum, strata }
    }

    /// All groups in one stratum, offset by `offset` (uniform in [0, 1)): systematic picks
    /// along the groups (detection clusters in time order).
    pub(crate) fn one_stratum(prn: Vec<f64>, offset: f64) -> Self {
        let stratum = vec![0; prn.len()];
        Self { prn, stratum, strata: vec![[0.0, offset]] }
    }
}

/// Samples per group for σ_1 (`weights` all 1) and σ_ρ (`weights` = rows): quotas
/// `q_g = clamp(s · w_g, lo, cap_g)`, rounded at random to integers with (about) the same
/// expectation, by `numbers`.
///
/// Rate mode: s is the rate, lo = 1, each group rounded up when its permanent random number is
/// below its fractional part. Budget mode: s solves Σ q_g = B exactly (a sweep over the
/// breakpoints of the piecewise linear sum), lo = 1 when B ≥ #groups (P1), else 0 with a
/// warning; then the fractional parts' picks by strata ([`order_sample`], through
/// [`round_to_total`]) give integers summing to exactly B (all caps when B exceeds them, with a
/// warning).
pub(crate) fn group_quotas(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    numbers: &Numbers,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    debug_assert_eq!(numbers.prn.len(), weights.len());
    let groups = weights.len();
    match size {
        SampleSize::Rate(rate) => weights
            .iter()
            .zip(caps)
            .zip(&numbers.prn)
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
            round_to_total(&quotas, caps, budget as u64, numbers)
        }
    }
}

/// Samples per group for the closest-first sampler: one per group first (its closest pair),
/// then the rest in proportion to `weights` (the rows, as σ_ρ): `q_g = 1 + clamp(s · w_g, 0,
/// cap_g − 1)`, rounded at random by `numbers` as [`group_quotas`] does. Every cap is at least 1.
///
/// Rate mode: `1 + r · w_g` rounded at random, at most the cap. Budget mode: the rest, `B −
/// #groups`, is shared without a floor (every group has its one already); a budget below the
/// number of groups gives one sample to that many groups, chosen ∝ their weight, with a warning;
/// a budget above every cap gives all of them, with a warning.
pub(crate) fn first_then_quotas(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    numbers: &Numbers,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    debug_assert!(caps.iter().all(|&cap| cap >= 1));
    match size {
        SampleSize::Rate(rate) => weights
            .iter()
            .zip(caps)
            .zip(&numbers.prn)
            .map(|((&w, &cap), &u)| (1 + round_by(u, rate * w)).min(cap))
            .collect(),
        SampleSize::Budget(budget) => {
            if let Some(all) = every_cap(budget, caps, warnings) {
                return all;
            }
            if budget < weights.len() {
                return group_quotas(weights, &vec![1; weights.len()], size, numbers, warnings);
            }
            let rest: Vec<u64> = caps.iter().map(|&cap| cap - 1).collect();
            let extra = (budget - weights.len()) as u64;
            let scale = solve_scale(weights, &rest, 0.0, extra as f64);
            let quotas: Vec<f64> =
                weights.iter().zip(&rest).map(|(&w, &cap)| (scale * w).clamp(0.0, cap as f64)).collect();
            round_to_total(&quotas, &rest, extra, numbers).into_iter().map(|k| k + 1).collect()
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
///
/// F(s) = constant + slope · s between breakpoints: a group enters the linear part at lo / w
/// and leaves it (saturated) at cap / w. The breakpoints are visited in order up to the first
/// where F reaches `total`; only those at or below a breakpoint where F is already past it are
/// sorted (a fleet's draw has a budget far below its hundreds of thousands of components, so
/// that the crossing comes after few of them): the same breakpoints in the same order, and so
/// the same scale, bit for bit, as sorting them all. O(groups) where few groups saturate below
/// the crossing, O(groups log groups) at worst.
fn solve_scale(weights: &[f64], caps: &[u64], lo: f64, total: f64) -> f64 {
    if let Some(bound) = past_total(weights, caps, lo, total)
        && let Ok(s) = cross(weights, caps, lo, total, breakpoints(weights, caps, lo, Some(bound)))
    {
        return s;
    }
    // F stays below `total` (but for rounding, it reaches Σ cap > total): the last breakpoint.
    cross(weights, caps, lo, total, breakpoints(weights, caps, lo, None)).unwrap_or_else(|last| last)
}

/// The breakpoints of [`solve_scale`]'s F with their group and whether it enters the linear
/// part there, in group order: all of them, or the sorted order's first ones up to the first
/// at `bound` (by `total_cmp`, entries before exits, then by group, as they are sorted): those
/// below it and the first at it.
fn breakpoints(weights: &[f64], caps: &[u64], lo: f64, bound: Option<f64>) -> Vec<(f64, bool, usize)> {
    let Some(bound) = bound else {
        let mut events = Vec::with_capacity(2 * weights.len());
        for (g, (&w, &cap)) in weights.iter().zip(caps).enumerate() {
            events.extend(group_breakpoints(w, cap, lo).map(|(s, enter)| (s, enter, g)));
        }
        return events;
    };
    let mut events = Vec::new();
    let mut at: Option<(bool, usize)> = None;
    for (g, (&w, &cap)) in weights.iter().zip(caps).enumerate() {
        for (s, enter) in group_breakpoints(w, cap, lo) {
            match s.total_cmp(&bound) {
                std::cmp::Ordering::Less => events.push((s, enter, g)),
                std::cmp::Ordering::Equal if at.is_none_or(|(first, _)| enter && !first) => at = Some((enter, g)),
                _ => {}
            }
        }
    }
    events.extend(at.map(|(enter, g)| (bound, enter, g)));
    events
}

/// Where a group of weight `w` and cap `cap` enters F's linear part (lo / w) and leaves it,
/// saturated (cap / w), each with whether it enters there.
fn group_breakpoints(w: f64, cap: u64, lo: f64) -> [(f64, bool); 2] {
    [(lo / w, true), (cap as f64 / w, false)]
}

/// A breakpoint of [`solve_scale`]'s F (lo / w or cap / w of a group) at which F ≥ `total`,
/// the smallest at or above a scale where it is (from total / Σ w, doubled until F, summed
/// directly, reaches `total`), or the last breakpoint where that scale is past them all;
/// `None` when no such scale is found.
fn past_total(weights: &[f64], caps: &[u64], lo: f64, total: f64) -> Option<f64> {
    let f = |s: f64| weights.iter().zip(caps).map(|(&w, &cap)| (s * w).max(lo).min(cap as f64)).sum::<f64>();
    let mut s = total / weights.iter().sum::<f64>();
    if !(s.is_finite() && s > 0.0) {
        return None;
    }
    for _ in 0..64 {
        if f(s) >= total {
            // The first breakpoint from s on, or the last one (beyond it F is Σ cap).
            let (mut first, mut last) = (None::<f64>, None::<f64>);
            for (b, _) in weights.iter().zip(caps).flat_map(|(&w, &cap)| group_breakpoints(w, cap, lo)) {
                if b.total_cmp(&s).is_ge() && first.is_none_or(|f| b.total_cmp(&f).is_lt()) {
                    first = Some(b);
                }
                if last.is_none_or(|l| b.total_cmp(&l).is_gt()) {
                    last = Some(b);
                }
            }
            return first.or(last);
        }
        s *= 2.0;
    }
    None
}

/// The scale where F crosses `total`, walking `events` (breakpoints with their group, whether
/// it enters the linear part there) in order; else the last breakpoint, as an error.
fn cross(
    weights: &[f64],
    caps: &[u64],
    lo: f64,
    total: f64,
    mut events: Vec<(f64, bool, usize)>,
) -> std::result::Result<f64, f64> {
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    let (mut constant, mut slope) = (lo * weights.len() as f64, 0.0);
    let mut last = 0.0;
    for (s, enter, g) in events {
        let value = constant + slope * s;
        if value >= total {
            // F is continuous and non-decreasing: the crossing is in [last, s].
            return Ok(if slope > 0.0 { ((total - constant) / slope).clamp(last, s) } else { last });
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
    Err(last)
}

/// Integers k_g ∈ [⌊q_g⌋, ⌈q_g⌉] ∩ [0, cap_g] with Σ k_g = total (Σ q_g ≈ total): the floors,
/// then one more for the groups [`order_sample`] picks by their fractional parts.
fn round_to_total(quotas: &[f64], caps: &[u64], total: u64, numbers: &Numbers) -> Vec<u64> {
    let mut counts: Vec<u64> = quotas.iter().zip(caps).map(|(&q, &cap)| (q.floor() as u64).min(cap)).collect();
    let assigned: u64 = counts.iter().sum();
    let mut deficit = total.saturating_sub(assigned);
    let fractions: Vec<f64> =
        quotas.iter().zip(&counts).zip(caps).map(|((&q, &k), &cap)| if k < cap { q - k as f64 } else { 0.0 }).collect();
    for g in order_sample(&fractions, deficit, numbers) {
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

/// The groups (at most `count`, each once) whose fractional part `f_g` ∈ (0, 1) (Σ f_g ≈
/// `count`) takes one more pick, by `numbers`: each stratum's share, the sum of its groups'
/// fractions, is its floor plus one more for the strata [`pareto`] picks by their fractional
/// parts and rank numbers; then a stratum's share of picks goes to its groups by systematic
/// sampling in group order (points `step · (offset + k)`, `step` = its fractions' sum over its
/// share, each group taken when a point falls in its stretch of the fractions' running sum, at
/// most once). Each group is picked with a probability close to `f_g`; the picks of a stratum
/// are spread along its groups, and a stratum keeps its picks while its own fractions and its
/// rank's cut stay put. Fewer than `count` where points fall twice in one group (the caller
/// gives what is left to the largest fractions). O(groups + strata).
pub(crate) fn order_sample(fractions: &[f64], count: u64, numbers: &Numbers) -> Vec<usize> {
    debug_assert_eq!(fractions.len(), numbers.stratum.len());
    let strata = numbers.strata.len();
    let mut sums = vec![0.0; strata];
    for (g, &f) in fractions.iter().enumerate() {
        if f > 0.0 {
            sums[numbers.stratum[g] as usize] += f;
        }
    }
    let mut shares: Vec<u64> = sums.iter().map(|&sum| sum.floor() as u64).collect();
    let floors: u64 = shares.iter().sum();
    let parts: Vec<f64> = sums.iter().zip(&shares).map(|(&sum, &k)| sum - k as f64).collect();
    let ranks: Vec<f64> = numbers.strata.iter().map(|&[rank, _]| rank).collect();
    for k in pareto(&parts, count.saturating_sub(floors), &ranks) {
        shares[k] += 1;
    }
    // Each stratum's walk: the step, the next point, the running sum, the picks left.
    let mut walks: Vec<(f64, f64, f64, u64)> = (0..strata)
        .map(|k| {
            let step = if shares[k] > 0 { sums[k] / shares[k] as f64 } else { 0.0 };
            (step, step * numbers.strata[k][1], 0.0, shares[k])
        })
        .collect();
    let mut picked = Vec::with_capacity(count as usize);
    for (g, &f) in fractions.iter().enumerate() {
        if f <= 0.0 {
            continue;
        }
        let (step, point, start, left) = &mut walks[numbers.stratum[g] as usize];
        let end = *start + f;
        if *left > 0 && *point < end {
            picked.push(g);
            *left -= 1;
            while *point < end {
                *point += *step;
            }
        }
        *start = end;
    }
    picked.truncate(count as usize);
    picked
}

/// Pareto order sampling: of the groups with a fraction `f_g` ∈ (0, 1) (Σ f_g ≈ `count`), the
/// `count` (at most that many) with the smallest ranks `u_g (1 − f_g) / ((1 − u_g) f_g)`, ties
/// by index, `u_g` the group's permanent random number. Each is picked with probability close to
/// `f_g`, and a group whose fraction moves a little keeps its pick unless its rank crosses the
/// cut. O(groups).
fn pareto(fractions: &[f64], count: u64, prn: &[f64]) -> Vec<usize> {
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

    /// `n` independent permanent random numbers from `rng`, each group a stratum of its own.
    fn independent(rng: &mut ChaCha8Rng, n: usize) -> Numbers {
        Numbers::independent(uniforms(rng, n))
    }

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
                &independent(&mut rng, weights.len()),
                &mut warnings,
            );
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        let mut warnings = Vec::new();
        let q =
            group_quotas(&weights, &caps, SampleSize::Budget(20), &independent(&mut rng, weights.len()), &mut warnings);
        assert_eq!(q.iter().sum::<u64>(), 20);
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 20, groups: 50 }]));
        let mut warnings = Vec::new();
        let q = group_quotas(
            &weights,
            &caps,
            SampleSize::Budget(5000),
            &independent(&mut rng, weights.len()),
            &mut warnings,
        );
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3825 }]));
    }

    /// [`solve_scale`] as it was: every breakpoint sorted, then walked.
    fn solve_scale_sorting_all(weights: &[f64], caps: &[u64], lo: f64, total: f64) -> f64 {
        cross(weights, caps, lo, total, breakpoints(weights, caps, lo, None)).unwrap_or_else(|last| last)
    }

    #[test]
    fn the_scale_is_that_of_every_breakpoint_sorted_bit_for_bit() {
        // Budgets far below the groups (no floor), at and above them (a floor of one), and
        // near every cap; weights spread over six orders of magnitude or all equal (ties), caps
        // near the weights (many groups saturate before the crossing) or far above them.
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let (mut checked, mut short) = (0, 0);
        for case in 0..400 {
            let groups = rng.random_range(1..300);
            let weights: Vec<f64> = (0..groups)
                .map(|_| match case % 3 {
                    0 => 10f64.powf(rng.random_range(-3.0..3.0)),
                    1 => 4.0,
                    _ => rng.random_range(1..60) as f64,
                })
                .collect();
            let caps: Vec<u64> = weights
                .iter()
                .map(|&w| if case % 2 == 0 { (w.ceil() as u64).max(1) } else { rng.random_range(1..5000) })
                .collect();
            let available: u64 = caps.iter().sum();
            for budget in [1, groups / 3, groups, groups + 1, (available / 2) as usize, available as usize - 1] {
                let lo = if budget >= groups { 1.0 } else { 0.0 };
                if (budget as u64) >= available || budget == 0 || lo * groups as f64 > budget as f64 {
                    continue;
                }
                let (fast, all) = (
                    solve_scale(&weights, &caps, lo, budget as f64),
                    solve_scale_sorting_all(&weights, &caps, lo, budget as f64),
                );
                assert_eq!(fast.to_bits(), all.to_bits(), "case {case}, budget {budget}: {fast} against {all}");
                checked += 1;
                // ... from the breakpoints below the bound alone, not by sorting them all again.
                let bound = past_total(&weights, &caps, lo, budget as f64);
                let prefix = bound.map(|b| breakpoints(&weights, &caps, lo, Some(b)));
                if prefix.is_some_and(|p| cross(&weights, &caps, lo, budget as f64, p).is_ok()) {
                    short += 1;
                }
            }
        }
        assert!(checked > 1500, "{checked}");
        assert!(short as f64 > 0.99 * checked as f64, "{short} of {checked} from a prefix");
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
                &independent(&mut rng, weights.len()),
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
                &independent(&mut rng, 3),
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
            &independent(&mut rng, weights.len()),
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
            &independent(&mut rng, weights.len()),
            &mut warnings,
        );
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3001 }]));
        // Rate mode: one, plus r · w rounded at random, capped.
        let q = first_then_quotas(
            &[0.1, 10.0, 4.0],
            &[5, 5, 2],
            SampleSize::Rate(0.5),
            &independent(&mut rng, 3),
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
                &independent(&mut rng, weights.len()),
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
        let q = group_quotas(&[0.1, 10.0], &[5, 5], SampleSize::Rate(0.5), &independent(&mut rng, 2), &mut Vec::new());
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
            let q = group_quotas(&weights, &caps, SampleSize::Budget(400), &independent(&mut rng, 40), &mut Vec::new());
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
            let numbers = Numbers::independent(prn[..n].to_vec());
            group_quotas(&weights[..n], &caps[..n], SampleSize::Budget(budget(n)), &numbers, &mut Vec::new())
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
            &Numbers::independent(other[..2000].to_vec()),
            &mut Vec::new(),
        );
        let differ = (0..2000).filter(|&g| before[g] != redrawn[g]).count();
        assert!(differ > 500, "{differ}");
    }

    /// The groups a budget below their number picks, in group order.
    fn picks(q: &[u64]) -> Vec<usize> {
        q.iter().enumerate().filter(|&(_, &k)| k > 0).map(|(g, _)| g).collect()
    }

    #[test]
    fn picks_in_a_stratum_are_spread_along_it() {
        // 1,000 equal groups in one stratum, a budget of 10: one pick every 100 groups, from
        // the offset on; independent numbers leave gaps of any length.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (weights, caps) = (vec![1.0; 1000], vec![5; 1000]);
        for _ in 0..20 {
            let offset = rng.random::<f64>();
            let numbers = Numbers::one_stratum(uniforms(&mut rng, 1000), offset);
            let q = group_quotas(&weights, &caps, SampleSize::Budget(10), &numbers, &mut Vec::new());
            let at = picks(&q);
            assert_eq!(at.len(), 10);
            assert!(at.windows(2).all(|w| w[1] - w[0] == 100), "{at:?}");
            assert_eq!(at[0], (offset * 100.0) as usize);
        }
        let numbers = Numbers::independent(uniforms(&mut rng, 1000));
        let q = group_quotas(&weights, &caps, SampleSize::Budget(10), &numbers, &mut Vec::new());
        let at = picks(&q);
        assert!(at.windows(2).any(|w| w[1] - w[0] < 50 || w[1] - w[0] > 150), "{at:?}");
    }

    #[test]
    fn stratified_picks_keep_each_expectation_and_the_total() {
        // Three strata of uneven groups and a budget below the groups: over the numbers each
        // group is picked about as often as its share, and every draw sums to the budget.
        let weights: Vec<f64> = (0..60).map(|g| 1.0 + (g * 37 % 23) as f64 / 3.0).collect();
        let stratum: Vec<u32> = (0..60).map(|g| [0, 1, 2][g * 7 % 3]).collect();
        let total: f64 = weights.iter().sum();
        let caps = vec![1; 60];
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mut mean = vec![0.0; 60];
        for _ in 0..6000 {
            let strata = (0..3).map(|_| [rng.random::<f64>(), rng.random::<f64>()]).collect();
            let numbers = Numbers::stratified(uniforms(&mut rng, 60), stratum.clone(), strata);
            let q = group_quotas(&weights, &caps, SampleSize::Budget(17), &numbers, &mut Vec::new());
            assert_eq!(q.iter().sum::<u64>(), 17);
            for (g, &k) in q.iter().enumerate() {
                mean[g] += k as f64 / 6000.0;
            }
        }
        for (g, &w) in weights.iter().enumerate() {
            let share = 17.0 * w / total;
            assert!((mean[g] - share).abs() < 0.03, "{g}: {} for {share}", mean[g]);
        }
    }

    #[test]
    fn a_stratum_keeps_its_picks_when_others_come() {
        // Forty strata of 50 groups each, then ten more with the budget grown to keep the
        // scale: the old strata's picks stay but for a few strata at the cut; other offsets
        // move most of them.
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let weights: Vec<f64> = (0..2500).map(|_| rng.random_range(1.0..5.0)).collect();
        let stratum: Vec<u32> = (0..2500).map(|g| (g / 50) as u32).collect();
        let strata: Vec<[f64; 2]> = (0..50).map(|_| [rng.random::<f64>(), rng.random::<f64>()]).collect();
        let prn = uniforms(&mut rng, 2500);
        let caps = vec![1; 2500];
        let budget = |n: usize| (0.1 * weights[..n].iter().sum::<f64>()).round() as usize;
        let quotas = |n: usize, strata: &[[f64; 2]]| {
            let numbers = Numbers::stratified(prn[..n].to_vec(), stratum[..n].to_vec(), strata[..n / 50].to_vec());
            group_quotas(&weights[..n], &caps[..n], SampleSize::Budget(budget(n)), &numbers, &mut Vec::new())
        };
        let (before, after) = (quotas(2000, &strata), quotas(2500, &strata));
        let moved = (0..40).filter(|&k| (50 * k..50 * k + 50).any(|g| before[g] != after[g])).count();
        assert!(moved <= 8, "{moved} of 40 strata moved");
        let other: Vec<[f64; 2]> = (0..50).map(|_| [rng.random::<f64>(), rng.random::<f64>()]).collect();
        let redrawn = quotas(2000, &other);
        let differ = (0..40).filter(|&k| (50 * k..50 * k + 50).any(|g| before[g] != redrawn[g])).count();
        assert!(differ > 30, "{differ}");
    }
}

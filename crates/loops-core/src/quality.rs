//! How representative a sample is (paper, Sec. 5.2: P1, P2, P3), measured against the exact
//! loop components of S_γ, never against the detection clusters it may have been drawn from.

use crate::cluster::check_epsilon_s;
use crate::error::Result;
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::sample::Samples;

/// A loop component without a sample (a P1 failure: a revisit the back end never hears of).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct MissedComponent {
    /// Component id in [`Loops::components`].
    pub id: usize,
    /// Whether it is a trivial component (it holds the diagonal).
    pub trivial: bool,
    /// Its area, s² (as [`LoopComponent::area_s2`](crate::LoopComponent::area_s2)).
    pub area_s2: f64,
    /// Its lattice cells (as [`LoopComponent::pair_count`](crate::LoopComponent::pair_count)).
    pub pair_count: u64,
    /// Its pose pairs i < j (as [`LoopComponent::pose_pair_count`](crate::LoopComponent::pose_pair_count)).
    pub pose_pair_count: u64,
}

/// P1, P2 and P3 of a sample (paper, Sec. 5.2).
///
/// Components count when they hold at least one pair (i, j) with i < j (a component made of a
/// lone diagonal cell cannot be sampled).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, PartialEq)]
pub struct SampleQuality {
    /// Number of samples.
    pub samples: usize,
    /// Samples outside S_γ (δ(x_i, x_j) > γ: false detections, or baselines with a wider radius).
    pub outside: usize,
    /// Loop components that can be sampled.
    pub components: usize,
    /// P1: components with at least one sample.
    pub covered: usize,
    /// Non-trivial components (revisits proper) that can be sampled.
    pub nontrivial_components: usize,
    /// P1 over the non-trivial components.
    pub nontrivial_covered: usize,
    /// P1: the components without a sample, largest area first.
    pub missed: Vec<MissedComponent>,
    /// The ε of P2, seconds.
    pub epsilon_s: f64,
    /// P2: samples with another sample of the same component within ε in the (t, t′) plane
    /// (Euclidean, seconds): redundant loop constraints.
    pub redundant: usize,
    /// P2: median over samples of the distance to the nearest other sample of the same
    /// component, seconds (`None` when no component has two samples).
    pub median_spacing_s: Option<f64>,
    /// P3: least-squares slope of ln(samples) against ln(area) across the covered components
    /// (≈ 0 for σ_1, ≈ 1 for σ_α, in between for σ_ρ); `None` with fewer than two distinct areas.
    pub p3_slope: Option<f64>,
    /// Number of components in the P3 fit.
    pub p3_components: usize,
    /// Samples per component, by component id.
    pub per_component: Vec<u64>,
    /// The exact component of each sample, in the order of [`Samples::rows`] (`None` outside
    /// S_γ).
    pub sample_components: Vec<Option<usize>>,
    /// Each sample's distance to the nearest other sample of its component, seconds, in the
    /// order of [`Samples::rows`] (`None` when alone in its component or outside S_γ).
    pub nearest_spacing_s: Vec<Option<f64>>,
}

impl SampleQuality {
    /// P1 as a fraction: covered / components (1 when there are no components).
    pub fn coverage(&self) -> f64 {
        if self.components == 0 { 1.0 } else { self.covered as f64 / self.components as f64 }
    }

    /// Samples in no loop component: farther apart than γ, or (with a separation) within γ
    /// but not a revisit. P1 counts the components the other samples reach; these reach none.
    pub fn outside_components(&self) -> usize {
        self.sample_components.iter().filter(|c| c.is_none()).count()
    }

    /// P2 as a fraction: redundant / samples (0 without samples).
    pub fn redundancy(&self) -> f64 {
        if self.samples == 0 { 0.0 } else { self.redundant as f64 / self.samples as f64 }
    }
}

/// Measures P1, P2 and P3 of `samples` against the exact loop components of `loops`: each sample
/// (i, j) belongs to `loops.component_of(i, j)` (samples given only by times are placed on the
/// nearest poses). O(runs + samples log samples).
///
/// # Errors
/// [`Error::InvalidParameter`](crate::Error::InvalidParameter) unless `epsilon_s` is positive and finite;
/// [`Error::TrajectoryMismatch`](crate::Error::TrajectoryMismatch) when the samples index another trajectory;
/// [`Error::DetectionOutsideSpan`](crate::Error::DetectionOutsideSpan) for a sample time outside it;
/// [`Error::Interrupted`](crate::Error::Interrupted) when an [`Interrupt`] installed on this
/// thread is interrupted.
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, UrbanDrive, find_loops, sample_loops, sample_quality};
/// let drive = UrbanDrive { duration_s: 900.0, ..UrbanDrive::default() }.generate()?;
/// let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
/// let sampler = Sampler::new(SamplerKind::One, SampleSize::Budget(500), 0);
/// let samples = sample_loops(&drive.trajectory, &Euclidean, &loops, &sampler)?;
/// let quality = sample_quality(&samples, &loops, 30.0)?;
/// assert_eq!(quality.covered, quality.components); // P1
/// assert!(quality.missed.is_empty());
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn sample_quality(samples: &Samples, loops: &Loops, epsilon_s: f64) -> Result<SampleQuality> {
    check_epsilon_s(epsilon_s)?;
    let pairs = samples.pairs_on(loops.timestamps_s())?;
    let components = loops.components();
    let mut samplable = vec![false; components.len()];
    for run in loops.runs() {
        samplable[run.component] |= run.end > run.row;
    }
    let labels: Vec<Option<usize>> = pairs.iter().map(|p| loops.component_of(p[0], p[1])).collect();
    let mut per_component = vec![0u64; components.len()];
    for &c in labels.iter().flatten() {
        per_component[c] += 1;
    }

    // P1.
    let counted = |c: &&crate::LoopComponent| samplable[c.id];
    let mut missed: Vec<MissedComponent> = components
        .iter()
        .filter(counted)
        .filter(|c| per_component[c.id] == 0)
        .map(|c| MissedComponent {
            id: c.id,
            trivial: c.trivial,
            area_s2: c.area_s2,
            pair_count: c.pair_count,
            pose_pair_count: c.pose_pair_count,
        })
        .collect();
    missed.sort_by(|a, b| b.area_s2.total_cmp(&a.area_s2).then(a.id.cmp(&b.id)));
    let total = components.iter().filter(counted).count();
    let nontrivial = components.iter().filter(counted).filter(|c| !c.trivial).count();
    let nontrivial_missed = missed.iter().filter(|m| !m.trivial).count();

    // P2: nearest other sample of the same component, in the (t, t′) plane.
    let rows = samples.rows();
    let mut by_component: Vec<(usize, f64, f64, usize)> = labels
        .iter()
        .zip(rows)
        .enumerate()
        .filter_map(|(k, (c, row))| c.map(|c| (c, row.t_s, row.t_prime_s, k)))
        .collect();
    by_component.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.total_cmp(&b.2)));
    let mut nearest_spacing_s = vec![None; rows.len()];
    let interrupt = Interrupt::current();
    let mut start = 0;
    while start < by_component.len() {
        let end = start + by_component[start..].iter().take_while(|p| p.0 == by_component[start].0).count();
        let group = &by_component[start..end];
        for (spacing, point) in nearest_spacings(group, &interrupt)?.into_iter().zip(group) {
            nearest_spacing_s[point.3] = spacing;
        }
        start = end;
    }
    let mut spacings: Vec<f64> = nearest_spacing_s.iter().flatten().copied().collect();
    let redundant = spacings.iter().filter(|&&d| d <= epsilon_s).count();
    spacings.sort_by(f64::total_cmp);
    let median_spacing_s = (!spacings.is_empty()).then(|| {
        let m = spacings.len();
        if m % 2 == 1 { spacings[m / 2] } else { 0.5 * (spacings[m / 2 - 1] + spacings[m / 2]) }
    });

    // P3.
    let points: Vec<(f64, f64)> = components
        .iter()
        .filter(counted)
        .filter(|c| per_component[c.id] > 0)
        .map(|c| (c.area_s2.ln(), (per_component[c.id] as f64).ln()))
        .collect();
    let p3_slope = slope(&points);

    Ok(SampleQuality {
        samples: rows.len(),
        outside: labels.iter().filter(|c| c.is_none()).count(),
        components: total,
        covered: total - missed.len(),
        nontrivial_components: nontrivial,
        nontrivial_covered: nontrivial - nontrivial_missed,
        missed,
        epsilon_s,
        redundant,
        median_spacing_s,
        p3_slope,
        p3_components: points.len(),
        per_component,
        sample_components: labels,
        nearest_spacing_s,
    })
}

/// For points sorted by t, the distance to the nearest other point (`None` for a lone point).
/// A sweep outwards in t that stops once |Δt| exceeds the best distance so far: up to all the
/// points for one of many at the same t, so `interrupt` is looked at before every point.
fn nearest_spacings(points: &[(usize, f64, f64, usize)], interrupt: &Interrupt) -> Result<Vec<Option<f64>>> {
    (0..points.len())
        .map(|a| {
            interrupt.check()?;
            let (_, x, y, _) = points[a];
            let mut best = f64::INFINITY;
            for &(_, bx, by, _) in &points[a + 1..] {
                let dx = bx - x;
                if dx > best {
                    break;
                }
                best = best.min(dx.hypot(by - y));
            }
            for &(_, bx, by, _) in points[..a].iter().rev() {
                let dx = x - bx;
                if dx > best {
                    break;
                }
                best = best.min(dx.hypot(by - y));
            }
            Ok(best.is_finite().then_some(best))
        })
        .collect()
}

/// Least-squares slope of y on x; `None` unless x takes at least two values.
fn slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), p| (a + (p.0 - mx) * (p.1 - my), b + (p.0 - mx).powi(2)));
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spacing_and_slope() {
        let points = [(0, 0.0, 0.0, 0), (0, 3.0, 4.0, 1), (0, 3.0, 5.0, 2), (0, 100.0, 0.0, 3)];
        let none = Interrupt::new();
        let got = nearest_spacings(&points, &none).unwrap();
        assert_eq!(got, [Some(5.0), Some(1.0), Some(1.0), Some(97.0f64.hypot(4.0))]);
        assert_eq!(nearest_spacings(&points[..1], &none).unwrap(), [None]);
        let stopped = Interrupt::new();
        stopped.interrupt();
        assert_eq!(nearest_spacings(&points, &stopped), Err(crate::Error::Interrupted));
        assert_eq!(slope(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]), Some(2.0));
        assert_eq!(slope(&[(1.0, 1.0), (1.0, 3.0)]), None);
    }
}

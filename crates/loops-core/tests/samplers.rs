//! Samplers σ_1, σ_ρ (random and dispersed), σ_α, closest-first and the baselines, from detection clusters and
//! from the exact components: exact budgets, P1, reproducibility across runs and thread counts,
//! and `sample_quality` on hand-made cases whose answer is known.

use std::collections::{BTreeMap, BTreeSet};

use loops_core::{
    DetectionClusters, Detections, Error, Euclidean, Loops, Metric, SampleSize, SampleWarning, Sampler, SamplerKind,
    Samples, Trajectory, UrbanDrive, cluster_detections, find_loops, sample_clusters, sample_loops, sample_quality,
    with_threads,
};

const SIGMAS: [SamplerKind; 7] = [
    SamplerKind::One,
    SamplerKind::Rho,
    SamplerKind::RhoDispersed,
    SamplerKind::Alpha,
    SamplerKind::ClosestFirst,
    SamplerKind::ClosestThenSpread,
    SamplerKind::NearestThenUniform,
];
const BASELINES: [SamplerKind; 4] =
    [SamplerKind::LioSam, SamplerKind::HdlGraphSlam, SamplerKind::Cartographer, SamplerKind::TimeGap];

struct Setup {
    traj: Trajectory,
    loops: Loops,
    clusters: DetectionClusters,
}

fn setup() -> Setup {
    let drive = UrbanDrive { duration_s: 1800.0, seed: 5, ..UrbanDrive::default() }.generate().unwrap();
    let loops = find_loops(&drive.trajectory, &Euclidean, 40.0).unwrap();
    let detections = Detections::draw(&loops, SampleSize::Rate(0.01), 2).unwrap();
    let clusters = cluster_detections(&detections, 10.0).unwrap();
    Setup { traj: drive.trajectory, loops, clusters }
}

/// Components with at least one pair i < j: the groups of the exact route.
fn samplable(loops: &Loops) -> BTreeSet<usize> {
    loops.runs().filter(|run| run.end > run.row).map(|run| run.component).collect()
}

#[test]
fn budget_is_exact_and_p1_holds_on_clusters() {
    let s = setup();
    let groups = s.clusters.len();
    assert!(groups > 10, "{groups} clusters");
    for kind in SIGMAS {
        for budget in [groups, groups + 1, 3 * groups + 7, 2000] {
            let samples = sample_clusters(&s.clusters, &Sampler::new(kind, SampleSize::Budget(budget), 9)).unwrap();
            assert_eq!(samples.len(), budget, "{kind} budget {budget}");
            assert!(samples.warnings().is_empty(), "{kind}: {:?}", samples.warnings());
            let detections: BTreeSet<usize> = samples.rows().iter().map(|r| r.detection.unwrap()).collect();
            assert_eq!(detections.len(), budget, "{kind}: a detection sampled twice");
            for row in samples.rows() {
                let k = row.detection.unwrap();
                assert_eq!(row.cluster, Some(s.clusters.labels()[k] as usize));
                assert_eq!(
                    (row.t_s, row.t_prime_s),
                    (s.clusters.detections().t_s()[k], s.clusters.detections().t_prime_s()[k])
                );
                assert_eq!(row.sampler, kind);
            }
            if kind != SamplerKind::Alpha {
                let covered: BTreeSet<usize> = samples.rows().iter().map(|r| r.cluster.unwrap()).collect();
                assert_eq!(covered.len(), groups, "{kind} budget {budget}: P1 fails");
            }
        }
    }
}

#[test]
fn budget_is_exact_and_p1_holds_on_exact_components() {
    let s = setup();
    let groups = samplable(&s.loops);
    for kind in SIGMAS {
        for budget in [groups.len(), groups.len() + 3, 1500] {
            let sampler = Sampler::new(kind, SampleSize::Budget(budget), 4);
            let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
            assert_eq!(samples.len(), budget, "{kind} budget {budget}");
            let mut seen = BTreeSet::new();
            for row in samples.rows() {
                let [i, j] = row.pair.unwrap();
                assert!(i < j && seen.insert((i, j)), "{kind}: pair ({i}, {j}) diagonal or repeated");
                assert_eq!(row.component, s.loops.component_of(i, j));
                assert!(row.component.is_some());
                let d = Euclidean.distance(s.traj.point(i), s.traj.point(j));
                assert_eq!(row.distance, Some(d));
                assert!(d <= 40.0);
                assert_eq!((row.t_s, row.t_prime_s), (s.traj.timestamps_s()[i], s.traj.timestamps_s()[j]));
            }
            let quality = sample_quality(&samples, &s.loops, 30.0).unwrap();
            assert_eq!(quality.components, groups.len());
            assert_eq!(quality.outside, 0);
            if kind != SamplerKind::Alpha {
                assert_eq!(samples.groups(), groups.len());
                assert_eq!(quality.covered, groups.len(), "{kind} budget {budget}: P1 fails: {:?}", quality.missed);
                assert!(quality.missed.is_empty());
            }
        }
    }
}

#[test]
fn budget_below_groups_warns() {
    let s = setup();
    let groups = s.clusters.len();
    let budget = groups / 2;
    let samples = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(budget), 0)).unwrap();
    assert_eq!(samples.len(), budget);
    assert_eq!(samples.warnings(), &[SampleWarning::BudgetBelowGroups { budget, groups }]);
    assert!(samples.warnings()[0].to_string().contains("P1 cannot hold"));
    // σ_1 spreads the budget over distinct groups.
    let covered: BTreeSet<usize> = samples.rows().iter().map(|r| r.cluster.unwrap()).collect();
    assert_eq!(covered.len(), budget);
    // More than there is: everything, with a warning.
    let all = s.clusters.detections().len();
    let samples =
        sample_clusters(&s.clusters, &Sampler::new(SamplerKind::Rho, SampleSize::Budget(all + 5), 0)).unwrap();
    assert_eq!(samples.len(), all);
    assert!(matches!(samples.warnings(), [SampleWarning::BudgetAboveAvailable { .. }]));
}

#[test]
fn rate_mode() {
    let s = setup();
    let sizes: Vec<usize> = s.clusters.clusters().iter().map(|c| c.size).collect();
    // σ_1 with c = 2: exactly min(2, size) per cluster.
    let samples = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::One, SampleSize::Rate(2.0), 1)).unwrap();
    let mut per_cluster = vec![0usize; sizes.len()];
    samples.rows().iter().for_each(|r| per_cluster[r.cluster.unwrap()] += 1);
    assert!(per_cluster.iter().zip(&sizes).all(|(&k, &size)| k == size.min(2)), "{per_cluster:?}");
    // σ_ρ with a tiny r still keeps one per cluster.
    let samples = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::Rho, SampleSize::Rate(1e-6), 1)).unwrap();
    assert_eq!(samples.len(), sizes.len());
    // σ_α keeps each detection with probability p.
    let n = s.clusters.detections().len() as f64;
    let samples = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::Alpha, SampleSize::Rate(0.1), 1)).unwrap();
    assert!((samples.len() as f64 - 0.1 * n).abs() < 5.0 * (0.1 * n).sqrt(), "{} of {n}", samples.len());
}

#[test]
fn dispersed_rho_spreads_over_rows_and_takes_closest_pairs() {
    let s = setup();
    let sampler = Sampler::new(SamplerKind::RhoDispersed, SampleSize::Budget(800), 3);
    let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
    let set = s.loops.sublevel_set();
    let mut rows_per_component: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for row in samples.rows() {
        let [i, j] = row.pair.unwrap();
        let c = row.component.unwrap();
        rows_per_component.entry(c).or_default().push(i);
        // The closest pair of row i among the component's runs off the diagonal.
        let off_diagonal: Vec<usize> = set
            .row(i)
            .iter()
            .filter(|run| run.start as usize > i && s.loops.component_of(i, run.start as usize) == Some(c))
            .flat_map(|run| run.start as usize..=run.end as usize)
            .collect();
        if !set
            .row(i)
            .iter()
            .any(|run| run.start as usize <= i && run.end as usize > i && s.loops.component_of(i, i + 1) == Some(c))
        {
            let best = off_diagonal
                .iter()
                .map(|&k| Euclidean.distance(s.traj.point(i), s.traj.point(k)))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(row.distance, Some(best), "({i}, {j}) is not the closest pair of its row");
        }
    }
    // The budget is below the rows of every component here: one sample per row at most, and
    // evenly spaced rows.
    for (c, rows) in &rows_per_component {
        let distinct: BTreeSet<usize> = rows.iter().copied().collect();
        assert_eq!(distinct.len(), rows.len(), "component {c}: two samples in one row");
    }
}

/// Closest-first: every component's closest pair first (P1 with the likeliest match), then the
/// rest as the dispersed σ_ρ, one per row while the budget is below the rows; P3 as σ_ρ's.
#[test]
fn closest_first_takes_every_closest_pair_then_disperses() {
    let s = setup();
    let components = s.loops.components();
    let groups = samplable(&s.loops);
    let closest = |c: usize| -> [usize; 2] {
        let [i, j] = components[c].closest_pair;
        [i.min(j), i.max(j)]
    };
    for budget in [groups.len(), groups.len() + 5, 3 * groups.len(), 1500] {
        let sampler = Sampler::new(SamplerKind::ClosestFirst, SampleSize::Budget(budget), 6);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        assert_eq!(samples.len(), budget);
        assert!(samples.warnings().is_empty(), "{:?}", samples.warnings());
        let pairs: BTreeSet<[usize; 2]> = samples.rows().iter().map(|r| r.pair.unwrap()).collect();
        assert_eq!(pairs.len(), budget, "a pair twice");
        for &c in groups.iter().filter(|&&c| !components[c].trivial) {
            assert!(pairs.contains(&closest(c)), "budget {budget}: component {c} without its closest pair");
        }
        if budget == groups.len() {
            // One each: the trivial component's is its closest pair off the diagonal.
            let trivial: Vec<_> = samples.rows().iter().filter(|r| components[r.component.unwrap()].trivial).collect();
            assert_eq!(trivial.len(), groups.iter().filter(|&&c| components[c].trivial).count());
        }
        let quality = sample_quality(&samples, &s.loops, 30.0).unwrap();
        assert_eq!(quality.covered, groups.len(), "budget {budget}: P1 fails");
    }
    // The rest grows with the rows (P3) like σ_ρ's: the same budget, the same slope within noise.
    let budget = 4 * groups.len();
    let slope = |kind| {
        let samples =
            sample_loops(&s.traj, &Euclidean, &s.loops, &Sampler::new(kind, SampleSize::Budget(budget), 1)).unwrap();
        sample_quality(&samples, &s.loops, 30.0).unwrap().p3_slope.unwrap()
    };
    let (first, rho, one) = (slope(SamplerKind::ClosestFirst), slope(SamplerKind::Rho), slope(SamplerKind::One));
    assert!(one < first && (first - rho).abs() < 0.25, "slopes: closest-first {first}, rho {rho}, one {one}");
    // A budget below the components: one closest pair each for that many, with the warning.
    let sampler = Sampler::new(SamplerKind::ClosestFirst, SampleSize::Budget(groups.len() / 2), 0);
    let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
    assert_eq!(samples.len(), groups.len() / 2);
    assert!(matches!(samples.warnings(), [SampleWarning::BudgetBelowGroups { .. }]));
    for row in samples.rows().iter().filter(|r| !components[r.component.unwrap()].trivial) {
        assert_eq!(row.pair.unwrap(), closest(row.component.unwrap()));
    }
}

/// Closest-then-spread: every component's closest pair first when the budget
/// covers the components, then σ_ρ's counts, in proportion to the rows (the first pick counts
/// towards them, unlike closest-first's one-plus-a-share), spread one per row.
#[test]
fn closest_then_spread_takes_every_closest_pair_then_shares_by_rows() {
    let s = setup();
    let components = s.loops.components();
    let groups = samplable(&s.loops);
    let rows_of = |c: usize| -> f64 {
        let rows: BTreeSet<usize> =
            s.loops.runs().filter(|r| r.component == c && r.end > r.row).map(|r| r.row).collect();
        (rows.last().unwrap() - rows.first().unwrap() + 1) as f64
    };
    let counts_of = |kind, budget, seed| -> BTreeMap<usize, usize> {
        let samples =
            sample_loops(&s.traj, &Euclidean, &s.loops, &Sampler::new(kind, SampleSize::Budget(budget), seed)).unwrap();
        assert_eq!(samples.len(), budget);
        let mut counts = BTreeMap::new();
        for r in samples.rows() {
            *counts.entry(r.component.unwrap()).or_insert(0) += 1;
        }
        counts
    };
    let counts = |kind, budget| counts_of(kind, budget, 6);
    for budget in [groups.len(), groups.len() + 5, 3 * groups.len(), 1500] {
        let sampler = Sampler::new(SamplerKind::ClosestThenSpread, SampleSize::Budget(budget), 6);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        assert!(samples.warnings().is_empty(), "{:?}", samples.warnings());
        let pairs: BTreeSet<[usize; 2]> = samples.rows().iter().map(|r| r.pair.unwrap()).collect();
        assert_eq!(pairs.len(), budget, "a pair twice");
        for &c in groups.iter().filter(|&&c| !components[c].trivial) {
            let [i, j] = components[c].closest_pair;
            assert!(pairs.contains(&[i.min(j), i.max(j)]), "budget {budget}: component {c} without its closest pair");
        }
        // The counts: at least one each, then in proportion to the rows; s fitted on the
        // components above the floor, each count within rounding of s · rows.
        let mine = counts(SamplerKind::ClosestThenSpread, budget);
        assert_eq!(mine.len(), groups.len(), "budget {budget}: P1 fails");
        let above: Vec<(usize, usize)> = mine.iter().filter(|&(_, &k)| k > 1).map(|(&c, &k)| (c, k)).collect();
        if above.len() > 3 {
            let scale =
                above.iter().map(|&(_, k)| k as f64).sum::<f64>() / above.iter().map(|&(c, _)| rows_of(c)).sum::<f64>();
            for &(c, k) in &above {
                let want = scale * rows_of(c);
                assert!((k as f64 - want).abs() < 1.5, "budget {budget}: component {c}: {k} samples for {want:.2}");
            }
            for (&c, _) in mine.iter().filter(|&(_, &k)| k == 1) {
                assert!(
                    scale * rows_of(c) < 2.5,
                    "budget {budget}: component {c} at the floor with {} rows",
                    rows_of(c)
                );
            }
        }
        // Closest-first gives every component one plus a share: more to the small ones (over
        // five seeds: one draw's rounding may give both the same).
        if budget == 3 * groups.len() {
            let mut rows: Vec<f64> = mine.keys().map(|&c| rows_of(c)).collect();
            rows.sort_by(f64::total_cmp);
            let quartile = rows[rows.len() / 4];
            let small = |kind| -> usize {
                (6..11)
                    .map(|seed| {
                        let k = counts_of(kind, budget, seed);
                        mine.keys().filter(|c| rows_of(**c) <= quartile).map(|c| k[c]).sum::<usize>()
                    })
                    .sum()
            };
            let (spread, first) = (small(SamplerKind::ClosestThenSpread), small(SamplerKind::ClosestFirst));
            assert!(spread > 0);
            assert!(spread < first, "small components: {spread} against {first}");
        }
    }
    // A budget below the components: that many components, each with its closest pair.
    let sampler = Sampler::new(SamplerKind::ClosestThenSpread, SampleSize::Budget(groups.len() / 2), 0);
    let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
    assert_eq!(samples.len(), groups.len() / 2);
    assert!(matches!(samples.warnings(), [SampleWarning::BudgetBelowGroups { .. }]));
}

/// Nearest-then-uniform (the default): up to one row in six, all picks are closest pairs of rows (checked
/// against every cell of the row), every component's closest pair among them, shared in
/// proportion to the rows as σ_ρ shares them (below one per component too, where a long
/// component may take two); beyond that, every component keeps those picks and
/// the rest is shared in proportion to the pairs each has left, within one of its expectation.
#[test]
fn nearest_then_uniform_takes_rows_closest_pairs_then_uniform_picks() {
    assert_eq!(SamplerKind::default(), SamplerKind::DEFAULT);
    assert_eq!(SamplerKind::DEFAULT, SamplerKind::NearestThenUniform);
    let s = setup();
    let components = s.loops.components();
    let groups = samplable(&s.loops);
    let mut rows: BTreeMap<usize, BTreeSet<usize>> = BTreeMap::new();
    let mut pairs: BTreeMap<usize, u64> = BTreeMap::new();
    // The cells off the diagonal of each (component, row), as column ranges.
    let mut cells: BTreeMap<(usize, usize), Vec<(usize, usize)>> = BTreeMap::new();
    for run in s.loops.runs() {
        rows.entry(run.component).or_default().insert(run.row);
        let first = run.start.max(run.row + 1);
        if first <= run.end {
            *pairs.entry(run.component).or_default() += (run.end - first + 1) as u64;
            cells.entry((run.component, run.row)).or_default().push((first, run.end));
        }
    }
    // The closest column of a row of a component, by brute force over its cells.
    let closest = |c: usize, i: usize| {
        cells[&(c, i)]
            .iter()
            .flat_map(|&(a, b)| a..=b)
            .map(|j| Euclidean.distance(s.traj.point(i), s.traj.point(j)))
            .fold(f64::INFINITY, f64::min)
    };
    let span = |c: usize| (rows[&c].last().unwrap() - rows[&c].first().unwrap() + 1) as u64;
    // One row in six at most gives its closest pair before the uniform picks.
    let near = |c: usize| span(c).div_ceil(6).clamp(1, pairs[&c]);
    let near_total: u64 = groups.iter().map(|&c| near(c)).sum();
    let available: u64 = groups.iter().map(|&c| pairs[&c]).sum();
    assert!(groups.len() < (near_total / 2) as usize && near_total < available);
    let draw = |budget: u64, seed: u64| {
        let sampler = Sampler::new(SamplerKind::NearestThenUniform, SampleSize::Budget(budget as usize), seed);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        assert!(samples.warnings().is_empty(), "{:?}", samples.warnings());
        assert_eq!(samples.len() as u64, budget);
        let set: BTreeSet<[usize; 2]> = samples.rows().iter().map(|r| r.pair.unwrap()).collect();
        assert_eq!(set.len() as u64, budget, "a pair twice");
        samples
    };
    // Picks per component; each non-trivial pick is its row's closest pair.
    let rows_closest_counts = |samples: &Samples| {
        let mut counts: BTreeMap<usize, u64> = BTreeMap::new();
        for r in samples.rows() {
            let c = r.component.unwrap();
            *counts.entry(c).or_default() += 1;
            if !components[c].trivial {
                let [i, _] = r.pair.unwrap();
                assert_eq!(r.distance.unwrap(), closest(c, i), "{:?}: not its row's closest pair", r.pair);
            }
        }
        counts
    };
    for seed in [0, 7] {
        let samples = draw(near_total / 2, seed);
        let counts = rows_closest_counts(&samples);
        assert_eq!(counts.len(), groups.len(), "P1 fails");
        let picked: BTreeSet<[usize; 2]> = samples.rows().iter().map(|r| r.pair.unwrap()).collect();
        for &c in groups.iter().filter(|&&c| !components[c].trivial) {
            let [i, j] = components[c].closest_pair;
            assert!(picked.contains(&[i.min(j), i.max(j)]), "component {c} without its closest pair");
        }
        // At least one each, then in proportion to the rows as σ_ρ: no component far above
        // its share (the floors of one only lower the others' scale).
        let scale = (near_total / 2) as f64 / groups.iter().map(|&c| span(c)).sum::<u64>() as f64;
        for (&c, &k) in &counts {
            assert!(
                k as f64 <= 2.0 + scale * span(c) as f64,
                "component {c}: {k} picks, share {:.2}",
                scale * span(c) as f64
            );
        }

        // Fewer picks than components: shared by rows as σ_ρ shares them (a long component
        // takes more than one, never more than its near cap), all closest pairs of rows.
        let budget = groups.len() / 2;
        let sampler = Sampler::new(SamplerKind::NearestThenUniform, SampleSize::Budget(budget), seed);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        assert_eq!(samples.len(), budget);
        assert!(matches!(samples.warnings(), [SampleWarning::BudgetBelowGroups { .. }]));
        let counts = rows_closest_counts(&samples);
        let spans: u64 = groups.iter().map(|&c| span(c)).sum();
        for (&c, &k) in &counts {
            assert!(k <= near(c), "component {c}: {k} picks above its near cap {}", near(c));
        }
        let longest = *groups.iter().max_by_key(|&&c| span(c)).unwrap();
        // Its share at least budget · span / Σ span (caps on others only raise it), floored.
        let share = (budget as u64 * span(longest) / spans).min(near(longest));
        assert!(share >= 2, "the setup gives no component two picks: {share}");
        assert!(counts.get(&longest).copied().unwrap_or(0) >= share, "longest component below its share {share}");

        let budget = near_total + (available - near_total) / 3;
        let samples = draw(budget, seed);
        let mut counts: BTreeMap<usize, u64> = BTreeMap::new();
        for r in samples.rows() {
            *counts.entry(r.component.unwrap()).or_default() += 1;
        }
        let left_total = (available - near_total) as f64;
        for &c in &groups {
            let uniform = counts[&c] - near(c);
            let want = (budget - near_total) as f64 * (pairs[&c] - near(c)) as f64 / left_total;
            assert!((uniform as f64 - want).abs() < 1.0, "component {c}: {uniform} uniform picks for {want:.2}");
        }
    }
}

/// On detection clusters, closest-first takes each cluster's best-scored detection first.
#[test]
fn closest_first_on_clusters_takes_the_best_score_first() {
    let s = setup();
    let det = s.clusters.detections().clone();
    // Scores that peak somewhere inside each cluster, away from its first and last detection.
    let scores: Vec<f64> = (0..det.len()).map(|k| ((k * 7919) % 1000) as f64).collect();
    let scored = cluster_detections(&det.with_scores(scores.clone()).unwrap(), 10.0).unwrap();
    let labels = scored.labels();
    let mut best = vec![None::<usize>; scored.len()];
    for k in 0..labels.len() {
        let g = labels[k] as usize;
        if best[g].is_none_or(|b| scores[k] > scores[b]) {
            best[g] = Some(k);
        }
    }
    for budget in [scored.len(), 2 * scored.len() + 1] {
        let sampler = Sampler::new(SamplerKind::ClosestFirst, SampleSize::Budget(budget), 3);
        let samples = sample_clusters(&scored, &sampler).unwrap();
        assert_eq!(samples.len(), budget);
        let picked: BTreeSet<usize> = samples.rows().iter().map(|r| r.detection.unwrap()).collect();
        assert_eq!(picked.len(), budget);
        for (g, b) in best.iter().enumerate() {
            let b = b.unwrap();
            // Equal scores: the first in (t, t′) order is taken, which has the same score.
            let has_best = samples.rows().iter().any(|r| r.cluster == Some(g) && r.score == Some(scores[b]));
            assert!(has_best, "budget {budget}: cluster {g} without its best-scored detection");
        }
    }
}

#[test]
fn same_seed_same_samples_on_any_thread_count() {
    let s = setup();
    for kind in SIGMAS.into_iter().chain(BASELINES) {
        let sampler = Sampler::new(kind, SampleSize::Budget(700), 17);
        let run = |threads| {
            with_threads(Some(threads), || {
                let exact = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
                let clusters = (!kind.is_baseline()).then(|| sample_clusters(&s.clusters, &sampler).unwrap());
                (exact, clusters)
            })
            .unwrap()
        };
        let one = run(1);
        assert_eq!(one, run(2), "{kind}: differs between 1 and 2 threads");
        assert_eq!(one, run(2), "{kind}: differs between runs");
        if kind != SamplerKind::LioSam && kind != SamplerKind::HdlGraphSlam {
            let other = sample_loops(&s.traj, &Euclidean, &s.loops, &Sampler { seed: 18, ..sampler.clone() }).unwrap();
            assert_ne!(one.0, other, "{kind}: the seed changes nothing");
        }
    }
}

#[test]
fn baselines_under_the_budget() {
    let s = setup();
    for kind in BASELINES {
        let sampler = Sampler::new(kind, SampleSize::Budget(300), 2);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        assert!(samples.len() <= 300);
        assert!(samples.available() >= samples.len() as u64);
        if samples.len() < 300 {
            assert!(matches!(samples.warnings(), [SampleWarning::BudgetAboveAvailable { budget: 300, .. }]));
        }
        let times = s.traj.timestamps_s();
        for row in samples.rows() {
            let [i, j] = row.pair.unwrap();
            assert!(i < j && row.distance.unwrap() <= 40.0 && row.component.is_some(), "{kind}: ({i}, {j})");
            let gap = times[j] - times[i];
            match kind {
                SamplerKind::LioSam => assert!(gap > 30.0),
                SamplerKind::TimeGap => assert!(gap >= 30.0),
                SamplerKind::Cartographer => assert!(gap >= 10.0),
                _ => {}
            }
        }
    }
}

#[test]
fn bad_input() {
    let s = setup();
    let err = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(0), 0)).unwrap_err();
    assert!(matches!(err, Error::InvalidParameter { name: "budget", .. }), "{err}");
    let err = sample_loops(&s.traj, &Euclidean, &s.loops, &Sampler::new(SamplerKind::Rho, SampleSize::Budget(0), 0))
        .unwrap_err();
    assert!(matches!(err, Error::InvalidParameter { name: "budget", .. }), "{err}");
    for (kind, rate) in [(SamplerKind::Alpha, 1.5), (SamplerKind::One, 0.0), (SamplerKind::Rho, f64::NAN)] {
        let err = sample_clusters(&s.clusters, &Sampler::new(kind, SampleSize::Rate(rate), 0)).unwrap_err();
        assert!(matches!(err, Error::InvalidParameter { name: "rate", .. }), "{err}");
    }
    let err = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::LioSam, SampleSize::Budget(10), 0)).unwrap_err();
    assert!(err.to_string().contains("one, rho, rho-dispersed, alpha"), "{err}");
    let err = "sigma-1".parse::<SamplerKind>().unwrap_err();
    assert!(matches!(err, Error::UnknownName { kind: "sampler", .. }));
    let other = UrbanDrive { duration_s: 300.0, ..UrbanDrive::default() }.generate().unwrap().trajectory;
    let err = sample_loops(&other, &Euclidean, &s.loops, &Sampler::new(SamplerKind::One, SampleSize::Budget(10), 0))
        .unwrap_err();
    assert!(matches!(err, Error::TrajectoryMismatch { what: "trajectory", .. }), "{err}");
    let samples = sample_clusters(&s.clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(50), 0)).unwrap();
    let other_loops = find_loops(&other, &Euclidean, 40.0).unwrap();
    let err = sample_quality(&samples, &other_loops, 30.0).unwrap_err();
    assert!(matches!(err, Error::TrajectoryMismatch { what: "samples", .. }), "{err}");
    let err = sample_quality(&samples, &s.loops, 0.0).unwrap_err();
    assert!(matches!(err, Error::InvalidParameter { name: "epsilon_s", .. }), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Quality on a hand-made case
// ---------------------------------------------------------------------------------------------

/// Three circular petals of radii 20, 14 and 27 m through the origin, one pose a second at
/// about 1 m/s: the origin is visited four times, so there are several non-trivial components of
/// different areas near it.
fn clover() -> (Trajectory, Loops) {
    let mut points = Vec::new();
    for (petal, radius) in [20.0f64, 14.0, 27.0].into_iter().enumerate() {
        let theta = petal as f64 * std::f64::consts::TAU / 3.0;
        let centre = [radius * theta.cos(), radius * theta.sin()];
        let steps = (std::f64::consts::TAU * radius).round() as usize;
        for k in 0..steps {
            let a = theta + std::f64::consts::PI + std::f64::consts::TAU * k as f64 / steps as f64;
            points.push([centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]);
        }
    }
    points.push([0.0, 0.0]);
    let traj = Trajectory::from_points((0..points.len()).map(|k| k as f64).collect(), &points).unwrap();
    let loops = find_loops(&traj, &Euclidean, 3.0).unwrap();
    (traj, loops)
}

/// Every sample given as a detection, sampled with σ_α at rate 1: the samples are exactly them.
fn samples_of(detections: Detections) -> Samples {
    let clusters = cluster_detections(&detections, 1.0).unwrap();
    sample_clusters(&clusters, &Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0)).unwrap()
}

#[test]
fn quality_of_a_known_sample() {
    let (traj, loops) = clover();
    let nontrivial: Vec<usize> = loops.components().iter().filter(|c| !c.trivial).map(|c| c.id).collect();
    assert!(nontrivial.len() >= 3, "{:?}", loops.components());
    // The two largest non-trivial components: three samples in the larger (a little L of
    // neighbouring cells), one in the other; one pair outside S_γ; nothing elsewhere.
    let mut by_area = nontrivial.clone();
    by_area.sort_by(|&a, &b| loops.components()[b].area_s2.total_cmp(&loops.components()[a].area_s2));
    let (big, small) = (by_area[0], by_area[1]);
    let [i, j] = loops.components()[big].closest_pair;
    let l_shape = [[i, j], [i + 1, j], [i, j + 1]];
    assert!(l_shape.iter().all(|p| loops.component_of(p[0], p[1]) == Some(big)), "pick another shape");
    let lone = loops.components()[small].closest_pair;
    let far = (1..traj.len()).find(|&k| loops.component_of(0, k).is_none()).unwrap();
    let pairs: Vec<[usize; 2]> = l_shape.iter().copied().chain([lone, [0, far]]).collect();
    let (is, js): (Vec<usize>, Vec<usize>) = pairs.iter().map(|p| (p[0], p[1])).unzip();

    let by_indices = samples_of(Detections::from_indices(&traj, &is, &js).unwrap());
    // The same detections given as times only: placed on the nearest poses by the quality.
    let times = traj.timestamps_s();
    let by_times = samples_of(
        Detections::new(is.iter().map(|&k| times[k] + 0.2).collect(), js.iter().map(|&k| times[k] - 0.3).collect())
            .unwrap(),
    );
    for samples in [&by_indices, &by_times] {
        let q = sample_quality(samples, &loops, 1.5).unwrap();
        assert_eq!(q.samples, 5);
        assert_eq!(q.outside, 1);
        let components = samplable(&loops).len();
        assert_eq!(q.components, components);
        assert_eq!(q.covered, 2);
        assert_eq!(q.nontrivial_components, nontrivial.len());
        assert_eq!(q.nontrivial_covered, 2);
        // Missed: every other component, largest first, with its area.
        let mut expected: Vec<(usize, f64)> = samplable(&loops)
            .into_iter()
            .filter(|&c| c != big && c != small)
            .map(|c| (c, loops.components()[c].area_s2))
            .collect();
        expected.sort_by(|a, b| b.1.total_cmp(&a.1));
        let missed: Vec<(usize, f64)> = q.missed.iter().map(|m| (m.id, m.area_s2)).collect();
        assert_eq!(missed, expected);
        assert_eq!(q.missed.iter().filter(|m| m.trivial).count(), 1);
        // P2: the three of the L are 1 s from a neighbour (≤ ε = 1.5 s), the lone one is not.
        assert_eq!(q.redundant, 3);
        assert!((q.redundancy() - 0.6).abs() < 1e-12);
        // P3: ln 3 over the log ratio of the two areas.
        let (a_big, a_small) = (loops.components()[big].area_s2, loops.components()[small].area_s2);
        let slope = 3f64.ln() / (a_big.ln() - a_small.ln());
        assert_eq!(q.p3_components, 2);
        assert!((q.p3_slope.unwrap() - slope).abs() < 1e-9, "{:?} vs {slope}", q.p3_slope);
        assert_eq!(q.per_component[big], 3);
        assert_eq!(q.per_component[small], 1);
        assert!((q.coverage() - 2.0 / components as f64).abs() < 1e-12);
    }
    // Spacing: 1 s to the nearest for each of the L (exact with pose times); none for the lone
    // sample and the one outside S_γ. Per-sample values follow the order of the rows.
    let q = sample_quality(&by_indices, &loops, 1.5).unwrap();
    assert_eq!(q.median_spacing_s, Some(1.0));
    for (k, row) in by_indices.rows().iter().enumerate() {
        let pair = row.pair.unwrap();
        let expected = if l_shape.contains(&pair) { Some(1.0) } else { None };
        assert_eq!(q.nearest_spacing_s[k], expected, "{pair:?}");
        assert_eq!(q.sample_components[k], loops.component_of(pair[0], pair[1]));
    }
    // With a smaller ε nothing is redundant.
    assert_eq!(sample_quality(&by_indices, &loops, 0.5).unwrap().redundant, 0);
}

#[test]
fn quality_separates_the_samplers_on_a_drive() {
    // The paper's finding at a small scale: σ_1 and σ_ρ cover every component, σ_α's growth with
    // area is the steepest and σ_1's the flattest.
    let s = setup();
    let budget = 4 * samplable(&s.loops).len();
    let slope = |kind| {
        let samples =
            sample_loops(&s.traj, &Euclidean, &s.loops, &Sampler::new(kind, SampleSize::Budget(budget), 1)).unwrap();
        let q = sample_quality(&samples, &s.loops, 30.0).unwrap();
        if kind != SamplerKind::Alpha {
            assert_eq!(q.covered, q.components, "{kind}");
        }
        q.p3_slope.unwrap()
    };
    let (one, rho, alpha) = (slope(SamplerKind::One), slope(SamplerKind::Rho), slope(SamplerKind::Alpha));
    assert!(one < rho && rho < alpha, "slopes: one {one}, rho {rho}, alpha {alpha}");
}

/// `skip_trivial`: σ_1, σ_ρ and σ_α draw only from the non-trivial components, keep the exact
/// budget and P1 over them, and do not change the components they cover otherwise; the budget
/// the trivial component took goes to the others. Clusters and baselines refuse it.
#[test]
fn skip_trivial_leaves_out_the_trivial_components() {
    let s = setup();
    let components = s.loops.components();
    let nontrivial: BTreeSet<usize> = samplable(&s.loops).into_iter().filter(|&c| !components[c].trivial).collect();
    assert!(nontrivial.len() > 10 && nontrivial.len() < samplable(&s.loops).len(), "{nontrivial:?}");
    for kind in SIGMAS {
        let budget = 4 * nontrivial.len() + 3;
        let plain = Sampler::new(kind, SampleSize::Budget(budget), 4);
        let skipping = Sampler { skip_trivial: true, ..plain.clone() };
        let all = sample_loops(&s.traj, &Euclidean, &s.loops, &plain).unwrap();
        let only = sample_loops(&s.traj, &Euclidean, &s.loops, &skipping).unwrap();
        assert_eq!(only.len(), budget, "{kind}");
        let trivial_picks =
            |samples: &Samples| samples.rows().iter().filter(|r| components[r.component.unwrap()].trivial).count();
        assert!(trivial_picks(&all) > 0, "{kind}: the plain sampler should reach the trivial component");
        assert_eq!(trivial_picks(&only), 0, "{kind}");
        if kind != SamplerKind::Alpha {
            let covered: BTreeSet<usize> = only.rows().iter().map(|r| r.component.unwrap()).collect();
            assert_eq!(covered, nontrivial, "{kind}: P1 over the non-trivial components");
            assert_eq!(only.groups(), nontrivial.len());
        }
        for row in only.rows() {
            let [i, j] = row.pair.unwrap();
            assert!(i < j && s.loops.component_of(i, j) == row.component, "{kind}: {row:?}");
        }
    }
    // A rate keeps its meaning: σ_1 at one per group gives exactly the non-trivial groups.
    let one = Sampler { skip_trivial: true, ..Sampler::new(SamplerKind::One, SampleSize::Rate(1.0), 0) };
    assert_eq!(sample_loops(&s.traj, &Euclidean, &s.loops, &one).unwrap().len(), nontrivial.len());

    let on_clusters = Sampler { skip_trivial: true, ..Sampler::new(SamplerKind::Rho, SampleSize::Budget(10), 0) };
    let error = sample_clusters(&s.clusters, &on_clusters).unwrap_err();
    assert!(matches!(error, Error::NotApplicable { option: "skip_trivial", .. }), "{error}");
    assert!(error.to_string().contains("detection clusters"), "{error}");
    for kind in BASELINES {
        let baseline = Sampler { skip_trivial: true, ..Sampler::new(kind, SampleSize::Budget(10), 0) };
        let error = sample_loops(&s.traj, &Euclidean, &s.loops, &baseline).unwrap_err();
        assert!(error.to_string().contains(&format!("the {kind} baseline")), "{error}");
    }
}

/// On a drive with only a trivial component, skipping it leaves nothing: no samples and a
/// warning, not an error.
#[test]
fn skip_trivial_with_nothing_else_gives_no_samples() {
    let line: Vec<f64> = (0..100).map(|k| k as f64).collect();
    let traj = Trajectory::new((0..100).map(f64::from).collect(), line, 1).unwrap();
    let loops = find_loops(&traj, &Euclidean, 2.5).unwrap();
    assert!(loops.components().iter().all(|c| c.trivial));
    let sampler = Sampler { skip_trivial: true, ..Sampler::new(SamplerKind::Rho, SampleSize::Budget(5), 0) };
    let samples = sample_loops(&traj, &Euclidean, &loops, &sampler).unwrap();
    assert!(samples.is_empty());
    assert_eq!(samples.warnings(), [SampleWarning::BudgetAboveAvailable { budget: 5, available: 0 }]);
}

#[test]
fn a_budget_below_the_components_spreads_along_them() {
    // σ_1 weighs every component alike: a budget of a tenth of them picks one component in
    // every ten or so, in id order (in time), not a random few; another seed moves the picks.
    let s = setup();
    let order: Vec<usize> = samplable(&s.loops).into_iter().collect();
    let budget = order.len() / 10;
    let picked = |seed: u64| -> Vec<usize> {
        let sampler = Sampler::new(SamplerKind::One, SampleSize::Budget(budget), seed);
        let samples = sample_loops(&s.traj, &Euclidean, &s.loops, &sampler).unwrap();
        let picked: BTreeSet<usize> = samples.rows().iter().map(|r| r.component.unwrap()).collect();
        picked.iter().map(|c| order.binary_search(c).unwrap()).collect()
    };
    let stride = order.len() as f64 / budget as f64;
    for seed in 0..5 {
        let at = picked(seed);
        assert_eq!(at.len(), budget);
        assert!(
            at.windows(2).all(|w| ((w[1] - w[0]) as f64 - stride).abs() < 1.0),
            "seed {seed}: stride {stride}, picks at {at:?}"
        );
    }
    assert_ne!(picked(0), picked(1));
}

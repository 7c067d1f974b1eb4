//! The online sampler: the same candidates whether poses come one at a time or in
//! batches; every candidate a pair of its component within γ; P1 online (a component's first
//! candidate in the first row where it has a pair to offer); the cap and the separation hold;
//! σ_ρ's rate and uniformity, by counts against their expectations with fixed seeds.

mod support;

use loops_core::{
    Euclidean, MetricSpec, Separation, Trajectory, UrbanDrive,
    online::{Candidate, Cap, ComponentId, FirstOffer, OnlineLoops, OnlineSampler, OnlineSamplerOptions, Update},
    path_length,
};
use proptest::prelude::*;
use support::{any_case, config};

/// Pushes `traj` in chunks of the sizes in `chunks` (cycled), offering every update.
fn run(
    traj: &Trajectory,
    gamma: f64,
    options: OnlineSamplerOptions,
    chunks: &[usize],
) -> (OnlineLoops, Vec<Candidate>, Vec<Update>) {
    let dim = traj.dim();
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, dim, gamma).unwrap();
    let mut sampler = OnlineSampler::new(options).unwrap();
    let (mut candidates, mut updates) = (Vec::new(), Vec::new());
    let mut pushed = 0;
    for &size in chunks.iter().cycle() {
        if pushed == traj.len() {
            break;
        }
        let end = (pushed + size.max(1)).min(traj.len());
        let update =
            online.push_many(&traj.timestamps_s()[pushed..end], &traj.coords()[pushed * dim..end * dim]).unwrap();
        candidates.extend(sampler.offer(&online, &update).unwrap());
        updates.push(update);
        pushed = end;
    }
    (online, candidates, updates)
}

fn drive(duration_s: f64, seed: u64) -> Trajectory {
    UrbanDrive { duration_s, seed, ..UrbanDrive::default() }.generate().unwrap().trajectory
}

/// The pairs (j, n) a row offers, by component (as of the row): `(row, component, runs of the
/// kept columns)`, from single-pose updates, with the separation measured independently.
fn offers(traj: &Trajectory, updates: &[Update], separation: Separation) -> Vec<(usize, ComponentId, Vec<[usize; 2]>)> {
    let s = path_length(traj, &Euclidean);
    let t = traj.timestamps_s();
    let mut out: Vec<(usize, ComponentId, Vec<[usize; 2]>)> = Vec::new();
    for run in updates.iter().flat_map(|u| &u.runs) {
        let n = run.row;
        let kept: Vec<usize> = (run.run.start as usize..=run.run.end as usize)
            .filter(|&j| j < n && s[n] - s[j] >= separation.path && t[n] - t[j] >= separation.time_s)
            .collect();
        let Some((&a, &b)) = kept.first().zip(kept.last()) else { continue };
        match out.iter_mut().find(|(row, c, _)| *row == n && *c == run.component) {
            Some((_, _, spans)) => spans.push([a, b]),
            None => out.push((n, run.component, vec![[a, b]])),
        }
    }
    // By row, then component: the order of the candidates.
    out.sort_by_key(|&(n, c, _)| (n, c));
    out
}

fn options_strategy() -> impl Strategy<Value = OnlineSamplerOptions> {
    (
        prop_oneof![Just(0.0), 0.0..3.0f64, Just(1.0)],
        prop_oneof![Just(Cap::None), (0.5..30.0f64).prop_map(Cap::PerMinute), (0.01..2.0f64).prop_map(Cap::PerMetre)],
        (any::<bool>(), any::<bool>()),
        prop_oneof![
            Just(Separation::NONE),
            (0.0..4.0f64, 0.0..3.0f64).prop_map(|(p, t)| Separation { path: p, time_s: t })
        ],
        any::<u64>(),
    )
        .prop_map(|(rate, cap, (first_on_appearance, closest_in_row), separation, seed)| OnlineSamplerOptions {
            rate,
            cap,
            first_on_appearance,
            first_offer: FirstOffer::AtEdge,
            closest_in_row,
            separation,
            seed,
        })
}

/// Candidates by emitted component, in order.
fn by_component(candidates: &[Candidate]) -> std::collections::BTreeMap<ComponentId, Vec<&Candidate>> {
    let mut map: std::collections::BTreeMap<ComponentId, Vec<&Candidate>> = Default::default();
    for c in candidates {
        map.entry(c.component).or_default().push(c);
    }
    map
}

/// Every candidate's pair is within γ, in a run of its row with its component, kept by the
/// separation; the cap's bucket bound holds for every component; P1 online holds.
fn check_candidates(
    traj: &Trajectory,
    gamma: f64,
    options: &OnlineSamplerOptions,
    candidates: &[Candidate],
    updates: &[Update],
) -> Result<(), TestCaseError> {
    let s = path_length(traj, &Euclidean);
    let t = traj.timestamps_s();
    let offered = offers(traj, updates, options.separation);
    for c in candidates {
        let [j, n] = c.pair;
        prop_assert!(j < n && n == c.keyframe);
        prop_assert_eq!(c.distance, MetricSpec::Euclidean.distance(traj.point(j), traj.point(n)));
        prop_assert!(c.distance <= gamma);
        let spans = offered.iter().find(|(row, id, _)| *row == n && *id == c.component);
        prop_assert!(spans.is_some_and(|(_, _, spans)| spans.iter().any(|&[a, b]| (a..=b).contains(&j))), "{:?}", c);
        prop_assert!(s[n] - s[j] >= options.separation.path && t[n] - t[j] >= options.separation.time_s);
    }
    // Pairs are distinct within a (keyframe, component).
    let mut keys: Vec<(usize, ComponentId, usize)> =
        candidates.iter().map(|c| (c.keyframe, c.component, c.pair[0])).collect();
    keys.sort_unstable();
    prop_assert!(keys.windows(2).all(|w| w[0] != w[1]));
    // The cap: a token bucket of max(1, c) refilled at c per unit, per component.
    let bound = match options.cap {
        Cap::None => None,
        Cap::PerMinute(c) => Some((c, 60.0, false)),
        Cap::PerMetre(c) => Some((c, 1.0, true)),
    };
    if let Some((c, unit, by_path)) = bound {
        let clock = |n: usize| if by_path { s[n] } else { t[n] };
        for list in by_component(candidates).values() {
            for k in 0..list.len() {
                for l in k..list.len() {
                    let allowed = c.max(1.0) + c * (clock(list[l].keyframe) - clock(list[k].keyframe)) / unit;
                    prop_assert!(
                        (l - k + 1) as f64 <= allowed + 1e-9,
                        "cap broken: {} candidates in {:?}",
                        l - k + 1,
                        list
                    );
                }
            }
        }
    }
    // P1 online: the first row where a component (with all merged into it) offers a pair gives
    // it a `first` candidate, its closest offered pair; no other row does.
    let mut lineage: Vec<u32> = Vec::new();
    let mut served: Vec<bool> = Vec::new();
    fn root(lineage: &mut [u32], mut id: u32) -> u32 {
        while lineage[id as usize] != id {
            id = lineage[id as usize];
        }
        id
    }
    let mut merges = updates.iter().flat_map(|u| &u.merged).peekable();
    let mut k = 0;
    for (n, id, spans) in &offered {
        let grow = |lineage: &mut Vec<u32>, served: &mut Vec<bool>, id: u32| {
            while lineage.len() <= id as usize {
                lineage.push(lineage.len() as u32);
                served.push(false);
            }
        };
        grow(&mut lineage, &mut served, *id);
        while let Some(m) = merges.next_if(|m| m.pose <= *n) {
            grow(&mut lineage, &mut served, m.retired);
            let (a, b) = (root(&mut lineage, m.retired), root(&mut lineage, m.survivor));
            lineage[a as usize] = b;
            served[b as usize] |= served[a as usize];
        }
        while k < candidates.len() && (candidates[k].keyframe, candidates[k].component) < (*n, *id) {
            k += 1;
        }
        let here: Vec<&Candidate> =
            candidates[k..].iter().take_while(|c| (c.keyframe, c.component) == (*n, *id)).collect();
        let r = root(&mut lineage, *id);
        let firsts: Vec<&&Candidate> = here.iter().filter(|c| c.first).collect();
        if options.first_on_appearance && !served[r as usize] {
            prop_assert_eq!(firsts.len(), 1, "row {} component {}: no first candidate", n, id);
            // The closest offered pair (earliest on ties).
            let rank = |j: usize| MetricSpec::Euclidean.distance(traj.point(j), traj.point(*n));
            let best = spans.iter().flat_map(|&[a, b]| a..=b).min_by(|&x, &y| rank(x).total_cmp(&rank(y))).unwrap();
            prop_assert_eq!(rank(firsts[0].pair[0]), rank(best));
        } else {
            prop_assert!(firsts.is_empty(), "row {} component {}: a second first", n, id);
        }
        served[r as usize] |= !here.is_empty();
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(96, 0x0419_0002))]

    #[test]
    fn batches_give_the_same_candidates_and_every_rule_holds(
        case in any_case(160),
        options in options_strategy(),
        chunks in prop::collection::vec(1..30usize, 1..6),
    ) {
        let (_, single, updates) = run(&case.traj, case.gamma, options, &[1]);
        let (_, batched, _) = run(&case.traj, case.gamma, options, &chunks);
        prop_assert_eq!(&single, &batched);
        check_candidates(&case.traj, case.gamma, &options, &single, &updates)?;
        for first_offer in [FirstOffer::EdgeThenClosest, FirstOffer::AtClosestApproach] {
            let options = OnlineSamplerOptions { first_offer, ..options };
            let (_, one, _) = run(&case.traj, case.gamma, options, &[1]);
            prop_assert_eq!(&one, &run(&case.traj, case.gamma, options, &chunks).1);
            if first_offer == FirstOffer::EdgeThenClosest {
                check_improvements(&case.traj, &options, &one, &single, &updates)?;
            }
        }
    }
}

/// The offered rows by component root as of the row (merges replayed in order), and each
/// merge's pose with the two roots it joined.
#[allow(clippy::type_complexity)]
fn rows_by_root(
    traj: &Trajectory,
    updates: &[Update],
    separation: Separation,
) -> (Vec<(usize, ComponentId, Vec<[usize; 2]>)>, Vec<(usize, [ComponentId; 2])>) {
    fn root(lineage: &[u32], mut id: u32) -> u32 {
        while lineage[id as usize] != id {
            id = lineage[id as usize];
        }
        id
    }
    let grow = |lineage: &mut Vec<u32>, id: u32| {
        while lineage.len() <= id as usize {
            lineage.push(lineage.len() as u32);
        }
    };
    let (mut lineage, mut rows, mut joins) = (Vec::new(), Vec::new(), Vec::new());
    let mut merges = updates.iter().flat_map(|u| &u.merged).peekable();
    for (n, id, spans) in offers(traj, updates, separation) {
        grow(&mut lineage, id);
        while let Some(m) = merges.next_if(|m| m.pose <= n) {
            grow(&mut lineage, m.retired.max(m.survivor));
            let (a, b) = (root(&lineage, m.retired), root(&lineage, m.survivor));
            lineage[a as usize] = b;
            joins.push((m.pose, [a, b]));
        }
        rows.push((n, root(&lineage, id), spans));
    }
    (rows, joins)
}

/// With the edge then the closest approach (`with`): without its improvements the stream is
/// the edge one (`edge`); every improvement names an earlier first candidate and comes after
/// it; where no merge touches the pass, brute force over the offered pairs: the rows from the
/// first candidate's to the one before the improvement's all offer the component and the
/// improvement's row does not, the improvement is the closest pair of those rows (earliest on
/// ties) and closer than the first; a first candidate whose pass ends before the drive does
/// gets an improvement exactly when its pair is not the pass's closest. Returns the
/// improvements checked by brute force.
fn check_improvements(
    traj: &Trajectory,
    options: &OnlineSamplerOptions,
    with: &[Candidate],
    edge: &[Candidate],
    updates: &[Update],
) -> Result<usize, TestCaseError> {
    let kept: Vec<Candidate> = with.iter().filter(|c| c.improves.is_none()).copied().collect();
    prop_assert_eq!(&kept, edge, "the improvements are the only difference");
    let (rows, joins) = rows_by_root(traj, updates, options.separation);
    let root_at = |n: usize, id: ComponentId| rows.iter().find(|r| r.0 == n && r.1 == id).is_some();
    let distance = |[j, k]: [usize; 2]| MetricSpec::Euclidean.distance(traj.point(j), traj.point(k));
    let mut checked = 0;
    for f in with.iter().filter(|c| c.first) {
        let improvements: Vec<&Candidate> = with.iter().filter(|c| c.improves == Some(f.pair)).collect();
        prop_assert!(improvements.len() <= 1, "{:?}", improvements);
        let id = f.component; // a root as of its row: the engine's ids are resolved
        prop_assert!(root_at(f.keyframe, id), "{:?}", f);
        // The pass: rows from the first one on that offer the component.
        let end = (f.keyframe..traj.len()).find(|&n| !root_at(n, id));
        let window_end = end.unwrap_or(traj.len());
        if joins.iter().any(|&(pose, pair)| pose >= f.keyframe && pose <= window_end && pair.contains(&id)) {
            continue; // a merge joins another pass: not brute-forced
        }
        let Some(end) = end else {
            prop_assert!(improvements.is_empty(), "a pass still under way improved: {:?}", improvements);
            continue;
        };
        let mut best = (f64::INFINITY, [0, 0]);
        for (n, _, spans) in rows.iter().filter(|r| r.1 == id && (f.keyframe..end).contains(&r.0)) {
            for j in spans.iter().flat_map(|&[a, b]| a..=b) {
                let d = distance([j, *n]);
                if d < best.0 {
                    best = (d, [j, *n]);
                }
            }
        }
        if best.1 == f.pair || best.0 == f.distance {
            prop_assert!(improvements.is_empty(), "the first was the closest: {:?} {:?}", f, improvements);
        } else {
            prop_assert_eq!(improvements.len(), 1, "no improvement for {:?}, closest {:?}", f, best);
            let c = improvements[0];
            prop_assert_eq!((c.keyframe, c.pair, c.distance, c.first), (end, best.1, best.0, false), "{:?}", c);
            prop_assert!(c.component == id && c.distance < f.distance);
            checked += 1;
        }
    }
    for c in with.iter().filter(|c| c.improves.is_some()) {
        prop_assert!(c.pair[1] < c.keyframe && !c.first, "{:?}", c);
        prop_assert!(with.iter().any(|f| f.first && Some(f.pair) == c.improves && f.keyframe < c.keyframe), "{:?}", c);
    }
    Ok(checked)
}

#[test]
fn the_urban_drive_with_every_rule() {
    let traj = drive(1200.0, 5);
    let gamma = 20.0;
    for options in [
        OnlineSamplerOptions { rate: 0.2, ..OnlineSamplerOptions::default() },
        OnlineSamplerOptions {
            rate: 2.0,
            cap: Cap::PerMinute(3.0),
            separation: Separation::for_gamma(gamma),
            seed: 9,
            ..OnlineSamplerOptions::default()
        },
        OnlineSamplerOptions {
            rate: 1.0,
            cap: Cap::PerMetre(0.05),
            separation: Separation::time_s(30.0),
            seed: 4,
            ..OnlineSamplerOptions::default()
        },
    ] {
        let (online, single, updates) = run(&traj, gamma, options, &[1]);
        let (_, batched, _) = run(&traj, gamma, options, &[1, 10, 100]);
        assert_eq!(single, batched);
        // The rules of the edge offer; the improvements are checked on their own.
        let at_edge: Vec<Candidate> = single.iter().filter(|c| c.improves.is_none()).copied().collect();
        check_candidates(&traj, gamma, &options, &at_edge, &updates).unwrap();
        // P1 on the final components: every component that offers a pair has a candidate.
        let loops = online.to_loops().unwrap();
        let offered = offers(&traj, &updates, options.separation);
        let mut covered = vec![false; loops.components().len()];
        for c in &single {
            covered[loops.component_of(c.pair[0], c.pair[1]).unwrap()] = true;
        }
        for (n, _, spans) in &offered {
            let k = loops.component_of(spans[0][0], *n).unwrap();
            assert!(covered[k], "component {k} offers pairs but has no candidate");
        }
        // The cap binds: fewer candidates than the rate alone would give.
        if options.cap != Cap::None {
            let uncapped = run(&traj, gamma, OnlineSamplerOptions { cap: Cap::None, ..options }, &[50]).1;
            assert!(single.len() * 2 < uncapped.len(), "{} capped, {} not", single.len(), uncapped.len());
        }
    }
}

/// σ_ρ's counts and uniformity against their expectations: per (row, component) offering m
/// pairs, min(K, m) distinct draws with K = ⌊r⌋ + Bernoulli(r − ⌊r⌋), uniform over the m pairs.
#[test]
fn the_rate_and_the_spread_are_sigma_rho() {
    let traj = drive(1800.0, 11);
    let gamma = 30.0;
    for rate in [0.37, 2.5] {
        let options = OnlineSamplerOptions {
            rate,
            first_on_appearance: false,
            closest_in_row: false,
            seed: 2,
            ..OnlineSamplerOptions::default()
        };
        let (_, candidates, updates) = run(&traj, gamma, options, &[1]);
        let offered = offers(&traj, &updates, Separation::NONE);
        let (low, p) = (rate.floor(), rate.fract());
        let (mut expected, mut variance) = (0.0, 0.0);
        let mut bins_expected = [0.0; 10];
        let mut bins_found = [0.0; 10];
        let mut k = 0;
        for (n, id, spans) in &offered {
            let m: usize = spans.iter().map(|[a, b]| b - a + 1).sum();
            let (a, b) = ((low as usize).min(m) as f64, ((low as usize) + 1).min(m) as f64);
            let mean = (1.0 - p) * a + p * b;
            expected += mean;
            variance += (1.0 - p) * a * a + p * b * b - mean * mean;
            while k < candidates.len() && (candidates[k].keyframe, candidates[k].component) < (*n, *id) {
                k += 1;
            }
            if m >= 10 {
                // Each pair is drawn with probability mean / m; bins by its place among the m.
                let place = |j: usize| {
                    let mut before = 0;
                    for &[a, b] in spans {
                        if j <= b {
                            return before + j - a;
                        }
                        before += b - a + 1;
                    }
                    unreachable!()
                };
                for q in 0..m {
                    bins_expected[10 * q / m] += mean / m as f64;
                }
                for c in candidates[k..].iter().take_while(|c| (c.keyframe, c.component) == (*n, *id)) {
                    bins_found[10 * place(c.pair[0]) / m] += 1.0;
                }
            }
        }
        let z = (candidates.len() as f64 - expected) / variance.sqrt();
        let chi2: f64 = bins_found.iter().zip(&bins_expected).map(|(f, e)| (f - e) * (f - e) / e).sum();
        eprintln!(
            "rate {rate}: {} candidates, {expected:.1} ± {:.1} expected (z = {z:.2}); χ² = {chi2:.1}",
            candidates.len(),
            variance.sqrt()
        );
        assert!(
            z.abs() < 5.0,
            "rate {rate}: {} candidates, {expected:.0} ± {:.0} expected",
            candidates.len(),
            variance.sqrt()
        );
        // Not vacuous: thousands of draws, a standard deviation under 2% of them.
        assert!(expected > 3000.0 && variance.sqrt() < 0.02 * expected, "{expected} ± {}", variance.sqrt());
        assert!(bins_expected.iter().all(|&e| e > 200.0), "{bins_expected:?}");
        // The 99.9% point of χ² with 9 degrees of freedom.
        assert!(chi2 < 27.88, "rate {rate}: χ² = {chi2:.1} over {bins_found:?} against {bins_expected:?}");
    }
}

/// The default's pick in a row: at rate 1 every drawn candidate is the closest pair its
/// component offers in that row (measured here by brute force over the offered pairs); without
/// `closest_in_row` most are not.
#[test]
fn the_default_draws_the_closest_pair_of_each_row() {
    let traj = drive(1200.0, 4);
    let gamma = 30.0;
    let options = OnlineSamplerOptions { rate: 1.0, first_on_appearance: false, ..OnlineSamplerOptions::default() };
    assert!(options.closest_in_row, "the default sampler takes a row's closest pair");
    let closest_share = |options: OnlineSamplerOptions| {
        let (_, candidates, updates) = run(&traj, gamma, options, &[1]);
        let offered = offers(&traj, &updates, Separation::NONE);
        let distance = |j: usize, n: usize| {
            let (a, b) = (traj.point(j), traj.point(n));
            a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
        };
        let mut closest = 0;
        for c in &candidates {
            let n = c.keyframe;
            let (_, _, spans) = offered.iter().find(|(row, id, _)| *row == n && *id == c.component).unwrap();
            let best = spans.iter().flat_map(|&[a, b]| a..=b).map(|j| distance(j, n)).fold(f64::INFINITY, f64::min);
            closest += usize::from(distance(c.pair[0], n) <= best + 1e-9);
        }
        (closest, candidates.len())
    };
    let (closest, all) = closest_share(options);
    assert!(all > 1000, "{all} candidates");
    assert_eq!(closest, all, "{closest} of {all} candidates are their row's closest pair");
    let (uniform, all) = closest_share(OnlineSamplerOptions { closest_in_row: false, ..options });
    assert!(uniform < all / 2, "uniform draws: {uniform} of {all} the closest");
}

#[test]
fn seeds_matter_and_a_rebuild_starts_the_sampler_again() {
    let traj = drive(600.0, 2);
    let options = OnlineSamplerOptions { rate: 0.5, ..OnlineSamplerOptions::default() };
    let a = run(&traj, 20.0, options, &[1]).1;
    let b = run(&traj, 20.0, OnlineSamplerOptions { seed: 1, ..options }, &[1]).1;
    assert_ne!(a, b);
    assert_eq!(a.iter().filter(|c| c.first).count(), b.iter().filter(|c| c.first).count());
    // After a rebuild every component is new to the sampler: the next pose of each component
    // that offers a pair gets a first candidate again.
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 3, 20.0).unwrap();
    let mut sampler = OnlineSampler::new(options).unwrap();
    let half = traj.len() / 2;
    let update = online.push_many(&traj.timestamps_s()[..half], &traj.coords()[..3 * half]).unwrap();
    assert!(sampler.offer(&online, &update).unwrap().iter().any(|c| c.first));
    let part = Trajectory::new(traj.timestamps_s()[..half].to_vec(), traj.coords()[..3 * half].to_vec(), 3).unwrap();
    online.rebuild(&part).unwrap();
    let update = online.push(traj.timestamps_s()[half], traj.point(half)).unwrap();
    let after = sampler.offer(&online, &update).unwrap();
    assert!(after.iter().any(|c| c.first), "{after:?}");
    assert!(OnlineSampler::new(OnlineSamplerOptions { rate: -1.0, ..options }).is_err());
    assert!(OnlineSampler::new(OnlineSamplerOptions { cap: Cap::PerMinute(0.0), ..options }).is_err());
    assert!(OnlineSampler::new(OnlineSamplerOptions { separation: Separation::path(f64::NAN), ..options }).is_err());
}

#[test]
fn an_update_is_offered_once_in_order_by_its_own_engine() {
    let points = [0.0, 0.0, 0.2, 0.0, 5.0, 0.0, 0.1, 0.0];
    let push = |online: &mut OnlineLoops| online.push_many(&[0.0, 1.0, 2.0, 3.0], &points).unwrap();
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, 1.0).unwrap();
    let mut sampler = OnlineSampler::new(OnlineSamplerOptions::default()).unwrap();
    let update = push(&mut online);
    let expected = sampler.offer(&online, &update).unwrap();
    assert!(expected.iter().any(|c| c.first), "{expected:?}");
    let twice = sampler.offer(&online, &update).unwrap_err();
    assert!(twice.to_string().contains("already offered"), "{twice}");
    // An older update, one that names no engine, one of a clone: not the engine's last push.
    let older = update.clone();
    let _ = online.push(4.0, &[0.0, 0.0]).unwrap();
    let copy = online.clone();
    let latest = online.push(5.0, &[0.0, 0.1]).unwrap();
    for stale in [older, Update { stamp: Default::default(), ..latest.clone() }] {
        let refused = sampler.offer(&online, &stale).unwrap_err();
        assert!(refused.to_string().contains("not the last push"), "{refused}");
    }
    assert!(sampler.offer(&copy, &latest).is_err());
    // Engines made one after another (each dropped before the next) are new to the sampler,
    // whichever address they get: each gets its first candidates again.
    for _ in 0..3 {
        let mut fresh = OnlineLoops::new(MetricSpec::Euclidean, 2, 1.0).unwrap();
        let update = push(&mut fresh);
        assert_eq!(sampler.offer(&fresh, &update).unwrap(), expected);
    }
}

#[test]
fn a_saved_sampler_goes_on_as_the_original() {
    let traj = drive(900.0, 4);
    let options = OnlineSamplerOptions { rate: 0.3, cap: Cap::PerMinute(2.0), ..OnlineSamplerOptions::default() };
    let (t, coords, dim) = (traj.timestamps_s(), traj.coords(), traj.dim());
    let half = traj.len() / 2;
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, dim, 20.0).unwrap();
    let mut sampler = OnlineSampler::new(options).unwrap();
    let update = online.push_many(&t[..half], &coords[..dim * half]).unwrap();
    sampler.offer(&online, &update).unwrap();
    let bytes = rmp_serde::to_vec(&sampler).unwrap();
    let mut copy: OnlineSampler = rmp_serde::from_slice(&bytes).unwrap();
    // The copy follows a copy of the engine (another engine, at the same pose and rebuild count).
    let mut other = online.clone();
    let rest = |online: &mut OnlineLoops| online.push_many(&t[half..], &coords[dim * half..]).unwrap();
    let (update, other_update) = (rest(&mut online), rest(&mut other));
    let expected = sampler.offer(&online, &update).unwrap();
    assert_eq!(copy.offer(&other, &other_update).unwrap(), expected);
    // What it carried matters: P1 served the components it saw, which a new sampler serves again.
    let mut third = online.clone();
    let third_update = third.push(t[t.len() - 1] + 1.0, traj.point(traj.len() - 1)).unwrap();
    let mut carried: OnlineSampler = rmp_serde::from_slice(&rmp_serde::to_vec(&sampler).unwrap()).unwrap();
    let mut new = OnlineSampler::new(options).unwrap();
    let fresh = new.offer(&third, &third_update).unwrap();
    let went_on = carried.offer(&third, &third_update).unwrap();
    assert!(fresh.iter().filter(|c| c.first).count() > went_on.iter().filter(|c| c.first).count(), "{fresh:?}");
    // A saved sampler offered an update that does not start where it stopped starts afresh.
    let mut restarted: OnlineSampler = rmp_serde::from_slice(&bytes).unwrap();
    let mut anew = OnlineLoops::new(MetricSpec::Euclidean, dim, 20.0).unwrap();
    let whole = anew.push_many(t, coords).unwrap();
    let from_scratch = OnlineSampler::new(options).unwrap().offer(&anew, &whole).unwrap();
    assert_eq!(restarted.offer(&anew, &whole).unwrap(), from_scratch);
    // A forged state is refused, naming the component.
    let mut forged: serde_json::Value = serde_json::to_value(&sampler).unwrap();
    let states = forged["states"].as_array_mut().unwrap();
    let k = states.iter().position(|s| !s.is_null()).unwrap();
    states[k]["tokens"] = serde_json::json!(-1.0);
    let refused = serde_json::from_value::<OnlineSampler>(forged).unwrap_err();
    assert!(refused.to_string().contains(&format!("component {k}")), "{refused}");
}

/// A straight road east from the origin, a detour east, south and west, then a road north that
/// passes the origin 3 m off: γ = 6 reaches the start of the road first 6 m before the closest
/// approach.
fn pass_by() -> Trajectory {
    let leg = |from: [f64; 2], to: [f64; 2], steps: usize| {
        (1..=steps).map(move |k| {
            let f = k as f64 / steps as f64;
            [from[0] + f * (to[0] - from[0]), from[1] + f * (to[1] - from[1])]
        })
    };
    let mut points = vec![[0.0, 0.0]];
    points.extend(leg([0.0, 0.0], [200.0, 0.0], 400));
    points.extend(leg([200.0, 0.0], [200.0, -100.0], 200));
    points.extend(leg([200.0, -100.0], [-3.0, -100.0], 406));
    points.extend(leg([-3.0, -100.0], [-3.0, 100.0], 400));
    let times = (0..points.len()).map(|k| k as f64 * 0.1).collect();
    Trajectory::new(times, points.concat(), 2).unwrap()
}

#[test]
fn the_first_candidate_at_the_closest_approach_is_the_pass_closest_pair() {
    let traj = pass_by();
    let separation = Separation::path(50.0);
    let at_edge = OnlineSamplerOptions {
        rate: 0.0,
        separation,
        first_offer: FirstOffer::AtEdge,
        ..OnlineSamplerOptions::default()
    };
    let at_closest = OnlineSamplerOptions { first_offer: FirstOffer::AtClosestApproach, ..at_edge };
    // The brute-force closest separated pair within γ, and the rows that reach the road east.
    let s = path_length(&traj, &Euclidean);
    let (mut closest, mut rows) = ((f64::INFINITY, [0, 0]), Vec::new());
    for k in 0..traj.len() {
        for j in 0..k {
            let (a, b) = (traj.point(j), traj.point(k));
            let d = (a[0] - b[0]).hypot(a[1] - b[1]);
            if d <= 6.0 && s[k] - s[j] >= 50.0 {
                if d < closest.0 {
                    closest = (d, [j, k]);
                }
                rows.push(k);
            }
        }
    }
    let last_row = *rows.iter().max().unwrap();
    assert!((closest.0 - 3.0).abs() < 1e-12, "{closest:?}");
    let edge = run(&traj, 6.0, at_edge, &[1]).1;
    assert_eq!(edge.len(), 1, "{edge:?}");
    assert!(edge[0].distance > 5.5, "at the edge of γ: {:?}", edge[0]);
    for chunks in [&[1][..], &[7, 1, 300], &[traj.len()]] {
        let found = run(&traj, 6.0, at_closest, chunks).1;
        assert_eq!(found.len(), 1, "{found:?}");
        let c = found[0];
        assert_eq!((c.pair, c.distance, c.first), (closest.1, closest.0, true), "{c:?}");
        assert_eq!(c.keyframe, last_row + 1, "offered at the first row after the pass");
    }
    // The drive stops in the middle of the pass: no first candidate yet.
    let cut =
        Trajectory::new(traj.timestamps_s()[..last_row].to_vec(), traj.coords()[..2 * last_row].to_vec(), 2).unwrap();
    assert!(run(&cut, 6.0, at_closest, &[1]).1.is_empty());
}

#[test]
fn the_default_offers_the_edge_then_improves_it_at_the_closest_approach() {
    let traj = pass_by();
    let separation = Separation::path(50.0);
    let options = OnlineSamplerOptions { rate: 0.0, separation, ..OnlineSamplerOptions::default() };
    assert_eq!(options.first_offer, FirstOffer::EdgeThenClosest);
    let edge = run(&traj, 6.0, OnlineSamplerOptions { first_offer: FirstOffer::AtEdge, ..options }, &[1]).1;
    let closest =
        run(&traj, 6.0, OnlineSamplerOptions { first_offer: FirstOffer::AtClosestApproach, ..options }, &[1]).1;
    for chunks in [&[1][..], &[7, 1, 300], &[traj.len()]] {
        let found = run(&traj, 6.0, options, chunks).1;
        assert_eq!(found.len(), 2, "{found:?}");
        assert_eq!(found[0], edge[0], "the edge candidate at once");
        let improvement = Candidate { first: false, improves: Some(edge[0].pair), ..closest[0] };
        assert_eq!(found[1], improvement, "then the closest approach, once the pass is over");
    }
    // A path that reaches γ and turns back at once: the edge pair is the pass's closest, and
    // is not offered twice.
    let mut points: Vec<[f64; 2]> = (0..traj.len()).map(|k| [traj.point(k)[0], traj.point(k)[1]]).collect();
    points.truncate(1007); // ... the detour back to (-3, -100)
    points.extend((0..=189).map(|k| [0.0, -100.3 + 0.5 * k as f64])); // north to (0, -5.8)
    points.extend((1..=200).map(|k| [0.5 * k as f64, -6.3])); // and east, beyond γ of the road
    let times = (0..points.len()).map(|k| k as f64 * 0.1).collect();
    let back = Trajectory::new(times, points.concat(), 2).unwrap();
    let found = run(&back, 6.0, options, &[1]).1;
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].first && (found[0].distance - 5.8).abs() < 1e-9, "{found:?}");
}

#[test]
fn the_default_differs_from_the_edge_only_by_its_improvements() {
    let traj = drive(1200.0, 5);
    let gamma = 20.0;
    for options in [
        OnlineSamplerOptions { rate: 0.2, ..OnlineSamplerOptions::default() },
        OnlineSamplerOptions {
            rate: 2.0,
            cap: Cap::PerMinute(3.0),
            separation: Separation::for_gamma(gamma),
            seed: 9,
            ..OnlineSamplerOptions::default()
        },
        OnlineSamplerOptions { rate: 0.0, separation: Separation::for_gamma(gamma), ..OnlineSamplerOptions::default() },
    ] {
        let (_, with, updates) = run(&traj, gamma, options, &[1]);
        for chunks in [&[1, 10, 100][..], &[traj.len()]] {
            assert_eq!(run(&traj, gamma, options, chunks).1, with);
        }
        let edge = run(&traj, gamma, OnlineSamplerOptions { first_offer: FirstOffer::AtEdge, ..options }, &[3]).1;
        let checked = check_improvements(&traj, &options, &with, &edge, &updates).unwrap();
        let improvements = with.iter().filter(|c| c.improves.is_some()).count();
        // A few passes meet a merge, and are not brute-forced.
        assert!(checked >= 3 && 4 * checked >= 3 * improvements, "{improvements} improvements, {checked} checked");
    }
}

#[test]
fn the_first_candidates_at_the_closest_approach_do_not_depend_on_batches() {
    let traj = drive(1200.0, 6);
    let options = OnlineSamplerOptions {
        rate: 0.2,
        cap: Cap::PerMinute(1.0),
        first_offer: FirstOffer::AtClosestApproach,
        separation: Separation::for_gamma(20.0),
        ..OnlineSamplerOptions::default()
    };
    let (online, one, _) = run(&traj, 20.0, options, &[1]);
    assert_eq!(run(&traj, 20.0, options, &[5, 1, 97]).1, one);
    let firsts: Vec<&Candidate> = one.iter().filter(|c| c.first).collect();
    assert!(firsts.len() >= 3, "{firsts:?}");
    for c in &firsts {
        assert!(c.pair[0] < c.pair[1] && c.pair[1] < c.keyframe, "{c:?}");
        let id = online.resolve(c.component);
        // Never closer than the component's closest pair of the whole drive.
        let closest = online.component(id).unwrap().closest_distance;
        assert!(c.distance >= closest && c.distance <= 20.0, "{c:?}");
    }
}

//! Nothing aborted: requests too big for one answer are refused before anything is drawn
//! (`MAX_SAMPLES`), and an `Interrupt` stops every long computation soon after it is set.

use std::sync::atomic::{AtomicU64, Ordering};

use loops_core::{
    Detections, Error, Euclidean, Interrupt, MAX_SAMPLES, Metric, SampleSize, Sampler, SamplerKind, TooManySamples,
    Trajectory, UrbanDrive, cluster_detections, find_loops,
    plane::{PlaneGrid, distance_image},
    sample_clusters, sample_loops, with_threads,
};

/// A robot parked for `n` poses: every pair is within γ, so S_γ has n(n − 1)/2 off-diagonal
/// pairs in one run per row (cheap to find, many to sample).
fn parked(n: usize) -> Trajectory {
    Trajectory::new((0..n).map(|i| i as f64 * 0.1).collect(), vec![0.0; 2 * n], 2).unwrap()
}

#[test]
fn a_budget_beyond_max_samples_is_refused_before_drawing() {
    // 3,600 poses: 6.5 million candidate pairs (5.4 million 30 s apart), more than MAX_SAMPLES.
    let traj = parked(3_600);
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    let available = 3_600_u64 * 3_599 / 2;
    assert!(available > MAX_SAMPLES as u64);
    for kind in [SamplerKind::Alpha, SamplerKind::Rho, SamplerKind::One, SamplerKind::TimeGap] {
        let sampler = Sampler::new(kind, SampleSize::Budget(usize::MAX), 0);
        let error = sample_loops(&traj, &Euclidean, &loops, &sampler).unwrap_err();
        let Error::TooManySamples(refused) = error.clone() else {
            panic!("{kind}: {error}");
        };
        let TooManySamples { what, count, bytes, max, .. } = *refused;
        assert_eq!((what, max), ("samples", MAX_SAMPLES), "{kind}");
        // All the pairs the sampler would hand out, and at least their rows' size in memory.
        assert!(count <= available && count > MAX_SAMPLES as u64, "{kind}: {count}");
        assert!(bytes >= count * size_of::<loops_core::Sample>() as u64, "{kind}: {bytes}");
        let message = error.to_string();
        assert!(!message.contains('\n'), "one line: {message}");
        assert!(
            message.starts_with(&format!("budget {} asks for {count} samples (about ", usize::MAX))
                && message.contains("GiB of memory")
                && message.contains("give a budget of at most 5000000, or a smaller rate"),
            "{message}"
        );
    }
    // A rate that keeps every pair: refused by its expected count.
    let all = Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0);
    let error = sample_loops(&traj, &Euclidean, &loops, &all).unwrap_err();
    assert!(matches!(&error, Error::TooManySamples(refused) if refused.count == available), "{error}");
    assert!(error.to_string().starts_with("rate 1 asks for "), "{error}");
    // Drawn detections have the same bound.
    let error = Detections::draw(&loops, SampleSize::Rate(1.0), 0).unwrap_err();
    assert!(matches!(&error, Error::TooManySamples(refused) if refused.what == "detections"), "{error}");
    // Within the bound, the budget is spent exactly.
    let within = Sampler::new(SamplerKind::Rho, SampleSize::Budget(100_000), 0);
    assert_eq!(sample_loops(&traj, &Euclidean, &loops, &within).unwrap().len(), 100_000);
}

#[test]
fn an_interrupted_token_stops_every_long_call() {
    let drive = UrbanDrive { duration_s: 900.0, seed: 3, ..UrbanDrive::default() }.generate().unwrap();
    let traj = &drive.trajectory;
    let loops = find_loops(traj, &Euclidean, 40.0).unwrap();
    let detections = Detections::draw(&loops, SampleSize::Rate(0.05), 0).unwrap();
    let clusters = cluster_detections(&detections, 10.0).unwrap();
    let grid = PlaneGrid::new(traj, None, 200).unwrap();
    let stop = Interrupt::new();
    stop.interrupt();
    let interrupted = |what: &str, result: Result<(), Error>| assert_eq!(result, Err(Error::Interrupted), "{what}");
    stop.run(|| {
        interrupted("find_loops", find_loops(traj, &Euclidean, 40.0).map(drop));
        let set = loops.sublevel_set().clone();
        interrupted("Loops::try_from_set", loops_core::Loops::try_from_set(traj, &Euclidean, set).map(drop));
        for kind in [SamplerKind::Rho, SamplerKind::Alpha, SamplerKind::Cartographer] {
            let sampler = Sampler::new(kind, SampleSize::Budget(100), 0);
            interrupted(kind.name(), sample_loops(traj, &Euclidean, &loops, &sampler).map(drop));
        }
        let sampler = Sampler::new(SamplerKind::Rho, SampleSize::Budget(100), 0);
        interrupted("sample_clusters", sample_clusters(&clusters, &sampler).map(drop));
        interrupted("draw", Detections::draw(&loops, SampleSize::Budget(100), 0).map(drop));
        interrupted("cluster_detections", cluster_detections(&detections, 10.0).map(drop));
        interrupted("distance_image", distance_image(traj, &Euclidean, &grid).map(drop));
        interrupted("label_image", loops.label_image(&grid).map(drop));
        // On the threads of `with_threads` too.
        interrupted("with_threads", with_threads(Some(2), || find_loops(traj, &Euclidean, 40.0)).unwrap().map(drop));
    });
    // Outside `run`, nothing is interrupted.
    assert!(find_loops(traj, &Euclidean, 40.0).is_ok());
}

/// The Euclidean metric, counting its distances and interrupting `stop` at the `after`-th.
struct Interrupting<'a> {
    stop: &'a Interrupt,
    after: u64,
    count: AtomicU64,
}

impl Metric for Interrupting<'_> {
    fn name(&self) -> String {
        "interrupting euclidean".into()
    }

    fn check_dim(&self, dim: usize) -> loops_core::Result<()> {
        Euclidean.check_dim(dim)
    }

    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        if self.count.fetch_add(1, Ordering::Relaxed) + 1 == self.after {
            self.stop.interrupt();
        }
        Euclidean.distance(a, b)
    }
}

#[test]
fn an_interrupt_stops_a_scan_in_flight_within_a_row() {
    // A 1 h drive: the full scan measures millions of distances.
    let drive = UrbanDrive { duration_s: 3600.0, seed: 1, ..UrbanDrive::default() }.generate().unwrap();
    let traj = &drive.trajectory;
    let full = Interrupting { stop: &Interrupt::new(), after: 0, count: AtomicU64::new(0) };
    find_loops(traj, &full, 40.0).unwrap();
    let full = full.count.into_inner();
    assert!(full > 1_000_000, "{full}");
    // Interrupted a third of the way through.
    let stop = Interrupt::new();
    let metric = Interrupting { stop: &stop, after: full / 3, count: AtomicU64::new(0) };
    let result = with_threads(Some(2), || stop.run(|| find_loops(traj, &metric, 40.0))).unwrap();
    assert_eq!(result, Err(Error::Interrupted));
    // After the interrupt, each thread finishes at most the row it is in.
    let after = metric.count.into_inner() - full / 3;
    assert!(after < full / 100, "{after} distances measured after the interrupt, of {full}");
}

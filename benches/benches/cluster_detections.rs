//! `cluster_detections` on detections drawn from S_γ (γ = 40 m) of the urban drive, ε = 30 s:
//! the dense workload of `benches/cluster_compare.py` (2.1 h drive, 10⁵ and 10⁶ detections),
//! the same 10⁶ in random order, on one thread and on every core.

use criterion::{Criterion, criterion_group, criterion_main};
use loops_core::{Detections, Euclidean, SampleSize, cluster_detections, find_loops, with_threads};
use std::hint::black_box;

fn bench_cluster_detections(c: &mut Criterion) {
    let mut group = c.benchmark_group("cluster_detections");
    group.sample_size(20);
    let traj = loops_benches::urban_drive(2.1);
    let loops = find_loops(&traj, &Euclidean, 40.0).expect("valid drive");
    for n in [100_000, 1_000_000] {
        let in_time_order = Detections::draw(&loops, SampleSize::Budget(n), 0).expect("budget below |S_γ|");
        // The same detections in a fixed pseudo-random order.
        let mut order: Vec<usize> = (0..n).collect();
        let mut state = 7u64;
        for k in (1..n).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            order.swap(k, (state >> 33) as usize % (k + 1));
        }
        let (t, t_prime) = (in_time_order.t_s(), in_time_order.t_prime_s());
        let shuffled =
            Detections::new(order.iter().map(|&k| t[k]).collect(), order.iter().map(|&k| t_prime[k]).collect())
                .expect("finite times");
        for (name, detections) in [("in_time_order", &in_time_order), ("shuffled", &shuffled)] {
            if n < 1_000_000 && name == "shuffled" {
                continue;
            }
            for threads in [1, 2] {
                group.bench_function(format!("urban_2.1h_dense_{n}_{name}_eps30_threads{threads}"), |b| {
                    b.iter(|| {
                        with_threads(Some(threads), || {
                            cluster_detections(black_box(detections), 30.0).map(|clusters| clusters.len())
                        })
                        .expect("thread pool")
                    })
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, bench_cluster_detections);
criterion_main!(benches);

//! `find_loops` on the urban drive: exact components with areas, holes and closest pairs, and
//! loop duration τ, on one thread and on every core.

use criterion::{Criterion, criterion_group, criterion_main};
use loops_core::{Euclidean, RotationDistance, Scale, Se3, Selection, Side, UrbanDrive, find_loops, with_threads};
use std::hint::black_box;

fn bench_find_loops(c: &mut Criterion) {
    let mut group = c.benchmark_group("find_loops");
    group.sample_size(10);
    for hours in [0.5, 2.1] {
        let traj = loops_benches::urban_drive(hours);
        for threads in [1, 2] {
            group.bench_function(format!("urban_{hours}h_{}poses_gamma40_threads{threads}", traj.len()), |b| {
                b.iter(|| {
                    with_threads(Some(threads), || {
                        let loops = find_loops(black_box(&traj), &Euclidean, 40.0).expect("valid input");
                        let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).expect("all");
                        black_box((loops.components().len(), tau[0]))
                    })
                    .expect("thread pool")
                });
            });
        }
    }
    group.finish();

    // SE(3) against Euclidean on the same 2.1 h drive (headings from the drive), one thread.
    let mut group = c.benchmark_group("metric");
    group.sample_size(10);
    let drive = UrbanDrive { duration_s: 2.1 * 3600.0, ..UrbanDrive::default() }.generate().expect("drive");
    let se3_traj = drive.se3_trajectory().expect("unit quaternions");
    let se3 = Se3 { rotation_weight_m_per_rad: 10.0, rotation: RotationDistance::Geodesic };
    group.bench_function("urban_2.1h_euclidean_threads1", |b| {
        b.iter(|| {
            with_threads(Some(1), || find_loops(&drive.trajectory, &Euclidean, 40.0).map(|l| l.components().len()))
        })
    });
    group.bench_function("urban_2.1h_se3_10m_per_rad_threads1", |b| {
        b.iter(|| with_threads(Some(1), || find_loops(&se3_traj, &se3, 40.0).map(|l| l.components().len())))
    });
    group.finish();
}

criterion_group!(benches, bench_find_loops);
criterion_main!(benches);

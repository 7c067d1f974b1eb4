//! Saved results (the `serde` feature): every trajectory and result reads back equal, and a
//! saved form whose parts do not fit together is an error naming what is wrong, never a result
//! that panics later.

use loops_core::{
    Detections, Euclidean, Loops, SampleQuality, SampleSize, Sampler, SamplerKind, Samples, Trajectory, UrbanDrive,
    cluster_detections, find_loops, plane::PlaneGrid, sample_clusters, sample_loops, sample_quality,
};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Value, json};

fn round_trip<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(value: &T) {
    let text = serde_json::to_string(value).unwrap();
    let back: T = serde_json::from_str(&text).unwrap();
    assert_eq!(&back, value);
}

/// `value` saved, changed by `forge`, and read back: the error's message.
fn forged<T: Serialize + DeserializeOwned>(value: &T, forge: impl FnOnce(&mut Value)) -> String {
    let mut saved = serde_json::to_value(value).unwrap();
    forge(&mut saved);
    match serde_json::from_value::<T>(saved) {
        Ok(_) => panic!("a forged state was accepted"),
        Err(error) => error.to_string(),
    }
}

struct Drive {
    traj: Trajectory,
    loops: Loops,
}

fn drive() -> Drive {
    let drive = UrbanDrive { duration_s: 600.0, seed: 4, ..UrbanDrive::default() }.generate().unwrap();
    let loops = find_loops(&drive.trajectory, &Euclidean, 40.0).unwrap();
    Drive { traj: drive.trajectory, loops }
}

#[test]
fn every_result_reads_back_equal() {
    let Drive { traj, loops } = drive();
    round_trip(&traj);
    round_trip(&loops);
    let revisits = loops_core::find_loops_separated(&traj, &Euclidean, 40.0, loops_core::Separation::for_gamma(40.0));
    round_trip(&revisits.unwrap());
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let se3 =
        Trajectory::se3(vec![0.0, 1.0], &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], &[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, s, s]]);
    round_trip(&se3.unwrap());
    let detections = Detections::draw(&loops, SampleSize::Budget(500), 1).unwrap();
    round_trip(&detections);
    let scored = Detections::new(vec![0.0, 5.0], vec![9.0, 1.0]).unwrap().with_scores(vec![0.5, 0.25]).unwrap();
    round_trip(&scored);
    let clusters = cluster_detections(&detections, 20.0).unwrap();
    round_trip(&clusters);
    let from_clusters = sample_clusters(&clusters, &Sampler::new(SamplerKind::Rho, SampleSize::Budget(40), 0));
    round_trip(&from_clusters.unwrap());
    let samples = sample_loops(&traj, &Euclidean, &loops, &Sampler::new(SamplerKind::Rho, SampleSize::Budget(50), 0));
    let samples = samples.unwrap();
    round_trip(&samples);
    let quality: SampleQuality = sample_quality(&samples, &loops, 30.0).unwrap();
    round_trip(&quality);
    round_trip(&PlaneGrid::new(&traj, None, 64).unwrap());
    // A fleet: the joint trajectory's time cells end at every session, and its S_gamma breaks.
    let later = UrbanDrive { duration_s: 300.0, seed: 5, ..UrbanDrive::default() }.generate().unwrap();
    let fleet = loops_core::fleet::Fleet::new(vec![("a".into(), traj), ("b".into(), later.trajectory)]).unwrap();
    let fleet_loops =
        loops_core::fleet::find_fleet_loops(&fleet, &Euclidean, 40.0, &loops_core::fleet::FleetOptions::default())
            .unwrap();
    round_trip(fleet.joint());
    round_trip(fleet_loops.loops());
}

#[test]
fn a_forged_trajectory_is_refused_as_its_constructor_would() {
    let Drive { traj, .. } = drive();
    let message = forged(&traj, |v| v["timestamps_s"][3] = json!(-1.0));
    assert!(message.starts_with("timestamps must strictly increase: index 3"), "{message}");
    let message = forged(&traj, |v| v["dim"] = json!(7));
    assert!(message.contains("coordinates do not split into points of dimension 7"), "{message}");
    let se3 = Trajectory::se3(vec![0.0, 1.0], &[[0.0; 3]; 2], &[[0.0, 0.0, 0.0, 1.0]; 2]).unwrap();
    let message = forged(&se3, |v| v["coords"][13] = json!(2.0));
    assert!(message.starts_with("quaternion of pose 1 has norm"), "{message}");
}

#[test]
fn forged_loops_are_refused_naming_the_part() {
    let Drive { loops, .. } = drive();
    let components = loops.components().len();
    let message = forged(&loops, |v| v["labels"][3] = json!(components));
    assert_eq!(message, format!("invalid saved Loops: run 3 belongs to component {components}, of {components}"));
    let message = forged(&loops, |v| v["labels"].as_array_mut().unwrap().pop().map(drop).unwrap());
    assert!(message.starts_with("invalid saved Loops: "), "{message}");
    let message = forged(&loops, |v| v["components"][1]["closest_pair"] = json!([0, 1_000_000]));
    assert!(message.starts_with("invalid saved Loops: component 1 has id 1"), "{message}");
    let message = forged(&loops, |v| v["set"]["runs"][5]["end"] = json!(u32::MAX));
    assert!(message.starts_with("invalid saved SublevelSet: run "), "{message}");
    let message = forged(&loops, |v| v["set"]["row_offsets"][10] = json!(0));
    assert!(message.starts_with("invalid saved SublevelSet: the runs of row 9 are "), "{message}");
    let message = forged(&loops, |v| v["set"]["gamma"] = json!(-1.0));
    assert_eq!(message, "gamma must be a positive finite distance, got -1");
    let message = forged(&loops, |v| v["gamma"] = json!(41.0));
    assert!(message.contains("differ from its S_gamma's"), "{message}");
    let message = forged(&loops, |v| v["timestamps_s"].as_array_mut().unwrap().push(json!(1e9)));
    assert!(message.starts_with("invalid saved Loops: "), "{message}");
}

#[test]
fn forged_detections_clusters_samples_and_grids_are_refused() {
    let Drive { traj, loops } = drive();
    let detections = Detections::draw(&loops, SampleSize::Budget(100), 1).unwrap();
    let message = forged(&detections, |v| v["located"]["pairs"][7] = json!([5, 1_000_000]));
    assert!(message.starts_with("invalid saved Detections: 100 pairs for 100 detections"), "{message}");
    let message = forged(&detections, |v| v["t_prime_s"].as_array_mut().unwrap().pop().map(drop).unwrap());
    assert!(message.starts_with("t_prime_s has 99 values, but 100 are needed"), "{message}");
    let clusters = cluster_detections(&detections, 20.0).unwrap();
    let count = clusters.len();
    let message = forged(&clusters, |v| v["labels"][0] = json!(count));
    assert_eq!(message, format!("invalid saved DetectionClusters: detection 0 is in cluster {count}, of {count}"));
    let message = forged(&clusters, |v| v["epsilon_s"] = json!(0.0));
    assert!(message.starts_with("epsilon_s = 0 is invalid"), "{message}");
    let samples: Samples =
        sample_loops(&traj, &Euclidean, &loops, &Sampler::new(SamplerKind::Rho, SampleSize::Budget(20), 0)).unwrap();
    let message = forged(&samples, |v| v["rows"][2]["pair"] = json!([3, traj.len()]));
    assert!(message.starts_with("invalid saved Samples: sample 2 has the pair"), "{message}");
    let message = forged(&samples, |v| v["poses"] = json!(null));
    assert!(message.starts_with("invalid saved Samples: sample 0"), "{message}");
    let grid = PlaneGrid::new(&traj, None, 16).unwrap();
    let message = forged(&grid, |v| v["columns"][0] = json!(traj.len()));
    assert!(message.starts_with("invalid saved PlaneGrid: 16 columns with 17 edges"), "{message}");
    // A state that is not one at all.
    assert!(serde_json::from_str::<Loops>("{\"gamma\": 1}").is_err());
    assert!(matches!(
        serde_json::from_value::<Loops>(json!(null)).map_err(|e| e.to_string()),
        Err(message) if !message.is_empty()
    ));
}

#[test]
fn forged_time_cells_metric_names_and_separations_are_refused() {
    let loops = drive().loops;
    let wide = forged(&loops, |v| v["cell_widths_s"][3] = json!(1e308));
    assert!(wide.contains("the time cell of pose 3 is 1e308 s"), "{wide}");
    let named = forged(&loops, |v| v["metric"] = json!("x"));
    assert!(named.contains("its metric \"x\" is neither"), "{named}");
    let mut custom = serde_json::to_value(&loops).unwrap();
    custom["metric"] = json!("custom(mine)");
    assert_eq!(serde_json::from_value::<Loops>(custom).unwrap().metric_name(), "custom(mine)");
    let separation = forged(&loops_core::Separation::path(3.0), |v| v["path"] = json!(-1.0));
    assert!(separation.contains("path separation"), "{separation}");
}

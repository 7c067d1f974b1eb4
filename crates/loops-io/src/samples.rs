//! Candidate pairs out: the samples a sampler chose ([`loops_core::Samples`]), as CSV or JSON
//! for a SLAM back end, with timestamps, pose indices, component, distance and sampler.

use std::fmt;
use std::io::{self, Write};
use std::path::Path;
use std::str::FromStr;

use loops_core::{Sample, Samples};

use crate::atomic::write_atomically;
use crate::csv_rows::write_csv;
use crate::error::WriteError;
use crate::json::write_json;

/// A file format for samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SamplesFormat {
    /// One header line, then one line a sample: see [`samples_to_csv`].
    Csv,
    /// One object with the sampler's facts and a list of samples: see [`samples_to_json`].
    Json,
}

impl SamplesFormat {
    /// The accepted names.
    pub const NAMES: &'static str = "csv, json";

    /// The format's name: `csv`, `json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Json => "json",
        }
    }
}

impl fmt::Display for SamplesFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SamplesFormat {
    type Err = loops_core::Error;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        match name.to_ascii_lowercase().as_str() {
            "csv" => Ok(Self::Csv),
            "json" => Ok(Self::Json),
            _ => Err(loops_core::Error::UnknownName {
                kind: "samples format",
                name: name.to_owned(),
                expected: Self::NAMES,
            }),
        }
    }
}

/// The CSV header: times in seconds, pose indices, the exact loop component, the detection
/// cluster and detection index (samples drawn from detections), δ(x_i, x_j) in the metric's
/// unit, the detection's score, the sampler's name, and the relative pose the trajectory
/// predicts from pose i to pose j ([`loops_core::relative_pose`]: the scan matcher's initial
/// guess): `dx dy dz` (in the frame of pose i for SE(2) and SE(3); the coordinate difference
/// for positions alone), `dqx dqy dqz dqw` (SE(2) and SE(3)) and `dtheta_rad` (SE(2)), then where
/// the two poses are: `i_x i_y i_z j_x j_y j_z` ([`Samples::set_positions`](loops_core::Samples::set_positions),
/// the positions of `loop_duration.csv`). No uncertainty column: trajectories hold no covariance.
pub const CSV_HEADER: &str = "t_s,t_prime_s,i,j,component,cluster,detection,distance,score,sampler,dx,dy,dz,dqx,dqy,\
    dqz,dqw,dtheta_rad,i_x,i_y,i_z,j_x,j_y,j_z";

/// Writes `samples` as CSV: [`CSV_HEADER`], then one line a sample in the samples' order
/// ((t, t′) order). Unknown values (no pose pair, no component, no score, ...) are empty fields;
/// numbers are printed so that they read back to the same `f64`. O(samples).
///
/// # Errors
/// What `out` returns.
///
/// # Examples
/// ```
/// use loops_core::{Detections, SampleSize, Sampler, SamplerKind, cluster_detections, sample_clusters};
/// let det = Detections::new(vec![0.0, 500.0], vec![100.0, 900.0])?;
/// let clusters = cluster_detections(&det, 30.0)?;
/// let samples = sample_clusters(&clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(2), 0))?;
/// let mut text = Vec::new();
/// loops_io::samples_to_csv(&samples, &mut text).unwrap();
/// let text = String::from_utf8(text).unwrap();
/// assert_eq!(text.lines().nth(1), Some("0,100,,,,0,0,,,one,,,,,,,,,,,,,,"));
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn samples_to_csv<W: Write>(samples: &Samples, out: W) -> io::Result<()> {
    write_csv(out, &SAMPLE_COLUMNS, samples.rows().iter().map(SampleRow::from))
}

/// One row of a samples file ([`CSV_HEADER`]; one object of the JSON `samples` list): a
/// [`Sample`] with its pose pair split into `i` and `j`. `None` is unknown: an empty CSV field,
/// `null` in JSON.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct SampleRow {
    /// Time of the earlier pose, seconds.
    pub t_s: f64,
    /// Time of the later pose, seconds.
    pub t_prime_s: f64,
    /// Index of the earlier pose, when the sample is a pose pair.
    pub i: Option<usize>,
    /// Index of the later pose, when the sample is a pose pair.
    pub j: Option<usize>,
    /// The exact loop component of the pair, when known.
    pub component: Option<usize>,
    /// The detection cluster, for samples drawn from detections.
    pub cluster: Option<usize>,
    /// The detection's index, for samples drawn from detections.
    pub detection: Option<usize>,
    /// δ(x_i, x_j), in the metric's unit, when known.
    pub distance: Option<f64>,
    /// The detection's score, when it has one.
    pub score: Option<f64>,
    /// The sampler's name.
    pub sampler: &'static str,
    /// The translation of the relative pose from pose i to pose j, when there is one.
    pub dx: Option<f64>,
    /// See [`dx`](Self::dx).
    pub dy: Option<f64>,
    /// See [`dx`](Self::dx).
    pub dz: Option<f64>,
    /// The rotation of the relative pose, `[dqx, dqy, dqz, dqw]`, for SE(2) and SE(3).
    pub dqx: Option<f64>,
    /// See [`dqx`](Self::dqx).
    pub dqy: Option<f64>,
    /// See [`dqx`](Self::dqx).
    pub dqz: Option<f64>,
    /// See [`dqx`](Self::dqx).
    pub dqw: Option<f64>,
    /// The heading change of the relative pose, radians in (−π, π], for SE(2).
    pub dtheta_rad: Option<f64>,
    /// x of pose i, when its position is known.
    pub i_x: Option<f64>,
    /// y of pose i.
    pub i_y: Option<f64>,
    /// z of pose i.
    pub i_z: Option<f64>,
    /// x of pose j.
    pub j_x: Option<f64>,
    /// y of pose j.
    pub j_y: Option<f64>,
    /// z of pose j.
    pub j_z: Option<f64>,
}

/// The columns of a sample's positions, the last of [`CSV_HEADER`]: x, y and z of pose i, then of
/// pose j.
pub const SAMPLE_POSITION_COLUMNS: [&str; 6] = ["i_x", "i_y", "i_z", "j_x", "j_y", "j_z"];

/// The columns of [`SampleRow`], as the CSV header names them.
const SAMPLE_COLUMNS: [&str; 24] = crate::components::columns(&[
    &[
        "t_s",
        "t_prime_s",
        "i",
        "j",
        "component",
        "cluster",
        "detection",
        "distance",
        "score",
        "sampler",
        "dx",
        "dy",
        "dz",
        "dqx",
        "dqy",
        "dqz",
        "dqw",
        "dtheta_rad",
    ],
    &SAMPLE_POSITION_COLUMNS,
]);

impl From<&Sample> for SampleRow {
    fn from(row: &Sample) -> Self {
        let guess = row.relative_pose;
        let rotation = guess.and_then(|g| g.rotation_xyzw);
        let at = |pose: usize, axis: usize| row.positions.map(|p| p[pose][axis]);
        Self {
            t_s: row.t_s,
            t_prime_s: row.t_prime_s,
            i: row.pair.map(|p| p[0]),
            j: row.pair.map(|p| p[1]),
            component: row.component,
            cluster: row.cluster,
            detection: row.detection,
            distance: row.distance,
            score: row.score,
            sampler: row.sampler.name(),
            dx: guess.map(|g| g.translation[0]),
            dy: guess.map(|g| g.translation[1]),
            dz: guess.map(|g| g.translation[2]),
            dqx: rotation.map(|q| q[0]),
            dqy: rotation.map(|q| q[1]),
            dqz: rotation.map(|q| q[2]),
            dqw: rotation.map(|q| q[3]),
            dtheta_rad: guess.and_then(|g| g.rotation_rad),
            i_x: at(0, 0),
            i_y: at(0, 1),
            i_z: at(0, 2),
            j_x: at(1, 0),
            j_y: at(1, 1),
            j_z: at(1, 2),
        }
    }
}

/// The whole file in JSON.
#[derive(serde::Serialize)]
struct JsonSamples {
    sampler: &'static str,
    count: usize,
    groups: usize,
    available: u64,
    poses: Option<usize>,
    warnings: Vec<String>,
    samples: Vec<SampleRow>,
}

/// Writes `samples` as one JSON object: `sampler` (its name), `count`, `groups` (clusters or
/// components sampled from), `available` (candidates chosen from), `poses` (of the trajectory
/// the pairs index, or `null`), `warnings` (sentences) and `samples`, a list of objects with the
/// columns of [`CSV_HEADER`] (`null` for unknown values). O(samples).
///
/// # Errors
/// What `out` returns.
pub fn samples_to_json<W: Write>(samples: &Samples, out: W) -> io::Result<()> {
    let document = JsonSamples {
        sampler: samples.sampler().name(),
        count: samples.len(),
        groups: samples.groups(),
        available: samples.available(),
        poses: samples.poses(),
        warnings: samples.warnings().iter().map(ToString::to_string).collect(),
        samples: samples.rows().iter().map(SampleRow::from).collect(),
    };
    write_json(&document, out)
}

/// Writes `samples` to the file `path` in `format`, atomically ([`write_atomically`]): into a
/// temporary file in the same directory, then renamed into place, so that a reader never sees
/// half a file. Without `overwrite`, an existing file is left alone (checked first, and again
/// without a race when the file is moved into place).
///
/// # Errors
/// [`WriteError::Exists`] when the file exists and `overwrite` is false;
/// [`WriteError::Write`] when the directory is missing, not writable, or the disk is full.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_core::{Detections, SampleSize, Sampler, SamplerKind, cluster_detections, sample_clusters};
/// use loops_io::{SamplesFormat, WriteError, write_samples};
/// let det = Detections::new(vec![0.0, 500.0], vec![100.0, 900.0])?;
/// let samples = sample_clusters(&cluster_detections(&det, 30.0)?, &Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0))?;
/// let path = std::env::temp_dir().join(format!("loops-io-samples-{}.json", std::process::id()));
/// write_samples(&path, &samples, SamplesFormat::Json, true)?;
/// assert!(matches!(write_samples(&path, &samples, SamplesFormat::Json, false), Err(WriteError::Exists { .. })));
/// let text = std::fs::read_to_string(&path)?;
/// assert!(text.contains("\"count\": 2"));
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn write_samples(path: &Path, samples: &Samples, format: SamplesFormat, overwrite: bool) -> Result<(), WriteError> {
    write_atomically(path, overwrite, |out| match format {
        SamplesFormat::Csv => samples_to_csv(samples, out),
        SamplesFormat::Json => samples_to_json(samples, out),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::json::ClosedPipe;
    use std::fs;

    use loops_core::{
        Detections, Euclidean, SampleSize, Sampler, SamplerKind, Trajectory, cluster_detections, find_loops,
        sample_clusters, sample_loops,
    };

    fn samples() -> Samples {
        let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &[[0.0], [1.0], [1.0], [0.0]]).unwrap();
        let loops = find_loops(&traj, &Euclidean, 0.5).unwrap();
        sample_loops(&traj, &Euclidean, &loops, &Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0)).unwrap()
    }

    #[test]
    fn the_header_names_the_row_fields() {
        assert_eq!(CSV_HEADER, SAMPLE_COLUMNS.join(","));
        let row = SampleRow::from(&samples().rows()[0]);
        assert_eq!(crate::csv_rows::inferred_columns(&row), SAMPLE_COLUMNS);
    }

    #[test]
    fn csv_has_every_column() {
        let mut text = Vec::new();
        samples_to_csv(&samples(), &mut text).unwrap();
        let text = String::from_utf8(text).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], CSV_HEADER);
        assert_eq!(lines[1..], ["0,3,0,3,1,,,0,,alpha,0,0,0,,,,,,,,,,,", "1,2,1,2,2,,,0,,alpha,0,0,0,,,,,,,,,,,"]);
        // With the positions of the poses (x = the 1-D point, y = 10 + index).
        let mut placed = samples();
        let xs = [0.0, 1.0, 1.0, 0.0];
        placed.set_positions(|k| Some([xs[k], 10.0 + k as f64, 0.0]));
        let mut text = Vec::new();
        samples_to_csv(&placed, &mut text).unwrap();
        let text = String::from_utf8(text).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[1..],
            ["0,3,0,3,1,,,0,,alpha,0,0,0,,,,,,0,10,0,0,13,0", "1,2,1,2,2,,,0,,alpha,0,0,0,,,,,,1,11,0,1,12,0"]
        );
    }

    #[test]
    fn json_round_trips_numbers() {
        let det =
            Detections::new(vec![0.1, 1.0 / 3.0], vec![2.0, 7.0]).unwrap().with_scores(vec![0.25, 1e-300]).unwrap();
        let samples = sample_clusters(
            &cluster_detections(&det, 1.0).unwrap(),
            &Sampler::new(SamplerKind::Alpha, SampleSize::Budget(5), 0),
        )
        .unwrap();
        let mut text = Vec::new();
        samples_to_json(&samples, &mut text).unwrap();
        let value: serde_json::Value = serde_json::from_slice(&text).unwrap();
        assert_eq!(value["count"], 2);
        assert_eq!(value["poses"], serde_json::Value::Null);
        assert_eq!(value["warnings"][0], "budget 5 is more than the 2 candidates: all of them were returned");
        assert_eq!(value["samples"][1]["t_s"].as_f64(), Some(1.0 / 3.0));
        assert_eq!(value["samples"][1]["score"].as_f64(), Some(1e-300));
        assert_eq!(value["samples"][1]["i"], serde_json::Value::Null);
        assert_eq!(value["samples"][0]["sampler"], "alpha");
    }

    #[test]
    fn files_are_not_overwritten_unless_asked() {
        let dir = std::env::temp_dir().join(format!("loops-io-samples-test-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("samples.csv");
        let _ = fs::remove_file(&path);
        write_samples(&path, &samples(), SamplesFormat::Csv, false).unwrap();
        let first = fs::read_to_string(&path).unwrap();
        fs::write(&path, "keep me").unwrap();
        let err = write_samples(&path, &samples(), SamplesFormat::Csv, false).unwrap_err();
        assert!(matches!(err, WriteError::Exists { .. }));
        assert!(err.to_string().ends_with("samples.csv: the file exists; refusing to overwrite it"));
        assert_eq!(fs::read_to_string(&path).unwrap(), "keep me");
        write_samples(&path, &samples(), SamplesFormat::Csv, true).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), first);
        let err = write_samples(&dir.join("missing/samples.csv"), &samples(), SamplesFormat::Csv, false).unwrap_err();
        assert!(matches!(err, WriteError::Write { .. }));
        // No temporary file is left behind.
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
        assert_eq!("JSON".parse::<SamplesFormat>().unwrap(), SamplesFormat::Json);
        assert!("xml".parse::<SamplesFormat>().is_err());
    }

    #[test]
    fn a_closed_pipe_is_reported_as_one() {
        // A robot standing still: every pair is a loop, more samples than the buffer holds.
        let n = 60;
        let traj = Trajectory::from_points((0..n).map(f64::from).collect(), &vec![[0.0]; n as usize]).unwrap();
        let loops = find_loops(&traj, &Euclidean, 0.5).unwrap();
        let all = Sampler::new(SamplerKind::Alpha, SampleSize::Rate(1.0), 0);
        let samples = sample_loops(&traj, &Euclidean, &loops, &all).unwrap();
        assert_eq!(samples.len(), 60 * 59 / 2);
        let error = samples_to_json(&samples, ClosedPipe).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::BrokenPipe);
    }
}

//! Seeded synthetic trajectories: the "urban drive", for demos, tests and benchmarks.

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::memory::try_with_capacity;
use crate::trajectory::{MAX_POSES, Trajectory};

/// A vehicle on a Manhattan grid: random turns at intersections, a speed drawn per block, stops
/// at some intersections, driving in the right-hand lane with a little lateral noise, z nearly
/// flat. The defaults are the paper's experiment: a 1 km² city of 100 m blocks, 10 Hz for 2.1 h
/// (75,600 poses); the stop probability (0.08) is set so that, at γ = 40 m, the default drive has
/// about as many loop components (481) as the paper reports for its drive (490).
///
/// # Examples
/// ```
/// use loops_core::UrbanDrive;
/// let drive = UrbanDrive { duration_s: 60.0, ..UrbanDrive::default() }.generate()?;
/// assert_eq!(drive.trajectory.len(), 600);
/// assert_eq!(drive.trajectory.dim(), 3);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct UrbanDrive {
    /// Length of the drive, seconds.
    pub duration_s: f64,
    /// Pose rate, Hz.
    pub rate_hz: f64,
    /// Side of the square city, metres.
    pub city_size_m: f64,
    /// Side of a block, metres.
    pub block_m: f64,
    /// Slowest cruising speed, m/s.
    pub min_speed_mps: f64,
    /// Fastest cruising speed, m/s.
    pub max_speed_mps: f64,
    /// Probability of stopping at an intersection.
    pub stop_probability: f64,
    /// Shortest stop, seconds (stop lengths are log-uniform between the two bounds).
    pub min_stop_s: f64,
    /// Longest stop, seconds.
    pub max_stop_s: f64,
    /// Distance of the lane from the street's centre line (right-hand traffic), metres.
    pub lane_offset_m: f64,
    /// Standard deviation of the slowly varying lateral offset, metres.
    pub lateral_noise_m: f64,
    /// Seed of the random choices: the same seed gives the same drive on every machine.
    pub seed: u64,
    /// Work the city one district at a time instead of roaming all of it: `None` (the default)
    /// is a random walk over the whole city.
    pub districts: Option<Districts>,
    /// With districts, the district worked first, counted in their snake order (wrapping
    /// around): vehicles of a fleet that start at different districts work different parts of
    /// the city at any time. 0 by default.
    pub first_district: usize,
}

/// A drive that works one square district at a time, like a delivery or mapping vehicle: it
/// roams a district for `dwell_s`, then drives to the next one, in snake order (row by row,
/// alternating direction, back to the first after the last). The revisits of a place are then
/// bounded by the time spent in its district, however long the drive: the answer (runs and
/// loop components of S_γ) grows in proportion to the number of poses. A random walk over a
/// whole city of fixed size instead comes back to every street more often the longer it drives.
///
/// # Examples
/// ```
/// use loops_core::{Districts, UrbanDrive};
/// let spec = UrbanDrive {
///     duration_s: 1200.0,
///     city_size_m: 10_000.0,
///     districts: Some(Districts { side_m: 1000.0, dwell_s: 600.0 }),
///     ..UrbanDrive::default()
/// };
/// let drive = spec.generate()?;
/// // The first 10 minutes stay in the first district (plus the lane offset).
/// assert!(drive.trajectory.coords().chunks(3).take(6000).all(|p| p[0] < 1005.0 && p[1] < 1005.0));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Districts {
    /// Side of a district, metres: a whole number of blocks (rounded to the nearest, at least
    /// one), at most the city.
    pub side_m: f64,
    /// Time spent in each district, seconds.
    pub dwell_s: f64,
}

impl Districts {
    /// A default time in each district: 10,000 s (2.8 h, 10⁵ poses at 10 Hz).
    pub const DEFAULT_DWELL_S: f64 = 10_000.0;

    /// The districts from the options of a front end: a side (metres) and, optionally, a time
    /// in each (seconds, default [`DEFAULT_DWELL_S`](Self::DEFAULT_DWELL_S)); no side, no
    /// districts. The values themselves are checked by [`UrbanDrive::generate`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`district_dwell_s`) for a time without a side.
    ///
    /// # Examples
    /// ```
    /// use loops_core::Districts;
    /// assert_eq!(Districts::from_options(None, None)?, None);
    /// let d = Districts::from_options(Some(1000.0), None)?.unwrap();
    /// assert_eq!((d.side_m, d.dwell_s), (1000.0, Districts::DEFAULT_DWELL_S));
    /// assert!(Districts::from_options(None, Some(600.0)).is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn from_options(side_m: Option<f64>, dwell_s: Option<f64>) -> Result<Option<Self>> {
        match (side_m, dwell_s) {
            (Some(side_m), dwell_s) => Ok(Some(Self { side_m, dwell_s: dwell_s.unwrap_or(Self::DEFAULT_DWELL_S) })),
            (None, Some(value)) => Err(Error::InvalidParameter {
                name: "district_dwell_s",
                value,
                expected: "to come with district_m (the side of the districts)",
            }),
            (None, None) => Ok(None),
        }
    }

    /// The nodes (inclusive ranges along x and y) of the district the drive works at time
    /// `t_s`, in a city of `blocks` blocks a side.
    #[cfg(test)]
    fn area(&self, t_s: f64, blocks: i64, block_m: f64) -> [[i64; 2]; 2] {
        self.area_from(0, t_s, blocks, block_m)
    }

    /// [`area`](Self::area) of a drive that starts at the district `first` (snake order).
    fn area_from(&self, first: usize, t_s: f64, blocks: i64, block_m: f64) -> [[i64; 2]; 2] {
        let side = ((self.side_m / block_m).round() as i64).clamp(1, blocks.max(1));
        let per_row = (blocks + side - 1) / side;
        let count = per_row * per_row;
        let index = ((t_s / self.dwell_s).floor() as i64 + (first as i64).rem_euclid(count)).rem_euclid(count);
        let (row, mut col) = (index / per_row, index % per_row);
        if row % 2 == 1 {
            col = per_row - 1 - col;
        }
        let (x, y) = (col * side, row * side);
        [[x, (x + side).min(blocks)], [y, (y + side).min(blocks)]]
    }
}

impl Default for UrbanDrive {
    fn default() -> Self {
        Self {
            duration_s: 2.1 * 3600.0,
            rate_hz: 10.0,
            city_size_m: 1000.0,
            block_m: 100.0,
            min_speed_mps: 5.0,
            max_speed_mps: 12.0,
            stop_probability: 0.08,
            min_stop_s: 5.0,
            max_stop_s: 240.0,
            lane_offset_m: 2.0,
            lateral_noise_m: 0.1,
            seed: 0,
            districts: None,
            first_district: 0,
        }
    }
}

/// A fleet of vehicles in one city, over one or more days: every session an [`UrbanDrive`] of
/// the template `drive` (its city, duration, rate and districts) with its own seed, start time
/// and, with districts, its own first district, so that vehicles meet only where their paths
/// cross. Sessions are named `car{v}-day{d}` (numbers zero-padded to the same width), in order
/// of day, then vehicle; their clocks are seconds since the first day's midnight.
///
/// # Examples
/// ```
/// use loops_core::{UrbanDrive, UrbanFleet};
/// let spec = UrbanFleet {
///     vehicles: 3,
///     days: 2,
///     drive: UrbanDrive { duration_s: 120.0, seed: 7, ..UrbanDrive::default() },
///     ..UrbanFleet::default()
/// };
/// let fleet = spec.generate()?;
/// assert_eq!(fleet.len(), 6);
/// assert_eq!(fleet.names()[4], "car1-day1");
/// assert!(fleet.session(4).timestamps_s()[0] >= 86_400.0);
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct UrbanFleet {
    /// Vehicles, at least one.
    pub vehicles: usize,
    /// Days, at least one: each vehicle drives once a day.
    pub days: usize,
    /// Each session's drive; its `seed` is the fleet's seed, from which every session's own
    /// seed, start and first district are drawn.
    pub drive: UrbanDrive,
    /// Sessions start at a time drawn uniformly within this many seconds of midnight.
    pub start_spread_s: f64,
}

/// Sessions generated in parallel before they are moved into the fleet.
const SESSIONS_PER_BATCH: usize = 1024;

impl Default for UrbanFleet {
    /// 10 vehicles, one day, 10-minute drives in the default 1 km² city, starts spread over an
    /// hour.
    fn default() -> Self {
        Self {
            vehicles: 10,
            days: 1,
            drive: UrbanDrive { duration_s: 600.0, ..UrbanDrive::default() },
            start_spread_s: 3600.0,
        }
    }
}

impl UrbanFleet {
    /// Generates the sessions (in parallel; the same seed gives the same fleet on any number
    /// of threads).
    ///
    /// # Errors
    /// As [`drives`](Self::drives); [`Fleet::new`](crate::fleet::Fleet::new)'s, checked before any
    /// session is generated: [`Error::TooManyPoses`] for more poses in all than one trajectory
    /// may hold, [`Error::OutOfMemory`] when the joint trajectory does not fit in memory.
    pub fn generate(&self) -> Result<crate::fleet::Fleet> {
        let sessions = self.session_count()?;
        self.drive.validate()?;
        let poses = self.drive.pose_count()?.saturating_mul(sessions);
        if poses > MAX_POSES {
            return Err(Error::TooManyPoses { count: poses, max: MAX_POSES });
        }
        // The joint trajectory's room (timestamps, three coordinates, time cells), taken first so
        // that a fleet too big for memory is refused at once, naming its size, instead of after
        // its sessions were generated; given back just before the joint trajectory takes it.
        let room: Vec<f64> = try_with_capacity(poses * 5, "the joint trajectory of a fleet")?;
        let drives = self.drives()?;
        drop(room);
        let mut named = try_with_capacity(drives.len(), "the sessions of a fleet")?;
        named.extend(drives.into_iter().map(|(name, drive)| (name, drive.trajectory)));
        crate::fleet::Fleet::new(named)
    }

    /// vehicles × days.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for no vehicles or days, or more sessions than 2³².
    fn session_count(&self) -> Result<usize> {
        for (name, value) in [("vehicles", self.vehicles), ("days", self.days)] {
            if value == 0 {
                return Err(Error::InvalidParameter { name, value: 0.0, expected: "at least 1" });
            }
        }
        self.vehicles.checked_mul(self.days).filter(|&n| n <= u32::MAX as usize).ok_or(Error::InvalidParameter {
            name: "vehicles * days",
            value: self.vehicles as f64 * self.days as f64,
            expected: "at most 2³² sessions",
        })
    }

    /// Each session's name and drive, in fleet order, its trajectory on the session's clock
    /// (seconds since the first day's midnight) and with its headings: the sessions of
    /// [`generate`](Self::generate), for writing them as pose logs with orientations.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for no vehicles or days, a negative or non-finite spread, or
    /// more sessions than 2³²; the drive's own errors; [`Error::OutOfMemory`] when the sessions
    /// do not fit in memory.
    pub fn drives(&self) -> Result<Vec<(String, SyntheticDrive)>> {
        use rayon::prelude::*;
        let sessions = self.session_count()?;
        if !(self.start_spread_s >= 0.0 && self.start_spread_s.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "start_spread_s",
                value: self.start_spread_s,
                expected: "a finite number of seconds, at least 0",
            });
        }
        self.drive.validate()?;
        let width = |n: usize| (n - 1).max(1).ilog10() as usize + 1;
        let (vw, dw) = (width(self.vehicles), width(self.days));
        let session = |k: usize| -> Result<(String, SyntheticDrive)> {
            let (day, vehicle) = (k / self.vehicles, k % self.vehicles);
            // Each session's own stream of the fleet seed.
            let mut rng = ChaCha8Rng::seed_from_u64(self.drive.seed);
            rng.set_stream(1 + k as u64);
            let start = day as f64 * 86_400.0 + rng.random::<f64>() * self.start_spread_s;
            let spec = UrbanDrive { seed: rng.random(), first_district: vehicle, ..self.drive.clone() };
            let SyntheticDrive { trajectory, yaw_rad } = spec.generate()?;
            let dim = trajectory.dim();
            let (mut times, coords) = trajectory.into_parts();
            times.iter_mut().for_each(|t| *t += start);
            let trajectory = Trajectory::new(times, coords, dim)?;
            Ok((format!("car{vehicle:0vw$}-day{day:0dw$}"), SyntheticDrive { trajectory, yaw_rad }))
        };
        // In parallel a batch at a time, into room taken first: memory that runs out is an error
        // of the batch's session, not an abort of a parallel collect.
        let mut drives = try_with_capacity(sessions, "the sessions of a fleet")?;
        for first in (0..sessions).step_by(SESSIONS_PER_BATCH) {
            let batch: Vec<Result<(String, SyntheticDrive)>> =
                (first..(first + SESSIONS_PER_BATCH).min(sessions)).into_par_iter().map(session).collect();
            for drive in batch {
                drives.push(drive?);
            }
        }
        Ok(drives)
    }
}

/// A generated drive: positions (x, y, z metres) and the heading of travel.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticDrive {
    /// Positions in R³, metres, at `rate_hz` from t = 0.
    pub trajectory: Trajectory,
    /// Heading (yaw about +z, from +x), radians, one per pose.
    pub yaw_rad: Vec<f64>,
}

impl SyntheticDrive {
    /// The drive as SE(3) poses (position and the heading as a yaw quaternion), for
    /// [`Se3`](crate::Se3) and friends.
    ///
    /// # Errors
    /// None in practice (the drive is valid); as [`Trajectory::se3`].
    pub fn se3_trajectory(&self) -> Result<Trajectory> {
        let positions: Vec<[f64; 3]> = self.trajectory.coords().as_chunks::<3>().0.to_vec();
        let quaternions: Vec<[f64; 4]> =
            self.yaw_rad.iter().map(|yaw| [0.0, 0.0, (0.5 * yaw).sin(), (0.5 * yaw).cos()]).collect();
        Trajectory::se3(self.trajectory.timestamps_s().to_vec(), &positions, &quaternions)
    }
}

impl UrbanDrive {
    /// The γ of the paper's experiment on this drive, metres: the threshold of the demos (the
    /// default drive then has about the paper's 490 loop components).
    pub const DEFAULT_GAMMA_M: f64 = 40.0;

    /// Generates the drive. Deterministic in the parameters (ChaCha8 seeded by `seed`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-positive duration, rate, block or speed, a city
    /// smaller than one block, speeds or stops out of order, a probability outside [0, 1], or a
    /// drive shorter than two poses or longer than [`MAX_POSES`](crate::MAX_POSES) (checked before
    /// anything is allocated); [`Error::OutOfMemory`] when the drive does not fit in memory.
    pub fn generate(&self) -> Result<SyntheticDrive> {
        self.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let blocks = (self.city_size_m / self.block_m).floor() as i64;
        let poses = self.pose_count()?;
        // The box of nodes the walk keeps to at a time: the whole city, or the current district.
        let area = |t: f64| -> [[i64; 2]; 2] {
            self.districts
                .map_or([[0, blocks], [0, blocks]], |d| d.area_from(self.first_district, t, blocks, self.block_m))
        };
        let start = area(0.0);
        let mut node = [rng.random_range(start[0][0]..=start[0][1]), rng.random_range(start[1][0]..=start[1][1])];
        let mut heading = DIRECTIONS[rng.random_range(0..4)];
        let mut out = Emitter::new(self, poses)?;
        let mut t = 0.0_f64;
        while !out.done() {
            let [xs, ys] = area(t);
            let inside = |p: [i64; 2]| (xs[0]..=xs[1]).contains(&p[0]) && (ys[0]..=ys[1]).contains(&p[1]);
            let options: Vec<[i64; 2]> = if inside(node) {
                DIRECTIONS
                    .iter()
                    .copied()
                    .filter(|d| *d != [-heading[0], -heading[1]])
                    .filter(|d| inside([node[0] + d[0], node[1] + d[1]]))
                    .collect()
            } else {
                // On the way to the next district: any turn that brings the car closer to it.
                let gap =
                    |p: [i64; 2]| (xs[0] - p[0]).max(p[0] - xs[1]).max(0) + (ys[0] - p[1]).max(p[1] - ys[1]).max(0);
                let closer: Vec<[i64; 2]> = DIRECTIONS
                    .iter()
                    .copied()
                    .filter(|d| *d != [-heading[0], -heading[1]])
                    .filter(|d| gap([node[0] + d[0], node[1] + d[1]]) < gap(node))
                    .collect();
                if closer.is_empty() { vec![[-heading[0], -heading[1]]] } else { closer }
            };
            // A corner reached head-on still has two options; an empty list means a 1-block city.
            heading = if options.is_empty() {
                [-heading[0], -heading[1]]
            } else {
                options[rng.random_range(0..options.len())]
            };
            let speed = rng.random_range(self.min_speed_mps..=self.max_speed_mps);
            let start = [node[0] as f64 * self.block_m, node[1] as f64 * self.block_m];
            let leg_s = self.block_m / speed;
            let (t0, dir) = (t, heading);
            out.emit(
                t + leg_s,
                |time| {
                    let along = (time - t0) * speed;
                    ([start[0] + along * dir[0] as f64, start[1] + along * dir[1] as f64], dir)
                },
                &mut rng,
            );
            t += leg_s;
            node = [node[0] + heading[0], node[1] + heading[1]];
            if rng.random_bool(self.stop_probability) {
                // Log-uniform: most stops are short (traffic lights), a few are long.
                let stop_s = if self.min_stop_s > 0.0 {
                    (rng.random_range(self.min_stop_s.ln()..=self.max_stop_s.ln())).exp()
                } else {
                    rng.random_range(self.min_stop_s..=self.max_stop_s)
                };
                let at_node = [node[0] as f64 * self.block_m, node[1] as f64 * self.block_m];
                out.emit(t + stop_s, |_| (at_node, dir), &mut rng);
                t += stop_s;
            }
        }
        let Emitter { timestamps, coords, yaw_rad, .. } = out;
        let trajectory = Trajectory::new(timestamps, coords, 3)?;
        Ok(SyntheticDrive { trajectory, yaw_rad })
    }

    /// The number of poses of the drive, checked before anything is allocated: a huge duration
    /// is an error, not an out-of-memory abort.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for fewer than two poses or more than
    /// [`MAX_POSES`](crate::MAX_POSES).
    fn pose_count(&self) -> Result<usize> {
        let count = (self.duration_s * self.rate_hz).round();
        if count > MAX_POSES as f64 {
            return Err(Error::InvalidParameter {
                name: "duration_s * rate_hz",
                value: count,
                expected: "at most MAX_POSES = 2³² − 2 poses (the engine's limit)",
            });
        }
        if count < 2.0 {
            return Err(Error::InvalidParameter {
                name: "duration_s * rate_hz",
                value: self.duration_s * self.rate_hz,
                expected: "at least 2 poses",
            });
        }
        Ok(count as usize)
    }

    fn validate(&self) -> Result<()> {
        let positive = [
            ("duration_s", self.duration_s),
            ("rate_hz", self.rate_hz),
            ("block_m", self.block_m),
            ("min_speed_mps", self.min_speed_mps),
            ("max_speed_mps", self.max_speed_mps),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidParameter { name, value, expected: "a positive finite number" });
            }
        }
        let non_negative = [
            ("min_stop_s", self.min_stop_s),
            ("max_stop_s", self.max_stop_s),
            ("lane_offset_m", self.lane_offset_m),
            ("lateral_noise_m", self.lateral_noise_m),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::InvalidParameter { name, value, expected: "a finite number ≥ 0" });
            }
        }
        if !(self.city_size_m.is_finite() && self.city_size_m >= self.block_m) {
            return Err(Error::InvalidParameter {
                name: "city_size_m",
                value: self.city_size_m,
                expected: "at least one block (block_m)",
            });
        }
        if self.max_speed_mps < self.min_speed_mps {
            return Err(Error::InvalidParameter {
                name: "max_speed_mps",
                value: self.max_speed_mps,
                expected: "at least min_speed_mps",
            });
        }
        if self.max_stop_s < self.min_stop_s {
            return Err(Error::InvalidParameter {
                name: "max_stop_s",
                value: self.max_stop_s,
                expected: "at least min_stop_s",
            });
        }
        if let Some(districts) = &self.districts {
            if !(districts.side_m.is_finite() && districts.side_m > 0.0 && districts.side_m <= self.city_size_m) {
                return Err(Error::InvalidParameter {
                    name: "districts.side_m",
                    value: districts.side_m,
                    expected: "a positive side no larger than city_size_m",
                });
            }
            if !(districts.dwell_s.is_finite() && districts.dwell_s > 0.0) {
                return Err(Error::InvalidParameter {
                    name: "districts.dwell_s",
                    value: districts.dwell_s,
                    expected: "a positive finite time, seconds",
                });
            }
        }
        if !(0.0..=1.0).contains(&self.stop_probability) {
            return Err(Error::InvalidParameter {
                name: "stop_probability",
                value: self.stop_probability,
                expected: "a probability in [0, 1]",
            });
        }
        Ok(())
    }
}

/// Places poses at the fixed rate along the legs of the drive.
struct Emitter<'a> {
    spec: &'a UrbanDrive,
    poses: usize,
    dt: f64,
    keep: f64,
    kick: f64,
    lateral: f64,
    timestamps: Vec<f64>,
    coords: Vec<f64>,
    yaw_rad: Vec<f64>,
}

impl<'a> Emitter<'a> {
    /// # Errors
    /// [`Error::OutOfMemory`] when the drive does not fit in memory.
    fn new(spec: &'a UrbanDrive, poses: usize) -> Result<Self> {
        let what = "the poses of a synthetic drive";
        let (timestamps, coords, yaw_rad) =
            (try_with_capacity(poses, what)?, try_with_capacity(3 * poses, what)?, try_with_capacity(poses, what)?);
        let dt = 1.0 / spec.rate_hz;
        // Lateral offset: an AR(1) process with a ~10 s correlation time and the given deviation.
        let keep = (-dt / 10.0_f64).exp();
        let kick = spec.lateral_noise_m * (1.0 - keep * keep).sqrt();
        Ok(Self { spec, poses, dt, keep, kick, lateral: 0.0, timestamps, coords, yaw_rad })
    }

    fn done(&self) -> bool {
        self.timestamps.len() >= self.poses
    }

    /// Emits every pose due before `until_s`, on the street centre line `at(time)` with
    /// direction of travel, shifted into the lane.
    fn emit(&mut self, until_s: f64, at: impl Fn(f64) -> ([f64; 2], [i64; 2]), rng: &mut impl Rng) {
        loop {
            let k = self.timestamps.len();
            let time = k as f64 * self.dt;
            if k >= self.poses || time >= until_s {
                return;
            }
            let (centre, dir) = at(time);
            self.lateral = self.keep * self.lateral + self.kick * standard_normal(rng);
            let offset = self.spec.lane_offset_m + self.lateral;
            // Right-hand traffic: the lane is to the right of the direction of travel.
            let (right_x, right_y) = (dir[1] as f64, -(dir[0] as f64));
            self.timestamps.push(time);
            self.coords.push(centre[0] + offset * right_x);
            self.coords.push(centre[1] + offset * right_y);
            self.coords.push(0.3 * (time / 600.0).sin() + 0.02 * standard_normal(rng));
            self.yaw_rad.push((dir[1] as f64).atan2(dir[0] as f64));
        }
    }
}

const DIRECTIONS: [[i64; 2]; 4] = [[1, 0], [0, 1], [-1, 0], [0, -1]];

/// A standard normal deviate (Box–Muller; one of the pair is discarded for simplicity).
fn standard_normal(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drive_beyond_the_pose_limit_is_an_error_before_any_allocation() {
        let error = UrbanDrive { duration_s: 1e12, ..UrbanDrive::default() }.generate().unwrap_err();
        assert!(matches!(error, Error::InvalidParameter { name: "duration_s * rate_hz", .. }), "{error}");
        assert!(error.to_string().contains("MAX_POSES"), "{error}");
    }

    #[test]
    fn same_seed_same_drive_and_bounded() {
        let spec = UrbanDrive { duration_s: 600.0, ..UrbanDrive::default() };
        let a = spec.generate().unwrap();
        assert_eq!(a, spec.generate().unwrap());
        assert_ne!(a, UrbanDrive { seed: 1, ..spec.clone() }.generate().unwrap());
        for p in a.trajectory.coords().chunks(3) {
            assert!(p[0] > -5.0 && p[0] < 1005.0 && p[1] > -5.0 && p[1] < 1005.0, "{p:?}");
        }
        let steps = (1..a.trajectory.len())
            .map(|i| {
                let (p, q) = (a.trajectory.point(i - 1), a.trajectory.point(i));
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max);
        assert!(steps < 6.0, "a 10 Hz step of {steps} m");
    }

    /// The district worked at each time, from the positions: the drive keeps to it except on
    /// the way between two districts, visits them in snake order, and its revisits stay bounded.
    #[test]
    fn districts_are_worked_in_turn() {
        let districts = Districts { side_m: 300.0, dwell_s: 900.0 };
        let spec = UrbanDrive {
            duration_s: 9.0 * 900.0,
            city_size_m: 900.0,
            districts: Some(districts),
            ..UrbanDrive::default()
        };
        let drive = spec.generate().unwrap();
        let blocks = 9;
        let mut outside = 0;
        for (i, p) in drive.trajectory.coords().chunks(3).enumerate() {
            let t = i as f64 / spec.rate_hz;
            let [xs, ys] = districts.area(t, blocks, spec.block_m);
            let within = |v: f64, r: [i64; 2]| v > r[0] as f64 * 100.0 - 5.0 && v < r[1] as f64 * 100.0 + 5.0;
            if !(within(p[0], xs) && within(p[1], ys)) {
                outside += 1;
                // Only just after a change of district (a few blocks of driving).
                assert!(t % 900.0 < 240.0, "pose {i} at t = {t} s is outside {xs:?} × {ys:?}: {p:?}");
            }
        }
        // 8 changes of district, each a few blocks and maybe a stop: under a minute on average.
        assert!(outside < 8 * 600, "{outside} poses in transit");
        // Snake order over the 3 × 3 districts.
        let corners: Vec<[i64; 2]> = (0..9)
            .map(|k| {
                let [xs, ys] = districts.area(k as f64 * 900.0 + 1.0, blocks, spec.block_m);
                [xs[0], ys[0]]
            })
            .collect();
        assert_eq!(corners, [[0, 0], [3, 0], [6, 0], [6, 3], [3, 3], [0, 3], [0, 6], [3, 6], [6, 6]]);
        assert_eq!(districts.area(9.0 * 900.0 + 1.0, blocks, spec.block_m), [[0, 3], [0, 3]], "wraps around");
    }

    #[test]
    fn rejects_bad_parameters() {
        let bad = UrbanDrive { rate_hz: 0.0, ..UrbanDrive::default() };
        assert!(matches!(bad.generate(), Err(Error::InvalidParameter { name: "rate_hz", .. })));
        let bad = UrbanDrive { stop_probability: 2.0, ..UrbanDrive::default() };
        assert!(bad.generate().is_err());
        for (side_m, dwell_s, name) in
            [(0.0, 1.0, "districts.side_m"), (2000.0, 1.0, "districts.side_m"), (100.0, f64::NAN, "districts.dwell_s")]
        {
            let bad = UrbanDrive { districts: Some(Districts { side_m, dwell_s }), ..UrbanDrive::default() };
            assert!(matches!(bad.generate(), Err(Error::InvalidParameter { name: n, .. }) if n == name), "{name}");
        }
        let bad = UrbanDrive { duration_s: 0.1, ..UrbanDrive::default() };
        assert!(bad.generate().is_err());
    }

    #[test]
    fn fleet_vehicles_start_in_their_own_districts_and_reproduce() {
        let spec = UrbanFleet {
            vehicles: 4,
            days: 1,
            drive: UrbanDrive {
                duration_s: 60.0,
                city_size_m: 2000.0,
                districts: Some(Districts { side_m: 1000.0, dwell_s: 600.0 }),
                seed: 3,
                ..UrbanDrive::default()
            },
            start_spread_s: 10.0,
        };
        let fleet = spec.generate().unwrap();
        // Snake order over 2 × 2 districts: (0, 0), (1, 0), (1, 1), (0, 1).
        let corners = [[0.0, 0.0], [1000.0, 0.0], [1000.0, 1000.0], [0.0, 1000.0]];
        for (v, corner) in corners.iter().enumerate() {
            let traj = fleet.session(v);
            let p = traj.point(0);
            assert!((0..2).all(|k| p[k] >= corner[k] - 5.0 && p[k] <= corner[k] + 1005.0), "car {v} at {p:?}");
            assert!((0.0..10.0).contains(&traj.timestamps_s()[0]));
        }
        assert_eq!(fleet.names(), ["car0-day0", "car1-day0", "car2-day0", "car3-day0"]);
        let again = spec.generate().unwrap();
        assert!((0..4).all(|v| again.session(v) == fleet.session(v)), "seeded");
        assert!(UrbanFleet { vehicles: 0, ..spec.clone() }.generate().is_err());
        // The drives are the sessions, with a heading per pose.
        let drives = spec.drives().unwrap();
        assert_eq!(drives.len(), fleet.len());
        for (k, (name, drive)) in drives.iter().enumerate() {
            assert_eq!((name, &drive.trajectory), (&fleet.names()[k], fleet.session(k)));
            assert_eq!(drive.yaw_rad.len(), drive.trajectory.len());
        }
    }
}

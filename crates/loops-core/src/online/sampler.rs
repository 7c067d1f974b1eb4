//! [`OnlineSampler`]: loop-closure candidates per keyframe, σ_ρ with a cap, P1 online and the
//! revisit separation.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::engine::{ComponentId, OnlineLoops, PushStamp, RowRun, Update};
use crate::draw::choose_indices;
use crate::error::{Error, Result};
use crate::metric::Metric;
use crate::sample::SamplerKind;
use crate::separation::Separation;
use crate::spec::with_metric;

/// A cap on a component's candidates: a token bucket per component that holds at most one
/// unit's worth of candidates (at least one) and refills at the given rate, starting full. In
/// any stretch of the drive, a component gets at most `max(1, c) + c · (length of the stretch)`
/// candidates, the length in minutes or in metres (the metric's unit) of travel.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Cap {
    /// No cap.
    #[default]
    None,
    /// At most `c` candidates per minute per component (refilled by time).
    PerMinute(f64),
    /// At most `c` candidates per metre of travel per component (refilled by path length
    /// under the metric, in its unit).
    PerMetre(f64),
}

/// What an [`OnlineSampler`] does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnlineSamplerOptions {
    /// σ_ρ: the expected number of candidates per component per pose (the paper's r), drawn
    /// uniformly from the component's pairs in the new row, rounded randomly (r = 0.3 gives one
    /// candidate at 30% of the poses); 0 keeps only the first-appearance candidates.
    pub rate: f64,
    /// A cap per component.
    pub cap: Cap,
    /// P1 online: a component's first candidate comes in the first row where it has a pair to
    /// offer (at its creation, for a component off the diagonal): the closest such pair.
    pub first_on_appearance: bool,
    /// The first of a row's draws for a component is its closest pair in the row (the likeliest
    /// match), the others uniform; `false`: all uniform (the paper's σ_ρ). The default follows
    /// the default sampler ([`SamplerKind::DEFAULT`]): each row is one time of the component,
    /// so taking its closest pair spreads the candidates in time as the batch sampler does.
    pub closest_in_row: bool,
    /// Only pairs this far apart along the trajectory ([`Separation::NONE`]: every pair j < n).
    pub separation: Separation,
    /// The seed: every random choice is keyed by (seed, pose, component), so that pushing one
    /// pose at a time or in batches gives the same candidates.
    pub seed: u64,
}

impl Default for OnlineSamplerOptions {
    /// σ_ρ at r = 1 with the default sampler's pick in a row, no cap, P1 online, no separation,
    /// seed 0.
    fn default() -> Self {
        Self {
            rate: 1.0,
            cap: Cap::None,
            first_on_appearance: true,
            closest_in_row: SamplerKind::DEFAULT.picks_closest_in_row(),
            separation: Separation::NONE,
            seed: 0,
        }
    }
}

/// A loop-closure candidate: a pair (j, keyframe), j < keyframe, within γ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The pose whose push made it possible.
    pub keyframe: usize,
    /// The pair `[j, keyframe]`, j < keyframe.
    pub pair: [usize; 2],
    /// Its component at the keyframe.
    pub component: ComponentId,
    /// δ(x_j, x_keyframe), the metric's unit.
    pub distance: f64,
    /// Emitted by the first-appearance rule (P1 online), not drawn.
    pub first: bool,
}

/// Picks loop-closure candidates from each [`Update`] of an [`OnlineLoops`]: the paper's σ_ρ
/// per keyframe, with a cap per component, P1 online and the revisit separation.
///
/// At every pose n and for every component with pairs (j, n), j < n, in the new row (separated
/// ones only, with a [`Separation`]), in this order:
/// 1. P1 online ([`first_on_appearance`](OnlineSamplerOptions::first_on_appearance)): the first
///    time the component (with every component merged into it) has such a pair, its closest
///    one is a candidate, whatever the rate and the cap (a bucket starts full).
/// 2. σ_ρ: ⌊r⌋ or ⌈r⌉ distinct pairs (⌈r⌉ with probability r − ⌊r⌋): with
///    [`closest_in_row`](OnlineSamplerOptions::closest_in_row) (the default) the first of them
///    the row's closest pair, the others uniformly among the rest; without it all uniformly;
///    dropping the one the first rule took.
/// 3. The [`Cap`]: a candidate takes a token from the component's bucket, and is dropped when
///    there is none. Merged components keep the smaller of their buckets.
///
/// Every random choice comes from a ChaCha8 stream keyed by (seed, pose, component), and a
/// component's id at a pose is the same whether the poses came one at a time or in batches
/// ([`RowRun::component`](super::RowRun::component) is the id as of the row), so the candidates
/// do not depend on how the poses were pushed. After a [rebuild](OnlineLoops::rebuild) the ids
/// start again, and so does the sampler: every component is new to it; likewise when it is
/// offered the updates of another engine.
///
/// Cost per update: its runs plus the candidates, and a closest column (O(log n)) per component
/// that P1 serves; memory a few words per component.
///
/// # Examples
/// ```
/// use loops_core::{Cap, MetricSpec, OnlineLoops, OnlineSampler, OnlineSamplerOptions, Separation, UrbanDrive};
/// let drive = UrbanDrive { duration_s: 900.0, seed: 3, ..UrbanDrive::default() }.generate()?;
/// let traj = &drive.trajectory;
/// let mut online = OnlineLoops::new(MetricSpec::Euclidean, traj.dim(), 20.0)?;
/// let options = OnlineSamplerOptions {
///     rate: 0.05,                          // one candidate per component per 20 keyframes
///     cap: Cap::PerMinute(6.0),            // at most about 6 a minute per place
///     separation: Separation::for_gamma(20.0), // revisits only: 80 m of travel apart
///     ..OnlineSamplerOptions::default()
/// };
/// let mut sampler = OnlineSampler::new(options)?;
/// let mut candidates = Vec::new();
/// for n in 0..traj.len() {
///     let update = online.push(traj.timestamps_s()[n], traj.point(n))?;
///     candidates.extend(sampler.offer(&online, &update)?);
/// }
/// assert!(!candidates.is_empty());
/// assert!(candidates.iter().all(|c| c.pair[1] == c.keyframe && c.distance <= 20.0));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct OnlineSampler {
    options: OnlineSamplerOptions,
    /// The push offered last: its engine and rebuild count are those the states were made for.
    offered: Option<PushStamp>,
    /// By component id: `None` until the component has a pair to offer.
    states: Vec<Option<Bucket>>,
}

/// What the sampler remembers of a component.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bucket {
    /// It had a candidate (P1 is served).
    served: bool,
    /// Candidates it may still take (the cap's token bucket).
    tokens: f64,
    /// The clock (seconds or path length) the tokens were counted at.
    clock: f64,
}

impl OnlineSampler {
    /// A sampler with `options`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a rate that is negative or not finite, or a cap that is
    /// not positive and finite; [`Error::InvalidSeparation`].
    pub fn new(options: OnlineSamplerOptions) -> Result<Self> {
        if !(options.rate.is_finite() && options.rate >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "rate",
                value: options.rate,
                expected: "a finite number of candidates per component per pose, at least 0",
            });
        }
        match options.cap {
            Cap::PerMinute(c) | Cap::PerMetre(c) if !(c.is_finite() && c > 0.0) => {
                let name = if matches!(options.cap, Cap::PerMinute(_)) { "cap per minute" } else { "cap per metre" };
                return Err(Error::InvalidParameter {
                    name,
                    value: c,
                    expected: "a positive finite number of candidates",
                });
            }
            _ => {}
        }
        options.separation.check()?;
        Ok(Self { options, offered: None, states: Vec::new() })
    }

    /// Its options.
    pub fn options(&self) -> &OnlineSamplerOptions {
        &self.options
    }

    /// The candidates that `update` (the last push's, from `loops`) made possible, by keyframe,
    /// component and column. Call it after every push or push_many, in order, once each.
    ///
    /// # Errors
    /// [`Error::UpdateNotLatest`] when `update` is not `loops`' [last
    /// push](OnlineLoops::last_push); [`Error::UpdateAlreadyOffered`] when it was offered to
    /// this sampler already. Nothing changes then.
    pub fn offer(&mut self, loops: &OnlineLoops, update: &Update) -> Result<Vec<Candidate>> {
        let (first_pose, pose) = (update.first_pose, update.pose);
        if update.stamp != loops.last_push() {
            return Err(Error::UpdateNotLatest { first_pose, pose });
        }
        if self.offered == Some(update.stamp) {
            return Err(Error::UpdateAlreadyOffered { first_pose, pose });
        }
        if !self.offered.is_some_and(|offered| offered.same_run(update.stamp)) {
            self.states.clear();
        }
        self.offered = Some(update.stamp);
        let mut candidates = Vec::new();
        let mut merges = update.merged.iter().peekable();
        let mut runs = &update.runs[..];
        while let Some(first) = runs.first() {
            let n = first.row;
            let row_len = runs.iter().take_while(|r| r.row == n).count();
            let (row, rest) = runs.split_at(row_len);
            runs = rest;
            while let Some(merge) = merges.next_if(|m| m.pose <= n) {
                self.merge(loops, merge.pose, merge.retired, merge.survivor);
            }
            self.offer_row(loops, n, row, &mut candidates);
        }
        for merge in merges {
            self.merge(loops, merge.pose, merge.retired, merge.survivor);
        }
        Ok(candidates)
    }

    /// The candidates of row n (`row`: its runs, in column order).
    fn offer_row(&mut self, loops: &OnlineLoops, n: usize, row: &[RowRun], out: &mut Vec<Candidate>) {
        let Some(last) = self.last_column(loops, n) else { return };
        let mut components: Vec<ComponentId> = row.iter().map(|r| r.component).collect();
        components.sort_unstable();
        components.dedup();
        let start = out.len();
        for c in components {
            // The component's pairs (j, n), j ≤ last, as column ranges.
            let available: Vec<(RowRun, usize)> = row
                .iter()
                .filter(|r| r.component == c && r.run.start as usize <= last)
                .map(|r| (*r, (r.run.end as usize).min(last)))
                .collect();
            let count: u64 = available.iter().map(|(r, end)| (end - r.run.start as usize + 1) as u64).sum();
            if count == 0 {
                continue;
            }
            let clock = self.clock(loops, n);
            let capacity = self.capacity();
            let slot = c as usize;
            if self.states.len() <= slot {
                self.states.resize(slot + 1, None);
            }
            let mut bucket = self.states[slot].unwrap_or(Bucket { served: false, tokens: capacity, clock });
            bucket.refill(self.rate_per_unit(), capacity, clock);
            let mut columns: Vec<(usize, bool)> = Vec::new();
            if self.options.first_on_appearance && !bucket.served {
                columns.push((closest_available(loops, n, &available), true));
            }
            let mut rng = keyed_rng(self.options.seed, n, c);
            let rate = self.options.rate;
            let mut draws = rate.floor() as u64 + u64::from(rng.random::<f64>() < rate.fract());
            if self.options.closest_in_row && draws > 0 {
                let j = closest_available(loops, n, &available);
                if columns.iter().all(|&(taken, _)| taken != j) {
                    columns.push((j, false));
                }
                draws -= 1;
            }
            for k in choose_indices(count, draws.min(count), &mut rng) {
                let j = column_at(&available, k);
                if columns.iter().all(|&(taken, _)| taken != j) {
                    columns.push((j, false));
                }
            }
            let x_n = loops.poses().point(n);
            for (j, first) in columns {
                if !matches!(self.options.cap, Cap::None) {
                    if bucket.tokens < 1.0 {
                        break;
                    }
                    bucket.tokens -= 1.0;
                }
                bucket.served = true;
                let distance = loops.metric().distance(loops.poses().point(j), x_n);
                out.push(Candidate { keyframe: n, pair: [j, n], component: c, distance, first });
            }
            self.states[slot] = Some(bucket);
        }
        out[start..].sort_by_key(|c| (c.component, c.pair[0]));
    }

    /// The last column j < n whose pair (j, n) keeps the separation, if any.
    fn last_column(&self, loops: &OnlineLoops, n: usize) -> Option<usize> {
        let separation = self.options.separation;
        if separation.is_none() {
            return n.checked_sub(1);
        }
        let (s, t) = (loops.path_length(), loops.timestamps_s());
        // Both differences shrink as j grows: count the j < n that keep both.
        let kept = s[..n].partition_point(|&s_j| s[n] - s_j >= separation.path);
        let kept = kept.min(t[..n].partition_point(|&t_j| t[n] - t_j >= separation.time_s));
        kept.checked_sub(1)
    }

    /// The clock the cap counts: seconds, or path length.
    fn clock(&self, loops: &OnlineLoops, n: usize) -> f64 {
        match self.options.cap {
            Cap::PerMetre(_) => loops.path_length()[n],
            _ => loops.timestamps_s()[n],
        }
    }

    /// Tokens per unit of the clock.
    fn rate_per_unit(&self) -> f64 {
        match self.options.cap {
            Cap::None => f64::INFINITY,
            Cap::PerMinute(c) => c / 60.0,
            Cap::PerMetre(c) => c,
        }
    }

    /// The most tokens a bucket holds: a minute's or a metre's worth, at least one.
    fn capacity(&self) -> f64 {
        match self.options.cap {
            Cap::None => f64::INFINITY,
            Cap::PerMinute(c) | Cap::PerMetre(c) => c.max(1.0),
        }
    }

    /// `retired` merged into `survivor` at pose n: P1 is served if it was for either, and the
    /// bucket is the smaller of the two.
    fn merge(&mut self, loops: &OnlineLoops, n: usize, retired: ComponentId, survivor: ComponentId) {
        // Nothing moves when the retired one never had a pair to offer.
        let Some(mut gone) = self.states.get(retired as usize).copied().flatten() else { return };
        let merged = match self.states[survivor as usize] {
            None => gone,
            Some(mut kept) => {
                let clock = self.clock(loops, n);
                let (rate, capacity) = (self.rate_per_unit(), self.capacity());
                gone.refill(rate, capacity, clock);
                kept.refill(rate, capacity, clock);
                Bucket { served: gone.served || kept.served, tokens: gone.tokens.min(kept.tokens), clock }
            }
        };
        // The survivor's id is the smaller, so its slot exists.
        self.states[survivor as usize] = Some(merged);
    }
}

impl Bucket {
    /// Adds the tokens earned since its clock, up to `capacity`.
    fn refill(&mut self, rate_per_unit: f64, capacity: f64, clock: f64) {
        if clock > self.clock {
            self.tokens = (self.tokens + rate_per_unit * (clock - self.clock)).min(capacity);
            self.clock = clock;
        }
    }
}

/// The ChaCha8 stream of `(seed, pose, component)`.
fn keyed_rng(seed: u64, pose: usize, component: ComponentId) -> ChaCha8Rng {
    let mut key = [0_u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(&(pose as u64).to_le_bytes());
    key[16..20].copy_from_slice(&component.to_le_bytes());
    key[20..28].copy_from_slice(b"online19");
    ChaCha8Rng::from_seed(key)
}

/// The column of the `k`-th pair of `available` (runs and the last column kept of each).
fn column_at(available: &[(RowRun, usize)], k: u64) -> usize {
    let mut k = k as usize;
    for &(run, end) in available {
        let len = end - run.run.start as usize + 1;
        if k < len {
            return run.run.start as usize + k;
        }
        k -= len;
    }
    unreachable!("k is below the number of pairs")
}

/// The available pair of row n closest to pose n: the earliest smallest rank, measured as the
/// batch measures (j, n).
fn closest_available(loops: &OnlineLoops, n: usize, available: &[(RowRun, usize)]) -> usize {
    let traj = loops.poses();
    with_metric!(&loops.metric(), m => {
        let mut best = (f64::INFINITY, usize::MAX);
        for &(run, end) in available {
            let start = run.run.start as usize;
            // The run's own closest column when it is kept, else the closest of the kept part.
            let j = if run.closest <= end { run.closest } else { loops.closest_column(m, n, start, end) };
            let rank = m.distance_rank(traj.point(j), traj.point(n));
            if rank < best.0 {
                best = (rank, j);
            }
        }
        best.1
    })
}

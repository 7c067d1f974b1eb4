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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// Where P1's candidate goes (with [`first_on_appearance`](Self::first_on_appearance)): at
    /// the edge of γ, at the closest approach of the component's first pass, or the edge at once
    /// and the closest approach as an improvement once the pass is over (the default). A state
    /// saved before this setting held `first_at_closest_approach`, a flag in its place, and
    /// reads back as what it did: `false` the edge, `true` the closest approach.
    #[cfg_attr(
        feature = "serde",
        serde(alias = "first_at_closest_approach", deserialize_with = "first_offer_or_flag")
    )]
    pub first_offer: FirstOffer,
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
            first_offer: FirstOffer::DEFAULT,
            closest_in_row: SamplerKind::DEFAULT.picks_closest_in_row(),
            separation: Separation::NONE,
            seed: 0,
        }
    }
}

/// A [`FirstOffer`], or the flag `first_at_closest_approach` that states saved before it held.
#[cfg(feature = "serde")]
fn first_offer_or_flag<'de, D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<FirstOffer, D::Error> {
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Saved {
        Offer(FirstOffer),
        Flag(bool),
    }
    Ok(match <Saved as serde::Deserialize>::deserialize(deserializer)? {
        Saved::Offer(offer) => offer,
        Saved::Flag(false) => FirstOffer::AtEdge,
        Saved::Flag(true) => FirstOffer::AtClosestApproach,
    })
}

/// Where P1 online puts a component's first candidate. A component's first pass is the rows in
/// a row where it has a pair to offer, from its first such row to the row before the first one
/// where it has none (the path has left it again).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FirstOffer {
    /// `"edge"`: the closest pair of the first row where the component has a pair to offer, at
    /// once: as the path comes within γ, the pair is about γ apart (a poor initial guess for a
    /// scan matcher).
    AtEdge,
    /// `"closest-approach"`: the closest pair of the whole first pass instead, offered at the
    /// first row after it (so the candidate's [`keyframe`](Candidate::keyframe) is later than
    /// its pair). It goes beyond the cap (it takes a token if there is one). A pass still under
    /// way when the drive stops has no first candidate yet.
    AtClosestApproach,
    /// `"edge-then-closest"`: the edge candidate at once, and once the pass is over its closest
    /// pair as a second candidate that [`improves`](Candidate::improves) it, unless the edge
    /// candidate was that pair already. The improvement is not drawn and takes no token (the
    /// first one was counted): the other candidates are those of [`AtEdge`](Self::AtEdge).
    EdgeThenClosest,
}

impl FirstOffer {
    /// The default: no latency for the first candidate, the best pair once the pass is over.
    pub const DEFAULT: Self = Self::EdgeThenClosest;

    /// Every kind, in the order of [`NAMES`](Self::NAMES).
    pub const ALL: [Self; 3] = [Self::AtEdge, Self::AtClosestApproach, Self::EdgeThenClosest];

    /// The names, as parsed.
    pub const NAMES: &'static str = "edge, closest-approach, edge-then-closest";

    /// The name, as parsed.
    pub fn name(self) -> &'static str {
        match self {
            Self::AtEdge => "edge",
            Self::AtClosestApproach => "closest-approach",
            Self::EdgeThenClosest => "edge-then-closest",
        }
    }

    /// Whether the sampler follows a component's first pass to its closest pair.
    fn follows_pass(self) -> bool {
        !matches!(self, Self::AtEdge)
    }
}

impl Default for FirstOffer {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl std::fmt::Display for FirstOffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for FirstOffer {
    type Err = Error;

    /// `"edge"`, `"closest-approach"` or `"edge-then-closest"`.
    fn from_str(name: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name).ok_or_else(|| Error::UnknownName {
            kind: "first offer",
            name: name.to_owned(),
            expected: Self::NAMES,
        })
    }
}

/// A loop-closure candidate: a pair (j, k), j < k ≤ keyframe, within γ, offered at the
/// keyframe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The pose whose push offered it: the pair's later pose, but for a candidate at the
    /// closest approach ([`FirstOffer::AtClosestApproach`], and the improvements of
    /// [`FirstOffer::EdgeThenClosest`]), offered once the pass was over.
    pub keyframe: usize,
    /// The pair `[j, k]`, j < k ≤ keyframe.
    pub pair: [usize; 2],
    /// Its component at the keyframe.
    pub component: ComponentId,
    /// δ(x_j, x_k), the metric's unit.
    pub distance: f64,
    /// Emitted by the first-appearance rule (P1 online), not drawn.
    pub first: bool,
    /// For an improvement of [`FirstOffer::EdgeThenClosest`]: the pair of the first candidate it
    /// improves (offered earlier, at the edge of γ); this one is the closest pair of that first
    /// pass. It is not `first` and may have been drawn already in its row.
    pub improves: Option<[usize; 2]>,
}

/// Picks loop-closure candidates from each [`Update`] of an [`OnlineLoops`]: the paper's σ_ρ
/// per keyframe, with a cap per component, P1 online and the revisit separation.
///
/// At every pose n and for every component with pairs (j, n), j < n, in the new row (separated
/// ones only, with a [`Separation`]), in this order:
/// 1. P1 online ([`first_on_appearance`](OnlineSamplerOptions::first_on_appearance)): the first
///    time the component (with every component merged into it) has such a pair, its closest
///    one is a candidate, whatever the rate and the cap (a bucket starts full). At the closest
///    approach ([`FirstOffer::AtClosestApproach`]), the closest pair of the rows of that first
///    pass instead, offered at the row after it; with [`FirstOffer::EdgeThenClosest`] (the
///    default) both: the edge one at once, and the pass's closest pair at the row after it as an
///    improvement, unless it is the same pair.
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
/// With the `serde` feature a sampler saves and reads back its state (options, buckets, what
/// P1 served, the pose it has reached): the copy goes on as the original does. The engine it
/// followed is not part of it (engines are known by a number of this process); the copy
/// follows the first engine whose update it is offered, if that update starts at the pose
/// after the last one offered, at the same rebuild count; any other starts it afresh.
///
/// # Examples
/// ```
/// use loops_core::online::{Cap, OnlineLoops, OnlineSampler, OnlineSamplerOptions};
/// use loops_core::{MetricSpec, Separation, UrbanDrive};
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
/// assert!(candidates.iter().all(|c| c.pair[1] <= c.keyframe && c.distance <= 20.0));
/// // A component's first candidate comes at the edge of γ; once the pass is over, the closest
/// // pair of the pass follows, naming the pair it improves.
/// let improved = candidates.iter().filter(|c| c.improves.is_some());
/// assert!(improved.clone().all(|c| c.pair[1] < c.keyframe && !c.first));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(try_from = "SamplerState", into = "SamplerState")
)]
#[derive(Debug, Clone)]
pub struct OnlineSampler {
    options: OnlineSamplerOptions,
    /// The push offered last: its engine and rebuild count are those the states were made for.
    offered: Option<PushStamp>,
    /// Where the states continue: the pose after the last one offered and the engine's rebuild
    /// count then. It decides alone for a copy read back, which knows no engine (`offered` is
    /// `None`).
    reached: Option<Reached>,
    /// By component id: `None` until the component has a pair to offer.
    states: Vec<Option<Bucket>>,
    /// The components whose first pass is under way (they had a pair to offer in the last row
    /// and P1 at the closest approach has still to offer its closest pair), increasing.
    passing: Vec<ComponentId>,
}

/// The pose after the last one a sampler was offered, and its engine's rebuild count then.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
struct Reached {
    next_pose: usize,
    rebuilds: u64,
}

/// What a saved [`OnlineSampler`] holds: everything but the engine it followed.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct SamplerState {
    options: OnlineSamplerOptions,
    reached: Option<Reached>,
    states: Vec<Option<Bucket>>,
    passing: Vec<ComponentId>,
}

#[cfg(feature = "serde")]
impl From<OnlineSampler> for SamplerState {
    fn from(sampler: OnlineSampler) -> Self {
        let OnlineSampler { options, offered: _, reached, states, passing } = sampler;
        Self { options, reached, states, passing }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<SamplerState> for OnlineSampler {
    type Error = Error;

    /// Checked as [`OnlineSampler::new`] checks the options; every bucket's tokens at least 0
    /// and its clock a number.
    fn try_from(state: SamplerState) -> Result<Self> {
        let mut sampler = Self::new(state.options)?;
        if let Some(index) =
            state.states.iter().position(|b| b.is_some_and(|b| b.tokens.is_nan() || b.tokens < 0.0 || b.clock.is_nan()))
        {
            return Err(Error::InvalidState {
                what: "OnlineSampler",
                reason: format!("component {index} has a bucket with tokens below 0 or a clock that is not a number"),
            });
        }
        if let Some(c) = state.passing.iter().find(|&&c| state.states.get(c as usize).is_none_or(|b| b.is_none())) {
            return Err(Error::InvalidState {
                what: "OnlineSampler",
                reason: format!("component {c} is passing but has no bucket"),
            });
        }
        sampler.reached = state.reached;
        sampler.states = state.states;
        sampler.passing = state.passing;
        Ok(sampler)
    }
}

/// What the sampler remembers of a component.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bucket {
    /// It had its first candidate (P1 is served).
    served: bool,
    /// P1 at the closest approach: the closest pair of its first pass so far, while the pass is
    /// under way.
    closest: Option<Closest>,
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
        Ok(Self { options, offered: None, reached: None, states: Vec::new(), passing: Vec::new() })
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
        let continues = match self.offered {
            Some(offered) => offered.same_run(update.stamp),
            None => self.reached == Some(Reached { next_pose: first_pose, rebuilds: update.stamp.rebuilds() }),
        };
        if !continues {
            self.states.clear();
            self.passing.clear();
        }
        self.offered = Some(update.stamp);
        self.reached = Some(Reached { next_pose: pose + 1, rebuilds: update.stamp.rebuilds() });
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
        let start = out.len();
        let Some(last) = self.last_column(loops, n) else {
            self.close_passes(loops, n, &[], out);
            return;
        };
        let mut components: Vec<ComponentId> =
            row.iter().filter(|r| r.run.start as usize <= last).map(|r| r.component).collect();
        components.sort_unstable();
        components.dedup();
        self.close_passes(loops, n, &components, out);
        let first_offer = self.options.first_on_appearance.then_some(self.options.first_offer);
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
            let mut bucket =
                self.states[slot].unwrap_or(Bucket { served: false, closest: None, tokens: capacity, clock });
            bucket.refill(self.rate_per_unit(), capacity, clock);
            let mut columns: Vec<(usize, bool)> = Vec::new();
            // A first pass starts where P1 is not served yet, and goes on while it is followed.
            let in_first_pass = !bucket.served || bucket.closest.is_some();
            if let Some(first_offer) = first_offer.filter(|_| in_first_pass) {
                let (j, rank) = closest_available(loops, n, &available);
                if first_offer != FirstOffer::AtClosestApproach && !bucket.served {
                    columns.push((j, true));
                }
                if first_offer.follows_pass() {
                    let improves = (first_offer == FirstOffer::EdgeThenClosest).then_some([j, n]);
                    match &mut bucket.closest {
                        Some(best) if rank < best.rank => (best.pair, best.rank) = ([j, n], rank),
                        Some(_) => {}
                        None => bucket.closest = Some(Closest { pair: [j, n], rank, improves }),
                    }
                    if let Err(at) = self.passing.binary_search(&c) {
                        self.passing.insert(at, c);
                    }
                }
            }
            let mut rng = keyed_rng(self.options.seed, n, c);
            let rate = self.options.rate;
            let mut draws = rate.floor() as u64 + u64::from(rng.random::<f64>() < rate.fract());
            if self.options.closest_in_row && draws > 0 {
                let j = closest_available(loops, n, &available).0;
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
                bucket.served |= first;
                let distance = loops.metric().distance(loops.poses().point(j), x_n);
                out.push(Candidate { keyframe: n, pair: [j, n], component: c, distance, first, improves: None });
            }
            self.states[slot] = Some(bucket);
        }
        out[start..].sort_by_key(|c| (c.component, c.pair[0]));
    }

    /// P1 at the closest approach: the components passing until row n that have no pair to offer
    /// in it (`present`: those that have, increasing) get their first candidate, the closest
    /// pair of their pass, offered at n.
    fn close_passes(&mut self, loops: &OnlineLoops, n: usize, present: &[ComponentId], out: &mut Vec<Candidate>) {
        let (rate, capacity) = (self.rate_per_unit(), self.capacity());
        let clock = self.clock(loops, n);
        let passing = std::mem::take(&mut self.passing);
        for c in passing {
            if present.binary_search(&c).is_ok() {
                self.passing.push(c);
                continue;
            }
            let Some(bucket) = self.states.get_mut(c as usize).and_then(Option::as_mut) else { continue };
            let Some(Closest { pair: [j, k], improves, .. }) = bucket.closest.take() else { continue };
            if improves == Some([j, k]) {
                continue; // The edge candidate was the closest pair already.
            }
            if improves.is_none() {
                bucket.refill(rate, capacity, clock);
                if bucket.tokens >= 1.0 && !matches!(self.options.cap, Cap::None) {
                    bucket.tokens -= 1.0;
                }
                bucket.served = true;
            }
            let distance = loops.metric().distance(loops.poses().point(j), loops.poses().point(k));
            let first = improves.is_none();
            out.push(Candidate { keyframe: n, pair: [j, k], component: c, distance, first, improves });
        }
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

    /// `retired` merged into `survivor` at pose n: P1 is served if it was for either, the first
    /// pass is over if it was for either (else the closer of the two passes' pairs goes on), and
    /// the bucket is the smaller of the two.
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
                let closest = match (gone.closest, kept.closest) {
                    _ if gone.pass_over() || kept.pass_over() => None,
                    (Some(a), Some(b)) => Some(if b.rank <= a.rank { b } else { a }),
                    (a, b) => a.or(b),
                };
                Bucket { served: gone.served || kept.served, closest, tokens: gone.tokens.min(kept.tokens), clock }
            }
        };
        // A component is passing exactly when its pass has a closest pair.
        if let Ok(at) = self.passing.binary_search(&retired) {
            self.passing.remove(at);
        }
        match self.passing.binary_search(&survivor) {
            Ok(at) if merged.closest.is_none() => {
                self.passing.remove(at);
            }
            Err(at) if merged.closest.is_some() => self.passing.insert(at, survivor),
            _ => {}
        }
        // The survivor's id is the smaller, so its slot exists.
        self.states[survivor as usize] = Some(merged);
    }
}

/// The closest pair of a pass so far, and its rank under the metric.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, PartialEq)]
struct Closest {
    pair: [usize; 2],
    rank: f64,
    /// With [`FirstOffer::EdgeThenClosest`]: the pair of the first candidate, offered at the edge.
    #[cfg_attr(feature = "serde", serde(default))]
    improves: Option<[usize; 2]>,
}

impl Bucket {
    /// Its first pass is over: P1 served and no pass followed.
    fn pass_over(&self) -> bool {
        self.served && self.closest.is_none()
    }

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

/// The available pair of row n closest to pose n and its rank: the earliest smallest rank,
/// measured as the batch measures (j, n).
fn closest_available(loops: &OnlineLoops, n: usize, available: &[(RowRun, usize)]) -> (usize, f64) {
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
        (best.1, best.0)
    })
}

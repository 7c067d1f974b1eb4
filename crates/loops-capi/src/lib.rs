//! The C ABI of inexact-loops' online engine, for SLAM front ends written in C or C++: loop
//! components kept up to date while poses arrive ([`loops_core::online::OnlineLoops`]) and the
//! loop-closure candidates of each keyframe ([`loops_core::online::OnlineSampler`]).
//!
//! The header is `include/inexact_loops.h`, generated from this crate by cbindgen (the test
//! `tests/header.rs` fails when the committed header differs; `UPDATE_HEADER=1 cargo test -p
//! loops-capi --test header` rewrites it). Link `libinexact_loops.a` (with `-lpthread -ldl -lm`)
//! or `libinexact_loops.so`; `examples/cpp/online_replay.cpp` is a whole front end in 100 lines.
//!
//! # Conventions
//! - **Handles** are opaque: [`LoopsOnline`] (one trajectory's online loops) and
//!   [`LoopsSampler`] (a candidate sampler). Each is made by its `_new` function into a pointer
//!   the caller owns and gives back to its `_free` function exactly once (`_free` of NULL does
//!   nothing). A handle may move between threads but is not to be used by two at once.
//! - **Status codes**: every function that can fail returns a [`LoopsStatus`]; on anything
//!   but [`LoopsStatus::Ok`] nothing changed, and [`loops_last_error`] gives a one-line message
//!   naming the pose index and value (a thread-local string, valid until the next call of this
//!   library on the same thread). Getters that cannot fail return their value (0 for NULL).
//! - **No unwinding across the boundary**: every entry point catches panics (a bug) and returns
//!   [`LoopsStatus::Internal`]; NULL pointers where a value is needed are
//!   [`LoopsStatus::NullPointer`].
//! - **Buffers** belong to the caller: inputs are read during the call only; outputs are written
//!   up to the capacity given, and the count is always the whole count.
//! - Metrics are named as in Python and on the command line: `"euclidean"`,
//!   `"se3(rotation_weight_m_per_rad=10)"`, ... (see `loops_core::MetricSpec`); distances and γ
//!   in the metric's unit, times in seconds.

// The C ABI is raw pointers and exported symbols: unsafe by nature. Every `unsafe` block is a
// read or write through a pointer the caller promised (see each function's `# Safety`), after a
// NULL check.
#![allow(unsafe_code)]
#![warn(missing_docs)]

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

use loops_core::{
    Error, ErrorClass, MetricSpec, Separation, Trajectory,
    online::{Candidate, Cap, FirstOffer, OnlineComponent, OnlineLoops, OnlineSampler, OnlineSamplerOptions, Update},
};

/// What a call of this library did: `Ok` (`LOOPS_STATUS_OK` in C), or why it did nothing (the message is
/// [`loops_last_error`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopsStatus {
    /// Done.
    Ok = 0,
    /// A pointer that must not be NULL was NULL.
    NullPointer = 1,
    /// A parameter out of range or unknown: γ, the metric's name or weight, the rate, the cap,
    /// the separation, a text that is not UTF-8, a buffer of the wrong size.
    InvalidParameter = 2,
    /// A pose the engine refuses: a coordinate or time that is NaN or infinite, a time not after
    /// the last, the wrong number of coordinates, a quaternion that is not unit, too few poses for
    /// a rebuild.
    InvalidTrajectory = 3,
    /// A pose index past the last pose.
    IndexOutOfRange = 4,
    /// Memory could not be had (the message says how much).
    OutOfMemory = 5,
    /// A bug of the library (a panic, caught): please report the message.
    Internal = 6,
}

/// How an [`LoopsSamplerOptions`] caps each component's candidates (a token bucket per
/// component): the values of its `cap_kind`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopsCapKind {
    /// No cap.
    None = 0,
    /// At most `cap_value` candidates per minute per component.
    PerMinute = 1,
    /// At most `cap_value` candidates per metre of travel (the metric's unit) per component.
    PerMetre = 2,
}

/// The options of a [`LoopsSampler`]; [`loops_sampler_options_default`] fills in the library's
/// defaults (σ_ρ at rate 1, no cap, a candidate at each component's first appearance, no
/// separation, seed 0).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopsSamplerOptions {
    /// σ_ρ: the expected number of candidates per component per pose (0: only the
    /// first-appearance candidates).
    pub rate: f64,
    /// The kind of cap per component: one of [`LoopsCapKind`]'s values (`LOOPS_CAP_KIND_NONE`,
    /// ...); any other is refused with [`LoopsStatus::InvalidParameter`]. An integer rather
    /// than the enum, so that a value outside it is an error here, not undefined behaviour.
    pub cap_kind: u32,
    /// The cap's value (candidates per minute or per metre); ignored without a cap.
    pub cap_value: f64,
    /// P1 online: a candidate (the closest pair) when a component first has a pair to offer.
    pub first_on_appearance: bool,
    /// Only pairs at least this path length apart along the trajectory (the metric's unit).
    pub separation_path: f64,
    /// Only pairs at least this many seconds apart.
    pub separation_time_s: f64,
    /// The seed of the random choices: the same candidates on every machine, whether poses are
    /// pushed one at a time or in batches.
    pub seed: u64,
}

/// Where a sampler puts a component's first candidate: the values of
/// [`LoopsSamplerOptionsV2`]'s `first_offer`. A component's first pass is the keyframes from
/// the first one where it has a pair to offer to the last one before the path leaves it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopsFirstOffer {
    /// The closest pair of the first keyframe where the component has a pair to offer, at once
    /// (at the edge of γ: about γ apart).
    AtEdge = 0,
    /// The closest pair of the whole first pass, offered at the keyframe after it (its `k`
    /// before its `keyframe`), beyond the cap.
    AtClosestApproach = 1,
    /// Both: the edge candidate at once, and once the pass is over its closest pair as a second
    /// candidate that names the first in `improves_j`, `improves_k` (none when the first was
    /// that pair). The library's default.
    EdgeThenClosest = 2,
}

/// The options of a sampler made by [`loops_sampler_new_v2`]: those of
/// [`LoopsSamplerOptions`] and where the first candidate goes;
/// [`loops_sampler_options_default_v2`] fills in the library's defaults.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopsSamplerOptionsV2 {
    /// The options of the first version.
    pub base: LoopsSamplerOptions,
    /// One of [`LoopsFirstOffer`]'s values (`LOOPS_FIRST_OFFER_EDGE_THEN_CLOSEST`, ...); any
    /// other is refused with [`LoopsStatus::InvalidParameter`].
    pub first_offer: u32,
}

/// What a push changed, in counts (the candidates come from [`loops_sampler_offer`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoopsUpdate {
    /// Index of the first pose the push added.
    pub first_pose: usize,
    /// Index of the last pose pushed (the keyframe).
    pub pose: usize,
    /// Runs (intervals of earlier poses within γ) of the new rows.
    pub run_count: usize,
    /// Components created.
    pub created_count: usize,
    /// Components that existed before and gained pairs.
    pub extended_count: usize,
    /// Merges of two components.
    pub merged_count: usize,
    /// The loop duration τ of the last pose so far, seconds.
    pub loop_duration_s: f64,
}

/// A loop-closure candidate: the pair (j, keyframe), j < keyframe, within γ.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoopsCandidate {
    /// The pose whose push made it possible (the later pose of the pair).
    pub keyframe: usize,
    /// The earlier pose of the pair.
    pub j: usize,
    /// Its component's id at the keyframe.
    pub component: u32,
    /// δ(x_j, x_keyframe), the metric's unit.
    pub distance: f64,
    /// Emitted by the first-appearance rule rather than drawn.
    pub first: bool,
}

/// A loop-closure candidate of a [`loops_sampler_new_v2`] sampler: the pair (j, k),
/// j < k ≤ keyframe, within γ.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoopsCandidateV2 {
    /// The keyframe whose offer gave it: `k`, but for a candidate at the closest approach,
    /// offered once the pass was over.
    pub keyframe: usize,
    /// The earlier pose of the pair.
    pub j: usize,
    /// The later pose of the pair.
    pub k: usize,
    /// Its component's id at the keyframe.
    pub component: u32,
    /// δ(x_j, x_k), the metric's unit.
    pub distance: f64,
    /// Emitted by the first-appearance rule rather than drawn.
    pub first: bool,
    /// It is the closest approach that improves the component's first candidate, whose pair is
    /// (`improves_j`, `improves_k`) (both 0 otherwise).
    pub improves: bool,
    /// The earlier pose of the pair it improves.
    pub improves_j: usize,
    /// The later pose of the pair it improves.
    pub improves_k: usize,
}

/// A live loop component's statistics so far (as the batch `find_loops` gives them for the
/// trajectory pushed so far).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoopsComponent {
    /// Its id (creation order from 0; a merge keeps the smaller).
    pub id: u32,
    /// Holds the diagonal (its pairs are simple loops).
    pub trivial: bool,
    /// Area in the (t, t′) plane, s².
    pub area_s2: f64,
    /// Lattice cells (i, j).
    pub pair_count: u64,
    /// Runs (row intervals) of the batch's upper half.
    pub run_count: usize,
    /// Holes.
    pub holes: u64,
    /// First and last pose i of the half i ≤ j.
    pub i_min: usize,
    /// Last pose i.
    pub i_max: usize,
    /// First pose j.
    pub j_min: usize,
    /// Last pose j.
    pub j_max: usize,
    /// The closest pair (i, j), i ≤ j: i.
    pub closest_i: usize,
    /// The closest pair's j.
    pub closest_j: usize,
    /// δ at the closest pair.
    pub closest_distance: f64,
    /// The pose whose row created it.
    pub first_pose: usize,
    /// The last pose whose row extended it.
    pub last_pose: usize,
}

/// One trajectory's online loops: poses pushed one at a time or in batches, the loop
/// components kept up to date. Made by [`loops_online_new`], freed by [`loops_online_free`].
#[derive(Debug)]
pub struct LoopsOnline {
    inner: OnlineLoops,
    /// The last push's update, for [`loops_sampler_offer`].
    last: Option<Update>,
}

/// A loop-closure candidate sampler. Made by [`loops_sampler_new`], freed by
/// [`loops_sampler_free`].
#[derive(Debug)]
pub struct LoopsSampler {
    inner: OnlineSampler,
    /// The candidates of the last offer.
    candidates: Vec<Candidate>,
}

/// Why a call failed, before it becomes a status and a message.
enum Failure {
    Core(Error),
    Null(&'static str),
    Parameter(String),
}

impl From<Error> for Failure {
    fn from(error: Error) -> Self {
        Self::Core(error)
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    // A message never holds NUL; if one did, it is cut there.
    let bytes: Vec<u8> = message.bytes().take_while(|&b| b != 0).collect();
    let text = CString::new(bytes).unwrap_or_default();
    LAST_ERROR.with(|last| *last.borrow_mut() = text);
}

/// The status of a core error: its [`ErrorClass`], the class Python raises; a point of another
/// dimension than the engine's is a pose it refuses here (for Python, a metric that does not fit
/// the trajectory).
fn core_status(error: &Error) -> LoopsStatus {
    match (error, error.class()) {
        (Error::DimensionMismatch { .. }, _) | (_, ErrorClass::InvalidTrajectory) => LoopsStatus::InvalidTrajectory,
        (_, ErrorClass::IndexOutOfRange) => LoopsStatus::IndexOutOfRange,
        (_, ErrorClass::OutOfMemory) => LoopsStatus::OutOfMemory,
        _ => LoopsStatus::InvalidParameter,
    }
}

/// Runs the body of an entry point: its error or panic becomes a status and the thread's last
/// error message; success clears the message.
fn entry(name: &str, body: impl FnOnce() -> Result<(), Failure>) -> LoopsStatus {
    let (status, message) = match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => (LoopsStatus::Ok, String::new()),
        Ok(Err(Failure::Core(error))) => (core_status(&error), error.to_string()),
        Ok(Err(Failure::Null(argument))) => (LoopsStatus::NullPointer, format!("{name}: {argument} is NULL")),
        Ok(Err(Failure::Parameter(message))) => (LoopsStatus::InvalidParameter, format!("{name}: {message}")),
        Err(payload) => {
            let text = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_owned());
            (LoopsStatus::Internal, format!("{name}: internal error (please report): {text}"))
        }
    };
    set_last_error(&message);
    status
}

/// A value computed by an entry point that cannot fail (getters): `fallback` for a NULL handle
/// or a panic.
fn getter<T>(fallback: T, body: impl FnOnce() -> Option<T>) -> T {
    catch_unwind(AssertUnwindSafe(body)).ok().flatten().unwrap_or(fallback)
}

/// `&*pointer`, or [`Failure::Null`] naming `argument`.
///
/// # Safety
/// `pointer` is NULL or valid for reads of a `T` for `'a`.
unsafe fn reference<'a, T>(pointer: *const T, argument: &'static str) -> Result<&'a T, Failure> {
    // SAFETY: the caller's promise, after the NULL check.
    unsafe { pointer.as_ref() }.ok_or(Failure::Null(argument))
}

/// `&mut *pointer`, or [`Failure::Null`] naming `argument`.
///
/// # Safety
/// `pointer` is NULL or valid for reads and writes of a `T` for `'a`, used by nothing else.
unsafe fn exclusive<'a, T>(pointer: *mut T, argument: &'static str) -> Result<&'a mut T, Failure> {
    // SAFETY: the caller's promise, after the NULL check.
    unsafe { pointer.as_mut() }.ok_or(Failure::Null(argument))
}

/// The slice of `len` values at `pointer` (which may be NULL when `len` is 0).
///
/// # Safety
/// `pointer` is NULL or valid for reads of `len` values of `T` for `'a`.
unsafe fn slice<'a, T>(pointer: *const T, len: usize, argument: &'static str) -> Result<&'a [T], Failure> {
    if len == 0 {
        return Ok(&[]);
    }
    if pointer.is_null() {
        return Err(Failure::Null(argument));
    }
    // SAFETY: the caller's promise, after the NULL check.
    Ok(unsafe { std::slice::from_raw_parts(pointer, len) })
}

/// Writes `value` through `out` when it is not NULL.
///
/// # Safety
/// `out` is NULL or valid for writes of a `T`.
unsafe fn write_optional<T>(out: *mut T, value: T) {
    if let Some(out) = unsafe { out.as_mut() } {
        *out = value;
    }
}

impl LoopsUpdate {
    fn of(update: &Update) -> Self {
        Self {
            first_pose: update.first_pose,
            pose: update.pose,
            run_count: update.runs.len(),
            created_count: update.created.len(),
            extended_count: update.extended.len(),
            merged_count: update.merged.len(),
            loop_duration_s: update.loop_duration_s,
        }
    }
}

impl LoopsCandidate {
    fn of(candidate: &Candidate) -> Self {
        Self {
            keyframe: candidate.keyframe,
            j: candidate.pair[0],
            component: candidate.component,
            distance: candidate.distance,
            first: candidate.first,
        }
    }
}

impl LoopsCandidateV2 {
    fn of(candidate: &Candidate) -> Self {
        let [improves_j, improves_k] = candidate.improves.unwrap_or_default();
        Self {
            keyframe: candidate.keyframe,
            j: candidate.pair[0],
            k: candidate.pair[1],
            component: candidate.component,
            distance: candidate.distance,
            first: candidate.first,
            improves: candidate.improves.is_some(),
            improves_j,
            improves_k,
        }
    }
}

impl LoopsComponent {
    fn of(c: &OnlineComponent) -> Self {
        Self {
            id: c.id,
            trivial: c.trivial,
            area_s2: c.area_s2,
            pair_count: c.pair_count,
            run_count: c.run_count,
            holes: c.holes,
            i_min: c.i_range[0],
            i_max: c.i_range[1],
            j_min: c.j_range[0],
            j_max: c.j_range[1],
            closest_i: c.closest_pair[0],
            closest_j: c.closest_pair[1],
            closest_distance: c.closest_distance,
            first_pose: c.first_pose,
            last_pose: c.last_pose,
        }
    }
}

impl LoopsSamplerOptions {
    fn of(options: &OnlineSamplerOptions) -> Self {
        let (cap_kind, cap_value) = match options.cap {
            Cap::None => (LoopsCapKind::None, 0.0),
            Cap::PerMinute(c) => (LoopsCapKind::PerMinute, c),
            Cap::PerMetre(c) => (LoopsCapKind::PerMetre, c),
        };
        Self {
            rate: options.rate,
            cap_kind: cap_kind as u32,
            cap_value,
            first_on_appearance: options.first_on_appearance,
            separation_path: options.separation.path,
            separation_time_s: options.separation.time_s,
            seed: options.seed,
        }
    }

    fn to_core(self) -> Result<OnlineSamplerOptions, Failure> {
        let cap = match LoopsCapKind::checked(self.cap_kind)? {
            LoopsCapKind::None => Cap::None,
            LoopsCapKind::PerMinute => Cap::PerMinute(self.cap_value),
            LoopsCapKind::PerMetre => Cap::PerMetre(self.cap_value),
        };
        Ok(OnlineSamplerOptions {
            rate: self.rate,
            cap,
            first_on_appearance: self.first_on_appearance,
            separation: Separation { path: self.separation_path, time_s: self.separation_time_s },
            seed: self.seed,
            // A `LoopsCandidate` names its pair by the keyframe: the first candidate is offered
            // at the edge, where its pair ends. Samplers of `loops_sampler_new_v2` choose.
            first_offer: FirstOffer::AtEdge,
            // The C options keep their layout: a row's pick is the default sampler's.
            ..OnlineSamplerOptions::default()
        })
    }
}

impl LoopsSamplerOptionsV2 {
    fn of(options: &OnlineSamplerOptions) -> Self {
        Self { base: LoopsSamplerOptions::of(options), first_offer: LoopsFirstOffer::of(options.first_offer) as u32 }
    }

    fn to_core(self) -> Result<OnlineSamplerOptions, Failure> {
        let first_offer = LoopsFirstOffer::checked(self.first_offer)?.to_core();
        Ok(OnlineSamplerOptions { first_offer, ..self.base.to_core()? })
    }
}

impl LoopsFirstOffer {
    const ALL: [Self; 3] = [Self::AtEdge, Self::AtClosestApproach, Self::EdgeThenClosest];

    fn of(first_offer: FirstOffer) -> Self {
        match first_offer {
            FirstOffer::AtEdge => Self::AtEdge,
            FirstOffer::AtClosestApproach => Self::AtClosestApproach,
            FirstOffer::EdgeThenClosest => Self::EdgeThenClosest,
        }
    }

    fn to_core(self) -> FirstOffer {
        match self {
            Self::AtEdge => FirstOffer::AtEdge,
            Self::AtClosestApproach => FirstOffer::AtClosestApproach,
            Self::EdgeThenClosest => FirstOffer::EdgeThenClosest,
        }
    }

    /// The value whose number is `value`, checked: a C enum may hold any integer.
    fn checked(value: u32) -> Result<Self, Failure> {
        Self::ALL.into_iter().find(|&kind| kind as u32 == value).ok_or_else(|| {
            Failure::Parameter(format!(
                "first_offer = {value} is invalid: LOOPS_FIRST_OFFER_AT_EDGE (0), \
                 LOOPS_FIRST_OFFER_AT_CLOSEST_APPROACH (1) or LOOPS_FIRST_OFFER_EDGE_THEN_CLOSEST (2)"
            ))
        })
    }
}

impl LoopsCapKind {
    /// The kind whose value is `value`, checked: a C enum may hold any integer.
    fn checked(value: u32) -> Result<Self, Failure> {
        [Self::None, Self::PerMinute, Self::PerMetre].into_iter().find(|&kind| kind as u32 == value).ok_or_else(|| {
            Failure::Parameter(format!(
                "cap_kind = {value} is invalid: LOOPS_CAP_KIND_NONE (0), LOOPS_CAP_KIND_PER_MINUTE (1) or \
                 LOOPS_CAP_KIND_PER_METRE (2)"
            ))
        })
    }
}

/// The message of the last failed call of this library on the calling thread, one line in
/// UTF-8 naming the argument, pose index or value; `""` after a call that succeeded. The
/// string belongs to the library and stays valid until the next call of this library on the
/// same thread: copy it to keep it. Never NULL.
#[unsafe(no_mangle)]
pub extern "C" fn loops_last_error() -> *const c_char {
    LAST_ERROR.with(|last| last.borrow().as_ptr())
}

/// The library's version, e.g. `"0.1.0"` (static, never NULL).
#[unsafe(no_mangle)]
pub extern "C" fn loops_version() -> *const c_char {
    static VERSION: &CStr = match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
        Ok(version) => version,
        Err(_) => c"unknown",
    };
    VERSION.as_ptr()
}

/// Makes an empty online engine: poses of `dim` coordinates measured by the metric named
/// `metric` (NUL-terminated UTF-8, e.g. `"euclidean"` or
/// `"se3(rotation_weight_m_per_rad=10)"`; NULL is `"euclidean"`), threshold `gamma` > 0 in the
/// metric's unit. On success `*out` is a new handle for [`loops_online_free`].
///
/// # Errors
/// [`LoopsStatus::InvalidParameter`] for γ, the metric, and a `dim` the metric does not take
/// or above 65,536 (`loops_core::online::OnlineLoops::MAX_DIM`).
///
/// # Safety
/// `metric` is NULL or a NUL-terminated string; `out` is valid for writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_new(
    metric: *const c_char,
    dim: usize,
    gamma: f64,
    out: *mut *mut LoopsOnline,
) -> LoopsStatus {
    entry("loops_online_new", || {
        let out = unsafe { exclusive(out, "out") }?;
        let spec = if metric.is_null() {
            MetricSpec::default()
        } else {
            // SAFETY: a NUL-terminated string, the caller's promise.
            let text = unsafe { CStr::from_ptr(metric) }
                .to_str()
                .map_err(|_| Failure::Parameter("metric is not UTF-8".to_owned()))?;
            text.parse::<MetricSpec>()?
        };
        let inner = OnlineLoops::new(spec, dim, gamma)?;
        *out = Box::into_raw(Box::new(LoopsOnline { inner, last: None }));
        Ok(())
    })
}

/// Frees a handle of [`loops_online_new`]; NULL does nothing.
///
/// # Safety
/// `online` is NULL or a handle of [`loops_online_new`] not yet freed; it is not used after.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_free(online: *mut LoopsOnline) {
    if !online.is_null() {
        // SAFETY: a handle of `loops_online_new` (a Box), freed once: the caller's promise.
        let handle = unsafe { Box::from_raw(online) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(handle)));
    }
}

/// Pushes one pose: time `t_s` (after the last pose's) and `dim` coordinates at `point` (`dim`
/// must be the handle's). `update` (may be NULL) receives what changed; then offer it to a
/// sampler with [`loops_sampler_offer`].
///
/// # Safety
/// `online` is a live handle; `point` is valid for reading `dim` doubles; `update` is NULL or
/// valid for writing a [`LoopsUpdate`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_push(
    online: *mut LoopsOnline,
    t_s: f64,
    point: *const f64,
    dim: usize,
    update: *mut LoopsUpdate,
) -> LoopsStatus {
    // SAFETY: as promised by the caller.
    unsafe { loops_online_push_many(online, &t_s, point, 1, dim, update) }
}

/// Pushes `count` poses at once: times `timestamps_s[0..count]` (increasing, after the last
/// pose's) and coordinates `coords[0..count * dim]`, row-major (`dim` must be the handle's). All
/// or nothing: on an error no pose is added and the message names the first bad pose by its
/// index in the whole trajectory. `update` (may be NULL) receives what changed, all poses
/// together; offer it to a sampler with [`loops_sampler_offer`]: the candidates are the same as
/// pushing the poses one at a time and offering each.
///
/// # Safety
/// `online` is a live handle; `timestamps_s` and `coords` are valid for reading `count` and
/// `count * dim` doubles (NULL when `count` is 0); `update` is NULL or valid for writing a
/// [`LoopsUpdate`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_push_many(
    online: *mut LoopsOnline,
    timestamps_s: *const f64,
    coords: *const f64,
    count: usize,
    dim: usize,
    update: *mut LoopsUpdate,
) -> LoopsStatus {
    entry("loops_online_push_many", || {
        let online = unsafe { exclusive(online, "online") }?;
        if dim != online.inner.dim() {
            return Err(Failure::Parameter(format!(
                "poses of {dim} coordinates pushed to an engine of {} coordinates",
                online.inner.dim()
            )));
        }
        let coordinates = online.inner.coordinate_count(count)?;
        let timestamps_s = unsafe { slice(timestamps_s, count, "timestamps_s") }?;
        let coords = unsafe { slice(coords, coordinates, "coords") }?;
        let pushed = online.inner.push_many(timestamps_s, coords)?;
        unsafe { write_optional(update, LoopsUpdate::of(&pushed)) };
        online.last = Some(pushed);
        Ok(())
    })
}

/// Restarts from a corrected trajectory (the back end moved past poses after a loop closure):
/// `count` ≥ 2 poses, times `timestamps_s[0..count]` and coordinates `coords[0..count * dim]`
/// (the handle's `dim`), computed in one batch; later pushes continue from its last pose.
/// Component ids restart from 0; samplers reset themselves at their next offer.
///
/// # Safety
/// `online` is a live handle; `timestamps_s` and `coords` are valid for reading `count` and
/// `count * dim` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_rebuild(
    online: *mut LoopsOnline,
    timestamps_s: *const f64,
    coords: *const f64,
    count: usize,
) -> LoopsStatus {
    entry("loops_online_rebuild", || {
        let online = unsafe { exclusive(online, "online") }?;
        let dim = online.inner.dim();
        let coordinates = online.inner.coordinate_count(count)?;
        let timestamps_s = unsafe { slice(timestamps_s, count, "timestamps_s") }?;
        let coords = unsafe { slice(coords, coordinates, "coords") }?;
        let traj = Trajectory::new(timestamps_s.to_vec(), coords.to_vec(), dim)?;
        online.inner.rebuild(&traj)?;
        online.last = None;
        Ok(())
    })
}

/// Forgets every pose (ids restart too).
///
/// # Safety
/// `online` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_clear(online: *mut LoopsOnline) -> LoopsStatus {
    entry("loops_online_clear", || {
        let online = unsafe { exclusive(online, "online") }?;
        online.inner.clear();
        online.last = None;
        Ok(())
    })
}

/// Number of poses pushed (0 for NULL).
///
/// # Safety
/// `online` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_len(online: *const LoopsOnline) -> usize {
    getter(0, || unsafe { online.as_ref() }.map(|online| online.inner.len()))
}

/// Number of live loop components (0 for NULL).
///
/// # Safety
/// `online` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_component_count(online: *const LoopsOnline) -> usize {
    getter(0, || unsafe { online.as_ref() }.map(|online| online.inner.components().count()))
}

/// The live loop components by id, increasing: the first `min(capacity, n)` written to `out`
/// (NULL when `capacity` is 0), `n` to `*count`.
///
/// # Safety
/// `online` is a live handle; `out` is valid for writing `capacity` [`LoopsComponent`]s;
/// `count` is valid for writing a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_components(
    online: *const LoopsOnline,
    out: *mut LoopsComponent,
    capacity: usize,
    count: *mut usize,
) -> LoopsStatus {
    entry("loops_online_components", || {
        let online = unsafe { reference(online, "online") }?;
        let count = unsafe { exclusive(count, "count") }?;
        if capacity > 0 && out.is_null() {
            return Err(Failure::Null("out"));
        }
        let mut n = 0;
        for (_, component) in online.inner.components() {
            if n < capacity {
                // SAFETY: n < capacity, within the caller's buffer.
                unsafe { out.add(n).write(LoopsComponent::of(component)) };
            }
            n += 1;
        }
        *count = n;
        Ok(())
    })
}

/// The loop duration τ of pose `pose` so far, seconds, into `*out`.
///
/// # Safety
/// `online` is a live handle; `out` is valid for writing a double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_online_loop_duration(
    online: *const LoopsOnline,
    pose: usize,
    out: *mut f64,
) -> LoopsStatus {
    entry("loops_online_loop_duration", || {
        let online = unsafe { reference(online, "online") }?;
        let out = unsafe { exclusive(out, "out") }?;
        *out = online.inner.loop_duration_s(pose)?;
        Ok(())
    })
}

/// Fills `*options` with the library's defaults: σ_ρ at rate 1, no cap, a candidate at each
/// component's first appearance, no separation, seed 0.
///
/// # Safety
/// `options` is valid for writing a [`LoopsSamplerOptions`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_options_default(options: *mut LoopsSamplerOptions) -> LoopsStatus {
    entry("loops_sampler_options_default", || {
        let options = unsafe { exclusive(options, "options") }?;
        *options = LoopsSamplerOptions::of(&OnlineSamplerOptions::default());
        Ok(())
    })
}

/// Fills `*options` with the library's defaults: those of [`loops_sampler_options_default`]
/// and the first candidate at the edge, then improved at the closest approach
/// (`LOOPS_FIRST_OFFER_EDGE_THEN_CLOSEST`).
///
/// # Safety
/// `options` is valid for writing a [`LoopsSamplerOptionsV2`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_options_default_v2(options: *mut LoopsSamplerOptionsV2) -> LoopsStatus {
    entry("loops_sampler_options_default_v2", || {
        let options = unsafe { exclusive(options, "options") }?;
        *options = LoopsSamplerOptionsV2::of(&OnlineSamplerOptions::default());
        Ok(())
    })
}

/// Makes a candidate sampler with `*options` (NULL: the library's defaults, as
/// [`loops_sampler_options_default_v2`]); on success `*out` is a new handle for
/// [`loops_sampler_free`]. Read its candidates with [`loops_sampler_offer_v2`] and
/// [`loops_sampler_candidates_v2`] (the first version's refuse a first offer other than
/// `LOOPS_FIRST_OFFER_AT_EDGE`).
///
/// # Errors
/// As [`loops_sampler_new`], and a `first_offer` that is not one of [`LoopsFirstOffer`]'s
/// values.
///
/// # Safety
/// `options` is NULL or valid for reading a [`LoopsSamplerOptionsV2`]; `out` is valid for
/// writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_new_v2(
    options: *const LoopsSamplerOptionsV2,
    out: *mut *mut LoopsSampler,
) -> LoopsStatus {
    entry("loops_sampler_new_v2", || {
        let out = unsafe { exclusive(out, "out") }?;
        // SAFETY: NULL or a valid options struct, the caller's promise.
        let options = match unsafe { options.as_ref() } {
            Some(options) => options.to_core()?,
            None => OnlineSamplerOptions::default(),
        };
        let inner = OnlineSampler::new(options)?;
        *out = Box::into_raw(Box::new(LoopsSampler { inner, candidates: Vec::new() }));
        Ok(())
    })
}

/// Makes a candidate sampler with `*options` (NULL: the defaults); on success `*out` is a new
/// handle for [`loops_sampler_free`]. Its first candidates are offered at the edge of γ
/// (`LOOPS_FIRST_OFFER_AT_EDGE`), where a [`LoopsCandidate`] can name their pairs: for the
/// library's default, the closest approach as an improvement, use [`loops_sampler_new_v2`].
///
/// # Errors
/// [`LoopsStatus::InvalidParameter`] for a `cap_kind` that is not one of [`LoopsCapKind`]'s
/// values, and options the sampler refuses (a negative rate, a cap that is not positive).
///
/// # Safety
/// `options` is NULL or valid for reading a [`LoopsSamplerOptions`]; `out` is valid for
/// writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_new(
    options: *const LoopsSamplerOptions,
    out: *mut *mut LoopsSampler,
) -> LoopsStatus {
    entry("loops_sampler_new", || {
        let out = unsafe { exclusive(out, "out") }?;
        // SAFETY: NULL or a valid options struct, the caller's promise.
        let options = match unsafe { options.as_ref() } {
            Some(options) => options.to_core()?,
            None => LoopsSamplerOptions::of(&OnlineSamplerOptions::default()).to_core()?,
        };
        let inner = OnlineSampler::new(options)?;
        *out = Box::into_raw(Box::new(LoopsSampler { inner, candidates: Vec::new() }));
        Ok(())
    })
}

/// Frees a handle of [`loops_sampler_new`]; NULL does nothing.
///
/// # Safety
/// `sampler` is NULL or a handle of [`loops_sampler_new`] not yet freed; it is not used after.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_free(sampler: *mut LoopsSampler) {
    if !sampler.is_null() {
        // SAFETY: a handle of `loops_sampler_new` (a Box), freed once: the caller's promise.
        let handle = unsafe { Box::from_raw(sampler) };
        let _ = catch_unwind(AssertUnwindSafe(move || drop(handle)));
    }
}

/// Offers `online`'s last push to the sampler, which picks its loop-closure candidates: call it
/// after every push (or push_many), in order, once each. The first `min(capacity, n)` candidates
/// (by keyframe, component and pose) are written to `out` (NULL when `capacity` is 0) and `n`
/// to `*count`; all `n` stay readable with [`loops_sampler_candidates`] until the next offer.
/// Offered the pushes of another engine (a new one, even at a freed one's address), or of one
/// rebuilt or cleared, the sampler starts afresh: every component is new to it.
///
/// # Errors
/// [`LoopsStatus::InvalidParameter`] when `online` has not been pushed to since its last
/// rebuild or clear, or when its last push was already offered to this sampler.
///
/// # Safety
/// `sampler` and `online` are live handles; `out` is valid for writing `capacity`
/// [`LoopsCandidate`]s; `count` is valid for writing a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_offer(
    sampler: *mut LoopsSampler,
    online: *const LoopsOnline,
    out: *mut LoopsCandidate,
    capacity: usize,
    count: *mut usize,
) -> LoopsStatus {
    entry("loops_sampler_offer", || {
        let sampler = unsafe { exclusive(sampler, "sampler") }?;
        sampler.check_first_version("loops_sampler_offer_v2")?;
        // SAFETY: as promised by the caller.
        unsafe { offer_into(sampler, online, out, capacity, count, LoopsCandidate::of) }
    })
}

/// [`loops_sampler_offer`] for a sampler of any version, its candidates as [`LoopsCandidateV2`]:
/// the same order and count.
///
/// # Errors
/// As [`loops_sampler_offer`].
///
/// # Safety
/// `sampler` and `online` are live handles; `out` is valid for writing `capacity`
/// [`LoopsCandidateV2`]s; `count` is valid for writing a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_offer_v2(
    sampler: *mut LoopsSampler,
    online: *const LoopsOnline,
    out: *mut LoopsCandidateV2,
    capacity: usize,
    count: *mut usize,
) -> LoopsStatus {
    entry("loops_sampler_offer_v2", || {
        let sampler = unsafe { exclusive(sampler, "sampler") }?;
        // SAFETY: as promised by the caller.
        unsafe { offer_into(sampler, online, out, capacity, count, LoopsCandidateV2::of) }
    })
}

/// The body of the offers: `online`'s last push offered to `sampler`, its candidates written as
/// `T`.
///
/// # Safety
/// As [`loops_sampler_offer`], for `T`.
unsafe fn offer_into<T>(
    sampler: &mut LoopsSampler,
    online: *const LoopsOnline,
    out: *mut T,
    capacity: usize,
    count: *mut usize,
    convert: fn(&Candidate) -> T,
) -> Result<(), Failure> {
    let online = unsafe { reference(online, "online") }?;
    let count = unsafe { exclusive(count, "count") }?;
    if capacity > 0 && out.is_null() {
        return Err(Failure::Null("out"));
    }
    let Some(update) = &online.last else {
        return Err(Failure::Parameter(
            "nothing to offer: no pose was pushed since the engine was made, rebuilt or cleared".to_owned(),
        ));
    };
    sampler.candidates = sampler.inner.offer(&online.inner, update)?;
    for (k, candidate) in sampler.candidates.iter().take(capacity).enumerate() {
        // SAFETY: k < capacity, within the caller's buffer.
        unsafe { out.add(k).write(convert(candidate)) };
    }
    *count = sampler.candidates.len();
    Ok(())
}

impl LoopsSampler {
    /// Refuses a sampler whose candidates a [`LoopsCandidate`] cannot hold (a pair that ends
    /// before its keyframe, an improvement), naming the function that reads them.
    fn check_first_version(&self, instead: &str) -> Result<(), Failure> {
        let options = self.inner.options();
        if options.first_on_appearance && options.first_offer != FirstOffer::AtEdge {
            return Err(Failure::Parameter(format!(
                "this sampler's first offer is {}, whose candidates a LoopsCandidate cannot hold: read them with \
                 {instead}",
                options.first_offer
            )));
        }
        Ok(())
    }
}

/// The candidates of the sampler's last offer from index `offset` on: the first `min(capacity,
/// n − offset)` written to `out`, that number to `*written` (0 when `offset` ≥ n).
///
/// # Safety
/// `sampler` is a live handle; `out` is valid for writing `capacity` [`LoopsCandidate`]s;
/// `written` is valid for writing a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_candidates(
    sampler: *const LoopsSampler,
    offset: usize,
    out: *mut LoopsCandidate,
    capacity: usize,
    written: *mut usize,
) -> LoopsStatus {
    entry("loops_sampler_candidates", || {
        let sampler = unsafe { reference(sampler, "sampler") }?;
        sampler.check_first_version("loops_sampler_candidates_v2")?;
        // SAFETY: as promised by the caller.
        unsafe { candidates_into(sampler, offset, out, capacity, written, LoopsCandidate::of) }
    })
}

/// [`loops_sampler_candidates`] for a sampler of any version, as [`LoopsCandidateV2`].
///
/// # Safety
/// `sampler` is a live handle; `out` is valid for writing `capacity` [`LoopsCandidateV2`]s;
/// `written` is valid for writing a `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn loops_sampler_candidates_v2(
    sampler: *const LoopsSampler,
    offset: usize,
    out: *mut LoopsCandidateV2,
    capacity: usize,
    written: *mut usize,
) -> LoopsStatus {
    entry("loops_sampler_candidates_v2", || {
        let sampler = unsafe { reference(sampler, "sampler") }?;
        // SAFETY: as promised by the caller.
        unsafe { candidates_into(sampler, offset, out, capacity, written, LoopsCandidateV2::of) }
    })
}

/// The body of the candidate reads: from `offset` on, written as `T`.
///
/// # Safety
/// As [`loops_sampler_candidates`], for `T`.
unsafe fn candidates_into<T>(
    sampler: &LoopsSampler,
    offset: usize,
    out: *mut T,
    capacity: usize,
    written: *mut usize,
    convert: fn(&Candidate) -> T,
) -> Result<(), Failure> {
    let written = unsafe { exclusive(written, "written") }?;
    if capacity > 0 && out.is_null() {
        return Err(Failure::Null("out"));
    }
    let rest = sampler.candidates.get(offset..).unwrap_or(&[]);
    let n = rest.len().min(capacity);
    for (k, candidate) in rest[..n].iter().enumerate() {
        // SAFETY: k < capacity, within the caller's buffer.
        unsafe { out.add(k).write(convert(candidate)) };
    }
    *written = n;
    Ok(())
}

//! The C ABI called as C calls it: status codes and messages for every kind of bad input, NULL
//! pointers, buffers too small, and the candidates equal to those of the Rust API.
#![allow(unsafe_code)]

use std::ffi::{CStr, CString};
use std::ptr;

use inexact_loops::*;
use loops_core::{
    MetricSpec, Separation,
    online::{Cap, FirstOffer, OnlineLoops, OnlineSampler, OnlineSamplerOptions},
};

fn last_error() -> String {
    // SAFETY: the library's string, valid until its next call on this thread.
    unsafe { CStr::from_ptr(loops_last_error()) }.to_str().unwrap().to_owned()
}

/// A handle made with `metric`, `dim` and `gamma`; panics with the message on failure.
fn online(metric: &str, dim: usize, gamma: f64) -> *mut LoopsOnline {
    let metric = CString::new(metric).unwrap();
    let mut out = ptr::null_mut();
    let status = unsafe { loops_online_new(metric.as_ptr(), dim, gamma, &mut out) };
    assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
    assert!(!out.is_null());
    out
}

fn sampler(options: &LoopsSamplerOptions) -> *mut LoopsSampler {
    let mut out = ptr::null_mut();
    let status = unsafe { loops_sampler_new(options, &mut out) };
    assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
    out
}

fn default_options() -> LoopsSamplerOptions {
    let mut options = LoopsSamplerOptions {
        rate: f64::NAN,
        cap_kind: LoopsCapKind::None as u32,
        cap_value: 0.0,
        first_on_appearance: false,
        separation_path: 0.0,
        separation_time_s: 0.0,
        seed: 99,
    };
    assert_eq!(unsafe { loops_sampler_options_default(&mut options) }, LoopsStatus::Ok);
    options
}

/// A square driven three times, 1 m a pose: every lap revisits the first.
fn laps() -> (Vec<f64>, Vec<f64>) {
    let mut coords = Vec::new();
    for _ in 0..3 {
        for side in 0..4 {
            for k in 0..20 {
                let s = f64::from(k);
                let (x, y) = match side {
                    0 => (s, 0.0),
                    1 => (20.0, s),
                    2 => (20.0 - s, 20.0),
                    _ => (0.0, 20.0 - s),
                };
                coords.extend([x, y, 0.0]);
            }
        }
    }
    let times = (0..coords.len() / 3).map(|k| k as f64 * 0.5).collect();
    (times, coords)
}

#[test]
fn defaults_are_the_cores() {
    let options = default_options();
    let core = OnlineSamplerOptions::default();
    assert_eq!(options.rate, core.rate);
    assert_eq!(options.cap_kind, LoopsCapKind::None as u32);
    assert_eq!(options.first_on_appearance, core.first_on_appearance);
    assert_eq!((options.separation_path, options.separation_time_s), (0.0, 0.0));
    assert_eq!(options.seed, core.seed);
    assert!(!unsafe { CStr::from_ptr(loops_version()) }.to_str().unwrap().is_empty());
}

#[test]
fn bad_parameters_are_statuses_with_one_line_messages() {
    let mut out = ptr::null_mut();
    let metric = CString::new("euclidean").unwrap();
    assert_eq!(unsafe { loops_online_new(metric.as_ptr(), 3, f64::NAN, &mut out) }, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("NaN"), "{}", last_error());
    assert!(!last_error().contains('\n'));
    assert!(out.is_null());
    let unknown = CString::new("manhattan").unwrap();
    assert_eq!(unsafe { loops_online_new(unknown.as_ptr(), 3, 1.0, &mut out) }, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("manhattan"), "{}", last_error());
    let se3 = CString::new("se3(rotation_weight_m_per_rad=1)").unwrap();
    assert_ne!(unsafe { loops_online_new(se3.as_ptr(), 3, 1.0, &mut out) }, LoopsStatus::Ok);
    assert!(!last_error().is_empty());
    // NULL metric is euclidean.
    assert_eq!(unsafe { loops_online_new(ptr::null(), 2, 1.0, &mut out) }, LoopsStatus::Ok);
    assert_eq!(last_error(), "");
    unsafe { loops_online_free(out) };

    let options = LoopsSamplerOptions { rate: -1.0, ..default_options() };
    let mut s = ptr::null_mut();
    assert_eq!(unsafe { loops_sampler_new(&options, &mut s) }, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("rate"), "{}", last_error());
    let options = LoopsSamplerOptions { separation_path: -3.0, ..default_options() };
    assert_eq!(unsafe { loops_sampler_new(&options, &mut s) }, LoopsStatus::InvalidParameter);
    assert!(s.is_null());
    // NULL options are the defaults.
    assert_eq!(unsafe { loops_sampler_new(ptr::null(), &mut s) }, LoopsStatus::Ok);
    unsafe { loops_sampler_free(s) };
}

#[test]
fn null_pointers_are_refused_and_free_of_null_does_nothing() {
    let metric = CString::new("euclidean").unwrap();
    assert_eq!(unsafe { loops_online_new(metric.as_ptr(), 3, 1.0, ptr::null_mut()) }, LoopsStatus::NullPointer);
    assert_eq!(last_error(), "loops_online_new: out is NULL");
    let point = [0.0; 3];
    let status = unsafe { loops_online_push(ptr::null_mut(), 0.0, point.as_ptr(), 3, ptr::null_mut()) };
    assert_eq!(status, LoopsStatus::NullPointer);
    let o = online("euclidean", 3, 1.0);
    let status = unsafe { loops_online_push(o, 0.0, ptr::null(), 3, ptr::null_mut()) };
    assert_eq!(status, LoopsStatus::NullPointer);
    assert!(last_error().contains("coords"), "{}", last_error());
    let mut count = 0;
    let mut buffer = [LoopsComponent::default(); 2];
    assert_eq!(unsafe { loops_online_components(o, ptr::null_mut(), 4, &mut count) }, LoopsStatus::NullPointer);
    assert_eq!(
        unsafe { loops_online_components(o, buffer.as_mut_ptr(), 2, ptr::null_mut()) },
        LoopsStatus::NullPointer
    );
    assert_eq!(unsafe { loops_online_len(ptr::null()) }, 0);
    assert_eq!(unsafe { loops_online_component_count(ptr::null()) }, 0);
    let s = sampler(&default_options());
    let status = unsafe { loops_sampler_offer(s, ptr::null(), ptr::null_mut(), 0, &mut count) };
    assert_eq!(status, LoopsStatus::NullPointer);
    // Nothing pushed yet: nothing to offer.
    let status = unsafe { loops_sampler_offer(s, o, ptr::null_mut(), 0, &mut count) };
    assert_eq!(status, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("nothing to offer"), "{}", last_error());
    unsafe {
        loops_sampler_free(s);
        loops_online_free(o);
        loops_online_free(ptr::null_mut());
        loops_sampler_free(ptr::null_mut());
    }
}

#[test]
fn bad_poses_name_their_index_and_change_nothing() {
    let o = online("euclidean", 2, 1.0);
    let mut update = LoopsUpdate::default();
    let times = [0.0, 1.0, 2.0];
    let coords = [0.0, 0.0, 1.0, 0.0, 2.0, 0.0];
    assert_eq!(
        unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), 3, 2, &mut update) },
        LoopsStatus::Ok,
        "{}",
        last_error()
    );
    assert_eq!((update.first_pose, update.pose), (0, 2));
    // NaN coordinate of the fourth pose.
    let nan = [f64::NAN, 0.0];
    assert_eq!(unsafe { loops_online_push(o, 3.0, nan.as_ptr(), 2, ptr::null_mut()) }, LoopsStatus::InvalidTrajectory);
    assert!(last_error().contains('3') && last_error().contains("NaN"), "{}", last_error());
    // Time going back.
    let point = [3.0, 0.0];
    assert_eq!(
        unsafe { loops_online_push(o, 1.5, point.as_ptr(), 2, ptr::null_mut()) },
        LoopsStatus::InvalidTrajectory
    );
    assert!(last_error().contains("1.5"), "{}", last_error());
    // Wrong dimension.
    let wide = [3.0, 0.0, 0.0];
    assert_eq!(unsafe { loops_online_push(o, 3.0, wide.as_ptr(), 3, ptr::null_mut()) }, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("3 coordinates"), "{}", last_error());
    // A batch with a bad pose in the middle adds none of its poses.
    let times = [3.0, 4.0, 4.0];
    let coords = [3.0, 0.0, 4.0, 0.0, 5.0, 0.0];
    assert_eq!(
        unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), 3, 2, ptr::null_mut()) },
        LoopsStatus::InvalidTrajectory
    );
    assert!(last_error().contains('5'), "the pose is named by its index in the trajectory: {}", last_error());
    assert_eq!(unsafe { loops_online_len(o) }, 3);
    let mut tau = 0.0;
    assert_eq!(unsafe { loops_online_loop_duration(o, 7, &mut tau) }, LoopsStatus::IndexOutOfRange);
    // A rebuild needs two poses.
    assert_eq!(unsafe { loops_online_rebuild(o, times.as_ptr(), coords.as_ptr(), 1) }, LoopsStatus::InvalidTrajectory);
    assert_eq!(unsafe { loops_online_len(o) }, 3);
    unsafe { loops_online_free(o) };
}

/// The candidates of the C ABI, pose by pose, with a buffer of `capacity`.
fn c_candidates(options: &LoopsSamplerOptions, capacity: usize) -> Vec<LoopsCandidate> {
    let (times, coords) = laps();
    let o = online("euclidean", 3, 2.5);
    let s = sampler(options);
    let mut all = Vec::new();
    let mut buffer = vec![LoopsCandidate::default(); capacity];
    for (k, &t) in times.iter().enumerate() {
        let mut update = LoopsUpdate::default();
        let status = unsafe { loops_online_push(o, t, coords[3 * k..].as_ptr(), 3, &mut update) };
        assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
        assert_eq!(update.pose, k);
        let mut count = usize::MAX;
        let status = unsafe { loops_sampler_offer(s, o, buffer.as_mut_ptr(), capacity, &mut count) };
        assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
        all.extend_from_slice(&buffer[..count.min(capacity)]);
        // The rest, read from the sampler in chunks (of one when the buffer holds none).
        let mut offset = capacity;
        let mut chunk = vec![LoopsCandidate::default(); capacity.max(1)];
        while offset < count {
            let mut written = 0;
            let status = unsafe { loops_sampler_candidates(s, offset, chunk.as_mut_ptr(), chunk.len(), &mut written) };
            assert_eq!(status, LoopsStatus::Ok);
            assert!(written > 0);
            all.extend_from_slice(&chunk[..written]);
            offset += written;
        }
        // An update is offered once.
        let status = unsafe { loops_sampler_offer(s, o, buffer.as_mut_ptr(), capacity, &mut count) };
        assert_eq!(status, LoopsStatus::InvalidParameter);
        assert!(last_error().contains("already offered"), "{}", last_error());
    }
    assert_eq!(unsafe { loops_online_len(o) }, times.len());
    unsafe {
        loops_sampler_free(s);
        loops_online_free(o);
    }
    all
}

#[test]
fn candidates_equal_the_rust_apis_whatever_the_buffer() {
    let options = LoopsSamplerOptions {
        rate: 0.3,
        cap_kind: LoopsCapKind::PerMinute as u32,
        cap_value: 4.0,
        seed: 7,
        ..default_options()
    };
    let (times, coords) = laps();
    let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 3, 2.5).unwrap();
    let mut rust = OnlineSampler::new(OnlineSamplerOptions {
        rate: 0.3,
        cap: Cap::PerMinute(4.0),
        first_on_appearance: true,
        first_offer: FirstOffer::AtEdge,
        separation: Separation::NONE,
        seed: 7,
        ..OnlineSamplerOptions::default()
    })
    .unwrap();
    let mut expected = Vec::new();
    for (k, &t) in times.iter().enumerate() {
        let update = engine.push(t, &coords[3 * k..3 * k + 3]).unwrap();
        expected.extend(rust.offer(&engine, &update).unwrap().iter().map(|c| LoopsCandidate {
            keyframe: c.keyframe,
            j: c.pair[0],
            component: c.component,
            distance: c.distance,
            first: c.first,
        }));
    }
    assert!(expected.len() > 10 && expected.iter().any(|c| c.first), "{expected:?}");
    for capacity in [0, 1, 3, 64] {
        assert_eq!(c_candidates(&options, capacity), expected, "capacity {capacity}");
    }
}

#[test]
fn components_and_rebuild() {
    let (times, coords) = laps();
    let o = online("euclidean", 3, 2.5);
    let status = unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), times.len(), 3, ptr::null_mut()) };
    assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
    let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 3, 2.5).unwrap();
    engine.push_many(&times, &coords).unwrap();
    let n = unsafe { loops_online_component_count(o) };
    assert_eq!(n, engine.components().count());
    let mut count = 0;
    assert_eq!(unsafe { loops_online_components(o, ptr::null_mut(), 0, &mut count) }, LoopsStatus::Ok);
    assert_eq!(count, n);
    let mut buffer = vec![LoopsComponent::default(); n];
    assert_eq!(unsafe { loops_online_components(o, buffer.as_mut_ptr(), n, &mut count) }, LoopsStatus::Ok);
    for (c, (id, core)) in buffer.iter().zip(engine.components()) {
        assert_eq!(
            (c.id, c.pair_count, c.area_s2, c.closest_distance),
            (id, core.pair_count, core.area_s2, core.closest_distance)
        );
    }
    // Rebuild from the first half, then push the rest: the same components.
    let half = times.len() / 2;
    let status = unsafe { loops_online_rebuild(o, times.as_ptr(), coords.as_ptr(), half) };
    assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
    assert_eq!(unsafe { loops_online_len(o) }, half);
    let status = unsafe {
        loops_online_push_many(
            o,
            times[half..].as_ptr(),
            coords[3 * half..].as_ptr(),
            times.len() - half,
            3,
            ptr::null_mut(),
        )
    };
    assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
    assert_eq!(unsafe { loops_online_component_count(o) }, n);
    let mut tau = 0.0;
    assert_eq!(unsafe { loops_online_loop_duration(o, 0, &mut tau) }, LoopsStatus::Ok);
    assert_eq!(tau, engine.loop_duration_s(0).unwrap());
    assert_eq!(unsafe { loops_online_clear(o) }, LoopsStatus::Ok);
    assert_eq!(unsafe { loops_online_len(o) }, 0);
    unsafe { loops_online_free(o) };
}

#[test]
fn a_cap_kind_outside_the_enum_is_refused() {
    for cap_kind in [3, 7, u32::MAX] {
        let options = LoopsSamplerOptions { cap_kind, cap_value: 1.0, ..default_options() };
        let mut s = ptr::null_mut();
        assert_eq!(unsafe { loops_sampler_new(&options, &mut s) }, LoopsStatus::InvalidParameter);
        assert!(last_error().contains(&format!("cap_kind = {cap_kind}")), "{}", last_error());
        assert!(s.is_null());
    }
    for kind in [LoopsCapKind::None, LoopsCapKind::PerMinute, LoopsCapKind::PerMetre] {
        let s = sampler(&LoopsSamplerOptions { cap_kind: kind as u32, cap_value: 1.0, ..default_options() });
        unsafe { loops_sampler_free(s) };
    }
}

#[test]
fn dimensions_and_counts_beyond_the_limits_are_refused_before_any_read() {
    let mut out = ptr::null_mut();
    for dim in [1 << 62, usize::MAX, OnlineLoops::MAX_DIM + 1] {
        assert_eq!(unsafe { loops_online_new(ptr::null(), dim, 1.0, &mut out) }, LoopsStatus::InvalidParameter);
        assert!(last_error().contains(&format!("dim = {dim}")), "{}", last_error());
        assert!(out.is_null());
    }
    // The largest dimension is an engine that works.
    let widest = OnlineLoops::MAX_DIM;
    let o = online("euclidean", widest, 1.0);
    let point = vec![0.5; widest];
    assert_eq!(unsafe { loops_online_push(o, 0.0, point.as_ptr(), widest, ptr::null_mut()) }, LoopsStatus::Ok);
    unsafe { loops_online_free(o) };
    // Counts whose coordinates would pass the end of memory are refused without reading them
    // (the buffers here hold one pose).
    let o = online("euclidean", 3, 1.0);
    let (times, coords) = ([0.0], [0.0; 3]);
    for count in [1 << 61, usize::MAX / 3 + 1, usize::MAX] {
        let status = unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), count, 3, ptr::null_mut()) };
        assert_eq!(status, LoopsStatus::InvalidTrajectory, "{count}");
        assert!(last_error().contains(&count.to_string()), "{}", last_error());
        let status = unsafe { loops_online_rebuild(o, times.as_ptr(), coords.as_ptr(), count) };
        assert_eq!(status, LoopsStatus::InvalidTrajectory, "{count}");
    }
    assert_eq!(unsafe { loops_online_len(o) }, 0);
    unsafe { loops_online_free(o) };
}

/// The candidates of a fresh sampler offered one push of `times` and `coords` (2-D) to a fresh
/// engine.
fn fresh_candidates(times: &[f64], coords: &[f64]) -> Vec<LoopsCandidate> {
    let o = online("euclidean", 2, 1.0);
    let s = sampler(&default_options());
    let pushed = unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), times.len(), 2, ptr::null_mut()) };
    assert_eq!(pushed, LoopsStatus::Ok, "{}", last_error());
    let mut buffer = [LoopsCandidate::default(); 16];
    let mut count = 0;
    assert_eq!(unsafe { loops_sampler_offer(s, o, buffer.as_mut_ptr(), 16, &mut count) }, LoopsStatus::Ok);
    unsafe {
        loops_sampler_free(s);
        loops_online_free(o);
    }
    buffer[..count].to_vec()
}

#[test]
fn an_engine_made_where_a_freed_one_was_is_a_new_engine_to_a_sampler() {
    let times = [0.0, 1.0, 2.0, 3.0];
    let coords = [0.0, 0.0, 0.2, 0.0, 5.0, 0.0, 0.1, 0.0];
    let expected = fresh_candidates(&times, &coords);
    assert!(expected.iter().any(|c| c.first), "{expected:?}");
    let s = sampler(&default_options());
    let mut buffer = [LoopsCandidate::default(); 16];
    let (mut previous, mut reused) = (ptr::null_mut(), 0);
    for _ in 0..32 {
        let o = online("euclidean", 2, 1.0);
        reused += usize::from(o == previous);
        let pushed =
            unsafe { loops_online_push_many(o, times.as_ptr(), coords.as_ptr(), times.len(), 2, ptr::null_mut()) };
        assert_eq!(pushed, LoopsStatus::Ok, "{}", last_error());
        let mut count = 0;
        let status = unsafe { loops_sampler_offer(s, o, buffer.as_mut_ptr(), 16, &mut count) };
        assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
        // Every engine is new to the sampler: its components are served afresh.
        assert_eq!(&buffer[..count], &expected[..]);
        unsafe { loops_online_free(o) };
        previous = o;
    }
    unsafe { loops_sampler_free(s) };
    // The allocator gave a freed engine's address to the next one at least once (else this test
    // proves nothing about addresses).
    assert!(reused > 0, "no engine was made at a freed engine's address");
}

/// A road east, a detour, and a road north that passes its start 3 m off, 0.5 m a pose: the
/// component of the second road appears at the edge of γ = 6, closest 3 m off.
fn pass_by() -> (Vec<f64>, Vec<f64>) {
    let mut coords = Vec::new();
    let mut leg = |from: [f64; 2], to: [f64; 2], steps: usize| {
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            coords.extend([from[0] + f * (to[0] - from[0]), from[1] + f * (to[1] - from[1]), 0.0]);
        }
    };
    leg([0.5, 0.0], [0.0, 0.0], 1);
    leg([0.0, 0.0], [100.0, 0.0], 200);
    leg([100.0, 0.0], [100.0, -50.0], 100);
    leg([100.0, -50.0], [-3.0, -50.0], 206);
    leg([-3.0, -50.0], [-3.0, 50.0], 200);
    let times = (0..coords.len() / 3).map(|k| k as f64 * 0.5).collect();
    (times, coords)
}

#[test]
fn the_second_version_reads_the_improvements() {
    // Its defaults are the core's.
    let mut options = LoopsSamplerOptionsV2 { base: default_options(), first_offer: 99 };
    assert_eq!(unsafe { loops_sampler_options_default_v2(&mut options) }, LoopsStatus::Ok);
    assert_eq!(options.base, default_options());
    assert_eq!(options.first_offer, LoopsFirstOffer::EdgeThenClosest as u32);
    let core = OnlineSamplerOptions::default();
    assert_eq!(core.first_offer, FirstOffer::EdgeThenClosest);
    // A value outside the enum is refused.
    let mut s = ptr::null_mut();
    let bad = LoopsSamplerOptionsV2 { first_offer: 7, ..options };
    assert_eq!(unsafe { loops_sampler_new_v2(&bad, &mut s) }, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("first_offer = 7"), "{}", last_error());
    assert!(s.is_null());
    // Its candidates are the Rust API's, improvements included.
    options.base = LoopsSamplerOptions { rate: 0.0, separation_path: 50.0, ..options.base };
    let (times, coords) = pass_by();
    let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 3, 6.0).unwrap();
    let mut rust =
        OnlineSampler::new(OnlineSamplerOptions { rate: 0.0, separation: Separation::path(50.0), ..core }).unwrap();
    let o = online("euclidean", 3, 6.0);
    assert_eq!(unsafe { loops_sampler_new_v2(&options, &mut s) }, LoopsStatus::Ok, "{}", last_error());
    let (mut expected, mut found) = (Vec::new(), Vec::new());
    let mut buffer = [LoopsCandidateV2::default(); 1];
    for (k, &t) in times.iter().enumerate() {
        let update = engine.push(t, &coords[3 * k..3 * k + 3]).unwrap();
        expected.extend(rust.offer(&engine, &update).unwrap());
        assert_eq!(unsafe { loops_online_push(o, t, coords[3 * k..].as_ptr(), 3, ptr::null_mut()) }, LoopsStatus::Ok);
        let mut count = 0;
        let status = unsafe { loops_sampler_offer_v2(s, o, buffer.as_mut_ptr(), 1, &mut count) };
        assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
        found.extend_from_slice(&buffer[..count.min(1)]);
        for offset in 1..count {
            let mut written = 0;
            let status = unsafe { loops_sampler_candidates_v2(s, offset, buffer.as_mut_ptr(), 1, &mut written) };
            assert_eq!((status, written), (LoopsStatus::Ok, 1));
            found.push(buffer[0]);
        }
        // The first version's read cannot hold them, and says which to use.
        let mut old = LoopsCandidate::default();
        let status = unsafe { loops_sampler_candidates(s, 0, &mut old, 1, &mut count) };
        assert_eq!(status, LoopsStatus::InvalidParameter);
        assert!(last_error().contains("loops_sampler_candidates_v2"), "{}", last_error());
    }
    assert_eq!(expected.len(), 2, "the edge, then the closest approach: {expected:?}");
    let as_v2: Vec<LoopsCandidateV2> = expected
        .iter()
        .map(|c| LoopsCandidateV2 {
            keyframe: c.keyframe,
            j: c.pair[0],
            k: c.pair[1],
            component: c.component,
            distance: c.distance,
            first: c.first,
            improves: c.improves.is_some(),
            improves_j: c.improves.map_or(0, |p| p[0]),
            improves_k: c.improves.map_or(0, |p| p[1]),
        })
        .collect();
    assert_eq!(found, as_v2);
    let [edge, closest] = [found[0], found[1]];
    assert!(edge.first && edge.distance > 5.5 && !edge.improves, "{edge:?}");
    assert!(!closest.first && closest.improves && (closest.distance - 3.0).abs() < 1e-9, "{closest:?}");
    assert_eq!((closest.improves_j, closest.improves_k), (edge.j, edge.k));
    assert!(closest.k < closest.keyframe);
    unsafe {
        loops_sampler_free(s);
        loops_online_free(o);
    }
}

#[test]
fn the_first_version_offers_at_the_edge() {
    // Its candidates name their pair by the keyframe: a sampler of `loops_sampler_new`, with
    // options or NULL, offers its first candidates at the edge and no improvement.
    let (times, coords) = pass_by();
    let base = LoopsSamplerOptions { rate: 0.0, separation_path: 50.0, ..default_options() };
    let options = LoopsSamplerOptionsV2 { base, first_offer: LoopsFirstOffer::AtEdge as u32 };
    for made in [0, 1] {
        let o = online("euclidean", 3, 6.0);
        let mut s = ptr::null_mut();
        let status = if made == 0 {
            unsafe { loops_sampler_new(&base, &mut s) }
        } else {
            unsafe { loops_sampler_new_v2(&options, &mut s) }
        };
        assert_eq!(status, LoopsStatus::Ok);
        let mut all = Vec::new();
        for (k, &t) in times.iter().enumerate() {
            assert_eq!(
                unsafe { loops_online_push(o, t, coords[3 * k..].as_ptr(), 3, ptr::null_mut()) },
                LoopsStatus::Ok
            );
            let mut buffer = [LoopsCandidate::default(); 4];
            let mut count = 0;
            let status = unsafe { loops_sampler_offer(s, o, buffer.as_mut_ptr(), 4, &mut count) };
            assert_eq!(status, LoopsStatus::Ok, "{}", last_error());
            all.extend_from_slice(&buffer[..count]);
        }
        assert_eq!(all.len(), 1, "{all:?}");
        assert!(all[0].first && all[0].distance > 5.5, "{all:?}");
        unsafe {
            loops_sampler_free(s);
            loops_online_free(o);
        }
    }
    // The first version's offer refuses a sampler whose first offer waits, and changes nothing.
    let o = online("euclidean", 3, 6.0);
    let mut s = ptr::null_mut();
    assert_eq!(unsafe { loops_sampler_new_v2(ptr::null(), &mut s) }, LoopsStatus::Ok);
    assert_eq!(unsafe { loops_online_push(o, 0.0, [0.0; 3].as_ptr(), 3, ptr::null_mut()) }, LoopsStatus::Ok);
    let mut count = 0;
    let status = unsafe { loops_sampler_offer(s, o, ptr::null_mut(), 0, &mut count) };
    assert_eq!(status, LoopsStatus::InvalidParameter);
    assert!(last_error().contains("edge-then-closest"), "{}", last_error());
    assert_eq!(unsafe { loops_sampler_offer_v2(s, o, ptr::null_mut(), 0, &mut count) }, LoopsStatus::Ok);
    unsafe {
        loops_sampler_free(s);
        loops_online_free(o);
    }
}

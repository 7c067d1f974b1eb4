//! The scene while the robot drives: what the online engine reports at each keyframe, as the
//! messages of a live stream on the topics and in the schemas of the scene's MCAP file
//! ([`SCENE_TOPICS`]), built by the same code. A [`LiveScene`] holds the log's poses; at each
//! keyframe, [`LiveScene::keyframe`] turns the engine's [`Update`] and the sampler's
//! [`Candidate`]s into the messages of [`LIVE_TOPICS`] and keeps the candidates' pairs;
//! [`LiveScene::plane`] gives the (t, t′) plane with them at the end, drawn as the file's. Sending them is the caller's (`loops replay --serve` serves them over
//! Foxglove's WebSocket protocol): this crate stays free of a network stack.

use loops_core::online::{Candidate, OnlineLoops, Update};

use foxglove::messages::{PosesInFrame, RawImage, SceneEntityDeletion, SceneUpdate, Timestamp, scene_entity_deletion};

use crate::cdr_write::RosTime;
use crate::scene::{
    MARKER_ARRAY_SCHEMA, Marker, SCENE_FRAME, SCENE_TOPICS, SceneComponent, SceneTopic, candidate_marker,
    candidates_entity, component_deletions, component_entity, component_markers, foxglove_schema, loops_plane,
    marker_array, path_markers, plane_raw_image, poses_in_frame, protobuf, tau_entity, tau_rgba,
};

/// The live stream sends the (t, t′) plane each time the poses pushed pass a multiple of this
/// many (and [`LiveScene::plane`] at the end): the image is made anew from the engine's
/// snapshot, O(runs + poses + pixels), so not at every keyframe.
pub const LIVE_PLANE_POSES: usize = 100;

/// The topics of the live stream, in channel order: those of [`SCENE_TOPICS`], under the same
/// names and schemas. Each keyframe sends one message on each, in this order, but the plane,
/// sent every [`LIVE_PLANE_POSES`] poses.
pub const LIVE_TOPICS: [SceneTopic; 6] = [
    SceneTopic { holds: "every pose pushed so far, position and orientation", ..SCENE_TOPICS[0] },
    SceneTopic {
        holds: "the entity `tau/<log>`: the path so far coloured by τ so far (red = the longest)",
        ..SCENE_TOPICS[1]
    },
    SceneTopic {
        holds: "what the keyframe changed: a deletion of `component/<id>` per component merged into another, \
                and the entity `component/<id>` of each component created, extended or merged into, as it is now; \
                an empty update when nothing changed",
        ..SCENE_TOPICS[2]
    },
    SceneTopic {
        holds: "the entity `candidates/<pose>` of the keyframe's candidates, one line each, with their pairs and \
                components as JSON metadata (`pairs`: [[keyframe, j], ...], `components`); an empty update \
                when there are none",
        ..SCENE_TOPICS[3]
    },
    SceneTopic {
        holds: "the (t, t′) plane of the poses so far, rgb8 (t to the right, t′ up, each component in its colour, \
                the candidates sent so far white), each time the poses pass a multiple of 100 (LIVE_PLANE_POSES) and at the end",
        ..SCENE_TOPICS[4]
    },
    SceneTopic {
        holds: "the same for RViz (ROS 2 CDR), a MarkerArray a keyframe: namespaces trajectory and tau (id 0, \
                the path so far), components (3 markers each, DELETE for one merged into another), candidates \
                (id = the keyframe's pose, one line a candidate)",
        ..SCENE_TOPICS[5]
    },
];

/// The channels of [`LIVE_TOPICS`] by role.
const TRAJECTORY: usize = 0;
const PLANE: usize = 4;
const MARKERS: usize = 5;

/// The schema of a channel of the live stream.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct LiveChannel {
    /// Its topic.
    pub topic: &'static str,
    /// The encoding of its messages (`protobuf`).
    pub message_encoding: &'static str,
    /// Its schema's name (`foxglove.SceneUpdate`).
    pub schema_name: String,
    /// Its schema's encoding (`protobuf`).
    pub schema_encoding: String,
    /// Its schema: a serialized protobuf `FileDescriptorSet`.
    pub schema_data: Vec<u8>,
}

/// A message of the live stream.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct LiveMessage {
    /// Its channel: an index into [`LIVE_TOPICS`] and [`LiveScene::channels`].
    pub channel: usize,
    /// The keyframe's time, ns since the epoch (`None` for a time before 1970 or after 2038,
    /// which the messages' timestamps cannot hold: they are 0 then).
    pub log_time_ns: Option<u64>,
    /// The message, encoded.
    pub data: Vec<u8>,
}

/// The poses of a log being replayed, to draw what the online engine reports on them, and the
/// pairs of the candidates sent so far, for the plane; see the [module](self).
#[derive(Debug, Clone, PartialEq)]
pub struct LiveScene {
    name: String,
    frame_id: String,
    positions: Vec<[f64; 3]>,
    orientations_xyzw: Option<Vec<[f64; 4]>>,
    /// The pose pairs of every candidate of [`LiveScene::keyframe`] so far, in order.
    pairs: Vec<[usize; 2]>,
}

impl LiveScene {
    /// The scene of the log `name` whose poses are at `positions` (and `orientations_xyzw`,
    /// when the log has them), in the order they will be pushed, in frame [`SCENE_FRAME`].
    ///
    /// # Errors
    /// [`loops_core::Error::RowCountMismatch`] when `orientations_xyzw` has not one row per
    /// position.
    pub fn new(
        name: &str,
        positions: Vec<[f64; 3]>,
        orientations_xyzw: Option<Vec<[f64; 4]>>,
    ) -> loops_core::Result<Self> {
        let mut scene = Self {
            name: name.to_owned(),
            frame_id: SCENE_FRAME.to_owned(),
            positions: Vec::new(),
            orientations_xyzw: None,
            pairs: Vec::new(),
        };
        scene.set_poses(positions, orientations_xyzw)?;
        Ok(scene)
    }

    /// Replaces the scene's poses by `positions` (and `orientations_xyzw`): those pushed so far,
    /// when they come as the robot drives rather than from a log read first. The candidates'
    /// pairs are kept.
    ///
    /// # Errors
    /// [`loops_core::Error::RowCountMismatch`] as [`LiveScene::new`]; the scene is unchanged.
    pub fn set_poses(
        &mut self,
        positions: Vec<[f64; 3]>,
        orientations_xyzw: Option<Vec<[f64; 4]>>,
    ) -> loops_core::Result<()> {
        if let Some(rows) = orientations_xyzw.as_ref().map(Vec::len).filter(|&rows| rows != positions.len()) {
            return Err(loops_core::Error::RowCountMismatch {
                first: "positions",
                first_rows: positions.len(),
                second: "orientations",
                second_rows: rows,
            });
        }
        (self.positions, self.orientations_xyzw) = (positions, orientations_xyzw);
        Ok(())
    }

    /// The channels of the stream, one per topic of [`LIVE_TOPICS`], in order: Foxglove's
    /// schemas in protobuf, the `MarkerArray` in CDR with its `ros2msg` schema.
    pub fn channels() -> Vec<LiveChannel> {
        LIVE_TOPICS
            .iter()
            .map(|topic| {
                let (schema_name, schema_encoding, schema_data) = match topic.schema {
                    "foxglove.PosesInFrame" => foxglove_schema::<PosesInFrame>(),
                    "foxglove.RawImage" => foxglove_schema::<RawImage>(),
                    "foxglove.SceneUpdate" => foxglove_schema::<SceneUpdate>(),
                    ros => (ros.to_owned(), "ros2msg".to_owned(), MARKER_ARRAY_SCHEMA.as_bytes().to_vec()),
                };
                let message_encoding = if schema_encoding == "ros2msg" { "cdr" } else { "protobuf" };
                LiveChannel { topic: topic.topic, message_encoding, schema_name, schema_encoding, schema_data }
            })
            .collect()
    }

    /// The (t, t′) plane of the poses `engine` holds, as the message of the plane's channel
    /// (`None` before the second pose), drawn as the scene's file draws it: each component in
    /// its colour, the pixels of the candidates sent so far (and their mirrors) white.
    /// O(runs + poses + candidates + pixels).
    ///
    /// # Errors
    /// What [`OnlineLoops::to_loops`] returns ([`loops_core::Error::OutOfMemory`],
    /// [`loops_core::Error::Interrupted`]).
    pub fn plane(&self, engine: &OnlineLoops) -> loops_core::Result<Option<LiveMessage>> {
        if engine.len() < 2 {
            return Ok(None);
        }
        let stamp = RosTime::of_seconds(engine.timestamps_s()[engine.len() - 1]);
        // Pairs of a longer run than the engine's (another engine's) are left out.
        let pairs: Vec<[usize; 2]> = self.pairs.iter().copied().filter(|p| p[0].max(p[1]) < engine.len()).collect();
        let image = plane_raw_image(Some(timestamp(stamp)), &loops_plane(&engine.to_loops()?, &pairs)?);
        let data = protobuf(&image).expect("a Vec holds any message");
        Ok(Some(LiveMessage { channel: PLANE, log_time_ns: stamp.map(|s| s.ns()), data }))
    }

    /// The messages of the keyframe that `update` reports (`engine`'s last push), with the
    /// `candidates` the sampler offered for it: one per topic of [`LIVE_TOPICS`], in order (see
    /// there), the plane only when the poses pass a multiple of [`LIVE_PLANE_POSES`]. The
    /// candidates' pairs are kept for the plane. O(poses
    /// pushed so far + cells of the changed components' stretches), and [`LiveScene::plane`]'s
    /// with the plane.
    ///
    /// # Errors
    /// [`loops_core::Error::IndexOutOfRange`] when `engine` holds more poses than the scene, or
    /// `update` or `candidates` name a pose it does not hold.
    ///
    /// # Examples
    /// ```
    /// use loops_core::online::{OnlineLoops, OnlineSampler, OnlineSamplerOptions};
    /// use loops_core::MetricSpec;
    /// let square = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
    /// let positions: Vec<[f64; 3]> = (0..8).map(|i| [square[i % 4][0], square[i % 4][1], 0.0]).collect();
    /// let mut scene = loops_io::LiveScene::new("square", positions.clone(), None)?;
    /// let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 2, 1.0)?;
    /// let mut sampler = OnlineSampler::new(OnlineSamplerOptions::default())?;
    /// for (k, p) in positions.iter().enumerate() {
    ///     let update = engine.push(k as f64, &p[..2])?;
    ///     let candidates = sampler.offer(&engine, &update)?;
    ///     let messages = scene.keyframe(&engine, &update, &candidates)?;
    ///     assert_eq!(messages.len(), loops_io::LIVE_TOPICS.len() - 1); // the plane: every 100 poses
    ///     assert_eq!(messages.last().unwrap().channel, 5); // the MarkerArray
    /// }
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn keyframe(
        &mut self,
        engine: &OnlineLoops,
        update: &Update,
        candidates: &[Candidate],
    ) -> loops_core::Result<Vec<LiveMessage>> {
        let n = engine.len();
        if n > self.positions.len() || update.pose >= n {
            let index = n.max(update.pose + 1) - 1;
            return Err(loops_core::Error::IndexOutOfRange { index, len: self.positions.len().min(n) });
        }
        let positions = &self.positions[..n];
        let t_s = engine.timestamps_s()[update.pose];
        let stamp = RosTime::of_seconds(t_s);
        let timestamp = Some(timestamp(stamp));
        let frame_id = &self.frame_id;
        let name = self.name.as_str();

        let orientations = self.orientations_xyzw.as_deref().map(|q| &q[..n]);
        let trajectory = poses_in_frame(frame_id, timestamp, positions, orientations);

        let loop_duration_s =
            (0..n).map(|pose| engine.loop_duration_s(pose)).collect::<loops_core::Result<Vec<_>>>()?;
        let max_tau = loop_duration_s.iter().copied().fold(0.0, f64::max);
        let tau = SceneUpdate {
            deletions: Vec::new(),
            entities: vec![tau_entity(frame_id, timestamp, name, positions, &loop_duration_s, max_tau)],
        };

        let tau_colors: Vec<[f64; 4]> = loop_duration_s.iter().map(|&t| tau_rgba(t, max_tau)).collect();
        let mut markers: Vec<Marker<'_>> = path_markers(0, positions, &tau_colors).into();
        markers.extend(update.merged.iter().flat_map(|m| component_deletions(m.retired as usize)));

        let deletions = update
            .merged
            .iter()
            .map(|m| SceneEntityDeletion {
                timestamp,
                r#type: scene_entity_deletion::Type::MatchingId as i32,
                id: format!("component/{}", m.retired),
            })
            .collect();
        let mut changed: Vec<u32> = (update.created.iter().chain(&update.extended).copied())
            .chain(update.merged.iter().map(|m| m.survivor))
            .map(|id| engine.resolve(id))
            .collect();
        changed.sort_unstable();
        changed.dedup();
        let entities = changed
            .into_iter()
            .filter_map(|id| engine.component(id))
            .map(|c| {
                let component = SceneComponent::from(c);
                markers.extend(component_markers(&component, [positions, positions]));
                component_entity(frame_id, timestamp, [positions, positions], [name, name], &component)
            })
            .collect();
        let components = SceneUpdate { deletions, entities };

        let mut points = Vec::with_capacity(2 * candidates.len());
        for c in candidates {
            for pose in [c.pair[1], c.pair[0]] {
                points.push(*positions.get(pose).ok_or(loops_core::Error::IndexOutOfRange { index: pose, len: n })?);
            }
        }
        let entities = if candidates.is_empty() {
            Vec::new()
        } else {
            let pairs: Vec<[usize; 2]> = candidates.iter().map(|c| [c.pair[1], c.pair[0]]).collect();
            self.pairs.extend(&pairs);
            let ids: Vec<u32> = candidates.iter().map(|c| c.component).collect();
            let metadata = vec![
                ("pose", update.pose.to_string()),
                ("count", candidates.len().to_string()),
                ("pairs", serde_json::to_string(&pairs).expect("numbers")),
                ("components", serde_json::to_string(&ids).expect("numbers")),
            ];
            markers.push(candidate_marker(update.pose, points.clone()));
            vec![candidates_entity(frame_id, timestamp, format!("candidates/{}", update.pose), points, metadata)]
        };
        let candidates = SceneUpdate { deletions: Vec::new(), entities };

        let log_time_ns = stamp.map(|s| s.ns());
        // Encoding into a `Vec` cannot fail: it grows to fit.
        let encoded = [protobuf(&trajectory), protobuf(&tau), protobuf(&components), protobuf(&candidates)];
        let mut messages: Vec<LiveMessage> = encoded
            .into_iter()
            .enumerate()
            .map(|(channel, data)| LiveMessage {
                channel: TRAJECTORY + channel,
                log_time_ns,
                data: data.expect("a Vec holds any message"),
            })
            .collect();
        // The plane when the poses pass a multiple of LIVE_PLANE_POSES.
        if update.first_pose / LIVE_PLANE_POSES < n / LIVE_PLANE_POSES {
            messages.extend(self.plane(engine)?);
        }
        let data = marker_array(frame_id, stamp.unwrap_or(RosTime { sec: 0, nanosec: 0 }), &markers);
        messages.push(LiveMessage { channel: MARKERS, log_time_ns, data });
        Ok(messages)
    }
}

/// `stamp` as a Foxglove timestamp (0 for none).
fn timestamp(stamp: Option<RosTime>) -> Timestamp {
    stamp.map_or(Timestamp::new(0, 0), |s| Timestamp::new(s.sec.unsigned_abs(), s.nanosec))
}

#[cfg(test)]
mod tests {
    use foxglove::Decode;
    use loops_core::MetricSpec;

    use super::*;

    #[test]
    fn a_keyframe_past_the_scene_poses_is_an_error() {
        let mut scene = LiveScene::new("two", vec![[0.0; 3], [1.0, 0.0, 0.0]], None).unwrap();
        let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 1, 0.5).unwrap();
        for t in 0..2 {
            let update = engine.push(f64::from(t), &[f64::from(t)]).unwrap();
            assert_eq!(scene.keyframe(&engine, &update, &[]).unwrap().len(), LIVE_TOPICS.len() - 1);
        }
        let update = engine.push(2.0, &[2.0]).unwrap();
        let error = scene.keyframe(&engine, &update, &[]).unwrap_err();
        assert!(matches!(error, loops_core::Error::IndexOutOfRange { index: 2, len: 2 }), "{error}");
        let rows = LiveScene::new("bad", vec![[0.0; 3]; 2], Some(vec![[0.0, 0.0, 0.0, 1.0]]));
        assert!(matches!(rows, Err(loops_core::Error::RowCountMismatch { second_rows: 1, .. })));
    }

    #[test]
    fn the_plane_comes_every_hundred_poses_with_the_markers_at_every_keyframe() {
        let positions: Vec<[f64; 3]> = (0..250).map(|k| [f64::from(k % 10), 0.0, 0.0]).collect();
        let mut scene = LiveScene::new("back and forth", positions.clone(), None).unwrap();
        let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 1, 0.5).unwrap();
        let mut planes = Vec::new();
        for (k, p) in positions.iter().enumerate() {
            let update = engine.push(k as f64, &p[..1]).unwrap();
            let messages = scene.keyframe(&engine, &update, &[]).unwrap();
            let channels: Vec<usize> = messages.iter().map(|m| m.channel).collect();
            if channels.contains(&PLANE) {
                planes.push(k + 1);
                assert_eq!(channels, [0, 1, 2, 3, PLANE, MARKERS]);
            } else {
                assert_eq!(channels, [0, 1, 2, 3, MARKERS]);
            }
        }
        assert_eq!(planes, [100, 200]);
        let last = scene.plane(&engine).unwrap().unwrap();
        let image = RawImage::decode(last.data.as_slice()).unwrap();
        assert_eq!((image.encoding.as_str(), image.width, image.height), ("rgb8", 250, 250));
        assert_eq!(last.log_time_ns, Some(249_000_000_000));
        let one = LiveScene::new("one", vec![[0.0; 3]], None).unwrap();
        let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 1, 0.5).unwrap();
        engine.push(0.0, &[0.0]).unwrap();
        assert!(one.plane(&engine).unwrap().is_none(), "no plane before the second pose");
    }

    #[test]
    fn the_plane_draws_every_candidate_sent_white() {
        use loops_core::online::{OnlineSampler, OnlineSamplerOptions};
        let positions: Vec<[f64; 3]> = (0..120).map(|k| [f64::from(k % 10), 0.0, 0.0]).collect();
        let mut scene = LiveScene::new("back and forth", positions.clone(), None).unwrap();
        let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 1, 0.5).unwrap();
        let mut sampler = OnlineSampler::new(OnlineSamplerOptions::default()).unwrap();
        let mut sent = std::collections::BTreeSet::new();
        for (k, p) in positions.iter().enumerate() {
            let update = engine.push(k as f64, &p[..1]).unwrap();
            let candidates = sampler.offer(&engine, &update).unwrap();
            sent.extend(candidates.iter().flat_map(|c| [c.pair, [c.pair[1], c.pair[0]]]));
            scene.keyframe(&engine, &update, &candidates).unwrap();
        }
        assert!(!sent.is_empty());
        let image = RawImage::decode(scene.plane(&engine).unwrap().unwrap().data.as_slice()).unwrap();
        let n = positions.len();
        assert_eq!((image.width as usize, image.height as usize), (n, n));
        // Pixel (t, t′) at column t, row n - 1 - t′ (t′ up).
        let white: std::collections::BTreeSet<[usize; 2]> = (0..n * n)
            .filter(|&at| image.data[3 * at..3 * at + 3] == [255, 255, 255])
            .map(|at| [at % n, n - 1 - at / n])
            .collect();
        assert_eq!(white, sent);
    }

    #[test]
    fn the_trajectory_grows_keyframe_by_keyframe() {
        let positions: Vec<[f64; 3]> = (0..5).map(|k| [f64::from(k), 0.0, 0.0]).collect();
        let mut scene = LiveScene::new("line", positions, None).unwrap();
        let mut engine = OnlineLoops::new(MetricSpec::Euclidean, 1, 0.5).unwrap();
        for k in 0..5 {
            let update = engine.push(1.7e9 + f64::from(k), &[f64::from(k)]).unwrap();
            let messages = scene.keyframe(&engine, &update, &[]).unwrap();
            let poses = PosesInFrame::decode(messages[0].data.as_slice()).unwrap();
            assert_eq!(poses.poses.len(), k as usize + 1);
            assert_eq!(messages[0].log_time_ns, Some(1_700_000_000_000_000_000 + k as u64 * 1_000_000_000));
            let candidates = SceneUpdate::decode(messages[3].data.as_slice()).unwrap();
            assert!(candidates.entities.is_empty());
        }
    }
}

"""The results in Foxglove, RViz and Rerun: ``results.mcap`` of ``loops run --mcap`` and
``loops fleet --mcap``, ``viewers.to_mcap`` and ``viewers.to_rerun``, read back with the
official readers and decoders, independent of the writer: ``mcap`` for the file, Foxglove's
published protobuf classes (``foxglove-schemas-protobuf``) for its messages, ``rosbags``' own
ROS 2 Humble definition for the MarkerArray's CDR, and rerun-sdk's RRD reader. Every pose,
component and candidate is checked against the input log (read with ``mcap-ros2-support``),
``components.csv`` and ``samples.csv``.
"""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from foxglove_schemas_protobuf.PosesInFrame_pb2 import PosesInFrame
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from google.protobuf.descriptor_pb2 import FileDescriptorSet
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory
from rosbags.typesys import Stores, get_typestore

import inexact_loops as il
from inexact_loops import viewers

TOPICS = {
    "/loops/trajectory": "foxglove.PosesInFrame",
    "/loops/tau": "foxglove.SceneUpdate",
    "/loops/components": "foxglove.SceneUpdate",
    "/loops/candidates": "foxglove.SceneUpdate",
    "/loops/plane": "foxglove.RawImage",
    "/loops/markers": "visualization_msgs/msg/MarkerArray",
}


def loops_cli(*args: object, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


def read_messages(path: Path) -> dict[str, list[tuple[object, bytes, int]]]:
    """Every message of the file by topic, in the file's order, with its schema and log time,
    from the official reader."""
    out: dict[str, list[tuple[object, bytes, int]]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert message.publish_time == message.log_time
            out.setdefault(channel.topic, []).append((schema, message.data, message.log_time))
    return out


def stamp_ns(seconds: str) -> int:
    """A time of the CSV files in nanoseconds: exact for at most 9 decimals (as printed), else
    the value's nearest nanosecond."""
    value = Decimal(seconds)
    if value.as_tuple().exponent < -9:
        value = Decimal(float(seconds))
    return int(round(value * 10**9))


def header_ns(header) -> int:
    return header.stamp.sec * 10**9 + header.stamp.nanosec


def read_table(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def input_poses(log: Path) -> np.ndarray:
    """The log's positions, decoded by mcap-ros2-support."""
    with open(log, "rb") as f:
        reader = make_reader(f, decoder_factories=[Ros2DecoderFactory()])
        rows = []
        for _, _, _, msg in reader.iter_decoded_messages():
            pose = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
            rows.append([pose.position.x, pose.position.y, pose.position.z])
    return np.array(rows)


def check_file(path: Path, sessions: list[str]) -> dict[str, list]:
    """Checks the topics and schemas, decodes every message with the published classes, and
    returns them by topic, with their log times by topic under ``"times"``."""
    messages = read_messages(path)
    assert {topic: schemas[0][0].name for topic, schemas in messages.items()} == TOPICS
    times = {topic: [t for _, _, t in rows] for topic, rows in messages.items()}
    for topic, stamps in times.items():  # a timeline: in time order on each channel
        assert stamps == sorted(stamps), topic
    for rows in messages.values():
        schema = rows[0][0]
        if schema.encoding == "protobuf":
            names = {
                m.name
                for f in FileDescriptorSet.FromString(schema.data).file
                for m in f.message_type
            }
            assert schema.name.split(".")[1] in names
    with open(path, "rb") as f:
        metadata = list(make_reader(f).iter_metadata())
    assert json.loads(metadata[0].metadata["sessions"]) == sessions
    store = get_typestore(Stores.ROS2_HUMBLE)
    return {
        "/loops/trajectory": [
            PosesInFrame.FromString(d) for _, d, _ in messages["/loops/trajectory"]
        ],
        "/loops/tau": [SceneUpdate.FromString(d) for _, d, _ in messages["/loops/tau"]],
        "/loops/components": [
            SceneUpdate.FromString(d) for _, d, _ in messages["/loops/components"]
        ],
        "/loops/candidates": [
            SceneUpdate.FromString(d) for _, d, _ in messages["/loops/candidates"]
        ],
        "/loops/plane": [RawImage.FromString(d) for _, d, _ in messages["/loops/plane"]],
        "/loops/markers": [
            store.deserialize_cdr(d, "visualization_msgs/msg/MarkerArray")
            for _, d, _ in messages["/loops/markers"]
        ],
        "times": times,
    }


def xyz(traj: il.Trajectory) -> np.ndarray:
    """The first three coordinates of each point, 0 for those it lacks."""
    p = np.asarray(traj.positions, dtype=float).reshape(len(traj), -1)[:, :3]
    return np.c_[p, np.zeros((len(p), 3 - p.shape[1]))]


def points(line) -> np.ndarray:
    return np.array([[p.x, p.y, p.z] for p in line.points])


def check_scene(
    decoded: dict[str, list],
    positions: list[np.ndarray],
    stamps_ns: list[np.ndarray],
    sessions: list[str],
    components: list[dict[str, str]],
    samples: list[dict[str, str]],
    tau: list[np.ndarray],
) -> None:
    """Every pose, component and candidate of the decoded file against the independent
    ``positions`` and their times ``stamps_ns`` (one array per session), ``components.csv``,
    ``samples.csv`` and τ."""
    times = decoded["times"]
    check_growing_paths(decoded, positions, stamps_ns, sessions, tau)
    last_ns = [int(s[-1]) for s in stamps_ns]

    # Each component alone, at the time its second stretch begins (t′_min).
    entities = {}
    for update, at in zip(decoded["/loops/components"], times["/loops/components"], strict=True):
        (entity,) = update.entities
        entities[entity.id] = (entity, at)
    assert sorted(entities) == sorted(f"component/{row['id']}" for row in components)
    by_ns: dict[str, dict[int, object]] = {}
    for markers in decoded["/loops/markers"]:
        for marker in markers.markers:
            if marker.ns in ("trajectory", "tau"):
                continue  # the path as it grows (check_growing_paths)
            assert marker.id not in by_ns.get(marker.ns, {})
            by_ns.setdefault(marker.ns, {})[marker.id] = marker
    assert len(by_ns["components"]) == 3 * len(components)
    for row in components:
        entity, at = entities[f"component/{row['id']}"]
        b = int(row["session_b"]) if "session_b" in row else 0
        assert at == stamp_ns(row["t_prime_min_s"]) <= last_ns[b], row
        assert entity.timestamp.seconds * 10**9 + entity.timestamp.nanos == at
        meta = {kv.key: kv.value for kv in entity.metadata}
        for key in ("i_min", "i_max", "j_min", "j_max", "closest_i", "closest_j", "pair_count"):
            assert int(meta[key]) == int(row[key]), key
        for key in ("area_s2", "closest_distance"):
            assert float(meta[key]) == float(row[key]), key
        a, b = (int(row["session_a"]), int(row["session_b"])) if "session_a" in row else (0, 0)
        if "name_a" in row:
            for key in ("session_a", "session_b", "name_a", "name_b"):
                assert meta[key] == row[key], key
            assert [sessions[a], sessions[b]] == [row["name_a"], row["name_b"]]
        i0, i1, j0, j1 = (int(row[k]) for k in ("i_min", "i_max", "j_min", "j_max"))
        ci, cj = int(row["closest_i"]), int(row["closest_j"])
        stretch_a, stretch_b, closest = entity.lines
        np.testing.assert_array_equal(points(stretch_a), positions[a][i0 : i1 + 1])
        np.testing.assert_array_equal(points(stretch_b), positions[b][j0 : j1 + 1])
        np.testing.assert_array_equal(points(closest), [positions[a][ci], positions[b][cj]])
        # The MarkerArray: the same three lines, in RViz's types (LINE_STRIP 4, LINE_LIST 5).
        k = int(row["id"])
        for part, (kind, expected) in enumerate(
            [
                (4, positions[a][i0 : i1 + 1]),
                (4, positions[b][j0 : j1 + 1]),
                (5, [positions[a][ci], positions[b][cj]]),
            ]
        ):
            marker = by_ns["components"][3 * k + part]
            assert marker.type == kind
            np.testing.assert_array_equal(points(marker), expected)
            assert marker.header.frame_id == "map"
            assert header_ns(marker.header) == at

    # Each candidate alone, at its later pose's time (t′).
    candidates = {}
    for update, at in zip(decoded["/loops/candidates"], times["/loops/candidates"], strict=True):
        (entity,) = update.entities
        candidates[entity.id] = (entity, at)
    assert len(candidates) == len(samples) == len(by_ns["candidates"]) > 0
    for k, row in enumerate(samples):
        a, b = (int(row["session_a"]), int(row["session_b"])) if "session_a" in row else (0, 0)
        pair = [positions[a][int(row["i"])], positions[b][int(row["j"])]]
        entity, at = candidates[f"candidate/{k}"]
        assert at == stamp_ns(row["t_prime_s"]) <= last_ns[b], row
        if a == b:
            assert stamp_ns(row["t_s"]) <= at
        (line,) = entity.lines
        assert line.type == 2  # LINE_LIST
        np.testing.assert_array_equal(points(line), pair)
        np.testing.assert_array_equal(points(by_ns["candidates"][k]), pair)
        assert header_ns(by_ns["candidates"][k].header) == at

    (image,) = decoded["/loops/plane"]
    assert image.encoding == "rgb8" and image.step == 3 * image.width
    assert len(image.data) == image.height * image.step > 0


def check_growing_paths(
    decoded: dict[str, list],
    positions: list[np.ndarray],
    stamps_ns: list[np.ndarray],
    sessions: list[str],
    tau: list[np.ndarray],
) -> None:
    """Each session's path and τ grow as the log plays: each message, at a pose's time, holds
    exactly the poses up to that time (PosesInFrame, the τ strip and the MarkerArray's
    trajectory and tau markers), each adds poses, the last holds them all; at most
    ``PATH_STEPS`` messages a session."""
    times = decoded["times"]["/loops/trajectory"]
    trajectory, tau_updates = decoded["/loops/trajectory"], decoded["/loops/tau"]
    assert decoded["times"]["/loops/tau"] == times
    path_markers = [
        (a, header_ns(a.markers[0].header))
        for a in decoded["/loops/markers"]
        if a.markers[0].ns in ("trajectory", "tau")
    ]
    assert [at for _, at in path_markers] == times
    max_tau = max(t.max() for t in tau)
    held = [0] * len(sessions)
    messages = [0] * len(sessions)
    for message, update, (markers, _), at in zip(
        trajectory, tau_updates, path_markers, times, strict=True
    ):
        (entity,) = update.entities
        k = sessions.index(entity.id.removeprefix("tau/"))
        count = int(np.searchsorted(stamps_ns[k], at, side="right"))
        assert count > held[k], "each message adds poses"
        held[k], messages[k] = count, messages[k] + 1
        assert message.timestamp.seconds * 10**9 + message.timestamp.nanos == at
        got = np.array([[p.position.x, p.position.y, p.position.z] for p in message.poses])
        np.testing.assert_array_equal(got, positions[k][:count])
        (strip,) = entity.lines
        np.testing.assert_array_equal(points(strip), positions[k][:count])
        red = np.array([c.r for c in strip.colors])
        np.testing.assert_allclose(red * max_tau, tau[k][:count], atol=1e-9 * max_tau)
        assert [(m.ns, m.id) for m in markers.markers] == [("trajectory", k), ("tau", k)]
        for marker in markers.markers:
            np.testing.assert_array_equal(points(marker), positions[k][:count])
    assert held == [len(p) for p in positions], "the last message holds the whole path"
    assert messages == [path_steps(len(p)) for p in positions], messages


def path_steps(n: int) -> int:
    """The number of path messages of a session of ``n`` poses, as documented: one every
    ⌈n / m⌉ poses for m = 2 · 200,000 // n, between 1 and 100 (``loops_io::path_steps``)."""
    most = min(max(2 * 200_000 // n, 1), 100)
    stride = -(-n // most)
    return -(-n // stride)


def seconds_ns(seconds: np.ndarray) -> np.ndarray:
    """Times in seconds as the writer stamps them: each float's shortest decimal, to the
    nanosecond (:func:`stamp_ns`)."""
    return np.array([stamp_ns(repr(float(t))) for t in seconds], dtype=np.int64)


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("logs")
    done = loops_cli(
        "synth", folder / "drives", "--count", 1, "--duration-s", 900, "--force", cwd=folder
    )
    assert done.returncode == 0, done.stderr
    done = loops_cli(
        "synth", folder / "fleet", "--vehicles", 2, "--days", 1, "--duration-s", 600, cwd=folder
    )
    assert done.returncode == 0, done.stderr
    return folder


def test_loops_run_mcap_holds_every_pose_component_and_candidate(logs, tmp_path):
    (log,) = sorted((logs / "drives").glob("*.mcap"))
    out = tmp_path / "results"
    done = loops_cli(
        "run", log, "--gamma", 40, "--budget", 200, "--out", out, "--mcap", "--quiet", cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr
    folder = out / log.stem
    assert json.loads((folder / "foxglove-layout.json").read_text())["configById"]
    summary = json.loads((folder / "summary.json").read_text())
    assert {"results.mcap", "foxglove-layout.json"} <= set(summary["files"])
    components = read_table(folder / "components.csv")
    samples = read_table(folder / "samples.csv")
    tau = np.array([float(r["loop_duration_s"]) for r in read_table(folder / "loop_duration.csv")])
    times = seconds_ns(np.array([r["t_s"] for r in read_table(folder / "loop_duration.csv")]))
    decoded = check_file(folder / "results.mcap", [log.stem])
    check_scene(decoded, [input_poses(log)], [times], [log.stem], components, samples, [tau])
    assert len(components) > 5 and sum(r["trivial"] == "false" for r in components) > 0
    check_colours_match_report(folder / "report.html", decoded, components)


def check_colours_match_report(report: Path, decoded: dict, components: list[dict]) -> None:
    """Each component has the colour of its swatch in the HTML report's table, in the
    SceneUpdate and in the MarkerArray: one palette wherever the component is seen."""
    html = report.read_text()
    swatches = {
        name: tuple(int(colour[k : k + 2], 16) for k in (0, 2, 4))
        for name, colour in re.findall(r"\.(k\w+) \{ background: #([0-9a-f]{6}); \}", html)
    }
    assert "kt" in swatches and "k0" in swatches
    classes = {i: k for k, i in re.findall(r'<i class="swatch (k\w+)"></i>(\d+)', html)}
    by_entity = {u.entities[0].id: u.entities[0] for u in decoded["/loops/components"]}
    by_id = {m.id: m for a in decoded["/loops/markers"] for m in a.markers if m.ns == "components"}
    checked = 0
    for row in components:
        entity = by_entity[f"component/{row['id']}"]
        if row["id"] not in classes:
            continue  # the table lists the largest components only
        expected = swatches[classes[row["id"]]]
        colour = entity.lines[0].color
        assert tuple(round(255 * c) for c in (colour.r, colour.g, colour.b)) == expected, row
        marker = by_id[3 * int(row["id"])].color
        assert tuple(round(255 * c) for c in (marker.r, marker.g, marker.b)) == expected, row
        checked += 1
    assert checked > 0


def test_loops_fleet_mcap_holds_every_session(logs, tmp_path):
    fleet_logs = sorted((logs / "fleet").glob("*.mcap"))
    assert len(fleet_logs) == 2
    out = tmp_path / "fleet"
    done = loops_cli(
        "fleet",
        *fleet_logs,
        "--gamma",
        40,
        "--budget",
        100,
        "--out",
        out,
        "--mcap",
        "--quiet",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    names = [p.stem for p in fleet_logs]
    components = read_table(out / "components.csv")
    samples = read_table(out / "samples.csv")
    # τ over the whole fleet, per session: the sessions' columns as the fleet computes them.
    fleet = il.Fleet(
        {name: il.read_trajectory(p) for name, p in zip(names, fleet_logs, strict=True)}
    )
    table = il.find_fleet_loops(fleet, gamma=40.0).loop_duration()
    total = np.asarray(table["own_s"]) + np.asarray(table["other_s"])
    tau = [total[np.asarray(table["session"]) == k] for k in range(len(names))]
    times = [
        seconds_ns(np.array([r["t_s"] for r in read_table(out / name / "loop_duration.csv")]))
        for name in names
    ]
    decoded = check_file(out / "results.mcap", names)
    poses = [input_poses(p) for p in fleet_logs]
    check_scene(decoded, poses, times, names, components, samples, tau)
    assert any(r["session_a"] != r["session_b"] for r in components)
    assert any(r["session_a"] != r["session_b"] for r in samples)
    for name in names:  # each session's folder, as `loops run` writes it
        assert (out / name / "results.mcap").is_file()


def test_python_to_mcap_equals_the_csv_files(tmp_path):
    traj = il.urban_drive(duration_s=900.0)
    loops = il.find_loops(traj, gamma=40.0)
    samples = il.sample(loops, "rho", budget=100, seed=3, trajectory=traj)
    loops.components_to_csv(tmp_path / "components.csv")
    samples.to_csv(tmp_path / "samples.csv")
    viewers.to_mcap(loops, samples, tmp_path / "results.mcap", trajectory=traj, name="urban")
    decoded = check_file(tmp_path / "results.mcap", ["urban"])
    positions = xyz(traj)
    components = read_table(tmp_path / "components.csv")
    tau = loops.loop_duration()
    samples_table = read_table(tmp_path / "samples.csv")
    times = [seconds_ns(np.asarray(traj.timestamps))]
    check_scene(decoded, [positions], times, ["urban"], components, samples_table, [tau])
    assert (tmp_path / viewers.LAYOUT_FILE).is_file()


def mcap_records(path: Path) -> tuple[object, list[tuple[int, int, int, int, bytes]]]:
    """The summary and every message (channel id, sequence, log time, publish time, data) of
    an MCAP file, in the file's order, from the official reader."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = [
            (c.id, m.sequence, m.log_time, m.publish_time, m.data)
            for _, c, m in reader.iter_messages(log_time_order=False)
        ]
    return summary, messages


def test_merge_log_keeps_the_logs_schemas_channels_and_messages(logs, tmp_path):
    """``--merge-log``: results.mcap holds the user's log as it was (its schemas and channels
    under their ids, byte for byte, every message with its times and sequence) beside the
    scene's topics, all in log-time order; without ``--mcap`` it is a usage error."""
    (log,) = sorted((logs / "drives").glob("*.mcap"))
    out = tmp_path / "merged"
    args = ("run", log, "--gamma", 40, "--budget", 50, "--out", out, "--quiet")
    refused = loops_cli(*args, "--merge-log", cwd=tmp_path)
    assert refused.returncode == 2 and "--mcap" in refused.stderr, refused.stderr
    done = loops_cli(*args, "--mcap", "--merge-log", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    theirs, their_messages = mcap_records(log)
    merged, messages = mcap_records(out / log.stem / "results.mcap")
    for id_, schema in theirs.schemas.items():
        got = merged.schemas[id_]
        assert (got.name, got.encoding, got.data) == (schema.name, schema.encoding, schema.data)
    for id_, channel in theirs.channels.items():
        got = merged.channels[id_]
        fields = ("topic", "schema_id", "message_encoding", "metadata")
        assert [getattr(got, f) for f in fields] == [getattr(channel, f) for f in fields]
    kept = [m for m in messages if m[0] in theirs.channels]
    assert sorted(kept) == sorted(their_messages) and len(their_messages) > 100
    topics = {c.topic for c in merged.channels.values()}
    assert topics == set(TOPICS) | {c.topic for c in theirs.channels.values()}
    ours = [m for m in messages if merged.channels[m[0]].topic in TOPICS]
    assert len(ours) + len(kept) == len(messages) and ours
    stamps = [m[2] for m in messages]
    assert stamps == sorted(stamps), "one timeline"


def write_log_with_attachments(path: Path) -> tuple[list[tuple], list[tuple]]:
    """A JSON pose log (foxglove.PoseInFrame on /pose: two laps of a 40 m square) written by
    the official ``mcap`` writer with two attachments and two metadata records; those as
    (name, media type, log time, create time, data) and (name, {key: value})."""
    from mcap.writer import CompressionType, Writer

    attachments = [
        ("calibration.yaml", "application/yaml", 5, 7, b"camera: {fx: 525.0}\n"),
        ("map.bin", "application/octet-stream", 9, 0, bytes(range(256)) * 3),
    ]
    metadata = [
        ("robot", {"name": "rover-1", "firmware": "2.4.1"}),
        ("operator", {"shift": "night"}),
    ]
    side = np.linspace(0.0, 40.0, 20, endpoint=False)
    lap = np.concatenate([np.c_[side, 0 * side], np.c_[40 + 0 * side, side]])
    lap = np.concatenate([lap, np.c_[40 - side, 40 + 0 * side], np.c_[0 * side, 40 - side]])
    xy = np.tile(lap, (2, 1))
    with open(path, "wb") as stream:
        writer = Writer(stream, compression=CompressionType.NONE)
        writer.start()
        schema = writer.register_schema(
            name="foxglove.PoseInFrame", encoding="jsonschema", data=b'{"type": "object"}'
        )
        pose = writer.register_channel(topic="/pose", message_encoding="json", schema_id=schema)
        for k, (x, y) in enumerate(xy):
            stamp_ns = 10**9 + k * 10**8
            message = {
                "timestamp": {"sec": stamp_ns // 10**9, "nsec": stamp_ns % 10**9},
                "frame_id": "map",
                "pose": {
                    "position": {"x": float(x), "y": float(y), "z": 0.0},
                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                },
            }
            data = json.dumps(message).encode()
            writer.add_message(pose, log_time=stamp_ns, publish_time=stamp_ns, data=data)
        for name, media_type, log_time, create_time, data in attachments:
            writer.add_attachment(
                create_time=create_time,
                log_time=log_time,
                name=name,
                media_type=media_type,
                data=data,
            )
        for name, record in metadata:
            writer.add_metadata(name, record)
        writer.finish()
    return attachments, metadata


def test_merge_log_keeps_the_logs_attachments_and_metadata(tmp_path):
    """``--merge-log`` copies the log's attachments and metadata records as they are (read back
    with the official ``mcap`` reader), in the log's order, beside the scene's ``loops`` record."""
    log = tmp_path / "drive.mcap"
    attachments, metadata = write_log_with_attachments(log)
    out = tmp_path / "merged"
    done = loops_cli(
        "run", log, "--gamma", 2, "--budget", 10, "--out", out, "--mcap", "--merge-log",
        "--quiet", cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    with open(out / log.stem / "results.mcap", "rb") as f:
        reader = make_reader(f)
        got = [
            (a.name, a.media_type, a.log_time, a.create_time, bytes(a.data))
            for a in reader.iter_attachments()
        ]
        records = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    assert got == attachments
    assert records[:-1] == metadata and records[-1][0] == "loops"


def test_existing_files_are_not_replaced_without_force(tmp_path):
    traj = il.urban_drive(duration_s=300.0)
    loops = il.find_loops(traj, gamma=40.0)
    samples = il.sample(loops, "one", budget=5, seed=0, trajectory=traj)
    target = tmp_path / "results.mcap"
    target.write_bytes(b"mine")
    with pytest.raises(FileExistsError, match="results.mcap"):
        viewers.to_mcap(loops, samples, target, trajectory=traj)
    assert target.read_bytes() == b"mine" and not (tmp_path / viewers.LAYOUT_FILE).exists()
    with pytest.raises(FileExistsError, match="rrd"):
        (tmp_path / "r.rrd").write_bytes(b"mine")
        viewers.to_rerun(loops, samples, tmp_path / "r.rrd", trajectory=traj)
    assert (tmp_path / "r.rrd").read_bytes() == b"mine"
    viewers.to_mcap(loops, samples, target, trajectory=traj, overwrite=True)
    assert target.read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_cli_refuses_a_users_results_mcap_and_replaces_its_own_with_force(logs, tmp_path):
    fleet_logs = sorted((logs / "fleet").glob("*.mcap"))
    out = tmp_path / "fleet"
    out.mkdir()
    (out / "results.mcap").write_bytes(b"mine")
    done = loops_cli(
        "fleet",
        *fleet_logs,
        "--gamma",
        40,
        "--out",
        out,
        "--mcap",
        "--quiet",
        "--force",
        cwd=tmp_path,
    )
    assert done.returncode == 2 and "results.mcap" in done.stderr, done.stderr
    assert (out / "results.mcap").read_bytes() == b"mine"
    (out / "results.mcap").unlink()
    args = ("fleet", *fleet_logs, "--gamma", 40, "--out", out, "--mcap", "--quiet")
    assert loops_cli(*args, cwd=tmp_path).returncode == 0
    first = (out / "results.mcap").read_bytes()
    again = loops_cli(*args, cwd=tmp_path)
    assert again.returncode == 2 and "--force" in again.stderr, again.stderr
    assert (out / "results.mcap").read_bytes() == first
    assert loops_cli(*args, "--force", cwd=tmp_path).returncode == 0
    assert (out / "results.mcap").read_bytes() == first  # the same results, byte for byte


def test_a_corrupt_log_gives_a_clear_error_and_no_mcap(logs, tmp_path):
    (log,) = sorted((logs / "drives").glob("*.mcap"))
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(log.read_bytes()[: log.stat().st_size // 2])
    out = tmp_path / "results"
    done = loops_cli("run", broken, "--gamma", 40, "--out", out, "--mcap", "--quiet", cwd=tmp_path)
    assert done.returncode == 1
    assert "broken.mcap" in done.stderr and "\n" not in done.stderr.strip().splitlines()[-1]
    assert not list(out.rglob("results.mcap"))


def test_rerun_recording_holds_the_same_entities(tmp_path):
    rerun_chunk = pytest.importorskip("rerun.chunk")
    traj = il.urban_drive(duration_s=900.0)
    loops = il.find_loops(traj, gamma=40.0)
    samples = il.sample(loops, "rho", budget=50, seed=1, trajectory=traj)
    path = tmp_path / "results.rrd"
    viewers.to_rerun(loops, samples, path, trajectory=traj, name="urban")
    entities: dict[str, dict[str, list]] = {}
    for chunk in rerun_chunk.RrdReader(path).stream():
        batch = chunk.to_record_batch()
        columns = entities.setdefault(str(chunk.entity_path), {})
        for name in batch.schema.names:
            columns.setdefault(name, []).extend(batch.column(name).to_pylist())
    positions = xyz(traj)
    (trajectory,) = entities["/loops/trajectory/urban"]["Points3D:positions"]
    np.testing.assert_allclose(trajectory, positions, rtol=1e-6, atol=1e-3)  # float32
    table = loops.components
    ids = [int(i) for i in table["id"]]
    assert {f"/loops/components/{i}" for i in ids} <= set(entities)
    assert len([e for e in entities if e.startswith("/loops/components/")]) == len(ids)
    for k in ids:
        columns = entities[f"/loops/components/{k}"]
        assert columns["area_s2"] == [[table["area_s2"][k]]]
        (strips,) = columns["LineStrips3D:strips"]
        i0, i1 = int(table["i_min"][k]), int(table["i_max"][k])
        np.testing.assert_allclose(strips[0], positions[i0 : i1 + 1], rtol=1e-6, atol=1e-3)
    (candidates,) = entities["/loops/candidates"]["LineStrips3D:strips"]
    expected = np.stack([positions[samples.i], positions[samples.j]], axis=1)
    np.testing.assert_allclose(np.array(candidates), expected, rtol=1e-6, atol=1e-3)
    assert "Image:buffer" in entities["/loops/plane"]

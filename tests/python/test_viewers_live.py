"""``loops replay --serve``: the replay's keyframes live over Foxglove's WebSocket protocol, read
by a client of our own on loopback that speaks the protocol's v1 (``foxglove.websocket.v1``,
which Foxglove's SDK serves under its new name ``foxglove.sdk.v1``) with
the ``websockets`` package and decodes the messages with Foxglove's published protobuf classes
(``foxglove-schemas-protobuf``) and the ROS 2 ``MarkerArray`` with ``rosbags``. Every keyframe
of the log is checked against the JSON lines of a replay without ``--serve``, the poses against
the log's text, the components left at the end against :class:`inexact_loops.OnlineLoops`
pushed the same poses, and the (t, t′) plane against the pairs within γ by brute force, with
every candidate's pixel white.
"""

from __future__ import annotations

import asyncio
import json
import re
import socket
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

websockets = pytest.importorskip("websockets")
from foxglove_schemas_protobuf.PosesInFrame_pb2 import PosesInFrame  # noqa: E402
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage  # noqa: E402
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from websockets.asyncio.client import connect  # noqa: E402

import inexact_loops as il  # noqa: E402
from inexact_loops import viewers  # noqa: E402

TOPICS = {
    "/loops/trajectory": "foxglove.PosesInFrame",
    "/loops/tau": "foxglove.SceneUpdate",
    "/loops/components": "foxglove.SceneUpdate",
    "/loops/candidates": "foxglove.SceneUpdate",
    "/loops/plane": "foxglove.RawImage",
    "/loops/markers": "visualization_msgs/msg/MarkerArray",
}
#: The topics with a message at every keyframe (the plane: every 100 poses, and at the end).
EVERY_KEYFRAME = [t for t in TOPICS if t != "/loops/plane"]
#: The plane's colour outside S_γ (the scene's background), and of the candidates' pixels.
BACKGROUND_RGB = (32, 32, 32)
CANDIDATE_RGB = (255, 255, 255)
GAMMA = 3.0
#: The whole exchange ends well before this (seconds); a hang fails instead of blocking.
DEADLINE_S = 120


def write_log(path: Path) -> np.ndarray:
    """Three laps of a 10 m square, 16 poses a lap, 0.5 s apart, 1 m of noise; the rows t x y z
    as the file holds them."""
    rng = np.random.default_rng(7)
    corners = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]])
    sides = zip(corners[:-1], corners[1:], strict=True)
    lap = np.concatenate([np.linspace(a, b, 4, endpoint=False) for a, b in sides])
    xy = np.tile(lap, (3, 1)) + rng.normal(0, 1.0, (3 * len(lap), 2))
    t = 1_700_000_000.0 + 0.5 * np.arange(len(xy))
    rows = np.c_[t, xy, np.zeros(len(xy))]
    with open(path, "w") as f:
        for r in rows:
            f.write(f"{r[0]:.1f} {r[1]:.6f} {r[2]:.6f} {r[3]:.6f} 0 0 0 1\n")
    return np.loadtxt(path)[:, :4]


def cli(*args: object) -> list[str]:
    return [sys.executable, "-m", "inexact_loops._cli", *map(str, args)]


async def read_port(process: asyncio.subprocess.Process) -> int:
    """The port of the line ``serving on ws://ADDR:PORT`` on stderr."""
    assert process.stderr is not None
    while line := await process.stderr.readline():
        if found := re.search(rb"serving on ws://127\.0\.0\.1:(\d+)", line):
            return int(found.group(1))
    raise AssertionError("no `serving on` line")


async def serve_and_listen(log: Path) -> tuple[dict, dict, dict[str, list], int, int, bytes]:
    """Runs ``loops replay LOG --serve 127.0.0.1:0``, subscribes to every channel and reads until
    the server closes: serverInfo, the channels by topic, the messages by topic (log time,
    payload), the exit code and the port."""
    process = await asyncio.create_subprocess_exec(
        *cli("replay", log, "--gamma", GAMMA, "--serve", "127.0.0.1:0", "--quiet"),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        port = await read_port(process)
        messages: dict[str, list] = {topic: [] for topic in TOPICS}
        # The protocol's v1 under both its names: the SDK's server speaks it as foxglove.sdk.v1.
        url, offered = f"ws://127.0.0.1:{port}", ["foxglove.sdk.v1", "foxglove.websocket.v1"]
        async with connect(url, subprotocols=offered, proxy=None) as ws:
            assert ws.subprotocol == "foxglove.sdk.v1"
            info = json.loads(await ws.recv())
            channels: dict[str, dict] = {}
            while len(channels) < len(TOPICS):
                message = json.loads(await ws.recv())
                assert message["op"] == "advertise", message
                channels.update({c["topic"]: c for c in message["channels"]})
            by_subscription = {k: c["topic"] for k, c in enumerate(channels.values())}
            subscriptions = [
                {"id": k, "channelId": channels[t]["id"]} for k, t in by_subscription.items()
            ]
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            # The server closes the connection after the last keyframe.
            async for frame in ws:
                if isinstance(frame, str):
                    continue  # status and other text ops
                assert frame[0] == 1, frame[:1]  # messageData
                subscription, log_time = struct.unpack_from("<IQ", frame, 1)
                messages[by_subscription[subscription]].append((log_time, frame[13:]))
        code = await process.wait()
        assert process.stderr is not None
        rest = await process.stderr.read()
        return info, channels, messages, code, port, rest
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()


def test_replay_serves_every_keyframe_to_a_foxglove_client(tmp_path: Path):
    log = tmp_path / "square.tum"
    rows = write_log(log)
    reference = subprocess.run(
        cli("replay", log, "--gamma", GAMMA), capture_output=True, text=True, timeout=300
    )
    assert reference.returncode == 0, reference.stderr
    keyframes = [json.loads(line) for line in reference.stdout.splitlines()]
    assert len(keyframes) == len(rows)
    assert sum(len(k["candidates"]) for k in keyframes) > 0 and any(k["merged"] for k in keyframes)

    info, channels, messages, code, port, stderr = asyncio.run(
        asyncio.wait_for(serve_and_listen(log), DEADLINE_S)
    )
    assert code == 0, stderr
    assert info["op"] == "serverInfo" and info["name"].startswith("loops replay")
    assert {t: c["schemaName"] for t, c in channels.items()} == TOPICS
    encodings = {t: (c["encoding"], c["schemaEncoding"]) for t, c in channels.items()}
    assert encodings.pop("/loops/markers") == ("cdr", "ros2msg")
    assert set(encodings.values()) == {("protobuf", "protobuf")}
    assert all(len(messages[t]) == len(keyframes) for t in EVERY_KEYFRAME), {
        t: len(m) for t, m in messages.items()
    }
    # 48 poses: no multiple of 100, so one plane, the whole log's, after the last keyframe.
    assert [t for t, _ in messages["/loops/plane"]] == [round(rows[-1, 0] * 1e9)]
    sent = [(c["k"], c["j"]) for k in keyframes for c in k["candidates"]]
    check_plane(RawImage.FromString(messages["/loops/plane"][0][1]), rows, sent)
    store = get_typestore(Stores.ROS2_HUMBLE)
    markers: dict[tuple[str, int], object] = {}

    # The components' entities, as Foxglove keeps them: updated by id, removed by deletions.
    live: dict[str, SceneUpdate.SceneEntity] = {}
    for k, line in enumerate(keyframes):
        n = line["pose"] + 1
        stamp_ns = round(rows[line["pose"], 0] * 1e9)
        for topic in EVERY_KEYFRAME:
            assert messages[topic][k][0] == stamp_ns, (topic, k)
        check_markers(store, messages["/loops/markers"][k][1], markers, line, rows)
        poses = PosesInFrame.FromString(messages["/loops/trajectory"][k][1])
        assert poses.frame_id == "map" and len(poses.poses) == n
        got = np.array([[p.position.x, p.position.y, p.position.z] for p in poses.poses])
        np.testing.assert_allclose(got, rows[:n, 1:4], atol=1e-9)

        (tau,) = SceneUpdate.FromString(messages["/loops/tau"][k][1]).entities
        assert tau.id == "tau/square" and len(tau.lines[0].colors) == n
        max_tau = float(dict((m.key, m.value) for m in tau.metadata)["max_loop_duration_s"])
        if max_tau > 0:
            # The colour's red channel is τ / max τ: the keyframe's τ of its JSON line.
            red = tau.lines[0].colors[-1].r
            assert red * max_tau == pytest.approx(line["loop_duration_s"], rel=1e-9)

        components = SceneUpdate.FromString(messages["/loops/components"][k][1])
        retired = [f"component/{m['retired']}" for m in line["merged"]]
        assert [d.id for d in components.deletions] == retired
        for deletion in components.deletions:
            live.pop(deletion.id, None)
        ids = {e.id for e in components.entities}
        assert {f"component/{c}" for c in line["created"]} - set(retired) <= ids
        assert line["extended_count"] == 0 or ids
        live.update({e.id: e for e in components.entities})

        candidates = SceneUpdate.FromString(messages["/loops/candidates"][k][1])
        if not line["candidates"]:
            assert not candidates.entities
            continue
        (entity,) = candidates.entities
        meta = {m.key: m.value for m in entity.metadata}
        assert entity.id == f"candidates/{line['pose']}"
        assert json.loads(meta["pairs"]) == [[c["k"], c["j"]] for c in line["candidates"]]
        assert json.loads(meta["components"]) == [c["component"] for c in line["candidates"]]
        ends = np.array([[p.x, p.y, p.z] for p in entity.lines[0].points]).reshape(-1, 2, 3)
        for (a, b), c in zip(ends, line["candidates"], strict=True):
            np.testing.assert_allclose([a, b], rows[[c["k"], c["j"]], 1:4], atol=1e-9)

    # The entities left are the live components of the engine pushed the same poses.
    online = il.OnlineLoops(gamma=GAMMA, dim=3)
    online.push_many(rows[:, 0], rows[:, 1:4])
    table = online.components
    assert sorted(live) == sorted(f"component/{i}" for i in table["id"].tolist())
    assert sorted(i for ns, i in markers if ns == "components") == sorted(
        3 * i + part for i in table["id"].tolist() for part in range(3)
    )
    for row in range(len(table["id"])):
        meta = {m.key: m.value for m in live[f"component/{table['id'][row]}"].metadata}
        for column in ("i_min", "i_max", "j_min", "j_max", "pair_count"):
            assert int(meta[column]) == int(table[column][row]), column

    # The server is gone: nothing listens on its port.
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=5).close()


def check_markers(store, data: bytes, markers: dict, line: dict, rows: np.ndarray) -> None:
    """The keyframe's MarkerArray (decoded by ``rosbags``): the path so far (``trajectory`` and
    ``tau``, id 0), the components' markers as RViz keeps them (``markers``, by namespace and
    id: ADD replaces, DELETE removes) and the keyframe's candidates (id = its pose)."""
    array = store.deserialize_cdr(data, "visualization_msgs/msg/MarkerArray")
    n = line["pose"] + 1
    path = {m.ns: m for m in array.markers if m.ns in ("trajectory", "tau")}
    assert sorted(path) == ["tau", "trajectory"]
    for marker in path.values():
        assert marker.id == 0 and marker.header.frame_id == "map"
        got = np.array([[p.x, p.y, p.z] for p in marker.points])
        np.testing.assert_allclose(got, rows[:n, 1:4], atol=1e-9)
    assert len(path["tau"].colors) == n
    deleted = {m.id for m in array.markers if m.ns == "components" and m.action == 2}
    assert deleted == {3 * m["retired"] + part for m in line["merged"] for part in range(3)}
    for marker in array.markers:
        if marker.ns == "components":
            if marker.action == 2:
                markers.pop((marker.ns, marker.id), None)
            else:
                markers[(marker.ns, marker.id)] = marker
    candidates = [m for m in array.markers if m.ns == "candidates"]
    if not line["candidates"]:
        assert not candidates
        return
    (marker,) = candidates
    assert marker.id == line["pose"] and marker.type == 5  # LINE_LIST
    ends = np.array([[p.x, p.y, p.z] for p in marker.points]).reshape(-1, 2, 3)
    for (a, b), c in zip(ends, line["candidates"], strict=True):
        np.testing.assert_allclose([a, b], rows[[c["k"], c["j"]], 1:4], atol=1e-9)


def check_plane(image: RawImage, rows: np.ndarray, pairs: list[tuple[int, int]]) -> None:
    """The (t, t′) plane of the whole log, one pixel a pose (t to the right, t′ up): coloured
    exactly where the two poses lie within γ, by brute force over the log's positions, and
    white exactly at the candidates ``pairs`` sent (pose indices) and their mirrors."""
    n = len(rows)
    assert (image.encoding, image.width, image.height, image.step) == ("rgb8", n, n, 3 * n)
    rgb = np.frombuffer(image.data, dtype=np.uint8).reshape(n, n, 3)[::-1]  # row 0: first t′
    coloured = (rgb != BACKGROUND_RGB).any(axis=2)
    xyz = rows[:, 1:4]
    within = np.linalg.norm(xyz[:, None, :] - xyz[None, :, :], axis=2) <= GAMMA
    np.testing.assert_array_equal(coloured, within)
    assert pairs, "no candidate to see on the plane"
    candidate = np.zeros((n, n), dtype=bool)
    for i, j in pairs:
        candidate[i, j] = candidate[j, i] = True
    white = (rgb == CANDIDATE_RGB).all(axis=2)
    np.testing.assert_array_equal(white, candidate)


async def listen_to_python_server(rows: np.ndarray) -> tuple[dict[str, list], list, int]:
    """Starts :func:`viewers.serve`, subscribes a client to every channel, pushes ``rows``
    into an :class:`il.OnlineLoops` one pose a keyframe with an :class:`il.OnlineSampler`'s
    candidates, sends each and then the plane, reads every message, and closes the server:
    the messages by topic, the candidates offered at each keyframe, and the port."""
    server = viewers.serve("127.0.0.1:0", name="square")
    port = server.port
    messages: dict[str, list] = {topic: [] for topic in TOPICS}
    offered = []
    offers = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
    async with connect(f"ws://{server.address}", subprotocols=offers, proxy=None) as ws:
        assert json.loads(await ws.recv())["op"] == "serverInfo"
        channels: dict[str, dict] = {}
        while len(channels) < len(TOPICS):
            message = json.loads(await ws.recv())
            channels.update({c["topic"]: c for c in message["channels"]})
        assert {t: c["schemaName"] for t, c in channels.items()} == TOPICS
        by_subscription = {k: c["topic"] for k, c in enumerate(channels.values())}
        subscriptions = [
            {"id": k, "channelId": channels[t]["id"]} for k, t in by_subscription.items()
        ]
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
        assert await asyncio.to_thread(server.wait_for_client, 30.0)
        online, sampler = il.OnlineLoops(gamma=GAMMA, dim=3), il.OnlineSampler()
        for t, *point in rows:
            update = online.push(t, point)
            candidates = sampler.offer(online, update)
            offered.append([c.pair for c in candidates])
            server.send(online, update, candidates)
        server.send_plane(online)
        # A keyframe from the second pose on: a message on each topic but the plane; then the
        # plane of all 48 poses.
        expected = (len(rows) - 1) * len(EVERY_KEYFRAME) + 1
        while sum(len(m) for m in messages.values()) < expected:
            frame = await ws.recv()
            if isinstance(frame, str):
                continue
            subscription, log_time = struct.unpack_from("<IQ", frame, 1)
            messages[by_subscription[subscription]].append((log_time, frame[13:]))
        server.close()
        with pytest.raises(websockets.ConnectionClosed):
            while True:  # nothing more, then the server's close
                frame = await ws.recv()
                assert isinstance(frame, str), "no message after the last"
    assert server.closed
    return messages, offered, port


def test_python_serve_sends_each_keyframe_and_closing_frees_the_port(tmp_path: Path):
    rows = write_log(tmp_path / "square.tum")
    messages, offered, port = asyncio.run(
        asyncio.wait_for(listen_to_python_server(rows), DEADLINE_S)
    )
    n = len(rows)
    assert all(len(messages[t]) == n - 1 for t in EVERY_KEYFRAME)
    assert sum(map(len, offered)) > 0
    store = get_typestore(Stores.ROS2_HUMBLE)
    for k in range(n - 1):
        stamp_ns = round(rows[k + 1, 0] * 1e9)
        assert all(messages[t][k][0] == stamp_ns for t in EVERY_KEYFRAME)
        poses = PosesInFrame.FromString(messages["/loops/trajectory"][k][1])
        got = np.array([[p.position.x, p.position.y, p.position.z] for p in poses.poses])
        np.testing.assert_allclose(got, rows[: k + 2, 1:4], atol=1e-9)
        (tau,) = SceneUpdate.FromString(messages["/loops/tau"][k][1]).entities
        assert tau.id == "tau/square"
        candidates = SceneUpdate.FromString(messages["/loops/candidates"][k][1]).entities
        pairs = [json.loads({m.key: m.value for m in e.metadata}["pairs"]) for e in candidates]
        assert [tuple(p) for e in pairs for p in e] == [(k_, j) for j, k_ in offered[k + 1]]
        markers = store.deserialize_cdr(
            messages["/loops/markers"][k][1], "visualization_msgs/msg/MarkerArray"
        )
        assert len(markers.markers[0].points) == k + 2
    ((at, image),) = messages["/loops/plane"]
    assert at == round(rows[-1, 0] * 1e9)
    check_plane(RawImage.FromString(image), rows, [tuple(p) for k in offered for p in k])
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=5).close()


def test_a_port_taken_is_a_one_line_error(tmp_path: Path):
    log = tmp_path / "square.tum"
    write_log(log)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            cli("replay", log, "--gamma", GAMMA, "--serve", f"127.0.0.1:{port}"),
            capture_output=True,
            text=True,
            timeout=300,
        )
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and f"--serve 127.0.0.1:{port}" in lines[0], done.stderr

"""``loops replay --serve``: the replay's keyframes live over Foxglove's WebSocket protocol, read
by a client of our own on loopback that speaks the protocol's v1 (``foxglove.websocket.v1``,
which Foxglove's SDK serves under its new name ``foxglove.sdk.v1``) with
the ``websockets`` package and decodes the messages with Foxglove's published protobuf classes
(``foxglove-schemas-protobuf``). Every keyframe of the log is checked against the JSON lines of
a replay without ``--serve``, the poses against the log's text, and the components left at the
end against :class:`inexact_loops.OnlineLoops` pushed the same poses.
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
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate  # noqa: E402
from websockets.asyncio.client import connect  # noqa: E402

import inexact_loops as il  # noqa: E402

TOPICS = {
    "/loops/trajectory": "foxglove.PosesInFrame",
    "/loops/tau": "foxglove.SceneUpdate",
    "/loops/components": "foxglove.SceneUpdate",
    "/loops/candidates": "foxglove.SceneUpdate",
}
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
    assert {c["encoding"] for c in channels.values()} == {"protobuf"}
    assert all(len(m) == len(keyframes) for m in messages.values()), {
        t: len(m) for t, m in messages.items()
    }

    # The components' entities, as Foxglove keeps them: updated by id, removed by deletions.
    live: dict[str, SceneUpdate.SceneEntity] = {}
    for k, line in enumerate(keyframes):
        n = line["pose"] + 1
        stamp_ns = round(rows[line["pose"], 0] * 1e9)
        for topic in TOPICS:
            assert messages[topic][k][0] == stamp_ns, (topic, k)
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
        assert json.loads(meta["pairs"]) == [[c["keyframe"], c["j"]] for c in line["candidates"]]
        assert json.loads(meta["components"]) == [c["component"] for c in line["candidates"]]
        ends = np.array([[p.x, p.y, p.z] for p in entity.lines[0].points]).reshape(-1, 2, 3)
        for (a, b), c in zip(ends, line["candidates"], strict=True):
            np.testing.assert_allclose([a, b], rows[[c["keyframe"], c["j"]], 1:4], atol=1e-9)

    # The entities left are the live components of the engine pushed the same poses.
    online = il.OnlineLoops(gamma=GAMMA, dim=3)
    online.push_many(rows[:, 0], rows[:, 1:4])
    table = online.components
    assert sorted(live) == sorted(f"component/{i}" for i in table["id"].tolist())
    for row in range(len(table["id"])):
        meta = {m.key: m.value for m in live[f"component/{table['id'][row]}"].metadata}
        for column in ("i_min", "i_max", "j_min", "j_max", "pair_count"):
            assert int(meta[column]) == int(table[column][row]), column

    # The server is gone: nothing listens on its port.
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

"""Bags from Python: rosbag2 (sqlite3, MCAP, zstd per message) and ROS 1 bags written by the
independent ``rosbags`` writer read back exactly through ``il.read_trajectory`` and
``il.list_topics``, by folder, ``metadata.yaml`` and file; a broken bag raises ``LoopsIOError``
naming the file. Skipped when ``rosbags`` is not installed."""

from __future__ import annotations

import numpy as np
import pytest

import inexact_loops as il

rosbags = pytest.importorskip("rosbags")

from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

N = 50


def poses():
    t = 1_600_000_000 + np.arange(N) * 0.1
    angle = np.arange(N) * 0.13
    return t, np.c_[10 * np.cos(angle), 10 * np.sin(angle), np.arange(N) * 1e-3]


def pose_stamped(store, ns: int, p, ros1: bool):
    t = store.types
    stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    header = (
        t["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="map")
        if ros1
        else t["std_msgs/msg/Header"](stamp=stamp, frame_id="map")
    )
    pose = t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    return t["geometry_msgs/msg/PoseStamped"](header=header, pose=pose)


def stamps_ns(t):
    return [round(x * 1e9) for x in t]


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bags")
    t, p = poses()
    store = get_typestore(Stores.ROS2_HUMBLE)
    made = {}
    for name, plugin, compress in [
        ("sqlite3", StoragePlugin.SQLITE3, False),
        ("mcap-zstd", StoragePlugin.MCAP, True),
    ]:
        writer = Writer2(folder / name, version=9, storage_plugin=plugin)
        if compress:
            writer.set_compression(CompressionMode.MESSAGE, CompressionFormat.ZSTD)
        with writer:
            conn = writer.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=store)
            for ns, row in zip(stamps_ns(t), p, strict=True):
                message = pose_stamped(store, ns, row, ros1=False)
                writer.write(
                    conn, ns, store.serialize_cdr(message, "geometry_msgs/msg/PoseStamped")
                )
        made[name] = folder / name
    store1 = get_typestore(Stores.ROS1_NOETIC)
    writer = Writer1(folder / "drive.bag")
    writer.set_compression(Writer1.CompressionFormat.BZ2)
    with writer:
        conn = writer.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=store1)
        for ns, row in zip(stamps_ns(t), p, strict=True):
            message = pose_stamped(store1, ns, row, ros1=True)
            writer.write(conn, ns, store1.serialize_ros1(message, "geometry_msgs/msg/PoseStamped"))
    made["ros1"] = folder / "drive.bag"
    return made


def test_every_bag_reads_back_exactly_every_way(bags):
    t, p = poses()
    expected_t = [ns // 10**9 + (ns % 10**9) / 1e9 for ns in stamps_ns(t)]
    for name, path in bags.items():
        ways = [path] if name == "ros1" else [path, path / "metadata.yaml", *path.glob("*_0.*")]
        for way in ways:
            traj = il.read_trajectory(way)
            np.testing.assert_array_equal(traj.positions, p, err_msg=str(way))
            np.testing.assert_array_equal(traj.timestamps, expected_t, err_msg=str(way))
            (topic,) = il.list_topics(way)
            assert topic["topic"] == "/pose"
            assert topic["messages"] == N
            assert topic["pose_type"] == "geometry_msgs/msg/PoseStamped"
            assert topic["encoding"] == ("ros1" if name == "ros1" else "cdr")


def test_broken_bags_name_the_file(bags, tmp_path):
    cut = tmp_path / "cut.bag"
    cut.write_bytes(bags["ros1"].read_bytes()[:5000])
    with pytest.raises(il.LoopsIOError, match=r"cut\.bag offset \d+: .*truncated"):
        il.read_trajectory(cut)
    db3 = tmp_path / "cut.db3"
    (source,) = bags["sqlite3"].glob("*.db3")
    db3.write_bytes(source.read_bytes()[:3000])
    with pytest.raises(il.LoopsIOError, match=r"cut\.db3"):
        il.read_trajectory(db3)


def test_every_surface_names_sessions_alike(bags, tmp_path):
    """``loops fleet`` (its summary.json), ``il.Fleet`` and ``inexact_loops.dask`` name the session
    of a log by one rule: a TUM file and a standalone MCAP file by their stems, a rosbag2 bag by
    its folder however it is given (folder, metadata.yaml, storage file), a ROS 1 bag by its
    stem."""
    import json
    import subprocess
    import sys

    from inexact_loops import dask

    t, p = poses()
    tum = tmp_path / "monday.tum"
    tum.write_text(
        "".join(f"{a} {x + 50} {y} {z} 0 0 0 1\n" for a, (x, y, z) in zip(t, p, strict=True))
    )
    standalone = tmp_path / "tuesday.mcap"
    standalone.write_bytes(next(bags["mcap-zstd"].glob("*.mcap")).read_bytes())
    sqlite = bags["sqlite3"]
    ways = {
        sqlite: "sqlite3",
        sqlite / "metadata.yaml": "sqlite3",
        next(sqlite.glob("*.db3")): "sqlite3",
        next(bags["mcap-zstd"].glob("*.mcap")): "mcap-zstd",
        bags["ros1"]: "drive",
        standalone: "tuesday",
    }
    for k, (way, expected) in enumerate(ways.items()):
        assert il.Fleet([way, tum]).names == [expected, "monday"], way
        assert [name for name, _ in dask._named_sources([way, tum])] == [expected, "monday"], way
        out = tmp_path / f"out{k}"
        run = subprocess.run(
            [sys.executable, "-m", "inexact_loops._cli", "fleet", str(way), str(tum)]
            + ["--gamma", "1", "--budget", "5", "--out", str(out), "--quiet"],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 0, run.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert [s["name"] for s in summary["sessions"]] == [expected, "monday"], way

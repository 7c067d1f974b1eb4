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
        named = dask._tasks.named_sources([way, tum])
        assert [name for name, _ in named] == [expected, "monday"], way
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


# Transform trees: map -> odom (2 Hz) -> base_link (10 Hz) on /tf, base_link -> velodyne on
# /tf_static, composed by scipy's Rotation and Slerp as the reference.

TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"


def tf_tree_links():
    """The two moving links (stamps in ns, positions, rotations) and the static one."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(7)
    t0 = 1_600_000_000 * 10**9
    odom_ns = t0 + np.arange(0, 41) * 100_000_000  # 10 Hz, 4 s
    map_ns = t0 - 300_000_000 + np.arange(0, 9) * 500_000_000  # 2 Hz, ends before odom
    moving = {}
    for name, stamps in (("map_odom", map_ns), ("odom_base", odom_ns)):
        n = len(stamps)
        moving[name] = (
            stamps,
            np.cumsum(rng.normal(0, 0.3, (n, 3)), axis=0),
            Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.1, (n, 3)), axis=0)),
        )
    fixed = (np.array([0.4, -0.1, 1.2]), Rotation.from_euler("xyz", [0.05, -0.2, 1.3]))
    return moving, fixed


def tf_tree_expected():
    """map -> velodyne at each odom -> base_link stamp within map -> odom's span, by scipy."""
    from scipy.spatial.transform import Slerp

    moving, (p_fixed, r_fixed) = tf_tree_links()
    m_ns, m_p, m_r = moving["map_odom"]
    o_ns, o_p, o_r = moving["odom_base"]
    inside = (o_ns >= m_ns[0]) & (o_ns <= m_ns[-1])
    at = o_ns[inside]
    r_map = Slerp(m_ns.astype(float), m_r)(at.astype(float))
    p_map = np.stack([np.interp(at, m_ns, m_p[:, k]) for k in range(3)], axis=1)
    r_base, p_base = o_r[inside], o_p[inside]
    # T_map_velodyne = T_map_odom * T_odom_base * T_base_velodyne
    p = p_map + r_map.apply(p_base + r_base.apply(p_fixed))
    r = r_map * r_base * r_fixed
    return at, p, r


def tf_message(store, transforms, ros1: bool):
    t = store.types
    items = []
    for ns, parent, child, p, r in transforms:
        stamp = t["builtin_interfaces/msg/Time"](sec=int(ns) // 10**9, nanosec=int(ns) % 10**9)
        header = (
            t["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=parent)
            if ros1
            else t["std_msgs/msg/Header"](stamp=stamp, frame_id=parent)
        )
        x, y, z, w = r.as_quat()
        transform = t["geometry_msgs/msg/Transform"](
            translation=t["geometry_msgs/msg/Vector3"](x=p[0], y=p[1], z=p[2]),
            rotation=t["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
        )
        items.append(
            t["geometry_msgs/msg/TransformStamped"](
                header=header, child_frame_id=child, transform=transform
            )
        )
    return t["tf2_msgs/msg/TFMessage"](transforms=items)


@pytest.fixture(scope="module")
def tf_bags(tmp_path_factory):
    """The tree written by rosbags: rosbag2 sqlite3, rosbag2 MCAP and ROS 1."""
    from rosbags.typesys import get_types_from_msg

    folder = tmp_path_factory.mktemp("tf")
    moving, (p_fixed, r_fixed) = tf_tree_links()
    messages = []  # (log ns, transforms)
    for (parent, child), (stamps, ps, rs) in zip(
        [("map", "odom"), ("odom", "base_link")], moving.values(), strict=True
    ):
        for i, ns in enumerate(stamps):
            messages.append((int(ns), [(ns, parent, child, ps[i], rs[i])]))
    messages.sort(key=lambda m: m[0])
    t0 = int(moving["odom_base"][0][0])
    static = [(t0, "base_link", "velodyne", p_fixed, r_fixed)]
    store2 = get_typestore(Stores.ROS2_HUMBLE)
    store1 = get_typestore(Stores.ROS1_NOETIC)
    store1.register(get_types_from_msg(TF_MESSAGE, "tf2_msgs/msg/TFMessage"))
    made = {}
    name = "tf2_msgs/msg/TFMessage"
    for kind, plugin in [("sqlite3", StoragePlugin.SQLITE3), ("mcap", StoragePlugin.MCAP)]:
        with Writer2(folder / kind, version=9, storage_plugin=plugin) as writer:
            tf = writer.add_connection("/tf", name, typestore=store2)
            tf_static = writer.add_connection("/tf_static", name, typestore=store2)
            writer.write(
                tf_static, t0 - 1, store2.serialize_cdr(tf_message(store2, static, False), name)
            )
            for log, transforms in messages:
                writer.write(
                    tf, log, store2.serialize_cdr(tf_message(store2, transforms, False), name)
                )
        made[kind] = folder / kind
    with Writer1(folder / "tf.bag") as writer:
        tf = writer.add_connection("/tf", name, typestore=store1)
        tf_static = writer.add_connection("/tf_static", name, typestore=store1)
        writer.write(
            tf_static, t0 - 1, store1.serialize_ros1(tf_message(store1, static, True), name)
        )
        for log, transforms in messages:
            writer.write(tf, log, store1.serialize_ros1(tf_message(store1, transforms, True), name))
    made["ros1"] = folder / "tf.bag"
    return made


@pytest.mark.parametrize("kind", ["sqlite3", "mcap", "ros1"])
def test_tf_trees_compose_at_the_stamps_of_the_lowest_moving_link(tf_bags, kind):
    from scipy.spatial.transform import Rotation

    at, p, r = tf_tree_expected()
    traj = il.read_trajectory(
        tf_bags[kind],
        topic="/tf",
        frames=("map", "velodyne"),
        metric="se3(rotation_weight_m_per_rad=1)",
    )
    assert len(at) < 41, "some odom stamps lie outside map -> odom's span and have no pose"
    np.testing.assert_array_equal(traj.timestamps, at / 1e9)
    np.testing.assert_allclose(traj.positions[:, :3], p, atol=1e-9)
    got = Rotation.from_quat(traj.positions[:, 3:7])
    assert np.max((got.inv() * r).magnitude()) < 1e-9
    # A direct pair still reads as it is.
    direct = il.read_trajectory(tf_bags[kind], topic="/tf", frames=("odom", "base_link"))
    assert len(direct) == 41


def test_tf_frames_not_linked_name_the_missing_link(tf_bags):
    with pytest.raises(il.LoopsIOError) as error:
        il.read_trajectory(tf_bags["mcap"], topic="/tf", frames=("map", "camera_mount"))
    message = str(error.value)
    assert "camera_mount" in message and "map" in message, message
    with pytest.raises(il.LoopsIOError) as error:
        il.read_trajectory(tf_bags["ros1"], topic="/tf", frames=("base_link", "laser"))
    assert "not linked" in str(error.value) or "no transform" in str(error.value), error.value

#!/usr/bin/env python3
"""Bag test files for loops-io, written by an independent writer: the `rosbags` package.

    python3 make_bag_fixtures.py POSES OUT_DIR          # the bags below and OUT_DIR/manifest.json
    python3 make_bag_fixtures.py --bench N OUT_DIR      # N PoseStamped: a sqlite3 and a ROS 1 bag
    python3 make_bag_fixtures.py --read PATH            # read and deserialise every message (bench)

POSES has one pose a line, `stamp_ns x y z qx qy qz qw`, the numbers as Python parses them back
exactly (shortest round-trip decimals). For each message type (geometry_msgs/PoseStamped on
/pose, nav_msgs/Odometry on /odom) the fixtures are:

- rosbag2, sqlite3 and MCAP storage: uncompressed; `compression_mode: message` (zstd);
  `compression_mode: file` (zstd); split into 3 storage files;
- ROS 1 bags with uncompressed, bz2 and lz4 chunks.

Every bag also holds /tf (tf2_msgs/TFMessage: map -> odom, identity, and odom -> base_link, the
pose) and /chatter (std_msgs/String); ROS 1 bags hold /tf_old too, as tf/tfMessage. Header
stamps are the poses' stamps; record (log) times are 1 ms later. rosbags writes no split bags:
the split bag is three bags of a third of the poses each, their storage files moved into one
folder with a metadata.yaml listing the three (as rosbag2 writes for splits).

Exit code 3 (with a message) when `rosbags` is missing: the Rust test then skips.
"""

from __future__ import annotations

import json
import shutil
import sys
import time
from pathlib import Path

try:
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    from ruamel.yaml import YAML
except ImportError as error:  # pragma: no cover - depends on the machine
    print(f"missing Python package ({error}): pip install rosbags", file=sys.stderr)
    sys.exit(3)

LOG_DELAY_NS = 1_000_000
TF2_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"


def typestores():
    ros2 = get_typestore(Stores.ROS2_HUMBLE)
    ros1 = get_typestore(Stores.ROS1_NOETIC)
    extra = {}
    extra.update(get_types_from_msg(TF2_MESSAGE, "tf2_msgs/msg/TFMessage"))
    extra.update(get_types_from_msg(TF2_MESSAGE, "tf/msg/tfMessage"))
    ros1.register(extra)
    return ros2, ros1


def read_poses(path: Path) -> list[tuple[int, list[float], list[float]]]:
    poses = []
    for line in path.read_text().splitlines():
        fields = line.split()
        if not fields:
            continue
        numbers = [float(v) for v in fields[1:]]
        poses.append((int(fields[0]), numbers[:3], numbers[3:7]))
    return poses


class Messages:
    """Builds the messages of one typestore (ROS 2 or ROS 1)."""

    def __init__(self, store, ros1: bool):
        self.t = store.types
        self.ros1 = ros1
        self.store = store

    def time(self, ns: int):
        return self.t["builtin_interfaces/msg/Time"](
            sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000
        )

    def header(self, ns: int, frame: str, seq: int):
        if self.ros1:
            return self.t["std_msgs/msg/Header"](seq=seq, stamp=self.time(ns), frame_id=frame)
        return self.t["std_msgs/msg/Header"](stamp=self.time(ns), frame_id=frame)

    def pose(self, p, q):
        t = self.t
        return t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
            orientation=t["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
        )

    def transform(self, ns, parent, child, p, q, seq):
        t = self.t
        return t["geometry_msgs/msg/TransformStamped"](
            header=self.header(ns, parent, seq),
            child_frame_id=child,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](x=p[0], y=p[1], z=p[2]),
                rotation=t["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
            ),
        )

    def message(self, kind: str, seq: int, ns: int, p, q):
        t = self.t
        if kind == "PoseStamped":
            return t["geometry_msgs/msg/PoseStamped"](
                header=self.header(ns, "map", seq), pose=self.pose(p, q)
            )
        covariance = [0.01 * i for i in range(36)]
        import numpy as np

        return t["nav_msgs/msg/Odometry"](
            header=self.header(ns, "odom", seq),
            child_frame_id="base_link",
            pose=t["geometry_msgs/msg/PoseWithCovariance"](
                pose=self.pose(p, q), covariance=np.array(covariance)
            ),
            twist=t["geometry_msgs/msg/TwistWithCovariance"](
                twist=t["geometry_msgs/msg/Twist"](
                    linear=t["geometry_msgs/msg/Vector3"](x=1.0, y=0.0, z=0.0),
                    angular=t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.1),
                ),
                covariance=np.array(covariance),
            ),
        )

    def tf(self, typename: str, seq: int, ns: int, p, q):
        return self.t[typename](
            transforms=[
                self.transform(ns, "map", "odom", [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], seq),
                self.transform(ns, "odom", "base_link", p, q, seq),
            ]
        )

    def chatter(self, seq: int):
        return self.t["std_msgs/msg/String"](data=f"hello {seq}")

    def serialize(self, message, typename):
        if self.ros1:
            return self.store.serialize_ros1(message, typename)
        return self.store.serialize_cdr(message, typename)


TYPES = {
    "PoseStamped": ("/pose", "geometry_msgs/msg/PoseStamped"),
    "Odometry": ("/odom", "nav_msgs/msg/Odometry"),
}


def write_rosbag2(folder: Path, store, poses, kind, storage, mode, with_extras=True) -> None:
    build = Messages(store, ros1=False)
    topic, typename = TYPES[kind]
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    writer = Writer2(folder, version=9, storage_plugin=plugin)
    if mode != "none":
        writer.set_compression(
            CompressionMode.MESSAGE if mode == "message" else CompressionMode.FILE,
            CompressionFormat.ZSTD,
        )
    with writer:
        pose_conn = writer.add_connection(topic, typename, typestore=store)
        tf_conn = (
            writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
            if with_extras
            else None
        )
        chat_conn = (
            writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
            if with_extras
            else None
        )
        for seq, (ns, p, q) in enumerate(poses):
            log = ns + LOG_DELAY_NS
            writer.write(
                pose_conn, log, build.serialize(build.message(kind, seq, ns, p, q), typename)
            )
            if with_extras:
                tf = build.tf("tf2_msgs/msg/TFMessage", seq, ns, p, q)
                writer.write(tf_conn, log, build.serialize(tf, "tf2_msgs/msg/TFMessage"))
                if seq % 10 == 0:
                    writer.write(
                        chat_conn, log, build.serialize(build.chatter(seq), "std_msgs/msg/String")
                    )


def write_split(folder: Path, store, poses, kind, storage) -> list[str]:
    """Three bags of a third each, their storage files in one folder, one metadata.yaml."""
    parts = folder.with_name(folder.name + "-parts")
    shutil.rmtree(parts, ignore_errors=True)
    parts.mkdir()
    third = (len(poses) + 2) // 3
    names, metas = [], []
    for index in range(3):
        part = parts / f"part{index}"
        write_rosbag2(
            part, store, poses[index * third : (index + 1) * third], kind, storage, "none"
        )
        yaml = YAML()
        meta = yaml.load((part / "metadata.yaml").read_text())
        info = meta["rosbag2_bagfile_information"]
        (source,) = info["relative_file_paths"]
        name = f"{folder.name}_{index}{Path(source).suffix}"
        metas.append(meta)
        names.append(name)
        folder.mkdir(exist_ok=True)
        shutil.move(str(part / source), str(folder / name))
        for entry in info.get("files", []):
            entry["path"] = name
    first = metas[0]["rosbag2_bagfile_information"]
    first["relative_file_paths"] = names
    first["files"] = [
        entry for meta in metas for entry in meta["rosbag2_bagfile_information"].get("files", [])
    ]
    first["message_count"] = sum(
        meta["rosbag2_bagfile_information"]["message_count"] for meta in metas
    )
    for topic_index, topic in enumerate(first["topics_with_message_count"]):
        topic["message_count"] = sum(
            meta["rosbag2_bagfile_information"]["topics_with_message_count"][topic_index][
                "message_count"
            ]
            for meta in metas
        )
    with (folder / "metadata.yaml").open("w") as out:
        YAML().dump(metas[0], out)
    shutil.rmtree(parts)
    return names


def write_ros1(path: Path, store, poses, kind, compression) -> None:
    build = Messages(store, ros1=True)
    topic, typename = TYPES[kind]
    writer = Writer1(path)
    if compression != "none":
        writer.set_compression(Writer1.CompressionFormat[compression.upper()])
    with writer:
        pose_conn = writer.add_connection(topic, typename, typestore=store)
        tf_conn = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        tf_old_conn = writer.add_connection("/tf_old", "tf/msg/tfMessage", typestore=store)
        chat_conn = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=store)
        for seq, (ns, p, q) in enumerate(poses):
            log = ns + LOG_DELAY_NS
            writer.write(
                pose_conn, log, build.serialize(build.message(kind, seq, ns, p, q), typename)
            )
            writer.write(
                tf_conn,
                log,
                build.serialize(
                    build.tf("tf2_msgs/msg/TFMessage", seq, ns, p, q), "tf2_msgs/msg/TFMessage"
                ),
            )
            writer.write(
                tf_old_conn,
                log,
                build.serialize(build.tf("tf/msg/tfMessage", seq, ns, p, q), "tf/msg/tfMessage"),
            )
            if seq % 10 == 0:
                writer.write(
                    chat_conn, log, build.serialize(build.chatter(seq), "std_msgs/msg/String")
                )


def storage_files(folder: Path) -> list[str]:
    yaml = YAML()
    meta = yaml.load((folder / "metadata.yaml").read_text())
    return list(meta["rosbag2_bagfile_information"]["relative_file_paths"])


def make_all(poses_path: Path, out: Path) -> None:
    ros2, ros1 = typestores()
    poses = read_poses(poses_path)
    out.mkdir(parents=True)
    fixtures = []
    for kind, (topic, _) in TYPES.items():
        for storage in ("sqlite3", "mcap"):
            for mode in ("none", "message", "file", "split3"):
                name = f"r2-{storage}-{mode}-{kind}"
                folder = out / name
                if mode == "split3":
                    write_split(folder, ros2, poses, kind, storage)
                else:
                    write_rosbag2(folder, ros2, poses, kind, storage, mode)
                fixtures.append(
                    {
                        "name": name,
                        "kind": "rosbag2",
                        "storage": storage,
                        "compression": mode,
                        "type": kind,
                        "topic": topic,
                        "folder": name,
                        "files": [f"{name}/{f}" for f in storage_files(folder)],
                    }
                )
        for compression in ("none", "bz2", "lz4"):
            name = f"ros1-{compression}-{kind}.bag"
            write_ros1(out / name, ros1, poses, kind, compression)
            fixtures.append(
                {
                    "name": name,
                    "kind": "ros1",
                    "compression": compression,
                    "type": kind,
                    "topic": topic,
                    "files": [name],
                }
            )
    manifest = {"log_delay_ns": LOG_DELAY_NS, "poses": len(poses), "fixtures": fixtures}
    (out / "manifest.json").write_text(json.dumps(manifest, indent=1))


def make_bench(count: int, out: Path) -> None:
    """`count` PoseStamped on /pose at 10 Hz: a rosbag2 sqlite3 bag, a ROS 1 bag (uncompressed)."""
    import math

    ros2, ros1 = typestores()
    out.mkdir(parents=True, exist_ok=True)
    poses = []
    for i in range(count):
        angle = i * 1e-3
        poses.append(
            (
                1_700_000_000_000_000_000 + i * 100_000_000,
                [100 * math.cos(angle), 100 * math.sin(angle), 0.0],
                [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)],
            )
        )
    folder = out / "bench-sqlite3"
    shutil.rmtree(folder, ignore_errors=True)
    write_rosbag2(folder, ros2, poses, "PoseStamped", "sqlite3", "none", with_extras=False)
    bag = out / "bench.bag"
    bag.unlink(missing_ok=True)
    build = Messages(ros1, ros1=True)
    with Writer1(bag) as writer:
        conn = writer.add_connection("/pose", "geometry_msgs/msg/PoseStamped", typestore=ros1)
        for seq, (ns, p, q) in enumerate(poses):
            data = build.serialize(
                build.message("PoseStamped", seq, ns, p, q), "geometry_msgs/msg/PoseStamped"
            )
            writer.write(conn, ns, data)


def read_all(path: Path) -> None:
    """Reads every message of a bag with rosbags and deserialises it; prints count and seconds."""
    import numpy as np

    start = time.perf_counter()
    xs = []
    if path.suffix == ".bag":
        from rosbags.rosbag1 import Reader

        store = get_typestore(Stores.ROS1_NOETIC)
        with Reader(path) as reader:
            for connection, _, raw in reader.messages():
                msg = store.deserialize_ros1(raw, connection.msgtype)
                xs.append((msg.header.stamp.sec, msg.header.stamp.nanosec, msg.pose.position.x))
    else:
        from rosbags.rosbag2 import Reader

        store = get_typestore(Stores.ROS2_HUMBLE)
        with Reader(path) as reader:
            for connection, _, raw in reader.messages():
                msg = store.deserialize_cdr(raw, connection.msgtype)
                xs.append((msg.header.stamp.sec, msg.header.stamp.nanosec, msg.pose.position.x))
    array = np.array(xs)
    print(json.dumps({"messages": len(array), "seconds": time.perf_counter() - start}))


def main(argv: list[str]) -> None:
    if argv[:1] == ["--bench"]:
        make_bench(int(argv[1]), Path(argv[2]))
    elif argv[:1] == ["--read"]:
        read_all(Path(argv[1]))
    elif len(argv) == 2:
        make_all(Path(argv[0]), Path(argv[1]))
    else:
        print(__doc__, file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main(sys.argv[1:])

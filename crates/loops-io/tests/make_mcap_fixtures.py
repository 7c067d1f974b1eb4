#!/usr/bin/env python3
"""MCAP test files for loops-io, written by the official Python writers.

    python3 make_mcap_fixtures.py OUT_DIR             # the test files and manifest.json
    python3 make_mcap_fixtures.py --bench N OUT.mcap  # N PoseStamped messages (speed check)
    python3 make_mcap_fixtures.py --read OUT.mcap     # read them with mcap + mcap-ros2-support

The files come from `mcap` (low-level Writer), `mcap-ros2-support` (ROS 2 CDR),
`mcap-protobuf-support` with `foxglove-schemas-protobuf` (Foxglove protobuf) and `mcap` with
`json` (Foxglove JSON). Each pose type is written unchunked, and chunked uncompressed, zstd and
lz4. `manifest.json` says what each file holds: every pose with its stamp, log and publish time,
and its numbers as IEEE-754 bit patterns, so the Rust test can check they read back exactly.

Exit code 3 (with a message) when a package is missing: the Rust test then skips.
"""

from __future__ import annotations

import contextlib
import json
import random
import struct
import sys
import time
from functools import partial
from pathlib import Path

try:
    import mcap_protobuf.writer
    import mcap_ros2.writer
    from foxglove_schemas_protobuf import (
        FrameTransform_pb2,
        FrameTransforms_pb2,
        Odometry_pb2,
        PoseInFrame_pb2,
        PosesInFrame_pb2,
    )
    from mcap.writer import CompressionType
    from mcap.writer import Writer as McapWriter
    from mcap_ros2._dynamic import serialize_dynamic
except ImportError as error:  # pragma: no cover - depends on the machine
    print(
        f"missing Python package ({error}): pip install mcap mcap-ros2-support "
        "mcap-protobuf-support foxglove-schemas-protobuf",
        file=sys.stderr,
    )
    sys.exit(3)

SEP = "=" * 80

TIME = "int32 sec\nuint32 nanosec\n"
HEADER = "builtin_interfaces/Time stamp\nstring frame_id\n"
POINT = "float64 x\nfloat64 y\nfloat64 z\n"
QUATERNION = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"
POSE = "Point position\nQuaternion orientation\n"
TRANSFORM = "Vector3 translation\nQuaternion rotation\n"
TWIST = "Vector3 linear\nVector3 angular\n"


def msgdef(main: str, *deps: tuple[str, str]) -> str:
    """A ros2msg schema: the main definition, then each dependency after a separator."""
    parts = [main] + [f"{SEP}\nMSG: {name}\n{text}" for name, text in deps]
    return "\n".join(parts)


BASE_DEPS = (
    ("std_msgs/Header", HEADER),
    ("builtin_interfaces/Time", TIME),
)
POSE_DEPS = (
    ("geometry_msgs/Pose", POSE),
    ("geometry_msgs/Point", POINT),
    ("geometry_msgs/Quaternion", QUATERNION),
)
TRANSFORM_STAMPED = msgdef(
    "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
    *BASE_DEPS,
    ("geometry_msgs/Transform", TRANSFORM),
    ("geometry_msgs/Vector3", POINT),
    ("geometry_msgs/Quaternion", QUATERNION),
)
ROS_SCHEMAS = {
    "geometry_msgs/msg/PoseStamped": msgdef(
        "std_msgs/Header header\nPose pose\n", *BASE_DEPS, *POSE_DEPS
    ),
    "geometry_msgs/msg/PoseWithCovarianceStamped": msgdef(
        "std_msgs/Header header\nPoseWithCovariance pose\n",
        *BASE_DEPS,
        ("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"),
        *POSE_DEPS,
    ),
    "geometry_msgs/msg/TransformStamped": TRANSFORM_STAMPED,
    "nav_msgs/msg/Odometry": msgdef(
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
        *BASE_DEPS,
        ("geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"),
        *POSE_DEPS,
        ("geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"),
        ("geometry_msgs/Twist", TWIST),
        ("geometry_msgs/Vector3", POINT),
    ),
    "tf2_msgs/msg/TFMessage": msgdef(
        "geometry_msgs/TransformStamped[] transforms\n",
        (
            "geometry_msgs/TransformStamped",
            "std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
        ),
        *BASE_DEPS,
        ("geometry_msgs/Transform", TRANSFORM),
        ("geometry_msgs/Vector3", POINT),
        ("geometry_msgs/Quaternion", QUATERNION),
    ),
    "std_msgs/msg/String": "string data\n",
    "my_msgs/msg/Custom": "float64 value\n",
}

# name, chunked, compression
MODES = [
    ("unchunked", False, CompressionType.NONE),
    ("chunked", True, CompressionType.NONE),
    ("zstd", True, CompressionType.ZSTD),
    ("lz4", True, CompressionType.LZ4),
]
CHUNK_SIZE = 2048  # small: many chunks
COUNT = 24  # messages per topic


def bits(value: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", value))[0]


@contextlib.contextmanager
def unchunked(module):
    """Makes a high-level writer module build its mcap Writer without chunks."""
    original = module.McapWriter
    module.McapWriter = partial(original, use_chunking=False)
    try:
        yield
    finally:
        module.McapWriter = original


class Poses:
    """Seeded poses with stamps, log and publish times; records what was written."""

    def __init__(self, seed: int):
        self.rng = random.Random(seed)
        self.stamp_ns = 1_700_000_000 * 10**9 + self.rng.randrange(10**9)

    def next_stamp(self) -> int:
        self.stamp_ns += self.rng.randrange(10**6, 10**8)
        return self.stamp_ns

    def pose(self):
        rng = self.rng
        position = [rng.uniform(-500.0, 500.0) for _ in range(3)]
        q = [rng.gauss(0.0, 1.0) for _ in range(4)]
        norm = sum(v * v for v in q) ** 0.5
        return position, [v / norm for v in q]

    def record(self, stamp_ns: int, log_time: int, publish_time: int, position, quaternion) -> dict:
        return {
            "stamp_ns": stamp_ns,
            "log_time": log_time,
            "publish_time": publish_time,
            "p": [bits(v) for v in position],
            "q": [bits(v) for v in quaternion],
        }


def ros_time(stamp_ns: int) -> dict:
    return {"sec": stamp_ns // 10**9, "nanosec": stamp_ns % 10**9}


def ros_pose(position, q) -> dict:
    return {
        "position": dict(zip("xyz", position, strict=True)),
        "orientation": dict(zip("xyzw", q, strict=True)),
    }


def ros_transform(stamp_ns, parent, child, position, q) -> dict:
    return {
        "header": {"stamp": ros_time(stamp_ns), "frame_id": parent},
        "child_frame_id": child,
        "transform": {
            "translation": dict(zip("xyz", position, strict=True)),
            "rotation": dict(zip("xyzw", q, strict=True)),
        },
    }


def topic_entry(schema: str, encoding: str) -> dict:
    return {"schema": schema, "encoding": encoding, "count": 0, "poses": [], "pairs": {}}


def write_ros2(path: Path, chunked: bool, compression, seed: int) -> dict:
    """Every ROS 2 pose type on its own topic, plus a String and an unknown type."""
    poses = Poses(seed)
    topics = {
        "/pose": topic_entry("geometry_msgs/msg/PoseStamped", "cdr"),
        "/pose_cov": topic_entry("geometry_msgs/msg/PoseWithCovarianceStamped", "cdr"),
        "/transform": topic_entry("geometry_msgs/msg/TransformStamped", "cdr"),
        "/odom": topic_entry("nav_msgs/msg/Odometry", "cdr"),
        "/tf": topic_entry("tf2_msgs/msg/TFMessage", "cdr"),
        "/status": topic_entry("std_msgs/msg/String", "cdr"),
        "/custom": topic_entry("my_msgs/msg/Custom", "cdr"),
    }
    context = contextlib.nullcontext() if chunked else unchunked(mcap_ros2.writer)
    with context, open(path, "wb") as stream:
        writer = mcap_ros2.writer.Writer(stream, chunk_size=CHUNK_SIZE, compression=compression)
        schemas = {name: writer.register_msgdef(name, text) for name, text in ROS_SCHEMAS.items()}
        sequence = 0
        for k in range(COUNT):
            for topic, entry in topics.items():
                stamp = poses.next_stamp()
                log_time = stamp + poses.rng.randrange(1, 10**7)
                publish_time = stamp + poses.rng.randrange(1, 10**6)
                schema = entry["schema"]
                if schema == "std_msgs/msg/String":
                    message = {"data": f"status {k}"}
                elif schema == "my_msgs/msg/Custom":
                    message = {"value": float(k)}
                elif schema == "tf2_msgs/msg/TFMessage":
                    transforms = []
                    pairs = [("map", "odom"), ("odom", "base_link")] + (
                        [("base_link", "laser")] if k % 5 == 0 else []
                    )
                    for index, (parent, child) in enumerate(pairs):
                        position, q = poses.pose()
                        transform_stamp = stamp + 1000 * index
                        transforms.append(
                            ros_transform(transform_stamp, parent, child, position, q)
                        )
                        record = poses.record(transform_stamp, log_time, publish_time, position, q)
                        entry["pairs"].setdefault(f"{parent}->{child}", []).append(record)
                    message = {"transforms": transforms}
                else:
                    position, q = poses.pose()
                    record = poses.record(stamp, log_time, publish_time, position, q)
                    if schema == "geometry_msgs/msg/TransformStamped":
                        message = ros_transform(stamp, "map", "base_link", position, q)
                        entry["pairs"].setdefault("map->base_link", []).append(record)
                    else:
                        header = {
                            "stamp": ros_time(stamp),
                            "frame_id": "odom" if "Odometry" in schema else "map",
                        }
                        covariance = [poses.rng.random() for _ in range(36)]
                        pose = ros_pose(position, q)
                        if schema == "geometry_msgs/msg/PoseStamped":
                            message = {"header": header, "pose": pose}
                        elif schema == "geometry_msgs/msg/PoseWithCovarianceStamped":
                            message = {
                                "header": header,
                                "pose": {"pose": pose, "covariance": covariance},
                            }
                        else:
                            twist = {
                                "linear": {"x": 1.0, "y": 2.0, "z": 3.0},
                                "angular": {"x": 0.1, "y": 0.2, "z": 0.3},
                            }
                            message = {
                                "header": header,
                                "child_frame_id": "base_link",
                                "pose": {"pose": pose, "covariance": covariance},
                                "twist": {"twist": twist, "covariance": covariance},
                            }
                        entry["poses"].append(record)
                writer.write_message(
                    topic,
                    schemas[schema],
                    message,
                    log_time=log_time,
                    publish_time=publish_time,
                    sequence=sequence,
                )
                sequence += 1
                entry["count"] += 1
        writer.finish()
    return topics


def proto_time(message, stamp_ns: int):
    message.timestamp.seconds = stamp_ns // 10**9
    message.timestamp.nanos = stamp_ns % 10**9


def set_pose(pose, position, q):
    pose.position.x, pose.position.y, pose.position.z = position
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = q


def set_transform(transform, stamp_ns, parent, child, position, q):
    proto_time(transform, stamp_ns)
    transform.parent_frame_id = parent
    transform.child_frame_id = child
    transform.translation.x, transform.translation.y, transform.translation.z = position
    transform.rotation.x, transform.rotation.y, transform.rotation.z, transform.rotation.w = q


FOXGLOVE_TOPICS = {
    "/fox/pose": "foxglove.PoseInFrame",
    "/fox/poses": "foxglove.PosesInFrame",
    "/fox/tf": "foxglove.FrameTransform",
    "/fox/tfs": "foxglove.FrameTransforms",
    "/fox/odom": "foxglove.Odometry",
}


def foxglove_messages(poses: Poses, topics: dict):
    """(topic, protobuf message, log_time, publish_time) for every Foxglove type, recorded."""
    for _ in range(COUNT):
        for topic, schema in FOXGLOVE_TOPICS.items():
            entry = topics[topic]
            stamp = poses.next_stamp()
            log_time = stamp + poses.rng.randrange(1, 10**7)
            publish_time = stamp + poses.rng.randrange(1, 10**6)
            record = partial(poses.record, log_time=log_time, publish_time=publish_time)

            if schema == "foxglove.PoseInFrame":
                message = PoseInFrame_pb2.PoseInFrame(frame_id="map")
                proto_time(message, stamp)
                position, q = poses.pose()
                set_pose(message.pose, position, q)
                entry["poses"].append(record(stamp, position=position, quaternion=q))
            elif schema == "foxglove.PosesInFrame":
                message = PosesInFrame_pb2.PosesInFrame(frame_id="map")
                proto_time(message, stamp)
                for _ in range(2):
                    position, q = poses.pose()
                    set_pose(message.poses.add(), position, q)
                    entry["poses"].append(record(stamp, position=position, quaternion=q))
            elif schema == "foxglove.FrameTransform":
                message = FrameTransform_pb2.FrameTransform()
                position, q = poses.pose()
                set_transform(message, stamp, "world", "robot", position, q)
                entry["pairs"].setdefault("world->robot", []).append(
                    record(stamp, position=position, quaternion=q)
                )
            elif schema == "foxglove.FrameTransforms":
                message = FrameTransforms_pb2.FrameTransforms()
                for index, (parent, child) in enumerate([("world", "odom"), ("odom", "robot")]):
                    position, q = poses.pose()
                    set_transform(
                        message.transforms.add(), stamp + 1000 * index, parent, child, position, q
                    )
                    record_ = record(stamp + 1000 * index, position=position, quaternion=q)
                    entry["pairs"].setdefault(f"{parent}->{child}", []).append(record_)
            else:
                message = Odometry_pb2.Odometry(frame_id="odom", body_frame_id="robot")
                proto_time(message, stamp)
                position, q = poses.pose()
                set_pose(message.pose, position, q)
                message.linear_velocity.x = 1.0
                entry["poses"].append(record(stamp, position=position, quaternion=q))
            entry["count"] += 1
            yield topic, message, log_time, publish_time


def write_protobuf(path: Path, chunked: bool, compression, seed: int) -> dict:
    topics = {topic: topic_entry(schema, "protobuf") for topic, schema in FOXGLOVE_TOPICS.items()}
    context = contextlib.nullcontext() if chunked else unchunked(mcap_protobuf.writer)
    with context, open(path, "wb") as stream:
        writer = mcap_protobuf.writer.Writer(stream, chunk_size=CHUNK_SIZE, compression=compression)
        for sequence, (topic, message, log_time, publish_time) in enumerate(
            foxglove_messages(Poses(seed), topics)
        ):
            writer.write_message(
                topic, message, log_time=log_time, publish_time=publish_time, sequence=sequence
            )
        writer.finish()
    return topics


def json_time(stamp_ns: int) -> dict:
    return {"sec": stamp_ns // 10**9, "nsec": stamp_ns % 10**9}


def to_json(message) -> dict:
    """Foxglove's JSON encoding of a protobuf message: field names, timestamps as sec/nsec."""
    out = {}
    for field, value in message.ListFields():
        repeated = (
            field.is_repeated
            if hasattr(field, "is_repeated")
            else field.label == field.LABEL_REPEATED
        )
        if (
            field.message_type is not None
            and field.message_type.full_name == "google.protobuf.Timestamp"
        ):
            out[field.name] = json_time(value.seconds * 10**9 + value.nanos)
        elif field.message_type is not None and repeated:
            out[field.name] = [to_json(item) for item in value]
        elif field.message_type is not None:
            out[field.name] = to_json(value)
        elif repeated:
            out[field.name] = list(value)
        else:
            out[field.name] = value
    return out


def write_json(path: Path, chunked: bool, compression, seed: int) -> dict:
    topics = {topic: topic_entry(schema, "json") for topic, schema in FOXGLOVE_TOPICS.items()}
    with open(path, "wb") as stream:
        writer = McapWriter(
            stream, chunk_size=CHUNK_SIZE, compression=compression, use_chunking=chunked
        )
        writer.start(profile="", library="loops-io fixtures (mcap json)")
        channels = {}
        for topic, schema in FOXGLOVE_TOPICS.items():
            schema_id = writer.register_schema(
                name=schema,
                encoding="jsonschema",
                data=json.dumps({"title": schema, "type": "object"}).encode(),
            )
            channels[topic] = writer.register_channel(
                topic=topic, message_encoding="json", schema_id=schema_id
            )
        for sequence, (topic, message, log_time, publish_time) in enumerate(
            foxglove_messages(Poses(seed), topics)
        ):
            data = json.dumps(to_json(message)).encode()
            writer.add_message(
                channels[topic],
                log_time=log_time,
                data=data,
                publish_time=publish_time,
                sequence=sequence,
            )
        writer.finish()
    return topics


def ros2_encoder(schema: str):
    return serialize_dynamic(schema, ROS_SCHEMAS[schema])[schema]


def write_special(out: Path) -> dict:
    """Files for picking topics, splitting a recording, and broken messages."""
    files = {}
    pose_schema = "geometry_msgs/msg/PoseStamped"

    # One pose topic among a TF topic and a String topic: picked automatically.
    poses = Poses(7)
    topics = {
        "/robot/pose": topic_entry(pose_schema, "cdr"),
        "/tf": topic_entry("tf2_msgs/msg/TFMessage", "cdr"),
    }
    with open(out / "auto_pick.mcap", "wb") as stream:
        writer = mcap_ros2.writer.Writer(stream)
        schemas = {name: writer.register_msgdef(name, ROS_SCHEMAS[name]) for name in ROS_SCHEMAS}
        for k in range(COUNT):
            stamp = poses.next_stamp()
            position, q = poses.pose()
            message = {
                "header": {"stamp": ros_time(stamp), "frame_id": "map"},
                "pose": ros_pose(position, q),
            }
            writer.write_message(
                "/robot/pose", schemas[pose_schema], message, log_time=stamp, publish_time=stamp
            )
            topics["/robot/pose"]["poses"].append(poses.record(stamp, stamp, stamp, position, q))
            tf = {"transforms": [ros_transform(stamp, "map", "base_link", position, q)]}
            writer.write_message(
                "/tf", schemas["tf2_msgs/msg/TFMessage"], tf, log_time=stamp, publish_time=stamp
            )
            writer.write_message(
                "/status",
                schemas["std_msgs/msg/String"],
                {"data": str(k)},
                log_time=stamp,
                publish_time=stamp,
            )
        writer.finish()
    files["auto_pick.mcap"] = topics

    # Two pose topics: no automatic pick.
    with open(out / "two_pose_topics.mcap", "wb") as stream:
        writer = mcap_ros2.writer.Writer(stream)
        pose = writer.register_msgdef(pose_schema, ROS_SCHEMAS[pose_schema])
        odom = writer.register_msgdef("nav_msgs/msg/Odometry", ROS_SCHEMAS["nav_msgs/msg/Odometry"])
        for k in range(3):
            header = {"stamp": ros_time(10**9 * (k + 1)), "frame_id": "map"}
            writer.write_message("/a", pose, {"header": header}, log_time=k + 1)
            writer.write_message("/b", odom, {"header": header}, log_time=k + 1)
        writer.finish()
    files["two_pose_topics.mcap"] = {}

    # One recording split in two files, messages alternating between them.
    poses = Poses(11)
    split = {"/pose": topic_entry(pose_schema, "cdr")}
    writers = []
    for name in ("split_even.mcap", "split_odd.mcap"):
        stream = open(out / name, "wb")
        writer = mcap_ros2.writer.Writer(stream, compression=CompressionType.LZ4)
        writers.append(
            (stream, writer, writer.register_msgdef(pose_schema, ROS_SCHEMAS[pose_schema]))
        )
    for k in range(2 * COUNT):
        stamp = poses.next_stamp()
        position, q = poses.pose()
        _, writer, schema = writers[k % 2]
        message = {
            "header": {"stamp": ros_time(stamp), "frame_id": "map"},
            "pose": ros_pose(position, q),
        }
        writer.write_message("/pose", schema, message, log_time=stamp + 5, publish_time=stamp + 3)
        split["/pose"]["poses"].append(poses.record(stamp, stamp + 5, stamp + 3, position, q))
    for stream, writer, _ in writers:
        writer.finish()
        stream.close()
    files["split"] = split

    # A pose topic with a channel and no message, beside a String topic with messages.
    with open(out / "empty_topic.mcap", "wb") as stream:
        writer = McapWriter(stream)
        writer.start(profile="ros2", library="loops-io fixtures (mcap)")
        schema_id = writer.register_schema(
            pose_schema, "ros2msg", ROS_SCHEMAS[pose_schema].encode()
        )
        writer.register_channel(topic="/pose", message_encoding="cdr", schema_id=schema_id)
        string_id = writer.register_schema(
            "std_msgs/msg/String", "ros2msg", ROS_SCHEMAS["std_msgs/msg/String"].encode()
        )
        status = writer.register_channel(
            topic="/status", message_encoding="cdr", schema_id=string_id
        )
        encode = ros2_encoder("std_msgs/msg/String")
        for k in range(3):
            writer.add_message(status, log_time=k, data=encode({"data": "idle"}), publish_time=k)
        writer.finish()
    files["empty_topic.mcap"] = {}

    # No topic of a pose type: a String topic and one of an unknown type.
    with open(out / "no_pose_topic.mcap", "wb") as stream:
        writer = mcap_ros2.writer.Writer(stream)
        string = writer.register_msgdef("std_msgs/msg/String", ROS_SCHEMAS["std_msgs/msg/String"])
        custom = writer.register_msgdef("my_msgs/msg/Custom", ROS_SCHEMAS["my_msgs/msg/Custom"])
        for k in range(3):
            writer.write_message("/status", string, {"data": "idle"}, log_time=k)
            writer.write_message("/custom", custom, {"value": 1.5}, log_time=k)
        writer.finish()
    files["no_pose_topic.mcap"] = {}

    # A PoseStamped message 8 bytes shorter than its type (the 4th), unchunked and in a chunk.
    encode = ros2_encoder(pose_schema)
    for name, chunked in (("short_cdr.mcap", False), ("short_cdr_chunked.mcap", True)):
        with open(out / name, "wb") as stream:
            writer = McapWriter(stream, use_chunking=chunked, compression=CompressionType.ZSTD)
            writer.start(profile="ros2", library="loops-io fixtures (mcap)")
            schema_id = writer.register_schema(
                pose_schema, "ros2msg", ROS_SCHEMAS[pose_schema].encode()
            )
            channel = writer.register_channel(
                topic="/pose", message_encoding="cdr", schema_id=schema_id
            )
            for k in range(6):
                message = {
                    "header": {"stamp": ros_time(10**9 * (k + 1)), "frame_id": "map"},
                    "pose": ros_pose([k, 0, 0], [0, 0, 0, 1]),
                }
                data = encode(message)
                writer.add_message(
                    channel, log_time=k, data=data[:-8] if k == 3 else data, publish_time=k
                )
            writer.finish()
        files[name] = {}
    return files


def write_bench(path: Path, count: int) -> None:
    """`count` PoseStamped at 100 Hz, with the ROS 2 writer's defaults (zstd, 1 MiB chunks)."""
    rng = random.Random(1)
    schema_name = "geometry_msgs/msg/PoseStamped"
    start = time.perf_counter()
    with open(path, "wb") as stream:
        writer = mcap_ros2.writer.Writer(stream)
        schema = writer.register_msgdef(schema_name, ROS_SCHEMAS[schema_name])
        stamp = 1_700_000_000 * 10**9
        for _ in range(count):
            stamp += 10**7
            position = [rng.uniform(-500, 500) for _ in range(3)]
            message = {
                "header": {"stamp": ros_time(stamp), "frame_id": "map"},
                "pose": ros_pose(position, [0, 0, 0, 1]),
            }
            writer.write_message("/pose", schema, message, log_time=stamp, publish_time=stamp)
        writer.finish()
    print(f"wrote {count} PoseStamped to {path} in {time.perf_counter() - start:.1f} s")


def read_python(path: Path) -> None:
    """The Python reference: mcap's reader with mcap-ros2-support's decoder, poses into lists."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    start = time.perf_counter()
    stamps, positions, orientations = [], [], []
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        for _, _, _, message in reader.iter_decoded_messages(topics=["/pose"]):
            stamp = message.header.stamp
            stamps.append(stamp.sec * 10**9 + stamp.nanosec)
            p, q = message.pose.position, message.pose.orientation
            positions.append((p.x, p.y, p.z))
            orientations.append((q.x, q.y, q.z, q.w))
    seconds = time.perf_counter() - start
    rate = len(stamps) / seconds
    print(f"mcap + mcap-ros2-support: {len(stamps)} poses in {seconds:.2f} s ({rate:.0f} poses/s)")


def main(argv: list[str]) -> None:
    if len(argv) == 3 and argv[0] == "--bench":
        write_bench(Path(argv[2]), int(float(argv[1])))
        return
    if len(argv) == 2 and argv[0] == "--read":
        read_python(Path(argv[1]))
        return
    if len(argv) != 1 or argv[0].startswith("-"):
        sys.exit(__doc__)
    out = Path(argv[0])
    out.mkdir(parents=True, exist_ok=True)
    manifest = {"files": []}
    for index, (mode, chunked, compression) in enumerate(MODES):
        for family, write in (
            ("ros2", write_ros2),
            ("protobuf", write_protobuf),
            ("json", write_json),
        ):
            name = f"{family}_{mode}.mcap"
            topics = write(out / name, chunked, compression, seed=100 * index + len(family))
            manifest["files"].append(
                {
                    "name": name,
                    "family": family,
                    "chunked": chunked,
                    "compression": mode,
                    "topics": topics,
                }
            )
    manifest["special"] = write_special(out)
    (out / "manifest.json").write_text(json.dumps(manifest))


if __name__ == "__main__":
    main(sys.argv[1:])

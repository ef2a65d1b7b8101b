#!/usr/bin/env python3
"""Reference logs for twinloop-logs, written by the reference Python libraries.

Writes into crates/twinloop-logs/tests/data/:

* joints_zstd.mcap, joints_lz4.mcap: `mcap` 1.6 + `mcap-ros2-support` 0.6
  (`mcap_ros2.writer.Writer`, chunked; zstd is the library's default, lz4 the other
  compression the MCAP spec names), small chunks so there are several.
* bag_mcap/, bag_db3/: rosbag2 folders (metadata.yaml version 9) by `rosbags` 0.11
  with MCAP and SQLite3 storage.
* expected.json: every value written, as the hex of its f64 bits, so the Rust test
  compares to the last bit.

Topics: /joint_states (sensor_msgs/JointState, 3 joints, position velocity effort),
/imu (sensor_msgs/Imu), /plate (geometry_msgs/WrenchStamped), /array
(std_msgs/Float64MultiArray, 2 values, no labels), /tf (tf2_msgs/TFMessage, world ->
base_link), /chatter (std_msgs/String, which twinloop does not read). Values are
awkward on purpose: thirds, pi multiples, a subnormal, -0.0, huge and tiny numbers.

    pip install mcap==1.6.0 mcap-ros2-support==0.6.0 rosbags==0.11.9
    python3 tools/oracle/logs_reference.py
"""
import json
import math
import pathlib
import shutil
import struct

from mcap.writer import CompressionType
from mcap_ros2.writer import Writer as Ros2Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as BagWriter
from rosbags.typesys import Stores, get_typestore

OUT = pathlib.Path(__file__).resolve().parents[2] / "crates/twinloop-logs/tests/data"
JOINTS = ["l_hip_pitch", "l_knee", "r_ankle_roll"]
N = 40
T0 = 1_700_000_000_123_456_789  # ns: a 2023 stamp, ns digits all used
DT = 1_000_000  # 1 kHz
TS = get_typestore(Stores.ROS2_HUMBLE)


def bits(x):
    return "%016x" % struct.unpack("<Q", struct.pack("<d", x))[0]


def joint_values(k):
    q = [math.pi * k / 7.0, (k + 1) / 3.0, -0.0 if k == 0 else 5e-324 * k]
    v = [1e300 / (k + 1), -1.0 / (k + 3), math.sqrt(k)]
    e = [math.e ** (k % 5), -k * 0.1, 1e-310]
    return q, v, e


def stamp(k):
    return T0 + k * DT


def imu_values(k):
    return [0.01 * k, -0.02 * k, 1.0 / 3.0 + k, 9.81, -0.5 * k, k / 7.0]


def wrench_values(k):
    return [1.5 * k, -2.5, 300.0 + k / 3.0, 0.1 * k, -0.2, 0.7]


def tf_values(k):
    c, s = math.cos(0.01 * k), math.sin(0.01 * k)
    return [0.001 * k, 0.0, 0.8, 0.0, 0.0, s, c]


def messages():
    """(topic, type, fields) for every message, in log order."""
    T = TS.types
    time = T["builtin_interfaces/msg/Time"]
    header = T["std_msgs/msg/Header"]
    v3 = T["geometry_msgs/msg/Vector3"]
    quat = T["geometry_msgs/msg/Quaternion"]
    import numpy as np
    for k in range(N):
        ns = stamp(k)
        h = header(stamp=time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="")
        q, v, e = joint_values(k)
        yield k, "/joint_states", "sensor_msgs/msg/JointState", T["sensor_msgs/msg/JointState"](
            header=h, name=JOINTS, position=np.array(q), velocity=np.array(v), effort=np.array(e))
        if k % 2 == 0:
            g = imu_values(k)
            hi = header(stamp=h.stamp, frame_id="imu_link")
            yield k, "/imu", "sensor_msgs/msg/Imu", T["sensor_msgs/msg/Imu"](
                header=hi, orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=np.zeros(9), angular_velocity=v3(x=g[0], y=g[1], z=g[2]),
                angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(x=g[3], y=g[4], z=g[5]),
                linear_acceleration_covariance=np.zeros(9))
            w = wrench_values(k)
            hp = header(stamp=h.stamp, frame_id="plate")
            yield k, "/plate", "geometry_msgs/msg/WrenchStamped", T["geometry_msgs/msg/WrenchStamped"](
                header=hp, wrench=T["geometry_msgs/msg/Wrench"](force=v3(x=w[0], y=w[1], z=w[2]),
                                                              torque=v3(x=w[3], y=w[4], z=w[5])))
        lay = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
        yield k, "/array", "std_msgs/msg/Float64MultiArray", T["std_msgs/msg/Float64MultiArray"](
            layout=lay, data=np.array([k / 3.0, -k * math.pi]))
        p = tf_values(k)
        tr = T["geometry_msgs/msg/TransformStamped"](
            header=header(stamp=h.stamp, frame_id="world"), child_frame_id="base_link",
            transform=T["geometry_msgs/msg/Transform"](translation=v3(x=p[0], y=p[1], z=p[2]),
                                                       rotation=quat(x=p[3], y=p[4], z=p[5], w=p[6])))
        yield k, "/tf", "tf2_msgs/msg/TFMessage", T["tf2_msgs/msg/TFMessage"](transforms=[tr])
        if k == 0:
            yield k, "/chatter", "std_msgs/msg/String", T["std_msgs/msg/String"](data="hello")


def msgdef(typename):
    """The ros2msg schema text (definition + dependencies) rosbag2 would record."""
    return TS.generate_msgdef(typename, ros_version=2)[0]


def write_mcap(path, compression):
    with open(path, "wb") as f:
        w = Ros2Writer(f, chunk_size=4096, compression=compression)
        schemas = {}
        for k, topic, typ, msg in messages():
            if typ not in schemas:
                schemas[typ] = w.register_msgdef(typ, msgdef(typ))
            data = TS.serialize_cdr(msg, typ)
            # Log time = the stamp + 0.5 ms: a reader that used it would be off.
            w.write_message(topic, schemas[typ], msg_to_dict(msg), log_time=stamp(k) + 500_000,
                            publish_time=stamp(k) + 500_000, sequence=k)
        w.finish()


def msg_to_dict(msg):
    """rosbags' message object as the plain dict mcap_ros2's encoder takes."""
    import numpy as np
    if hasattr(msg, "__dataclass_fields__"):
        return {k: msg_to_dict(getattr(msg, k)) for k in msg.__dataclass_fields__ if k != "__msgtype__"}
    if isinstance(msg, np.ndarray):
        return [float(x) for x in msg]
    if isinstance(msg, list):
        return [msg_to_dict(x) for x in msg]
    return msg


def write_bag(path, plugin):
    if path.exists():
        shutil.rmtree(path)
    with BagWriter(path, version=9, storage_plugin=plugin) as w:
        conns = {}
        for k, topic, typ, msg in messages():
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=TS)
            w.write(conns[topic], stamp(k) + 500_000, TS.serialize_cdr(msg, typ))


def expected():
    rows = []
    for k in range(N):
        q, v, e = joint_values(k)
        rows.append({"stamp": stamp(k), "q": [bits(x) for x in q], "v": [bits(x) for x in v],
                     "tau": [bits(x) for x in e], "imu": [bits(x) for x in imu_values(k)],
                     "wrench": [bits(x) for x in wrench_values(k)],
                     "array": [bits(k / 3.0), bits(-k * math.pi)],
                     "tf": [bits(x) for x in tf_values(k)]})
    return {"joints": JOINTS, "log_offset_ns": 500_000, "rows": rows}


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    write_mcap(OUT / "joints_zstd.mcap", CompressionType.ZSTD)
    write_mcap(OUT / "joints_lz4.mcap", CompressionType.LZ4)
    write_bag(OUT / "bag_mcap", StoragePlugin.MCAP)
    write_bag(OUT / "bag_db3", StoragePlugin.SQLITE3)
    (OUT / "expected.json").write_text(json.dumps(expected(), indent=1) + "\n")


if __name__ == "__main__":
    main()

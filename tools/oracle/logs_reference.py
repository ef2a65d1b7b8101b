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

With `--from-csv TABLE.csv OUT.mcap OUT_BAG/` it writes a twinloop CSV table as a
team's recorder would: an MCAP (`mcap-ros2-support`) and a rosbag2 folder with MCAP
storage (`rosbags`), one message per topic per row, stamped at T0 + t (t to the
ns): `q:<j>` (with `v:<j>`, `tau:<j>` when every joint has one) as a JointState on
/joint_states, `q:base.*` as a TFMessage world -> base_link on /tf, `imu:<l>.gx..az`
as an Imu on /imu/<l>, `wrench:<f>.fx..tz` as a WrenchStamped on /wrench/<f>, and
every other column on /columns, a Float64MultiArray whose one dimension's label
names them (so twinloop reads them with no --topic). The tests that give a command
the same data as CSV and as a log (cli_logs.rs) use it.
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


def read_csv(path):
    """A twinloop CSV table: its columns and rows (comment lines skipped)."""
    import csv
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#") and l.strip()]
    rows = list(csv.reader(lines))
    return rows[0], [[float(x) for x in r] for r in rows[1:]]


def table_messages(columns, rows):
    """(stamp ns, topic, type, message) for every row of a twinloop table."""
    import numpy as np
    T = TS.types
    col = {c: i for i, c in enumerate(columns)}
    v3, quat = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    joints = [c[2:] for c in columns if c.startswith("q:") and not c.startswith("q:base.")]
    have = lambda p: joints and all(p + j in col for j in joints)
    fields = [("q:", True), ("v:", have("v:")), ("tau:", have("tau:"))]
    base = ["q:base." + s for s in ("x", "y", "z", "qx", "qy", "qz", "qw")]
    base = base if all(b in col for b in base) else []
    six = lambda pre, names: {c[len(pre):-len(names[0]) - 1] for c in columns
                              if c.startswith(pre) and c.endswith("." + names[0])}
    imus = sorted(six("imu:", ["gx"]))
    wrenches = sorted(six("wrench:", ["fx"]))
    gi, wi = ("gx", "gy", "gz", "ax", "ay", "az"), ("fx", "fy", "fz", "tx", "ty", "tz")
    used = {"t"} | {p + j for p, on in fields if on for j in joints} | set(base)
    used |= {"imu:%s.%s" % (l, s) for l in imus for s in gi}
    used |= {"wrench:%s.%s" % (l, s) for l in wrenches for s in wi}
    rest = [c for c in columns if c not in used]
    label = ",".join(rest)
    for r in rows:
        ns = T0 + round(r[col["t"]] * 1e9)
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        header = lambda frame: T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)
        arr = lambda p: np.array([r[col[p + j]] for j in joints]) if have(p) else np.array([])
        if joints:
            yield ns, "/joint_states", "sensor_msgs/msg/JointState", T["sensor_msgs/msg/JointState"](
                header=header(""), name=joints, position=np.array([r[col["q:" + j]] for j in joints]),
                velocity=arr("v:"), effort=arr("tau:"))
        if base:
            p = [r[col[b]] for b in base]
            tr = T["geometry_msgs/msg/TransformStamped"](
                header=header("world"), child_frame_id="base_link",
                transform=T["geometry_msgs/msg/Transform"](
                    translation=v3(x=p[0], y=p[1], z=p[2]), rotation=quat(x=p[3], y=p[4], z=p[5], w=p[6])))
            yield ns, "/tf", "tf2_msgs/msg/TFMessage", T["tf2_msgs/msg/TFMessage"](transforms=[tr])
        for l in imus:
            g = [r[col["imu:%s.%s" % (l, s)]] for s in gi]
            yield ns, "/imu/" + l, "sensor_msgs/msg/Imu", T["sensor_msgs/msg/Imu"](
                header=header(l), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=np.zeros(9), angular_velocity=v3(x=g[0], y=g[1], z=g[2]),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=v3(x=g[3], y=g[4], z=g[5]), linear_acceleration_covariance=np.zeros(9))
        for f in wrenches:
            w = [r[col["wrench:%s.%s" % (f, s)]] for s in wi]
            yield ns, "/wrench/" + f, "geometry_msgs/msg/WrenchStamped", T["geometry_msgs/msg/WrenchStamped"](
                header=header(f), wrench=T["geometry_msgs/msg/Wrench"](
                    force=v3(x=w[0], y=w[1], z=w[2]), torque=v3(x=w[3], y=w[4], z=w[5])))
        if rest:
            dim = T["std_msgs/msg/MultiArrayDimension"](label=label, size=len(rest), stride=len(rest))
            lay = T["std_msgs/msg/MultiArrayLayout"](dim=[dim], data_offset=0)
            yield ns, "/columns", "std_msgs/msg/Float64MultiArray", T["std_msgs/msg/Float64MultiArray"](
                layout=lay, data=np.array([r[col[c]] for c in rest]))


def from_csv(csv_path, mcap_path, bag_path):
    columns, rows = read_csv(csv_path)
    msgs = list(table_messages(columns, rows))
    with open(mcap_path, "wb") as f:
        w = Ros2Writer(f)
        schemas = {}
        for k, (ns, topic, typ, msg) in enumerate(msgs):
            if typ not in schemas:
                schemas[typ] = w.register_msgdef(typ, msgdef(typ))
            w.write_message(topic, schemas[typ], msg_to_dict(msg), log_time=ns, publish_time=ns, sequence=k)
        w.finish()
    bag = pathlib.Path(bag_path)
    if bag.exists():
        shutil.rmtree(bag)
    with BagWriter(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = {}
        for ns, topic, typ, msg in msgs:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=TS)
            w.write(conns[topic], ns, TS.serialize_cdr(msg, typ))


def main():
    import sys
    if len(sys.argv) == 5 and sys.argv[1] == "--from-csv":
        return from_csv(*sys.argv[2:])
    OUT.mkdir(parents=True, exist_ok=True)
    write_mcap(OUT / "joints_zstd.mcap", CompressionType.ZSTD)
    write_mcap(OUT / "joints_lz4.mcap", CompressionType.LZ4)
    write_bag(OUT / "bag_mcap", StoragePlugin.MCAP)
    write_bag(OUT / "bag_db3", StoragePlugin.SQLITE3)
    (OUT / "expected.json").write_text(json.dumps(expected(), indent=1) + "\n")


if __name__ == "__main__":
    main()

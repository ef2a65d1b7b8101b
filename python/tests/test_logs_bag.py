"""Recordings written as rosbag2 folders (`--out NAME/`, docs/logs.md, Writing) open in
ROS 2's tools: the reference reader `rosbags` (which, like `ros2 bag`, reads a folder's
metadata.yaml, not a bare .mcap) finds the topics, types and message counts, and every
value the CSV of the same run holds, to the bit.
"""

import subprocess

import numpy as np

from conftest import oracle
from test_cli_parity import cli


def read_bag(path):
    """{topic: (type, count the metadata says)} and {topic: [(log time, message)]}."""
    rosbag2, typesys = oracle("rosbags.rosbag2"), oracle("rosbags.typesys")
    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    msgs = {}
    with rosbag2.Reader(path) as r:
        topics = {c.topic: (c.msgtype, c.msgcount) for c in r.connections}
        for c, t, raw in r.messages():
            msgs.setdefault(c.topic, []).append((t, store.deserialize_cdr(raw, c.msgtype)))
    return topics, msgs


def read_csv(path):
    """A twinloop CSV: {column: values}, every value parsed exactly."""
    lines = [l for l in path.read_text().splitlines() if l and not l.startswith("#")]
    cols = lines[0].split(",")
    data = np.array([[float(x) for x in l.split(",")] for l in lines[1:]])
    return {c: data[:, i] for i, c in enumerate(cols)}, cols


def stamp(msg):
    return msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec


def run_both(tmp_path, args):
    """`args` with --out NAME.csv and --out NAME/: the CSV's columns and the bag."""
    exe = cli()
    csv, bag = tmp_path / "run.csv", tmp_path / "run"
    for out in (str(csv), str(bag) + "/"):
        subprocess.run([exe, *args, "--out", out], check=True, capture_output=True, timeout=120)
    assert sorted(p.name for p in bag.iterdir()) == ["metadata.yaml", "run_0.mcap"]
    return read_csv(csv), read_bag(bag)


def check_joint_states(msgs, table, cols):
    names = [c[2:] for c in cols if c.startswith("q:") and not c.startswith("q:base.")]
    ns = np.round(table["t"] * 1e9).astype(np.int64)
    for k, (t, m) in enumerate(msgs):
        assert list(m.name) == names
        assert t == stamp(m) == ns[k]
        for field, prefix in (("position", "q:"), ("velocity", "v:"), ("effort", "tau:")):
            want = [table[prefix + n][k] for n in names] if f"{prefix}{names[0]}" in table else []
            assert np.array_equal(np.asarray(getattr(m, field)), np.asarray(want)), (field, k)


def test_simulate_out_folder_is_a_bag_rosbags_reads_as_the_csv(tmp_path):
    (table, cols), (topics, msgs) = run_both(
        tmp_path, ["simulate", "--robot", "builtin:km20", "--duration", "0.05"])
    n = len(table["t"])
    assert topics == {
        "/joint_states": ("sensor_msgs/msg/JointState", n),
        "/tf": ("tf2_msgs/msg/TFMessage", n),
        "/imu": ("sensor_msgs/msg/Imu", n),
        "/twinloop/columns": ("std_msgs/msg/Float64MultiArray", n),
        "/robot_description": ("std_msgs/msg/String", 1),
    }
    assert {t: len(m) for t, m in msgs.items()} == {t: c for t, (_, c) in topics.items()}
    check_joint_states(msgs["/joint_states"], table, cols)
    base = [table["q:base." + s] for s in ("x", "y", "z", "qx", "qy", "qz", "qw")]
    for k, (_, m) in enumerate(msgs["/tf"]):
        (tr,) = m.transforms
        p, q = tr.transform.translation, tr.transform.rotation
        assert (tr.header.frame_id, tr.child_frame_id) == ("world", "torso")  # km20's root link
        assert [p.x, p.y, p.z, q.x, q.y, q.z, q.w] == [b[k] for b in base]
    imu = [c for c in cols if c.startswith("imu:")]
    link = imu[0][4:].rsplit(".", 1)[0]
    for k, (_, m) in enumerate(msgs["/imu"]):
        g, a = m.angular_velocity, m.linear_acceleration
        want = [table[f"imu:{link}.{s}"][k] for s in ("gx", "gy", "gz", "ax", "ay", "az")]
        assert m.header.frame_id == link and [g.x, g.y, g.z, a.x, a.y, a.z] == want
    for k, (_, m) in enumerate(msgs["/twinloop/columns"]):
        (dim,) = m.layout.dim
        names = dim.label.split(",")
        assert np.array_equal(m.data, [table[c][k] for c in names], equal_nan=True)  # a foot off the ground: no CoP
    (_, description), = msgs["/robot_description"]
    assert description.data.startswith("<?xml") and 'name="l_knee"' in description.data


def test_experiment_lean_out_folder_is_a_bag_rosbags_reads_as_the_csv(tmp_path):
    # A recording opened through twinloop_io::open_recording (the guarded robot's,
    # the servo log's path), not the simulator's writer.
    (table, cols), (topics, msgs) = run_both(
        tmp_path, ["experiment", "lean", "--robot", "builtin:km20", "--amplitude", "1", "--ramp", "0.2",
                   "--hold", "0.1", "--settle", "0.1"])
    n = len(table["t"])
    assert topics == {
        "/joint_states": ("sensor_msgs/msg/JointState", n),
        "/twinloop/columns": ("std_msgs/msg/Float64MultiArray", n),
    }
    assert {t: len(m) for t, m in msgs.items()} == {"/joint_states": n, "/twinloop/columns": n}
    check_joint_states(msgs["/joint_states"], table, cols)
    for k, (_, m) in enumerate(msgs["/twinloop/columns"]):
        names = m.layout.dim[0].label.split(",")
        assert names[0].startswith("tilt:") and any(c.startswith("goal:") for c in names)
        assert np.array_equal(m.data, [table[c][k] for c in names], equal_nan=True)

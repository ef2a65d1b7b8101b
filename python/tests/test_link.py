"""The link client against a virtual robot served on a pseudo-terminal (no hardware)."""

import subprocess

import numpy as np
import pytest

import twinloop as tl
from conftest import oracle


@pytest.fixture(scope="module")
def server():
    with tl.VirtualRobotServer("builtin:km20", mapping="builtin:km20") as srv:
        yield srv


def bus_of(server):
    # Generous reply timeout and retries: the test machine may be busy.
    return tl.Bus(server.path, timeout_ms=100.0, retries=5)


def test_scan_finds_the_mapped_servos(server):
    bus = bus_of(server)
    found = bus.scan(protocol=1, ids=(1, 20))
    assert len(found) == 20  # km20's twenty joints, on RX-28 and RX-64 servos
    assert {s["model"] for s in found} == {"RX-28", "RX-64"}
    assert all(set(s) == {"protocol", "id", "model", "model_number", "firmware"} for s in found)
    assert [s["id"] for s in found] == list(range(1, 21))
    del bus  # one owner per port: this bus lets the port go before another opens it
    assert tl.Bus(server.path, timeout_ms=20.0, retries=0).scan(protocol=2, ids=(0, 3)) == []  # no Protocol 2.0


def test_read_a_control_table(server):
    bus = bus_of(server)
    servo = bus.scan(protocol=1, ids=(1, 1))[0]
    r = bus.read(servo["id"], protocol=1)
    assert r["model"] == "RX-28" and r["id"] == servo["id"]
    regs = {x["name"]: x for x in r["registers"]}
    assert regs["Model Number"]["raw"] == servo["model_number"]
    one = bus.read(servo["id"], protocol=1, registers=["Model Number"])
    assert [x["name"] for x in one["registers"]] == ["Model Number"]
    with pytest.raises(ValueError, match="^registers:"):
        bus.read(servo["id"], protocol=1, registers=["No Such Register"])
    with pytest.raises(ValueError, match="^protocol:"):
        bus.read(servo["id"], protocol=3)


def test_port_errors_are_os_errors(tmp_path):
    with pytest.raises(OSError):
        tl.Bus(str(tmp_path / "no-such-port"))


def km20_joint_ids():
    """Joint name -> servo id from the km20 mapping file (zero offsets 0, directions +1)."""
    import tomllib

    from conftest import REPO

    text = (REPO / "crates" / "twinloop-link" / "src" / "mappings" / "km20.toml").read_text()
    return {j["name"]: j["id"] for j in tomllib.loads(text)["joint"]}


def test_record_reads_what_the_registers_say(server, tmp_path):
    ids = km20_joint_ids()
    bus = bus_of(server)
    out = tmp_path / "rec.csv"
    rec = bus.record(0.6, map="builtin:km20", rate=50.0, out=out)
    names = list(ids)
    assert rec["columns"] == ["t"] + [f"{p}:{n}" for p in ("q", "v", "tau") for n in names]
    data = rec["data"]
    assert data.shape == (rec["rows"], 1 + 3 * len(names)) and rec["rows"] >= 5
    assert data.flags.writeable and not rec["interrupted"]
    assert set(rec["failures"]) == set(names) and sum(rec["failures"].values()) == 0
    assert np.all(np.diff(data[:, 0]) > 0) and np.isfinite(data).all()
    # The file holds the same rows at full precision.
    header = out.read_text().splitlines()[0].split(",")
    assert header == rec["columns"]
    np.testing.assert_array_equal(np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2), data)
    # Independent: each joint's angle is its servo's Present Position register, read on
    # its own (km20: zero 0, direction +1); the robot stands still, within 2 counts.
    last = dict(zip(rec["columns"], data[-1]))
    for name, sid in ids.items():
        reg = bus.read(sid, protocol=1, registers=["Present Position"])["registers"][0]
        assert abs(last[f"q:{name}"] - reg["value"]) < 2 * 0.0051, name


def test_record_by_ids_and_the_cli_agree(server, tmp_path):
    bus = bus_of(server)
    rec = bus.record(0.4, protocol=1, ids=[1, 2, 13], rate=0.0)
    assert rec["columns"][:4] == ["t", "q:id1", "q:id2", "q:id13"] and rec["data"].shape[1] == 10
    del bus
    from test_cli_parity import cli

    csv = tmp_path / "cli.csv"
    subprocess.run([cli(), "link", "record", "--port", server.path, "--protocol", "1", "--ids", "1,2,13",
                    "--duration", "0.4", "--rate", "0", "--timeout-ms", "100", "--retries", "5", "--out", str(csv)],
                   check=True, capture_output=True, timeout=120)
    theirs = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    assert csv.read_text().splitlines()[0].split(",") == rec["columns"]
    # The robot holds still: the same angles through both (within a count).
    np.testing.assert_allclose(np.median(theirs[:, 1:4], axis=0), np.median(rec["data"][:, 1:4], axis=0), atol=0.0052)


def test_record_bad_input(server, tmp_path):
    bus = bus_of(server)
    with pytest.raises(ValueError, match="^duration:"):
        bus.record(0.0, map="builtin:km20")
    with pytest.raises(ValueError, match="give map=MAPPING"):
        bus.record(1.0)
    with pytest.raises(ValueError, match="^method:"):
        bus.record(1.0, map="builtin:km20", method="telepathy")
    # Protocol 1.0 servos have no SYNC_READ: refused before the bus is lent, which stays usable.
    with pytest.raises(ValueError, match="^method:"):
        bus.record(1.0, map="builtin:km20", method="sync")
    assert len(bus.scan(protocol=1, ids=(1, 2))) == 2
    # Nobody answers at ids 100-101: an OSError naming them, and no file of NaN left.
    out = tmp_path / "nobody.csv"
    with pytest.raises(OSError):
        bus.record(1.0, protocol=1, ids=[100, 101], out=out)
    assert not out.exists()


def test_record_to_mcap_holds_the_rows_it_returns(server, tmp_path):
    # The reference reader (mcap + mcap-ros2-support) decodes what twinloop wrote.
    reader, decoder = oracle("mcap.reader"), oracle("mcap_ros2.decoder")
    bus = bus_of(server)
    out = tmp_path / "rec.mcap"
    rec = bus.record(0.3, map="builtin:km20", rate=50.0, out=out)
    names = [c[2:] for c in rec["columns"] if c.startswith("q:")]
    with open(out, "rb") as f:
        r = reader.make_reader(f, decoder_factories=[decoder.DecoderFactory()])
        msgs = [m for _, _, _, m in r.iter_decoded_messages(topics=["/joint_states"])]
    assert len(msgs) == rec["rows"]
    for msg, row in zip(msgs, rec["data"]):
        assert list(msg.name) == names
        n = len(names)
        np.testing.assert_array_equal(np.array(msg.position), row[1:1 + n])
        np.testing.assert_array_equal(np.array(msg.velocity), row[1 + n:1 + 2 * n])
        np.testing.assert_array_equal(np.array(msg.effort), row[1 + 2 * n:])
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        assert abs(stamp - row[0]) < 1e-9


def test_record_to_a_folder_writes_a_bag_rosbags_reads(server, tmp_path):
    # `out="run/"`: a rosbag2 folder (metadata.yaml + run_0.mcap), as `--out run/` is.
    rosbag2, typesys = oracle("rosbags.rosbag2"), oracle("rosbags.typesys")
    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    bus = bus_of(server)
    bag = tmp_path / "run"
    rec = bus.record(0.3, map="builtin:km20", rate=50.0, out=str(bag) + "/")
    assert sorted(p.name for p in bag.iterdir()) == ["metadata.yaml", "run_0.mcap"]
    names = [c[2:] for c in rec["columns"] if c.startswith("q:")]
    with rosbag2.Reader(bag) as r:
        conns = [c for c in r.connections if c.topic == "/joint_states"]
        assert conns and conns[0].msgcount == rec["rows"]
        msgs = [store.deserialize_cdr(raw, c.msgtype) for c, _, raw in r.messages(connections=conns)]
    for msg, row in zip(msgs, rec["data"]):
        assert list(msg.name) == names
        np.testing.assert_array_equal(np.array(msg.position), row[1:1 + len(names)])

"""The link client against a virtual robot served on a pseudo-terminal (no hardware)."""

import pytest

import twinloop as tl


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

"""The simulator from Python: state get/set, sensors, and rollout == stepping one by one."""

import numpy as np
import pytest

import twinloop as tl
from conftest import OP3

OP3_MJCF = OP3.parent / "mjcf" / "op3.xml"


@pytest.fixture(scope="module")
def desc():
    return tl.load(OP3_MJCF)


def test_standing_robot_weighs_its_mass(desc):
    sim = tl.Simulator(desc)
    sim.step(500)
    s = sim.sensors()
    assert s["foot_names"] == ["l_ank_roll_link", "r_ank_roll_link"]
    weight = tl.Model.from_description(desc).total_mass * 9.81
    assert abs(s["foot_force"].sum() - weight) < 0.01 * weight
    assert s["positions"].shape == (20,) and s["imu_accel"].shape == (3,)
    assert abs(s["imu_accel"][2] - 9.81) < 0.1  # at rest the IMU reads +g upward
    assert sim.time == pytest.approx(0.5)


def test_state_round_trip_and_validation(desc):
    sim = tl.Simulator(desc, {"dt": 0.002, "servo": "rx28"})
    assert sim.dt == 0.002
    sim.step(10)
    q, v = sim.q, sim.v
    other = tl.Simulator(desc, {"dt": 0.002, "servo": "rx28"})
    other.set_state(q, v)
    np.testing.assert_array_equal(other.get_state(), np.concatenate([q, v]))
    with pytest.raises(ValueError, match="^q:"):
        sim.set_state(q[:-1], v)
    bad = v.copy()
    bad[0] = np.nan
    with pytest.raises(ValueError, match=r"^v\[0\] is"):
        sim.set_state(q, bad)
    with pytest.raises(ValueError, match="^goals:"):
        sim.goals = np.zeros(3)
    with pytest.raises(ValueError, match=r'^config\["dt"\]'):
        tl.Simulator(desc, {"dt": -1.0})
    with pytest.raises(ValueError, match=r'^config\["servo"\]'):
        tl.Simulator(desc, {"servo": "stepper"})
    with pytest.raises(ValueError, match="no collision primitives"):
        tl.Simulator(OP3)  # the mesh-free URDF has nothing to stand on


def test_rollout_equals_stepping_one_by_one(desc):
    sim = tl.Simulator(desc)
    q0 = sim.q
    rng = np.random.default_rng(5)
    n, t = 5, 60
    goals = q0[7:] + 0.2 * rng.uniform(-1, 1, (n, t, 20))
    Q0 = np.tile(q0, (n, 1))
    Q0[:, 2] += rng.uniform(0, 0.01, n)  # start a little above the ground
    states = sim.rollout(Q0, goals)
    assert states.shape == (n, t, sim.nq + sim.nv) and states.flags.writeable
    np.testing.assert_array_equal(states, sim.rollout(Q0, goals, threads=1))
    np.testing.assert_array_equal(states, sim.rollout(Q0, goals, threads=3))
    for i in range(n):
        one = tl.Simulator(desc)
        one.set_state(Q0[i], np.zeros(one.nv))
        for k in range(t):
            one.goals = goals[i, k]
            one.step()
            np.testing.assert_array_equal(one.get_state(), states[i, k])
    assert sim.time == 0.0  # rollout leaves the simulator as it was


def test_rollout_argument_errors(desc):
    sim = tl.Simulator(desc)
    with pytest.raises(ValueError, match="^goals:"):
        sim.rollout(sim.q, np.zeros((2, 3, 19)))
    with pytest.raises(ValueError, match="^q0:"):
        sim.rollout(np.zeros((3, sim.nq)), np.zeros((2, 3, 20)))
    goals = np.zeros((2, 3, 20))
    goals[1, 2, 4] = np.nan
    with pytest.raises(ValueError, match=r"^goals\[1, 2, 4\] is"):
        sim.rollout(sim.q, goals)

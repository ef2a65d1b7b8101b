"""Sweeps on a local 2-CPU Ray equal the serial loop, even when a worker dies mid-batch."""

import os
import pathlib

import numpy as np
import pytest

import twinloop as tl
from conftest import oracle

KM20 = "builtin:km20"


@pytest.fixture(scope="module")
def ray():
    ray = oracle("ray")
    if ray.is_initialized():
        ray.shutdown()
    os.environ.setdefault("RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO", "0")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


# The simulated study's ramps for the 200-job sweep: 10 deg/s, creeping at 2 deg/s
# from half a degree before the first tip. About 0.17 CPU-s a study, so the serial
# loop and the sweep on 2 CPUs take about a minute together; the default 0.5 deg/s
# (the seeds' protocol, tips 1 mm accurate) costs 30 times that per study.
FAST = {"ramp": 10.0, "slow_ramp": 2.0}


def test_200_simulated_tipovers_on_ray_equal_the_serial_loop(ray):
    import twinloop.distributed as td

    prior = tl.load(KM20)
    changes = tl.random_changes(prior, 200, seed=11)
    serial = [tl.tipover_changes(prior, [c], simulate=True, threads=1, **FAST)[0] for c in changes]
    swept = td.tipover_sweep(prior, changes, simulate=True, batch_size=15, progress=False, **FAST)
    # Every field, bit for bit (the studies are deterministic), as writable arrays.
    loop = td.TipoverSweep.from_rows(serial)
    assert swept.changes == loop.changes == changes
    for name in ("static_deg", "com", "total_mass", "simulated_deg"):
        ours = getattr(swept, name)
        assert ours.flags.writeable and ours.dtype == np.float64, name
        np.testing.assert_array_equal(ours, getattr(loop, name), err_msg=name)
    assert swept.simulated_deg.shape == (200, 4)
    assert len({tuple(r) for r in swept.simulated_deg}) == 200  # 200 different robots
    # Each simulated study tipped near its change's static angles (the fast ramp
    # overshoots them by a few degrees): 200 real studies, not 200 errors or zeros.
    sim, static = swept.simulated_deg, swept.static_deg
    assert np.all(sim > static - 1.0) and np.all(sim < static + 6.0)


def test_a_worker_killed_mid_batch_is_retried_without_loss_or_duplicates(ray, tmp_path):
    import twinloop.distributed as td

    marker = str(tmp_path / "killed-once")

    def dies_once(robot, changes, threads=1):
        rows = []
        for c in changes:
            if c["mass"] == victim_mass:
                try:
                    fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
                except FileExistsError:
                    pass  # the retry: carry on
                else:
                    os.close(fd)
                    os._exit(1)  # the worker process dies half way through its batch
            rows.append(tl.tipover_changes(robot, [c], threads=threads)[0])
        return rows

    changes = tl.random_changes(KM20, 40, seed=5)
    victim_mass = changes[25]["mass"]  # the middle of batch 2 (jobs 20..29)
    swept = td.map_batches(dies_once, KM20, changes, batch_size=10, progress=False, max_retries=3)
    assert pathlib.Path(marker).exists(), "the worker was killed"
    assert swept == tl.tipover_changes(KM20, changes)
    assert [r["change"] for r in swept] == changes


def test_static_identification_monte_carlo(ray):
    import twinloop.distributed as td

    prior = tl.load(KM20)
    truth = prior.with_point_mass("torso", 0.3, [0.04, 0.01, 0.05])
    trials = td.static_identification_monte_carlo(prior, truth, seeds=[1, 2, 3, 4], count=60, cop_noise=1e-3,
                                                  batch_size=2, progress=False)
    assert [t["seed"] for t in trials] == [1, 2, 3, 4]
    masses = np.array([t["mass"] for t in trials])
    assert masses.flags.writeable and masses.shape[0] == 4
    # Every trial keeps the weighed total mass; the noise makes the trials differ.
    for t in trials:
        assert t["mass"].sum() == pytest.approx(truth.total_mass, rel=1e-9)
    assert np.ptp(masses, axis=0).max() > 0


def first_order(n, noise, seed):
    """y[k] = 0.5 y[k-1] + 0.3 u[k-1] + output noise: a known system."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 1))
    y = np.zeros((n, 1))
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1]
    return u, y + noise * rng.normal(size=y.shape)


def test_sysid_order_sweep(ray):
    import twinloop.distributed as td

    u, y = first_order(600, 0.02, seed=1)
    uv, yv = first_order(400, 0.02, seed=2)
    orders = [1, 2, (3, 2, 1), (1, 1, 2), 4, (300, 300, 1)]  # the last: more parameters than samples
    sweep = td.sysid_order_sweep(u, y, orders, u_val=uv, y_val=yv, sample_time=0.01, batch_size=2, progress=False)
    assert sweep.orders == [(1, 1, 1), (2, 2, 1), (3, 2, 1), (1, 1, 2), (4, 4, 1), (300, 300, 1)]
    assert sweep.fit_data == "validation"
    for k, order in enumerate(sweep.orders[:-1]):
        na, nb, nk = order
        serial = tl.sysid.arx(u, y, na=na, nb=nb, nk=nk, u_val=uv, y_val=yv, sample_time=0.01)
        serial.pop("timing_seconds")
        assert sweep.models[k] == serial, order
        assert sweep.simulation_fit[k, 0] == serial["fit_percent"]["simulation"][0]
        assert sweep.prediction_cost[k] == serial["prediction_cost"]
    with pytest.raises(ValueError) as e:
        tl.sysid.arx(u, y, na=300, nb=300, u_val=uv, y_val=yv, sample_time=0.01)
    assert sweep.errors[-1] == str(e.value) and sweep.models[-1] is None
    assert np.isnan(sweep.simulation_fit[-1]).all() and sweep.simulation_fit.flags.writeable
    # Known truth: the first-order model with the right delay explains the validation
    # record to its noise; a delay of 2 cannot.
    assert sweep.simulation_fit[0, 0] > 90 > sweep.simulation_fit[3, 0]
    assert sweep.best() in (0, 1, 2, 4)
    a1 = sweep.models[0]["A"][0][0][0]
    assert a1 == pytest.approx(-0.5, abs=0.02)
    # State-space orders through the same helper.
    ss = td.sysid_order_sweep(u, y, [1, 2], method="n4sid", u_val=uv, y_val=yv, progress=False)
    one = tl.sysid.ss(u, y, 1, method="n4sid", u_val=uv, y_val=yv)
    one.pop("timing_seconds")
    assert ss.models[0] == one and ss.simulation_fit.shape == (2, 1)


def test_team_adaptation(ray):
    import twinloop.distributed as td

    prior = tl.load(KM20)
    # Three robots of a team, each with its own hidden part (kg, link, m in the link).
    parts = [(0.2, "torso", (0.05, 0.0, 0.0)), (0.3, "torso", (-0.03, 0.02, 0.04)), (0.15, "l_thigh", (0.0, 0.02, -0.05))]
    tips = [tl.tipover(prior, ramp=2.0, slow_ramp=0.2, add_mass=[p]) for p in parts]
    robots = [{"tipover": t, "total_mass": prior.total_mass + p[0]} for t, p in zip(tips, parts)]
    team = td.team_adaptation(prior, robots, batch_size=1, progress=False)
    for k, r in enumerate(robots):
        report, adapted = tl.adapt(prior, r["tipover"], total_mass=r["total_mass"])
        assert team.reports[k] == report
        assert team.adapted[k].to_urdf() == adapted.to_urdf()
    assert team.added_mass.flags.writeable and team.added_position.shape == (3, 3)
    # Known truth: the weighed mass fixes the added mass, and the adapted model's CoM is
    # each robot's true CoM (what its tip-over study simulated) across the floor within
    # a millimetre, where the prior's is 2.6-3.1 mm off. (Height is what the 2 deg/s
    # tip-over measures worst: 4-5 mm here, 0.6 mm at the default 0.5 deg/s.)
    np.testing.assert_allclose(team.added_mass, [p[0] for p in parts], atol=1e-9)
    true_com = np.array([t["com"]["true"] for t in tips])
    prior_com = np.array([r["prior_com"] for r in team.reports])
    adapted_off = np.linalg.norm((team.adapted_com - true_com)[:, :2], axis=1)
    prior_off = np.linalg.norm((prior_com - true_com)[:, :2], axis=1)
    assert np.all(adapted_off < 1e-3) and np.all(prior_off > 2e-3), (adapted_off, prior_off)
    with pytest.raises(ValueError, match=r"^robots\[0\]"):
        td.team_adaptation(prior, [{"total_mass": 3.0}], progress=False)


def test_adapt_train_on_ray_trains_the_same_network_as_the_serial_command(tmp_path):
    """`twinloop adapt train --ray local --ray-cpus 2` (the set made as Ray tasks in a Python
    subprocess) against the same command without --ray (the set made in Rust)."""
    import json
    import subprocess
    import sys

    oracle("ray")
    from test_cli_parity import cli

    exe = cli()
    common = ["adapt", "train", "--robot", KM20, "--samples", "80", "--seed", "3", "--epochs", "40",
              "--restarts", "1", "--threads", "1"]
    env = dict(os.environ, TWINLOOP_PYTHON=sys.executable, RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO="0")
    out = {}
    for name, extra in (("serial", []), ("ray", ["--ray", "local", "--ray-cpus", "2"])):
        net, js = tmp_path / f"{name}.net.json", tmp_path / f"{name}.json"
        r = subprocess.run([exe, *common, *extra, "--out", str(net), "--json", str(js)], env=env,
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr
        out[name] = (net.read_text(), json.loads(js.read_text()))
    assert out["ray"][0] == out["serial"][0]  # the same network, weight for weight
    ray_report, serial_report = out["ray"][1], out["serial"][1]
    for report in (ray_report, serial_report):
        report.pop("seconds"), report.pop("files")  # wall-clock times and file names differ
    assert ray_report == serial_report
    # And the samples Ray made are the package's serial ones (the same draws by index).
    from twinloop.adapt_train import main

    samples = tmp_path / "samples.json"
    assert main(["--robot", KM20, "--samples", "30", "--seed", "3", "--ray", "local", "--ray-cpus", "2",
                 "--batch-size", "7", "--out", str(samples)]) == 0
    assert json.loads(samples.read_text()) == tl.training_samples(KM20, 0, 30, seed=3, noise_deg=0.05)

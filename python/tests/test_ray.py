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
    assert swept == serial  # every field, bit for bit: the studies are deterministic
    assert len({tuple(r["simulated_deg"]) for r in swept}) == 200  # 200 different robots
    # Each simulated study tipped near its change's static angles (the fast ramp
    # overshoots them by a few degrees): 200 real studies, not 200 errors or zeros.
    sim = np.array([r["simulated_deg"] for r in swept])
    static = np.array([r["static_deg"] for r in swept])
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

"""The examples in python/examples run (the Ray sweep at a small size) and print what
they promise."""

import os
import subprocess
import sys

import pytest

from conftest import REPO, oracle

EXAMPLES = REPO / "python" / "examples"


def run(name, *args, timeout=300):
    env = dict(os.environ, RAY_ACCEL_ENV_VAR_OVERRIDE_ON_ZERO="0")
    r = subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True,
                       timeout=timeout, env=env, cwd=REPO)
    assert r.returncode == 0, f"{name} failed:\n{r.stdout}\n{r.stderr}"
    return r.stdout


def test_every_example_is_tested():
    tested = {"dynamics.py", "rollout.py", "tipover_adaptation.py", "ray_sweep.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


def test_dynamics_example():
    out = run("dynamics.py")
    # Its own consistency checks print near-zero residuals (M a + nle = rnea, aba inverts rnea).
    residuals = [float(line.split("=")[1]) for line in out.splitlines() if line.startswith("|")]
    assert len(residuals) == 2 and max(residuals) < 1e-9, out
    assert "gravity torques of 1000 poses: (1000, 35)" in out


def test_rollout_example():
    out = run("rollout.py")
    assert "32 rollouts x 1000 steps" in out
    heights = out.split("per rollout:")[1].replace("[", " ").replace("]", " ").split()
    assert len(heights) == 32 and all(0.2 < float(h) < 0.3 for h in heights)  # all still standing


def test_tipover_adaptation_example():
    out = run("tipover_adaptation.py")
    line = next(x for x in out.splitlines() if x.startswith("adapt:"))
    assert line.startswith("adapt: 0.200 kg added at"), out
    assert "adapted model: 3.536 kg (prior 3.336 kg)" in out


def test_ray_sweep_example_at_a_small_size():
    oracle("ray")
    out = run("ray_sweep.py", "--jobs", "40", timeout=600)
    assert "40 tip-overs in" in out and "fall angles (deg)" in out

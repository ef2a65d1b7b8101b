"""The CLI and Python give the same numbers for the same job (their JSONs compared)."""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import twinloop as tl
from conftest import REPO


def cli():
    """The twinloop binary: $TWINLOOP_CLI, else the workspace's ci/release/debug build, else PATH."""
    candidates = [os.environ.get("TWINLOOP_CLI")]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    candidates += [str(target / p / "twinloop") for p in ("ci", "release", "debug")]
    candidates.append(shutil.which("twinloop"))
    for c in candidates:
        if c and pathlib.Path(c).is_file():
            return c
    if os.environ.get("TWINLOOP_REQUIRE_ORACLES") == "1":
        pytest.fail("the twinloop CLI binary is required (TWINLOOP_REQUIRE_ORACLES=1): build it with cargo build -p twinloop-cli --profile ci")
    pytest.skip("no twinloop CLI binary built")


def assert_same(path, ours, theirs):
    """Same keys and values, floats to 1e-12 relative (the same code, the same build flags)."""
    if isinstance(theirs, dict):
        assert set(ours) == set(theirs), f"{path}: keys {sorted(ours)} vs the CLI's {sorted(theirs)}"
        for k in theirs:
            assert_same(f"{path}.{k}", ours[k], theirs[k])
    elif isinstance(theirs, list):
        assert len(ours) == len(theirs), f"{path}: length"
        for i, (a, b) in enumerate(zip(ours, theirs)):
            assert_same(f"{path}[{i}]", a, b)
    elif isinstance(theirs, float):
        assert np.isclose(ours, theirs, rtol=1e-12, atol=1e-15), f"{path}: {ours} vs the CLI's {theirs}"
    else:
        assert ours == theirs, f"{path}: {ours!r} vs the CLI's {theirs!r}"


def test_tipover_json_matches_the_cli(tmp_path):
    exe = cli()
    out = tmp_path / "tipover.json"
    args = ["experiment", "tipover", "--robot", "builtin:km20", "--ramp", "2", "--slow-ramp", "0.2",
            "--add-mass", "0.2@torso:0.05,0,0", "--json", str(out)]
    subprocess.run([exe, *args], check=True, capture_output=True, timeout=300)
    theirs = json.loads(out.read_text())
    ours = tl.tipover("builtin:km20", ramp=2.0, slow_ramp=0.2, add_mass=[(0.2, "torso", (0.05, 0.0, 0.0))])
    assert_same("tipover", ours, theirs)
    assert ours["com"]["true"][2] > 0.1  # a real result, not an empty one


def test_adapt_json_matches_the_cli(tmp_path):
    exe = cli()
    prior = tl.load("builtin:km20")
    tip = tl.tipover(prior, ramp=2.0, slow_ramp=0.2, add_mass=[(0.2, "torso", (0.05, 0.0, 0.0))])
    tip_file = tmp_path / "tip.json"
    tip_file.write_text(json.dumps(tip))
    out = tmp_path / "adapt.json"
    total = prior.total_mass + 0.2
    subprocess.run([exe, "adapt", "--robot", "builtin:km20", "--tipover", str(tip_file), "--total-mass", repr(total),
                    "--json", str(out)], check=True, capture_output=True, timeout=300)
    theirs = json.loads(out.read_text())
    ours, adapted = tl.adapt(prior, tip, total_mass=total)
    assert_same("adapt", ours, theirs)
    assert ours["added"]["mass"] == pytest.approx(0.2, abs=1e-9)
    assert adapted.total_mass == pytest.approx(total)

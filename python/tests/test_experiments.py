"""Experiments and identification from Python, checked against independent routes."""

import numpy as np
import pytest

import twinloop as tl

KM20 = "builtin:km20"
DIRECTIONS = ["forward", "backward", "left", "right"]


def test_static_route_equals_the_studys_rigid_reference():
    # Two separate code paths: the ANN data's static route on a changed robot, and the
    # tip-over study's rigid static reference of the same change added with add_mass.
    change = tl.random_changes(KM20, 1, seed=3)[0]
    static = tl.tipover_changes(KM20, [change])[0]
    study = tl.tipover(KM20, ramp=5.0, slow_ramp=1.0, add_mass=[(change["mass"], change["link"], change["xyz"])])
    rigid = [study[d]["rigid_static_deg"] for d in DIRECTIONS]
    np.testing.assert_allclose(static["static_deg"], rigid, rtol=1e-12)
    # The simulated tip happens near the static angle (the servos bend a little).
    measured = [study[d]["measured_deg"] for d in DIRECTIONS]
    np.testing.assert_allclose(measured, rigid, atol=2.0)
    assert static["total_mass"] == pytest.approx(tl.load(KM20).total_mass + change["mass"])


def test_tipover_changes_threads_agree_and_errors_name_the_change():
    changes = tl.random_changes(KM20, 9, seed=4)
    one = tl.tipover_changes(KM20, changes, threads=1)
    assert one == tl.tipover_changes(KM20, changes, threads=4)
    assert [r["change"] for r in one] == changes
    with pytest.raises(ValueError, match=r"^changes\[1\]: needs \"mass\""):
        tl.tipover_changes(KM20, [changes[0], {"link": "torso"}])
    with pytest.raises(ValueError, match=r"^changes\[0\]"):
        tl.tipover_changes(KM20, [{"link": "no_such_link", "mass": 0.1, "xyz": [0, 0, 0]}])


def test_static_identification_explains_a_changed_robot():
    prior = tl.load(KM20)
    truth = prior.with_point_mass("torso", 0.3, [0.04, 0.01, 0.05])
    poses = tl.static_poses(truth, count=60, seed=2)
    assert poses["q"].shape == (60, 27) and poses["cop"].shape == (60, 2)
    r = tl.identify_static(prior, poses["q"], poses["cop"], truth.total_mass, cop_sigma=0.0, category=poses["category"])
    res = r["result"]
    assert r["schema"] == "twinloop-static-identification/1"
    assert max(res["gcom_distance_before"]) > 1e-3  # the prior misses the CoP by mm
    assert max(res["gcom_distance_after"]) < 1e-6  # the identified model explains it
    assert res["total_mass"] == pytest.approx(truth.total_mass)
    with pytest.raises(ValueError, match="^cop:"):
        tl.identify_static(prior, poses["q"], poses["cop"][:-1], truth.total_mass)
    with pytest.raises(ValueError, match="^total_mass:"):
        tl.identify_static(prior, poses["q"], poses["cop"], -1.0)


def test_training_samples_split_anywhere_give_the_same_draws():
    whole = tl.training_samples(KM20, 0, 6, seed=9, noise_deg=0.1)
    parts = tl.training_samples(KM20, 0, 2, seed=9, noise_deg=0.1) + tl.training_samples(KM20, 2, 6, seed=9, noise_deg=0.1)
    assert whole == parts and len(whole) == 6

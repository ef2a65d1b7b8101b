"""Every public function fed empty, wrong-shaped and non-finite arrays: a ValueError
naming the argument, never a Rust panic (pyo3's PanicException is a BaseException,
which `except Exception` in a user's script would not catch)."""

import numpy as np
import pytest

import twinloop as tl
from conftest import OP3

KM20 = "builtin:km20"


def value_error(call, name=None):
    """`call()` raises ValueError (its message starting with `name`), nothing else."""
    try:
        call()
    except ValueError as e:
        if name is not None:
            assert str(e).startswith(name), f"expected a message naming {name!r}, got {e!r}"
        return str(e)
    except BaseException as e:  # a PanicException lands here
        pytest.fail(f"expected ValueError, got {type(e).__module__}.{type(e).__name__}: {e}")
    pytest.fail("expected ValueError, nothing was raised")


@pytest.fixture(scope="module")
def op3():
    return tl.Model.from_description(tl.load(OP3))


def bad_variants(good):
    """Empty, one entry short, one dimension too many, NaN and inf in place of `good`."""
    nan, inf = good.copy(), good.copy()
    nan.flat[-1] = np.nan
    inf.flat[0] = np.inf
    return {
        "empty": np.zeros((0,) * good.ndim),
        "short": good[..., :-1],
        "extra_dim": good[None],
        "nan": nan,
        "inf": inf,
        "complex": good.astype(complex),
    }


# Each dynamics function with its array arguments, by name: (name, shape from the model).
SINGLE = {
    "forward_kinematics": ["q"],
    "frames_forward_kinematics": ["q"],
    "center_of_mass": ["q"],
    "jacobian_center_of_mass": ["q"],
    "compute_joint_jacobians": ["q"],
    "rnea": ["q", "v", "a"],
    "nonlinear_effects": ["q", "v"],
    "compute_generalized_gravity": ["q"],
    "crba": ["q"],
    "aba": ["q", "v", "tau"],
    "joint_torque_regressor": ["q", "v", "a"],
    "static_com_regressor": ["q"],
}


@pytest.mark.parametrize("fn", sorted(SINGLE) + ["frame_jacobian"])
@pytest.mark.parametrize("variant", ["empty", "short", "extra_dim", "nan", "inf", "complex"])
def test_single_forms_refuse_bad_arrays(op3, fn, variant):
    names = SINGLE.get(fn, ["q"])
    good = {n: (op3.neutral() if n == "q" else np.zeros(op3.nv)) for n in names}
    for bad_name in names:
        args = dict(good)
        args[bad_name] = bad_variants(good[bad_name])[variant]
        extra = (op3.frame_names[3],) if fn == "frame_jacobian" else ()
        value_error(lambda: getattr(tl, fn)(op3, tl.Data(op3), *args.values(), *extra), bad_name)


BATCH = {
    "rnea_batch": ["Q", "V", "A"],
    "aba_batch": ["Q", "V", "TAU"],
    "nonlinear_effects_batch": ["Q", "V"],
    "crba_batch": ["Q"],
    "center_of_mass_batch": ["Q"],
    "jacobian_center_of_mass_batch": ["Q"],
    "compute_joint_jacobians_batch": ["Q"],
    "frame_jacobian_batch": ["Q"],
    "joint_torque_regressor_batch": ["Q", "V", "A"],
    "static_com_regressor_batch": ["Q"],
}


def batch_call(op3, fn, arrays):
    extra = (op3.frame_names[3],) if fn == "frame_jacobian_batch" else ()
    return getattr(tl, fn)(op3, *arrays, *extra)


@pytest.mark.parametrize("fn", sorted(BATCH))
def test_batch_forms_refuse_bad_arrays_and_take_zero_rows(op3, fn):
    names = BATCH[fn]
    n = 4
    good = {k: (np.tile(op3.neutral(), (n, 1)) if k == "Q" else np.zeros((n, op3.nv))) for k in names}
    for bad_name in names:
        for variant, bad in bad_variants(good[bad_name]).items():
            args = dict(good)
            args[bad_name] = bad
            value_error(lambda: batch_call(op3, fn, args.values()), bad_name)
        # One row fewer than Q (Q sets N: a short Q makes the next array the mismatch),
        # or a single row (1-D) where rows are expected.
        args = dict(good)
        args[bad_name] = good[bad_name][:-1]
        if len(names) > 1:
            value_error(lambda: batch_call(op3, fn, args.values()), bad_name if bad_name != "Q" else names[1])
        args[bad_name] = good[bad_name][0]
        value_error(lambda: batch_call(op3, fn, args.values()), bad_name)
    # N = 0 rows is an empty batch, as numpy's reductions over zero rows are: (0, ...).
    zero = [np.zeros((0, op3.nq if k == "Q" else op3.nv)) for k in names]
    out = batch_call(op3, fn, zero)
    assert out.shape[0] == 0 and out.shape[1:] == batch_call(op3, fn, [g[:1] for g in good.values()]).shape[1:]
    # threads=0 is refused, not a division by zero.
    value_error(lambda: getattr(tl, fn)(op3, *good.values(), *((0,) if fn == "frame_jacobian_batch" else ()),
                                        threads=0), "threads")


def test_the_shape_message_names_each_dimension(op3):
    msg = value_error(lambda: tl.rnea_batch(op3, np.zeros(op3.nq), np.zeros(op3.nv), np.zeros(op3.nv)), "Q")
    assert msg == f"Q: expected shape (N, nq = {op3.nq}), got ({op3.nq},)"
    msg = value_error(lambda: tl.sysid.arx(np.zeros(10), np.zeros(10)), "u")
    assert msg == "u: expected shape (N, nu), got (10,)"
    msg = value_error(lambda: tl.sysid.arx(np.zeros((10, 1)), np.zeros(10)), "y")
    assert msg == "y: expected shape (N (rows of u) = 10, ny), got (10,)"
    sim = tl.Simulator(KM20)
    msg = value_error(lambda: sim.rollout(sim.q, np.zeros((2, 20))), "goals")
    assert msg == "goals: expected shape (N, T, joints = 20), got (2, 20)"
    msg = value_error(lambda: sim.rollout(np.zeros((3, sim.nq)), np.zeros((2, 1, 20))), "q0")
    assert msg == f"q0: expected shape (N (rollouts in goals) = 2, nq = {sim.nq}), got (3, {sim.nq})"


def test_frame_arguments(op3):
    d = tl.Data(op3)
    for frame in (-1, len(op3.frame_names), 10**30):
        msg = value_error(lambda: tl.frame_jacobian(op3, d, op3.neutral(), frame), "frame")
        assert "out of range" in msg
    value_error(lambda: tl.frame_jacobian(op3, d, op3.neutral(), 2.5), "frame")
    value_error(lambda: tl.frame_jacobian_batch(op3, np.zeros((1, op3.nq)), "nope"), "frame")


def io(n, nu=1, ny=1, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, nu)), rng.normal(size=(n, ny))


@pytest.mark.parametrize("fit", ["arx", "ss"])
def test_sysid_refuses_short_empty_and_non_finite_records(fit):
    call = (lambda u, y, **k: tl.sysid.arx(u, y, **k)) if fit == "arx" else \
        (lambda u, y, **k: tl.sysid.ss(u, y, order=1, **k))
    for n in (0, 1):
        u, y = io(n)
        msg = value_error(lambda: call(u, y), "u")
        assert msg == f"u: {n} samples: an identification needs a record of at least 2"
    u, y = io(60)
    for variant, bad in bad_variants(u).items():
        if variant == "empty":
            # Zero rows of u: y's 60 rows are then the mismatch the message names.
            value_error(lambda: call(bad, y), "y: expected shape (N (rows of u) = 0, ny)")
        elif variant == "short":
            # (60, 0): a record without inputs, which these models cannot use.
            assert "input" in value_error(lambda: call(bad, y))
        else:
            value_error(lambda: call(bad, y), "u")
    for variant, bad in bad_variants(y).items():
        value_error(lambda: call(u, bad), "y")
    assert value_error(lambda: call(u, np.zeros((60, 0))), "y") == "y: no output channel (shape (60, 0))"
    uv, yv = io(0, seed=1)
    value_error(lambda: call(u, y, u_val=uv, y_val=yv), "u_val")
    uv, yv = io(30, seed=1)
    yv[4, 0] = np.nan
    value_error(lambda: call(u, y, u_val=uv, y_val=yv), "y_val[4, 0]")
    value_error(lambda: call(u, y, sample_time=0.0), "u")
    value_error(lambda: call(u, y, u_val=uv), "u_val, y_val")


def test_sysid_orders_that_do_not_fit_the_record():
    u, y = io(50)
    value_error(lambda: tl.sysid.arx(u, y, na=0, nb=0))
    value_error(lambda: tl.sysid.arx(u, y, na=10**6, nb=1))
    value_error(lambda: tl.sysid.arx(u, y, nk=10**6))
    value_error(lambda: tl.sysid.ss(u, y, order=0))
    value_error(lambda: tl.sysid.ss(u, y, order=10**6))
    for method in ("n4sid", "pem", "arx-reduce-pem"):
        value_error(lambda: tl.sysid.ss(*io(5), order=1, method=method))
        value_error(lambda: tl.sysid.ss(np.zeros((60, 0)), io(60)[1], order=1, method=method))


def test_static_identification_bad_poses():
    km20 = tl.Model.from_description(tl.load(KM20))
    poses = tl.static_poses(KM20, count=50, seed=3)
    q, cop = poses["q"], poses["cop"]
    value_error(lambda: tl.identify_static(KM20, np.zeros((0, km20.nq)), np.zeros((0, 2)), 3.0))
    for variant, bad in bad_variants(q).items():
        value_error(lambda: tl.identify_static(KM20, bad, cop, 3.0), "q")
    for variant, bad in bad_variants(cop).items():
        value_error(lambda: tl.identify_static(KM20, q, bad, 3.0), "cop")
    for mass in (0.0, -1.0, np.nan, np.inf):
        value_error(lambda: tl.identify_static(KM20, q, cop, mass), "total_mass")
    value_error(lambda: tl.identify_static(KM20, q, cop, 3.0, cop_sigma=np.nan))
    value_error(lambda: tl.identify_static(KM20, q, cop, 3.0, category=["single"]), "category")
    value_error(lambda: tl.identify_static(KM20, q, cop, 3.0, links=[]))
    value_error(lambda: tl.static_poses(KM20, count=0))
    value_error(lambda: tl.static_poses(KM20, cop_noise=np.nan), "cop_noise")
    value_error(lambda: tl.static_poses(KM20, joint_noise=-1.0), "joint_noise")


def test_experiments_refuse_bad_numbers():
    assert tl.random_changes(KM20, 0) == [] and tl.tipover_changes(KM20, []) == []
    assert tl.training_samples(KM20, 3, 3) == []
    value_error(lambda: tl.random_changes(KM20, 1, mass_range=(np.nan, 1.0)), "mass_range")
    for change in ({"link": "torso", "mass": np.nan, "xyz": [0, 0, 0]},
                   {"link": "torso", "mass": 0.1, "xyz": [0, np.inf, 0]},
                   {"link": "torso", "mass": 0.0, "xyz": [0, 0, 0]},  # negative: a part taken off
                   {"link": "torso", "mass": -50.0, "xyz": [0, 0, 0]},  # more than the torso has
                   {"link": "torso", "mass": 0.1}):
        value_error(lambda: tl.tipover_changes(KM20, [change]), "changes[0]")
    for key in ("ramp", "slow_ramp"):
        value_error(lambda: tl.tipover_changes(KM20, [], **{key: 0.0}), key)
        value_error(lambda: tl.tipover(KM20, **{key: np.nan}), key)
    value_error(lambda: tl.tipover(KM20, add_mass=[(np.nan, "torso", [0, 0, 0])]), "add_mass")
    value_error(lambda: tl.training_samples(KM20, 2, 1), "stop")
    value_error(lambda: tl.training_samples(KM20, 0, 1, noise_deg=np.nan))
    value_error(lambda: tl.adapt(KM20, {}), "tipover")
    value_error(lambda: tl.load(KM20).with_point_mass("torso", np.nan, [0, 0, 0]), "mass")


def test_simulator_refuses_bad_arrays():
    sim = tl.Simulator(KM20)
    q, v = sim.q.copy(), sim.v.copy()
    for variant, bad in bad_variants(q).items():
        value_error(lambda: sim.set_state(bad, v), "q")
        value_error(lambda: sim.rollout(bad, np.zeros((2, 2, 20))), "q0")  # (1, nq): not 2 rows
    for variant, bad in bad_variants(v).items():
        value_error(lambda: sim.set_state(q, bad), "v")
    goals = np.zeros((2, 3, 20))
    for variant, bad in bad_variants(sim.goals.copy()).items():
        value_error(lambda: setattr(sim, "goals", bad), "goals")
    for variant, bad in bad_variants(goals).items():
        value_error(lambda: sim.rollout(q, bad), "goals")
    # Zero rollouts or zero steps are empty results, not errors.
    assert sim.rollout(q, np.zeros((0, 3, 20))).shape == (0, 3, sim.nq + sim.nv)
    assert sim.rollout(q, np.zeros((2, 0, 20))).shape == (2, 0, sim.nq + sim.nv)
    value_error(lambda: sim.rollout(q, goals, threads=0), "threads")
    for dt in (0.0, -1e-3, np.nan, np.inf):
        value_error(lambda: tl.Simulator(KM20, {"dt": dt}), 'config["dt"]')

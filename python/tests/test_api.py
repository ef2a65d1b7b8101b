"""The Python API itself: batched forms equal the loop, Data's views are read-only
and up to date, bad arguments raise ValueError naming them, errors have the right
types, pickling a model or a description computes the same."""

import pickle

import numpy as np
import pytest

import twinloop as tl
from conftest import G1, OP3, TEST_URDF


@pytest.fixture(scope="module")
def op3():
    return tl.Model.from_description(tl.load(OP3))


def random_states(m, n, seed=3):
    rng = np.random.default_rng(seed)
    nj = len(m.joint_names)
    Q = np.zeros((n, m.nq))
    Q[:, :3] = rng.uniform(-1, 1, (n, 3))
    quat = rng.normal(size=(n, 4))
    Q[:, 3:7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    Q[:, 7:] = rng.uniform(-1.5, 1.5, (n, nj))
    return Q, rng.normal(size=(n, m.nv)), rng.normal(size=(n, m.nv))


@pytest.mark.parametrize("threads", [1, 2, 3, None])
def test_batched_forms_equal_the_loop(op3, threads):
    m, d = op3, tl.Data(op3)
    Q, V, A = random_states(m, 37)
    frame = m.frame_names[5]
    cases = [
        (tl.rnea_batch(m, Q, V, A, threads=threads), lambda i: tl.rnea(m, d, Q[i], V[i], A[i])),
        (tl.aba_batch(m, Q, V, A, threads=threads), lambda i: tl.aba(m, d, Q[i], V[i], A[i])),
        (tl.nonlinear_effects_batch(m, Q, V, threads=threads), lambda i: tl.nonlinear_effects(m, d, Q[i], V[i])),
        (tl.crba_batch(m, Q, threads=threads), lambda i: tl.crba(m, d, Q[i])),
        (tl.center_of_mass_batch(m, Q, threads=threads), lambda i: tl.center_of_mass(m, d, Q[i])),
        (tl.jacobian_center_of_mass_batch(m, Q, threads=threads), lambda i: tl.jacobian_center_of_mass(m, d, Q[i])),
        (tl.compute_joint_jacobians_batch(m, Q, threads=threads), lambda i: tl.compute_joint_jacobians(m, d, Q[i])),
        (tl.frame_jacobian_batch(m, Q, frame, "WORLD", threads=threads), lambda i: tl.frame_jacobian(m, d, Q[i], frame, "WORLD")),
        (tl.joint_torque_regressor_batch(m, Q, V, A, threads=threads), lambda i: tl.joint_torque_regressor(m, d, Q[i], V[i], A[i])),
        (tl.static_com_regressor_batch(m, Q, threads=threads), lambda i: tl.static_com_regressor(m, d, Q[i])),
    ]
    for batched, one in cases:
        assert batched.shape[0] == 37 and batched.flags.writeable
        for i in range(37):
            np.testing.assert_array_equal(batched[i], one(i))


def test_batch_of_zero_rows(op3):
    out = tl.rnea_batch(op3, np.zeros((0, op3.nq)), np.zeros((0, op3.nv)), np.zeros((0, op3.nv)))
    assert out.shape == (0, op3.nv)


def test_views_are_read_only_and_up_to_date(op3):
    m, d = op3, tl.Data(op3)
    Q, V, A = random_states(m, 2)
    tau = tl.rnea(m, d, Q[0], V[0], A[0])
    first = tau.copy()
    view = d.tau
    assert not tau.flags.writeable and not tau.flags.owndata
    with pytest.raises(ValueError):
        tau[0] = 1.0
    with pytest.raises(ValueError):
        d.tau[:] = 0.0
    with pytest.raises(ValueError):
        tau.setflags(write=True)  # the memory belongs to Data: numpy refuses
    tl.rnea(m, d, Q[1], V[1], A[1])
    # The same memory, now holding the second call's result.
    assert not np.array_equal(view, first)
    np.testing.assert_array_equal(tau, view)
    np.testing.assert_array_equal(view, tl.rnea_batch(m, Q[1:], V[1:], A[1:])[0])
    M = tl.crba(m, d, Q[0])
    assert not M.flags.writeable and M.shape == (m.nv, m.nv)
    np.testing.assert_array_equal(M, M.T)
    for name in ["ddq", "M", "J", "Jcom", "com", "joint_torque_regressor", "static_regressor"]:
        with pytest.raises(ValueError):
            getattr(d, name).flat[0] = 1.0


def test_copies_are_read_only_so_a_write_cannot_be_silently_lost(op3):
    # rust-numpy#408's trap: a property handing out a writable copy lets
    # `sim.goals[0] = 1` succeed and change nothing. Every such copy is read-only.
    d = tl.Data(op3)
    tl.frames_forward_kinematics(op3, d, op3.neutral())
    sim = tl.Simulator("builtin:km20")
    desc = tl.load("builtin:km20")
    copies = {
        "Data.oMi[1]": lambda: d.oMi[1],
        "Data.oMf[2]": lambda: d.oMf[2],
        "Model.gravity": lambda: op3.gravity,
        "Model.lower_position_limit": lambda: op3.lower_position_limit,
        "Model.upper_position_limit": lambda: op3.upper_position_limit,
        "Simulator.q": lambda: sim.q,
        "Simulator.v": lambda: sim.v,
        "Simulator.goals": lambda: sim.goals,
        "Simulator.applied": lambda: sim.applied,
        "Description.links com": lambda: desc.links[0]["com"],
        "Description.links inertia": lambda: desc.links[0]["inertia"],
    }
    for what, get in copies.items():
        x = get()
        before = x.copy()
        assert not x.flags.writeable, what
        with pytest.raises(ValueError, match="read-only"):
            x.flat[0] = 42.0
        with pytest.raises(ValueError, match="read-only"):
            x += 1.0
        np.testing.assert_array_equal(get(), before, err_msg=what)
    # The ways that do change the state still do.
    goals = np.array(sim.goals)
    goals[0] += 0.1
    sim.goals = goals
    np.testing.assert_array_equal(sim.goals, goals)
    q = np.array(sim.q)
    q[2] += 0.01
    sim.set_state(q, sim.v)
    assert sim.q[2] == q[2]
    # A function's new result stays writable: it is the caller's array.
    assert tl.frame_jacobian(op3, d, op3.neutral(), 2).flags.writeable
    assert op3.neutral().flags.writeable and tl.body_parameters(op3).flags.writeable


def test_view_keeps_data_alive(op3):
    d = tl.Data(op3)
    q = op3.neutral()
    tau = tl.compute_generalized_gravity(op3, d, q)
    expected = tau.copy()
    del d
    np.testing.assert_array_equal(tau, expected)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda m, d, q, v: tl.rnea(m, d, q[:-1], v, v), "q"),
        (lambda m, d, q, v: tl.rnea(m, d, q, v[:-1], v), "v"),
        (lambda m, d, q, v: tl.rnea(m, d, q, v, np.zeros((2, m.nv))), "a"),
        (lambda m, d, q, v: tl.aba(m, d, q, v, v[:3]), "tau"),
        (lambda m, d, q, v: tl.crba(m, d, "abc"), "q"),
        (lambda m, d, q, v: tl.rnea_batch(m, q, v, v), "Q"),
        (lambda m, d, q, v: tl.rnea_batch(m, q[None], v[None], np.zeros((2, m.nv))), "A"),
        (lambda m, d, q, v: tl.frame_jacobian(m, d, q, "no_such_frame"), "frame"),
        (lambda m, d, q, v: tl.frame_jacobian(m, d, q, 0, "SIDEWAYS"), "reference"),
        (lambda m, d, q, v: tl.rnea_batch(m, q[None], v[None], v[None], threads=0), "threads"),
    ],
)
def test_bad_shapes_raise_value_error_naming_the_argument(op3, call, name):
    d = tl.Data(op3)
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        call(op3, d, op3.neutral(), np.zeros(op3.nv))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_values_raise_value_error_naming_the_entry(op3, bad):
    d = tl.Data(op3)
    q, v = op3.neutral(), np.zeros(op3.nv)
    q[9] = bad
    with pytest.raises(ValueError, match=r"^q\[9\] is"):
        tl.rnea(op3, d, q, v, v)
    V = np.zeros((4, op3.nv))
    V[2, 5] = bad
    with pytest.raises(ValueError, match=r"^V\[2, 5\] is"):
        tl.rnea_batch(op3, np.tile(op3.neutral(), (4, 1)), V, np.zeros_like(V))


def test_lists_and_strided_arrays_are_accepted(op3):
    d = tl.Data(op3)
    q = op3.neutral()
    v = np.arange(2 * op3.nv, dtype=float)[::2] / 10  # not contiguous
    ref = tl.rnea(op3, d, q, np.ascontiguousarray(v), np.zeros(op3.nv)).copy()
    np.testing.assert_array_equal(tl.rnea(op3, d, list(q), v, [0.0] * op3.nv), ref)
    np.testing.assert_array_equal(tl.rnea(op3, d, q.astype(np.float32).astype(np.float64), v, np.zeros(op3.nv, dtype=np.int64)), ref)


def test_data_of_another_model_is_refused(op3):
    other = tl.Model.from_description(tl.load(OP3))
    with pytest.raises(ValueError, match="^data: made for another model"):
        tl.crba(op3, tl.Data(other), op3.neutral())


def test_errors_have_the_right_types(tmp_path):
    with pytest.raises(OSError, match="cannot read"):
        tl.load(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="x"><link name="a"/><joint name="j" type="revolute"><parent link="a"/><child link="nope"/></joint></robot>')
    with pytest.raises(tl.ModelError, match="bad.urdf"):
        tl.load(bad)
    with pytest.raises(tl.ModelError, match="unknown built-in robot"):
        tl.load("builtin:nosuch")
    assert issubclass(tl.ModelError, ValueError)
    garbage = tmp_path / "garbage.urdf"
    garbage.write_bytes(b"\x00\xff<robot")
    with pytest.raises(tl.ModelError):
        tl.load(garbage)


def test_description_contents():
    d = tl.load(OP3)
    assert d.name == "robotis_op3"
    assert abs(sum(link["mass"] for link in d.links) - d.total_mass) < 1e-12
    joints = {j["name"]: j for j in d.joints}
    assert joints["l_knee"]["type"] == "revolute"
    report = d.lint()
    assert report["robot"] == "robotis_op3" and report["findings"] == d.findings
    assert all({"severity", "code", "subject", "name", "message"} <= set(f) for f in d.findings)
    km20 = tl.load("builtin:km20")
    assert len(tl.Model.from_description(km20).joint_names) == 20


@pytest.mark.parametrize("path", [OP3, G1, None])
def test_pickle_round_trip_computes_the_same(path):
    desc = tl.Description.from_urdf(TEST_URDF) if path is None else tl.load(path)
    for floating in (True, False):
        m = tl.Model.from_description(desc, floating=floating)
        m2 = pickle.loads(pickle.dumps(m))
        assert (m2.nq, m2.nv, m2.joint_names, m2.floating) == (m.nq, m.nv, m.joint_names, m.floating)
        rng = np.random.default_rng(1)
        q = m.neutral()
        nj = len(m.joint_names)
        q[m.nq - nj:] = rng.uniform(-1, 1, nj)
        v, a = rng.normal(size=m.nv), rng.normal(size=m.nv)
        np.testing.assert_array_equal(tl.rnea(m2, tl.Data(m2), q, v, a), tl.rnea(m, tl.Data(m), q, v, a))
        np.testing.assert_array_equal(tl.crba(m2, tl.Data(m2), q), tl.crba(m, tl.Data(m), q))
    d2 = pickle.loads(pickle.dumps(desc))
    assert d2.to_urdf() == desc.to_urdf() and d2.total_mass == desc.total_mass


def test_pickle_keeps_mjcf_gravity_and_armature():
    desc = tl.load(OP3.parent / "mjcf" / "op3.xml")
    m = tl.Model.from_description(desc)
    m2 = pickle.loads(pickle.dumps(m))
    armature = {j["name"]: j["armature"] for j in desc.joints}
    assert max(armature.values()) > 0
    assert {j["name"]: j["armature"] for j in m2.description.joints if j["name"] in armature} == armature
    np.testing.assert_array_equal(m2.gravity, m.gravity)
    q = m.neutral()
    # An MJCF model pickles as URDF text: its rotations travel as rpy derived from the
    # matrices MJCF gave, so the mass matrix agrees to rounding (3e-18 seen), not bit for bit.
    np.testing.assert_allclose(
        tl.crba(m2, tl.Data(m2), q), tl.crba(m, tl.Data(m), q), rtol=1e-12, atol=1e-15
    )


def test_pickle_keeps_the_free_joint_armature():
    # BXI Elf2: its default class gives the free joint armature 0.01, which MuJoCo puts on
    # the six base diagonal entries of M (M[0][0] = total mass + 0.01); URDF cannot say it.
    desc = tl.load(OP3.parents[1] / "bxi_elf2" / "mjcf" / "elf2_dof25.xml")
    assert desc.base_armature == 0.01
    m2 = pickle.loads(pickle.dumps(tl.Model.from_description(desc)))
    assert m2.description.base_armature == 0.01
    mass = tl.crba(m2, tl.Data(m2), m2.neutral())
    assert abs(mass[0, 0] - (desc.total_mass + 0.01)) < 1e-12
    assert tl.Description.from_urdf(desc.to_urdf()).base_armature == 0.0


def test_aba_refuses_a_singular_mass_matrix_naming_the_joint(tmp_path):
    # A massless leaf on a hinge: M(q) has a zero row for that joint, and
    # Pinocchio's ABA would divide by zero. The Rust check names the joint.
    urdf = tmp_path / "massless_leaf.urdf"
    urdf.write_text(
        '<robot name="leaf"><link name="base"><inertial><mass value="1"/>'
        '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<link name="tip"/><joint name="spin" type="revolute"><parent link="base"/>'
        '<child link="tip"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
        "</joint></robot>"
    )
    model = tl.Model.from_description(tl.load(urdf), floating=False)
    data = tl.Data(model)
    with pytest.raises(ValueError, match="spin"):
        tl.aba(model, data, model.neutral(), np.zeros(model.nv), np.zeros(model.nv))


# A massless link turning about x carries a point mass on a slider along y: the
# inertia about the hinge is m y^2, so M(q) is singular exactly when the slider is
# at 0 (and only then).
SLIDER_ON_HINGE = """<robot name="slider_on_hinge">
  <link name="base"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"/>
  <link name="bead"><inertial><mass value="0.5"/>
    <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="slide" type="prismatic"><parent link="arm"/><child link="bead"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.mark.parametrize("threads", [1, 2, 4])
def test_aba_batch_refuses_a_singular_row_naming_the_row_and_the_joint(threads):
    model = tl.Model.from_description(tl.Description.from_urdf(SLIDER_ON_HINGE), floating=False)
    data = tl.Data(model)
    rng = np.random.default_rng(2)
    Q = np.column_stack([rng.uniform(-1, 1, 6), rng.uniform(0.1, 0.5, 6)])
    V, TAU = rng.normal(size=(6, 2)), rng.normal(size=(6, 2))
    # Away from the singular pose the batch is the loop (and finite: the check is not
    # refusing everything).
    ddq = tl.aba_batch(model, Q, V, TAU, threads=threads)
    assert np.isfinite(ddq).all()
    for i in range(6):
        np.testing.assert_array_equal(ddq[i], tl.aba(model, data, Q[i], V[i], TAU[i]))
    # The mass matrix there is m y^2 about the hinge and m along the slide (analytic).
    M = tl.crba(model, data, Q[0])
    np.testing.assert_allclose(np.diag(M), [0.5 * Q[0, 1] ** 2, 0.5], rtol=1e-12)
    Q[3, 1] = Q[5, 1] = 0.0  # rows 3 and 5 singular: the lowest is named
    with pytest.raises(ValueError) as single:
        tl.aba(model, data, Q[3], V[3], TAU[3])
    assert '"hinge"' in str(single.value)
    with pytest.raises(ValueError) as batch:
        tl.aba_batch(model, Q, V, TAU, threads=threads)
    assert str(batch.value) == f"row 3: {single.value}"

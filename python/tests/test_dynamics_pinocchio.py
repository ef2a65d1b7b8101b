"""Every dynamics function agrees with Pinocchio's Python bindings to 1e-9.

Pinocchio numbers its joints in its own depth-first order; twinloop keeps the file's
child order. Both are free-flyer rooted (Pinocchio: JointModelFreeFlyer, the same
q = [x, y, z, qx, qy, qz, qw, ...] and v = [linear, angular in the base frame, ...]),
so coordinates are mapped by joint name and compared entry by entry.
"""

import numpy as np
import pytest

import twinloop as tl
from conftest import G1, OP3, TEST_URDF, oracle

TOL = 1e-9
STATES = 5


def close(what, ours, theirs):
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    assert ours.shape == theirs.shape, f"{what}: shape {ours.shape} vs Pinocchio's {theirs.shape}"
    err = np.abs(ours - theirs) / np.maximum(1.0, np.abs(theirs))
    assert err.max(initial=0.0) <= TOL, f"{what}: max relative error {err.max():.3e}"


class Pair:
    """One robot in both libraries, with the coordinate maps between them."""

    def __init__(self, desc, pin_model, floating=True):
        pin = oracle("pinocchio")
        self.pin = pin
        self.m = tl.Model.from_description(desc, floating=floating)
        self.d = tl.Data(self.m)
        self.pm = pin_model
        self.pd = pin_model.createData()
        m, pm = self.m, pin_model
        nj = len(m.joint_names)
        qo, vo = m.nq - nj, m.nv - nj
        # v_pin[i]: Pinocchio's v index of twinloop's v index i; same for q.
        self.v_pin = np.zeros(m.nv, dtype=int)
        self.q_pin = np.zeros(m.nq, dtype=int)
        self.v_pin[:vo] = np.arange(vo)
        self.q_pin[:qo] = np.arange(qo)
        # Parameter block of each Pinocchio joint (1-based joint ids, excluding universe).
        self.block_of_pin_joint = []
        for jid in range(1, pm.njoints):
            name = pm.names[jid]
            jm = pm.joints[jid]
            if jm.shortname() == "JointModelFreeFlyer":
                self.block_of_pin_joint.append(0)
                continue
            b = m.joint_index(name)
            assert b is not None, f"Pinocchio joint {name} missing in twinloop"
            self.v_pin[vo + b] = jm.idx_v
            self.q_pin[qo + b] = jm.idx_q
            self.block_of_pin_joint.append(b + (1 if floating else 0))

    def to_pin_q(self, q):
        out = np.zeros(self.pm.nq)
        out[self.q_pin] = q
        return out

    def to_pin_v(self, v):
        out = np.zeros(self.pm.nv)
        out[self.v_pin] = v
        return out

    def random_state(self, rng):
        m = self.m
        nj = len(m.joint_names)
        q = np.zeros(m.nq)
        if m.floating:
            q[:3] = rng.uniform(-1, 1, 3)
            quat = rng.normal(size=4)
            q[3:7] = quat / np.linalg.norm(quat)
        q[m.nq - nj:] = rng.uniform(-1.5, 1.5, nj)
        return q, rng.normal(size=m.nv), rng.normal(size=m.nv), rng.normal(size=m.nv)


def op3_pair():
    pin = oracle("pinocchio")
    return Pair(tl.load(OP3), pin.buildModelFromUrdf(str(OP3), pin.JointModelFreeFlyer()))


def g1_pair():
    pin = oracle("pinocchio")
    return Pair(tl.load(str(G1)), pin.buildModelFromUrdf(str(G1), pin.JointModelFreeFlyer()))


def made_pair(floating=True):
    pin = oracle("pinocchio")
    desc = tl.Description.from_urdf(TEST_URDF)
    if floating:
        pm = pin.buildModelFromXML(TEST_URDF, pin.JointModelFreeFlyer())
    else:
        pm = pin.buildModelFromXML(TEST_URDF)
    return Pair(desc, pm, floating=floating)


PAIRS = {"op3": op3_pair, "g1": g1_pair, "made": made_pair, "made_fixed": lambda: made_pair(False)}


@pytest.fixture(scope="module", params=list(PAIRS))
def pair(request):
    return PAIRS[request.param]()


def states(pair, seed=7):
    rng = np.random.default_rng(seed)
    return [pair.random_state(rng) for _ in range(STATES)]


def test_sizes_and_mass(pair):
    assert pair.m.nv == pair.pm.nv
    assert pair.m.nq == pair.pm.nq
    close("total mass", pair.m.total_mass, pair.pin.computeTotalMass(pair.pm))


def test_rnea_nle_gravity_aba(pair):
    pin, vp = pair.pin, pair.v_pin
    for q, v, a, tau in states(pair):
        qp, vpn, ap, taup = pair.to_pin_q(q), pair.to_pin_v(v), pair.to_pin_v(a), pair.to_pin_v(tau)
        close("rnea", tl.rnea(pair.m, pair.d, q, v, a), pin.rnea(pair.pm, pair.pd, qp, vpn, ap)[vp])
        close("nle", tl.nonlinear_effects(pair.m, pair.d, q, v), pin.nonLinearEffects(pair.pm, pair.pd, qp, vpn)[vp])
        close("gravity", tl.compute_generalized_gravity(pair.m, pair.d, q), pin.computeGeneralizedGravity(pair.pm, pair.pd, qp)[vp])
        close("aba", tl.aba(pair.m, pair.d, q, v, tau), pin.aba(pair.pm, pair.pd, qp, vpn, taup)[vp])


def test_crba(pair):
    pin, vp = pair.pin, pair.v_pin
    for q, *_ in states(pair):
        M = pin.crba(pair.pm, pair.pd, pair.to_pin_q(q))
        close("crba", tl.crba(pair.m, pair.d, q), M[np.ix_(vp, vp)])


def test_center_of_mass_and_jacobian(pair):
    pin, vp = pair.pin, pair.v_pin
    for q, *_ in states(pair):
        qp = pair.to_pin_q(q)
        close("com", tl.center_of_mass(pair.m, pair.d, q), pin.centerOfMass(pair.pm, pair.pd, qp))
        Jc = pin.jacobianCenterOfMass(pair.pm, pair.pd, qp)
        close("Jcom", tl.jacobian_center_of_mass(pair.m, pair.d, q), Jc[:, vp])
        close("com after Jcom", pair.d.com, pair.pd.com[0])


def test_joint_and_frame_jacobians(pair):
    pin, vp = pair.pin, pair.v_pin
    refs = {"LOCAL": pin.LOCAL, "WORLD": pin.WORLD, "LOCAL_WORLD_ALIGNED": pin.LOCAL_WORLD_ALIGNED}
    names = [n for n in pair.m.frame_names if pair.pm.existFrame(n)]
    assert len(names) >= 3
    for q, *_ in states(pair):
        qp = pair.to_pin_q(q)
        J = tl.compute_joint_jacobians(pair.m, pair.d, q)
        close("joint jacobians", J, pin.computeJointJacobians(pair.pm, pair.pd, qp)[:, vp])
        for name in names:
            fid = pair.pm.getFrameId(name)
            for key, ref in refs.items():
                ours = tl.frame_jacobian(pair.m, pair.d, q, name, key)
                theirs = pin.computeFrameJacobian(pair.pm, pair.pd, qp, fid, ref)[:, vp]
                close(f"J {name} {key}", ours, theirs)


def test_frame_placements(pair):
    pin = pair.pin
    for q, *_ in states(pair):
        qp = pair.to_pin_q(q)
        tl.frames_forward_kinematics(pair.m, pair.d, q)
        pin.framesForwardKinematics(pair.pm, pair.pd, qp)
        oMf = pair.d.oMf
        for k, name in enumerate(pair.m.frame_names):
            if not pair.pm.existFrame(name):
                continue
            close(f"oMf {name}", oMf[k], pair.pd.oMf[pair.pm.getFrameId(name)].homogeneous)


def test_joint_torque_regressor(pair):
    pin, vp = pair.pin, pair.v_pin
    params = tl.body_parameters(pair.m)
    for q, v, a, _ in states(pair):
        Y = tl.joint_torque_regressor(pair.m, pair.d, q, v, a)
        Yp = pin.computeJointTorqueRegressor(pair.pm, pair.pd, pair.to_pin_q(q), pair.to_pin_v(v), pair.to_pin_v(a))
        for k, b in enumerate(pair.block_of_pin_joint):
            close(f"regressor block {b}", Y[:, 10 * b:10 * b + 10], Yp[vp, 10 * k:10 * k + 10])
        close("Y @ params == rnea", Y @ params, tl.rnea(pair.m, pair.d, q, v, a))


def test_static_com_regressor(pair):
    pin = pair.pin
    m = pair.m
    for q, *_ in states(pair):
        G = tl.static_com_regressor(m, pair.d, q) / m.total_mass
        Gp = pin.computeStaticRegressor(pair.pm, pair.pd, pair.to_pin_q(q))
        # Pinocchio's block per joint is twinloop's block of the link that starts that body.
        for k, b in enumerate(pair.block_of_pin_joint):
            jid = k + 1
            body_link = next(f.name for f in pair.pm.frames if f.parentJoint == jid and f.type == pin.BODY)
            l = m.link_names.index(body_link)
            close(f"static regressor {body_link}", G[:, 4 * l:4 * l + 4], Gp[:, 4 * k:4 * k + 4])
        params = tl.link_static_parameters(m)
        # Links welded to the world (a fixed base) carry no mass into the CoM.
        for f in pair.pm.frames:
            if f.parentJoint == 0 and f.type == pin.BODY and f.name in m.link_names:
                l = m.link_names.index(f.name)
                params[4 * l:4 * l + 4] = 0.0
        com = tl.static_com_regressor(m, pair.d, q) @ params / m.total_mass
        close("G @ params == com", com, pin.centerOfMass(pair.pm, pair.pd, pair.to_pin_q(q)))

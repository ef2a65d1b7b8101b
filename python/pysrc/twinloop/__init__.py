"""twinloop: a humanoid's digital twin, from Python.

Models and dynamics with Pinocchio's names and conventions (``twinloop.rnea(model,
data, q, v, a)``), their batched forms (``twinloop.rnea_batch(model, Q, V, A)``) that
loop in Rust with the GIL released, the simulator and its parallel rollouts, and the
experiments and identifications of the ``twinloop`` command, returning the same
fields as its JSON.

Conventions (as Pinocchio's JointModelFreeFlyer): a floating base has
``q = [x, y, z, qx, qy, qz, qw, joints...]`` (position in the world, unit quaternion,
scalar last) and ``v = [vx, vy, vz, wx, wy, wz, joint velocities...]`` (linear then
angular, both in the base frame). SI units: m, kg, s, rad, N, N m. Every array is
float64.
"""

from ._native import (
    Bus,
    VirtualRobotServer,
    Data,
    Description,
    Model,
    ModelError,
    SimulationError,
    Simulator,
    aba,
    adapt,
    adapt_to_protocol,
    aba_batch,
    body_parameters,
    center_of_mass,
    center_of_mass_batch,
    compute_generalized_gravity,
    compute_joint_jacobians,
    compute_joint_jacobians_batch,
    crba,
    crba_batch,
    forward_kinematics,
    fit_compliant,
    frame_jacobian,
    identify_static,
    random_changes,
    static_poses,
    tipover,
    tipover_changes,
    training_samples,
    frame_jacobian_batch,
    frames_forward_kinematics,
    jacobian_center_of_mass,
    jacobian_center_of_mass_batch,
    joint_torque_regressor,
    joint_torque_regressor_batch,
    link_static_parameters,
    load,
    nonlinear_effects,
    nonlinear_effects_batch,
    rnea,
    rnea_batch,
    static_com_regressor,
    static_com_regressor_batch,
)

from . import sysid  # noqa: E402  (twinloop.sysid.arx / .ss)

LOCAL = "LOCAL"
WORLD = "WORLD"
LOCAL_WORLD_ALIGNED = "LOCAL_WORLD_ALIGNED"

__all__ = [name for name in dir() if not name.startswith("_")]

"""Type stubs of twinloop's native module. Shapes in brackets; units SI (m, kg, s, rad, N, N m).

Floating base (Pinocchio's JointModelFreeFlyer): q = [x, y, z, qx, qy, qz, qw, joints...]
(nq = 7 + joints), v = [vx, vy, vz, wx, wy, wz, joints...] (nv = 6 + joints), linear then
angular, both in the base frame. Arguments accept anything numpy converts to float64;
a wrong shape, a non-finite entry or a complex array raises ValueError naming the argument.
"""

from os import PathLike
from typing import Any, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
ArrayLike = npt.ArrayLike
Reference = Literal["LOCAL", "WORLD", "LOCAL_WORLD_ALIGNED"]
RobotSpec = Union["Description", str, PathLike[str]]

class ModelError(ValueError):
    """A description that cannot be read or compiled; the message names file, line, element."""

class SimulationError(RuntimeError):
    """The simulation diverged."""

def load(path_or_builtin: Union[str, PathLike[str]]) -> Description:
    """Load "builtin:km20", "builtin:lab17" or a URDF/MJCF file (OSError: unreadable; ModelError: invalid)."""

class Description:
    """What a robot file says. Picklable (as URDF text from the lossless writer)."""
    @staticmethod
    def from_urdf(text: str) -> Description:
        """A description from URDF text (ModelError naming line and element if invalid)."""
    @property
    def name(self) -> str:
        """The robot's name (<robot name=...>)."""
    @property
    def total_mass(self) -> float:
        """Sum of link masses, kg."""
    @property
    def links(self) -> list[dict[str, Any]]:
        """name, mass (kg), com [3] (m, link frame), inertia [3, 3] (kg m^2); None without <inertial>.
        The arrays are read-only copies."""
    @property
    def joints(self) -> list[dict[str, Any]]:
        """name, type, parent, child, axis, lower/upper (rad or m), effort (N m or N), velocity (rad/s or m/s),
        armature (kg m^2 or kg)."""
    @property
    def base_armature(self) -> float:
        """The floating base's armature (an MJCF free joint's, on the six base diagonal entries of M); 0 for URDF."""
    @property
    def findings(self) -> list[dict[str, Any]]:
        """Lint findings: severity, code, subject, name, message."""
    def lint(self) -> dict[str, Any]:
        """`twinloop model check --json`'s report."""
    def with_point_mass(self, link: str, mass: float, xyz: Sequence[float]) -> Description:
        """A copy with mass (kg) added at xyz [3] (m, link frame), the link's inertial merged."""
    def to_urdf(self) -> str:
        """The description as URDF text (twinloop's lossless writer)."""

class Model:
    """The compiled dynamics model (constant). Picklable."""
    @staticmethod
    def from_description(description: Description, floating: bool = True) -> Model:
        """Compile a description; floating=True gives it a free-flyer base (nq = 7 + joints, nv = 6 + joints),
        False welds its root link to the world. ModelError for a description the dynamics cannot take."""
    @property
    def name(self) -> str:
        """The robot's name."""
    @property
    def nq(self) -> int:
        """Length of q (7 + joints for a floating base)."""
    @property
    def nv(self) -> int:
        """Length of v (6 + joints for a floating base)."""
    @property
    def joint_names(self) -> list[str]:
        """Joint i has q index nq - len(joint_names) + i and v index nv - len(joint_names) + i."""
    @property
    def frame_names(self) -> list[str]:
        """Frames (description links, then extra frames), by index, for frame_jacobian."""
    @property
    def link_names(self) -> list[str]:
        """Description links: the blocks of static_com_regressor."""
    @property
    def floating(self) -> bool:
        """Whether the base is a free flyer."""
    @property
    def total_mass(self) -> float:
        """Total mass, kg."""
    @property
    def gravity(self) -> F64:
        """[3], m/s^2, world frame; read-only."""
    @property
    def lower_position_limit(self) -> F64:
        """[joints] lower position limits, rad or m; read-only."""
    @property
    def upper_position_limit(self) -> F64:
        """[joints] upper position limits, rad or m; read-only."""
    @property
    def description(self) -> Description:
        """The description this model was compiled from."""
    def joint_index(self, name: str) -> Optional[int]:
        """Index of a joint in joint_names, None if absent."""
    def frame_index(self, name: Union[str, int]) -> int:
        """Index of a frame (Pinocchio's getFrameId); ValueError if absent or out of range."""
    def neutral(self) -> F64:
        """[nq] (a new array): base at the origin, identity orientation, joints 0."""

class Data:
    """Workspace of one model. Its arrays are read-only views (no copy), updated by every call."""
    def __init__(self, model: Model) -> None:
        """A workspace for `model` (Pinocchio's Data(model)); it refuses any other model."""
    @property
    def tau(self) -> F64:
        """[nv] N m (or N) from rnea / nonlinear_effects / compute_generalized_gravity."""
    @property
    def ddq(self) -> F64:
        """[nv] rad/s^2 (or m/s^2) from aba."""
    @property
    def M(self) -> F64:
        """[nv, nv] from crba, symmetric (kg m^2, kg, kg m)."""
    @property
    def J(self) -> F64:
        """[6, nv] joint Jacobians (world) from compute_joint_jacobians, rows linear then angular."""
    @property
    def Jcom(self) -> F64:
        """[3, nv] from jacobian_center_of_mass (m/rad, world)."""
    @property
    def com(self) -> F64:
        """[3] m, world."""
    @property
    def joint_torque_regressor(self) -> F64:
        """[nv, 10 * bodies]."""
    @property
    def static_regressor(self) -> F64:
        """[3, 4 * links]."""
    @property
    def oMi(self) -> list[F64]:
        """Body placements [4, 4] (homogeneous, m), after forward_kinematics; read-only copies."""
    @property
    def oMf(self) -> list[F64]:
        """Frame placements [4, 4] (m), after frames_forward_kinematics; read-only copies."""

def forward_kinematics(model: Model, data: Data, q: ArrayLike) -> None:
    """Body placements at q [nq] into data.oMi."""
def frames_forward_kinematics(model: Model, data: Data, q: ArrayLike) -> None:
    """Body and frame placements at q [nq] into data.oMi and data.oMf."""
def center_of_mass(model: Model, data: Data, q: ArrayLike) -> F64:
    """[3] m, world (view of data.com)."""
def jacobian_center_of_mass(model: Model, data: Data, q: ArrayLike) -> F64:
    """[3, nv] (view of data.Jcom; also sets data.com)."""
def compute_joint_jacobians(model: Model, data: Data, q: ArrayLike) -> F64:
    """[6, nv] (view of data.J)."""
def frame_jacobian(model: Model, data: Data, q: ArrayLike, frame: Union[str, int], reference: Reference = "LOCAL") -> F64:
    """[6, nv], rows linear then angular (a new array)."""
def rnea(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> F64:
    """tau [nv] = M a + C v + g (view of data.tau); q [nq], v [nv] (rad/s), a [nv] (rad/s^2)."""
def nonlinear_effects(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> F64:
    """C(q, v) v + g(q) [nv], N m (view of data.tau); q [nq], v [nv] rad/s."""
def compute_generalized_gravity(model: Model, data: Data, q: ArrayLike) -> F64:
    """g(q) [nv], N m (view of data.tau)."""
def crba(model: Model, data: Data, q: ArrayLike) -> F64:
    """M [nv, nv] (view of data.M)."""
def aba(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> F64:
    """ddq [nv] (view of data.ddq); ValueError naming the joint if M(q) is singular."""
def joint_torque_regressor(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> F64:
    """Y [nv, 10 * bodies]; rnea = Y @ body_parameters(model)."""
def static_com_regressor(model: Model, data: Data, q: ArrayLike) -> F64:
    """G [3, 4 * links]; total_mass * com = G @ link_static_parameters(model)."""
def body_parameters(model: Model) -> F64:
    """[10 * bodies] per body (m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz) (kg, kg m, kg m^2), the
    vector joint_torque_regressor multiplies; the floating base first."""
def link_static_parameters(model: Model) -> F64:
    """[4 * links] per description link (m, m c_x, m c_y, m c_z) (kg, kg m), the vector static_com_regressor
    multiplies."""

def rnea_batch(model: Model, Q: ArrayLike, V: ArrayLike, A: ArrayLike, threads: Optional[int] = None) -> F64:
    """[N, nq], [N, nv], [N, nv] -> tau [N, nv], GIL released, on `threads` threads (default all cores)."""
def aba_batch(model: Model, Q: ArrayLike, V: ArrayLike, TAU: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq], V [N, nv] (rad/s), TAU [N, nv] (N m) -> ddq [N, nv] (rad/s^2); ValueError naming the lowest row
    and the joint where M(q) is singular, as aba."""
def nonlinear_effects_batch(model: Model, Q: ArrayLike, V: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq], V [N, nv] (rad/s) -> C v + g [N, nv] (N m)."""
def crba_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> M [N, nv, nv], full and symmetric."""
def center_of_mass_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> CoM [N, 3], m, world."""
def jacobian_center_of_mass_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> Jcom [N, 3, nv], world."""
def compute_joint_jacobians_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> J [N, 6, nv], world, rows linear then angular."""
def frame_jacobian_batch(model: Model, Q: ArrayLike, frame: Union[str, int], reference: Reference = "LOCAL", threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> the frame's Jacobian [N, 6, nv] in `reference`, rows linear then angular."""
def joint_torque_regressor_batch(model: Model, Q: ArrayLike, V: ArrayLike, A: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq], V, A [N, nv] -> Y [N, nv, 10 * bodies]."""
def static_com_regressor_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq] -> G [N, 3, 4 * links]."""

class Simulator:
    """config: dt (s, 1e-3), servo ("auto", "rx28", "rx64", "xm430", "passive", "torque"), ground, stand."""
    def __init__(self, robot: RobotSpec, config: Optional[dict[str, Any]] = None) -> None:
        """A floating-base robot on its servos, standing on the ground at the neutral pose (stand=True);
        ValueError for a bad config entry or a robot with nothing to stand on."""
    def step(self, n: int = 1) -> None:
        """Advance n steps of dt, GIL released; SimulationError if the state diverges."""
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def dt(self) -> float:
        """Time step, s."""
    @property
    def nq(self) -> int:
        """Length of q (7 + joints)."""
    @property
    def nv(self) -> int:
        """Length of v (6 + joints)."""
    @property
    def joint_names(self) -> list[str]:
        """Joints in the order of goals, applied and q[7:]."""
    @property
    def q(self) -> F64:
        """[nq]: x, y, z (m), qx, qy, qz, qw, joints (rad); a read-only copy (set_state changes it)."""
    @property
    def v(self) -> F64:
        """[nv]: linear (m/s), angular (rad/s, base frame), joints (rad/s); a read-only copy."""
    def get_state(self) -> F64:
        """[nq + nv]: q then v (a new array)."""
    def set_state(self, q: ArrayLike, v: ArrayLike) -> None:
        """Set q [nq] and v [nv], time kept; contacts released."""
    @property
    def goals(self) -> F64:
        """[joints] joint goals (rad for servos, N m for torque actuators); a read-only copy: assign the
        whole array to change them."""
    @goals.setter
    def goals(self, goals: ArrayLike) -> None:
        """Set every joint's goal, [joints] (rad, or N m for torque actuators)."""
    @property
    def applied(self) -> F64:
        """[joints] torque each actuator applied in the last step, N m; read-only."""
    def center_of_mass(self) -> F64:
        """[3] CoM now, m, world (a new array)."""
    def sensors(self) -> dict[str, Any]:
        """time, positions, velocities, efforts, imu_gyro, imu_accel, imu_orientation, foot_names, foot_force, foot_cop."""
    def rollout(self, q0: ArrayLike, goals: ArrayLike, v0: Optional[ArrayLike] = None, threads: Optional[int] = None) -> F64:
        """q0 [nq] or [N, nq], goals [N, T, joints] -> states [N, T, nq + nv]."""

def tipover(robot: Optional[RobotSpec] = None, ramp: float = 0.5, slow_ramp: float = 0.05, compliance_slope: float = 2.0,
            encoders: bool = False,
            add_mass: Union[None, str, Sequence[Union[str, tuple[float, str, Sequence[float]]]]] = None, *,
            port: Optional[str] = None, map: Optional[str] = None, directions: Optional[Sequence[str]] = None,
            record: Optional[Union[str, PathLike[str]]] = None, yes: bool = False, realtime_factor: float = 1.0,
            ankle_slope: float = 32.0, creeps: int = 2, dither: bool = True, baud: int = 1_000_000, timeout_ms: float = 10.0, retries: int = 2,
            soft_servos: bool = False) -> dict[str, Any]:
    """`twinloop experiment tipover --json`'s fields: on the simulator, or with `port` and `map` on a robot over its bus
    (`experiment tipover --port --map`; fewer than four `directions` give robot, port and each direction's angles).
    Ramps in deg/s; add_mass: "KG@LINK:X,Y,Z" (as --add-mass) or (kg, link, xyz m in the link frame), one or a list; dither: sigma-delta goal counts over a bus (False:
    whole counts); soft_servos: leave the servos as they are (not stiffened; the result says so). A serial port needs yes=True; a silent or faulty
    servo raises OSError, the servos left holding."""
def random_changes(robot: RobotSpec, n: int, seed: int = 1, mass_range: tuple[float, float] = (0.05, 0.5)) -> list[dict[str, Any]]:
    """n hardware changes {link, mass (kg, within mass_range), xyz [3] (m, link frame, inside its collision outline)}
    drawn from seed."""
def tipover_changes(robot: RobotSpec, changes: list[dict[str, Any]], simulate: bool = False, ramp: float = 0.5,
                    slow_ramp: float = 0.05, threads: Optional[int] = None) -> list[dict[str, Any]]:
    """Per change: change, static_deg [4] (deg: forward, backward, left, right), com [3] (m, standing frame),
    total_mass (kg), simulated_deg [4] (deg, with simulate=True; ramps in deg/s) or None; GIL released."""
def static_poses(robot: RobotSpec, count: int = 172, cop_noise: float = 0.0, joint_noise: float = 0.0, seed: int = 1) -> dict[str, Any]:
    """q [P, nq], cop [P, 2] (m), category [P]; cop_noise m, joint_noise rad."""
def identify_static(robot: RobotSpec, q: ArrayLike, cop: ArrayLike, total_mass: float, links: Optional[list[str]] = None,
                    cop_sigma: float = 1e-3, com_margin: float = 0.03, category: Optional[list[Optional[str]]] = None) -> dict[str, Any]:
    """`twinloop identify static --json`'s schema, cop_sigma, com_margin and result; q [P, nq], cop [P, 2] (m),
    total_mass kg, cop_sigma and com_margin m."""
def training_samples(robot: RobotSpec, start: int, stop: int, seed: int = 1, mass_range: tuple[float, float] = (0.05, 0.5),
                     noise_deg: float = 0.0, threads: Optional[int] = None) -> list[dict[str, Any]]:
    """Samples start..stop of `twinloop adapt train`'s set (the same draws however split): change, part,
    static fall angles (deg, true and noisy), CoM (m), total_mass (kg), feet and the three-mass LIPM."""
def adapt(prior: RobotSpec, tipover: dict[str, Any], total_mass: Optional[float] = None, host: Optional[str] = None,
          merge: bool = False, resolution: Optional[float] = None, check: bool = False) -> tuple[dict[str, Any], Optional[Description]]:
    """`twinloop adapt --tipover FILE --json`'s report and the adapted description (None if not fixed);
    total_mass kg, resolution deg."""
def adapt_to_protocol(prior: RobotSpec, tipover: dict[str, Any], passes: int = 3, total_mass: Optional[float] = None,
                      host: Optional[str] = None, merge: bool = False, resolution: Optional[float] = None,
                      ground_sink: Optional[float] = None) -> tuple[dict[str, Any], Optional[Description], Optional[dict[str, Any]]]:
    """`twinloop adapt --tipover FILE --protocol-passes N --json`'s report, the adapted description (None if not
    fixed) and the passes (`demo --json`'s calibration: passes [{bias_deg, static_deg, protocol_deg, adapted_com}],
    kept; None when none ran); total_mass kg, resolution deg (None: as adapt), ground_sink m (None: found from the sideways tips, as the CLI); GIL released."""
def fit_compliant(data: Union[str, PathLike[str]], plant: Union[str, PathLike[str]],
                  method: Literal["lm", "cmaes", "power"] = "lm", params: Optional[Union[str, Sequence[str]]] = None,
                  start: Optional[Sequence[float]] = None, max_evaluations: Optional[int] = None, sigma: float = 0.05,
                  seed: int = 2012, noise_std: Optional[float] = None,
                  val: Sequence[Union[str, PathLike[str]]] = ()) -> dict[str, Any]:
    """`twinloop identify compliant --json` (seed 002, section 4): the compact compliant model's corrections fitted
    to a CSV of t, xr, zr, x, z, phase; returns the CLI's fields (params, mse_before/after in m^2, identifiability, ...)."""
def sysid_arx(u: ArrayLike, y: ArrayLike, na: int = 2, nb: int = 2, nk: int = 1, u_val: Optional[ArrayLike] = None,
              y_val: Optional[ArrayLike] = None, sample_time: Optional[float] = None, input_names: Optional[list[str]] = None,
              output_names: Optional[list[str]] = None, kstep: int = 1, lags: int = 25, detrend: bool = True) -> dict[str, Any]:
    """u [N, nu], y [N, ny] (N >= 2), sample_time s -> `twinloop identify arx --json`'s fields; detrend as the CLI
    (False: --no-detrend)."""
def sysid_ss(u: ArrayLike, y: ArrayLike, order: int, method: Literal["n4sid", "pem", "arx-reduce-pem"] = "pem",
             u_val: Optional[ArrayLike] = None, y_val: Optional[ArrayLike] = None, sample_time: Optional[float] = None,
             na: int = 10, nb: int = 10, nk: int = 1, max_iter: int = 100, feedthrough: bool = False,
             estimate_x0: bool = False, focus: Literal["prediction", "simulation"] = "prediction", kstep: int = 1,
             lags: int = 25, detrend: bool = True, input_names: Optional[list[str]] = None,
             output_names: Optional[list[str]] = None) -> dict[str, Any]:
    """u [N, nu], y [N, ny] (N >= 2), sample_time s -> `twinloop identify ss --json`'s fields."""

class Bus:
    """A Dynamixel bus (serial device, pty path or tcp:HOST:PORT); OSError on port and servo errors."""
    def __init__(self, port: str, baud: int = 1_000_000, timeout_ms: float = 10.0, retries: int = 2) -> None:
        """Open the port at baud (bit/s); timeout_ms: the wait for a reply (ms); retries: resends of an
        unanswered packet."""
    def scan(self, protocol: Optional[int] = None, ids: Optional[tuple[int, int]] = None) -> list[dict[str, Any]]:
        """`twinloop link scan --json`: protocol, id, model, model_number, firmware."""
    def read(self, id: int, protocol: int, registers: Optional[list[str]] = None) -> dict[str, Any]:
        """`twinloop link read --json`: protocol, id, model, registers (address, name, size, access, raw, value)."""
    def record(self, duration: float, map: Optional[str] = None, protocol: Optional[int] = None,
               ids: Optional[Sequence[int]] = None, rate: float = 100.0,
               method: Literal["auto", "read", "bulk", "sync", "fast"] = "auto",
               out: Optional[Union[str, PathLike[str]]] = None, verified_reads: bool = False) -> dict[str, Any]:
        """`twinloop link record`: read every joint for `duration` s at `rate` reads/s (0: as fast as the bus allows).

        The robot is `map` (mapping TOML or builtin:NAME) or `protocol` and `ids`. Returns columns (t, q:*, v:*,
        tau:*), data (rows, 1 + 3 joints) in s, rad, rad/s, N m with NaN where a servo did not answer, rows,
        seconds, failures (per joint), interrupted (Ctrl-C). `out`: also write each row to that CSV as it is read.
        """

class VirtualRobotServer:
    """A simulated robot behind the servo protocol on a new pty (`twinloop serve`); a context manager."""
    def __init__(self, robot: Optional[RobotSpec] = None, mapping: str = "builtin:km20", realtime_factor: float = 1.0,
                 catch_falls: bool = False, ground_sink: Optional[float] = None) -> None:
        """Serve `robot` (default km20) through `mapping`; realtime_factor: simulated s per wall-clock s;
        catch_falls: stand a fallen robot up; ground_sink: the floor's give under the robot's weight, m (1 mm)."""
    @property
    def path(self) -> str:
        """The pty to open a Bus on."""
    def close(self) -> None:
        """Stop serving (OSError if the server failed)."""
    def __enter__(self) -> VirtualRobotServer:
        """The server itself."""
    def __exit__(self, *args: Any) -> None:
        """close()."""

"""Type stubs of twinloop's native module. Shapes in brackets; units SI (m, kg, s, rad, N, N m).

Floating base (Pinocchio's JointModelFreeFlyer): q = [x, y, z, qx, qy, qz, qw, joints...]
(nq = 7 + joints), v = [vx, vy, vz, wx, wy, wz, joints...] (nv = 6 + joints), linear then
angular, both in the base frame. Arguments accept anything numpy converts to float64;
a wrong shape or a non-finite entry raises ValueError naming the argument.
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
    def from_urdf(text: str) -> Description: ...
    @property
    def name(self) -> str: ...
    @property
    def total_mass(self) -> float:
        """Sum of link masses, kg."""
    @property
    def links(self) -> list[dict[str, Any]]:
        """name, mass (kg), com [3] (m, link frame), inertia [3, 3] (kg m^2); None without <inertial>."""
    @property
    def joints(self) -> list[dict[str, Any]]:
        """name, type, parent, child, axis, lower/upper (rad or m), effort, velocity, armature."""
    @property
    def findings(self) -> list[dict[str, Any]]:
        """Lint findings: severity, code, subject, name, message."""
    def lint(self) -> dict[str, Any]:
        """`twinloop model check --json`'s report."""
    def with_point_mass(self, link: str, mass: float, xyz: Sequence[float]) -> Description:
        """A copy with mass (kg) added at xyz (m, link frame)."""
    def to_urdf(self) -> str: ...

class Model:
    """The compiled dynamics model (constant). Picklable."""
    @staticmethod
    def from_description(description: Description, floating: bool = True) -> Model: ...
    @property
    def name(self) -> str: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def joint_names(self) -> list[str]:
        """Joint i has q index nq - len(joint_names) + i and v index nv - len(joint_names) + i."""
    @property
    def frame_names(self) -> list[str]: ...
    @property
    def link_names(self) -> list[str]:
        """Description links: the blocks of static_com_regressor."""
    @property
    def floating(self) -> bool: ...
    @property
    def total_mass(self) -> float: ...
    @property
    def gravity(self) -> F64:
        """[3], m/s^2, world frame."""
    @property
    def lower_position_limit(self) -> F64: ...
    @property
    def upper_position_limit(self) -> F64: ...
    @property
    def description(self) -> Description: ...
    def joint_index(self, name: str) -> Optional[int]: ...
    def frame_index(self, name: Union[str, int]) -> int: ...
    def neutral(self) -> F64:
        """[nq]: base at the origin, identity orientation, joints 0."""

class Data:
    """Workspace of one model. Its arrays are read-only views (no copy), updated by every call."""
    def __init__(self, model: Model) -> None: ...
    @property
    def tau(self) -> F64:
        """[nv] from rnea / nonlinear_effects / compute_generalized_gravity."""
    @property
    def ddq(self) -> F64:
        """[nv] from aba."""
    @property
    def M(self) -> F64:
        """[nv, nv] from crba, symmetric."""
    @property
    def J(self) -> F64:
        """[6, nv] joint Jacobians (world) from compute_joint_jacobians."""
    @property
    def Jcom(self) -> F64:
        """[3, nv] from jacobian_center_of_mass."""
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
        """Body placements [4, 4] (copies)."""
    @property
    def oMf(self) -> list[F64]:
        """Frame placements [4, 4] (copies), after frames_forward_kinematics."""

def forward_kinematics(model: Model, data: Data, q: ArrayLike) -> None: ...
def frames_forward_kinematics(model: Model, data: Data, q: ArrayLike) -> None: ...
def center_of_mass(model: Model, data: Data, q: ArrayLike) -> F64:
    """[3] m, world (view of data.com)."""
def jacobian_center_of_mass(model: Model, data: Data, q: ArrayLike) -> F64:
    """[3, nv] (view of data.Jcom)."""
def compute_joint_jacobians(model: Model, data: Data, q: ArrayLike) -> F64:
    """[6, nv] (view of data.J)."""
def frame_jacobian(model: Model, data: Data, q: ArrayLike, frame: Union[str, int], reference: Reference = "LOCAL") -> F64:
    """[6, nv], rows linear then angular (a new array)."""
def rnea(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> F64:
    """tau [nv] = M a + C v + g (view of data.tau)."""
def nonlinear_effects(model: Model, data: Data, q: ArrayLike, v: ArrayLike) -> F64: ...
def compute_generalized_gravity(model: Model, data: Data, q: ArrayLike) -> F64: ...
def crba(model: Model, data: Data, q: ArrayLike) -> F64:
    """M [nv, nv] (view of data.M)."""
def aba(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> F64:
    """ddq [nv] (view of data.ddq); ValueError naming the joint if M(q) is singular."""
def joint_torque_regressor(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> F64:
    """Y [nv, 10 * bodies]; rnea = Y @ body_parameters(model)."""
def static_com_regressor(model: Model, data: Data, q: ArrayLike) -> F64:
    """G [3, 4 * links]; total_mass * com = G @ link_static_parameters(model)."""
def body_parameters(model: Model) -> F64: ...
def link_static_parameters(model: Model) -> F64: ...

def rnea_batch(model: Model, Q: ArrayLike, V: ArrayLike, A: ArrayLike, threads: Optional[int] = None) -> F64:
    """[N, nq], [N, nv], [N, nv] -> [N, nv], GIL released, on `threads` threads (default all cores)."""
def aba_batch(model: Model, Q: ArrayLike, V: ArrayLike, TAU: ArrayLike, threads: Optional[int] = None) -> F64:
    """Q [N, nq], V [N, nv] (rad/s), TAU [N, nv] (N m) -> ddq [N, nv] (rad/s^2); ValueError naming the lowest row
    and the joint where M(q) is singular, as aba."""
def nonlinear_effects_batch(model: Model, Q: ArrayLike, V: ArrayLike, threads: Optional[int] = None) -> F64: ...
def crba_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """[N, nv, nv]."""
def center_of_mass_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64:
    """[N, 3]."""
def jacobian_center_of_mass_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64: ...
def compute_joint_jacobians_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64: ...
def frame_jacobian_batch(model: Model, Q: ArrayLike, frame: Union[str, int], reference: Reference = "LOCAL", threads: Optional[int] = None) -> F64: ...
def joint_torque_regressor_batch(model: Model, Q: ArrayLike, V: ArrayLike, A: ArrayLike, threads: Optional[int] = None) -> F64: ...
def static_com_regressor_batch(model: Model, Q: ArrayLike, threads: Optional[int] = None) -> F64: ...

class Simulator:
    """config: dt (s, 1e-3), servo ("auto", "rx28", "rx64", "xm430", "passive", "torque"), ground, stand."""
    def __init__(self, robot: RobotSpec, config: Optional[dict[str, Any]] = None) -> None: ...
    def step(self, n: int = 1) -> None: ...
    @property
    def time(self) -> float: ...
    @property
    def dt(self) -> float: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def q(self) -> F64: ...
    @property
    def v(self) -> F64: ...
    def get_state(self) -> F64:
        """[nq + nv]."""
    def set_state(self, q: ArrayLike, v: ArrayLike) -> None: ...
    @property
    def goals(self) -> F64: ...
    @goals.setter
    def goals(self, goals: ArrayLike) -> None: ...
    @property
    def applied(self) -> F64: ...
    def center_of_mass(self) -> F64: ...
    def sensors(self) -> dict[str, Any]:
        """time, positions, velocities, efforts, imu_gyro, imu_accel, imu_orientation, foot_names, foot_force, foot_cop."""
    def rollout(self, q0: ArrayLike, goals: ArrayLike, v0: Optional[ArrayLike] = None, threads: Optional[int] = None) -> F64:
        """q0 [nq] or [N, nq], goals [N, T, joints] -> states [N, T, nq + nv]."""

def tipover(robot: Optional[RobotSpec] = None, ramp: float = 0.5, slow_ramp: float = 0.05, compliance_slope: float = 2.0,
            encoders: bool = False, add_mass: Optional[Sequence[tuple[float, str, Sequence[float]]]] = None, *,
            port: Optional[str] = None, map: Optional[str] = None, directions: Optional[Sequence[str]] = None,
            record: Optional[Union[str, PathLike[str]]] = None, yes: bool = False, realtime_factor: float = 1.0,
            ankle_slope: float = 32.0, creeps: int = 2, baud: int = 1_000_000, timeout_ms: float = 10.0, retries: int = 2) -> dict[str, Any]:
    """`twinloop experiment tipover --json`'s fields: on the simulator, or with `port` and `map` on a robot over its bus
    (`experiment tipover --port --map`; fewer than four `directions` give robot, port and each direction's angles).
    A serial port needs yes=True; a silent or faulty servo raises OSError, the servos left holding."""
def random_changes(robot: RobotSpec, n: int, seed: int = 1, mass_range: tuple[float, float] = (0.05, 0.5)) -> list[dict[str, Any]]: ...
def tipover_changes(robot: RobotSpec, changes: list[dict[str, Any]], simulate: bool = False, ramp: float = 0.5,
                    slow_ramp: float = 0.05, threads: Optional[int] = None) -> list[dict[str, Any]]: ...
def static_poses(robot: RobotSpec, count: int = 172, cop_noise: float = 0.0, joint_noise: float = 0.0, seed: int = 1) -> dict[str, Any]:
    """q [P, nq], cop [P, 2] (m), category [P]."""
def identify_static(robot: RobotSpec, q: ArrayLike, cop: ArrayLike, total_mass: float, links: Optional[list[str]] = None,
                    cop_sigma: float = 1e-3, com_margin: float = 0.03, category: Optional[list[Optional[str]]] = None) -> dict[str, Any]:
    """`twinloop identify static --json`'s schema, cop_sigma, com_margin and result."""
def training_samples(robot: RobotSpec, start: int, stop: int, seed: int = 1, mass_range: tuple[float, float] = (0.05, 0.5),
                     noise_deg: float = 0.0, threads: Optional[int] = None) -> list[dict[str, Any]]: ...
def adapt(prior: RobotSpec, tipover: dict[str, Any], total_mass: Optional[float] = None, host: Optional[str] = None,
          merge: bool = False, resolution: float = 0.05, check: bool = False) -> tuple[dict[str, Any], Optional[Description]]:
    """`twinloop adapt --tipover FILE --json`'s report and the adapted description (None if not fixed)."""
def fit_compliant(data: Union[str, PathLike[str]], plant: Union[str, PathLike[str]],
                  method: Literal["lm", "cmaes", "power"] = "lm", params: Optional[Union[str, Sequence[str]]] = None,
                  start: Optional[Sequence[float]] = None, max_evaluations: Optional[int] = None, sigma: float = 0.05,
                  seed: int = 2012, noise_std: Optional[float] = None,
                  val: Sequence[Union[str, PathLike[str]]] = ()) -> dict[str, Any]:
    """`twinloop identify compliant --json` (seed 002, section 4): the compact compliant model's corrections fitted
    to a CSV of t, xr, zr, x, z, phase; returns the CLI's fields (params, mse_before/after in m^2, identifiability, ...)."""
def sysid_arx(u: ArrayLike, y: ArrayLike, na: int = 2, nb: int = 2, nk: int = 1, u_val: Optional[ArrayLike] = None,
              y_val: Optional[ArrayLike] = None, sample_time: Optional[float] = None, input_names: Optional[list[str]] = None,
              output_names: Optional[list[str]] = None, kstep: int = 1, lags: int = 25) -> dict[str, Any]:
    """u [N, nu], y [N, ny] -> `twinloop identify arx --json`'s fields."""
def sysid_ss(u: ArrayLike, y: ArrayLike, order: int, method: Literal["n4sid", "pem", "arx-reduce-pem"] = "pem",
             u_val: Optional[ArrayLike] = None, y_val: Optional[ArrayLike] = None, sample_time: Optional[float] = None,
             na: int = 10, nb: int = 10, nk: int = 1, max_iter: int = 100, feedthrough: bool = False,
             estimate_x0: bool = False, focus: Literal["prediction", "simulation"] = "prediction", kstep: int = 1,
             lags: int = 25) -> dict[str, Any]:
    """u [N, nu], y [N, ny] -> `twinloop identify ss --json`'s fields."""

class Bus:
    """A Dynamixel bus (serial device, pty path or tcp:HOST:PORT); OSError on port and servo errors."""
    def __init__(self, port: str, baud: int = 1_000_000, timeout_ms: float = 10.0, retries: int = 2) -> None: ...
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
                 catch_falls: bool = False, ground_sink: Optional[float] = None) -> None: ...
    @property
    def path(self) -> str: ...
    def close(self) -> None: ...
    def __enter__(self) -> VirtualRobotServer: ...
    def __exit__(self, *args: Any) -> None: ...

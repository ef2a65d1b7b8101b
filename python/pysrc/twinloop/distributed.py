"""Sweeps of independent jobs on Ray (``pip install "twinloop[ray]"``).

Four kinds of job, each a function returning writable numpy arrays (in a dataclass)
equal to the serial loop's results:

- :func:`tipover_sweep`: the tip-over (static, or the simulated study) of many
  hardware changes of one robot;
- :func:`static_identification_monte_carlo`: static identification from many noisy
  draws of force-plate poses;
- :func:`sysid_order_sweep`: ARX or state-space models of one record at many orders;
- :func:`team_adaptation`: the adaptation of each robot of a team to its own
  tip-over experiment.

:func:`map_batches` runs your own. Each Ray task takes a batch of jobs, rebuilds the
robot in its worker from the pickled description (URDF text, a few tens of kB, put in
Ray's object store once, as is any ``shared`` data such as a sysid record), sizes its
Rust threads from the CPUs Ray gave it, and returns ``(batch index, results)``. The
driver keeps one result per batch index, so a task that Ray runs again after its
worker died (``max_retries``) neither loses nor duplicates results: the results come
back in job order, exactly as the serial loop gives them.

``ray.init()`` is called locally unless Ray is already initialised or ``address=``
names a cluster (``"auto"``, ``"ray://host:10001"``).

    >>> import twinloop, twinloop.distributed as td
    >>> changes = twinloop.random_changes("builtin:km20", 1000, seed=1)
    >>> sweep = td.tipover_sweep("builtin:km20", changes, batch_size=50)
    >>> sweep.static_deg.shape
    (1000, 4)
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _native

__all__ = ["map_batches", "tipover_sweep", "TipoverSweep", "static_identification_monte_carlo",
           "sysid_order_sweep", "SysidSweep", "team_adaptation", "TeamAdaptation", "assigned_cpus"]

# The keyword arguments of map_batches, which the job helpers pass on to it.
_MAP_OPTIONS = ("batch_size", "address", "cpus_per_task", "max_retries", "progress")


def _split_options(options: dict) -> tuple[dict, dict]:
    """(map_batches' options, the rest) of a helper's keyword arguments."""
    ours = {k: v for k, v in options.items() if k in _MAP_OPTIONS}
    return ours, {k: v for k, v in options.items() if k not in _MAP_OPTIONS}


def _ray():
    try:
        import ray
    except ImportError as e:  # pragma: no cover - the message is the point
        raise ImportError('twinloop.distributed needs Ray: pip install "twinloop[ray]"') from e
    return ray


def assigned_cpus() -> int:
    """CPUs Ray assigned to the current task (1 outside a task)."""
    ray = _ray()
    try:
        cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1.0)
    except AssertionError:  # not inside a Ray worker
        return 1
    return max(1, int(math.floor(cpus)))


def _as_description(robot: Any) -> _native.Description:
    if isinstance(robot, _native.Description):
        return robot
    return _native.load(robot)


def _progress(total: int, enabled: bool, desc: str):
    if not enabled:
        return None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return _TextBar(total, desc)
    return tqdm(total=total, desc=desc, unit="job")


class _TextBar:
    """A minimal progress line on stderr when tqdm is not installed."""

    def __init__(self, total: int, desc: str):
        self.total, self.done, self.desc = total, 0, desc

    def update(self, n: int) -> None:
        self.done += n
        print(f"\r{self.desc}: {self.done}/{self.total} jobs", end="", file=sys.stderr, flush=True)

    def close(self) -> None:
        print(file=sys.stderr)


def _run_batch(func: Callable, index: int, robot: Any, jobs: list, kwargs: dict, shared: Any = None):
    """The body of every Ray task: one batch of jobs, threads from the CPUs given."""
    if shared is not None:
        kwargs = dict(kwargs, shared=shared)
    return index, func(robot, jobs, threads=assigned_cpus(), **kwargs)


def map_batches(
    func: Callable[..., list],
    robot: Any,
    jobs: Sequence,
    *,
    batch_size: int = 20,
    address: str | None = None,
    cpus_per_task: float = 1,
    max_retries: int = 3,
    progress: bool = True,
    shared: Any = None,
    **kwargs,
) -> list:
    """Run ``func(robot, batch, threads=n, **kwargs) -> list`` over ``jobs`` in batches
    of ``batch_size``, one Ray task per batch, and return the concatenated results in
    job order. ``func`` must be deterministic (a retried batch then gives the same
    results) and return one result per job. ``robot`` is a Description (or a path or
    builtin name, loaded here), or None for jobs without one; it travels pickled, once,
    through the object store. So does ``shared`` (data every task needs, such as the
    arrays of a record), given to ``func`` as ``shared=`` when it is not None.
    """
    if batch_size < 1:
        raise ValueError(f"batch_size: must be at least 1, got {batch_size}")
    ray = _ray()
    if not ray.is_initialized():
        ray.init(address=address, include_dashboard=False)
    robot_ref = ray.put(None if robot is None else _as_description(robot))
    shared_ref = None if shared is None else ray.put(shared)
    task = ray.remote(num_cpus=cpus_per_task, max_retries=max_retries, retry_exceptions=False)(_run_batch)
    batches = [list(jobs[i:i + batch_size]) for i in range(0, len(jobs), batch_size)]
    pending = {task.remote(func, k, robot_ref, b, kwargs, shared_ref): k for k, b in enumerate(batches)}
    results: dict[int, list] = {}
    bar = _progress(len(jobs), progress, getattr(func, "__name__", "jobs"))
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                k, out = ray.get(ref)
                del pending[ref]
                if len(out) != len(batches[k]):
                    raise RuntimeError(f"batch {k}: {len(out)} results for {len(batches[k])} jobs")
                if k not in results and bar is not None:
                    bar.update(len(out))
                results[k] = out  # idempotent: a batch's result replaces, never adds
    finally:
        if bar is not None:
            bar.close()
    return [r for k in range(len(batches)) for r in results[k]]


def _tipover_batch(robot, changes, threads=1, simulate=False, ramp=0.5, slow_ramp=0.05):
    return _native.tipover_changes(robot, changes, simulate=simulate, ramp=ramp, slow_ramp=slow_ramp, threads=threads)


@dataclass
class TipoverSweep:
    """The tip-over of each change, row k for ``changes[k]``: writable float64 arrays.

    static_deg: (N, 4) static fall angles, deg (forward, backward, left, right);
    com: (N, 3) CoM, m, standing frame (ankle pitch midpoint, x forward, z up);
    total_mass: (N,) kg; simulated_deg: (N, 4) the simulated study's measured angles,
    deg, or None without ``simulate``.
    """

    changes: list
    static_deg: np.ndarray
    com: np.ndarray
    total_mass: np.ndarray
    simulated_deg: Optional[np.ndarray]

    @classmethod
    def from_rows(cls, rows: Sequence[dict]) -> "TipoverSweep":
        """From ``twinloop.tipover_changes``' dicts (the serial loop's)."""
        simulated = [r["simulated_deg"] for r in rows]
        return cls(
            changes=[r["change"] for r in rows],
            static_deg=np.array([r["static_deg"] for r in rows], dtype=float).reshape(-1, 4),
            com=np.array([r["com"] for r in rows], dtype=float).reshape(-1, 3),
            total_mass=np.array([r["total_mass"] for r in rows], dtype=float),
            simulated_deg=None if any(s is None for s in simulated) else
            np.array(simulated, dtype=float).reshape(-1, 4),
        )

    def __len__(self) -> int:
        return len(self.changes)


def tipover_sweep(robot: Any, changes: Sequence[dict], *, simulate: bool = False, ramp: float = 0.5,
                  slow_ramp: float = 0.05, **options) -> TipoverSweep:
    """The tip-over of every change (dicts {link, mass (kg), xyz (m)}, e.g. from
    ``twinloop.random_changes``) on Ray: per change the static fall angles (deg), the
    CoM (m), the total mass (kg) and, with ``simulate=True``, the simulated study's
    measured angles (deg; ramps in deg/s), as a :class:`TipoverSweep` of arrays equal to
    ``TipoverSweep.from_rows(twinloop.tipover_changes(robot, changes, ...))``.
    ``options`` go to :func:`map_batches` (batch_size, address, cpus_per_task,
    max_retries, progress).
    """
    rows = map_batches(_tipover_batch, robot, list(changes), simulate=simulate, ramp=ramp,
                       slow_ramp=slow_ramp, **options)
    return TipoverSweep.from_rows(rows)


def _static_trial_batch(robot, trials, threads=1, truth=None, total_mass=None, count=60, cop_noise=1e-3,
                        joint_noise=0.0, cop_sigma=1e-3):
    out = []
    for seed in trials:
        poses = _native.static_poses(truth, count=count, cop_noise=cop_noise, joint_noise=joint_noise, seed=seed)
        r = _native.identify_static(robot, poses["q"], poses["cop"], total_mass, cop_sigma=cop_sigma,
                                    category=poses["category"])
        links = r["result"]["links"]
        out.append({
            "seed": seed,
            "links": [link["name"] for link in links],
            "mass": np.array([link["mass"] for link in links]),
            "com": np.array([link["com"] for link in links]),
        })
    return out


def static_identification_monte_carlo(prior: Any, truth: Any, seeds: Sequence[int], *, count: int = 60,
                                      cop_noise: float = 1e-3, joint_noise: float = 0.0,
                                      cop_sigma: float = 1e-3, **options) -> list[dict]:
    """Monte Carlo of static identification on Ray: for each seed, ``count`` virtual
    force-plate poses of ``truth`` with CoP noise ``cop_noise`` (m) and joint noise
    (rad), identified from ``prior`` with the true total mass. Returns per seed the
    identified link masses (kg) and CoMs (m, link frames) as writable numpy arrays.
    """
    truth_d = _as_description(truth)
    return map_batches(_static_trial_batch, prior, list(seeds), truth=truth_d, total_mass=truth_d.total_mass,
                       count=count, cop_noise=cop_noise, joint_noise=joint_noise, cop_sigma=cop_sigma, **options)


def _arx_orders(order: Union[int, Sequence[int]]) -> tuple[int, int, int]:
    if isinstance(order, (int, np.integer)):
        return int(order), int(order), 1
    na, nb, nk = order
    return int(na), int(nb), int(nk)


def _sysid_batch(robot, orders, threads=1, shared=None, method="arx", fit_options=None):
    u, y, u_val, y_val = shared
    out = []
    for order in orders:
        try:
            if method == "arx":
                na, nb, nk = order
                model = _native.sysid_arx(u, y, na=na, nb=nb, nk=nk, u_val=u_val, y_val=y_val, **fit_options)
            else:
                model = _native.sysid_ss(u, y, order, method=method, u_val=u_val, y_val=y_val, **fit_options)
        except ValueError as e:  # an order the record cannot support: a row, not a failed sweep
            out.append({"error": str(e)})
            continue
        model.pop("timing_seconds")  # wall-clock times differ from run to run
        out.append(model)
    return out


@dataclass
class SysidSweep:
    """One model per order, row k for ``orders[k]``: writable float64 arrays, NaN where
    the order failed (its message in ``errors[k]``).

    simulation_fit, prediction_fit: (J, ny) FIT % on the validation record when one was
    given, else on the estimation record (``fit_data`` says which); prediction_cost:
    (J,) the prediction-error cost; models: the full ``twinloop identify arx/ss --json``
    fields of each order (without ``timing_seconds``), or None where it failed.
    """

    orders: list
    simulation_fit: np.ndarray
    prediction_fit: np.ndarray
    prediction_cost: np.ndarray
    fit_data: str
    models: list
    errors: list

    def best(self) -> int:
        """Index of the order with the highest mean simulation FIT."""
        ok = ~np.isnan(self.simulation_fit).any(axis=1)
        if not ok.any():
            raise ValueError(f"no order succeeded: {self.errors[0]}")
        means = np.full(len(ok), -np.inf)
        means[ok] = self.simulation_fit[ok].mean(axis=1)
        return int(np.argmax(means))


def sysid_order_sweep(u: Any, y: Any, orders: Sequence, *, method: str = "arx", u_val: Any = None,
                      y_val: Any = None, **options) -> SysidSweep:
    """Black-box models of one record at many orders on Ray: ``method="arx"`` with
    orders (na, nb, nk) (an int n is (n, n, 1)), or ``"n4sid"``, ``"pem"``,
    ``"arx-reduce-pem"`` with state counts. u: (N, nu), y: (N, ny) samples (and
    u_val, y_val to evaluate on), put in Ray's object store once. Each order is
    ``twinloop.sysid.arx`` / ``ss`` with the other ``options`` (sample_time, detrend,
    input_names, output_names, kstep, lags; for ss na, nb, nk, max_iter, focus, ...);
    batch_size, address, cpus_per_task, max_retries and progress go to
    :func:`map_batches`. Returns a :class:`SysidSweep`.
    """
    ours, fit_options = _split_options(options)
    if method == "arx":
        jobs = [_arx_orders(o) for o in orders]
    elif method in ("n4sid", "pem", "arx-reduce-pem"):
        jobs = [int(o) for o in orders]
    else:
        raise ValueError(f'method: "{method}" is not arx, n4sid, pem or arx-reduce-pem')
    arrays = tuple(None if a is None else np.ascontiguousarray(a, dtype=float) for a in (u, y, u_val, y_val))
    ours.setdefault("batch_size", max(1, len(jobs) // 8))
    models = map_batches(_sysid_batch, None, jobs, shared=arrays, method=method, fit_options=fit_options, **ours)
    ny = arrays[1].shape[1] if arrays[1].ndim == 2 else 1
    nan = np.full(ny, np.nan)
    ok = [m for m in models if "error" not in m]
    return SysidSweep(
        orders=jobs,
        simulation_fit=np.array([m["fit_percent"]["simulation"] if "error" not in m else nan for m in models],
                                dtype=float).reshape(-1, ny),
        prediction_fit=np.array([m["fit_percent"]["prediction"] if "error" not in m else nan for m in models],
                                dtype=float).reshape(-1, ny),
        prediction_cost=np.array([m.get("prediction_cost", np.nan) for m in models], dtype=float),
        fit_data=ok[0]["fit_percent"]["data"] if ok else ("validation" if u_val is not None else "estimation"),
        models=[None if "error" in m else m for m in models],
        errors=[m.get("error") for m in models],
    )


def _adapt_batch(prior, robots, threads=1, resolution=None, merge=False, check=False):
    out = []
    for r in robots:
        report, adapted = _native.adapt(prior, r["tipover"], total_mass=r.get("total_mass"), host=r.get("host"),
                                        merge=merge, resolution=resolution, check=check)
        out.append((report, adapted))
    return out


@dataclass
class TeamAdaptation:
    """Each robot's adaptation, row k for ``robots[k]``: writable float64 arrays.

    added_mass: (R,) kg; added_position: (R, 3) m, in the frame of the report's
    CoMs (ankle pitch midpoint of the standing pose, x forward, y left, z up);
    measured_com, adapted_com: (R, 3) m, same frame; reports: each ``twinloop adapt
    --json`` report; adapted: each adapted Description (None where the family of
    solutions was not fixed: neither total_mass nor host given).
    """

    reports: list
    adapted: list
    added_mass: np.ndarray
    added_position: np.ndarray
    measured_com: np.ndarray
    adapted_com: np.ndarray


def team_adaptation(prior: Any, robots: Sequence[dict], *, resolution: Optional[float] = None, merge: bool = False,
                    check: bool = False, **options) -> TeamAdaptation:
    """Adapt ``prior`` to each robot of a team on Ray: ``robots`` are dicts with
    ``tipover`` (that robot's tip-over report: ``twinloop.tipover()``'s dict or the
    JSON of ``twinloop experiment tipover``) and ``total_mass`` (kg, the robot on a
    scale) or ``host`` (the link the added mass is on), as ``twinloop.adapt`` takes
    them, with ``resolution`` (deg), ``merge`` and ``check``. ``options`` go to
    :func:`map_batches`. Returns a :class:`TeamAdaptation`.
    """
    for k, r in enumerate(robots):
        if "tipover" not in r:
            raise ValueError(f'robots[{k}]: needs "tipover" (the robot\'s tip-over report)')
    pairs = map_batches(_adapt_batch, prior, [dict(r) for r in robots], resolution=resolution, merge=merge,
                        check=check, **options)
    reports = [p[0] for p in pairs]
    added = [r["added"] for r in reports]
    return TeamAdaptation(
        reports=reports,
        adapted=[p[1] for p in pairs],
        added_mass=np.array([a["mass"] for a in added], dtype=float),
        added_position=np.array([a["position"] for a in added], dtype=float).reshape(-1, 3),
        measured_com=np.array([r["measured_com"] for r in reports], dtype=float).reshape(-1, 3),
        adapted_com=np.array([r["adapted_com"] for r in reports], dtype=float).reshape(-1, 3),
    )

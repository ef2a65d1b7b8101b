"""Sweeps of independent jobs on Ray (``pip install "twinloop[ray]"``).

Each Ray task takes a batch of jobs, rebuilds the robot in its worker from the
pickled description (URDF text, a few tens of kB, put in Ray's object store once),
sizes its Rust threads from the CPUs Ray gave it, and returns ``(batch index,
results)``. The driver keeps one result per batch index, so a task that Ray runs
again after its worker died (``max_retries``) neither loses nor duplicates results:
the results come back in job order, exactly as the serial loop gives them.

``ray.init()`` is called locally unless Ray is already initialised or ``address=``
names a cluster (``"auto"``, ``"ray://host:10001"``).

    >>> import twinloop, twinloop.distributed as td
    >>> changes = twinloop.random_changes("builtin:km20", 1000, seed=1)
    >>> rows = td.tipover_sweep("builtin:km20", changes, batch_size=50)
"""

from __future__ import annotations

import math
import sys
from typing import Any, Callable, Sequence

import numpy as np

from . import _native

__all__ = ["map_batches", "tipover_sweep", "static_identification_monte_carlo", "assigned_cpus"]


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


def _run_batch(func: Callable, index: int, robot: Any, jobs: list, kwargs: dict):
    """The body of every Ray task: one batch of jobs, threads from the CPUs given."""
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
    **kwargs,
) -> list:
    """Run ``func(robot, batch, threads=n, **kwargs) -> list`` over ``jobs`` in batches
    of ``batch_size``, one Ray task per batch, and return the concatenated results in
    job order. ``func`` must be deterministic (a retried batch then gives the same
    results) and return one result per job. ``robot`` is a Description (or a path or
    builtin name, loaded here) and travels pickled, once, through the object store.
    """
    if batch_size < 1:
        raise ValueError(f"batch_size: must be at least 1, got {batch_size}")
    ray = _ray()
    if not ray.is_initialized():
        ray.init(address=address, include_dashboard=False)
    robot_ref = ray.put(_as_description(robot))
    task = ray.remote(num_cpus=cpus_per_task, max_retries=max_retries, retry_exceptions=False)(_run_batch)
    batches = [list(jobs[i:i + batch_size]) for i in range(0, len(jobs), batch_size)]
    pending = {task.remote(func, k, robot_ref, b, kwargs): k for k, b in enumerate(batches)}
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


def tipover_sweep(robot: Any, changes: Sequence[dict], *, simulate: bool = False, ramp: float = 0.5,
                  slow_ramp: float = 0.05, **options) -> list[dict]:
    """The tip-over of every change (dicts {link, mass (kg), xyz (m)}, e.g. from
    ``twinloop.random_changes``) on Ray: per change the static fall angles (deg), the
    CoM (m) and, with ``simulate=True``, the simulated study's measured angles.
    Equal to ``twinloop.tipover_changes(robot, changes, ...)``. ``options`` go to
    :func:`map_batches` (batch_size, address, cpus_per_task, max_retries, progress).
    """
    return map_batches(_tipover_batch, robot, list(changes), simulate=simulate, ramp=ramp,
                       slow_ramp=slow_ramp, **options)


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

#!/usr/bin/env python3
"""twinloop from Python against its peers, same models, same states, same run.

    python3 bench/python/bench_python.py [--quick] [--skip-ray] [--json out.json]

1. Per call: twinloop.rnea / aba vs pinocchio.rnea / aba called from Python (binding
   overhead included), G1 and OP3, median over repeats.
2. Batched, N = 1000: twinloop.rnea_batch / aba_batch on 1 and 2 threads vs a Python
   loop over Pinocchio.
3. Rollouts: 64 standing OP3 rollouts of 1 s (dt 1 ms) with Simulator.rollout vs
   mujoco.rollout on op3's MJCF (scene with floor), steps per second per core.
4. Ray: 200 tip-overs (static route, ~0.4 ms each) and 16 simulated tip-over studies
   (~1 s each) of random km20 changes on a local Ray with 1 and 2 CPUs; overhead per
   task; bytes moved per job.

Needs: twinloop (python/test.sh builds it), pin, mujoco, ray.
"""

import argparse
import json
import os
import pathlib
import pickle
import statistics
import time

import numpy as np

import twinloop as tl

REPO = pathlib.Path(__file__).resolve().parents[2]
MODELS = {
    "g1": REPO / "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf",
    "op3": REPO / "models/op3/robotis_op3.nomesh.urdf",
}


def median_per_call(fn, calls, repeats):
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        samples.append((time.perf_counter() - t0) / calls)
    return statistics.median(samples)


def random_states(m, n, rng):
    nj = len(m.joint_names)
    Q = np.zeros((n, m.nq))
    Q[:, :3] = rng.uniform(-1, 1, (n, 3))
    quat = rng.normal(size=(n, 4))
    Q[:, 3:7] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    Q[:, 7:] = rng.uniform(-1.5, 1.5, (n, nj))
    return Q, rng.normal(size=(n, m.nv)), rng.normal(size=(n, m.nv))


def pin_pair(name):
    import pinocchio as pin

    m = tl.Model.from_description(tl.load(MODELS[name]))
    pm = pin.buildModelFromUrdf(str(MODELS[name]), pin.JointModelFreeFlyer())
    q_pin = np.zeros(m.nq, dtype=int)
    nj = len(m.joint_names)
    q_pin[: m.nq - nj] = np.arange(m.nq - nj)
    v_pin = np.zeros(m.nv, dtype=int)
    v_pin[: m.nv - nj] = np.arange(m.nv - nj)
    for jid in range(2, pm.njoints):
        b = m.joint_index(pm.names[jid])
        q_pin[m.nq - nj + b] = pm.joints[jid].idx_q
        v_pin[m.nv - nj + b] = pm.joints[jid].idx_v
    return pin, m, pm, q_pin, v_pin


def per_call(results, quick):
    calls, repeats = (300, 5) if quick else (2000, 15)
    for name in MODELS:
        pin, m, pm, q_pin, v_pin = pin_pair(name)
        d, pd = tl.Data(m), pm.createData()
        Q, V, A = random_states(m, 1, np.random.default_rng(0))
        q, v, a = Q[0], V[0], A[0]
        qp, vp, ap = np.zeros(pm.nq), np.zeros(pm.nv), np.zeros(pm.nv)
        qp[q_pin], vp[v_pin], ap[v_pin] = q, v, a
        row = {
            "twinloop.rnea": median_per_call(lambda: tl.rnea(m, d, q, v, a), calls, repeats),
            "pinocchio.rnea": median_per_call(lambda: pin.rnea(pm, pd, qp, vp, ap), calls, repeats),
            "twinloop.aba": median_per_call(lambda: tl.aba(m, d, q, v, a), calls, repeats),
            "pinocchio.aba": median_per_call(lambda: pin.aba(pm, pd, qp, vp, ap), calls, repeats),
        }
        row["rnea ratio (pin / twinloop)"] = row["pinocchio.rnea"] / row["twinloop.rnea"]
        row["aba ratio (pin / twinloop)"] = row["pinocchio.aba"] / row["twinloop.aba"]
        results[f"per_call_{name}_us"] = {k: x * (1 if "ratio" in k else 1e6) for k, x in row.items()}
        results[f"per_call_{name}_us"]["load"] = os.getloadavg()[0]
        print(f"{name} per call (us): " + ", ".join(f"{k} {x:.4g}" for k, x in results[f"per_call_{name}_us"].items()))


def batched(results, quick):
    n = 1000
    repeats = 3 if quick else 9
    for name in MODELS:
        pin, m, pm, q_pin, v_pin = pin_pair(name)
        pd = pm.createData()
        Q, V, A = random_states(m, n, np.random.default_rng(1))
        Qp, Vp, Ap = np.zeros((n, pm.nq)), np.zeros((n, pm.nv)), np.zeros((n, pm.nv))
        Qp[:, q_pin], Vp[:, v_pin], Ap[:, v_pin] = Q, V, A

        def pin_loop(f, X):
            for i in range(n):
                f(pm, pd, Qp[i], Vp[i], X[i])

        row = {
            "pinocchio.rnea loop": median_per_call(lambda: pin_loop(pin.rnea, Ap), 1, repeats),
            "rnea_batch 1 thread": median_per_call(lambda: tl.rnea_batch(m, Q, V, A, threads=1), 1, repeats),
            "rnea_batch 2 threads": median_per_call(lambda: tl.rnea_batch(m, Q, V, A, threads=2), 1, repeats),
            "pinocchio.aba loop": median_per_call(lambda: pin_loop(pin.aba, Ap), 1, repeats),
            "aba_batch 1 thread": median_per_call(lambda: tl.aba_batch(m, Q, V, A, threads=1), 1, repeats),
            "aba_batch 2 threads": median_per_call(lambda: tl.aba_batch(m, Q, V, A, threads=2), 1, repeats),
        }
        r = {k: x * 1e3 for k, x in row.items()}
        r["rnea ratio (pin loop / 1 thread)"] = row["pinocchio.rnea loop"] / row["rnea_batch 1 thread"]
        r["aba ratio (pin loop / 1 thread)"] = row["pinocchio.aba loop"] / row["aba_batch 1 thread"]
        r["rnea 1 / 2 threads"] = row["rnea_batch 1 thread"] / row["rnea_batch 2 threads"]
        r["aba 1 / 2 threads"] = row["aba_batch 1 thread"] / row["aba_batch 2 threads"]
        r["load"] = os.getloadavg()[0]
        results[f"batch_{name}_ms"] = r
        print(f"{name} N=1000 (ms): " + ", ".join(f"{k} {x:.4g}" for k, x in r.items()))


def rollouts(results, quick):
    import mujoco
    from mujoco import rollout as mj_rollout

    nroll, nstep = (16, 200) if quick else (64, 1000)
    threads = os.cpu_count() or 1
    sim = tl.Simulator(tl.load(REPO / "models/op3/mjcf/op3.xml"), {"dt": 1e-3})
    q0 = sim.q
    goals = np.tile(q0[7:], (nroll, nstep, 1))
    t0 = time.perf_counter()
    states = sim.rollout(q0, goals, threads=threads)
    ours = time.perf_counter() - t0
    height = states[:, -1, 2]

    # The repository keeps op3's MJCF without its meshes: drop the (visual) mesh geoms.
    spec = mujoco.MjSpec.from_file(str(REPO / "models/op3/mjcf/scene.xml"))
    for g in list(spec.geoms):
        if g.type == mujoco.mjtGeom.mjGEOM_MESH:
            spec.delete(g)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    mm = spec.compile()
    mm.opt.timestep = 1e-3
    datas = [mujoco.MjData(mm) for _ in range(threads)]
    d0 = datas[0]
    mujoco.mj_resetData(mm, d0)
    d0.qpos[2] = q0[2]  # the same standing height (the free joint's z)
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    init = np.zeros(mujoco.mj_stateSize(mm, full))
    mujoco.mj_getState(mm, d0, init, full)
    ctrl = np.zeros((nroll, nstep, mm.nu))
    t0 = time.perf_counter()
    mj_state, _ = mj_rollout.rollout([mm] * nroll, datas, np.tile(init, (nroll, 1)), ctrl)
    theirs = time.perf_counter() - t0
    steps = nroll * nstep
    results["rollout_op3"] = {
        "rollouts": nroll, "steps": nstep, "threads": threads,
        "twinloop_steps_per_s_per_core": steps / ours / threads,
        "mujoco_steps_per_s_per_core": steps / theirs / threads,
        "twinloop_final_base_height_m": float(np.median(height)),
        "mujoco_final_base_height_m": float(np.median(mj_state[:, -1, 1 + 2])),
        "ratio": theirs / ours,
        "load": os.getloadavg()[0],
    }
    r = results["rollout_op3"]
    print(f"rollout {nroll} x {nstep} OP3 steps on {threads} threads: twinloop {r['twinloop_steps_per_s_per_core']:.0f}, "
          f"mujoco {r['mujoco_steps_per_s_per_core']:.0f} steps/s/core")


def _tipover_each(robot, changes, threads=1, **kw):
    """tipover_changes one change at a time, so a change whose simulated study fails is
    one error row (counted in the results), not a failed batch."""
    out = []
    for c in changes:
        t0 = time.process_time()
        try:
            row = tl.tipover_changes(robot, [c], threads=threads, **kw)[0]
        except ValueError as e:
            row = {"change": c, "error": str(e)}
        # CPU seconds of the job where it ran: on a shared machine wall time measures the
        # scheduler's share, CPU time the work a cluster node would do.
        row["cpu_s"] = time.process_time() - t0
        out.append(row)
    return out


def _without_cpu(rows):
    return [{k: v for k, v in r.items() if k != "cpu_s"} for r in rows]


def ray_sweep(results, quick, jobs=200, batch_size=10, simulate=False, serial_jobs=None):
    """The sweep on a local Ray of 1 and 2 CPUs; the serial loop on `serial_jobs` of the
    jobs (all by default) gives the time per job the overhead is counted against."""
    import ray

    import twinloop.distributed as td

    prior = tl.load("builtin:km20")
    changes = tl.random_changes(prior, jobs, seed=1)
    kw = {"simulate": simulate, "ramp": 5.0, "slow_ramp": 1.0}
    ns = serial_jobs or jobs
    t0 = time.perf_counter()
    serial = _tipover_each(prior, changes[:ns], threads=1, **kw)
    per_job = (time.perf_counter() - t0) / ns
    serial_cpu = sum(r["cpu_s"] for r in serial) / ns
    serial = _without_cpu(serial)
    t_serial = per_job * jobs
    tasks = -(-jobs // batch_size)
    row = {"jobs": jobs, "batch_size": batch_size, "simulate": simulate, "serial_jobs_timed": ns,
           "serial_s": t_serial, "per_job_s": per_job, "per_job_cpu_s": serial_cpu,
           "description_pickle_bytes": len(pickle.dumps(prior)),
           "bytes_per_job": (len(pickle.dumps(changes[:ns])) + len(pickle.dumps(serial))) / ns,
           "load_before": os.getloadavg()[0]}
    outs = {}
    for cpus in (1, 2):
        ray.init(num_cpus=cpus, include_dashboard=False, log_to_driver=False)
        # Start the workers first: one task per CPU, so neither run pays for it.
        ray.get([ray.remote(lambda: None).remote() for _ in range(4 * cpus)])
        t0 = time.perf_counter()
        outs[cpus] = td.map_batches(_tipover_each, prior, changes, batch_size=batch_size, progress=False, **kw)
        row[f"ray_{cpus}cpu_s"] = time.perf_counter() - t0
        row[f"ray_{cpus}cpu_job_cpu_s"] = sum(r["cpu_s"] for r in outs[cpus]) / jobs
        outs[cpus] = _without_cpu(outs[cpus])
        assert outs[cpus][:ns] == serial
        ray.shutdown()
    assert outs[1] == outs[2]
    row["failed_jobs"] = [i for i, r in enumerate(outs[1]) if "error" in r]
    row["load_after"] = os.getloadavg()[0]
    row["speedup_2_vs_1"] = row["ray_1cpu_s"] / row["ray_2cpu_s"]
    row["overhead_per_task_ms"] = (row["ray_1cpu_s"] - t_serial) / tasks * 1e3
    results[f"ray_sweep_{'simulated' if simulate else 'static'}"] = row
    print(f"ray {jobs} {'simulated' if simulate else 'static'} tip-overs: " + ", ".join(
        f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--skip-ray", action="store_true")
    ap.add_argument("--only-ray", action="store_true")
    ap.add_argument("--sim-jobs", type=int, default=200, help="simulated tip-overs in the Ray sweep")
    ap.add_argument("--json")
    a = ap.parse_args()
    results = {"cpus": os.cpu_count(), "load_at_start": os.getloadavg()}
    if not a.only_ray:
        per_call(results, a.quick)
        batched(results, a.quick)
        rollouts(results, a.quick)
    if not a.skip_ray:
        ray_sweep(results, a.quick)
        # The 200-job sweep of simulated tip-overs (about a second each); the
        # serial time per job from the first 20.
        ray_sweep(results, a.quick, jobs=8 if a.quick else a.sim_jobs, batch_size=2 if a.quick else 10,
                  simulate=True, serial_jobs=None if a.quick else 20)
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()

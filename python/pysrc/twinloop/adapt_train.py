"""The training set of ``twinloop adapt train`` made as Ray tasks.

``twinloop adapt train --ray ADDRESS`` runs ``python -m twinloop.adapt_train`` with
its own flags, reads the samples it writes and trains on them as it does on the
samples it makes itself: the Rust command keeps the training, the report and every
output, and Python only spreads the part that grows with the sample count (each
change's static tip-over) over a Ray cluster. Each sample's draw depends only on the
seed and its index, so the set equals the serial one, sample for sample.

    python -m twinloop.adapt_train --robot builtin:km20 --samples 10000 --seed 1 \\
        --ray ray://head:10001 --out samples.json

``--ray local`` starts a Ray on this machine (``--ray-cpus`` CPUs, default all).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, Sequence

from . import _native, distributed


def _samples_batch(robot, indices, threads=1, seed=1, mass_range=(0.05, 0.5), noise_deg=0.05):
    # A batch is a run of consecutive indices (map_batches cuts the job list in order).
    return _native.training_samples(robot, indices[0], indices[-1] + 1, seed=seed, mass_range=mass_range,
                                    noise_deg=noise_deg, threads=threads)


def training_set(robot: Any, samples: int, *, seed: int = 1, mass_range: Sequence[float] = (0.05, 0.5),
                 noise_deg: float = 0.05, **options) -> list[dict]:
    """Samples ``0..samples`` of ``adapt train``'s set on Ray, equal to
    ``twinloop.training_samples(robot, 0, samples, ...)``. ``options`` go to
    :func:`twinloop.distributed.map_batches` (batch_size, address, cpus_per_task, ...).
    """
    return distributed.map_batches(_samples_batch, robot, list(range(samples)), seed=seed,
                                   mass_range=tuple(mass_range), noise_deg=noise_deg, **options)


def _mass_range(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not LO,HI (kg)") from None
    return lo, hi


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m twinloop.adapt_train",
        description="Make twinloop adapt train's training set as Ray tasks and write it as JSON.")
    p.add_argument("--robot", required=True, help="builtin:NAME or a URDF/MJCF path")
    p.add_argument("--samples", type=int, required=True, help="random changes to draw")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--mass-range", type=_mass_range, default=(0.05, 0.5), metavar="LO,HI")
    p.add_argument("--noise", type=float, default=0.05, metavar="DEG", help="one-sigma noise on each fall angle")
    p.add_argument("--ray", required=True, metavar="ADDRESS",
                   help='a Ray cluster ("auto", "ray://host:10001") or "local" for a Ray started here')
    p.add_argument("--ray-cpus", type=int, default=None, metavar="N", help="CPUs of a local Ray (default: all)")
    p.add_argument("--batch-size", type=int, default=0, metavar="N",
                   help="samples per Ray task (default: four tasks per CPU of the cluster)")
    p.add_argument("--out", required=True, metavar="FILE.json", help="the samples, a JSON list (- for stdout)")
    a = p.parse_args(argv)
    if a.samples < 1:
        p.error(f"--samples: must be at least 1, got {a.samples}")
    ray = distributed._ray()
    if not ray.is_initialized():
        if a.ray == "local":
            ray.init(num_cpus=a.ray_cpus, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=a.ray, include_dashboard=False, log_to_driver=False)
    cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
    batch = a.batch_size or max(1, math.ceil(a.samples / (4 * cpus)))
    robot = _native.load(a.robot)
    samples = training_set(robot, a.samples, seed=a.seed, mass_range=a.mass_range, noise_deg=a.noise,
                           batch_size=batch)
    text = json.dumps(samples)
    if a.out == "-":
        sys.stdout.write(text)
    else:
        with open(a.out, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

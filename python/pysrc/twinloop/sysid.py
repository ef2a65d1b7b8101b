"""Black-box identification on arrays: ARX and state-space models (seed 002's route).

``arx(u, y, na, nb, nk)`` and ``ss(u, y, order, method)`` take samples as (N, nu) and
(N, ny) arrays and return the fields of ``twinloop identify arx/ss --json``.
"""

from ._native import sysid_arx as arx
from ._native import sysid_ss as ss

__all__ = ["arx", "ss"]

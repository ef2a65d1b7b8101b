"""twinloop.sysid on arrays: recovery of a known system."""

import numpy as np
import pytest

import twinloop as tl


def first_order(n, noise, seed=0):
    """y[k] = 0.5 y[k-1] + 0.3 u[k-1] (+ output noise)."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 1))
    y = np.zeros((n, 1))
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1]
    return u, y + noise * rng.normal(size=y.shape)


def test_arx_recovers_a_known_system():
    u, y = first_order(500, 0.0)
    # The record as it is (the CLI's --no-detrend): the relation holds exactly.
    r = tl.sysid.arx(u, y, na=1, nb=1, nk=1, sample_time=0.01, detrend=False)
    assert r["data"]["offsets"] is None
    assert r["kind"] == "arx" and r["orders"] == {"na": 1, "nb": 1, "nk": 1}
    # MATLAB's sign convention: A(q) = 1 + a1 q^-1.
    assert r["A"][0][0][0] == pytest.approx(-0.5, abs=1e-12)
    assert r["B"][0][0][0] == pytest.approx(0.3, abs=1e-12)
    assert r["fit_percent"]["simulation"][0] == pytest.approx(100.0, abs=1e-9)


def test_state_space_finds_the_pole():
    u, y = first_order(2000, 0.01)
    r = tl.sysid.ss(u, y, order=1, method="pem")
    pole = np.linalg.eigvals(np.array(r["A"]))
    assert abs(pole[0] - 0.5) < 0.01
    assert r["fit_percent"]["prediction"][0] > 95


def test_sysid_argument_errors():
    u, y = first_order(50, 0.0)
    with pytest.raises(ValueError, match="^y:"):
        tl.sysid.arx(u, y[:-1])
    with pytest.raises(ValueError, match="^method:"):
        tl.sysid.ss(u, y, order=1, method="magic")
    with pytest.raises(ValueError, match="^u_val, y_val"):
        tl.sysid.arx(u, y, u_val=u)


def test_detrending_removes_the_estimation_means_as_the_cli_does():
    u, y = first_order(2000, 0.0)
    # An operating point the system is in equilibrium at: u = 1, y = 0.3 / (1 - 0.5).
    r = tl.sysid.arx(u + 1.0, y + 0.6, na=1, nb=1, nk=1)
    offsets = r["data"]["offsets"]
    assert offsets["inputs"] == pytest.approx([np.mean(u) + 1.0], abs=1e-12)
    assert offsets["outputs"] == pytest.approx([np.mean(y) + 0.6], abs=1e-12)
    # The dynamics about it are the system's (exact but for the record's two ends).
    assert r["A"][0][0][0] == pytest.approx(-0.5, abs=1e-3)
    assert r["B"][0][0][0] == pytest.approx(0.3, abs=1e-3)

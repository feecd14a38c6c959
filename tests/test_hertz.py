"""Hertz line contact: a frictionless elastic half-cylinder pressed on a rigid plane.

Reference (Johnson, Contact Mechanics, eq. 4.43, plane strain, rigid flat): E* = E/(1 - nu^2),
a = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi a), p(x) = p0 sqrt(1 - x^2/a^2).
"""

import csv

import numpy as np
import pytest

from dolfinx_fretting.analytic import hertz_line_contact, hertz_pressure
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

E, NU, R = 115000.0, 0.342, 6.0
E_STAR = E / (1 - NU**2)


def _frictionless(tmp_path, P, h, name):
    scene = load_scene("hertz", [
        "contact.mu=0.0", f"loading.normal_force={P}", "loading.tangential_force=0.0",
        "loading.normal_increments=1", f"geometry.contact_mesh_size={h}",
        "output.xdmf=false", "output.plots=false",
    ])
    out = tmp_path / name
    summary = run_scene(scene, out, quiet=True)
    with open(out / "contact_profiles.csv") as f:
        rows = [r for r in csv.DictReader(f) if int(r["increment"]) == summary["increments"]]
    x = np.array([float(r["position"]) for r in rows])
    p = np.array([float(r["pressure"]) for r in rows])
    return summary, x, p


@pytest.mark.parametrize("P", [100.0, 199.24])
def test_hertz_peak_pressure_and_half_width(tmp_path, P):
    h = 0.01
    summary, x, p = _frictionless(tmp_path, P, h, f"P{P}")
    a, p0 = hertz_line_contact(P, R, E_STAR)
    assert summary["converged"]
    # Force control reaches the prescribed load to the solver's force tolerance (1e-8 relative).
    assert summary["normal_force"] == pytest.approx(P, rel=1e-7)
    # 1 %: the nodal pressure r_n / tributary length is second-order accurate in h/a (here h/a < 0.1,
    # so the discretisation error is a few 0.1 %); the finite body (R = 6 mm vs a ~ 0.1 mm) changes the
    # approach, not the pressure, to first order.
    assert summary["max_pressure"] == pytest.approx(p0, rel=0.01)
    # The true edge lies between the last loaded node and the first unloaded one: within one element.
    assert abs(summary["contact_width"] / 2 - a) <= h
    # The contact is centred on the lowest point (symmetric problem).
    loaded = x[p > 0]
    assert abs(loaded.max() + loaded.min()) <= h * 1.01


def test_hertz_error_falls_with_refinement(tmp_path):
    P = 199.24
    errors = []
    for h in (0.04, 0.02, 0.01):
        _, x, p = _frictionless(tmp_path, P, h, f"h{h}")
        ref = hertz_pressure(x, P, R, E_STAR)
        a, p0 = hertz_line_contact(P, R, E_STAR)
        inside = np.abs(x) <= 1.2 * a
        errors.append(np.sqrt(np.mean((p[inside] - ref[inside]) ** 2)) / p0)
    # Each halving of the contact element size must reduce the RMS pressure error.
    assert errors[1] < errors[0] and errors[2] < errors[1], errors

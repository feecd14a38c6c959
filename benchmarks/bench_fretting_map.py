"""A fretting map of the ``sphere-flat`` scene at one normal load: the partial-to-gross slip transition amplitude
against Mindlin's closed form, and the cost of a map point.

Mindlin's ``delta_t = 3 mu P / (16 G* a)`` (identical bodies, 1/G* = sum (2 - nu_i)/G_i) is the displacement of
remote points of two half-spaces at the onset of sliding. The scene imposes the flat's displacement on finite
bodies, so its transition amplitude adds the bodies' bulk compliance C_b times mu P. Like with like: C_b is
measured on the map's own partial-slip points as ``(delta* - delta_M(Q*)) / Q*`` (delta_M: Mindlin's loading curve,
``analytic.mindlin_tangential_displacement``; the first quarter cycle is the virgin curve up to (delta*, Q*)), so
the prediction ``delta_t + C_b mu P`` tests the shape of Mindlin's curve up to sliding, not the bulk's stiffness.

The map's own correction (``contact_amplitude = delta* - C_b Q*``, C_b its ``bulk_compliance``: the loop's slope at
its reversals less Mindlin's stuck contact compliance ``1 / (8 G* a)``) is tabulated beside it: the reversal slope
less the curve's C_b is the FE model's stuck contact compliance, compared with Mindlin's; the picture is drawn
against the contact amplitude (``axis="contact"``), on which Mindlin's delta_t is the like-for-like curve.

Usage::

    .venv/bin/python benchmarks/bench_fretting_map.py [--amplitudes 0.002,0.004,...] [--work DIR]

Writes ``benchmarks/results/fretting_map_sphere.md`` (and the map's ``map.png`` beside it).
"""

from __future__ import annotations

import argparse
import datetime
import platform
import shlex
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

from mpi4py import MPI

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # this checkout's package, not an installed one
sys.path.insert(0, str(HERE))
from _machine import cpu_model  # noqa: E402
from dolfinx_fretting.analytic import (hertz_sphere, mindlin_shear_modulus,  # noqa: E402
                                       mindlin_tangential_displacement)
from dolfinx_fretting.fretting_map import (mindlin_contact_compliance,  # noqa: E402
                                           mindlin_transition_amplitude, parse_values, plan_map, run_map,
                                           transition_brackets)

#: No wear (the transition of the unworn contact), two cycles of 16 increments: the stick classifier reads the
#: virgin curve and the closed loop.
OVERRIDES = ["wear.law='none'", "wear.k=none", "loading.increments_per_cycle=16"]
NORMAL = 100.0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--amplitudes", default="0.002,0.003,0.004,0.005,0.006,0.007,0.008,0.01")
    parser.add_argument("--work", default=None)
    args = parser.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="bench_map_"))
    amplitudes = parse_values(args.amplitudes, "--amplitudes")
    plan = plan_map("sphere-flat", [NORMAL], amplitudes, cycles=2, overrides=OVERRIDES)
    rows = run_map(plan, work, MPI.COMM_WORLD, overwrite=True, axis="contact")
    scene = plan[0].scene
    m, mu, P = scene.material, scene.contact.mu, NORMAL
    g_star = mindlin_shear_modulus(m.E, m.nu, m.E, m.nu)
    a = hertz_sphere(P, scene.geometry.radius, scene.contact_modulus)[0]
    delta_t = mindlin_transition_amplitude(scene, P)
    compliances = []
    contact = mindlin_contact_compliance(scene, P)
    lines = ["| delta* (um) | delta_c (um) | regime (energy) | regime (stick) | A (last) | Q*/(mu P) | "
             "C_b curve (um/N) | reversal slope (um/N) | C_b slope (um/N) | wall (s) |",
             "| ---: | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        c_b = float("nan")
        if r["converged"] and r["regime_by_stick"] == "partial":
            q_star = r["force_ratio_last"] * mu * P
            c_b = (r["amplitude"] - mindlin_tangential_displacement(q_star, mu, P, a, g_star)) / q_star
            compliances.append(c_b)
        lines.append(f"| {1e3 * r['amplitude']:g} | {1e3 * r['contact_amplitude']:.4g} | {r['regime']} | "
                     f"{r['regime_by_stick']} | {r['energy_ratio_last']:.3g} | {r['force_ratio_last']:.4g} | "
                     f"{1e3 * c_b:.4g} | {1e3 * r['reversal_compliance']:.5g} | {1e3 * r['bulk_compliance']:.4g} | "
                     f"{r['wall_time_s']:.1f} |")
    bracket = transition_brackets(rows, "regime_by_stick").get(P)
    bracket_energy = transition_brackets(rows, "regime").get(P)
    c_b = statistics.mean(compliances) if compliances else float("nan")
    slopes = [r["reversal_compliance"] for r in rows
              if r["converged"] and r["reversal_compliance"] == r["reversal_compliance"]]  # (not NaN)
    slope = statistics.median(slopes) if slopes else float("nan")
    bracket_contact = transition_brackets(rows, "regime_by_stick", "contact_amplitude").get(P)
    predicted = delta_t + c_b * mu * P
    walls = [r["wall_time_s"] for r in rows[1:]]
    command = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fretting_map.py " + " ".join(
        shlex.quote(a) for a in sys.argv[1:])
    text = [f"# Fretting map of sphere-flat at P = {P:g} N: transition against Mindlin", "",
            f"Command: `{command}` ({datetime.date.today()}, {cpu_model()}, Python {platform.python_version()}; "
            f"{MPI.COMM_WORLD.size} rank). Scene: sphere-flat, {' '.join(OVERRIDES)}, 2 cycles; the scene's mesh "
            "(a/4 cubes).", "", *lines, "",
            f"- Mindlin delta_t = 3 mu P / (16 G* a) = {1e3 * delta_t:.4g} um (a = {1e3 * a:.4g} um, G* = {g_star:.5g} "
            "MPa): the contact's own displacement.",
            f"- Bulk compliance of the model, from the partial-slip points ((delta* - delta_M(Q*)) / Q*): C_b = "
            f"{1e3 * c_b:.4g} um/N (spread {1e3 * (max(compliances) - min(compliances)) if compliances else 0:.2g} "
            "um/N over the points: a constant C_b means Mindlin's curve holds below sliding).",
            f"- Predicted imposed transition delta_t + C_b mu P = {1e3 * predicted:.4g} um; the map brackets it (stick "
            f"zone) in {'%g < delta_t < %g um' % (1e3 * bracket[0], 1e3 * bracket[1]) if bracket else 'none'}"
            f"; by the energy ratio (A_t = 0.2) in "
            f"{'%g .. %g um' % (1e3 * bracket_energy[0], 1e3 * bracket_energy[1]) if bracket_energy else 'none'}.",
            f"- The loop's slope at its reversals (median over the points, {len(slopes)} read): "
            f"{1e3 * slope:.5g} um/N; "
            f"less the curve's C_b, the FE model's stuck contact compliance {1e3 * (slope - c_b):.5g} um/N against "
            f"Mindlin's 1/(8 G* a) = (2 - nu)/(4 G a) = {1e3 * contact:.5g} um/N "
            f"({100 * ((slope - c_b) / contact - 1):+.2f} %). The map's C_b (slope - Mindlin's): "
            f"{1e3 * (slope - contact):.4g} um/N against the curve's {1e3 * c_b:.4g} um/N.",
            f"- In contact terms (delta_c = delta* - C_b Q*, the map's C_b), the stick zone brackets the transition in "
            + ('%.4g < delta_t < %.4g um' % (1e3 * bracket_contact[0], 1e3 * bracket_contact[1])
               if bracket_contact else 'none') +
            f": Mindlin's {1e3 * delta_t:.4g} um. The picture is drawn against delta_c.",
            f"- Cost per map point (after the first, which loads the kernels): median "
            f"{statistics.median(walls) if walls else float('nan'):.1f} s; first {rows[0]['wall_time_s']:.1f} s.", ""]
    out = HERE / "results" / "fretting_map_sphere.md"
    out.write_text("\n".join(text))
    shutil.copy(work / "map.png", HERE / "results" / "fretting_map_sphere.png")
    print("\n".join(text))


if __name__ == "__main__":
    main()

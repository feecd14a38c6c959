"""Fretting maps: a grid of (normal load, displacement amplitude) runs of a scene, each classified into partial,
mixed or gross slip.

``dolfinx-fretting map SCENE --normal P1,P2 --amplitude d1,d2 --out DIR`` runs the scene once per grid point through
the scene runner (:func:`dolfinx_fretting.simulation.run_scene`, the trade study's quiet outputs
:data:`dolfinx_fretting.study.QUIET_OUTPUT`), with ``loading.normal_force = P`` and the obstacle's tangential
displacement ``loading.tangential_displacement = d`` (cyclic, the scene's waveform), one folder per point under
``DIR/runs/``, and classifies each run from its ``cycles.csv`` by two independent criteria:

* **the energy ratio** (Fouvry, Kapsa & Vincent, *Analysis of sliding behaviour for fretting loadings:
  determination of transition criteria*, Wear 185 (1995) 35-46): ``A = E_d / (4 delta* Q*)`` of a cycle, E_d the
  energy it dissipated, delta* its displacement amplitude and Q* its tangential force amplitude (half the ranges of
  ``displacement_max/min`` and ``tangential_force_max/min``). Gross slip when ``A >= A_t``; Fouvry's transition for
  a sphere on a plane is ``A_t = 0.2`` (:data:`GROSS_SLIP_ENERGY_RATIO`): Mindlin's loop at the onset of sliding
  dissipates ``4 mu P (delta_t - 0.8 delta_t)``. delta* is the *imposed* displacement, which holds the bodies' bulk
  compliance besides the contact's: a compliant set-up lowers A at the transition below 0.2 (Fouvry et al. correct
  delta* for the rig's compliance; here it is an option, ``threshold``);
* **the stick zone**: a cycle is gross slip when some increment of it has every loaded contact sliding (the
  ``regime`` column of ``cycles.csv``, :func:`dolfinx_fretting.output.cycle_row`), partial slip otherwise.

A run is **mixed** when its cycles' regimes differ (Vincent, Berthier & Godet, *Testing methods in fretting
fatigue: a critical appraisal*, ASTM STP 1159 (1992) 33-48: the first cycles in gross slip, then partial, or the
reverse, as friction or wear changes the contact). The first cycle starts from Q = 0 on the virgin loading curve,
not a closed loop, so its energy ratio is lower than the steady cycles' and Fouvry's criterion does not apply to
it: the energy classifier reads the cycles from the second on (the first alone in a one-cycle run); the stick
classifier reads every cycle (the virgin curve reaches full sliding at the same displacement as the closed loop,
Masing's rule).

For the sphere (``geometry.kind = "sphere"``) the map also gives Mindlin's transition amplitude
``delta_t = 3 mu P / (16 G* a)`` (:func:`mindlin_transition_amplitude`, identical bodies or a rigid flat) as the
contact's own share; the imposed displacement at the transition adds the bulk compliance times mu P.

**The contact's own slip amplitude** (``contact_amplitude``, a sphere): a rig's measured delta* holds the
machine's and the bodies' bulk compliance C_b besides the contact's, and tribologists plot maps against the
contact's amplitude ``delta_c = delta* - C_b Q*``. C_b is read from the loop itself, as on a rig: at a load
reversal the whole contact sticks again (Mindlin & Deresiewicz: the slip annulus of the unloading branch grows
from zero width), so the loop's slope there, ``dDelta/dQ`` as the force change goes to 0
(:func:`reversal_compliance`), is purely elastic: the bulk's compliance plus the stuck contact's,
``1 / (8 G* a) = (2 - nu) / (4 G a)`` for identical bodies (Johnson, *Contact Mechanics*, §7.2: the slope of
eq. 7.42 at Q = 0, both bodies' compliances; :func:`mindlin_contact_compliance`). So
``C_b = slope - 1 / (8 G* a)``: only the bulk is removed, not the contact's tangential compliance, which is
part of the contact's own displacement (removing the whole slope would leave the loop's opening at Q = 0,
2 (1/2)^(2/3) - 1 = 0.26 delta_t at the transition by Masing's rule, not the slip amplitude). The slope is
the chords from the reversal over its first two increments, extrapolated linearly to a zero force change
(Mindlin's unloading branch has chord slopes ``C (1 + u/6 + 2 u^2/27 + ...)``, u the force change over 2 mu P:
the extrapolation leaves ``2 u1 u2 / 27``).
The bulk compliance does not depend on the amplitude: each point's contact amplitude uses the median of the
measured C_b of the converged points at its normal load (a loop that slides within two increments of its
reversal gives none itself). Why not the FE model's far-field compliance: the bulk and the contact's shares of a
finite body's displacement separate only against the half-space's, which is Mindlin's closed form either way;
the loop's slope is what a rig measures, so map and rig are corrected alike. On an FE model the slope holds the
mesh's error on the contact's stiffness too (``sphere-flat`` at a/4, 16 increments a cycle: 1/(8 G* a)
-1.9 % .. +3.1 % over the amplitudes, of the size of its bulk's share: benchmarks/results/fretting_map_sphere.md),
so there delta_c is good to about 2 % of delta_t; the correction matters where the set-up is compliant (a
rig's compliance is often several times the contact's). A 2D line contact has no
contact compliance apart from the bodies' size (a half-plane's displacement grows with the log of the
distance): its ``contact_amplitude`` and ``bulk_compliance`` stay blank; its ``reversal_compliance`` is given.

Outputs in ``DIR``: ``map.csv`` (:data:`MAP_FIELDS`), ``map.md`` and ``map.png`` (amplitude against normal load, one
marker per regime; the transition bracketed by the grid and, for a sphere, Mindlin's curve; the abscissa the
imposed amplitude or, ``axis="contact"``, the contact's own). A point whose run fails
stays in the table with ``converged = False`` and its message; the map goes on.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from .analytic import hertz_sphere, mindlin_shear_modulus
from .contact_output import read_table
from .outdir import OutputFolderError, ensure_writable_folder
from .scenes import Scene, SceneError, load_scene
from .study import QUIET_OUTPUT, check_on_rank0, run_point
from .tables import cell_text, read_rows, write_table
from .units import Units

__all__ = ["GROSS_SLIP_ENERGY_RATIO", "MAP_FIELDS", "MAP_FILES", "MAP_AXES", "REGIMES", "MapPoint", "parse_values",
           "energy_ratios", "regime_of_cycles", "classify_cycles", "mindlin_transition_amplitude",
           "mindlin_contact_compliance", "reversal_compliance", "contact_amplitudes", "check_axis",
           "transition_brackets", "plan_map", "check_map_folder", "run_map", "write_map_table", "read_map_csv",
           "format_markdown", "plot_map"]

#: Fouvry's energy ratio at the partial-to-gross slip transition of a sphere on a plane (Fouvry, Kapsa & Vincent,
#: Wear 185 (1995) 35-46): Mindlin's loop at the onset of sliding, E_d = 4 mu P (delta_t - 0.8 delta_t).
GROSS_SLIP_ENERGY_RATIO = 0.2
#: The regimes a run is classified into (``"open"``: no contact loaded in any cycle).
REGIMES = ("partial", "mixed", "gross", "open")
#: Columns of ``map.csv``: the point (P, the imposed delta*, the contact's own amplitude delta* - C_b Q*), the loop's
#: slope at its reversals and the bulk compliance C_b it gives (mm/N; see the module doc), its classification by
#: the energy ratio (``regime``) and by the stick zone (``regime_by_stick``), whether they agree, the last cycle's
#: Q* and Q*/(mu P), the cycles run, the run's outcome.
MAP_FIELDS = ["normal", "amplitude", "contact_amplitude", "reversal_compliance", "bulk_compliance",
              "energy_ratio_first", "energy_ratio_last", "regime", "regime_by_stick", "regimes_agree",
              "force_amplitude_last", "force_ratio_last", "cycles", "converged", "error", "wall_time_s", "folder"]
#: The picture's abscissa: the imposed amplitude (``amplitude``) or the contact's own (``contact_amplitude``).
MAP_AXES = {"imposed": "amplitude", "contact": "contact_amplitude"}
#: Files a map writes into its folder (besides ``runs/``).
MAP_FILES = ("map.csv", "map.md", "map.png")
#: What the map needs of every run besides the study's quiet outputs: no contact profiles (the classification
#: reads ``cycles.csv`` only).
MAP_OUTPUT = [*QUIET_OUTPUT, "output.contact_profiles=false"]
#: ``cycles.csv``'s stick regime names (output.cycle_row) -> the map's.
_STICK_REGIMES = {"partial_slip": "partial", "gross_slip": "gross", "open": "open"}


@dataclass
class MapPoint:
    """One run of the map.

    Attributes:
        normal: Normal load P (``loading.normal_force``: N/mm in 2D, N in 3D).
        amplitude: Displacement amplitude delta* (``loading.tangential_displacement``, mm).
        label: Its folder's name under ``runs/``.
        overrides: ``section.key=value`` overrides on the scene, in order.
        scene: The validated scene of this run.
    """

    normal: float
    amplitude: float
    label: str
    overrides: list[str]
    scene: Scene | None = field(default=None, repr=False)


# Classification (pure) -----------------------------------------------------------------------------------------
def energy_ratios(cycles: dict[str, np.ndarray]) -> np.ndarray:
    """Fouvry's energy ratio ``A = E_d / (4 delta* Q*)`` of each row of a ``cycles.csv`` table.

    Args:
        cycles: Columns ``dissipated_energy``, ``tangential_force_max``, ``tangential_force_min``,
            ``displacement_max``, ``displacement_min`` (``cycles.csv``, :func:`~dolfinx_fretting.output.cycle_row`).

    Returns:
        A per cycle; 0 where the loop has no width or height (nothing slid).
    """
    energy = np.asarray(cycles["dissipated_energy"], dtype=float)
    force = 0.5 * (np.asarray(cycles["tangential_force_max"], dtype=float)
                   - np.asarray(cycles["tangential_force_min"], dtype=float))
    displacement = 0.5 * (np.asarray(cycles["displacement_max"], dtype=float)
                          - np.asarray(cycles["displacement_min"], dtype=float))
    rectangle = 4.0 * force * displacement
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(rectangle > 0, energy / np.where(rectangle > 0, rectangle, 1.0), 0.0)


def regime_of_cycles(regimes: Sequence[str]) -> str:
    """A run's regime from its cycles' (``"partial"``, ``"gross"``, ``"open"``): theirs when they all agree,
    ``"mixed"`` when partial and gross slip both occur (Vincent, Berthier & Godet 1992), the loaded ones' when some
    cycles are open; ``"open"`` when none is loaded (or no cycle)."""
    loaded = [r for r in regimes if r != "open"]
    if not loaded:
        return "open"
    kinds = set(loaded)
    return loaded[0] if len(kinds) == 1 else "mixed"


def classify_cycles(cycles: dict[str, np.ndarray], threshold: float = GROSS_SLIP_ENERGY_RATIO) -> dict[str, Any]:
    """Classify a run from its ``cycles.csv`` by the energy ratio and by the stick zone (see the module doc).

    Args:
        cycles: The table's columns (:func:`energy_ratios`' and ``regime``, ``min_stick``).
        threshold: The energy ratio A_t at and above which a cycle is gross slip (> 0 and < 1).

    Returns:
        ``energy_ratio_first`` and ``energy_ratio_last`` (A of the first and last cycles the energy classifier
        reads: from the second cycle on when there are several), ``regime`` (by the energy ratio),
        ``regime_by_stick``, ``regimes_agree``, ``cycles`` (rows of the table), ``energy_ratios`` (every cycle's A)
        and the per-cycle regimes ``cycle_regimes`` and ``cycle_regimes_by_stick``.

    Raises:
        ValueError: ``threshold`` outside (0, 1).
    """
    if not 0.0 < threshold < 1.0:
        raise ValueError(f"energy ratio threshold = {threshold!r}: allowed a number > 0 and < 1 (Fouvry's A_t = "
                         f"{GROSS_SLIP_ENERGY_RATIO} for a sphere on a plane)")
    ratios = energy_ratios(cycles) if cycles else np.zeros(0)
    n = int(ratios.size)
    stick = [_STICK_REGIMES.get(str(r), "open") for r in np.atleast_1d(cycles.get("regime", []))][:n]
    loaded = [r != "open" for r in stick] if stick else [True] * n
    by_energy = [("gross" if a >= threshold else "partial") if on else "open" for a, on in zip(ratios, loaded)]
    closed = slice(1, None) if n > 1 else slice(0, None)  # the first cycle starts on the virgin curve
    read = ratios[closed]
    return {"energy_ratio_first": float(read[0]) if read.size else math.nan,
            "energy_ratio_last": float(read[-1]) if read.size else math.nan,
            "regime": regime_of_cycles(by_energy[closed]) if n else "",
            "regime_by_stick": regime_of_cycles(stick) if stick else "",
            "regimes_agree": bool(n) and regime_of_cycles(by_energy[closed]) == regime_of_cycles(stick),
            "cycles": n, "energy_ratios": ratios, "cycle_regimes": by_energy, "cycle_regimes_by_stick": stick}


def _mindlin_sphere(scene: Scene, normal: float) -> tuple[float, float] | None:
    """(G*, a) of a sphere scene at ``normal`` (None for another geometry)."""
    if scene.geometry.kind != "sphere":
        return None
    material = scene.material
    two_bodies = scene.contact.obstacle == "elastic_flat"
    g_star = mindlin_shear_modulus(material.E, material.nu, material.E if two_bodies else None,
                                   material.nu if two_bodies else None)
    return g_star, hertz_sphere(normal, scene.geometry.radius, scene.contact_modulus)[0]


def mindlin_contact_compliance(scene: Scene, normal: float) -> float | None:
    """The stuck contact's tangential compliance of a sphere, ``1 / (8 G* a)`` (mm/N): ``(2 - nu) / (4 G a)`` for
    identical bodies (Johnson, *Contact Mechanics*, §7.2: each body's displacement under the stuck circle's
    traction ``Q / (2 pi a sqrt(a^2 - r^2))`` is ``(2 - nu) Q / (8 G a)``; the slope of eq. 7.42 at Q = 0),
    G* of :func:`~dolfinx_fretting.analytic.mindlin_shear_modulus` (the flat's term dropped on a rigid flat), a the
    Hertz radius. None when the scene is not a sphere (a line contact has none apart from the bodies' size)."""
    sphere = _mindlin_sphere(scene, normal)
    return None if sphere is None else 1.0 / (8.0 * sphere[0] * sphere[1])


def mindlin_transition_amplitude(scene: Scene, normal: float) -> float | None:
    """Mindlin's partial-to-gross slip transition amplitude ``delta_t = 3 mu P / (16 G* a)`` of a sphere (Johnson,
    *Contact Mechanics*, eq. 7.42 at Q = mu P), a the Hertz radius (:func:`~dolfinx_fretting.analytic.hertz_sphere`)
    and ``1/G* = (2 - nu1)/G1 + (2 - nu2)/G2`` for identical bodies (the sphere's second term dropped on a rigid
    flat, :func:`~dolfinx_fretting.analytic.mindlin_shear_modulus`). The displacement is the contact's own (of
    remote points of two half-spaces): the scene's imposed displacement adds its bodies' bulk compliance.

    Returns:
        delta_t (mm), or None when the scene is not a sphere (a 2D contact's displacement depends on the bodies'
        size: gross slip starts when Q reaches mu P).
    """
    sphere = _mindlin_sphere(scene, normal)
    if sphere is None:
        return None
    (g_star, a), mu = sphere, scene.contact.mu
    return 3.0 * mu * normal / (16.0 * g_star * a)


def reversal_compliance(displacement: np.ndarray, force: np.ndarray) -> float:
    """The loop's slope ``dDelta/dQ`` at its load reversals, as the force change goes to 0 (mm/N): the elastic
    compliance of the bodies and the stuck contact (see the module doc).

    At each reversal (the cycle's largest and smallest displacement), the chords to the next two increments,
    ``s_k = (delta_k - delta_0) / (Q_k - Q_0)`` over force changes ``c_1 < c_2``, extrapolated linearly to
    ``c = 0``: ``(s_1 c_2 - s_2 c_1) / (c_2 - c_1)``. A reversal is left out when it has no two increments after it
    in the cycle, when a chord's force change is 0 or does not grow, or when the second chord reaches the
    cycle's opposite force extreme (to within 1 % of the range: the loop slid, the chord is not elastic).

    Args:
        displacement: The cycle's displacement at each increment's end (the imposed one).
        force: Its tangential force Q at each increment's end.

    Returns:
        The mean over the reversals read, NaN when none is (a slope not > 0 counts as none).
    """
    delta = np.asarray(displacement, dtype=float)
    force = np.asarray(force, dtype=float)
    if delta.size == 0 or force.size == 0:
        return math.nan
    span = float(force.max() - force.min())
    slopes = []
    # after the largest displacement the force heads for its smallest value, and the other way round
    for turn, opposite in ((int(np.argmax(delta)), float(force.min())), (int(np.argmin(delta)), float(force.max()))):
        if turn + 2 >= delta.size or span <= 0:
            continue
        changes = np.abs(force[turn + 1:turn + 3] - force[turn])
        if not (0 < changes[0] < changes[1]) or abs(force[turn + 2] - opposite) <= 0.01 * span:
            continue
        chords = (delta[turn + 1:turn + 3] - delta[turn]) / (force[turn + 1:turn + 3] - force[turn])
        slope = (chords[0] * changes[1] - chords[1] * changes[0]) / (changes[1] - changes[0])
        if math.isfinite(slope) and slope > 0:
            slopes.append(float(slope))
    return float(np.mean(slopes)) if slopes else math.nan


def contact_amplitudes(rows: Sequence[dict[str, Any]], plan: Sequence[MapPoint]) -> None:
    """Fill each row's ``bulk_compliance`` (its reversal slope less Mindlin's stuck contact compliance,
    :func:`mindlin_contact_compliance`) and ``contact_amplitude`` (``delta* - C_b Q*``, C_b the median of the
    bulk compliances measured at its normal load: the bulk's does not depend on the amplitude), in place. Blank
    (NaN) for a scene that is not a sphere, a failed point, or a load where no point gave a slope."""
    for row, point in zip(rows, plan):
        contact = mindlin_contact_compliance(point.scene, point.normal)
        row["bulk_compliance"] = (float(row.get("reversal_compliance", math.nan)) - contact
                                  if contact is not None and row.get("converged") else math.nan)
    for normal in {float(r["normal"]) for r in rows}:
        same = [r for r in rows if float(r["normal"]) == normal]
        measured = [r["bulk_compliance"] for r in same if math.isfinite(r["bulk_compliance"])]
        bulk = float(np.median(measured)) if measured else math.nan
        for r in same:
            r["contact_amplitude"] = (float(r["amplitude"]) - bulk * float(r["force_amplitude_last"])
                                      if r.get("converged") else math.nan)


def transition_brackets(rows: Sequence[dict[str, Any]], column: str = "regime",
                        amplitude: str = "amplitude") -> dict[float, tuple[float, float]]:
    """The transition amplitude bracketed by the grid, per normal load: (largest amplitude in partial slip, smallest
    in gross slip) when every partial amplitude lies below every gross one (converged points, ``column`` the
    classifier's; ``amplitude`` the column read: the imposed ``amplitude`` or the ``contact_amplitude``); loads
    without both regimes, or with them interleaved, are left out (and points without the amplitude)."""
    out: dict[float, tuple[float, float]] = {}
    for normal in sorted({float(r["normal"]) for r in rows}):
        points = [r for r in rows if float(r["normal"]) == normal and r.get("converged")
                  and math.isfinite(float(r.get(amplitude, math.nan)))]
        partial = [float(r[amplitude]) for r in points if r.get(column) == "partial"]
        gross = [float(r[amplitude]) for r in points if r.get(column) == "gross"]
        if partial and gross and max(partial) < min(gross):
            out[normal] = (max(partial), min(gross))
    return out


# Planning --------------------------------------------------------------------------------------------------------
def parse_values(text: str, option: str) -> list[float]:
    """``"v1,v2,..."`` as distinct finite positive numbers, in the given order.

    Raises:
        SceneError: naming ``option``, the value and the allowed range.
    """
    values: list[float] = []
    for item in text.split(","):
        item = item.strip()
        try:
            value = float(item)
        except ValueError:
            raise SceneError(f"{option} {text!r}: {item!r} is not a number; allowed: comma-separated numbers > 0")
        if not (math.isfinite(value) and value > 0):
            raise SceneError(f"{option} {text!r}: {item} is out of range; allowed: finite numbers > 0")
        if value in values:
            raise SceneError(f"{option} {text!r}: {item} is given twice")
        values.append(value)
    return values


def _label(normal: float, amplitude: float) -> str:
    return f"P={normal:g}_d={amplitude:g}"


def plan_map(source: str | Path | dict, normals: Sequence[float], amplitudes: Sequence[float],
             cycles: int | None = None, overrides: Sequence[str] | None = None) -> list[MapPoint]:
    """Validate every run of a map before any starts.

    Each point is the scene with ``overrides`` (e.g. a coarser mesh), then ``loading.normal_force = P`` and
    ``loading.tangential_displacement = d`` (the scene's other normal and tangential controls removed), then
    ``loading.cycles`` and the quiet outputs (:data:`MAP_OUTPUT`) with the last cycle's increments in
    ``history.csv`` (``output.history_every`` = the cycles: the loop's reversals, :func:`reversal_compliance`).

    Args:
        source: The scene (built-in name, TOML file or dict).
        normals: Normal loads (``loading.normal_force``; > 0).
        amplitudes: Displacement amplitudes (``loading.tangential_displacement``, mm; > 0).
        cycles: Cycles of every run (>= 1); None: the scene's ``loading.cycles`` (which must then be >= 1).
        overrides: ``section.key=value`` overrides applied to the scene first.

    Returns:
        The points, normal loads outer, amplitudes inner.

    Raises:
        SceneError: An invalid scene or override, a point whose scene is refused (named), no values, or a run of
            no cycles.
    """
    if not normals or not amplitudes:
        raise SceneError("map: give at least one normal load (--normal) and one amplitude (--amplitude)")
    for name, values in (("--normal", normals), ("--amplitude", amplitudes)):
        bad = [v for v in values if not (math.isfinite(v) and v > 0)]
        if bad:
            raise SceneError(f"map {name} = {bad[0]!r}: allowed: finite numbers > 0")
    if cycles is not None and not (isinstance(cycles, int) and cycles >= 1):
        raise SceneError(f"map --cycles = {cycles!r}: allowed: an integer >= 1")
    base = list(overrides or [])
    scene = load_scene(source, base)
    if cycles is None:
        cycles = scene.loading.cycles
        if cycles < 1:
            raise SceneError(f"map: loading.cycles = {cycles} in {scene.name}: a map needs cyclic runs; give "
                             "--cycles N (N >= 1)")
    plan = []
    for normal in normals:
        for amplitude in amplitudes:
            over = base + [f"loading.normal_force={normal!r}", "loading.normal_displacement=none",
                           "loading.tangential_force=none", "loading.tangential_pressure=none",
                           f"loading.tangential_displacement={amplitude!r}", f"loading.cycles={cycles}"]
            try:
                point_scene = load_scene(source, over + MAP_OUTPUT + [f"output.history_every={cycles}"])
            except SceneError as exc:
                raise SceneError(f"map point P = {normal:g}, delta* = {amplitude:g}: {exc}") from None
            plan.append(MapPoint(normal, amplitude, _label(normal, amplitude), over, point_scene))
    return plan


def check_map_folder(out: str | Path, overwrite: bool = False) -> Path:
    """Check a map's output folder before any run: a writable folder (created), holding no map unless
    ``overwrite``. Serial.

    Raises:
        OutputFolderError: naming the folder and the reason.
    """
    folder = ensure_writable_folder(out)
    held = [name for name in MAP_FILES if (folder / name).exists()]
    if held and not overwrite:
        raise OutputFolderError(f"--out {folder} already holds a map ({', '.join(held)}); replace it with "
                                "--overwrite, or choose another folder")
    return folder


# Running ---------------------------------------------------------------------------------------------------------
def _point_row(point: MapPoint, folder: Path, failure: str, wall: float, threshold: float) -> dict[str, Any]:
    """The row of one point from its folder: ``summary.json``'s outcome and ``cycles.csv``'s classification."""
    try:
        summary = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        summary = {}
    converged = not failure and summary.get("converged") is True
    error = failure or ("" if converged else str(summary.get("error") or "no summary.json"))
    cycles = read_table(folder / "cycles.csv")
    row: dict[str, Any] = {"normal": point.normal, "amplitude": point.amplitude, "converged": converged,
                           "error": error, "wall_time_s": wall, "folder": str(Path("runs") / point.label),
                           "contact_amplitude": math.nan, "bulk_compliance": math.nan}
    if converged and cycles.get("cycle", np.zeros(0)).size:
        classes = classify_cycles(cycles, threshold)
        row.update({k: classes[k] for k in ("energy_ratio_first", "energy_ratio_last", "regime", "regime_by_stick",
                                            "regimes_agree", "cycles")})
        force = 0.5 * (cycles["tangential_force_max"][-1] - cycles["tangential_force_min"][-1])
        mu = point.scene.contact.mu
        row["force_amplitude_last"] = float(force)
        row["force_ratio_last"] = float(force / (mu * point.normal)) if mu > 0 else math.nan
        history = read_table(folder / "history.csv")
        last = history.get("cycle", np.zeros(0)) == cycles["cycle"][-1]
        row["reversal_compliance"] = (reversal_compliance(history["tangential_displacement"][last],
                                                          history["tangential_force"][last])
                                      if last.any() else math.nan)
    else:  # a failed point: no regime (its completed cycles may be on disk; a map point is all or nothing)
        row.update(energy_ratio_first=math.nan, energy_ratio_last=math.nan, regime="failed", regime_by_stick="failed",
                   regimes_agree=False, force_amplitude_last=math.nan, force_ratio_last=math.nan,
                   reversal_compliance=math.nan, cycles=int(cycles.get("cycle", np.zeros(0)).size))
        if converged:
            row.update(converged=False, error="no cycle in cycles.csv")
    return row


def check_axis(plan: Sequence[MapPoint], axis: str) -> None:
    """Refuse a picture's abscissa the map cannot draw: ``axis`` not one of :data:`MAP_AXES`, or ``"contact"`` for
    a scene that is not a sphere (no contact compliance apart from the bodies' size: no contact amplitude).

    Raises:
        SceneError: naming the option, the value and what is allowed.
    """
    if axis not in MAP_AXES:
        raise SceneError(f"map --axis = {axis!r}: allowed {', '.join(MAP_AXES)}")
    if axis == "contact" and plan and plan[0].scene.geometry.kind != "sphere":
        raise SceneError(f"map --axis = 'contact': the contact's own amplitude needs Mindlin's contact compliance, "
                         f"a sphere (geometry.kind = 'sphere'); {plan[0].scene.name} has geometry.kind = "
                         f"{plan[0].scene.geometry.kind!r}: allowed --axis imposed")


def run_map(plan: Sequence[MapPoint], out: str | Path, comm=None, quiet: bool = False,
            threshold: float = GROSS_SLIP_ENERGY_RATIO, overwrite: bool = False,
            ignore_size: bool = False, axis: str = "imposed") -> list[dict[str, Any]]:
    """Run every point of ``plan``, classify it and write ``map.csv``, ``map.md`` and ``map.png``.

    Collective: every rank runs every scene; files are written and rows built on rank 0 and broadcast. A point
    whose run fails (whatever the exception: an increment's, PETSc's or MUMPS's, a check that needs the mesh, a
    bug) is kept with ``converged = False``, ``regime = "failed"`` and its message; the map goes on. SIGINT or
    SIGTERM during a run (:class:`~dolfinx_fretting.simulation.RunInterrupted`) stops the map.

    Args:
        plan: From :func:`plan_map`.
        out: Output folder (the runs go to ``out/runs/<label>``).
        comm: Communicator (default ``MPI.COMM_WORLD``).
        quiet: Print nothing.
        threshold: Energy ratio A_t of the gross-slip transition (:data:`GROSS_SLIP_ENERGY_RATIO`).
        overwrite: Replace the map ``out`` holds (its runs are rerun in place).
        ignore_size: Run each scene even if its size estimate exceeds the memory available.
        axis: The picture's abscissa (:data:`MAP_AXES`): the imposed amplitude, or the contact's own (a sphere).

    Returns:
        The rows of ``map.csv`` (:data:`MAP_FIELDS`), in the plan's order.

    Raises:
        OutputFolderError: before any run: ``out`` is a file, not writable, or holds a map and not ``overwrite``;
            or a point's folder is locked by another run.
        RunInterrupted: A signal stopped a run.
        ValueError: ``threshold`` outside (0, 1), before any run.
        SceneError: ``axis`` refused (:func:`check_axis`), before any run.
    """
    classify_cycles({}, threshold)  # the threshold's range, before any run
    check_axis(plan, axis)
    comm = comm or MPI.COMM_WORLD
    rank0 = comm.rank == 0
    out = Path(out)
    check_on_rank0(check_map_folder, out, overwrite, comm)
    say = (lambda m: print(m, flush=True)) if (rank0 and not quiet) else (lambda m: None)
    rows: list[dict[str, Any]] = []
    for i, point in enumerate(plan):
        folder = out / "runs" / point.label
        say(f"[map {i + 1}/{len(plan)}] P = {point.normal:g}, delta* = {point.amplitude:g}: "
            f"{point.scene.loading.cycles} cycles ...")
        failure, wall = run_point(point.scene, folder, comm, ignore_size)
        row: dict[str, Any] = {}
        if rank0:
            row = _point_row(point, folder, failure, wall, threshold)
            say(f"    {wall:.2f} s: " + (f"{row['regime']} (A = {row['energy_ratio_last']:.3g}), by the stick zone "
                                         f"{row['regime_by_stick']}" if row["converged"] else
                                         f"failed: {row['error']}"))
        rows.append(row)
    if rank0:
        contact_amplitudes(rows, plan)
    rows = comm.bcast(rows, root=0)
    if rank0:
        write_map_table(rows, out)
        scene = plan[0].scene
        mindlin = {p.normal: mindlin_transition_amplitude(p.scene, p.normal) for p in plan}
        plot_map(rows, out / "map.png", title=f"{scene.name}: fretting map ({scene.loading.cycles} cycles, "
                 f"A_t = {threshold:g})", force_unit=Units.mm_N_MPa().contact_force(scene.dim),
                 mindlin={k: v for k, v in mindlin.items() if v is not None}, axis=axis)
    comm.barrier()
    return rows


# Tables and picture ----------------------------------------------------------------------------------------------
def write_map_table(rows: Sequence[dict[str, Any]], out: str | Path) -> tuple[Path, Path]:
    """Write ``map.csv`` (:data:`MAP_FIELDS`) and ``map.md`` into ``out``; returns their paths."""
    return write_table(out, "map", rows, MAP_FIELDS, format_markdown(rows))


def read_map_csv(path: str | Path) -> list[dict[str, Any]]:
    """``map.csv`` back as rows: numbers as floats (blank: NaN), ``cycles`` an int, the flags as bools."""
    return read_rows(path, text={"regime", "regime_by_stick", "error", "folder"},
                     flags={"converged", "regimes_agree"}, integers={"cycles"})


def format_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """The map as a markdown table, then the transition amplitudes the grid brackets (by each classifier)."""
    head = ["P", "delta*", "delta_c", "A (first)", "A (last)", "regime (energy)", "regime (stick)", "Q*/(mu P)",
            "cycles", "wall time (s)"]
    lines = ["| " + " | ".join(head) + " |", "| ---: | ---: | ---: | ---: | ---: | --- | --- | ---: | ---: | ---: |"]
    for r in rows:
        regime = str(r.get("regime", ""))
        if not r.get("converged", False):
            regime = "**failed**: " + str(r.get("error", "")).replace("|", "/")[:120]
        elif not r.get("regimes_agree", True):
            regime += " (disagree)"
        lines.append("| " + " | ".join([cell_text(r.get("normal")), cell_text(r.get("amplitude")),
                                        cell_text(r.get("contact_amplitude")),
                                        cell_text(r.get("energy_ratio_first")),
                                        cell_text(r.get("energy_ratio_last")), regime,
                                        cell_text(r.get("regime_by_stick")) if r.get("converged") else "",
                                        cell_text(r.get("force_ratio_last")), cell_text(r.get("cycles")),
                                        f"{r.get('wall_time_s', math.nan):.2f}"]) + " |")
    for amplitude, what in (("amplitude", "amplitude"), ("contact_amplitude", "contact amplitude")):
        for column, name in (("regime", "energy ratio"), ("regime_by_stick", "stick zone")):
            brackets = transition_brackets(rows, column, amplitude)
            if brackets:
                lines.append("")
                lines.append(f"Transition {what} by the {name}: " + "; ".join(
                    f"P = {p:g}: {low:g} < delta_t < {high:g}" for p, (low, high) in brackets.items()))
    if any(math.isfinite(float(r.get("contact_amplitude", math.nan))) for r in rows):
        lines += ["", "delta_c = delta* - C_b Q*: the contact's own amplitude, C_b the bulk compliance (the loop's "
                  "slope at its reversals less Mindlin's stuck contact compliance 1/(8 G* a); map.csv's "
                  "reversal_compliance and bulk_compliance)."]
    return "\n".join(lines)


#: Marker, colour and legend of each regime in ``map.png``.
_STYLE = {"partial": ("o", "tab:blue", "partial slip"), "mixed": ("D", "tab:green", "mixed"),
          "gross": ("s", "tab:red", "gross slip"), "open": (".", "0.5", "open"), "failed": ("x", "k", "failed")}


def plot_map(rows: Sequence[dict[str, Any]], path: str | Path, title: str = "", force_unit: str = "N",
             mindlin: dict[float, float] | None = None, axis: str = "imposed") -> Path:
    """Displacement amplitude (abscissa, log) against normal load (ordinate, log), one marker per regime by the
    energy ratio; a point the stick-zone classifier puts elsewhere is ringed in black. The transition bracketed
    by the grid (mid-points, geometric) as a line; Mindlin's delta_t (a sphere) dashed.

    Args:
        rows: ``map.csv``'s rows.
        path: The PNG.
        title: Its title.
        force_unit: The normal load's unit (N/mm in 2D, N in 3D).
        mindlin: Mindlin's transition amplitude (mm) per normal load, or None.
        axis: The abscissa (:data:`MAP_AXES`): ``"imposed"`` delta*, or ``"contact"`` the contact's own amplitude
            delta* - C_b Q* (points without it are left out), on which Mindlin's delta_t is the like-for-like curve.

    Raises:
        ValueError: ``axis`` not one of :data:`MAP_AXES`.
    """
    if axis not in MAP_AXES:
        raise ValueError(f"plot_map: axis = {axis!r}: allowed {', '.join(MAP_AXES)}")
    column = MAP_AXES[axis]
    rows = [r for r in rows if math.isfinite(float(r.get(column, math.nan)))]
    # Lazy: matplotlib is heavy and only the picture needs it; plots imports numba (through output)
    from matplotlib import ticker

    from .plots import _figure, _save

    fig = _figure((7.5, 5.6))
    ax = fig.subplots(1, 1, gridspec_kw=dict(left=0.12, right=0.97, top=0.88, bottom=0.12))
    for regime, (marker, colour, name) in _STYLE.items():
        sel = [r for r in rows if r.get("regime") == regime]
        if sel:
            ax.plot([r[column] for r in sel], [r["normal"] for r in sel], ls="", marker=marker, ms=9,
                    color=colour, label=name)
    ringed = [r for r in rows if r.get("converged") and not r.get("regimes_agree", True)]
    if ringed:
        ax.plot([r[column] for r in ringed], [r["normal"] for r in ringed], ls="", marker="o", ms=16,
                mfc="none", mec="k", label="stick zone says otherwise")
    brackets = transition_brackets(rows, amplitude=column)
    if brackets:
        normals = sorted(brackets)
        ax.plot([math.sqrt(brackets[p][0] * brackets[p][1]) for p in normals], normals, color="tab:purple",
                lw=1.5, marker="|", ms=12, label="transition (grid, energy ratio)")
    if mindlin:
        normals = sorted(mindlin)
        ax.plot([mindlin[p] for p in normals], normals, color="k", ls="--", lw=1.2,
                label="Mindlin 3 mu P / (16 G* a)" + (" (contact only)" if axis == "imposed" else ""))
    ax.set_xscale("log")
    ax.set_yscale("log")
    for scale in (ax.xaxis, ax.yaxis):  # plain numbers: the grid's values are what the user typed
        scale.set_major_formatter(ticker.FormatStrFormatter("%g"))
        scale.set_minor_formatter(ticker.FormatStrFormatter("%g"))
    ax.set_xlabel("displacement amplitude delta* (mm)" if axis == "imposed"
                  else "contact's amplitude delta_c = delta* - C_b Q* (mm)")
    ax.set_ylabel(f"normal load P ({force_unit})")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="best")
    if title:
        fig.suptitle(title, fontsize=11)
    return _save(fig, Path(path))

"""Pictures of a finished run, drawn from its output files (matplotlib, Agg, PNG; rank 0 only).

Everything is read back from ``history.csv``, ``cycles.csv`` and ``contact_profiles.csv``, so the same
pictures can be redrawn from any (even interrupted) output folder: ``plot_run(folder)``. What the pictures need to
know about the run (its name, load control, tracked positions, Hertz reference) is read from the folder's
``run.json`` (:class:`~dolfinx_fretting.output.RunDescription`), written by any
:class:`~dolfinx_fretting.output.FrettingWriter`: a user's own script gets the same pictures as a scene.

Pictures (all in the output folder):

* ``profiles.png``: contact pressure and shear at the end of the preload and at the last increment
  (with the frictionless Hertz pressure for a half-cylinder).
* 3D contacts: ``contact_maps.png``, maps over the contact plane of the pressure, the shear and slip
  magnitudes, the contact state and the wear depth at the end of the preload and at the last kept increment;
  ``profiles_across.png``, the pressure and shear across the sliding direction (along t2, through the line of
  nodes nearest to t1 = 0); the other pictures show the profiles along the sliding direction through the line
  of nodes nearest to t2 = 0 (the plane of symmetry of a half model).
* cyclic runs only:

  - ``wear_first_cycle.png`` (paper Fig. 6): wear gap and contact pressure along the surface at the
    four quarter points of cycle 1;
  - ``wear_evolution.png`` (paper Fig. 7): wear gap and pressure at the last step of each snapshot cycle;
  - ``node_history.png`` (paper Figs. 8-9): normal gap, slip increment, P_n and P_t of the tracked nodes
    over the steps of the first, a middle and the last snapshot cycle, shaded by contact state;
  - ``fretting_loops.png``: tangential contact force against displacement for the loop cycles;
  - ``wear_growth.png``: maximum wear depth, wear area and dissipated energy per cycle;
  - ``fatigue.png`` (a scene's ``[fatigue]``, from ``fatigue.csv``): SWT and Miner's damage over the near-surface
    region at the last evaluated cycle.

A run with several contact zones is drawn for its first zone (the one a scene's ``[loading]`` drives): its
profiles (the ``zone`` column of ``contact_profiles.csv``) and its forces (``zone0_normal_force``,
``zone0_tangential_force``: in its own frame, where the zone-less columns sum every zone's contacts); the fretting
loops add each other zone's tangential force against the same abscissa.

Each picture is drawn independently: one whose data are missing (a partly written folder) is left
out, one that fails is left out with a :class:`RuntimeWarning`, and :func:`plot_run` never raises.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .analytic import hertz_pressure
from .contact_output import STATE_NAMES, ContactProfiles, read_profiles, read_table
from .io import plot_profiles
from .output import RunDescription, read_description
from .tables import read_rows
from .units import Units

# matplotlib (heavy: ~0.5 s to import) is imported inside the functions that draw, so that importing this
# module (the runner does, at its top) costs nothing until a picture is drawn.
if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_run", "read_table", "plot_wear_first_cycle", "plot_wear_evolution", "plot_node_history",
           "plot_fretting_loops", "plot_wear_growth", "plot_fatigue_map", "tracked_nodes", "CYCLIC_PICTURES"]

#: PNG files :func:`plot_run` writes for a cyclic run besides ``profiles.png``.
CYCLIC_PICTURES = ("wear_first_cycle.png", "wear_evolution.png", "node_history.png", "fretting_loops.png",
                   "wear_growth.png")
#: Lengths (mm) below this are round-off of the contact solver (gaps, slips of closed/sticking nodes).
_ROUND_OFF = 1e-9
#: Colours of the contact states (0 open, 1 stick, 2 slip).
STATE_COLORS = {0: "#d9d9d9", 1: "#4c9be8", 2: "#f28e2b"}


def _figure(figsize: tuple[float, float]) -> Figure:
    """A matplotlib figure drawn by the Agg canvas, without pyplot's global state.

    The pictures use fixed margins (``gridspec_kw``) rather than ``tight_layout``, which draws every
    figure twice.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # lazy: matplotlib (see the note at the imports)
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as a PNG (110 dpi) and return ``path``."""
    fig.savefig(path, dpi=110)
    return path


def _length_unit(values: np.ndarray | float, units: Units | None = None) -> tuple[float, str]:
    """Factor and name of a length unit in which ``values`` (in ``units.length``; default mm) read as plain
    numbers (:meth:`~dolfinx_fretting.units.Units.length_scale`: mm, µm or nm for mm)."""
    return (units or Units.mm_N_MPa()).length_scale(values)


def _mm(x: float) -> str:
    """A position (mm) for a label: round-off around 0 printed as 0."""
    return f"{round(float(x), 9) + 0.0:.4g}"


class _History:
    """``history.csv`` indexed by (cycle, step)."""

    def __init__(self, table: dict[str, np.ndarray]):
        self.t = table
        self.n = table["increment"].size if "increment" in table else 0

    def force(self, name: str, zone: int = 0) -> np.ndarray:
        """Column ``name`` (``normal_force``, ``tangential_force``) of zone ``zone`` when the run has several zones
        (``zone<i>_<name>``), else the table's own."""
        return self.t.get(f"zone{zone}_{name}", self.t[name])

    def zones(self) -> int:
        """The run's contact zones (1 without zone columns)."""
        return sum(1 for i in range(len(self.t)) if f"zone{i}_tangential_force" in self.t) or 1

    def row(self, cycle: int, step: int) -> int | None:
        """Row of (cycle, step), or ``None`` when it is not in the table."""
        if not self.n:
            return None
        hit = np.flatnonzero((self.t["cycle"] == cycle) & (self.t["step"] == step))
        return int(hit[-1]) if hit.size else None

    def cycle_rows(self, cycle: int) -> np.ndarray:
        """Rows of ``cycle`` in increment order."""
        if not self.n:
            return np.zeros(0, dtype=int)
        rows = np.flatnonzero(self.t["cycle"] == cycle)
        return rows[np.argsort(self.t["increment"][rows], kind="stable")]

    def cycles(self) -> np.ndarray:
        """Cycles present in the table, ascending."""
        return np.unique(self.t["cycle"]) if self.n else np.zeros(0, dtype=int)


def _load_label(run: RunDescription, hist: _History, cycle: int, step: int) -> str:
    """The tangential load at (cycle, step) read from ``history.csv``, e.g. ``q = +10 MPa`` (``run.units``).

    Values within 1e-6 of the load amplitude of zero (round-off of a force-controlled load) read 0.
    """
    r = hist.row(cycle, step)
    kind = run.tangential_control
    if r is None or kind == "none":
        return ""
    units = run.units
    column, symbol, unit = {"pressure": ("face_pressure", "q", units.stress),
                            "displacement": ("tangential_displacement", "δ", units.length),
                            "force": ("tangential_force", "Q", units.contact_force(run.dim))}[kind]
    value = float((hist.force(column) if column == "tangential_force" else hist.t[column])[r])
    if abs(value) <= 1e-6 * abs(run.tangential_amplitude):
        return f"{symbol} = 0 {unit}"
    return f"{symbol} = {value:+.3g} {unit}"


def _profile_pair_legend(fig: Figure, ax_w, ax_p, wear: np.ndarray) -> None:
    """One legend under the two panels of a profile picture; a note on an all-zero wear panel."""
    handles, labels = ax_p.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 5), fontsize=8.5, frameon=False)
    if not np.any(wear):
        ax_w.text(0.5, 0.6, "no wear (wear.law = none or no slip)", transform=ax_w.transAxes, ha="center",
                  color="0.4")


def _side_by_side(n_labels: int) -> dict[str, float]:
    """Margins of a two-panel profile picture with a legend of ``n_labels`` entries under it."""
    rows = -(-n_labels // 5)
    return dict(left=0.065, right=0.99, bottom=0.12 + 0.05 * rows, top=0.91, wspace=0.2)


def _preload_row(prof: ContactProfiles) -> int | None:
    """Row of the last kept increment of the preload (cycle 0)."""
    rows = prof.rows_of_cycle(0)
    return int(rows[-1]) if rows.size else None


def _snapshot_cycles(prof: ContactProfiles) -> list[int]:
    """Cycles (>= 1) with kept increments in the profiles, ascending."""
    return [int(c) for c in np.unique(prof.cycles) if c >= 1]


def _shade_states(ax, steps: np.ndarray, states: np.ndarray) -> None:
    """Colour the background of ``ax`` by contact state, one band per run of equal states."""
    if steps.size == 0:
        return
    start = 0
    for k in range(1, steps.size + 1):
        if k == steps.size or states[k] != states[start]:
            colour = STATE_COLORS.get(int(states[start]), "white")
            ax.axvspan(steps[start] - 0.5, steps[k - 1] + 0.5, color=colour, alpha=0.35, lw=0, zorder=0)
            start = k


def _quarter_lines(ax, n: int) -> None:
    for s in (n // 4, n // 2, 3 * n // 4):
        ax.axvline(s, color="k", lw=0.6, ls=":", zorder=1)


def tracked_nodes(run: RunDescription, prof: ContactProfiles) -> list[int]:
    """Columns of the contact nodes whose history is drawn.

    The nodes nearest to ``run.track_positions``; when none is given, the outermost node in
    contact at the end of the preload (on the side of the smaller position) and the node nearest to the
    centre of the contact nodes.

    Args:
        run: The run's description (``run.json``).
        prof: Its contact profiles.

    Returns:
        Distinct columns of ``prof`` (at most one per tracked position).
    """
    picks = [prof.nearest_node(x) for x in run.track_positions]
    if not picks:
        pre = _preload_row(prof)
        closed = np.flatnonzero(prof.values["state"][pre] != 0) if pre is not None else np.zeros(0, int)
        if closed.size:
            edge = int(closed[np.argmin(prof.position[closed])])
        else:
            edge = int(np.argmin(prof.position))
        centre = prof.nearest_node(0.5 * (prof.position.min() + prof.position.max()))
        picks = [edge, centre]
    return list(dict.fromkeys(picks))


def plot_wear_first_cycle(path: Path, run: RunDescription, prof: ContactProfiles, hist: _History) -> Path | None:
    """Wear gap and contact pressure along the surface at the quarter points of cycle 1 (paper Fig. 6).

    When cycle 1 was not kept, the first kept cycle is drawn (named in the title).

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        prof: Contact profiles.
        hist: ``history.csv`` (for the load values in the legend).

    Returns:
        ``path``, or ``None`` when no step of a cycle was kept.
    """
    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    cycle = 1 if 1 in cycles else cycles[0]
    n = run.increments_per_cycle
    rows = prof.rows_of_cycle(cycle)
    by_step = {int(prof.steps[r]): int(r) for r in rows}
    chosen = [(s, by_step[s]) for s in (n // 4, n // 2, 3 * n // 4, n) if s in by_step]
    if not chosen:
        return None
    wear = prof.values["wear"][[r for _, r in chosen]]
    f, unit = _length_unit(wear, run.units)
    pre = _preload_row(prof)
    n_labels = len(chosen) + (pre is not None)
    fig = _figure((12, 4.6 + 0.25 * -(-n_labels // 5)))
    ax_w, ax_p = fig.subplots(1, 2, gridspec_kw=_side_by_side(n_labels))
    # later curves drawn thinner on top of earlier ones, so that equal stretches stay visible
    styles = [("tab:blue", "o", 3.2), ("tab:orange", "s", 2.4), ("tab:green", "^", 1.7),
              ("tab:red", "v", 1.0)]
    for (s, r), (c, marker, lw) in zip(chosen, styles):
        load = _load_label(run, hist, cycle, s)
        label = f"step {s}/{n}" + (f", {load}" if load else "")
        for ax, y in ((ax_w, prof.values["wear"][r] * f), (ax_p, prof.values["pressure"][r])):
            ax.plot(prof.position, y, "-", marker=marker, ms=3.5, lw=lw, color=c, label=label)
    if pre is not None:
        ax_p.plot(prof.position, prof.values["pressure"][pre], "k--", lw=1, label="end of preload")
    ax_w.set_ylabel(f"wear gap ({unit})")
    ax_p.set_ylabel(f"contact pressure P_n ({run.units.stress})")
    for ax in (ax_w, ax_p):
        ax.set_xlabel(f"position along the surface ({run.units.length})")
        ax.grid(alpha=0.3)
    _profile_pair_legend(fig, ax_w, ax_p, wear)
    fig.suptitle(f"{run.name}: wear gap and contact pressure during cycle {cycle} (quarter points)")
    return _save(fig, path)


def plot_wear_evolution(path: Path, run: RunDescription, prof: ContactProfiles, hist: _History) -> Path | None:
    """Wear gap and contact pressure at the last kept step of each snapshot cycle (paper Fig. 7).

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        prof: Contact profiles.
        hist: ``history.csv`` (for the load value in the title).

    Returns:
        ``path``, or ``None`` when no cycle was kept.
    """
    import matplotlib  # lazy: matplotlib (see the note at the imports)

    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    n = run.increments_per_cycle
    last = [(c, int(prof.rows_of_cycle(c)[-1])) for c in cycles]
    f, unit = _length_unit(prof.values["wear"][[r for _, r in last]], run.units)
    cmap = matplotlib.colormaps["viridis"]
    pre = _preload_row(prof)
    n_labels = len(last) + (pre is not None)
    fig = _figure((12, 4.6 + 0.25 * -(-n_labels // 5)))
    ax_w, ax_p = fig.subplots(1, 2, gridspec_kw=_side_by_side(n_labels))
    for k, (c, r) in enumerate(last):
        colour = cmap(k / max(len(last) - 1, 1) * 0.9)
        s = int(prof.steps[r])
        label = f"cycle {c}" + ("" if s == n else f" (step {s} of {n})")
        ax_w.plot(prof.position, prof.values["wear"][r] * f, ".-", ms=3, color=colour, label=label)
        ax_p.plot(prof.position, prof.values["pressure"][r], ".-", ms=3, color=colour, label=label)
    if pre is not None:
        ax_p.plot(prof.position, prof.values["pressure"][pre], "k--", lw=1, label="end of preload")
    ax_w.set_ylabel(f"wear gap ({unit})")
    ax_p.set_ylabel(f"contact pressure P_n ({run.units.stress})")
    for ax in (ax_w, ax_p):
        ax.set_xlabel(f"position along the surface ({run.units.length})")
        ax.grid(alpha=0.3)
    _profile_pair_legend(fig, ax_w, ax_p, prof.values["wear"][[r for _, r in last]])
    load = _load_label(run, hist, last[-1][0], n)
    fig.suptitle(f"{run.name}: wear gap and contact pressure at the end of the cycle (step {n}"
                 + (f", {load}" if load else "") + ")")
    return _save(fig, path)


def plot_node_history(path: Path, run: RunDescription, prof: ContactProfiles) -> Path | None:
    """State of the tracked nodes over the steps of up to three snapshot cycles (paper Figs. 8-9).

    One block of panels per tracked node (:func:`tracked_nodes`) and one column per cycle (the first, a
    middle and the last kept cycle); three rows per block: the normal gap x_n, the tangential relative
    displacement increment Δx_t (the ``slip`` column, which is the slip increment while the node slips
    and 0 while it sticks) and the contact tractions P_n, P_t. The background of every panel is coloured
    by the contact state of the node at each step (open, stick, slip); dotted lines mark the quarter
    points of the cycle.

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        prof: Contact profiles.

    Returns:
        ``path``, or ``None`` when no cycle was kept.
    """
    from matplotlib.lines import Line2D  # lazy: matplotlib (see the note at the imports)
    from matplotlib.patches import Patch

    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    shown = list(dict.fromkeys([cycles[0], cycles[len(cycles) // 2], cycles[-1]]))
    nodes = tracked_nodes(run, prof)
    n = run.increments_per_cycle
    rows_of = {c: prof.rows_of_cycle(c) for c in shown}
    gap, slip = prof.values["gap"], prof.values["slip"]
    pairs = [(j, c) for j in nodes for c in shown]
    fg, ug = _length_unit(np.concatenate([gap[rows_of[c], j] for j, c in pairs]), run.units)
    fs, us = _length_unit(np.concatenate([slip[rows_of[c], j] for j, c in pairs]), run.units)
    ncol, nn = len(shown), len(nodes)
    # three rows of panels per node, a thin empty row between the nodes' blocks
    ratios: list[float] = []
    for k in range(nn):
        ratios += ([0.3] if k else []) + [1.0, 1.0, 1.0]
    width, height = max(4.2 * ncol, 8.0), 2.0 * sum(ratios) + 1.3
    fig = _figure((width, height))
    grid = fig.add_gridspec(len(ratios), ncol, height_ratios=ratios, hspace=0.12, wspace=0.08,
                            left=0.95 / width, right=0.985, top=1 - 0.75 / height, bottom=0.95 / height)
    first = None
    for b, j in enumerate(nodes):
        top = 4 * b
        axes = np.empty((3, ncol), dtype=object)
        for i in range(3):
            for k in range(ncol):
                share_y = axes[i, 0] if k else None
                axes[i, k] = fig.add_subplot(grid[top + i, k], sharex=first, sharey=share_y)
                first = first or axes[i, k]
        for k, c in enumerate(shown):
            rows = rows_of[c]
            steps = prof.steps[rows]
            ax_g, ax_s, ax_p = axes[:, k]
            for ax in axes[:, k]:
                _shade_states(ax, steps, prof.values["state"][rows, j])
                _quarter_lines(ax, n)
                ax.axhline(0.0, color="k", lw=0.5, zorder=1)
                ax.grid(alpha=0.3)
                if ax is not ax_p or b < nn - 1:
                    ax.tick_params(labelbottom=False)
                if k:
                    ax.tick_params(labelleft=False)
            ax_g.plot(steps, gap[rows, j] * fg, "k.-", ms=3, lw=1)
            ax_s.plot(steps, slip[rows, j] * fs, "k.-", ms=3, lw=1)
            ax_p.plot(steps, prof.values["pressure"][rows, j], ".-", ms=3, lw=1, color="tab:red")
            ax_p.plot(steps, prof.values["shear"][rows, j], ".-", ms=3, lw=1, color="tab:purple")
            ax_g.set_title(f"node {int(prof.nodes[j])} at x = {_mm(prof.position[j])} {run.units.length}, cycle {c}",
                           fontsize=9.5)
            if b == nn - 1:
                ax_p.set_xlabel(f"step in the cycle (of {n})")
        # a row of round-off only (a node that never opens: |x_n| ~ 1e-14 mm) is not blown up to fill it
        for i, (values, factor) in enumerate(((gap, fg), (slip, fs))):
            block = np.concatenate([values[rows_of[c], j] for c in shown])
            if not np.nanmax(np.abs(block), initial=0.0) > _ROUND_OFF:
                every = np.concatenate([values[rows_of[c], jj] for jj, c in pairs])
                span = 0.05 * float(np.nanmax(np.abs(every), initial=0.0)) * factor
                axes[i, 0].set_ylim(-(span if span > _ROUND_OFF * factor else 1.0),
                                    span if span > _ROUND_OFF * factor else 1.0)
        axes[0, 0].set_ylabel(f"normal gap x_n ({ug})", fontsize=9)
        axes[1, 0].set_ylabel(f"tangential incr. Δx_t ({us})", fontsize=9)
        axes[2, 0].set_ylabel(f"P_n, P_t ({run.units.stress})", fontsize=9)
    first.set_xticks([1, n // 4, n // 2, 3 * n // 4, n])
    first.set_xlim(0.5, n + 0.5)
    handles = [Patch(color=STATE_COLORS[s], alpha=0.5, label=STATE_NAMES[s]) for s in (0, 1, 2)]
    handles += [Line2D([], [], color="tab:red", marker=".", label="P_n (pressure)"),
                Line2D([], [], color="tab:purple", marker=".", label="P_t (shear)")]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=9, frameon=False)
    fig.suptitle(f"{run.name}: contact state of tracked nodes over a cycle", fontsize=12,
                 y=1 - 0.12 / height)
    return _save(fig, path)


def _loop_displacement(run: RunDescription, hist: _History) -> tuple[np.ndarray, str]:
    """The fretting loop's abscissa and what it is (the x label without its unit).

    Displacement control: the obstacle's tangential displacement D_t1. Otherwise ``-mean_relative_tangential``:
    the history column is the mean over *all* candidate contacts (loaded or not) of the body's tangential
    position relative to the obstacle, y_t1 = u_t1 - D_t1, which runs opposite to Q (the body dragged by Q > 0
    lags behind the obstacle); its negative, the obstacle's displacement relative to the contact nodes, turns
    with Q like the obstacle's displacement does (the same abscissa as ``cycles.csv``'s ``displacement_*``).
    """
    if run.tangential_control == "displacement":
        return hist.t["tangential_displacement"], "tangential displacement of the obstacle D_t1"
    return (-hist.t["mean_relative_tangential"],
            "obstacle's tangential displacement relative to the contact nodes,\n"
            "mean over all candidate contacts (−mean y_t1)")


def plot_fretting_loops(path: Path, run: RunDescription, hist: _History) -> Path | None:
    """Tangential contact force against displacement over the loop cycles (``history.csv``).

    The displacement is the obstacle's tangential displacement for a displacement-controlled load, else
    the obstacle's tangential displacement relative to the body's contact nodes, averaged over all candidate
    contacts (``-mean_relative_tangential``: the same sign as Q, see :func:`_loop_displacement`). Q is the
    contact force on the body along t1, in ``run.units.contact_force(run.dim)`` (N/mm in 2D, N in 3D for the
    scenes). A pressure-controlled run gets a second panel with
    the force against the face pressure q. The cycles are ``run.loop_cycles`` found in the
    table, else up to four cycles spread over those present. Each loop starts at the last row before
    its cycle (the end of the previous cycle or of the preload), so it is closed.

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        hist: ``history.csv``.

    Returns:
        ``path``, or ``None`` when the table has no cyclic row.
    """
    import matplotlib  # lazy: matplotlib (see the note at the imports)

    present = [int(c) for c in hist.cycles() if c >= 1]
    if not present:
        return None
    wanted = [c for c in run.loop_cycles if c in present]
    if not wanted:
        idx = np.unique(np.linspace(0, len(present) - 1, min(4, len(present))).round().astype(int))
        wanted = [present[i] for i in idx]
    x_all, what = _loop_displacement(run, hist)
    loops = []
    for c in wanted:
        rows = hist.cycle_rows(c)
        before = np.flatnonzero(hist.t["increment"] == hist.t["increment"][rows[0]] - 1)
        if before.size:
            rows = np.concatenate([before[-1:], rows])
        loops.append((c, rows))
    f, unit = _length_unit(np.concatenate([x_all[r] for _, r in loops]), run.units)
    cmap = matplotlib.colormaps["viridis"]
    pressure = run.tangential_control == "pressure"
    fig = _figure((12.5, 5.2) if pressure else (7, 5.2))
    axes = list(np.atleast_1d(fig.subplots(1, 2 if pressure else 1, gridspec_kw=dict(
        left=0.065 if pressure else 0.12, right=0.985, bottom=0.11, top=0.9, wspace=0.2))))
    Q = hist.force("tangential_force")
    zones = hist.zones()
    for k, (c, rows) in enumerate(loops):
        colour = cmap(k / max(len(loops) - 1, 1) * 0.9)
        axes[0].plot(x_all[rows] * f, Q[rows], ".-", ms=3, lw=1.2, color=colour,
                     label=f"cycle {c}" + (", zone 0" if zones > 1 else ""))
        for zone in range(1, zones):  # the other zones' tangential forces against the same abscissa, dashed
            axes[0].plot(x_all[rows] * f, hist.force("tangential_force", zone)[rows], "--", lw=1.0, color=colour,
                         label=f"cycle {c}, zone {zone}")
        if pressure:
            axes[1].plot(hist.t["face_pressure"][rows], Q[rows], ".-", ms=3, lw=1.2, color=colour,
                         label=f"cycle {c}")
    axes[0].set_xlabel(f"{what} ({unit})")
    if pressure:
        axes[1].set_xlabel(f"face pressure q on '{run.pressure_face}' ({run.units.stress})")
    for ax in axes:
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(0, color="k", lw=0.5)
        ax.set_ylabel(f"tangential contact force Q ({run.units.contact_force(run.dim)})")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{run.name}: fretting loops")
    return _save(fig, path)


def plot_wear_growth(path: Path, run: RunDescription, cycles: dict[str, np.ndarray]) -> Path | None:
    """Maximum wear depth, wear area and dissipated energy per cycle against the cycle (``cycles.csv``).

    The x axis is ``equivalent_cycles`` (physical cycles: simulated cycles times ``wear.acceleration``).

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        cycles: ``cycles.csv`` as read by :func:`read_table`.

    Returns:
        ``path``, or ``None`` when the table has no row.
    """
    if not cycles or cycles.get("cycle", np.zeros(0)).size == 0:
        return None
    x = cycles["equivalent_cycles"]
    style = ".-" if x.size <= 200 else "-"
    depth = cycles["max_wear_depth"]
    f, unit = _length_unit(depth, run.units)
    fig = _figure((7, 8))
    ax_d, ax_a, ax_e = fig.subplots(3, 1, sharex=True, gridspec_kw=dict(
        left=0.16, right=0.97, bottom=0.065, top=0.94, hspace=0.14))
    ax_d.plot(x, depth * f, style, ms=3, color="tab:red")
    ax_d.set_ylabel(f"max wear depth ({unit})")
    ax_a.plot(x, cycles["wear_area"], style, ms=3, color="tab:blue")
    ax_a.set_ylabel(f"{'wear area' if run.dim == 2 else 'wear volume'} ({run.units.wear_measure(run.dim)})")
    ax_e.plot(x, cycles["dissipated_energy"], style, ms=3, color="tab:green")
    ax_e.set_ylabel(f"dissipated energy per cycle\n({run.units.energy(run.dim)})")
    ax_e.set_xlabel("cycles (equivalent physical cycles)")
    for ax in (ax_d, ax_a, ax_e):
        ax.grid(alpha=0.3)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4), useMathText=True)
    ax_d.set_ylim(bottom=0)
    ax_a.set_ylim(bottom=0)
    acc = run.wear_acceleration
    fig.suptitle(f"{run.name}: wear growth" + (f" (wear acceleration {acc:g})" if acc != 1 else ""))
    return _save(fig, path)


def plot_fatigue_map(path: Path, run: RunDescription, table: Path) -> Path | None:
    """SWT (and Miner's damage, where ``fatigue.csv`` has it) at the points of the near-surface region, x against
    depth, at the last evaluated cycle of ``fatigue.csv``.

    Returns:
        ``path``, or ``None`` when the table has no row.
    """
    rows = read_rows(table, integers=("cycle",))
    if not rows:
        return None
    last = max(row["cycle"] for row in rows)
    rows = [row for row in rows if row["cycle"] == last]
    columns = {name: np.array([row[name] for row in rows]) for name in ("x", "depth", "swt", "damage")}
    shown = [("swt", "SWT (MPa)")] + ([("damage", "Miner's damage D")]
                                      if np.isfinite(columns["damage"]).any() else [])
    fig = _figure((8, 2.6 * len(shown) + 0.6))
    axes = fig.subplots(len(shown), 1, sharex=True, squeeze=False, gridspec_kw=dict(
        left=0.1, right=0.97, bottom=0.16 if len(shown) == 1 else 0.09, top=0.88, hspace=0.25))[:, 0]
    length = run.units.length
    for ax, (name, label) in zip(axes, shown):
        dots = ax.scatter(columns["x"], -columns["depth"], c=columns[name], s=14, cmap="viridis")
        fig.colorbar(dots, ax=ax, label=label)
        ax.set_ylabel(f"-depth ({length})")
    axes[-1].set_xlabel(f"x ({length})")
    fig.suptitle(f"{run.name}: fatigue parameters, cycle {last}")
    return _save(fig, path)


#: The fields of ``contact_maps.png``: (name, quantity: "stress", "length" (in the run's units) or "state"; value of a
#: row of the profiles).
_MAP_FIELDS = (
    ("pressure", "stress", lambda v, r: v["pressure"][r]),
    ("|shear|", "stress", lambda v, r: np.hypot(v["shear"][r], v["shear_2"][r])),
    ("|slip increment|", "length", lambda v, r: np.hypot(v["slip"][r], v["slip_2"][r])),
    ("state", "state", lambda v, r: v["state"][r]),
    ("wear depth", "length", lambda v, r: v["wear"][r]),
)


def plot_contact_maps(path: Path, run: RunDescription, prof: ContactProfiles) -> Path | None:
    """Maps over the contact plane (t1, t2) of a 3D contact: pressure, shear and slip magnitudes, state and wear
    depth at the end of the preload and at the last kept increment (one row each).

    Args:
        path: PNG file.
        run: The run's description (``run.json``).
        prof: Contact profiles of a 3D contact (``prof.position_2`` set).

    Returns:
        ``path``, or ``None`` for a 2D contact or fewer than three nodes.
    """
    import matplotlib.tri as mtri  # lazy: matplotlib (see the note at the imports)
    from matplotlib.colors import BoundaryNorm, ListedColormap

    if prof.position_2 is None or prof.position.size < 3:
        return None
    # the end of the preload (a monotonic run's rows are all of cycle 0: the preload is its first increments)
    pre = prof.index(run.preload_increments) if run.preload_increments else _preload_row(prof)
    rows = list(dict.fromkeys([r for r in (pre, prof.increments.size - 1) if r is not None]))
    tri = mtri.Triangulation(prof.position, prof.position_2)
    height = 3.1 * len(rows) + 0.7
    fig = _figure((3.9 * len(_MAP_FIELDS), height))
    axes = np.atleast_2d(fig.subplots(len(rows), len(_MAP_FIELDS), gridspec_kw=dict(
        left=0.045, right=0.975, bottom=0.45 / height, top=1 - 0.6 / height, wspace=0.55, hspace=0.35)))
    states = ListedColormap([STATE_COLORS[k] for k in (0, 1, 2)])
    for i, r in enumerate(rows):
        for j, (name, quantity, value) in enumerate(_MAP_FIELDS):
            ax = axes[i, j]
            data = np.nan_to_num(np.asarray(value(prof.values, r), dtype=float))
            if quantity == "state":
                # a state is a node's, not an area's: one dot per node (colouring triangles would average codes)
                art = ax.scatter(prof.position, prof.position_2, c=data, s=max(4.0, 3000.0 / data.size),
                                 cmap=states, norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5], 3), linewidths=0)
                bar = fig.colorbar(art, ax=ax, ticks=[0, 1, 2], fraction=0.046)
                bar.ax.set_yticklabels([STATE_NAMES[k] for k in (0, 1, 2)])
                title = name
            else:
                f, unit = _length_unit(data, run.units) if quantity == "length" else (1.0, run.units.stress)
                art = ax.tripcolor(tri, data * f, shading="gouraud", cmap="viridis")
                bar = fig.colorbar(art, ax=ax, fraction=0.046)
                bar.formatter.set_useOffset(False)  # a nearly uniform field reads as its values, not "1e-5+2"
                title = f"{name} ({unit})"
            ax.set_aspect("equal")
            ax.set_title(title, fontsize=9)
            ax.tick_params(labelsize=7)
            if j == 0:
                inc = int(prof.increments[r])
                label = f"end of preload (inc {inc})" if r == pre else f"increment {inc}"
                ax.set_ylabel(f"{label}\nt2 ({run.units.length})", fontsize=8)
            if i == len(rows) - 1:
                ax.set_xlabel(f"t1 ({run.units.length})", fontsize=8)
    fig.suptitle(f"{run.name}: the contact plane (t1 the first tangent, t2 the second)")
    return _save(fig, path)


def _plot_profiles(out: Path, run: RunDescription, prof: ContactProfiles, hist: _History,
                   name: str = "profiles.png", direction: str = "") -> Path | None:
    """``profiles.png`` (or ``name``): pressure and shear at the end of the preload and at the last kept increment,
    along ``prof``'s positions (``direction`` names them in the title, 3D)."""
    pre = run.preload_increments
    chosen = [i for i in (pre, int(prof.increments.max())) if prof.index(i) is not None]
    if not chosen:
        chosen = [int(prof.increments.max())]
    curves = []
    for inc in dict.fromkeys(chosen):
        r = prof.index(inc)
        label = "end of preload" if inc == pre else "final"
        curves.append((f"{label} (inc {inc})", prof.values["pressure"][r], prof.values["shear"][r]))
    reference = None
    pre_rows = np.flatnonzero(hist.t["increment"] == pre) if hist.n else np.zeros(0, int)
    if run.hertz is not None and pre_rows.size:
        P = float(hist.force("normal_force")[pre_rows[-1]])
        xs = np.linspace(prof.position.min(), prof.position.max(), 400)
        radius, E_star = run.hertz
        two_bodies = run.obstacle == "elastic_body"
        reference = ("Hertz" + (", two identical bodies" if two_bodies else ", rigid flat, frictionless")
                     + ", end of preload", xs, hertz_pressure(xs, P, radius, E_star))
    path = out / name
    plot_profiles(path, prof.position, curves, reference, title=f"{run.name}: contact tractions{direction}",
                  units=run.units)
    return path


def plot_run(out: Path, run: RunDescription | None = None) -> list[Path]:
    """Write the run's PNGs into ``out`` (see the module docstring for the list).

    Never raises: a picture whose data are missing is skipped, one that fails is skipped with a
    :class:`RuntimeWarning` naming it.

    Args:
        out: The run's output folder.
        run: The run's description; default: the folder's ``run.json`` (none there: no pictures, a warning).

    Returns:
        The PNG files written.
    """
    if run is None:
        run = read_description(out)
        if run is None:
            warnings.warn(f"{out}: no run.json (written by FrettingWriter), no pictures", RuntimeWarning,
                          stacklevel=2)
            return []
    out = Path(out)
    written: list[Path] = []

    def attempt(name: str, draw: Callable[[], Path | None]) -> None:
        try:
            path = draw()
        except Exception as exc:  # noqa: BLE001 - a failed picture must not stop the others
            warnings.warn(f"{run.name}: {name} not drawn: {type(exc).__name__}: {exc}", RuntimeWarning,
                          stacklevel=2)
            return
        if path is not None:
            written.append(path)

    try:
        prof = read_profiles(out / "contact_profiles.csv")
        hist = _History(read_table(out / "history.csv"))
        cycles = read_table(out / "cycles.csv") if run.cycles > 0 else {}
    except Exception as exc:  # noqa: BLE001 - unreadable tables: no pictures, but no failure either
        warnings.warn(f"{run.name}: output tables not readable, no pictures: {type(exc).__name__}: {exc}",
                      RuntimeWarning, stacklevel=2)
        return written

    along = ""
    if prof is not None and prof.dim == 3:
        full = prof
        attempt("contact_maps.png", lambda: plot_contact_maps(out / "contact_maps.png", run, full))
        attempt("profiles_across.png", lambda: _plot_profiles(out, run, full.section_across(0.0), hist,
                                                              "profiles_across.png", " across the sliding direction "
                                                              "(along t2, through x = 0)"))
        prof = prof.section(0.0)
        along = " along the sliding direction (t1, through y = 0)"
    if prof is not None:
        attempt("profiles.png", lambda: _plot_profiles(out, run, prof, hist, direction=along))
    if run.cycles > 0:
        if prof is not None:
            attempt("wear_first_cycle.png",
                    lambda: plot_wear_first_cycle(out / "wear_first_cycle.png", run, prof, hist))
            attempt("wear_evolution.png",
                    lambda: plot_wear_evolution(out / "wear_evolution.png", run, prof, hist))
            attempt("node_history.png", lambda: plot_node_history(out / "node_history.png", run, prof))
        if hist.n:
            attempt("fretting_loops.png",
                    lambda: plot_fretting_loops(out / "fretting_loops.png", run, hist))
        if cycles:
            attempt("wear_growth.png", lambda: plot_wear_growth(out / "wear_growth.png", run, cycles))
        if (out / "fatigue.csv").is_file():
            attempt("fatigue.png", lambda: plot_fatigue_map(out / "fatigue.png", run, out / "fatigue.csv"))
    return written

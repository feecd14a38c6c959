"""Pictures of a finished run, drawn from its output files (matplotlib, Agg, PNG; rank 0 only).

Everything is read back from ``history.csv``, ``cycles.csv`` and ``contact_profiles.csv``, so the same
pictures can be redrawn from any (even interrupted) output folder: ``plot_run(folder, scene)``.

Pictures (all in the output folder):

* ``profiles.png``: contact pressure and shear at the end of the preload and at the last increment
  (with the frictionless Hertz pressure for a half-cylinder).
* cyclic runs only:

  - ``wear_first_cycle.png`` (paper Fig. 6): wear gap and contact pressure along the surface at the
    four quarter points of cycle 1;
  - ``wear_evolution.png`` (paper Fig. 7): wear gap and pressure at the last step of each snapshot cycle;
  - ``node_history.png`` (paper Figs. 8-9): normal gap, slip increment, P_n and P_t of the tracked nodes
    over the steps of the first, a middle and the last snapshot cycle, shaded by contact state;
  - ``fretting_loops.png``: tangential contact force against displacement for the loop cycles;
  - ``wear_growth.png``: maximum wear depth, wear area and dissipated energy per cycle.

Each picture is drawn independently: one that cannot be drawn (missing or partial table) is skipped
with a warning, and :func:`plot_run` never raises.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .contact_output import STATE_NAMES, ContactProfiles, read_profiles, read_table
from .scenes import Scene

__all__ = ["plot_run", "read_table", "plot_wear_first_cycle", "plot_wear_evolution", "plot_node_history",
           "plot_fretting_loops", "plot_wear_growth", "tracked_nodes", "CYCLIC_PICTURES"]

#: PNG files :func:`plot_run` writes for a cyclic run besides ``profiles.png``.
CYCLIC_PICTURES = ("wear_first_cycle.png", "wear_evolution.png", "node_history.png", "fretting_loops.png",
                   "wear_growth.png")
#: Colours of the contact states (0 open, 1 stick, 2 slip).
STATE_COLORS = {0: "#d9d9d9", 1: "#4c9be8", 2: "#f28e2b"}


def _figure(figsize: tuple[float, float]):
    """A matplotlib figure drawn by the Agg canvas, without pyplot's global state."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: Path) -> Path:
    fig.savefig(path, dpi=110)
    return path


def _length_unit(values: np.ndarray | float) -> tuple[float, str]:
    """Factor and name of a length unit (mm, µm or nm) in which ``values`` (mm) read as plain numbers."""
    arr = np.asarray(values, dtype=float)
    arr = arr[np.isfinite(arr)]
    m = float(np.max(np.abs(arr))) if arr.size else 0.0
    if m >= 0.1 or m == 0.0:
        return 1.0, "mm"
    if m >= 1e-4:
        return 1e3, "µm"
    return 1e6, "nm"


class _History:
    """``history.csv`` indexed by (cycle, step)."""

    def __init__(self, table: dict[str, np.ndarray]):
        self.t = table
        self.n = table["increment"].size if "increment" in table else 0

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
        return np.unique(self.t["cycle"]) if self.n else np.zeros(0, dtype=int)


def _load_label(scene: Scene, hist: _History, cycle: int, step: int) -> str:
    """The tangential load at (cycle, step) read from ``history.csv``, e.g. ``q = +10 MPa``."""
    r = hist.row(cycle, step)
    kind = scene.loading.tangential_kind
    if r is None or kind == "none":
        return ""
    if kind == "pressure":
        return f"q = {hist.t['face_pressure'][r]:+.3g} MPa"
    if kind == "displacement":
        return f"δ = {hist.t['tangential_displacement'][r]:+.3g} mm"
    return f"Q = {hist.t['tangential_force'][r]:+.3g} N/mm"


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


def tracked_nodes(scene: Scene, prof: ContactProfiles) -> list[int]:
    """Columns of the contact nodes whose history is drawn.

    The nodes nearest to ``scene.output.track_positions``; when none is given, the outermost node in
    contact at the end of the preload (on the side of the smaller position) and the node nearest to the
    centre of the contact nodes.

    Args:
        scene: The run's scene.
        prof: Its contact profiles.

    Returns:
        Distinct columns of ``prof`` (at most one per tracked position).
    """
    picks = [prof.nearest_node(x) for x in scene.output.track_positions]
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


def plot_wear_first_cycle(path: Path, scene: Scene, prof: ContactProfiles, hist: _History) -> Path | None:
    """Wear gap and contact pressure along the surface at the quarter points of cycle 1 (paper Fig. 6).

    When cycle 1 was not kept, the first kept cycle is drawn (named in the title).

    Args:
        path: PNG file.
        scene: The run's scene.
        prof: Contact profiles.
        hist: ``history.csv`` (for the load values in the legend).

    Returns:
        ``path``, or ``None`` when no step of a cycle was kept.
    """
    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    cycle = 1 if 1 in cycles else cycles[0]
    n = scene.loading.increments_per_cycle
    rows = prof.rows_of_cycle(cycle)
    by_step = {int(prof.steps[r]): int(r) for r in rows}
    chosen = [(s, by_step[s]) for s in (n // 4, n // 2, 3 * n // 4, n) if s in by_step]
    if not chosen:
        return None
    wear = prof.values["wear"][[r for _, r in chosen]]
    f, unit = _length_unit(wear)
    fig = _figure((12, 4.6))
    ax_w, ax_p = fig.subplots(1, 2)
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    for (s, r), c in zip(chosen, colours):
        load = _load_label(scene, hist, cycle, s)
        label = f"step {s}/{n}" + (f", {load}" if load else "")
        ax_w.plot(prof.position, prof.values["wear"][r] * f, ".-", ms=3, color=c, label=label)
        ax_p.plot(prof.position, prof.values["pressure"][r], ".-", ms=3, color=c, label=label)
    pre = _preload_row(prof)
    if pre is not None:
        ax_p.plot(prof.position, prof.values["pressure"][pre], "k--", lw=1, label="end of preload")
    ax_w.set_ylabel(f"wear gap ({unit})")
    ax_p.set_ylabel("contact pressure P_n (MPa)")
    for ax in (ax_w, ax_p):
        ax.set_xlabel("position along the surface (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{scene.name}: wear gap and contact pressure during cycle {cycle} (quarter points)")
    fig.tight_layout()
    return _save(fig, path)


def plot_wear_evolution(path: Path, scene: Scene, prof: ContactProfiles, hist: _History) -> Path | None:
    """Wear gap and contact pressure at the last kept step of each snapshot cycle (paper Fig. 7).

    Args:
        path: PNG file.
        scene: The run's scene.
        prof: Contact profiles.
        hist: ``history.csv`` (for the load value in the title).

    Returns:
        ``path``, or ``None`` when no cycle was kept.
    """
    import matplotlib

    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    n = scene.loading.increments_per_cycle
    last = [(c, int(prof.rows_of_cycle(c)[-1])) for c in cycles]
    f, unit = _length_unit(prof.values["wear"][[r for _, r in last]])
    cmap = matplotlib.colormaps["viridis"]
    fig = _figure((12, 4.6))
    ax_w, ax_p = fig.subplots(1, 2)
    for k, (c, r) in enumerate(last):
        colour = cmap(k / max(len(last) - 1, 1) * 0.9)
        s = int(prof.steps[r])
        label = f"cycle {c}" + ("" if s == n else f" (step {s} of {n})")
        ax_w.plot(prof.position, prof.values["wear"][r] * f, ".-", ms=3, color=colour, label=label)
        ax_p.plot(prof.position, prof.values["pressure"][r], ".-", ms=3, color=colour, label=label)
    pre = _preload_row(prof)
    if pre is not None:
        ax_p.plot(prof.position, prof.values["pressure"][pre], "k--", lw=1, label="end of preload")
    ax_w.set_ylabel(f"wear gap ({unit})")
    ax_p.set_ylabel("contact pressure P_n (MPa)")
    for ax in (ax_w, ax_p):
        ax.set_xlabel("position along the surface (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2 if len(last) > 6 else 1)
    load = _load_label(scene, hist, last[-1][0], n)
    fig.suptitle(f"{scene.name}: wear gap and contact pressure at the end of the cycle (step {n}"
                 + (f", {load}" if load else "") + ")")
    fig.tight_layout()
    return _save(fig, path)


def plot_node_history(path: Path, scene: Scene, prof: ContactProfiles) -> Path | None:
    """State of the tracked nodes over the steps of up to three snapshot cycles (paper Figs. 8-9).

    One column per (node, cycle) with the first, a middle and the last kept cycle; three rows: the
    normal gap x_n, the slip increment Δx_t and the contact tractions P_n, P_t. The background of every
    panel is coloured by the contact state of the node at each step (open, stick, slip).

    Args:
        path: PNG file.
        scene: The run's scene.
        prof: Contact profiles.

    Returns:
        ``path``, or ``None`` when no cycle was kept.
    """
    from matplotlib.patches import Patch

    cycles = _snapshot_cycles(prof)
    if not cycles:
        return None
    shown = list(dict.fromkeys([cycles[0], cycles[len(cycles) // 2], cycles[-1]]))
    nodes = tracked_nodes(scene, prof)
    n = scene.loading.increments_per_cycle
    columns = [(j, c) for j in nodes for c in shown]
    rows_of = {c: prof.rows_of_cycle(c) for c in shown}
    gap, slip = prof.values["gap"], prof.values["slip"]
    fg, ug = _length_unit(np.concatenate([gap[rows_of[c], j] for j, c in columns]))
    fs, us = _length_unit(np.concatenate([slip[rows_of[c], j] for j, c in columns]))
    ncol = len(columns)
    fig = _figure((max(3.4 * ncol, 7.0), 8.2))
    axes = fig.subplots(3, ncol, sharex=True, sharey="row", squeeze=False)
    for k, (j, c) in enumerate(columns):
        rows = rows_of[c]
        steps = prof.steps[rows]
        states = prof.values["state"][rows, j]
        ax_g, ax_s, ax_p = axes[:, k]
        for ax in axes[:, k]:
            _shade_states(ax, steps, states)
            _quarter_lines(ax, n)
            ax.axhline(0.0, color="k", lw=0.5, zorder=1)
            ax.grid(alpha=0.3)
        ax_g.plot(steps, gap[rows, j] * fg, "k.-", ms=3, lw=1)
        ax_s.plot(steps, slip[rows, j] * fs, "k.-", ms=3, lw=1)
        ax_p.plot(steps, prof.values["pressure"][rows, j], ".-", ms=3, lw=1, color="tab:red", label="P_n")
        ax_p.plot(steps, prof.values["shear"][rows, j], ".-", ms=3, lw=1, color="tab:purple", label="P_t")
        ax_g.set_title(f"x = {prof.position[j]:.3g} mm, cycle {c}", fontsize=9)
        ax_p.set_xlabel(f"step in the cycle (of {n})")
        ax_p.set_xlim(0.5, n + 0.5)
        if k == 0:
            ax_g.set_ylabel(f"normal gap x_n ({ug})")
            ax_s.set_ylabel(f"slip increment Δx_t ({us})")
            ax_p.set_ylabel("P_n, P_t (MPa)")
            ax_p.legend(fontsize=8, loc="best")
    handles = [Patch(color=STATE_COLORS[s], alpha=0.5, label=STATE_NAMES[s]) for s in (0, 1, 2)]
    fig.legend(handles=handles, loc="upper right", ncol=3, fontsize=9, title="state", title_fontsize=9)
    fig.suptitle(f"{scene.name}: contact state of tracked nodes over a cycle", x=0.02, ha="left")
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    return _save(fig, path)


def _loop_displacement(scene: Scene, hist: _History) -> tuple[np.ndarray, str]:
    if scene.loading.tangential_kind == "displacement":
        return hist.t["tangential_displacement"], "tangential displacement of the obstacle"
    return hist.t["mean_relative_tangential"], "mean relative tangential displacement"


def plot_fretting_loops(path: Path, scene: Scene, hist: _History) -> Path | None:
    """Tangential contact force against displacement over the loop cycles (``history.csv``).

    The cycles are ``scene.output.loop_cycles`` found in the table, else up to four cycles spread over
    those present. Each loop starts at the last row before its cycle (the end of the previous cycle or
    of the preload), so it is closed.

    Args:
        path: PNG file.
        scene: The run's scene.
        hist: ``history.csv``.

    Returns:
        ``path``, or ``None`` when the table has no cyclic row.
    """
    import matplotlib

    present = [int(c) for c in hist.cycles() if c >= 1]
    if not present:
        return None
    wanted = [c for c in scene.output.loop_cycles if c in present]
    if not wanted:
        idx = np.unique(np.linspace(0, len(present) - 1, min(4, len(present))).round().astype(int))
        wanted = [present[i] for i in idx]
    x_all, what = _loop_displacement(scene, hist)
    loops = []
    for c in wanted:
        rows = hist.cycle_rows(c)
        before = np.flatnonzero(hist.t["increment"] == hist.t["increment"][rows[0]] - 1)
        if before.size:
            rows = np.concatenate([before[-1:], rows])
        loops.append((c, rows))
    f, unit = _length_unit(np.concatenate([x_all[r] for _, r in loops]))
    cmap = matplotlib.colormaps["viridis"]
    fig = _figure((7, 5.2))
    ax = fig.subplots()
    for k, (c, rows) in enumerate(loops):
        colour = cmap(k / max(len(loops) - 1, 1) * 0.9)
        ax.plot(x_all[rows] * f, hist.t["tangential_force"][rows], ".-", ms=3, lw=1.2, color=colour,
                label=f"cycle {c}")
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel(f"{what} ({unit})")
    ax.set_ylabel("tangential contact force Q (N/mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{scene.name}: fretting loops")
    fig.tight_layout()
    return _save(fig, path)


def plot_wear_growth(path: Path, scene: Scene, cycles: dict[str, np.ndarray]) -> Path | None:
    """Maximum wear depth, wear area and dissipated energy per cycle against the cycle (``cycles.csv``).

    The x axis is ``equivalent_cycles`` (physical cycles: simulated cycles times ``wear.acceleration``).

    Args:
        path: PNG file.
        scene: The run's scene.
        cycles: ``cycles.csv`` as read by :func:`read_table`.

    Returns:
        ``path``, or ``None`` when the table has no row.
    """
    if not cycles or cycles.get("cycle", np.zeros(0)).size == 0:
        return None
    x = cycles["equivalent_cycles"]
    style = ".-" if x.size <= 200 else "-"
    depth = cycles["max_wear_depth"]
    f, unit = _length_unit(depth)
    fig = _figure((7, 8))
    ax_d, ax_a, ax_e = fig.subplots(3, 1, sharex=True)
    ax_d.plot(x, depth * f, style, ms=3, color="tab:red")
    ax_d.set_ylabel(f"max wear depth ({unit})")
    ax_a.plot(x, cycles["wear_area"], style, ms=3, color="tab:blue")
    ax_a.set_ylabel("wear area (mm²)")
    ax_e.plot(x, cycles["dissipated_energy"], style, ms=3, color="tab:green")
    ax_e.set_ylabel("dissipated energy per cycle\n(N·mm/mm)")
    ax_e.set_xlabel("cycles (equivalent physical cycles)")
    for ax in (ax_d, ax_a, ax_e):
        ax.grid(alpha=0.3)
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4), useMathText=True)
    ax_d.set_ylim(bottom=0)
    ax_a.set_ylim(bottom=0)
    acc = scene.wear.acceleration
    fig.suptitle(f"{scene.name}: wear growth" + (f" (wear acceleration {acc:g})" if acc != 1 else ""))
    fig.tight_layout()
    return _save(fig, path)


def _plot_profiles(out: Path, scene: Scene, prof: ContactProfiles, hist: _History) -> Path | None:
    """``profiles.png``: pressure and shear at the end of the preload and at the last kept increment."""
    from .analytic import hertz_pressure
    from .io import plot_profiles

    pre = scene.loading.normal_increments
    chosen = [i for i in (pre, int(prof.increments.max())) if prof.index(i) is not None]
    if not chosen:
        chosen = [int(prof.increments.max())]
    curves = []
    for inc in dict.fromkeys(chosen):
        r = prof.index(inc)
        label = "end of preload" if inc == pre else "final"
        curves.append((f"{label} (inc {inc})", prof.values["pressure"][r], prof.values["shear"][r]))
    reference = None
    g = scene.geometry
    r = hist.row(0, 0) if scene.loading.cycles > 0 else None
    pre_rows = np.flatnonzero(hist.t["increment"] == pre) if hist.n else np.zeros(0, int)
    if g.kind == "half_cylinder" and pre_rows.size:
        P = float(hist.t["normal_force"][pre_rows[-1]])
        xs = np.linspace(prof.position.min(), prof.position.max(), 400)
        reference = ("Hertz, frictionless, end of preload", xs,
                     hertz_pressure(xs, P, g.radius, scene.material.E / (1 - scene.material.nu**2)))
    del r
    path = out / "profiles.png"
    plot_profiles(path, prof.position, curves, reference, title=f"{scene.name}: contact tractions")
    return path


def plot_run(out: Path, scene: Scene) -> list[Path]:
    """Write the run's PNGs into ``out`` (see the module docstring for the list).

    Never raises: a picture whose data are missing is skipped, one that fails is skipped with a
    :class:`RuntimeWarning` naming it.

    Args:
        out: The run's output folder.
        scene: The run's scene.

    Returns:
        The PNG files written.
    """
    out = Path(out)
    written: list[Path] = []

    def attempt(name: str, draw: Callable[[], Path | None]) -> None:
        try:
            path = draw()
        except Exception as exc:  # noqa: BLE001 - a failed picture must not stop the others
            warnings.warn(f"{scene.name}: {name} not drawn: {type(exc).__name__}: {exc}", RuntimeWarning,
                          stacklevel=2)
            return
        if path is not None:
            written.append(path)

    try:
        prof = read_profiles(out / "contact_profiles.csv")
        hist = _History(read_table(out / "history.csv"))
        cycles = read_table(out / "cycles.csv") if scene.loading.cycles > 0 else {}
    except Exception as exc:  # noqa: BLE001 - unreadable tables: no pictures, but no failure either
        warnings.warn(f"{scene.name}: output tables not readable, no pictures: {type(exc).__name__}: {exc}",
                      RuntimeWarning, stacklevel=2)
        return written

    if prof is not None:
        attempt("profiles.png", lambda: _plot_profiles(out, scene, prof, hist))
    if scene.loading.cycles > 0:
        if prof is not None:
            attempt("wear_first_cycle.png",
                    lambda: plot_wear_first_cycle(out / "wear_first_cycle.png", scene, prof, hist))
            attempt("wear_evolution.png",
                    lambda: plot_wear_evolution(out / "wear_evolution.png", scene, prof, hist))
            attempt("node_history.png", lambda: plot_node_history(out / "node_history.png", scene, prof))
        if hist.n:
            attempt("fretting_loops.png", lambda: plot_fretting_loops(out / "fretting_loops.png", scene, hist))
        if cycles:
            attempt("wear_growth.png", lambda: plot_wear_growth(out / "wear_growth.png", scene, cycles))
    return written

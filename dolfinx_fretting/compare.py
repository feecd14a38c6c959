"""Side-by-side pictures and a summary table of several finished runs (paper section 8.2, Figs. 13-19).

The paper compares an elastic and an elastic-plastic cylinder-on-flat run; :func:`compare_runs` draws the
same comparison from any number of output folders (``summary.json``, ``history.csv``, ``cycles.csv``,
``contact_profiles.csv``, see :mod:`dolfinx_fretting.io`), read back with the tolerant readers of
:mod:`dolfinx_fretting.contact_output`, so partly written folders work too.

Files written into the output folder:

* ``compare_first_cycle.png`` (Figs. 13/17): wear gap and contact pressure along the surface at the last
  kept step of cycle 1, one colour per run; the end-of-preload pressure dashed.
* ``compare_cycles.png`` (Figs. 15/16/18/19): wear gap and pressure at the end of chosen cycles, one
  colour per cycle and one line style per run.
* ``compare_node_history.png`` (Fig. 14): the node nearest to a position, over the steps of cycle 1 (step
  0: end of the preload): normal gap, slip increment, P_n, P_t and the contact state, runs overlaid.
* ``compare_summary.csv``: one row per run (:data:`SUMMARY_FIELDS`).

Every picture names the obstacle of the runs (``summary.json``'s ``obstacle``: in the built-in scenes the
flat is a rigid plane, not the paper's second elastic body). A picture whose data are missing in every
run is skipped with a :class:`RuntimeWarning`; a run missing from one picture is named in a warning.

A run that did not end converged (:data:`RUN_STATUSES`: ``failed``, ``interrupted``, or ``incomplete``: no
``summary.json``, a crashed or killed run) is marked as such in the table (its ``status``), in the pictures' legends
(``label [status]``) and in a :class:`RuntimeWarning` with the reason; its values are its last written ones.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .contact_output import STATE_NAMES, ContactProfiles, read_profiles, read_table
from .outdir import OutputFolderError, ensure_writable_folder
from .output import OBSTACLE_TEXT, RunDescription, read_description
from .plots import _figure, _length_unit, _mm, _save

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["compare_runs", "load_run", "RunData", "default_label", "run_status", "summary_rows", "read_summary_csv",
           "format_table", "RUN_STATUSES",
           "SUMMARY_FIELDS", "COMPARE_PICTURES"]

#: Columns of ``compare_summary.csv`` (``status``: :data:`RUN_STATUSES`).
SUMMARY_FIELDS = ["label", "material_model", "status", "max_pressure", "max_wear_depth", "wear_area",
                  "dissipated_energy", "max_equivalent_plastic_strain", "contact_width", "wall_time_s",
                  "cycles", "equivalent_cycles"]
#: What a run's folder says of its end (:attr:`RunData.status`): ``converged``; ``failed`` (its summary says
#: ``converged: false``, with the error); ``interrupted`` (SIGINT or SIGTERM: a checkpoint to resume from);
#: ``incomplete`` (no readable ``summary.json``: the run crashed, was killed or is still running, or a summary without
#: ``converged``). The values of a run that is not ``converged`` are those of its last written increment or cycle.
RUN_STATUSES = ("converged", "failed", "interrupted", "incomplete")
#: PNG files :func:`compare_runs` writes when every run has the data.
COMPARE_PICTURES = ("compare_first_cycle.png", "compare_cycles.png", "compare_node_history.png")
#: Names of the material models in the default labels.
_MODEL_NAMES = {"elastic": "elastic", "elastoplastic": "elastic-plastic"}
#: At most this many cycles in ``compare_cycles.png`` when they are not chosen explicitly.
_MAX_DEFAULT_CYCLES = 8
#: Lengths (mm) below this are round-off of the contact solver (gaps and slips of closed/sticking nodes).
_ROUND_OFF = 1e-9
#: Colours of the contact states (as in :mod:`dolfinx_fretting.plots`).
_STATE_COLORS = {0: "#d9d9d9", 1: "#4c9be8", 2: "#f28e2b"}
_RUN_COLORS = ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive",
               "tab:cyan", "tab:gray", "tab:orange")
_RUN_STYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (8, 2)))
_RUN_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "<", ">")


@dataclass(eq=False)
class RunData:
    """One run's output folder read back.

    Attributes:
        folder: The output folder.
        label: Its name in the pictures and the table.
        summary: ``summary.json`` (empty when missing or unreadable).
        profiles: ``contact_profiles.csv`` (``None`` when missing or without a complete increment).
        history: ``history.csv`` as columns (empty when missing).
        cycles: ``cycles.csv`` as columns (empty when missing).
        description: ``run.json`` (what was modelled, as data), or None for a folder of an older release.
    """

    folder: Path
    label: str
    summary: dict[str, Any] = field(default_factory=dict)
    profiles: ContactProfiles | None = None
    history: dict[str, np.ndarray] = field(default_factory=dict)
    cycles: dict[str, np.ndarray] = field(default_factory=dict)
    description: RunDescription | None = None

    @property
    def status(self) -> str:
        """How the run ended, one of :data:`RUN_STATUSES`, read from ``summary.json``."""
        return run_status(self.summary)[0]

    @property
    def status_reason(self) -> str:
        """Why a run is not ``converged`` (its summary's error, or what is missing); empty if it is."""
        return run_status(self.summary)[1]

    @property
    def increments_per_cycle(self) -> int:
        """Steps of a cycle: the largest step of a cyclic row in ``history.csv`` or the profiles (0: none)."""
        n = 0
        h = self.history
        if h.get("step", np.zeros(0)).size:
            cyc = h["cycle"] >= 1
            if np.any(cyc):
                n = int(np.nanmax(h["step"][cyc]))
        p = self.profiles
        if p is not None and np.any(p.cycles >= 1):
            n = max(n, int(p.steps[p.cycles >= 1].max()))
        return n

    def kept_cycles(self) -> list[int]:
        """Cycles (>= 1) with kept increments in the profiles, ascending."""
        if self.profiles is None:
            return []
        return [int(c) for c in np.unique(self.profiles.cycles) if c >= 1]

    def preload_row(self) -> int | None:
        """Row of the profiles at the end of the preload (last kept increment of cycle 0)."""
        if self.profiles is None:
            return None
        rows = self.profiles.rows_of_cycle(0)
        return int(rows[-1]) if rows.size else None

    def end_row(self, cycle: int) -> int | None:
        """Row of the profiles at the last kept step of ``cycle``."""
        if self.profiles is None:
            return None
        rows = self.profiles.rows_of_cycle(cycle)
        return int(rows[-1]) if rows.size else None


def run_status(summary: dict[str, Any]) -> tuple[str, str]:
    """(status, reason) of a run from its ``summary.json`` (empty: none or unreadable), see :data:`RUN_STATUSES`."""
    if not summary:
        return "incomplete", "no summary.json: the run crashed, was killed or is still running"
    error = str(summary.get("error") or "")
    if summary.get("interrupted"):
        return "interrupted", error or f"interrupted by {summary['interrupted']}"
    if summary.get("converged") is True:
        return "converged", ""
    if summary.get("converged") is False:
        return "failed", error or "summary.json says converged: false"
    return "incomplete", "summary.json does not say whether the run converged"


def default_label(summary: dict[str, Any], folder: Path) -> str:
    """``elastic`` / ``elastic-plastic`` (from ``material_model``) plus `` k x100`` when ``wear_acceleration``
    is not 1; the folder name when the summary has no material model."""
    model = summary.get("material_model")
    label = _MODEL_NAMES.get(str(model), str(model)) if model else Path(folder).name
    acc = summary.get("wear_acceleration")
    try:
        acc = float(acc) if acc is not None else 1.0
    except (TypeError, ValueError):
        acc = 1.0
    if math.isfinite(acc) and acc != 1.0:
        label += f" k x{acc:g}"
    return label


def load_run(folder: str | Path, label: str | None = None) -> RunData:
    """Read one output folder.

    Raises:
        ValueError: The folder does not exist, or has neither ``summary.json`` nor a readable
            ``contact_profiles.csv`` (the message names the folder).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such output folder")
    summary: dict[str, Any] = {}
    spath = folder / "summary.json"
    if spath.is_file():
        try:
            with open(spath, encoding="utf-8") as f:
                data = json.load(f)
            if isinstance(data, dict):
                summary = data
            else:
                warnings.warn(f"{spath}: not a JSON object, ignored", RuntimeWarning, stacklevel=2)
        except (OSError, ValueError) as exc:
            warnings.warn(f"{spath}: not readable ({exc}), ignored", RuntimeWarning, stacklevel=2)
    profiles = read_profiles(folder / "contact_profiles.csv")
    if not summary and profiles is None:
        raise ValueError(f"{folder}: not a run's output folder (no readable summary.json and no "
                         f"contact_profiles.csv)")
    return RunData(folder=folder, label=label if label is not None else default_label(summary, folder),
                   summary=summary, profiles=profiles, history=read_table(folder / "history.csv"),
                   cycles=read_table(folder / "cycles.csv"), description=read_description(folder))


# Summary table --------------------------------------------------------------------------------------------
def _number(value: Any) -> float | None:
    """A finite float, or ``None`` (missing, text, NaN)."""
    if value is None or isinstance(value, (bool, str)):
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _last(table: dict[str, np.ndarray], name: str) -> float | None:
    col = table.get(name)
    if col is None or col.size == 0:
        return None
    return _number(col[-1])


def _total(table: dict[str, np.ndarray], name: str) -> float | None:
    col = table.get(name)
    if col is None or col.size == 0:
        return None
    return _number(np.nansum(np.asarray(col, dtype=float)))


def summary_rows(runs: Sequence[RunData]) -> list[dict[str, Any]]:
    """One row of :data:`SUMMARY_FIELDS` per run.

    Values come from ``summary.json``; a value it lacks (an interrupted run) is taken from the last row of
    ``cycles.csv`` (``max_pressure_end``, ``max_wear_depth``, ``wear_area``, ``cycle``,
    ``equivalent_cycles``; sums of ``dissipated_energy`` and ``wall_time_s``), then from the last row of
    ``history.csv``. ``max_equivalent_plastic_strain`` is ``None`` for an elastic run; a value found
    nowhere is ``None`` (a blank cell in the CSV).
    """
    out = []
    for run in runs:
        s, cyc, hist = run.summary, run.cycles, run.history

        def pick(*candidates: Callable[[], float | None]) -> float | None:
            for c in candidates:
                v = c()
                if v is not None:
                    return v
            return None

        model = s.get("material_model")
        plastic = None if model == "elastic" else _number(s.get("max_equivalent_plastic_strain"))
        cycles = pick(lambda: _number(s.get("cycles")), lambda: _last(cyc, "cycle"))
        out.append({
            "label": run.label,
            "material_model": model if model is not None else "",
            "status": run.status,
            "max_pressure": pick(lambda: _number(s.get("max_pressure")),
                                 lambda: _last(cyc, "max_pressure_end"),
                                 lambda: _last(hist, "max_pressure")),
            "max_wear_depth": pick(lambda: _number(s.get("max_wear_depth")),
                                   lambda: _last(cyc, "max_wear_depth"),
                                   lambda: _last(hist, "max_wear_depth")),
            "wear_area": pick(lambda: _number(s.get("wear_area")), lambda: _last(cyc, "wear_area"),
                              lambda: _last(hist, "wear_area")),
            "dissipated_energy": pick(lambda: _number(s.get("dissipated_energy")),
                                      lambda: _total(cyc, "dissipated_energy"),
                                      lambda: _total(hist, "dissipated_energy")),
            "max_equivalent_plastic_strain": plastic,
            "contact_width": pick(lambda: _number(s.get("contact_width")),
                                  lambda: _last(hist, "contact_width")),
            "wall_time_s": pick(lambda: _number(s.get("wall_time_s")), lambda: _total(cyc, "wall_time_s")),
            "cycles": int(cycles) if cycles is not None else None,
            "equivalent_cycles": pick(lambda: _number(s.get("equivalent_cycles")),
                                      lambda: _last(cyc, "equivalent_cycles")),
        })
    return out


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(float(value))  # a numpy 2 float64's repr is "np.float64(...)"
    return str(value)


def _write_summary_csv(path: Path, rows: list[dict[str, Any]]) -> Path:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(SUMMARY_FIELDS)
        for r in rows:
            w.writerow([_cell(r[k]) for k in SUMMARY_FIELDS])
    return path


def read_summary_csv(path: str | Path) -> list[dict[str, Any]]:
    """Rows of a ``compare_summary.csv`` (blank cells ``None``, ``cycles`` int, other numbers float)."""
    rows = []
    with open(path, newline="", encoding="utf-8") as f:
        for raw in csv.DictReader(f):
            row: dict[str, Any] = {}
            for k in SUMMARY_FIELDS:
                v = raw.get(k, "")
                if k in ("label", "material_model", "status"):
                    row[k] = v or ""
                elif v in ("", None):
                    row[k] = None
                elif k == "cycles":
                    row[k] = int(float(v))
                else:
                    row[k] = float(v)
            rows.append(row)
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """The summary rows as an aligned text table (4 significant digits)."""
    heads = {"label": "label", "material_model": "material", "status": "status", "max_pressure": "p_max MPa",
             "max_wear_depth": "wear depth mm", "wear_area": "wear area mm2", "dissipated_energy": "energy",
             "max_equivalent_plastic_strain": "max eps_p", "contact_width": "width mm",
             "wall_time_s": "wall s",
             "cycles": "cycles", "equivalent_cycles": "equiv."}

    def fmt(v: Any) -> str:
        if v is None or v == "":
            return "-"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    table = [[heads[k] for k in SUMMARY_FIELDS]] + [[fmt(r[k]) for k in SUMMARY_FIELDS] for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(SUMMARY_FIELDS))]
    lines = []
    for k, row in enumerate(table):
        cells = [c.ljust(w) if i < 3 else c.rjust(w) for i, (c, w) in enumerate(zip(row, widths))]
        lines.append("  ".join(cells).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


# Pictures: helpers ----------------------------------------------------------------------------------------
def _obstacle_note(runs: Sequence[RunData]) -> str:
    """The obstacle of the runs for a subtitle (one text when all runs agree, else per run)."""
    texts = {r.label: OBSTACLE_TEXT[r.description.obstacle] if r.description is not None
             else str(r.summary["obstacle"]) for r in runs if r.description is not None or r.summary.get("obstacle")}
    if not texts:
        return "obstacle: not recorded (no run.json)"
    unique = list(dict.fromkeys(texts.values()))
    if len(unique) == 1 and len(texts) == len(runs):
        return f"obstacle: {unique[0]}"
    return "obstacle: " + "; ".join(f"{k}: {v}" for k, v in texts.items())


def _titles(fig: Figure, title: str, runs: Sequence[RunData], extra: str = "") -> None:
    """Title (after the scene name when all runs share it) and, under it in a smaller font, the obstacle
    note (and ``extra``)."""
    h = fig.get_figheight()
    scenes = {str(r.summary.get("scene")) for r in runs}
    if len(scenes) == 1 and all(r.summary.get("scene") for r in runs):
        title = f"{scenes.pop()}: {title[0].lower()}{title[1:]}"
    fig.suptitle(title, fontsize=12, y=1 - 0.1 / h, va="top")
    note = _obstacle_note(runs) + (f"\n{extra}" if extra else "")
    fig.text(0.5, 1 - 0.42 / h, note, ha="center", va="top", fontsize=8.5, color="0.3", style="italic")


def _acceleration_note(runs: Sequence[RunData]) -> str:
    acc = {r.label: _number(r.summary.get("wear_acceleration")) for r in runs}
    fast = {k: v for k, v in acc.items() if v is not None and v != 1.0}
    if not fast:
        return ""
    return "wear acceleration: " + ", ".join(f"{k}: 1 simulated cycle = {v:g} physical cycles"
                                               for k, v in fast.items())


def _profile_axes(ax_w, ax_p, window, unit: str, wear_all: np.ndarray, empty_text: str) -> None:
    """Labels, grid, x window and y limits shared by the wear / pressure profile panels."""
    ax_w.set_ylabel(f"wear gap ({unit})")
    ax_p.set_ylabel("contact pressure P_n (MPa)")
    for ax in (ax_w, ax_p):
        ax.set_xlabel("position along the surface (mm)")
        ax.grid(alpha=0.3)
        if window is not None:
            ax.set_xlim(*window)
    ax_w.set_ylim(bottom=0.0 if np.nanmin(wear_all, initial=0.0) >= 0 else None)
    if not np.any(wear_all):
        ax_w.set_ylim(0.0, 1.0)
        ax_w.text(0.5, 0.6, empty_text, transform=ax_w.transAxes, ha="center", color="0.4")
    ax_p.set_ylim(bottom=0.0)


def _x_window(curves: list[tuple[np.ndarray, np.ndarray]]) -> tuple[float, float] | None:
    """x limits around the nodes where some curve is non-zero (in contact or worn), with a margin."""
    x_min, x_max, full_min, full_max = np.inf, -np.inf, np.inf, -np.inf
    for x, y in curves:
        if x.size == 0:
            continue
        full_min, full_max = min(full_min, float(x.min())), max(full_max, float(x.max()))
        on = np.flatnonzero(np.abs(np.nan_to_num(y)) > 0)
        if on.size:
            # one node beyond the last non-zero one on each side
            a, b = max(on.min() - 1, 0), min(on.max() + 1, x.size - 1)
            x_min, x_max = min(x_min, float(x[a])), max(x_max, float(x[b]))
    if not np.isfinite(full_min):
        return None
    if not np.isfinite(x_min) or x_max <= x_min:
        return full_min, full_max
    pad = 0.15 * (x_max - x_min)
    return max(full_min, x_min - pad), min(full_max, x_max + pad)


def _preload_groups(runs: Sequence[RunData]) -> list[list[RunData]]:
    """Runs grouped by equal end-of-preload pressure (same nodes, within 0.1 % of the peak), in order."""
    groups: list[list[RunData]] = []
    for r in runs:
        x, p = r.profiles.position, r.profiles.values["pressure"][r.preload_row()]
        for g in groups:
            x0, p0 = g[0].profiles.position, g[0].profiles.values["pressure"][g[0].preload_row()]
            scale = max(float(np.nanmax(np.abs(p0), initial=0.0)), 1e-300)
            if (x0.shape == x.shape and np.allclose(x0, x, atol=1e-9)
                    and float(np.nanmax(np.abs(p - p0), initial=0.0)) <= 1e-3 * scale):
                g.append(r)
                break
        else:
            groups.append([r])
    return groups


def _step_note(run: RunData, cycle: int, row: int) -> str:
    n, s = run.increments_per_cycle, int(run.profiles.steps[row])
    return "" if s == n or n == 0 else f" (step {s} of {n})"


# Pictures -------------------------------------------------------------------------------------------------
def plot_compare_first_cycle(path: Path, runs: Sequence[RunData]) -> Path | None:
    """Wear gap and pressure at the last kept step of cycle 1 of every run (paper Figs. 13/17).

    Returns:
        ``path``, or ``None`` when no run kept a step of cycle 1.
    """
    shown = [r for r in runs if r.end_row(1) is not None]
    missing = [r.label for r in runs if all(r is not x for x in shown)]
    if not shown:
        return None
    if missing:
        warnings.warn(f"compare_first_cycle.png: cycle 1 not in the contact profiles of {', '.join(missing)}",
                      RuntimeWarning, stacklevel=2)
    wear_all = np.concatenate([r.profiles.values["wear"][r.end_row(1)] for r in shown])
    f, unit = _length_unit(wear_all)
    with_pre = [r for r in shown if r.preload_row() is not None]
    groups = _preload_groups(with_pre)
    n_labels = len(shown) + len(groups)
    legend_rows = -(-n_labels // 3)
    height = 5.2 + 0.22 * legend_rows
    fig = _figure((12.5, height))
    ax_w, ax_p = fig.subplots(1, 2, gridspec_kw=dict(left=0.065, right=0.99, wspace=0.2,
                                                     top=1 - 0.95 / height,
                                                     bottom=(0.75 + 0.22 * legend_rows) / height))
    window_curves = []
    for k, r in enumerate(shown):
        row = r.end_row(1)
        prof = r.profiles
        wear, pressure = prof.values["wear"][row], prof.values["pressure"][row]
        colour, style = _RUN_COLORS[k % len(_RUN_COLORS)], _RUN_STYLES[k % len(_RUN_STYLES)]
        label = (f"{r.label}{_step_note(r, 1, row)}: max P_n {np.nanmax(pressure):.4g} MPa, "
                 f"max wear {np.nanmax(wear) * f:.3g} {unit}")
        lw = max(2.6 - 0.6 * k, 1.0)  # later runs thinner on top, so that equal stretches stay visible
        ax_w.plot(prof.position, wear * f, ls=style, marker=_RUN_MARKERS[k % len(_RUN_MARKERS)], ms=3,
                  lw=lw, color=colour, label=label)
        ax_p.plot(prof.position, pressure, ls=style, marker=_RUN_MARKERS[k % len(_RUN_MARKERS)], ms=3,
                  lw=lw, color=colour, label=label)
        window_curves += [(prof.position, wear), (prof.position, pressure)]
    for g in groups:
        prof = g[0].profiles
        p = prof.values["pressure"][g[0].preload_row()]
        window_curves.append((prof.position, p))
        if len(groups) == 1:
            who, colour = ("all runs" if len(shown) > 1 else g[0].label), "k"
        else:
            who = ", ".join(r.label for r in g) if len(g) < len(shown) else "all runs"
            colour = "k" if len(g) > 1 else _RUN_COLORS[next(i for i, r in enumerate(shown) if r is g[0])
                                                        % len(_RUN_COLORS)]
        ax_p.plot(prof.position, p, "--", lw=1, color=colour, alpha=0.85,
                  label=f"end of preload ({who}): max P_n {np.nanmax(p):.4g} MPa")
    _profile_axes(ax_w, ax_p, _x_window(window_curves), unit, wear_all, "no wear in cycle 1")
    handles, labels = ax_p.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 3), fontsize=8.5, frameon=False)
    _titles(fig, "Wear gap and contact pressure at the end of the first cycle", runs)
    return _save(fig, path)


def _choose_cycles(runs: Sequence[RunData], cycles: Sequence[int] | None) -> list[int]:
    """The cycles of ``compare_cycles.png``: the given ones, else the kept cycles all runs share (at most
    :data:`_MAX_DEFAULT_CYCLES`, spread over them, first and last included)."""
    if cycles:
        return sorted(dict.fromkeys(int(c) for c in cycles))
    common: set[int] | None = None
    for r in runs:
        kept = set(r.kept_cycles())
        if kept:
            common = kept if common is None else common & kept
    chosen = sorted(common or ())
    if len(chosen) > _MAX_DEFAULT_CYCLES:
        idx = np.unique(np.linspace(0, len(chosen) - 1, _MAX_DEFAULT_CYCLES).round().astype(int))
        chosen = [chosen[i] for i in idx]
    return chosen


def plot_compare_cycles(path: Path, runs: Sequence[RunData], cycles: Sequence[int] | None) -> Path | None:
    """Wear gap and pressure at the last kept step of chosen cycles (paper Figs. 15/16/18/19): one colour
    per cycle, one line style per run.

    Returns:
        ``path``, or ``None`` when no chosen cycle is kept by any run.
    """
    # Lazy: matplotlib (heavy) only where a picture is drawn, as in plots
    import matplotlib
    from matplotlib.lines import Line2D

    chosen = _choose_cycles(runs, cycles)
    if not chosen:
        return None
    curves = []  # (run index, cycle index, row)
    for k, r in enumerate(runs):
        absent = []
        for i, c in enumerate(chosen):
            row = r.end_row(c)
            if row is None:
                absent.append(c)
            else:
                curves.append((k, i, row))
        if absent and r.profiles is not None:
            warnings.warn(f"compare_cycles.png: {r.label}: cycle(s) {', '.join(map(str, absent))} not in its "
                          f"contact profiles", RuntimeWarning, stacklevel=2)
        elif r.profiles is None:
            warnings.warn(f"compare_cycles.png: {r.label}: no contact profiles", RuntimeWarning, stacklevel=2)
    if not curves:
        return None
    used_runs = sorted({k for k, _, _ in curves})
    used_cycles = sorted({i for _, i, _ in curves})
    wear_all = np.concatenate([runs[k].profiles.values["wear"][row] for k, _, row in curves])
    f, unit = _length_unit(wear_all)
    cmap = matplotlib.colormaps["viridis"]

    def colour(i: int) -> Any:
        pos = used_cycles.index(i)
        return cmap(pos / max(len(used_cycles) - 1, 1) * 0.9)

    n_labels = len(used_cycles) + len(used_runs)
    legend_rows = -(-n_labels // 6)
    acc_note = _acceleration_note(runs)
    top_in = 0.95 + (0.18 if acc_note else 0.0)
    height = 5.2 + 0.22 * legend_rows + (0.18 if acc_note else 0.0)
    fig = _figure((12.5, height))
    ax_w, ax_p = fig.subplots(1, 2, gridspec_kw=dict(left=0.065, right=0.99, wspace=0.2,
                                                     top=1 - top_in / height,
                                                     bottom=(0.75 + 0.22 * legend_rows) / height))
    window_curves = []
    odd_steps = []
    for k, i, row in curves:
        r = runs[k]
        prof = r.profiles
        style = _RUN_STYLES[used_runs.index(k) % len(_RUN_STYLES)]
        wear, pressure = prof.values["wear"][row], prof.values["pressure"][row]
        # earlier cycles thicker, so that the later ones drawn on top leave equal stretches visible
        lw = 3.0 - 1.8 * used_cycles.index(i) / max(len(used_cycles) - 1, 1)
        ax_w.plot(prof.position, wear * f, ls=style, lw=lw, color=colour(i))
        ax_p.plot(prof.position, pressure, ls=style, lw=lw, color=colour(i))
        window_curves += [(prof.position, wear), (prof.position, pressure)]
        note = _step_note(r, chosen[i], row)
        if note:
            odd_steps.append(f"{r.label} cycle {chosen[i]}{note}")
    if odd_steps:
        warnings.warn(f"compare_cycles.png: not the last step of the cycle: {'; '.join(odd_steps)}",
                      RuntimeWarning, stacklevel=2)
    _profile_axes(ax_w, ax_p, _x_window(window_curves), unit, wear_all, "no wear")
    handles = [Line2D([], [], color=colour(i), lw=2.2, label=f"cycle {chosen[i]}") for i in used_cycles]
    handles += [Line2D([], [], color="k", lw=1.6, ls=_RUN_STYLES[j % len(_RUN_STYLES)], label=runs[k].label)
                for j, k in enumerate(used_runs)]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), fontsize=9, frameon=False,
               handlelength=3.2)
    _titles(fig, "Wear gap and contact pressure at the end of each cycle (colour: cycle, line: run)", runs,
            acc_note)
    return _save(fig, path)


def _node_history_runs(runs: Sequence[RunData],
                       node_position: float | None) -> list[tuple[RunData, int, np.ndarray]]:
    """(run, node column, profile rows: end of preload if kept, then the steps of cycle 1) per run that
    kept cycle 1."""
    out = []
    for r in runs:
        prof = r.profiles
        if prof is None or not prof.rows_of_cycle(1).size:
            continue
        if node_position is None:
            pre = r.preload_row()
            closed = np.flatnonzero(prof.values["state"][pre] != 0) if pre is not None else np.zeros(0, int)
            pts = prof.position[closed] if closed.size else prof.position
            j = prof.nearest_node(0.5 * (float(pts.min()) + float(pts.max())))
        else:
            j = prof.nearest_node(node_position)
        rows = prof.rows_of_cycle(1)
        pre = r.preload_row()
        if pre is not None:
            rows = np.concatenate([[pre], rows])
        out.append((r, j, rows))
    return out


def plot_compare_node_history(path: Path, runs: Sequence[RunData],
                              node_position: float | None) -> Path | None:
    """The node nearest to ``node_position`` (``None``: the centre of the contact at the end of the
    preload) over cycle 1 of every run (paper Fig. 14): normal gap x_n, slip increment Δx_t (the
    ``slip`` column), P_n, P_t and the contact state per step; step 0 is the end of the preload.

    Returns:
        ``path``, or ``None`` when no run kept cycle 1.
    """
    # Lazy: matplotlib (heavy) only where a picture is drawn, as in plots
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    picks = _node_history_runs(runs, node_position)
    missing = [r.label for r in runs if all(r is not p[0] for p in picks)]
    if not picks:
        return None
    if missing:
        warnings.warn(f"compare_node_history.png: cycle 1 not in the contact profiles of "
                      f"{', '.join(missing)}",
                      RuntimeWarning, stacklevel=2)
    gap_all = np.concatenate([r.profiles.values["gap"][rows, j] for r, j, rows in picks])
    slip_all = np.concatenate([r.profiles.values["slip"][rows, j] for r, j, rows in picks])
    fg, ug = _length_unit(gap_all if np.nanmax(np.abs(gap_all), initial=0.0) > _ROUND_OFF else 0.0)
    fs, us = _length_unit(slip_all if np.nanmax(np.abs(slip_all), initial=0.0) > _ROUND_OFF else 0.0)
    if ug == "mm" and not np.nanmax(np.abs(gap_all), initial=0.0) > _ROUND_OFF:
        fg, ug = 1e3, "µm"
    n = max(r.increments_per_cycle for r, _, _ in picks)
    nr = len(picks)
    ratios = [1.0, 1.0, 1.0, 1.0, 0.16 * nr + 0.12]
    height = 2.0 * sum(ratios) + 2.2 + 0.15 * ((nr - 1) // 3)
    fig = _figure((9.5, height))
    # room on the left for the run labels of the state row
    left_in = max(1.1, 0.5 + 0.058 * max(len(r.label) for r, _, _ in picks))
    width = 8.5 + left_in
    fig.set_size_inches(width, height)
    grid = fig.add_gridspec(len(ratios), 1, height_ratios=ratios, hspace=0.1, left=left_in / width,
                            right=1 - 0.3 / width, top=1 - (1.15 + 0.15 * ((nr - 1) // 3)) / height,
                            bottom=1.05 / height)
    axes = []
    for i in range(len(ratios)):
        axes.append(fig.add_subplot(grid[i, 0], sharex=axes[0] if axes else None))
    ax_g, ax_s, ax_n, ax_t, ax_state = axes
    titles = []
    for k, (r, j, rows) in enumerate(picks):
        prof = r.profiles
        steps = prof.steps[rows].astype(float)
        steps[prof.cycles[rows] == 0] = 0.0
        colour, style = _RUN_COLORS[k % len(_RUN_COLORS)], _RUN_STYLES[k % len(_RUN_STYLES)]
        # later runs thinner on top of earlier ones, so that equal stretches stay visible
        kw = dict(ls=style, marker=_RUN_MARKERS[k % len(_RUN_MARKERS)], ms=max(4.5 - 0.8 * k, 2.5),
                  lw=max(2.4 - 0.5 * k, 1.0), color=colour)
        ax_g.plot(steps, prof.values["gap"][rows, j] * fg, **kw)
        ax_s.plot(steps, prof.values["slip"][rows, j] * fs, **kw)
        ax_n.plot(steps, prof.values["pressure"][rows, j], **kw)
        ax_t.plot(steps, prof.values["shear"][rows, j], **kw)
        states = prof.values["state"][rows, j]
        y = nr - 1 - k
        for step, state in zip(steps, states):
            ax_state.add_patch(_state_box(step, y, int(state)))
        titles.append((r.label, f"node {int(prof.nodes[j])} at x = {_mm(prof.position[j])} mm"))
    for ax in axes[:4]:
        ax.axhline(0.0, color="k", lw=0.5, zorder=1)
        ax.grid(alpha=0.3)
    for ax in axes:
        for s in (n / 4, n / 2, 3 * n / 4):
            ax.axvline(s, color="k", lw=0.6, ls=":", zorder=1)
        if ax is not ax_state:
            ax.tick_params(labelbottom=False)
    for ax, values in ((ax_g, gap_all), (ax_s, slip_all)):
        if not np.nanmax(np.abs(values), initial=0.0) > _ROUND_OFF:
            ax.set_ylim(-1.0, 1.0)
            ax.text(0.02, 0.85, "round-off only (|value| < 1e-9 mm)", transform=ax.transAxes, fontsize=8,
                    color="0.4")
    ax_g.set_ylabel(f"normal gap x_n ({ug})", fontsize=9)
    ax_s.set_ylabel(f"slip increment Δx_t ({us})", fontsize=9)
    ax_n.set_ylabel("P_n (MPa)", fontsize=9)
    ax_t.set_ylabel("P_t (MPa)", fontsize=9)
    ax_state.set_ylim(-0.5, nr - 0.5)
    ax_state.set_yticks(range(nr))
    ax_state.set_yticklabels([r.label for r, _, _ in reversed(picks)], fontsize=8.5)
    ax_state.set_ylabel("state", fontsize=9)
    ax_state.set_xlabel(f"step of cycle 1 (of {n}; 0: end of preload)" if n else "step of cycle 1")
    ticks = sorted({0, n // 4, n // 2, 3 * n // 4, n}) if n else [0]
    ax_state.set_xticks(ticks)
    ax_state.set_xlim(-0.6, max(n, 1) + 0.6)
    handles = [Line2D([], [], color=_RUN_COLORS[k % len(_RUN_COLORS)], ls=_RUN_STYLES[k % len(_RUN_STYLES)],
                      marker=_RUN_MARKERS[k % len(_RUN_MARKERS)], ms=3.5, label=r.label)
               for k, (r, _, _) in enumerate(picks)]
    handles += [Patch(color=_STATE_COLORS[s], label=STATE_NAMES[s]) for s in (0, 1, 2)]
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), fontsize=9, frameon=False,
               handlelength=3.0)
    where = "the centre of the contact" if node_position is None else f"x = {_mm(node_position)} mm"
    if len({t for _, t in titles}) == 1:
        nodes = titles[0][1] + (" in every run" if len(titles) > 1 else f" ({titles[0][0]})")
    else:
        parts = [f"{lab}: {t}" for lab, t in titles]
        nodes = "\n".join("; ".join(parts[i:i + 3]) for i in range(0, len(parts), 3))
    _titles(fig, f"Contact state of the node nearest to {where} in the first cycle", runs, nodes)
    return _save(fig, path)


def _state_box(step: float, y: float, state: int):
    from matplotlib.patches import Rectangle  # lazy: matplotlib is heavy, as above

    return Rectangle((step - 0.5, y - 0.38), 1.0, 0.76, facecolor=_STATE_COLORS.get(state, "white"),
                     edgecolor="white", lw=0.5)


# Entry point ----------------------------------------------------------------------------------------------
def _unique_labels(runs: list[RunData]) -> None:
    """Append the folder name to labels that several runs share."""
    counts: dict[str, int] = {}
    for r in runs:
        counts[r.label] = counts.get(r.label, 0) + 1
    for r in runs:
        if counts[r.label] > 1:
            r.label = f"{r.label} ({r.folder.name or r.folder})"
    seen: dict[str, int] = {}
    for r in runs:  # the same folder twice
        seen[r.label] = seen.get(r.label, 0) + 1
        if seen[r.label] > 1:
            r.label = f"{r.label} #{seen[r.label]}"


def compare_runs(folders: Sequence[str | Path], labels: Sequence[str] | None, out: str | Path,
                 cycles: Sequence[int] | None = None, node_position: float | None = 0.0) -> list[Path]:
    """Write the comparison pictures and ``compare_summary.csv`` of several runs into ``out``.

    Args:
        folders: The runs' output folders.
        labels: One name per folder; ``None``: from each ``summary.json`` (:func:`default_label`; labels
            that several runs share get the folder name appended).
        out: Output folder (created).
        cycles: Cycles of ``compare_cycles.png``; ``None``: the kept cycles all runs have in common.
        node_position: Position (mm along the surface) of the node of ``compare_node_history.png``;
            ``None``: the centre of the contact at the end of the preload.

    Returns:
        The files written (PNGs that could be drawn, then the CSV).

    Raises:
        ValueError: No folder, a label count that does not match, a folder that does not exist or has
            neither ``summary.json`` nor contact profiles, or an ``out`` that is a file, under a file or not
            writable (named in the message).
    """
    folders = [Path(f) for f in folders]
    if not folders:
        raise ValueError("no run folder to compare")
    if labels is not None:
        labels = [str(x) for x in labels]
        if len(labels) != len(folders):
            raise ValueError(f"{len(labels)} label(s) for {len(folders)} folder(s)")
    if cycles is not None:
        cycles = [int(c) for c in cycles]
        if any(c < 1 for c in cycles):
            raise ValueError(f"cycles must be >= 1, got {cycles}")
    runs = [load_run(f, labels[i] if labels is not None else None) for i, f in enumerate(folders)]
    if labels is None:
        _unique_labels(runs)
    try:  # a file, under a file, not writable: said here, not as a traceback of the first picture
        out = ensure_writable_folder(out)
    except OutputFolderError as exc:
        raise ValueError(str(exc)) from None
    for run in runs:  # never a crashed or stopped run that reads like a finished one
        if run.status != "converged":
            warnings.warn(f"{run.label} ({run.folder}): {run.status}: {run.status_reason}; its values are those of its "
                          "last written increment or cycle", RuntimeWarning, stacklevel=2)
    # the pictures name a run that is not converged by its status too
    drawn = [run if run.status == "converged" else replace(run, label=f"{run.label} [{run.status}]") for run in runs]
    written: list[Path] = []

    def attempt(name: str, draw: Callable[[], Path | None]) -> None:
        try:
            path = draw()
        except Exception as exc:  # noqa: BLE001 - a failed picture must not stop the others
            warnings.warn(f"{name} not drawn: {type(exc).__name__}: {exc}", RuntimeWarning, stacklevel=3)
            return
        if path is None:
            warnings.warn(f"{name} not drawn: no run has its data", RuntimeWarning, stacklevel=3)
        else:
            written.append(path)

    attempt("compare_first_cycle.png",
            lambda: plot_compare_first_cycle(out / "compare_first_cycle.png", drawn))
    attempt("compare_cycles.png", lambda: plot_compare_cycles(out / "compare_cycles.png", drawn, cycles))
    attempt("compare_node_history.png",
            lambda: plot_compare_node_history(out / "compare_node_history.png", drawn, node_position))
    written.append(_write_summary_csv(out / "compare_summary.csv", summary_rows(runs)))
    return written

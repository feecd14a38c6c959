"""Results on disk: ``summary.json``, ``history.csv``, contact profiles, XDMF fields and PNG plots.

Tables are written by rank 0 only, row by row and flushed, so an interrupted run leaves every finished
increment readable; ``summary.json`` is replaced atomically (write to a temporary file, then rename).
XDMF output is collective (every rank calls it).
"""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

__all__ = ["ResultWriter", "write_json_atomic", "HISTORY_FIELDS", "PROFILE_FIELDS"]

#: Columns of ``history.csv`` (one row per increment).
HISTORY_FIELDS = [
    "increment", "stage", "normal_displacement", "tangential_displacement", "normal_force",
    "tangential_force", "max_pressure", "contact_width", "stick_width", "n_open", "n_stick", "n_slip",
    "local_iterations", "local_error", "load_solves", "converged", "wall_time_s",
]
#: Columns of ``contact_profiles.csv`` (one row per contact node and increment).
PROFILE_FIELDS = ["increment", "node", "position", "gap", "pressure", "shear", "slip", "state"]


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write JSON through a temporary file and a rename, so readers never see half a file."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w") as f:
        json.dump(data, f, indent=2, default=_jsonable)
        f.write("\n")
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


class ResultWriter:
    """Writes a run's outputs into ``out_dir``.

    Args:
        out_dir: Output folder (created).
        comm: Communicator; tables and pictures are written by its rank 0.
        profiles: Write ``contact_profiles.csv``.
    """

    def __init__(self, out_dir: str | Path, comm: MPI.Comm, profiles: bool = True):
        self.out = Path(out_dir)
        self.comm = comm
        self.rank0 = comm.rank == 0
        if self.rank0:
            self.out.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        self._history = self._profiles = None
        if self.rank0:
            self._history_file = open(self.out / "history.csv", "w", newline="")
            self._history = csv.DictWriter(self._history_file, fieldnames=HISTORY_FIELDS)
            self._history.writeheader()
            if profiles:
                self._profiles_file = open(self.out / "contact_profiles.csv", "w", newline="")
                self._profiles = csv.writer(self._profiles_file)
                self._profiles.writerow(PROFILE_FIELDS)
        self._xdmf_path = self.out / "fields.xdmf"
        self._xdmf_started = False

    def history_row(self, row: dict[str, Any]) -> None:
        if self._history is not None:
            self._history.writerow({k: row[k] for k in HISTORY_FIELDS})
            self._history_file.flush()

    def profile_rows(self, increment: int, position: np.ndarray, gap: np.ndarray, pressure: np.ndarray,
                     shear: np.ndarray, slip: np.ndarray, state: np.ndarray) -> None:
        if self._profiles is not None:
            for i in range(position.size):
                self._profiles.writerow([increment, i, f"{position[i]:.10g}", f"{gap[i]:.10g}",
                                         f"{pressure[i]:.10g}", f"{shear[i]:.10g}", f"{slip[i]:.10g}",
                                         int(state[i])])
            self._profiles_file.flush()

    def fields(self, t: float, functions: list) -> None:
        """Append functions at time ``t`` to ``fields.xdmf`` (collective); the file is closed after each
        write so what is on disk is always complete."""
        from dolfinx.io import XDMFFile

        msh = functions[0].function_space.mesh
        mode = "a" if self._xdmf_started else "w"
        with XDMFFile(self.comm, str(self._xdmf_path), mode) as f:
            if not self._xdmf_started:
                f.write_mesh(msh)
            for fn in functions:
                f.write_function(fn, t)
        self._xdmf_started = True

    def summary(self, data: dict[str, Any]) -> None:
        if self.rank0:
            write_json_atomic(self.out / "summary.json", data)

    def close(self) -> None:
        if self.rank0:
            self._history_file.close()
            if self._profiles is not None:
                self._profiles_file.close()


def plot_profiles(path: Path, position: np.ndarray, curves: list[tuple[str, np.ndarray, np.ndarray]],
                  reference: tuple[str, np.ndarray, np.ndarray] | None = None, title: str = "") -> None:
    """Pressure and shear traction along the contact (matplotlib, PNG).

    Args:
        path: PNG file.
        position: Node positions along the surface (mm).
        curves: (label, pressure, shear) per snapshot.
        reference: Optional (label, x, pressure) closed form drawn dashed.
        title: Figure title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_p, ax_s) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for label, p, s in curves:
        ax_p.plot(position, p, ".-", ms=3, label=label)
        ax_s.plot(position, s, ".-", ms=3, label=label)
    if reference is not None:
        ax_p.plot(reference[1], reference[2], "k--", lw=1, label=reference[0])
    ax_p.set_ylabel("contact pressure p (MPa)")
    ax_s.set_ylabel("shear traction q (MPa)")
    ax_s.set_xlabel("position along the surface (mm)")
    for ax in (ax_p, ax_s):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

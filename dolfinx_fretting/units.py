"""The units a model's numbers are in, for labels only: the solver is unit-agnostic.

A :class:`Units` holds three names (length, force, stress) and derives the others a fretting run writes: the
contact force of a 2D plane-strain model (force per unit length of thickness), the dissipated energy, the worn
area or volume, the wear coefficient (1/stress). The numbers are never converted; only the labels of
``run.json``, ``summary.json`` and the plots read them::

    Units.mm_N_MPa()                                 # the built-in scenes: mm, N, MPa
    Units.si()                                       # m, N, Pa
    Units(length="in", force="lbf", stress="psi")    # your own names: not checked

Archard's coefficient k must then be in 1/stress of the same system (``k p |slip|`` is a length).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Units"]

#: Known names and their factor to SI, for the consistency check and the length ladder of the plots.
_LENGTH_SI = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6, "um": 1e-6, "nm": 1e-9}
_FORCE_SI = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "MN": 1e6}
_STRESS_SI = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}
#: Lengths a plot may rescale to (factor 1e3 each), largest first.
_LADDER = ("m", "mm", "µm", "nm")


@dataclass(frozen=True)
class Units:
    """The names of the units of a model's numbers (labels only; nothing is converted).

    Attributes:
        length: Unit of lengths (coordinates, gaps, slips, wear depths).
        force: Unit of forces (a 3D contact force; in 2D plane strain the contact force is per unit length of
            thickness: :meth:`contact_force`).
        stress: Unit of stresses and pressures.

    The default, ``Units()``, names no unit: the dimension symbols L, F and F/L², which are true of every model.
    It is the default of :class:`~dolfinx_fretting.output.RunDescription` for a user's own model, whose units
    the package cannot know (labelling it mm would claim what nobody declared); the scene runner passes
    :meth:`mm_N_MPa` explicitly.

    When all three names are known SI multiples (m, cm, mm, µm; N, kN, mN, MN; Pa, kPa, MPa, GPa) the stress must
    be force / length² (``Units("mm", "N", "Pa")`` is refused); other names are free strings and are not
    checked.
    """

    length: str = "L"
    force: str = "F"
    stress: str = "F/L²"

    def __post_init__(self) -> None:
        for name in ("length", "force", "stress"):
            value = getattr(self, name)
            if not isinstance(value, str) or not value.strip():
                raise ValueError(f"Units.{name} must be a non-empty string, got {value!r}")
        if self.length in _LENGTH_SI and self.force in _FORCE_SI and self.stress in _STRESS_SI:
            expected = _FORCE_SI[self.force] / _LENGTH_SI[self.length] ** 2
            if not np.isclose(_STRESS_SI[self.stress], expected, rtol=1e-9, atol=0.0):
                raise ValueError(f"Units({self.length!r}, {self.force!r}, {self.stress!r}): the stress of "
                                 f"{self.force}/{self.length}² is not {self.stress}")

    @classmethod
    def mm_N_MPa(cls) -> Units:
        """The built-in scenes' units: mm, N, MPa (N/mm² = MPa)."""
        return cls(length="mm", force="N", stress="MPa")

    @classmethod
    def si(cls) -> Units:
        """SI: m, N, Pa."""
        return cls(length="m", force="N", stress="Pa")

    @property
    def declared(self) -> bool:
        """Whether these are named units (not the default dimension symbols)."""
        return self != Units()

    # Derived labels ---------------------------------------------------------------------------------------
    def contact_force(self, dim: int) -> str:
        """Unit of a contact force: per unit length of thickness in 2D plane strain (N/mm), a force in 3D (N)."""
        return f"{self.force}/{self.length}" if dim == 2 else self.force

    def energy(self, dim: int) -> str:
        """Unit of a dissipated energy (N·mm; per mm of thickness in 2D: N·mm/mm)."""
        work = f"{self.force}·{self.length}"
        return f"{work}/{self.length}" if dim == 2 else work

    def wear_measure(self, dim: int) -> str:
        """Unit of the worn measure: an area per unit thickness in 2D (mm²/mm), a volume in 3D (mm³)."""
        return f"{self.length}²/{self.length}" if dim == 2 else f"{self.length}³"

    def area(self, dim: int) -> str:
        """Unit of a loaded measure: a length in 2D (the contact's width), an area in 3D."""
        return self.length if dim == 2 else f"{self.length}²"

    @property
    def wear_coefficient(self) -> str:
        """Unit of Archard's coefficient k: 1/stress (``k p |slip|`` is a length)."""
        stress = f"({self.stress})" if any(c in self.stress for c in "/·* ") else self.stress
        return f"1/{stress}"

    def length_scale(self, values) -> tuple[float, str]:
        """Factor and name of a length unit in which ``values`` (in :attr:`length`) read as plain numbers: steps of
        1e3 down the ladder m, mm, µm, nm while the largest ``|value|`` is below 0.1; a length not on the ladder (or the
        symbol L) is never rescaled."""
        arr = np.asarray(values, dtype=float)
        arr = arr[np.isfinite(arr)]
        m = float(np.max(np.abs(arr))) if arr.size else 0.0
        name = "µm" if self.length == "um" else self.length
        if name not in _LADDER:
            return 1.0, self.length
        k, factor = _LADDER.index(name), 1.0
        while m > 0.0 and m * factor < 0.1 and k + 1 < len(_LADDER):
            k, factor = k + 1, factor * 1e3
        return factor, _LADDER[k]

    def to_json(self, dim: int) -> dict[str, str]:
        """The ``units`` entry of ``run.json`` and ``summary.json``: the three names and the derived ones."""
        return {"length": self.length, "force": self.force, "stress": self.stress,
                "contact_force": self.contact_force(dim), "energy": self.energy(dim),
                "wear_measure": self.wear_measure(dim), "wear_coefficient": self.wear_coefficient,
                "declared": self.declared}

    @classmethod
    def from_json(cls, data: dict[str, str]) -> Units:
        return cls(length=data["length"], force=data["force"], stress=data["stress"])

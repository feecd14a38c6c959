"""The contact's laws as objects: friction (how much tangential force a contact carries before it slides) and
wear (what the wear gap gains in an increment from the contact pressure and the slip).

A friction law is any object with the :class:`FrictionLaw` protocol; :class:`Coulomb` (constant coefficient,
one value or one per contact) is the one the package ships, and a plain number given as ``mu`` to
:class:`~dolfinx_fretting.contact.Contact` means ``Coulomb(mu)``. The local solvers read the coefficient per
contact (:meth:`FrictionLaw.coefficients`).

A wear law is any object with the :class:`WearLaw` protocol; :class:`Archard` (the paper's equation 5) is the
one the package ships. The kernels that commit an increment (:func:`dolfinx_fretting.wear.commit_increment`,
the compiled cycle loop of :mod:`dolfinx_fretting.cycling`) apply the law in its rate form
``dg = c p |dx_t|`` at sliding contacts, with ``c = law.coefficient(in_cycle)``; they also keep the columns of
the increment (forces, energies, widths, state counts), which are not the law's business. Everything else
(the scene runner's cycle jumps, the writers, the tests) reads the law through its public methods.

An energy law (Fouvry's, ``dg = alpha tau |dx_t|``) has this form at sliding contacts under constant friction
(``tau = mu p``: ``c = alpha mu``), which is the room the protocol leaves for it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .settings import finite

__all__ = ["FrictionLaw", "Coulomb", "WearLaw", "Archard"]


@runtime_checkable
class FrictionLaw(Protocol):
    """What a contact needs of a friction law."""

    def coefficients(self, contacts: int) -> np.ndarray:
        """The friction coefficient of each of ``contacts`` contacts (finite, >= 0)."""

    def describe(self) -> str:
        """One line for a run's description."""


@dataclass(frozen=True)
class Coulomb:
    """Coulomb friction, ``|r_t| <= mu r_n``, with a constant coefficient: one value, or one per contact (in the
    contact set's order)."""

    mu: float | np.ndarray

    def __post_init__(self) -> None:
        try:
            values = np.asarray(self.mu, dtype=float)
        except (TypeError, ValueError):  # a string, None, a ragged list
            values = np.array(np.nan)
        if values.ndim > 1 or not np.all(np.isfinite(values)) or np.any(values < 0):
            raise ValueError(f"Coulomb.mu = {self.mu!r}: expected a finite value >= 0 (or one per contact)")

    def coefficients(self, contacts: int) -> np.ndarray:
        """``mu`` for each contact; one value per contact must be ``contacts`` values."""
        values = np.asarray(self.mu, dtype=float)
        if values.ndim == 0:
            return np.full(contacts, float(values))
        if values.shape != (contacts,):
            raise ValueError(f"Coulomb.mu: {values.size} values for {contacts} contacts (one value or one per contact)")
        return values.copy()

    def describe(self) -> str:
        """``"Coulomb, mu = 0.5"`` (the range for per-contact values)."""
        values = np.asarray(self.mu, dtype=float)
        if values.ndim == 0:
            return f"Coulomb, mu = {float(values):g}"
        return f"Coulomb, mu = {values.min():g} to {values.max():g} per contact"


@runtime_checkable
class WearLaw(Protocol):
    """What the public problem needs of a wear law.

    Attributes:
        acceleration: Each simulated cycle stands for this many physical ones (>= 1).
    """

    acceleration: float

    def coefficient(self, in_cycle: bool) -> float:
        """The rate ``c`` of ``dg = c p |dx_t|`` applied to an increment (length per pressure per slip), with
        the acceleration in a load cycle."""

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body (1 when one body wears)."""

    @property
    def body_coefficients(self) -> tuple[float, float]:
        """The physical coefficients of the slave and the master body (without acceleration)."""

    def increment(self, pressure: np.ndarray, slip_increment: np.ndarray, in_cycle: bool = False) -> np.ndarray:
        """The wear-gap increment of sliding contacts from their pressure (any shape, e.g. ``(nc,)`` or
        ``(increments, nc)``) and slip increment (the same shape and one more axis: its tangential components,
        1 in 2D, 2 in 3D)."""

    def describe(self) -> str:
        """One line for a run's description."""


@dataclass(frozen=True)
class Archard:
    """Archard's wear law, the paper's equation 5: the wear gap grows by ``k p |dx_t|`` where contacts slide.

    Give ``k`` (1/MPa with N, mm), or for two deformable bodies ``k_slave`` and ``k_master``: both see the
    same pressure and slip, the wear gap grows with their sum and each body wears its share.
    ``acceleration`` multiplies k in cycles (each simulated cycle stands for that many physical ones).
    """

    k: float | None = None
    k_slave: float | None = None
    k_master: float | None = None
    acceleration: float = 1.0

    def __post_init__(self) -> None:
        per_body = (self.k_slave is not None, self.k_master is not None)
        if any(per_body) and not all(per_body):
            raise ValueError("Archard: give both k_slave and k_master, or k alone")
        if any(per_body) and self.k is not None:
            raise ValueError("Archard: give either k or (k_slave, k_master), not both")
        if not any(per_body) and self.k is None:
            raise ValueError("Archard: k (1/MPa, finite, >= 0) is required")
        for name in ("k", "k_slave", "k_master"):
            if getattr(self, name) is not None:
                finite(f"Archard.{name}", getattr(self, name), 0.0)
        finite("Archard.acceleration", self.acceleration, 1.0)

    @property
    def k_total(self) -> float:
        """The wear gap's coefficient, ``k`` or ``k_slave + k_master``."""
        return float(self.k) if self.k is not None else float(self.k_slave + self.k_master)

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body (1 with a single ``k``)."""
        if self.k is not None or self.k_total == 0:
            return 1.0
        return float(self.k_slave) / self.k_total

    @property
    def body_coefficients(self) -> tuple[float, float]:
        """(slave, master) coefficients: ``(k, 0)`` with a single ``k``."""
        return (self.k_total, 0.0) if self.k is not None else (float(self.k_slave), float(self.k_master))

    def coefficient(self, in_cycle: bool) -> float:
        """The coefficient applied to an increment: :attr:`k_total`, times ``acceleration`` in a load cycle (each
        simulated cycle stands for that many physical ones)."""
        return self.k_total * (self.acceleration if in_cycle else 1.0)

    def increment(self, pressure: np.ndarray, slip_increment: np.ndarray, in_cycle: bool = False) -> np.ndarray:
        """``c p |dx_t|`` (:meth:`coefficient`), ``|dx_t|`` the norm of the last axis of ``slip_increment`` (its
        tangential components: both in 3D)."""
        pressure = np.asarray(pressure, dtype=float)
        slip = np.asarray(slip_increment, dtype=float)
        if slip.shape != pressure.shape + slip.shape[-1:] or slip.shape[-1] not in (1, 2):
            raise ValueError(f"Archard.increment: slip_increment of shape {slip.shape} for pressure of shape "
                             f"{pressure.shape}: expected {pressure.shape + (1,)} (2D) or {pressure.shape + (2,)} (3D)")
        return self.coefficient(in_cycle) * pressure * np.linalg.norm(slip, axis=-1)

    def describe(self) -> str:
        """``"Archard, k = ... 1/MPa x acceleration ..."``."""
        return f"Archard, k = {self.k_total} 1/MPa x acceleration {self.acceleration}"

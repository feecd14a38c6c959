"""The contact's laws as objects: friction (how much tangential force a contact carries before it slides) and
wear (what the wear gap gains in an increment from the contact pressure and the slip).

A friction law is any object with the :class:`FrictionLaw` protocol; :class:`Coulomb` (constant coefficient,
one value or one per contact) is the one the package ships, and a plain number given as ``mu`` to
:class:`~dolfinx_fretting.contact.Contact` means ``Coulomb(mu)``. The local solvers read the coefficient per
contact (:meth:`FrictionLaw.coefficients`).

A wear law is any object with the :class:`WearLaw` protocol. The package ships two:

- :class:`Archard` (the paper's equation 5): the wear gap grows by ``k p |dx_t|``, the worn volume is
  proportional to the normal force times the sliding distance;
- :class:`EnergyWear` (Fouvry's energy law, Fouvry, Kapsa & Vincent, Wear 1996): the worn volume is ``alpha``
  times the dissipated frictional energy, the wear gap grows by ``alpha tau |dx_t|``. At a sliding contact
  ``tau = mu p`` (Coulomb), so it is the rate form below with ``c = alpha mu`` per contact.

The kernels that commit an increment (:func:`dolfinx_fretting.wear.commit_increment`, the compiled cycle loop of
:mod:`dolfinx_fretting.cycling`) apply a law in its rate form ``dg = c p |dx_t|`` at sliding contacts, with each
contact's ``c`` from :meth:`WearLaw.coefficients` (given the contacts' friction coefficients); they also keep the
columns of the increment (forces, energies, widths, state counts), which are not the law's business. Everything
else (the scene runner's cycle jumps, the writers, the tests) reads the law through its public methods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .settings import finite

__all__ = ["FrictionLaw", "Coulomb", "WearLaw", "Archard", "EnergyWear"]


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

    def coefficients(self, in_cycle: bool, mu: np.ndarray) -> np.ndarray:
        """The rate ``c`` of ``dg = c p |dx_t|`` applied to an increment at each contact (length per pressure per
        slip), with the acceleration in a load cycle, given the contacts' friction coefficients ``mu``."""

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body (1 when one body wears)."""

    @property
    def body_coefficients(self) -> tuple[float, float]:
        """The physical coefficients of the slave and the master body (without acceleration)."""

    def describe(self) -> str:
        """One line for a run's description."""


class _PerBodyCoefficient:
    """What the laws with one coefficient, or one per body (``<name>``, or ``<name>_slave`` and
    ``<name>_master``), share: the check of the coefficients and each body's share of the wear gap."""

    #: The coefficient's field name (``"k"``, ``"alpha"``).
    _coefficient: str = ""
    acceleration: float

    def _given(self) -> tuple[float | None, float | None, float | None]:
        name = self._coefficient
        return getattr(self, name), getattr(self, f"{name}_slave"), getattr(self, f"{name}_master")

    def __post_init__(self) -> None:
        law, name = type(self).__name__, self._coefficient
        total, slave, master = self._given()
        per_body = (slave is not None, master is not None)
        if any(per_body) and not all(per_body):
            raise ValueError(f"{law}: give both {name}_slave and {name}_master, or {name} alone")
        if any(per_body) and total is not None:
            raise ValueError(f"{law}: give either {name} or ({name}_slave, {name}_master), not both")
        if not any(per_body) and total is None:
            raise ValueError(f"{law}: {name} (1/MPa, finite, >= 0) is required")
        for key, value in zip((name, f"{name}_slave", f"{name}_master"), (total, slave, master)):
            if value is not None:
                finite(f"{law}.{key}", value, 0.0)
        finite(f"{law}.acceleration", self.acceleration, 1.0)

    @property
    def body_coefficients(self) -> tuple[float, float]:
        """(slave, master) coefficients: ``(coefficient, 0)`` with a single one."""
        total, slave, master = self._given()
        return (float(total), 0.0) if total is not None else (float(slave), float(master))

    @property
    def slave_share(self) -> float:
        """Fraction of the wear gap worn from the slave body: its coefficient's share (1 with a single coefficient
        or when nothing wears)."""
        slave, master = self.body_coefficients
        return 1.0 if slave + master == 0 else slave / (slave + master)


@dataclass(frozen=True)
class Archard(_PerBodyCoefficient):
    """Archard's wear law, the paper's equation 5: the wear gap grows by ``k p |dx_t|`` where contacts slide.

    Give ``k`` (1/MPa with N, mm), or for two deformable bodies ``k_slave`` and ``k_master``: both see the
    same pressure and slip, the wear gap grows with their sum and each body wears its share.
    ``acceleration`` multiplies k in cycles (each simulated cycle stands for that many physical ones).
    """

    k: float | None = None
    k_slave: float | None = None
    k_master: float | None = None
    acceleration: float = 1.0
    _coefficient = "k"

    @property
    def k_total(self) -> float:
        """The wear gap's coefficient, ``k`` or ``k_slave + k_master``."""
        return sum(self.body_coefficients)

    def coefficient(self, in_cycle: bool) -> float:
        """The coefficient applied to an increment: :attr:`k_total`, times ``acceleration`` in a load cycle (each
        simulated cycle stands for that many physical ones)."""
        return self.k_total * (self.acceleration if in_cycle else 1.0)

    def coefficients(self, in_cycle: bool, mu: np.ndarray) -> np.ndarray:
        """:meth:`coefficient` at every contact (Archard's rate does not depend on friction)."""
        return np.full(np.shape(mu), self.coefficient(in_cycle))

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


@dataclass(frozen=True)
class EnergyWear(_PerBodyCoefficient):
    """Fouvry's energy wear law (Fouvry, Kapsa & Vincent 1996, Wear 200; Fouvry, Liskiewicz, Kapsa, Hannel &
    Sauger 2003, Wear 255): the worn volume is ``alpha`` times the dissipated frictional energy. Locally the wear
    gap grows by ``alpha tau |dx_t|`` where a contact slides, with ``tau = mu p`` there (Coulomb), so the rate
    ``c`` of ``dg = c p |dx_t|`` is ``alpha mu`` at each contact: the worn area (volume in 3D) of an increment is
    exactly ``alpha`` times its dissipated energy, whatever the friction coefficient.

    Give ``alpha`` (mm^3 per N mm of dissipated energy, i.e. 1/MPa, like Archard's k; 1e-5 mm^3/J is
    1e-8 1/MPa), or for two deformable bodies ``alpha_slave`` and ``alpha_master`` (each body wears its share
    ``alpha_body / (alpha_slave + alpha_master)``). ``acceleration`` multiplies alpha in cycles.
    """

    alpha: float | None = None
    alpha_slave: float | None = None
    alpha_master: float | None = None
    acceleration: float = 1.0
    _coefficient = "alpha"

    @property
    def alpha_total(self) -> float:
        """The wear gap's energy coefficient, ``alpha`` or ``alpha_slave + alpha_master``."""
        return sum(self.body_coefficients)

    def coefficients(self, in_cycle: bool, mu: np.ndarray) -> np.ndarray:
        """``alpha mu`` at each contact, times ``acceleration`` in a load cycle: at a sliding contact
        ``alpha tau |dx_t| = alpha mu p |dx_t|``."""
        return self.alpha_total * (self.acceleration if in_cycle else 1.0) * np.asarray(mu, dtype=float)

    def describe(self) -> str:
        """``"Fouvry energy law, alpha = ... 1/MPa x acceleration ..."``."""
        return f"Fouvry energy law, alpha = {self.alpha_total} 1/MPa x acceleration {self.acceleration}"

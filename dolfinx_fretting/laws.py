"""The contact's laws as objects: friction (how much tangential force a contact carries before it slides) and
wear (what the wear gap gains in an increment from the contact pressure and the slip).

A friction law is any object with the :class:`FrictionLaw` protocol. The package ships two:

- :class:`Coulomb`: a constant coefficient, one value or one per contact; a plain number given as ``mu`` to
  :class:`~dolfinx_fretting.contact.Contact` means ``Coulomb(mu)``;
- :class:`EvolvingFriction`: a coefficient that follows the load cycles committed or each contact's accumulated
  dissipated energy density (a table or the user's function), as the coefficient of many metal pairs rises from
  about 0.2 to 0.8 over the first cycles while the oxide films wear through.

The local solvers read each contact's coefficient from the state an increment starts from
(:func:`dolfinx_fretting.friction.coefficients`): a constant law's :meth:`FrictionLaw.coefficients`, an evolving
law's :meth:`EvolvingFriction.at` of the state's cycles or energy.

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

from dataclasses import dataclass, field
from typing import Callable, Protocol, Sequence, runtime_checkable

import numpy as np

from .settings import finite

__all__ = ["FrictionLaw", "Coulomb", "EvolvingFriction", "FRICTION_VARIABLES", "WearLaw", "Archard", "EnergyWear"]


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


#: What an :class:`EvolvingFriction` coefficient follows: the load cycles committed (physical ones: each simulated
#: cycle counts the wear law's acceleration), or each contact's accumulated dissipated energy per unit area.
FRICTION_VARIABLES = ("cycles", "energy")


@dataclass(frozen=True)
class EvolvingFriction:
    """Coulomb friction whose coefficient evolves with the load cycles or with the dissipated energy.

    ``mu`` is a table ``((x0, mu0), (x1, mu1), ...)`` with strictly increasing abscissae, interpolated piecewise
    linearly and held at its end values outside them, or a function of the variable (a NumPy array, one value per
    contact) returning the coefficients (finite, >= 0). ``variable`` says what x is:

    - ``"cycles"``: the load cycles committed (:attr:`~dolfinx_fretting.state.ContactState.cycles`: every
      :meth:`~dolfinx_fretting.problem.FrettingProblem.run_cycle` result committed, each counting the wear law's
      acceleration: the physical cycles it stands for). One value for the whole zone, held over a cycle.
    - ``"energy"``: each contact's accumulated dissipated frictional energy per unit area
      (:attr:`~dolfinx_fretting.state.ContactState.friction_energy`; N mm / mm^2 = N/mm with N, mm, i.e. kJ/m^2),
      counting the acceleration in cycles likewise.

    The update is explicit: an increment is solved with the coefficients of the state it starts from, and its
    commit updates the variable. Held within the increment, the local problem stays the plain Coulomb one the
    solvers converge on (an implicit coefficient would make it a fixed point in mu as well); the error is one
    increment's change of mu, which the increments of a cycle keep small.

    Example:
        ``Contact(V, surface, obstacle, mu=EvolvingFriction([(0, 0.2), (5, 0.8)], variable="cycles"))``
    """

    mu: Sequence[Sequence[float]] | Callable[[np.ndarray], np.ndarray]
    variable: str = "cycles"
    _abscissae: np.ndarray | None = field(init=False, repr=False, compare=False, default=None)
    _values: np.ndarray | None = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        if self.variable not in FRICTION_VARIABLES:
            raise ValueError(f"EvolvingFriction.variable = {self.variable!r}: allowed {', '.join(FRICTION_VARIABLES)}")
        if callable(self.mu):
            self.at(np.zeros(1))   # refuses a function that gives no finite coefficient >= 0 at the start
            return
        abscissae, values = check_friction_table("EvolvingFriction.mu", self.mu)
        object.__setattr__(self, "_abscissae", abscissae)
        object.__setattr__(self, "_values", values)

    @property
    def table(self) -> np.ndarray | None:
        """The table as an (n, 2) array (None for a function)."""
        return None if self._abscissae is None else np.column_stack([self._abscissae, self._values])

    def at(self, values: np.ndarray) -> np.ndarray:
        """The coefficient at each of ``values`` of the variable (one per contact).

        Raises:
            ValueError: the user's function gave a coefficient that is not finite or below 0, or not one per value.
        """
        values = np.asarray(values, dtype=float)
        if self._abscissae is not None:
            return np.interp(values, self._abscissae, self._values)
        out = np.asarray(self.mu(values.copy()), dtype=float)
        if out.shape == ():
            out = np.full(values.shape, float(out))
        if out.shape != values.shape or not np.all(np.isfinite(out)) or np.any(out < 0):
            bad = "" if out.shape != values.shape else values[~(np.isfinite(out) & (out >= 0))][:3].tolist()
            where = f" (at {self.variable} {bad})" if bad else ""
            raise ValueError(f"EvolvingFriction.mu: the function gave {out.ravel()[:3].tolist()}...{where}: expected a "
                             f"finite coefficient >= 0 for each of {values.size} value(s) of the {self.variable}")
        return out

    def coefficients(self, contacts: int) -> np.ndarray:
        """The coefficient at the start (the variable at 0) for each contact."""
        return self.at(np.zeros(contacts))

    def constant_until(self, values: np.ndarray) -> np.ndarray:
        """For each of ``values``, the largest value of the variable up to which the coefficient stays the one at
        ``values`` (inf when it never changes again; the value itself where it changes right away, and for a
        function, whose course is not known): how far a cycle jump may carry the variable without changing mu."""
        values = np.asarray(values, dtype=float)
        if self._abscissae is None:
            return values.copy()
        x, mu = self._abscissae, self._values
        out = np.full(values.shape, np.inf)
        for index, value in np.ndenumerate(values):
            # the first breakpoint past ``value`` after which mu differs from mu(value)
            here = float(np.interp(value, x, mu))
            later = np.flatnonzero((x > value) & (mu != here))
            if later.size:
                first = later[0]
                # mu changes from the breakpoint before the first different one (linear in between)
                out[index] = max(value, float(x[first - 1])) if first > 0 else value
        return out

    def describe(self) -> str:
        """``"mu(cycles) from table [[0, 0.2], [5, 0.8]]"`` (a function: its name)."""
        if self._abscissae is None:
            return f"mu({self.variable}) = {getattr(self.mu, '__qualname__', type(self.mu).__name__)}(...)"
        rows = ", ".join(f"[{x:g}, {m:g}]" for x, m in zip(self._abscissae, self._values))
        return f"mu({self.variable}) from table [{rows}]"


def check_friction_table(key: str, table) -> tuple[np.ndarray, np.ndarray]:
    """(abscissae, coefficients) of a friction table ``((x0, mu0), (x1, mu1), ...)``.

    Raises:
        ValueError: naming ``key``, the value and the allowed range: not rows of two finite numbers, an abscissa
            not above the one before, a coefficient below 0.
    """
    try:
        array = np.asarray(table, dtype=float)
    except (TypeError, ValueError):  # a string, None, ragged rows
        array = np.zeros((0, 0))
    if array.ndim != 2 or array.shape[0] < 1 or array.shape[1] != 2 or not np.all(np.isfinite(array)):
        raise ValueError(f"{key} = {table!r}: expected rows [x, mu] of two finite numbers (at least one row)")
    abscissae, values = array[:, 0].copy(), array[:, 1].copy()
    step = np.flatnonzero(np.diff(abscissae) <= 0)
    if step.size:
        i = int(step[0]) + 1
        raise ValueError(f"{key} = {table!r}: row {i} has x = {abscissae[i]:g}: allowed x > {abscissae[i - 1]:g} "
                         "(the abscissae strictly increasing)")
    low = np.flatnonzero(values < 0)
    if low.size:
        i = int(low[0])
        raise ValueError(f"{key} = {table!r}: row {i} has mu = {values[i]:g}: allowed mu >= 0")
    return abscissae, values


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

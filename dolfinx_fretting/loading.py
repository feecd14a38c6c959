"""Load paths and load control of the public problem.

Loads reach the contact through the obstacle's rigid motion ``D`` (a vector in global coordinates):
moving a rigid plane by ``D`` against a body held on its far face is the same as moving that face by
``-D``, and it changes only the local problem's right-hand side, ``q(D) = q0 - G D`` with
``G = ContactSet.rigid_modes``. A prescribed displacement fixes a component of ``D``; a prescribed force
makes that component an unknown found so that the total contact force matches the target
(:func:`find_displacement`), each trial being one warm-started local solve.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

__all__ = ["Displacement", "Force", "CyclePath", "waveform", "find_displacement", "tangential_item",
           "LoadControlError", "MAX_EVAL", "FORCE_SWEEPS", "saturated_message", "not_bracketed_message",
           "not_reached_message"]

#: The load control's bound on trials (local solves) per root find.
MAX_EVAL = 200
#: The load control's bound on sweeps over the force-controlled components of an increment (each a root find).
FORCE_SWEEPS = 100


class LoadControlError(RuntimeError):
    """A prescribed force could not be reached (e.g. a tangential force above mu times the normal force)."""


def _finite_values(name: str, value: Any) -> None:
    """Refuse a target (a number or an array of them) unless every value is a finite number; the message names
    ``name``, the value and the first non-finite entry."""
    try:
        values = np.asarray(value, dtype=float)
    except (TypeError, ValueError):   # a string, None, a ragged list
        raise ValueError(f"{name} = {value!r}: expected a finite number (or an array of them)") from None
    if not np.all(np.isfinite(values)):
        first = np.unravel_index(int(np.flatnonzero(~np.isfinite(values))[0]), values.shape)
        where = f" (entry {tuple(int(i) for i in first)}: {values[first]})" if values.ndim else ""
        raise ValueError(f"{name} = {value!r}: expected finite values{where}")


@dataclass(frozen=True)
class Displacement:
    """A prescribed obstacle displacement component (or per-increment array of them, in a :class:`CyclePath`);
    refused unless finite."""

    value: Any

    def __post_init__(self) -> None:
        _finite_values("Displacement.value", self.value)


@dataclass(frozen=True)
class Force:
    """A prescribed total contact force component on the body (the obstacle position becomes unknown); refused
    unless finite."""

    value: Any

    def __post_init__(self) -> None:
        _finite_values("Force.value", self.value)



@dataclass(frozen=True)
class CyclePath:
    """The targets of the increments of one load cycle (``n`` increments).

    ``normal`` and ``tangential`` are :class:`Displacement` or :class:`Force` of arrays: ``normal`` of shape
    (n,), ``tangential`` (n,) in 2D or (n, 2) in 3D (components along t1, t2; (n,) in 3D: along t1, t2 at 0);
    in 3D ``tangential`` may also be a pair of items of shape (n,) with their own controls, e.g.
    ``(Force(Q), Displacement(zeros))`` in a half model. ``loads`` maps load names to (n,) factors. Names and
    components not given keep the state's values. With several contact zones ``normal`` and ``tangential`` map
    each zone's :class:`~dolfinx_fretting.contact.Contact` to its item (zones not named keep their values).
    """

    normal: Displacement | Force | Mapping | None = None
    tangential: Displacement | Force | tuple | Mapping | None = None
    loads: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # Targets are checked by Displacement and Force themselves; plain numbers here are a load's factors.
        for name, values in self.loads.items():
            _finite_values(f"CyclePath.loads[{name!r}]", values)

    @property
    def increments(self) -> int:
        """The number of increments (the length of the first target given)."""
        for given in (self.normal, self.tangential):
            for item in (given.values() if isinstance(given, Mapping) else [given]):
                if isinstance(item, tuple):
                    item = item[0]
                if item is not None:
                    return int(np.shape(item.value)[0])
        for v in self.loads.values():
            return int(np.shape(v)[0])
        raise ValueError("CyclePath: no target given")

    @classmethod
    def waveform(cls, increments: int, shape: str = "triangular", *, normal: Displacement | Force | float | None = None,
                 tangential: Displacement | Force | float | None = None,
                 loads: Mapping[str, float] | None = None) -> CyclePath:
        """A periodic path: ``normal`` held, ``tangential`` and ``loads`` amplitudes times the waveform
        (:func:`waveform`: ``"triangular"`` 0 → A → 0 → −A → 0, or ``"sinusoidal"``; ``increments`` a multiple of
        4, so that the path reaches ±A). Non-finite amplitudes are refused, named."""
        wave = waveform(shape, increments)
        for name, given in (("normal", normal), ("tangential", tangential)):
            for item in (given.values() if isinstance(given, Mapping) else [given]):
                for part in (item if isinstance(item, tuple) else [item]):
                    if part is not None and not isinstance(part, (Displacement, Force)):
                        _finite_values(f"CyclePath.waveform: {name}", part)
        for name, amplitude in (loads or {}).items():
            _finite_values(f"CyclePath.waveform: loads[{name!r}]", amplitude)

        def held(item):
            if isinstance(item, Mapping):
                return {zone: held(value) for zone, value in item.items()}
            if item is None:
                return None
            kind = type(item) if isinstance(item, (Displacement, Force)) else Displacement
            value = item.value if isinstance(item, (Displacement, Force)) else item
            return kind(np.full(increments, float(value)))

        def waved(item):
            if isinstance(item, Mapping):
                return {zone: waved(value) for zone, value in item.items()}
            if item is None:
                return None
            if isinstance(item, tuple):
                return tuple(waved(i) for i in item)
            kind = type(item) if isinstance(item, (Displacement, Force)) else Displacement
            amp = np.asarray(item.value if isinstance(item, (Displacement, Force)) else item, dtype=float)
            return kind(np.multiply.outer(wave, amp) if amp.ndim else amp * wave)

        return cls(held(normal), waved(tangential), {k: a * wave for k, a in (loads or {}).items()})



def tangential_item(values: np.ndarray, forced: np.ndarray):
    """The ``tangential`` argument of :meth:`~dolfinx_fretting.problem.FrettingProblem.solve` for these values and
    controls: one
    Displacement or Force of all components, or one item per component when the controls differ."""
    if forced.all() or not forced.any():
        return (Force if forced.all() else Displacement)(values)
    return tuple((Force if f else Displacement)(float(v)) for v, f in zip(values, forced))



def waveform(kind: str, n: int, phase: float = 0.0) -> np.ndarray:
    """Shape of one load cycle at the ends of its ``n`` increments, t = j/n (j = 1 .. n), in [-1, 1].

    ``"triangular"``: 0 -> 1 at t = 1/4 -> 0 at 1/2 -> -1 at 3/4 -> 0 at t = 1 (the paper's Example 1
    path); ``"sinusoidal"``: sin(2 pi t). ``phase`` (degrees): the shape lagging by that much, w(t - phase / 360)
    (periodic; 0: the shape itself, bit for bit).

    ``n`` must be a multiple of 4 (as a scene's ``loading.increments_per_cycle``): both shapes peak at t = 1/4 and
    3/4, which are increment ends only then; with n = 3 the path would turn at 0.67 of its amplitude, with n = 6
    too, with n = 10 at 0.8, and the cycle's slip and wear would be those of a smaller amplitude.

    Raises:
        ValueError: ``n`` is not a multiple of 4 (at least 4), or ``kind`` is not one of the two shapes.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 4 or n % 4:
        raise ValueError(f"increments per cycle = {n!r}: expected a multiple of 4, at least 4 (the waveform peaks at "
                         "1/4 and 3/4 of the cycle, increment ends only then; otherwise the path never reaches its "
                         "amplitude)")
    t = np.mod(np.arange(1, n + 1) / n - phase / 360.0, 1.0)  # t = 1 is t = 0 of the next cycle
    if kind == "triangular":
        return np.interp(t, [0.0, 0.25, 0.75, 1.0], [0.0, 1.0, -1.0, 0.0])
    if kind == "sinusoidal":
        w = np.sin(2 * np.pi * t)
        w[np.isclose(t, 0.5) | np.isclose(t, 0.0) | np.isclose(t, 1.0)] = 0.0  # exact zeros at the half and full cycle
        return w
    raise ValueError(f"loading.waveform = {kind!r}: allowed 'triangular', 'sinusoidal'")


def find_displacement(force: Callable[[float], float], target: float, d0: float, stiffness: float,
                      tol: float, max_eval: int = MAX_EVAL, name: str = "force") -> tuple[float, float, int]:
    """Find d with ``force(d) = target`` for a continuous non-decreasing ``force`` (piecewise linear here).

    Brackets the root by steps that double from ``(target - force(d0)) / stiffness``, then closes it by
    the Illinois variant of regula falsi, exact in one step on a linear piece.

    Args:
        force: Map from the obstacle displacement component to the matching total force.
        target: The prescribed force.
        d0: Starting displacement (the previous increment's).
        stiffness: A positive estimate of d force / d d, used for the first step only.
        tol: Absolute force tolerance.
        max_eval: Bound on evaluations (each one is a local solve).
        name: Used in the error message.

    Returns:
        (d, force(d), number of evaluations).

    Raises:
        LoadControlError: if the force cannot reach the target (it saturates) or ``max_eval`` is exceeded.
    """
    f0 = force(d0) - target
    evals = 1
    if abs(f0) <= tol:
        return d0, f0 + target, evals
    step = -f0 / max(stiffness, 1e-300)
    a, fa = d0, f0
    b, fb = d0 + step, force(d0 + step) - target
    evals += 1
    # Expand until the sign changes; a force that stops moving means the target is unreachable.
    flat_steps = 0
    while fa * fb > 0:
        # Unreachable: the force stopped changing while non-zero (friction saturated at mu P). A zero,
        # flat force only means the contact is still open: keep stepping. A flat force over a step or two
        # may also be the local solver's noise when the first step is tiny (the start was already within
        # that noise of the target): saturation is declared only after the force stayed flat while the
        # step grew 16-fold.
        flat = abs(fb - fa) <= tol and abs(fb + target) > tol
        flat_steps = flat_steps + 1 if flat else 0
        if flat_steps >= 5:
            raise LoadControlError(saturated_message(name, target, fb + target))
        if evals >= max_eval:
            raise LoadControlError(not_bracketed_message(name, target, max_eval, f0 + target, fb + target))
        step *= 2.0
        a, fa = b, fb
        b = b + step
        fb = force(b) - target
        evals += 1
    if abs(fb) <= tol:
        return b, fb + target, evals
    while evals < max_eval:
        c = b - fb * (b - a) / (fb - fa)
        fc = force(c) - target
        evals += 1
        if abs(fc) <= tol:
            return c, fc + target, evals
        if fc * fb < 0:
            a, fa = b, fb
        else:
            # The far end is kept again: halve its value (Illinois) so the bracket keeps shrinking.
            fa = fa / 2.0
        b, fb = c, fc
    raise LoadControlError(not_reached_message(name, target, max_eval, fb, tol))


def saturated_message(name: str, target: float, force: float) -> str:
    """:func:`find_displacement`'s message when the force stops at ``force`` short of ``target``."""
    return (f"{name}: prescribed value {target:.6g} cannot be reached: the contact force saturates at "
            f"{force:.6g} (for a tangential force: it must stay below mu times the normal force)")


def not_bracketed_message(name: str, target: float, max_eval: int, first: float, last: float) -> str:
    """:func:`find_displacement`'s message when ``max_eval`` trials moved the force from ``first`` to ``last``
    without crossing ``target``."""
    return (f"{name}: prescribed value {target:.6g} not bracketed in {max_eval} local solves: the force "
            f"moved from {first:.6g} to {last:.6g} without crossing it")


def not_reached_message(name: str, target: float, max_eval: int, residual: float, tol: float) -> str:
    """:func:`find_displacement`'s message when the bracket did not close to ``tol`` in ``max_eval`` trials."""
    return (f"{name}: target {target:.6g} not reached in {max_eval} local solves "
            f"(last residual {residual:.3g}, tolerance {tol:.3g}); if the residual stays near the "
            "tolerance, the local solver's noise exceeds it: tighten solver.local_tol or "
            "loosen solver.force_tol (about 100 x local_tol)")

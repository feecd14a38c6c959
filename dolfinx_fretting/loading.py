"""Load paths and load control.

Loads reach the contact through the obstacle's rigid motion ``D`` (a vector in global coordinates):
moving a rigid plane by ``D`` against a body held on its far face is the same as moving that face by
``-D``, and it changes only the local problem's right-hand side, ``q(D) = q0 - G D`` with
``G = ContactSet.rigid_modes``. A prescribed displacement fixes a component of ``D``; a prescribed force
makes that component an unknown found so that the total contact force matches the target
(:func:`find_displacement`), each trial being one warm-started local solve.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from .scenes import LoadingSettings

__all__ = ["LoadStep", "monotonic_path", "find_displacement", "LoadControlError"]


class LoadControlError(RuntimeError):
    """A prescribed force could not be reached (e.g. a tangential force above mu times the normal force)."""


@dataclass(frozen=True)
class LoadStep:
    """Targets of one increment along the plane's normal (n) and first tangent (t).

    ``normal``/``tangential`` are displacements (mm) where the matching ``*_force_controlled`` flag is
    false, forces (N/mm in 2D) where it is true.
    """

    increment: int
    stage: str
    normal: float
    tangential: float
    normal_force_controlled: bool
    tangential_force_controlled: bool


def monotonic_path(loading: LoadingSettings) -> Iterator[LoadStep]:
    """Preload (linear ramp of the normal target, no tangential motion), then a tangential ramp."""
    n_target = loading.normal_force if loading.normal_force_controlled else loading.normal_displacement
    t_fc = loading.tangential_force_controlled
    t_target = (loading.tangential_force if t_fc else loading.tangential_displacement) or 0.0
    inc = 0
    for i in range(1, loading.normal_increments + 1):
        inc += 1
        # During the preload the tangential component is held: zero displacement, or zero force when
        # the tangential load is force controlled (the cylinder is free to slide sideways).
        yield LoadStep(inc, "normal", n_target * i / loading.normal_increments, 0.0,
                       loading.normal_force_controlled, t_fc)
    nt = loading.tangential_increments if t_target != 0.0 else 0
    for i in range(1, nt + 1):
        inc += 1
        yield LoadStep(inc, "tangential", n_target, t_target * i / nt, loading.normal_force_controlled, t_fc)


def find_displacement(force: Callable[[float], float], target: float, d0: float, stiffness: float,
                      tol: float, max_eval: int = 200, name: str = "force") -> tuple[float, float, int]:
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
    while fa * fb > 0:
        # Unreachable: the force stopped changing while non-zero (friction saturated at mu P). A zero,
        # flat force only means the contact is still open: keep stepping.
        flat = abs(fb - fa) <= tol
        if evals >= max_eval or (flat and abs(fb + target) > tol):
            raise LoadControlError(
                f"{name}: prescribed value {target:.6g} cannot be reached: the contact force saturates at "
                f"{fb + target:.6g} (for a tangential force: it must stay below mu times the normal force)")
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
    raise LoadControlError(f"{name}: target {target:.6g} not reached in {max_eval} local solves "
                           f"(last residual {fb:.3g}, tolerance {tol:.3g})")

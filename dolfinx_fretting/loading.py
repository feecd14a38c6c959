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

__all__ = ["LoadStep", "waveform", "preload_path", "monotonic_path", "cycle_path", "find_displacement",
           "LoadControlError"]


class LoadControlError(RuntimeError):
    """A prescribed force could not be reached (e.g. a tangential force above mu times the normal force)."""


@dataclass(frozen=True)
class LoadStep:
    """Targets of one increment along the plane's normal (n) and first tangent (t).

    ``normal``/``tangential`` are displacements (mm) where the matching ``*_force_controlled`` flag is
    false, forces (N/mm in 2D) where it is true; ``pressure`` is the face pressure (MPa).
    ``cycle`` is 0 in the preload and monotonic stages, 1, 2, ... in the cyclic stage, where ``step`` is
    the increment's position in its cycle (1 .. increments_per_cycle).
    """

    increment: int
    stage: str
    normal: float
    tangential: float
    normal_force_controlled: bool
    tangential_force_controlled: bool
    pressure: float = 0.0
    cycle: int = 0
    step: int = 0


def waveform(kind: str, n: int) -> np.ndarray:
    """Shape of one load cycle at the ends of its ``n`` increments, t = j/n (j = 1 .. n), in [-1, 1].

    ``"triangular"``: 0 -> 1 at t = 1/4 -> 0 at 1/2 -> -1 at 3/4 -> 0 at t = 1 (the paper's Example 1
    path); ``"sinusoidal"``: sin(2 pi t).
    """
    if n < 1:
        raise ValueError(f"n = {n}: expected >= 1 increments per cycle")
    t = np.arange(1, n + 1) / n
    if kind == "triangular":
        return np.interp(t, [0.0, 0.25, 0.75, 1.0], [0.0, 1.0, -1.0, 0.0])
    if kind == "sinusoidal":
        w = np.sin(2 * np.pi * t)
        w[np.isclose(t, 0.5) | np.isclose(t, 1.0)] = 0.0  # exact zeros at the half and full cycle
        return w
    raise ValueError(f"loading.waveform = {kind!r}: allowed 'triangular', 'sinusoidal'")


def _normal_target(loading: LoadingSettings) -> float:
    return loading.normal_force if loading.normal_force_controlled else loading.normal_displacement


def preload_path(loading: LoadingSettings) -> list[LoadStep]:
    """The normal preload: a linear ramp of the normal target with no tangential load.

    During the preload the tangential component is held: zero displacement, or zero force when the
    tangential load is force controlled (the body is free to slide sideways).
    """
    n_target = _normal_target(loading)
    t_fc = loading.tangential_force_controlled
    ni = loading.normal_increments
    return [LoadStep(i, "normal", n_target * i / ni, 0.0, loading.normal_force_controlled, t_fc)
            for i in range(1, ni + 1)]


def _tangential_step(loading: LoadingSettings, increment: int, stage: str, value: float, cycle: int = 0,
                     step: int = 0) -> LoadStep:
    pressure = value if loading.tangential_kind == "pressure" else 0.0
    tangential = 0.0 if loading.tangential_kind in ("pressure", "none") else value
    return LoadStep(increment, stage, _normal_target(loading), tangential, loading.normal_force_controlled,
                    loading.tangential_force_controlled, pressure, cycle, step)


def monotonic_path(loading: LoadingSettings) -> Iterator[LoadStep]:
    """Preload, then a linear ramp of the tangential load to its value (``cycles = 0``)."""
    steps = preload_path(loading)
    yield from steps
    inc = len(steps)
    target = loading.tangential_amplitude
    nt = loading.tangential_increments if target != 0.0 else 0
    for i in range(1, nt + 1):
        inc += 1
        yield _tangential_step(loading, inc, "tangential", target * i / nt)


def cycle_path(loading: LoadingSettings, cycle: int) -> list[LoadStep]:
    """The increments of cycle ``cycle`` (1-based) of a cyclic load, numbered after the preload."""
    n = loading.increments_per_cycle
    wave = loading.tangential_amplitude * waveform(loading.waveform, n)
    first = loading.normal_increments + (cycle - 1) * n
    return [_tangential_step(loading, first + j + 1, "cycle", float(wave[j]), cycle, j + 1) for j in range(n)]


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
            raise LoadControlError(
                f"{name}: prescribed value {target:.6g} cannot be reached: the contact force saturates at "
                f"{fb + target:.6g} (for a tangential force: it must stay below mu times the normal force)")
        if evals >= max_eval:
            raise LoadControlError(
                f"{name}: prescribed value {target:.6g} not bracketed in {max_eval} local solves: the force "
                f"moved from {f0 + target:.6g} to {fb + target:.6g} without crossing it")
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
                           f"(last residual {fb:.3g}, tolerance {tol:.3g}); if the residual stays near the "
                           "tolerance, the local solver's noise exceeds it: tighten solver.local_tol or "
                           "loosen solver.force_tol (about 100 x local_tol)")

"""Settings of the public problem: the local contact solve and the elastic–plastic Newton loop.

Small frozen value objects, validated once when made, with messages that name the argument, the value and the
allowed range (:class:`LocalSolver`, :class:`Plasticity`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["LocalSolver", "Plasticity", "finite"]


def finite(name: str, value: float, low: float | None = None, strict: bool = False) -> float:
    """``value`` as a float, refused unless finite (and ``>= low``, or ``> low`` if ``strict``); the message names
    ``name``, the value and the allowed range."""
    v = float(value)
    if not np.isfinite(v) or (low is not None and (v <= low if strict else v < low)):
        rel = ">" if strict else ">="
        raise ValueError(f"{name} = {value!r}: expected a finite number" + (f" {rel} {low}" if low is not None else ""))
    return v


@dataclass(frozen=True)
class LocalSolver:
    """Settings of the local contact solve (see :func:`dolfinx_fretting.local_solvers.solve`).

    Attributes:
        method: ``"uzawa"`` (the paper's), ``"nsgs"``, ``"newton"`` or ``"auto"``; the compiled cycle loop is
            Uzawa-based, so another method runs cycles increment by increment.
        tol: Natural-map tolerance (unit-free).
        max_iter: Sweeps per local solve.
        force_tol: Relative tolerance of a prescribed force.
        compiled_cycles: Run elastic cycles in the compiled loop (prescribed forces found inside it).
        warm_start: ``"cycle"``: an increment of a compiled cycle starts from the same increment of the previous
            cycle; ``"increment"``: from the previous increment.
        pattern_reuse: 2D compiled cycles first try the previous cycle's contact pattern (an exact linear solve
            accepted only if it meets ``tol``); not under force control (its root finder would move the answers
            by the local tolerance's effect).
    """

    method: str = "uzawa"
    tol: float = 1e-10
    max_iter: int = 20000
    force_tol: float = 1e-8
    compiled_cycles: bool = True
    warm_start: str = "cycle"
    pattern_reuse: bool = True

    def __post_init__(self) -> None:
        if self.method not in ("uzawa", "nsgs", "newton", "auto"):
            raise ValueError(f"LocalSolver.method = {self.method!r}: allowed 'uzawa', 'nsgs', 'newton', 'auto'")
        if self.warm_start not in ("cycle", "increment"):
            raise ValueError(f"LocalSolver.warm_start = {self.warm_start!r}: allowed 'cycle', 'increment'")
        if not (0 < finite("LocalSolver.tol", self.tol) < 1):
            raise ValueError(f"LocalSolver.tol = {self.tol!r}: expected 0 < tol < 1")
        if not (0 < finite("LocalSolver.force_tol", self.force_tol) < 1):
            raise ValueError(f"LocalSolver.force_tol = {self.force_tol!r}: expected 0 < force_tol < 1")
        if int(self.max_iter) != self.max_iter or self.max_iter < 1:
            raise ValueError(f"LocalSolver.max_iter = {self.max_iter!r}: expected an integer >= 1")


@dataclass(frozen=True)
class Plasticity:
    """An elastic–plastic body: Newton with the contact solve inside every iteration (the paper's Figure 4).

    The constitutive update is the hook: ``law`` is any object with the elastic constants ``E`` and ``nu``
    (they make K, W and the elastic predictor) and a method
    ``update(strain, eps_p, p) -> (stress, eps_p_new, p_new, tangent, yielded)`` on arrays of quadrature
    points: Mandel strain and stress ``(n, 6)`` (``[xx, yy, zz, √2 yz, √2 xz, √2 xy]``; in 2D plane strain the
    out-of-plane strains are zero), plastic strain ``(n, 6)``, a scalar internal variable ``p`` ``(n,)``,
    the consistent tangent ``(n, 6, 6)`` and a boolean ``yielded`` ``(n,)``. It must start from the committed
    ``(eps_p, p)`` it is given and not modify them (the committed history is kept by the state).
    :class:`dolfinx_fretting.materials.J2Plasticity` (von Mises, linear isotropic hardening) is one instance.

    Attributes:
        law: The constitutive update (see above).
        quadrature_degree: Degree of the quadrature rule that carries the plastic state (and of K).
        tangent: Newton iteration matrix: ``"adaptive"`` (default), ``"consistent"`` or ``"elastic"``.
        max_iter, residual_tol, displacement_tol: Newton settings.
        max_cutbacks: Halvings of an increment whose Newton loop fails, in
            :meth:`~dolfinx_fretting.problem.FrettingProblem.advance`.
        elastic_cells: Local cells that stay elastic whatever the stress (e.g. the other body of a pair).
    """

    law: Any
    quadrature_degree: int = 2
    tangent: str = "adaptive"
    max_iter: int = 60
    residual_tol: float = 1e-8
    displacement_tol: float = 1e-6
    max_cutbacks: int = 4
    elastic_cells: np.ndarray | None = None

"""The scene runner's load paths: a scene's ``[loading]`` table as the targets of each increment.

The runner's translation of :class:`~dolfinx_fretting.scenes.LoadingSettings` (preload, monotonic ramp, cycles)
into :class:`LoadStep` targets; the public problem's own paths are :mod:`dolfinx_fretting.loading`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .loading import waveform
from .scenes import LoadingSettings

__all__ = ["LoadStep", "preload_path", "monotonic_path", "cycle_path"]


@dataclass(frozen=True)
class LoadStep:
    """Targets of one increment along the plane's normal (n) and first tangent (t).

    ``normal``/``tangential`` are displacements (mm) where the matching ``*_force_controlled`` flag is
    false, forces (N/mm in 2D) where it is true; ``pressure`` is the face pressure (MPa), ``bulk_stress`` the
    fretting-fatigue rig's bulk stress (MPa).
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
    bulk_stress: float = 0.0


def _normal_target(loading: LoadingSettings) -> float:
    return loading.normal_force if loading.normal_force_controlled else loading.normal_displacement


def _bulk_wave(loading: LoadingSettings) -> np.ndarray:
    """The bulk stress at the ends of a cycle's increments (MPa): its amplitude times the waveform, lagging by
    ``loading.bulk_phase``."""
    return (loading.bulk_stress or 0.0) * waveform(loading.waveform, loading.increments_per_cycle,
                                                   loading.bulk_phase or 0.0)


def preload_path(loading: LoadingSettings) -> list[LoadStep]:
    """The normal preload: a linear ramp of the normal target with no tangential load.

    During the preload the tangential component is held: zero displacement, or zero force when the
    tangential load is force controlled (the body is free to slide sideways). A cyclic bulk stress that lags the
    tangential load is not zero where the cycle starts: it ramps with the preload to that value.
    """
    n_target = _normal_target(loading)
    t_fc = loading.tangential_force_controlled
    ni = loading.normal_increments
    start = float(_bulk_wave(loading)[-1]) if loading.cycles > 0 else 0.0  # t = 1 is the cycle's start
    return [LoadStep(i, "normal", n_target * i / ni, 0.0, loading.normal_force_controlled, t_fc,
                     bulk_stress=start * i / ni) for i in range(1, ni + 1)]


def _tangential_step(loading: LoadingSettings, increment: int, stage: str, value: float, cycle: int = 0,
                     step: int = 0, bulk_stress: float = 0.0) -> LoadStep:
    pressure = value if loading.tangential_kind == "pressure" else 0.0
    tangential = 0.0 if loading.tangential_kind in ("pressure", "none") else value
    return LoadStep(increment, stage, _normal_target(loading), tangential, loading.normal_force_controlled,
                    loading.tangential_force_controlled, pressure, cycle, step, bulk_stress)


def monotonic_path(loading: LoadingSettings) -> Iterator[LoadStep]:
    """Preload, then a linear ramp of the tangential load and the bulk stress together to their values
    (``cycles = 0``)."""
    steps = preload_path(loading)
    yield from steps
    inc = len(steps)
    target, bulk = loading.tangential_amplitude, loading.bulk_stress or 0.0
    nt = loading.tangential_increments if target != 0.0 or bulk != 0.0 else 0
    for i in range(1, nt + 1):
        inc += 1
        yield _tangential_step(loading, inc, "tangential", target * i / nt, bulk_stress=bulk * i / nt)


def cycle_path(loading: LoadingSettings, cycle: int) -> list[LoadStep]:
    """The increments of cycle ``cycle`` (1-based) of a cyclic load, numbered after the preload."""
    n = loading.increments_per_cycle
    wave = loading.tangential_amplitude * waveform(loading.waveform, n)
    bulk = _bulk_wave(loading)
    first = loading.normal_increments + (cycle - 1) * n
    return [_tangential_step(loading, first + j + 1, "cycle", float(wave[j]), cycle, j + 1, float(bulk[j]))
            for j in range(n)]

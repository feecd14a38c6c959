"""Output writers of a fretting problem's states: tables, contact profiles, fields and the run description.

A user's own script and the scene runner write results the same way::

    writer = FrettingWriter(problem, "out", RunDescription.of(problem, "punch", path=path))
    state = problem.advance(state, normal=Force(P))[0]
    writer.write_increment(state, stage="normal")
    for cycle in range(1, cycles + 1):
        result = problem.run_cycle(state, path, keep=True)
        start, state = state, problem.commit(state, result)
        writer.write_cycle(cycle, start, result, profiles=True)
    writer.write_worn_profiles(state)
    writer.close()
    plot_run("out")            # the folder's plots, from its tables and run.json alone

What goes where (the columns are declared once, in :mod:`dolfinx_fretting.io`):

- ``history.csv``: one row per increment (:data:`~dolfinx_fretting.io.HISTORY_FIELDS`);
- ``cycles.csv``: one row per cycle (:data:`~dolfinx_fretting.io.CYCLE_FIELDS`, :func:`cycle_row`);
- ``contact_profiles.csv``: one row per contact node of every written increment;
- with several contact zones, each zone's columns too (``zone0_normal_force``, ...:
  :data:`~dolfinx_fretting.io.ZONE_HISTORY_FIELDS`, :data:`~dolfinx_fretting.io.ZONE_CYCLE_FIELDS`, a ``zone``
  column in the profiles) and every zone in ``run.json`` (:class:`ZoneDescription`); a one-zone run's files are
  those of a release without zones;
- ``flat_profiles.csv``: finite sliding only, the master's worn depth at its nodes at the end of each profiled
  cycle (its wear lives there, not on the contacts);
- ``fields.xdmf``: displacement, von Mises stress (and the equivalent plastic strain), collective;
- ``worn_profiles.csv``: each body's worn depth at the end;
- ``run.json``: the :class:`RunDescription`, which plots, pictures and ``compare`` read instead of the scene.

Tables are written by rank 0; fields by every rank (collective), like DOLFINx's ``XDMFFile``.
"""

from __future__ import annotations

import csv
import json
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from . import friction
from .io import (FRICTION_CYCLE_FIELDS, RUN_DESCRIPTION, ZONE_CYCLE_FIELDS, ResultWriter, cycle_fields,
                 history_fields, profile_fields,
                 write_json_atomic, zone_columns, zone_history_fields)
from .loading import Displacement, Force
from .obstacles import obstacle_kind
from .state import INCREMENT_COLUMNS
from .units import Units

__all__ = ["RunDescription", "ZoneDescription", "FrettingWriter", "cycle_row", "read_description", "OBSTACLE_TEXT",
           "EXTENSIVE_COLUMNS", "contact_measures", "zone_records", "zone_cycle_columns", "friction_columns"]

#: What each kind of obstacle is, in words (pictures and ``compare`` label runs with it).
OBSTACLE_TEXT = {"rigid_plane": "rigid plane",
                 "elastic_body": "elastic counter-body (two deformable bodies, small-sliding pairing)"}
#: Columns that sum over the contacts (forces, energies, worn area or volume, loaded areas): a model of a fraction
#: of the bodies (a half model about a symmetry plane) reports them divided by that fraction, the whole contact's.
EXTENSIVE_COLUMNS = ("normal_force", "tangential_force", "dissipated_energy", "wear_area_increment", "wear_area",
                     "contact_area", "stick_area")
#: A zone's columns (:data:`~dolfinx_fretting.io.ZONE_HISTORY_FIELDS`) that sum over its contacts (divided by the
#: model's fraction like :data:`EXTENSIVE_COLUMNS`).
ZONE_EXTENSIVE = ("normal_force", "tangential_force", "tangential_force_2", "dissipated_energy", "wear_area")
#: How the tangential load of a run is controlled (:attr:`RunDescription.tangential_control`).
TANGENTIAL_CONTROLS = ("displacement", "force", "pressure", "none")


@dataclass(frozen=True)
class ZoneDescription:
    """One contact zone of a run with several (``run.json``'s ``zones``).

    Attributes:
        obstacle: ``"rigid_plane"`` or ``"elastic_body"``.
        plane_point, plane_normal: The zone's obstacle plane (normal from the obstacle into the body): its frame's
            n, the direction of its ``zone<i>_normal_*`` columns.
        plane_tangent: The frame's t1 (its ``zone<i>_tangential_*`` columns).
        marker: The facet marker of the zone's surface in the user's facet tags, or None.
        surface: The surface's name (a scene's physical group), or None.
    """

    obstacle: str
    plane_point: tuple[float, ...]
    plane_normal: tuple[float, ...]
    plane_tangent: tuple[float, ...] = ()
    marker: int | None = None
    surface: str | None = None

    def to_json(self, zone: int) -> dict[str, Any]:
        return {"zone": zone, "kind": self.obstacle, "point": list(self.plane_point),
                "normal": list(self.plane_normal), "tangent": list(self.plane_tangent), "marker": self.marker,
                "surface": self.surface}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> ZoneDescription:
        return cls(obstacle=data["kind"], plane_point=tuple(data["point"]), plane_normal=tuple(data["normal"]),
                   plane_tangent=tuple(data.get("tangent", ())), marker=data.get("marker"),
                   surface=data.get("surface"))

    @classmethod
    def of(cls, contact, surface: str | None = None) -> ZoneDescription:
        """The description of a :class:`~dolfinx_fretting.contact.Contact`'s zone."""
        obstacle = contact.obstacle
        return cls(obstacle=obstacle_kind(obstacle),
                   plane_point=tuple(float(v) for v in getattr(obstacle, "point", np.zeros(contact.dim))),
                   plane_normal=tuple(float(v) for v in contact.frame[0]),
                   plane_tangent=tuple(float(v) for v in contact.frame[1]), marker=int(contact.surface[1]),
                   surface=surface)


@dataclass(frozen=True)
class RunDescription:
    """What the readers of an output folder need to know about the run, as data (``run.json``).

    Attributes:
        name: The run's name (titles of the plots).
        dim: Geometric dimension of the contact (2 or 3).
        obstacle: ``"rigid_plane"`` or ``"elastic_body"``.
        plane_point, plane_normal: The obstacle plane (normal from the obstacle into the body); for an elastic
            body the plane of its undeformed contact face.
        slave_wear_share: The contact body's share of the wear gap (two bodies; None: a rigid obstacle or no
            wear law).
        cycles: Cycles asked for (0: a monotonic run).
        preload_increments: Increments of the normal preload.
        increments_per_cycle: Increments of each cycle.
        tangential_control: One of :data:`TANGENTIAL_CONTROLS`: what drives the tangential load.
        tangential_amplitude: Its amplitude (a length, a contact force or a stress in :attr:`units`).
        pressure_face: The face a tangential pressure acts on (for labels), or None.
        wear_acceleration: Factor on the wear coefficient (the plots' titles say so when it is not 1).
        hertz: (radius, E*) of a Hertz line-contact reference drawn on the profiles, or None.
        track_positions: Contact positions whose nodes' histories are drawn (empty: chosen automatically).
        loop_cycles: Cycles whose fretting loops are drawn.
        model_fraction: The fraction of the bodies the model holds (0.5: a half model about a symmetry plane);
            the tables' :data:`EXTENSIVE_COLUMNS` are the whole contact's (the model's divided by it).
        units: The :class:`~dolfinx_fretting.units.Units` of the model's numbers, for the labels of ``run.json``,
            the plots and the pictures (nothing is converted). Default ``Units()``: the dimension symbols L, F,
            F/L², because the package cannot know a user's units and a default of mm would label an SI model
            wrongly (issue 22); requiring them would break every script written before. The scene runner passes
            :meth:`Units.mm_N_MPa() <dolfinx_fretting.units.Units.mm_N_MPa>`; declare yours with
            ``RunDescription.of(problem, name, units=Units.si())``.
        zones: With several contact zones, each one's :class:`ZoneDescription` in the problem's order (the
            attributes above describe the first, the zone a scene's ``[loading]`` drives); empty with one zone.
        evolving_friction: A zone's friction evolves (:class:`~dolfinx_fretting.laws.EvolvingFriction`):
            ``cycles.csv`` has the coefficient at each cycle's end (:data:`~dolfinx_fretting.io.FRICTION_CYCLE_FIELDS`).
    """

    name: str
    dim: int
    obstacle: str
    plane_point: tuple[float, ...]
    plane_normal: tuple[float, ...]
    slave_wear_share: float | None = None
    cycles: int = 0
    preload_increments: int = 0
    increments_per_cycle: int = 0
    tangential_control: str = "none"
    tangential_amplitude: float = 0.0
    pressure_face: str | None = None
    wear_acceleration: float = 1.0
    hertz: tuple[float, float] | None = None
    track_positions: tuple[float, ...] = ()
    loop_cycles: tuple[int, ...] = field(default_factory=tuple)
    model_fraction: float = 1.0
    units: Units = field(default_factory=Units)
    zones: tuple[ZoneDescription, ...] = ()
    evolving_friction: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.units, Units):
            raise TypeError(f"RunDescription.units must be a Units, got {type(self.units).__name__}")
        if not (np.isfinite(self.model_fraction) and 0 < self.model_fraction <= 1):
            raise ValueError(f"RunDescription.model_fraction = {self.model_fraction}: expected 0 < fraction <= 1")
        if self.obstacle not in OBSTACLE_TEXT:
            raise ValueError(f"RunDescription.obstacle must be 'rigid_plane' or 'elastic_body', got {self.obstacle!r}")
        if self.tangential_control not in TANGENTIAL_CONTROLS:
            raise ValueError(f"RunDescription.tangential_control must be one of {TANGENTIAL_CONTROLS}, got "
                             f"{self.tangential_control!r}")
        if len(self.zones) == 1 or not all(isinstance(z, ZoneDescription) for z in self.zones):
            raise ValueError(f"RunDescription.zones: expected no zone (one contact zone) or a ZoneDescription for "
                             f"each of 2 or more, got {self.zones!r}")

    @classmethod
    def of(cls, problem, name: str, *, path=None, cycles: int = 0, preload_increments: int = 0,
           plane_point=None, surfaces=None, **extra: Any) -> RunDescription:
        """The description of a run of ``problem``, the rest read from ``problem`` and the cycle ``path``.

        Args:
            problem: The :class:`~dolfinx_fretting.problem.FrettingProblem`.
            name: The run's name.
            path: The :class:`~dolfinx_fretting.loading.CyclePath` of its cycles (sets the increments per cycle
                and the tangential control), or None.
            cycles: Cycles asked for.
            preload_increments: Increments before the first cycle.
            plane_point: A point of the obstacle plane (default: the rigid plane's, else the origin); with several
                zones, the first zone's.
            surfaces: The name of each zone's surface (a scene's physical groups), or None.
            **extra: Any other attribute (``units``, ``tangential_control``, ``hertz``, ``track_positions`` ...).
        """
        contacts = problem.contacts
        first = contacts[0]   # with several zones the first describes the run's obstacle (what [loading] drives)
        obstacle = first.obstacle
        if plane_point is None:
            plane_point = getattr(obstacle, "point", np.zeros(first.dim))
        wear = problem.wear_laws[0]   # the first zone's (the laws share their acceleration)
        names = list(surfaces) if surfaces is not None else [None] * len(contacts)
        values: dict[str, Any] = {
            "dim": first.dim, "obstacle": obstacle_kind(obstacle),
            "plane_point": tuple(float(v) for v in plane_point),
            "plane_normal": tuple(float(v) for v in first.frame[0]),
            "slave_wear_share": (wear.slave_share if wear is not None and problem.contact.contact_set.two_body
                                 else None),
            "zones": (tuple(ZoneDescription.of(zone, name) for zone, name in zip(contacts, names))
                      if len(contacts) > 1 else ()),
            "cycles": cycles, "preload_increments": preload_increments,
            "evolving_friction": bool(friction.evolving_laws(problem.contact)),
            "wear_acceleration": float(wear.acceleration) if wear is not None else 1.0}
        if path is not None:
            values["increments_per_cycle"] = path.increments
            tangential = path.tangential
            if isinstance(tangential, Mapping):   # several zones: the first zone's (what a scene's [loading] drives)
                tangential = next((item for zone, item in tangential.items()
                                   if problem.operators.zone_of(zone) == 0), None)
            if isinstance(tangential, (Displacement, Force)):
                amplitude = float(np.abs(np.asarray(tangential.value, dtype=float)).max(initial=0.0))
                if amplitude > 0:
                    values["tangential_control"] = "displacement" if isinstance(tangential, Displacement) else "force"
                    values["tangential_amplitude"] = amplitude
        values.update(extra)
        return cls(name=name, **values)

    @property
    def displacement_controlled(self) -> bool:
        """Whether the obstacle's tangential displacement is prescribed (then the fretting loop's abscissa)."""
        return self.tangential_control == "displacement"

    def to_json(self) -> dict[str, Any]:
        """The ``run.json`` document (with the tables' columns and the units)."""
        data = asdict(self)
        zones = max(len(self.zones), 1)
        head = {"format": 3, "scene": self.name, "dim": self.dim,
                "obstacle": {"kind": self.obstacle, "point": list(self.plane_point),
                             "normal": list(self.plane_normal)}}
        if self.zones:  # only with several: a one-zone run.json is that of a release without zones
            head["zones"] = [zone.to_json(i) for i, zone in enumerate(self.zones)]
        return {**head, "slave_wear_share": self.slave_wear_share,
                "units": self.units.to_json(self.dim),
                "tables": {"history.csv": history_fields(zones, self.dim),
                           "cycles.csv": cycle_fields(zones, self.evolving_friction),
                           "contact_profiles.csv": profile_fields(self.dim, zones)},
                "run": {k: data[k] for k in ("cycles", "preload_increments", "increments_per_cycle",
                                             "tangential_control", "tangential_amplitude", "pressure_face",
                                             "wear_acceleration", "hertz", "track_positions", "loop_cycles",
                                             "model_fraction", "evolving_friction")}}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunDescription:
        """The description of a ``run.json``. Formats 1 and 2 (before units were declared) always labelled mm, N,
        MPa: they read as :meth:`Units.mm_N_MPa() <dolfinx_fretting.units.Units.mm_N_MPa>`, with a
        :class:`UserWarning` saying so. A run.json without ``zones`` (one zone, or a release before zones) has
        none."""
        run = dict(data.get("run", {}))  # format 1 (no "run" section): the defaults
        for key in ("track_positions", "loop_cycles", "hertz"):
            if run.get(key) is not None:
                run[key] = tuple(run[key])
        if int(data.get("format", 1)) >= 3:
            units = Units.from_json(data["units"])
        else:
            units = Units.mm_N_MPa()
            warnings.warn(f"run.json of {data.get('scene')!r} (format {data.get('format', 1)}) declares no units: "
                          "labelled mm, N, MPa as its release did", UserWarning, stacklevel=2)
        return cls(name=data["scene"], dim=int(data["dim"]), obstacle=data["obstacle"]["kind"],
                   plane_point=tuple(data["obstacle"]["point"]), plane_normal=tuple(data["obstacle"]["normal"]),
                   slave_wear_share=data.get("slave_wear_share"), units=units,
                   zones=tuple(ZoneDescription.from_json(z) for z in data.get("zones", ())), **run)


def read_description(folder: str | Path) -> RunDescription | None:
    """The :class:`RunDescription` in a run's output folder, or None when it has none (an older release)."""
    try:
        data = json.loads((Path(folder) / RUN_DESCRIPTION).read_text())
    except (OSError, ValueError):
        return None
    return RunDescription.from_json(data)


def contact_measures(problem, state, model_fraction: float = 1.0) -> dict[str, float]:
    """Sizes of a 3D contact for a summary: equivalent radii of the loaded and sticking areas, the loaded
    extents along the sliding direction t1 and across it (t2), and the worn volume, all of the whole contact.

    ``contact_radius = sqrt(A / pi)`` and ``stick_radius = sqrt(A_stick / pi)`` from the lumped areas (tributary
    areas of the loaded, of the sticking nodes) divided by ``model_fraction``. A half model (0.5) is taken to be
    cut by its symmetry plane t2 = 0 through the contact's centre: its extent across is twice the largest
    ``|t2|`` of a loaded node. Empty for a 2D contact (its widths are in the history).
    """
    contact_set = problem.contact.contact_set
    if contact_set.dim != 3 or state.status is None:
        return {}
    loaded = state.status > 0
    sticking = state.status == 1
    along = np.einsum("ij,ij->i", contact_set.coords, contact_set.frames[:, 1])
    across = np.einsum("ij,ij->i", contact_set.coords, contact_set.frames[:, 2])
    area = float(contact_set.tributary[loaded].sum()) / model_fraction
    stick_area = float(contact_set.tributary[sticking].sum()) / model_fraction

    def span(values: np.ndarray) -> float:
        return float(values.max() - values.min()) if values.size else 0.0

    return {"contact_radius": float(np.sqrt(area / np.pi)), "stick_radius": float(np.sqrt(stick_area / np.pi)),
            "contact_extent_along": span(along[loaded]),
            "contact_extent_across": (span(across[loaded]) if model_fraction == 1.0
                                      else 2.0 * float(np.abs(across[loaded]).max(initial=0.0))),
            "wear_volume": problem.worn_measure(state) / model_fraction}


def cycle_row(cycle: int, records: dict[str, np.ndarray], *, displacement_controlled: bool,
              wear_acceleration: float = 1.0, wall: float = 0.0, jump: dict[str, Any] | None = None) -> dict[str, Any]:
    """One row of ``cycles.csv`` from the per-increment columns of a cycle.

    Args:
        cycle: The cycle's number.
        records: Per-increment arrays of the cycle: the :data:`~dolfinx_fretting.state.INCREMENT_COLUMNS` and
            ``tangential_displacement`` (the obstacle's).
        displacement_controlled: The loop's abscissa (``displacement_max``, ``displacement_min``) is the
            obstacle's displacement; else it is ``-mean_relative_tangential``: the obstacle's tangential
            displacement relative to the body's contact nodes, averaged over all the candidate contacts (the
            history column holds the body's relative to the obstacle, y_t1 = u_t1 - D_t1, whose sign is opposite
            to Q's: a body dragged by Q > 0 lags behind the obstacle). Either way the loop turns with Q.
        wear_acceleration: Factor on the wear coefficient (``equivalent_cycles``).
        wall: Wall time of the cycle (s).
        jump: The cycle jump that follows it (``jump``, ``bound``, ``stability_limit``, ``error``,
            ``error_total``, ``plastic_error_total``) and an elastic-plastic body's cycle (``plastic_regime``,
            ``plastic_flow``, ``plastic_net``: :class:`~dolfinx_fretting.cycle_jump.PlasticCycle`), or None.
    """
    Q = records["tangential_force"]
    disp = records["tangential_displacement"] if displacement_controlled else -records["mean_relative_tangential"]
    energy = float(records["dissipated_energy"].sum())
    force_amplitude = 0.5 * (Q.max() - Q.min())
    displacement_amplitude = 0.5 * (disp.max() - disp.min())
    loaded = (records["n_stick"] + records["n_slip"]) > 0
    min_stick = int(records["n_stick"][loaded].min()) if loaded.any() else 0
    gross = bool(np.any((records["n_stick"] == 0) & (records["n_slip"] > 0)))
    jump = jump or {}
    n_jump = jump.get("jump", 1)
    loop_area = 4 * force_amplitude * displacement_amplitude  # the rectangle of the loop's amplitudes
    return {"cycle": cycle, "equivalent_cycles": (cycle + n_jump - 1) * wear_acceleration,
            "jump": n_jump, "jump_bound": jump.get("bound", "none"),
            "jump_stability_limit": jump.get("stability_limit", 0.0),
            "jump_error_estimate": jump.get("error", 0.0),
            "wear_error_estimate": jump.get("error_total", 0.0), "dissipated_energy": energy,
            "wear_area": float(records["wear_area"][-1]), "max_wear_depth": float(records["max_wear_depth"][-1]),
            "tangential_force_max": float(Q.max()), "tangential_force_min": float(Q.min()),
            "displacement_max": float(disp.max()), "displacement_min": float(disp.min()),
            "energy_ratio": energy / loop_area if loop_area > 0 else 0.0, "min_stick": min_stick,
            "regime": "gross_slip" if gross else ("partial_slip" if loaded.any() else "open"),
            "max_pressure_end": float(records["max_pressure"][-1]),
            "plastic_regime": jump.get("plastic_regime", "none"), "plastic_flow": jump.get("plastic_flow", 0.0),
            "plastic_net": jump.get("plastic_net", 0.0), "plastic_error_estimate": jump.get("plastic_error_total", 0.0),
            "local_iterations": int(records["local_iterations"].sum()), "wall_time_s": round(wall, 6)}


def zone_records(problem, forces: np.ndarray, slip: np.ndarray, wear_gap: np.ndarray, obstacle: np.ndarray,
                 model_fraction: float = 1.0) -> dict[str, np.ndarray]:
    """Each zone's ``history.csv`` columns (``zone<i>_...``, :func:`~dolfinx_fretting.io.zone_history_fields`) of
    increments of a problem with several contact zones, from their arrays.

    The force is :meth:`~dolfinx_fretting.problem.FrettingProblem.total_force`'s (the zone's contact forces along its
    obstacle's frame); the peak pressure, energy and worn area are those of the increment's bookkeeping
    (:func:`~dolfinx_fretting.wear.commit_increment`) restricted to the zone's contacts: ``max p`` (the pressure
    read, :meth:`~dolfinx_fretting.contact.ContactSet.tractions`: ``r_n / A`` or the smoothed one),
    ``-sum r_t . x_t``, ``sum A g_w``. The sums over the zones are the totals of the zone-less columns.

    Args:
        problem: The :class:`~dolfinx_fretting.problem.FrettingProblem` (several zones).
        forces, slip: (n, m) contact forces and local solutions of n increments (m = dim x contacts).
        wear_gap: (n, contacts) the wear gap after each increment.
        obstacle: (n, dim x zones) each zone's obstacle position.
        model_fraction: The model's fraction of the bodies (the sums are the whole contact's).

    Returns:
        Column name -> (n,) array.
    """
    contacts, stacked = problem.contacts, problem.contact
    dim = contacts[0].dim
    tributary = stacked.contact_set.tributary
    forces, slip = np.atleast_2d(forces), np.atleast_2d(slip)
    wear_gap, obstacle = np.atleast_2d(wear_gap), np.atleast_2d(obstacle)
    n = forces.shape[0]
    r = forces.reshape(n, -1, dim)
    x = slip.reshape(n, -1, dim)
    pressure = stacked.contact_set.tractions(forces)[..., 0]   # each zone's pressure_recovery
    totals = np.array([stacked.obstacle_forces(f) for f in forces]).reshape(n, len(contacts), dim)
    components = ("normal", "tangential", "tangential_2")[:dim]
    out: dict[str, np.ndarray] = {}
    for i in range(len(contacts)):
        rows = stacked.zone_slice(i)
        area = tributary[rows]
        values = {f"{c}_displacement": obstacle[:, dim * i + k] for k, c in enumerate(components)}
        values.update({f"{c}_force": totals[:, i, k] for k, c in enumerate(components)})
        values["max_pressure"] = np.maximum(pressure[:, rows].max(axis=1, initial=0.0), 0.0)
        values["dissipated_energy"] = -np.einsum("nac,nac->n", r[:, rows, 1:], x[:, rows, 1:])
        values["wear_area"] = wear_gap[:, rows] @ area
        for name in zone_history_fields(dim):
            column = values[name]
            out[f"zone{i}_{name}"] = column / model_fraction if name in ZONE_EXTENSIVE else column
    return out


def zone_cycle_columns(records: dict[str, np.ndarray], zones: int) -> dict[str, float]:
    """Each zone's ``cycles.csv`` columns (:data:`~dolfinx_fretting.io.ZONE_CYCLE_FIELDS`) from a cycle's
    :func:`zone_records`."""
    out: dict[str, float] = {}
    for i in range(zones if zones > 1 else 0):
        zone = {name: records[f"zone{i}_{name}"] for name in ("normal_force", "tangential_force", "max_pressure",
                                                               "dissipated_energy", "wear_area")}
        values = {"dissipated_energy": zone["dissipated_energy"].sum(), "wear_area": zone["wear_area"][-1],
                  "normal_force_max": zone["normal_force"].max(), "normal_force_min": zone["normal_force"].min(),
                  "tangential_force_max": zone["tangential_force"].max(),
                  "tangential_force_min": zone["tangential_force"].min(),
                  "max_pressure_end": zone["max_pressure"][-1]}
        out.update({f"zone{i}_{name}": float(values[name]) for name in ZONE_CYCLE_FIELDS})
    return out


def friction_columns(problem, state) -> dict[str, float]:
    """The friction coefficients of ``state`` (:func:`~dolfinx_fretting.friction.coefficients`: those its next
    increment is solved with) as :data:`~dolfinx_fretting.io.FRICTION_CYCLE_FIELDS`, over every zone and, with
    several, each zone's (``zone<i>_mu_mean`` ...): over the contacts with a normal force > 0 (none: every contact of
    the zone, the mean unweighted), ``mu_mean`` weighted by that force."""
    contact = problem.contact
    mu = np.asarray(friction.coefficients(contact, state), dtype=float)
    dim = contact.contact_set.dim
    normal = np.asarray(state.forces, dtype=float).reshape(-1, dim)[:, 0]

    def reduced(rows: slice) -> dict[str, float]:
        values, weights = mu[rows], np.maximum(normal[rows], 0.0)
        loaded = weights > 0
        if loaded.any():
            values, weights = values[loaded], weights[loaded]
        else:
            weights = np.ones_like(values)
        return {"mu_mean": float(np.dot(values, weights) / weights.sum()), "mu_min": float(values.min()),
                "mu_max": float(values.max())}

    out = reduced(slice(0, mu.size))
    zones = len(problem.contacts)
    for zone in range(zones if zones > 1 else 0):
        out.update({f"zone{zone}_{name}": value for name, value in reduced(contact.zone_slice(zone)).items()})
    return out


class FrettingWriter:
    """Writes a :class:`~dolfinx_fretting.problem.FrettingProblem`'s states into a folder. Collective.

    Args:
        problem: The problem whose states are written.
        folder: Output folder (created).
        description: What the folder's readers need (``run.json``, written at once); default
            ``RunDescription.of(problem, "run")``.
        profiles: Write ``contact_profiles.csv``.
        fields: Write ``fields.xdmf`` (displacement, von Mises, equivalent plastic strain).
        von_mises: UFL von Mises stress of a displacement ``u -> expr`` for elastic problems (elastic–plastic
            ones take it from the plastic state); None: the fields hold the displacement only.
        pressure_load: The named load whose factor is the ``face_pressure`` column (None: 0).
        shifted_cells: Cells whose displacement is drawn moved by the obstacle's reverse motion (two bodies
            driven as the paper does: the obstacle body held, the contact body moved); None: none.
        resume: ``checkpoint_info()`` of a checkpoint to continue from: the tables are truncated to its sizes
            and appended to (a table shorter than recorded raises :class:`~dolfinx_fretting.io.TableError`).

    With several contact zones each zone's columns follow the tables' own (:func:`zone_records`); they are computed
    from every increment's contact forces, so a cycle written with its history is solved with ``keep=True``.
    """

    def __init__(self, problem, folder: str | Path, description: RunDescription | None = None, *,
                 profiles: bool = True, fields: bool = True, von_mises: Callable | None = None,
                 pressure_load: str | None = None, shifted_cells: np.ndarray | None = None,
                 resume: dict[str, Any] | None = None):
        self.problem = problem
        self.folder = Path(folder)
        self.comm = problem.comm
        self.description = description if description is not None else RunDescription.of(problem, "run")
        self.fields_enabled = fields
        self.von_mises = von_mises
        self.shifted_cells = shifted_cells
        names = problem.load_names
        self._pressure_index = names.index(pressure_load) if pressure_load in names else None
        resume = resume or {}
        #: The problem's contact zones (with several, each zone's columns).
        self.zones = len(problem.contacts)
        self.tables = ResultWriter(self.folder, self.comm, profiles=profiles, resume_sizes=resume.get("sizes"),
                                   xdmf_started=bool(resume.get("xdmf_started", False)),
                                   fields_steps=resume.get("fields_steps"), dim=problem.contact.dim,
                                   flat_profiles=problem.operators.surface_compliance is not None, zones=self.zones,
                                   evolving_friction=self.description.evolving_friction)
        self._functions = None
        if self.comm.rank == 0:
            write_json_atomic(self.folder / RUN_DESCRIPTION, self.description.to_json())

    # Rows ----------------------------------------------------------------------------------------------
    def _face_pressure(self, load_factors: np.ndarray) -> np.ndarray | float:
        if self._pressure_index is None:
            return np.zeros(load_factors.shape[:-1]) if load_factors.ndim > 1 else 0.0
        return load_factors[..., self._pressure_index]

    def _whole(self, values: dict[str, Any]) -> dict[str, Any]:
        """The :data:`EXTENSIVE_COLUMNS` of a model of a fraction of the bodies as the whole contact's."""
        fraction = self.description.model_fraction
        if fraction == 1.0:
            return values
        return {k: (v / fraction if k in EXTENSIVE_COLUMNS else v) for k, v in values.items()}

    def history_row(self, state, *, stage: str, cycle: int = 0, step: int = 0) -> dict[str, Any]:
        """The ``history.csv`` row of a committed state (sums over the contacts: the whole contact's)."""
        values = self._whole(state.record)
        row = {"increment": state.increment, "cycle": cycle, "step": step, "stage": stage,
               "normal_displacement": float(state.obstacle[0]), "tangential_displacement": float(state.obstacle[1]),
               "face_pressure": float(self._face_pressure(state.load_factors)),
               **{k: values[k] for k in INCREMENT_COLUMNS}}
        if self.zones > 1:
            zones = zone_records(self.problem, state.forces, state.slip, state.wear_gap, state.obstacle,
                                 self.description.model_fraction)
            row.update({k: float(v[0]) for k, v in zones.items()})
        return row

    def write_increment(self, state, *, stage: str = "increment", profile: bool = True,
                        fields: bool = True) -> dict[str, Any]:
        """Append a committed increment: its history row, its contact profile and its fields. Collective.

        Returns:
            The history row.
        """
        row = self.history_row(state, stage=stage)
        self.tables.rows("history", [row])
        if profile:
            self.write_profile(state.increment, 0, 0, state.slip, state.positions, state.forces, state.wear_gap,
                               state.status)
        if fields:
            self.write_fields(float(state.increment), state)
        self.tables.flush()
        return row

    def cycle_end_row(self, cycle: int, start, result) -> dict[str, Any]:
        """The ``history.csv`` row of a cycle's last increment (written or not: the summary reads it)."""
        records = self.cycle_records(result)
        n = records["normal_force"].size
        last = {k: (v[-1].item() if hasattr(v[-1], "item") else v[-1]) for k, v in records.items()}
        return {"increment": start.increment + n, "cycle": cycle, "step": n, "stage": "cycle",
                **{k: last[k] for k in ("normal_displacement", "tangential_displacement", "face_pressure")},
                **{k: last[k] for k in INCREMENT_COLUMNS},
                **{k: last[k] for k in zone_columns(zone_history_fields(self.problem.contact.dim), self.zones)}}

    def cycle_records(self, result) -> dict[str, np.ndarray]:
        """A cycle's per-increment columns with the obstacle's displacement and the face pressure (and, with
        several zones, each zone's: :func:`zone_records`, from the cycle's kept increments)."""
        records = {**self._whole(result.records), "normal_displacement": result.obstacle[:, 0],
                   "tangential_displacement": result.obstacle[:, 1],
                   "face_pressure": self._face_pressure(result.load_factors)}
        if self.zones > 1:
            if result.kept is None:
                raise ValueError("FrettingWriter: a problem with several contact zones writes each zone's columns "
                                 "from every increment's forces: solve the cycle with run_cycle(..., keep=True)")
            out_r, out_x, _, out_wear, _ = result.kept
            records.update(zone_records(self.problem, out_r, out_x, out_wear, result.obstacle,
                                        self.description.model_fraction))
        return records

    def write_cycle(self, cycle: int, start, result, *, history: bool = True, profiles: bool = False,
                    fields: bool | None = None, wall: float = 0.0, jump: dict[str, Any] | None = None,
                    end=None) -> dict[str, Any]:
        """Append a committed cycle: its history block, its ``cycles.csv`` row, and with ``profiles`` the contact
        profile of every increment and the fields of its most loaded instant. Collective.

        Args:
            cycle: The cycle's number.
            start: The state the cycle started from.
            result: The :class:`~dolfinx_fretting.state.CycleResult` (solved with ``keep=True`` for profiles).
            history: Write the cycle's increments into ``history.csv``.
            profiles: Write the contact profiles (and, unless ``fields`` is False, the fields).
            fields: Write the fields (default: with the profiles).
            wall: Wall time of the cycle (s), for the table.
            jump: The cycle jump after it (see :func:`cycle_row`).
            end: The state after the cycle and its jump, whose friction coefficients an evolving law's columns
                give (:func:`friction_columns`; default ``result.final``, the cycle's own end).

        Returns:
            The ``cycles.csv`` row.
        """
        records = self.cycle_records(result)
        n = records["normal_force"].size
        if history:
            head = list(zip(range(start.increment + 1, start.increment + n + 1), [cycle] * n, range(1, n + 1)))
            columns = history_fields(self.zones, self.problem.contact.dim)[4:]   # after stage
            self.tables.history_block(head, np.column_stack([records[c] for c in columns]), "cycle")
        row = cycle_row(cycle, records, displacement_controlled=self.description.displacement_controlled,
                        wear_acceleration=self.description.wear_acceleration, wall=wall, jump=jump)
        row.update(zone_cycle_columns(records, self.zones))
        if self.description.evolving_friction:
            row.update(friction_columns(self.problem, result.final if end is None else end))
        self.tables.rows("cycles", [row])
        if profiles:
            if result.kept is None:
                raise ValueError("write_cycle(profiles=True) needs the cycle solved with keep=True")
            out_r, out_x, out_y, out_wear, out_status = result.kept
            for j in range(n):
                self.write_profile(start.increment + j + 1, cycle, j + 1, out_x[j], out_y[j], out_r[j], out_wear[j],
                                   out_status[j])
            self.write_flat_profile(start.increment + n, cycle, result.final)
        if profiles if fields is None else fields:
            j, shown = self.most_loaded(result)
            self.write_fields(float(start.increment + j + 1), shown)
        self.tables.flush()
        return row

    def most_loaded(self, result) -> tuple[int, Any]:
        """The increment of a cycle whose fields are drawn and its state: the most loaded instant (largest
        normal + ``|tangential|`` contact force; a cycle often ends unloaded, as Example 1's face pressure
        does); elastic–plastic problems: the cycle's end (the plastic history kept is the end's)."""
        n = result.records["normal_force"].size
        if self.problem.body is not None or result.kept is None:
            return n - 1, result.final
        j = int(np.argmax(result.records["normal_force"] + np.abs(result.records["tangential_force"])))
        out_r, out_x, out_y, out_wear, out_status = result.kept
        # finite sliding: the increment's arrays are in its own pairing's frames
        pairing = result.kept_pairings[j] if result.kept_pairings is not None else result.final.pairing
        return j, replace(result.final, forces=out_r[j], slip=out_x[j], positions=out_y[j], wear_gap=out_wear[j],
                          status=out_status[j], obstacle=result.obstacle[j], load_factors=result.load_factors[j],
                          pairing=pairing)

    def write_profile(self, increment: int, cycle: int, step: int, slip: np.ndarray, positions: np.ndarray,
                      forces: np.ndarray, wear_gap: np.ndarray, status: np.ndarray) -> None:
        """Append one increment's contact profile (rank 0): the columns of
        :func:`~dolfinx_fretting.io.profile_fields` (t1 components, and in 3D the t2 ones and the position
        along t2)."""
        contact_set = self.problem.contact.contact_set
        dim = contact_set.dim
        if status is None:
            status = np.zeros(contact_set.nc, dtype=np.int8)
        traction = contact_set.tractions(forces)   # the contact's pressure_recovery
        columns = [contact_set.abscissa, positions[0::dim], traction[:, 0], traction[:, 1],
                   slip[1::dim], positions[1::dim], wear_gap]
        if dim == 3:
            columns += [np.einsum("ij,ij->i", contact_set.coords, contact_set.frames[:, 2]), traction[:, 2],
                        slip[2::dim], positions[2::dim]]
        zone = None
        if self.zones > 1:
            zone = np.repeat(np.arange(self.zones), np.diff(self.problem.contact.offsets))
        self.tables.profile_block(increment, cycle, step, [*columns, status], zone)

    def write_flat_profile(self, increment: int, cycle: int, state) -> None:
        """Finite sliding: append the master's worn depth at its nodes (``flat_profiles.csv``, rank 0): there the
        master's wear lives on its own nodes, not on the contacts (with small sliding it is the wear gap's share
        in ``contact_profiles.csv``)."""
        if self.problem.operators.surface_compliance is None or self.comm.rank != 0:
            return
        worn = self.problem.body_wear(state)
        frame = self.problem.contact.frame
        x = worn["master_coordinates"]
        along = np.column_stack([x @ frame[1], x @ frame[2] if x.shape[1] == 3 else np.zeros(x.shape[0])])
        self.tables.flat_block(increment, cycle, along, worn["master"])

    # Fields ----------------------------------------------------------------------------------------------
    def write_fields(self, t: float, state) -> None:
        """Append the displacement, von Mises stress (and equivalent plastic strain) of ``state`` at time ``t``
        to ``fields.xdmf``. Collective."""
        if not self.fields_enabled:
            return
        # Lazy: DOLFINx only to write fields; compare, plots and the pictures read the tables through this module
        # without it
        from dolfinx import fem

        from . import _dolfinx as dfx

        problem = self.problem
        if self._functions is None:
            V = problem.V
            Q = dfx.scalar_space(V.mesh, "DG", 0)
            u = fem.Function(V, name="displacement")
            self._functions = (u, fem.Function(Q, name="von_mises"), fem.Function(Q, name="equivalent_plastic_strain"))
            self._von_mises_expr = (dfx.expression(self.von_mises(u), dfx.interpolation_points(Q))
                                    if self.von_mises is not None else None)
        u, von_mises, plastic_strain = self._functions
        problem.displacement(state, out=u)
        functions = [u]
        if problem.body is not None:
            plastic = problem.plastic_state(state)
            n = plastic.cells.size
            von_mises.x.array[:n] = plastic.cell_average(plastic.von_mises())
            plastic_strain.x.array[:n] = plastic.cell_average(plastic.p)
            von_mises.x.scatter_forward()
            plastic_strain.x.scatter_forward()
            functions += [von_mises, plastic_strain]
        elif self._von_mises_expr is not None:
            von_mises.interpolate(self._von_mises_expr)
            functions.append(von_mises)
        if self.shifted_cells is not None:
            D = problem.obstacle_translation(state.obstacle)
            # The cells' dofs from the dofmap (locate_dofs_topological on cells needs the cell-to-cell
            # connectivity on DOLFINx 0.11, which a 3D mesh under MPI has not computed).
            nodes = np.unique(dfx.cell_dofmap(u.function_space)[self.shifted_cells])
            u.x.array.reshape(-1, u.function_space.dofmap.index_map_bs)[nodes, :D.size] -= D
        self.tables.fields(t, functions)

    # The end ---------------------------------------------------------------------------------------------
    def write_worn_profiles(self, state) -> None:
        """``worn_profiles.csv`` (rank 0): each body's worn depth along the contact.

        Both bodies see the same pressure and slip, so each wears its share ``k_body / k_total`` of the wear
        gap; the obstacle body's depth is placed at the master point paired with each contact node. With several
        contact zones a last column ``zone`` says whose (positions along each zone's own t1).
        """
        if self.comm.rank != 0:
            return
        contact_set = self.problem.contact_set_of(state)
        wear_gap = state.wear_gap
        rows = []
        if not contact_set.two_body:
            nc = contact_set.nc
            rows = zip(contact_set.abscissa, wear_gap, wear_gap, np.full(nc, np.nan), np.zeros(nc))
        else:
            worn = self.problem.body_wear(state)
            if self.zones > 1:   # each zone's master points along its own t1 (its contacts' frames: small sliding)
                flat_x = np.einsum("ij,ij->i", worn["master_coordinates"], contact_set.frames[:, 1])
            else:
                flat_x = worn["master_coordinates"] @ self.problem.contact.frame[1]
            # the flat's share placed at each contact's paired point
            if self.problem.operators.surface_compliance is None:
                rows = zip(contact_set.abscissa, wear_gap, worn["slave"], flat_x, worn["master"])
            else:   # finite sliding: the cylinder's rows, then the flat's nodes (blank where a body has none)
                blank, blank_flat = np.full(contact_set.nc, np.nan), np.full(flat_x.size, np.nan)
                rows = [*zip(contact_set.abscissa, wear_gap, worn["slave"], blank, blank),
                        *zip(blank_flat, blank_flat, blank_flat, flat_x, worn["master"])]
        header = ["position", "wear_gap", "cylinder_wear", "flat_position", "flat_wear"]
        if self.zones > 1:   # (finite sliding, whose rows differ, has one zone)
            zone = np.repeat(np.arange(self.zones), np.diff(self.problem.contact.offsets))
            header.append("zone")
            rows = [(*values, z) for values, z in zip(rows, zone)]
        with open(self.folder / "worn_profiles.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(header)
            for values in rows:
                w.writerow([f"{v:.12g}" for v in values[:5]] + [str(int(v)) for v in values[5:]])

    def write_summary(self, summary: dict[str, Any]) -> None:
        """``summary.json`` (rank 0, atomically; non-finite numbers as null with their keys listed)."""
        self.tables.summary(summary)

    def checkpoint_info(self) -> dict[str, Any]:
        """What a checkpoint records to resume the writer (``resume=``): the tables' sizes, the XDMF state (started,
        and its time steps: a resume drops those written after the checkpoint)."""
        return {"sizes": self.tables.sizes(), "xdmf_started": self.tables.xdmf_started,
                "fields_steps": self.tables.fields_steps}

    def flush(self) -> None:
        self.tables.flush()

    def close(self) -> None:
        self.tables.close()

    def __enter__(self) -> FrettingWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

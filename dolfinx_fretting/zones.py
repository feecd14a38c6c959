"""Several contact zones in one problem: a corner touching two walls, a dovetail's two flanks, the pads of a
bridge-type fretting-fatigue rig.

Each zone is a :class:`~dolfinx_fretting.contact.Contact` of its own (facet marker, obstacle, friction law,
window); :class:`ContactZones` stacks them into one contact set, so that W = H K⁻¹ Hᵀ couples every zone through
the body (one factorisation) and the local solvers, the compiled cycles and the wear bookkeeping see one set of
contacts. A node may belong to two zones (a corner: two constraints with their own normals, two rows of H on the
same dofs). Each zone's obstacle moves on its own: the obstacle vector of a
:class:`~dolfinx_fretting.state.ContactState` holds ``dim`` components per zone, each in its zone's frame.

:class:`ContactZones` offers what :class:`~dolfinx_fretting.operators.ContactOperators` reads of a single
:class:`~dolfinx_fretting.contact.Contact` (the same attribute names: ``contact_set``, ``H_free``, ``held_rows``,
``mu``, ``outside``, and the obstacle's ``translations``, ``rigid_motion``, ``obstacle_forces`` ...), so the
operators, increments and cycles do not branch on the number of zones.
"""

from __future__ import annotations

import warnings
from typing import Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from .contact import Contact, ContactSet
from .friction import evolving_laws
from .laws import WearLaw

__all__ = ["ContactZones", "concatenate", "as_zones", "zone_wear_laws"]


def concatenate(sets: Sequence[ContactSet]) -> ContactSet:
    """One contact set of ``sets`` in turn (their rows of every array and of H). The master body's arrays are kept
    when every set has them (every zone against an elastic body), else dropped (the zones are read one by one:
    :meth:`ContactZones.zone_set`)."""
    dim = sets[0].dim

    def join(name: str, fill: float = 0):
        values = [getattr(s, name) for s in sets]
        if any(v is None for v in values):
            return None
        if values[0].ndim == 2:
            # master nodes and weights per contact: 2 (a segment), 4 (a face) or a mortar row's count, padded as a
            # triangle's are (node -1, weight 0); the points' width is the dimension, the same in every zone
            width = max(v.shape[1] for v in values)
            values = [np.pad(v, ((0, 0), (0, width - v.shape[1])), constant_values=fill) for v in values]
        return np.concatenate(values)

    surfaces = {id(s.master_surface) for s in sets}
    return ContactSet(dim, np.concatenate([s.global_nodes for s in sets]), np.concatenate([s.coords for s in sets]),
                      np.concatenate([s.frames for s in sets]), np.concatenate([s.gap0 for s in sets]),
                      np.concatenate([s.tributary for s in sets]), np.concatenate([s.abscissa for s in sets]),
                      sp.vstack([s.H for s in sets], format="csr"),
                      join("master_nodes", -1), join("master_weights"), join("master_points"), join("master_sizes"),
                      None, sets[0].master_surface if len(surfaces) == 1 else None, None, _joined_mass(sets))


def _joined_mass(sets: Sequence[ContactSet]) -> sp.csr_matrix | None:
    """The zones' surface mass matrices side by side (the zones' surfaces are apart), None when no zone smooths
    its tractions; a ``"nodal"`` zone's is diag(A), which the smoothing leaves at ``r / A``."""
    if all(s.surface_mass is None for s in sets):
        return None
    return sp.block_diag([sp.diags(s.tributary) if s.surface_mass is None else s.surface_mass for s in sets],
                         format="csr")


class ContactZones:
    """The contact zones of one problem, stacked (see the module). Collective to build (each zone's rebuild for a
    new window is).

    Args:
        zones: The :class:`~dolfinx_fretting.contact.Contact` of each zone, all on the problem's space ``V`` and
            built with the same Dirichlet conditions.

    Attributes:
        zones: The zones, in the order given (a zone's index is its place here).
        contact_set: Every zone's contacts in turn (:func:`concatenate`).
        offsets: (zones + 1,) the first contact of each zone in :attr:`contact_set` (and the end).
        H_free, held_rows, mu: Every zone's, stacked (row and contact indices of :attr:`contact_set`).
        outside: Every zone's nodes outside its window, stacked (None if no zone has any).
        outside_zone: The zone of each node of ``outside``.

    Raises:
        TypeError: a zone is not a Contact.
        ValueError: no zone; the same Contact twice; zones on different spaces or with different conditions; a
            zone with finite sliding (:class:`~dolfinx_fretting.contact.ElasticBody`'s ``sliding="finite"`` pairs
            one zone anew on its own surface compliance: one zone per problem).
    """

    def __init__(self, zones: Sequence[Contact]):
        zones = tuple(zones)
        if not zones:
            raise ValueError("FrettingProblem: contact = []: expected a Contact or a non-empty list of Contacts")
        for i, zone in enumerate(zones):
            if not isinstance(zone, Contact):
                raise TypeError(f"FrettingProblem: contact[{i}] must be a Contact, got {type(zone).__name__}")
        if len({id(zone) for zone in zones}) < len(zones):
            raise ValueError("FrettingProblem: the same Contact is listed twice (two zones on one surface and one "
                             "obstacle would count every constraint twice)")
        first = zones[0]
        for i, zone in enumerate(zones[1:], start=1):
            if zone.V is not first.V:
                raise ValueError(f"FrettingProblem: contact[{i}] is on another function space than contact[0]: every "
                                 "zone must be built on the problem's V")
            if not np.array_equal(zone.fixed_global, first.fixed_global):
                raise ValueError(f"FrettingProblem: contact[{i}] was built with other Dirichlet conditions than "
                                 f"contact[0] ({zone.fixed_global.size} fixed dofs, {first.fixed_global.size} there): "
                                 "pass the problem's bcs to every Contact(..., bcs=...)")
        for i, zone in enumerate(zones):
            if len(zones) > 1 and zone.obstacle.finite_sliding:
                raise ValueError(f"FrettingProblem: contact[{i}] has ElasticBody(sliding='finite'): finite sliding "
                                 "pairs its zone anew on a surface compliance of its own and is available with one "
                                 "zone per problem; use sliding='small' here")
        self.zones = zones
        self.V = first.V
        self.bcs = first.bcs
        self.fixed_global = first.fixed_global
        self._combine()
        self._warn_shared_friction()

    def _warn_shared_friction(self) -> None:
        """Warn (rank 0) when a node is a contact of two zones that both have friction: its frictional forces act
        on the same displacement components (a corner's tangent along one wall is the other's normal), so their
        split is not unique and the local solver converges slowly, if at all. A frictionless zone at the corner
        keeps it unique."""
        nodes = self.contact_set.global_nodes
        # (an evolving law may start frictionless and gain friction later)
        frictional = self.mu > 0
        for zone, _ in evolving_laws(self):
            frictional[self.zone_slice(zone)] = True
        shared, counts = np.unique(nodes[frictional], return_counts=True)
        shared = shared[counts > 1]
        if shared.size and self.V.mesh.comm.rank == 0:
            where = self.contact_set.coords[np.flatnonzero(np.isin(nodes, shared))[0]]
            warnings.warn(f"{shared.size} node(s) (the first at {np.round(where, 6).tolist()}) are contacts of two "
                          "zones that both have friction: their two frictional constraints act on the same "
                          "displacement, their forces are not unique and the local solver may not converge. Leave "
                          "the node out of one zone's surface, or make one zone frictionless there",
                          RuntimeWarning, stacklevel=3)

    def _combine(self) -> None:
        zones = self.zones
        dim = zones[0].dim
        sets = [zone.contact_set for zone in zones]
        self.offsets = np.cumsum([0] + [s.nc for s in sets])
        self.contact_set = concatenate(sets)
        self.H_free = sp.vstack([zone.H_free for zone in zones], format="csr")
        self.held_rows = np.concatenate([zone.held_rows + dim * start for zone, start in zip(zones, self.offsets)])
        self.mu = np.concatenate([zone.mu for zone in zones])
        outside = [(i, zone.outside) for i, zone in enumerate(zones) if zone.outside is not None]
        self.outside = concatenate([o for _, o in outside]) if outside else None
        self.outside_zone = np.concatenate([np.full(o.nc, i) for i, o in outside]) if outside else np.zeros(0, int)
        self._outside_of = outside

    # What a single Contact offers, for every zone ---------------------------------------------------------------
    @property
    def dim(self) -> int:
        """Components per contact (the space dimension)."""
        return self.zones[0].dim

    @property
    def nc(self) -> int:
        """Contacts of every zone."""
        return self.contact_set.nc

    @property
    def obstacle_size(self) -> int:
        """Components of the obstacles' motion: ``dim`` per zone (n, t1[, t2] of each zone's frame in turn)."""
        return len(self.zones) * self.dim

    @property
    def windows(self) -> tuple[float | None, ...]:
        """Each zone's candidate window."""
        return tuple(zone.window for zone in self.zones)

    @property
    def frame(self) -> np.ndarray:
        raise AttributeError("several contact zones: each has its own obstacle frame (problem.contacts[i].frame)")

    @property
    def obstacle(self):
        raise AttributeError("several contact zones: each has its own obstacle (problem.contacts[i].obstacle)")

    def zone_slice(self, zone: int) -> slice:
        """The contacts of zone ``zone`` in :attr:`contact_set`."""
        return slice(int(self.offsets[zone]), int(self.offsets[zone + 1]))

    def zone_set(self, zone: int) -> ContactSet:
        """Zone ``zone``'s own contact set (with its master arrays)."""
        return self.zones[zone].contact_set

    def _split(self, values: np.ndarray, per_contact: int) -> list[np.ndarray]:
        return [values[..., per_contact * s.start:per_contact * s.stop]
                for s in (self.zone_slice(i) for i in range(len(self.zones)))]

    def _components(self, obstacle: np.ndarray) -> list[np.ndarray]:
        dim = self.dim
        return [obstacle[..., dim * i:dim * (i + 1)] for i in range(len(self.zones))]

    def translations(self, obstacle: np.ndarray) -> np.ndarray:
        """Each zone's obstacle translation D (global frame), in turn along the last axis."""
        obstacle = np.asarray(obstacle, dtype=float)
        return np.concatenate([zone.translations(part) for zone, part in zip(self.zones, self._components(obstacle))],
                              axis=-1)

    def rigid_motion(self, obstacle: np.ndarray) -> np.ndarray:
        """Each contact's local relative displacement when every zone's obstacle moves by its components."""
        return np.concatenate([zone.rigid_motion(part) for zone, part in zip(self.zones, self._components(obstacle))])

    @property
    def rigid_modes(self) -> np.ndarray:
        """G of the compiled cycles: block-diagonal, zone by zone (m, dim x zones), against :meth:`translations`."""
        dim = self.dim
        G = np.zeros((self.nc * dim, self.obstacle_size))
        for i, zone in enumerate(self.zones):
            rows = self.zone_slice(i)
            G[dim * rows.start:dim * rows.stop, dim * i:dim * (i + 1)] = zone.contact_set.rigid_modes
        return G

    def obstacle_forces(self, forces: np.ndarray, contact_set: ContactSet | None = None) -> np.ndarray:
        """Each zone's total contact force on the body along its obstacle's components, in turn."""
        return np.concatenate([zone.obstacle_forces(part) for zone, part in zip(self.zones, self._split(forces,
                                                                                                      self.dim))])

    def held_components(self, contact_set: ContactSet | None = None) -> np.ndarray:
        """Each zone's obstacle components along a direction the conditions hold, in turn."""
        return np.concatenate([zone.held_components() for zone in self.zones])

    def component_names(self) -> list[str]:
        """``contact[i] normal``, ``contact[i] tangential t1`` ... (messages)."""
        return [f"contact[{i}] {name}" for i, zone in enumerate(self.zones) for name in zone.component_names()]

    def outside_distance(self) -> np.ndarray:
        """Each outside node's in-plane distance from its zone's window centre."""
        return np.concatenate([self.zones[i].window_distance(o) for i, o in self._outside_of])

    def outside_motion(self) -> np.ndarray:
        """(k, obstacle_size): each outside node's normal displacement per unit obstacle component of its zone."""
        motion = np.zeros((self.outside.nc, self.obstacle_size))
        start, dim = 0, self.dim
        for i, o in self._outside_of:
            motion[start:start + o.nc, dim * i:dim * (i + 1)] = self.zones[i].outside_motion()
            start += o.nc
        return motion

    def with_window(self, window: float | None, zone: int = 0) -> ContactZones:
        """The same zones with zone ``zone``'s window changed (collective)."""
        zones = list(self.zones)
        zones[zone] = zones[zone].with_window(window)
        return ContactZones(zones)


def zone_wear_laws(zones: tuple[Contact, ...], wear) -> tuple:
    """Each zone's wear law from the problem's ``wear``: None (no wear), one law for every zone, or a mapping from
    each zone's :class:`~dolfinx_fretting.contact.Contact` to its law (a zone not named does not wear). The laws
    must agree on ``acceleration`` (each simulated cycle stands for that many physical ones: one number per run).

    Raises:
        TypeError: a value is not a wear law (the :class:`~dolfinx_fretting.laws.WearLaw` protocol) or None.
        ValueError: a key is not one of the zones; the laws' accelerations differ.
    """
    if not isinstance(wear, Mapping):
        laws = (wear,) * len(zones)
        named = {}
    else:
        where = {id(zone): i for i, zone in enumerate(zones)}
        laws = [None] * len(zones)
        named = {}
        for key, law in wear.items():
            if id(key) not in where:
                raise ValueError(f"FrettingProblem: wear: a key is not one of this problem's contact zones ({key!r}): "
                                 "name each zone by the Contact given to FrettingProblem")
            laws[where[id(key)]] = law
            named[where[id(key)]] = law
        laws = tuple(laws)
    for i, law in enumerate(laws):
        if law is not None and not isinstance(law, WearLaw):
            where = f"wear[contact[{i}]]" if named else "wear"
            raise TypeError(f"FrettingProblem: {where} = {type(law).__name__}: expected a wear law (the WearLaw "
                            "protocol of dolfinx_fretting.laws, e.g. Archard) or None")
    accelerations = {float(law.acceleration) for law in laws if law is not None}
    if len(accelerations) > 1:
        raise ValueError(f"FrettingProblem: wear: the zones' laws have accelerations {sorted(accelerations)}: "
                         "allowed one value for every zone (each simulated cycle stands for that many physical ones)")
    return laws


def as_zones(contact: Contact | Sequence[Contact]) -> Contact | ContactZones:
    """What the operators hold: a single :class:`~dolfinx_fretting.contact.Contact` as it is (one zone: the
    arithmetic of a one-zone problem unchanged to the bit), a list of one its element, a longer list stacked."""
    if isinstance(contact, Contact):
        return contact
    if isinstance(contact, (str, bytes)) or not isinstance(contact, Sequence):
        raise TypeError(f"FrettingProblem: contact must be a Contact or a list of Contacts, got "
                        f"{type(contact).__name__}")
    zones = ContactZones(contact)
    return zones.zones[0] if len(zones.zones) == 1 else zones

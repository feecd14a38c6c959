"""Scene files: what to simulate, validated once at the edge before any expensive work.

A scene is a TOML file (or a built-in name) with the sections ``[geometry]``, ``[material]``,
``[contact]``, ``[wear]``, ``[loading]``, ``[solver]`` and ``[output]``. Units are N, mm and MPa
throughout; in 2D (plane strain) forces are per unit thickness (N/mm).

Every key is checked here: an unknown key, a wrong type or a value outside its range stops with a
:class:`SceneError` whose message names the key (``section.key``), the value given and the allowed
range. Checks that need the mesh (for instance "no contact candidate found") are made right after the
mesh is built, still before any factorisation.
"""

from __future__ import annotations

import copy
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

__all__ = ["Scene", "SceneError", "builtin_scenes", "load_scene", "apply_overrides"]


class SceneError(ValueError):
    """A scene file or override is invalid; the message names the key and the allowed range."""


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


def _range_error(key: str, value: Any, allowed: str) -> ValueError:
    return ValueError(f"{key} = {value!r} is out of range; allowed: {allowed}")


class GeometrySettings(_Section):
    """Body and mesh (mm)."""

    kind: Literal["half_cylinder", "rectangle"] = "half_cylinder"
    #: Half-cylinder radius (mm).
    radius: float = Field(6.0, gt=0)
    #: Element size in the refined contact zone (mm); the paper uses 10 µm.
    contact_mesh_size: float = Field(0.01, gt=0)
    #: Half-width of the refined contact zone (mm); ``None``: chosen from the radius (R/15).
    contact_half_width: float | None = Field(None, gt=0)
    #: Element size far from the contact (mm); ``None``: R/10 (half-cylinder) .
    coarse_mesh_size: float | None = Field(None, gt=0)
    #: Rectangle width and height (mm) and its number of cells along x and y.
    width: float = Field(50.0, gt=0)
    height: float = Field(50.0, gt=0)
    nx: int = Field(40, ge=1)
    ny: int = Field(40, ge=1)
    #: Quadrilateral (four-node) cells; triangles otherwise.
    quadrilateral: bool = True

    @model_validator(mode="after")
    def _sizes_fit_the_body(self) -> GeometrySettings:
        if self.kind == "half_cylinder":
            if self.contact_mesh_size >= self.radius:
                raise _range_error("geometry.contact_mesh_size", self.contact_mesh_size,
                                   f"0 < contact_mesh_size < geometry.radius = {self.radius} mm")
            if self.contact_half_width is not None and self.contact_half_width >= self.radius:
                raise _range_error("geometry.contact_half_width", self.contact_half_width,
                                   f"0 < contact_half_width < geometry.radius = {self.radius} mm")
            if self.contact_half_width is not None and self.contact_half_width < self.contact_mesh_size:
                raise _range_error("geometry.contact_half_width", self.contact_half_width,
                                   f"contact_mesh_size = {self.contact_mesh_size} <= contact_half_width"
                                   f" < radius = {self.radius} mm")
            if self.coarse_mesh_size is not None and self.coarse_mesh_size >= self.radius:
                raise _range_error("geometry.coarse_mesh_size", self.coarse_mesh_size,
                                   f"0 < coarse_mesh_size < geometry.radius = {self.radius} mm")
        else:
            hx, hy = self.width / self.nx, self.height / self.ny
            if min(hx, hy) <= 0 or hx > self.width or hy > self.height:  # pragma: no cover - Field bounds
                raise _range_error("geometry.nx", self.nx, "nx, ny >= 1")
        return self

    @property
    def refined_half_width(self) -> float:
        """Half-width of the refined contact zone (mm) the mesh generator uses."""
        if self.contact_half_width is not None:
            return self.contact_half_width
        return max(self.radius / 15.0, 10 * self.contact_mesh_size)


class MaterialSettings(_Section):
    """Linear elastic material (MPa)."""

    model: Literal["elastic"] = "elastic"
    #: Young's modulus (MPa).
    E: float = Field(115000.0, gt=0)
    #: Poisson's ratio; plane strain needs -1 < nu < 0.5.
    nu: float = Field(0.342, gt=-1.0, lt=0.5)


class ContactSettings(_Section):
    """Frictional contact with an obstacle."""

    #: Coulomb friction coefficient.
    mu: float = Field(0.9, ge=0)
    obstacle: Literal["rigid_plane"] = "rigid_plane"
    #: A point of the rigid plane (mm) and its unit normal pointing from the plane into the body.
    plane_point: list[float] = Field(default_factory=lambda: [0.0, 0.0], min_length=2, max_length=3)
    plane_normal: list[float] = Field(default_factory=lambda: [0.0, 1.0], min_length=2, max_length=3)
    #: Boundary of the body that may touch the obstacle (a facet tag name of the mesh).
    surface: str = "surface"
    #: Candidate window: nodes of ``surface`` within this distance (mm, along the plane) of the point
    #: of the body closest to the plane. ``None``: the refined contact zone of the mesh (half-cylinder)
    #: or the whole surface (rectangle).
    candidate_half_width: float | None = Field(None, gt=0)

    @model_validator(mode="after")
    def _normal_is_a_direction(self) -> ContactSettings:
        if len(self.plane_point) != len(self.plane_normal):
            raise ValueError(f"contact.plane_point {self.plane_point} and contact.plane_normal "
                             f"{self.plane_normal} must have the same length (2 in 2D)")
        if sum(c * c for c in self.plane_normal) < 1e-24:
            raise _range_error("contact.plane_normal", self.plane_normal, "a non-zero vector")
        return self


class WearSettings(_Section):
    """Wear law (Archard: wear gap rate = k p |slip rate|)."""

    law: Literal["none", "archard"] = "none"
    #: Archard wear coefficient (1/MPa).
    k: float = Field(0.0, ge=0)


class LoadingSettings(_Section):
    """Normal preload, then a tangential load, applied through the obstacle's rigid motion.

    Exactly one of ``normal_displacement`` (approach of the obstacle, mm) and ``normal_force``
    (total normal contact force, N/mm in 2D) is given; at most one of ``tangential_displacement`` (mm)
    and ``tangential_force`` (N/mm in 2D).
    """

    normal_displacement: float | None = Field(None, gt=0)
    normal_force: float | None = Field(None, gt=0)
    tangential_displacement: float | None = None
    tangential_force: float | None = None
    #: Increments of the normal preload stage and of the tangential stage.
    normal_increments: int = Field(4, ge=1, le=100000)
    tangential_increments: int = Field(10, ge=0, le=100000)
    #: Number of fretting cycles; 0 = preload then a monotonic tangential load.
    cycles: int = Field(0, ge=0)
    increments_per_cycle: int = Field(80, ge=2, le=100000)

    @model_validator(mode="after")
    def _one_control_each(self) -> LoadingSettings:
        if self.cycles != 0:
            raise _range_error("loading.cycles", self.cycles,
                               "0 (preload and a monotonic tangential load; cyclic loading is not in this version)")
        if (self.normal_displacement is None) == (self.normal_force is None):
            raise ValueError("loading: give exactly one of loading.normal_displacement (mm, > 0) and "
                             "loading.normal_force (N/mm, > 0)")
        if self.tangential_displacement is not None and self.tangential_force is not None:
            raise ValueError("loading: give at most one of loading.tangential_displacement (mm) and "
                             "loading.tangential_force (N/mm)")
        return self

    @property
    def normal_force_controlled(self) -> bool:
        return self.normal_force is not None

    @property
    def tangential_force_controlled(self) -> bool:
        return self.tangential_force is not None


class SolverSettings(_Section):
    """Local (contact) solver and the factorisation behind W."""

    local_method: Literal["uzawa"] = "uzawa"
    #: Unit-free tolerance of the local solver's error measure.
    local_tol: float = Field(1e-10, gt=0, lt=1)
    local_max_iter: int = Field(20000, ge=1)
    #: Relative tolerance on a prescribed force (force-controlled loads).
    force_tol: float = Field(1e-8, gt=0, lt=1)
    #: How W = H K^-1 H^T is built from the MUMPS factorisation.
    delassus_method: Literal["auto", "columns", "block", "selected_inverse"] = "auto"
    #: Extra PETSc options for the factorisation (prefix ``dolfinx_fretting_delassus_`` is added).
    petsc_options: dict[str, str | int | float | bool] = Field(default_factory=dict)


class OutputSettings(_Section):
    """What the run writes besides ``summary.json`` and ``history.csv``."""

    xdmf: bool = True
    plots: bool = True
    #: Write contact profiles (position, pressure, shear, slip, state) of every increment.
    contact_profiles: bool = True


class Scene(_Section):
    """A whole scene; see the README for every key with its unit."""

    name: str = "scene"
    description: str = ""
    geometry: GeometrySettings = Field(default_factory=GeometrySettings)
    material: MaterialSettings = Field(default_factory=MaterialSettings)
    contact: ContactSettings = Field(default_factory=ContactSettings)
    wear: WearSettings = Field(default_factory=WearSettings)
    loading: LoadingSettings = Field(default_factory=lambda: LoadingSettings(normal_force=100.0))
    solver: SolverSettings = Field(default_factory=SolverSettings)
    output: OutputSettings = Field(default_factory=OutputSettings)

    @model_validator(mode="after")
    def _window_fits(self) -> Scene:
        g, c = self.geometry, self.contact
        if g.kind == "half_cylinder" and c.candidate_half_width is not None and c.candidate_half_width > g.radius:
            raise _range_error("contact.candidate_half_width", c.candidate_half_width,
                               f"0 < candidate_half_width <= geometry.radius = {g.radius} mm")
        if len(c.plane_normal) != 2:
            raise _range_error("contact.plane_normal", c.plane_normal,
                               "a 2-vector: the geometries built in are two-dimensional (plane strain)")
        return self

    @property
    def dim(self) -> int:
        return len(self.contact.plane_normal)


def _allowed_keys(loc: tuple) -> list[str]:
    model: type[BaseModel] = Scene
    for part in loc:
        field = model.model_fields.get(str(part))
        annotation = field.annotation if field else None
        if not (isinstance(annotation, type) and issubclass(annotation, BaseModel)):
            return []
        model = annotation
    return list(model.model_fields)


def _format_validation_error(err: ValidationError, source: str) -> str:
    lines = [f"invalid scene ({source}):"]
    for e in err.errors():
        key = ".".join(str(p) for p in e["loc"])
        msg = e["msg"].removeprefix("Value error, ")
        if e["type"] == "extra_forbidden":
            msg = f"unknown key {key!r}; allowed keys here: {', '.join(_allowed_keys(e['loc'][:-1]))}"
        elif e["type"] == "missing":
            msg = f"missing key {key!r}"
        elif key and key not in msg:
            given = e.get("input")
            msg = f"{key} = {given!r}: {msg}"
        lines.append(f"  - {msg}")
    return "\n".join(lines)


def builtin_scenes() -> dict[str, Path]:
    """Built-in scene names mapped to their TOML files."""
    folder = resources.files("dolfinx_fretting") / "builtin_scenes"
    return {Path(str(p)).stem: Path(str(p)) for p in folder.iterdir() if str(p).endswith(".toml")}


def _parse_override(item: str) -> tuple[list[str], Any]:
    if "=" not in item:
        raise SceneError(f"--set {item!r}: expected section.key=value")
    key, raw = item.split("=", 1)
    path = [p for p in key.strip().split(".") if p]
    if not path:
        raise SceneError(f"--set {item!r}: empty key")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # a bare word is a string: --set geometry.kind=rectangle
    return path, value


def apply_overrides(data: dict[str, Any], overrides: list[str] | None) -> dict[str, Any]:
    """Return a copy of ``data`` with ``section.key=value`` overrides applied (values in TOML syntax)."""
    data = copy.deepcopy(data)
    for item in overrides or []:
        path, value = _parse_override(item)
        node = data
        for p in path[:-1]:
            node = node.setdefault(p, {})
            if not isinstance(node, dict):
                raise SceneError(f"--set {item!r}: {p!r} is not a section")
        node[path[-1]] = value
    return data


def load_scene(source: str | Path | dict[str, Any], overrides: list[str] | None = None) -> Scene:
    """Load and validate a scene.

    Args:
        source: A built-in scene name (see :func:`builtin_scenes`), a path to a TOML file or a dict.
        overrides: ``section.key=value`` strings applied on top (the CLI's ``--set``).

    Returns:
        The validated :class:`Scene`.

    Raises:
        SceneError: naming the offending key, its value and the allowed range.
    """
    if isinstance(source, dict):
        data, label = source, "dict"
    else:
        scenes = builtin_scenes()
        path = scenes.get(str(source), Path(source))
        if not path.is_file():
            raise SceneError(f"scene {str(source)!r} is neither a built-in scene ({', '.join(sorted(scenes))}) "
                             "nor a TOML file")
        try:
            data = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as exc:
            raise SceneError(f"{path}: not valid TOML: {exc}") from None
        label = str(path)
    data = apply_overrides(data, overrides)
    try:
        return Scene.model_validate(data)
    except ValidationError as exc:
        raise SceneError(_format_validation_error(exc, label)) from None

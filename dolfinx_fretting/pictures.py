"""Off-screen pyvista pictures of a run, drawn from its output folder.

Two PNG files, from ``fields.xdmf``/``fields.h5`` (the body's mesh, displacement and von Mises stress at
the last time written) and ``contact_profiles.csv`` (positions, pressure and wear gap of the contact
nodes at the last kept increment):

* ``deformed_von_mises.png``: the deformed body at the last field time (or the last loaded one when the
  last carries no load, said so: e.g. Example 1 after 9000 cycles), displacement magnified (the factor in
  the title), coloured by the cell-wise von Mises stress, whole body on the left and the contact zone zoomed on the
  right (the zoomed region framed in red on the left), with the rigid plane drawn; one colour scale,
  from the minimum to the maximum von Mises stress of the fields file.
* ``worn_profile.png``: the original contact surface and the worn one (wear gap magnified along the
  plane normal, the factor in the title), the removed layer coloured by wear depth, over the undeformed
  mesh. Not drawn when nothing wore.

The contact nodes are found in the mesh by their position along the surface (the t1 coordinate of
:func:`dolfinx_fretting.contact.tangent_frame`) as the mesh nodes nearest the plane, so the plane's
normal (and point, for the plane's line) must be known: the run passes its scene's; for an existing
folder they are read from the checkpoint's scene record, or given on the command line.

The pictures are rendered by VTK without a display (EGL when ``DISPLAY`` is unset). A run draws them in
a separate process (:func:`draw_in_subprocess`), so that a missing or broken pyvista/VTK/OpenGL can
only skip the pictures, never end a finished run; the same command redraws them for any output folder::

    python -m dolfinx_fretting.pictures RESULTS_DIR [--plane PX,PY,NX,NY]

In 3D (tetrahedra or hexahedra) the same two files hold a perspective view of the body (magnified, cut by
its symmetry plane where it is a half model) beside the contact zone at true scale, and the worn contact
surface (``contact.xdmf``'s triangles) with the wear magnified over the original surface.
Nothing here uses MPI: it runs on rank 0 after the run.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .contact_output import read_contact_xdmf, read_profiles
from .interrupts import stage_hook
from .io import read_run_description
from .units import Units

__all__ = ["Fields", "read_fields", "field_times", "contact_surface", "nice_factor", "deformed_plotter",
           "deformed_plotter_3d", "worn_plotter", "worn_plotter_3d", "write_pictures", "draw_in_subprocess",
           "PICTURES", "VM_TITLE", "main"]

#: Files written by :func:`write_pictures`.
PICTURES = ("deformed_von_mises.png", "worn_profile.png")
#: Scalar bar titles of a folder in the scenes' units (the tests find the colour scales by them); a folder's own
#: are :func:`vm_title` and :func:`wear_title` of its ``run.json``'s units.
VM_TITLE = "von Mises stress (MPa)"
WEAR_TITLE = "wear depth (mm)"
#: XDMF topology name -> (VTK cell type, nodes per cell); DOLFINx writes VTK node order.
_CELL_TYPES = {"Triangle": (5, 3), "Quadrilateral": (9, 4), "Tetrahedron": (10, 4), "Hexahedron": (12, 8)}
#: Colour map of both pictures (perceptually uniform, readable in grey).
CMAP = "viridis"
_WINDOW = (1600, 720)


@dataclass
class Fields:
    """The body's mesh and fields at one time of ``fields.xdmf``.

    Attributes:
        points: Node coordinates, shape (N, 3) (z = 0 in 2D).
        gdim: Geometric dimension of the mesh (2 or 3).
        cell_type: VTK cell type of every cell.
        cells: Node indices of each cell, shape (M, nodes per cell).
        displacement: Nodal displacement, shape (N, 3).
        von_mises: Cell-wise von Mises stress, shape (M,).
        time: The time (increment number) read.
    """

    points: np.ndarray
    gdim: int
    cell_type: int
    cells: np.ndarray
    displacement: np.ndarray
    von_mises: np.ndarray
    time: float


def _h5_ref(item: ET.Element, folder: Path) -> tuple[Path, str]:
    file, _, dataset = (item.text or "").strip().partition(":")
    return folder / file, dataset


def _series(domain: ET.Element, name: str) -> dict[float, ET.Element]:
    """Time -> DataItem of the temporal collection ``name``."""
    out = {}
    for grid in domain.findall("Grid"):
        if grid.get("Name") == name and grid.get("GridType") == "Collection":
            for g in grid.findall("Grid"):
                t, att = g.find("Time"), g.find("Attribute")
                if t is not None and att is not None and att.find("DataItem") is not None:
                    out[float(t.get("Value"))] = att.find("DataItem")
    return out


def field_times(folder: str | Path) -> list[float]:
    """Times of ``folder/fields.xdmf`` that hold both the displacement and the von Mises stress."""
    domain = ET.parse(Path(folder) / "fields.xdmf").getroot().find("Domain")
    return sorted(set(_series(domain, "displacement")) & set(_series(domain, "von_mises")))


def read_fields(folder: str | Path, time: float | None = None) -> Fields:
    """Read the body's mesh, displacement and von Mises stress from ``folder/fields.xdmf``.

    Args:
        folder: A run's output folder.
        time: Time to read (default: the last time that has both fields).

    Raises:
        FileNotFoundError: no ``fields.xdmf`` (the run had ``output.xdmf = false``).
        ValueError: a mesh this module does not draw (not linear triangles or quadrilaterals), or no time
            with both fields.
    """
    import h5py  # lazy: not a declared dependency (installed with DOLFINx by scripts/setup.sh)

    folder = Path(folder)
    path = folder / "fields.xdmf"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found (the run wrote no fields: output.xdmf = false?)")
    domain = ET.parse(path).getroot().find("Domain")
    mesh = next((g for g in domain.findall("Grid") if g.get("GridType", "Uniform") == "Uniform"), None)
    if mesh is None:
        raise ValueError(f"{path}: no mesh grid")
    topo, geom = mesh.find("Topology"), mesh.find("Geometry")
    kind = topo.get("TopologyType")
    if kind not in _CELL_TYPES:
        raise ValueError(f"{path}: cells of type {kind!r} are not drawn (2D linear triangles and "
                         "quadrilaterals only)")
    u_items, vm_items = _series(domain, "displacement"), _series(domain, "von_mises")
    times = sorted(set(u_items) & set(vm_items))
    if not times:
        raise ValueError(f"{path}: no time holds both displacement and von_mises")
    t = times[-1] if time is None else time
    if t not in u_items or t not in vm_items:
        raise ValueError(f"{path}: time {time} not written; times: {times}")

    def load(item: ET.Element) -> np.ndarray:
        file, dataset = _h5_ref(item, folder)
        with h5py.File(file, "r") as f:
            return np.asarray(f[dataset])

    x = load(geom.find("DataItem"))
    gdim = x.shape[1]
    points = np.zeros((x.shape[0], 3))
    points[:, :gdim] = x
    cells = load(topo.find("DataItem")).astype(np.int64)
    u = load(u_items[t])
    disp = np.zeros((x.shape[0], 3))
    disp[:, :u.shape[1]] = u
    vm = load(vm_items[t]).reshape(-1)
    if vm.size != cells.shape[0]:
        raise ValueError(f"{path}: von_mises has {vm.size} values for {cells.shape[0]} cells (not cell-wise)")
    return Fields(points=points, gdim=gdim, cell_type=_CELL_TYPES[kind][0], cells=cells, displacement=disp,
                  von_mises=vm, time=t)


def contact_surface(points: np.ndarray, position: np.ndarray, normal: np.ndarray,
                    plane_point: np.ndarray | None = None) -> np.ndarray:
    """Mesh node of each contact node: the node at ``position`` along t1 nearest the plane.

    Args:
        points: Mesh node coordinates (N, 3).
        position: Contact node positions along the surface (the t1 coordinate; written to 10 digits).
        normal: The plane's normal (2 components), pointing into the body.
        plane_point: A point of the plane: only nodes on the body's side of it are taken (needed when a
            second body lies under the plane).

    Returns:
        Node indices, shape (len(position),).

    Raises:
        ValueError: a position that no mesh node has (the folder's mesh is not the one of its profiles,
            or the normal is not the run's).
    """
    n = np.asarray(normal, dtype=float)[:2]
    n = n / np.linalg.norm(n)
    t1 = np.array([n[1], -n[0]])
    s = points[:, :2] @ t1
    h = points[:, :2] @ n
    p0_h = None if plane_point is None else float(np.asarray(plane_point, dtype=float)[:2] @ n)
    size = float(np.ptp(points[:, :2], axis=0).max()) or 1.0
    tol = 1e-7 * size  # positions are written with 10 significant digits
    order = np.argsort(s)
    nodes = np.empty(position.size, dtype=np.int64)
    for i, p in enumerate(position):
        start, stop = np.searchsorted(s[order], [p - tol, p + tol])
        cand = order[start:stop]
        if cand.size == 0:
            raise ValueError(f"no mesh node at contact position {p:.10g} (along t1 = {t1.tolist()}): "
                             "the plane normal or the folder's files do not match")
        # On the body's side of the plane: with an elastic flat under it, the flat's nodes below the plane
        # share the positions (the flat's bottom is the lowest node there).
        above = cand[h[cand] >= float(p0_h) - tol] if p0_h is not None else cand
        cand = above if above.size else cand
        nodes[i] = cand[np.argmin(h[cand])]
    return nodes


def nice_factor(target: float) -> float:
    """The largest of 1, 2, 5 x 10^k not above ``target`` (> 0): a magnification that reads well."""
    if not math.isfinite(target) or target <= 0:
        return 1.0
    k = math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**k <= target * (1 + 1e-12):
            return m * 10.0**k
    return 10.0**k


def _pyvista():
    """pyvista, off screen; EGL when there is no X display (set before VTK is loaded)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv  # lazy: optional and heavy (VTK); its backend is chosen above, before VTK loads

    pv.OFF_SCREEN = True
    return pv


def _grid(pv, f: Fields, points: np.ndarray):
    grid = pv.UnstructuredGrid({f.cell_type: f.cells}, points)
    return grid


def _frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = np.asarray(n, dtype=float)[:2]
    n = n / np.linalg.norm(n)
    return n, np.array([n[1], -n[0]])


def _to3(v: np.ndarray) -> np.ndarray:
    return np.array([v[0], v[1], 0.0])


def _view_2d(renderer, centre: np.ndarray, half_width: float, half_height: float, aspect: float,
             bar_room: float = 0.2) -> tuple[np.ndarray, np.ndarray]:
    """Parallel projection looking down -z that shows the box ``centre +- (half_width, half_height)`` in
    the part of the viewport above its bottom ``bar_room`` share (kept for a colour bar).

    Args:
        aspect: Width / height of the viewport in pixels.

    Returns:
        Lower and upper corners of the region shown above the colour bar (at least the box asked for).
    """
    S = max(half_height, half_width / aspect) / (1 - bar_room)  # half of the viewport's height, in mm
    cy = centre[1] - bar_room * S  # the box centred in the part above the bar
    cam = renderer.camera
    cam.enable_parallel_projection()
    cam.focal_point = (centre[0], cy, 0.0)
    cam.position = (centre[0], cy, 10.0 * S)
    cam.up = (0.0, 1.0, 0.0)
    cam.parallel_scale = S
    renderer.camera_set = True  # else pyvista resets the camera to fit everything at the first render
    lower = np.array([centre[0] - S * aspect, cy - S + 2 * bar_room * S])
    upper = np.array([centre[0] + S * aspect, cy + S])
    return lower, upper


def _outline(pv, lower: np.ndarray, upper: np.ndarray):
    pts = np.array([[lower[0], lower[1], 0], [upper[0], lower[1], 0], [upper[0], upper[1], 0], [lower[0], upper[1], 0]])
    return pv.lines_from_points(np.vstack([pts, pts[:1]]))


def _scalar_bar(pl, title: str, mapper) -> None:
    """A horizontal colour bar at the bottom of the current viewport, labels and title below it.

    pyvista keeps one bar per title in a plotter: a second viewport's bar needs another title string.
    """
    pl.add_scalar_bar(title=title, mapper=mapper, vertical=False, position_x=0.2, position_y=0.02,
                            width=0.6, height=0.11, title_font_size=18, label_font_size=15, n_labels=5,
                            fmt="%.4g", color="black", background_color="white")
    pl.scalar_bars[title].SetTextPositionToPrecedeScalarBar()


def deformed_plotter(folder: str | Path, plane_point, plane_normal, f: Fields | None = None,
                     draw_plane: bool = True):
    """The deformed-mesh picture as an off-screen pyvista Plotter (not yet rendered).

    Returns:
        (plotter, info): ``info`` holds ``clim`` (the colour range: min and max von Mises stress of the
        fields), ``scale`` (displacement magnification), ``zoom`` (lower and upper corners of the zoomed
        region, deformed coordinates) and ``time``. ``draw_plane``: draw the rigid plane (not when the obstacle
        is a second, meshed body).
    """
    pv = _pyvista()
    f = read_fields(folder) if f is None else f
    if f.gdim != 2:
        raise ValueError("3D meshes are not drawn")
    vm_bar = vm_title(folder_units(folder))
    n, t1 = _frame(plane_normal)
    p0 = np.asarray(plane_point, dtype=float)[:2]
    lower, upper = f.points.min(axis=0), f.points.max(axis=0)
    size = float(np.max(upper - lower))
    umax = float(np.linalg.norm(f.displacement, axis=1).max())
    # Magnify so that the largest displacement shows as ~4 % of the body's size.
    scale = nice_factor(0.04 * size / umax) if umax > 0 else 1.0
    # The whole body magnified; the zoom at true scale, where a magnified rigid approach would push the
    # contact surface through the plane.
    grids = []
    for factor in (scale, 1.0):
        g = _grid(pv, f, f.points + factor * f.displacement)
        g.cell_data[vm_bar] = f.von_mises
        grids.append(g)
    xdef = f.points + f.displacement
    clim = (float(f.von_mises.min()), float(f.von_mises.max()))
    if clim[1] <= clim[0]:
        clim = (clim[0], clim[0] + 1.0)

    # The contact zone: the loaded contact nodes at the fields' increment, else at the last kept one (all
    # of them when none is loaded).
    prof = read_profiles(folder)
    zlo, zhi = lower[:2], upper[:2]
    if prof is not None:
        nodes = contact_surface(f.points, prof.position, n, p0)
        row = prof.index(int(round(f.time)))  # the fields' increment (time = increment number)
        loaded = prof.values["pressure"][-1 if row is None else row] > 0
        sel = nodes[loaded] if loaded.any() else nodes
        pts = xdef[sel, :2]
        s = pts @ t1
        along = np.sort(f.points[nodes, :2] @ t1)
        spacing = float(np.median(np.diff(along))) if nodes.size > 1 else size / 50
        half = max(0.5 * float(s.max() - s.min()), 3 * spacing) * 1.3
        c_s = 0.5 * (s.max() + s.min())
        c_h = float((pts @ n).min())
        centre = c_s * t1 + (c_h + 0.45 * half) * n
        zlo = np.minimum(centre - half * t1 - 0.5 * half * n, centre + half * t1 + 0.5 * half * n)
        zhi = np.maximum(centre - half * t1 - 0.5 * half * n, centre + half * t1 + 0.5 * half * n)
    title_h = 0.07  # the title row's share of the window height
    aspect = (_WINDOW[0] / 2) / (_WINDOW[1] * (1 - title_h))

    pl = pv.Plotter(off_screen=True, shape=(2, 2), groups=[(0, np.s_[:])], row_weights=[title_h, 1 - title_h],
                    window_size=list(_WINDOW), border=False)
    pl.set_background("white")
    pl.subplot(0, 0)
    pl.add_text(f"Deformed shape coloured by von Mises stress, increment {f.time:g} "
                f"(displacement x {scale:g} on the left)",
                position="upper_edge", font_size=13, color="black")
    undeformed = _grid(pv, f, f.points).extract_feature_edges(boundary_edges=True, feature_edges=False,
                                                              manifold_edges=False, non_manifold_edges=False)
    plane = pv.Line(_to3(p0 - 2 * size * t1), _to3(p0 + 2 * size * t1))
    mesh_kw = dict(scalars=vm_bar, cmap=CMAP, clim=clim, lighting=False, show_scalar_bar=False)
    many = f.cells.shape[0] > 4000  # edges of small cells would paint the whole body grey
    labels = (f"whole body, displacement x {scale:g} (undeformed outline grey)",
              "contact zone, true scale (framed red on the left)")
    for col, title in enumerate(labels):
        pl.subplot(1, col)
        actor = pl.add_mesh(grids[col], show_edges=col == 1 or not many, edge_color="#404040", line_width=0.5,
                            **mesh_kw)
        pl.add_mesh(undeformed, color="#9a9a9a", line_width=1)
        if draw_plane:
            pl.add_mesh(plane, color="black", line_width=3)
        label = pl.add_text(title, position="upper_left", font_size=10, color="black")
        label.GetTextProperty().SetBackgroundColor(1.0, 1.0, 1.0)
        label.GetTextProperty().SetBackgroundOpacity(0.85)
        _scalar_bar(pl, vm_bar + " " * col, actor.mapper)
        bar_room = 0.2  # bottom share of the viewport kept for the colour bar
        if col == 0:
            c, hw, hh = 0.5 * (lower + upper)[:2], 0.55 * (upper - lower)[0], 0.55 * (upper - lower)[1]
        else:
            c, hw, hh = 0.5 * (zlo + zhi), 0.5 * (zhi - zlo)[0], 0.5 * (zhi - zlo)[1]
        shown = _view_2d(pl.renderer, c, hw, hh, aspect, bar_room)
        if col == 1:
            pl.subplot(1, 0)
            margin = 0.03 * size  # the frame: what the zoom shows, within the body's box plus a margin
            frame = _outline(pv, np.maximum(shown[0], lower[:2] - margin), np.minimum(shown[1], upper[:2] + margin))
            pl.add_mesh(frame, color="red", line_width=2)
    return pl, {"clim": clim, "scale": scale, "zoom": (zlo, zhi), "time": f.time, "fields": f}


def worn_plotter(folder: str | Path, plane_normal, f: Fields | None = None, plane_point=None):
    """The worn-profile picture as an off-screen pyvista Plotter, or ``None`` when nothing wore.

    Returns:
        (plotter, info) with ``magnification`` (of the wear gap), ``max_wear`` (in the folder's length unit), ``cycle`` and
        ``increment`` of the profile drawn; ``(None, info)`` when the wear is zero everywhere.
    """
    pv = _pyvista()
    f = read_fields(folder) if f is None else f
    units = folder_units(folder)
    wear_bar = wear_title(units)
    prof = read_profiles(folder)
    if prof is None:
        raise FileNotFoundError(f"{Path(folder) / 'contact_profiles.csv'}: no complete contact profile")
    n, t1 = _frame(plane_normal)
    wear = prof.values["wear"][-1]
    info = {"cycle": int(prof.cycles[-1]), "increment": int(prof.increments[-1]),
            "max_wear": float(wear.max()) if wear.size else 0.0}
    if not wear.size or wear.max() <= 0:
        return None, info
    nodes = contact_surface(f.points, prof.position, n, plane_point)
    order = np.argsort(prof.position)
    nodes, wear = nodes[order], wear[order]
    x0 = f.points[nodes, :2]
    worn_zone = np.flatnonzero(wear > 0)
    s = x0 @ t1
    s_lo, s_hi = s[worn_zone.min()], s[worn_zone.max()]
    spacing = float(np.median(np.diff(s))) if s.size > 1 else 1.0
    width = max(s_hi - s_lo, 4 * spacing) * 1.25
    # Magnify the wear so the deepest point shows as ~20 % of the worn zone's width.
    mag = nice_factor(0.2 * width / wear.max())
    # One body: the wear gap is removed from it. Two bodies (the obstacle is a meshed flat): each loses its
    # share k_body / (k_slave + k_master) of the gap, the cylinder upwards, the flat downwards from the
    # plane, at the point paired with each cylinder node.
    share = _slave_share(Path(folder)) if plane_point is not None else None
    layers = [(x0, wear if share is None else share * wear, 1.0)]
    if share is not None and share < 1.0:
        p0_h = float(np.asarray(plane_point, dtype=float)[:2] @ n)
        flat0 = x0 - ((x0 @ n) - p0_h)[:, None] * n[None, :]
        layers.append((flat0, (1.0 - share) * wear, -1.0))
    pl = pv.Plotter(off_screen=True, window_size=[_WINDOW[0], _WINDOW[1]])
    pl.set_background("white")
    k = x0.shape[0]
    quads = np.array([[4, i, i + 1, k + i + 1, k + i] for i in range(k - 1)]).ravel()
    for surface, removed, sign in layers:
        pts = np.zeros((2 * k, 3))
        pts[:k, :2], pts[k:, :2] = surface, surface + sign * mag * removed[:, None] * n[None, :]
        # Above the mesh drawn for scale (z towards the camera), the surfaces' lines above the band.
        pts[:, 2] = 1e-3 * width
        band = pv.PolyData(pts, faces=quads)
        band.point_data[wear_bar] = np.concatenate([removed, removed])
        actor = pl.add_mesh(band, scalars=wear_bar, cmap=CMAP, clim=(0.0, float(wear.max())), lighting=False,
                            show_scalar_bar=False)
        pl.add_mesh(pv.lines_from_points(pts[:k] + [0.0, 0.0, 1e-3 * width]), color="black", line_width=3)
        pl.add_mesh(pv.lines_from_points(pts[k:] + [0.0, 0.0, 1e-3 * width]), color="#d62728", line_width=3)
    _scalar_bar(pl, wear_bar, actor.mapper)
    # Key in the free band between the profile and the colour bar (the profile sits above 40 % of the height).
    pl.add_text("black: original surface", position=(40, int(0.3 * _WINDOW[1])), font_size=11, color="black")
    pl.add_text(f"red: worn surface (wear x {mag:g})", position=(40, int(0.25 * _WINDOW[1])), font_size=11,
                color="#d62728")
    cycle = f"cycle {info['cycle']}" if info["cycle"] > 0 else "the monotonic load"
    bodies = "" if len(layers) == 1 else (f"\nthe wear gap shared: cylinder {100 * share:.0f} % (above), "
                                          f"flat {100 * (1 - share):.0f} % (below)")
    pl.add_text(f"Worn profile after {cycle} (increment {info['increment']}): wear x {mag:g}, "
                f"max wear gap {wear.max():.3g} {units.length}{bodies}", position="upper_edge", font_size=12, color="black")
    c_s = 0.5 * (s_lo + s_hi)
    h0 = float((x0 @ n)[worn_zone].min())
    depth = mag * float(wear.max())
    centre = c_s * t1 + (h0 + 0.5 * depth * (1.0 if len(layers) == 1 else share - (1 - share))) * n
    lower, upper = _view_2d(pl.renderer, centre, 0.5 * width, 0.9 * depth, _WINDOW[0] / _WINDOW[1])
    # The undeformed mesh around the contact for scale, below the title (top 12 % of the view).
    top = upper[1] - 0.12 * (upper[1] - lower[1])
    body = _grid(pv, f, f.points)
    centres = body.cell_centers().points[:, :2]
    near = body.extract_cells(np.flatnonzero(np.all((centres > lower) & (centres < [upper[0], top]), axis=1)))
    if near.n_cells:
        pl.add_mesh(near, style="wireframe", color="#c8c8c8", line_width=1)
    info.update(magnification=mag)
    return pl, info


def _contact_box_3d(folder: Path, f: Fields) -> tuple[np.ndarray, float]:
    """Centre and half-size of the loaded contact (at the fields' increment, else the last kept one)."""
    prof = read_profiles(folder)
    size = float(np.max(f.points.max(axis=0) - f.points.min(axis=0)))
    if prof is None or prof.position_2 is None:
        return 0.5 * (f.points.min(axis=0) + f.points.max(axis=0)), 0.5 * size
    row = prof.index(int(round(f.time)))
    pressure = prof.values["pressure"][-1 if row is None else row]
    loaded = pressure > 0 if (pressure > 0).any() else np.ones(pressure.size, bool)
    xy = np.column_stack([prof.position[loaded], prof.position_2[loaded]])
    spacing = float(np.median(np.diff(np.unique(prof.position)))) if prof.position.size > 1 else size / 50
    half = max(float(np.abs(xy).max()), 3 * spacing) * 1.6
    return np.array([0.0, 0.0, 0.0]), half


def deformed_plotter_3d(folder: str | Path, f: Fields | None = None):
    """The 3D deformed-body picture as an off-screen pyvista Plotter (not yet rendered): the whole mesh with
    the displacement magnified, and the contact zone at true scale, coloured by von Mises stress, seen
    obliquely from the side of the symmetry plane y = 0 (a half model shows its cut there).

    Returns:
        (plotter, info) with ``clim``, ``scale``, ``time`` as :func:`deformed_plotter`.
    """
    pv = _pyvista()
    vm_bar = vm_title(folder_units(folder))
    folder = Path(folder)
    f = read_fields(folder) if f is None else f
    if f.gdim != 3:
        raise ValueError("deformed_plotter_3d draws 3D meshes; deformed_plotter draws 2D ones")
    lower, upper = f.points.min(axis=0), f.points.max(axis=0)
    size = float(np.max(upper - lower))
    umax = float(np.linalg.norm(f.displacement, axis=1).max())
    scale = nice_factor(0.04 * size / umax) if umax > 0 else 1.0
    clim = (float(f.von_mises.min()), float(f.von_mises.max()))
    if clim[1] <= clim[0]:
        clim = (clim[0], clim[0] + 1.0)
    centre, half = _contact_box_3d(folder, f)
    pl = pv.Plotter(off_screen=True, shape=(1, 2), window_size=list(_WINDOW), border=False)
    pl.set_background("white")
    titles = (f"Deformed body coloured by von Mises stress, increment {f.time:g} (displacement x {scale:g})",
              "contact zone, true scale")
    for col, factor in enumerate((scale, 1.0)):
        pl.subplot(0, col)
        grid = _grid(pv, f, f.points + factor * f.displacement)
        grid.cell_data[vm_bar] = f.von_mises
        if col == 1:  # the cells around the contact only: the zone is a small part of the body
            box = (centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half, centre[2] - half,
                   centre[2] + half)
            grid = grid.clip_box(box, invert=False)
        actor = pl.add_mesh(grid, scalars=vm_bar, cmap=CMAP, clim=clim, show_edges=col == 1,
                            edge_color="#404040", line_width=0.5, show_scalar_bar=False)
        _scalar_bar(pl, vm_bar + " " * col, actor.mapper)
        pl.add_text(titles[col], position="upper_left", font_size=11 if col == 0 else 10, color="black")
        # Obliquely from -y (the symmetry plane's side), a little above the contact plane; framed to fit.
        pl.view_vector((0.55, -1.0, 0.45), viewup=(0.0, 0.0, 1.0))
        pl.reset_camera()
        pl.camera.zoom(0.9)
    return pl, {"clim": clim, "scale": scale, "time": f.time, "fields": f}


def worn_plotter_3d(folder: str | Path, plane_normal):
    """The worn contact surface in 3D (``contact.xdmf``'s last time): the surface moved by the magnified
    wear gap along the plane normal (into the body), coloured by the wear gap, over the original surface's
    wireframe. ``(None, info)`` when nothing wore.

    Returns:
        (plotter, info) with ``magnification``, ``max_wear`` (in the folder's length unit), ``cycle`` and ``increment``.
    """
    pv = _pyvista()
    folder = Path(folder)
    units = folder_units(folder)
    wear_bar = wear_title(units)
    data = read_contact_xdmf(folder / "contact.xdmf")
    wear = np.asarray(data["point_data"][-1]["wear"], dtype=float)
    info = {"cycle": int(data["cycles"][-1]), "increment": int(data["times"][-1]),
            "max_wear": float(wear.max()) if wear.size else 0.0}
    if not wear.size or wear.max() <= 0:
        return None, info
    n = np.asarray(plane_normal, dtype=float)
    n = n / np.linalg.norm(n)
    points = np.asarray(data["points"], dtype=float)
    worn_zone = points[wear > 0]
    width = float(np.max(worn_zone.max(axis=0) - worn_zone.min(axis=0))) or 1.0
    mag = nice_factor(0.15 * width / wear.max())  # the deepest point at ~15 % of the scar's width
    tri = np.asarray(data["cells"][1], dtype=np.int64)
    faces = np.column_stack([np.full(tri.shape[0], 3), tri]).ravel()
    worn = pv.PolyData(points + mag * wear[:, None] * n[None, :], faces=faces)
    worn.point_data[wear_bar] = wear
    original = pv.PolyData(points, faces=faces)
    pl = pv.Plotter(off_screen=True, window_size=[_WINDOW[0], _WINDOW[1]])
    pl.set_background("white")
    actor = pl.add_mesh(worn, scalars=wear_bar, cmap=CMAP, clim=(0.0, float(wear.max())), show_scalar_bar=False,
                        lighting=False)
    pl.add_mesh(original, style="wireframe", color="#9a9a9a", line_width=1)
    _scalar_bar(pl, wear_bar, actor.mapper)
    cycle = f"cycle {info['cycle']}" if info["cycle"] > 0 else "the monotonic load"
    pl.add_text(f"Worn contact surface after {cycle} (increment {info['increment']}): wear x {mag:g}, "
                f"max wear gap {wear.max():.3g} {units.length}\n(grey: the original surface)", position="upper_left",
                font_size=11, color="black")
    pl.view_vector(tuple(np.array([0.5, -1.0, 0.0]) - 0.8 * n), viewup=tuple(n))  # from below the plane
    pl.reset_camera()
    info.update(magnification=mag)
    return pl, info


def folder_units(folder: str | Path) -> Units:
    """The units of a run's output folder (``run.json``). A folder without declared units (no ``run.json``, or
    one of format 1 or 2, written before units were declared) is labelled as its release did: mm, N, MPa."""
    run = read_run_description(folder)
    if run is None or int(run.get("format", 1)) < 3 or "units" not in run:
        return Units.mm_N_MPa()
    return Units.from_json(run["units"])


def vm_title(units: Units) -> str:
    """The von Mises scalar bar's title."""
    return f"von Mises stress ({units.stress})"


def wear_title(units: Units) -> str:
    """The wear depth scalar bar's title."""
    return f"wear depth ({units.length})"


def _plane_from_description(folder: Path) -> tuple[list[float], list[float]] | None:
    """The obstacle plane (point, normal) recorded in the folder's ``run.json``, if any."""
    run = read_run_description(folder)
    if run is None:
        return None
    return list(run["obstacle"]["point"]), list(run["obstacle"]["normal"])


def _slave_share(folder: Path) -> float | None:
    """The cylinder's share of the wear gap when the obstacle is a meshed body (``run.json``), else None."""
    run = read_run_description(folder)
    if run is None or run["obstacle"]["kind"] != "elastic_body" or run.get("slave_wear_share") is None:
        return None
    return float(run["slave_wear_share"])


def _obstacle_is_a_body(folder: Path) -> bool:
    """Whether the run's obstacle is a meshed body (``run.json``)."""
    run = read_run_description(folder)
    return run is not None and run["obstacle"]["kind"] == "elastic_body"


def write_pictures(folder: str | Path, plane_point=None, plane_normal=None) -> list[str]:
    """Draw :data:`PICTURES` into ``folder`` (a run's output folder).

    Args:
        folder: The output folder (``fields.xdmf``, ``contact_profiles.csv``).
        plane_point, plane_normal: The rigid plane (normal pointing into the body); default: the scene in
            the folder's run.json, else the built-in scenes' plane y = 0 with normal (0, 1).

    Returns:
        One line per picture: the file written, or why it was not.
    """
    folder = Path(folder)
    notes = []
    if plane_normal is None:
        rec = _plane_from_description(folder)
        if rec is None:
            rec = ([0.0, 0.0], [0.0, 1.0])
            notes.append("plane not recorded in the folder: assumed y = 0, normal (0, 1)")
        plane_point, plane_normal = rec
    if plane_point is None:
        plane_point = [0.0, 0.0]
    f = read_fields(folder)
    if not f.displacement.any() and not f.von_mises.any():
        # e.g. Example 1 after 9000 cycles: the preload is worn away and q = 0 at the end of a cycle
        loaded = None
        for t in reversed(field_times(folder)[:-1]):
            g = read_fields(folder, t)
            if g.von_mises.any():
                loaded = g
                break
        notes.append(f"the last field time (increment {f.time:g}) carries no load"
                     + (f": the deformed picture shows increment {loaded.time:g}, the last loaded one"
                        if loaded is not None else ""))
        f = loaded if loaded is not None else f
    if f.gdim == 3:
        pl, info = deformed_plotter_3d(folder, f)
        pl_worn, winfo = worn_plotter_3d(folder, plane_normal)
        kind = "3D, "
    else:
        pl, info = deformed_plotter(folder, plane_point, plane_normal, f, draw_plane=not _obstacle_is_a_body(folder))
        pl_worn, winfo = worn_plotter(folder, plane_normal, f, plane_point)
        kind = ""
    pl.screenshot(str(folder / PICTURES[0]))
    pl.close()
    notes.append(f"wrote {folder / PICTURES[0]} ({kind}displacement x {info['scale']:g}, von Mises "
                 f"{info['clim'][0]:.4g}..{info['clim'][1]:.4g} {folder_units(folder).stress})")
    if pl_worn is None:
        notes.append(f"{PICTURES[1]} not drawn: no wear")
    else:
        pl_worn.screenshot(str(folder / PICTURES[1]))
        pl_worn.close()
        notes.append(f"wrote {folder / PICTURES[1]} ({kind}wear x {winfo['magnification']:g})")
    return notes


def draw_in_subprocess(folder: str | Path, plane_point, plane_normal, timeout: float = 300.0,
                       stop: Callable[[], bool] | None = None) -> str:
    """Draw the pictures by ``python -m dolfinx_fretting.pictures`` in a child process; never raises.

    A run calls this on rank 0 once its outputs are on disk: whatever happens in VTK (no pyvista, no
    OpenGL, a crash) costs the pictures only.

    Args:
        folder: The run's output folder.
        plane_point: The rigid plane's point (2 or 3 numbers).
        plane_normal: Its normal.
        timeout: Seconds after which the drawing is stopped.
        stop: Asked every :data:`POLL_SECONDS` while the child draws; when it says yes (a signal reached the
            run), the child is stopped and the pictures skipped.

    Returns:
        A one-line report: what was written, or that the pictures were skipped and why.
    """
    p = ",".join(f"{v:.17g}" for v in (*list(plane_point), *list(plane_normal)))  # 4 numbers in 2D, 6 in 3D
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "PMI_"))}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[1]), env.get("PYTHONPATH", "")])
    # the child's output goes to temporary files, not pipes: VTK's warnings cannot fill a pipe while it is polled
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen([sys.executable, "-m", "dolfinx_fretting.pictures", str(folder), "--plane", p],
                                env=env, stdout=out, stderr=err, text=True)
        deadline = time.monotonic() + timeout
        while proc.poll() is None:
            if stop is not None and stop():
                _end(proc)
                return "pictures skipped: the run was interrupted"
            if time.monotonic() > deadline:
                _end(proc)
                return f"pictures skipped: drawing took more than {timeout:g} s"
            time.sleep(POLL_SECONDS)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    if proc.returncode != 0:
        lines = (stderr or stdout).strip().splitlines()
        return f"pictures skipped: {lines[-1] if lines else f'exit code {proc.returncode}'}"
    return "pictures: " + "; ".join(stdout.strip().splitlines())


#: Seconds between two looks at a drawing child (a signal stops it within this).
POLL_SECONDS = 0.05


def _end(proc: subprocess.Popen) -> None:
    """Stop a drawing child: SIGTERM, then SIGKILL if it has not ended within 5 s."""
    proc.terminate()
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def main(argv: list[str] | None = None) -> int:
    """``python -m dolfinx_fretting.pictures DIR [--plane PX,PY,NX,NY | PX,PY,PZ,NX,NY,NZ]``: 0 drawn, 1 skipped
    or failed, 2 a bad ``--plane``."""
    ap = argparse.ArgumentParser(prog="python -m dolfinx_fretting.pictures",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path, help="a run's output folder")
    ap.add_argument("--plane", default=None, metavar="PX,PY,NX,NY",
                    help="the rigid plane's point and normal, 2D (or PX,PY,PZ,NX,NY,NZ in 3D; default: from the "
                         "folder's run.json)")
    args = ap.parse_args(argv)
    point = normal = None
    if args.plane is not None:
        try:
            v = [float(t) for t in args.plane.split(",")]
            half = len(v) // 2
            if len(v) not in (4, 6) or not all(map(math.isfinite, v)) or not any(v[half:]):
                raise ValueError
        except ValueError:
            print(f"--plane: four (2D) or six (3D) finite numbers, a point and a non-zero normal, got "
                  f"{args.plane!r}", file=sys.stderr)
            return 2
        point, normal = v[:half], v[half:]
    stage_hook("pictures")  # a test hook: wait here (interrupts.TEST_HOOK) for the run to stop this process
    try:
        import pyvista  # noqa: F401 - lazy: optional (the pictures extra); tried here to fail with a message
    except Exception as exc:  # noqa: BLE001 - ImportError, or a VTK that cannot load
        print(f"pyvista not importable ({type(exc).__name__}: {exc}); install it with scripts/setup.sh",
              file=sys.stderr)
        return 1
    try:
        for line in write_pictures(args.folder, point, normal):
            print(line)
    except (OSError, ValueError) as exc:
        print(f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

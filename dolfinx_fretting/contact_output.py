"""Contact output read back from a run's tables, and written as an XDMF time series of the contact nodes.

Tables (``history.csv``, ``cycles.csv``, ``contact_profiles.csv``, see :mod:`dolfinx_fretting.io`) are read
with :func:`read_table`, which accepts a folder a run is still writing or left behind when it was stopped:
an unterminated last line is ignored. :func:`read_profiles` turns ``contact_profiles.csv`` into arrays of
shape (kept increments, contact nodes), dropping increments whose rows are incomplete.

:func:`write_contact_xdmf` writes ``contact.xdmf`` + ``contact.h5``: the contact nodes as a polyline at
``(position, 0, 0)`` (position along the surface, mm), one grid per kept increment in a temporal
collection (time = increment number) with the point attributes of :data:`XDMF_FIELDS`. The XML is plain
XDMF 3 without XInclude: every grid names the same HDF5 topology and geometry datasets, which ParaView
and meshio's ``TimeSeriesReader`` both read. :func:`read_contact_xdmf` reads the pair back by following
the XML. Everything here is plain Python for rank 0 (no MPI).
"""

from __future__ import annotations

import csv
import os
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["read_table", "read_profiles", "ContactProfiles", "write_contact_xdmf", "read_contact_xdmf",
           "XDMF_FIELDS", "STATE_NAMES"]

#: Columns of the tables that hold text; every other column is numeric.
_TEXT_COLUMNS = frozenset({"stage", "regime", "jump_bound", "plastic_regime"})
#: Numeric columns that hold integers (counts, indices, state codes).
_INT_COLUMNS = frozenset({"increment", "cycle", "step", "node", "state", "n_open", "n_stick", "n_slip",
                          "local_iterations", "load_solves", "jump", "zone"})
#: Per-node columns of ``contact_profiles.csv`` after ``position``.
_PROFILE_VALUES = ("gap", "pressure", "shear", "slip", "relative_tangential", "wear", "state")
#: The t2 columns of a 3D contact's profiles (besides ``position_2``, the node's position along t2).
_PROFILE_VALUES_3D = ("shear_2", "slip_2", "relative_tangential_2")
#: Point attributes of ``contact.xdmf`` (``state``: 0 open, 1 stick, 2 slip).
XDMF_FIELDS = ("pressure", "shear", "slip", "wear", "gap", "relative_tangential", "state")
#: Names of the contact state codes.
STATE_NAMES = {0: "open", 1: "stick", 2: "slip"}


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """Read one of a run's CSV tables as a dict of columns.

    Text columns (``stage``, ``regime``, ``jump_bound``, ``plastic_regime``) are arrays of ``str``, integer
    columns (``increment``, ``node``, ``state``, ...) ``int64`` and the others ``float64``. The table may be incomplete: a last line without
    its newline (a write in progress or cut short) and lines with the wrong number of fields are skipped,
    and a value that is not a number reads as NaN (an integer column that holds one stays ``float64``).
    Well-formed tables stream through numpy's C parser (a 720 000-row ``history.csv`` in about a second,
    without holding its text in memory).

    Args:
        path: The CSV file (header line first).

    Returns:
        Column name -> array; all arrays have the same length (possibly 0). An empty dict when the file
        does not exist or has no complete header line.
    """
    path = Path(path)
    if not path.is_file():
        return {}
    with open(path, encoding="utf-8", errors="replace") as f:
        head = f.readline()
    if not head.endswith("\n") or not head.strip():
        return {}
    header = [h.strip() for h in head.split(",")]
    try:
        table = _parse_fast(path, header)
    except ValueError:
        table = _parse_slow(path, header)
    for name in _INT_COLUMNS.intersection(table):
        arr = table[name]
        if not arr.size or np.all(np.isfinite(arr)):
            table[name] = arr.astype(np.int64)
    return table


def _rows(path: Path, ncol: int):
    """The complete data lines of a CSV file with ``ncol`` fields (header and other lines skipped)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        f.readline()
        for line in f:
            if line.endswith("\n") and line.count(",") == ncol - 1:
                yield line


def _parse_fast(path: Path, header: list[str]) -> dict[str, np.ndarray]:
    """Columns of the complete rows by ``np.loadtxt``; ``ValueError`` when a value is not a number."""
    ncol = len(header)
    num = [i for i, h in enumerate(header) if h not in _TEXT_COLUMNS]
    table: dict[str, np.ndarray] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "input contained no data": a header-only table
        if num:
            values = np.loadtxt(_rows(path, ncol), delimiter=",", usecols=num, dtype=float, ndmin=2)
            for k, i in enumerate(num):
                table[header[i]] = values[:, k]
        for i, h in enumerate(header):
            if h in _TEXT_COLUMNS:
                # a fixed width: numpy's parser is slow for dtype=str
                text = np.loadtxt(_rows(path, ncol), delimiter=",", usecols=[i], dtype="U32", ndmin=1)
                table[h] = text.astype(f"U{max(1, int(np.char.str_len(text).max(initial=1)))}")
    return {h: table[h] for h in header}


def _parse_slow(path: Path, header: list[str]) -> dict[str, np.ndarray]:
    """Columns of the complete rows value by value: a value that is not a number reads as NaN."""
    rows = list(csv.reader(_rows(path, len(header))))
    columns = list(zip(*rows)) if rows else [()] * len(header)
    table: dict[str, np.ndarray] = {}
    for name, values in zip(header, columns):
        if name in _TEXT_COLUMNS:
            table[name] = np.array(values, dtype=str)
        else:
            table[name] = np.array([_to_float(v) for v in values], dtype=float)
    return table


def _to_float(value: str) -> float:
    try:
        return float(value)
    except ValueError:
        return float("nan")


@dataclass
class ContactProfiles:
    """The complete increments of ``contact_profiles.csv`` as arrays.

    Attributes:
        increments: Kept increment numbers, ascending, shape (m,).
        cycles: Cycle of each kept increment (0: preload or monotonic load), shape (m,).
        steps: Step of each kept increment within its cycle, shape (m,).
        nodes: Column numbers 0..n-1 (the CSV's ``node`` column when the node set never changed), shape (n,).
        position: Node positions along the surface (mm; in 3D along t1), ascending, shape (n,): the union
            over the kept increments.
        values: ``gap``, ``pressure``, ``shear``, ``slip``, ``relative_tangential``, ``wear`` (float) and
            ``state`` (int: 0 open, 1 stick, 2 slip), each of shape (m, n), row i for ``increments[i]``; in 3D
            also ``shear_2``, ``slip_2``, ``relative_tangential_2`` (the t2 components).
        position_2: 3D: node positions along t2 (nodes ordered by (position, position_2)); None in 2D.
    """

    increments: np.ndarray
    cycles: np.ndarray
    steps: np.ndarray
    nodes: np.ndarray
    position: np.ndarray
    values: dict[str, np.ndarray] = field(default_factory=dict)
    position_2: np.ndarray | None = None

    @property
    def dim(self) -> int:
        """2 or 3 (the contact's dimension)."""
        return 2 if self.position_2 is None else 3

    def index(self, increment: int) -> int | None:
        """Row of ``increment`` in the arrays, or ``None`` when it was not kept."""
        i = int(np.searchsorted(self.increments, increment))
        if i < self.increments.size and self.increments[i] == increment:
            return i
        return None

    def rows_of_cycle(self, cycle: int) -> np.ndarray:
        """Rows of the kept increments of ``cycle``, in increasing step order."""
        rows = np.flatnonzero(self.cycles == cycle)
        return rows[np.argsort(self.steps[rows], kind="stable")]

    def section(self, position_2: float = 0.0) -> ContactProfiles:
        """A 3D contact's nodes on the line along t1 nearest to ``position_2`` (a profile along the sliding
        direction), as 2D profiles; 2D profiles are returned as they are."""
        if self.position_2 is None:
            return self
        levels = np.unique(self.position_2)
        level = levels[np.argmin(np.abs(levels - position_2))]
        cols = np.flatnonzero(self.position_2 == level)
        return ContactProfiles(self.increments, self.cycles, self.steps, np.arange(cols.size), self.position[cols],
                               {k: v[:, cols] for k, v in self.values.items()})

    def section_across(self, position: float = 0.0) -> ContactProfiles:
        """A 3D contact's nodes on the line along t2 nearest to ``position`` (a profile across the sliding
        direction), as 2D profiles whose position is along t2."""
        if self.position_2 is None:
            raise ValueError("section_across: a 2D contact has no direction across the sliding one")
        levels = np.unique(self.position)
        level = levels[np.argmin(np.abs(levels - position))]
        cols = np.flatnonzero(self.position == level)
        cols = cols[np.argsort(self.position_2[cols], kind="stable")]
        return ContactProfiles(self.increments, self.cycles, self.steps, np.arange(cols.size), self.position_2[cols],
                               {k: v[:, cols] for k, v in self.values.items()})

    def nearest_node(self, position: float, position_2: float = 0.0) -> int:
        """Column of the contact node nearest to ``position`` (mm along the surface; in 3D the point
        (``position``, ``position_2``) of the contact plane)."""
        if self.position_2 is None:
            return int(np.argmin(np.abs(self.position - position)))
        return int(np.argmin(np.hypot(self.position - position, self.position_2 - position_2)))


def read_profiles(path: str | Path, zone: int | None = None) -> ContactProfiles | None:
    """Read ``contact_profiles.csv`` into a :class:`ContactProfiles`.

    An increment is kept when it has exactly one row for each of its contact nodes 0..n-1; a partly
    written increment at the end of an interrupted run, or an increment whose rows appear twice, is
    dropped. When the candidate window grew during the run, the node set grows too: every increment is
    placed on the union of the positions, with NaN (state -1) for nodes that were not candidates yet.

    A run with several contact zones has a ``zone`` column: one zone's rows are read (each zone is a profile of
    its own, along its own surface).

    Args:
        path: ``contact_profiles.csv`` or the output folder holding it.
        zone: With several zones, the zone read (default 0: the first, the one a scene's ``[loading]`` drives);
            ignored by a table without zones.

    Returns:
        The profiles, or ``None`` when the file is missing, empty or has no complete increment.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "contact_profiles.csv"
    table = read_table(path)
    need = ("increment", "cycle", "step", "node", "position", *_PROFILE_VALUES,
            *(_PROFILE_VALUES_3D if "position_2" in table else ()))
    if not table or any(k not in table for k in need) or table["increment"].size == 0:
        return None
    ok = np.isfinite(np.asarray(table["increment"], dtype=float)) & np.isfinite(
        np.asarray(table["node"], dtype=float))
    if "zone" in table:
        ok &= np.asarray(table["zone"], dtype=float) == (zone or 0)
    inc = np.asarray(table["increment"][ok], dtype=np.int64)
    node = np.asarray(table["node"][ok], dtype=np.int64)
    order = np.lexsort((node, inc))
    inc_sorted = inc[order]
    uniq, start, count = np.unique(inc_sorted, return_index=True, return_counts=True)
    if uniq.size == 0:
        return None
    # An increment is complete when its rows are the nodes 0..n-1 once each. The node set may grow during a
    # run (the candidate window widens): increments are then placed on the union of the positions, NaN
    # (state -1) where a node was not yet a candidate. The last increment may be partly written (an
    # interrupted run): kept only if it has as many rows as the one before.
    node_sorted = node[order]
    pos_all = np.asarray(table["position"][ok], dtype=float)[order]
    three_d = "position_2" in table
    if three_d:  # nodes keyed by their point of the contact plane: complex numbers sort by (real, imaginary)
        pos_all = pos_all + 1j * np.asarray(table["position_2"][ok], dtype=float)[order]
    keep: list[int] = []
    for k in range(uniq.size):
        nodes_k = node_sorted[start[k]:start[k] + count[k]]
        if not np.array_equal(nodes_k, np.arange(count[k])):
            continue
        if k == uniq.size - 1 and k > 0 and count[k] < count[k - 1]:
            continue
        keep.append(k)
    if not keep:
        return None
    keep_arr = np.array(keep)
    # Positions are written with 10 significant digits: equal nodes give equal text, hence equal floats.
    union = np.unique(np.concatenate([pos_all[start[k]:start[k] + count[k]] for k in keep]))
    m, n = keep_arr.size, union.size
    rows = np.full((m, n), -1, dtype=np.int64)
    for i, k in enumerate(keep):
        cols = np.searchsorted(union, pos_all[start[k]:start[k] + count[k]])
        rows[i, cols] = order[start[k]:start[k] + count[k]]
    present = rows >= 0

    def col(name: str, fill: float = np.nan) -> np.ndarray:
        data = np.asarray(np.asarray(table[name])[ok], dtype=float)
        out = np.full((m, n), fill)
        out[present] = data[rows[present]]
        return out

    values = {name: col(name) for name in _PROFILE_VALUES + (_PROFILE_VALUES_3D if three_d else ())}
    state = values["state"]
    values["state"] = np.where(np.isfinite(state), state, -1).astype(np.int64)
    first_rows = order[start[keep_arr]]
    return ContactProfiles(
        increments=uniq[keep_arr].astype(np.int64),
        cycles=np.asarray(np.asarray(table["cycle"])[ok][first_rows], dtype=np.int64),
        steps=np.asarray(np.asarray(table["step"])[ok][first_rows], dtype=np.int64),
        nodes=np.arange(n, dtype=np.int64),
        position=union.real.copy() if three_d else union,
        values=values,
        position_2=union.imag.copy() if three_d else None,
    )


def _data_item(parent: ET.Element, h5_name: str, dataset: str, shape: tuple[int, ...], kind: str) -> None:
    """A ``DataItem`` naming an HDF5 dataset (``kind``: ``"Float"`` 8 bytes or ``"Int"`` 8 bytes)."""
    item = ET.SubElement(parent, "DataItem", {
        "Dimensions": " ".join(str(s) for s in shape), "NumberType": kind, "Precision": "8", "Format": "HDF"})
    item.text = f"{h5_name}:{dataset}"


def write_contact_xdmf(out_dir: str | Path, zone: int | None = None) -> Path | None:
    """Write the contact profiles of a run as ``contact.xdmf`` + ``contact.h5`` in ``out_dir``.

    Reads ``out_dir/contact_profiles.csv`` (complete increments only, see :func:`read_profiles`). HDF5
    layout: ``/Mesh/contact/geometry`` (n, 3) node coordinates ``(position, 0, 0)`` in mm,
    ``/Mesh/contact/topology`` the polyline joining the nodes in order of position ((n - 1, 2), or
    (1, 1) polyvertex for a single node), ``/Mesh/contact/node`` the CSV node numbers, ``/Data/increment``,
    ``/Data/cycle``, ``/Data/step`` (m,) and ``/Data/<field>/<increment>`` (n,) for each field of
    :data:`XDMF_FIELDS`, in node order (the order of the CSV). A 3D contact is the surface of its nodes in
    the contact plane: coordinates ``(position, position_2, 0)`` (along t1, t2), triangles of their Delaunay
    triangulation, and the t2 components as ``shear_2``, ``slip_2``, ``relative_tangential_2``. Both files are written under temporary
    names and renamed, so an existing pair is replaced only by a complete one. Plain Python; call on
    one rank only. A run with several contact zones: zone ``zone``'s nodes (:func:`read_profiles`), written as
    ``contact.xdmf`` for zone 0 (the default) and ``contact_zone<i>.xdmf`` for the others.

    Args:
        out_dir: A run's output folder.
        zone: The zone written (several zones; default 0).

    Returns:
        The path of ``contact.xdmf``, or ``None`` when there is no complete contact profile to write.
    """
    import h5py  # lazy: not a declared dependency (installed with DOLFINx by scripts/setup.sh)

    out = Path(out_dir)
    prof = read_profiles(out / "contact_profiles.csv", zone)
    if prof is None:
        return None
    n = prof.nodes.size
    stem = f"contact_zone{zone}" if zone else "contact"
    xdmf_path, h5_path = out / f"{stem}.xdmf", out / f"{stem}.h5"
    tmp_xdmf, tmp_h5 = out / f"{stem}.xdmf.tmp", out / f"{stem}.h5.tmp"

    geometry = np.zeros((n, 3))
    geometry[:, 0] = prof.position
    fields = XDMF_FIELDS
    if prof.position_2 is not None:
        geometry[:, 1] = prof.position_2
        fields = XDMF_FIELDS + _PROFILE_VALUES_3D
    by_position = np.argsort(prof.position, kind="stable")
    if prof.position_2 is not None and n >= 3:
        from scipy.spatial import Delaunay  # lazy: up to ~0.15 s to import, for a 3D contact only

        topology = Delaunay(geometry[:, :2]).simplices.astype(np.int64)
        topo_type, per_element = "Triangle", 3
    elif n >= 2:
        topology = np.column_stack([by_position[:-1], by_position[1:]]).astype(np.int64)
        topo_type, per_element = "Polyline", 2
    else:
        topology = np.zeros((1, 1), dtype=np.int64)
        topo_type, per_element = "Polyvertex", 1

    with h5py.File(tmp_h5, "w") as h5:
        mesh = h5.create_group("Mesh/contact")
        mesh.create_dataset("geometry", data=geometry)
        mesh.create_dataset("topology", data=topology)
        mesh.create_dataset("node", data=prof.nodes)
        data = h5.create_group("Data")
        data.create_dataset("increment", data=prof.increments)
        data.create_dataset("cycle", data=prof.cycles)
        data.create_dataset("step", data=prof.steps)
        for name in fields:
            group = data.create_group(name)
            arr = prof.values[name]
            for i, inc in enumerate(prof.increments):
                group.create_dataset(str(int(inc)), data=arr[i])

    h5_name = h5_path.name
    root = ET.Element("Xdmf", {"Version": "3.0"})
    domain = ET.SubElement(root, "Domain")
    series = ET.SubElement(domain, "Grid", {"Name": "contact", "GridType": "Collection",
                                            "CollectionType": "Temporal"})
    for i, inc in enumerate(prof.increments):
        grid = ET.SubElement(series, "Grid", {"Name": f"increment_{int(inc)}", "GridType": "Uniform"})
        topo = ET.SubElement(grid, "Topology", {"TopologyType": topo_type,
                                                "NumberOfElements": str(topology.shape[0]),
                                                "NodesPerElement": str(per_element)})
        _data_item(topo, h5_name, "/Mesh/contact/topology", topology.shape, "Int")
        geo = ET.SubElement(grid, "Geometry", {"GeometryType": "XYZ"})
        _data_item(geo, h5_name, "/Mesh/contact/geometry", geometry.shape, "Float")
        ET.SubElement(grid, "Time", {"Value": str(int(inc))})
        ET.SubElement(grid, "Information", {"Name": "cycle", "Value": str(int(prof.cycles[i]))})
        ET.SubElement(grid, "Information", {"Name": "step", "Value": str(int(prof.steps[i]))})
        for name in fields:
            att = ET.SubElement(grid, "Attribute",
                                {"Name": name, "AttributeType": "Scalar", "Center": "Node"})
            _data_item(att, h5_name, f"/Data/{name}/{int(inc)}", (n,),
                       "Int" if name == "state" else "Float")
    ET.indent(root, space="  ")
    with open(tmp_xdmf, "wb") as f:
        f.write(b'<?xml version="1.0"?>\n')
        f.write(ET.tostring(root, encoding="utf-8"))
        f.write(b"\n")
    os.replace(tmp_h5, h5_path)
    os.replace(tmp_xdmf, xdmf_path)
    return xdmf_path


def read_contact_xdmf(xdmf_path: str | Path) -> dict:
    """Read a ``contact.xdmf`` written by :func:`write_contact_xdmf` back by following its XML.

    Every ``DataItem`` is resolved through the HDF5 file it names (relative to the XDMF file) and its
    ``Dimensions`` are checked against the dataset's shape, as a viewer would.

    Args:
        xdmf_path: The ``.xdmf`` file.

    Returns:
        ``{"points": (n, 3), "cells": (type, array), "times": [t, ...], "cycles": [...], "steps": [...],
        "point_data": [{name: (n,) array}, ...]}`` with one ``point_data`` entry per grid of the temporal
        collection.

    Raises:
        ValueError: the XML is not a temporal collection of uniform grids with HDF data items, or a data
            item's dimensions do not match its dataset.
    """
    import h5py  # lazy: not a declared dependency, as above

    xdmf_path = Path(xdmf_path)
    root = ET.parse(xdmf_path).getroot()
    if root.tag != "Xdmf" or root.get("Version", "").split(".")[0] not in ("2", "3"):
        raise ValueError(f"{xdmf_path}: not an XDMF 2/3 file")
    series = root.find("Domain/Grid[@GridType='Collection']")
    if series is None or series.get("CollectionType") != "Temporal":
        raise ValueError(f"{xdmf_path}: no temporal collection")
    files: dict[Path, h5py.File] = {}

    def load(item: ET.Element | None) -> np.ndarray:
        if item is None or item.get("Format") != "HDF":
            raise ValueError(f"{xdmf_path}: expected an HDF DataItem")
        fname, dset = item.text.strip().split(":", 1)
        fpath = xdmf_path.parent / fname
        if fpath not in files:
            files[fpath] = h5py.File(fpath, "r")
        arr = files[fpath][dset][()]
        dims = tuple(int(d) for d in item.get("Dimensions").split())
        if int(np.prod(dims)) != arr.size:
            raise ValueError(f"{xdmf_path}: {dset} has shape {arr.shape}, the XML says {dims}")
        return arr.reshape(dims)

    result: dict = {"points": None, "cells": None, "times": [], "cycles": [], "steps": [], "point_data": []}
    try:
        for grid in series.findall("Grid"):
            if grid.get("GridType") != "Uniform":
                raise ValueError(f"{xdmf_path}: grid {grid.get('Name')} is not uniform")
            topo, geo = grid.find("Topology"), grid.find("Geometry")
            if topo is None or geo is None or geo.get("GeometryType") != "XYZ":
                raise ValueError(f"{xdmf_path}: grid {grid.get('Name')} lacks its topology or XYZ geometry")
            points = load(geo.find("DataItem"))
            cells = load(topo.find("DataItem"))
            if cells.shape[0] != int(topo.get("NumberOfElements")) or \
                    cells.shape[1] != int(topo.get("NodesPerElement")):
                raise ValueError(f"{xdmf_path}: topology shape {cells.shape} does not match its attributes")
            if result["points"] is None:
                result["points"], result["cells"] = points, (topo.get("TopologyType"), cells)
            info = {e.get("Name"): e.get("Value") for e in grid.findall("Information")}
            result["times"].append(float(grid.find("Time").get("Value")))
            result["cycles"].append(int(info.get("cycle", -1)))
            result["steps"].append(int(info.get("step", -1)))
            pdata = {}
            for att in grid.findall("Attribute"):
                if att.get("Center") != "Node":
                    raise ValueError(f"{xdmf_path}: attribute {att.get('Name')} is not node-centred")
                arr = load(att.find("DataItem"))
                if arr.shape[0] != points.shape[0]:
                    raise ValueError(f"{xdmf_path}: attribute {att.get('Name')} has {arr.shape[0]} values "
                                     f"for {points.shape[0]} points")
                pdata[att.get("Name")] = arr
            result["point_data"].append(pdata)
    finally:
        for f in files.values():
            f.close()
    return result

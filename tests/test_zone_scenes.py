"""A scene with several contact zones: ``[[contact]]`` tables naming a user's mesh file's facet groups.

The mesh (gmsh, built here): a block clamped at its top, resting on a rigid floor (the first table, driven by
``[loading]``: a normal force and a fretting stroke) and bearing on a rigid, frictionless wall beside it (the second
table, held at an interference). The run goes through the command line as a user's would. The checks are identities
of the physics that need no package code: a frictionless wall carries no tangential force and dissipates nothing
(so the floor's energy is the run's), the floor's force control reaches the prescribed force, and the wall's
interference presses it (a positive normal force).
"""

import json
from pathlib import Path

import gmsh
import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

from dolfinx_fretting.cli import main  # noqa: E402
from dolfinx_fretting.contact_output import read_profiles, read_table, write_contact_xdmf  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from support.mesh_files import shared_folder, write_msh  # noqa: E402

COMM = MPI.COMM_WORLD
WIDTH, HEIGHT, RELIEF, H = 2.0, 1.0, 0.25, 0.125   # the block (mm), the wall's relief at its foot, element size
P, STROKE, INTERFERENCE = 200.0, 2e-3, 2e-4          # floor force (N/mm), floor stroke (mm), wall interference (mm)


def write_block(path: Path) -> Path:
    """The block [0, WIDTH] x [0, HEIGHT] with physical groups "floor" (y = 0), "wall" (x = WIDTH above the
    relief: the corner is in one zone only), "top" (clamped) and "block"."""
    def build():
        g = gmsh.model.geo
        p = [g.addPoint(x, y, 0, H) for x, y in [(0, 0), (WIDTH, 0), (WIDTH, RELIEF), (WIDTH, HEIGHT), (0, HEIGHT)]]
        lines = [g.addLine(p[i], p[(i + 1) % 5]) for i in range(5)]   # floor, relief, wall, top, left
        g.addPlaneSurface([g.addCurveLoop(lines)])
        g.synchronize()
        for dim, tags, tag, name in ((1, [lines[0]], 1, "floor"), (1, [lines[2]], 2, "wall"), (1, [lines[3]], 3, "top"),
                                     (2, [1], 1, "block")):
            gmsh.model.addPhysicalGroup(dim, tags, tag)
            gmsh.model.setPhysicalName(dim, tag, name)
    return write_msh(path, build)


@pytest.fixture(scope="module")
def block_file(tmp_path_factory):
    return write_block(shared_folder(tmp_path_factory, "block") / "block.msh")


SCENE = """name = "block in a corner"
[geometry]
kind = "file"
path = "block.msh"
[boundary]
fixed = ["top"]
[[contact]]
surface = "floor"
plane_point = [0.0, 0.0]
plane_normal = [0.0, 1.0]
mu = 0.5
[[contact]]
surface = "wall"
plane_point = [{width}, 0.0]
plane_normal = [-1.0, 0.0]
mu = 0.0
approach = {interference}
[loading]
normal_force = {force}
normal_increments = 2
tangential_displacement = {stroke}
cycles = 2
increments_per_cycle = 8
[output]
xdmf = false
progress = false
"""


def test_a_block_on_a_floor_against_a_wall(block_file, capsys):
    """Two cycles through ``dolfinx-fretting run``: exit 0, each zone's columns in the tables, the frictionless
    wall's tangential force and energy 0 (a frictionless contact's tangential force is exactly zero in the local
    solver: 1e-12 of P allows the rounding of the frame products), the floor's preload force P to the force
    tolerance (1e-8 of P; 1e-7 allowed), the floor's energy the run's (the wall adds 0: the sum identity to the
    printing, 1e-9)."""
    scene_path = block_file.parent / "corner.toml"
    if COMM.rank == 0:
        scene_path.write_text(SCENE.format(width=WIDTH, interference=INTERFERENCE, force=P, stroke=STROKE))
    COMM.barrier()
    scene = load_scene(scene_path)
    assert [scene.contact.surface, *(z.surface for z in scene.zones)] == ["floor", "wall"]
    out = block_file.parent / "out"
    code = main(["run", str(scene_path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is True and summary["cycles"] == 2
    hist = read_table(out / "history.csv")
    cycles = read_table(out / "cycles.csv")
    assert {"zone0_normal_force", "zone1_normal_force", "zone1_tangential_force"} <= set(hist)
    assert {"zone0_dissipated_energy", "zone1_dissipated_energy"} <= set(cycles)
    assert np.abs(hist["zone1_tangential_force"]).max() <= 1e-12 * P
    assert np.abs(hist["zone1_dissipated_energy"]).max() <= 1e-12 * np.abs(hist["dissipated_energy"]).max()
    preload = hist["stage"] == "normal"
    assert hist["zone0_normal_force"][preload][-1] == pytest.approx(P, rel=1e-7)
    # the wall reaches its interference with the preload (half of it at the first of two increments), then holds it
    assert hist["zone1_normal_displacement"][preload].tolist() == pytest.approx([INTERFERENCE / 2, INTERFERENCE],
                                                                               rel=1e-9)
    assert np.all(hist["zone1_normal_displacement"][~preload] == hist["zone1_normal_displacement"][preload][-1])
    assert hist["zone1_normal_force"].min() > 0
    # the floor is rubbed (its t1 motion is the run's tangential displacement) and dissipates the run's energy
    assert np.abs(hist["zone0_tangential_displacement"] - hist["tangential_displacement"]).max() == 0
    assert cycles["dissipated_energy"].min() > 0
    assert np.abs(cycles["zone0_dissipated_energy"] - cycles["dissipated_energy"]).max() \
        <= 1e-9 * cycles["dissipated_energy"].max()
    # run.json and the summary name every zone; each zone's profile reads on its own
    run = json.loads((out / "run.json").read_text())
    assert [(z["surface"], z["normal"]) for z in run["zones"]] == [("floor", [0.0, 1.0]), ("wall", [-1.0, 0.0])]
    assert [z["surface"] for z in summary["zones"]] == ["floor", "wall"]
    wall = read_profiles(out, zone=1)
    # the wall's nodes: from the relief every 0.125 mm (the mesh's boundary size) to below the clamped top corner
    # (a node with every component fixed is no contact)
    assert wall.position.tolist() == pytest.approx(np.arange(RELIEF, HEIGHT - H / 2, H).tolist(), abs=1e-9)
    assert (out / "fretting_loops.png").is_file()
    assert write_contact_xdmf(out, 1).name == "contact_zone1.xdmf"   # each further zone's point cloud of its own


REFUSALS = [
    # (changes to the scene file, the one-line message's key part, the exit code): the schema's refusals exit 2
    # before anything is read; a surface name that is not a group of the file is found once the file is read
    # (before any assembly), bad input too: exit 2, as with one [contact] table (tests/test_mesh_file_faults.py)
    ({"geometry": {"kind": "rectangle"}, "boundary": None},
     "contact = '2 [[contact]] tables' is out of range; allowed: one [contact] table with geometry.kind = 'rectangle'"),
    ({"contact1": {"obstacle": "elastic_flat"}}, "contact[1].obstacle = 'elastic_flat' is out of range"),
    ({"contact1": {"sliding": "finite"}}, "unknown key 'contact[1].sliding'"),
    ({"contact1": {"mu": -0.1}}, "contact[1].mu = -0.1"),
    ({"contact1": {"plane_normal": [0.0, 0.0]}}, "contact[1].plane_normal = [0.0, 0.0] is out of range"),
    ({"contact0": {"approach": 1e-3}}, "contact[0].approach = 0.001 is out of range"),
    ({"contact1": {"surface": "side"}}, "contact[1].surface = 'side' is not a physical group of"),
    # a further zone's window too narrow for its interference: its nodes outside penetrate; its window does not
    # grow, the run stops naming the key (exit 1, a failed run's, after the increment that found it)
    ({"contact1": {"candidate_half_width": 0.1, "approach": 2e-4}},
     "contact[1].candidate_half_width (now 0.1 mm) or leave it out", 1),
    ({"material": {"model": "elastoplastic", "yield_stress": 500.0, "hardening_modulus": 1000.0}},
     "material.model = 'elastoplastic' is out of range"),
]
REFUSALS = [(*case, 2) if len(case) == 2 else case for case in REFUSALS]


def toml_of(data: dict) -> str:
    """A scene as TOML: its tables, the contact tables as [[contact]] (no TOML writer is a dependency)."""
    def value(v):
        return json.dumps(v) if not isinstance(v, bool) else str(v).lower()

    text = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, (dict, list))]
    for section, table in data.items():
        for one in (table if isinstance(table, list) else [table] if isinstance(table, dict) else []):
            text.append(f"[[{section}]]" if isinstance(table, list) else f"[{section}]")
            text += [f"{k} = {value(v)}" for k, v in one.items()]
    return "\n".join(text) + "\n"


def scene_with(changes: dict) -> dict:
    data = {"name": "corner", "geometry": {"kind": "file", "path": "block.msh"}, "boundary": {"fixed": ["top"]},
            "contact": [{"surface": "floor", "mu": 0.5},
                        {"surface": "wall", "plane_point": [WIDTH, 0.0], "plane_normal": [-1.0, 0.0], "mu": 0.0}],
            "loading": {"normal_force": P, "normal_increments": 1},
            "output": {"xdmf": False, "plots": False, "progress": False}}
    for key, value in changes.items():
        if key.startswith("contact"):
            data["contact"][int(key[-1])].update(value)
        elif value is None or key == "geometry":   # a section removed, or the geometry replaced
            data.pop(key)
            if value is not None:
                data[key] = value
        else:
            data[key] = {**data.get(key, {}), **value}
    return data


@pytest.mark.parametrize("changes, message, exit_code", REFUSALS, ids=[m.split(" ")[0] for _, m, _ in REFUSALS])
def test_every_refusal_is_one_line(block_file, tmp_path, capsys, changes, message, exit_code):
    """A scene file with several zones that cannot run is refused in one line naming the key, its value and the
    allowed values, without a traceback: exit 2 for the schema's refusals (before any mesh) and for a surface the
    file does not have (found when the file is read, before any assembly), 1 for a further zone's window too
    narrow."""
    path = block_file.parent / f"bad_{abs(hash(message))}.toml"
    if COMM.rank == 0:
        path.write_text(toml_of(scene_with(changes)))
    COMM.barrier()
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert code == exit_code, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], err

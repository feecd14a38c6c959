"""``run.json``: the run described as data for the folder's readers (pictures, plots, compare)."""

import csv
import json

import pytest

from dolfinx_fretting.io import read_run_description
from dolfinx_fretting.pictures import _obstacle_is_a_body, _plane_from_description, _slave_share
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

QUIET = ["output.plots=false", "output.xdmf=false", "output.progress=false"]


def test_run_description_of_two_bodies(tmp_path):
    run_scene(load_scene("mccoll", QUIET + ["geometry.contact_mesh_size=0.04", "loading.normal_increments=1",
                                            "loading.cycles=1", "loading.increments_per_cycle=4"]),
              tmp_path, quiet=True)
    run = read_run_description(tmp_path)
    scene = load_scene("mccoll")
    assert run["obstacle"]["kind"] == "elastic_body" and _obstacle_is_a_body(tmp_path)
    # the cylinder's share of the wear gap is its coefficient over the sum (scene keys, independently)
    assert _slave_share(tmp_path) == pytest.approx(scene.wear.k_slave / (scene.wear.k_slave + scene.wear.k_master),
                                                   rel=1e-15)
    assert _plane_from_description(tmp_path) == ([0.0, 0.0], [0.0, 1.0])
    # the columns declared once are the columns written
    for table, columns in run["tables"].items():
        with open(tmp_path / table) as f:
            assert next(csv.reader(f)) == columns, table


def test_run_description_of_a_rigid_plane(tmp_path):
    run_scene(load_scene("hertz", QUIET + ["geometry.contact_mesh_size=0.04", "loading.normal_increments=1",
                                           "loading.tangential_increments=1"]), tmp_path, quiet=True)
    assert not _obstacle_is_a_body(tmp_path) and _slave_share(tmp_path) is None
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["dim"] == 2
    # issue 22: the scenes' units declared, in run.json and in summary.json (force per mm of thickness in 2D)
    summary = json.loads((tmp_path / "summary.json").read_text())
    for units in (run["units"], summary["units"]):
        assert (units["length"], units["force"], units["stress"]) == ("mm", "N", "MPa")
        assert (units["contact_force"], units["energy"], units["wear_measure"], units["wear_coefficient"]) == \
            ("N/mm", "N·mm/mm", "mm²/mm", "1/MPa")

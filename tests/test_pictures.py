"""pyvista pictures at the end of a run (off screen): written, not blank, and showing the fields' numbers."""

import os
import re

import h5py
import numpy as np
import pytest

from dolfinx_fretting.pictures import (PICTURES, contact_surface, draw_in_subprocess,
                                       nice_factor, read_fields, worn_plotter)
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

pyvista = pytest.importorskip("pyvista", reason="scripts/setup.sh installs pyvista (extra 'pictures')")
TINY = ["geometry.nx=8", "geometry.ny=8", "loading.cycles=3", "loading.increments_per_cycle=16",
        "output.snapshot_cycles=[1, 3]", "output.progress=false", "wear.k=1e-4"]


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("pictures") / "block"
    summary = run_scene(load_scene("stromberg-block", TINY), out, quiet=True)
    return out, summary


def _last_von_mises(out):
    """Von Mises stress of the last time in fields.h5, read without the module under test."""
    with h5py.File(out / "fields.h5", "r") as f:
        group = f["Function/von_mises"]
        last = max(group, key=float)
        return np.asarray(group[last]).ravel()


def test_run_writes_non_blank_pictures(tiny_run):
    out, _ = tiny_run
    from PIL import Image

    for name in PICTURES:
        img = np.asarray(Image.open(out / name).convert("RGB"), dtype=float)
        assert img.shape == (720, 1600, 3)
        # A blank (single-colour) picture has zero variance; ours are mostly white with coloured meshes.
        assert img.std() > 20, name
        drawn = (np.abs(img - 255).sum(axis=2) > 30).mean()
        assert drawn > 0.05, f"{name}: only {drawn:.1%} of the pixels drawn"


# Rendering runs in a child process, as in a run (draw_in_subprocess): in one long pytest process a VTK
# render once aborted (std::bad_alloc) after dozens of other tests, which no subset reproduced.
_SAMPLE = r"""
import json, sys
import numpy as np
from vtkmodules.vtkRenderingCore import vtkCoordinate
from dolfinx_fretting.pictures import deformed_plotter
pl, info = deformed_plotter(sys.argv[1], [0.0, 0.0], [0.0, 1.0])
pl.subplot(1, 0)  # the whole-body viewport
ren = pl.renderer
img = pl.screenshot(return_img=True)
f = info["fields"]
x = f.points + info["scale"] * f.displacement
out = {"clim": info["clim"], "vm": f.von_mises.tolist(), "colours": {}}
for cell in (int(np.argmax(f.von_mises)), int(np.argmin(f.von_mises))):
    c = vtkCoordinate()
    c.SetCoordinateSystemToWorld()
    c.SetValue(*x[f.cells[cell]].mean(axis=0))
    px, py = c.GetComputedDisplayValue(ren)
    row = img.shape[0] - 1 - py
    # median over 7 x 7 pixels: the quad's diagonal through its centre is blended by anti-aliasing
    out["colours"][cell] = np.median(img[row - 3:row + 4, px - 3:px + 4].reshape(-1, 3), axis=0).tolist()
pl.close()
print(json.dumps(out))
"""


def test_colour_scale_and_colours_are_the_fields_von_mises(tiny_run):
    import json
    import subprocess
    import sys

    out, _ = tiny_run
    vm = _last_von_mises(out)
    proc = subprocess.run([sys.executable, "-c", _SAMPLE, str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    # The colour bar spans exactly the fields' von Mises range (the same float64 numbers, through JSON's
    # round trip of doubles), and the module drew the fields file's values.
    assert tuple(got["clim"]) == (vm.min(), vm.max())
    np.testing.assert_array_equal(got["vm"], vm)
    from matplotlib import colormaps

    for cell, value in ((int(np.argmax(vm)), 1.0), (int(np.argmin(vm)), 0.0)):
        colour = np.array(got["colours"][str(cell)])
        expected = np.array(colormaps["viridis"](value)[:3]) * 255
        # Unlit flat colours: the pixels at the hottest (coldest) cell's centre are the colour map's top
        # (bottom) colour, to 8-bit rounding and one colour-table bin (256 bins of viridis: <= 3 a channel).
        assert np.abs(colour - expected).max() <= 4, (cell, colour, expected)


def test_worn_profile_shows_the_runs_wear(tiny_run):
    out, summary = tiny_run
    pl, info = worn_plotter(out, [0.0, 1.0])
    assert pl is not None
    pl.close()
    assert summary["max_wear_depth"] > 0
    # contact_profiles.csv holds 10 significant digits
    assert info["max_wear"] == pytest.approx(summary["max_wear_depth"], rel=1e-9)
    assert info["cycle"] == 3
    # The magnified deepest point shows as 8-20 % of the worn zone's width (at most 1.25 x 50 mm here):
    # the magnification is the 1-2-5 step just below 20 %.
    depth = info["magnification"] * summary["max_wear_depth"]
    assert 0.08 * 50 <= depth <= 0.2 * 62.5


def test_contact_nodes_found_in_the_mesh(tiny_run):
    out, _ = tiny_run
    f = read_fields(out)
    # the block's bottom nodes (y = 0) at x = 0, 6.25, ..., 50 mm
    pos = np.linspace(0.0, 50.0, 9)
    nodes = contact_surface(f.points, pos, [0.0, 1.0])
    np.testing.assert_allclose(f.points[nodes, :2], np.column_stack([pos, np.zeros(9)]), atol=1e-12)
    with pytest.raises(ValueError, match="no mesh node at contact position 3.1"):
        contact_surface(f.points, np.array([3.1]), [0.0, 1.0])


def test_nice_factor():
    targets = (1.0, 1.9, 2.0, 4.99, 5.0, 9.9, 0.03, 7.3e5)
    assert [nice_factor(t) for t in targets] == [1, 1, 2, 2, 5, 5, 0.02, 5e5]
    assert nice_factor(0.0) == 1.0 and nice_factor(float("inf")) == 1.0


def test_run_succeeds_and_says_so_without_pyvista(tmp_path, monkeypatch, capsys):
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "pyvista.py").write_text("raise ImportError('pyvista removed for this test')\n")
    monkeypatch.setenv("PYTHONPATH", str(fake))
    out = tmp_path / "run"
    summary = run_scene(load_scene("stromberg-block", TINY[:2] + ["loading.cycles=1", "output.progress=false",
                                                                  "loading.increments_per_cycle=8"]), out)
    assert summary["converged"]
    said = capsys.readouterr().out
    assert re.search(r"pictures skipped: pyvista not importable "
                     r"\(ImportError: pyvista removed for this test\)", said), said
    assert not any((out / name).exists() for name in PICTURES)
    assert (out / "profiles.png").is_file()  # the matplotlib plots are unaffected


def test_subprocess_reports_a_folder_without_fields(tmp_path):
    msg = draw_in_subprocess(tmp_path, [0, 0], [0, 1])
    assert msg.startswith("pictures skipped: FileNotFoundError") and "fields.xdmf" in msg


def test_unloaded_last_time_draws_the_last_loaded_one(tiny_run, tmp_path):
    import shutil

    from dolfinx_fretting.pictures import field_times

    out, _ = tiny_run
    folder = tmp_path / "copy"
    shutil.copytree(out, folder)
    times = field_times(folder)
    with h5py.File(folder / "fields.h5", "r+") as f:  # the last time unloaded, as after Example 1's 9000 cycles
        for name in ("displacement", "von_mises"):
            f[f"Function/{name}/{times[-1]:g}"][...] = 0.0
    (folder / PICTURES[0]).unlink()
    said = draw_in_subprocess(folder, [0.0, 0.0], [0.0, 1.0])
    assert said.startswith(f"pictures: the last field time (increment {times[-1]:g}) carries no load: the "
                           f"deformed picture shows increment {times[-2]:g}, the last loaded one; wrote "), said
    assert (folder / PICTURES[0]).is_file()


@pytest.fixture(scope="module")
def sphere_run(tmp_path_factory):
    """The 3D ball on a flat, coarse (h = 0.09 mm, 7344 dofs), three cycles with wear; the run draws its pictures."""
    out = tmp_path_factory.mktemp("pictures3d") / "sphere"
    summary = run_scene(load_scene("sphere-flat", ["geometry.contact_mesh_size=0.09", "loading.cycles=3",
                                                   "loading.increments_per_cycle=16", "output.snapshot_cycles=[1, 3]",
                                                   "output.progress=false", "wear.k=1e-6"]), out, quiet=True)
    return out, summary


def test_3d_run_draws_the_body_and_the_worn_surface(sphere_run):
    out, summary = sphere_run
    from PIL import Image

    from dolfinx_fretting.pictures import deformed_plotter_3d, worn_plotter_3d

    for name in PICTURES:  # drawn by the run (a child process), not blank
        img = np.asarray(Image.open(out / name).convert("RGB"), dtype=float)
        assert img.shape == (720, 1600, 3) and img.std() > 20, name
        assert (np.abs(img - 255).sum(axis=2) > 30).mean() > 0.05, name
    pl, info = deformed_plotter_3d(out)
    pl.close()
    vm = _last_von_mises(out)
    assert info["fields"].gdim == 3 and tuple(info["clim"]) == (vm.min(), vm.max())
    pl, winfo = worn_plotter_3d(out, [0.0, 0.0, 1.0])
    pl.close()
    # contact.xdmf's last time is the run's end: its deepest wear gap is the summary's (HDF5 doubles)
    assert summary["max_wear_depth"] > 0
    assert winfo["max_wear"] == pytest.approx(summary["max_wear_depth"], rel=1e-12)
    assert winfo["cycle"] == 3

"""Every built-in scene under every load control the schema accepts, through the command line (issue 22): the
normal load by force or by approach, the tangential one by force, displacement, face pressure or none, monotonic
(``loading.cycles = 0``) or cyclic (one cycle), at tiny sizes. A run ends with exit 0 and a converged summary, or
is refused before any work with exit 2 and one line naming the key, its value and what is allowed; never a
traceback (the CLI re-raises an unexpected exception in a serial run, so a traceback fails the test).

Refused by the scene validation, and only these: a cycle without a tangential amplitude, and a face pressure on
the half-cylinder (its faces are the fixed top and the contact surface) or on the sphere. Before issue 22, 42 of
the 112 failed: ``sphere-flat`` under a tangential force (4) stopped in ``problem._check_held``'s traceback (the
runner prescribed a force along the half model's held direction), and the 38 refusals took two lines (a header,
then the error), the half-cylinder's pressure one advising ``loading.pressure_face`` values it then refused.
"""

import itertools
import json

import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx on the wheel)

from dolfinx_fretting.cli import main  # noqa: E402
from dolfinx_fretting.scenes import builtin_scenes, load_scene  # noqa: E402

#: Tiny meshes: 20 um contact elements on the half-cylinders (5 to 8 across their contacts), cubes of about a/2
#: under the ball, an 8 x 8 block; ``sphere-flat:whole`` is the whole ball (no held direction).
TINY = {
    "hertz": ["geometry.contact_mesh_size=0.02"],
    "cylinder-flat": ["geometry.contact_mesh_size=0.02"],
    "cylinder-flat-partial": ["geometry.contact_mesh_size=0.02"],
    "mccoll": ["geometry.contact_mesh_size=0.02"],
    "sphere-flat": ["geometry.contact_mesh_size=0.09"],
    "sphere-flat:whole": ["geometry.contact_mesh_size=0.09", "geometry.half_model=false"],
    "stromberg-block": ["geometry.nx=8", "geometry.ny=8"],
    "pad-specimen": ["geometry.contact_mesh_size=0.04"],
}
#: (normal force, an approach giving about that force on the tiny mesh (measured), tangential force = mu P / 2,
#: stroke, face pressure) in the scene's units: loads that make sense, so that every run must end converged.
LOADS = {
    "hertz": (199.24, 0.0045, 89.658, 0.002, 10.0),
    "cylinder-flat": (199.24, 0.0089, 89.658, 0.01, 10.0),
    "cylinder-flat-partial": (199.24, 0.0089, 89.658, 0.01, 10.0),
    "mccoll": (18.5, 0.00104, 8.3, 0.01, 10.0),   # a stroke of half an element an increment (finite sliding)
    "sphere-flat": (100.0, 0.0033, 40.0, 0.02, 10.0),
    "sphere-flat:whole": (100.0, 0.0033, 40.0, 0.02, 10.0),
    "stromberg-block": (24.4, 1e-4, 4.88, 0.001, 10.0),   # 1e-4 mm: the scene's approach (24.4 N/mm measured)
    # 0.0064 mm: 93.25 N/mm measured. Q = mu P / 4: under an approach the bulk stress (92.7 MPa, the scene's)
    # thins the specimen by Poisson's ratio and unloads the pad to mu P = 38.6 N/mm (refused at mu P / 2, measured)
    "pad-specimen": (93.25, 0.0064, 17.48, 0.002, 10.0),
}
QUIET = ["output.xdmf=false", "output.plots=false", "output.progress=false", "loading.normal_increments=1",
         "loading.tangential_increments=2", "loading.increments_per_cycle=4"]
CASES = list(itertools.product(TINY, ("force", "displacement"), ("force", "displacement", "pressure", "none"),
                               (0, 1)))


def test_the_matrix_holds_every_built_in_scene():
    assert {name.split(":")[0] for name in TINY} == set(builtin_scenes())
    # The default suite's runs of the costly scenes (DEFAULT_RUNS below): runs, not refusals, of each of them.
    assert set(DEFAULT_RUNS) == set(TINY) - {"stromberg-block"}
    assert all(_refusal(name, tangential, cycles) is None
               for name, runs in DEFAULT_RUNS.items() for _, tangential, cycles in runs)


def _refusal(name, tangential, cycles):
    """What the message of a refused combination says (the key and its value, what is allowed), or None (it runs)."""
    if tangential == "none" and cycles:
        return "loading.cycles = 1: a cyclic load needs its amplitude: one of loading.tangential_displacement"
    kind = load_scene(name.split(":")[0]).geometry.kind
    if tangential == "pressure" and kind in ("half_cylinder", "sphere", "pad_specimen"):
        return f"loading.tangential_pressure = 10.0 is out of range; allowed: unset with geometry.kind = {kind!r}"
    return None


#: The runs of the default suite on the scenes that mesh a cylinder or a ball (~1-3 s each: the whole matrix
#: takes 50 s on DOLFINx 0.5.2 and 90 s on 0.11): two a scene, one under a normal force with a cycle and one
#: under an approach without, the tangential controls rotated among the scenes. ``sphere-flat`` (the half
#: ball, whose held direction a tangential force once ran into, issue 22) keeps the tangential force in both.
DEFAULT_RUNS = {
    "hertz": {("force", "force", 1), ("displacement", "none", 0)},
    "cylinder-flat": {("force", "displacement", 1), ("displacement", "force", 0)},
    "cylinder-flat-partial": {("force", "force", 1), ("displacement", "displacement", 0)},
    "mccoll": {("force", "displacement", 1), ("displacement", "none", 0)},
    "sphere-flat": {("force", "force", 1), ("displacement", "force", 0)},
    "sphere-flat:whole": {("force", "displacement", 1), ("displacement", "displacement", 0)},
    "pad-specimen": {("force", "force", 1), ("displacement", "none", 0)},
}


def _case(name, normal, tangential, cycles):
    """The default suite runs every refusal (they cost nothing), every run of ``stromberg-block`` (~0.1 s
    each: the one scene that takes a face pressure, so every control and every pair of normal and tangential
    controls, with and without cycles) and two runs of each other scene (``DEFAULT_RUNS``: each scene under
    both normal controls, monotonic and cyclic, and each tangential control but the pressure on three or more
    scenes). The other runs are ``slow`` (./tasks.sh bench runs the whole matrix)."""
    runs = _refusal(name, tangential, cycles) is None
    slow = runs and name != "stromberg-block" and (normal, tangential, cycles) not in DEFAULT_RUNS[name]
    return pytest.param(name, normal, tangential, cycles, marks=[pytest.mark.slow] if slow else [],
                        id=f"{name}-N_{normal}-T_{tangential}-{'cyclic' if cycles else 'monotonic'}")


@pytest.mark.parametrize("name, normal, tangential, cycles", [_case(*case) for case in CASES])
def test_every_load_control_runs_or_is_refused_in_one_line(tmp_path, capsys, name, normal, tangential, cycles):
    P, approach, Q, stroke, pressure = LOADS[name]
    values = {"force": Q, "displacement": stroke, "pressure": pressure}
    overrides = TINY[name] + QUIET + [
        f"loading.cycles={cycles}", "loading.normal_force=none", "loading.normal_displacement=none",
        "loading.tangential_displacement=none", "loading.tangential_force=none", "loading.tangential_pressure=none",
        f"loading.normal_force={P}" if normal == "force" else f"loading.normal_displacement={approach}"]
    if tangential != "none":
        overrides.append(f"loading.tangential_{tangential}={values[tangential]}")
    out = tmp_path / "out"
    code = main(["run", name.split(":")[0], "--out", str(out), "--quiet",
                 *[arg for item in overrides for arg in ("--set", item)]])
    err = capsys.readouterr().err
    refused = _refusal(name, tangential, cycles)
    assert "Traceback" not in err
    if refused is None:
        assert code == 0, err
        assert json.loads((out / "summary.json").read_text())["converged"] is True
    else:
        assert code == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and refused in lines[0], err
        assert not out.exists()  # refused before any work

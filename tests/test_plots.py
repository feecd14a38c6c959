"""Pictures and the contact XDMF of a run, drawn from small synthetic output folders.

The folders are written here with the exact columns of :mod:`dolfinx_fretting.io`, so these tests need
no simulation; they check that every picture is written, that a partial folder never makes
``plot_run`` raise, and that ``contact.xdmf``/``contact.h5`` hold the values of ``contact_profiles.csv``.
"""

from __future__ import annotations

import csv
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from support.images import assert_png

from dolfinx_fretting import plots
from dolfinx_fretting.contact_output import (XDMF_FIELDS, read_contact_xdmf, read_profiles, read_table,
                                             write_contact_xdmf)
from dolfinx_fretting.io import CYCLE_FIELDS, HISTORY_FIELDS, PROFILE_FIELDS
from dolfinx_fretting.plots import CYCLIC_PICTURES, plot_run, tracked_nodes
from dolfinx_fretting.output import RunDescription, cycle_row
from dolfinx_fretting.units import Units

N_NODES, N_STEPS, N_CYCLES = 11, 8, 3
POSITIONS = np.linspace(0.0, 10.0, N_NODES)


def _triangular(step: int) -> float:
    """0 -> +1 -> 0 -> -1 -> 0 over the N_STEPS steps of a cycle."""
    t = step / N_STEPS
    return 4 * t if t <= 0.25 else (2 - 4 * t if t <= 0.75 else 4 * t - 4)


def _profile(inc: int, q: float) -> dict[str, np.ndarray]:
    """A made-up but consistent contact state: the load tilts the pressure, open where it vanishes."""
    pressure = np.maximum(0.0, 1.0 + q * (POSITIONS - 5.0) / 5.0) * (1.0 + 0.01 * inc)
    state = np.where(pressure <= 0, 0, np.where(np.arange(N_NODES) % 3 == 0, 1, 2))
    sign = 1.0 if q >= 0 else -1.0
    shear = np.where(state == 2, -0.4 * sign * pressure, np.where(state == 1, 0.1 * pressure, 0.0))
    slip = np.where(state == 2, 1e-5 * sign * (1 + POSITIONS / 10), np.where(state == 0, 2e-5, 0.0))
    gap = np.where(state == 0, 1e-4 * (1 + abs(q)) * (1 + POSITIONS), 0.0)
    wear = 1e-7 * inc * (1 + POSITIONS / 10)
    return {"position": POSITIONS, "gap": gap, "pressure": pressure, "shear": shear, "slip": slip,
            "relative_tangential": np.cumsum(slip) + 1e-6 * inc, "wear": wear, "state": state}


def _write_csv(path: Path, fields: list[str], rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})


def write_cyclic_folder(out: Path, skip_history_cycles: tuple[int, ...] = (2,),
                        snapshots: tuple[int, ...] = (1, 3)) -> None:
    """history.csv (cycle 2 skipped as with output.history_every), cycles.csv and contact_profiles.csv
    (preload and the snapshot cycles) of a face-pressure-loaded cyclic run with N_CYCLES cycles."""
    out.mkdir(parents=True, exist_ok=True)
    hist, prof, cyc = [], [], []
    schedule = [(1, 0, 0, "normal")] + [(1 + (c - 1) * N_STEPS + s, c, s, "cycle")
                                        for c in range(1, N_CYCLES + 1) for s in range(1, N_STEPS + 1)]
    for inc, cycle, step, stage in schedule:
        q = 10.0 * _triangular(step) if cycle else 0.0
        p = _profile(inc, q / 10.0)
        if cycle not in skip_history_cycles:
            row = {k: 0.0 for k in HISTORY_FIELDS}
            row.update(increment=inc, cycle=cycle, step=step, stage=stage, normal_displacement=1e-4,
                       tangential_displacement=0.0, face_pressure=q, normal_force=float(p["pressure"].sum()),
                       tangential_force=float(p["shear"].sum()), max_pressure=float(p["pressure"].max()),
                       max_wear_depth=float(p["wear"].max()), wear_area=float(p["wear"].sum()),
                       n_open=int((p["state"] == 0).sum()), n_stick=int((p["state"] == 1).sum()),
                       n_slip=int((p["state"] == 2).sum()),
                       mean_relative_tangential=1e-3 * q / 10 + 1e-4 * step,
                       local_iterations=10, load_solves=1)
            hist.append(row)
        if cycle == 0 or cycle in snapshots:
            for node in range(N_NODES):
                row = {"increment": inc, "cycle": cycle, "step": step, "node": node}
                row.update({k: (int(p[k][node]) if k == "state" else float(p[k][node]))
                            for k in PROFILE_FIELDS[4:]})
                prof.append(row)
    for c in range(1, N_CYCLES + 1):
        row = {k: 0.0 for k in CYCLE_FIELDS}
        row.update(cycle=c, equivalent_cycles=float(c), dissipated_energy=0.4 - 0.001 * c, wear_area=1e-5 * c,
                   max_wear_depth=7e-7 * c, regime="gross_slip", local_iterations=100)
        cyc.append(row)
    _write_csv(out / "history.csv", HISTORY_FIELDS, hist)
    _write_csv(out / "contact_profiles.csv", PROFILE_FIELDS, prof)
    _write_csv(out / "cycles.csv", CYCLE_FIELDS, cyc)


def cyclic_description(**changes) -> RunDescription:
    """What plot_run knows of the synthetic cyclic run: a face-pressure load of amplitude 10 MPa."""
    values = dict(name="synthetic-block", dim=2, obstacle="rigid_plane", plane_point=(0.0, 0.0),
                  plane_normal=(0.0, 1.0), cycles=N_CYCLES, preload_increments=1, increments_per_cycle=N_STEPS,
                  tangential_control="pressure", tangential_amplitude=10.0, pressure_face="right",
                  loop_cycles=(1, 3), track_positions=(1.2, 5.0), units=Units.mm_N_MPa())
    values.update(changes)
    return RunDescription(**values)


@pytest.fixture
def cyclic_run():
    return cyclic_description()


def _csv_rows(path: Path, increment: int) -> list[dict[str, str]]:
    """Rows of one increment, read independently of the package (csv module)."""
    with open(path) as f:
        return sorted((r for r in csv.DictReader(f) if int(r["increment"]) == increment),
                      key=lambda r: int(r["node"]))


def test_plot_run_cyclic_writes_every_picture(tmp_path, cyclic_run):
    write_cyclic_folder(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        written = plot_run(tmp_path, cyclic_run)
    problems = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not problems, problems
    assert sorted(p.name for p in written) == sorted(["profiles.png", *CYCLIC_PICTURES])
    for name in ["profiles.png", *CYCLIC_PICTURES]:
        assert_png(tmp_path / name)


def test_plot_run_reads_the_run_description_of_the_folder(tmp_path):
    """plot_run(folder) needs nothing but the folder: run.json round-trips the description exactly."""
    import json

    write_cyclic_folder(tmp_path)
    with pytest.warns(RuntimeWarning, match="no run.json"):
        assert plot_run(tmp_path) == []
    run = cyclic_description()
    (tmp_path / "run.json").write_text(json.dumps(run.to_json()))
    assert RunDescription.from_json(json.loads((tmp_path / "run.json").read_text())) == run
    assert sorted(p.name for p in plot_run(tmp_path)) == sorted(["profiles.png", *CYCLIC_PICTURES])


def test_plot_run_monotonic_writes_only_profiles(tmp_path):
    run = RunDescription(name="hertz", dim=2, obstacle="rigid_plane", plane_point=(0.0, 0.0),
                         plane_normal=(0.0, 1.0), preload_increments=4, tangential_control="displacement",
                         tangential_amplitude=1e-3, hertz=(10.0, 2.3e5))
    out = tmp_path
    hist, prof = [], []
    x = np.linspace(-0.2, 0.2, 21)
    for inc in range(1, 6):
        p = np.maximum(0.0, 1000.0 * (1 - (x / 0.1) ** 2)) * inc / 5
        row = {k: 0.0 for k in HISTORY_FIELDS}
        row.update(increment=inc, cycle=0, step=0, stage="normal" if inc <= 4 else "tangential",
                   normal_force=float(p.sum() * 0.02))
        hist.append(row)
        for node in range(x.size):
            prof.append({"increment": inc, "cycle": 0, "step": 0, "node": node, "position": float(x[node]),
                         "gap": 0.0, "pressure": float(p[node]), "shear": 0.0, "slip": 0.0,
                         "relative_tangential": 0.0, "wear": 0.0, "state": int(p[node] > 0)})
    _write_csv(out / "history.csv", HISTORY_FIELDS, hist)
    _write_csv(out / "contact_profiles.csv", PROFILE_FIELDS, prof)
    _write_csv(out / "cycles.csv", CYCLE_FIELDS, [])
    written = plot_run(out, run)
    assert [p.name for p in written] == ["profiles.png"]
    assert_png(out / "profiles.png")
    assert not any((out / name).exists() for name in CYCLIC_PICTURES)


def _truncate(path: Path, fraction: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[:int(len(data) * fraction)])


@pytest.mark.parametrize("damage", ["empty_folder", "headers_only", "cut_mid_line", "no_profiles",
                                    "no_history", "garbage_rows"])
def test_plot_run_never_raises_on_a_partial_folder(tmp_path, cyclic_run, damage):
    write_cyclic_folder(tmp_path)
    files = {n: tmp_path / f"{n}.csv" for n in ("history", "cycles", "contact_profiles")}
    if damage == "empty_folder":
        for p in files.values():
            p.unlink()
    elif damage == "headers_only":
        for p in files.values():
            p.write_text(p.read_text().splitlines()[0] + "\n")
    elif damage == "cut_mid_line":
        for p in files.values():
            _truncate(p, 0.37)
    elif damage == "no_profiles":
        files["contact_profiles"].unlink()
    elif damage == "no_history":
        files["history"].unlink()
        files["cycles"].unlink()
    elif damage == "garbage_rows":
        with open(files["history"], "a") as f:
            f.write("1,2,3\nnot,a,row\n")
        with open(files["contact_profiles"], "a") as f:
            f.write("999,9,9,0,abc\n")
    written = plot_run(tmp_path, cyclic_run)  # must not raise
    for p in written:
        assert_png(p)
    names = {p.name for p in written}
    if damage in ("empty_folder", "headers_only"):
        assert not names
    if damage == "no_profiles":
        assert names == {"fretting_loops.png", "wear_growth.png"}
    if damage == "no_history":
        assert {"wear_first_cycle.png", "wear_evolution.png", "node_history.png"} <= names
    if damage == "garbage_rows":
        assert names == {"profiles.png", *CYCLIC_PICTURES}


def test_a_failing_picture_is_skipped_with_a_warning(tmp_path, cyclic_run, monkeypatch):
    write_cyclic_folder(tmp_path)

    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    monkeypatch.setattr(plots, "plot_node_history", broken)
    with pytest.warns(RuntimeWarning, match="node_history.png not drawn: RuntimeError: boom"):
        written = plot_run(tmp_path, cyclic_run)
    names = {p.name for p in written}
    assert "node_history.png" not in names
    assert {"wear_first_cycle.png", "wear_evolution.png", "fretting_loops.png", "wear_growth.png"} <= names


def test_read_profiles_drops_a_partly_written_increment(tmp_path):
    write_cyclic_folder(tmp_path)
    path = tmp_path / "contact_profiles.csv"
    lines = path.read_text().splitlines(keepends=True)
    last_inc = int(lines[-1].split(",")[0])
    # keep 4 complete rows of the last increment and half of a fifth one
    path.write_text("".join(lines[:-N_NODES + 4]) + lines[-N_NODES + 4][:12])
    prof = read_profiles(path)
    assert prof is not None
    assert last_inc not in prof.increments
    assert prof.increments[-1] == last_inc - 1
    assert prof.values["pressure"].shape == (prof.increments.size, N_NODES)
    np.testing.assert_allclose(prof.position, POSITIONS)
    # the preload and every step of the snapshot cycles 1 and 3 (less the dropped one)
    assert prof.increments.size == 1 + 2 * N_STEPS - 1
    assert set(np.unique(prof.cycles)) == {0, 1, 3}


def test_read_table_types_and_unterminated_line(tmp_path):
    write_cyclic_folder(tmp_path)
    path = tmp_path / "history.csv"
    text = path.read_text()
    path.write_text(text + "999,9,1,cyc")  # a row being written: no newline yet
    t = read_table(path)
    assert list(t) == HISTORY_FIELDS
    assert t["increment"].dtype == np.int64 and 999 not in t["increment"]
    assert t["stage"][0] == "normal" and t["stage"].dtype.kind == "U"
    assert t["face_pressure"].dtype == np.float64
    assert t["increment"].size == 1 + (N_CYCLES - 1) * N_STEPS
    assert read_table(tmp_path / "missing.csv") == {}
    # a value that is not a number reads NaN, the rest of its row is kept; a short row is skipped
    odd = tmp_path / "odd.csv"
    odd.write_text("increment,regime,energy_ratio\n1,gross_slip,0.5\n2,open,abc\n3,open\n")
    t = read_table(odd)
    assert t["increment"].tolist() == [1, 2] and t["regime"].tolist() == ["gross_slip", "open"]
    assert t["energy_ratio"][0] == 0.5 and np.isnan(t["energy_ratio"][1])


def test_tracked_nodes_and_load_labels(tmp_path, cyclic_run):
    write_cyclic_folder(tmp_path)
    prof = read_profiles(tmp_path)
    assert tracked_nodes(cyclic_run, prof) == [1, 5]  # nearest to 1.2 mm and 5.0 mm
    untracked = cyclic_description(track_positions=())
    # the edge node in contact at the end of the preload (all are) and the centre node
    assert tracked_nodes(untracked, prof) == [0, 5]
    hist = plots._History(read_table(tmp_path / "history.csv"))
    assert plots._load_label(cyclic_run, hist, 1, N_STEPS // 4) == "q = +10 MPa"
    assert plots._load_label(cyclic_run, hist, 1, 3 * N_STEPS // 4) == "q = -10 MPa"
    assert plots._load_label(cyclic_run, hist, 1, N_STEPS // 2) == "q = 0 MPa"
    assert plots._load_label(cyclic_run, hist, 2, 1) == ""  # cycle 2 not in history.csv


def test_contact_xdmf_holds_the_csv_values(tmp_path):
    import h5py

    write_cyclic_folder(tmp_path)
    xdmf = write_contact_xdmf(tmp_path)
    assert xdmf == tmp_path / "contact.xdmf"
    h5_path = tmp_path / "contact.h5"
    assert h5_path.stat().st_size > 0
    csv_path = tmp_path / "contact_profiles.csv"
    with open(csv_path) as f:
        increments = sorted({int(r["increment"]) for r in csv.DictReader(f)})

    # the XML: a temporal collection, one uniform grid per kept increment, time = increment
    root = ET.parse(xdmf).getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    series = root.find("Domain/Grid")
    assert series.get("GridType") == "Collection" and series.get("CollectionType") == "Temporal"
    grids = series.findall("Grid")
    assert [int(g.find("Time").get("Value")) for g in grids] == increments

    chosen = increments[1 + N_STEPS // 2]  # a step in the middle of cycle 1
    rows = _csv_rows(csv_path, chosen)
    grid = grids[increments.index(chosen)]
    with h5py.File(h5_path, "r") as h5:
        geometry = h5["Mesh/contact/geometry"][()]
        np.testing.assert_array_equal(geometry[:, 0], [float(r["position"]) for r in rows])
        np.testing.assert_array_equal(geometry[:, 1:], 0.0)
        topology = h5["Mesh/contact/topology"][()]
        np.testing.assert_array_equal(topology,
                                      np.column_stack([np.arange(N_NODES - 1), np.arange(1, N_NODES)]))
        for name in ("pressure", "shear", "slip", "wear", "gap", "state"):
            expected = np.array([float(r[name]) for r in rows])
            np.testing.assert_array_equal(h5[f"Data/{name}/{chosen}"][()], expected, err_msg=name)
        # every DataItem of the chosen grid points at an existing dataset of the announced size
        for item in grid.iter("DataItem"):
            fname, dset = item.text.strip().split(":")
            assert fname == "contact.h5"
            dims = [int(d) for d in item.get("Dimensions").split()]
            assert h5[dset].size == int(np.prod(dims)), dset
        assert {a.get("Name") for a in grid.findall("Attribute")} == set(XDMF_FIELDS)

    back = read_contact_xdmf(xdmf)
    assert back["times"] == [float(i) for i in increments]
    assert back["cells"][0] == "Polyline"
    np.testing.assert_array_equal(back["point_data"][increments.index(chosen)]["pressure"],
                                  [float(r["pressure"]) for r in rows])
    assert sorted(set(back["cycles"])) == [0, 1, 3]



def test_contact_xdmf_reads_with_meshio(tmp_path):
    meshio = pytest.importorskip("meshio")
    write_cyclic_folder(tmp_path)
    xdmf = write_contact_xdmf(tmp_path)
    prof = read_profiles(tmp_path)
    k = 3
    rows = _csv_rows(tmp_path / "contact_profiles.csv", int(prof.increments[k]))
    with meshio.xdmf.TimeSeriesReader(str(xdmf)) as reader:
        points, cells = reader.read_points_cells()
        t, point_data, _ = reader.read_data(k)
    assert reader.num_steps == prof.increments.size
    assert t == prof.increments[k] and points.shape == (N_NODES, 3) and cells[0].type == "line"
    np.testing.assert_array_equal(point_data["pressure"], [float(r["pressure"]) for r in rows])


def test_contact_xdmf_without_profiles(tmp_path):
    assert write_contact_xdmf(tmp_path) is None
    (tmp_path / "contact_profiles.csv").write_text(",".join(PROFILE_FIELDS) + "\n")
    assert write_contact_xdmf(tmp_path) is None
    assert not (tmp_path / "contact.xdmf").exists()


def _drawn(monkeypatch) -> dict:
    """The figures plot_run draws, by file name (plots._save records them instead of writing PNGs)."""
    drawn = {}

    def keep(fig, path):
        drawn[Path(path).name] = fig
        return path

    monkeypatch.setattr(plots, "_save", keep)
    return drawn


def _labels(fig) -> list[str]:
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend()] + list(fig.legends)
    return [t for ax in fig.axes for t in (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) if t] + \
        [t.get_text() for legend in legends for t in legend.texts]


def test_an_si_run_is_labelled_in_si(tmp_path, monkeypatch):
    """Issue 22: run.json of a run declared SI says m, N, Pa, and every plot drawn from the folder alone labels
    its axes in m and Pa (N/m for a 2D contact force), none in mm or MPa."""
    import json

    write_cyclic_folder(tmp_path)
    run = cyclic_description(units=Units.si())
    (tmp_path / "run.json").write_text(json.dumps(run.to_json()))
    units = json.loads((tmp_path / "run.json").read_text())["units"]
    assert (units["length"], units["force"], units["stress"], units["contact_force"]) == ("m", "N", "Pa", "N/m")
    drawn = _drawn(monkeypatch)
    plot_run(tmp_path)
    assert set(CYCLIC_PICTURES) <= set(drawn)
    every = [t for fig in drawn.values() for t in _labels(fig)]
    # small lengths (wear, gaps, slips) are drawn rescaled down the ladder m, mm, µm, nm to read as plain numbers;
    # no stress, force, energy or area is ever in the scenes' units
    assert not [t for t in every if any(u in t for u in ("MPa", "N/mm", "N·mm", "mm²"))], every
    assert all(t.endswith("(m)") for t in every if t.startswith("position"))
    assert drawn["fretting_loops.png"].axes[0].get_ylabel() == "tangential contact force Q (N/m)"
    assert drawn["fretting_loops.png"].axes[1].get_xlabel() == "face pressure q on 'right' (Pa)"
    growth = [ax.get_ylabel() for ax in drawn["wear_growth.png"].axes]
    assert growth[1:] == ["wear area (m²/m)", "dissipated energy per cycle\n(N·m/m)"]
    first = drawn["wear_first_cycle.png"].axes
    assert first[1].get_ylabel() == "contact pressure P_n (Pa)" and first[0].get_xlabel() == \
        "position along the surface (m)"
    assert "step 2/8, q = +10 Pa" in _labels(drawn["wear_first_cycle.png"])


def test_a_3d_force_loop_is_in_newtons_and_turns_with_Q(tmp_path, monkeypatch):
    """Issue 22: a 3D contact force is a force (N), not N/mm; the abscissa of a force-controlled loop is the
    obstacle's displacement relative to the contacts (-mean_relative_tangential, which the history holds with the
    opposite sign to Q: tests/test_output_3d.py), so the loop turns with Q; cycles.csv's extremes are the same."""
    steps = np.arange(1, N_STEPS + 1)
    Q = 5.0 * np.array([_triangular(s) for s in steps])
    hist = plots._History({"increment": steps, "cycle": np.ones(N_STEPS, int), "step": steps,
                           "tangential_force": Q, "mean_relative_tangential": -2e-3 * Q,
                           "tangential_displacement": 3e-3 * Q, "face_pressure": np.zeros(N_STEPS)})
    run = cyclic_description(dim=3, tangential_control="force", tangential_amplitude=5.0, pressure_face=None,
                             loop_cycles=(1,))
    drawn = _drawn(monkeypatch)
    plots.plot_fretting_loops(tmp_path / "fretting_loops.png", run, hist)
    ax = drawn["fretting_loops.png"].axes[0]
    assert ax.get_ylabel() == "tangential contact force Q (N)"
    assert "mean" in ax.get_xlabel() and "relative to the contact nodes" in ax.get_xlabel()
    x, y = ax.lines[0].get_xdata(), ax.lines[0].get_ydata()
    assert np.corrcoef(x, y)[0, 1] > 0.99
    records = {"tangential_force": Q, "mean_relative_tangential": -2e-3 * Q, "tangential_displacement": 3e-3 * Q,
               "dissipated_energy": np.zeros(N_STEPS), "n_stick": np.ones(N_STEPS), "n_slip": np.zeros(N_STEPS),
               "wear_area": np.zeros(N_STEPS), "max_wear_depth": np.zeros(N_STEPS),
               "max_pressure": np.ones(N_STEPS), "local_iterations": np.ones(N_STEPS)}
    row = cycle_row(1, records, displacement_controlled=False)
    assert row["displacement_max"] == pytest.approx(2e-3 * Q.max()) and row["displacement_min"] == \
        pytest.approx(2e-3 * Q.min())


def test_a_folder_without_declared_units_keeps_the_old_labels(tmp_path, monkeypatch):
    """A run.json of format 2 (before units were declared: mm, N, MPa hard-coded) still reads, with a note, and is
    drawn with the labels of its release."""
    import json

    write_cyclic_folder(tmp_path)
    old = cyclic_description().to_json()
    old.update(format=2, units={"length": "mm", "force": "N/mm", "stress": "MPa"})
    (tmp_path / "run.json").write_text(json.dumps(old))
    with pytest.warns(UserWarning, match="declares no units"):
        run = RunDescription.from_json(old)
    assert run.units == Units.mm_N_MPa()
    drawn = _drawn(monkeypatch)
    with pytest.warns(UserWarning, match="declares no units"):
        plot_run(tmp_path)
    assert drawn["fretting_loops.png"].axes[0].get_ylabel() == "tangential contact force Q (N/mm)"


def test_units_are_checked_when_known_and_free_otherwise():
    """The presets are consistent (stress = force / length²); a known but inconsistent set is refused; free names
    are taken as given; the default names no unit (dimension symbols), so a user's model is never called mm."""
    assert Units.mm_N_MPa() == Units("mm", "N", "MPa") and Units.si() == Units("m", "N", "Pa")
    with pytest.raises(ValueError, match="not Pa"):
        Units("mm", "N", "Pa")
    assert Units("in", "lbf", "psi").contact_force(2) == "lbf/in"
    assert not Units().declared and Units().to_json(2)["length"] == "L"
    assert RunDescription(name="r", dim=2, obstacle="rigid_plane", plane_point=(0, 0), plane_normal=(0, 1)).units \
        == Units()
    assert Units.mm_N_MPa().wear_coefficient == "1/MPa" and Units.mm_N_MPa().energy(2) == "N·mm/mm"
    assert Units.si().length_scale([2e-5]) == (1e6, "µm") and Units.mm_N_MPa().length_scale([5e-4]) == (1e3, "µm")

"""Comparison of runs (``dolfinx_fretting.compare`` and ``dolfinx-fretting compare``) on synthetic folders.

The folders are written here with the exact columns of :mod:`dolfinx_fretting.io` and a minimal
``summary.json``, so no simulation is needed: an "elastic" and an "elastic-plastic" run (and a hundredfold
wear one) of a made-up cylinder-on-flat contact.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from support.images import assert_png

from dolfinx_fretting import cli
from dolfinx_fretting.compare import (COMPARE_PICTURES, SUMMARY_FIELDS, compare_runs, default_label, load_run,
                                      read_summary_csv)
from dolfinx_fretting.io import CYCLE_FIELDS, HISTORY_FIELDS, PROFILE_FIELDS

N_NODES, N_STEPS = 15, 8
POSITIONS = np.linspace(-0.3, 0.3, N_NODES)
OBSTACLE = "rigid plane (the flat is rigid: two deformable bodies are not modelled yet)"


def _write_csv(path: Path, fields: list[str], rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})


def _profile(p0: float, half: float, cycle: int, step: int, k: float) -> dict[str, np.ndarray]:
    """A Hertz-like pressure of peak p0 and half-width ``half``, shifted with the tangential load."""
    q = np.sin(2 * np.pi * step / N_STEPS) if cycle else 0.0
    x = POSITIONS - 0.02 * q
    pressure = p0 * np.sqrt(np.clip(1 - (x / half) ** 2, 0.0, None))
    state = np.where(pressure <= 0, 0, np.where(abs(q) < 0.5, 1, 2))
    slip = np.where(state == 2, 1e-3 * np.sign(q), 0.0)
    shear = np.where(state == 2, -0.9 * np.sign(q) * pressure, 0.1 * pressure)
    gap = np.where(state == 0, 1e-3 * (np.abs(POSITIONS) - half).clip(0), 0.0)
    done = (cycle - 1) * N_STEPS + step if cycle else 0
    wear = k * done * pressure
    return {"position": POSITIONS, "gap": gap, "pressure": pressure, "shear": shear, "slip": slip,
            "relative_tangential": np.cumsum(slip), "wear": wear, "state": state}


def write_run(out: Path, model: str = "elastic", p0: float = 1200.0, half: float = 0.11,
              cycles: int = 3, snapshots: tuple[int, ...] = (1, 2, 3), acceleration: float = 1.0,
              summary: dict | None = None, with_summary: bool = True) -> dict:
    """A cyclic run folder (preload of 2 increments, ``cycles`` cycles of N_STEPS steps); returns the
    summary written (or that would have been written)."""
    out.mkdir(parents=True, exist_ok=True)
    k = 1e-9 * acceleration
    hist, prof, cyc = [], [], []
    schedule = [(1, 0, 0, "normal"), (2, 0, 0, "normal")] + [
        (2 + (c - 1) * N_STEPS + s, c, s, "cycle")
        for c in range(1, cycles + 1) for s in range(1, N_STEPS + 1)]
    for inc, cycle, step, stage in schedule:
        p = _profile(p0 * (0.5 if inc == 1 else 1.0), half, cycle, step, k)
        row = {f: 0.0 for f in HISTORY_FIELDS}
        row.update(increment=inc, cycle=cycle, step=step, stage=stage,
                   normal_force=float(p["pressure"].sum()),
                   max_pressure=float(p["pressure"].max()), max_wear_depth=float(p["wear"].max()),
                   wear_area=float(p["wear"].sum()), dissipated_energy=0.5, contact_width=2 * half,
                   n_open=int((p["state"] == 0).sum()), n_stick=int((p["state"] == 1).sum()),
                   n_slip=int((p["state"] == 2).sum()), local_iterations=10, load_solves=1)
        hist.append(row)
        if cycle == 0 or cycle in snapshots:
            for node in range(N_NODES):
                r = {"increment": inc, "cycle": cycle, "step": step, "node": node}
                r.update({f: (int(p[f][node]) if f == "state" else float(p[f][node]))
                          for f in PROFILE_FIELDS[4:]})
                prof.append(r)
        if cycle and step == N_STEPS:
            r = {f: 0.0 for f in CYCLE_FIELDS}
            r.update(cycle=cycle, equivalent_cycles=float(cycle * acceleration), dissipated_energy=4.0,
                     wear_area=float(p["wear"].sum()), max_wear_depth=float(p["wear"].max()),
                     max_pressure_end=float(p["pressure"].max()), regime="gross_slip", local_iterations=80,
                     wall_time_s=0.25)
            cyc.append(r)
    _write_csv(out / "history.csv", HISTORY_FIELDS, hist)
    _write_csv(out / "contact_profiles.csv", PROFILE_FIELDS, prof)
    _write_csv(out / "cycles.csv", CYCLE_FIELDS, cyc)
    last = hist[-1]
    data = {"scene": "cylinder-flat", "increments": last["increment"], "cycles": cycles, "converged": True,
            "wall_time_s": 1.234 + p0 / 1e4, "wear_acceleration": acceleration,
            "equivalent_cycles": cycles * acceleration, "dissipated_energy": 4.0 * cycles + 1.0,
            "material_model": model, "obstacle": OBSTACLE, "max_pressure": last["max_pressure"],
            "contact_width": 2 * half + 0.001, "max_wear_depth": last["max_wear_depth"],
            "wear_area": last["wear_area"]}
    if model != "elastic":
        data["max_equivalent_plastic_strain"] = 0.0123
    data.update(summary or {})
    if with_summary:
        (out / "summary.json").write_text(json.dumps(data, indent=2))
    return data


def _csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture
def two_runs(tmp_path):
    e = write_run(tmp_path / "elastic_run", "elastic", p0=1200.0, half=0.11)
    p = write_run(tmp_path / "plastic_run", "elastoplastic", p0=950.0, half=0.13)
    return tmp_path / "elastic_run", tmp_path / "plastic_run", e, p


def test_compare_writes_pictures_and_summary(tmp_path, two_runs):
    fe, fp, se, sp = two_runs
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        written = compare_runs([fe, fp], None, tmp_path / "cmp")
    problems = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not problems, problems
    assert [p.name for p in written] == [*COMPARE_PICTURES, "compare_summary.csv"]
    for name in COMPARE_PICTURES:
        assert_png(tmp_path / "cmp" / name)
    rows = _csv(tmp_path / "cmp" / "compare_summary.csv")
    assert list(rows[0]) == SUMMARY_FIELDS
    assert [r["label"] for r in rows] == ["elastic", "elastic-plastic"]
    for row, s in zip(rows, (se, sp)):
        assert row["material_model"] == s["material_model"]
        for key in ("max_pressure", "max_wear_depth", "wear_area", "dissipated_energy", "contact_width",
                    "wall_time_s", "equivalent_cycles"):
            assert float(row[key]) == s[key], key
        assert int(row["cycles"]) == s["cycles"]
    assert rows[0]["max_equivalent_plastic_strain"] == ""
    assert float(rows[1]["max_equivalent_plastic_strain"]) == 0.0123
    # read back for the CLI's table
    back = read_summary_csv(tmp_path / "cmp" / "compare_summary.csv")
    assert back[1]["max_pressure"] == sp["max_pressure"] and back[0]["max_equivalent_plastic_strain"] is None


def test_default_labels(tmp_path):
    assert default_label({"material_model": "elastic", "wear_acceleration": 1.0}, tmp_path) == "elastic"
    assert default_label({"material_model": "elastoplastic", "wear_acceleration": 100.0},
                         tmp_path) == "elastic-plastic k x100"
    assert default_label({}, tmp_path / "some_run") == "some_run"
    write_run(tmp_path / "a", "elastic")
    write_run(tmp_path / "b", "elastic")
    write_run(tmp_path / "c", "elastic", acceleration=100.0)
    compare_runs([tmp_path / "a", tmp_path / "b", tmp_path / "c"], None, tmp_path / "cmp")
    labels = [r["label"] for r in _csv(tmp_path / "cmp" / "compare_summary.csv")]
    assert labels == ["elastic (a)", "elastic (b)", "elastic k x100"]


def test_given_labels_cycles_and_node(tmp_path, two_runs):
    fe, fp, _, _ = two_runs
    write_run(tmp_path / "short", "elastic", cycles=1, snapshots=(1,))
    with pytest.warns(RuntimeWarning, match="short run: cycle"):
        written = compare_runs([fe, fp, tmp_path / "short"], ["E", "EP", "short run"], tmp_path / "cmp",
                               cycles=[1, 3], node_position=None)
    assert {p.name for p in written} == {*COMPARE_PICTURES, "compare_summary.csv"}
    assert [r["label"] for r in _csv(tmp_path / "cmp" / "compare_summary.csv")] == ["E", "EP", "short run"]
    with pytest.raises(ValueError, match="label"):
        compare_runs([fe, fp], ["only one"], tmp_path / "cmp2")


def test_missing_data_skips_pictures(tmp_path, two_runs):
    fe, _, se, _ = two_runs
    # summary only: no picture can be drawn, but the table is written from summary.json
    only = tmp_path / "summary_only"
    only.mkdir()
    (only / "summary.json").write_text(json.dumps(se))
    with pytest.warns(RuntimeWarning, match="not drawn"):
        written = compare_runs([only], ["S"], tmp_path / "cmp")
    assert [p.name for p in written] == ["compare_summary.csv"]
    row = _csv(tmp_path / "cmp" / "compare_summary.csv")[0]
    assert float(row["max_pressure"]) == se["max_pressure"]
    # no summary.json (an interrupted run): values from cycles.csv / history.csv, label from the folder
    write_run(tmp_path / "interrupted", "elastic", with_summary=False)
    with pytest.warns(RuntimeWarning, match="interrupted .*: incomplete: no summary.json"):
        compare_runs([fe, tmp_path / "interrupted"], None, tmp_path / "cmp3")
    row = _csv(tmp_path / "cmp3" / "compare_summary.csv")[1]
    assert row["status"] == "incomplete"
    cyc = load_run(tmp_path / "interrupted").cycles
    assert row["label"] == "interrupted" and row["material_model"] == ""
    assert float(row["max_pressure"]) == cyc["max_pressure_end"][-1]
    assert float(row["max_wear_depth"]) == cyc["max_wear_depth"][-1]
    assert float(row["dissipated_energy"]) == pytest.approx(cyc["dissipated_energy"].sum())
    assert int(row["cycles"]) == 3


def test_runs_that_did_not_converge_are_marked(tmp_path, two_runs):
    """A crashed run (no summary.json; its history holds only a first increment of zeros, as the traceback of
    loading.normal_force = 1e-300 left it before issue 27), a failed one and an interrupted one are each marked with
    their status in the table, the CLI's table and a warning with the reason; before, the crashed run read as a row of
    zeros like a finished run's."""
    fe, _, se, _ = two_runs
    crashed = tmp_path / "crashed"
    crashed.mkdir()
    row = {f: 0.0 for f in HISTORY_FIELDS}
    row.update(increment=1, cycle=0, step=0, stage="normal", n_open=15)
    _write_csv(crashed / "history.csv", HISTORY_FIELDS, [row])
    _write_csv(crashed / "contact_profiles.csv", PROFILE_FIELDS,
               [{"increment": 1, "cycle": 0, "step": 0, "node": n, **{f: 0.0 for f in PROFILE_FIELDS[4:]}}
                for n in range(N_NODES)])
    write_run(tmp_path / "failed", summary={"converged": False, "error": "increment 9 (cycle 1, step 7): local "
                                             "solver did not converge"})
    write_run(tmp_path / "stopped", summary={"converged": False, "interrupted": "SIGTERM",
                                             "error": "interrupted by SIGTERM after increment 10 (cycle 1)"})
    folders = [fe, crashed, tmp_path / "failed", tmp_path / "stopped"]
    with pytest.warns(RuntimeWarning) as caught:
        compare_runs(folders, ["done", "crashed", "failed", "stopped"], tmp_path / "cmp")
    rows = read_summary_csv(tmp_path / "cmp" / "compare_summary.csv")
    assert [r["status"] for r in rows] == ["converged", "incomplete", "failed", "interrupted"]
    messages = [str(w.message) for w in caught]
    assert any(m.startswith(f"crashed ({crashed}): incomplete: no summary.json") for m in messages), messages
    assert any("failed: increment 9 (cycle 1, step 7): local solver did not converge" in m for m in messages)
    assert any("interrupted: interrupted by SIGTERM" in m for m in messages)
    assert not any(m.startswith("done") for m in messages)
    res = _cli(*map(str, folders), "--out", str(tmp_path / "cli"), "--labels", "done,crashed,failed,stopped")
    assert res.returncode == 0, res.stderr
    table = {line.split()[0]: line.split() for line in res.stdout.splitlines() if line.split()}
    assert table["crashed"][1:3] == ["-", "incomplete"] and table["done"][2] == "converged"
    assert table["failed"][2] == "failed" and table["stopped"][2] == "interrupted"
    assert "crashed" in res.stderr and "incomplete" in res.stderr


def test_bad_folder_error_names_it(tmp_path, two_runs):
    fe, _, _, _ = two_runs
    empty = tmp_path / "empty_folder"
    empty.mkdir()
    (empty / "notes.txt").write_text("nothing here")
    with pytest.raises(ValueError, match="empty_folder"):
        compare_runs([fe, empty], None, tmp_path / "cmp")
    with pytest.raises(ValueError, match="does_not_exist"):
        compare_runs([fe, tmp_path / "does_not_exist"], None, tmp_path / "cmp")
    assert not (tmp_path / "cmp" / "compare_summary.csv").exists()


def _cli(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "dolfinx_fretting", "compare", *args], capture_output=True,
                          text=True, env=env, timeout=120)


def test_cli(tmp_path, two_runs):
    fe, fp, _, sp = two_runs
    out = tmp_path / "cli_out"
    res = _cli(str(fe), str(fp), "--out", str(out), "--labels", "el,ep", "--cycles", "1,2", "--node", "0.0")
    assert res.returncode == 0, res.stderr
    for name in (*COMPARE_PICTURES, "compare_summary.csv"):
        assert str(out / name) in res.stdout
        assert (out / name).is_file()
    assert "ep" in res.stdout and f"{sp['max_pressure']:.4g}" in res.stdout


def _main(capsys, *args: str) -> tuple[int, str]:
    """``dolfinx-fretting compare ARGS`` in this process (cli.main, which the console script calls): its exit
    code and stderr. An argparse refusal exits with its code."""
    try:
        code = cli.main(["compare", *args])
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


def test_cli_bad_input_exits_2_naming_the_problem(tmp_path, two_runs, capsys):
    """Bad input: exit 2 with a message naming the problem. In this process (cli.main, the function the console
    script and ``python -m dolfinx_fretting`` call: test_cli above runs the latter once): five child processes
    here cost ~7 s a stack, each mostly the interpreter's start-up."""
    fe, fp, _, _ = two_runs
    missing = tmp_path / "no_such_run"
    code, err = _main(capsys, str(fe), str(missing), "--out", str(tmp_path / "x"))
    assert code == 2 and str(missing) in err, err
    empty = tmp_path / "empty_run"
    empty.mkdir()
    code, err = _main(capsys, str(empty), "--out", str(tmp_path / "x"))
    assert code == 2 and "empty_run" in err, err
    code, err = _main(capsys, str(fe), str(fp), "--out", str(tmp_path / "x"), "--labels", "a")
    assert code == 2 and "label" in err, err
    code, err = _main(capsys, str(fe), "--out", str(tmp_path / "x"), "--cycles", "1,x")
    assert code == 2 and "--cycles" in err, err
    code, err = _main(capsys, str(fe))
    assert code == 2 and "--out" in err, err


def test_obstacle_note_reads_the_run_description(tmp_path):
    """The obstacle named under the pictures comes from run.json (data), not from summary.json's prose; a
    folder of an older release without run.json falls back to the prose."""
    from dolfinx_fretting.compare import RunData, _obstacle_note
    from dolfinx_fretting.output import OBSTACLE_TEXT, RunDescription

    two_bodies = RunDescription(name="mccoll", dim=2, obstacle="elastic_body", plane_point=(0.0, 0.0),
                                plane_normal=(0.0, 1.0))
    runs = [RunData(tmp_path, "a", summary={"obstacle": "stale prose"}, description=two_bodies),
            RunData(tmp_path, "b", summary={}, description=two_bodies)]
    assert _obstacle_note(runs) == f"obstacle: {OBSTACLE_TEXT['elastic_body']}"
    assert _obstacle_note([RunData(tmp_path, "old", summary={"obstacle": OBSTACLE})]) == f"obstacle: {OBSTACLE}"

"""Command line: ``dolfinx-fretting scenes``, ``dolfinx-fretting run SCENE --out DIR [--set k=v ...]``,
``dolfinx-fretting compare DIR [DIR ...] --out OUT [--labels a,b] [--cycles 1,10,100] [--node 0.0]`` and
``dolfinx-fretting study SCENE --out DIR [--sweep k=v1,v2 ...] [--reference k=v ...] [--point "k=v k=v"]`` and
``dolfinx-fretting map SCENE --normal P1,P2 --amplitude D1,D2 --out DIR [--cycles N] [--set k=v ...]``.

Exit codes: 0 done; 2 bad input (scene, options, output folder, a checkpoint that cannot be resumed), with a
message and before any expensive work; 1 a run that failed (an increment, PETSc or MUMPS, a non-finite
result, a full disk, its output folder deleted or replaced), with a message; 130 / 143 a run stopped by SIGINT /
SIGTERM at any stage (:mod:`dolfinx_fretting.interrupts`), with a message. Never a traceback for any.

Under MPI (``mpirun -n N dolfinx-fretting ...``) an error on any rank stops every rank: the ranks meet at the
end (:func:`_finish`); a rank that failed alone (e.g. rank 0 could not write a table while the others went on
to the next increment's collectives) waits :data:`MEET_SECONDS` for the others, then prints its message and
calls ``MPI_Abort`` with its exit code. An unexpected exception (a bug) prints its traceback and aborts too.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
import traceback
import warnings

from mpi4py import MPI

from . import fretting_map, study
from .interrupts import Interrupted, RunSignals
from .outdir import OutputFolderError, check_output_folder
from .scenes import SceneError, builtin_scenes, load_scene
from .sizes import check_size

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="dolfinx-fretting", description="Fretting wear simulation with DOLFINx")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("scenes", help="list the built-in scenes")
    run = sub.add_parser("run", help="run a scene (a built-in name or a TOML file)")
    run.add_argument("scene", help="built-in scene name or path to a scene TOML file")
    run.add_argument("--out", required=True, help="output folder")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                     help="override a scene value (TOML syntax, e.g. --set contact.mu=0.5); repeatable")
    run.add_argument("--quiet", action="store_true", help="print only errors")
    run.add_argument("--verbose", action="store_true",
                     help="also print the form compiler's build log (hidden by default)")
    run.add_argument("--resume", action="store_true",
                     help="continue the run checkpointed in --out (the scene may differ only in its solver and "
                          "output sections and in loading.cycles)")
    run.add_argument("--overwrite", action="store_true",
                     help="replace the run --out holds (deletes its files, checkpoint included; other files stay)")
    run.add_argument("--ignore-size", action="store_true",
                     help="run even if the size estimate exceeds the memory available (refused by default)")
    show = sub.add_parser("show", help="print a scene with every default filled in, as validated")
    show.add_argument("scene")
    show.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    cmp = sub.add_parser("compare",
                         help="compare finished runs: pictures (paper Figs. 13-19) and a summary table")
    cmp.add_argument("folders", nargs="+", metavar="DIR", help="output folders of the runs")
    cmp.add_argument("--out", required=True, help="folder for the pictures and compare_summary.csv")
    cmp.add_argument("--labels", type=_csv_list, default=None, metavar="A,B,...",
                     help="one label per folder (default: the material model, plus ' k xN' for a wear "
                          "acceleration N)")
    cmp.add_argument("--cycles", type=_int_list, default=None, metavar="1,10,100",
                     help="cycles of compare_cycles.png (default: the snapshot cycles the runs share)")
    cmp.add_argument("--node", type=_node_position, default=0.0, metavar="X",
                     help="position (mm) of the node of compare_node_history.png, or 'centre' (default 0.0)")
    study_parser = sub.add_parser("study", help="speed-vs-accuracy trade study: a fine reference run and a "
                                  "sweep of numerics, with errors against the reference (study.csv, .md, .png)")
    add = study_parser.add_argument
    add("scene", help="built-in scene name or path to a scene TOML file")
    add("--out", required=True, help="output folder (the runs go to DIR/runs/)")
    add("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help="override a scene value for every run, reference included (e.g. loading.cycles=20)")
    add("--reference", action="append", default=None, metavar="SECTION.KEY=VALUE",
        help="the reference's overrides; repeatable (default: contact elements halved, twice the "
             "increments, local_tol 1e-12, no wear acceleration)")
    add("--sweep", action="append", default=None, metavar="SECTION.KEY=V1,V2,...",
        help="a key and its values, swept one at a time around the reference; repeatable (default: "
             "contact element size, increments per cycle, local_tol, wear acceleration)")
    add("--point", action="append", default=[], metavar='"K=V K=V"',
        help="a combination of overrides on top of the reference's, run as one point; repeatable")
    add("--no-warm-up", dest="warm_up", action="store_false",
        help="skip the untimed one-cycle run that loads the compiled kernels first")
    add("--quiet", action="store_true", help="print only the final table")
    add("--verbose", action="store_true", help="also print the form compiler's build log (hidden by default)")
    add("--overwrite", action="store_true", help="replace the study --out holds (its table, picture and runs)")
    add("--ignore-size", action="store_true",
        help="run even if a run's size estimate exceeds the memory available (refused by default)")
    _add_map_parser(sub)
    return p


#: Seconds a rank that failed waits for the others at the end before it aborts them all: ranks that failed
#: together (bad input, a collective solver failure) meet within a fraction of a second.
MEET_SECONDS = 5.0
#: Seconds between a lone failing rank's message and its MPI_Abort, for the launcher to forward the message.
ABORT_GRACE_SECONDS = 1.0

#: The message of this rank's failure (printed once by :func:`_finish`), or None.
_failure: list[str] = []


def _say_error(prefix: str, exc: BaseException | str) -> None:
    """Record this rank's error message; :func:`_finish` prints it once (every rank may hold the same one)."""
    _failure.append(f"{prefix}: {exc}")


def _quiet_form_compiler(verbose: bool) -> None:
    """Keep the form compiler's build log (``INFO:root:running build_ext`` and the compiler command lines)
    out of the run's output unless ``verbose``. FFCx 0.5 installs a root handler (``logging.basicConfig``)
    and cffi lowers the root logger's threshold while it compiles, so the handlers' own level is what holds;
    ``verbose`` makes sure there is a handler (newer FFCx installs none)."""
    # Lazy: the form compiler is heavy and only a run needs it. FFCx 0.5's import installs the root handler
    # this adjusts.
    import ffcx  # noqa: F401

    if verbose:
        logging.basicConfig()  # no-op if a handler exists
        logging.getLogger().setLevel(logging.INFO)
    for handler in logging.getLogger().handlers:
        handler.setLevel(logging.INFO if verbose else logging.WARNING)


def _finish(code: int, comm) -> int:
    """Every rank's exit: print the failure once and return ``code``, or abort all ranks if this one failed
    alone (the others would wait in their next collective forever)."""
    message = _failure[-1] if _failure else None
    if comm is None or comm.size == 1:
        if message:
            print(message, file=sys.stderr)
        return code
    request = _exit_comm.Ibarrier()
    if code == 0:
        request.Wait()  # a rank that finished waits for the others (an Abort elsewhere ends it)
    else:
        deadline = time.monotonic() + MEET_SECONDS
        while not request.Test():
            if time.monotonic() > deadline:
                print(f"{message or 'dolfinx-fretting: failed'} (on rank {comm.rank} alone: stopping all "
                      f"{comm.size} ranks)", file=sys.stderr, flush=True)
                # MPICH's launcher may drop a line still in its pipe when the abort kills the job (a loaded
                # machine lost this one in CI): give it time to forward the message first.
                time.sleep(ABORT_GRACE_SECONDS)
                comm.Abort(code)
            time.sleep(0.01)
    outcomes = _exit_comm.allgather((code, message))
    failed = [(c, m) for c, m in outcomes if c != 0]
    if comm.rank == 0 and failed:
        for text in dict.fromkeys(m for _, m in failed if m):  # the same message once, distinct ones each
            print(text, file=sys.stderr)
    return max(c for c, _ in outcomes) if failed else 0


_exit_comm = None


def _study(args: argparse.Namespace) -> int:
    """``dolfinx-fretting study``: the trade study; 2 for bad input, 1 if the reference run or any point fails (the
    failed points are in the table)."""
    try:
        sweep = study.parse_sweep(args.sweep) if args.sweep is not None else None
        points = [study.parse_point(p) for p in args.point]
        plan = study.plan_study(args.scene, args.overrides, args.reference, sweep, points)
        for point in plan:  # every run's size before the first starts (SizeError is a SceneError)
            check_size(point.scene, MPI.COMM_WORLD, ignore=args.ignore_size)
        study.check_study_folder(args.out, overwrite=args.overwrite)
    except (SceneError, OutputFolderError) as exc:
        _say_error("dolfinx-fretting study", exc)
        return 2
    _quiet_form_compiler(args.verbose)
    try:
        rows = study.run_study(plan, args.out, MPI.COMM_WORLD, quiet=args.quiet, warm_up=args.warm_up,
                         overwrite=args.overwrite, ignore_size=args.ignore_size)
    except OutputFolderError as exc:
        _say_error("dolfinx-fretting study", exc)
        return 2
    except RuntimeError as exc:
        _say_error("dolfinx-fretting study", exc)
        return 1
    failed = [row["label"] for row in rows if not row["converged"]]
    if MPI.COMM_WORLD.rank == 0:
        print(study.format_markdown(rows))
        print(f"wrote {args.out}/study.csv, study.md, study.png")
        if failed:  # kept in the table with their messages; the exit code says the study is not whole
            print(f"dolfinx-fretting study: {len(failed)} of {len(rows)} runs failed ({', '.join(failed)}); their "
                  "messages are in study.csv and study.md", file=sys.stderr)
    return 1 if failed else 0


# dolfinx-fretting map --------------------------------------------------------------------------------------------
def _add_map_parser(sub) -> None:
    map_parser = sub.add_parser("map", help="fretting map: a grid of (normal load, displacement amplitude) runs "
                                "classified into partial / mixed / gross slip (map.csv, .md, .png)")
    add = map_parser.add_argument
    add("scene", help="built-in scene name or path to a scene TOML file")
    add("--normal", required=True, metavar="P1,P2,...", help="normal loads (loading.normal_force: N/mm in 2D, N in 3D)")
    add("--amplitude", required=True, metavar="D1,D2,...",
        help="displacement amplitudes (loading.tangential_displacement, mm)")
    add("--cycles", type=int, default=None, metavar="N", help="cycles of every run (default: the scene's)")
    add("--out", required=True, help="output folder (the runs go to DIR/runs/)")
    add("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help="override a scene value for every run (e.g. geometry.contact_mesh_size=0.02)")
    add("--energy-threshold", type=float, default=fretting_map.GROSS_SLIP_ENERGY_RATIO, metavar="A_T",
        help="energy ratio A = E_d / (4 delta* Q*) at and above which a cycle is gross slip (default 0.2: Fouvry's "
             "sphere/plane transition)")
    add("--axis", default="imposed", metavar="imposed|contact",
        help="the picture's abscissa: the imposed amplitude delta* (default) or the contact's own delta* - C_b Q* "
             "(a sphere: the bulk compliance C_b from the loop's slope at its reversals less Mindlin's)")
    add("--quiet", action="store_true", help="print only the final table")
    add("--verbose", action="store_true", help="also print the form compiler's build log (hidden by default)")
    add("--overwrite", action="store_true", help="replace the map --out holds (its table, picture and runs)")
    add("--ignore-size", action="store_true",
        help="run even if a run's size estimate exceeds the memory available (refused by default)")


def _map(args: argparse.Namespace) -> int:
    """``dolfinx-fretting map``: the fretting map; 2 for bad input, 1 if any point fails (the failed points are in
    the table)."""
    try:
        if not 0.0 < args.energy_threshold < 1.0:
            raise SceneError(f"--energy-threshold = {args.energy_threshold!r}: allowed a number > 0 and < 1")
        plan = fretting_map.plan_map(args.scene, fretting_map.parse_values(args.normal, "--normal"),
                                     fretting_map.parse_values(args.amplitude, "--amplitude"), args.cycles,
                                     args.overrides)
        fretting_map.check_axis(plan, args.axis)
        for point in plan:  # every run's size before the first starts (SizeError is a SceneError)
            check_size(point.scene, MPI.COMM_WORLD, ignore=args.ignore_size)
        fretting_map.check_map_folder(args.out, overwrite=args.overwrite)
    except (SceneError, OutputFolderError) as exc:
        _say_error("dolfinx-fretting map", exc)
        return 2
    _quiet_form_compiler(args.verbose)
    try:
        rows = fretting_map.run_map(plan, args.out, MPI.COMM_WORLD, quiet=args.quiet,
                                    threshold=args.energy_threshold, overwrite=args.overwrite,
                                    ignore_size=args.ignore_size, axis=args.axis)
    except OutputFolderError as exc:
        _say_error("dolfinx-fretting map", exc)
        return 2
    failed = [f"P = {row['normal']:g}, delta* = {row['amplitude']:g}" for row in rows if not row["converged"]]
    if MPI.COMM_WORLD.rank == 0:
        print(fretting_map.format_markdown(rows))
        print(f"wrote {args.out}/map.csv, map.md, map.png")
        if failed:  # kept in the table with their messages; the exit code says the map is not whole, as the study's
            print(f"dolfinx-fretting map: {len(failed)} of {len(rows)} runs failed ({'; '.join(failed)}); their "
                  "messages are in map.csv and map.md", file=sys.stderr)
    return 1 if failed else 0


def _csv_list(text: str) -> list[str]:
    items = [t.strip() for t in text.split(",")]
    if not all(items):
        raise argparse.ArgumentTypeError(f"empty label in {text!r}")
    return items


def _int_list(text: str) -> list[int]:
    try:
        values = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a comma-separated list of integers: {text!r}") from None
    if not values or any(v < 1 for v in values):
        raise argparse.ArgumentTypeError(f"cycles must be integers >= 1: {text!r}")
    return values


def _node_position(text: str) -> float | None:
    if text.strip().lower() in ("centre", "center"):
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a position (mm) or 'centre': {text!r}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"not a finite position: {text!r}")
    return value


def _compare(args: argparse.Namespace) -> int:
    """``dolfinx-fretting compare``: pictures and summary table; 2 for bad input."""
    # Lazy: compare imports numba (through output -> state -> wear), about 0.4 s the other commands do not need
    from .compare import compare_runs, format_table, read_summary_csv

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RuntimeWarning)
            written = compare_runs(args.folders, args.labels, args.out, cycles=args.cycles,
                                   node_position=args.node)
    except (ValueError, OSError) as exc:
        print(f"dolfinx-fretting compare: {exc}", file=sys.stderr)
        return 2
    for w in caught:
        print(f"dolfinx-fretting compare: warning: {w.message}", file=sys.stderr)
    for path in written:
        print(f"wrote {path}")
    print(format_table(read_summary_csv(written[-1])))
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit code (0 ok, 2 bad input, 1 failed run), the same on every rank."""
    global _exit_comm
    args = _parser().parse_args(argv)  # the same arguments on every rank: argparse's exit is collective
    _failure.clear()
    if args.command not in ("run", "study", "map"):
        return _finish(_command(args), None)
    comm = MPI.COMM_WORLD
    if _exit_comm is None and comm.size > 1:
        _exit_comm = comm.Dup()  # the end-of-run meeting never matches a collective of the run itself
    try:
        code = _command(args)
    except Exception:  # noqa: BLE001 - a bug: its traceback, and no rank left waiting for this one
        if comm.size == 1:
            raise
        traceback.print_exc()
        print(f"dolfinx-fretting: unexpected error on rank {comm.rank}: stopping all {comm.size} ranks",
              file=sys.stderr, flush=True)
        # As in _finish: the launcher may drop what is still in its pipe when the abort kills the job (the
        # traceback's last lines were lost once on 3 ranks of 2 cores): give it time to forward them.
        time.sleep(ABORT_GRACE_SECONDS)
        comm.Abort(1)
    return _finish(code, comm)


def _command(args: argparse.Namespace) -> int:
    if args.command == "scenes":
        for name in sorted(builtin_scenes()):
            print(f"{name:20s} {load_scene(name).description}")
        return 0
    if args.command == "compare":
        return _compare(args)
    if args.command == "study":
        return _study(args)
    if args.command == "map":
        return _map(args)
    try:
        scene = load_scene(args.scene, args.overrides)
    except SceneError as exc:
        _say_error("dolfinx-fretting", exc)
        return 2
    if args.command == "show":
        print(scene.model_dump_json(indent=2))
        return 0
    return _run(args, scene)


def _run(args: argparse.Namespace, scene) -> int:
    """``dolfinx-fretting run``: the output folder checked before DOLFINx is imported, then the run. A signal
    before the run takes its own handlers (while DOLFINx is imported) or after it gives them back ends in the
    same kind of message and exit code as one during the run (:mod:`dolfinx_fretting.interrupts`)."""
    signals = RunSignals()
    signals.install()
    try:
        with signals.raising():
            try:  # each rank checks (the same answer: a file, not writable, holds a run); run_scene locks it
                check_output_folder(args.out, resume=args.resume, overwrite=args.overwrite)
            except OutputFolderError as exc:
                _say_error("dolfinx-fretting", exc)
                return 2
        code = _run_checked(args, scene, signals)
    except Interrupted as exc:
        _say_error("dolfinx-fretting", f"interrupted by {exc} before the run started; nothing was computed")
        return 128 + exc.signum
    finally:
        signals.restore()
    if code == 0 and signals.received:  # after the run gave its handlers back: its outputs are complete
        _say_error("dolfinx-fretting", f"interrupted by {signals.name} as the run ended; its outputs are complete")
        code = 128 + signals.received
    return code


def _run_checked(args: argparse.Namespace, scene, signals: RunSignals) -> int:
    with signals.raising():
        # Lazy: petsc4py and DOLFINx (PETSc initialised; io: numba), which the other commands and a refused
        # output folder never need
        from petsc4py import PETSc

        from .compliance import DelassusError
        from .io import TableError
        from .simulation import RunInterrupted, SimulationError, run_scene

        _quiet_form_compiler(args.verbose)
    try:
        run_scene(scene, args.out, MPI.COMM_WORLD, quiet=args.quiet, resume=args.resume, overwrite=args.overwrite,
                  ignore_size=args.ignore_size)
    except RunInterrupted as exc:  # the run stopped cleanly; its message says what is on disk and what is not
        _say_error("dolfinx-fretting", exc)
        return exc.exit_code
    except (OutputFolderError, TableError, SceneError) as exc:  # SceneError: the size check (sizes.SizeError)
        _say_error("dolfinx-fretting", exc)
        return 2
    except SimulationError as exc:  # an OutputFolderLost too: the folder deleted or replaced during the run
        _say_error("dolfinx-fretting: run failed", exc)
        return 1
    except (DelassusError, PETSc.Error) as exc:  # options PETSc or MUMPS refuse only when they factorise
        lines = [x.strip() for x in str(exc).splitlines() if x.strip()] or [type(exc).__name__]
        text = lines[0] + (f" ... {lines[-1]}" if len(lines) > 1 else "")  # PETSc's stack trace in between
        _say_error("dolfinx-fretting: run failed: PETSc/MUMPS", f"{text} (solver.petsc_options: "
                   f"{scene.solver.petsc_options or 'none given'})")
        return 1
    except OSError as exc:  # e.g. the disk filled up while writing
        _say_error("dolfinx-fretting: run failed: writing the outputs", exc)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

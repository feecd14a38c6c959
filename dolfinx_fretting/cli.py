"""Command line: ``dolfinx-fretting scenes`` and ``dolfinx-fretting run SCENE --out DIR [--set k=v ...]``."""

from __future__ import annotations

import argparse
import sys

from .scenes import SceneError, builtin_scenes, load_scene

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
    run.add_argument("--resume", action="store_true",
                     help="continue the run checkpointed in --out (the scene may differ only in its solver and "
                          "output sections and in loading.cycles)")
    show = sub.add_parser("show", help="print a scene with every default filled in, as validated")
    show.add_argument("scene")
    show.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit code (0 ok, 2 bad input, 1 failed run)."""
    args = _parser().parse_args(argv)
    if args.command == "scenes":
        from .scenes import load_scene as _load
        for name in sorted(builtin_scenes()):
            print(f"{name:20s} {_load(name).description}")
        return 0
    try:
        scene = load_scene(args.scene, args.overrides)
    except SceneError as exc:
        print(f"dolfinx-fretting: {exc}", file=sys.stderr)
        return 2
    if args.command == "show":
        print(scene.model_dump_json(indent=2))
        return 0

    from mpi4py import MPI

    from .simulation import SimulationError, run_scene

    try:
        run_scene(scene, args.out, MPI.COMM_WORLD, quiet=args.quiet, resume=args.resume)
    except SimulationError as exc:
        if MPI.COMM_WORLD.rank == 0:
            print(f"dolfinx-fretting: run failed: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

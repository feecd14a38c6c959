"""CPU seconds of chosen tests, per test, on two source trees: what a change to the tests saves.

Each tree's tests run in one pytest session with this file as a plugin (``-p bench_test_cpu``): a test's CPU time is
user + system of the pytest process and of every child it waited for (subprocesses, ``mpiexec`` and its ranks), from
its setup to its teardown. CPU time, not wall time: on a machine shared with other jobs the wall time of a test
grows with the load, its CPU time hardly (the start-up of the children and the arithmetic are the same work).

    python benchmarks/bench_test_cpu.py --tree /path/to/old/checkout --tree . [--python .venv/bin/python] \\
        --out benchmarks/results/test_cpu.md -- tests/test_x.py::test_y ...

A tree is a checkout whose ``tests/`` are run with its own package first on ``PYTHONPATH``.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

_rows: list[tuple[str, float]] = []


def _cpu() -> float:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    start = _cpu()
    yield
    _rows.append((item.nodeid, _cpu() - start))


def pytest_sessionfinish(session):
    out = os.environ.get("BENCH_TEST_CPU_OUT")
    if out:
        Path(out).write_text("".join(f"{seconds:.2f}\t{nodeid}\n" for nodeid, seconds in _rows))


def _run(tree: Path, python: str, tests: list[str], table: Path) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tree), str(Path(__file__).resolve().parent)]),
               OPENBLAS_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               BENCH_TEST_CPU_OUT=str(table))
    proc = subprocess.run([python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "bench_test_cpu", *tests],
                          cwd=tree, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"tests failed on {tree}:\n{proc.stdout[-3000:]}{proc.stderr[-3000:]}")
    return {line.split("\t")[1]: float(line.split("\t")[0]) for line in table.read_text().splitlines()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", action="append", type=Path, required=True, help="a checkout (twice: before, after)")
    parser.add_argument("--python", default=sys.executable, help="the stack's interpreter")
    parser.add_argument("--out", type=Path, help="append the table (Markdown) to this file")
    parser.add_argument("tests", nargs="+", help="pytest node ids, relative to a tree")
    args = parser.parse_args()
    times = [_run(tree.resolve(), args.python, args.tests, Path(f"/tmp/bench_test_cpu_{i}.tsv"))
             for i, tree in enumerate(args.tree)]
    names = [str(tree) for tree in args.tree]
    lines = [f"| test | {' | '.join(names)} |", "|---" * (len(names) + 1) + "|"]
    for nodeid in sorted(set().union(*times), key=lambda n: -times[0].get(n, 0.0)):
        lines.append(f"| `{nodeid}` | " + " | ".join(f"{t.get(nodeid, float('nan')):.1f}" for t in times) + " |")
    lines.append("| total | " + " | ".join(f"{sum(t.values()):.1f}" for t in times) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        with open(args.out, "a") as f:
            f.write(f"\n`{' '.join(sys.argv)}` ({Path(args.python).parent.parent.name}):\n\n{text}")


if __name__ == "__main__":
    main()

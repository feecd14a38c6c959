"""What the benchmarks say about the machine they ran on (shared by the benchmark scripts)."""

from __future__ import annotations

import datetime
import json
import os
import platform
import resource
import shlex
import subprocess
import time
from pathlib import Path

import numba
import numpy as np


def cpu_model() -> str:
    """The processor's model name from ``/proc/cpuinfo`` (else what ``platform`` knows)."""
    model = platform.processor() or platform.machine() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return model


def run_tree(command: list[str], tree: Path) -> tuple[float, float]:
    """Run ``command`` with the package's sources from ``tree`` (``PYTHONPATH``; one BLAS thread) and its output
    thrown away: (its CPU seconds, user + system of the child, and its wall seconds)."""
    env = {**os.environ, "PYTHONPATH": str(tree), "OPENBLAS_NUM_THREADS": "1"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, env=env, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def command_line(script: str, argv: list[str]) -> str:
    """The command a benchmark ran, as its results file states it: BLAS threads, interpreter, script, arguments."""
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "<unset>")
    return (f"OPENBLAS_NUM_THREADS={threads} .venv/bin/python benchmarks/{script}"
            + "".join(" " + shlex.quote(a) for a in argv))


def machine_record(**settings) -> dict:
    """The date, the machine, the Python / numpy / numba versions and the load average at the start, with the
    benchmark's own ``settings``; :func:`write_results` adds the load average at the end."""
    return {"date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"), "cpu": cpu_model(),
            "logical_cpus": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__,
            "numba": numba.__version__, "load_start": list(os.getloadavg()), **settings}


def machine_lines(info: dict) -> list[str]:
    """The results file's two lines on the machine and its load (from :func:`machine_record`'s ``info``)."""
    return [f"- date: {info['date']}; machine: {info['cpu']}, {info['logical_cpus']} logical CPUs shared with other "
            f"jobs; Python {info['python']}, numpy {info['numpy']}, numba {info['numba']}",
            f"- load average (1, 5, 15 min) at start {', '.join(f'{v:.2f}' for v in info['load_start'])}, at end "
            f"{', '.join(f'{v:.2f}' for v in info['load_end'])}"]


def write_results(out: Path, command: str, info: dict, records: list[dict], markdown) -> None:
    """``out.json`` (the command, ``info`` with the load average now, the records) and ``out.md``
    (``markdown(command, info, records)``), written again after each record so that a stopped run keeps its part."""
    info["load_end"] = list(os.getloadavg())
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"command": command, "machine": info, "results": records},
                                                   indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(command, info, records))

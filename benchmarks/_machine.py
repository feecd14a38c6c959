"""What the benchmarks say about the machine they ran on (shared by the benchmark scripts)."""

from __future__ import annotations

import os
import platform
import resource
import subprocess
import time
from pathlib import Path


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

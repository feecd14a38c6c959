"""The memory a new run, or a second factor inside one, can take: read from the machine, not estimated.

:func:`~dolfinx_fretting.sizes.check_size` compares a scene's estimate with it before anything is built;
:class:`~dolfinx_fretting.compliance.DelassusOperator`'s ``"auto"`` route reads it before it takes the Schur route,
whose second factor may not fit where K's did.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["available_memory"]


def available_memory() -> tuple[int, str]:
    """Bytes of memory available to a new run, and where the number comes from.

    ``MemAvailable`` of ``/proc/meminfo`` (what can be allocated without swapping), lowered to the room left
    under a cgroup v2 limit (``memory.max - memory.current``) in a container; without ``/proc``,
    ``os.sysconf``'s available physical pages.
    """
    value, source = None, ""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                value, source = int(line.split()[1]) * 1024, "MemAvailable"
                break
    except OSError:
        pass
    if value is None:
        try:
            value = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
            source = "sysconf(SC_AVPHYS_PAGES)"
        except (ValueError, OSError, AttributeError):
            return 0, "unknown"
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            room = int(limit) - int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
            if room < value:
                value, source = room, "the cgroup's memory.max - memory.current"
    except (OSError, ValueError):
        pass
    return int(value), source

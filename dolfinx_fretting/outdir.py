"""Output folders: checked before any work, locked for a run's duration, cleared only of the package's files.

A run starts with :func:`claim_output_folder` (collective: rank 0 does the file-system work and broadcasts the
outcome, so every rank raises the same :class:`OutputFolderError`):

* the folder must be a folder that can be created and written (not a file, not under a file);
* a lock file (:data:`LOCK_NAME`) is held for the run's duration with ``flock``: a second run into the same
  folder is refused with the holder's pid and host. The kernel drops the lock when its process dies (even
  by ``kill -9``), so the lock file a dead run leaves behind, with its dead pid, is taken over;
* a folder that already holds a run (:data:`RUN_MARKERS`: ``summary.json``, ``checkpoint.npz`` or a table) is
  refused unless the run resumes it or overwrites it; ``overwrite`` deletes the old run's files
  (:data:`RUN_FILES`, the checkpoint included) and nothing else: files the package did not write stay.

The command line calls :func:`check_output_folder` first, before it imports DOLFINx, so a bad ``--out`` costs
nothing. :func:`load_checkpoint` reads a checkpoint for ``--resume`` and refuses, naming the file or key, one
that does not load, tables shorter than it records (their rows would be lost: a shorter file extended by
``truncate`` fills with NUL bytes) and a cycle count below what it has done.
"""

from __future__ import annotations

import fcntl
import json
import os
import socket
import tempfile
import time
import zipfile
from itertools import takewhile
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

__all__ = ["OutputFolderError", "OutputLock", "check_output_folder", "ensure_writable_folder", "claim_output_folder",
           "folder_lost",
           "held_run_files", "clear_run_files", "check_resume_tables", "load_checkpoint", "lock_holder", "LOCK_NAME", "RUN_FILES",
           "RUN_MARKERS", "CHECKPOINT_NAME", "TABLE_NAMES"]

#: The lock file a run holds in its output folder.
LOCK_NAME = ".dolfinx_fretting.lock"
#: The checkpoint a cyclic run writes (``simulation.CHECKPOINT``).
CHECKPOINT_NAME = "checkpoint.npz"
#: The tables a run appends to (``io.ResultWriter``).
TABLE_NAMES = ("history.csv", "cycles.csv", "contact_profiles.csv", "flat_profiles.csv")
#: Files whose presence means the folder holds a run.
RUN_MARKERS = ("summary.json", "run.json", CHECKPOINT_NAME, *TABLE_NAMES)
#: Every file a run writes into its folder (``io``, ``simulation``, ``contact_output``, ``plots``, ``pictures``),
#: with the temporary names of its atomic writes: what ``overwrite`` deletes, and nothing else.
RUN_FILES = (*RUN_MARKERS, "summary.json.tmp", "run.json.tmp", CHECKPOINT_NAME + ".tmp.npz", "worn_profiles.csv",
             "fields.xdmf", "fields.h5", "fields.xdmf.tmp", "contact.xdmf", "contact.h5", "contact.xdmf.tmp",
             "contact.h5.tmp",
             "profiles.png", "profiles_across.png", "wear_first_cycle.png", "wear_evolution.png", "node_history.png", "fretting_loops.png",
             "wear_growth.png", "deformed_von_mises.png", "worn_profile.png",
             "fatigue.csv", "fatigue.png")


class OutputFolderError(RuntimeError):
    """The output folder cannot be used (a file, not writable, in use by another run, holding a run, or a
    checkpoint that cannot be resumed); the message names the folder or file and what to do."""


# Checks ------------------------------------------------------------------------------------------------------
def check_output_folder(path: str | Path, *, resume: bool = False, overwrite: bool = False) -> Path:
    """Check an output folder: not a file, not under a file, writable (or, if it does not exist yet, creatable
    where it would be: it is not created, so that a run refused later leaves nothing behind; the run's claim,
    :func:`claim_output_folder`, creates it); and, unless ``resume`` or ``overwrite``, not holding a run already.
    Serial (call it on one rank or on each).

    Returns:
        The folder as a :class:`~pathlib.Path`.

    Raises:
        OutputFolderError: naming the folder and the reason (also ``resume`` without a checkpoint).
    """
    if resume and overwrite:
        raise OutputFolderError(f"{path}: --resume continues the run in it, --overwrite deletes it: give one")
    folder = Path(path)
    existing = _existing_place(folder)
    _probe(folder, existing)
    if existing != folder:  # nothing there yet: no run held, no checkpoint
        if resume:
            raise OutputFolderError(f"--resume: no checkpoint {folder / CHECKPOINT_NAME}; run without --resume to "
                                    "start afresh")
        return folder
    _refuse_held_run(folder, resume, overwrite)
    if resume and not (folder / CHECKPOINT_NAME).is_file():
        raise OutputFolderError(f"--resume: no checkpoint {folder / CHECKPOINT_NAME}; run without --resume to "
                                "start afresh")
    return folder


def _usable_folder(path: str | Path, resume: bool, overwrite: bool) -> Path:
    if resume and overwrite:
        raise OutputFolderError(f"{path}: --resume continues the run in it, --overwrite deletes it: give one")
    return ensure_writable_folder(path)


def _existing_place(folder: Path) -> Path:
    """``folder`` if it is a folder, else its nearest existing ancestor (where it would be created).

    Raises:
        OutputFolderError: ``folder`` is a file, or under one.
    """
    if folder.exists() and not folder.is_dir():
        raise OutputFolderError(f"--out {folder} is a file, not a folder; choose a folder")
    if folder.is_dir():
        return folder
    for parent in folder.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputFolderError(f"--out {folder} is under {parent}, which is a file, not a folder")
            return parent
    raise OutputFolderError(f"--out {folder}: no folder of its path exists")  # pragma: no cover - '/' exists


def _probe(folder: Path, place: Path) -> None:
    """Write and delete a file in ``place`` (``folder`` or the ancestor it would be created in): os.access answers
    yes to root on a read-only file system."""
    try:
        with tempfile.NamedTemporaryFile(dir=place, prefix=".write_probe_"):
            pass
    except OSError as exc:
        what = "is not writable" if place == folder else f"cannot be created in {place}"
        raise OutputFolderError(f"--out {folder} {what}: {exc.strerror or exc}") from None


def ensure_writable_folder(path: str | Path) -> Path:
    """Create ``path`` if needed and check that it is a folder this process can write (compare, study).

    Raises:
        OutputFolderError: it is a file, under a file, or cannot be created or written.
    """
    folder = Path(path)
    _existing_place(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputFolderError(f"--out {folder} cannot be created: {exc.strerror or exc}") from None
    _probe(folder, folder)
    return folder


def _refuse_held_run(folder: Path, resume: bool, overwrite: bool) -> None:
    held = held_run_files(folder)
    if held and not (resume or overwrite):
        if CHECKPOINT_NAME not in held:  # nothing to resume from (e.g. a run stopped while its model was built)
            raise OutputFolderError(
                f"--out {folder} already holds a run ({', '.join(held)}) with no checkpoint to resume from; "
                "replace it with --overwrite (deletes that run's files), or choose another folder")
        raise OutputFolderError(
            f"--out {folder} already holds a run ({', '.join(held)}); continue it with --resume, replace it with "
            "--overwrite (deletes that run's files, its checkpoint included), or choose another folder")


def held_run_files(folder: str | Path) -> list[str]:
    """The :data:`RUN_MARKERS` present in ``folder``."""
    folder = Path(folder)
    return [name for name in RUN_MARKERS if (folder / name).exists()]


def clear_run_files(folder: str | Path) -> list[str]:
    """Delete the files a run writes (:data:`RUN_FILES`) from ``folder``; other files and any sub-folder stay.

    Returns:
        The names deleted.
    """
    folder = Path(folder)
    removed = []
    for name in RUN_FILES:
        p = folder / name
        if p.is_file() or p.is_symlink():
            p.unlink()
            removed.append(name)
    return removed


# The lock ------------------------------------------------------------------------------------------------------
def _process_record() -> dict[str, Any]:
    return {"pid": os.getpid(), "host": socket.gethostname(), "started": time.strftime("%Y-%m-%dT%H:%M:%S")}


def lock_holder(folder: str | Path) -> dict[str, Any] | None:
    """What the lock file of ``folder`` records (pid, host, start time), or ``None`` (no file, unreadable)."""
    try:
        return json.loads((Path(folder) / LOCK_NAME).read_text())
    except (OSError, ValueError):
        return None


class OutputLock:
    """The lock of an output folder, held from :func:`claim_output_folder` until :meth:`release` (or the end
    of a ``with`` block). Only the rank that did the file-system work holds the file; on the others this is
    an empty token.

    Attributes:
        folder: The output folder.
        previous_holder: The record of a stale lock taken over (a run that died), or ``None``.
        removed: Files deleted by ``overwrite``.
        created: The folders the claim created (the output folder first, then the parents it needed):
            :meth:`release` deletes them again if the run left them empty (a run refused once its model was read,
            e.g. a mesh file's fault, leaves no empty folder behind).
    """

    def __init__(self, folder: Path, fd: int | None = None, previous_holder: dict[str, Any] | None = None,
                 removed: list[str] | None = None):
        self.folder = folder
        self._fd = fd
        self.previous_holder = previous_holder
        self.removed = removed or []
        self.created: list[Path] = []
        # The folder itself, open: its (device, inode) tells a folder deleted or replaced by another of the same
        # name (or moved away), and the lock file is deleted from it wherever it is now.
        self._dir_fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY) if fd is not None else None
        self._identity = _identity(self._dir_fd) if fd is not None else None

    def replaced(self) -> bool:
        """The folder's path now names another folder (not collective; False where the lock is not held)."""
        if self._fd is None:
            return False
        try:
            return _identity(self.folder) != self._identity
        except OSError:
            return False

    def lost(self) -> str | None:
        """Why the folder locked is no longer the one at its path, or ``None`` if it is (not collective; on
        the rank that holds the lock; ``None`` elsewhere). Checked by the run before it writes."""
        if self._fd is None:
            return None
        try:
            now = _identity(self.folder)
        except OSError:
            return f"--out {self.folder} was deleted (or moved away) during the run"
        if now != self._identity:
            return f"--out {self.folder} was replaced during the run (another folder now has its name)"
        try:
            mine = os.stat(LOCK_NAME, dir_fd=self._dir_fd).st_ino == os.fstat(self._fd).st_ino
        except OSError:
            mine = False
        if not mine:
            return f"--out {self.folder}: the run's lock file {LOCK_NAME} was deleted or replaced during the run"
        return None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def release(self) -> None:
        """Delete the lock file and drop the lock (idempotent; not collective)."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        dir_fd, self._dir_fd = self._dir_fd, None
        try:
            # unlink while still holding it: a run that opened the old file finds it gone and retries. Through
            # the folder's descriptor (the folder moved away: its lock goes too; replaced: the new one's stays),
            # and only the file this lock holds.
            if os.stat(LOCK_NAME, dir_fd=dir_fd).st_ino == os.fstat(fd).st_ino:
                os.unlink(LOCK_NAME, dir_fd=dir_fd)
            if self.created and _identity(self.folder) == self._identity:  # still ours: not one of the same name
                for folder in self.created:
                    os.rmdir(folder)  # only if empty: anything the run (or anyone) wrote keeps it (and its parents)
        except OSError:  # gone with its folder, or not empty
            pass
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
            os.close(fd)
            os.close(dir_fd)

    def __enter__(self) -> OutputLock:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __del__(self) -> None:  # a lock dropped without release (an exception before the with block)
        try:
            self.release()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass


def _acquire(folder: Path) -> OutputLock:
    """Take the folder's lock (flock, non-blocking) and write this process's record into it."""
    path = folder / LOCK_NAME
    for _attempt in range(20):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # BlockingIOError: a live process holds it
            os.close(fd)
            holder = lock_holder(folder) or {}
            raise OutputFolderError(
                f"--out {folder} is in use by another run (pid {holder.get('pid', '?')} on "
                f"{holder.get('host', '?')}, started {holder.get('started', '?')}; lock file {path}): wait for it "
                "to end, or choose another folder") from None
        try:  # the file locked must still be the one at `path` (a run that ends deletes it first)
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)
    else:  # pragma: no cover - 20 runs ending while we open
        raise OutputFolderError(f"--out {folder}: could not take the lock file {path}")
    previous = lock_holder(folder)  # a lock file nobody holds: its run died (the kernel dropped its lock)
    record = json.dumps(_process_record()).encode()
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, record, 0)
        os.fsync(fd)
    except OSError:  # a full disk: no empty lock file left behind
        path.unlink(missing_ok=True)
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)
        raise
    return OutputLock(folder, fd, previous)


def _identity(folder: Path | int) -> tuple[int, int]:
    info = os.stat(folder)  # a path or an open descriptor
    return info.st_dev, info.st_ino


def folder_lost(lock: OutputLock, comm: Any) -> str | None:
    """Collective: :meth:`OutputLock.lost` of the rank holding the lock (rank 0), on every rank."""
    message = lock.lost() if comm.rank == 0 else None
    return comm.bcast(message, root=0) if comm.size > 1 else message


def claim_output_folder(path: str | Path, comm: Any = None, resume: bool = False,
                        overwrite: bool = False) -> OutputLock:
    """Check the output folder, lock it for this run and, with ``overwrite``, delete the old run's files.

    Collective on ``comm`` (default ``MPI.COMM_WORLD``): rank 0 does the file-system work and broadcasts the
    outcome, so every rank raises the same error. Call it before any expensive work; release the lock at the
    end (``with claim_output_folder(...):``).

    Args:
        path: The output folder (created if missing).
        comm: Communicator.
        resume: The run continues the one in the folder (a held run is expected, not refused).
        overwrite: Delete the files of the run the folder holds (:data:`RUN_FILES` only) after taking the lock.

    Returns:
        The lock (held on rank 0).

    Raises:
        OutputFolderError: the folder is a file or under one, cannot be written, is locked by a live run
            (its pid named), or holds a run and neither ``resume`` nor ``overwrite`` was given.
    """
    if comm is None:
        comm = MPI.COMM_WORLD
    folder = Path(path)
    lock: OutputLock | None = None
    error = None
    if comm.rank == 0:
        created = list(takewhile(lambda p: not p.exists(), [folder.absolute(), *folder.absolute().parents]))
        try:
            _usable_folder(folder, resume, overwrite)
            lock = _acquire(folder)
            lock.created = created
            _refuse_held_run(folder, resume, overwrite)  # under the lock: no run can start in between
            if overwrite:
                lock.removed = clear_run_files(folder)
        except OutputFolderError as exc:
            error = str(exc)
        except OSError as exc:
            error = f"--out {folder}: {exc.strerror or exc}"
        if error is not None and lock is not None:
            lock.release()
    if comm.size > 1:
        error = comm.bcast(error, root=0)
    if error is not None:
        raise OutputFolderError(error)
    return lock if lock is not None else OutputLock(folder)


# Resume --------------------------------------------------------------------------------------------------------
def check_resume_tables(folder: str | Path, sizes: dict[str, int], checkpoint: str | Path | None = None) -> str | None:
    """A message if a table is missing or shorter than the byte size a checkpoint recorded for it, else ``None``.

    Args:
        folder: The output folder.
        sizes: Table name (``history``, ``cycles``, ``contact_profiles``) to its recorded size in bytes.
        checkpoint: The checkpoint file, for the message.
    """
    folder = Path(folder)
    where = f" (recorded in {checkpoint})" if checkpoint is not None else ""
    for name, size in sizes.items():
        path = folder / f"{name}.csv"
        if not path.is_file():
            return (f"{path} is missing but the checkpoint{where} counts {int(size)} bytes of it: its rows would be "
                    "lost; restore it, or start afresh with --overwrite")
        actual = path.stat().st_size
        if actual < int(size):
            return (f"{path} holds {actual} bytes, fewer than the {int(size)} the checkpoint{where} counts: rows "
                    "the checkpoint relies on are gone (the table was truncated or replaced); restore it, or start "
                    "afresh with --overwrite")
    return None


def load_checkpoint(path: str | Path, planned_cycles: int | None = None) -> dict[str, Any]:
    """Read a run's checkpoint for ``--resume`` and check that the folder can be resumed from it.

    Args:
        path: The checkpoint file (``checkpoint.npz``).
        planned_cycles: ``loading.cycles`` of the resumed scene; refused if below the cycles done.

    Returns:
        Its arrays by name, and ``"meta"``: the parsed record (increment, cycle, table sizes, scene identity...).

    Raises:
        OutputFolderError: no checkpoint; a file that does not load (not a zip, truncated, a missing entry); a
            table missing or shorter than recorded; ``loading.cycles`` below the cycles done. The message names
            the file or the key.
    """
    path = Path(path)
    if not path.is_file():
        raise OutputFolderError(f"no checkpoint {path}; run without --resume to start afresh")
    try:
        with np.load(path, allow_pickle=False) as data:
            ck = {k: data[k] for k in data.files}
        # The problem's state (FrettingProblem.save_state) with the run's record in its "meta".
        info = json.loads(str(ck.pop("state")))
        meta = dict(info["meta"])
        meta["increment"] = int(info["increment"])
        meta["cycle"] = int(meta["progress"]["cycle"])
        for key in ("sizes", "identity"):
            meta[key]  # noqa: B018 - a missing entry is a damaged file
        for key in ("forces", "positions", "wear_gap", "obstacle"):
            ck[key]  # noqa: B018
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise OutputFolderError(f"the checkpoint {path} cannot be read ({type(exc).__name__}: {exc}); it is damaged "
                                "or truncated: start afresh with --overwrite") from None
    problem = check_resume_tables(path.parent, meta["sizes"], path)
    if problem is not None:
        raise OutputFolderError(problem)
    done = int(meta["cycle"])
    if planned_cycles is not None and planned_cycles < done:
        raise OutputFolderError(f"loading.cycles = {planned_cycles} is below the {done} cycles the checkpoint {path} "
                                f"has done; allowed: loading.cycles >= {done}")
    ck["meta"] = meta
    return ck

"""SIGINT and SIGTERM during a run: where they stop it, never a traceback.

A run (``simulation.run_scene``) holds a :class:`RunSignals` from before it claims its output folder to after it
releases it. What a signal does depends on the stage it arrives in:

* while the model is built (meshing, K, W): nothing is computed yet, so it stops the run at once
  (:meth:`RunSignals.raising`: :class:`Interrupted` is raised from the handler; a ``BaseException``, so no
  ``except Exception`` in the build swallows it);
* in the increments and cycles: noted; the run stops at the end of the increment or cycle, checkpointed;
* while the outputs are finished (summary, plots, pictures) and during a stop: noted; what is left of the
  optional outputs (``contact.xdmf``, plots, pictures) is skipped and the summary lists it.

gmsh sets SIGINT to its default action (the process killed at once, the lock file left) when it is imported
(4.8) or initialised (4.11+): :func:`keep_handlers` puts the run's handlers back around it.

:data:`TEST_HOOK` is a test hook: ``DOLFINX_FRETTING_TEST_HOOK=STAGE`` makes a run print
``test hook: STAGE`` on stderr when it reaches that stage and, for the stages that wait, wait there (at most
:data:`HOOK_WAIT_SECONDS`) until a signal arrives, so a test can send its signal at a known point instead of
after a guessed delay. Unset, it costs one dictionary look-up per stage.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["Interrupted", "RunSignals", "keep_handlers", "stage_hook", "TEST_HOOK", "HOOK_WAIT_SECONDS"]

#: The signals a run handles: each ends it with exit code 128 + its number (130, 143).
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Environment variable naming the stage where a run waits for a signal (tests only; see the module docstring).
TEST_HOOK = "DOLFINX_FRETTING_TEST_HOOK"
#: Seconds a test hook waits for its signal before the run goes on.
HOOK_WAIT_SECONDS = 120.0


class Interrupted(BaseException):
    """A signal stopped a stage that has nothing to save (raised by :class:`RunSignals`' handler)."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


class RunSignals:
    """The run's SIGINT/SIGTERM handlers: the first signal received is kept (its exit code is the run's).

    Handlers are installed only in the main thread (the only one Python delivers signals to); elsewhere
    :meth:`install` does nothing and :attr:`received` stays 0.

    Attributes:
        received: The first signal received (0: none).
        count: Signals received so far.
    """

    def __init__(self) -> None:
        self.received = 0
        self.count = 0
        self._raise_at_once = False
        self._previous: dict[int, object] = {}

    @property
    def name(self) -> str:
        """The first signal's name (``SIGINT``), or an empty string."""
        return signal.Signals(self.received).name if self.received else ""

    def _handle(self, signum: int, frame) -> None:  # noqa: ARG002
        self.received = self.received or signum
        self.count += 1
        if self._raise_at_once:
            self._raise_at_once = False  # a second signal during the stop that follows is only noted
            raise Interrupted(self.received)

    def install(self) -> None:
        """Put the handlers in place (main thread only); :meth:`restore` puts the previous ones back."""
        if threading.current_thread() is not threading.main_thread():
            return
        for sig in SIGNALS:
            previous = signal.signal(sig, self._handle)
            self._previous.setdefault(sig, previous)

    def reinstall(self) -> None:
        """Put the handlers back after a library replaced them (gmsh); keeps the handlers to restore."""
        if self._previous:
            for sig in SIGNALS:
                signal.signal(sig, self._handle)

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}

    @contextmanager
    def raising(self) -> Iterator[None]:
        """A stage with nothing to save: a signal (or one that came before) raises :class:`Interrupted` at once."""
        if self.received:
            raise Interrupted(self.received)
        self._raise_at_once = True
        try:
            yield
        finally:
            self._raise_at_once = False


@contextmanager
def keep_handlers() -> Iterator[None]:
    """Restore SIGINT's and SIGTERM's handlers after the block (gmsh's import and ``initialize`` set SIGINT to
    its default action, which kills the process with no clean-up)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = {sig: signal.getsignal(sig) for sig in SIGNALS}
    try:
        yield
    finally:
        for sig, handler in saved.items():
            if handler is not None:
                signal.signal(sig, handler)


def stage_hook(stage: str, signals: RunSignals | None = None, wait: bool = True) -> None:
    """Test hook (:data:`TEST_HOOK`): at ``stage``, say so on stderr and, if ``wait``, wait for a signal.

    The wait ends when ``signals`` notes one more signal (a stage whose signals are only noted) or when the
    handler raises (a :meth:`RunSignals.raising` stage), or after :data:`HOOK_WAIT_SECONDS`.
    """
    if os.environ.get(TEST_HOOK) != stage:
        return
    before = signals.count if signals is not None else 0
    print(f"test hook: {stage}", file=sys.stderr, flush=True)
    deadline = time.monotonic() + HOOK_WAIT_SECONDS
    while wait and time.monotonic() < deadline and not (signals is not None and signals.count > before):
        time.sleep(0.02)

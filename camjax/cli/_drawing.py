"""A command's figures, drawn beside its computation.

Matplotlib's import (about half a second) and the drawing of a command's PNG figures
(about as much again) used to follow the numbers they show.  The ``camjax`` executable
now forks a drawing process before it computes: the child imports matplotlib while the
parent sweeps, then draws what the parent sends it while the parent writes its tables.
The parent waits for it before it reports the files written, so a figure that fails is
an error of the command, as it was in one process.

A fork is safe only before JAX starts its backends (XLA's threads do not survive one),
and only where the figures need no windowing system (Linux, where Agg draws them): the
executable forks there; anywhere else, and in a caller's own process (``camjax.cli.main``),
the figures are drawn in-process, matplotlib imported on a thread while XLA compiles.
"""

from __future__ import annotations

import os
import pickle
import sys
import threading
import traceback
from typing import NamedTuple

from ._common import import_aside


class Figure(NamedTuple):
    """One figure: ``camjax.plot``'s function ``kind`` called with ``args`` and ``kwargs``,
    saved to ``path``."""

    kind: str
    path: os.PathLike
    args: tuple = ()
    kwargs: dict = {}


def can_fork() -> bool:
    """Whether a drawing process may be forked now: on Linux, before JAX's backends start
    (not where this JAX cannot say)."""
    if not sys.platform.startswith("linux") or not hasattr(os, "fork"):
        return False
    from ..sharding import backends_started

    return backends_started() is False


def _draw(figures: list[Figure]) -> None:
    from .. import plot

    for figure in figures:
        plot.save(getattr(plot, figure.kind)(*figure.args, **figure.kwargs), figure.path)


class Drawing:
    """Where a command's figures are drawn: ``Drawing(aside=True)`` forks the drawing process
    (see the module) if ``can_fork()``, else they are drawn in-process.  Start it before the
    work (the child imports matplotlib meanwhile), then ``draw`` once and ``wait``."""

    def __init__(self, aside: bool):
        self._child = None
        self._figures: list[Figure] = []
        if aside and can_fork():
            jobs, self._jobs = os.pipe()
            self._status, status = os.pipe()
            pid = os.fork()
            if pid == 0:
                os.close(self._jobs)
                os.close(self._status)
                _serve(jobs, status)  # never returns
            os.close(jobs)
            os.close(status)
            self._child = pid
        else:
            self._plotting = import_aside("camjax.plot")

    @property
    def forked(self) -> bool:
        """Whether the figures are drawn in a forked process."""
        return self._child is not None

    def draw(self, figures: list[Figure]) -> None:
        """Start drawing ``figures`` (the forked process draws them now; in-process, at
        ``wait``)."""
        if self._child is None:
            self._figures = list(figures)
            return

        data = pickle.dumps(list(figures), protocol=pickle.HIGHEST_PROTOCOL)

        def send():
            with os.fdopen(self._jobs, "wb") as jobs:
                jobs.write(data)

        # On a thread: the child may still be importing matplotlib, and the pipe holds
        # 64 KiB; the command writes its tables meanwhile.
        self._sending = threading.Thread(target=send)
        self._sending.start()

    def wait(self) -> None:
        """Return once every figure is written.

        Raises:
            RuntimeError: the drawing process failed (its traceback in the message).
        """
        if self._child is None:
            self._plotting()
            _draw(self._figures)
            return
        self._sending.join()
        with os.fdopen(self._status, "rb") as status:
            failure = status.read().decode()
        _, code = os.waitpid(self._child, 0)
        if failure or code:
            raise RuntimeError(f"the figures' drawing process failed (status {code}):\n{failure}")


def _serve(jobs: int, status: int) -> None:
    """The forked child: import matplotlib, draw the figures the parent sends, report any
    failure, and end without running the parent's exit handlers or flushing its buffers."""
    failure = b""
    try:
        from .. import plot  # noqa: F401  (imported while the parent computes)

        with os.fdopen(jobs, "rb") as stream:
            figures = pickle.load(stream)  # EOFError if the parent ends without drawing
        _draw(figures)
    except EOFError:
        os._exit(0)
    except BaseException:  # noqa: BLE001  (every failure goes back to the parent)
        failure = traceback.format_exc().encode()
    try:
        os.write(status, failure)
    finally:
        os._exit(1 if failure else 0)

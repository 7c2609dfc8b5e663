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


class _Child(NamedTuple):
    """A forked drawing process: its pid, the pipe the parent sends its figures into, and
    the pipe it reports a failure through."""

    pid: int
    jobs: int
    status: int

    @classmethod
    def fork(cls) -> _Child:
        jobs, send = os.pipe()
        receive, status = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(send)
            os.close(receive)
            _serve(jobs, status)  # never returns
        os.close(jobs)
        os.close(status)
        return cls(pid, send, receive)


PROCESSES = 2
"""Drawing processes a command forks: the figures are shared among them in turn (three
PNG figures of ``camjax ct`` take 0.5 s of Agg in one process)."""


class Drawing:
    """Where a command's figures are drawn: ``Drawing(aside=True)`` forks ``processes``
    drawing processes (see the module) if ``can_fork()``, else they are drawn in-process.
    Start it before the work (the children import matplotlib meanwhile), then ``draw``
    once and ``wait``."""

    def __init__(self, aside: bool, processes: int = PROCESSES):
        self._children: list[_Child] = []
        self._figures: list[Figure] = []
        self._sending: list[threading.Thread] = []
        if aside and can_fork():
            self._children = [_Child.fork() for _ in range(processes)]
        else:
            self._plotting = import_aside("camjax.plot")

    @property
    def forked(self) -> bool:
        """Whether the figures are drawn in forked processes."""
        return bool(self._children)

    def draw(self, figures: list[Figure]) -> None:
        """Start drawing ``figures`` (the forked processes draw them now, the first figure
        to the first process, the second to the second, and so on; in-process, at
        ``wait``)."""
        figures = list(figures)
        if not self._children:
            self._figures = figures
            return
        count = len(self._children)
        for i, child in enumerate(self._children):
            data = pickle.dumps(figures[i::count], protocol=pickle.HIGHEST_PROTOCOL)
            # On a thread: the child may still be importing matplotlib, and a pipe holds
            # 64 KiB; the command writes its tables meanwhile.
            sending = threading.Thread(target=_send, args=(child.jobs, data))
            sending.start()
            self._sending.append(sending)

    def wait(self) -> None:
        """Return once every figure is written.

        Raises:
            RuntimeError: a drawing process failed (its traceback in the message).
        """
        if not self._children:
            self._plotting()
            _draw(self._figures)
            return
        for sending in self._sending:
            sending.join()
        failures = []
        for child in self._children:
            with os.fdopen(child.status, "rb") as status:
                failure = status.read().decode()
            _, code = os.waitpid(child.pid, 0)
            if failure or code:
                failures.append(f"(status {code}):\n{failure}")
        if failures:
            raise RuntimeError(f"the figures' drawing process failed {failures[0]}")


def _send(jobs: int, data: bytes) -> None:
    with os.fdopen(jobs, "wb") as stream:
        stream.write(data)


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

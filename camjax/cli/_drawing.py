"""A command's figures, drawn beside its computation.

Matplotlib's import (about half a second) and the drawing of a command's PNG figures
(about as much again) used to follow the numbers they show.  The ``camjax`` executable
now forks a drawing process before it computes: the child imports matplotlib while the
parent sweeps, then draws what the parent sends it while the parent writes its tables,
sharing the figures with forks of itself (``PROCESSES`` in all), which start with
matplotlib and the figures already in memory.  The parent waits for it before it
reports the files written, so a figure that fails is an error of the command, as it was
in one process; a command that exits without waiting ends its drawing process.

A fork is safe only before JAX starts its backends (XLA's threads do not survive one),
and only on Linux (Windows has no fork; macOS's system libraries are not safe to use in
a forked child): the executable forks there; anywhere else, and in a caller's own
process (``camjax.cli.main``), the figures are drawn in-process, matplotlib imported on a
thread while XLA compiles.
"""

from __future__ import annotations

import atexit
import functools
import os
import pickle
import signal
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


PROCESSES = 2
"""Processes that draw a command's figures at once, each taking every ``PROCESSES``-th
figure (three PNG figures of ``camjax ct`` take 0.5 s of Agg in one process)."""


class _Forked(NamedTuple):
    """A forked process and the pipe it reports through: a failure's traceback, or nothing."""

    pid: int
    status: int

    @classmethod
    def run(cls, work, child_closes: tuple[int, ...] = (), parent_closes: tuple[int, ...] = ()) -> _Forked:
        """Fork a process that calls ``work()``, reports, and ends without the parent's exit
        handlers or buffers.  Each side closes its copies of the other's pipe ends."""
        receive, status = os.pipe()
        pid = os.fork()
        if pid == 0:
            for descriptor in (receive, *child_closes):
                os.close(descriptor)
            failure = b""
            try:
                work()
            except EOFError:  # the parent ended without sending figures: nothing to draw
                pass
            except BaseException:  # noqa: BLE001  (every failure goes back to the parent)
                failure = traceback.format_exc().encode()
            try:
                os.write(status, failure)
            finally:
                os._exit(1 if failure else 0)
        for descriptor in (status, *parent_closes):
            os.close(descriptor)
        return cls(pid, receive)

    def result(self) -> str:
        """Wait for the process; its failure (traceback and exit status), or ``""``."""
        with os.fdopen(self.status, "rb") as status:
            failure = status.read().decode()
        _, code = os.waitpid(self.pid, 0)
        return f"(status {code}):\n{failure}" if failure or code else ""


def _serve(jobs: int, processes: int) -> None:
    """The drawing process: import matplotlib while the parent works, read the figures,
    and draw them, every ``processes``-th in each of ``processes - 1`` forks of itself."""
    from .. import plot  # noqa: F401  (imported while the parent computes)

    with os.fdopen(jobs, "rb") as stream:
        figures = pickle.load(stream)  # EOFError if the parent ends without drawing
    helpers = [_Forked.run(functools.partial(_draw, figures[i::processes]))
               for i in range(1, processes) if figures[i::processes]]
    try:
        _draw(figures[::processes])
    finally:
        failures = [failure for failure in (helper.result() for helper in helpers) if failure]
    if failures:
        raise RuntimeError("a drawing helper failed " + failures[0])


class Drawing:
    """Where a command's figures are drawn: ``Drawing(aside=True)`` forks the drawing process
    (see the module) if ``can_fork()``, else they are drawn in-process.  Start it before
    the work (the child imports matplotlib meanwhile), then ``draw`` once and ``wait``."""

    def __init__(self, aside: bool, processes: int = PROCESSES):
        self._child: _Forked | None = None
        self._figures: list[Figure] = []
        if aside and can_fork():
            jobs, self._jobs = os.pipe()
            self._child = _Forked.run(functools.partial(_serve, jobs, processes),
                                      child_closes=(self._jobs,), parent_closes=(jobs,))
            # A command that fails before it waits (a bad option found late, an interrupt)
            # ends its drawing process with it rather than leave it to the pipe's close.
            atexit.register(self._abandon)
        else:
            self._plotting = import_aside("camjax.plot")

    @property
    def forked(self) -> bool:
        """Whether the figures are drawn in a forked process."""
        return self._child is not None

    def draw(self, figures: list[Figure]) -> None:
        """Start drawing ``figures`` (the forked process draws them now; in-process, at
        ``wait``)."""
        figures = list(figures)
        if self._child is None:
            self._figures = figures
            return
        data = pickle.dumps(figures, protocol=pickle.HIGHEST_PROTOCOL)
        # On a thread: the child may still be importing matplotlib, and a pipe holds
        # 64 KiB; the command writes its tables meanwhile.
        self._sending = threading.Thread(target=_send, args=(self._jobs, data))
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
        atexit.unregister(self._abandon)
        failure = self._child.result()
        if failure:
            raise RuntimeError(f"the figures' drawing process failed {failure}")

    def _abandon(self) -> None:
        """End and reap the drawing process of a command that never waited for it."""
        try:
            os.kill(self._child.pid, signal.SIGTERM)
            os.waitpid(self._child.pid, 0)
        except OSError:  # ended already
            pass


def drawing_for(args) -> Drawing:
    """The command's ``Drawing``: forked where the executable asked for it
    (``args.figures_aside``, set by ``camjax.cli.main(one_run=True)``), in-process where a
    caller's own parser built ``args``."""
    return Drawing(aside=vars(args).get("figures_aside", False))


def _send(jobs: int, data: bytes) -> None:
    with os.fdopen(jobs, "wb") as stream:
        stream.write(data)

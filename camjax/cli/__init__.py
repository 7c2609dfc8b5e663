"""The ``camjax`` command.  Each subcommand lives in its own module with ``register``."""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import os
import sys

from .._cache_dir import using_cache_dir
from ._cache import cache_dir as cache_dir
from ._cache import enable_compilation_cache
from ._common import CliError as CliError
from ._common import HelpFormatter
from ._common import dump_json as dump_json
from ._common import laws_of as laws_of
from ._common import split_law_specs as split_law_specs
from ._common import sweep_options_for as sweep_options_for
from ._drawing import Drawing as Drawing
from ._drawing import Figure as Figure
from ._drawing import can_fork as can_fork


class _Parser(argparse.ArgumentParser):
    """An argument parser whose help shows every option's default (see HelpFormatter)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

# Modules under camjax.cli that define ``register(subparsers)``; each sets ``func``.
COMMANDS = ("laws", "ct", "design", "backlash", "follower", "bench", "program", "sweep", "studio")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="camjax",
        description="Cam-mechanism dynamics: motion laws, responses, Ct curves, design.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=_Parser)
    # The sweeps' static options a command passes to the library (compile_for_one_run).
    parser.set_defaults(sweep_options={})
    for name in COMMANDS:
        importlib.import_module(f"camjax.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None, *, one_run: bool = False) -> int:
    """Run one ``camjax`` command; ``one_run``: this process runs nothing else (the
    executable), so XLA may be set up for it (:func:`compile_for_one_run`)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    directory = enable_compilation_cache()
    try:
        with using_cache_dir(directory):  # the library's traces follow, the environment untouched
            if one_run:
                compile_for_one_run(args)
                args.figures_aside = True  # a drawing process beside the work (cli._drawing)
            return args.func(args) or 0
    except (CliError, ValueError) as error:
        print(f"camjax {args.command}: error: {error}", file=sys.stderr)
        return 2
    except RuntimeError as error:
        from ..errors import SolverError  # not at the top: --help stays free of JAX

        if not isinstance(error, SolverError):
            raise
        # A solve the command needed failed (a sweep's failed ratios are named by the
        # commands that can leave them out, as ``ct`` does): no result, one line.
        print(f"camjax {args.command}: error: {error}", file=sys.stderr)
        return 1


def command() -> None:
    """The ``camjax`` executable: :func:`main` in a process tuned for one short command.

    Two costs of a short-lived Python process that imports JAX are not the command's work;
    this entry point removes them (:func:`main`, which tests and scripts call inside their
    own process, leaves the process alone):

    - Python's cyclic garbage collector, at its default threshold of 700 allocations,
      rescanned the millions of objects that the imports and traces keep to the end: about
      0.3 s of ``camjax ct``.  Young objects are collected every 10,000 allocations instead.
    - Interpreter shutdown (clearing every module, a last collection, XLA's destructors)
      took 0.4-0.5 s after the output was written.  Every exit handler that the command's
      imports registered still runs (JAX's clean-up and distributed shutdown, matplotlib's),
      since Python runs them last-registered first and this one is registered before them;
      it then ends the process.  Every file a command writes is closed before it returns.
    """
    gc.set_threshold(10_000, 10, 10)
    status = {"code": 1}  # an exception that escapes main exits with 1, as Python's would
    atexit.register(_end_process, status)
    try:
        status["code"] = main(one_run=True)
    except SystemExit as stop:  # argparse's --help and usage errors
        code = stop.code
        status["code"] = code if isinstance(code, int) else (0 if code is None else 1)
        raise
    except KeyboardInterrupt:
        status["code"], status["interrupted"] = 130, True
        raise
    sys.exit(status["code"])


SHORT_COMMANDS = ("laws", "ct", "design", "backlash", "follower", "program")
"""Commands whose cold run is mostly XLA's compilation (``camjax sweep`` and ``bench`` are
not: a long sweep's run time, and a benchmark's figures, are the library's own)."""
LONG_CT_SWEEP = 100_000
"""Period ratios from which ``camjax ct`` is a long sweep and keeps XLA's default emitters."""


def one_run_sweep_options() -> dict:
    """The sweeps' options of a short command: the dense peak search
    (``SpringMassOptions.peak_search``) compiles a smaller program than the bounded one,
    which pays only when a program runs many times (docs/performance.md); so do the wider
    vectors of ``camjax.sharding.CPU_COMPILER_OPTIONS`` (``SweepOptions.run_once`` drops
    them)."""
    from ..sharding import SweepOptions

    return {"peak_search": "dense", "sweep": SweepOptions.run_once()}


def compile_for_one_run(args: argparse.Namespace) -> None:
    """XLA's classic CPU fusion emitters, and the sweeps' options of a short command
    (``one_run_sweep_options``, into ``args.sweep_options``, which the commands pass to
    the library), for ``args`` (parsed).

    The emitters compile camjax's programs in about half the time and run them about 1.2x
    slower (the exact kernel, 2026-11-25): a cold ``camjax ct`` took 0.86x, ``camjax
    program`` 0.69x and ``camjax design`` 0.77x the time with them.  A flag the user set in
    ``XLA_FLAGS`` wins; it must be set before JAX starts its CPU backend, as here.
    """
    if args.command not in SHORT_COMMANDS:
        return
    if args.command == "ct":
        from ._common import parse_range

        if parse_range(args.n, "--n").size >= LONG_CT_SWEEP:
            return
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_cpu_use_fusion_emitters" not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} --xla_cpu_use_fusion_emitters=false".strip()
    if args.command == "follower":
        store_checked_solves()  # before one_run_sweep_options imports equinox
    args.sweep_options = one_run_sweep_options()


def store_checked_solves() -> None:
    """Let JAX's persistent cache keep ``camjax follower``'s solve: equinox's runtime
    checks as a select, not a host callback (``EQX_ON_ERROR=nan``), unless the user set
    that variable, and only before equinox is imported (it reads it then).

    JAX never stores a program with a host callback, and diffrax checks inside its own
    ``jit`` that the save times rise and lie in the span, with a callback each: the
    follower's save times are camjax's own grid, so the checks cannot fail, yet every
    process compiled the solve again (2.8 s).  Were a check to fail, its value would be
    NaN, which the follower reports as a failed solve (``SolverError``), never as a number.
    """
    if "equinox" not in sys.modules:
        os.environ.setdefault("EQX_ON_ERROR", "nan")


def _end_process(status: dict) -> None:
    """Flush the output and end the process without Python's interpreter shutdown."""
    code = status["code"]
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (camjax ... | head): output was lost
            code = code or 1
    if status.get("interrupted"):  # end by SIGINT, as Python does, so a shell loop stops too
        import signal

        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    os._exit(code)

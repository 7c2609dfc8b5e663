"""The ``camjax`` command.  Each subcommand lives in its own module with ``register``."""

from __future__ import annotations

import argparse
import importlib
import sys

from ._cache import enable_compilation_cache
from ._common import CliError, HelpFormatter


class _Parser(argparse.ArgumentParser):
    """An argument parser whose help shows every option's default (see HelpFormatter)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

# Modules under camjax.cli that define ``register(subparsers)``; each sets ``func``.
_COMMANDS = ("laws", "ct", "design", "backlash", "follower", "bench", "program", "sweep")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="camjax",
        description="Cam-mechanism dynamics: motion laws, responses, Ct curves, design.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=_Parser)
    for name in _COMMANDS:
        importlib.import_module(f"camjax.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    enable_compilation_cache()
    try:
        return args.func(args) or 0
    except (CliError, ValueError) as error:
        print(f"camjax {args.command}: error: {error}", file=sys.stderr)
        return 2

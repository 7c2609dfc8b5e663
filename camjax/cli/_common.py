"""Helpers shared by the subcommands: argument parsing and output.

Nothing here imports JAX (nor NumPy at import time), so that ``--help`` stays instant.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import re
from pathlib import Path

from .._plain import json_ready
from .._plain import parse_float_list as _parse_float_list
from .._plain import parse_range as _parse_range

RANGE_METAVAR = "START:STOP:COUNT|V1,V2,..."


class CliError(Exception):
    """A bad argument: reported on one line, exit status 2."""


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the descriptions' line breaks and appends each option's default to its help.

    Options whose help already names its default, or whose default is None or False
    (flags, and values computed at run time, whose help says how), are left as written.
    """

    def _get_help_string(self, action):
        text = action.help or ""
        if (
            "default" in text
            or action.default is None
            or action.default is False
            or action.default == argparse.SUPPRESS
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"


LAW_HELP = ("a name of `camjax laws` or a family there (scca:A,B,C, modified-sine-asym:L, ...), "
            "an alias such as modsine, or a law file written by `camjax design` (law.json)")


def add_law_option(parser: argparse.ArgumentParser, default=None, what: str = "motion law") -> None:
    """The repeatable ``--law NAME`` of every command (``--law a,b`` also works)."""
    if default is None:
        shown = "all standard laws"
    else:
        shown = ", ".join(default)
    parser.add_argument(
        "--law", action="append", metavar="NAME",
        help=f"{what}: {LAW_HELP} (repeatable, or comma-separated; default: {shown})",
    )


def split_law_specs(text: str) -> list[str]:
    """``--law`` text as law specs: split at commas, except those between the numbers of a
    ``scca:A,B,C`` (a number joins the spec before it), so ``scca:0.25,0,0.75,cycloidal``
    is two laws."""
    specs: list[str] = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        if specs and ":" in specs[-1] and _is_number(part):
            specs[-1] += "," + part
        else:
            specs.append(part)
    return specs


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def law_names_of(args, default=None) -> list[str]:
    """The ``--law`` specs (``split_law_specs``); ``default`` (None: every standard law) if none."""
    given = [spec for item in (args.law or []) for spec in split_law_specs(item)]
    if given:
        return given
    if args.law:
        raise CliError("--law: no law name given")
    if default is None:
        from ..laws import standard_laws

        return [law.name for law in standard_laws()]
    return list(default)


def law_of(spec: str, option: str = "--law", tool: str | None = None):
    """The law that ``spec`` names: a law file (``*.json``, or an existing file) or a name,
    as a ``CliError`` naming ``option`` if neither; with ``tool`` (``"camjax ct"``) also if
    it is no rise from rest to rest (``camjax.laws.rest_to_rest``)."""
    from ..laws import get, load, rest_to_rest

    try:
        if spec.lower().endswith(".json") or Path(spec).is_file():
            law = load(spec)
        else:
            law = get(spec)
        return law if tool is None else rest_to_rest(law, tool)
    except (ValueError, TypeError) as error:
        raise CliError(f"{option}: {error}") from None


def laws_of(args, default=None, tool: str | None = None) -> dict:
    """The ``--law`` laws by name, in the order given: a name given twice (or an alias of
    it) counts once; a law file whose law's name is taken goes by the file's stem.  With
    ``tool``, each must rise from rest to rest (``law_of``)."""
    selected = {}
    for spec in law_names_of(args, default):
        law = law_of(spec, tool=tool)
        from_file = spec.lower().endswith(".json") or Path(spec).is_file()
        name = Path(spec).stem if from_file and law.name in selected else law.name
        selected[name] = law
    return selected


def check_damping(value: float, option: str = "--damping") -> float:
    """``value`` if a damping ratio in ``[0, 1)``, else a ``CliError`` naming ``option``."""
    if not 0.0 <= value < 1.0:  # NaN fails too
        raise CliError(f"{option}: damping ratio must be in [0, 1) (an underdamped payload), "
                       f"got {value:g}")
    return value


@contextlib.contextmanager
def options_named(option: str | None = None, /, **names: str):
    """Report a ``ValueError`` of the API called inside as a ``CliError`` that says the
    user's options (``options_named(total_swing="--rise")``) instead of the API's argument
    names, without the class name the API prefixes (``Caps: ...``), after ``option: `` if
    given (the option whose value the API refused)."""
    try:
        yield
    except ValueError as error:
        text = re.sub(r"^[A-Z][A-Za-z*]+: ", "", str(error))
        for name, replacement in names.items():
            text = re.sub(rf"\b{name}\b", replacement, text)
        raise CliError(text if option is None else f"{option}: {text}") from None


@contextlib.contextmanager
def file_named(path):
    """A ``ValueError`` raised inside (a check after loading: a cusp under a flat face, a
    grid too fine, no damping) prefixed with the file ``path``, as the load-time checks
    prefix theirs; one that names it already passes unchanged."""
    try:
        yield
    except ValueError as error:
        text = str(error)
        if text.startswith(f"{path}: "):
            raise
        raise ValueError(f"{path}: {text}") from None


def parse_float_list(text: str, what: str) -> list[float]:
    """``"1,2.5,4"`` as floats, or a ``CliError`` naming ``what``."""
    with options_named():
        return _parse_float_list(text, what)


def parse_range(text: str, what: str):
    """``camjax._plain.parse_range`` (``START:STOP:COUNT`` or ``V1,V2,...``) with its
    ``ValueError`` as a ``CliError``; ``--n`` counts are checked as period ratios, ``--rpm``
    counts as speeds (``camjax.checks.speed_count``), before the range is built."""
    check_count = None
    if what == "--n":
        from ..checks import period_ratio_count as check_count
    elif what == "--rpm":
        from ..checks import speed_count as check_count
    with options_named():
        values = _parse_range(text, what, check_count)
        if check_count is not None:
            check_count(values.size, what)  # a list V1,V2,... as long
        return values


def sweep_options_for(args: argparse.Namespace, model=None) -> dict:
    """The command's sweep options (``compile_for_one_run`` puts them in
    ``args.sweep_options``; none where a command's own parser built ``args``), those that
    ``model``'s options take where a model is given (the peak search is the exact path's
    alone)."""
    chosen = dict(vars(args).get("sweep_options", {}))
    if model is None:
        return chosen
    fields = {field.name for field in dataclasses.fields(model.options_type)}
    return {name: value for name, value in chosen.items() if name in fields}


def add_format(parser: argparse.ArgumentParser, choices=("table", "json", "csv")) -> None:
    parser.add_argument("--format", choices=choices, default=choices[0],
                        help="output format on standard output")


def dump_json(value, path: Path | None = None) -> str:
    text = json.dumps(json_ready(value), indent=1)
    if path is not None:
        path.write_text(text + "\n")
    return text


def output_dir(text: str | None, what: str = "--out") -> Path | None:
    """The output directory ``text``, created and checked writable before any work, or a
    one-line ``CliError`` naming ``what`` (the option, or the spec key) and the path."""
    if text is None:
        return None
    import tempfile

    path = Path(text)
    if path.exists() and not path.is_dir():
        raise CliError(f"{what}: {text!r} exists and is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as error:
        reason = error.strerror or str(error)
        raise CliError(f"{what}: cannot write to directory {text!r} ({reason})") from None
    return path


def import_aside(module: str):
    """Start importing ``module`` on a thread; return a function that waits and returns it.

    XLA releases the GIL while it compiles, so a slow import (matplotlib: half a second)
    runs during a command's first compile instead of before or after it.  An import that
    fails raises, as usual, when the returned function is called.
    """
    import importlib
    import threading

    thread = threading.Thread(target=importlib.import_module, args=(module,))
    thread.start()

    def finish():
        thread.join()
        return importlib.import_module(module)

    return finish


PROBES_HELP = ("report these probes beside the built-in per-speed outputs: NAME in the Python file FILE.py "
               "(run as a script), a camjax.program.Outputs, a probe or a list of probes (docs/extending.md)")


def add_probes_option(parser: argparse.ArgumentParser) -> None:
    """The ``--probes FILE.py:NAME`` of the commands that analyse a program."""
    parser.add_argument("--probes", metavar="FILE.py:NAME", help=PROBES_HELP)


def outputs_of(text: str | None):
    """The per-speed outputs ``--probes FILE.py:NAME`` names (``camjax.program.Outputs``:
    the built-in ones and NAME's probes), or the built-in ones alone without it."""
    from ..program import BUILT_IN_OUTPUTS, Outputs, Probe

    if text is None:
        return BUILT_IN_OUTPUTS
    file, _, name = text.rpartition(":")
    if not file or not name.isidentifier():
        raise CliError(f"--probes: expected FILE.py:NAME (a Python file and a name it defines), got {text!r}")
    path = Path(file)
    if not path.is_file():
        raise CliError(f"--probes: no file {file}")
    import runpy

    try:
        namespace = runpy.run_path(str(path), run_name=f"camjax_probes_{path.stem}")
    except Exception as error:  # the user's script: its failure on one line, named
        raise CliError(f"--probes: running {file} failed: {type(error).__name__}: {error}") from None
    if name not in namespace:
        raise CliError(f"--probes: {file} defines no {name!r}")
    given = namespace[name]
    try:
        return Outputs.of([given] if isinstance(given, Probe) else given)
    except ValueError as error:
        raise CliError(f"--probes: {name} in {file}: {error}") from None

"""Helpers shared by the subcommands: argument parsing and output."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np


class CliError(Exception):
    """A bad argument: reported on one line, exit status 2."""


def parse_float_list(text: str, what: str) -> list[float]:
    """``"1,2.5,4"`` as floats, or a ``CliError`` naming ``what``."""
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise CliError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if not values:
        raise CliError(f"{what}: no values given")
    if not all(math.isfinite(v) for v in values):
        raise CliError(f"{what}: values must be finite, got {text!r}")
    return values


def parse_range(text: str, what: str) -> np.ndarray:
    """``START:STOP:COUNT`` (inclusive linspace) or ``V1,V2,...`` as an array."""
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise CliError(f"{what}: expected START:STOP:COUNT, got {text!r}")
        start, stop = parse_float_list(parts[0], what)[0], parse_float_list(parts[1], what)[0]
        try:
            count = int(parts[2])
        except ValueError:
            raise CliError(f"{what}: COUNT must be an integer, got {parts[2]!r}") from None
        if count < 1:
            raise CliError(f"{what}: COUNT must be at least 1, got {count}")
        return np.linspace(start, stop, count)
    return np.asarray(parse_float_list(text, what))


def add_format(parser: argparse.ArgumentParser, choices=("table", "json", "csv")) -> None:
    parser.add_argument("--format", choices=choices, default=choices[0], help="output format")


def json_ready(value):
    """Nested lists of floats for JSON, with inf and NaN as null."""
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [json_ready(v) for v in value]
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def dump_json(value, path: Path | None = None) -> str:
    text = json.dumps(json_ready(value), indent=1)
    if path is not None:
        path.write_text(text + "\n")
    return text


def output_dir(text: str | None) -> Path | None:
    if text is None:
        return None
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise CliError(f"--out: {text!r} exists and is not a directory")
    path.mkdir(parents=True, exist_ok=True)
    return path

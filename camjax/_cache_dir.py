"""The one setting of camjax's caches on disk, shared by the library and the command.

The environment variable ``CAMJAX_CACHE_DIR`` names a directory, or turns the caches off
(``0``, ``off``, ``false``, ``no`` or empty).  The library keeps traced programs under
``DIR/traces`` only when it names a directory (``camjax._traces``); the command also
keeps JAX's compiled programs in ``DIR``, and where the variable is unset it uses the
user's cache directory and sets the variable for the rest of its process, so the command
and the library it calls take the same path.  No JAX import here: ``--help`` stays free of it.
"""

from __future__ import annotations

import os
from pathlib import Path

ENV = "CAMJAX_CACHE_DIR"
_OFF = {"", "0", "off", "false", "no"}


def configured_dir(default: Path | None = None) -> Path | None:
    """The directory ``CAMJAX_CACHE_DIR`` names, None where it turns the caches off, and
    ``default`` where it is unset."""
    value = os.environ.get(ENV)
    if value is None:
        return default
    if value.strip().lower() in _OFF:
        return None
    return Path(value).expanduser()

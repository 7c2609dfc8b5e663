"""The one setting of camjax's caches on disk, shared by the library and the command.

The setting is a directory, or off (``None``).  A block of code is given it explicitly by
``using_cache_dir(directory)`` (the command runs inside one, with its own cache
directory); outside such a block it is the environment variable ``CAMJAX_CACHE_DIR``: a
directory, or off (``0``, ``off``, ``false``, ``no`` or empty), or unset (off for the
library).  The library keeps traced programs under ``DIR/traces`` only when the setting
names a directory (``camjax._traces``); the command also keeps JAX's compiled programs in
``DIR``.  Nothing here writes the environment: a command run in-process (a test, a
notebook) leaves its caller's setting as it was.

The block's setting is a context variable, so it holds in the thread that entered the
block; work handed to another thread carries it with ``carried``.  No JAX import here:
``--help`` stays free of it.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import os
from collections.abc import Callable, Iterator
from pathlib import Path

ENV = "CAMJAX_CACHE_DIR"
_OFF = {"", "0", "off", "false", "no"}
_FROM_ENVIRONMENT = object()
_GIVEN: contextvars.ContextVar = contextvars.ContextVar("camjax_cache_dir", default=_FROM_ENVIRONMENT)


def configured_dir(default: Path | None = None) -> Path | None:
    """The directory of the setting in effect: the one ``using_cache_dir`` gives (None: off);
    outside such a block the one ``CAMJAX_CACHE_DIR`` names, None where it turns the caches
    off, and ``default`` where it is unset."""
    given = _GIVEN.get()
    if given is not _FROM_ENVIRONMENT:
        return given
    value = os.environ.get(ENV)
    if value is None:
        return default
    if value.strip().lower() in _OFF:
        return None
    return Path(value).expanduser()


@contextlib.contextmanager
def using_cache_dir(directory: Path | None) -> Iterator[Path | None]:
    """Inside the block, the caches' directory is ``directory`` (None: off), whatever
    ``CAMJAX_CACHE_DIR`` says; the environment is not touched."""
    token = _GIVEN.set(None if directory is None else Path(directory))
    try:
        yield directory
    finally:
        _GIVEN.reset(token)


def carried(fn: Callable) -> Callable:
    """``fn`` bound to the caller's context (its cache setting among it), to run on another
    thread: a thread starts without its creator's context."""
    return functools.partial(contextvars.copy_context().run, fn)

"""JAX's persistent compilation cache for the ``camjax`` command.

Every command compiles the same few programs on every run; with the cache on, a second
run loads them from disk instead (seconds saved per command).  It is on by default, in
the user's cache directory (``platformdirs.user_cache_dir("camjax")/jax``).  The
environment variable ``CAMJAX_CACHE_DIR`` moves it (a directory) or turns it off
(``0``, ``off``, ``false``, ``no`` or empty).  A cache that JAX_COMPILATION_CACHE_DIR (or
the caller's ``jax.config``) already set is left alone.  The traced programs kept beside
it follow the same setting: the command runs inside ``using_cache_dir`` of the directory
``enable_compilation_cache`` returns (``camjax._cache_dir``), without writing the
environment.
"""

from __future__ import annotations

import os
from pathlib import Path

from .._cache_dir import ENV, configured_dir


def cache_dir() -> Path | None:
    """Where the command caches compiled programs, or None when ``CAMJAX_CACHE_DIR`` turns it off."""
    if os.environ.get(ENV) is not None:
        return configured_dir()
    import platformdirs

    return Path(platformdirs.user_cache_dir("camjax")) / "jax"


def enable_compilation_cache() -> Path | None:
    """Point JAX's persistent cache at :func:`cache_dir` and cache every program.

    JAX by default only keeps programs that took over a second to compile; camjax's
    commands compile several smaller ones, so the thresholds are set to zero.  Returns
    the directory of the command's caches, the setting its run is given
    (``camjax._cache_dir.using_cache_dir``): None when off.
    """
    import jax

    if jax.config.jax_compilation_cache_dir:
        if os.environ.get(ENV) is not None:  # the setting's own directory, or off
            return cache_dir()
        return Path(jax.config.jax_compilation_cache_dir)
    path = cache_dir()
    if path is None:
        return None
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None  # an unwritable cache only costs time: run without it
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path

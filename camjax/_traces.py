"""Traced programs kept on disk beside JAX's compilation cache (``jax.export``).

JAX's persistent cache saves a new process the XLA compile of a program it has seen, but
not the tracing and lowering that come first: for the cam program's steady state that is
most of a cached command's wait.  ``exported_jit(fn, name)`` is ``jax.jit(fn)`` that, when
the trace cache is on, keeps each shape's traced program (``jax.export``, serialised
StableHLO) under ``DIR/traces/<version>/`` and reads it back in the next process instead
of tracing again (the compile itself then comes from JAX's cache).

The one switch is the setting ``CAMJAX_CACHE_DIR`` (``camjax._cache_dir``): the library
keeps traces when it names a directory ``DIR``, and the command sets it to its own cache
directory, so both take the same path.  Without it ``exported_jit`` is plain
``equinox.filter_jit``.

A kept program is found by a key of everything that changes it: the function's name, the
arguments' structure, shapes and dtypes, their constants, the platform and the x64 flag,
in a folder named by a hash of the versions of JAX, jaxlib and equinox and of camjax's
own source files (an edit of the code or an upgrade is a new folder).  The newest
``KEPT_VERSIONS`` folders (by last use) are kept and older ones deleted when a new one is
made.  Anything unreadable is traced afresh and written again; a program ``jax.export``
cannot keep is marked and traced in each process: silently where JAX says why (a host
callback, which ``jax.export`` does not serialise: a known limit, nothing to act on), else
reported once (a ``RuntimeWarning`` naming the program and the error).  Each ``exported_jit`` remembers at most ``memo_size``
(``MEMO_SIZE``) loaded programs in its process (the least recently used go first).
"""

from __future__ import annotations

import collections
import functools
import hashlib
import importlib.metadata
import os
import shutil
import tempfile
import warnings
from pathlib import Path

import equinox as eqx
import jax
from jax import export

from ._cache_dir import configured_dir

_PACKAGE = Path(__file__).resolve().parent

KEPT_VERSIONS = 3
"""Version folders kept under ``traces/`` (the most recently used); older ones are deleted."""

MEMO_SIZE = 32
"""Loaded programs each ``exported_jit`` keeps in its process (shapes and constants)."""


@functools.cache
def version_key() -> str:
    """A hash of what shapes a trace besides its arguments: the versions of JAX, jaxlib and
    equinox, and camjax's Python source (the files' bytes, in path order)."""
    digest = hashlib.sha256()
    for package in ("jax", "jaxlib", "equinox"):
        try:
            version = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            version = "absent"
        digest.update(f"{package}={version};".encode())
    for path in sorted(_PACKAGE.rglob("*.py")):
        digest.update(str(path.relative_to(_PACKAGE)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _root() -> Path | None:
    """``DIR/traces`` of the setting, or None (off)."""
    directory = configured_dir()
    return directory / "traces" if directory is not None else None


def _directory() -> Path | None:
    """``DIR/traces/<version_key>``, or None without the setting."""
    root = _root()
    return root / version_key() if root is not None else None


def kept() -> bool:
    """Whether traced programs are kept on disk in this process (``CAMJAX_CACHE_DIR``)."""
    return _root() is not None


def prune(root: Path, keep: int = KEPT_VERSIONS) -> list[Path]:
    """Delete all but the ``keep`` most recently used version folders under ``root``;
    returns the deleted ones."""
    try:
        folders = sorted((p for p in root.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime,
                         reverse=True)
    except OSError:
        return []
    for old in folders[keep:]:
        shutil.rmtree(old, ignore_errors=True)
    return folders[keep:]


def register_types(*types) -> None:
    """Let ``jax.export`` write outputs holding these ``NamedTuple`` types (by their
    qualified name)."""
    for cls in types:
        try:
            export.register_namedtuple_serialization(cls, serialized_name=f"{cls.__module__}.{cls.__qualname__}")
        except ValueError:  # registered already (a module reloaded)
            pass


_PLAIN = (bool, int, float, complex, str, type(None))
_UNKEPT = object()  # the marker of arguments whose program is not kept


class exported_jit:
    """``jax.jit(fn)`` whose traced programs persist across processes (see the module).

    The arguments' arrays are the program's inputs; their other leaves (Python numbers
    and strings, as ``equinox.filter_jit`` takes them) are compiled in and part of the
    key.  Arguments holding anything else (a function, an object) run through
    ``equinox.filter_jit`` as they are, untouched by the cache.
    """

    def __init__(self, fn, name: str, memo_size: int = MEMO_SIZE):
        self.fn, self.name, self.memo_size = fn, name, memo_size
        self.jitted = eqx.filter_jit(fn)
        self.loaded: collections.OrderedDict[tuple, object] = collections.OrderedDict()  # memo_size at most
        functools.update_wrapper(self, fn)

    def __call__(self, *args):
        directory = _directory()
        if directory is None:
            return self.jitted(*args)
        dynamic, static = eqx.partition(args, eqx.is_array)
        leaves, tree = jax.tree.flatten(dynamic)
        constants = jax.tree.leaves(static)
        shapes = tuple((x.dtype, x.shape) for x in leaves)
        memo = (tree, shapes, repr(constants))  # repr: 1, 1.0, True and -0.0, 0.0 differ
        try:
            program = self.loaded.get(memo)
        except TypeError:  # a structure holding something unhashable
            return self.jitted(*args)
        if program is not None:
            self.loaded.move_to_end(memo)
        else:
            described = str(tree)
            if not all(isinstance(x, _PLAIN) for x in constants) or " at 0x" in described:
                program = _UNKEPT  # no key that a new process would find again
            else:
                text = "|".join([self.name, described, repr(constants), repr(shapes), jax.default_backend(),
                                 str(jax.config.jax_enable_x64)])
                key = hashlib.sha256(text.encode()).hexdigest()[:32]
                program = self._program(directory / f"{self.name}-{key}.bin", tree, static, leaves)
            self.loaded[memo] = program
            if len(self.loaded) > self.memo_size:
                self.loaded.popitem(last=False)
        return self.jitted(*args) if program is _UNKEPT else program(leaves)

    def _program(self, path: Path, tree, static, leaves):
        def flat(arrays):
            return self.fn(*eqx.combine(jax.tree.unflatten(tree, arrays), static))

        plain = path.with_suffix(".plain")  # a program export cannot keep (a host callback)
        if plain.exists():
            return jax.jit(flat)
        try:
            exported = export.deserialize(bytearray(path.read_bytes()))
            _touch(path.parent)
        except Exception:  # absent, truncated or from another JAX: trace afresh
            try:
                exported = export.export(jax.jit(flat))(leaves)
                data = exported.serialize()
            except Exception as error:  # not exportable or its output not writable
                if not _host_callback(error):
                    warnings.warn(f"camjax: the traced program {self.name!r} cannot be kept on disk "
                                  f"({type(error).__name__}: {error}); it is traced in each process",
                                  RuntimeWarning, stacklevel=3)
                _write(plain, b"")
                return jax.jit(flat)
            new_version = not path.parent.exists()
            _write(path, data)
            if new_version:  # the first program of this version: older versions beyond the newest go
                prune(path.parent.parent)
        return jax.jit(exported.call)


def _host_callback(error: Exception) -> bool:
    """Whether ``jax.export`` refused a program for its host callback (a known limit)."""
    return isinstance(error, NotImplementedError) and "host_callback" in str(error)


def _touch(folder: Path) -> None:
    """Mark a version folder as used now (``prune`` keeps the most recently used)."""
    try:
        os.utime(folder)
    except OSError:
        pass


def _write(path: Path, data: bytes) -> None:
    """Whole or not at all (a concurrent reader never sees half a file)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, delete=False) as handle:
            handle.write(data)
        os.replace(handle.name, path)
    except OSError:
        pass  # an unwritable cache only costs time

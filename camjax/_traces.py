"""Traced programs kept on disk beside JAX's compilation cache (``jax.export``).

JAX's persistent cache saves a new process the XLA compile of a program it has seen, but
not the tracing and lowering that come first: for the cam program's steady state that is
most of a cached command's wait.  ``exported_jit(fn, name)`` is ``jax.jit(fn)`` that, when
the compilation cache is on, keeps each shape's traced program (``jax.export``,
serialised StableHLO) under ``<compilation cache>/traces/<source hash>/`` and reads it back
in the next process instead of tracing again (the compile itself then comes from JAX's
cache).

A kept program is found by a key of everything that changes it: the function's name, the
arguments' structure, shapes and dtypes, their constants, the platform, JAX's version and
the x64 flag, in a folder named by a hash of camjax's own source files (an edit of the
code is a new folder).  Anything unreadable is traced afresh and written again; a program
``jax.export`` cannot keep (one with a host callback) is marked and traced in each process.
Without the compilation cache (a library call that did not turn it on) it is plain
``jax.jit``.
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path

import equinox as eqx
import jax
from jax import export

_PACKAGE = Path(__file__).resolve().parent


@functools.cache
def _source_hash() -> str:
    """A hash of camjax's Python source (the files' bytes, in path order)."""
    digest = hashlib.sha256()
    for path in sorted(_PACKAGE.rglob("*.py")):
        digest.update(str(path.relative_to(_PACKAGE)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _directory() -> Path | None:
    """``<compilation cache>/traces/<source hash>``: one folder per version of camjax's code
    (an old one may be deleted to reclaim its space), or None without the cache."""
    root = jax.config.jax_compilation_cache_dir
    return Path(root) / "traces" / _source_hash()[:16] if root else None


def kept() -> bool:
    """Whether traced programs are kept on disk in this process (the compilation cache is on)."""
    return bool(jax.config.jax_compilation_cache_dir)


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

    def __init__(self, fn, name: str):
        self.fn, self.name = fn, name
        self.jitted = eqx.filter_jit(fn)
        self.loaded: dict[tuple, object] = {}  # by structure, shapes and constants
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
        if program is None:
            described = str(tree)
            if not all(isinstance(x, _PLAIN) for x in constants) or " at 0x" in described:
                program = _UNKEPT  # no key that a new process would find again
            else:
                text = "|".join([self.name, described, repr(constants), repr(shapes), jax.default_backend(),
                                 jax.__version__, str(jax.config.jax_enable_x64)])
                key = hashlib.sha256(text.encode()).hexdigest()[:32]
                program = self._program(directory / f"{self.name}-{key}.bin", tree, static, leaves)
            self.loaded[memo] = program
        return self.jitted(*args) if program is _UNKEPT else program(leaves)

    def _program(self, path: Path, tree, static, leaves):
        def flat(arrays):
            return self.fn(*eqx.combine(jax.tree.unflatten(tree, arrays), static))

        plain = path.with_suffix(".plain")  # a program export cannot keep (a host callback)
        if plain.exists():
            return jax.jit(flat)
        try:
            exported = export.deserialize(bytearray(path.read_bytes()))
        except Exception:  # absent, truncated or from another JAX: trace afresh
            try:
                exported = export.export(jax.jit(flat))(leaves)
                data = exported.serialize()
            except Exception:  # not exportable or its output not writable: this process traces it
                _write(plain, b"")
                return jax.jit(flat)
            _write(path, data)
        return jax.jit(exported.call)


def _write(path: Path, data: bytes) -> None:
    """Whole or not at all (a concurrent reader never sees half a file)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, delete=False) as handle:
            handle.write(data)
        os.replace(handle.name, path)
    except OSError:
        pass  # an unwritable cache only costs time

"""The caches camjax keeps, in one place.

- **Compiled programs on disk**: JAX's persistent compilation cache, which the command
  turns on in ``CAMJAX_CACHE_DIR`` (default: the user's cache directory; see
  ``camjax.cli.enable_compilation_cache``); in Python, JAX's own ``jax_compilation_cache_dir``.
- **Traced programs on disk** (``exported_jit``): ``DIR/traces/<version>/`` when the setting
  ``CAMJAX_CACHE_DIR`` names ``DIR``, in the library and the command alike; one folder per
  version of JAX, jaxlib, equinox and camjax's source, the newest ``KEPT_VERSIONS`` kept
  (``prune_traces``); each ``exported_jit`` remembers ``MEMO_SIZE`` loaded programs.
- **Compiled programs in the process**: JAX's and equinox's own jit caches, keyed by the
  shapes and static arguments of module-level compiled functions (a cam program's turn,
  a design's steps); nothing of camjax's changes a result by being cached.
"""

from ._cache_dir import ENV as SETTING
from ._cache_dir import configured_dir as configured_dir
from ._traces import KEPT_VERSIONS as KEPT_VERSIONS
from ._traces import MEMO_SIZE as MEMO_SIZE
from ._traces import exported_jit as exported_jit
from ._traces import kept as traces_kept
from ._traces import prune as prune_traces
from ._traces import version_key as version_key

__all__ = [
    "SETTING",
    "KEPT_VERSIONS",
    "MEMO_SIZE",
    "configured_dir",
    "exported_jit",
    "prune_traces",
    "traces_kept",
    "version_key",
]

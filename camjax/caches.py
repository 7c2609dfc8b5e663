"""The caches camjax keeps, in one place.  None changes a result by being cached: each is
keyed by everything its value depends on, and each in-process one is bounded.

On disk, under one setting (``camjax._cache_dir``: ``using_cache_dir`` for a block of code,
else the environment variable ``CAMJAX_CACHE_DIR``; the command runs inside
``using_cache_dir`` of its own directory and never writes the environment):

- **Compiled programs**: JAX's persistent compilation cache, which the command turns on in
  the setting's directory (default: the user's cache directory; see
  ``camjax.cli.enable_compilation_cache``); in Python, JAX's own ``jax_compilation_cache_dir``.
- **Traced programs** (``exported_jit``): ``DIR/traces/<version>/`` when the setting names
  ``DIR``, in the library and the command alike; one folder per version of JAX, jaxlib,
  equinox and camjax's source, the newest ``KEPT_VERSIONS`` kept (``prune_traces``); each
  ``exported_jit`` remembers ``MEMO_SIZE`` loaded programs.

In the process:

- **Compiled programs**: JAX's and equinox's own jit caches, keyed by the shapes and static
  arguments of module-level compiled functions (a cam program's turn, a design's steps).
  Each holds memory maps of the process; ``relieve_memory_maps`` lets them all go when the
  process holds more than ``CROWDED_FRACTION`` of the system's limit (the studio before
  each analysis; ``camjax._memory_maps`` says why).
- **Sampled laws** (``camjax.sdof.SampledLaw.of``): the last ``SAMPLED_LAWS_KEPT``, keyed by
  the law's values (``camjax.sdof.law_value_key``).
- **Compiled accelerations of the studies' scipy reference** (``camjax.studies``): the last
  ``camjax.studies.COMPILED_ACCELERATIONS_KEPT``, keyed by the law's values.
- **Small tables** behind ``functools.lru_cache`` / ``functools.cache`` of a few static
  arguments: spline knots, boundary inverses, Hermite matrices, result-code tables, the
  sweep's default template (16), the solve's and the sweep's compiled programs per compiler
  option set; a program's law ends (``camjax.program``, 256 laws at most).
"""

from ._cache_dir import ENV as SETTING
from ._cache_dir import carried as carried
from ._cache_dir import configured_dir as configured_dir
from ._cache_dir import using_cache_dir as using_cache_dir
from ._memory_maps import CROWDED_FRACTION as CROWDED_FRACTION
from ._memory_maps import memory_maps as memory_maps
from ._memory_maps import relieve as relieve_memory_maps
from ._traces import KEPT_VERSIONS as KEPT_VERSIONS
from ._traces import MEMO_SIZE as MEMO_SIZE
from ._traces import exported_jit as exported_jit
from ._traces import kept as traces_kept
from ._traces import prune as prune_traces
from ._traces import version_key as version_key
from .sdof import SAMPLED_LAWS_KEPT as SAMPLED_LAWS_KEPT

__all__ = [
    "CROWDED_FRACTION",
    "SETTING",
    "KEPT_VERSIONS",
    "MEMO_SIZE",
    "SAMPLED_LAWS_KEPT",
    "carried",
    "configured_dir",
    "exported_jit",
    "memory_maps",
    "prune_traces",
    "relieve_memory_maps",
    "traces_kept",
    "using_cache_dir",
    "version_key",
]

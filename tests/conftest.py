"""Every test runs in float64 (importing camjax turns it on).

A test worker lives through hundreds of tests and compiles thousands of programs: after
each test module, JAX's compiled programs are let go once the worker holds 40% of the
system's memory maps (``camjax.caches.relieve_memory_maps``).  Without it a worker reached
the limit late in the suite and XLA crashed it (a segmentation fault while compiling).

Python's cyclic collector runs every 10,000 allocations instead of 700, as in the
``camjax`` executable (``camjax.cli.command``): at 700 it rescanned JAX's millions of
long-lived objects, 5-8% of the suite's time (tests/test_laws.py and test_response.py:
116-122 s to 110-115 s, one process).
"""

import gc

import jax
import pytest

import camjax  # noqa: F401
from camjax.caches import relieve_memory_maps

gc.set_threshold(10_000, 10, 10)

assert jax.config.jax_enable_x64, "camjax tests need float64"


@pytest.fixture(autouse=True, scope="module")
def _memory_maps_relieved():
    yield
    relieve_memory_maps()

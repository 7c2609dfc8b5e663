"""Every test runs in float64 (importing camjax turns it on).

Python's cyclic collector runs every 10,000 allocations instead of 700, as in the
``camjax`` executable (``camjax.cli.command``): at 700 it rescanned JAX's millions of
long-lived objects, 5-8% of the suite's time (tests/test_laws.py and test_response.py:
116-122 s to 110-115 s, one process).
"""

import gc

import jax

import camjax  # noqa: F401

gc.set_threshold(10_000, 10, 10)

assert jax.config.jax_enable_x64, "camjax tests need float64"

"""Every test runs in float64 (importing camjax turns it on)."""

import jax

import camjax  # noqa: F401

assert jax.config.jax_enable_x64, "camjax tests need float64"

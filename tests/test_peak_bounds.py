"""The candidate peak search of the exact path: its bound holds, it agrees with the dense
search, and flagged members are redone."""

import jax.numpy as jnp
import numpy as np
import pytest

from camjax.laws import SCCA, Cycloidal, ModifiedTrapezoid
from camjax.sdof import (
    bounded_peak_in_motion,
    default_resolution,
    dense_peak_in_motion,
    eigenvalue,
    mode_between,
    mode_gain,
    motion_grid,
    peak_bounds,
    propagate,
    with_fallback,
)

CASES = [(Cycloidal(), 0.0, 0.5), (ModifiedTrapezoid(), 0.05, 7.3), (SCCA(0.1, 0.8, 0.1), 0.2, 29.9),
         (ModifiedTrapezoid(), 0.0, 29.9)]


@pytest.mark.parametrize("law, zeta, n", CASES)
def test_upper_bound_holds_on_exact_values_and_search_matches_dense(law, zeta, n):
    grid = motion_grid(law, default_resolution(max(n, 1.0)))
    omega = 2 * np.pi * n
    q = propagate(grid, omega, zeta)
    gain = mode_gain(omega, zeta)
    lower, upper = peak_bounds(gain, q, grid, omega, zeta)
    nodes = np.asarray(grid.nodes)
    t = (nodes[:-1, None] + np.diff(nodes)[:, None] * np.linspace(0, 1, 33)).ravel()
    exact = np.abs(np.real(complex(gain) * mode_between(grid, q, complex(eigenvalue(omega, zeta)), t)))
    per_interval = exact.reshape(-1, 33).max(axis=1)
    assert np.all(per_interval <= np.asarray(upper))
    assert np.max(per_interval) >= float(jnp.max(lower))
    peak, overflow = bounded_peak_in_motion(q, grid, omega, zeta)
    dense = dense_peak_in_motion(q, grid, omega, zeta)
    if not bool(overflow):
        assert float(peak) == pytest.approx(float(dense), rel=1e-13)
    # The refined peak lies between the sampled exact values and the bound.
    assert np.max(per_interval) * (1 - 1e-12) <= float(dense) <= float(jnp.max(upper))


def test_overflow_is_flagged_on_a_plateau():
    # A damped high ratio on the trapezoid's constant-acceleration plateau: hundreds of
    # intervals are within the bound's slack of the peak.
    grid = motion_grid(ModifiedTrapezoid(), default_resolution(99.0))
    omega = 2 * np.pi * 99.0
    assert bool(bounded_peak_in_motion(propagate(grid, omega, 0.2), grid, omega, 0.2)[1])


@pytest.mark.parametrize("flagged", [[], [3], [1, 4, 6], list(range(10))])
def test_with_fallback_recomputes_exactly_the_flagged_members(flagged):
    batch = jnp.arange(10.0)
    mask = jnp.isin(jnp.arange(10), jnp.asarray(flagged, dtype=int))

    def fast(x):
        return -x, mask[x.astype(int)]

    out = with_fallback(fast, lambda x: x, batch, spill=3)
    expected = np.where(np.asarray(mask), np.arange(10.0), -np.arange(10.0))
    np.testing.assert_array_equal(np.asarray(out), expected)

"""A law-sized grid for the exact kernel, against the engine's grid, in one process.

The engine's grid is sized by the period ratio (``w h <= 1.5``: 128 intervals per rise over
n <= 30, 448 over n <= 100), because each interval's peak is refined by one interpolant of
degree 11.  The propagation is exact at any step, and the forcing needs only about 48
intervals per rise (residuals within 1e-10 up to n = 100).  This script builds the kernel
that such a grid needs and times it against the engine's, to say whether it pays:

- the grid: ``--resolution`` intervals per rise plus two per piece, whatever the ratio;
- the propagation: ``camjax.sdof.propagate`` with the kicks from ``psi`` (any ``w h``);
- a bound of ``|x''|`` on each interval that holds at any ``w h``: on an interval whose
  forcing is the polynomial ``a``, ``q = q_p + C exp(lambda t)`` with the particular
  solution ``q_p = -sum_j a^(j) / lambda^(j+1)``; so ``|x''| <= max |Re(K q_p)|`` (the
  largest Bernstein coefficient of a quintic) ``+ |K C|`` (the free vibration's modulus);
- refinement: a candidate interval cut into ``m`` parts of ``w h <= 1.5``, the exact mode at
  their ends, and the engine's degree-11 Hermite peak on each part.

It prints, per law: the grid, ``m``, the largest difference of Ct from the engine's, the
refinement steps the search took (mean and most, over the ratios), and the warm times of
the engine, of this search, and of its best case (propagation, bounds and one refinement:
what any tighter bound could reach), and of the propagation alone.

    python experiments/law_sized_grid.py [--resolution 48] [--n-max 30] [--damping 0.0]
                                         [--repeats 15] [--laws modified-sine ...]
"""

from __future__ import annotations

import argparse
import math
import time

import jax
import jax.numpy as jnp
import numpy as np

from camjax import checks, laws, sweep
from camjax.metrics import _hermite_matrix, _peak_and_location, _polynomial, hermite_data
from camjax.models._spring_mass import batch_metrics
from camjax.sdof import (
    SampledLaw,
    chunked_map,
    dwell_peak,
    eigenvalue,
    gain_derivatives,
    mode_gain,
    propagate,
    psi,
)
from camjax.sharding import sweep_jit

DEGREE = 6  # coefficients of the forcing's quintic on an interval
_BERNSTEIN = np.array([[math.comb(i, r) / math.comb(5, r) if r <= i else 0.0
                        for r in range(DEGREE)] for i in range(DEGREE)])


def law_tensors(grid):
    """Law-only arrays of the bound: ``(K * 6, 6)`` Bernstein coefficients of ``Re(K q_p)``
    per power ``j`` of ``1 / lambda``, ``(K, 6)`` the terms of ``q_p`` at each left end, and
    ``(K, 6)`` their magnitudes (the bound's rounding slack)."""
    c, h = np.asarray(grid.forcing), np.asarray(grid.widths)
    terms = np.zeros((c.shape[0], DEGREE, DEGREE))  # [interval, power of sigma, j]
    for r in range(DEGREE):
        for j in range(DEGREE - r):
            terms[:, r, j] = math.factorial(r + j) / math.factorial(r) * h**-j * c[:, r + j]
    bernstein = np.einsum("ir,krj->kij", _BERNSTEIN, terms)
    start = np.array([math.factorial(j) for j in range(DEGREE)]) * h[:, None] ** -np.arange(DEGREE) * c
    scale = np.abs(start) + np.abs(bernstein).sum(axis=1)
    return jnp.asarray(bernstein.reshape(-1, DEGREE)), jnp.asarray(start), jnp.asarray(scale)


def interval_bounds(q, tensors, omega, zeta):
    """``(K,)`` bounds of ``|x''|`` on every interval, at any ``w h``."""
    bernstein, start, scale = tensors
    gain, lam = mode_gain(omega, zeta), eigenvalue(omega, zeta)
    g = jnp.stack([-gain / lam ** (j + 1) for j in range(DEGREE)])
    quintic = jnp.max(jnp.abs((bernstein @ jnp.real(g)).reshape(-1, DEGREE)), axis=1)
    free = gain * q[:-1] - (start @ jnp.real(g) + 1j * (start @ jnp.imag(g)))
    rounding = 1e-13 * (scale @ jnp.abs(g) + jnp.abs(gain * q[:-1]))
    return quintic + jnp.abs(free) + rounding


def part_coefficients(q, grid, omega, zeta, index, parts: int):
    """``(len(index), parts, 12)`` degree-11 coefficients on the parts of intervals ``index``."""
    lam, gain = eigenvalue(omega, zeta), mode_gain(omega, zeta)
    c, h = grid.forcing[index], grid.widths[index]
    sigma = jnp.arange(parts + 1) / parts
    delta = h[:, None] * sigma
    powers = sigma[:, None] ** jnp.arange(DEGREE)
    kick = delta * jnp.sum(c[:, None, :] * powers * psi(lam * delta), axis=-1)
    modes = (jnp.exp(lam * delta) * q[index][:, None] + kick).at[:, -1].set(q[index + 1])
    forcing, coefficients = [], c
    for order in range(5):  # a, a', ..., a'''' at the parts' ends
        forcing.append(jnp.sum(coefficients[:, None, :] * powers, axis=-1) / h[:, None] ** order)
        coefficients = jnp.concatenate([coefficients[:, 1:] * jnp.arange(1, DEGREE),
                                        jnp.zeros_like(coefficients[:, :1])], axis=1)
    count = modes.shape[0]
    jets = gain_derivatives(gain, lam, modes.reshape(-1),
                            jnp.stack(forcing, axis=-1).reshape(-1, 5)).reshape(count, parts + 1, 5)
    values = jnp.real(gain * modes)
    widths = jnp.repeat(h[:, None] / parts, parts, axis=1).reshape(-1)
    data = hermite_data(values[:, :-1].reshape(-1), widths, jets[:, :-1].reshape(-1, 5),
                        jets[:, 1:].reshape(-1, 5), values[:, 1:].reshape(-1))
    return jnp.dot(data, jnp.asarray(_hermite_matrix(5).T),
                   precision=jax.lax.Precision.HIGHEST).reshape(count, parts, -1)


def peak(q, grid, omega, zeta, tensors, parts: int, steps: int | None = None):
    """``(max |x''| over the rise, refinement steps)``: a search until no bound beats the
    best value (``steps=None``), or exactly ``steps`` refinements of the largest bounds."""
    values = jnp.abs(jnp.real(mode_gain(omega, zeta) * q))
    bound = interval_bounds(q, tensors, omega, zeta) * (1 + 64 * jnp.finfo(q.real.dtype).eps)

    def refine(state):
        best, winner, part, where, open_bound, count = state
        i = jnp.argmax(open_bound)
        peaks, at = _peak_and_location(part_coefficients(q, grid, omega, zeta, i[None], parts)[0])
        top = jnp.argmax(peaks)
        better = peaks[top] > best
        return (jnp.where(better, peaks[top], best), jnp.where(better, i, winner),
                jnp.where(better, top, part), jnp.where(better, at[top], where),
                open_bound.at[i].set(-jnp.inf), count + 1)

    state = (jnp.max(values), jnp.zeros((), int), jnp.zeros((), int),
             jnp.zeros((), values.dtype), bound, jnp.zeros((), int))
    if steps is None:
        state = jax.lax.while_loop(lambda s: jnp.max(s[4]) > s[0] * (1 + 1e-11), refine, state)
    else:
        for _ in range(steps):
            state = refine(state)
    _, winner, part, where, _, count = state
    found = _polynomial(part_coefficients(q, grid, omega, zeta, winner[None], parts)[0, part], where)[0]
    return jnp.maximum(jnp.abs(found), jnp.max(values)), count


def law_grid_kernel(sampled, ratios, zeta, tensors, parts, steps=None):
    def one(n):
        omega = 2 * jnp.pi * n
        q = propagate(sampled.grid, omega, zeta)
        in_motion, count = peak(q, sampled.grid, omega, zeta, tensors, parts, steps)
        return jnp.maximum(in_motion, dwell_peak(q[-1], omega, zeta, 1.0)) / sampled.Ca, count
    return chunked_map(one, ratios, sampled.grid.nodes.shape[0])


def best_ms(fn, sampled, ratios, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        jax.block_until_ready(fn(sampled, ratios))
        times.append(time.perf_counter() - start)
    return 1e3 * min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=int, default=48, help="intervals per rise")
    parser.add_argument("--n-max", type=float, default=30.0)
    parser.add_argument("--damping", type=float, default=0.0)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--laws", nargs="+", default=["cycloidal", "modified-sine", "poly4567",
                                                      "modified-trapezoid", "scca:0.1,0.5,0.4",
                                                      "scca:0.005,0.99,0.005"])
    args = parser.parse_args()
    n = np.linspace(1.0, args.n_max, 1000)
    ratios, template, options = sweep.prepare_sweep(n, damping=args.damping)
    engine = sweep_jit(lambda s, r: batch_metrics(s, r, args.damping, options)[0].ct)
    print(f"1000 ratios in [1, {args.n_max:g}], damping {args.damping}; engine grid "
          f"{options.resolution} per rise, law-sized grid {args.resolution} per rise")
    print(f"{'law':<24} {'K':>4} {'m':>2} {'max dCt':>8} {'steps':>10} {'engine ms':>10} "
          f"{'search ms':>10} {'1 step ms':>10} {'propagate':>10}")
    for name in args.laws:
        law = laws.as_law(name)
        sampled = template.sweep_law(law, options)
        coarse = SampledLaw.of(law, args.resolution, SampledLaw.padded_pieces(law))
        tensors = law_tensors(coarse.grid)
        widest = float(np.max(np.asarray(coarse.grid.piece_width)))
        parts = max(1, math.ceil(2 * math.pi * args.n_max * widest / 1.5))
        search = sweep_jit(lambda s, r, t=tensors, m=parts: law_grid_kernel(s, r, args.damping, t, m))
        one_step = sweep_jit(lambda s, r, t=tensors, m=parts:
                             law_grid_kernel(s, r, args.damping, t, m, steps=1)[0])
        with checks.checked_outside():
            reference = np.asarray(engine(sampled, ratios))
        ct, steps = map(np.asarray, search(coarse, ratios))
        propagation = sweep_jit(lambda s, r: chunked_map(
            lambda x: propagate(s.grid, 2 * jnp.pi * x, args.damping)[-1], r, s.grid.nodes.shape[0]))
        one_step(coarse, ratios), propagation(coarse, ratios)
        times = [best_ms(engine, sampled, ratios, args.repeats)]
        times += [best_ms(fn, coarse, ratios, args.repeats) for fn in (search, one_step, propagation)]
        print(f"{law.name:<24} {coarse.grid.widths.shape[0]:4d} {parts:2d} "
              f"{np.max(np.abs(ct - reference)):8.1e} {steps.mean():5.1f} {steps.max():4d} "
              + " ".join(f"{t:10.2f}" for t in times))


if __name__ == "__main__":
    main()

"""A small work-precision study: time against error of each solution method.

Every method computes the Ct and residual curves of a law over a batch of period ratios
in one compiled call (``camjax.models.batch_metrics``); its errors are measured against
the exact path at a high resolution.  The full study, with scipy peers, float32 and the
charts, is ``experiments/benchmarks/work_precision.py``; ``camjax bench`` runs the quick one.
"""

from __future__ import annotations

import collections
import dataclasses
import math
import time
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .errors import RESULTS
from .laws import rest_to_rest
from .models import SpringMassOptions, batch_metrics
from .sdof import (
    TARGET_PHASE_STEP,
    check_grid_size,
    default_resolution,
    law_value_key,
    period_ratio_reach,
)
from .solvers import FIXED_STEP_SOLVERS

ACCURACY_GOAL = 1e-6
"""Largest error of Ct and R (units of Ca) a default method must meet on every law."""

STUDY_LAWS = ("poly4567", "modified-trapezoid", "harmonic", "parabolic")


@dataclasses.dataclass(frozen=True)
class Case:
    """One method configuration of the study.

    Attributes:
        label: a short name for tables and charts (``"tsit5 rtol=1e-08"``).
        family: ``exact``, ``fixed-step``, ``adaptive``, ``adaptive-no-jumps`` or ``implicit``.
        options: the solve options (resolution, method, tolerances, steps).
    """

    label: str
    family: str
    options: SpringMassOptions


class Timing(NamedTuple):
    """What ``timed`` measured: the value of the first call, its seconds (tracing,
    compilation and one run), the best and the median of the warm calls."""

    value: object
    first_s: float
    best_s: float
    median_s: float


def timed(fn, repeats: int = 5, *, clock=time.perf_counter) -> Timing:
    """Time ``fn()`` (returning JAX arrays, waited for): the first call, then the best of
    ``repeats`` warm calls; ``clock=time.process_time`` measures CPU time instead.  The
    one timing loop of the benchmarks and experiments."""
    start = clock()
    value = jax.block_until_ready(fn())
    first = clock() - start
    warm = []
    for _ in range(repeats):
        start = clock()
        jax.block_until_ready(fn())
        warm.append(clock() - start)
    return Timing(value, first, min(warm, default=math.inf), float(np.median(warm)) if warm else math.inf)


COMPILED_ACCELERATIONS_KEPT = 16
"""Laws whose compiled acceleration ``scipy_reference`` keeps (least recently used dropped
first), keyed by the law's values (``camjax.sdof.law_value_key``)."""
_COMPILED: collections.OrderedDict = collections.OrderedDict()


def compiled_acceleration(law):
    """The law's acceleration as a compiled scalar function (what a scipy user would call),
    kept for the next reference of the same law (``COMPILED_ACCELERATIONS_KEPT``)."""
    key = law_value_key(law)
    if key in _COMPILED:
        _COMPILED.move_to_end(key)
        return _COMPILED[key]
    # A closure, not ``jax.jit(law.a)``: jit would hash the law as a static ``self``,
    # and a law holding its parameters in arrays is not hashable.
    _COMPILED[key] = compiled = jax.jit(lambda t: law.a(t))
    if len(_COMPILED) > COMPILED_ACCELERATIONS_KEPT:
        _COMPILED.popitem(last=False)
    return compiled


def scipy_reference(law, n: float, method: str, rtol: float):
    """Ct, R and function evaluations of scipy's ``solve_ivp`` (undamped SDOF).

    Integrates the deflection ``e'' = a - w^2 e``; the payload acceleration is ``w^2 e``
    in the rise, and the dwell's free vibration has amplitude ``w |e' + i w e|`` at
    ``tau = 1``.  The in-motion peak is the max of the dense output sampled at 64 points
    per vibration period, polished by a bounded scalar search around every sampled crest
    within the sampling loss of the largest.
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import minimize_scalar

    accel = compiled_acceleration(law)
    omega = 2 * np.pi * n
    jumps = [float(t) for t in np.asarray(law.breakpoints())]
    edges = [0.0, *jumps, 1.0]

    def field(t, y):
        return [y[1], float(accel(t)) - omega**2 * y[0]]

    y, nfev, pieces = [0.0, 0.0], 0, []
    for t0, t1 in zip(edges[:-1], edges[1:]):  # restart at jumps, as jump_ts does
        sol = solve_ivp(field, (t0, t1), y, method=method, rtol=rtol, atol=rtol * 1e-2, dense_output=True)
        if sol.status != 0:
            raise RuntimeError(f"scipy {method} failed at n={n}: {sol.message}")
        y, nfev = sol.y[:, -1], nfev + sol.nfev
        pieces.append((t0, t1, sol.sol))
    peak = 0.0
    for t0, t1, dense in pieces:
        t = np.linspace(t0, t1, max(16, int(64 * n * (t1 - t0))))
        values = np.abs(omega**2 * dense(t)[0])
        peak = max(peak, values.max())
        # Polish every sampled crest that the sampling loss (up to 1 - cos(w h / 2)) could
        # lift above the largest sample, not only the largest one.
        loss = 1 - np.cos(omega * (t[1] - t[0]) / 2)
        padded = np.concatenate([[-np.inf], values, [-np.inf]])
        crests = (values >= padded[:-2]) & (values >= padded[2:]) & (values >= values.max() * (1 - 2 * loss))
        for k in np.flatnonzero(crests):
            lo, hi = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
            polished = minimize_scalar(lambda s, dense=dense: -abs(omega**2 * dense(s)[0]), bounds=(lo, hi),
                                       method="bounded", options={"xatol": 1e-12})
            peak = max(peak, -polished.fun)
    residual = omega * abs(complex(y[1], omega * y[0]))
    return max(peak, residual) / law.Ca, residual / law.Ca, nfev


def _adaptive(method: str, rtol: float, family: str, use_jump_ts: bool = True) -> Case:
    suffix = "" if use_jump_ts else " no-jumps"
    return Case(
        f"{method} rtol={rtol:.0e}{suffix}",
        family,
        SpringMassOptions(method=method, rtol=rtol, atol=rtol * 1e-2, use_jump_ts=use_jump_ts),
    )


LEVELS = ("quick", "medium", "full")


def study_cases(level: str = "quick", max_period_ratio: float | None = None) -> list[Case]:
    """The method configurations of the study, by size.

    ``quick``: six cases for the CLI and the tests; ``medium``: fifteen, every
    family at one to four settings (the figures in docs/work-precision.md); ``full``:
    every solver at every setting (53 cases; about 7 minutes per law over 200 period
    ratios on 2 loaded cores).  With ``max_period_ratio``, the cases whose options that
    range refuses are left out: an exact grid coarser than ``w h <= MAX_PHASE_STEP`` at
    the largest ratio, whose refined peaks would not be trusted.
    """
    if level not in LEVELS:
        raise ValueError(f"unknown study level {level!r}; valid levels: {', '.join(LEVELS)}")
    cases = _level_cases(level)
    if max_period_ratio is None:
        return cases
    return [case for case in cases if _accepted(case, max_period_ratio)]


def _accepted(case: Case, max_period_ratio: float) -> bool:
    try:
        case.options.checked(max_period_ratio)
    except ValueError:
        return False
    return True


def _level_cases(level: str) -> list[Case]:
    if level == "quick":
        return [
            Case("exact res=256", "exact", SpringMassOptions(resolution=256)),
            Case("exact default", "exact", SpringMassOptions()),
            Case("heun steps=4000", "fixed-step", SpringMassOptions(method="heun", steps=4000)),
            _adaptive("tsit5", 1e-6, "adaptive"),
            _adaptive("tsit5", 1e-10, "adaptive"),
            _adaptive("tsit5", 1e-10, "adaptive-no-jumps", use_jump_ts=False),
        ]
    if level == "medium":
        return [
            *(Case(f"exact res={r}", "exact", SpringMassOptions(resolution=r)) for r in (64, 256)),
            Case("exact default", "exact", SpringMassOptions()),
            Case("euler steps=16000", "fixed-step", SpringMassOptions(method="euler", steps=16000)),
            *(Case(f"heun steps={k}", "fixed-step", SpringMassOptions(method="heun", steps=k)) for k in (2000, 16000)),
            *(_adaptive("tsit5", rtol, "adaptive") for rtol in (1e-4, 1e-6, 1e-8, 1e-11)),
            _adaptive("bosh3", 1e-6, "adaptive"),
            _adaptive("dopri8", 1e-8, "adaptive"),
            _adaptive("tsit5", 1e-8, "adaptive-no-jumps", use_jump_ts=False),
            _adaptive("dopri8", 1e-8, "adaptive-no-jumps", use_jump_ts=False),
            _adaptive("kvaerno5", 1e-6, "implicit"),
        ]
    cases = [Case(f"exact res={r}", "exact", SpringMassOptions(resolution=r)) for r in (64, 128, 256, 512, 1024, 2048)]
    cases.append(Case("exact default", "exact", SpringMassOptions()))
    for method in FIXED_STEP_SOLVERS:
        for steps in (1000, 4000, 16000, 64000):
            cases.append(Case(f"{method} steps={steps}", "fixed-step", SpringMassOptions(method=method, steps=steps)))
    for method in ("bosh3", "tsit5", "dopri5", "dopri8"):
        for rtol in (1e-3, 1e-6, 1e-9, 1e-12):
            cases.append(_adaptive(method, rtol, "adaptive"))
        for rtol in (1e-6, 1e-9):
            cases.append(_adaptive(method, rtol, "adaptive-no-jumps", use_jump_ts=False))
    for method in ("kvaerno3", "kvaerno5"):
        for rtol in (1e-4, 1e-7, 1e-10):
            cases.append(_adaptive(method, rtol, "implicit"))
    return cases


def reference_resolution(max_period_ratio: float) -> int:
    """Grid of the exact reference: four times the default one, and at least 8192; refused
    (``check_grid_size``) past ``MAX_GRID_INTERVALS``."""
    resolution = max(8192, 4 * default_resolution(max_period_ratio))
    largest = period_ratio_reach(TARGET_PHASE_STEP / 4)
    check_grid_size(resolution, f"the reference (the exact path on a grid four times finer than w h = "
                    f"{TARGET_PHASE_STEP:g}) at period ratio {max_period_ratio:g}",
                    f"period ratios up to {math.floor(largest):,}")
    return resolution


def reference_metrics(law, period_ratios, max_period_ratio: float | None = None):
    """Exact-path Ct and R at :func:`reference_resolution` (NumPy arrays)."""
    n = jnp.asarray(period_ratios, dtype=float)
    resolution = reference_resolution(float(max_period_ratio or jnp.max(n)))
    metrics, _, _ = batch_metrics(law, n, 0.0, SpringMassOptions(resolution=resolution).checked(float(jnp.max(n))))
    return np.asarray(metrics.ct), np.asarray(metrics.residual)


def measure(law, period_ratios, case: Case, reference, *, repeats: int = 2) -> dict:
    """Time and error of one case on one law: a row of the work-precision table.

    ``first_s`` is the first call (tracing, compilation and one run); ``warm_s`` the best
    of ``repeats`` further calls; ``compile_s`` their difference.  Errors are the max
    absolute errors of Ct and R (units of Ca) over the period ratios that succeeded;
    ``failed`` counts the ones whose solver reported a failure (or gave non-finite values).
    """
    n = jnp.asarray(period_ratios, dtype=float)
    options = case.options.checked(float(jnp.max(n)))
    timing = timed(lambda: batch_metrics(law, n, 0.0, options), repeats)
    (metrics, result, steps), first, warm = timing.value, timing.first_s, timing.best_s
    ct, residual = np.asarray(metrics.ct), np.asarray(metrics.residual)
    ok = np.asarray(result == RESULTS.successful) & np.isfinite(ct) & np.isfinite(residual)
    ref_ct, ref_residual = reference
    steps = np.asarray(steps)
    where = locate_errors(np.asarray(n), ok, ct - ref_ct, residual - ref_residual)
    return {
        "law": law.name,
        "method": case.label,
        "family": case.family,
        "solver": options.method,
        "n_count": int(n.size),
        "warm_s": warm,
        "compile_s": max(first - warm, 0.0),
        "steps_mean": float(steps.mean()),
        "steps_max": int(steps.max()),
        "failed": int((~ok).sum()),
        "ct_error": float(np.max(np.abs(ct - ref_ct)[ok])) if ok.any() else np.nan,
        "residual_error": float(np.max(np.abs(residual - ref_residual)[ok])) if ok.any() else np.nan,
        **where,
    }


def locate_errors(period_ratios, ok, ct_error, residual_error) -> dict:
    """Where a case is worst: the period ratio of its largest Ct or R error among the ratios
    that succeeded (``worst_n``) and the smallest period ratio that failed (``failed_n_min``;
    NaN when none did)."""
    n, ok = np.asarray(period_ratios, dtype=float), np.asarray(ok, dtype=bool)
    error = np.maximum(np.abs(np.asarray(ct_error)), np.abs(np.asarray(residual_error)))
    error = np.where(ok & np.isfinite(error), error, -np.inf)
    return {
        "worst_n": float(n[np.argmax(error)]) if ok.any() else np.nan,
        "failed_n_min": float(n[~ok].min()) if (~ok).any() else np.nan,
    }


def pareto_front(times, errors) -> np.ndarray:
    """Indices of the points no other point beats in both time and error, by time."""
    times, errors = np.asarray(times, dtype=float), np.asarray(errors, dtype=float)
    valid = np.flatnonzero(np.isfinite(times) & np.isfinite(errors))
    order = valid[np.lexsort((errors[valid], times[valid]))]
    front, best = [], np.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return np.asarray(front, dtype=int)


def default_method(rows: list[dict], goal: float = ACCURACY_GOAL, laws=None) -> dict | None:
    """The method with the least total warm time that meets ``goal`` on every law.

    A method qualifies if it was run on every law (``laws``; by default every law in
    ``rows``), no period ratio failed and both the Ct and the R error are at most
    ``goal``.  Returns ``{"method", "warm_s"}`` or None.
    """
    laws = {row["law"] for row in rows} if laws is None else set(laws)
    by_method: dict[str, list[dict]] = {}
    for row in rows:
        by_method.setdefault(row["method"], []).append(row)
    qualified = {
        method: sum(r["warm_s"] for r in group)
        for method, group in by_method.items()
        if {r["law"] for r in group} == laws
        and all(r["failed"] == 0 and max(r["ct_error"], r["residual_error"]) <= goal for r in group)
    }
    if not qualified:
        return None
    method = min(qualified, key=qualified.get)
    return {"method": method, "warm_s": qualified[method]}


def run_study(laws, period_ratios, cases, *, repeats: int = 2, progress=None) -> list[dict]:
    """Rows of :func:`measure` for every law (or law name) and case."""
    rows = []
    for name in laws:
        law = rest_to_rest(name, "run_study")
        reference = reference_metrics(law, period_ratios)
        for case in cases:
            rows.append(measure(law, period_ratios, case, reference, repeats=repeats))
            if progress is not None:
                progress(rows[-1])
    return rows


COLUMNS = ("law", "method", "warm_s", "compile_s", "steps_mean", "failed", "ct_error", "residual_error")


def format_table(rows: list[dict], columns=COLUMNS) -> str:
    """A markdown table of the rows."""

    def cell(value):
        if isinstance(value, float):
            return "nan" if not np.isfinite(value) else f"{value:.3g}"
        return str(value)

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(row.get(c, "")) for c in columns) + " |" for row in rows]
    return "\n".join(lines)

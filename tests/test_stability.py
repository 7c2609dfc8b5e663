"""Failure modes of the solution methods are detected (issue 3), and the bench helpers work."""

import argparse

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_RTOL

import camjax  # noqa: F401  (float64)
from camjax import studies
from camjax.cli import bench
from camjax.models import SpringMassOptions, batch_metrics, response_metrics
from camjax.sdof import sdof_term
from camjax.solvers import MAX_FREE_VIBRATION_GROWTH, free_vibration_growth, solver

CYCLOIDAL = camjax.laws.get("cycloidal")


def cycloidal_residual(n):
    """Closed form R(n) = 2n |sin(pi n)| / |n^2 - 1| (MISSION.md)."""
    return 2 * n * abs(np.sin(np.pi * n)) / abs(n**2 - 1)


@pytest.mark.parametrize("method", ["euler", "heun", "midpoint", "ralston"])
def test_free_vibration_growth_matches_the_method_on_the_free_oscillator(method):
    """The growth formula equals the growth diffrax's own solver produces on q' = lambda q."""
    omega, steps = 2 * np.pi * 3.0, 200
    lam = 1j * omega
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(lambda t, y, args: (-omega**2 * y[1], y[0])),  # (x', x) of x'' = -w^2 x
        solver(method), 0.0, 1.0, 1.0 / steps, (jnp.array(1.0), jnp.array(0.0)),
        stepsize_controller=diffrax.ConstantStepSize(), saveat=diffrax.SaveAt(t1=True),
    )
    velocity, position = (float(y[-1]) for y in solution.ys)
    numerical = abs(velocity - np.conj(lam) * position)  # |q| with q(0) = 1
    assert float(free_vibration_growth(method, omega, 0.0, steps)) == pytest.approx(numerical, rel=1e-9)


def test_public_sdof_term_gives_the_cycloidal_residual():
    """``camjax.sdof.sdof_term`` is the equation the diffrax path integrates."""
    n = 2.5
    omega = 2 * np.pi * n
    solution = diffrax.diffeqsolve(
        sdof_term(), diffrax.Tsit5(), 0.0, 1.0, None, (jnp.array(0.0), jnp.array(0.0)),
        args=(CYCLOIDAL, omega, 0.0), stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-12),
        saveat=diffrax.SaveAt(t1=True),
    )
    e, de = (float(y[-1]) for y in solution.ys)
    residual = omega * abs(complex(de, omega * e)) / float(CYCLOIDAL.Ca)
    assert residual == pytest.approx(cycloidal_residual(n), abs=1e-7)


def test_unstable_fixed_step_raises_instead_of_a_wrong_ct():
    # Euler with 1000 steps at n = 30: w dt = 0.19, free vibration grows ~3e7-fold.
    with pytest.raises(camjax.SolverError, match="euler.*period ratio 30"):
        camjax.solve(CYCLOIDAL, camjax.SpringMass(30.0, 0.0), method="euler", steps=1000)
    with pytest.raises(camjax.SolverError, match="heun"):
        camjax.ct_curve(CYCLOIDAL, [2.0, 30.0], method="heun", steps=200)


def test_a_sweep_with_throw_false_marks_the_failed_ratios_only():
    """Heun with 200 steps is stable at n = 2.5 and not at n = 30: the sweep finishes, the
    failed ratio NaN with its code, the other as solved on its own."""
    grid = {"method": "heun", "steps": 200, "resolution": 4096}  # one grid for sweep and solve
    curve = camjax.ct_curve(CYCLOIDAL, [2.5, 30.0], throw=False, **grid)
    assert curve.result_names == ["successful", "unstable_fixed_step"]
    np.testing.assert_array_equal(curve.failed, [False, True])
    for values in (curve.ct, curve.residual, curve.peak_in_motion, curve.ca_ct):
        assert np.isfinite(values[0]) and np.isnan(values[1])
    alone = camjax.solve(CYCLOIDAL, camjax.SpringMass(2.5, 0.0), **grid)
    assert curve.ct[0] == pytest.approx(float(alone.metrics.ct), rel=COMPILED_RTOL)
    assert curve.residual[0] == pytest.approx(cycloidal_residual(2.5), rel=MAX_FREE_VIBRATION_GROWTH - 1)
    both = camjax.ct_curves([CYCLOIDAL], [2.5, 30.0], throw=False, **grid)
    assert both["cycloidal"].result_names == curve.result_names


def test_a_stack_with_throw_false_marks_each_laws_failed_ratios():
    """A stack of laws (over ``STACK_FROM``) where Heun fails at n = 30 only: every law's
    curve has that ratio NaN with its code and the other as the law's own sweep; with
    ``throw`` the error names the ratio, the law and the count over the stack."""
    from camjax.sweep import STACK_FROM

    grid = {"method": "heun", "steps": 200, "resolution": 4096}
    laws = [camjax.laws.SCCA(a, 1.0 - 2 * a, a) for a in np.linspace(0.05, 0.45, STACK_FROM + 1)]
    curves = camjax.ct_curves(laws, [2.5, 30.0], throw=False, **grid)
    assert len(curves) == len(laws)
    for law in laws[::4]:
        curve, alone = curves[law.name], camjax.ct_curve(law, [2.5, 30.0], throw=False, **grid)
        assert curve.name == law.name and curve.ca == pytest.approx(alone.ca, rel=COMPILED_RTOL)
        assert curve.result_names == alone.result_names == ["successful", "unstable_fixed_step"]
        for values, own in ((curve.ct, alone.ct), (curve.residual, alone.residual),
                            (curve.peak_in_motion, alone.peak_in_motion)):
            assert values[0] == pytest.approx(own[0], rel=COMPILED_RTOL) and np.isnan(values[1])
    first = laws[0].name.replace(".", r"\.")
    with pytest.raises(camjax.SolverError, match=rf"period ratio 30, damping 0\) with {first} failed "
                                                 rf"\(9 of 18 law and ratio pairs failed\): "):
        camjax.ct_curves(laws, [2.5, 30.0], **grid)
    with pytest.raises(camjax.SolverError, match=rf"with {first} failed \(1 of 2 failed\)"):
        camjax.ct_curves(laws[:1], [2.5, 30.0], **grid)  # a law of its own is named too


def test_the_first_bad_entry_of_a_batch_is_the_one_named():
    """``raise_if_failed`` names the first bad entry in batch order, a failure code or a
    non-finite value where the entry succeeded: a stack's laws are reported in order, as
    law by law (a failure code later in the batch used to be named first)."""
    from camjax.errors import RESULTS, raise_if_failed

    ok, failed = RESULTS.successful, RESULTS.max_steps_reached

    def check(codes, values):
        result = jax.tree.map(lambda *x: np.stack(x), *codes)  # a batch of codes, as vmap gives
        raise_if_failed(result, lambda i: f"entry {i}", np.asarray(values), entries="pairs")

    with pytest.raises(camjax.SolverError, match=r"^entry 0 produced non-finite values$"):
        check([ok, failed, ok], [np.nan, np.nan, 1.0])
    with pytest.raises(camjax.SolverError, match=r"^entry 1 failed \(1 of 3 pairs failed\): "
                                                 r"the maximum number of solver steps"):
        check([ok, failed, ok], [1.0, np.nan, np.inf])
    with pytest.raises(camjax.SolverError, match=r"^entry 2 produced non-finite values$"):
        check([ok, ok, ok], [1.0, 2.0, np.inf])
    check([ok, ok, ok], [1.0, 2.0, 3.0])  # nothing to raise


@pytest.mark.slow
@pytest.mark.parametrize("model", [
    camjax.models.CoulombFriction(1.0, 0.3),
    camjax.models.Backlash(1.0, 0.01, 0.5),
    camjax.models.TwoMass(1.0, 1.0, 1.0),
    camjax.SpringMass(1.0, 0.0),
], ids=lambda m: type(m).__name__)
def test_every_model_sweep_reports_its_failures_with_throw_false(model):
    """A step limit no ratio can meet: each model's sweep path returns the code per ratio.

    Slow (16-29 s per model, 90 s in all on the loaded 2-core machine, 2026-11-27): a step limit of 8 is a new static option, so each model's sweep path compiles again.
    """
    method = "tsit5" if isinstance(model, camjax.SpringMass) else None
    curve = camjax.ct_curve(CYCLOIDAL, [1.5, 8.0], model=model, method=method, max_steps=8,
                            throw=False)
    assert curve.result_names == ["max_steps_reached"] * 2 and np.isnan(curve.ct).all()
    with pytest.raises(camjax.SolverError, match=r"\(2 of 2 failed\): the maximum number of solver steps"):
        camjax.ct_curve(CYCLOIDAL, [1.5, 8.0], model=model, method=method, max_steps=8)


def test_detection_limit_is_where_the_growth_crosses_the_threshold():
    """Just inside the limit a run succeeds and is close to the closed form; just past it, it fails."""
    n = 5.5
    omega = 2 * np.pi * n
    steps = np.arange(100, 2000)
    growth = np.asarray(free_vibration_growth("heun", omega, 0.0, steps))
    first_stable = int(steps[np.argmax(growth <= MAX_FREE_VIBRATION_GROWTH)])
    options = [SpringMassOptions(method="heun", steps=k).checked(n) for k in (first_stable - 1, first_stable)]
    (bad, bad_result, _), (good, good_result, _) = (batch_metrics(CYCLOIDAL, jnp.array([n]), 0.0, o) for o in options)
    assert not bool(bad_result == camjax.RESULTS.successful)
    assert np.isnan(np.asarray(bad.ct)).all() and np.isnan(np.asarray(bad.residual)).all()
    assert bool(good_result == camjax.RESULTS.successful)
    # Accepted: the error is bounded by the spurious growth (10 %), not wild.
    assert float(good.residual[0]) == pytest.approx(cycloidal_residual(n), rel=MAX_FREE_VIBRATION_GROWTH - 1)


@pytest.mark.slow
def test_stable_fixed_step_converges_at_second_order():
    """Slow (28 s on the loaded 2-core machine, 2026-11-27): one compiled fixed-step program per step count."""
    n = 2.5
    errors = []
    for steps in (2000, 4000):
        response = camjax.solve(CYCLOIDAL, camjax.SpringMass(n, 0.0), method="heun", steps=steps)
        errors.append(abs(float(response.metrics.residual) - cycloidal_residual(n)))
    assert 3.0 < errors[0] / errors[1] < 5.0


def harmonic_ct(n):
    """Ct of simple harmonic motion, undamped, from its closed-form response.

    ``x'' = A (cos(pi t) - cos(w t))`` with ``A = w^2 Ca / (w^2 - pi^2)`` over the rise;
    in the dwell the vibration's amplitude is ``2 |A cos(w / 2)|``.  The rise maximum is
    found by dense sampling, then bounded scalar minimisation around the largest samples.
    """
    from scipy.optimize import minimize_scalar

    w, ca = 2 * np.pi * n, np.pi**2 / 2
    amplitude = w**2 * ca / (w**2 - np.pi**2)

    def magnitude(t):
        return abs(amplitude * (np.cos(np.pi * t) - np.cos(w * t)))

    t = np.linspace(0.0, 1.0, 20001)
    values = magnitude(t)
    best = values.max()
    for i in np.argsort(values)[-40:]:
        lo, hi = t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]
        found = minimize_scalar(lambda s: -magnitude(s), bounds=(lo, hi), method="bounded",
                                options={"xatol": 1e-13})
        best = max(best, -found.fun)
    return max(best, 2 * abs(amplitude * np.cos(w / 2))) / ca


def test_default_grid_finds_the_crest_at_high_period_ratio():
    """Harmonic at high n, where many crests of |x''| are nearly equal.

    The sampling loss between nodes (up to 3% at the default w h <= 0.5) reorders the
    crests; refining only the largest samples had Ct up to 1e-3 low here (e.g. n = 97.72).
    """
    law = camjax.laws.get("harmonic")
    n = np.concatenate([np.linspace(60.0, 100.0, 23), [97.72072072072072]])
    ct = camjax.ct_curve(law, n).ct
    reference = np.array([harmonic_ct(x) for x in n])
    np.testing.assert_allclose(ct, reference, rtol=1e-8)


def test_max_steps_exhaustion_raises():
    with pytest.raises(camjax.SolverError, match="maximum number of solver steps"):
        camjax.solve(CYCLOIDAL, camjax.SpringMass(50.0, 0.0), method="tsit5", rtol=1e-12, atol=1e-14, max_steps=100)


@pytest.mark.slow
def test_adaptive_without_jump_ts_stays_accurate_on_an_acceleration_jump():
    """Parabolic (acceleration jump at 0.5): both ways meet the tolerance's accuracy.

    Slow (38 s on the loaded 2-core machine, 2026-11-27): Tsit5 at a tight tolerance, compiled twice (with and without ``jump_ts``).
    """
    law = camjax.laws.get("parabolic")
    n = jnp.array([3.3, 7.9])
    reference = camjax.ct_curve(law, n, resolution=4096).residual
    for use_jump_ts in (True, False):
        curve = camjax.ct_curve(law, n, method="tsit5", rtol=1e-8, atol=1e-10, use_jump_ts=use_jump_ts)
        np.testing.assert_allclose(curve.residual, reference, atol=1e-6)


def test_pareto_front_and_default_method():
    times = [1.0, 2.0, 0.5, 3.0, 2.5]
    errors = [1e-3, 1e-6, 1e-2, 1e-9, 1e-5]
    assert studies.pareto_front(times, errors).tolist() == [2, 0, 1, 3]  # 4 is beaten by 1
    rows = [
        {"law": law, "method": m, "warm_s": t, "failed": f, "ct_error": e, "residual_error": e}
        for law in ("a", "b")
        for m, t, f, e in (("fast", 0.1, 0, 1e-3), ("good", 1.0, 0, 1e-8), ("broken", 0.01, 1, 0.0))
    ]
    assert studies.default_method(rows)["method"] == "good"
    assert studies.default_method(rows, goal=1e-12) is None


def test_bench_case_levels():
    assert len(studies.study_cases("quick")) < len(studies.study_cases("medium")) < len(studies.study_cases("full"))
    families = {case.family for case in studies.study_cases("full")}
    assert families == {"exact", "fixed-step", "adaptive", "adaptive-no-jumps", "implicit"}
    with pytest.raises(ValueError, match="level"):
        studies.study_cases("huge")


def _parse(argv):
    parser = argparse.ArgumentParser()
    bench.register(parser.add_subparsers())
    return parser.parse_args(argv)


def test_bench_cli_rejects_bad_arguments():
    with pytest.raises(camjax.cli.CliError, match="--law: unknown law 'nonsense'"):
        bench.run(_parse(["bench", "--law", "nonsense"]))
    with pytest.raises(camjax.cli.CliError, match="--n"):
        bench.run(_parse(["bench", "--n=-1:2:3"]))


def test_measure_reports_errors_against_the_reference():
    """One cheap case through ``measure``: the error equals the closed form's distance."""
    n = np.array([2.5, 3.5, 4.5])
    case = studies.Case("exact res=64", "exact", SpringMassOptions(resolution=64))
    reference = (np.zeros(3), np.asarray([cycloidal_residual(x) for x in n]) / 1.0)
    row = studies.measure(CYCLOIDAL, n, case, (reference[0], reference[1] / 1.0), repeats=1)
    curve = camjax.ct_curve(CYCLOIDAL, n, resolution=64)
    # The grid has the resolution's intervals plus two per law piece: an SCCA law inside
    # jit has seven traced breakpoints, so eight pieces (some of zero width).
    assert row["failed"] == 0 and row["steps_max"] == 64 + 2 * 8
    assert row["residual_error"] == pytest.approx(np.max(np.abs(curve.residual - reference[1])), abs=1e-12)
    # R of the cycloidal law is in units of Ca = 2 pi: the closed form above is in those units too
    assert row["residual_error"] < 1e-6


@pytest.mark.slow
def test_float32_error_floor_is_reported(tmp_path):
    """float32 (a child process) gives errors near 1e-4, far above float64's.

    Slow (30-34 s on the loaded 2-core machine, 2026-11-27): a child process imports JAX and compiles the exact path again in single precision.
    """
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "experiments" / "benchmarks" / "work_precision.py"
    spec = tmp_path / "spec.json"
    n = np.linspace(1.5, 10.0, 5)
    spec.write_text(json.dumps({"law": "cycloidal", "n": n.tolist()}))
    subprocess.run([sys.executable, str(script), "--float32-worker", str(spec)],
                   env={**os.environ, "JAX_ENABLE_X64": "0"}, check=True)
    data = json.loads(spec.read_text())["exact default"]
    assert data["dtype"] == "float32"
    error = np.max(np.abs(np.asarray(data["residual"]) - cycloidal_residual(n)))
    assert 1e-9 < error < 1e-2


@pytest.mark.slow
def test_gradient_through_diffrax_matches_exact_path():
    """d(R)/dn through Tsit5 (RecursiveCheckpointAdjoint) against the exact path's autodiff.

    Slow (52 s on the loaded 2-core machine, 2026-11-27): reverse mode through Tsit5 at rtol 1e-10 on a 512-interval grid compiles a large program.
    """
    import jax

    options = SpringMassOptions(method="tsit5", rtol=1e-10, atol=1e-12, resolution=512)

    def residual_tsit5(n):
        return response_metrics(CYCLOIDAL, camjax.SpringMass(n, 0.0), options).residual

    exact = jax.grad(lambda n: camjax.residual_vibration(CYCLOIDAL, n))(3.3)
    assert float(jax.grad(residual_tsit5)(3.3)) == pytest.approx(float(exact), rel=1e-6)


def test_scipy_reference_agrees_with_the_exact_path_on_an_scca_law():
    """The studies' scipy peer (``solve_ivp`` on the law's compiled acceleration) runs on a
    law that holds its parameters in arrays (an SCCA) and agrees with the exact path."""
    from camjax import laws

    law = laws.SCCA(0.25, 0.5, 0.25)
    ct, residual, evaluations = studies.scipy_reference(law, 4.3, "DOP853", 1e-10)
    exact = response_metrics(law, camjax.SpringMass(4.3), SpringMassOptions().checked(4.3))
    assert evaluations > 0
    np.testing.assert_allclose([ct, residual], [exact.ct, exact.residual], rtol=1e-7)


def test_study_cases_leave_out_the_grids_a_range_refuses():
    """Exact grids coarser than ``w h <= MAX_PHASE_STEP`` at the range's largest ratio are not run
    (their refined peaks would not be trusted); every other case is kept."""
    everything = studies.study_cases("medium")
    kept = studies.study_cases("medium", 30.0)
    dropped = [case.label for case in everything if case not in kept]
    assert dropped == ["exact res=64"]  # 64 resolves n <= 15.3 (w h <= 1.5); 256 n <= 61
    assert [case.label for case in studies.study_cases("medium", 100.0) if case.family == "exact"] == ["exact default"]
    assert studies.study_cases("medium", 5.0) == everything

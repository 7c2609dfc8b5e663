"""Gradient cost and accuracy: d(R)/d(SCCA fractions) and d(Ct)/d(n), every way.

Ways: the exact path's autodiff (``camjax.residual_vibration``, ``camjax.torsion_factor``);
diffrax Tsit5 (rtol 1e-10, ``jump_ts`` at the law's breakpoints) differentiated with
RecursiveCheckpointAdjoint, DirectAdjoint, ForwardMode (``jax.jacfwd``) and
BacksolveAdjoint; central finite differences of the exact path.  The reference is the
exact path's autodiff on a fine grid (resolution 8192), checked against its own central
differences.  Times are the best of three warm calls over a batch of period ratios; the
compile time is listed apart.

    python experiments/benchmarks/gradient_cost.py            # writes results/gradient_cost/
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import diffrax
import jax
import jax.numpy as jnp
import numpy as np

import camjax
from camjax.laws import SCCA
from camjax.models import response_metrics
from camjax.sdof import sdof_term
from camjax.studies import timed

FRACTIONS = jnp.array([0.2, 0.4, 0.3])  # an SCCA with a zero-acceleration share d = 0.1
PERIOD_RATIOS = jnp.array([2.3, 4.7, 7.7, 11.1, 15.1])


def exact_residual(fractions, n, resolution=1024):
    return camjax.residual_vibration(SCCA(*fractions), n, resolution=resolution)


def exact_ct(n, resolution=1024):
    return camjax.torsion_factor(camjax.laws.get("modified-trapezoid"), n, resolution=resolution)


def diffrax_residual(fractions, n, adjoint, rtol=1e-10):
    """R from the end state of a Tsit5 solve: ``w |e' + i w e| / Ca`` (undamped)."""
    law = SCCA(*fractions)
    omega = 2 * jnp.pi * n
    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=rtol, atol=rtol * 1e-2),
        # Step placement only: BacksolveAdjoint cannot differentiate a traced controller.
        jump_ts=jax.lax.stop_gradient(jnp.asarray(law.breakpoints())))
    solution = diffrax.diffeqsolve(
        sdof_term(), diffrax.Tsit5(), 0.0, 1.0, None, (jnp.zeros(()), jnp.zeros(())),
        args=(law, omega, 0.0), stepsize_controller=controller, adjoint=adjoint, max_steps=20_000,
        saveat=diffrax.SaveAt(t1=True))
    e, de = (y[-1] for y in solution.ys)
    return omega * jnp.sqrt(de**2 + (omega * e) ** 2) / law.Ca


def diffrax_ct(n, rtol=1e-10):
    options = camjax.models.SpringMassOptions(method="tsit5", rtol=rtol, atol=rtol * 1e-2, resolution=1024)
    return response_metrics(camjax.laws.get("modified-trapezoid"), camjax.SpringMass(n, 0.0), options).ct


def central_difference(f, x, h):
    """Central differences of scalar ``f`` along each coordinate of ``x``."""
    x = jnp.atleast_1d(x)
    steps = h * jnp.eye(x.size)
    return jnp.stack([(f(x + s) - f(x - s)) / (2 * h) for s in steps]).reshape(x.shape)


def residual_gradients():
    """Rows for d(R)/d(fractions) over PERIOD_RATIOS."""
    batch = lambda g: jax.jit(jax.vmap(g, in_axes=(None, 0)))  # noqa: E731
    ways = {
        "exact autodiff (res 1024)": batch(jax.grad(exact_residual)),
        "exact central FD h=1e-6": batch(lambda f, n: central_difference(lambda x: exact_residual(x, n), f, 1e-6)),
        "tsit5 RecursiveCheckpointAdjoint": batch(
            jax.grad(lambda f, n: diffrax_residual(f, n, diffrax.RecursiveCheckpointAdjoint()))),
        "tsit5 DirectAdjoint": batch(jax.grad(lambda f, n: diffrax_residual(f, n, diffrax.DirectAdjoint()))),
        "tsit5 ForwardMode (jacfwd)": batch(
            jax.jacfwd(lambda f, n: diffrax_residual(f, n, diffrax.ForwardMode()))),
        "tsit5 BacksolveAdjoint": batch(jax.grad(lambda f, n: diffrax_residual(f, n, diffrax.BacksolveAdjoint()))),
        "tsit5 central FD h=1e-6": batch(
            lambda f, n: central_difference(lambda x: diffrax_residual(x, n, diffrax.RecursiveCheckpointAdjoint()),
                                            f, 1e-6)),
    }
    reference = jax.vmap(jax.grad(lambda f, n: exact_residual(f, n, 8192)), in_axes=(None, 0))(FRACTIONS, PERIOD_RATIOS)
    check = jax.vmap(lambda n: central_difference(lambda x: exact_residual(x, n, 8192), FRACTIONS, 1e-5))(PERIOD_RATIOS)
    rows = []
    for label, fn in ways.items():
        try:
            timing = timed(lambda fn=fn: fn(FRACTIONS, PERIOD_RATIOS), 3)
            value, warm = np.asarray(timing.value), timing.best_s
            compile_s = max(timing.first_s - warm, 0.0)
        except Exception as error:  # a way that cannot differentiate this solve is a finding
            rows.append({"quantity": "dR/d(a,b,c)", "way": f"{label} (fails: {str(error).splitlines()[0]})",
                         "warm_s": np.nan, "compile_s": np.nan, "max_abs_error": np.nan, "max_rel_error": np.nan})
            continue
        rows.append({"quantity": "dR/d(a,b,c)", "way": label, "warm_s": warm, "compile_s": compile_s,
                     "max_abs_error": float(np.max(np.abs(value - reference))),
                     "max_rel_error": float(np.max(np.abs(value - reference)) / np.max(np.abs(reference)))})
    return rows, float(np.max(np.abs(check - reference)))


def ct_gradients():
    """Rows for d(Ct)/d(n) over PERIOD_RATIOS."""
    ways = {
        "exact autodiff (res 1024)": jax.jit(jax.vmap(jax.grad(exact_ct))),
        "exact central FD h=1e-6": jax.jit(jax.vmap(lambda n: (exact_ct(n + 1e-6) - exact_ct(n - 1e-6)) / 2e-6)),
        "tsit5 RecursiveCheckpointAdjoint": jax.jit(jax.vmap(jax.grad(diffrax_ct))),
        "tsit5 central FD h=1e-6": jax.jit(jax.vmap(lambda n: (diffrax_ct(n + 1e-6) - diffrax_ct(n - 1e-6)) / 2e-6)),
    }
    reference = jax.vmap(jax.grad(lambda n: exact_ct(n, 8192)))(PERIOD_RATIOS)
    check = jax.vmap(lambda n: (exact_ct(n + 1e-5, 8192) - exact_ct(n - 1e-5, 8192)) / 2e-5)(PERIOD_RATIOS)
    rows = []
    for label, fn in ways.items():
        timing = timed(lambda fn=fn: fn(PERIOD_RATIOS), 3)
        value, warm = np.asarray(timing.value), timing.best_s
        compile_s = max(timing.first_s - warm, 0.0)
        rows.append({"quantity": "dCt/dn", "way": label, "warm_s": warm, "compile_s": compile_s,
                     "max_abs_error": float(np.max(np.abs(value - reference))),
                     "max_rel_error": float(np.max(np.abs(value - reference)) / np.max(np.abs(reference)))})
    return rows, float(np.max(np.abs(check - reference)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/gradient_cost")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    residual_rows, residual_check = residual_gradients()
    ct_rows, ct_check = ct_gradients()
    rows = residual_rows + ct_rows
    from camjax.studies import format_table

    columns = ("quantity", "way", "warm_s", "compile_s", "max_abs_error", "max_rel_error")
    text = [
        "# Gradient cost and accuracy", "", f"Command: `python {' '.join(sys.argv)}`", "",
        f"Law: SCCA fractions (a, b, c) = {FRACTIONS.tolist()} ; period ratios "
        f"{PERIOD_RATIOS.tolist()} in one vmapped batch. Reference: exact-path autodiff at resolution 8192; "
        f"its distance to its own central differences: dR {residual_check:.2g}, dCt/dn {ct_check:.2g}.",
        "Timings: one shared 2-core CPU (see docs/work-precision.md for the load of the committed run).", "",
        format_table(rows, columns)]
    (out / "gradient_cost.md").write_text("\n".join(text) + "\n")
    (out / "gradient_cost.json").write_text(json.dumps(
        {"rows": rows, "reference_check": {"dR": residual_check, "dCt_dn": ct_check}}, indent=1))
    print("\n".join(text))


if __name__ == "__main__":
    main()

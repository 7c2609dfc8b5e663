"""Coulomb friction on the payload: residual vibration, in-motion peak and rest offset.

For every standard law at one period ratio, sweeps the normalised friction level
``mu = F T^2 / (W h)`` with the stick-slip (events) path, and charts the residual
vibration at the start and the end of a one-period dwell, the in-motion peak, and the
offset at which the payload comes to rest (with the stick band ``mu / w^2``).  Then the
same sweep with viscous damping added (Cycloidal and ModSine, ``zeta = 0.05``: does the
richer dissipation model change the answers?), and the error of the tanh regularisation
against stick-slip as ``eps`` shrinks.

    python experiments/examples/friction.py [--n 5.25] [--dwell 1.0] [--quick] [--out DIR]

writes results/friction/ (friction_sweep.csv, summary.json, *.png, README.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import matplotlib

import camjax

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camjax.models import CoulombFriction  # noqa: E402

OUT = Path(__file__).resolve().parents[2] / "results" / "friction"
SAMPLES = 2048  # per rise
DAMPING_CHECK = 0.05  # viscous damping ratio of the comparison with a richer model


def window_peak(response, start, stop):
    """Max |x''| over tau in [start, stop] (samples), per batch member."""
    tau = response.tau[0]
    inside = (tau >= start) & (tau <= stop)
    return jnp.max(jnp.where(inside, jnp.abs(response.payload_acceleration), 0.0), axis=-1)


def sweep(law, n, frictions, dwell, damping=0.0):
    """Events-path responses over the friction levels (one vmapped call)."""
    batch = jax.jit(
        jax.vmap(
            lambda mu: camjax.solve(
                law, CoulombFriction(n, mu, damping), dwell=dwell, samples=SAMPLES, throw=False
            )
        )
    )(jnp.asarray(frictions))
    # A failed member (a solve error, reported) would be charted as a gap.
    failed = ~np.asarray(batch.result == camjax.RESULTS.successful)
    if failed.any():
        print(f"  {law.name}: solver failed at friction {np.asarray(frictions)[failed].tolist()}")
    period = 1.0 / n
    ca = float(law.Ca)
    metrics = {
        "peak_in_motion": np.asarray(batch.metrics.peak_in_motion),
        "residual_start": np.asarray(window_peak(batch, 1.0, 1.0 + period)) / ca,
        "residual_end": np.asarray(window_peak(batch, 1.0 + dwell - period, 1.0 + dwell)) / ca,
        "rest_offset": np.asarray(batch.rest_offset),
        "settled": np.asarray(batch.settled).astype(float),
    }
    return batch, {k: np.where(failed, np.nan, v) for k, v in metrics.items()}, failed


def main():
    global OUT
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=float, default=5.25, help="period ratio")
    parser.add_argument("--dwell", type=float, default=1.0, help="dwell, motion periods")
    parser.add_argument("--quick", action="store_true", help="one law, few levels (a smoke run)")
    parser.add_argument("--out", type=Path, default=OUT, help="output folder (default: results/friction)")
    args = parser.parse_args()
    OUT = args.out
    OUT.mkdir(parents=True, exist_ok=True)
    n, dwell = args.n, args.dwell
    w = 2 * np.pi * n
    frictions = np.linspace(0.0, 1.5, 4 if args.quick else 31)
    laws = camjax.laws.standard_laws()[:1] if args.quick else camjax.laws.standard_laws()

    rows, summary, histories = [], {"period_ratio": n, "dwell": dwell, "laws": {}}, {}
    for law in laws:
        start = time.perf_counter()
        batch, metrics, failed = sweep(law, n, frictions, dwell)
        print(f"{law.name:20s} {time.perf_counter() - start:6.1f} s")
        histories[law.name] = batch
        summary["laws"][law.name] = {
            "ca": float(law.Ca),
            "friction": frictions.tolist(),
            "failed_at_friction": frictions[failed].tolist(),
            **{k: v.tolist() for k, v in metrics.items()},
        }
        for i, mu in enumerate(frictions):
            rows.append([law.name, mu, mu / w**2] + [float(metrics[k][i]) for k in metrics])
    header = "law,friction,stick_band,peak_in_motion,residual_start,residual_end,rest_offset,settled"
    with open(OUT / "friction_sweep.csv", "w") as f:
        f.write(header + "\n")
        for row in rows:
            f.write(",".join(str(x) for x in row) + "\n")

    # The next richer dissipation model: viscous damping on top of the friction.
    if not args.quick:
        summary["viscous_damping"] = {"damping": DAMPING_CHECK, "laws": {}}
        for law in (camjax.laws.Cycloidal(), camjax.laws.ModifiedSine()):
            _, metrics, failed = sweep(law, n, frictions, dwell, DAMPING_CHECK)
            summary["viscous_damping"]["laws"][law.name] = {
                "failed_at_friction": frictions[failed].tolist(),
                **{k: v.tolist() for k, v in metrics.items()},
            }

    # Regularisation error against stick-slip (Cycloidal, one friction level).
    law, mu = camjax.laws.Cycloidal(), 0.5
    exact = camjax.solve(law, CoulombFriction(n, mu), dwell=dwell, samples=SAMPLES)
    epsilons = np.logspace(-1, -5, 9)
    # eps is a static option of camjax.solve (one compilation per value); to sweep it in one
    # vmapped program, call the model's jittable solution with eps traced.
    model = CoulombFriction(n, mu)
    options = model.options("regularised", dwell, samples=SAMPLES)
    smooth = jax.jit(jax.vmap(lambda eps: model.response(law, dataclasses.replace(options, eps=eps))))(
        jnp.asarray(epsilons)
    )
    in_motion = exact.tau <= 1.0
    err_motion = np.asarray(jnp.max(jnp.where(in_motion, jnp.abs(smooth.position - exact.position), 0), axis=1))
    err_peak = np.abs(np.asarray(smooth.metrics.peak_in_motion) - float(exact.metrics.peak_in_motion))
    err_rest = np.abs(np.asarray(smooth.rest_offset) - float(exact.rest_offset))
    summary["regularisation"] = {
        "law": law.name,
        "friction": mu,
        "eps": epsilons.tolist(),
        "max_position_error_in_motion": err_motion.tolist(),
        "peak_in_motion_error": err_peak.tolist(),
        "rest_offset_error": err_rest.tolist(),
        "events_rest_offset": float(exact.rest_offset),
    }
    slope = np.polyfit(np.log(epsilons[3:]), np.log(err_motion[3:]), 1)[0]
    summary["regularisation"]["order_in_eps"] = float(slope)
    (OUT / "summary.json").write_text(json.dumps(summary, indent=1).replace('NaN', 'null'))

    # Figures.
    names = list(summary["laws"])
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for name in names:
        d = summary["laws"][name]
        axes[0].plot(frictions, d["residual_end"], label=name)
        axes[1].plot(frictions, d["peak_in_motion"], label=name)
        axes[2].plot(frictions, np.asarray(d["rest_offset"]) * 1e3, label=name)
    axes[2].fill_between(frictions, -frictions / w**2 * 1e3, frictions / w**2 * 1e3, color="0.9",
                         label="stick band $\\pm\\mu/w^2$")
    axes[0].set(xlabel="friction level $\\mu = F T^2/(W h)$", ylabel="residual |x''| / Ca",
                title=f"residual vibration after a {dwell:g}-period dwell (n = {n:g})")
    axes[1].set(xlabel="friction level $\\mu$", ylabel="peak |x''| in motion / Ca",
                title="in-motion peak (Ct over the rise)")
    axes[2].set(xlabel="friction level $\\mu$", ylabel="rest offset x - 1 (1e-3 stroke)",
                title="where the payload comes to rest")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "friction_sweep.png", dpi=120)

    fig, ax = plt.subplots(figsize=(9, 4.5))
    name = "cycloidal" if "cycloidal" in histories else names[0]
    batch = histories[name]
    tau = np.asarray(batch.tau[0])
    for i in np.linspace(0, len(frictions) - 1, 4).astype(int):
        ax.plot(tau, np.asarray(batch.payload_acceleration[i]) / float(camjax.laws.get(name).Ca),
                label=f"$\\mu$ = {frictions[i]:.2f}", lw=1)
    ax.plot(tau, np.asarray(camjax.laws.get(name).a(tau)) / float(camjax.laws.get(name).Ca), "k--",
            lw=0.8, label="command")
    ax.set(xlabel="tau", ylabel="x'' / Ca", title=f"{name}, n = {n:g}: friction stops the residual vibration")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT / "friction_history.png", dpi=120)

    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.loglog(epsilons, err_motion, "o-", label="max |x error| in motion")
    ax.loglog(epsilons, err_peak, "s-", label="in-motion peak error (/Ca)")
    ax.loglog(epsilons, err_rest, "^-", label="rest offset error")
    ax.set(xlabel="eps (velocity scale of tanh)", ylabel="error vs stick-slip",
           title=f"tanh regularisation, {law.name}, n = {n:g}, $\\mu$ = {mu:g}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(OUT / "regularisation_error.png", dpi=120)
    print(json.dumps(summary["regularisation"], indent=1))


if __name__ == "__main__":
    main()

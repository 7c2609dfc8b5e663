"""Backlash impact study: kinematic charts, dynamic vs kinematic, solver limits, low-impact design.

Writes results/backlash/:
  impact_velocity.png / .csv / .json - v against bk for several dn, every standard law
  dynamic_vs_kinematic.png / .csv    - first-impact velocity of the dead-zone SDOF over the
                                       kinematic estimate, against the period ratio n
  solver_limits.csv                  - steps and outcome of explicit/implicit solvers as the
                                       contact stiffens
  design.json                        - SCCA fractions optimised (optax) for low impact velocity
  summary.md                         - the numbers quoted in docs/backlash.md

Run: /work/venv/bin/python experiments/examples/backlash.py
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import matplotlib
import matplotlib.ticker
import numpy as np
import optax

import camjax
import camjax.models as bl

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

OUT = Path(__file__).resolve().parents[2] / "results" / "backlash"
BK = np.geomspace(1e-3, 1.0, 61)
DN = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
PERIOD_RATIOS = [3, 5, 7, 10, 14, 20, 28, 40, 56, 80]
DYNAMIC_CASES = [
    ("cycloidal", 0.02, 1.0),
    ("modified-sine", 0.02, 1.0),
    ("harmonic", 0.02, 1.0),
    ("modified-sine", 0.2, 0.0),
]


def kinematic_charts(summary: list[str]) -> None:
    names = [law.name for law in camjax.laws.standard_laws()]  # the classic seven
    fig, axes = plt.subplots(2, 4, figsize=(16, 7.5), sharex=True, sharey=True)
    rows, tables = [], {}
    for ax, name in zip(axes.flat, names, strict=False):
        law = camjax.laws.get(name)
        table = bl.kinematic_impact_table(law, BK, DN)
        v = np.asarray(table.impact_velocity)
        tables[name] = {
            "bk": BK,
            "dn": DN,
            "impact_velocity": v,
            "departure_tau": np.asarray(table.departure_tau),
            "impact_tau": np.asarray(table.impact_tau),
        }
        for d, row in zip(DN, v, strict=True):
            ax.plot(BK, row, label=f"dn = {d:g}")
            rows += [[name, d, b, x] for b, x in zip(BK, row, strict=True)]
        ax.set_title(f"{name} (Ca {float(law.Ca):.3g}, Cv {float(law.Cv):.3g})")
        ax.set_xscale("log")
        ax.grid(True, which="both", alpha=0.3)
    axes.flat[-1].axis("off")
    axes.flat[0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("normalised backlash bk")
    for ax in axes[:, 0]:
        ax.set_ylabel("normalised impact velocity v")
    fig.suptitle("Kinematic backlash impact velocity (gaps: no separation, or falls back)")
    fig.tight_layout()
    fig.savefig(OUT / "impact_velocity.png", dpi=110)
    plt.close(fig)
    with open(OUT / "impact_velocity.csv", "w", newline="") as f:
        csv.writer(f).writerows([["law", "dn", "bk", "impact_velocity"], *rows])
    from camjax.cli import dump_json

    dump_json({"laws": tables}, OUT / "impact_velocity.json")
    summary.append("## Kinematic impact velocity at bk = 0.01 (rows: law, columns: dn)\n")
    summary.append("| law | " + " | ".join(f"dn={d:g}" for d in DN) + " |")
    summary.append("|---" * (len(DN) + 1) + "|")
    for name in names:
        law = camjax.laws.get(name)
        t = bl.kinematic_impact_table(law, [0.01, 0.1], DN)
        cells = [f"{x:.3f}" if np.isfinite(x) else "-" for x in np.asarray(t.impact_velocity)[:, 0]]
        summary.append(f"| {name} | " + " | ".join(cells) + " |")
    summary.append("")


def dynamic_vs_kinematic(summary: list[str]) -> None:
    rows = []
    fig, ax = plt.subplots(figsize=(7, 4.5))
    summary.append(
        "## Dynamic (dead-zone SDOF, contact damping 0.05) over kinematic first-impact velocity\n"
    )
    summary.append(
        "| law | bk | dn | kinematic v | " + " | ".join(f"n={n}" for n in PERIOD_RATIOS) + " |"
    )
    summary.append("|---" * (len(PERIOD_RATIOS) + 4) + "|")
    for name, bk, dn in DYNAMIC_CASES:
        law = camjax.laws.get(name)
        kin = float(bl.kinematic_impact(law, bk, dn).impact_velocity)
        ratios = []
        for n in PERIOD_RATIOS:
            r = camjax.solve(law, bl.Backlash(float(n), bk, dn, 0.05), dwell=0.5)
            ratios.append(float(r.first_impact_velocity) / kin)
            rows.append([name, bk, dn, n, kin, float(r.first_impact_velocity), int(r.n_impacts)])
        ax.plot(PERIOD_RATIOS, ratios, "o-", label=f"{name}, bk={bk:g}, dn={dn:g}")
        summary.append(
            f"| {name} | {bk:g} | {dn:g} | {kin:.4f} | "
            + " | ".join(f"{x:.3f}" for x in ratios)
            + " |"
        )
    ax.axhspan(0.95, 1.05, color="0.9")
    ax.set_xscale("log")
    ax.set_xticks(PERIOD_RATIOS, [str(n) for n in PERIOD_RATIOS])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("period ratio n (transmission = contact stiffness)")
    ax.set_ylabel("dynamic / kinematic first-impact velocity")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(OUT / "dynamic_vs_kinematic.png", dpi=110)
    plt.close(fig)
    with open(OUT / "dynamic_vs_kinematic.csv", "w", newline="") as f:
        csv.writer(f).writerows(
            [["law", "bk", "dn", "n", "kinematic_v", "dynamic_v", "impacts"], *rows]
        )
    summary.append("")


def solver_limits(summary: list[str]) -> None:
    law = camjax.laws.ModifiedSine()
    rows = [
        ["method", "rtol", "atol", "n", "damping", "outcome", "first_impact_v", "steps", "segments"]
    ]
    settings = [("tsit5", 1e-9, 1e-12), ("kvaerno5", 1e-9, 1e-12), ("kvaerno5", 1e-8, 1e-8)]
    for method, rtol, atol in settings:
        for n in (80.0, 500.0, 2000.0, 20000.0, 2e5):
            try:
                r = camjax.solve(
                    law,
                    bl.Backlash(n, 0.02, 1.0, 0.5),
                    method=method,
                    max_step=None if method == "kvaerno5" else 0.125,  # stiff implicit: no cap
                    rtol=rtol,
                    atol=atol,
                    dwell=0.5,
                )
                rows.append(
                    [
                        method,
                        rtol,
                        atol,
                        n,
                        0.5,
                        "ok",
                        float(r.first_impact_velocity),
                        int(r.stats["steps"]),
                        int(r.stats["segments"]),
                    ]
                )
            except camjax.SolverError as error:
                rows.append(
                    [
                        method,
                        rtol,
                        atol,
                        n,
                        0.5,
                        "SolverError: " + str(error).split(":")[1][:60],
                        "",
                        "",
                        "",
                    ]
                )
    with open(OUT / "solver_limits.csv", "w", newline="") as f:
        csv.writer(f).writerows(rows)
    summary.append(
        "## Solver limits (ModSine, bk = 0.02, dn = 1, contact damping 0.5, dwell 0.5)\n"
    )
    summary.append("| method | rtol | atol | n | outcome | first-impact v | steps |")
    summary.append("|---|---|---|---|---|---|---|")
    for r in rows[1:]:
        v = f"{r[6]:.6f}" if r[6] != "" else ""
        summary.append(f"| {r[0]} | {r[1]:g} | {r[2]:g} | {r[3]:g} | {r[5]} | {v} | {r[7]} |")
    summary.append("")


def low_impact_design(summary: list[str]) -> None:
    """Minimise the impact velocity at (bk, dn) over SCCA fractions, holding Ca <= ModSine's."""
    bk, dn = 0.01, 1.0
    ca_limit = float(camjax.laws.ModifiedSine().Ca)

    def fractions(z):
        weights = jax.nn.softmax(jnp.append(z, 0.0))  # a, b, c, d >= 0 summing to 1
        return weights[:3]

    def objective(z):
        law = camjax.laws.SCCA(*fractions(z))
        v = bl.kinematic_impact(law, bk, dn).impact_velocity
        return v + 10.0 * jax.nn.relu(law.Ca - ca_limit) ** 2

    start = jnp.log(jnp.array([0.25, 1e-3, 0.75]) / 1e-3)  # near ModSine
    optimiser = optax.adam(0.05)
    state = optimiser.init(start)
    step = jax.jit(jax.value_and_grad(objective))
    z = start
    history = []
    for _ in range(150):
        value, grad = step(z)
        history.append(float(value))
        updates, state = optimiser.update(grad, state)
        z = optax.apply_updates(z, updates)
    best = camjax.laws.SCCA(*(float(x) for x in fractions(z)))
    results = {
        "bk": bk,
        "dn": dn,
        "ca_limit": ca_limit,
        "start": {"fractions": [float(x) for x in fractions(start)], "objective": history[0]},
        "modified-sine_v": float(
            bl.kinematic_impact(camjax.laws.ModifiedSine(), bk, dn).impact_velocity
        ),
        "harmonic_v": float(
            bl.kinematic_impact(camjax.laws.SimpleHarmonic(), bk, dn).impact_velocity
        ),
        "optimised": {
            "fractions": list(best.fractions),
            "Ca": float(best.Ca),
            "impact_velocity": float(bl.kinematic_impact(best, bk, dn).impact_velocity),
        },
    }
    (OUT / "design.json").write_text(json.dumps(results, indent=1) + "\n")
    summary.append("## Low-impact SCCA design (bk = 0.01, dn = 1, Ca <= ModSine's 5.528)\n")
    summary.append("```\n" + json.dumps(results, indent=1) + "\n```\n")


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    summary = ["# Backlash study (generated by experiments/examples/backlash.py)\n"]
    kinematic_charts(summary)
    dynamic_vs_kinematic(summary)
    solver_limits(summary)
    low_impact_design(summary)
    (OUT / "summary.md").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))


if __name__ == "__main__":
    main()

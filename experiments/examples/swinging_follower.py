"""The swinging roller-follower study: flexible rod, four laws, spectra, parameter effects.

    python experiments/examples/swinging_follower.py [--sets base,omega640,...] [--modes-study] [--sdof]

Writes results/swinging_follower/: profile.png, time_histories_<set>.png, spectra_<set>.png,
peaks.csv, peaks.md, summary.json (one entry per parameter set), modes.csv, sdof.csv.
The four laws of a set run in one vmapped solve (a LawBank picks the law by index).
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camjax  # noqa: E402
from camjax import geometry  # noqa: E402
from camjax.laws import (  # noqa: E402
    Cycloidal,
    LawBank,  # noqa: E402
    ModifiedSine,
    ModifiedTrapezoid,
    PolynomialLaw,
)
from camjax.models import SwingingFollower, spectral_peaks, spectrum  # noqa: E402

OUT = Path("results/swinging_follower")
LAWS = (Cycloidal(), ModifiedSine(), ModifiedTrapezoid(), PolynomialLaw(3))
LABELS = ("cycloidal", "modified sine", "modified trapezoid", "3-4-5")
SETS = {
    "base": {},
    "omega640": {"omega": 640.0},
    "length118": {"length": 0.118},
    "radius6": {"rod_radius": 0.006},
    "radius10": {"rod_radius": 0.010},
    "roller10g": {"roller_mass": 0.010},
    "roller100g": {"roller_mass": 0.100},
    "rise_pi12": {"total_swing": math.pi / 12},
}
# Every set passes these as arrays, so all sets share one compiled, vmapped solve.
VARIED = ("omega", "length", "rod_radius", "roller_mass", "total_swing")
TURNS, PER_TURN = 3, 512


@functools.partial(jax.jit, static_argnames="modes")
def _four_laws(params, modes):
    def one(index):
        bank = LawBank(LAWS, index)
        return camjax.solve(None, SwingingFollower(rise=bank, fall=bank, modes=modes, **params), turns=TURNS, samples_per_turn=PER_TURN, throw=False)

    return jax.vmap(one)(jnp.arange(len(LAWS)))


def run_set(name: str, modes: int = 3):
    """All four laws for one parameter set, in one vmapped solve (compiled once for all sets)."""
    base = SwingingFollower(modes=modes, **SETS[name])
    params = {key: jnp.asarray(getattr(base, key), dtype=float) for key in VARIED}
    start = time.perf_counter()
    responses = jax.block_until_ready(_four_laws(params, modes))
    seconds = time.perf_counter() - start
    if not bool(jnp.all(responses.result == camjax.RESULTS.successful)):
        raise camjax.SolverError(f"set {name}: a solve failed")
    return base, responses, seconds


def peaks_of(signal_mm, natural_order):
    harmonics, near = spectral_peaks(spectrum(signal_mm, TURNS), natural_order)
    return harmonics, near


_compiled = []


def study_set(name, rows, summary):
    model, responses, seconds = run_set(name)
    natural = float(model.fundamental_frequency())
    order = natural / float(model.omega)
    angle = np.degrees(np.asarray(responses.cam_angle[0]))
    fig, axes = plt.subplots(4, 2, figsize=(11, 9), sharex=True)
    sfig, saxes = plt.subplots(4, 2, figsize=(11, 9), sharex=True)
    entry = {"natural_frequency_rad_s": natural, "natural_order": order, "seconds_vmapped_4_laws": seconds, "laws": {}}
    entry["seconds_include_compile"] = not _compiled
    _compiled.append(name)
    for k, label in enumerate(LABELS):
        v = np.asarray(responses.transverse[k]) * 1e3
        u = np.asarray(responses.axial_end[k]) * 1e3
        axes[k, 0].plot(angle, v, lw=0.7)
        axes[k, 1].plot(angle, u, lw=0.7, color="C1")
        axes[k, 0].set_ylabel(f"{label}\nv (mm)")
        axes[k, 1].set_ylabel("u_end (mm)")
        for col, signal in enumerate((v, u)):
            spec = spectrum(signal, TURNS)
            saxes[k, col].semilogy(spec.order[1:], spec.amplitude[1:] + 1e-12, lw=0.7, color=f"C{col}")
            saxes[k, col].set_xlim(0, 60)
            saxes[k, col].axvline(order, color="k", lw=0.5, ls=":")
        saxes[k, 0].set_ylabel(f"{label}\n|V| (mm)")
        saxes[k, 1].set_ylabel("|U| (mm)")
        t_h, t_near = peaks_of(v, order)
        a_h, a_near = peaks_of(u, order)
        entry["laws"][label] = {
            "transverse_peaks": [{"order": o, "amplitude_mm": a} for o, a in t_h + [t_near]],
            "axial_peaks": [{"order": o, "amplitude_mm": a} for o, a in a_h + [a_near]],
            "max_transverse_mm": float(np.max(np.abs(v))),
            "max_axial_mm": float(np.max(np.abs(u))),
            "max_constraint_error_m": float(responses.max_constraint_error[k]),
            "steps": int(responses.stats["steps"][k]),
        }
        rows.append(
            [name, label, natural, *(a for _, a in t_h[:3]), t_near[0], t_near[1], *(a for _, a in a_h[:3]), a_near[1]]
        )
    axes[-1, 0].set_xlabel("cam angle Omega t (deg)")
    axes[-1, 1].set_xlabel("cam angle Omega t (deg)")
    saxes[-1, 0].set_xlabel("frequency (x Omega)")
    saxes[-1, 1].set_xlabel("frequency (x Omega)")
    fig.suptitle(f"{name}: transverse v at mid-rod and axial u at the roller end, three turns")
    sfig.suptitle(f"{name}: FFT spectra (dotted: fundamental {order:.1f} Omega)")
    fig.tight_layout()
    sfig.tight_layout()
    fig.savefig(OUT / f"time_histories_{name}.png", dpi=110)
    sfig.savefig(OUT / f"spectra_{name}.png", dpi=110)
    plt.close("all")
    summary[name] = entry
    note = " (incl. compile)" if entry["seconds_include_compile"] else ""
    print(f"{name}: {seconds:.1f} s{note} for four laws (vmapped), fundamental {natural:.0f} rad/s = {order:.2f} Omega")


def modes_study():
    """Cycloidal, base set, N = 1..5: where the answer stops changing."""
    rows = []
    for modes in range(1, 6):
        model = SwingingFollower(modes=modes)
        start = time.perf_counter()
        response = camjax.solve(None, model, turns=TURNS, samples_per_turn=PER_TURN)
        seconds = time.perf_counter() - start
        v = np.asarray(response.transverse) * 1e3
        u = np.asarray(response.axial_end) * 1e3
        natural = float(model.fundamental_frequency()) if modes > 1 else float("nan")
        order = natural / model.omega if modes > 1 else 41.5
        t_h, t_near = peaks_of(v, order)
        a_h, _ = peaks_of(u, order)
        rows.append([modes, natural, float(np.max(np.abs(v))), float(np.max(np.abs(u))), *(a for _, a in t_h[:3]), t_near[1], *(a for _, a in a_h[:3]), int(response.stats["steps"]), seconds])
        print(f"N={modes}: max|v| {rows[-1][2]:.5f} mm, max|u| {rows[-1][3]:.2e} mm, {seconds:.1f} s (incl. compile)")
        header = "modes,natural_rad_s,max_v_mm,max_u_mm,v1,v3,v5,v_near_natural,u1,u3,u5,steps,seconds_incl_compile"
        np.savetxt(OUT / "modes.csv", np.array(rows, dtype=float), delimiter=",", header=header, comments="", fmt="%.6g")


def sdof_comparison(summary):
    """Residual vibration in the dwell after the first rise: full model against the SDOF closed form.

    Mode 1 of the rod obeys b'' + w^2 b = -Gamma psi'' with Gamma = 2 l / pi (x/l against sin(pi x/l)),
    so its residual amplitude at mid-rod is Gamma * phi_T * |int s' e^(-i w u) du| = Gamma phi_T R Ca / w^2
    (MISSION.md), with n = T f, T = (pi/2) / Omega.
    """
    model = SwingingFollower(modes=3)
    rows = []
    for law, label in zip(LAWS, LABELS):
        response = camjax.solve(law, model, turns=1, samples_per_turn=PER_TURN)
        angle = np.degrees(np.asarray(response.cam_angle))
        dwell = (angle > 95) & (angle < 175)
        full = float(np.max(np.abs(np.asarray(response.transverse)[dwell]))) * 1e3
        natural = float(model.fundamental_frequency())
        n = (math.pi / 2) / model.omega * natural / (2 * math.pi)
        w = 2 * math.pi * n
        residual = float(camjax.residual_vibration(law, n, 0.0))
        sdof = 2 * model.length / math.pi * model.total_swing * residual * float(law.Ca) / w**2 * 1e3
        rows.append((label, n, full, sdof))
        print(f"{label}: dwell residual full {full:.3e} mm, SDOF {sdof:.3e} mm (n = {n:.2f})")
    with open(OUT / "sdof.csv", "w") as fh:
        fh.write("law,period_ratio,full_model_residual_mm,sdof_residual_mm\n")
        for row in rows:
            fh.write(f"{row[0]},{row[1]:.4f},{row[2]:.6e},{row[3]:.6e}\n")
    summary["sdof_residual"] = {r[0]: {"period_ratio": r[1], "full_mm": r[2], "sdof_mm": r[3]} for r in rows}


def profile_figure():
    model = SwingingFollower()
    theta = jnp.linspace(0, 2 * math.pi, 721)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.5))
    for law, label in zip(LAWS, LABELS):
        program = eqx.tree_at(lambda p: (p.rise, p.fall), model.program, (law, law))
        prof = geometry.cam_profile(model.follower, program, theta)
        if label == "cycloidal":
            for curve, style in ((prof.pitch, "k--"), (prof.inner, "C0"), (prof.outer, "C0")):
                axes[0].plot(curve[:, 0] * 1e3, curve[:, 1] * 1e3, style, lw=0.8)
        axes[1].plot(np.degrees(theta), np.degrees(prof.pressure_angle), label=label, lw=0.8)
        axes[2].plot(np.degrees(theta), prof.inner_radius_of_curvature * 1e3, label=label, lw=0.8)
    axes[0].set_aspect("equal")
    axes[0].set_title("cycloidal groove: pitch curve (dashed), flanks")
    axes[0].set_xlabel("x (mm)")
    axes[1].set_title("pressure angle (deg)")
    axes[2].set_title("inner-flank radius of curvature (mm)")
    axes[2].set_ylim(0, 100)
    for ax in axes[1:]:
        ax.set_xlabel("cam angle (deg)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "profile.png", dpi=110)
    plt.close(fig)


def write_tables():
    """peaks.md: one markdown table of peaks.csv (amplitudes in mm)."""
    lines = (OUT / "peaks.csv").read_text().splitlines()
    out = [
        "| set | law | fundamental (rad/s) | v 1 Omega | v 3 Omega | v 5 Omega | v near fund. (order) | u 1 Omega | u 3 Omega | u 5 Omega | u near fund. |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for line in lines[1:]:
        f = line.split(",")
        num = [float(x) for x in f[2:]]
        cells = [f[0], f[1], f"{num[0]:.0f}", *(f"{x:.2e}" for x in num[1:4]), f"{num[5]:.2e} ({num[4]:.1f})", *(f"{x:.2e}" for x in num[6:])]
        out.append("| " + " | ".join(cells) + " |")
    (OUT / "peaks.md").write_text("\n".join(out) + "\n")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sets", default="base", help="comma-separated names from " + ",".join(SETS))
    parser.add_argument("--modes-study", action="store_true")
    parser.add_argument("--sdof", action="store_true")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    summary = {}
    profile_figure()
    rows = []
    names = [name for name in args.sets.split(",") if name]
    for name in names:
        study_set(name, rows, summary)
    header = "set,law,natural_rad_s,v_1,v_3,v_5,v_near_order,v_near,u_1,u_3,u_5,u_near"
    csv = OUT / "peaks.csv"
    old_lines = csv.read_text().splitlines()[1:] if csv.exists() else []
    old = [line for line in old_lines if line.split(",")[0] not in names]
    new = [",".join([r[0], r[1]] + [f"{x:.6g}" for x in r[2:]]) for r in rows]
    if new:
        csv.write_text("\n".join([header] + old + new) + "\n")
    if (OUT / "peaks.csv").exists():
        write_tables()
    if args.modes_study:
        modes_study()
    if args.sdof:
        sdof_comparison(summary)
    summary_path = OUT / "summary.json"  # merged at the end, so runs of different sets combine
    merged = json.loads(summary_path.read_text()) if summary_path.exists() else {}
    summary_path.write_text(json.dumps(merged | summary, indent=1) + "\n")


if __name__ == "__main__":
    main()

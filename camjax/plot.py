"""Matplotlib figures, one function per kind.  Each returns the Figure it drew."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .metrics import fit_torsion_factor  # noqa: E402


def _curve_axes(title: str, ylabel: str):
    fig, ax = plt.subplots(figsize=(8, 4.8), constrained_layout=True)
    ax.set_xlabel("period ratio n = T f")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    return fig, ax


def ct_curves(curves: dict) -> plt.Figure:
    """Torsion factor Ct against period ratio, one line per law."""
    fig, ax = _curve_axes("Torsion factor (peak payload acceleration / Ca)", "Ct")
    for name, c in curves.items():
        ax.plot(c.period_ratio, c.ct, lw=1.1, label=name)
    ax.axhline(1.0, color="k", lw=0.6)
    ax.legend(ncol=2, fontsize=8)
    return fig


def residual_curves(curves: dict) -> plt.Figure:
    """Residual vibration R (units of Ca) against period ratio, log scale."""
    fig, ax = _curve_axes("Residual vibration in the dwell (units of Ca)", "R")
    for name, c in curves.items():
        ax.semilogy(c.period_ratio, np.maximum(c.residual, 1e-6), lw=1.0, label=name)
    ax.set_ylim(1e-4, None)
    ax.legend(ncol=2, fontsize=8)
    return fig


def best_law_switches(curves: dict, fits: dict) -> list[tuple[float, str, str]]:
    """Where the law with the lowest fitted Ca*Ct envelope changes: ``(n, from, to)``."""
    names = [k for k in curves if k in fits]
    if not names:
        return []
    n = np.linspace(
        max(curves[k].period_ratio.min() for k in names),
        min(curves[k].period_ratio.max() for k in names),
        4001,
    )
    loads = np.array([curves[k].ca * fits[k](n) for k in names])
    best = np.argmin(loads, axis=0)
    changes = np.nonzero(best[1:] != best[:-1])[0]
    return [(float(n[i]), names[best[i]], names[best[i + 1]]) for i in changes]


def ca_ct_chart(curves: dict, fits: dict | None = None) -> plt.Figure:
    """Peak inertia load Ca*Ct (units of h/T^2), with fitted envelopes and the n where
    the best law (lowest envelope) changes."""
    if fits is None:
        fits = {k: fit_torsion_factor(c) for k, c in curves.items()}
    fig, ax = _curve_axes("Peak inertia load Ca*Ct (units of h/T^2)", "Ca * Ct")
    for i, (name, c) in enumerate(curves.items()):
        color = f"C{i % 10}"
        ax.plot(c.period_ratio, c.ca_ct, lw=0.7, alpha=0.45, color=color)
        if name in fits:
            ax.plot(c.period_ratio, c.ca * fits[name](c.period_ratio), lw=2, color=color, label=name)
    for n, _, to in best_law_switches(curves, fits):
        ax.axvline(n, color="k", ls="--", lw=0.8)
        ax.annotate(f"n={n:.2f}: {to}", (n, ax.get_ylim()[1]), rotation=90, va="top",
                    ha="right", fontsize=7)
    ax.legend(ncol=2, fontsize=8, title="fitted envelope Ca(p/n^q + r)", title_fontsize=8)
    return fig


def response(result, title: str = "") -> plt.Figure:
    """Command and payload acceleration of one ``Response`` over the rise and dwell."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    ax.plot(result.tau, result.command_acceleration, color="k", lw=1.2, label="command s''")
    ax.plot(result.tau, result.payload_acceleration, color="C3", lw=1.0, label="payload x''")
    ax.axvline(1.0, color="0.5", lw=0.6)
    ax.set_xlabel("tau = t / T")
    ax.set_ylabel("acceleration (units of h/T^2)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def law_curves(laws: list, samples: int = 2001) -> plt.Figure:
    """s, v, a, j of one or more motion laws over the rise."""
    tau = np.linspace(0.0, 1.0, samples)
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True, constrained_layout=True)
    for law in laws:
        values = law.evaluate(tau)
        for ax, label, y in zip(axes.flat, ("s", "v", "a", "j"), values):
            ax.plot(tau, np.asarray(y), lw=1.1, label=law.name)
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("tau")
    axes[0, 0].legend(fontsize=8)
    return fig


def save(fig: plt.Figure, path) -> None:
    """Write a figure as PNG and close it."""
    fig.savefig(path, dpi=130)
    plt.close(fig)

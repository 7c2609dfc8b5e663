"""Matplotlib figures, one function per kind.  Each returns the Figure it drew.

Every figure says the conditions it was computed under (model, damping, dwell) and labels
normalised quantities with their units (Ct and R in units of the law's Ca, Ca*Ct in units
of h/T^2, tau = t/T).

The module leaves matplotlib's backend alone: without a display matplotlib draws with Agg,
and in a notebook the figures show inline.
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FuncFormatter, NullLocator

from .metrics import best_law_switches, fit_torsion_factor

PERIOD_RATIO_LABEL = "period ratio n = T f (motion period / natural period)"
R_FLOOR = 1e-6
"""Residuals below this are drawn at it (log axes cannot show zeros)."""


def _conditions(curves: dict, dwell: float | None) -> str:
    """One line naming the model, damping and dwell the curves were computed under."""
    dampings = sorted({float(c.damping) for c in curves.values()})
    zeta = ", ".join(f"{z:g}" for z in dampings)
    model = "undamped SDOF (zeta = 0)" if dampings == [0.0] else f"SDOF, damping zeta = {zeta}"
    text = model
    if dwell is not None:
        text += f"; dwell of {dwell:g} motion period{'s' if dwell != 1 else ''} after the rise"
    return text


_SUPERSCRIPT = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")


def _decade_label(value: float, _position=None) -> str:
    """``10⁻³`` in plain Unicode: matplotlib's own log labels are mathtext, whose parser
    took a quarter of a second to build in every process that drew one."""
    if not value > 0:
        return ""
    exponent = math.log10(value)
    if abs(exponent - round(exponent)) > 1e-9:
        return f"{value:g}"
    return "10" + str(round(exponent)).translate(_SUPERSCRIPT)


def _log_y(ax) -> None:
    """A log y axis labelled at decades only (minor log ticks halve the drawing speed)."""
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(_decade_label))
    ax.yaxis.set_minor_locator(NullLocator())


def _curve_figure(title: str, subtitle: str, ylabel: str, figsize=(10, 5), legend_width=1.8):
    """One axes with fixed margins (inches) and ``legend_width`` inches on the right for
    legends (``_legend_beside``): a layout engine measured every label and took about a
    third of the figure's time."""
    fig, ax = plt.subplots(figsize=figsize)
    width, height = figsize
    fig.subplots_adjust(left=0.75 / width, right=1 - (legend_width + 0.15) / width,
                        bottom=0.6 / height, top=1 - 0.7 / height)
    ax.set_xlabel(PERIOD_RATIO_LABEL)
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title}\n{subtitle}", fontsize=10)
    ax.grid(True, alpha=0.3)
    return fig, ax


def _legend_beside(fig, ax, corner: str = "upper", **kwargs):
    """A figure legend in the right margin, level with the top or bottom of ``ax``."""
    box = ax.get_position()
    y = box.y1 if corner == "upper" else box.y0
    return fig.legend(loc=f"{corner} left", bbox_to_anchor=(box.x1 + 0.01, y), **kwargs)


def ct_curves(curves: dict, *, dwell: float = 1.0) -> plt.Figure:
    """Torsion factor Ct against period ratio, one line per law.

    Args:
        curves: ``CtCurve`` per law name (as ``camjax.ct_curves`` returns).
        dwell: the dwell, in motion periods, over which Ct's peak was taken (stated on
            the figure).
    """
    fig, ax = _curve_figure("Torsion factor Ct = peak payload acceleration / Ca",
                            _conditions(curves, dwell), "Ct (units of Ca)")
    for name, c in curves.items():
        ax.plot(c.period_ratio, c.ct, lw=1.1, label=name)
    ax.axhline(1.0, color="k", lw=0.6)
    _legend_beside(fig, ax, fontsize=8, title="law", title_fontsize=8)
    return fig


def residual_curves(curves: dict, *, ncols: int = 2) -> plt.Figure:
    """Residual vibration R (units of Ca, log scale) against period ratio, one panel per law.

    One panel per law keeps seven laws legible: their zeros interleave, and on one axis
    the lines hide each other.  All panels share both axes, so heights compare directly;
    a grey line in every panel is the largest R of any law at each n.
    """
    names = list(curves)
    ncols = min(ncols, len(names))
    nrows = math.ceil(len(names) / ncols)
    width, height = 5 * ncols, 1.9 * nrows + 1.0
    fig, axes = plt.subplots(nrows, ncols, figsize=(width, height), sharex=True, sharey=True,
                             squeeze=False)
    # Fixed margins (inches) rather than a layout engine: constrained layout redrew the
    # panels' log ticks several times and took half of this figure's time.
    fig.subplots_adjust(left=0.8 / width, right=1 - 0.15 / width, bottom=0.55 / height,
                        top=1 - 0.75 / height, wspace=0.06, hspace=0.32)
    worst = np.max([np.maximum(c.residual, R_FLOOR) for c in curves.values()], axis=0) \
        if _same_ratios(curves) else None
    for i, (ax, name) in enumerate(zip(axes.flat, names)):
        c = curves[name]
        if worst is not None and len(names) > 1:
            ax.semilogy(c.period_ratio, worst, color="0.8", lw=0.8)
        ax.semilogy(c.period_ratio, np.maximum(c.residual, R_FLOOR), color=f"C{i % 10}", lw=1.0)
        ax.set_ylim(1e-4, None)
        _log_y(ax)
        ax.set_title(name, fontsize=9, loc="left")
        ax.grid(True, alpha=0.3)
    for ax in axes.flat[len(names):]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("R (units of Ca)")
    for column in range(ncols):  # the lowest panel of each column carries the n axis
        ax = axes[(len(names) - 1 - column) // ncols, column]
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(PERIOD_RATIO_LABEL if ncols == 1 else "period ratio n = T f")
    note = "; grey: the largest R of any law" if worst is not None and len(names) > 1 else ""
    fig.suptitle("Residual vibration in the dwell, units of Ca\n"
                 f"{_conditions(curves, None)}{note}", fontsize=10)
    return fig


def _same_ratios(curves: dict) -> bool:
    ratios = [c.period_ratio for c in curves.values()]
    return all(r.shape == ratios[0].shape and np.array_equal(r, ratios[0]) for r in ratios)


def ca_ct_chart(curves: dict, fits: dict | None = None, *, dwell: float = 1.0) -> plt.Figure:
    """Peak inertia load Ca*Ct (units of h/T^2), with fitted envelopes and the n where
    the best law (lowest envelope) changes.

    The switches are numbered on the chart and listed beside it, each naming the law
    that was best and the law that takes over, so close switches never overlap.
    """
    if fits is None:
        fits = {k: fit_torsion_factor(c) for k, c in curves.items()}
    fig, ax = _curve_figure("Peak inertia load Ca*Ct (units of h/T^2): raw curves thin, "
                            "fitted envelopes Ca(p/n^q + r) thick",
                            _conditions(curves, dwell), "Ca * Ct (units of h/T^2)",
                            figsize=(11, 5.5), legend_width=2.3)
    for i, (name, c) in enumerate(curves.items()):
        color = f"C{i % 10}"
        ax.plot(c.period_ratio, c.ca_ct, lw=0.7, alpha=0.45, color=color)
        if name in fits:
            ax.plot(c.period_ratio, c.ca * fits[name](c.period_ratio), lw=2, color=color,
                    label=name)
    switches = best_law_switches(curves, fits)
    top = ax.get_ylim()[1]
    for k, (n, _, _) in enumerate(switches, start=1):
        ax.axvline(n, color="k", ls="--", lw=0.8)
        # Cycle three heights so neighbouring numbers stay apart.
        y = top * (0.97, 0.91, 0.85)[(k - 1) % 3]
        ax.annotate(str(k), (n, y), ha="center", va="center", fontsize=7,
                    bbox=dict(boxstyle="circle,pad=0.2", fc="white", ec="k", lw=0.6))
    _legend_beside(fig, ax, fontsize=8, title="fitted envelope", title_fontsize=8)
    if switches:
        lines = ["lowest envelope changes:"]
        lines += [f"{k}: n = {n:.2f}\n   {old} \u2192 {new}"
                  for k, (n, old, new) in enumerate(switches, start=1)]
        _legend_beside(fig, ax, "lower", handles=[], title="\n".join(lines), title_fontsize=7,
                       frameon=True, alignment="left")
    return fig


def response(result, title: str = "") -> plt.Figure:
    """Command and payload acceleration of one ``Response`` over the rise and dwell."""
    fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    ax.plot(result.tau, result.command_acceleration, color="k", lw=1.2, label="command s''")
    ax.plot(result.tau, result.payload_acceleration, color="C3", lw=1.0, label="payload x''")
    ax.axvline(1.0, color="0.5", lw=0.6)
    ax.set_xlabel("normalised time tau = t / T (rise, then dwell)")
    ax.set_ylabel("acceleration (units of h/T^2)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


LAW_AXES = (("s", "units of h"), ("v = ds/dtau", "units of h/T"),
            ("a = d2s/dtau2", "units of h/T^2"), ("j = d3s/dtau3", "units of h/T^3"))


def law_curves(laws: list, samples: int = 2001, *, title: str = "",
               highlight: str | None = None, values: list | None = None) -> plt.Figure:
    """s, v, a, j of one or more motion laws over the rise, in normalised units.

    Args:
        laws: the laws to draw.
        samples: points over ``tau`` in [0, 1].
        title: the figure's title.
        highlight: the name of a law to draw thick and black (e.g. a designed law).
        values: each law's ``(s, v, a, j)`` at the samples, where the caller has them
            already (each law is evaluated here otherwise).
    """
    tau = np.linspace(0.0, 1.0, samples)
    fig, axes = plt.subplots(2, 2, figsize=(10, 6), sharex=True, layout="constrained")
    for i, law in enumerate(laws):
        values_of_law = law.evaluate(tau) if values is None else values[i]
        style = dict(lw=2.2, color="k") if law.name == highlight else dict(lw=1.1)
        for ax, (label, unit), y in zip(axes.flat, LAW_AXES, values_of_law):
            ax.plot(tau, np.asarray(y), label=law.name, **style)
            ax.set_ylabel(f"{label} ({unit})")
            ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("normalised time tau = t / T")
    if len(laws) > 1:
        fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside right upper",
                   fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def design_comparison(period_ratios, curves: dict, *, title: str) -> plt.Figure:
    """Residual R and Ca*Ct of a designed law beside the standard laws over a band.

    Args:
        period_ratios: the band's period ratios.
        curves: ``(R, Ca*Ct)`` arrays per law name; the law named ``"designed"`` is drawn
            thick and black.
        title: the objective, caps and damping of the design (the figure's title).
    """
    fig, (ax_r, ax_c) = plt.subplots(1, 2, figsize=(12, 4.8), layout="constrained")
    for i, (name, (r, load)) in enumerate(curves.items()):
        style = dict(lw=2.2, color="k") if name == "designed" else dict(lw=1, color=f"C{i % 10}")
        ax_r.semilogy(period_ratios, np.maximum(r, R_FLOOR), label=name, **style)
        ax_c.plot(period_ratios, load, **style)
    _log_y(ax_r)
    ax_r.set(xlabel="period ratio n = T f", ylabel="residual R (units of Ca)",
             title="residual vibration in the dwell")
    ax_c.set(xlabel="period ratio n = T f", ylabel="Ca*Ct (units of h/T^2)",
             title="peak inertia load")
    for ax in (ax_r, ax_c):
        ax.grid(alpha=0.3)
    fig.legend(loc="outside right upper", fontsize=8, title="law", title_fontsize=8)
    fig.suptitle(title, fontsize=10)
    return fig


def save(fig: plt.Figure, path) -> None:
    """Write a figure as PNG and close it."""
    fig.savefig(path, dpi=130, pil_kwargs={"compress_level": 1})  # zlib level 1: a third of level 6's time, 10% larger
    plt.close(fig)

"""Figures state their conditions, keep legends off the data and labels apart."""

import numpy as np
import pytest

from camjax import plot
from camjax.cli.design import design_title
from camjax.law_design import Caps
from camjax.metrics import best_law_switches
from camjax.sweep import CtCurve

N = np.linspace(1.0, 30.0, 300)


def _curve(name, ca, p, q, r, damping=0.0):
    """A synthetic Ct curve: the envelope p/n^q + r with a ripple under it."""
    ct = (p / N**q + r) * (1 - 0.05 * np.sin(np.pi * N) ** 2)
    residual = np.abs(np.sin(np.pi * N)) / N
    return CtCurve(period_ratio=N, ct=ct, residual=residual, peak_in_motion=ct, ca=ca,
                   name=name, damping=damping)


# (Ca, p, q, r) of the standard laws' fitted envelopes Ct = p/n^q + r (undamped SDOF,
# n in [1, 30]): their lowest Ca*Ct changes law three times between n = 2.5 and 3.1.
ENVELOPES = {
    "cycloidal": (6.2832, 2.745, 1.553, 1.026),
    "modified-sine": (5.5280, 2.145, 0.967, 1.000),
    "modified-trapezoid": (4.8881, 3.460, 1.035, 1.000),
    "harmonic": (4.9348, 0.665, 2.299, 2.001),
    "parabolic": (4.0000, 0.002, 0.050, 3.998),
    "poly345": (5.7735, 2.394, 1.201, 1.019),
    "poly4567": (7.5132, 3.490, 1.914, 1.000),
}


def _envelope(p, q, r):
    return lambda n: p / np.asarray(n) ** q + r


@pytest.fixture
def curves():
    return {k: _curve(k, *v, damping=0.02) for k, v in ENVELOPES.items()}


@pytest.fixture
def fits():
    return {k: _envelope(*v[1:]) for k, v in ENVELOPES.items()}


def _texts(fig):
    out = [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_title(), *(t.get_text() for t in ax.texts)]
    for legend in fig.legends:
        out.append(legend.get_title().get_text())
    return "\n".join(out)


def _render(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def test_ct_figure_states_damping_and_dwell_and_keeps_the_legend_off_the_axes(curves):
    fig = plot.ct_curves(curves, dwell=2.0)
    text = _texts(fig)
    assert "zeta = 0.02" in text and "dwell of 2 motion periods" in text
    renderer = _render(fig)
    (ax,) = fig.axes
    legend = fig.legends[0].get_window_extent(renderer)
    assert legend.x0 >= ax.get_window_extent(renderer).x1
    assert len(fig.legends[0].get_texts()) == len(curves)


def test_undamped_curves_say_so(curves):
    undamped = {"a": _curve("a", 4.0, 3.0, 1.0, 1.0)}
    assert "undamped SDOF (zeta = 0)" in _texts(plot.ct_curves(undamped))


def test_residual_figure_has_one_panel_per_law(curves):
    fig = plot.residual_curves(curves)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title(loc="left") for ax in visible] == list(curves)
    assert all(ax.get_yscale() == "log" for ax in visible)


def test_ca_ct_switch_labels_name_both_laws_and_do_not_overlap(curves, fits):
    switches = best_law_switches(curves, fits)
    assert sum(2.5 < n < 3.1 for n, _, _ in switches) == 3
    fig = plot.ca_ct_chart(curves, fits, dwell=1.0)
    listing = fig.legends[-1].get_title().get_text()
    for k, (n, old, new) in enumerate(switches, start=1):
        assert f"{k}: n = {n:.2f}\n   {old} \u2192 {new}" in listing
    renderer = _render(fig)
    (ax,) = fig.axes
    boxes = [t.get_window_extent(renderer) for t in ax.texts]
    assert len(boxes) == len(switches)
    for i, first in enumerate(boxes):
        for second in boxes[i + 1:]:
            assert not first.overlaps(second)


def test_design_title_names_objective_and_caps():
    title = design_title("max R over [6, 12]", Caps(7.5, 100.0), 0.0)
    assert "minimise max R over [6, 12]" in title
    assert "Ca <= 7.5" in title and "Cj <= 100" in title and "zeta = 0" in title
    assert "Cj free" in design_title("R(n=8)", Caps(7.5), 0.0)


def test_design_comparison_has_one_legend(curves):
    ratios = np.linspace(6, 12, 50)
    data = {"designed": (np.full(50, 1e-3), np.full(50, 7.0)),
            "cycloidal": (np.full(50, 0.1), np.full(50, 7.5))}
    fig = plot.design_comparison(ratios, data, title="t")
    assert len(fig.legends) == 1 and all(ax.get_legend() is None for ax in fig.axes)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["designed", "cycloidal"]

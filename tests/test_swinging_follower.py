"""Flexible swinging follower: beam frequencies, quasi-static deflection, constraints, spectra."""

import math

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import camjax
from camjax.models.swinging_follower import SwingingFollower, simulate, spectral_peaks, spectrum


def pinned_pinned_rayleigh(model, k):
    """Closed-form k-th bending frequency of a pinned-pinned Rayleigh beam (rad/s)."""
    E, rho, A, I, l = model.youngs_modulus, model.density, model.area, model.second_moment, model.length
    wave = k * math.pi / l
    return math.sqrt(E * I * wave**4 / (rho * A * (1 + I / A * wave**2)))


@pytest.mark.parametrize("radius", [0.005, 0.010])
def test_bending_frequencies_match_pinned_pinned_rayleigh_beam(radius):
    model = SwingingFollower(modes=4, rod_radius=radius)
    freqs = np.asarray(model.natural_frequencies())
    assert freqs[0] == pytest.approx(pinned_pinned_rayleigh(model, 1), rel=1e-9)
    for k in (1, 2, 3):
        assert np.min(np.abs(freqs / pinned_pinned_rayleigh(model, k) - 1)) < 1e-9
    # The paper's spectral peak near the fundamental sits at about 41.5 Omega for l = 98 mm, r = 5 mm.
    if radius == 0.005:
        assert freqs[0] / model.omega == pytest.approx(41.5, abs=0.2)


def test_axial_frequency_converges_to_rod_with_end_mass():
    # At the low dwell the groove is tangent to the rod: the end slides axially, carrying the
    # roller mass plus its rolling inertia J_r / r_r^2 = m_r / 2.  Exact: z tan z = m_rod / m_end.
    model = SwingingFollower(modes=10)
    end_mass = 1.5 * model.roller_mass
    rod_mass = model.density * model.area * model.length
    z = brentq(lambda z: z * math.tan(z) - rod_mass / end_mass, 1e-6, math.pi / 2 - 1e-9)
    exact = z / model.length * math.sqrt(model.youngs_modulus / model.density)
    freqs = np.asarray(model.natural_frequencies())
    assert np.min(np.abs(freqs / exact - 1)) < 1e-4


@pytest.mark.slow
def test_quasi_static_rigid_limit_and_constraints():
    nominal = SwingingFollower(modes=3)
    stiff = SwingingFollower(modes=3, youngs_modulus=100 * nominal.youngs_modulus)
    turns = 0.2  # inside the 90-degree rise
    soft_run = simulate(nominal, turns=turns, samples_per_turn=360)
    stiff_run = simulate(stiff, turns=turns, samples_per_turn=360)
    # Rigid-rod limit: deflections scale with 1/E once the rod is far stiffer than the forcing.
    assert float(jnp.max(jnp.abs(stiff_run.transverse))) < 0.015 * float(jnp.max(jnp.abs(soft_run.transverse)))
    assert float(jnp.max(jnp.abs(stiff_run.axial_end))) < 0.015 * float(jnp.max(jnp.abs(soft_run.axial_end)))
    # Quasi-static check against the closed-form pinned-pinned beam under the triangular inertia
    # load q(x) = -rho A psi'' x (the uniform rotary-inertia moment bends nothing).  What remains
    # is the free vibration started at theta = 0 (about 2% of the static value at 100 E).
    theta = np.asarray(stiff_run.cam_angle)
    _, _, d2y, _ = stiff.program.evaluate(theta)
    psi_ddot = -(stiff.omega**2) * np.asarray(d2y)
    l, x = stiff.length, 0.5 * stiff.length
    E, I = stiff.youngs_modulus, stiff.second_moment
    q0 = -stiff.density * stiff.area * psi_ddot * l
    static = q0 * x * (7 * l**4 - 10 * l**2 * x**2 + 3 * x**4) / (360 * l * E * I)
    middle = (theta > 0.3) & (theta < 1.2)
    scale = np.max(np.abs(static))
    np.testing.assert_allclose(np.asarray(stiff_run.transverse)[middle], static[middle], atol=0.025 * scale)
    # The roller stays in the groove: drift far below the deflections (nm against um).
    for run in (soft_run, stiff_run):
        assert float(run.max_constraint_error) < 1e-10
        assert float(run.max_constraint_error) < 1e-4 * float(jnp.max(jnp.abs(run.transverse)))


def test_spectrum_recovers_harmonic_amplitudes():
    turns, per_turn = 3, 256
    phase = 2 * math.pi * np.arange(turns * per_turn) / per_turn
    signal = 0.7 * np.sin(3 * phase + 0.4) + 0.2 * np.cos(5 * phase) + 0.05 * np.sin(124 / 3 * phase)
    harmonics, near = spectral_peaks(spectrum(signal, turns), natural_order=41.4)
    assert dict(harmonics)[3.0] == pytest.approx(0.7, rel=1e-12)
    assert dict(harmonics)[5.0] == pytest.approx(0.2, rel=1e-12)
    assert dict(harmonics)[1.0] < 1e-3
    assert near == pytest.approx((124 / 3, 0.05), rel=1e-12)


@pytest.mark.parametrize(
    "kwargs, message",
    [({"modes": 0}, "modes"), ({"length": -0.1}, "length"), ({"total_swing": 2.0}, "total_swing")],
)
def test_bad_parameters_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SwingingFollower(**kwargs)


def _cli(argv):
    import argparse

    from camjax.cli import follower
    from camjax.cli._common import CliError

    parser = argparse.ArgumentParser(prog="camjax")
    follower.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["follower", *argv])
    try:
        return args.func(args)
    except (CliError, ValueError) as error:
        return str(error)


@pytest.mark.parametrize(
    "argv, message",
    [(["--law", "nope"], "unknown law"), (["--law", "cycloidal", "--omega", "-3"], "--omega"), (["--law", "cycloidal", "--modes", "0"], "modes")],
)
def test_cli_rejects_bad_arguments(argv, message):
    assert message in _cli(argv)


@pytest.mark.slow
def test_cli_json_report(tmp_path, capsys):
    import json

    assert _cli(["--law", "cycloidal", "--format", "json", "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report == json.loads((tmp_path / "follower.json").read_text())
    model = SwingingFollower()
    assert report["natural_frequency_rad_s"] == pytest.approx(pinned_pinned_rayleigh(model, 1), rel=1e-9)
    orders = [p["order"] for p in report["transverse_peaks"]]
    assert orders[:5] == [1.0, 3.0, 5.0, 7.0, 9.0] and abs(orders[5] - report["natural_order"]) <= 3
    # The paper: the transverse spectrum peaks at 3 Omega, and axial amplitudes are far smaller.
    amplitudes = [p["amplitude_mm"] for p in report["transverse_peaks"]]
    assert max(amplitudes) == amplitudes[1]
    assert max(p["amplitude_mm"] for p in report["axial_peaks"]) < 0.1 * max(amplitudes)
    assert report["max_constraint_error"] < 1e-10

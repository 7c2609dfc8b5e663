"""The swinging follower's flexible arm in a train ([arm]): its beam's frequencies against the
Rayleigh and Euler-Bernoulli closed forms and their convergence with elements, its periodic
steady state against the exact continuous beam driven at each cam order (written here: the
Rayleigh beam's harmonic solution times the lift's Fourier series), the paper's tables
through the program file, and bad input."""

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest
import scipy.optimize

from camjax.cli import main
from camjax.program import (
    Arm,
    Body,
    Chain,
    Follower,
    Program,
    Spring,
    SteadyState,
    analyse,
    arm_bending,
    example_path,
)

E, RHO = 210e9, 7800.0
PAPER_OMEGA = 320.0  # rad/s
PAPER_RPM = PAPER_OMEGA * 60 / (2 * math.pi)
PAPER_FUNDAMENTAL = 13280.0  # rad/s: the paper's "about 41.5 Omega (13280 rad/s)"
# The full differential-algebraic model's spectral peaks of the mid-rod bending (mm), three
# turns from rest (camjax.models.SwingingFollower, docs/swinging-follower.md, base set):
FULL_MODEL = {
    "cycloidal": (0.00383944, 0.00827534, 0.00651499),
    "modified-sine": (0.00380492, 0.00762169, 0.00465231),
}


def rod(radius_mm=5.0):
    r = 1e-3 * radius_mm
    area, second = math.pi * r * r, math.pi * r**4 / 4
    return E * second, RHO * area, RHO * second


def paper_tables(**arm) -> dict:
    data = tomllib.loads(example_path("swinging_arm").read_text())
    data["arm"].update(arm)
    return data


def test_pinned_arm_against_the_rayleigh_closed_form():
    """Cam held: pinned at the pivot and at the roller, ``w_k^2 = EI k^4 / (rho A + rho I k^2)``
    with ``k = n pi / l``; the default elements put three modes within 0.4%, the first within
    1e-4; rotary inertia lowers them as the closed form says."""
    bending, mass, rotary = rod()
    for rho_i in (rotary, 0.0, 400 * rotary):  # Rayleigh, Euler-Bernoulli, a thick arm
        arm = Arm(bending, mass, 98.0, rotary_inertia_kg_m=rho_i, damping_ratio=0.01)
        chain = Chain((Body("roller", 0.025),), arm=arm)
        hz = chain.natural_frequencies(contact=True)[0]
        k = np.arange(1, 4) * math.pi / 0.098
        exact = np.sqrt(bending * k**4 / (mass + rho_i * k**2)) / (2 * math.pi)
        np.testing.assert_allclose(arm.pinned_frequencies_hz(), exact, rtol=1e-14)
        error = hz[:3] / exact - 1
        assert np.all(error > 0) and np.all(error < 4e-3) and error[0] < 1e-4, error
    # the paper's rod: 13,288 rad/s against the paper's 13,280 (41.5 Omega)
    paper = Arm(bending, mass, 98.0, rotary_inertia_kg_m=rotary).pinned_frequencies_hz()[0]
    assert abs(2 * math.pi * paper / PAPER_FUNDAMENTAL - 1) < 1e-3


def test_convergence_with_elements():
    """Cubic Hermite elements: the frequency error falls as the fourth power of the element
    size (16 times per halving)."""
    bending, mass, rotary = rod()
    errors = []
    for n in (4, 8, 16):
        arm = Arm(bending, mass, 98.0, rotary_inertia_kg_m=rotary, elements=n)
        hz = Chain((Body("roller", 0.025),), arm=arm).natural_frequencies()[0]
        errors.append(hz[:3] / arm.pinned_frequencies_hz() - 1)
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all((ratios > 14) & (ratios < 17)), ratios
    assert errors[-1].max() < 1e-4


def test_free_arm_against_the_pinned_free_closed_form():
    """The cam let go (in flight) with a negligible roller: the arm swings freely about its
    pivot (a zero frequency) and bends as a pinned-free Euler-Bernoulli beam,
    ``tan(b l) = tanh(b l)``, ``w = (b l)^2 sqrt(EI / (rho A l^4))``."""
    bending, mass, _ = rod()
    arm = Arm(bending, mass, 98.0, elements=16, modes=100)  # every mode: the beam itself
    hz = Chain((Body("roller", 1e-12),), arm=arm).natural_frequencies(contact=False)[0]
    roots = [
        scipy.optimize.brentq(
            lambda x: math.tan(x) - math.tanh(x),
            (n + 0.25) * math.pi - 0.3,
            (n + 0.25) * math.pi + 0.3,
        )
        for n in (1, 2, 3)
    ]
    exact = np.square(roots) * math.sqrt(bending / (mass * 0.098**4)) / (2 * math.pi)
    assert hz[0] < 1e-3 * exact[0]
    np.testing.assert_allclose(hz[1:4], exact, rtol=2e-4)


def test_a_mass_clamped_at_mid_span_against_the_continuous_beam():
    """A mass ``m`` at mid-span of the pinned Euler-Bernoulli arm: its first (symmetric) mode
    is the half beam ``w = A sin(bx) + C sinh(bx)`` with ``w'(l/2) = 0`` and
    ``EI w'''(l/2) + (m/2) w^2 w(l/2) = 0`` (the mass's inertia splits the shear jump)."""
    bending, mass, _ = rod()
    m, half = 0.05, 0.049
    arm = Arm(bending, mass, 98.0, elements=16)
    chain = Chain((Body("roller", 0.025), Body("weight", m, at_mm=49.0)), arm=arm)
    hz = chain.natural_frequencies()[0][0]

    def half_beam(b):
        w2 = b**4 * bending / mass
        matrix = np.array(
            [
                [b * math.cos(b * half), b * math.cosh(b * half)],
                [
                    -bending * b**3 * math.cos(b * half) + 0.5 * m * w2 * math.sin(b * half),
                    bending * b**3 * math.cosh(b * half) + 0.5 * m * w2 * math.sinh(b * half),
                ],
            ]
        )
        return np.linalg.det(matrix)

    bare = math.pi / 0.098
    b = scipy.optimize.brentq(half_beam, 0.5 * bare, 0.999 * bare)
    exact = b * b * math.sqrt(bending / mass) / (2 * math.pi)
    assert exact < Arm(bending, mass, 98.0).pinned_frequencies_hz()[0]
    assert abs(hz / exact - 1) < 1e-5


def test_the_arm_reduced_to_its_bodies_and_first_modes():
    """Craig-Bampton: the paper's rod with its mid-rod point kept and its first four modes
    with the bodies held (the default) gives the first two frequencies within 1e-4 of the
    closed form and the third within 0.3%; keeping every mode gives the elements' own
    frequencies (the full beam, whose coordinates are all kept), and fewer modes a higher
    first frequency (a reduction only stiffens)."""
    chain = Program.load(example_path("swinging_arm")).chain
    exact = chain.arm.pinned_frequencies_hz(3)
    hz = chain.natural_frequencies()[0]
    error = hz[:3] / exact - 1
    assert np.all(error > 0) and np.all(error[:2] < 1e-4) and error[2] < 3e-3, error
    everything = dataclasses.replace(chain, arm=dataclasses.replace(chain.arm, modes=100))
    full = everything.natural_frequencies()[0]
    only = Chain((chain.bodies[0],), arm=everything.arm).natural_frequencies()[0]
    np.testing.assert_allclose(full[:3], only[:3], rtol=1e-10)  # a massless point changes nothing
    fewer = dataclasses.replace(chain, arm=dataclasses.replace(chain.arm, modes=1))
    assert fewer.natural_frequencies()[0][0] > hz[0] > full[0]


def exact_bending_harmonics(program, chain, rpm, orders=(1, 3, 5), at=0.5):
    """The continuous Rayleigh beam pinned at the pivot, its roller end driven by the cam's
    lift: each cam order of the lift (an FFT of ``Program.lift``) times the beam's exact
    harmonic response ``w(x) = A sinh(a x) + C sin(b x)`` (``EI w'''' + rho I w^2 w'' -
    rho A w^2 w = 0``, ``w(0) = w''(0) = w''(l) = 0``, ``w(l) = Y``), less the rigid swing."""
    arm = chain.arm
    samples = 1 << 14
    y = program.lift(np.arange(samples) * 360.0 / samples + program.start_deg[0])[0]
    coefficients = np.fft.rfft(y) * 2 / samples
    length, ei, rho_a, rho_i = (
        arm.length,
        arm.bending_stiffness_n_m2,
        arm.mass_per_length_kg_per_m,
        arm.rotary_inertia_kg_m,
    )
    out = []
    for k in orders:
        w = 2 * math.pi * k * rpm / 60
        disc = math.sqrt((rho_i * w * w) ** 2 + 4 * ei * rho_a * w * w)
        a = math.sqrt((-rho_i * w * w + disc) / (2 * ei))
        b = math.sqrt((rho_i * w * w + disc) / (2 * ei))
        c_sin = a * a / (a * a + b * b) / math.sin(b * length)
        a_sinh = b * b / (a * a + b * b) / math.sinh(a * length)
        x = at * length
        transfer = a_sinh * math.sinh(a * x) + c_sin * math.sin(b * x) - at
        out.append(abs(transfer * coefficients[k]))
    return np.array(out)


def arm_section_of(program, rpm):
    return analyse(program, [rpm], with_flight=False).train["arm"]


def test_steady_state_against_the_exact_continuous_beam():
    """The paper's cam and rod at Omega = 640 rad/s with four elements (a coarse, quick
    grid) and light damping: the harmonics of the mid-rod bending at 1, 3, 5 and 7 Omega
    against the continuous beam's exact response, to the elements' accuracy."""
    data = paper_tables(elements=4, damping_ratio=1e-3)
    program = Program.from_dict(data)
    rpm = 2 * PAPER_RPM
    section = arm_section_of(program, rpm)
    got = np.asarray(section["speeds"][0]["bending_harmonics_mm"])
    exact = exact_bending_harmonics(program, program.chain, rpm, orders=(1, 3, 5, 7))
    np.testing.assert_allclose(got[[0, 2, 4, 6]], exact, rtol=2e-3)
    assert np.all(got[[1, 3, 5, 7]] < 1e-9 * got[0])  # the symmetric cam has no even orders
    # the bending is the mid-rod's displacement less half the roller's (its rigid swing)
    assert program.chain.lever_ratio == 0.5
    steady = SteadyState(program, rpm)
    cycles = steady.cycles([rpm])
    lift = np.asarray(steady.grid.lift_nodes)
    bending = np.max(np.abs(arm_bending(steady, cycles, [rpm])[0]))
    assert bending == pytest.approx(section["speeds"][0]["max_bending_mm"], rel=1e-12)
    assert 0 < bending < 0.01 * lift.max()


@pytest.mark.slow
def test_the_papers_tables_through_the_program_file(capsys):
    """Slow (two compiled turns of 12,500 intervals and the command's own start: over a
    minute on two loaded cores): ``camjax program swinging_arm`` at the paper's 320 rad/s gives the fundamental within 1% of the paper's 13,280 rad/s and the
    mid-rod bending at 1, 3 and 5 Omega within 10% of the full model's spectral peaks
    (measured: 0.3-0.9%), modified sine below cycloidal at each (the paper's finding)."""
    assert main(["program", "swinging_arm", "--rpm", f"{PAPER_RPM!r}", "--format", "json"]) == 0
    arm = json.loads(capsys.readouterr().out)["train"]["arm"]
    assert abs(arm["fundamental_rad_s"] / PAPER_FUNDAMENTAL - 1) < 0.01
    assert arm["speeds"][0]["fundamental_orders"] == pytest.approx(41.5, abs=0.1)
    cycloidal = np.asarray(arm["speeds"][0]["bending_harmonics_mm"])[[0, 2, 4]]
    np.testing.assert_allclose(cycloidal, FULL_MODEL["cycloidal"], rtol=0.10)
    np.testing.assert_allclose(cycloidal, FULL_MODEL["cycloidal"], rtol=0.01)  # what it gives
    data = paper_tables()
    for segment in data["segment"][::2]:
        segment["law"] = "modified-sine"
    program = Program.from_dict(data)
    sine = np.asarray(arm_section_of(program, PAPER_RPM)["speeds"][0]["bending_harmonics_mm"])[
        [0, 2, 4]
    ]
    np.testing.assert_allclose(sine, FULL_MODEL["modified-sine"], rtol=0.01)
    assert np.all(sine < cycloidal)
    exact = exact_bending_harmonics(program, program.chain, PAPER_RPM)
    np.testing.assert_allclose(sine, exact, rtol=2e-3)


def test_an_arm_round_trips_through_its_file():
    program = Program.load(example_path("swinging_arm"))
    again = Program.from_dict(tomllib.loads(program.to_toml()))
    assert again.chain == program.chain
    assert program.chain.arm.roller_mm == 98.0 and program.chain.bodies[1].at_mm == 49.0


def _edit(path, value):
    def apply(data):
        table, _, key = path.partition(".")
        if table == "train1":
            data["train"][1][key] = value
        elif table == "train0":
            data["train"][0][key] = value
        elif key:
            data[table][key] = value
        else:
            del data[table]
        return data

    return apply


@pytest.mark.parametrize(
    "edit, message",
    [
        (
            _edit("arm.bending_stiffness_n_m2", -1.0),
            r"\[arm\] bending_stiffness_n_m2 must be positive",
        ),
        (
            _edit("arm.mass_per_length_kg_per_m", 0),
            r"\[arm\] mass_per_length_kg_per_m must be positive",
        ),
        (
            _edit("arm.rotary_inertia_kg_m", -1e-6),
            r"\[arm\] rotary_inertia_kg_m must be non-negative",
        ),
        (_edit("arm.damping_ratio", 1.0), r"\[arm\] damping_ratio must be below 1"),
        (_edit("arm.elements", 1), r"\[arm\] elements must be a whole number from 2"),
        (_edit("arm.elements", 2.5), r"\[arm\] elements must be a whole number"),
        (_edit("arm.modes", 0), r"\[arm\] modes must be a whole number from 1"),
        (
            _edit("arm.length_mm", 50.0),
            r"\[arm\] length_mm = 50 is shorter than the roller's place",
        ),
        (_edit("arm.colour", "red"), r"\[arm\]: unknown field\(s\) colour"),
        (
            _edit("follower.arm_mm", 0.0),
            r"\[arm\] roller_mm \(the follower's arm_mm\) must be positive",
        ),
        (
            _edit("follower.kind", "translating-roller"),
            r"\[arm\]: a flexible arm belongs to a swinging roller",
        ),
        (
            _edit("train1.at_mm", 120.0),
            r"\[\[train\]\] body 2 \(mid-rod\) at_mm = 120 is past the arm's end",
        ),
        (_edit("train1.at_mm", -3.0), r"\[\[train\]\] body 2 \(mid-rod\) at_mm must be positive"),
        (
            _edit("train1.stiffness_n_per_mm", 10.0),
            r"body 2 \(mid-rod\) stiffness_n_per_mm: a body on the \[arm\]",
        ),
        (_edit("train1.mass_kg", -0.1), r"body 2 \(mid-rod\) mass_kg must be non-negative"),
        (
            _edit("train0.stiffness_n_per_mm", 10.0),
            r"body 1 \(roller\): on an \[arm\] the first body rides",
        ),
        (
            _edit("train0.at_mm", 40.0),
            r"body 1 \(roller\) at_mm: the body riding on the cam sits at the roller",
        ),
        (_edit("train", None), r"\[arm\] needs \[\[train\]\] bodies"),
        (
            _edit("arm", None),
            r"body 2 \(mid-rod\) at_mm: a place on the arm needs an \[arm\] table",
        ),
    ],
)
def test_bad_arm_input_is_one_line(edit, message):
    with pytest.raises(ValueError, match=message) as error:
        Program.from_dict(edit(paper_tables()))
    assert "\n" not in str(error.value)


def test_a_missing_place_or_field_and_an_arm_on_another_follower():
    data = paper_tables()
    del data["train"][1]["at_mm"]
    with pytest.raises(ValueError, match=r"body 2 \(mid-rod\): needs at_mm"):
        Program.from_dict(data)
    data = paper_tables()
    del data["arm"]["bending_stiffness_n_m2"]
    with pytest.raises(ValueError, match=r"\[arm\] needs bending_stiffness_n_m2"):
        Program.from_dict(data)
    # in Python: the chain's arm checked against the program's follower
    program = Program.load(example_path("swinging_arm"))
    flat = Follower(
        1.0, 1.0, kind="swinging-flat", arm_mm=98.0, pivot_mm=110.0, spring_rate_n_per_mm=1.0
    )
    with pytest.raises(
        ValueError, match=r"belongs to a swinging roller follower, not 'swinging-flat'"
    ):
        Program("p", program.segments, flat, chain=program.chain)
    longer = dataclasses.replace(program.follower, arm_mm=100.0, pivot_mm=112.0)
    with pytest.raises(
        ValueError, match=r"\[arm\] roller_mm = 98 is not the follower's arm_mm = 100"
    ):
        Program("p", program.segments, longer, chain=program.chain)


def test_a_return_spring_on_a_stiff_arm_in_flight_is_a_rigid_pendulum():
    """A stiff arm carrying a payload ``m`` at ``a`` on a return spring ``k``, the cam let go:
    it swings about its pivot as a rigid body, ``w^2 = k a^2 / (rho A l^3 / 3 + rho I l +
    m_r l^2 + m a^2)``; the cam's static force is the preload times ``a / l``."""
    _, mass, rotary = rod()
    bending = 1e3 * rod()[0]  # stiff (much stiffer leaves the eigenproblem ill-conditioned)
    a, m, k, roller, preload = 0.07, 0.2, 5e3, 0.025, 40.0
    arm = Arm(bending, mass, 98.0, rotary_inertia_kg_m=rotary, damping_ratio=0.01)
    chain = Chain(
        (Body("roller", roller), Body("payload", m, at_mm=1e3 * a)),
        Spring(1e-3 * k, preload),
        arm=arm,
    )
    inertia = mass * 0.098**3 / 3 + rotary * 0.098 + roller * 0.098**2 + m * a**2
    hz = chain.natural_frequencies(contact=False)[0][0]
    assert hz == pytest.approx(math.sqrt(k * a * a / inertia) / (2 * math.pi), rel=1e-5)
    assert chain.lever_ratio == pytest.approx(a / 0.098)
    assert chain.cam_preload_n == pytest.approx(preload * a / 0.098)

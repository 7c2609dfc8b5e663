"""A train in the program file and the report: the one-body train against the classic
follower's report, a two-body program's train section against ``SteadyState`` called
directly and its natural frequencies against the two-mass closed form, the preload it
reports against the chain's own contact force, the command's JSON and bad input."""

import json
import math
import tomllib

import numpy as np
import pytest
from helpers import two_cycloids

from camjax.cli import main
from camjax.program import (
    Chain,
    Program,
    SteadyState,
    analyse,
    design_warnings,
    example_names,
    example_path,
    flights_at,
    program_path,
)

CLASSIC = ("mass_kg", "stiffness_n_per_mm", "damping_ratio", "spring_rate_n_per_mm", "preload_n")


def tables(program: Program) -> dict:
    """``program``'s file as TOML tables."""
    return tomllib.loads(program.to_toml())


def one_body_train(program: Program) -> dict:
    """``program``'s file with its follower spelled as a one-body ``[[train]]``."""
    data = tables(program)
    f = program.follower
    data["follower"] = {k: v for k, v in data["follower"].items() if k not in CLASSIC}
    damping = 2 * f.damping_ratio * math.sqrt(1e3 * f.stiffness_n_per_mm * f.mass_kg)
    data["train"] = [
        {
            "name": "follower",
            "mass_kg": f.mass_kg,
            "stiffness_n_per_mm": f.stiffness_n_per_mm,
            "damping_n_s_per_m": damping,
        }
    ]
    data["spring"] = {"rate_n_per_mm": f.spring_rate_n_per_mm, "preload_n": f.preload_n}
    return data


TWO = dict(tappet=0.4, valve=0.6, element=300.0, damping=40.0, rate=20.0, preload=150.0)


def two_body(**edit) -> Program:
    """The two-cycloids cam driving a tappet that rides on it and a valve on an element."""
    t = {**TWO, **edit}
    data = tables(two_cycloids())
    data["follower"] = {k: v for k, v in data["follower"].items() if k not in CLASSIC}
    data["train"] = [
        {"name": "tappet", "mass_kg": t["tappet"]},
        {
            "name": "valve",
            "mass_kg": t["valve"],
            "stiffness_n_per_mm": t["element"],
            "damping_n_s_per_m": t["damping"],
        },
    ]
    data["spring"] = {"rate_n_per_mm": t["rate"], "preload_n": t["preload"]}
    return Program.from_dict(data)


def test_one_body_train_gives_the_classic_report():
    """The same numbers in every row; the train section's contact force and acceleration,
    from the same steady state, within 1e-12 of their peaks."""
    classic = two_cycloids()
    train = Program.from_dict(one_body_train(classic))
    assert train.one_body and train.chain == Chain.of_follower(classic.follower)
    rpm = [100.0, 125.0, 150.0]
    a, b = analyse(classic, rpm), analyse(train, rpm)
    assert a.train is None and "train" not in a.as_dict()
    for x, y in zip(a.speeds, b.speeds):
        for name, value in x.values.items():
            other = y.values[name]
            if isinstance(value, float):
                assert abs(value - other) <= 1e-10 * max(abs(value), 1.0), name
            else:
                assert value == other, name
        assert x.residual_vibration_mm == pytest.approx(
            y.residual_vibration_mm, rel=1e-10, abs=1e-15
        )
    assert (a.jump_speed_rpm, a.jump_below_range) == (b.jump_speed_rpm, b.jump_below_range)
    peak = max(s.max_contact_force_n for s in a.speeds)
    for row, chain_row in zip(a.speeds, b.train["speeds"]):
        assert abs(chain_row["min_contact_force_n"] - row.min_contact_force_n) < 1e-12 * peak
        assert abs(chain_row["max_contact_force_n"] - row.max_contact_force_n) < 1e-12 * peak
        accel = chain_row["max_acceleration_m_s2"]["follower"]
        assert abs(accel - row.max_payload_acceleration_m_s2) < 1e-12 * accel
    assert b.train["one_body"]


def test_two_body_report_is_the_chain_steady_state():
    program = two_body()
    rpm = np.array([600.0, 900.0, 1200.0, 1500.0])
    report = analyse(program, rpm)
    steady = SteadyState(program, rpm.min())
    direct = steady.summary(rpm)
    peaks = direct.cycles.train
    train = report.train
    assert not train["one_body"] and train["bodies"] == ["tappet", "valve"]
    for i, s in enumerate(train["speeds"]):
        assert s["min_contact_force_n"] == pytest.approx(direct.min_contact_force_n[i], rel=1e-12)
        assert s["max_contact_force_n"] == pytest.approx(direct.max_contact_force_n[i], rel=1e-12)
        assert list(s["max_acceleration_m_s2"].values()) == pytest.approx(
            peaks.max_acceleration_m_s2[i], rel=1e-12
        )
        assert s["max_lift_error_mm"] == pytest.approx(peaks.max_lift_error_mm[i], rel=1e-12)
        assert s["min_seat_force_n"] == pytest.approx(peaks.min_seat_force_n[i], rel=1e-12)
        assert s["max_seat_force_n"] == pytest.approx(peaks.max_seat_force_n[i], rel=1e-12)
        assert s["max_surge_n"] == pytest.approx(peaks.max_surge_n[i], rel=1e-12)
        row = report.speeds[i]  # the rows: the chain's numbers, every one the follower has
        assert row.min_contact_force_n == pytest.approx(direct.min_contact_force_n[i], rel=1e-12)
        assert row.max_payload_acceleration_m_s2 == pytest.approx(
            peaks.max_acceleration_m_s2[i, -1], rel=1e-12
        )
        assert row.jump == (direct.min_contact_force_n[i] < 0)
        assert row.max_drive_torque_n_m > 0 and len(row.residual_vibration_mm) == 2
        assert len(row.period_ratios) == 2
        # where the steady state loses contact, the chain's simulated flights (flights_at)
        assert (row.flights is not None) == bool(row.jump)
        if row.jump:
            assert list(row.flights) == flights_at(steady, [rpm[i]])[0] and row.flights
    held = train["natural_frequencies_held_hz"][0]  # the cam orders meeting it from 600 to 1500 rpm
    assert train["harmonic_check"][0]["orders"] == [
        k for k in range(1, 500) if 600 <= 60 * held / k <= 1500
    ]
    # the tappet rides on the cam: its peak acceleration is the cam's
    kinematic = [r.max_kinematic_acceleration_m_s2 for r in report.speeds]
    assert peaks.max_acceleration_m_s2[:, 0] == pytest.approx(kinematic, rel=1e-6)
    assert train["jump_speed_rpm"] == report.jump_speed_rpm


def test_two_body_natural_frequencies_against_the_closed_form():
    t = TWO
    m1, m2, k, ks = t["tappet"], t["valve"], 1e3 * t["element"], 1e3 * t["rate"]
    train = analyse(two_body(), [600.0]).train
    held = math.sqrt((k + ks) / m2) / (2 * math.pi)  # the tappet held on the cam
    assert train["natural_frequencies_held_hz"] == pytest.approx([held], rel=1e-12)
    # free: roots of m1 m2 w^4 - ((k + ks) m1 + k m2) w^2 + k ks = 0
    roots = np.roots([m1 * m2, -((k + ks) * m1 + k * m2), k * ks])
    free = np.sort(np.sqrt(roots)) / (2 * math.pi)
    assert train["natural_frequencies_free_hz"] == pytest.approx(free, rel=1e-10)


def test_the_reported_least_preload_just_keeps_contact():
    """The chain is linear in the preload: with the preload the report asks for, the least
    contact force at the cam is zero (a lever between them scales it)."""
    rpm = 1500.0
    program = two_body()
    needed = analyse(program, [rpm]).speeds[0].min_preload_n
    assert needed > 0
    again = analyse(two_body(preload=needed), [rpm]).speeds[0]
    assert abs(again.min_contact_force_n) < 1e-9 * again.max_contact_force_n


def test_a_chain_program_round_trips_through_its_file():
    program = Program.load(example_path("valve"))
    assert program_path("valve") == example_path("valve")
    again = Program.from_dict(tomllib.loads(program.to_toml()))
    assert again == program and again.chain == program.chain
    # the follower's one-body fields stand in for the chain, and are not written
    assert "[[train]]" in program.to_toml() and "\nmass_kg = 0.08" not in program.to_toml()


def test_cli_json_carries_the_train(capsys):
    assert main(["program", "valve", "--rpm", "1000,2000", "--format", "json"]) == 0
    report = json.loads(capsys.readouterr().out)
    train = report["train"]
    assert train["bodies"] == ["tappet", "valve"] and len(train["speeds"]) == 2
    program = Program.load(example_path("valve"))
    summary = SteadyState(program, 1000.0).summary(np.array([1000.0, 2000.0]))
    assert [s["max_surge_n"] for s in train["speeds"]] == pytest.approx(
        summary.cycles.train.max_surge_n, rel=1e-12
    )
    assert report["speeds"][0]["max_drive_torque_n_m"] > 0
    assert main(["program", "valve", "--rpm", "1000"]) == 0
    text = capsys.readouterr().out
    assert "train tappet -> valve" in text and "natural frequencies, cam held: 298.54" in text


@pytest.mark.parametrize(
    "edit, message",
    [
        (
            lambda d: d["follower"].update(mass_kg=1.0),
            r"\[follower\] mass_kg: a file with a \[\[train\]\]",
        ),
        (lambda d: d.pop("train"), r"\[spring\] belongs to a \[\[train\]\]"),
        (lambda d: d["train"][1].update(ratio=0.0), r"body 2 \(valve\) ratio must be positive"),
        (lambda d: d.update(gears=1), "top level: unknown field"),
        (
            lambda d: d["train"].pop(1),
            r"body 1 \(tappet\): a single body riding on the cam is rigid .* give it stiffness_n_per_mm",
        ),
        (lambda d: d["train"][0].update(name=""), r"body 1: name must be a non-empty text"),
        (
            lambda d: d["spring"].update(mass_kg=0.05, elements=1000),
            r"\[spring\] elements = 1000 is more than 64 \(the default meets 0\.5% with fewer; "
            r"the modes cost the cube of the elements\)$",
        ),
        (
            lambda d: d["train"].extend(
                {"name": f"b{j}", "mass_kg": 0.01, "stiffness_n_per_mm": 100} for j in range(63)
            ),
            r"\[\[train\]\]: 65 bodies are more than the 64 a chain may have \(its modes cost "
            r"the cube of its bodies\)$",
        ),
    ],
)
def test_bad_train_program_is_one_line(tmp_path, edit, message):
    data = tables(two_body())
    edit(data)
    path = tmp_path / "bad.toml"
    lines = [f"{key} = {value}" for key, value in data.items() if isinstance(value, int)]
    for key in ("program", "follower", "spring"):
        if key in data:
            lines += [f"[{key}]"] + [f"{k} = {json.dumps(v)}" for k, v in data[key].items()]
    for key in ("segment", "train"):
        for table in data.get(key, []):
            lines += [f"[[{key}]]"] + [f"{k} = {json.dumps(v)}" for k, v in table.items()]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=message) as error:
        Program.load(path)
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def test_design_over_a_train_at_its_last_body(tmp_path, capsys):
    """``design --program`` of a chain: the residual objective is the last body's through
    the chain, its gradient matches central finite differences, and the designed program
    is no worse than its start (or the design says it kept the start)."""
    import warnings

    import jax

    from camjax import laws
    from camjax.law_design import DesignNotImproved
    from camjax.program import MaxProgramResidual, design_segment

    program = two_body()
    objective = MaxProgramResidual(program, 1, 900.0, 1100.0)
    law = laws.BSplineLaw.fit(laws.get("cycloidal"), 8, 5)
    value = jax.jit(lambda c, p: objective.train(laws.BSplineLaw(c, 5), 1.0, p))
    features = jax.jit(lambda c: objective.features(laws.BSplineLaw(c, 5)))
    direction = np.random.default_rng(1).normal(size=8)
    # the last body's residual modes through the chain are affine in the law: their
    # derivative is the central difference's, to rounding
    _, tangent = jax.jvp(features, (law.coefficients,), (jax.numpy.asarray(direction),))
    h = 1e-3
    difference = (
        features(law.coefficients + h * direction) - features(law.coefficients - h * direction)
    ) / (2 * h)
    assert np.max(np.abs(tangent - difference)) < 1e-9 * np.max(np.abs(tangent))
    # the smooth maximum's shift (the least value) has a kink where two residuals tie, and
    # two do within 1e-7 here: the difference steps inside it
    gradient = jax.jit(jax.grad(value))(law.coefficients, 16.0)
    h = 1e-9
    difference = (
        value(law.coefficients + h * direction, 16.0)
        - value(law.coefficients - h * direction, 16.0)
    ) / (2 * h)
    assert float(gradient @ direction) == pytest.approx(float(difference), rel=1e-6)
    # the training value at a sharp maximum is the report's largest residual (the last body's)
    steady = SteadyState(program, 900.0)
    report = np.max(steady.summary(objective.speeds()).residual_vibration_mm)
    assert float(value(law.coefficients, 1e6)) == pytest.approx(report, rel=1e-2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        designed, result = design_segment(
            program, 1, 900.0, 1100.0, objective="residual", knots=8, steps=60, progress=False
        )
    label = objective.label
    start = objective.report(program.segments[0].law)
    assert result.initial_values[label] == pytest.approx(start, rel=1e-12)
    if result.kept_initial:
        assert any(issubclass(w.category, DesignNotImproved) for w in caught)
        assert designed == program
    else:
        assert result.values[label] < start
        assert objective.report(designed.segments[0].law) == pytest.approx(
            result.values[label], rel=1e-9
        )
    with pytest.raises(ValueError) as error:
        design_segment(program, 1, 900.0, 1100.0, objective="ca-ct")
    assert str(error.value) == (
        "objective 'ca-ct': a chain of bodies ([[train]]) is designed at its last body through "
        "the whole chain: residual or preload"
    )


def test_chain_messages_name_the_chains_own_fields():
    """A chain file has no follower.mass_kg or follower.stiffness_n_per_mm: the grid's
    refusal names the body and element that set the highest mode, or the spring's
    elements; the size warning names each body's mass as written, not their sum."""
    with pytest.raises(
        ValueError,
        match=r"raise \[\[train\]\] valve mass_kg or lower \[\[train\]\] valve "
        r"stiffness_n_per_mm",
    ) as error:
        SteadyState(two_body(valve=1e-9), 1000.0)
    assert "follower." not in str(error.value) and "\n" not in str(error.value)
    data = tables(two_body())
    data["spring"].update(mass_kg=0.05, damping_ratio=0.05, elements=64)
    with pytest.raises(ValueError, match=r"give \[spring\] fewer elements \(now 64\)") as error:
        SteadyState(Program.from_dict(data), 10.0)
    assert "follower." not in str(error.value)
    warnings = design_warnings(two_body(tappet=2e4, valve=2e4))
    heavy = [w for w in warnings if "10,000 kg" in w]
    assert [w.split(" is more")[0] for w in heavy] == [
        "[[train]] body 1 (tappet) mass_kg = 20000",
        "[[train]] body 2 (valve) mass_kg = 20000",
    ]


def test_a_chain_without_a_spring_is_form_closed(tmp_path):
    """No [spring]: a grooved chain, as the classic follower without spring_rate_n_per_mm
    (no jump, no least preload); its rows have no seat force or surge (nothing there), a
    groove clearance is refused (a groove's strikes are the one-body follower's)."""
    data = tables(two_body())
    data.pop("spring")
    program = Program.from_dict(data)
    assert program.follower.form_closed
    report = analyse(program, [1000.0, 3000.0]).as_dict()
    assert [s["jump"] for s in report["speeds"]] == [False, False]
    assert all(s["min_preload_n"] is None for s in report["speeds"])
    assert report["train"]["natural_frequencies_free_hz"][0] == 0.0
    for row in report["train"]["speeds"]:
        assert row["min_seat_force_n"] is row["max_seat_force_n"] is row["max_surge_n"] is None
    data["follower"]["groove_clearance_mm"] = 0.05
    with pytest.raises(
        ValueError,
        match=r"groove_clearance_mm: a groove's strikes are simulated for the "
        "one-body follower only",
    ):
        Program.from_dict(data)


def test_design_of_a_chain_with_lash_or_a_seat_is_refused_plainly():
    from camjax.program import design_segment

    program = Program.load(example_path("valve_lash"))
    for objective in ("residual", "preload"):
        with pytest.raises(
            ValueError,
            match=r"the residual and preload objectives design through the exact "
            r"steady state of a chain without lash or seat, and this chain has "
            r"\[\[train\]\] valve lash_mm, \[seat\]; objective 'seating' designs a chain with a seat",
        ) as error:
            design_segment(program, 1, 1000.0, 3000.0, objective=objective)
        assert "\n" not in str(error.value)


def test_every_built_in_example_is_named_where_names_are_listed(capsys):
    """The help texts and the missing file's error list every built-in example, each of
    which loads by its name."""
    names = example_names()
    assert {"indexer", "feed", "servo", "valve", "valve_lash", "swinging_arm"} <= set(names)
    for name in names:
        assert program_path(name) == example_path(name)
        Program.load(program_path(name))
    listed = ", ".join(names)
    for command in ("program", "design", "studio"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        assert listed in " ".join(capsys.readouterr().out.split())
    assert main(["program", "valvee"]) != 0
    assert (
        f"valvee: no such program file, nor a built-in example ({listed})"
        in capsys.readouterr().err
    )
    with pytest.raises(ValueError, match="nor a built-in example"):
        program_path("no_such_dir/valvee.toml")


def test_lash_on_the_first_element_is_the_cam_clearance(tmp_path, capsys):
    """A bucket tappet: one body on its element with lash and a seat; its lash is the
    clearance at the cam, and the text table says so."""
    text = example_path("valve_lash").read_text()
    head = text[: text.index("[[train]]")]
    path = tmp_path / "bucket.toml"
    path.write_text(
        head + '[[train]]\nname = "valve"\nmass_kg = 0.08\nstiffness_n_per_mm = 3000\n'
        "damping_n_s_per_m = 30\nlash_mm = 0.15\n\n[spring]\nrate_n_per_mm = 40\npreload_n = 250\n\n"
        "[seat]\nstiffness_n_per_mm = 50000\ndamping_n_s_per_m = 500\n"
    )
    assert main(["program", str(path), "--rpm", "1000"]) == 0
    out = capsys.readouterr().out
    assert "cam clearance (valve) opens 1x" in out and "lash at valve" not in out


def test_a_lever_on_the_first_element_is_a_riding_body(tmp_path):
    """``lever_mass_kg`` on a first element is refused in one line on the exact path and
    with a seat alike, naming the riding body that models it; that body with the element's
    ratio gives the hand-derived two-body frequencies (cam held and free)."""
    from camjax.program import Body, Seat, Spring

    message = (
        "[[train]] body 1 (valve) lever_mass_kg: a lever on the cam's side of the first element "
        "moves with the cam; give it as a first [[train]] body of mass_kg = 0.5 with no "
        "stiffness_n_per_mm (it rides on the cam)"
    )
    data = tables(two_body())  # its valve on a rocker of ratio 1.6 (the trial's file)
    data["train"] = [
        {
            "name": "valve",
            "mass_kg": 0.07,
            "stiffness_n_per_mm": 3000,
            "damping_n_s_per_m": 20,
            "ratio": 1.6,
            "lever_mass_kg": 0.5,
        }
    ]
    for seat in (None, {"stiffness_n_per_mm": 50000, "damping_n_s_per_m": 500}):
        if seat:
            data["seat"] = seat
        lines = []
        for key in ("program", "follower", "spring", "seat"):
            if key in data:
                lines += [f"[{key}]"] + [f"{k} = {json.dumps(v)}" for k, v in data[key].items()]
        for key in ("segment", "train"):
            for table in data.get(key, []):
                lines += [f"[[{key}]]"] + [f"{k} = {json.dumps(v)}" for k, v in table.items()]
        path = tmp_path / "lever.toml"
        path.write_text("\n".join(lines) + "\n")
        with pytest.raises(ValueError) as error:
            Program.load(path)
        assert str(error.value) == f"{path}: {message}"
    with pytest.raises(ValueError) as error:
        Chain((Body("valve", 0.07, 3000.0, 20.0, 1.6, 0.5),), Spring(35.0, 300.0), Seat(5e4))
    assert str(error.value) == message
    # the riding body it names: m_L m w^4 - (k r^2 m + (k + k_s) m_L) w^2 + k r^2 k_s = 0 free,
    # w^2 = (k + k_s) / m held (the lever moves with the cam)
    m_lever, m, k, r, k_s = 0.5, 0.07, 3e6, 1.6, 35e3
    chain = Chain(
        (Body("rocker", m_lever), Body("valve", m, 3000.0, 20.0, ratio=r)), Spring(35.0, 300.0)
    )
    held = chain.natural_frequencies(contact=True)[0]
    assert held == pytest.approx([math.sqrt((k + k_s) / m) / (2 * math.pi)], rel=1e-12)
    roots = np.roots([m_lever * m, -(k * r**2 * m + (k + k_s) * m_lever), k * r**2 * k_s])
    free = chain.natural_frequencies(contact=False)[0]
    assert free == pytest.approx(np.sort(np.sqrt(roots)) / (2 * math.pi), rel=1e-10)


def test_an_undamped_chain_names_its_undamped_elements():
    """A chain with no damping anywhere is refused before any turn, naming the fields that
    would damp it (the element with a ratio, the spring that surges)."""
    from camjax.program import Body, Oscillator, Spring

    chain = Chain((Body("valve", 0.1, 100.0, ratio=1.5),), Spring(35.0, 300.0))
    with pytest.raises(ValueError) as error:
        Oscillator.of_chain(chain)
    assert str(error.value) == (
        "the chain has a mode without damping (give [[train]] valve damping_n_s_per_m): its "
        "periodic steady state does not exist"
    )
    surging = Chain(
        (Body("tappet", 0.03), Body("valve", 0.05, 200.0)), Spring(52.0, 250.0, mass_kg=0.04)
    )
    with pytest.raises(ValueError) as error:
        Oscillator.of_chain(surging)
    assert str(error.value) == (
        "the chain has a mode without damping (give [[train]] valve damping_n_s_per_m or "
        "[spring] damping_ratio): its periodic steady state does not exist"
    )


def test_an_absurd_ratio_is_named_before_the_grid_remedy():
    """A ratio past ``ABSURD_SIZES`` (1600 on the valve's rocker) sets the highest mode; the
    grid's refusal names it first, before the speed and the stiffnesses it would ask for."""
    data = tables(two_body())
    data["train"] = [
        {"name": "tappet", "mass_kg": 0.06},
        {"name": "pushrod", "mass_kg": 0.04, "stiffness_n_per_mm": 8000.0},
        {"name": "valve", "mass_kg": 0.07, "stiffness_n_per_mm": 3000.0, "ratio": 1600.0},
    ]
    for body in data["train"][1:]:
        body["damping_n_s_per_m"] = 20.0
    with pytest.raises(ValueError) as error:
        SteadyState(Program.from_dict(data), 1500.0)
    named = (
        "[[train]] body 3 (valve) ratio = 1600 is more than 100, larger than any cam machine's "
        "lever: check it (the body's motion over the body's before); else the chain's highest "
        "mode vibrates "
    )
    what, remedy = str(error.value).split(": ", 1)
    assert what.startswith("a turn at 1500 rpm needs ") and remedy.startswith(named)


def test_compensating_a_linear_chain_is_refused_before_any_file(tmp_path, capsys):
    """``--compensate`` of a linear chain (the built-in valve train) is one line, exit 2, and
    ``--out`` holds no file: the refusal comes before the analysis writes its report."""
    out_dir = tmp_path / "out"
    code = main(
        ["program", "valve", "--rpm", "1000", "--compensate", "1000", "--out", str(out_dir)]
    )
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.strip().endswith(
        "--compensate: compensation of a chain of bodies ([[train]]) is not built yet: "
        "compensated_lift takes a chain's arrays, compensate only the one-body follower"
    )
    assert len(err.strip().splitlines()) == 1
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_rms_acceleration_with_a_chain_names_the_objectives_it_takes(tmp_path, capsys):
    """``design --objective rms-acceleration --program`` lists the objectives this program's
    segments take (``design_objectives``): no ca-ct for a chain, only seating with a seat."""
    for name, takes in (("valve", "residual or preload"), ("valve_lash", "seating")):
        argv = ["design", "--objective", "rms-acceleration", "--program", name]
        code = main([*argv, "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err.strip()
        assert code == 2 and err.endswith(
            "--objective rms-acceleration: not with --program (it designs a free rise; this "
            f"program's segment design takes {takes})"
        )


def test_the_harmonic_check_says_no_cam_order_in_words(capsys):
    """At one speed no whole cam order meets a mode: the table says "met by no cam order";
    a range's orders are those of ``Chain.harmonic_check``."""
    chain = Program.load(example_path("valve")).chain
    for rpm, lo, hi in (("1000", 1000.0, 1000.0), ("1000:3000:3", 1000.0, 3000.0)):
        assert main(["program", "valve", "--rpm", rpm]) == 0
        out = capsys.readouterr().out
        checks = chain.harmonic_check(lo, hi)
        assert lo < hi or not any(orders for _, orders in checks)
        for hz, orders in checks:
            met = (
                f"cam orders {orders[0]} to {orders[-1]}"
                if len(orders) > 1
                else f"cam order {orders[0]}"
                if orders
                else "no cam order"
            )
            assert f"harmonic check: {hz:.5g} Hz met by {met} in the speed range\n" in out


def test_the_modes_figure_does_not_run_the_bodies_names_together(tmp_path, monkeypatch):
    """Three bodies on neighbouring coordinates (tappet, pushrod, valve) and a surging spring:
    in modes.png no two names along the chain overlap, nor a name the axis label."""
    import camjax.plot

    data = tables(two_body())
    data["train"] = [
        {"name": "tappet", "mass_kg": 0.06},
        {"name": "pushrod", "mass_kg": 0.04, "stiffness_n_per_mm": 8000.0, "damping_n_s_per_m": 30},
        {"name": "valve", "mass_kg": 0.07, "stiffness_n_per_mm": 3000.0, "damping_n_s_per_m": 20},
    ]
    data["spring"].update(mass_kg=0.05, damping_ratio=0.05)
    path = tmp_path / "pushrod.toml"
    path.write_text(Program.from_dict(data).to_toml())
    saved = {}
    monkeypatch.setattr(camjax.plot, "save", lambda fig, where: saved.update({where.name: fig}))
    assert main(["program", str(path), "--rpm", "1000", "--out", str(tmp_path / "out")]) == 0
    fig = saved["modes.png"]
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        names = [t for t in ax.get_xticklabels() if t.get_text()]
        assert [t.get_text() for t in names][:3] == ["tappet", "pushrod", "valve"]
        boxes = [t.get_window_extent(renderer) for t in names]
        boxes.append(ax.xaxis.label.get_window_extent(renderer))
        assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])


def test_a_last_body_that_barely_follows_the_cam_is_warned_of():
    """A valve on a 10 N/mm element against a 20 N/mm spring follows the cam's 20 mm lift
    statically by ``k / (k + k_s)``: at 60 rpm (far below its 35 Hz mode) it misses it by
    ``20 * 20 / 30 = 13.33 mm``, two thirds of it: one warning naming the speeds, the numbers
    and the element (the 150 N preload compresses it by 15 mm).  The same chain on 300 N/mm
    misses it by 1.25 mm: no warning."""
    report = analyse(two_body(element=10.0), [60.0, 120.0])
    errors = [s["max_lift_error_mm"] for s in report.train["speeds"]]
    assert errors == pytest.approx([20 * 20 / 30] * 2, rel=2e-3)
    worst = max(errors)
    (line,) = [w for w in report.warnings if "kinematic lift" in w]
    assert line == (
        "at 60, 120 rpm the last body (valve) misses its kinematic lift (20 mm: the cam's lift "
        f"times the ratios) by up to {worst:.4g} mm ({100 * worst / 20:.3g}%, at "
        f"{60.0 if worst == errors[0] else 120.0:g} rpm): it barely follows the cam; the chain "
        "gives most at [[train]] body 2 (valve) stiffness_n_per_mm = 10 (the spring's preload, "
        "150 N, compresses it by 15 mm at the last body): stiffen it"
    )
    stiff = analyse(two_body(element=300.0), [60.0])
    assert stiff.train["speeds"][0]["max_lift_error_mm"] == pytest.approx(1.25, rel=2e-3)
    assert not [w for w in stiff.warnings if "kinematic lift" in w]

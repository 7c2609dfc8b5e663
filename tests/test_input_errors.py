"""Input a user may give: grids sized to the period ratio, law parameters checked even
traced, law names and law files wherever a law is taken, and one-line errors that name the
file, the key or the user's own option."""

import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_RTOL

import camjax
from camjax import laws
from camjax.cli import build_parser, main, split_law_specs
from camjax.models import SpringMass

MODSINE = laws.get("modsine")
FRACTIONS_RULE = "SCCA fractions must be finite and non-negative with 0 < a + b + c <= 1"


@pytest.fixture(autouse=True)
def _no_user_cache(monkeypatch):
    monkeypatch.setenv("CAMJAX_CACHE_DIR", "off")


# --- grids sized to the period ratio ------------------------------------------------------


def test_torsion_factor_at_a_high_period_ratio_agrees_with_ct_curve():
    """A fixed 1024-interval grid gave Ct = 4.04 here; the sweep's sized grid gives 1.00."""
    curve = camjax.ct_curve(MODSINE, [80000.0], damping=0.02)
    assert float(camjax.torsion_factor(MODSINE, 80000.0, 0.02)) == pytest.approx(
        curve.ct[0], rel=1e-9)
    assert curve.ct[0] == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("n", [3.3, 41.0])
def test_residual_vibration_agrees_with_ct_curve(n):
    curve = camjax.ct_curve(MODSINE, [n], damping=0.02)
    assert float(camjax.residual_vibration(MODSINE, n, 0.02)) == pytest.approx(
        curve.residual[0], rel=1e-9)


def test_a_period_ratio_past_the_largest_grid_is_refused():
    with pytest.raises(ValueError, match=r"period ratio 1e\+06 needs .* grid intervals \(the limit is"):
        camjax.torsion_factor(MODSINE, 1e6)


def test_a_grid_too_coarse_for_a_concrete_period_ratio_is_refused():
    message = ("period ratio must be at most 61.11 on a grid of resolution 256 (give resolution "
               ">= 4.19 n), got 200")
    with pytest.raises(ValueError) as error:
        camjax.residual_vibration(MODSINE, 200.0, resolution=256)
    assert str(error.value) == message


@pytest.mark.parametrize("transform", ["jit", "vmap", "grad"])
def test_a_traced_period_ratio_past_the_grid_raises_instead_of_a_number(transform):
    def ct(n):
        return camjax.torsion_factor(MODSINE, n)

    with pytest.raises(Exception, match=r"period ratio must be at most 168 "):
        if transform == "vmap":
            jax.vmap(ct)(jnp.array([5.0, 1e6]))
        else:
            getattr(jax, transform)(ct)(1e6)


@pytest.mark.parametrize("transform", ["jit", "jit-constant", "vmap", "grad", "eval_shape"])
@pytest.mark.parametrize("sweep", ["ct_curve", "ct_curves"])
def test_a_sweep_inside_a_transformation_is_refused_in_one_line(transform, sweep):
    """``ct_curve`` and ``ct_curves`` return NumPy arrays, so they cannot run inside jit,
    vmap or grad: one ``ValueError`` naming what traces instead, whether the ratios are
    traced or constants inside the trace (which failed in JAX's conversion before)."""
    def ct(n):
        curves = (camjax.ct_curve(MODSINE, n) if sweep == "ct_curve"
                  else camjax.ct_curves([MODSINE], n)[MODSINE.name])
        return curves.ct

    ratios = jnp.array([2.0, 3.0])
    with pytest.raises(ValueError, match=r"^a sweep \(ct_curve, ct_curves\) runs outside jit, "
                                         r"vmap and grad.*camjax.torsion_factor"):
        if transform == "jit-constant":
            jax.jit(lambda x: x * ct([2.0, 3.0])[0])(1.0)
        elif transform == "grad":
            jax.grad(lambda n: ct(n[None])[0])(jnp.array(2.0))
        elif transform == "eval_shape":
            jax.eval_shape(ct, ratios)
        else:
            getattr(jax, transform)(ct)(ratios if transform == "jit" else ratios[:, None])
    assert camjax.ct_curve(MODSINE, [2.0]).ct[0] == pytest.approx(
        float(camjax.torsion_factor(MODSINE, 2.0)), rel=COMPILED_RTOL)


def test_a_ca_ct_objective_past_the_largest_training_grid_is_refused():
    from camjax import law_design

    with pytest.raises(ValueError, match=r"^MaxCaCt: the training grid at period ratio 30000 needs [\d,]+ grid intervals"):
        law_design.MaxCaCt(1.0, 30000.0)
    law_design.MaxCaCt(1.0, 20000.0)  # within the limit


def test_residual_objectives_past_the_exact_paths_reach_and_oversized_designs_are_refused():
    from camjax import law_design

    past = (r"a rise at period ratio 300000 needs 1,256,640 grid intervals \(the limit is "
            r"1,048,576\): period ratios up to about 250,329 at the default resolution$")
    for make, name in ((lambda: law_design.Residual(3e5), "Residual"),
                       (lambda: law_design.MaxResidual(10.0, 3e5), "MaxResidual"),
                       (lambda: law_design.ExpectedResidual(2.9e5, 2.5e3), "ExpectedResidual")):
        with pytest.raises(ValueError, match=f"^{name}: {past}"):
            make()
    law_design.MaxResidual(10.0, 2.5e5)  # within the reach
    objective = law_design.Residual(3.0)
    with pytest.raises(ValueError, match=r"^knots must be from 1 to 200 .*got 201$"):
        law_design.design(objective, knots=201)
    with pytest.raises(ValueError, match=r"^steps must be from 1 to 1,000,000, got 1000001$"):
        law_design.design(objective, steps=1_000_001)


def test_gradient_at_the_traced_default_grid_matches_finite_differences():
    n, h = 6.4, 1e-4
    exact = float(jax.grad(lambda x: camjax.torsion_factor(MODSINE, x, 0.02))(n))
    fd = (float(camjax.torsion_factor(MODSINE, n + h, 0.02))
          - float(camjax.torsion_factor(MODSINE, n - h, 0.02))) / (2 * h)
    assert exact == pytest.approx(fd, rel=1e-5)


# --- law parameters checked when traced ---------------------------------------------------


def _residual_of_fractions(f):
    return camjax.residual_vibration(laws.SCCA(*f), 6.4)


@pytest.mark.parametrize("fractions", [[0.5, 0.5, 0.5], [-0.1, 0.6, 0.5], [np.nan, 0.0, 0.5],
                                       [0.0, 0.0, 0.0]])
def test_invalid_scca_fractions_raise_concrete_jit_and_grad(fractions):
    f = np.array(fractions)
    with pytest.raises(ValueError, match="SCCA fractions must"):
        laws.SCCA(*f)
    with pytest.raises(Exception, match=FRACTIONS_RULE.replace("+", r"\+")):
        jax.jit(_residual_of_fractions)(f)
    with pytest.raises(Exception, match=FRACTIONS_RULE.replace("+", r"\+")):
        jax.grad(_residual_of_fractions)(f)


def test_invalid_scca_fractions_raise_under_vmap_and_in_a_stack():
    rows = np.array([[0.25, 0.0, 0.75], [0.5, 0.5, 0.5]])
    with pytest.raises(Exception, match=FRACTIONS_RULE.replace("+", r"\+")):
        jax.vmap(_residual_of_fractions)(rows)
    with pytest.raises(ValueError, match="0 < a \\+ b \\+ c <= 1, got a \\+ b \\+ c = 1.5"):
        laws.SCCA(*rows.T)  # concrete, stacked


def test_valid_traced_fractions_give_the_concrete_value():
    f = np.array([0.25, 0.0, 0.75])
    assert float(jax.jit(_residual_of_fractions)(f)) == pytest.approx(
        float(_residual_of_fractions(f)), rel=1e-9)


def test_a_traced_spline_coefficient_that_is_not_finite_raises():
    start = laws.BSplineLaw.fit(laws.get("cycloidal"), 6)
    coefficients = np.asarray(start.coefficients).copy()

    def ca(c):
        return laws.BSplineLaw(c).Ca

    assert float(jax.jit(ca)(coefficients)) == pytest.approx(float(start.Ca), rel=1e-9)
    coefficients[2] = np.nan
    with pytest.raises(Exception, match="BSplineLaw coefficients must be finite"):
        jax.jit(ca)(coefficients)


# --- law names wherever a law is taken ----------------------------------------------------


def test_public_functions_take_law_names():
    n = [2.0, 5.5]
    by_law = camjax.ct_curve(laws.get("cycloidal"), n)
    np.testing.assert_allclose(camjax.ct_curve("cycloidal", n).ct, by_law.ct, rtol=COMPILED_RTOL)
    curves = camjax.ct_curves(["cycloidal", "scca:0.25,0,0.75"], n)
    assert list(curves) == ["cycloidal", "modified-sine"]
    np.testing.assert_allclose(curves["cycloidal"].ct, by_law.ct, rtol=COMPILED_RTOL)
    response = camjax.solve("modsine", SpringMass(5.5))
    assert float(response.metrics.ct) == pytest.approx(
        float(camjax.torsion_factor("modsine", 5.5)), rel=1e-9)
    impact = camjax.models.kinematic_impact("cycloidal", 0.05, 2.0)
    assert float(impact.impact_velocity) == float(
        camjax.models.kinematic_impact(laws.get("cycloidal"), 0.05, 2.0).impact_velocity)
    with pytest.raises(ValueError, match="unknown law 'nope'"):
        camjax.torsion_factor("nope", 3.0)
    with pytest.raises(TypeError, match="law must be a camjax motion law or a law name, got int"):
        camjax.ct_curve(3, n)


# --- errors under a caller's jit ----------------------------------------------------------


def test_a_traced_check_reads_as_docs_conventions_says():
    """camjax's entry points traced by grad alone: a one-line ValueError.  Under a caller's
    ``equinox.filter_jit`` and ``jax.jit`` the message is on the line docs/conventions.md
    names (JAX writes the rest of the report)."""
    bad = np.array([0.5, 0.5, 0.5])
    with pytest.raises(ValueError) as error:
        jax.grad(_residual_of_fractions)(bad)
    assert str(error.value) == FRACTIONS_RULE
    with pytest.raises(ValueError) as error:
        jax.grad(lambda n: camjax.torsion_factor(MODSINE, n))(1e6)
    assert str(error.value).splitlines()[0].startswith("period ratio must be at most 168 ")
    with pytest.raises(eqx.EquinoxRuntimeError) as error:
        eqx.filter_jit(_residual_of_fractions)(bad)
    assert f"equinox.EquinoxRuntimeError: {FRACTIONS_RULE}" in str(error.value).splitlines()
    with pytest.raises(Exception) as error:
        jax.jit(_residual_of_fractions)(bad)
    assert f"_EquinoxRuntimeError: {FRACTIONS_RULE}" in str(
        error.value).splitlines()


# --- the command line ---------------------------------------------------------------------


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_law_specs_split_at_commas_but_keep_scca_fractions():
    assert split_law_specs("scca:0.25,0,0.75") == ["scca:0.25,0,0.75"]
    assert split_law_specs("cycloidal,modsine") == ["cycloidal", "modsine"]
    assert split_law_specs("scca:0.3,0.2,0.5,poly:4,cycloidal") == [
        "scca:0.3,0.2,0.5", "poly:4", "cycloidal"]
    assert split_law_specs("law.json, cycloidal") == ["law.json", "cycloidal"]


def test_ct_takes_scca_fractions_and_a_law_file_beside_named_laws(capsys, tmp_path):
    spline = laws.BSplineLaw.fit(laws.get("cycloidal"), 6)
    path = laws.save(spline, tmp_path / "law.json")
    code, out, err = run(capsys, "ct", "--law", "scca:0.3,0.2,0.5", "--law", "cycloidal",
                         "--law", path, "--n", "2,5.5", "--format", "json")
    assert code == 0, err
    data = json.loads(out)["laws"]
    assert list(data) == ["scca:0.3,0.2,0.5", "cycloidal", "bspline:6"]
    expected = camjax.ct_curve(laws.SCCA(0.3, 0.2, 0.5), [2.0, 5.5])
    np.testing.assert_allclose(data["scca:0.3,0.2,0.5"]["ct"], expected.ct, rtol=COMPILED_RTOL)
    np.testing.assert_allclose(data["bspline:6"]["ct"], camjax.ct_curve(spline, [2.0, 5.5]).ct,
                               rtol=COMPILED_RTOL)


def test_backlash_takes_scca_fractions(capsys):
    code, out, err = run(capsys, "backlash", "--law", "scca:0.3,0.2,0.5,cycloidal", "--bk", "0.05",
                         "--dn", "2", "--format", "json")
    assert code == 0, err
    assert list(json.loads(out)["laws"]) == ["scca:0.3,0.2,0.5", "cycloidal"]


def test_every_option_with_a_default_states_it_in_help():
    """Each option entry of every subcommand's help (a line starting ``  -`` and its
    continuation lines) states the default, if the option has one."""
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    for name, sub in commands.items():
        entries: dict[str, str] = {}
        option = None
        for line in sub.format_help().split("options:")[-1].splitlines():
            if line.startswith("  -"):
                option = line.split()[0].rstrip(",")
                entries[option] = ""
            if option is not None:
                entries[option] += " " + line.strip()
        for action in sub._actions:
            if not action.option_strings or action.default in (None, False, "==SUPPRESS=="):
                continue
            entry = entries[action.option_strings[0]]
            assert "default" in entry, f"camjax {name} {action.option_strings[0]}: {entry}"


def test_bench_takes_scca_fractions_beside_a_named_law():
    from camjax.cli import laws_of

    args = build_parser().parse_args(["bench", "--law", "scca:0.3,0.2,0.5", "--law", "cycloidal"])
    assert list(laws_of(args)) == ["scca:0.3,0.2,0.5", "cycloidal"]


def _spec(tmp_path, body: str, name: str = "spec.toml"):
    path = tmp_path / name
    path.write_text(body)
    return path


GOOD_SPEC = 'output = "{out}"\n[period_ratio]\nvalues = [1.0]\n[laws]\nnames = ["cycloidal"]\n'


def _program(tmp_path, follower: str):
    text = (camjax.program.example_path().read_text().split("[follower]")[0]
            + "[follower]\n" + follower)
    path = tmp_path / "p.toml"
    path.write_text(text)
    return path


SWINGING = ('kind = "swinging-roller"\nmass_kg = 1.5\nstiffness_n_per_mm = 2000\n'
            'damping_ratio = 0.05\nspring_rate_n_per_mm = 10\npreload_n = 300\n'
            'base_radius_mm = 40\nroller_radius_mm = 12\npivot_mm = 120\n')


def _cases(tmp_path):
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    law_file = tmp_path / "bad.json"
    law_file.write_bytes(b"\xff\xfe\x00")
    a_file = tmp_path / "file"
    a_file.write_text("x")
    spec_damping = _spec(tmp_path, 'damping = "abc"\n' + GOOD_SPEC.format(out=tmp_path / "o"))
    twice = tmp_path / "twice.toml"
    twice.write_text(GOOD_SPEC.format(out=tmp_path / "o").replace(
        '"cycloidal"]', '"cycloidal", "cycloid"]'))
    unwritable = tmp_path / "unwritable.toml"
    unwritable.write_text(GOOD_SPEC.format(out=a_file / "sub"))
    return [
        (("program", binary),
         f"camjax program: error: {binary}: not a program file (TOML text), it is not UTF-8"),
        (("program", _program(tmp_path, SWINGING)),
         f"camjax program: error: {tmp_path / 'p.toml'}: follower.arm_mm is missing: a "
         "swinging-roller follower needs arm_mm and pivot_mm"),
        (("ct", "--law", law_file, "--n", "2"),
         f"camjax ct: error: --law: {law_file}: not a camjax law file (JSON text), it is not UTF-8"),
        (("sweep", spec_damping),
         f"camjax sweep: error: {spec_damping}: damping must be a number, got 'abc'"),
        (("sweep", twice),
         f"camjax sweep: error: {twice}: spec lists the law cycloidal twice (laws.names and the "
         "SCCA grid together must name each law once)"),
        (("sweep", unwritable),
         f"camjax sweep: error: {unwritable}: output: cannot write to directory "
         f"'{a_file / 'sub'}' (Not a directory)"),
        (("design", "--n", "3", "--damping", "1.2", "--out", tmp_path / "d"),
         "camjax design: error: --damping: damping ratio must be in [0, 1) (an underdamped "
         "payload), got 1.2"),
        (("design", "--n", "3", "--max-ca", "3", "--out", tmp_path / "d"),
         "camjax design: error: --max-ca = 3.0 is infeasible: every rise has Ca >= 4 (the "
         "parabolic law's bound)"),
        (("design", "--band", "1:30000", "--objective", "ca-ct", "--out", tmp_path / "d"),
         "camjax design: error: --band: the training grid at period ratio 30000 needs 1,508,096 "
         "grid intervals (the limit is 1,048,576): period ratios up to about 20,861"),
        (("ct", "--law", "cycloidal", "--n", "2", "--dwell", "1e4", "--model", "friction:0.1"),
         "camjax ct: error: dwell 10000 at 1024 samples per rise needs 10,241,024 samples; the "
         "limit is 1,000,000 (a shorter dwell, or fewer samples)"),
        (("bench", "--law", "cycloidal", "--n", "1:1e5:10"),
         "camjax bench: error: --n: the reference (the exact path on a grid four times finer "
         "than w h = 0.5) at period ratio 100000 needs 5,026,560 grid intervals (the limit is "
         "1,048,576): period ratios up to 20,860"),
        (("program", "--points", "1000000"),
         "camjax program: error: --points: must be from 8 to 100,000, got 1000000"),
        (("design", "--n", "1e6", "--out", tmp_path / "d"),
         "camjax design: error: --n: a rise at period ratio 1e+06 needs 4,188,800 grid intervals "
         "(the limit is 1,048,576): period ratios up to about 250,329 at the default "
         "resolution"),
        (("design", "--n", "240000", "--out", tmp_path / "d"),
         "camjax design: error: --n (compared over 0.8 to 1.2 times it): a rise at period ratio "
         "288000 needs 1,206,400 grid intervals (the limit is 1,048,576): period ratios up to "
         "about 250,329 at the default resolution"),
        (("design", "--band", "6:12", "--knots", "5000", "--out", tmp_path / "d"),
         "camjax design: error: --knots: must be from 1 to 200, got 5000"),
        (("design", "--band", "6:12", "--steps", "100000000000", "--out", tmp_path / "d"),
         "camjax design: error: --steps: must be from 1 to 1,000,000, got 100000000000"),
        (("sweep", _spec(tmp_path, GOOD_SPEC.format(out=tmp_path / "o"), "good.toml"), "--devices",
          "0"),
         "camjax sweep: error: --devices: must be between 1 and the "
         f"{jax.local_device_count()} local device(s), got 0"),
        (("ct", "--n", "2", "--method", "rk99"),
         "camjax ct: error: --method: unknown method 'rk99' for SpringMass; valid methods: "
         + ", ".join(SpringMass.methods)),
        (("follower", "--law", "cycloidal", "--rise", "10"),
         "camjax follower: error: --rise must be in (0, pi/2) rad, got 10.0"),
        (("follower", "--law", "cycloidal", "--radius", "1000"),
         "camjax follower: error: --radius must be well below the rod length"),
        (("follower", "--law", "cycloidal", "--modes", "0"),
         "camjax follower: error: --modes must be an integer 1..12, got 0"),
        (("ct", "--law", "scca:0.5,0.5,0.5", "--n", "2"),
         "camjax ct: error: --law: SCCA fractions must satisfy 0 < a + b + c <= 1, got "
         "a + b + c = 1.5"),
        (("ct", "--n", "2", "--model", "two-mass:-1,1"),
         "camjax ct: error: --model 'two-mass:-1,1': K must be positive and finite, got -1"),
        *[((*argv, "--out", out), f"camjax {argv[0]}: error: --out: cannot write to directory "
           f"'{out}' ({reason})")
          for argv in (("ct", "--n", "2"), ("backlash", "--bk", "0.1", "--dn", "1"),
                       ("program",), ("follower", "--law", "cycloidal"),
                       ("design", "--n", "3"))
          for out, reason in ((a_file / "sub", "Not a directory"),
                              ("/proc/x", "No such file or directory"))],
    ]


def test_bad_input_exits_2_with_one_line_naming_the_file_key_or_option(capsys, tmp_path):
    for argv, message in _cases(tmp_path):
        code, out, err = run(capsys, *argv)
        assert (code, out, err.strip()) == (2, "", message), argv


def test_solve_checks_a_traced_solution_when_it_runs():
    """``solve`` with its default ``throw=True`` inside jit, grad and vmap: a good solution
    gives the numbers of ``throw=False`` (it used to fail converting a tracer to NumPy), and
    a failed one fails the computation with one message instead of a number."""
    def ct(a, throw=True, model=None, **options):
        model = SpringMass(5.0) if model is None else model
        return camjax.solve(laws.SCCA(a, 0.0, 0.5), model, throw=throw, **options).metrics.ct

    expected = float(ct(0.4))
    assert float(jax.jit(ct)(0.4)) == pytest.approx(expected, rel=COMPILED_RTOL)
    assert float(jax.grad(ct)(0.4)) == pytest.approx(float(jax.grad(ct)(0.4, False)), rel=COMPILED_RTOL)
    np.testing.assert_allclose(jax.vmap(ct)(jnp.array([0.4, 0.4])), expected, rtol=COMPILED_RTOL)
    friction = camjax.CoulombFriction(1.0, 0.05)
    with pytest.raises(camjax.SolverError, match="max_steps"):
        ct(0.4, model=friction, max_steps=3)
    message = "events solve of CoulombFriction failed or produced non-finite values"
    for traced in (jax.jit(lambda a: ct(a, model=friction, max_steps=3)),
                   lambda a: jax.vmap(lambda x: ct(x, model=friction, max_steps=3))(jnp.array([a]))):
        with pytest.raises(Exception, match=message):
            traced(0.4)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, jnp.float32])
def test_a_low_precision_period_ratio_or_damping_is_widened_not_computed_in(dtype):
    """2.5 and 0 are exact in every float type: the result must be the float64 one (the
    closed form 2n|sin(pi n)| / |n^2 - 1|), concrete and traced alike."""
    law = camjax.laws.get("cycloidal")
    exact = 2 * 2.5 * abs(np.sin(np.pi * 2.5)) / abs(2.5**2 - 1)
    assert float(camjax.residual_vibration(law, dtype(2.5), 0.0)) == pytest.approx(exact, rel=1e-12)
    assert float(camjax.residual_vibration(law, 2.5, dtype(0.0))) == pytest.approx(exact, rel=1e-12)
    traced = jax.jit(lambda n: camjax.residual_vibration(law, n, 0.0))(jnp.asarray(2.5, jnp.float32))
    assert float(traced) == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("period_ratio, damping, shown", [
    (np.array([2.0, 3.0]), 0.0, "period_ratio.*got shape \\(2,\\)"),
    ("5", 0.0, "period_ratio.*got '5'"),
    (2.0, np.array([0.1, 0.2]), "damping.*got shape \\(2,\\)"),
    (2 + 0j, 0.0, "period_ratio.*got \\(2\\+0j\\)"),
])
def test_torsion_factor_takes_one_number_per_argument(period_ratio, damping, shown):
    law = camjax.laws.get("cycloidal")
    for metric in (camjax.torsion_factor, camjax.residual_vibration):
        with pytest.raises(ValueError, match=f"^{shown}$"):
            metric(law, period_ratio, damping)


# --- a law's parameters: what is wrong with them, in one line ---------------------------


@pytest.mark.parametrize("name, message", [
    ("modified-trapezoid-cv:P", "law 'modified-trapezoid-cv:P': P must be a number (the constant-velocity "
     "fraction, in [0, 1)), got 'P': in modified-trapezoid-cv:P, write a number in place of P"),
    ("poly:2.5", "law 'poly:2.5': K must be a whole number (the polynomial's order, 2 to 12), got '2.5'"),
    ("poly:", "law 'poly:': K is missing: poly:K takes a number there (the polynomial's order, 2 to 12)"),
    ("scca:0.2,0.5", "law 'scca:0.2,0.5': scca:A,B,C takes 3 numbers after the colon (the fractions of "
     "the rise), got 2"),
    ("cycloidal-asym:L", "law 'cycloidal-asym:L': L must be a number (the inflection point, in (0, 1)), "
     "got 'L': in cycloidal-asym:L, write a number in place of L"),
    ("triple-harmonic:1", "law 'triple-harmonic:1': triple-harmonic:A1,A2 takes 2 numbers after the colon "
     "(two amplitudes; A3 closes the rise), got 1"),
])
def test_a_laws_wrong_parameter_is_named_in_one_line(capsys, tmp_path, name, message):
    """Not the list of every law name: the parameter that is wrong and what it must be, from
    the library, the command and a program file alike."""
    with pytest.raises(ValueError) as error:
        laws.get(name)
    assert str(error.value) == message
    code, _, err = run(capsys, "ct", "--law", name, "--n", "1:2:3")
    assert code == 2 and err.strip() == f"camjax ct: error: --law: {message}"
    from camjax.program import Program, example_path

    text = example_path().read_text().replace('law = "cycloidal"', f'law = "{name}"')
    (tmp_path / "p.toml").write_text(text)
    with pytest.raises(ValueError) as error:
        Program.load(tmp_path / "p.toml")
    assert str(error.value) == f"{tmp_path / 'p.toml'}: segment 1: {message}"

"""The model interface: every model through every entry point, and the joins between them.

Bad input must raise whether it arrives concrete or traced (jit, vmap, grad); a non-model
is refused; the sweep of a model equals its solves one by one; the modules import in any
order (no import circle).
"""

import itertools
import subprocess
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import COMPILED_RTOL, EXAMPLES, SDOF_LIMITS, all_models, compiled_programs

import camjax
from camjax.models import (
    MODELS,
    AbstractMachineModel,
    Backlash,
    CoulombFriction,
    SpringMass,
    TwoMass,
)

LAW = camjax.laws.get("cycloidal")


def _torsion_factor(n, zeta=0.0):
    return camjax.torsion_factor(LAW, n, zeta, resolution=256)


BAD_PERIOD_RATIOS = [-3.0, 0.0, float("nan"), float("inf")]


@pytest.mark.parametrize("n", BAD_PERIOD_RATIOS)
def test_bad_period_ratio_raises_concrete_and_under_jit_grad_vmap(n):
    with pytest.raises(ValueError, match="period ratio must be positive"):
        _torsion_factor(n)
    with pytest.raises(Exception, match="period ratio must be positive"):
        jax.jit(_torsion_factor)(n)
    with pytest.raises(Exception, match="period ratio must be positive"):
        jax.grad(_torsion_factor)(n)
    with pytest.raises(Exception, match="period ratio must be positive"):
        jax.vmap(_torsion_factor)(jnp.array([3.0, n]))


@pytest.mark.parametrize("zeta", [-0.1, 1.0, 1.5, float("nan")])
def test_bad_damping_raises_concrete_and_traced(zeta):
    with pytest.raises(ValueError, match="damping ratio must be in"):
        _torsion_factor(3.0, zeta)
    with pytest.raises(Exception, match="damping ratio must be in"):
        jax.jit(lambda z: _torsion_factor(3.0, z))(zeta)
    with pytest.raises(Exception, match="damping ratio must be in"):
        jax.grad(lambda z: _torsion_factor(3.0, z))(zeta)


def test_good_input_under_jit_grad_vmap_gives_the_eager_numbers():
    eager = float(_torsion_factor(6.4, 0.02))
    assert float(jax.jit(_torsion_factor)(6.4, 0.02)) == pytest.approx(eager, rel=COMPILED_RTOL)
    batch = jax.vmap(_torsion_factor)(jnp.array([6.4, 3.0]), jnp.array([0.02, 0.0]))
    assert float(batch[0]) == pytest.approx(eager, rel=COMPILED_RTOL)
    h = 1e-5
    fd = (float(_torsion_factor(6.4 + h, 0.02)) - float(_torsion_factor(6.4 - h, 0.02))) / (2 * h)
    assert float(jax.grad(_torsion_factor)(6.4, 0.02)) == pytest.approx(fd, rel=1e-5)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda x: CoulombFriction(3.0, x), "friction must be >= 0"),
        (lambda x: Backlash(3.0, x, 1.0), "backlash bk must be positive"),
        (lambda x: Backlash(3.0, 0.1, x), "natural deceleration dn must be >= 0"),
        (lambda x: TwoMass(3.0, x, 1.0), "stiffness_ratio must be positive"),
        (lambda x: TwoMass(3.0, 1.0, x), "inertia_ratio must be >= 0"),
    ],
)
def test_model_parameters_are_checked_concrete_and_traced(make, message):
    with pytest.raises(ValueError, match=message):
        make(-1.0)
    # traced: the model's own check, which every solution path runs first
    with pytest.raises(Exception, match=message):
        jax.jit(lambda x: sum(jax.tree.leaves(make(x).validated())))(-1.0)


def test_solve_refuses_what_is_not_a_model_or_a_law():
    with pytest.raises(TypeError, match="model must be a camjax model"):
        camjax.solve(LAW, 6.4)
    with pytest.raises(TypeError, match="model must be a camjax model"):
        camjax.solve(LAW, {"period_ratio": 6.4})
    with pytest.raises(TypeError, match="law must be a camjax motion law or a law name, got float"):
        camjax.solve(3.0, SpringMass(6.4))
    with pytest.raises(TypeError, match="needs a motion law"):
        camjax.solve(None, SpringMass(6.4))
    with pytest.raises(ValueError, match="unknown method 'exact' for Backlash"):
        camjax.solve(LAW, Backlash(6.4, 0.1), method="exact")
    with pytest.raises(ValueError, match="unknown option 'resolution' for CoulombFriction"):
        camjax.solve(LAW, CoulombFriction(6.4, 0.1), resolution=512)
    with pytest.raises(TypeError, match="no period-ratio sweep"):
        camjax.ct_curve(LAW, [5.0], model=camjax.SwingingFollower())
    with pytest.raises(ValueError, match="give the damping in the model"):
        camjax.ct_curve(LAW, [5.0], model=CoulombFriction(1.0, 0.1), damping=0.05)


def test_a_period_ratio_too_large_for_memory_is_refused_before_any_work():
    with pytest.raises(ValueError, match=r"^a rise at period ratio 1e\+06 needs 4,188,800 grid intervals \(the limit is 1,048,576\)"):
        camjax.ct_curve(LAW, [1e6])


@pytest.mark.parametrize("template, tol", list(SDOF_LIMITS.values()), ids=list(SDOF_LIMITS))
def test_every_sdof_family_model_goes_through_solve_and_ct_curve_alike(template, tol):
    """One call shape for every model; the sweep equals the solves one by one, and with the
    extra physics switched off every model gives the SDOF's numbers."""
    ns = [3.3, 6.4]
    options = dict(samples=256)
    curve = camjax.ct_curve(LAW, ns, model=template, **options)
    assert curve.model == type(template).__name__
    for k, n in enumerate(ns):
        one = camjax.solve(LAW, template.with_period_ratio(n), **options)
        assert isinstance(one, camjax.Response)
        assert float(one.metrics.ct) == pytest.approx(curve.ct[k], rel=1e-8)
        assert float(one.metrics.residual) == pytest.approx(curve.residual[k], rel=1e-8)
        assert one.payload_acceleration.shape == one.tau.shape
    if tol is not None:  # damped like the SDOF
        sdof = camjax.ct_curve(LAW, ns, damping=0.05)
        np.testing.assert_allclose(curve.ct, sdof.ct, rtol=tol)
        np.testing.assert_allclose(curve.residual, sdof.residual, rtol=tol)
        np.testing.assert_allclose(curve.peak_in_motion, sdof.peak_in_motion, rtol=tol)


def test_throw_false_returns_the_result_code():
    response = camjax.solve(LAW, SpringMass(6.4), method="tsit5", max_steps=4, throw=False)
    assert not bool(response.result == camjax.RESULTS.successful)
    assert camjax.RESULTS[response.result] == camjax.RESULTS[camjax.RESULTS.max_steps_reached]
    with pytest.raises(camjax.SolverError, match="tsit5 solve of SpringMass.*maximum number"):
        camjax.solve(LAW, SpringMass(6.4), method="tsit5", max_steps=4)


def test_diffrax_codes_become_the_camjax_codes_of_the_same_name():
    """camjax's RESULTS is its own enumeration (the exact path never imports diffrax):
    every code diffrax has maps by name, batched and under jit, none to the fallback."""
    import diffrax

    from camjax.errors import promote

    names = list(diffrax.RESULTS._name_to_item)  # diffrax's own table of its codes
    assert "solver_failed" not in names  # camjax's fallback for a code it does not know
    assert all(hasattr(camjax.RESULTS, name) for name in names), names
    theirs = jax.tree.map(lambda *x: jnp.stack(x), *(getattr(diffrax.RESULTS, n) for n in names))
    ours = jax.jit(promote)(theirs)
    for i, name in enumerate(names):
        one = jax.tree.map(lambda x, i=i: x[i], ours)
        assert bool(one == getattr(camjax.RESULTS, name)), name
    assert promote(camjax.RESULTS.nonfinite) is camjax.RESULTS.nonfinite


def test_the_exact_path_imports_no_diffrax():
    """diffrax's import is a third of a second of every command's start: ``ct_curve`` and
    ``solve`` on the SDOF's exact path must not pay it (the diffrax models are lazy)."""
    code = ("import sys, camjax; from camjax.cli import ct; "
            "camjax.ct_curve(camjax.laws.get('cycloidal'), [2.0, 3.0]); "
            "camjax.solve(camjax.laws.get('poly345'), camjax.SpringMass(4.0)); "
            "ct.parse_model('spring-mass', 0.0); "
            "assert not {'diffrax', 'optimistix', 'lineax'} & set(sys.modules), 'imported'; "
            "camjax.models.Backlash; assert 'diffrax' in sys.modules")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr


def test_no_recompile_for_new_parameter_values():
    """Model parameters are traced leaves: one compilation serves every value."""
    camjax.solve(LAW, SpringMass(5.0, 0.01))
    with compiled_programs() as compiled:
        for n, zeta in [(5.5, 0.02), (7.0, 0.0)]:
            camjax.solve(LAW, SpringMass(n, zeta))
    assert "jit(_response)" not in compiled


MODULES = ["camjax.models", "camjax.sdof", "camjax.sweep", "camjax.laws", "camjax.errors"]


@pytest.mark.parametrize("order", list(itertools.permutations(MODULES, 3))[::7])
def test_submodules_import_in_any_order(order):
    code = "; ".join(f"import {m}" for m in order) + "; import camjax; camjax.solve"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr


def test_equinox_module_checks_hold():
    assert isinstance(SpringMass(2.0), eqx.Module)
    assert SpringMass.methods[0] == "exact" and Backlash.methods[0] == "tsit5"


def test_cli_refuses_a_huge_period_ratio_and_a_bad_model_before_any_work(capsys):
    from camjax.cli import main

    assert main(["ct", "--n", "1e6"]) == 2
    assert "needs 4,188,800 grid intervals" in capsys.readouterr().err
    assert main(["ct", "--n", "5", "--model", "bogus:1"]) == 2
    assert "unknown model" in capsys.readouterr().err
    assert main(["ct", "--n", "5", "--model", "backlash:0.1"]) == 2
    assert ("--model 'backlash:0.1': backlash takes 2 parameters, BK and DN (backlash:BK,DN), "
            "got 1") in capsys.readouterr().err
    assert main(["ct", "--n", "5", "--model", "friction:-1"]) == 2
    assert "--model 'friction:-1': MU must be >= 0" in capsys.readouterr().err


def test_only_models_that_ask_compile_their_solve_with_other_xla_options():
    """``solve`` and ``trace_solve`` pick one jitted program per model class: XLA's defaults
    for every SDOF-family model, the follower's own CPU options for the follower (its
    spectra under them are checked by the follower's tests), and XLA's defaults for it too
    inside a caller's ``jit`` (JAX refuses options on a nested program)."""
    from camjax.models import SwingingFollower, solve_program

    on_cpu = jax.default_backend() == "cpu"
    sdof = [solve_program(model) for _, model in all_models(swept=True)]
    assert all(p.compiler_options() == () for p in sdof)
    defaults = sdof[0].program()
    assert all(p.program() is defaults for p in sdof)  # one program for all of them
    own = (("xla_cpu_use_fusion_emitters", False),)
    assert SwingingFollower.cpu_compiler_options == own
    follower = solve_program(SwingingFollower())
    assert follower.compiler_options() == (own if on_cpu else ())
    assert (follower.program() is defaults) is not on_cpu
    picked = []
    jax.jit(lambda x: picked.append((follower.compiler_options(), follower.program())) or x)(1.0)
    assert picked == [((), defaults)]


def test_the_registry_and_the_test_table_list_the_same_models():
    """Every registered model has an example in tests/helpers.py (so the generic tests see
    it) and every swept one its SDOF limit; each example is the registry's class, and
    only machine models (holding their own laws) are not swept."""
    assert list(EXAMPLES) == [m.name for m in MODELS]
    assert set(SDOF_LIMITS) == {m.name for m in MODELS if m.swept} - {"spring-mass"}
    for entry, example in all_models():
        assert type(example) is entry.model_class()
        assert isinstance(example, AbstractMachineModel) == (not entry.swept)


@pytest.mark.parametrize("entry, example", all_models(swept=True), ids=lambda x: getattr(x, "name", ""))
def test_every_swept_model_is_reached_from_the_command_line(entry, example):
    """``--model NAME:V1,...`` builds the registry's class from its listed parameters, and
    ``solve``'s refusal of a non-model names every registered class."""
    from camjax.cli.ct import parse_model

    values = [float(getattr(example, field)) for field, _ in entry.parameters]
    text = entry.name + (":" + ",".join(map(str, values)) if values else "")
    template = parse_model(text, 0.0)
    assert type(template) is type(example)
    for field, _ in entry.parameters:
        assert float(getattr(template, field)) == float(getattr(example, field))
    with pytest.raises(TypeError, match=entry.class_name):
        camjax.solve(LAW, object())

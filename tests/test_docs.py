"""The API reference pages document every public name (the site's build is in CI)."""

import ast
import importlib
import inspect
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
API = ROOT / "docs" / "api"
# Module -> how its public names are found: a package's re-exports, or a module's own
# top-level definitions.
MODULES = ["camjax", "camjax.laws", "camjax.models", "camjax.law_design", "camjax.program", "camjax.sdof"]


def _resolve(path: str):
    module, _, name = path.rpartition(".")
    try:
        return getattr(importlib.import_module(module), name)
    except ModuleNotFoundError:
        return getattr(_resolve(module), name)


def _documented() -> dict[str, object]:
    entries = {}
    for page in sorted(API.glob("*.md")):
        for path in re.findall(r"^::: ([\w.]+)\s*$", page.read_text(), flags=re.M):
            entries[path] = _resolve(path)
    return entries


def _public(module_name: str) -> dict[str, object]:
    module = importlib.import_module(module_name)
    if hasattr(module, "__path__"):  # a package: what it re-exports (lazily: its __all__)
        names = [n for n in getattr(module, "__all__", vars(module)) if not n.startswith("_")
                 and n != "TYPE_CHECKING" and not isinstance(getattr(module, n), types.ModuleType)]
    else:  # a module: what it defines at top level
        tree = ast.parse(inspect.getsource(module))
        names = []
        for node in tree.body:
            if isinstance(node, ast.FunctionDef | ast.ClassDef):
                names.append(node.name)
            elif isinstance(node, ast.Assign):
                names += [t.id for t in node.targets if isinstance(t, ast.Name)]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names.append(node.target.id)
        names = [n for n in names if not n.startswith("_")]
    return {n: getattr(module, n) for n in names}


def test_api_entries_resolve():
    assert len(_documented()) > 50


@pytest.mark.parametrize("module_name", MODULES)
def test_every_public_name_has_an_api_entry(module_name):
    documented = _documented()
    by_identity = {id(obj) for obj in documented.values()}
    missing = [f"{module_name}.{name}" for name, obj in _public(module_name).items()
               if f"{module_name}.{name}" not in documented and id(obj) not in by_identity]
    assert not missing, f"add '::: NAME' entries to docs/api/*.md for {missing}"


def test_the_extending_page_runs(capsys):
    """docs/extending.md's examples, run as a reader would (its code blocks in order): the
    law written from scratch gives the built-in cycloidal's Ct curve, the loss-factor
    model SpringMass's at zeta = eta / 2 (sweep and solve), and the objective's training
    value (quadrature) its reported value (the exact path)."""
    code = "\n".join(re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "extending.md").read_text(),
                                flags=re.S))
    namespace = {}
    exec(compile(code, "docs/extending.md", "exec"), namespace)
    out = capsys.readouterr().out
    differences = [float(x) for x in re.findall(r"difference from [^:]*: (\S+)", out)]
    assert len(differences) == 2 and max(differences) < 5e-12  # rounding of two formulas
    # The probe's mean contact force against the mean lift's (trapezoid rules: 1e-5 apart).
    means = [tuple(map(float, m)) for m in re.findall(r"mean contact force (\S+) N, from the mean lift (\S+) N", out)]
    assert len(means) == 2 and all(abs(a - b) < 1e-4 * b for a, b in means), means
    ct = float(re.search(r"Ct at n = 6.4: (\S+)", out).group(1))
    import camjax

    law = camjax.laws.get("modified-sine")
    expected = float(camjax.solve(law, camjax.SpringMass(6.4, damping=0.05)).metrics.ct)
    assert ct == pytest.approx(expected, abs=1e-6)  # printed to six places
    training, reported = (float(x) for x in re.search(r"training value (\S+), reported (\S+)", out).groups())
    goal, law = namespace["goal"], namespace["law"]
    assert float(goal.train(law, law.Ca, 8.0)) == pytest.approx(goal.report(law), rel=1e-9)
    assert training == pytest.approx(reported, abs=1e-8)


def _readme_block(heading: str, language: str = "") -> str:
    """The first fenced block under a README heading."""
    readme = (ROOT / "README.md").read_text()
    match = re.search(rf"^## {heading}\n.*?^```{language}\n(.*?)^```", readme, flags=re.M | re.S)
    assert match, f"README has no ```{language} block under '## {heading}'"
    return match.group(1)


def test_ci_runs_the_readme_quick_start():
    commands = _readme_block("Quick start").strip().splitlines()
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert len(commands) == 2
    assert [line for line in ci if line in commands] == commands


@pytest.mark.slow  # the first jax.grad compiles for 13-15 s
def test_readme_library_example_prints_what_the_readme_shows():
    code = _readme_block("The library", "python")
    readme = (ROOT / "README.md").read_text()
    shown = re.search(r"^prints\n\n```\n(.*?)^```", readme, flags=re.M | re.S).group(1)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=True)
    assert done.stdout == shown

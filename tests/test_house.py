"""House rules of the library, checked on its own sources.

Tests, experiments and notebooks use camjax as a user does: through its public names.
A private module (``camjax.sdof._batch``) or a private name (``camjax.sweep._sweep``) may
change or vanish at any commit; code outside the library that reaches for one breaks
then, or, worse, keeps testing a helper the library no longer uses.
"""

import ast
import pathlib
import re

import pytest

from camjax.program import FOLLOWER_KINDS

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCANNED = ("tests", "experiments", "notebooks")


def _private(part: str) -> bool:
    """A leading underscore that is not a dunder (``__version__``, ``__main__`` are public)."""
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def _private_path(dotted: str) -> bool:
    return any(_private(part) for part in dotted.split("."))


def _dotted(node: ast.AST) -> list[str] | None:
    """``a.b.c`` as ``["a", "b", "c"]``; None when the chain does not start at a name."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return parts[::-1]


def private_uses(source: str) -> list[tuple[int, str]]:
    """Every use of a private camjax module or name in ``source``: (line, what).

    Caught: ``import camjax._x``, ``from camjax._x import y``, ``from camjax.x import _y``,
    ``module._y`` where ``module`` was bound to a camjax module by an import, and the
    ``setattr(module, "_y", ...)`` and ``getattr`` (``monkeypatch.setattr`` too), and the
    string forms ``"camjax.x._y"`` (``monkeypatch.setattr``, ``importlib.import_module``).
    """
    tree = ast.parse(source)
    found: list[tuple[int, str]] = []
    modules: set[str] = set()  # local names bound to camjax modules
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] != "camjax":
                    continue
                if _private_path(alias.name):
                    found.append((node.lineno, f"import {alias.name}"))
                modules.add(alias.asname or "camjax")
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "camjax":
                continue
            if _private_path(node.module):
                found.append((node.lineno, f"from {node.module} import ..."))
            for alias in node.names:
                if _private(alias.name):
                    found.append((node.lineno, f"from {node.module} import {alias.name}"))
                modules.add(alias.asname or alias.name)
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            chain = _dotted(node)
            if chain and chain[0] in modules:
                found.append((node.lineno, ".".join(chain)))
        elif isinstance(node, ast.Call) and len(node.args) >= 2:
            # setattr(module, "_x", ...), monkeypatch.setattr(module, "_x", ...), getattr
            target, name = node.args[0], node.args[1]
            chain = _dotted(target)
            if (chain and chain[0] in modules and isinstance(name, ast.Constant)
                    and isinstance(name.value, str) and _private(name.value)):
                found.append((node.lineno, f"{'.'.join(chain)}.{name.value}"))
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = node.value
            if (
                text.startswith("camjax.")
                and " " not in text
                and "\n" not in text
                and _private_path(text)
            ):
                found.append((node.lineno, repr(text)))
    return sorted(set(found))


def _sources():
    for folder in SCANNED:
        yield from sorted((ROOT / folder).rglob("*.py"))


def test_the_scanner_finds_each_form():
    """The checker itself: every form of private use is reported, public ones are not."""
    source = "\n".join(
        [
            "import camjax._shapes",
            "from camjax.sdof._batch import chunked",
            "from camjax.sweep import _sweep, prepare_sweep",
            "from camjax import sdof",
            "x = sdof._peaks",
            "import camjax.program as program",
            "program._groove.stroke_mm",
            "monkeypatch.setattr('camjax.cli._common.json_ready', f)",
            "import camjax, numpy",
            "camjax.__version__, numpy._core, obj._private",
            "from camjax import ModifiedSine",
            "monkeypatch.setattr(sdof, '_peak_search', {})",
            "setattr(numpy, '_x', 1); getattr(sdof, 'chunk_nodes')",
        ]
    )
    assert [line for line, _ in private_uses(source)] == [1, 2, 3, 5, 7, 8, 12]


@pytest.mark.parametrize("path", list(_sources()), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_camjax_outside_the_library(path):
    uses = private_uses(path.read_text())
    where = "; ".join(f"line {line}: {what}" for line, what in uses)
    assert not uses, f"{path.relative_to(ROOT)} uses private camjax names: {where}"


# --- inside the library: each package keeps its private names to itself -------------------

LIBRARY = ROOT / "camjax"


def _module_name(path: pathlib.Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _owner(module: str) -> str:
    """The package a module belongs to: ``camjax.sdof`` for ``camjax.sdof._grid``;
    ``camjax`` for the library's top-level modules (``camjax._traces``)."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 and (LIBRARY / parts[1]).is_dir() else "camjax"


def cross_package_private_uses(source: str, module: str, is_package: bool = False) -> list[tuple[int, str]]:
    """Every import in the library module ``module`` of a private name of another
    package: ``from camjax.sdof._grid import x`` or ``from ..sdof import _x`` inside
    ``camjax.program``, ``from .._traces import _memo`` anywhere.  The library's own
    top-level private modules (``camjax._plain``) are shared by its packages; their
    private names are not."""
    here = _owner(module)
    base = module.split(".") if is_package else module.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base[: len(base) - (node.level - 1)]
                target = ".".join(anchor + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names = [(target, alias.name) for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [(alias.name.rsplit(".", 1)[0], alias.name.rsplit(".", 1)[-1]) for alias in node.names]
        else:
            continue
        for target, name in names:
            if target.split(".")[0] != "camjax":
                continue
            full = f"{target}.{name}"
            owner = _owner(full if (LIBRARY.parent / full.replace(".", "/")).is_dir() else target)
            if owner == here:
                continue
            private_module = owner != "camjax" and _private_path(target.removeprefix(owner))
            if private_module or _private(name):
                found.append((node.lineno, f"from {target} import {name}"))
    return sorted(set(found))


def test_the_library_scanner_finds_each_form():
    source = "\n".join(
        [
            "from ..sdof._grid import piecewise_grid",
            "from ..sdof import _peaks",
            "from .._traces import kept",
            "from .._traces import _memo",
            "from ._dynamics import _cycle",
            "from camjax.metrics import _refine",
            "import camjax.sdof._batch",
            "from ..sdof import piecewise_grid",
        ]
    )
    found = cross_package_private_uses(source, "camjax.program.cycle")
    assert [line for line, _ in found] == [1, 2, 4, 6, 7]


@pytest.mark.parametrize("path", sorted(LIBRARY.rglob("*.py")), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_package_imports_a_private_name_of_another(path):
    module = _module_name(path)
    uses = cross_package_private_uses(path.read_text(), module, path.name == "__init__.py")
    where = "; ".join(f"line {line}: {what}" for line, what in uses)
    assert not uses, f"{path.relative_to(ROOT)} imports private names of another package: {where}"


@pytest.mark.parametrize("path", sorted(LIBRARY.rglob("__init__.py")), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_name_of_a_package_all_is_defined(path):
    """``from camjax.x import *`` works: each name ``__all__`` lists is bound in the package."""
    import importlib

    module = importlib.import_module(_module_name(path))
    missing = [name for name in getattr(module, "__all__", ()) if not hasattr(module, name)]
    assert not missing, f"{_module_name(path)}.__all__ names what it does not define: {missing}"


# --- the follower's kind is read in one place -------------------------------------------------

KIND_TEST = re.compile(r"""(endswith|startswith)\(\s*["'](-?flat|-?roller|swinging|translating)""", re.IGNORECASE)


def _library_sources():
    return [p for p in sorted(LIBRARY.rglob("*")) if p.suffix in (".py", ".js", ".html")]


@pytest.mark.parametrize("kind", list(FOLLOWER_KINDS))
def test_a_follower_kind_is_named_only_by_its_class(kind):
    """Each kind's name is written once in the library, as its ``camjax.geometry`` class's
    ``name``; the program's reader maps it to the class (``FOLLOWER_KINDS``), and every
    other place asks the class (its methods, ``swinging``, ``max_pressure_angle_deg``), so
    a new kind is one class and its entry in the reader."""
    quoted = re.compile(rf"""["']{re.escape(kind)}["']""")
    hits = [f"{path.relative_to(ROOT)}:{i}: {line.strip()}" for path in _library_sources()
            for i, line in enumerate(path.read_text().splitlines(), 1) if quoted.search(line)]
    cls = FOLLOWER_KINDS[kind]
    assert len(hits) == 1 and hits[0].startswith("camjax/geometry.py:") and f'name: ClassVar[str] = "{kind}"' in hits[0], (
        f"the kind {kind!r} is written outside its class ({cls.__name__}): {hits}")


def test_no_follower_kind_is_told_by_its_spelling():
    hits = [f"{path.relative_to(ROOT)}:{i}: {line.strip()}" for path in _library_sources()
            for i, line in enumerate(path.read_text().splitlines(), 1) if KIND_TEST.search(line)]
    assert not hits, f"a follower kind told by its name's spelling, not its class: {hits}"


def test_the_kind_scanner_finds_each_form():
    lines = ['f.kind.endswith("-flat")', "kind.startswith('swinging')", 'name.endswith(".toml")',
             '(f.kind || "").endsWith("-flat")', 'x.startswith("translating")']
    assert [bool(KIND_TEST.search(line)) for line in lines] == [True, True, False, True, True]

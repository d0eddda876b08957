"""Every module says what it holds and what of it is public: a module docstring of at most
300 words (the derivations live in the explanation pages of docs/), and an ``__all__`` whose
every name the module has (read off the source files, so a module without one is caught
whether or not something imports it)."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

import rockdec

PACKAGE = Path(rockdec.__file__).resolve().parent

#: The longest module docstring, in words.
MAX_WORDS = 300


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


SOURCES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def declared_all(module: str) -> list[str] | None:
    """The names of the module's top-level ``__all__`` (None without one): the literal list,
    else (a package's, computed from its modules') the imported module's."""
    for node in ast.parse(SOURCES[module].read_text(encoding="utf-8")).body:
        target = node.targets[0] if isinstance(node, ast.Assign) else node.target if isinstance(node, ast.AnnAssign) else None
        if isinstance(target, ast.Name) and target.id == "__all__":
            try:
                return list(ast.literal_eval(node.value))
            except ValueError:
                return list(importlib.import_module(module).__all__)
    return None


def test_every_module_is_read():
    assert {"rockdec", "rockdec.rdd.signatures", "rockdec.physics", "rockdec.__main__"} <= set(SOURCES)


@pytest.mark.parametrize("module", sorted(SOURCES))
def test_module_declares_all(module):
    names = declared_all(module)
    assert names is not None, f"{module} has no __all__"
    assert len(set(names)) == len(names), f"{module}.__all__ lists a name twice"


@pytest.mark.parametrize("module", sorted(m for m in SOURCES if m != "rockdec.__main__"))  # importing __main__ runs the command line
def test_all_names_exist(module):
    mod = importlib.import_module(module)
    missing = [name for name in declared_all(module) or [] if not hasattr(mod, name)]
    assert not missing, f"{module}.__all__ names what the module lacks: {missing}"


@pytest.mark.parametrize("module", sorted(SOURCES))
def test_module_docstring_is_short(module):
    doc = ast.get_docstring(ast.parse(SOURCES[module].read_text(encoding="utf-8")))
    assert doc, f"{module} has no module docstring"
    assert len(doc.split()) <= MAX_WORDS, f"{module}'s docstring has {len(doc.split())} words (at most {MAX_WORDS}; derivations go to docs/explanation)"


@pytest.mark.parametrize("package", ["rockdec.rdd", "rockdec.physics", "rockdec.estimation"])
def test_package_re_exports_its_modules(package):
    """The package's ``__all__`` is the union of its submodules' ``__all__``, each name the
    very object of the submodule it is defined in."""
    pkg = importlib.import_module(package)
    subs = {m: declared_all(m) for m in SOURCES if m.startswith(package + ".")}
    assert set(pkg.__all__) == set().union(*subs.values())
    for sub, names in subs.items():
        mod = importlib.import_module(sub)
        for name in names:
            assert getattr(pkg, name) is getattr(mod, name), f"{package}.{name} is not {sub}.{name}"


@pytest.mark.parametrize("module", ["rockdec", "rockdec.rdd.registry", "rockdec.physics.geometry"])
def test_packages_import_lazily(module):
    """Importing a package, or a light module of one, loads no numba kernel and no xarray."""
    code = f"import sys, {module}; print(sorted(m for m in ('numba', 'xarray', 'dask', 'rockdec.rdd.signatures', 'rockdec.physics.simulate') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", f"import {module} loads {out.strip()}"

"""The package's layers run one way: no module imports a higher layer, at module level or
inside a function (the import graph read off every source file's syntax tree)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import rockdec

PACKAGE = Path(rockdec.__file__).resolve().parent

#: The layers from the ground up; a module belongs to the first prefix it matches.
LAYERS = [
    ("base", ("rockdec._version", "rockdec.validate", "rockdec.timeaxis", "rockdec.console", "rockdec.sources", "rockdec.io",
              "rockdec.engine", "rockdec.cache", "rockdec.locks", "rockdec.warning_types", "rockdec.lazy")),
    ("physics", ("rockdec.physics",)),
    ("analysis", ("rockdec.rdd", "rockdec.free")),
    ("record", ("rockdec.record",)),
    ("calibrate", ("rockdec.calibrate",)),
    ("estimation", ("rockdec.estimation",)),
    ("report", ("rockdec.report",)),
    ("pipeline and studies", ("rockdec.pipeline", "rockdec.studies")),
    ("front door", ("rockdec.api", "rockdec.cli", "rockdec.__main__", "rockdec")),
]


def layer(module: str) -> int:
    for rank, (_, prefixes) in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes if p != "rockdec") or module == "rockdec" and "rockdec" in prefixes:
            return rank
    raise AssertionError(f"{module} belongs to no layer of LAYERS; place it")


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def is_module(name: str) -> bool:
    """Whether ``name`` is a module or package of rockdec's source (read off the files)."""
    base = PACKAGE.parent.joinpath(*name.split("."))
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def imported(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every rockdec module ``path`` imports, anywhere in the file."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.split(".")[0] == "rockdec"]
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "rockdec" and node.level == 0:
            for a in node.names:
                sub = f"{node.module}.{a.name}"
                out.append((node.lineno, sub if is_module(sub) else node.module))
    return out


SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_has_a_layer():
    for path in SOURCES:
        layer(module_name(path))


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: module_name(p))
def test_no_module_imports_a_higher_layer(path):
    me = module_name(path)
    if me == "rockdec":  # the package's face hands the public names on (imported lazily, by name)
        return
    upward = [f"line {line}: {name} ({LAYERS[layer(name)][0]})" for line, name in imported(path) if layer(name) > layer(me)]
    assert not upward, f"{me} ({LAYERS[layer(me)][0]}) imports a higher layer: " + "; ".join(upward)


def test_the_contract_sees_an_upward_import(tmp_path):
    """The check itself: an import from the physics layer up to the command line is found."""
    bad = tmp_path / "bad.py"
    bad.write_text("def f():\n    from rockdec.cli import main\n")
    assert [name for _, name in imported(bad) if layer(name) > layer("rockdec.physics.models")] == ["rockdec.cli"]

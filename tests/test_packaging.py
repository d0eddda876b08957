"""What a user installs: the version the command reports and the data files the wheel carries.

`.ci/run` builds the wheel, installs it in a fresh virtualenv and runs the command from an
empty folder; these tests are the fast guard in the suite.
"""

import fnmatch
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import yaml

from rockdec import __version__

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "src" / "rockdec"


def test_version_option_prints_the_installed_distribution_version():
    proc = subprocess.run([sys.executable, "-m", "rockdec.cli", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"rockdec {metadata.version('rockdec')}"
    assert __version__ == metadata.version("rockdec")


def test_installed_version_is_the_one_pyproject_declares():
    declared = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    assert metadata.version("rockdec") == declared


def test_package_data_globs_cover_every_data_file_of_the_package():
    globs = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["rockdec"]
    data = [
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*")
        if p.is_file() and p.suffix != ".py" and "__pycache__" not in p.parts
    ]
    assert "scene_schema.yaml" in data  # the file config.schema() reads
    missing = [f for f in data if not any(fnmatch.fnmatch(f, g) for g in globs)]
    assert not missing, f"add these to [tool.setuptools.package-data]: {missing}"


def test_citation_and_licence_agree_with_the_package_metadata():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    cff = yaml.safe_load((REPO / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["version"] == project["version"]
    assert cff["license"] == project["license"]["text"] == "MIT"
    assert (REPO / "LICENSE").read_text().startswith("MIT License")
    paper = cff["references"][0]
    assert paper["title"] in " ".join((REPO / "README.md").read_text().split())  # the paper the README names
    assert paper["authors"] and all(a.get("family-names") or a.get("name") for a in paper["authors"])  # CFF: a person or an entity


def test_readme_layout_map_lists_every_module():
    readme = (REPO / "README.md").read_text()
    layout = readme[readme.index("## Layout") :]
    modules = [p.name for p in PACKAGE.glob("*.py") if p.name != "__init__.py"]
    assert [m for m in modules if m not in layout] == []


def test_package_holds_no_reference_implementations():
    """Reference implementations serve tests and benchmarks only; they live under tests/."""
    import ast

    for path in PACKAGE.glob("*.py"):
        names = [node.name for node in ast.walk(ast.parse(path.read_text())) if isinstance(node, (ast.FunctionDef, ast.ClassDef))]
        assert [n for n in names if n.lstrip("_").startswith("reference")] == [], path.name

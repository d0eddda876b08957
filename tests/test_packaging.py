"""What a user installs and gets: the version the command reports, the data files the wheel
carries, the dependencies each use needs, files as readable as the umask says, provenance
that names rockdec's own source.

`.ci/run` builds the sdist and the wheel, installs the wheel in a fresh virtualenv, runs the
command from an empty folder without the workflow's dependencies, then the tiny scene with
them; these tests are the fast guard in the suite.
"""

import fnmatch
import json
import os
import re
import shutil
import stat
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr
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
    assert cff["license"] == project["license"] == "MIT"  # an SPDX expression (PEP 639)
    assert project["license-files"] == ["LICENSE"]
    assert (REPO / "LICENSE").read_text().startswith("MIT License")
    paper = cff["references"][0]
    assert paper["title"] in " ".join((REPO / "README.md").read_text().split())  # the paper the README names
    assert paper["authors"] and all(a.get("family-names") or a.get("name") for a in paper["authors"])  # CFF: a person or an entity


def test_the_layout_map_lists_every_module():
    layout = (REPO / "docs" / "development" / "layout.md").read_text()
    lines = layout.splitlines()
    missing = []
    for path in PACKAGE.rglob("*.py"):
        package = path.parent.relative_to(PACKAGE).as_posix()
        if path.name == "__init__.py":
            listed = package == "." or any(line.lstrip().startswith(f"{package}/") for line in lines)
        else:  # named on a line of its package's block
            block = layout[layout.index(f"  {package}/ ") :] if package != "." else layout
            listed = path.name in block
        if not listed:
            missing.append(path.relative_to(PACKAGE).as_posix())
    assert missing == []


def test_package_holds_no_reference_implementations():
    """Reference implementations serve tests and benchmarks only; they live under tests/."""
    import ast

    for path in PACKAGE.rglob("*.py"):
        names = [node.name for node in ast.walk(ast.parse(path.read_text())) if isinstance(node, (ast.FunctionDef, ast.ClassDef))]
        assert [n for n in names if n.lstrip("_").startswith("reference")] == [], path.name


def _requirement_names(requirements) -> set[str]:
    return {re.split(r"[<>=!~\[ ;]", r, maxsplit=1)[0].lower() for r in requirements}


def test_the_package_alone_needs_no_snakemake_and_the_workflow_extra_brings_it():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    core = _requirement_names(project["dependencies"])
    extras = project["optional-dependencies"]
    assert not {name for name in core if name.startswith("snakemake")}
    assert "snakemake" in _requirement_names(extras["workflow"])
    assert "rockdec[workflow]" in extras["test"] and "rockdec[workflow]" in extras["cluster"]
    assert "platformdirs" in core  # read by `rockdec estimate` for its cache folder


def test_every_declared_dependency_is_pinned_in_the_constraints():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    pinned = {line.split("==")[0].lower().replace("_", "-") for line in (REPO / "constraints.txt").read_text().split() if "==" in line}
    declared = _requirement_names([*project["dependencies"], *(r for extra in project["optional-dependencies"].values() for r in extra)])
    assert declared - {"rockdec"} <= pinned


def test_the_rules_conda_environment_pins_every_runtime_dependency_as_tested_and_not_rockdec():
    """`--sdm conda`: the environment holds rockdec's dependencies at the tested versions; the
    scripts import the rockdec that runs Snakemake (Snakemake appends its own search path to
    theirs), so no rockdec is pinned there (it is not on a package index)."""
    import yaml

    env = yaml.safe_load((REPO / "workflow" / "envs" / "rockdec.yaml").read_text())
    pip = next(d["pip"] for d in env["dependencies"] if isinstance(d, dict))
    in_env = {line.split("==")[0].lower(): line.split("==")[1] for line in pip}
    tested = {line.split("==")[0].lower(): line.split("==")[1] for line in (REPO / "constraints.txt").read_text().split() if "==" in line}
    runtime = _requirement_names(tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"])
    assert "rockdec" not in in_env
    assert {name: in_env.get(name) for name in runtime} == {name: tested[name] for name in runtime}


def test_metadata_has_classifiers_and_no_invented_url():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert "Topic :: Scientific/Engineering" in project["classifiers"]
    assert not any(c.startswith("License ::") for c in project["classifiers"])  # PEP 639: the licence is the SPDX string
    assert "urls" not in project  # the project has no public home yet: no address is made up


def test_the_sdist_template_carries_the_test_helpers_and_the_workflow():
    lines = (REPO / "MANIFEST.in").read_text().splitlines()
    assert "graft tests" in lines  # tests/cf_check.py, tests/rocking_reference.py
    assert {"include Snakefile", "graft workflow", "graft config", "graft profiles"} <= set(lines)


def test_products_are_as_readable_as_the_umask_says(tmp_path):
    """Under umask 022 every product, NetCDF, CSV, Markdown, PNG and JSON, is 0644."""
    from matplotlib.figure import Figure

    from rockdec.report import figures, tables
    from rockdec import io

    old = os.umask(0o022)
    try:
        io.write_netcdf(xr.Dataset({"x": ("t", np.arange(3.0))}), tmp_path / "a.nc")
        tables.write_table(pd.DataFrame({"a": [1.0]}), tmp_path / "t.csv", tmp_path / "t.md")
        fig = Figure(figsize=(2, 2))
        fig.add_subplot().plot([0, 1])
        figures.save(fig, [tmp_path / "f.png", tmp_path / "f.pdf"])
        (tmp_path / "run.json").write_text(json.dumps({}))
    finally:
        os.umask(old)
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in tmp_path.iterdir()}
    assert modes == {name: 0o644 for name in ("a.nc", "t.csv", "t.md", "f.png", "f.pdf", "run.json")}


def test_provenance_names_rockdec_s_own_commit_from_its_checkout():
    from rockdec import io

    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=PACKAGE, capture_output=True, text=True)
    if head.returncode != 0:
        pytest.skip("not run from a git checkout")
    assert io.git_commit() == head.stdout.strip()
    assert io.git_dirty() in (True, False)


def test_provenance_records_no_commit_when_installed_inside_another_repository(tmp_path):
    """A copy of the package in some project's git repository (a virtualenv inside it): the
    files it writes must not name that repository's commit nor its changes."""
    other = tmp_path / "project"
    site = other / ".venv" / "site-packages"
    shutil.copytree(PACKAGE, site / "rockdec", ignore=shutil.ignore_patterns("__pycache__", "_workflow"))
    (other / "pyproject.toml").write_text("[project]\nname = 'other'\n")
    (other / "notes.txt").write_text("uncommitted")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "init", "-q"], cwd=other, check=True)
    subprocess.run([*git, "add", "pyproject.toml"], cwd=other, check=True)
    subprocess.run([*git, "commit", "-qm", "other project"], cwd=other, check=True)
    code = "from rockdec import io; a = io.provenance('simulate'); print(io.__file__, a['git_commit'], io.git_dirty())"
    proc = subprocess.run([sys.executable, "-c", code], cwd=other, env={**os.environ, "PYTHONPATH": str(site)},
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    where, commit, dirty = proc.stdout.split()
    assert Path(where).is_relative_to(site)  # the copy ran, not the checkout
    assert commit == "unknown" and dirty == "None"


def test_every_dotted_rockdec_name_in_the_docs_and_docstrings_resolves():
    """``rockdec.<package>.<module>.<name>`` written in the package, the docs, the README or the
    workflow names something that exists (a module moved or a function renamed leaves none
    behind)."""
    import importlib
    import re

    texts = [*PACKAGE.rglob("*.py"), *(p for p in (REPO / "docs").rglob("*.md") if "_build" not in p.parts), REPO / "README.md", *(REPO / "workflow").rglob("*.smk"), *(REPO / "workflow").rglob("*.py")]
    stale = set()
    for path in texts:
        for ref in set(re.findall(r"\brockdec(?:\.[A-Za-z_]\w*)+", path.read_text())):
            if ref.endswith(".yaml"):  # the conda environment file workflow/envs/rockdec.yaml
                continue
            parts = ref.split(".")
            for i in range(len(parts), 0, -1):  # the longest importable module prefix
                try:
                    obj = importlib.import_module(".".join(parts[:i]))
                    break
                except ImportError:
                    continue
            for part in parts[i:]:
                if not hasattr(obj, part):
                    stale.add(f"{path.relative_to(REPO)}: {ref}")
                    break
                obj = getattr(obj, part)
    assert sorted(stale) == []

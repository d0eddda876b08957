"""Build hook: the wheel carries the workflow (Snakefile, workflow/, config/, profiles/) as
``rockdec/_workflow``, so ``rockdec workflow`` runs it from an install. Everything else
is declared in pyproject.toml."""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

#: The workflow's files, relative to the project's top folder (rockdec.cli.WORKFLOW_FILES).
WORKFLOW_FILES = ("Snakefile", "workflow", "config", "profiles")


class BuildWithWorkflow(build_py):
    """``build_py``, then a copy of the workflow into ``rockdec/_workflow`` of the build
    (an editable install runs the checkout's workflow instead)."""

    def run(self):
        super().run()
        if self.editable_mode:
            return
        here = Path(__file__).resolve().parent
        target = Path(self.build_lib) / "rockdec" / "_workflow"
        for name in WORKFLOW_FILES:
            source = here / name
            if source.is_dir():
                shutil.copytree(source, target / name, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
            else:
                target.mkdir(parents=True, exist_ok=True)
                shutil.copy2(source, target / name)


setup(cmdclass={"build_py": BuildWithWorkflow})

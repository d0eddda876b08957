"""The documentation's generated reference covers the command line and the scene schema.

A new option of the parser or a new field of the schema that the reference pages would not
show fails here, without building the site (the build itself, `sphinx-build -W -n`, runs in
CI: `.ci/run`).
"""

import argparse
import re
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
sys.path.insert(0, str(DOCS / "_ext"))

import rockdec_docs  # noqa: E402

from rockdec import cli  # noqa: E402


def options_of(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    """Every option string and positional name of one parser (not its subcommands')."""
    out = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        for name in action.option_strings or [action.dest]:
            out[name] = action
    return out


def parsers() -> dict[str, argparse.ArgumentParser]:
    """The main parser (``""``) and each subcommand's, by the path sphinx-argparse takes."""
    main = cli.build_parser()
    return {"": main, **rockdec_docs.subcommands(main)}


def test_the_cli_reference_renders_every_subcommand_and_shows_every_option():
    main = cli.build_parser()
    page = rockdec_docs.cli_markdown(main)
    assert "{include} _includes/cli.md" in (DOCS / "reference" / "cli.md").read_text()
    for path, parser in parsers().items():
        directive = f":path: {path}" if path else ":nosubcommands:"
        assert directive in page, path
        for name, action in options_of(parser).items():
            # sphinx-argparse leaves out what argparse hides: every option must have its help
            assert action.help is not argparse.SUPPRESS and action.help, f"rockdec {path} {name} has no help text"


def test_sphinx_argparse_lists_every_option_of_every_subcommand():
    parser_module = pytest.importorskip("sphinxarg.parser")  # the docs extra
    main = cli.build_parser()
    rendered = parser_module.parse_parser(main)
    by_path = {"": rendered, **{child["name"]: child for child in rendered["children"]}}
    for path, parser in parsers().items():
        shown = {name for group in by_path[path]["action_groups"] for option in group["options"] for name in option["name"]}
        missing = sorted(set(options_of(parser)) - shown - {"-h", "--help", "help"})
        assert missing == [], f"rockdec {path}: {missing}"


def test_the_scene_reference_lists_every_field_of_both_schemas():
    page = rockdec_docs.scene_config_markdown(rockdec_docs.load_schema())
    assert "{include} _includes/scene-config.md" in (DOCS / "reference" / "scene-config.md").read_text()
    for schema in (rockdec_docs.load_schema(), yaml.safe_load((REPO / "config" / "schema.yaml").read_text())):
        fields = [path for path, _ in rockdec_docs.schema_fields(schema)]
        assert "scenes.<name>.system.e" in fields and "coverage.records" in fields
        for path in fields:
            assert f"| `{path}` |" in page, path


def test_the_json_reference_lists_every_key_of_an_estimate():
    schema = rockdec_docs.load_estimate_schema()
    page = rockdec_docs.estimate_json_markdown(schema)
    assert "{include} _includes/estimate-json.md" in (DOCS / "reference" / "outputs.md").read_text()
    kinds = rockdec_docs.estimate_kinds(schema)
    assert set(kinds) == {"random", "free"}
    for kind in kinds.values():
        for key in kind["properties"]:
            assert f"| `{key}` |" in page, key


def test_every_scene_field_of_the_shipped_config_is_documented():
    """Each key the workflow's own scenes set is a documented field (nothing undeclared)."""
    documented = {path for path, _ in rockdec_docs.schema_fields(rockdec_docs.load_schema())}
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text())

    def walk(node, path):
        for key, value in node.items():
            here = f"{path}.{key}" if path else key
            if here.startswith("scenes.") and here.count(".") == 1:
                here = "scenes.<name>"
            assert here in documented or here == "scenes.<name>", here
            if isinstance(value, dict):
                walk(value, here)

    walk(config, "")


def test_the_glossary_page_holds_every_word_the_command_prints():
    from rockdec.report.glossary import GLOSSARY

    entries = rockdec_docs.glossary_entries(GLOSSARY)
    assert len(entries) >= 10 and all(word and meaning for word, meaning in entries)
    page = rockdec_docs.glossary_markdown(GLOSSARY)
    for word, _ in entries:
        assert f"`{word}`" in page


def test_the_readme_is_a_front_door():
    readme = (REPO / "README.md").read_text()
    assert len(readme.split()) <= 1200
    first_screen = "\n".join(readme.splitlines()[:40])
    ci = (REPO / ".ci" / "run").read_text()
    commands = re.findall(r"```bash\n(.*?)\n```", first_screen, flags=re.S)
    assert any("snakemake --cores 2" in c for c in commands)
    test_command = next(c for c in commands if "pytest" in c)
    assert test_command in ci  # the README's test command is what CI runs
    example = readme.split("<!-- example-start -->", 1)[1].split("<!-- example-end -->", 1)[0]
    assert "import rockdec" in example  # run as written by tests/api/test_public_api.py


def test_every_page_of_the_docs_is_linked_from_a_toctree():
    """Sphinx warns (and -W fails) on an orphan page; this says which one without a build."""
    pages = {p.relative_to(DOCS).with_suffix("").as_posix() for p in DOCS.rglob("*.md")
             if not {"_build", "generated", "_includes", "api"} & set(p.relative_to(DOCS).parts)}
    listed = {"index"}
    for page in pages:
        text = (DOCS / f"{page}.md").read_text()
        for block in re.findall(r"```\{toctree\}\n(.*?)```", text, flags=re.S):
            for line in block.splitlines():
                if line and not line.startswith(":"):
                    listed.add((Path(page).parent / line.strip()).as_posix().removeprefix("./"))
    assert sorted(pages - listed) == []


def test_every_relative_link_of_the_readme_reaches_a_file():
    """The README is not a page of the site (Sphinx's -n does not check it): its links into
    the docs and the repository must name files that exist."""
    readme = (REPO / "README.md").read_text()
    targets = [t.split("#", 1)[0] for t in re.findall(r"\]\(([^)\s]+)\)", readme) if "://" not in t]
    assert targets and sorted(t for t in targets if not (REPO / t).exists()) == []

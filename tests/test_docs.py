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
    assert set(kinds) == {"random", "free", "shake"}
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


# Prose pages whose numbers a reader takes for what the code does now: a study result typed
# into them goes stale silently, so they point to the study instead (its tables are included
# from the files the workflow writes, stamped with their commit). "." is the pages at the top.
PROSE_PAGES = ("explanation", "how-to", "getting-started", "reference", "development", ".")

# Fenced blocks that are not prose: code, and the directives that include generated files.
NOT_PROSE = ("{include}", "{toctree}", "{code-block}", "{code-cell}", "{literalinclude}", "{code}")

# What a hand-typed study result looks like.
STUDY_NUMBER = {
    "a percentage with decimals": r"(?<![\w.])(\d+\.\d+) ?%",
    "a timing": r"(?<![\w.])\d+(?:\.\d+)? ?(?:ms|us|s of CPU|s wall|s of wall|CPU-seconds|CPU-hours|minutes of CPU)\b",
    "a count of study records": r"(?<![\w.])\d[\d,]* of (?:the |its |their )?\d[\d,]* (?:\w+ )?(?:records|sets|pairs|cells|runs)\b",
    "a coverage": r"\bcover(?:s|ed)\s+\d",
    "a measured value": r"\bmeasured\s+(?:at|on|to|in|as|by)\b[^.;:\n]{0,60}?(?<![\w.])\d+(?:\.\d+)?\b",
}


def design_percentages() -> set[str]:
    """Percentages with decimals that are settings of the code, not study results."""
    from rockdec.calibrate import calibration, consistency
    from rockdec import estimation
    from rockdec.record import diagnostics, record_measure

    shares = [
        diagnostics.QUANTILE,  # a check's threshold quantile
        1.0 - diagnostics.QUANTILE,
        0.025, 0.975,  # the ends of a 95 % band
        consistency.LEVEL,  # the pooled-records check's chi-square point
        record_measure.NOISE_FLOOR,  # the smallest noise called noise
        calibration.SET_PPC_TOLERANCE,  # how closely a coloured calibration's sets hit their sampling
        estimation.coverage_floor(len(calibration.E_GRID) * calibration.SETS_PER_E),  # the selection's coverage floor
        estimation.coverage_floor(len(calibration.E_GRID_LONG) * calibration.SETS_PER_E_CAPPED),
    ]
    return {f"{100 * share:.1f}".rstrip("0").rstrip(".") for share in shares}


def prose_of(text: str) -> str:
    """``text`` without fenced code, included generated files, inline code and quoted messages."""
    out, fence, keep = [], None, True
    for line in text.splitlines():
        m = re.match(r"^\s*(`{3,}|~{3,})(.*)$", line)
        if fence is None and m:
            fence, info = m.group(1), m.group(2).strip()
            keep = info.startswith("{") and not info.startswith(NOT_PROSE)
            continue
        if fence is not None and m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence) and not m.group(2).strip():
            fence, keep = None, True
            continue
        if fence is None or keep:
            out.append(line)
    prose = re.sub(r"`[^`\n]*`", "CODE", "\n".join(out))
    return re.sub(r'"[^"]{0,600}"', "QUOTE", prose)


def study_numbers(text: str, allowed: set[str]) -> list[str]:
    """Every hand-typed study number in ``text``'s prose, as ``line N: match (kind)``."""
    prose = prose_of(text)
    hits = []
    for kind, pattern in STUDY_NUMBER.items():
        for m in re.finditer(pattern, prose):
            if kind == "a percentage with decimals" and m.group(1).rstrip("0").rstrip(".") in allowed:
                continue
            hits.append(f"line {prose.count(chr(10), 0, m.start()) + 1} of the prose: {m.group(0)!r} ({kind})")
    return hits


def test_the_study_number_check_tells_results_from_settings():
    allowed = design_percentages()
    assert {"98.5", "2.5", "97.5", "99.9", "0.2"} <= allowed
    results = ("covered 91.0 % of them", "fired on 8 of 167 records", "takes 5.4 ms a record",
               "was measured at 0.0304 on 12 records", "covers 96 %")
    for sentence in results:
        assert study_numbers(sentence, allowed), sentence
    settings = ("the 98.5 % quantile of the null", "10 values of `e`, 30 sets per `e`",
                "coverage 92-98 % in every cell", "```bash\nrockdec estimate  # 4.2 s, 91.3 %\n```",
                "```{include} ../../generated/studies/coverage.md\n```", "the message \"about 242 CPU-hours\"",
                "a measured load whose share is below 0.7")
    for sentence in settings:
        assert not study_numbers(sentence, allowed), sentence


@pytest.mark.parametrize("section", PROSE_PAGES + ("README",))
def test_the_prose_quotes_no_study_number_by_hand(section):
    """Measured results (coverages, false-alarm rates, timings, "measured at ...") belong in
    a table included from ``docs/generated/`` or in the study the prose points to; the
    prose says what the code does and which study holds the numbers."""
    allowed = design_percentages()
    if section == "README":
        pages = [REPO / "README.md"]
    elif section == ".":
        pages = sorted(DOCS.glob("*.md"))
    else:
        pages = sorted(p for p in (DOCS / section).rglob("*.md") if not {"_includes", "api"} & set(p.parts))
    assert pages
    found = {str(p.relative_to(REPO)): hits for p in pages if (hits := study_numbers(p.read_text(), allowed))}
    assert found == {}

"""Sphinx extension of the rockdec docs: the reference pages generated from the code.

At ``builder-inited`` it writes, under ``docs/reference/_includes/`` (git-ignored, included by
the reference pages):

- ``scene-config.md``: every field of the scene schema (``rockdec/scene_schema.yaml``, the
  file ``config/schema.yaml`` copies), with its type, default, range and description;
- ``glossary.md``: the words of an estimate's report, from ``rockdec.report.glossary.GLOSSARY``;
- ``estimate-json.md``: every key of ``rockdec estimate --json`` (``RestitutionEstimate.to_dict``),
  from the JSON schema the package ships (``rockdec/estimate.schema.json``);
- ``api.md``: an autosummary of the names ``rockdec.__all__`` exports.

The same functions serve ``tests/test_docs.py``, which checks that every field and every
command-line option reaches the reference without building the site.
"""

from __future__ import annotations

import importlib.resources
import json
import re
from pathlib import Path

import yaml

DOCS = Path(__file__).resolve().parents[1]
INCLUDES = DOCS / "reference" / "_includes"


def load_schema() -> dict:
    """The scene schema the package validates against (``rockdec/scene_schema.yaml``)."""
    return yaml.safe_load(importlib.resources.files("rockdec").joinpath("scene_schema.yaml").read_text())


def _resolve(node: dict, schema: dict) -> dict:
    ref = node.get("$ref")
    if ref:
        target = schema
        for part in ref.removeprefix("#/").split("/"):
            target = target[part]
        return target
    return node


def schema_fields(schema: dict) -> list[tuple[str, dict]]:
    """Every field of the schema as ``(dotted path, its schema node)``, depth first.

    The scenes' own fields are under ``scenes.<name>.``; other top-level sections keep their
    names (``coverage.records``).
    """
    out: list[tuple[str, dict]] = []

    def walk(node: dict, path: str) -> None:
        node = _resolve(node, schema)
        for name, child in node.get("properties", {}).items():
            child = _resolve(child, schema)
            here = f"{path}.{name}" if path else name
            out.append((here, child))
            walk(child, here)
        extra = node.get("additionalProperties")
        if isinstance(extra, dict):
            walk(extra, f"{path}.<name>" if path else "<name>")

    walk(schema, "")
    return out


def _type(node: dict) -> str:
    if "enum" in node:
        return "one of " + ", ".join(f"`{v}`" for v in node["enum"])
    if "anyOf" in node:
        return " or ".join(_type(n) for n in node["anyOf"])
    if "const" in node:
        return f"`{node['const']}`"
    kind = node.get("type", "")
    kinds = kind if isinstance(kind, list) else [kind]
    text = " or ".join(k for k in kinds if k)
    if "items" in node and isinstance(node["items"], dict):
        text += f" of {_type(node['items'])}"
    return text


def _range(node: dict) -> str:
    parts = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in node:
            parts.append(f"{sign} {node[key]}")
    for key, word in (("minItems", "items >="), ("minProperties", "entries >=")):
        if key in node:
            parts.append(f"{word} {node[key]}")
    if "anyOf" in node:
        parts += [_range(n) for n in node["anyOf"] if _range(n)]
    return ", ".join(parts)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ").strip()


def scene_config_markdown(schema: dict) -> str:
    """The scene configuration reference as a Markdown page body."""
    lines = [
        f"{schema.get('description', '').strip()}",
        "",
        "| field | type | default | range | what it sets |",
        "| --- | --- | --- | --- | --- |",
    ]
    for path, node in schema_fields(schema):
        if node.get("type") == "object" and "properties" in node and not node.get("description"):
            default = ""
        else:
            default = f"`{json.dumps(node['default'])}`" if "default" in node and node["default"] != {} else ""
        lines.append(f"| `{path}` | {_cell(_type(node))} | {_cell(default)} | {_cell(_range(node))} | {_cell(node.get('description', ''))} |")
    return "\n".join(lines) + "\n"


def load_estimate_schema() -> dict:
    """The JSON schema of an estimate's document (``rockdec/estimate.schema.json``)."""
    return json.loads(importlib.resources.files("rockdec").joinpath("estimate.schema.json").read_text())


def estimate_kinds(schema: dict) -> dict[str, dict]:
    """The documents the estimate's schema allows, by test (``random``, ``free``, ``shake``), each a
    schema of its own (with the definitions it refers to)."""
    tests = [entry["$ref"].rsplit("/", 1)[-1] for entry in schema.get("oneOf", [])]
    return {name: {**schema["$defs"][name], "$defs": schema.get("$defs", {})} for name in tests}


def estimate_json_markdown(schema: dict) -> str:
    """Every key of the estimate's JSON documents (one table per test), nested keys by their
    dotted path."""
    lines = [f"{schema.get('description', '').strip()}", ""]
    for name, kind in estimate_kinds(schema).items():
        lines += [
            f"### The {name} test",
            "",
            f"{kind.get('description', '').strip()}",
            "",
            "| key | type | what it holds |",
            "| --- | --- | --- |",
        ]
        for path, node in schema_fields(kind):
            lines.append(f"| `{path}` | {_cell(_type(node))} | {_cell(node.get('description', ''))} |")
        lines.append("")
    return "\n".join(lines)


def glossary_entries(text: str) -> list[tuple[str, str]]:
    """``(word, meaning)`` pairs of the report's glossary as the command prints it."""
    entries: list[list[str]] = []
    for line in text.splitlines()[1:]:
        if not line.strip():
            continue
        match = re.match(r"^  (\S.*?)(?: {2,}(.*))?$", line)
        if match and not line.startswith("   "):
            entries.append([match.group(1).strip(), (match.group(2) or "").strip()])
        elif entries:
            entries[-1][1] = f"{entries[-1][1]} {line.strip()}".strip()
    return [(w, m) for w, m in entries]


def glossary_markdown(text: str) -> str:
    """The glossary as a MyST definition list."""
    out = []
    for word, meaning in glossary_entries(text):
        out += [f"`{word}`", f": {meaning}", ""]
    return "\n".join(out)


def api_names() -> list[str]:
    """The public names ``rockdec.__all__`` exports (empty before it declares any)."""
    import rockdec

    return [n for n in getattr(rockdec, "__all__", []) if not n.startswith("_")]


def api_markdown(names: list[str]) -> str:
    """An autosummary of the public names, each on a generated page."""
    if not names:
        return "The public API (`rockdec.__all__`) is not declared in this version.\n"
    body = "\n".join(f"   {name}" for name in names)
    return "```{eval-rst}\n.. currentmodule:: rockdec\n\n.. autosummary::\n   :toctree: api\n\n" + body + "\n```\n"



def subcommands(parser) -> dict:
    """The subcommands of an ``argparse`` parser: ``{name: subparser}``."""
    import argparse

    return {name: sub for action in parser._actions if isinstance(action, argparse._SubParsersAction) for name, sub in action.choices.items()}


def _argparse(path: str = "") -> str:
    options = ["   :module: rockdec.cli", "   :func: build_parser", "   :prog: rockdec", "   :noepilog:"]
    options.append(f"   :path: {path}" if path else "   :nosubcommands:")
    return "```{eval-rst}\n.. argparse::\n" + "\n".join(options) + "\n```\n"


def cli_markdown(parser) -> str:
    """The command-line reference: the main parser, then each subcommand with its options
    (sphinx-argparse) and its examples and notes as the help prints them."""
    out = ["## `rockdec`", "", _argparse()]
    for name, sub in subcommands(parser).items():
        out += [f"## `rockdec {name}`", "", _argparse(name)]
        if sub.epilog:
            out += ["```text", sub.epilog.strip("\n"), "```", ""]
    return "\n".join(out)


def api_stub(name: str) -> str:
    """The reST page of one public name (what ``autosummary_generate`` would write)."""
    import importlib
    import inspect

    module, _, attr = f"rockdec.{name}".rpartition(".")
    obj = getattr(importlib.import_module(module), attr)
    kind = "autoclass" if inspect.isclass(obj) else "autofunction" if callable(obj) else "autodata"
    options = "   :members:\n" if kind == "autoclass" else ""
    title = f"rockdec.{name}"
    return f"{title}\n{'=' * len(title)}\n\n.. currentmodule:: {module}\n\n.. {kind}:: {attr}\n{options}"


def write_api_stubs(names: list[str]) -> None:
    """One page per public name under ``docs/reference/api/`` (git-ignored)."""
    folder = DOCS / "reference" / "api"
    folder.mkdir(parents=True, exist_ok=True)
    wanted = {f"rockdec.{name}.rst": api_stub(name) for name in names}
    for path in folder.glob("*.rst"):
        if path.name not in wanted:
            path.unlink()
    for file, text in wanted.items():
        path = folder / file
        if not path.exists() or path.read_text() != text:
            path.write_text(text)


def write_includes(app=None) -> None:
    """Write the generated reference sources (``builder-inited``)."""
    import rockdec.cli
    from rockdec.report.glossary import GLOSSARY

    INCLUDES.mkdir(parents=True, exist_ok=True)
    write_api_stubs(api_names())
    pages = {
        "scene-config.md": scene_config_markdown(load_schema()),
        "glossary.md": glossary_markdown(GLOSSARY),
        "api.md": api_markdown(api_names()),
        "cli.md": cli_markdown(rockdec.cli.build_parser()),
        "estimate-json.md": estimate_json_markdown(load_estimate_schema()),
    }
    for name, text in pages.items():
        path = INCLUDES / name
        if not path.exists() or path.read_text() != text:  # untouched files keep Sphinx's cache
            path.write_text(text)


def setup(app):
    app.connect("builder-inited", write_includes)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

"""An archive's ``ro-crate-metadata.json``: a Workflow Run Crate derived from its manifest.

:func:`crate_from_manifest` builds, with the ``rocrate`` library, the RO-Crate 1.1 that
describes an archive (:mod:`rockdec.pipeline.archive`) at the level of the whole workflow run
(Workflow Run Crate 0.5, which extends Process Run Crate 0.5 and Workflow RO-Crate 1.0):
the root dataset; one ``File`` per archived file with its media type, size and SHA-256;
the ``Snakefile`` as the ``ComputationalWorkflow`` (its rules, scripts and configuration
as its parts, the package versions as its software requirements); one ``CreateAction``,
the run, whose ``instrument`` is the workflow, whose ``object`` is the scene's settings as
``PropertyValue``s and whose ``result`` is the archived products; and the reproduced
paper as a cited ``ScholarlyArticle``. Everything in it comes from the manifest, so the
manifest stays the one source of truth and :func:`differences` can re-derive the crate
and compare.

:func:`profile_problems` checks a crate read with the ``rocrate`` library against the
required points of the three profiles (the official validator fetches remote resources;
these checks need no network).
"""

from __future__ import annotations

import copy
import json
import re
from datetime import datetime
from pathlib import PurePosixPath

from rocrate.model.contextentity import ContextEntity
from rocrate.rocrate import ROCrate

from rockdec.io import PAPER_TITLE

__all__ = ["crate_from_manifest", "differences", "profile_problems"]

RO_CRATE_VERSION = "1.1"
WORKFLOW_RUN_CONTEXT = "https://w3id.org/ro/terms/workflow-run/context"

#: ``sha256`` is no RO-Crate 1.1 term: the workflow-run context defines it, and the crate
#: repeats that definition inline so that a reader without network resolves it too.
TERMS = {"sha256": "https://w3id.org/ro/terms/workflow-run#sha256"}

#: The profiles the root dataset conforms to: permalink -> (name, version).
PROFILES = {
    "https://w3id.org/ro/wfrun/process/0.5": ("Process Run Crate", "0.5"),
    "https://w3id.org/ro/wfrun/workflow/0.5": ("Workflow Run Crate", "0.5"),
    "https://w3id.org/workflowhub/workflow-ro-crate/1.0": ("Workflow RO-Crate", "1.0"),
}

LICENSE = ("https://spdx.org/licenses/MIT", "MIT License")
"""The archive's licence (the repository's, which covers the workflow files it holds)."""

#: Media type of an archived file by its suffix (the Snakefile and rules are Snakemake's
#: Python dialect, registered under no media type of their own).
MEDIA_TYPES = {
    ".nc": "application/x-netcdf",
    ".csv": "text/csv",
    ".md": "text/markdown",
    ".json": "application/json",
    ".png": "image/png",
    ".pdf": "application/pdf",
    ".py": "text/x-python",
    ".smk": "text/plain",
    "": "text/plain",
    ".yaml": "application/yaml",
    ".rst": "text/x-rst",
}

PYPI = "https://pypi.org/project/{}/"
COMPLETED = "http://schema.org/CompletedActionStatus"


def media_type(name: str) -> str:
    """The media type of an archived file (``application/octet-stream`` if unknown)."""
    return MEDIA_TYPES.get(PurePosixPath(name).suffix, "application/octet-stream")


def _file(entry: dict, **properties) -> dict:
    return {
        "name": PurePosixPath(entry["name"]).name,
        "encodingFormat": media_type(entry["name"]),
        "contentSize": str(entry["size"]),
        "sha256": entry["sha256"],
        **properties,
    }


def _flat(settings: dict, prefix: str = "") -> dict[str, object]:
    """``settings`` as dotted keys (``records.n_points``) to scalar values."""
    out: dict[str, object] = {}
    for key, value in settings.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(_flat(value, f"{name}."))
        else:
            out[name] = value
    return out


def _datatype(value) -> tuple[str, object]:
    """schema.org DataType and JSON-LD value of a setting (lists and nulls as JSON text)."""
    if isinstance(value, bool):
        return "Boolean", value
    if isinstance(value, int):
        return "Integer", value
    if isinstance(value, float):
        return "Float", value
    if isinstance(value, str):
        return "Text", value
    return "Text", json.dumps(value)


def crate_from_manifest(manifest: dict, manifest_entry: dict) -> dict:
    """The JSON-LD of an archive's crate, from its manifest (checked by
    :func:`rockdec.pipeline.archive.check_manifest`) and the manifest file's own ``name``, ``size``
    and ``sha256`` (``manifest_entry``)."""
    crate = ROCrate(version=RO_CRATE_VERSION)
    crate.metadata.extra_contexts.append(WORKFLOW_RUN_CONTEXT)
    crate.metadata.extra_terms = dict(TERMS)
    scene, run, settings = manifest["scene"], manifest["run"], manifest["settings"]
    root = crate.root_dataset
    kind = manifest.get("kind", "scene")
    root["name"] = f"rockdec archive of the {kind} '{scene}'"
    root["description"] = (
        "The NetCDF files that the tables and figures of one rockdec scene are made from, the tables, "
        "and the Snakemake workflow that made them, with the run's settings and software versions."
        + (f" The scene: {settings['description'].strip()}" if isinstance(settings.get("description"), str) else "")
        if kind == "scene" else
        "The estimates of one rockdec test campaign, per record and per block (each as rockdec estimate --json prints it, "
        "and as CF NetCDF), their table and the NetCDF its figures are drawn from, and the Snakemake workflow that made "
        "them, with the records sheet's rows as settings and the software versions."
    )
    root["datePublished"] = manifest["datePublished"]
    root["license"] = crate.add(ContextEntity(crate, LICENSE[0], {"@type": "CreativeWork", "name": LICENSE[1]}))
    root["conformsTo"] = [
        crate.add(ContextEntity(crate, url, {"@type": "CreativeWork", "name": name, "version": version}))
        for url, (name, version) in PROFILES.items()
    ]
    root["citation"] = crate.add(ContextEntity(crate, "#paper", {"@type": "ScholarlyArticle", "name": PAPER_TITLE}))

    main, *parts = manifest["workflow"]
    versions = manifest["versions"]
    software = [
        crate.add(ContextEntity(crate, f"#software-{name}", {
            "@type": "SoftwareApplication", "name": name, "softwareVersion": ver,
            **({} if name == "rockdec" else {"url": PYPI.format(name)}),
        }))
        for name, ver in versions.items() if ver != "not installed"
    ]
    sources = [crate.add_file(dest_path=entry["name"], properties=_file(entry)) for entry in parts]
    dirty = {True: "with uncommitted changes", False: "with no uncommitted changes", None: "its changes unknown"}
    workflow = crate.add_workflow(
        dest_path=main["name"], main=True, lang="snakemake", lang_version=versions.get("snakemake"),
        properties=_file(
            main,
            name="rockdec workflow",
            description=f"The Snakemake workflow of rockdec, git commit {manifest['git_commit']} "
            f"({dirty[manifest['git_dirty']]}); its rules, scripts and configuration are its parts.",
            version=manifest["git_commit"],
        ),
    )
    workflow["hasPart"] = sources
    workflow["softwareRequirements"] = software

    values, parameters = [], []
    for key, value in _flat({"scene": scene, **settings}).items():
        kind, value = _datatype(value)
        value_entity = crate.add(ContextEntity(crate, f"#setting-{key}", {"@type": "PropertyValue", "name": key, "value": value}))
        parameter = crate.add(ContextEntity(crate, f"#parameter-{key}", {
            "@type": "FormalParameter", "name": key, "additionalType": kind,
        }))
        value_entity["exampleOfWork"] = parameter
        parameter["workExample"] = value_entity
        values.append(value_entity)
        parameters.append(parameter)
    workflow["input"] = parameters

    products = [
        crate.add_file(dest_path=entry["name"], properties=_file(entry, description=f"Written by rule `{entry['rule']}`."))
        for entry in manifest["files"]
    ]
    action = crate.add_action(
        workflow, identifier=run["id"], object=values, result=products,
        properties={
            "name": f"Snakemake run of the rockdec workflow for the {kind} '{scene}'",
            "description": "startTime and endTime: when the first and the last archived product were written.",
            "startTime": run["startTime"],
            "endTime": run["endTime"],
            "actionStatus": {"@id": COMPLETED},
        },
    )
    root["mentions"] = action
    crate.add_file(dest_path=manifest_entry["name"], properties=_file(
        manifest_entry, description="The archive's manifest, from which this crate is derived.", about={"@id": run["id"]}
    ))
    return crate.metadata.generate()


def _ids(value) -> list[str]:
    """The ``@id``s a property refers to (one reference or a list)."""
    items = value if isinstance(value, list) else [value]
    ids = [item.get("@id") if isinstance(item, dict) else getattr(item, "id", item) for item in items]
    return [i for i in ids if isinstance(i, str)]


def _types(entity) -> set[str]:
    kind = entity.type if entity is not None else []
    return set(kind if isinstance(kind, list) else [kind])


def _is_date(text) -> bool:
    try:
        datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        return False
    return True


def profile_problems(doc: dict) -> list[str]:
    """The required points of Workflow Run Crate 0.5 (with Process Run Crate 0.5 and Workflow
    RO-Crate 1.0 beneath it) and of RO-Crate 1.1's root that the crate ``doc`` (its JSON-LD)
    misses, one sentence each. The crate is read with the ``rocrate`` library; the root's and
    the descriptor's own properties are taken from ``doc`` itself, since the library fills in
    defaults (such as ``datePublished``) that the file may lack."""
    crate = ROCrate(copy.deepcopy(doc))
    problems = []
    written = {entity["@id"]: entity for entity in doc["@graph"]}
    descriptor = written.get(crate.metadata.id, {})
    spec = [i for i in _ids(descriptor.get("conformsTo")) if re.fullmatch(r"https://w3id\.org/ro/crate/1\.[1-9]\d*", i)]
    if not spec:
        problems.append("the metadata descriptor does not conform to RO-Crate 1.1 or later")
    root = crate.root_dataset
    root_written = written.get(root.id, {})
    if "Dataset" not in _types(root) or not root.id.endswith("/"):
        problems.append("the root data entity is not a Dataset whose @id ends with '/'")
    for key in ("name", "description", "license"):
        if not root_written.get(key):
            problems.append(f"the root data entity has no {key}")
    if not _is_date(root_written.get("datePublished")):
        problems.append("the root data entity has no datePublished in ISO 8601")
    profiles = _ids(root_written.get("conformsTo"))
    for prefix, name in (("https://w3id.org/ro/wfrun/process/", "Process Run Crate"), ("https://w3id.org/ro/wfrun/workflow/", "Workflow Run Crate")):
        if not any(p.startswith(prefix) and "CreativeWork" in _types(crate.get(p)) for p in profiles):
            problems.append(f"the root data entity does not conform to {name} (a CreativeWork named by its permalink)")
    parts = _ids(root_written.get("hasPart"))
    for part in parts:
        if not _types(crate.get(part)) & {"File", "Dataset"}:
            problems.append(f"hasPart '{part}' of the root is neither a File nor a Dataset")
    main = crate.get(_ids(root_written.get("mainEntity"))[0]) if _ids(root_written.get("mainEntity")) else None
    if main is None:
        problems.append("the root data entity names no mainEntity in the crate")
    else:
        if not {"File", "SoftwareSourceCode", "ComputationalWorkflow"} <= _types(main):
            problems.append(f"the mainEntity '{main.id}' is not a File, SoftwareSourceCode and ComputationalWorkflow")
        languages = [crate.get(i) for i in _ids(main.get("programmingLanguage"))]
        if not languages or not all("ComputerLanguage" in _types(lang) for lang in languages):
            problems.append(f"the mainEntity '{main.id}' names no ComputerLanguage as programmingLanguage")
        if main.id not in parts:
            problems.append(f"the mainEntity '{main.id}' is not a part of the root data entity")
    tools = {"SoftwareApplication", "SoftwareSourceCode", "ComputationalWorkflow"}
    actions = [e for e in crate.get_entities() if _types(e) & {"CreateAction", "ActivateAction", "UpdateAction"}]
    for action in actions:
        if not _ids(action.get("instrument")) or not all(_types(crate.get(i)) & tools for i in _ids(action.get("instrument"))):
            problems.append(f"the action '{action.id}' has no instrument that is a tool of the crate")
    if main is not None and not any(main.id in _ids(a.get("instrument")) for a in actions if "CreateAction" in _types(a)):
        problems.append("no CreateAction has the mainEntity as its instrument")
    for key in ("input", "output"):
        for ref in _ids(main.get(key)) if main is not None else []:
            if "FormalParameter" not in _types(crate.get(ref)):
                problems.append(f"the workflow's {key} '{ref}' is not a FormalParameter")
    for parameter in crate.get_by_type("FormalParameter"):
        examples = [crate.get(i) for i in _ids(parameter.get("workExample"))]
        if not parameter.get("additionalType") or not examples or not all(
            _types(e) & {"File", "Dataset", "Collection", "PropertyValue"} for e in examples
        ):
            problems.append(f"the FormalParameter '{parameter.id}' lacks an additionalType or a workExample")
    return problems


def differences(stored: dict, derived: dict) -> list[str]:
    """Where the crate ``stored`` (as read from its file) departs from the crate ``derived``
    from the manifest, one sentence per entity (or the context)."""
    if not isinstance(stored, dict) or stored.get("@context") != derived["@context"]:
        return ["its @context differs from the one rockdec writes"]
    graph = stored.get("@graph")
    if not isinstance(graph, list) or not all(isinstance(e, dict) and isinstance(e.get("@id"), str) for e in graph):
        return ["its @graph is not a list of entities with an @id each"]
    have = {entity["@id"]: entity for entity in graph}
    if len(have) < len(graph):
        return ["its @graph lists an @id twice"]
    want = {entity["@id"]: entity for entity in derived["@graph"]}
    out = [f"'{i}' is missing, though the manifest implies it" for i in want if i not in have]
    out += [f"'{i}' is not derived from the manifest" for i in have if i not in want]
    out += [f"'{i}' differs from what the manifest says" for i in want if i in have and have[i] != want[i]]
    return out

"""Which package sources a step runs: the code dependencies of workflow rules and caches.

:func:`package_sources` walks the ``rockdec`` imports of a module or a script, through every
module it reaches (imports inside functions included), and lists their source files. The
workflow's compute rules declare these files as inputs, so an edit reruns what it can change;
the calibration's cache key hashes the same list (:func:`rockdec.calibrate.calibration.pipeline_fingerprint`),
so no module the analysis runs can be left out of it. Reads source text only: nothing is
imported but the ``rockdec`` package itself (to locate its files).
"""

from __future__ import annotations

import ast
import functools
import re
from importlib.util import find_spec
from pathlib import Path

__all__ = ["fingerprint_file", "package_sources"]


def _rockdec_imports(path: Path) -> tuple[str, ...]:
    """The ``rockdec`` modules a source file imports, anywhere in it (absolute imports).

    Each file is parsed once while it is unchanged (:func:`_parsed_imports`): the workflow
    asks for the sources of a dozen steps that share most of their modules.
    """
    stat = path.stat()
    return _parsed_imports(str(path), stat.st_mtime_ns, stat.st_size)


#: A line that starts an absolute import of a ``rockdec`` module (indented too: inside a function).
_IMPORT_LINE = re.compile(r"^[ \t]*(?:from[ \t]+rockdec[\w.]*[ \t]+import|import[ \t]+rockdec)\b", re.M)


def _statement(text: str, start: int) -> str:
    """The statement of ``text`` whose line starts at ``start``: that line and the lines an
    open parenthesis or a closing backslash carries it on to."""
    end = start
    while True:
        newline = text.find("\n", end)
        end = len(text) if newline < 0 else newline
        piece = text[start:end]
        if end == len(text) or not (piece.count("(") > piece.count(")") or piece.rstrip().endswith("\\")):
            return piece
        end += 1


@functools.lru_cache(maxsize=1024)
def _parsed_imports(path: str, mtime_ns: int, size: int) -> tuple[str, ...]:
    """:func:`_rockdec_imports` of the file ``path`` as it is at ``mtime_ns`` and ``size``.

    Only the lines that start a ``rockdec`` import are parsed, each with its continuation
    (:func:`_statement`; the syntax tree of every module costs a warm ``rockdec estimate``
    more than its analysis), the whole file when one of them is no statement on its own (a
    docstring's text, say). A docstring line that reads as a whole import counts as one:
    it can only add a module to the list.
    """
    text = Path(path).read_text()
    try:
        nodes = [ast.parse(_statement(text, match.start()).strip()).body[0] for match in _IMPORT_LINE.finditer(text)]
    except SyntaxError:
        nodes = list(ast.walk(ast.parse(text)))
    names = []
    for node in nodes:
        if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").split(".")[0] == "rockdec":
            # ``from rockdec.physics import simulate`` imports a module by its package's name
            names += [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names += [alias.name for alias in node.names if alias.name.startswith("rockdec.")]
    return tuple(names)


@functools.lru_cache(maxsize=256)
def _is_package(name: str) -> bool:
    """Whether the module ``name`` is a package, so that ``name.x`` may be a module (finding
    the spec of a name under a plain module would import that module)."""
    spec = find_spec(name)
    return spec is not None and spec.submodule_search_locations is not None


def package_sources(*roots: str) -> list[str]:
    """Sorted source files of every ``rockdec`` module that ``roots`` reach by import.

    Each root is a module name (``"rockdec.calibrate.calibration"``, itself included) or the path of a
    Python file (a workflow script: only the modules it reaches are listed). A name that is
    no module (``from rockdec import __version__``) is skipped.
    """
    found: dict[str, str] = {}
    todo: list[str] = []
    for root in roots:
        if str(root).endswith(".py"):
            todo += _rockdec_imports(Path(root))
        else:
            todo.append(str(root))
    while todo:
        name = todo.pop()
        parent = name.rpartition(".")[0]
        spec = None if name in found or (parent and not _is_package(parent)) else find_spec(name)
        if spec is None or spec.origin is None:
            continue
        found[name] = spec.origin
        todo += _rockdec_imports(Path(spec.origin))
    return sorted(found.values())


def fingerprint_file(path: str | Path, sources) -> str:
    """Write ``path``: one line ``<SHA-256> <file>`` per file of ``sources`` (sorted), the one
    code input of a workflow rule in place of the files themselves. Rewritten only when that
    text changes (a module edited, added or dropped: its modification time then now, so the
    rule reruns); written the first time with the newest source's time, so products made
    after their code stay up to date; a file merely touched reruns nothing. Returns ``path``
    as given.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> module = folder / "m.py"
    >>> _ = module.write_text("x = 1\\n")
    >>> text = pathlib.Path(fingerprint_file(folder / "code.sha256", [module])).read_text()
    >>> text.split()[0] == __import__("hashlib").sha256(b"x = 1\\n").hexdigest()
    True
    """
    import hashlib
    import os

    files = sorted(str(s) for s in sources)
    text = "".join(f"{hashlib.sha256(Path(f).read_bytes()).hexdigest()} {f}\n" for f in files)
    target = Path(path)
    try:
        if target.read_text() == text:
            return str(path)
        first = False
    except OSError:
        first = True
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(f".{target.name}.{os.getpid()}.partial")
    partial.write_text(text)
    newest = max((Path(f).stat().st_mtime for f in files), default=None)
    if first and newest is not None:
        os.utime(partial, (newest, newest))
    os.replace(partial, target)
    return str(path)

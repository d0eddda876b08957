"""`verify` and `rebuild` on hostile archives (issue 38), on a small archive written here by
:func:`rockdec.pipeline.archive.write_archive` (no workflow run): a manifest name no file
system stores, a file whose size changed, a rebuild into the archive itself, onto a
symbolic link (dangling or not), or onto a disk with too little room. Each is named or
refused in one sentence, before any rebuild work."""

from __future__ import annotations

import errno
import json
import os
import shutil
from pathlib import Path

import pytest

from rockdec import io
from rockdec.pipeline import archive, config, steps

REPO = Path(__file__).resolve().parents[2]
hostile = pytest.mark.hostile


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    """An archive folder of two products (not real NetCDF: verify reads bytes only)."""
    base = tmp_path_factory.mktemp("small")
    results = base / "results"
    results.mkdir()
    (results / "signatures.nc").write_bytes(b"\x89HDF" + bytes(range(256)) * 8)
    (results / "table.csv").write_text("e,low,high\n0.95,0.94,0.96\n")
    folder = base / "archive"
    archive.write_archive(folder, results, {"signatures.nc": "signatures", "table.csv": "estimates"}, "tiny",
                          config.validate_scene({}), REPO)
    return folder


def _copy(small: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(small, tmp_path / "archive"))


def _rewrite(folder: Path, manifest: dict) -> None:
    (folder / archive.MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")


@hostile("archive", "refused")
@pytest.mark.parametrize("length", [256, 5000])
@pytest.mark.parametrize("group", ["files", "workflow"])
def test_a_manifest_name_longer_than_a_file_system_stores_is_refused(small, tmp_path, length, group):
    folder = _copy(small, tmp_path)
    manifest = json.loads((folder / archive.MANIFEST).read_text())
    manifest[group][-1]["name"] = "x" * length
    _rewrite(folder, manifest)
    with pytest.raises(archive.ArchiveError) as info:
        archive.verify(folder)
    text = str(info.value)
    assert f"field {group}.{len(manifest[group]) - 1}.name" in text and f"{length} bytes" in text and "\n" not in text
    assert len(text) < 600  # the name itself is cut short in the sentence


@hostile("archive", "refused")
def test_a_manifest_path_longer_than_the_system_takes_is_refused(small, tmp_path):
    folder = _copy(small, tmp_path)
    manifest = json.loads((folder / archive.MANIFEST).read_text())
    manifest["files"][0]["name"] = "/".join(["d" * 200] * 25)  # every part short, the path 5,024 bytes
    _rewrite(folder, manifest)
    with pytest.raises(archive.ArchiveError, match="longer than the 4095 a path may be"):
        archive.verify(folder)


@hostile("archive", "refused")
@pytest.mark.parametrize("change", ["appended", "truncated", "emptied"])
def test_a_file_whose_size_changed_is_named_by_its_size(small, tmp_path, change):
    folder = _copy(small, tmp_path)
    path = folder / "signatures.nc"
    before = path.stat().st_size
    data = path.read_bytes()
    path.write_bytes({"appended": data + b"!", "truncated": data[:-7], "emptied": b""}[change])
    after = path.stat().st_size
    assert archive.verify(folder) == [f"changed: signatures.nc (its size is {after} bytes, the manifest says {before})"]


@hostile("archive", "refused")
def test_a_file_changed_at_its_size_is_named_by_its_checksum(small, tmp_path):
    folder = _copy(small, tmp_path)
    path = folder / "table.csv"
    path.write_text(path.read_text().replace("0.95", "0.97"))
    assert archive.verify(folder) == ["changed: table.csv (SHA-256 differs from the manifest)"]


@hostile("output paths", "refused")
@pytest.mark.parametrize("where", ["inside", "the archive itself", "deep inside", "through a link to it"])
def test_a_rebuild_into_the_archive_it_verifies_is_refused(small, tmp_path, where):
    folder = _copy(small, tmp_path)
    (folder / "figures").mkdir(exist_ok=True)
    (tmp_path / "link").symlink_to(folder)
    out = {"inside": folder / "rebuilt", "the archive itself": folder, "deep inside": folder / "figures" / "rebuilt",
           "through a link to it": tmp_path / "link" / "rebuilt"}[where]
    before = sorted(p.relative_to(folder) for p in folder.rglob("*"))
    with pytest.raises(io.OutputError) as info:
        archive.rebuild(folder, out)
    assert ("lies inside the archive" in str(info.value)) or ("exists already" in str(info.value) and where == "the archive itself")
    assert sorted(p.relative_to(folder) for p in folder.rglob("*")) == before


@hostile("output paths", "refused")
@pytest.mark.parametrize("target", ["missing", "a folder", "a file"], ids=["dangling", "to a folder", "to a file"])
def test_a_rebuild_onto_a_symbolic_link_is_refused_before_any_work(small, tmp_path, monkeypatch, target):
    def no_work(*args, **kwargs):
        raise AssertionError("the rebuild started its work")

    monkeypatch.setattr(steps, "estimates", no_work)
    folder = _copy(small, tmp_path)
    pointed = tmp_path / "pointed"
    if target == "a folder":
        pointed.mkdir()
    elif target == "a file":
        pointed.write_text("keep")
    out = tmp_path / "rebuilt"
    out.symlink_to(pointed)
    with pytest.raises(io.OutputError) as info:
        archive.rebuild(folder, out)
    assert str(info.value).startswith(f"the rebuild folder '{out}' is a symbolic link") and "\n" not in str(info.value)
    assert out.is_symlink() and sorted(p.name for p in tmp_path.iterdir()) == sorted(["archive", "rebuilt", *(["pointed"] if target != "missing" else [])])


@hostile("limits", "refused")
def test_a_rebuild_onto_a_disk_without_room_is_refused_before_any_work(small, tmp_path, monkeypatch):
    def no_work(*args, **kwargs):
        raise AssertionError("the rebuild started its work")

    folder = _copy(small, tmp_path)
    real = shutil.disk_usage
    monkeypatch.setattr(steps, "estimates", no_work)
    monkeypatch.setattr(archive.shutil, "disk_usage", lambda p: real(p)._replace(free=10))
    with pytest.raises(io.OutputError) as info:
        archive.rebuild(folder, tmp_path / "rebuilt")
    assert "more than the 1e-05 MB free" in str(info.value) and "free some space" in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["archive"]


@hostile("limits", "refused")
@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EIO], ids=["disk full", "quota", "I/O error"])
def test_a_disk_that_fills_during_the_rebuild_is_one_sentence_and_leaves_nothing(small, tmp_path, monkeypatch, code):
    def fills(*args, **kwargs):
        raise OSError(code, os.strerror(code))

    folder = _copy(small, tmp_path)
    monkeypatch.setattr(archive, "_scene", lambda manifest, folder: config.validate_scene({}))
    monkeypatch.setattr(steps, "estimates", fills)
    with pytest.raises(io.OutputError) as info:
        archive.rebuild(folder, tmp_path / "rebuilt")
    text = str(info.value)
    assert text.startswith(f"the rebuild folder '{tmp_path / 'rebuilt'}': ") and text.endswith("choose another folder.")
    assert ("disk filled" in text) == (code != errno.EIO)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["archive"]

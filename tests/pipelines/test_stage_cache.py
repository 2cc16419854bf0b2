"""The stage cache's folder is checked before any stage runs: a file, or a folder that cannot be
written, is refused naming the stage cache and the way out (--cache DIR, --no-cache)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from pipelines.cli.main import main
from pipelines.stages import EXECUTIONS, StageCache, check_directory
from reduction.errors import InputError

CYLINDER = Path(__file__).resolve().parents[2] / "examples" / "cylinder_on_plane.toml"


def test_a_cache_that_is_a_file_is_refused_before_any_stage(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    before = EXECUTIONS.copy()
    assert main(["run", str(CYLINDER), "--out", str(tmp_path / "out"), "--cache", str(afile), "--quiet"]) == 2
    assert capsys.readouterr().err == (
        f"fretwork: error: the stage cache {afile} is a file: give a folder (it is created if missing); or keep "
        "the cache in another folder with --cache DIR (or FRETWORK_CACHE=DIR), or run without it: --no-cache\n")
    assert EXECUTIONS == before and sorted(tmp_path.iterdir()) == [afile]


def test_an_unwritable_default_cache_is_refused_before_any_stage(tmp_path, capsys, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir()
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != locked)  # root may write anywhere
    monkeypatch.setenv("FRETWORK_CACHE", str(locked / ".fretwork-cache"))
    assert main(["limit", str(CYLINDER), "--amplitude", "100:200", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.startswith(f"fretwork: error: the stage cache {locked}/.fretwork-cache: {locked} is not writable "
                            "(permission denied); ")
    assert "--cache DIR" in error and "--no-cache" in error
    assert not (tmp_path / "out").exists()


def test_no_cache_does_not_look_at_the_cache_folder(tmp_path):
    from types import SimpleNamespace

    from pipelines.cli.main import _cache

    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    assert _cache(SimpleNamespace(no_cache=True, cache=str(afile))) is None
    with pytest.raises(InputError, match="stage cache"):
        _cache(SimpleNamespace(no_cache=False, cache=str(afile)))


def test_check_directory_accepts_a_folder_to_be_created(tmp_path):
    assert check_directory(tmp_path / "new" / "cache") == tmp_path / "new" / "cache"
    with pytest.raises(InputError, match="^the stage cache /proc/c: /proc is a system folder"):
        check_directory("/proc/c")
    cache = StageCache(tmp_path / "new" / "cache")
    assert cache.get("stage", {"x": 1}, lambda: 2) == 2 and cache.get("stage", {"x": 1}, lambda: 3) == 2

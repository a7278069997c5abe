"""Atomic writes: results complete under their final name, or absent."""

import os
import stat

import pytest

from ballimpact.atomic import atomic_dir, atomic_path


def test_atomic_path_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.csv"
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(target) as tmp:
            assert tmp.parent == tmp_path and tmp.suffix == ".csv"
            tmp.write_text("partial", encoding="utf-8")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with atomic_path(target) as tmp:
        tmp.write_text("done", encoding="utf-8")
    assert target.read_text(encoding="utf-8") == "done"
    assert list(tmp_path.iterdir()) == [target]


def test_atomic_dir_replaces_the_folder(tmp_path):
    target = tmp_path / "qc"
    target.mkdir()
    (target / "old.png").write_bytes(b"old")
    with atomic_dir(target) as tmp:
        (tmp / "new.png").write_bytes(b"new")
    assert sorted(p.name for p in target.iterdir()) == ["new.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["qc"]


def test_atomic_results_are_readable_by_colleagues(tmp_path):
    # mkstemp alone would leave 0600 files behind os.replace
    old = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "r.nc") as tmp:
            tmp.write_bytes(b"x")
        with atomic_dir(tmp_path / "qc") as tmp:
            (tmp / "a.png").write_bytes(b"x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "r.nc").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "qc").stat().st_mode) == 0o755
    assert stat.S_IMODE((tmp_path / "qc" / "a.png").stat().st_mode) == 0o644


def test_atomic_path_refuses_when_nothing_written(tmp_path):
    with pytest.raises(RuntimeError, match="nothing was written"):
        with atomic_path(tmp_path / "empty.csv"):
            pass
    assert list(tmp_path.iterdir()) == []


def test_stale_temporary_files_of_a_killed_writer_are_removed(tmp_path):
    stale = tmp_path / ".out.nc.abc123.tmp.nc"
    stale.write_bytes(b"half")
    other = tmp_path / ".other.nc.abc123.tmp.nc"  # another output's: left alone
    other.write_bytes(b"x")
    with atomic_path(tmp_path / "out.nc") as tmp:
        tmp.write_bytes(b"whole")
    assert not stale.exists() and other.exists()
    stale_dir = tmp_path / ".qc.xyz.tmp"
    stale_dir.mkdir()
    with atomic_dir(tmp_path / "qc") as tmp:
        (tmp / "a.png").write_bytes(b"x")
    assert not stale_dir.exists()

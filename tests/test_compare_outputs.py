"""Tests of bench/compare_outputs.py: an identical copy of a results tree passes, a 1e-6 change anywhere fails."""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from workflow_helpers import bench_module


def _compare():
    return bench_module("compare_outputs")


@pytest.fixture()
def tree(tmp_path):
    """A small results tree: one CSV, one netCDF, one JSON, one PNG and a log that differs between runs."""
    root = tmp_path / "a" / "s1"
    (root / "logs").mkdir(parents=True)
    pd.DataFrame({"impact_id": ["i1", "i2"], "cor": [0.75, 0.5], "reason": ["", "gate"]}).to_csv(
        root / "impacts.csv", index=False)
    ds = xr.Dataset({"force_N": ("sample", np.array([1.0, 2.5, np.nan]), {"units": "N"})},
                    attrs={"title": "t", "date_created": "2026-01-01T00:00:00Z"})
    ds.to_netcdf(root / "s1.nc", engine="netcdf4")
    (root / "session.json").write_text('{"n": 2, "x": [0.25, "a"]}')
    (root / "fig.png").write_bytes(b"png a")
    (root / "logs" / "run.log").write_text("took 1.2 s")
    return tmp_path / "a"


def _copy(tree, tmp_path):
    other = tmp_path / "b"
    shutil.copytree(tree, other)
    (other / "s1" / "fig.png").write_bytes(b"png b, drawn again")  # images are listed, not compared
    (other / "s1" / "logs" / "run.log").write_text("took 3.4 s")  # logs hold run times: skipped
    return other


def test_identical_copy_passes(tree, tmp_path, capsys):
    other = _copy(tree, tmp_path)
    # a new date_created is the time of the run, not a difference
    with xr.open_dataset(other / "s1" / "s1.nc") as f:
        ds = f.load()
    ds.attrs["date_created"] = "2027-02-02T00:00:00Z"
    ds.to_netcdf(other / "s1" / "s1.nc", engine="netcdf4")
    assert _compare().main([str(tree), str(other)]) == 0
    out = capsys.readouterr().out
    assert "not compared (image): s1/fig.png" in out


@pytest.mark.parametrize("where", ["csv", "netcdf", "json"])
def test_relative_change_of_1e_6_fails(tree, tmp_path, where, capsys):
    other = _copy(tree, tmp_path)
    if where == "csv":
        pd.DataFrame({"impact_id": ["i1", "i2"], "cor": [0.75, 0.5 * (1 + 1e-6)], "reason": ["", "gate"]}).to_csv(
            other / "s1" / "impacts.csv", index=False)
    elif where == "netcdf":
        ds = xr.Dataset({"force_N": ("sample", np.array([1.0, 2.5 * (1 + 1e-6), np.nan]), {"units": "N"})},
                        attrs={"title": "t", "date_created": "2026-01-01T00:00:00Z"})
        ds.to_netcdf(other / "s1" / "s1.nc", engine="netcdf4")
    else:
        (other / "s1" / "session.json").write_text('{"n": 2, "x": [0.25000025, "a"]}')
    assert _compare().main([str(tree), str(other)]) == 1
    assert "DIFFERENT s1/" in capsys.readouterr().out


def test_changed_text_and_missing_file_fail(tree, tmp_path, capsys):
    other = _copy(tree, tmp_path)
    pd.DataFrame({"impact_id": ["i1", "i2"], "cor": [0.75, 0.5], "reason": ["", "gate time"]}).to_csv(
        other / "s1" / "impacts.csv", index=False)
    (other / "s1" / "fig.png").unlink()
    assert _compare().main([str(tree), str(other)]) == 1
    out = capsys.readouterr().out
    assert "column reason, row 3: 'gate' != 'gate time'" in out
    assert "s1/fig.png: only in A" in out

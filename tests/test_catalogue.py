"""Tests of ballimpact.catalogue: change test, pooled fits, ranking and the catalogue files.

The fast tests build sessions straight from the model (known parameters, 1 % noise on
TC and COR, no signal processing); the workflow test runs Snakemake on synthetic raw
sessions made by ballimpact.synth.
"""

from __future__ import annotations

import dataclasses
import math
import re
import shutil

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from numpy.testing import assert_allclose

from ballimpact import archive, catalogue
from ballimpact.balls import BALLS
from ballimpact.fitting import fit_ball_model
from ballimpact.model import simulate_impact

from workflow_helpers import REPO, run_snakemake

TRUE = {k: BALLS[k].params for k in ("pressurised", "punctured")}
# the punctured ball of the last session had its damping raised by half: a changed ball type
CHANGED = dataclasses.replace(TRUE["punctured"], ac=TRUE["punctured"].ac * 1.5)
N_PER_BALL = 10
NOISE = 0.01  # relative scatter of TC and COR about the model


def _session(session_id, date, params, seed):
    """SessionResults of a session whose impacts follow the model with ``params`` per ball."""
    rng = np.random.default_rng(seed)
    rows, fits = [], []
    for ball, p in params.items():
        vin = rng.uniform(14.0, 30.0, N_PER_BALL)
        sim = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        tc = sim.contact_time_s * (1 + NOISE * rng.standard_normal(N_PER_BALL))
        cor = sim.cor * (1 + NOISE * rng.standard_normal(N_PER_BALL))
        rows.append(pd.DataFrame({"ball_type": ball, "status": "ok", "vin_m_s": vin,
                                  "contact_time_ms": tc * 1e3, "cor": cor, "impact_mass_kg": p.mass_kg}))
        fit = fit_ball_model(vin, tc, cor, np.full(N_PER_BALL, p.mass_kg), kb0_N_m=p.kb0_N_m, n_bootstrap=0)
        fits.append(archive.fit_dataset(ball, fit, label=ball))
    table = pd.concat(rows, ignore_index=True)
    impacts = xr.Dataset({c: ("impact", table[c].to_numpy(dtype=object if c in ("ball_type", "status") else float))
                          for c in table.columns},
                         coords={"impact_id": ("impact", [f"{session_id}-{i:03d}" for i in range(len(table))])})
    balls = xr.concat(fits, dim="ball", data_vars="minimal", coords="minimal", compat="override")
    return catalogue.SessionResults(session_id, date, archive.parameters_table(balls), balls, impacts)


@pytest.fixture(scope="module")
def sessions():
    """Three sessions of two ball types; punctured changed (AC x 1.5) in the last one."""
    return [
        _session("s1", "2026-01-10", TRUE, 1),
        _session("s2", "2026-02-10", TRUE, 2),
        _session("s3", "2026-03-10", {"pressurised": TRUE["pressurised"], "punctured": CHANGED}, 3),
    ]


def _model_at(p, speed):
    sim = simulate_impact(speed, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    return float(sim.contact_time_s) * 1e3, float(sim.cor)


def test_change_test_flags_only_the_changed_ball(sessions):
    changed = catalogue.compare_sessions(sessions, "punctured")
    same = catalogue.compare_sessions(sessions, "pressurised")
    assert changed.p_value < catalogue.CHANGE_ALPHA and changed.changed
    assert same.p_value >= catalogue.CHANGE_ALPHA and not same.changed
    assert (changed.df_num, changed.df_den) == (6, 2 * 3 * N_PER_BALL - 9)
    # size of the change at 20 m/s against the model with the true parameters
    tc_a, cor_a = _model_at(TRUE["punctured"], 20.0)
    tc_b, cor_b = _model_at(CHANGED, 20.0)
    assert_allclose(changed.cor_change, abs(cor_a - cor_b), rtol=0.3)
    assert changed.tc_change_ms < 0.2  # AC moves COR much more than TC
    assert same.cor_change < 0.3 * abs(cor_a - cor_b)


def test_change_test_needs_two_sessions(sessions):
    test = catalogue.compare_sessions(sessions[:1], "punctured")
    assert math.isnan(test.p_value) and not test.changed
    assert "nothing to compare" in test.message


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"alpha": 0.0}, "alpha must be in"),
    ({"alpha": 1.5}, "alpha must be in"),
    ({"speed_m_s": -20.0}, "speed_m_s must be a positive"),
])
def test_change_test_rejects_bad_arguments(sessions, kwargs, match):
    with pytest.raises(ValueError, match=match):
        catalogue.compare_sessions(sessions, "punctured", **kwargs)


def test_pooled_fit_matches_the_true_curves(sessions):
    fit = catalogue.fit_pooled(sessions[:2], "pressurised", n_bootstrap=0)
    assert fit.n_impacts == 2 * N_PER_BALL
    p = TRUE["pressurised"]
    for speed in (15.0, 20.0, 28.0):
        tc_true, cor_true = _model_at(p, speed)
        sim = simulate_impact(speed, fit.mass_kg, fit.kb0_N_m, fit.ak, fit.a, fit.ac)
        assert_allclose(float(sim.contact_time_s) * 1e3, tc_true, rtol=0.01)
        assert_allclose(float(sim.cor), cor_true, rtol=0.01)
    assert fit.ac_lo < p.ac < fit.ac_hi


@pytest.mark.parametrize(("which", "ball", "match"), [
    ([0], "pressurised", "at least two sessions"),
    ([0, 0], "pressurised", "lists a session twice"),
    ([0, 1], "oversize", "has no ball type 'oversize'"),
])
def test_pooled_fit_rejects_bad_pools(sessions, which, ball, match):
    with pytest.raises(ValueError, match=match):
        catalogue.fit_pooled([sessions[i] for i in which], ball)


def test_ranking_follows_the_model_at_20_m_s(sessions):
    ranking = catalogue.ranking_table(sessions).set_index("ball")
    assert set(ranking["session_id"]) == {"s3"}  # each ball type's latest session
    truth = {"pressurised": TRUE["pressurised"], "punctured": CHANGED}
    cor = {b: _model_at(p, 20.0)[1] for b, p in truth.items()}
    kv = {b: p.mass_kg * math.pi**2 / (_model_at(p, 20.0)[0] * 1e-3) ** 2 / 1e3 for b, p in truth.items()}
    assert ranking.loc[max(cor, key=cor.get), "cor_rank"] == 1
    assert ranking.loc[max(kv, key=kv.get), "stiffness_rank"] == 1
    for ball in truth:
        assert_allclose(ranking.loc[ball, "cor"], cor[ball], rtol=0.02)
        assert_allclose(ranking.loc[ball, "stiffness_kN_m"], kv[ball], rtol=0.04)


def test_catalogue_table_one_row_per_session_and_ball(sessions):
    table = catalogue.catalogue_table(sessions)
    assert list(table.columns[:2]) == catalogue.ID_COLUMNS
    assert list(table.columns[2:-1]) == list(sessions[0].parameters.columns)
    assert table.columns[-1] == "pooled_sessions"
    assert len(table) == 3 * 2
    assert set(zip(table.session_id, table.ball)) == {(s, b) for s in ("s1", "s2", "s3") for b in TRUE}


def _write_results(session, root):
    """results/<session>/<session>.nc and parameters.csv as the workflow writes them."""
    folder = root / session.session_id
    folder.mkdir(parents=True)
    ds = xr.merge([session.impacts, session.balls], compat="override")
    ds.attrs.update(session_id=session.session_id, session_date=session.session_date)
    archive.write_dataset(archive.set_variable_attrs(ds), folder / f"{session.session_id}.nc")
    session.parameters.to_csv(folder / "parameters.csv", index=False)
    return folder


def test_write_catalogue_files(sessions, tmp_path):
    dirs = [_write_results(s, tmp_path / "results") for s in reversed(sessions)]
    out = tmp_path / "results" / "catalogue"
    result = catalogue.write_catalogue(
        dirs, out / "catalogue.csv", out / "catalogue.nc", out / "catalogue.pdf",
        pools=[{"ball": "pressurised", "sessions": ["s1", "s2"]}], n_bootstrap=10,
    )
    table = pd.read_csv(out / "catalogue.csv", keep_default_na=False, na_values=[""])
    assert list(table.session_id) == ["s1", "s1", "s2", "s2", "s3", "s3", "pooled:s1+s2"]  # by date
    pooled = table.iloc[-1]
    assert pooled.pooled_sessions == "s1+s2" and pooled.n_impacts == 2 * N_PER_BALL
    assert pooled.ak_lo < pooled.ak_kN_m < pooled.ak_hi
    ds = xr.open_dataset(out / "catalogue.nc")
    assert dict(ds["model_cor"].sizes) == {"session": 4, "ball": 2, "speed": archive.SPEED_GRID_M_S.size}
    assert ds["changed"].sel(ball="punctured").item() == "changed"
    assert ds["changed"].sel(ball="pressurised").item() == "unchanged"
    assert_allclose(ds["change_p_value"].sel(ball="punctured"), result["tests"]["punctured"].p_value, rtol=1e-12)
    # AK's kN m-(1+a) has no UDUNITS form: it is stated in units_metadata instead of units
    assert all({"units", "units_metadata"} & set(ds[v].attrs) and "long_name" in ds[v].attrs for v in ds.variables)
    assert (out / "catalogue.pdf").read_bytes().startswith(b"%PDF")


def test_read_session_results_names_the_missing_file(tmp_path):
    (tmp_path / "s9").mkdir()
    with pytest.raises(FileNotFoundError, match=r"s9\.nc: not found"):
        catalogue.read_session_results(tmp_path / "s9")


def test_read_session_results_rejects_another_sessions_archive(sessions, tmp_path):
    folder = _write_results(sessions[0], tmp_path)
    shutil.move(folder, tmp_path / "s7")
    (tmp_path / "s7" / "s1.nc").rename(tmp_path / "s7" / "s7.nc")
    with pytest.raises(ValueError, match="session_id is 's1', not the folder name 's7'"):
        catalogue.read_session_results(tmp_path / "s7")


# ------------------------------------------------------------------------ the workflow


def _synth(raw, session_id, date, seed, balls=None, n=8):
    from ballimpact.synth import SynthConfig, write_session

    kw = {"balls": balls, "labels": {k: k for k in balls}} if balls else {}
    write_session(raw / session_id, SynthConfig(session_id=session_id, seed=seed, impacts_per_ball=n,
                                                faults_per_kind=0, date=date, **kw))
    for truth in raw.glob(f"{session_id}.truth.*"):  # keep raw/ to session folders
        truth.unlink()


def _mtimes(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*") if p.is_file()}


@pytest.mark.slow
def test_workflow_catalogue_flags_the_changed_ball_and_adds_a_session(tmp_path):
    """Two synthetic sessions, punctured changed (AC x 1.5) in the second; then a third session.

    Snakemake is asked for the catalogue only (results/catalogue/catalogue.csv and what it
    needs: each session's archive and parameters.csv), not for the figures and reports,
    which this test does not read; the full runs are tested in test_workflow.py and test_run.py.
    """
    raw, results, work = tmp_path / "raw", tmp_path / "results", tmp_path / "work"
    raw.mkdir()
    work.mkdir()
    _synth(raw, "s2026-12-01", "2026-12-01", 101)
    changed = {k: b.params for k, b in BALLS.items()}
    changed["punctured"] = CHANGED
    _synth(raw, "s2027-01-15", "2027-01-15", 102, balls=changed)
    args = ["--snakefile", REPO / "Snakefile", "--directory", work, "--cores", "2",
            "--config", f"raw_dir={raw}", f"results_dir={results}", "bootstrap=10"]
    args = [results / "catalogue" / "catalogue.csv", *args]  # the target, before --config's list
    proc = run_snakemake(*args, cwd=work)
    assert proc.returncode == 0, proc.stdout[-5000:]
    cat = results / "catalogue"
    ds = xr.open_dataset(cat / "catalogue.nc")
    verdict = {str(b): str(v) for b, v in zip(ds["ball"].values, ds["changed"].values)}
    assert verdict == {"pressurised": "unchanged", "pressureless": "unchanged", "oversize": "unchanged",
                       "punctured": "changed"}, ds["change_p_value"].values
    assert float(ds["change_p_value"].sel(ball="punctured")) < 0.01
    table = pd.read_csv(cat / "catalogue.csv", keep_default_na=False, na_values=[""])
    assert len(table) == 2 * 4
    # parameters.csv of each session is in the catalogue as it is
    first = pd.read_csv(results / "s2026-12-01" / "parameters.csv", keep_default_na=False, na_values=[""])
    rows = table[table.session_id == "s2026-12-01"].drop(columns=["session_id", "session_date", "pooled_sessions"])
    assert_allclose(rows[["ak_kN_m", "a", "ac_kN_s_m3"]].to_numpy(float), first[["ak_kN_m", "a", "ac_kN_s_m3"]],
                    rtol=1e-12)

    # a third session: only it is processed, and the catalogue is rebuilt with it
    before = {p: t for p, t in _mtimes(results).items() if "catalogue" not in p.parts}
    cat_before = (cat / "catalogue.csv").stat().st_mtime_ns
    _synth(raw, "s2027-02-01", "2027-02-01", 103, balls={"pressurised": TRUE["pressurised"]}, n=5)
    proc = run_snakemake(*args, cwd=work)
    assert proc.returncode == 0, proc.stdout[-5000:]
    after = _mtimes(results)
    assert all(after[p] == t for p, t in before.items()), [p for p, t in before.items() if after[p] != t][:5]
    assert not [line for line in proc.stdout.splitlines()
                if "wildcards: session=" in line and "s2027-02-01" not in line]
    assert (results / "s2027-02-01" / "parameters.csv").is_file()
    assert (cat / "catalogue.csv").stat().st_mtime_ns > cat_before
    table = pd.read_csv(cat / "catalogue.csv", keep_default_na=False, na_values=[""])
    assert "s2027-02-01" in set(table.session_id)
    assert "Nothing to be done" in run_snakemake(*args, "-n", cwd=work).stdout


@pytest.fixture(scope="module")
def two_session_raw(tmp_path_factory):
    """raw/ with two small synthetic sessions a1 (every Table 2 ball) and a2 (pressurised only)."""
    raw = tmp_path_factory.mktemp("pool") / "raw"
    raw.mkdir()
    _synth(raw, "a1", "2026-05-01", 7, n=3)
    _synth(raw, "a2", "2026-05-02", 8, balls={"pressurised": TRUE["pressurised"]}, n=3)
    return raw


@pytest.mark.parametrize(("pool", "match"), [
    ("pool=[{ball: pressurised, sessions: [a1, a2]}]", None),
    ("pool=[{ball: pressurised, sessions: [a1, zz]}]", r"config key 'pool' entry 0 \(ball 'pressurised'\): "
                                                       r"session 'zz' is not selected"),
    ("pool=[{ball: punctured, sessions: [a1, a2]}]", r"session 'a2' has no impacts of ball type 'punctured'"),
    pytest.param("pool=[{ball: pressurised, sessions: [a1]}]", r"key 'pool.0.sessions'", marks=pytest.mark.slow),
    pytest.param("pool=[{ball: pressurised}]", r"missing required key 'pool.0.sessions'", marks=pytest.mark.slow),
])
def test_pool_config_is_checked_before_running(two_session_raw, tmp_path, pool, match):
    proc = run_snakemake("-n", "--cores", "2", "--directory", tmp_path, "--snakefile", REPO / "Snakefile",
                         "--config", f"raw_dir={two_session_raw}", f"results_dir={tmp_path / 'results'}", pool,
                         cwd=tmp_path)
    if match is None:
        assert proc.returncode == 0, proc.stdout[-3000:]
        assert "catalogue" in proc.stdout
    else:
        assert proc.returncode != 0
        assert re.search(match, proc.stdout), proc.stdout[-3000:]

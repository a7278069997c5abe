"""Synthetic sessions: determinism, format, planted faults, ground truth beside the folder."""

import hashlib

import numpy as np
import pandas as pd
import pytest
import yaml

from ballimpact.synth import FAULT_KINDS, SynthConfig, write_session
from ballimpact.traces import read_trace


def _digest(folder):
    h = hashlib.sha256()
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            h.update(p.relative_to(folder).as_posix().encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def _small(sid, **kw):
    return SynthConfig(session_id=sid, balls={k: v for k, v in list(SynthConfig().balls.items())[:2]},
                       impacts_per_ball=2, faults_per_kind=1, **kw)


def test_same_seed_same_bytes_other_seed_differs(tmp_path):
    a, _ = write_session(tmp_path / "a" / "s", _small("s", seed=7))
    b, _ = write_session(tmp_path / "b" / "s", _small("s", seed=7))
    c, _ = write_session(tmp_path / "c" / "s", _small("s", seed=8))
    assert _digest(a) == _digest(b)
    assert _digest(a) != _digest(c)


def test_truth_beside_not_inside_and_faults_planted(tmp_path):
    session, truth_csv = write_session(tmp_path / "s", _small("s", seed=1))
    assert truth_csv.parent == session.parent and truth_csv.exists()
    assert not any("truth" in p.name for p in session.rglob("*"))
    truth = pd.read_csv(truth_csv, keep_default_na=False)
    assert sorted(truth["fault"].unique()) == sorted([""] + list(FAULT_KINDS))
    impacts = pd.read_csv(session / "impacts.csv", dtype=str, keep_default_na=False)
    assert len(impacts) == len(truth) == 2 * 2 + len(FAULT_KINDS)
    missing = truth.loc[truth.fault == "missing_trace", "impact_id"].item()
    row = impacts.set_index("impact_id").loc[missing]
    assert not (session / row["trace"]).exists()
    gated = truth.loc[truth.fault == "missing_gate", "impact_id"].item()
    gates = impacts.set_index("impact_id").loc[gated, ["gate_in_1_s", "gate_in_2_s", "gate_out_2_s", "gate_out_1_s"]]
    assert (gates == "").sum() == 1
    meta = yaml.safe_load((session / "session.yaml").read_text())
    assert meta["synthetic"] is True and "SYNTHETIC" in meta["description"]


def test_trace_physics_polarity_and_clipping(tmp_path):
    session, truth_csv = write_session(tmp_path / "neg", _small("neg", seed=2, polarity=-1))
    truth = pd.read_csv(truth_csv, keep_default_na=False).set_index("impact_id")
    for impact_id, row in truth.iterrows():
        path = session / "traces" / f"{impact_id}.csv"
        if not path.exists():
            continue
        tr = read_trace(path, 66964.3)
        v = tr.voltage_V
        if row.fault == "clipped":
            assert np.isclose(v.min(), -10.0, atol=1e-3)  # negative polarity clips at the lower rail
        elif row.fault == "":
            # the impulse of the recorded voltage, offset removed, matches m (vin + vout) / kcal
            base = np.median(v[: int(0.02 * tr.sample_rate_hz)])
            i0 = int((row.contact_start_s - 0.001) * tr.sample_rate_hz)
            i1 = int((row.contact_start_s + row.contact_time_ms * 1e-3 + 0.001) * tr.sample_rate_hz)
            area = -np.trapezoid(v[i0:i1] - base, dx=1 / tr.sample_rate_hz)
            np.testing.assert_allclose(area * row.kcal_N_per_V, row.impulse_N_s, rtol=0.03)


def test_total_impacts_exact(tmp_path):
    session, truth_csv = write_session(tmp_path / "n", SynthConfig(session_id="n", total_impacts=23, faults_per_kind=1))
    assert len(pd.read_csv(session / "impacts.csv")) == 23


@pytest.mark.parametrize("kw, match", [({"polarity": 2}, "polarity"), ({"trace_format": "xls"}, "trace_format")])
def test_config_validation(kw, match):
    with pytest.raises(ValueError, match=match):
        SynthConfig(**kw)


def test_refuses_non_empty_folder(tmp_path):
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "x").write_text("keep me")
    with pytest.raises(FileExistsError, match="not empty"):
        write_session(tmp_path / "s", _small("s"))

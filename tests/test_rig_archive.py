"""The rig in the archive: the impacts the plate's fit pooled, and their free ringing rebuilt for a figure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ballimpact.rig_archive import plate_impacts, read_rig, ringing_overlay, rig_warnings

from rigkit import FN_HZ, NOISE_V, RING_V, ZETA, ringing_archive


def _misfit(overlay, fn_hz=FN_HZ, zeta=ZETA):
    """RMS of each curve about the true damped response exp(-zeta wn t) cos(wd t) (numpy, from the truth)."""
    wn = 2 * math.pi * fn_hz
    wd = wn * math.sqrt(1 - zeta**2)
    return np.array([np.sqrt(np.mean((y - np.exp(-zeta * wn * t) * np.cos(wd * t)) ** 2)) for t, y in overlay.curves])


def test_the_ringing_of_every_impact_falls_on_the_plate_s_damped_response():
    """Random phases, a slow baseline and noise: shifted by its phase and divided by its amplitude, each impact's
    ringing is the true exp(-zeta wn t) cos(wd t) within its noise (NOISE_V over an amplitude of about RING_V)."""
    ds = ringing_archive(8)
    overlay = ringing_overlay(ds)
    assert overlay is not None and overlay.source == "identified"
    assert overlay.impact_ids == tuple(str(i) for i in ds.impact_id.values)
    assert (overlay.frequency_hz, overlay.damping_ratio) == (FN_HZ, ZETA)
    misfit = _misfit(overlay)
    assert misfit.max() < 1.5 * NOISE_V / RING_V, misfit  # noise alone: about 1.1 NOISE_V / RING_V
    for t, y in overlay.curves:
        assert abs(t[0]) <= 0.5 / FN_HZ + 1e-12  # shifted by at most half a period
        near = np.abs(t) < 0.02 / FN_HZ
        if near.any():  # at the phase origin the ringing is at its crest, 1
            assert y[near].mean() == pytest.approx(1.0, abs=0.1)


def test_a_resonance_that_is_not_the_plate_s_leaves_the_curves_apart():
    """A stored fn 10 % off the plate's: the rebuilt curves miss the response by far more than their noise."""
    overlay = ringing_overlay(ringing_archive(8, fn_hz=1.1 * FN_HZ))
    assert overlay.frequency_hz == pytest.approx(1.1 * FN_HZ)
    assert np.median(_misfit(overlay, 1.1 * FN_HZ)) > 5 * NOISE_V / RING_V


def test_a_stated_plate_is_drawn_at_its_stated_values():
    overlay = ringing_overlay(ringing_archive(6, plate="stated"))
    assert overlay.source == "stated" and len(overlay.curves) == 6
    assert _misfit(overlay).max() < 1.5 * NOISE_V / RING_V


def test_only_the_impacts_the_fit_pooled_are_read_again():
    ds = ringing_archive(6)
    ds["rig_value"].attrs["plate_impacts"] = "imp-001,imp-004"
    assert plate_impacts(ds) == ["imp-001", "imp-004"]
    assert ringing_overlay(ds).impact_ids == ("imp-001", "imp-004")


def test_no_plate_no_rig_no_overlay():
    none = ringing_archive(6, plate="none")
    assert ringing_overlay(none) is None
    assert "no free ringing" in read_rig(none)["plate_resonance_hz"].note
    old = ringing_archive(6).drop_vars([v for v in ringing_archive(6).variables if str(v).startswith("rig_")])
    assert ringing_overlay(old) is None and plate_impacts(old) == [] and read_rig(old) == {} and rig_warnings(old) == []


@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_a_stated_plate_and_the_identified_one_agree_within_the_interval(tmp_path):
    """One rig of the session zoo (bench/rig_zoo.py: a 3.2 kHz plate at 174 kHz) written twice, its plate stated
    by the keys in one session and left to the traces in the other: the rig each workflow stores gives the stated
    values in the first, and in the second an identified interval that holds them, with no warning either way."""
    import dataclasses
    import importlib
    import sys
    import warnings
    from pathlib import Path

    from ballimpact import archive, pipeline

    bench = Path(__file__).resolve().parents[1] / "bench"
    sys.path.insert(0, str(bench))
    try:
        rig_zoo = importlib.import_module("rig_zoo")
    finally:
        sys.path.remove(str(bench))
    base = rig_zoo.draw_rig(1000, 14, (8, 8))
    found = {}
    others = tuple(k for k in base.stated if k != "resonance")
    for stated in (True, False):
        rig = dataclasses.replace(base, stated=others + (("resonance",) if stated else ()))
        raw, out = tmp_path / str(stated) / "raw", tmp_path / str(stated) / "out"
        rig_zoo.write_session(rig, raw)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            pipeline.session_impacts(raw / rig.session_id, out / "session.json", out / "impacts.csv",
                                     out / "impacts.nc")
        with archive.open_dataset(out / "impacts.nc") as ds:
            found[stated] = (read_rig(ds), rig_warnings(ds))
        assert not [w for w in caught if "session.yaml states" in str(w.message)]
    (given, warned_given), (own, warned_own) = found[True], found[False]
    assert warned_given == warned_own == []
    for name in ("plate_resonance_hz", "plate_damping_ratio"):
        assert given[name].source == "stated" and own[name].source == "identified"
        assert own[name].low <= given[name].value <= own[name].high, (name, given[name], own[name])
        assert "the session's traces give" in given[name].note

"""The session's identified plate, used in the impacts whose own trace could not undo it (ballimpact.session_plate)."""

from __future__ import annotations

import pytest

from ballimpact.rig import Rig, RigEstimate
from ballimpact.session_plate import (SESSION_MAINS_MIN_IMPACTS, SESSION_PLATE_MAX_SPREAD, SESSION_ZETA_CHARGE,
                                      retry_candidates, session_mains, session_plate, session_plate_uncertainty)
from ballimpact.signal.sensed_ends import SENSED_FN_UNCERTAINTY


def _rig(fn, low, high, zeta=0.05, source="identified", zeta_interval=(0.04, 0.06)):
    return Rig(estimates={"plate_resonance_hz": RigEstimate(fn, low, high, source=source, n_impacts=30),
                          "plate_damping_ratio": RigEstimate(zeta, *zeta_interval, source=source, n_impacts=30)})


def test_an_identified_plate_known_to_its_charge_is_used_and_no_other():
    assert session_plate(_rig(5000.0, 4980.0, 5030.0)) == (5000.0, 0.05)
    # an interval wider than SESSION_PLATE_MAX_SPREAD on either side: too little known to start from
    wide = 5000.0 * (1 + 1.2 * SESSION_PLATE_MAX_SPREAD)
    assert session_plate(_rig(5000.0, 4990.0, wide)) is None
    assert session_plate(_rig(5000.0, 5000.0, 5000.0, source="stated")) is None  # the impacts used it already
    assert session_plate(_rig(float("nan"), float("nan"), float("nan"), source="none")) is None
    with pytest.raises(KeyError, match="valid names"):
        Rig(estimates={})["plate_resonance_hz"]


def test_impacts_retried_are_those_a_plate_s_ringing_alone_withheld():
    ids = ["a", "b", "c", "d", "e", "f"]
    status = ["withheld", "withheld", "withheld", "ok", "withheld", "withheld"]
    codes = ["plate_ringing;negative_force", "peak_between_samples", "plate_ringing;multiple_impacts",
             "plate_ringing", "peak_on_ringing;contact_end_undetermined", ""]
    # b: no evidence of the plate; c: a fault besides; d: TC ok; f: nothing found
    assert retry_candidates(ids, status, codes) == ["a", "e"]


def _mains_rig(value, low, high, n_impacts=10, source="identified"):
    return Rig(estimates={"mains_hz": RigEstimate(value, low, high, source=source, n_impacts=n_impacts)})


def test_the_sessions_mains_is_used_where_every_impact_that_resolved_its_hum_agrees():
    assert session_mains(_mains_rig(60.0, 60.0, 60.0)) == 60.0
    assert session_mains(_mains_rig(60.0, 50.0, 60.0)) is None  # some impacts found 50 Hz: not known
    assert session_mains(_mains_rig(60.0, 60.0, 60.0, n_impacts=SESSION_MAINS_MIN_IMPACTS - 1)) is None
    assert session_mains(_mains_rig(50.0, 50.0, 50.0, source="stated")) is None  # the impacts used it already
    assert session_mains(_mains_rig(0.0, float("nan"), float("nan"), n_impacts=0, source="none")) is None


def test_impacts_retried_with_the_sessions_mains_are_those_an_unresolved_hum_withheld_without_a_fault():
    ids = ["a", "b", "c", "d"]
    status = ["withheld", "withheld", "excluded", "ok"]
    codes = ["mains_unresolved;contact_end_undetermined", "contact_end_undetermined",
             "mains_unresolved;clipping", "mains_unresolved"]
    # b: no hum finding; c: clipped (a fault) besides; d: TC ok
    assert retry_candidates(ids, status, codes, plate=False, mains=True) == ["a"]
    assert retry_candidates(ids, status, codes, plate=False, mains=False) == []


@pytest.mark.parametrize(("interval", "charged"), [
    ((0.049, 0.051), SESSION_ZETA_CHARGE[1]),  # 2 % either side: twice that is under the floor
    ((0.046, 0.0515), 2 * 0.08),  # the larger side, 8 %, twice
    ((0.04, 0.06), 2 * 0.2),  # 20 % either side: twice that, more than a stated plate's charge
])
def test_the_sessions_plate_is_charged_twice_its_damping_ratios_interval_within_bounds(interval, charged):
    fn_charge, zeta_charge = session_plate_uncertainty(_rig(5000.0, 4990.0, 5010.0, zeta_interval=interval))
    assert fn_charge == SENSED_FN_UNCERTAINTY  # 0.2 % either side: twice that is under a stated plate's 1 %
    assert zeta_charge == pytest.approx(charged, rel=1e-9)


def test_the_sessions_plate_known_to_a_few_per_cent_is_charged_twice_its_resonances_interval():
    fn_charge, _ = session_plate_uncertainty(_rig(5000.0, 4900.0, 5150.0))
    assert fn_charge == pytest.approx(2 * 0.03, rel=1e-9)  # the larger side, 3 %, twice

"""Reading an archive (ballimpact.archive_read) on a small archive built by hand: every value is known."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from numpy.testing import assert_allclose

from ballimpact import archive_read as ar


@pytest.fixture()
def ds():
    nan = np.nan
    return xr.Dataset(
        {
            "ball_type": ("impact", np.array(["b1", "b2", "b1", "b3"], dtype=object)),
            "status": ("impact", np.array(["ok", "ok", "excluded", "excluded"], dtype=object)),
            "reason": ("impact", np.array(["", "", "gate", "trace"], dtype=object)),
            "vin_m_s": ("impact", [20.0, 25.0, nan, 30.0]),
            "time_s": (("impact", "sample"), [[0.0, 1e-3, nan], [0.0, 1e-3, 2e-3], [nan] * 3, [nan] * 3]),
            "force_N": (("impact", "sample"), [[1.0, 2.0, nan], [3.0, 4.0, 5.0], [nan] * 3, [nan] * 3]),
            "ball_label": ("ball", np.array(["Ball one", ""], dtype=object)),
            "mass_kg": ("ball", [0.057, 0.058]),
            "kb0_kN_m": ("ball", [21.0, 23.0]),
            "ak_kN_m": ("ball", [24000.0, nan]),
            "ak_lo": ("ball", [15000.0, nan]),
            "ak_hi": ("ball", [38000.0, nan]),
            "a": ("ball", [1.75, 1.8]),
            "ac_kN_s_m3": ("ball", [3.5, 4.0]),
        },
        coords={"impact_id": ("impact", np.array(["i1", "i2", "i3", "i4"], dtype=object)),
                "ball": np.array(["b1", "b2"], dtype=object)},
    )


def test_balls_come_in_archive_order_then_impact_only_balls(ds):
    assert ar.balls(ds) == ["b1", "b2", "b3"]


@pytest.mark.parametrize(("ball", "status", "expected"), [
    (None, None, [0, 1, 2, 3]), ("b1", None, [0, 2]), ("b1", "ok", [0]), (None, "excluded", [2, 3]), ("b9", None, []),
])
def test_impacts_by_ball_and_status(ds, ball, status, expected):
    assert ar.impacts(ds, ball, status).tolist() == expected


def test_parameter_comes_with_its_interval(ds):
    assert_allclose(ar.parameter(ds, "ak_kN_m", "b1"), (24000.0, 15000.0, 38000.0), rtol=0)
    assert np.isnan(ar.parameter(ds, "ak_kN_m", "b2")).all()
    kb0, lo, hi = ar.parameter(ds, "kb0_kN_m", "b1")  # no kb0_lo/kb0_hi in this archive: NaN
    assert kb0 == 21.0 and np.isnan(lo) and np.isnan(hi)
    with pytest.raises(ValueError, match="parameter must be one of .*got 'mass_kg'"):
        ar.parameter(ds, "mass_kg", "b1")


def test_fitted_parameters_are_in_si_units_and_none_when_missing(ds):
    # kN/m -> N/m, kN m^-(1+a) -> N m^-(1+a), kN s/m^3 -> N s/m^3
    assert_allclose(ar.fitted_parameters(ds, "b1"), (0.057, 21e3, 24e6, 1.75, 3.5e3), rtol=1e-12)
    assert ar.fitted_parameters(ds, "b2") is None  # AK NaN: the fit failed
    assert ar.fitted_parameters(ds, "b3") is None  # no fit at all


def test_labels_fall_back_on_the_key(ds):
    assert [ar.ball_label(ds, b) for b in ("b1", "b2", "b3")] == ["Ball one", "b2", "b3"]


def test_contact_series_keeps_the_rows_with_a_time(ds):
    t, f, missing = ar.contact_series(ds, 0, "force_N", "velocity_m_s")
    assert_allclose(t, [0.0, 1e-3], rtol=0)
    assert_allclose(f, [1.0, 2.0], rtol=0)
    assert missing.shape == (2,) and np.isnan(missing).all()


def test_impact_lookup_and_exclusions(ds):
    assert ar.impact_position(ds, "i3") == 2
    with pytest.raises(KeyError, match="impact_id 'nope' is not in the archive"):
        ar.impact_position(ds, "nope")
    assert ar.excluded_impacts(ds) == [("i3", "b1", "gate"), ("i4", "b3", "trace")]
    assert ar.impact_value(ds, "vin_m_s", 1) == 25.0
    assert np.isnan(ar.impact_value(ds, "cor", 1))
    assert ar.ball_value(ds, "mass_kg", "b2") == 0.058
    assert ar.ball_array(ds, "model_cor", "b1") is None


@pytest.mark.parametrize(("attrs", "expected"), [
    ({"validate_warnings": '["w1", "w2"]'}, ["w1", "w2"]),
    ({"validate_warnings": "[]"}, []),
    ({}, []),  # an archive written before the attribute existed
    ({"validate_warnings": "not json"}, []),
    ({"validate_warnings": '{"a": 1}'}, []),
])
def test_validate_warnings_read_from_the_json_attribute(attrs, expected):
    assert ar.validate_warnings(xr.Dataset(attrs=attrs)) == expected

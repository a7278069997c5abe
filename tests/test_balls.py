"""Table 2 parameter sets."""

import pytest
from numpy.testing import assert_allclose

from ballimpact.balls import BALLS, BallModelParameters, get_ball


def test_table2_values_in_si():
    p = get_ball("pressurised").params
    assert_allclose([p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac], [0.0577, 21e3, 16e6, 1.65, 3.5e3], rtol=1e-12)
    assert set(BALLS) == {"pressurised", "pressureless", "oversize", "punctured"}


def test_table_units_round_trip():
    p = BallModelParameters.from_table_units(57.1, 23, 12_500, 1.7, 4.0)
    assert_allclose(list(p.table_units().values()), [57.1, 23, 12_500, 1.7, 4.0], rtol=1e-12)


def test_unknown_ball_lists_valid_names():
    with pytest.raises(KeyError, match="valid names: oversize, pressureless, pressurised, punctured"):
        get_ball("pressurized")

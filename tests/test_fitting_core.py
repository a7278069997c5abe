"""Tests of the core of ballimpact.fitting (the model inversion) that the sampled mutation run asked for.

The rest of fitting's tests are in tests/test_fitting.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from ballimpact.balls import BALLS
from ballimpact.fitting import fit_contact_time, fit_restitution

P = BALLS["pressurised"].params
VIN = np.array([15.0, 20.0, 25.0])


@pytest.mark.parametrize(("fit", "name"), [(fit_contact_time, "contact_time_s"), (fit_restitution, "cor")])
@pytest.mark.parametrize(("bad", "what"), [
    ([0.6, np.nan, 0.6], r"must be finite, got .*nan.*"),
    ([0.6, 0.6], r"must have 3 values \(one per impact\), got 2"),
])
def test_stages_name_the_bad_argument(fit, name, bad, what):
    """A bad measured series is refused with its argument's name (as in the signature) and what is wrong."""
    args = {"contact_time_s": (VIN, bad, P.mass_kg, P.kb0_N_m),
            "cor": (VIN, bad, P.mass_kg, P.kb0_N_m, P.ak, P.a)}[name]
    with pytest.raises(ValueError, match=rf"^{name} {what}$"):
        fit(*args)


@pytest.mark.parametrize(("jac", "dof", "expected"), [
    # TC and COR rows carry equal variance, each estimated with 8 degrees of freedom: their sum
    # has 16 (two independent chi-square estimates of the same size add their dof)
    ([[1.0], [1.0], [1.0], [1.0]], (8.0, 8.0), 16.0),
    # the COR rows carry no information on the parameter: only the TC scatter counts
    ([[1.0], [2.0], [0.0], [0.0]], (5.0, 9.0), 5.0),
    # unequal: Welch-Satterthwaite (v1 + v2)^2 / (v1^2 / n1 + v2^2 / n2) with v1 = 1/25, v2 = 4/25
    # (jac rows 1 and 2; cov = 1/5, v = cov * grad, v_k = (jac_k v)^2), n1 = 4, n2 = 6
    ([[1.0], [0.0], [2.0], [0.0]], (4.0, 6.0), (1 / 25 + 4 / 25) ** 2 / ((1 / 25) ** 2 / 4 + (4 / 25) ** 2 / 6)),
])
def test_satterthwaite_degrees_of_freedom(jac, dof, expected):
    """Degrees of freedom of a variance built from the TC and the COR scatter (Satterthwaite 1946)."""
    from ballimpact.fitting import _satterthwaite_dof

    got = _satterthwaite_dof(np.array([1.0]), np.array(jac), 2, *dof)
    assert got == pytest.approx(expected, rel=1e-12)

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

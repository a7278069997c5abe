"""Named ball parameter sets: the four ball types of Tables 1 and 2 in Goodwill & Haake 2004."""

from __future__ import annotations

from dataclasses import dataclass, replace

__all__ = [
    "BALLS",
    "BallModelParameters",
    "get_ball",
    "KN",
]

#: One kilonewton expressed in newtons [N/kN]; Table 2 quotes its parameters in kN.
KN = 1.0e3


@dataclass(frozen=True)
class BallModelParameters:
    """Parameters of the improved viscoelastic ball model, SI units.

    Attributes
    ----------
    mass_kg : float
        Ball mass [kg].
    kb0_N_m : float
        Stiffness at zero displacement kB(0) [N/m] (Eq. (4)).
    ak : float
        Stiffness coefficient AK [N/m^(1+a)], with x in metres (Eq. (4)). Table 2
        prints it in kN/m2; the value in SI is the table value times 1000.
    a : float
        Stiffness exponent a [-] (Eq. (4)).
    ac : float
        Damping area constant AC [N s/m^3] (Eq. (7)); Table 2 value times 1000.
    """

    mass_kg: float
    kb0_N_m: float
    ak: float
    a: float
    ac: float

    @classmethod
    def from_table_units(
        cls, mass_g: float, kb0_kN_m: float, ak_kN: float, a: float, ac_kN_s_m3: float
    ) -> "BallModelParameters":
        """Build from the units of Table 2 (g, kN/m, kN/m^(1+a), -, kN s/m^3)."""
        return cls(
            mass_kg=mass_g / 1000.0,
            kb0_N_m=kb0_kN_m * KN,
            ak=ak_kN * KN,
            a=a,
            ac=ac_kN_s_m3 * KN,
        )

    def table_units(self) -> dict[str, float]:
        """The parameters in Table 2 units: mass_g, kb0_kN_m, ak_kN_m, a, ac_kN_s_m3."""
        return {
            "mass_g": self.mass_kg * 1000.0,
            "kb0_kN_m": self.kb0_N_m / KN,
            "ak_kN_m": self.ak / KN,
            "a": self.a,
            "ac_kN_s_m3": self.ac / KN,
        }

    def with_(self, **changes: float) -> "BallModelParameters":
        """A copy with some parameters changed (SI units)."""
        return replace(self, **changes)


@dataclass(frozen=True)
class BallType:
    """A ball type of the paper: label, Table 1 measurements and Table 2 parameters.

    Attributes
    ----------
    key : str
        Short name used in session files.
    label : str
        Label as in the paper.
    params : BallModelParameters
        Table 2 parameters (SI).
    itf_rebound_cm : float
        Rebound from 254 cm [cm], Table 1.
    forward_deformation_mm, return_deformation_mm : float
        ITF deformation test at 80 N [mm], Table 1.
    """

    key: str
    label: str
    params: BallModelParameters
    itf_rebound_cm: float
    forward_deformation_mm: float
    return_deformation_mm: float


def _ball(key, label, mass_g, kb0, ak, a, ac, rebound, fwd, ret) -> BallType:
    return BallType(
        key=key,
        label=label,
        params=BallModelParameters.from_table_units(mass_g, kb0, ak, a, ac),
        itf_rebound_cm=rebound,
        forward_deformation_mm=fwd,
        return_deformation_mm=ret,
    )


#: The four ball types of Goodwill & Haake 2004: masses and ITF tests from Table 1,
#: model parameters kB(0) [kN/m], AK [kN/m^(1+a)], a [-], AC [kN s/m^3] from Table 2.
BALLS: dict[str, BallType] = {
    "pressurised": _ball("pressurised", "Ball 1: pressurised", 57.7, 21, 16_000, 1.65, 3.5, 138.9, 6.2, 8.6),
    "pressureless": _ball("pressureless", "Ball 2: pressureless", 57.1, 23, 12_500, 1.70, 4.0, 142.2, 6.4, 9.6),
    "oversize": _ball("oversize", "Ball 3: oversize", 56.7, 21, 3_600, 1.30, 3.2, 137.4, 6.8, 9.3),
    "punctured": _ball("punctured", "Ball 4: punctured", 57.5, 16, 60_000, 2.00, 5.8, 103.8, 8.4, 15.2),
}


def get_ball(name: str) -> BallType:
    """Look up a Table 2 ball type by key.

    Parameters
    ----------
    name : str
        One of the keys of :data:`BALLS`.

    Raises
    ------
    KeyError
        If the name is unknown; the message lists the valid names.
    """
    try:
        return BALLS[name]
    except KeyError:
        raise KeyError(
            f"unknown ball type {name!r}; valid names: {', '.join(sorted(BALLS))}"
        ) from None

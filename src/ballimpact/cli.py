"""Command line: `ballimpact simulate | itf | validate | synth`."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from . import __version__

SIMULATE_KEYS = ("vin_m_s", "contact_time_ms", "cor", "peak_force_N", "max_displacement_mm")


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _nonnegative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not np.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}")
    return value


def _mass_g(text: str) -> float:
    """A ball mass [g], checked as session.yaml ``mass_g`` is (error outside 1-1000 g)."""
    from .session import MASS_MAX_G, MASS_MIN_G

    value = _positive_float(text)
    if not MASS_MIN_G < value < MASS_MAX_G:
        hint = f" (in kg? {value:g} kg = {value * 1e3:g} g)" if value < MASS_MIN_G else ""
        raise argparse.ArgumentTypeError(
            f"the mass is in g and must be in ({MASS_MIN_G:g}, {MASS_MAX_G:g}) g, got {text!r}{hint}"
        )
    return value


def _speed_m_s(text: str) -> float:
    """An inbound speed [m/s] in the bounds processing accepts (validation.SPEED_RANGE_M_S)."""
    from .validation import SPEED_RANGE_M_S

    value = _positive_float(text)
    lo, hi = SPEED_RANGE_M_S
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"the inbound speed must be in {lo:g}-{hi:g} m/s, got {text!r}")
    return value


def _cmd_simulate(args) -> int:
    from .session import MASS_TYPICAL_MAX_G, MASS_TYPICAL_MIN_G

    if not MASS_TYPICAL_MIN_G <= args.mass_g <= MASS_TYPICAL_MAX_G:
        print(f"warning: --mass-g {args.mass_g:g} g is outside the usual {MASS_TYPICAL_MIN_G:g}-"
              f"{MASS_TYPICAL_MAX_G:g} g of a tennis ball", file=sys.stderr)
    from .balls import BallModelParameters
    from .model import simulate_impact

    params = BallModelParameters.from_table_units(args.mass_g, args.kb0, args.ak, args.a, args.ac)
    vin = np.asarray(args.vin, dtype=float)
    sim = simulate_impact(vin, params.mass_kg, params.kb0_N_m, params.ak, params.a, params.ac)
    rows = [
        {
            "vin_m_s": float(v),
            "contact_time_ms": float(tc) * 1e3,
            "cor": float(e),
            "peak_force_N": float(f),
            "max_displacement_mm": float(x) * 1e3,
        }
        for v, tc, e, f, x in zip(
            vin, sim.contact_time_s, sim.cor, sim.peak_force_N, sim.max_displacement_m
        )
    ]
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(
        f"Goodwill & Haake (2004) model: m = {args.mass_g:g} g, kB(0) = {args.kb0:g} kN/m, "
        f"AK = {args.ak:g} kN/m^(1+a), a = {args.a:g}, AC = {args.ac:g} kN s/m^3"
    )
    header = f"{'vin [m/s]':>10} {'TC [ms]':>9} {'COR [-]':>8} {'peak F [N]':>11} {'max x [mm]':>11}"
    print(header)
    for r in rows:
        print(
            f"{r['vin_m_s']:10.2f} {r['contact_time_ms']:9.3f} {r['cor']:8.4f} "
            f"{r['peak_force_N']:11.1f} {r['max_displacement_mm']:11.2f}"
        )
    return 0


def _cmd_itf(args) -> int:
    from .balls import BALLS, BallModelParameters
    from .itf import ITF_REBOUND_MAX_M, ITF_REBOUND_MIN_M, drop_test_cor, predict_itf_rebound

    custom = [args.mass_g, args.kb0, args.ak, args.a, args.ac]
    if any(v is not None for v in custom):
        if any(v is None for v in custom):
            print("error: custom parameters need all of --mass-g, --kb0, --ak, --a, --ac", file=sys.stderr)
            return 2
        balls = [("custom", BallModelParameters.from_table_units(*custom), args.measured_cm)]
    else:
        keys = args.ball or list(BALLS)
        balls = [(k, BALLS[k].params, BALLS[k].itf_rebound_cm) for k in keys]
    flight_kw = {"diameter_m": args.diameter_mm / 1000.0, "air_density_kg_m3": args.air_density,
                 "drag_coefficient": args.cd}
    rows = []
    for key, p, measured_cm in balls:
        pred = predict_itf_rebound(p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, **flight_kw)
        h_cm = float(pred.rebound_height_m) * 100.0
        row = {
            "ball": key,
            "impact_speed_m_s": float(pred.impact_speed_m_s),
            "model_cor": float(pred.cor),
            "itf_rebound_pred_cm": h_cm,
            "passes": bool(ITF_REBOUND_MIN_M * 100 <= h_cm <= ITF_REBOUND_MAX_M * 100),
            "itf_rebound_cm": measured_cm,
            "difference_cm": None,
            "drop_test_cor": None,
        }
        if measured_cm is not None:
            row["difference_cm"] = h_cm - measured_cm
            row["drop_test_cor"] = float(drop_test_cor(measured_cm / 100.0, p.mass_kg, **flight_kw))
        rows.append(row)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(
        f"ITF drop test (254 cm onto a rigid surface; pass {ITF_REBOUND_MIN_M * 100:.1f}-"
        f"{ITF_REBOUND_MAX_M * 100:.1f} cm) predicted by the Goodwill & Haake (2004) model, with air drag "
        f"(rho {args.air_density:g} kg/m^3, Cd {args.cd:g}, D {args.diameter_mm:g} mm)"
    )
    print(f"{'ball':>14} {'VB [m/s]':>9} {'model COR':>10} {'pred [cm]':>10} {'pass':>5} "
          f"{'measured [cm]':>14} {'diff [cm]':>10} {'drop COR':>9}")
    for r in rows:
        meas = "" if r["itf_rebound_cm"] is None else f"{r['itf_rebound_cm']:.1f}"
        diff = "" if r["difference_cm"] is None else f"{r['difference_cm']:+.1f}"
        dcor = "" if r["drop_test_cor"] is None else f"{r['drop_test_cor']:.3f}"
        print(f"{r['ball']:>14} {r['impact_speed_m_s']:9.3f} {r['model_cor']:10.3f} "
              f"{r['itf_rebound_pred_cm']:10.1f} {'yes' if r['passes'] else 'no':>5} {meas:>14} {diff:>10} {dcor:>9}")
    return 0


def _cmd_validate(args) -> int:
    from .session import SessionError
    from .validation import format_validation, validate_session

    try:
        report = validate_session(args.session)
    except SessionError as exc:
        for problem in exc.problems:  # every session-level problem, one line each
            print(f"error: {problem}", file=sys.stderr)
        return 2
    print(format_validation(report))
    nothing = report.n_impacts > 0 and len(report.impacts_with_problems) == report.n_impacts
    return 1 if nothing or (args.strict and report.problems) else 0


def _cmd_synth(args) -> int:
    from .balls import BALLS, BallModelParameters
    from .synth import SensorChain, SynthConfig, write_session

    out = Path(args.out_dir)
    chain_kw = {}
    if args.sample_rate_hz is not None:
        chain_kw["sample_rate_hz"] = args.sample_rate_hz
    if args.gate_to_plate_m is not None:
        chain_kw["gate_to_plate_m"] = args.gate_to_plate_m
    chain = SensorChain(**chain_kw)
    balls = {k: BALLS[k].params for k in (args.balls or list(BALLS))}
    labels = {k: BALLS[k].label for k in balls}
    if args.params:
        import yaml

        doc = yaml.safe_load(Path(args.params).read_text(encoding="utf-8"))
        balls, labels = {}, {}
        for key, p in doc.items():
            balls[key] = BallModelParameters.from_table_units(
                p["mass_g"], p["kb0_kN_m"], p["ak_kN_m"], p["a"], p["ac_kN_s_m3"]
            )
            labels[key] = p.get("label", key)
        # custom balls: a measured ITF rebound only when the YAML gives one (not Table 1's)
        chain_kw_itf = {"itf_rebound_cm": {k: float(p["itf_rebound_cm"]) for k, p in doc.items()
                                           if p.get("itf_rebound_cm") is not None}}
    else:
        chain_kw_itf = {}
    try:
        config = SynthConfig(
            session_id=out.name,
            seed=args.seed,
            balls=balls,
            labels=labels,
            impacts_per_ball=args.impacts_per_ball,
            faults_per_kind=args.faults_per_kind,
            polarity=args.polarity,
            trace_format=args.format,
            kb0_in_config=not args.no_kb0,
            chain=chain,
            **({"vin_range_m_s": tuple(args.vin_range)} if args.vin_range else {}),
            flight_drag=args.drag or args.vertical,
            rig_orientation="vertical" if args.vertical else "horizontal",
            **chain_kw_itf,
        )
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        session_dir, truth = write_session(out, config)
    except (FileExistsError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote synthetic session {session_dir} and its ground truth {truth}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ballimpact",
        description="Force-platform tennis ball impacts and the Goodwill & Haake (2004) ball model.",
    )
    parser.add_argument("--version", action="version", version=f"ballimpact {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_simulate(sub)
    _add_itf(sub)
    val = sub.add_parser("validate", help="check a raw session folder without processing it")
    val.add_argument("session", type=Path, help="session folder, e.g. raw/demo-2004")
    val.add_argument("--strict", action="store_true", help="exit 1 when any impact has a problem (without it, only when no impact can be processed)")
    val.set_defaults(func=_cmd_validate)
    _add_synth(sub)
    return parser


def _add_simulate(sub) -> None:
    """The ``simulate`` subcommand."""
    sim = sub.add_parser(
        "simulate",
        help="simulate impacts with the ball model (parameters in Table 2 units)",
        description="Contact time, COR, peak force and largest displacement per inbound speed.",
    )
    sim.add_argument("--mass-g", type=_mass_g, required=True, help="ball mass [g], e.g. 57.7 (not kg)")
    sim.add_argument("--kb0", type=_positive_float, required=True, help="kB(0) [kN/m], positive")
    sim.add_argument("--ak", type=_positive_float, required=True,
                     help="AK [kN/m^(1+a)] (Table 2: kN/m2), positive")
    sim.add_argument("--a", type=_positive_float, required=True, help="stiffness exponent a [-], positive")
    sim.add_argument("--ac", type=_positive_float, required=True, help="AC [kN s/m^3], positive")
    sim.add_argument("--vin", type=_speed_m_s, action="append", required=True,
                     help="inbound speed [m/s], 1-80; repeat for several")
    sim.add_argument("--json", action="store_true", help="print a JSON list of objects")
    sim.set_defaults(func=_cmd_simulate)


def _add_itf(sub) -> None:
    """The ``itf`` subcommand."""
    itf = sub.add_parser(
        "itf",
        help="predict the ITF 254 cm drop test with the ball model (Table 2 balls or given parameters)",
        description="Predicted rebound of the ITF drop test (254 cm onto a rigid surface), with air drag on "
                    "the fall and the rise, beside Table 1's measured rebound (Goodwill & Haake 2004).",
    )
    from .balls import BALLS as _BALLS
    itf.add_argument("--ball", action="append", choices=sorted(_BALLS),
                     help="Table 2 ball type; repeat for several (default all four)")
    itf.add_argument("--mass-g", type=_positive_float, help="custom ball: mass [g]")
    itf.add_argument("--kb0", type=_nonnegative_float, help="custom ball: kB(0) [kN/m]")
    itf.add_argument("--ak", type=_nonnegative_float, help="custom ball: AK [kN/m^(1+a)]")
    itf.add_argument("--a", type=_positive_float, help="custom ball: stiffness exponent a [-]")
    itf.add_argument("--ac", type=_nonnegative_float, help="custom ball: AC [kN s/m^3]")
    itf.add_argument("--measured-cm", type=_nonnegative_float, help="custom ball: measured rebound [cm]")
    itf.add_argument("--air-density", type=_nonnegative_float, default=1.2, help="air density [kg/m^3] (default 1.2)")
    itf.add_argument("--cd", type=_nonnegative_float, default=0.55, help="drag coefficient [-] (default 0.55)")
    itf.add_argument("--diameter-mm", type=_positive_float, default=65.4, help="ball diameter [mm] (default 65.4)")
    itf.add_argument("--json", action="store_true", help="print a JSON list of objects")
    itf.set_defaults(func=_cmd_itf)


def _add_synth(sub) -> None:
    """The ``synth`` subcommand."""
    syn = sub.add_parser("synth", help="write a synthetic session (seeded) and its ground truth")
    syn.add_argument("out_dir", type=Path, help="session folder to create; its name is the session id")
    syn.add_argument("--seed", type=int, default=0,
                     help="seed of the random numbers; the same seed writes the same files (default 0)")
    syn.add_argument("--balls", nargs="+", choices=sorted(__import__("ballimpact.balls", fromlist=["BALLS"]).BALLS),
                     help="Table 2 ball types to include (default all four)")
    syn.add_argument("--params", type=Path, help="YAML of custom ball types: key: {mass_g, kb0_kN_m, ak_kN_m, a, ac_kN_s_m3[, itf_rebound_cm]}")
    syn.add_argument("--impacts-per-ball", type=int, default=10,
                     help="good impacts per ball type, at speeds between 14 and 30 m/s (default 10)")
    syn.add_argument("--faults-per-kind", type=int, default=2,
                     help="impacts planted with each kind of fault: clipped, missing gate time, "
                          "missing trace file, double impact (default 2)")
    syn.add_argument("--polarity", type=int, choices=(1, -1), default=1,
                     help="plate.polarity: sign of the voltage for a compressive force (default 1)")
    syn.add_argument("--format", choices=("csv", "tdms", "mixed"), default="csv",
                     help="trace file format; mixed: CSV with and without time_s, and TDMS (default csv)")
    syn.add_argument("--sample-rate-hz", type=_positive_float, default=None,
                     help="DAQ sample rate [Hz] (default 66964.3, the paper's rig)")
    syn.add_argument("--no-kb0", action="store_true", help="leave kB(0) out of session.yaml (it is then extrapolated)")
    syn.add_argument("--vin-range", type=_positive_float, nargs=2, metavar=("LO", "HI"),
                     help="inbound speeds of the good impacts [m/s] (default 14 30)")
    syn.add_argument("--drag", action="store_true",
                     help="air drag between the gates and the plate; session.yaml gives gates.distance_to_plate_m")
    syn.add_argument("--vertical", action="store_true", help="vertical rig (ball fired down): drag and gravity")
    syn.add_argument("--gate-to-plate-m", type=_positive_float, default=None,
                     help="distance from gate 2 to the plate [m] (default 0.08; use > 0.0654 with --drag)")
    syn.set_defaults(func=_cmd_synth)


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

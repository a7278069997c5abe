"""Synthetic test sessions: the ball model passed through a realistic force-plate sensor chain.

The generator writes a session folder in the raw format (``docs/raw-format.md``)
and, beside it (never inside), the ground truth of every impact. It is seeded and
deterministic: the same arguments give byte-identical files.

The chain, in the order a real rig applies it:

1. force on the ball from :func:`ballimpact.model.simulate_impact` (time step
   0.01 ms as in the paper) with a small cloth force below 2 mm instead of the
   paper's exact zero;
2. the plate: a lightly damped second-order resonance (unit static gain), which
   rings after the steep rise at the end of the cloth phase;
3. the calibration: voltage = force / kCAL, kCAL drawn per impact around the
   session's nominal value with a spread of a few per cent;
4. the charge amplifier: a first-order high-pass (slow decay, undershoot after
   the contact);
5. polarity, DC offset, 50 Hz mains hum with harmonics, white noise;
6. the ADC: 16-bit quantisation over its range, clipping at the rails;
7. light gates: beam-break times on the timer's own clock, rounded down to the
   timer resolution. By default the ball flies at constant speed between the gates
   and the plate; with ``SynthConfig.flight_drag`` it flies with air drag (and
   gravity on a vertical rig, :mod:`ballimpact.flight`), so the gates see a faster
   inbound and a slower rebound speed than the plate, and session.yaml gives
   ``gates.distance_to_plate_m`` and ``rig``.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy import signal

from .balls import BALLS, BallModelParameters
from .flight import BALL_DIAMETER_M, G_M_S2, drag_constant, flight_time, speed_before
from .model import simulate_impact

__all__ = [
    "FAULT_KINDS",
    "SensorChain",
    "SynthConfig",
    "simulate_voltage",
    "write_session",
]

#: Impact-level faults the generator can plant, each with the substring the
#: processing must give as the exclusion reason.
FAULT_KINDS = {
    "clipped": "clipping",
    "missing_gate": "missing gate time",
    "missing_trace": "trace file not found",
    "double_impact": "more than one impact",
}

_FINE_DT_S = 1.0e-6  # time step of the continuous-time sensor simulation [s]


@dataclass(frozen=True)
class SensorChain:
    """Settings of the simulated force plate, charge amplifier, DAQ and gates.

    Attributes
    ----------
    kcal_N_per_V : float
        Nominal calibration factor [N/V].
    kcal_spread : float
        Relative standard deviation of kCAL between impacts [-].
    plate_frequency_hz : float
        Natural frequency of the plate resonance [Hz].
    plate_damping_ratio : float
        Damping ratio of the plate resonance [-].
    amplifier_time_constant_s : float
        Time constant of the charge amplifier's high-pass decay [s].
    offset_V : float
        Largest DC offset, drawn uniformly in ``[-offset_V, offset_V]`` [V].
    hum_V : float
        Amplitude of the mains hum fundamental [V]; harmonics are smaller.
    mains_hz : float
        Mains frequency [Hz].
    noise_V : float
        White noise standard deviation [V].
    adc_range_V : tuple of float
        ADC input range [V].
    adc_bits : int
        ADC resolution [bit].
    sample_rate_hz : float
        DAQ sample rate [Hz].
    pretrigger_s, trace_duration_s : float
        Quiet stretch before the contact, and the whole trace [s].
    cloth_stiffness_N_m : float
        Cloth stiffness below 2 mm [N/m].
    gate_spacing_m, gate_resolution_s, gate_to_plate_m : float
        Gate spacing [m], timer resolution [s], distance from the near gate to the plate [m].
    """

    kcal_N_per_V: float = 180.0
    kcal_spread: float = 0.03
    plate_frequency_hz: float = 25_000.0
    plate_damping_ratio: float = 0.3
    amplifier_time_constant_s: float = 0.8
    offset_V: float = 0.05
    hum_V: float = 0.012
    mains_hz: float = 50.0
    noise_V: float = 0.0015
    adc_range_V: tuple[float, float] = (-10.0, 10.0)
    adc_bits: int = 16
    sample_rate_hz: float = 66_964.3
    pretrigger_s: float = 0.025
    trace_duration_s: float = 0.070
    cloth_stiffness_N_m: float = 5_000.0
    gate_spacing_m: float = 0.100
    gate_resolution_s: float = 1.0e-6
    gate_to_plate_m: float = 0.080


@dataclass
class SynthConfig:
    """What to put in a synthetic session.

    Attributes
    ----------
    session_id : str
        Session id (the folder name).
    seed : int
        Seed of the random generator.
    balls : dict
        Ball key -> BallModelParameters (SI) used as truth.
    labels : dict
        Ball key -> label for session.yaml.
    impacts_per_ball : int
        Good impacts per ball type.
    vin_range_m_s : tuple of float
        Inbound speeds, evenly spread with jitter [m/s].
    faults_per_kind : int
        Faulty impacts of each kind of :data:`FAULT_KINDS`.
    polarity : int
        Plate polarity, +1 or -1.
    trace_format : str
        "csv", "tdms" or "mixed" (every fourth trace TDMS, every third CSV with a time_s column).
    total_impacts : int, optional
        When given, the number of good impacts is chosen so that the session holds
        exactly this many impacts (faults included), spread evenly over the balls.
    ball_variability : float
        Relative standard deviation of AK and AC between individual balls of one
        type [-]: real balls of one type differ a little (felt, rubber, pressure),
        which gives the scatter of measured TC and COR about the type's curve.
        The type's parameters (truth) are the medians.
    kb0_in_config : bool
        Write each ball's kB(0) into session.yaml (kb0_source = config).
    chain : SensorChain
        Sensor chain settings.
    date : str
        ISO date for session.yaml.
    itf_rebound_cm : dict
        Ball key -> measured ITF drop-test rebound [cm] written to session.yaml
        (default: Table 1 of the paper for its four ball keys).
    flight_drag : bool
        Gate times from a flight with air drag (and gravity when vertical) between
        the gates and the plate, at ``chain.gate_to_plate_m`` from gate 2; session.yaml
        then gives ``gates.distance_to_plate_m`` and ``rig``. The truth's speeds are
        the speeds at the plate.
    rig_orientation : str
        "horizontal" or "vertical" (ball fired down onto the plate), with ``flight_drag``.
    air_density_kg_m3 : float
        Air density of the flight [kg/m^3], with ``flight_drag``.
    """

    session_id: str = "synthetic"
    seed: int = 0
    balls: dict[str, BallModelParameters] = field(
        default_factory=lambda: {k: b.params for k, b in BALLS.items()}
    )
    labels: dict[str, str] = field(default_factory=lambda: {k: b.label for k, b in BALLS.items()})
    impacts_per_ball: int = 10
    vin_range_m_s: tuple[float, float] = (14.0, 30.0)
    faults_per_kind: int = 2
    polarity: int = 1
    trace_format: str = "csv"
    total_impacts: int | None = None
    ball_variability: float = 0.03
    kb0_in_config: bool = True
    chain: SensorChain = field(default_factory=SensorChain)
    date: str = "2026-11-21"
    itf_rebound_cm: dict[str, float] = field(
        default_factory=lambda: {k: b.itf_rebound_cm for k, b in BALLS.items()}
    )
    flight_drag: bool = False
    rig_orientation: str = "horizontal"
    air_density_kg_m3: float = 1.2

    def __post_init__(self):
        if self.polarity not in (1, -1):
            raise ValueError(f"polarity must be 1 or -1, got {self.polarity!r}")
        if self.trace_format not in ("csv", "tdms", "mixed"):
            raise ValueError(f"trace_format must be 'csv', 'tdms' or 'mixed', got {self.trace_format!r}")
        if self.impacts_per_ball < 1:
            raise ValueError(f"impacts_per_ball must be at least 1, got {self.impacts_per_ball}")
        if not 0 <= self.ball_variability < 0.5:
            raise ValueError(f"ball_variability must be in [0, 0.5), got {self.ball_variability}")
        if self.faults_per_kind < 0:
            raise ValueError(f"faults_per_kind must be non-negative, got {self.faults_per_kind}")
        lo, hi = self.vin_range_m_s
        if not 0 < lo <= hi:
            raise ValueError(f"vin_range_m_s must satisfy 0 < lo <= hi, got {self.vin_range_m_s}")
        if not self.balls:
            raise ValueError("balls must name at least one ball type")
        if self.rig_orientation not in ("horizontal", "vertical"):
            raise ValueError(f"rig_orientation must be 'horizontal' or 'vertical', got {self.rig_orientation!r}")
        if self.flight_drag and not self.chain.gate_to_plate_m > BALL_DIAMETER_M:
            raise ValueError(
                f"flight_drag needs chain.gate_to_plate_m > the ball diameter {BALL_DIAMETER_M:g} m, "
                f"got {self.chain.gate_to_plate_m!r}"
            )
        if not 0 < self.air_density_kg_m3 < 2:
            raise ValueError(f"air_density_kg_m3 must be in (0, 2), got {self.air_density_kg_m3!r}")


def _plate_and_amplifier(force_N, chain: SensorChain, dt_s: float):
    """Force through the plate resonance and the charge amplifier's high-pass [N-equivalent]."""
    wn = 2 * np.pi * chain.plate_frequency_hz
    z = chain.plate_damping_ratio
    plate = signal.cont2discrete(([wn**2], [1.0, 2 * z * wn, wn**2]), dt_s, method="bilinear")
    tau = chain.amplifier_time_constant_s
    hp = signal.cont2discrete(([1.0, 0.0], [1.0, 1.0 / tau]), dt_s, method="bilinear")
    out = signal.lfilter(np.ravel(plate[0]), plate[1], force_N)
    return signal.lfilter(np.ravel(hp[0]), hp[1], out)


def simulate_voltage(time_s, force_time_s, force_N, kcal_N_per_V, chain: SensorChain, polarity, rng):
    """Voltage a DAQ records for a force history, through the sensor chain.

    Parameters
    ----------
    time_s : numpy.ndarray
        DAQ sample times [s].
    force_time_s, force_N : numpy.ndarray
        Force on the plate [N] at times [s] (zero outside them).
    kcal_N_per_V : float
        True calibration factor of this impact [N/V].
    chain : SensorChain
        Sensor settings.
    polarity : int
        +1 or -1.
    rng : numpy.random.Generator
        Random source for offset, hum phase and noise.

    Returns
    -------
    numpy.ndarray
        Recorded voltage [V], quantised and clipped.
    """
    fine_t = np.arange(time_s[0], time_s[-1] + _FINE_DT_S, _FINE_DT_S)
    fine_f = np.interp(fine_t, force_time_s, force_N, left=0.0, right=0.0)
    volts = _plate_and_amplifier(fine_f, chain, _FINE_DT_S) / kcal_N_per_V
    v = polarity * np.interp(time_s, fine_t, volts)
    v += rng.uniform(-chain.offset_V, chain.offset_V)
    phase = rng.uniform(0, 2 * np.pi, size=3)
    for harmonic, rel in ((1, 1.0), (2, 0.15), (3, 0.35)):
        v += rel * chain.hum_V * np.sin(2 * np.pi * harmonic * chain.mains_hz * time_s + phase[harmonic - 1])
    v += rng.normal(0.0, chain.noise_V, size=v.size)
    lo, hi = chain.adc_range_V
    lsb = (hi - lo) / 2**chain.adc_bits
    codes = np.clip(np.round((v - lo) / lsb), 0, 2**chain.adc_bits - 1)
    return lo + codes * lsb


def _impact_force(vin, params: BallModelParameters, chain: SensorChain):
    sim = simulate_impact(
        vin, params.mass_kg, params.kb0_N_m, params.ak, params.a, params.ac,
        cloth_stiffness_N_m=chain.cloth_stiffness_N_m, record=True,
    )
    tc = float(sim.contact_time_s)
    t = sim.time_s
    f = np.asarray(sim.force_N, dtype=float)
    inside = t < tc
    # force samples up to the end of contact, then exactly zero at the interpolated end
    ft = np.concatenate([t[inside], [tc]])
    ff = np.concatenate([np.maximum(f[inside], 0.0), [0.0]])
    return sim, ft, ff


def _write_csv_trace(path: Path, time_s, voltage, rate, with_time: bool, metadata: dict):
    lines = [f"# sample_rate_hz: {rate}", "# units: V"]
    lines += [f"# {k}: {v}" for k, v in metadata.items()]
    if with_time:
        lines.append("time_s,voltage_V")
        body = "\n".join(f"{t:.8f},{x:.6f}" for t, x in zip(time_s, voltage))
    else:
        lines.append("voltage_V")
        body = "\n".join(f"{x:.6f}" for x in voltage)
    path.write_text("\n".join(lines) + "\n" + body + "\n", encoding="utf-8")


def _write_tdms_trace(path: Path, voltage, rate, metadata: dict):
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    props = {"wf_increment": 1.0 / rate, "wf_start_offset": 0.0, "unit_string": "V"}
    props.update({k: str(v) for k, v in metadata.items()})
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([
            RootObject({"title": "ballimpact synthetic trace"}),
            GroupObject("DAQ"),
            ChannelObject("DAQ", "charge_amplifier", np.asarray(voltage, dtype=np.float64), properties=props),
        ])


def write_session(out_dir, config: SynthConfig | None = None) -> tuple[Path, Path]:
    """Write a synthetic session folder and its ground truth beside it.

    Parameters
    ----------
    out_dir : path-like
        Session folder to create (its name becomes ``session_id`` unless the config
        sets one that differs, which is an error). Must not exist or be empty.
    config : SynthConfig, optional
        What to generate; defaults to the paper's four balls.

    Returns
    -------
    session_dir : pathlib.Path
        The session folder.
    truth_path : pathlib.Path
        ``<session_dir>.truth.csv`` (and ``<session_dir>.truth.yaml`` with the
        parameters and sensor chain), beside the folder.
    """
    out = Path(out_dir)
    if config is None:
        config = SynthConfig(session_id=out.name)
    if config.session_id != out.name:
        raise ValueError(f"session_id {config.session_id!r} must equal the folder name {out.name!r}")
    if out.exists() and any(out.iterdir()):
        raise FileExistsError(f"{out}: folder exists and is not empty; choose a new folder")
    (out / "traces").mkdir(parents=True, exist_ok=True)
    chain = config.chain
    rng = np.random.default_rng(config.seed)
    plan = _plan_impacts(config, rng)
    rows, truth = [], []
    timer = float(rng.uniform(1.0, 5.0))  # timer clock at the first impact [s]
    n_time = int(round(chain.trace_duration_s * chain.sample_rate_hz))
    for i, (key, vin, fault) in enumerate(plan):
        params = config.balls[key]
        if config.ball_variability > 0:
            jitter = np.exp(config.ball_variability * rng.standard_normal(2))
            params = params.with_(ak=params.ak * jitter[0], ac=params.ac * jitter[1])
        impact_id = f"{key}-{i + 1:03d}"
        sim, kcal, t_start, time_s, volts = _impact_trace(vin, params, fault, config, rng, n_time)
        tc, vout = float(sim.contact_time_s), float(sim.rebound_speed_m_s)
        gate_txt = _gate_cells(timer, tc, vin, vout, params.mass_kg, config)
        timer += float(rng.uniform(20.0, 60.0))
        if fault == "missing_gate":
            gate_txt[int(rng.integers(0, 4))] = ""
        trace_rel = _write_trace(out, impact_id, i, fault, time_s, volts, config)
        rows.append([impact_id, key, trace_rel, *gate_txt, "", f"synthetic {fault}" if fault else ""])
        truth.append({
            "impact_id": impact_id,
            "ball": key,
            "fault": fault,
            "expected_reason": FAULT_KINDS.get(fault, ""),
            "vin_m_s": vin,
            "vout_m_s": vout,
            "cor": vout / vin,
            "contact_time_ms": tc * 1e3,
            "kcal_N_per_V": kcal,
            # the model's own peak (at high speed the spike before buckling, 0.2 ms)
            "peak_force_N": float(sim.peak_force_N),
            "time_to_peak_ms": float(sim.time_to_peak_s) * 1e3,
            "max_displacement_mm": float(sim.max_displacement_m) * 1e3,
            "impulse_N_s": params.mass_kg * (vin + vout),
            "contact_start_s": t_start,
        })
    _write_impacts_csv(out / "impacts.csv", rows)
    _write_session_yaml(out / "session.yaml", config)
    truth_csv = out.parent / f"{out.name}.truth.csv"
    _write_truth(truth_csv, truth, config)
    return out, truth_csv


def _plan_impacts(config: SynthConfig, rng) -> list[tuple[str, float, str]]:
    """(ball key, inbound speed [m/s], fault or "") of every impact, in the session's order:
    good ones per ball, then the faults spread over the balls, shuffled."""
    plan = []
    ball_keys = list(config.balls)
    lo, hi = config.vin_range_m_s
    n_faults = config.faults_per_kind * len(FAULT_KINDS)
    if config.total_impacts is not None:
        n_good = config.total_impacts - n_faults
        if n_good < len(ball_keys):
            raise ValueError(
                f"total_impacts={config.total_impacts} leaves fewer good impacts than ball types"
            )
        per_ball = [n_good // len(ball_keys) + (i < n_good % len(ball_keys)) for i in range(len(ball_keys))]
    else:
        per_ball = [config.impacts_per_ball] * len(ball_keys)
    for key, n_ball in zip(ball_keys, per_ball):
        speeds = np.linspace(lo, hi, n_ball)
        jitter = (hi - lo) / max(n_ball, 2) * 0.3
        speeds = np.clip(speeds + rng.uniform(-jitter, jitter, speeds.size), lo, hi)
        plan += [(key, float(v), "") for v in speeds]
    k = 0
    for fault in FAULT_KINDS:
        for _ in range(config.faults_per_kind):
            plan.append((ball_keys[k % len(ball_keys)], float(rng.uniform(lo, hi)), fault))
            k += 1
    order = rng.permutation(len(plan))
    return [plan[i] for i in order]


def _impact_trace(vin, params, fault, config: SynthConfig, rng, n_time):
    """One impact's simulation and voltage trace: (model result, kCAL [N/V], contact start
    [s], sample times [s], voltage [V]); a clipped or double impact when ``fault`` says so."""
    chain = config.chain
    rate = chain.sample_rate_hz
    sim, ft, ff = _impact_force(vin, params, chain)
    tc = float(sim.contact_time_s)
    kcal = chain.kcal_N_per_V * (1.0 + chain.kcal_spread * rng.standard_normal())
    if fault == "clipped":
        # amplifier gain set too high: the peak reaches 1.4 times the upper rail
        kcal = float(sim.peak_force_N) / (1.4 * chain.adc_range_V[1])
    t_start = chain.pretrigger_s + rng.uniform(0, 1.0 / rate)  # contact start, sub-sample
    time_s = np.arange(n_time) / rate
    force_t = ft + t_start
    force_f = ff
    if fault == "double_impact":
        gap = rng.uniform(0.008, 0.015)
        dur = 2.5e-3
        tt = np.linspace(0, dur, 200)
        second = 0.25 * float(sim.peak_force_N) * np.sin(np.pi * tt / dur)
        force_t = np.concatenate([force_t, t_start + tc + gap + tt])
        force_f = np.concatenate([force_f, second])
    volts = simulate_voltage(time_s, force_t, force_f, kcal, chain, config.polarity, rng)
    return sim, kcal, t_start, time_s, volts


def _gate_cells(t_contact, tc, vin, vout, mass_kg, config: SynthConfig) -> list[str]:
    """The four gate times [s] of an impact whose contact starts at ``t_contact`` on the
    timer clock, rounded down to the timer resolution, as impacts.csv cells."""
    chain = config.chain
    if config.flight_drag:
        g_in_1, g_in_2, g_out_2, g_out_1 = _gate_times_with_drag(t_contact, tc, vin, vout, mass_kg, config)
    else:
        g_in_2 = t_contact - chain.gate_to_plate_m / vin
        g_in_1 = g_in_2 - chain.gate_spacing_m / vin
        g_out_2 = t_contact + tc + chain.gate_to_plate_m / vout
        g_out_1 = g_out_2 + chain.gate_spacing_m / vout
    res = chain.gate_resolution_s
    gates = [np.floor(g / res) * res for g in (g_in_1, g_in_2, g_out_2, g_out_1)]
    return [f"{g:.7f}" for g in gates]


def _write_trace(out: Path, impact_id: str, i: int, fault: str, time_s, volts, config: SynthConfig) -> str:
    """Write impact ``i``'s trace (CSV or TDMS as ``config.trace_format`` says; none for a
    missing trace) and return its path relative to the session folder."""
    fmt = config.trace_format
    use_tdms = fmt == "tdms" or (fmt == "mixed" and i % 4 == 3)
    trace_rel = f"traces/{impact_id}.{'tdms' if use_tdms else 'csv'}"
    meta = {"channel": "charge amplifier output", "impact_id": impact_id}
    if fault != "missing_trace":
        if use_tdms:
            _write_tdms_trace(out / trace_rel, volts, config.chain.sample_rate_hz, meta)
        else:
            with_time = fmt == "mixed" and i % 3 == 2
            _write_csv_trace(out / trace_rel, time_s, volts, config.chain.sample_rate_hz, with_time, meta)
    return trace_rel


def _gate_times_with_drag(t_contact, tc, vin, vout, mass_kg, config: SynthConfig):
    """Beam-break times of a flight with drag (and gravity on a vertical rig), leading surface at the beam.

    Inbound, the leading surface reaches the plate at ``t_contact`` after d from gate 2
    and d + L from gate 1; rebound, it leaves at D from the plate and meets gate 2 after
    d - D, gate 1 after d - D + L (:func:`ballimpact.flight.plate_speeds` inverts this).
    """
    chain = config.chain
    d, L, D = chain.gate_to_plate_m, chain.gate_spacing_m, BALL_DIAMETER_M
    k = drag_constant(mass_kg, D, config.air_density_kg_m3)
    g = G_M_S2 if config.rig_orientation == "vertical" else 0.0
    v_gate2 = speed_before(vin, d, k, +g)
    v_gate1 = speed_before(vin, d + L, k, +g)
    g_in_2 = t_contact - flight_time(v_gate2, d, k, +g)
    g_in_1 = t_contact - flight_time(v_gate1, d + L, k, +g)
    g_out_2 = t_contact + tc + flight_time(vout, d - D, k, -g)
    g_out_1 = t_contact + tc + flight_time(vout, d - D + L, k, -g)
    return g_in_1, g_in_2, g_out_2, g_out_1


def _write_impacts_csv(path: Path, rows):
    import csv

    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["impact_id", "ball", "trace", "gate_in_1_s", "gate_in_2_s", "gate_out_2_s",
                    "gate_out_1_s", "mass_g", "note"])
        w.writerows(rows)


def _write_session_yaml(path: Path, config: SynthConfig):
    chain = config.chain
    balls = {}
    for key, p in config.balls.items():
        entry = {"label": config.labels.get(key, key), "mass_g": round(p.mass_kg * 1000, 4)}
        if config.kb0_in_config:
            entry["kb0_kN_m"] = round(p.kb0_N_m / 1000, 6)
        if key in config.itf_rebound_cm:
            entry["itf_rebound_cm"] = float(config.itf_rebound_cm[key])
        balls[key] = entry
    doc = {
        "session_id": config.session_id,
        "date": config.date,
        "operator": "ballimpact synth (no operator: synthetic data)",
        "description": (
            "SYNTHETIC DATA, not a laboratory measurement. Made by `ballimpact synth` "
            f"(seed {config.seed}): impacts simulated with the Goodwill & Haake (2004) "
            "viscoelastic model and passed through a simulated sensor chain (plate "
            "resonance, per-impact kCAL spread, charge-amplifier high-pass decay, DC "
            "offset, mains hum, white noise, 16-bit ADC with clipping, gate timer "
            "rounding). Faulty impacts are planted on purpose; see their note."
        ),
        "synthetic": True,
        "plate": {"polarity": config.polarity},
        "daq": {
            "sample_rate_hz": chain.sample_rate_hz,
            "adc_range_v": [float(chain.adc_range_V[0]), float(chain.adc_range_V[1])],
            "mains_hz": chain.mains_hz,
        },
        "gates": {"spacing_m": chain.gate_spacing_m, "resolution_s": chain.gate_resolution_s},
        "balls": balls,
    }
    if config.flight_drag:
        doc["gates"]["distance_to_plate_m"] = chain.gate_to_plate_m
        doc["rig"] = {"orientation": config.rig_orientation, "air_density_kg_m3": config.air_density_kg_m3}
        doc = {k: doc[k] for k in ("session_id", "date", "operator", "description", "synthetic", "plate", "daq",
                                   "gates", "rig", "balls")}
    path.write_text(
        "# Synthetic session written by `ballimpact synth`. Not real measurements.\n"
        + yaml.safe_dump(doc, sort_keys=False, width=88),
        encoding="utf-8",
    )


def _write_truth(path: Path, truth, config: SynthConfig):
    import csv

    cols = list(truth[0])
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, lineterminator="\n")
        w.writeheader()
        for row in truth:
            w.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in row.items()})
    meta = {
        "session_id": config.session_id,
        "seed": config.seed,
        "balls": {k: asdict(p) for k, p in config.balls.items()},
        "sensor_chain": json.loads(json.dumps(asdict(config.chain))),
        **({"flight": {"drag": True, "orientation": config.rig_orientation,
                       "air_density_kg_m3": config.air_density_kg_m3, "diameter_m": BALL_DIAMETER_M,
                       "note": "vin_m_s, vout_m_s and cor of the truth are at the plate"}}
           if config.flight_drag else {}),
        "note": "Ground truth of a synthetic session written by ballimpact synth; SI units.",
    }
    path.with_suffix(".yaml").write_text(yaml.safe_dump(meta, sort_keys=False), encoding="utf-8")

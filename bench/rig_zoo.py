"""The session zoo of bench/rigs.py (issue 46): one rig drawn from the ranges of raw-format v1.2, its session and truth.

A rig is one plate, one charge amplifier, one mains supply and one DAQ; every impact of its session is measured
through it. :func:`draw_rig` draws it from the seed pair (run seed, rig index); :func:`write_session` writes its
session folder (session.yaml, impacts.csv, TDMS traces) and, beside it, ``<session_id>.truth.csv`` (per impact:
the true TC, kCAL, peak, speeds, COR, and its fault) and ``<session_id>.truth.yaml`` (the rig and its ball types).

The physics, in the order the rig applies it
--------------------------------------------
1. The force on the ball: the Goodwill & Haake model (:func:`ballimpact.model.simulate_impact`) at the ball
   type's random parameters, with a small cloth stiffness below 2 mm of compression (4-6 kN/m, a foot of
   0.4-2 % of the peak, as ``ballimpact.synth``), so that the force acts from first contact and the model's
   TC is the force's (docs/model.md, "Contact time"). Linear between the model's 0.01 ms steps.
2. The plate: a physical second-order system of unit static gain, 1-30 kHz (log-uniform), damping ratio
   0.02-0.15, or an ideal plate (one rig in five).
3. The DAQ's anti-aliasing filter (two rigs in five): linear phase, flat to 0.30-0.45 fs, 100 dB down from
   0.55 fs (``tests/zoo.py``'s ``_antialias``).
4. The charge amplifier: an exact first-order high-pass, time constant 0.3-100 s (log-uniform); voltage =
   polarity x force / kCAL (kCAL of the session, spread 0-0.5 % per impact), a DC offset, a slow drift.
5. Mains hum at 50 or 60 Hz (off by up to 0.05 Hz) with harmonics 2-5, 0-10 mV; white noise 0.5-3 mV;
   single-sample spikes on one rig in five.
6. A 16-bit ADC over +-10 V or +-5 V at 25-200 kHz (log-uniform).
Steps 2-4 are integrated on a fine grid (about 1 us) that holds every sample instant; outside the stretch where
the force and the plate's ringing live, the amplifier's tail decays exactly.

Stated or not, each at random (half the rigs): ``plate.resonance_hz`` with ``plate.damping_ratio`` (resonant plates
only), ``plate.time_constant_s``, ``daq.mains_hz``, ``daq.bandwidth_hz`` (the filter's cut-off, else the plate's
resonance; an ideal plate without a filter has none to state). ``kb0_kN_m`` of every ball type is stated (the
bench is about rigs, not about extrapolating kB(0)).

A session: 2-4 ball types (a Table 2 ball type's parameters scaled at random: mass 0.97-1.03, kB(0) 0.8-1.2,
AK 0.7-1.4, a 0.95-1.05, AC 0.8-1.25), 20-40 impacts at 10-35 m/s, 2-4 of them faulty: a second contact of
7-100 % of the peak 1-30 ms after the first, a contact truncated by the trace's start or end, a peak clipped at
the ADC's rail (an amplifier offset that was not reset), or impossible gate times (an interval swapped, the
rebound logged before the arrival, a missed event).
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import yaml
from scipy import signal

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "tests") not in sys.path:
    sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402  (tests/zoo.py: the plate, amplifier and anti-aliasing filters)
from ballimpact.balls import BALLS  # noqa: E402
from ballimpact.model import BUCKLING_TIME_S, TIME_STEP_S, simulate_impact  # noqa: E402

FAULT_KINDS = ("second contact", "truncated", "clipped", "gate times")
GATE_FAULTS = ("inbound interval swapped", "rebound interval swapped", "rebound before arrival", "missed event")
GATE_SPACING_M = 0.100  # [m]
ADC_BITS = 16
FINE_RATE_HZ = 1.0e6  # [Hz] the chain is integrated at least this finely
CLOTH_STIFFNESS_N_M = (4.0e3, 6.0e3)  # [N/m] below 2 mm of compression
SPEED_RANGE_M_S = (10.0, 35.0)
AA_PAD_S = 3.0e-3  # [s] fine-grid margin past the trace's end (longer than half the anti-aliasing filter)
RING_DECAY = 18.0  # the plate's ringing is followed for this many of its decay time constants [-]


@dataclass(frozen=True)
class BallTruth:
    """One ball type of a rig's session: its true model parameters (SI)."""

    key: str
    base: str  # the Table 2 ball type it was drawn around
    mass_kg: float
    kb0_N_m: float
    ak: float
    a: float
    ac: float
    cloth_N_m: float

    def simulate(self, vin_m_s, record: bool = False):
        """The model impact(s) at ``vin_m_s`` [m/s], with this ball's cloth force."""
        return simulate_impact(vin_m_s, self.mass_kg, self.kb0_N_m, self.ak, self.a, self.ac,
                               cloth_stiffness_N_m=self.cloth_N_m, record=record)


@dataclass(frozen=True)
class Rig:
    """Every drawn factor of one rig and its session (SI units)."""

    seed: int
    index: int
    sample_rate_hz: float
    plate_hz: float | None  # None = ideal plate
    plate_zeta: float
    antialias_hz: float | None  # None = no anti-aliasing filter
    tau_s: float
    mains_hz: float
    mains_dev_hz: float
    hum_V: float
    harmonics: tuple  # (k, relative amplitude) of harmonics 2-5
    noise_V: float
    rail_V: float
    kcal_N_per_V: float
    kcal_spread: float
    polarity: int
    offset_V: float
    drift_V_s: float
    spikes: bool
    pre_s: float
    post_s: float
    gate_resolution_s: float
    gate_to_plate_m: float
    stated: tuple  # of "resonance", "time_constant", "mains", "bandwidth"
    balls: tuple = field(default_factory=tuple)  # BallTruth
    n_impacts: int = 30
    faults: tuple = ()  # (impact position, kind)

    @property
    def session_id(self) -> str:
        return f"rig-{self.seed}-{self.index:03d}"

    @property
    def bandwidth_hz(self) -> float | None:
        """The highest frequency reaching the ADC [Hz]: the filter's cut-off, else the plate's resonance."""
        return self.antialias_hz if self.antialias_hz is not None else self.plate_hz

    @property
    def aliasing_ruled_out(self) -> bool:
        """Sampled at 60 kHz or more, or ``daq.bandwidth_hz`` stated at half the sample rate or below (a bandwidth
        stated above it says the plate aliases: it does not rule aliasing out)."""
        return self.sample_rate_hz >= 60e3 or ("bandwidth" in self.stated and self.bandwidth_hz is not None
                                               and self.bandwidth_hz <= 0.5 * self.sample_rate_hz)

    @property
    def clear_class(self) -> bool:
        """Issue 46's first class: aliasing ruled out, and the plate ideal or at 2 kHz or above."""
        return self.aliasing_ruled_out and (self.plate_hz is None or self.plate_hz >= 2e3)

    def describe(self) -> str:
        """One line: the rig's factors, with the keys its session states."""
        plate = ("ideal plate" if self.plate_hz is None
                 else f"plate {self.plate_hz / 1e3:.2f} kHz z {self.plate_zeta:.3f}")
        aa = f"AA {self.antialias_hz / 1e3:.1f} kHz" if self.antialias_hz is not None else "no AA"
        keys = ",".join(self.stated) or "none"
        return (f"fs {self.sample_rate_hz / 1e3:.1f} kHz, {plate}, {aa}, tau {self.tau_s:.3g} s, "
                f"hum {1e3 * self.hum_V:.1f} mV@{self.mains_hz:.0f} Hz, noise {1e3 * self.noise_V:.2f} mV, "
                f"rail {self.rail_V:.0f} V, post {1e3 * self.post_s:.0f} ms; stated: {keys}")


def _loguniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _draw_ball(rng, key: str, base: str) -> BallTruth:
    p = BALLS[base].params
    return BallTruth(key=key, base=base, mass_kg=p.mass_kg * float(rng.uniform(0.97, 1.03)),
                     kb0_N_m=p.kb0_N_m * float(rng.uniform(0.8, 1.2)), ak=p.ak * _loguniform(rng, 0.7, 1.4),
                     a=p.a * float(rng.uniform(0.95, 1.05)), ac=p.ac * float(rng.uniform(0.8, 1.25)),
                     cloth_N_m=float(rng.uniform(*CLOTH_STIFFNESS_N_M)))


def _draw_chain(rng) -> dict:
    """The plate, filter, amplifier, mains, noise and DAQ of a rig (Rig fields)."""
    fs = _loguniform(rng, 25e3, 200e3)
    plate = None if rng.uniform() < 0.2 else _loguniform(rng, 1e3, 30e3)
    zeta = float(rng.uniform(0.02, 0.15))
    aa = float(rng.uniform(0.30, 0.45)) * fs if rng.uniform() < 0.4 else None
    hum = 0.0 if rng.uniform() < 0.1 else _loguniform(rng, 0.3e-3, 10e-3)
    harmonics = tuple((k, float(rng.uniform(0.0, 0.6))) for k in (2, 3, 4, 5))
    stated = [name for name in ("resonance", "time_constant", "mains", "bandwidth") if rng.uniform() < 0.5]
    if plate is None:
        stated = [s for s in stated if s != "resonance"]
    if plate is None and aa is None:
        stated = [s for s in stated if s != "bandwidth"]
    return dict(sample_rate_hz=fs, plate_hz=plate, plate_zeta=zeta, antialias_hz=aa,
                tau_s=_loguniform(rng, 0.3, 100.0), mains_hz=float(rng.choice([50.0, 60.0])),
                mains_dev_hz=float(rng.uniform(-0.05, 0.05)), hum_V=hum, harmonics=harmonics,
                noise_V=_loguniform(rng, 0.5e-3, 3e-3), rail_V=10.0 if rng.uniform() < 0.7 else 5.0,
                polarity=int(rng.choice([-1, 1])), offset_V=float(rng.uniform(-0.3, 0.3)),
                drift_V_s=float(rng.uniform(0.0, 0.05)), spikes=bool(rng.uniform() < 0.2),
                pre_s=_loguniform(rng, 2e-3, 100e-3), post_s=_loguniform(rng, 12e-3, 1.0),
                gate_resolution_s=float(rng.choice([1e-6, 1e-7])), gate_to_plate_m=float(rng.uniform(0.05, 0.3)),
                stated=tuple(stated))


def draw_rig(seed: int, index: int, n_impacts: tuple = (20, 40)) -> Rig:
    """Rig ``index`` of the run ``seed``: its chain, 2-4 ball types, ``n_impacts`` (inclusive range) and faults."""
    rng = np.random.default_rng([seed, index, 46])
    chain = _draw_chain(rng)
    n_balls = int(rng.integers(2, 5))
    bases = [str(b) for b in rng.choice(sorted(BALLS), size=n_balls, replace=False)]
    balls = tuple(_draw_ball(rng, f"ball{k + 1}", base) for k, base in enumerate(bases))
    n = int(rng.integers(n_impacts[0], n_impacts[1] + 1))
    where = rng.choice(n, size=int(rng.integers(2, 5)), replace=False)
    faults = tuple(sorted((int(i), str(rng.choice(FAULT_KINDS))) for i in where))
    # kCAL: the strongest ball type's peak at the top speed reaches 35-85 % of the rail
    top = max(float(b.simulate(SPEED_RANGE_M_S[1]).peak_force_N) for b in balls)
    kcal = top / (float(rng.uniform(0.35, 0.85)) * chain["rail_V"])
    return Rig(seed=seed, index=index, kcal_N_per_V=kcal, kcal_spread=float(rng.uniform(0.0, 0.005)),
               balls=balls, n_impacts=n, faults=faults, **chain)


# ------------------------------------------------------------------ one impact


@dataclass
class ImpactTruth:
    """What a perfect processing reports for one impact (SI), and its fault ("" = clean)."""

    impact_id: str
    ball: str
    fault: str
    vin_m_s: float
    vout_m_s: float
    contact_time_s: float
    kcal_N_per_V: float
    peak_N: float
    peak_is_spike: bool
    time_to_peak_s: float

    @property
    def cor(self) -> float:
        return self.vout_m_s / self.vin_m_s

    def row(self) -> dict:
        return {"impact_id": self.impact_id, "ball": self.ball, "fault": self.fault, "vin_m_s": self.vin_m_s,
                "vout_m_s": self.vout_m_s, "cor": self.cor, "contact_time_ms": 1e3 * self.contact_time_s,
                "kcal_N_per_V": self.kcal_N_per_V, "peak_force_N": self.peak_N,
                "peak_is_spike": self.peak_is_spike, "time_to_peak_ms": 1e3 * self.time_to_peak_s}


def force_knots(ball: BallTruth, vin_m_s: float):
    """The model's force from first contact (t = 0) to its end: knot times [s], forces [N], the simulation."""
    sim = ball.simulate(vin_m_s, record=True)
    tc = float(sim.contact_time_s)
    if not math.isfinite(tc):
        raise ValueError(f"model impact did not end ({ball}, vin {vin_m_s})")
    inside = sim.time_s < tc
    t = np.concatenate([sim.time_s[inside], [tc]])
    f = np.concatenate([np.maximum(np.asarray(sim.force_N, dtype=float)[inside], 0.0), [0.0]])
    f[0] = 0.0
    return t, f, sim


def _second_contact(rig: Rig, ball: BallTruth, tc: float, peak: float, rng):
    """Knots of a second contact (7-100 % of the peak, 1-30 ms after the end) that fits in the trace, or None."""
    k_t, k_f, sim2 = force_knots(ball, float(rng.uniform(3.0, 10.0)))
    room = rig.post_s - tc - float(sim2.time_to_peak_s) - 0.5e-3
    if room < 1.0e-3:
        return None
    gap = float(rng.uniform(1.0e-3, min(30e-3, room)))
    return k_t + tc + gap, k_f * (float(rng.uniform(0.07, 1.0)) * peak / float(sim2.peak_force_N))


def _sensed(rig: Rig, t_fine: np.ndarray, knots: list, h: float) -> np.ndarray:
    """Force on the fine grid through the plate and the anti-aliasing filter [N] (before the amplifier)."""
    force = np.zeros(t_fine.size)
    for kt, kf in knots:
        a_ = max(0, int(np.searchsorted(t_fine, kt[0])) - 1)
        b_ = min(t_fine.size, int(np.searchsorted(t_fine, kt[-1])) + 1)
        force[a_:b_] += np.interp(t_fine[a_:b_], kt, kf, left=0.0, right=0.0)
    if rig.plate_hz is not None:
        b, a = zoo._plate_filter(rig.plate_hz, rig.plate_zeta, h)
        force = signal.lfilter(b, a, force)
    if rig.antialias_hz is not None:
        force = zoo._antialias(force, rig.antialias_hz, rig.sample_rate_hz, h)
    return force


def _amplifier_samples(rig: Rig, t0: float, n: int, knots: list, end_s: float) -> np.ndarray:
    """The amplifier's output [N equivalent] at the n samples t0 + i / fs: the sensed force, high-passed.

    The fine grid spans the force and the plate's ringing (RING_DECAY decay times); before it the output is
    zero, after it the high-pass's state decays exactly with the amplifier's time constant.
    """
    fs = rig.sample_rate_hz
    m = max(1, int(math.ceil(FINE_RATE_HZ / fs)))
    h = 1.0 / (m * fs)
    ring = 0.0 if rig.plate_hz is None else RING_DECAY / (rig.plate_zeta * 2 * math.pi * rig.plate_hz)
    i_a = int(math.floor((-1.0e-3 - t0) * fs))  # sample index 1 ms before the force (< 0: before the trace)
    i_b = int(math.ceil((end_s + ring + AA_PAD_S - t0) * fs))
    i_b = min(i_b, n + int(math.ceil(AA_PAD_S * fs)))
    t_fine = t0 + (i_a * m + np.arange((i_b - i_a) * m)) * h  # from 1 ms before the force, also when the trace
    sensed = _sensed(rig, t_fine, knots, h)  # starts later (a truncated start: the plate's state is the force's)
    amp = zoo._highpass(sensed, rig.tau_s, h)
    out = np.zeros(n)
    take = np.arange(max(i_a, 0), min(i_b, n))
    out[take] = amp[(take - i_a) * m]
    if i_b < n:  # after the window: the high-pass's state w (output -w) decays
        w_end = float(sensed[-1] - amp[-1])
        t_after = t0 + np.arange(i_b, n) / fs
        out[i_b:] = -w_end * np.exp(-(t_after - t_fine[-1]) / rig.tau_s)
    return out


def _volts(rig: Rig, amp_N: np.ndarray, t: np.ndarray, kcal: float, extra_offset: float, rng) -> np.ndarray:
    """Recorded voltage [V]: polarity, offset, drift, hum, noise, spikes and the 16-bit ADC."""
    v = rig.polarity * amp_N / kcal + rig.offset_V + extra_offset + float(rng.uniform(-0.02, 0.02))
    v = v + float(rng.choice([-1, 1])) * rig.drift_V_s * (t - t[0])
    if rig.hum_V > 0:
        f_m = rig.mains_hz + rig.mains_dev_hz
        v = v + rig.hum_V * np.sin(2 * np.pi * f_m * t + float(rng.uniform(0, 2 * np.pi)))
        for k, rel in rig.harmonics:
            v = v + rel * rig.hum_V * np.sin(2 * np.pi * k * f_m * t + float(rng.uniform(0, 2 * np.pi)))
    v = v + rng.normal(0.0, rig.noise_V, size=v.size)
    lsb = 2 * rig.rail_V / 2**ADC_BITS
    if rig.spikes:
        for _ in range(int(rng.poisson(1.0))):
            i = int(rng.integers(0, v.size))
            amp = float(rng.choice([-1, 1])) * _loguniform(rng, 0.02, 1.0)
            v[i] = float(np.clip(v[i] + amp, -rig.rail_V + 3 * lsb, rig.rail_V - 3 * lsb))
    codes = np.clip(np.round((v + rig.rail_V) / lsb), 0, 2**ADC_BITS - 1)
    return -rig.rail_V + codes * lsb


def _rail_in_contact(rig: Rig, volts: np.ndarray, t0: float, tc: float) -> bool:
    """Whether a sample inside the contact [0, tc] [s] sits on the ADC's first or last code (issue 45: clipping
    inside the contact is a fault, whatever drove the signal there: a plate's overshoot on the rail, an offset)."""
    lsb = 2 * rig.rail_V / 2**ADC_BITS
    i0, i1 = max(int(math.ceil(-t0 * rig.sample_rate_hz)), 0), int(math.floor((tc - t0) * rig.sample_rate_hz))
    inside = volts[i0:min(i1 + 1, volts.size)]
    return bool(np.any(inside <= -rig.rail_V + 0.5 * lsb) or np.any(inside >= rig.rail_V - 1.5 * lsb))


def render_impact(rig: Rig, ball: BallTruth, vin: float, fault: str, impact_id: str, rng):
    """The recorded trace [V] of one impact and its truth; ``fault`` one of FAULT_KINDS or ""."""
    fs = rig.sample_rate_hz
    knots_t, knots_f, sim = force_knots(ball, vin)
    tc, peak = float(knots_t[-1]), float(knots_f.max())
    vout = float(np.trapezoid(knots_f, knots_t)) / ball.mass_kg - vin
    kcal = rig.kcal_N_per_V * (1.0 + rig.kcal_spread * float(rng.standard_normal()))
    knots, end_s, extra_offset = [(knots_t, knots_f)], tc, 0.0
    if fault == "second contact":
        second = _second_contact(rig, ball, tc, peak, rng)
        fault = "truncated" if second is None else fault
        if second is not None:
            knots.append(second)
            end_s = float(second[0][-1])
    sub = float(rng.uniform(0.0, 1.0)) / fs
    t0, n = -(math.floor(rig.pre_s * fs) / fs + sub), int(math.floor((rig.pre_s + rig.post_s) * fs))
    if fault == "truncated":
        frac = float(rng.uniform(0.2, 0.9)) * tc
        if rng.uniform() < 0.5:  # the trace starts inside the contact
            t0 = frac - sub
            n = int(math.floor((rig.post_s - frac) * fs))
        else:  # it ends inside the contact
            n = int(math.floor((frac - t0) * fs))
    if fault == "clipped":  # an offset not reset: the peak reaches 1.05-1.6 x the rail
        extra_offset = rig.polarity * (float(rng.uniform(1.05, 1.6)) * rig.rail_V - peak / kcal) - rig.offset_V
    amp = _amplifier_samples(rig, t0, n, knots, end_s)
    volts = _volts(rig, amp, t0 + np.arange(n) / fs, kcal, extra_offset, rng)
    if not fault and _rail_in_contact(rig, volts, t0, tc):  # the rig clipped it: a fault, drawn or not
        fault = "clipped"
    spike = float(sim.time_to_peak_s) < BUCKLING_TIME_S + 0.5 * TIME_STEP_S
    truth = ImpactTruth(impact_id=impact_id, ball=ball.key, fault=fault, vin_m_s=vin, vout_m_s=vout,
                        contact_time_s=tc, kcal_N_per_V=kcal, peak_N=peak, peak_is_spike=spike,
                        time_to_peak_s=float(sim.time_to_peak_s))
    return volts, truth


# ------------------------------------------------------------------ gates and files


def gate_cells(rig: Rig, truth: ImpactTruth, t_contact: float, fault: str, rng) -> list[str]:
    """The four gate-time cells of impacts.csv (timer clock, rounded down to its resolution)."""
    d, s, r = rig.gate_to_plate_m, GATE_SPACING_M, rig.gate_resolution_s
    vin, vout = truth.vin_m_s, truth.vout_m_s
    g_in_2 = t_contact - d / vin
    g = [g_in_2 - s / vin, g_in_2, t_contact + truth.contact_time_s + d / vout, 0.0]
    g[3] = g[2] + s / vout
    digits = int(round(-math.log10(r)))
    cells = [f"{math.floor(x / r) * r:.{digits}f}" for x in g]
    if fault == "inbound interval swapped":
        cells[0], cells[1] = cells[1], cells[0]
    elif fault == "rebound interval swapped":
        cells[2], cells[3] = cells[3], cells[2]
    elif fault == "rebound before arrival":
        shift = float(rng.uniform(0.5, 2.0))
        cells[2:] = [f"{float(c) - shift:.{digits}f}" for c in cells[2:]]
    elif fault == "missed event":
        cells[int(rng.integers(0, 4))] = ""
    return cells


def _write_tdms(path: Path, volts: np.ndarray, fs: float) -> None:
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    with TdmsWriter(str(path)) as w:
        w.write_segment([RootObject({}), GroupObject("rig"),
                         ChannelObject("rig", "voltage", np.asarray(volts, dtype=np.float64),
                                       properties={"wf_increment": 1.0 / fs, "unit_string": "V"})])


def session_yaml(rig: Rig) -> dict:
    """session.yaml of the rig's session: the keys it states, and its ball types with kB(0)."""
    plate = {"polarity": rig.polarity}
    if "resonance" in rig.stated:
        plate.update(resonance_hz=round(rig.plate_hz, 1), damping_ratio=round(rig.plate_zeta, 4))
    if "time_constant" in rig.stated:
        plate["time_constant_s"] = float(f"{rig.tau_s:.4g}")
    daq = {"sample_rate_hz": float(rig.sample_rate_hz), "adc_range_v": [-rig.rail_V, rig.rail_V]}
    if "mains" in rig.stated:
        daq["mains_hz"] = rig.mains_hz
    if "bandwidth" in rig.stated:
        daq["bandwidth_hz"] = round(float(rig.bandwidth_hz), 1)
    balls = {b.key: {"label": f"{b.key} (about {b.base})", "mass_g": round(1e3 * b.mass_kg, 4),
                     "kb0_kN_m": round(b.kb0_N_m / 1e3, 4)} for b in rig.balls}
    return {"session_id": rig.session_id, "date": "2026-12-04", "description": f"bench/rigs.py: {rig.describe()}",
            "synthetic": True, "plate": plate, "daq": daq,
            "gates": {"spacing_m": GATE_SPACING_M, "resolution_s": rig.gate_resolution_s}, "balls": balls}


def write_session(rig: Rig, raw_dir) -> list[ImpactTruth]:
    """Write the rig's session under ``raw_dir`` and its truth beside it; returns the truth per impact."""
    raw_dir = Path(raw_dir)
    folder = raw_dir / rig.session_id
    (folder / "traces").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng([rig.seed, rig.index, 47])
    faults = dict(rig.faults)
    rows, truths = [], []
    order = rng.permutation([k % len(rig.balls) for k in range(rig.n_impacts)])  # the ball types take turns
    for k in range(rig.n_impacts):
        ball = rig.balls[int(order[k])]
        vin = float(rng.uniform(*SPEED_RANGE_M_S))
        kind = faults.get(k, "")
        impact_id = f"{ball.key}-{k + 1:03d}"
        gate_fault = str(rng.choice(GATE_FAULTS)) if kind == "gate times" else ""
        volts, truth = render_impact(rig, ball, vin, "" if gate_fault else kind, impact_id, rng)
        if gate_fault:
            truth.fault = f"gate times: {gate_fault}"
        _write_tdms(folder / "traces" / f"{impact_id}.tdms", volts, rig.sample_rate_hz)
        cells = gate_cells(rig, truth, 10.0 + 9.0 * k + float(rng.uniform(0, 3)), gate_fault, rng)
        rows.append([impact_id, ball.key, f"traces/{impact_id}.tdms", *cells])
        truths.append(truth)
    header = "impact_id,ball,trace,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s\n"
    (folder / "impacts.csv").write_text(header + "".join(",".join(r) + "\n" for r in rows), encoding="utf-8")
    (folder / "session.yaml").write_text(yaml.safe_dump(session_yaml(rig), sort_keys=False), encoding="utf-8")
    import pandas as pd

    pd.DataFrame([t.row() for t in truths]).to_csv(raw_dir / f"{rig.session_id}.truth.csv", index=False)
    doc = asdict(rig)
    doc["balls"] = [asdict(b) for b in rig.balls]
    (raw_dir / f"{rig.session_id}.truth.yaml").write_text(yaml.safe_dump(
        {"note": "truth of a bench/rigs.py session (SI units)", **_plain(doc)}, sort_keys=False), encoding="utf-8")
    return truths


def _plain(value):
    """Tuples to lists, numpy scalars to Python ones (for yaml.safe_dump)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value

"""Where a wandering baseline passes a wrong number: 1/f noise on top of the white noise (issue 9).

    python bench/wander_map.py --n 400 --seed 1

A charge amplifier's and a DAQ's noise is white only above a corner frequency; below it the noise density rises as
1/f, and the baseline wanders: neither a line nor a step nor the amplifier's decay, which is what the baseline fit
models. The zoo draws white noise only. Apart from the zoo's seeds: each rig is tests/zoo.py's benign rig
(``zoo.map_shot``: a Table 2 ball, the four in turn, at 10-35 m/s, white noise of 0.1-0.5 % of the peak) at
20-200 kHz, with a pre-trigger of 1-100 ms and a record of 5 ms to 1 s after the contact (log-uniform, as the
zoo draws them), three in ten on a plate of 3 kHz to 0.45 fs (damping 0.01-0.3), the amplifier's time constant
drawn from 0.01-100 s (log-uniform) and given in session.yaml for half of them, and 1/f noise added to the
recorded voltage: its density equals the white noise's at a corner frequency drawn from 1 Hz to 2 kHz
(log-uniform), shaped from white noise over the whole record. The wander is not the ball's force and the trace
stays measurable: an ok must be right. Rendered and judged as the zoo's traces are (``zoo.run_trace``). Prints
the categories by corner frequency, the first reasons of the exclusions, and the ok-but-wrong traces;
``--no-wander`` runs the same rigs and shots with the white noise alone, to tell what the wander costs.
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import dataclasses
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402

import zoo  # noqa: E402

BALLS = ("pressureless", "pressurised", "punctured", "oversize")
CORNER_BANDS_HZ = (10.0, 100.0, 1000.0)  # bands of the 1/f corner frequency [Hz]


def pink_noise(n: int, sample_rate_hz: float, white_rms_V: float, corner_hz: float, rng) -> np.ndarray:
    """1/f noise [V] over ``n`` samples whose one-sided density equals that of white noise of ``white_rms_V`` [V]
    at ``corner_hz`` [Hz]: white noise shaped by sqrt(corner / f) in the frequency domain (zero mean)."""
    spectrum = np.fft.rfft(rng.normal(0.0, white_rms_V, n))
    f = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    shape = np.zeros_like(f)
    shape[1:] = np.sqrt(corner_hz / f[1:])
    return np.fft.irfft(spectrum * shape, n)


def trace_for(seed: int, index: int, wander: bool = True):
    """One map trace with its wander: (ZooTrace, corner frequency [Hz], wander's RMS over the white noise's [-]);
    without ``wander`` the same rig and shot with the white noise alone (the wander still drawn, not added)."""
    rng = np.random.default_rng([seed, index, 1729])
    chain = zoo.map_chain(rng)
    corner = zoo._loguniform(rng, 1.0, 2e3)
    shot = zoo.map_shot(rng)
    rig = zoo.Rig(**dict(zoo._BENIGN, ball=BALLS[index % 4], mode="wander", **chain, **shot))
    trace = zoo.render(rig, rng, f"wander {seed}:{index}")
    wander_on, wander = wander, pink_noise(trace.voltage_V.size, rig.sample_rate_hz, rig.noise_V, corner, rng)
    ratio = float(np.std(wander)) / rig.noise_V
    return (dataclasses.replace(trace, voltage_V=trace.voltage_V + wander) if wander_on else trace), corner, ratio


def run_one(args):
    seed, index, wander = args
    trace, corner, ratio = trace_for(seed, index, wander)
    result, j = zoo.run_trace(trace)
    return index, trace.rig, corner, ratio, j.category, {k: 100 * v for k, v in j.errors.items()}, result.reason


def main(argv=None):
    ap = zoo.map_arguments(__doc__)
    ap.add_argument("--no-wander", action="store_true", help="the same rigs with white noise alone, to compare")
    a = ap.parse_args(argv)
    rows = zoo.map_rows(run_one, [(a.seed, i, not a.no_wander) for i in range(a.n)], a.workers)
    what = "white noise alone" if a.no_wander else "1/f noise with its corner at 1 Hz-2 kHz"
    print("\n".join(zoo.map_report(
        rows, a.seed, f"{what}, fs 20-200 kHz",
        [r[2] for r in rows], CORNER_BANDS_HZ, lambda band: f"  corner {band:>12}",
        lambda r: f"record {1e3 * r[1].pre_s:.0f} + {1e3 * r[1].post_s:.0f} ms, 1/f corner {r[2]:.3g} Hz "
                  f"(wander {r[3]:.2f} x the white noise)", unit=" Hz")))

if __name__ == "__main__":
    main()

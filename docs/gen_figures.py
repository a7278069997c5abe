"""Figures of the documentation site, made from the code: the demo's report and figures, and the signal processing step by step.

Run by docs/hooks.py when the site is built (``make docs``) and the images are missing or
older than the code; by hand::

    python docs/gen_figures.py [--out docs/generated] [--only demo|steps]

``demo``: raw/demo-2004 processed, fitted and reported in a temporary folder with the
pipeline's own functions (the calls of rules ``session_impacts`` and
``session_outputs``); every figure file of the session is copied to ``<out>/demo/`` and
every page of its report drawn to ``<out>/demo/report-page-NN.png``, and the report
itself copied to ``<out>/demo/report.pdf``.

``steps``: one impact of Table 2's ball 1 at 20 m/s, simulated by the model and passed
through the synthetic sensor chain of ``ballimpact.synth``, then each main step of the
processing applied to it, one figure per step with the trace before and after
(``<out>/steps/<step>.png``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from ballimpact.threads import one_blas_thread  # noqa: E402

one_blas_thread()

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

DEMO = REPO / "raw" / "demo-2004"
REPORT_DPI = 90  # an A4 page of 8.27 x 11.69 in: 744 x 1052 pixels
STEP_DPI = 110
VIN_M_S = 20.0  # [m/s] the impact of the step figures
FS_HZ = 100_000.0  # [Hz] its sample rate
KCAL_N_PER_V = 180.0  # [N/V] its calibration factor


# --- the demo's report and figures -----------------------------------------------------

def demo_figures(out: Path, *, bootstrap: int = 200, seed: int = 0) -> list[Path]:
    """Process, fit and report raw/demo-2004 in a temporary folder; copy its figures to
    ``out`` and draw every page of its report there. Returns the files written."""
    from ballimpact import archive, pipeline, report
    from ballimpact.session import read_session

    out.mkdir(parents=True, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory(prefix="ballimpact-docs-") as tmp:
        work = Path(tmp)
        session_json, impacts_csv, impacts_nc = work / "session.json", work / "impacts.csv", work / "impacts.nc"
        pipeline.session_impacts(DEMO, session_json, impacts_csv, impacts_nc)
        balls = list(read_session(DEMO).meta.balls)
        figures_dir = work / "figures"
        pipeline.session_outputs(DEMO, impacts_nc, balls, work / "fits.nc", work / "demo-2004.nc",
                                 work / "parameters.csv", figures_dir, work / "report.pdf",
                                 n_bootstrap=bootstrap, seed=seed, snapshot_json=session_json)
        for png in sorted(figures_dir.rglob("*.png")):
            target = out / png.relative_to(figures_dir)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(png, target)
            written.append(target)
        shutil.copyfile(work / "report.pdf", out / "report.pdf")
        written.append(out / "report.pdf")
        ds = archive.open_dataset(work / "demo-2004.nc")
        for number, page in enumerate(report.report_pages(ds, figures_dir), 1):
            target = out / f"report-page-{number:02d}.png"
            page.savefig(target, dpi=REPORT_DPI)
            written.append(target)
        ds.close()
    return written


# --- the signal processing, step by step -----------------------------------------------

def _ball_force(vin_m_s: float = VIN_M_S):
    """Table 2's ball 1 at vin_m_s [m/s]: the model's force [N] at its times [s], zero at the end."""
    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    p = BALLS["pressurised"].params
    sim = simulate_impact(vin_m_s, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac, cloth_stiffness_N_m=5000.0, record=True)
    tc = float(sim.contact_time_s)
    inside = sim.time_s < tc
    force_t = np.concatenate([sim.time_s[inside], [tc]])
    force = np.concatenate([np.maximum(np.asarray(sim.force_N, dtype=float)[inside], 0.0), [0.0]])
    return p, sim, force_t, force


def _recorded(chain, seed: int = 3, vin_m_s: float = VIN_M_S):
    """The voltage the chain records for the ball's force at vin_m_s [m/s], with its sample times [s]."""
    from ballimpact.synth import simulate_voltage

    _, _, force_t, force = _ball_force(vin_m_s)
    t = np.arange(int(round(chain.trace_duration_s * chain.sample_rate_hz))) / chain.sample_rate_hz
    v = simulate_voltage(t, force_t + chain.pretrigger_s, force, KCAL_N_PER_V, chain, 1, np.random.default_rng(seed))
    return t, v


def _two_panels(title_before: str, title_after: str, *, sharey: bool = True):
    fig = Figure(figsize=(8.0, 3.1), layout="constrained")
    ax = fig.subplots(1, 2, sharey=sharey)
    ax[0].set_title(title_before, fontsize=10)
    ax[1].set_title(title_after, fontsize=10)
    for a in ax:
        a.grid(alpha=0.3)
        a.set_xlabel("time [ms]")
    return fig, ax


def _rig_chain(**kw):
    from ballimpact.synth import SensorChain

    base = dict(sample_rate_hz=FS_HZ, pretrigger_s=0.020, trace_duration_s=0.060, plate_frequency_hz=25_000.0,
                plate_damping_ratio=0.3)
    base.update(kw)
    return SensorChain(**base)


def step_spikes(out: Path) -> Path:
    """Single-sample spikes replaced by the mean of their neighbours."""
    from ballimpact.signal.spikes import remove_spikes

    t, v = _recorded(_rig_chain(amplifier_time_constant_s=0.8, hum_V=0.0, offset_V=0.0))
    start = int(round(0.020 * FS_HZ))
    spiky = v.copy()
    spiky[start - 300] += 0.4  # a spike in the quiet record before the contact
    spiky[start + 150] -= 0.8  # one on the force's smooth part
    clean, replaced = remove_spikes(spiky)
    fig, ax = _two_panels("before: two single-sample spikes", f"after: {len(replaced)} samples replaced")
    window = slice(start - 400, start + 500)
    for a, y in zip(ax, (spiky, clean)):
        a.plot(1e3 * t[window], y[window], ".-", ms=2, lw=0.7)
    ax[0].set_ylabel("voltage [V]")
    return _save(fig, out / "spikes.png")


def step_baseline(out: Path) -> Path:
    """Offset, mains hum and the charge amplifier's decay removed."""
    from ballimpact.signal.conditioning import condition_voltage

    t, v = _recorded(_rig_chain(amplifier_time_constant_s=0.05, hum_V=0.03, offset_V=0.05))
    cs = condition_voltage(v, FS_HZ, polarity=1)
    fig, ax = _two_panels("before: offset, 50 Hz hum, amplifier decay",
                          f"after: tau {cs.tau_s:.3f} s ({cs.tau_source}), hum {1e3 * cs.hum_amplitude_V:.0f} mV removed")
    ax[0].plot(1e3 * t, v, lw=0.6, label="recorded")
    ax[0].plot(1e3 * t, cs.baseline_V, lw=1.2, label="fitted offset and hum")
    ax[0].legend(fontsize=8, loc="upper right")
    ax[1].plot(1e3 * t, cs.voltage_V, lw=0.6, color="C2")
    ax[0].set_ylim(-0.25, 0.35)
    ax[0].set_ylabel("voltage [V] (the contact is off the scale)")
    ax[0].yaxis.label.set_fontsize(8)
    return _save(fig, out / "baseline.png")


def step_plate(out: Path) -> Path:
    """A ringing plate's resonance identified and undone."""
    from ballimpact.signal.conditioning import condition_voltage

    chain = _rig_chain(plate_frequency_hz=12_000.0, plate_damping_ratio=0.05, noise_V=0.0005)
    t, v = _recorded(chain)
    kept = condition_voltage(v, FS_HZ, polarity=1, undo_plate=False)
    undone = condition_voltage(v, FS_HZ, polarity=1)
    plate = undone.plate
    after = ("after: plate undone" if plate is None else
             f"after: {plate.frequency_hz / 1e3:.1f} kHz, damping {plate.damping_ratio:.3f}, undone")
    fig, ax = _two_panels("before: a 12 kHz plate, damping ratio 0.05", after)
    start = kept.contact.start_s
    window = (t > start - 0.5e-3) & (t < start + 5.5e-3)
    for a, y in zip(ax, (kept.voltage_V, undone.voltage_V)):
        a.plot(1e3 * (t[window] - start), y[window], ".-", ms=2, lw=0.7)
    ax[0].set_ylabel("corrected voltage [V]")
    for a in ax:
        a.set_xlabel("time from the contact start [ms]")
    return _save(fig, out / "plate.png")


def step_contact(out: Path) -> Path:
    """The contact's start and end, each to a fraction of a sample."""
    from ballimpact.signal.conditioning import condition_voltage

    t, v = _recorded(_rig_chain())
    cs = condition_voltage(v, FS_HZ, polarity=1)
    c = cs.contact
    fig, ax = _two_panels(f"start {1e3 * c.start_s:.4f} ms", f"end {1e3 * c.end_s:.4f} ms", sharey=False)
    for a, edge in zip(ax, (c.start_s, c.end_s)):
        near = (t > edge - 0.25e-3) & (t < edge + 0.25e-3)
        a.plot(1e3 * t[near], cs.voltage_V[near], "o-", ms=3, lw=0.7, label="corrected samples")
        a.axvline(1e3 * edge, color="C3", lw=1.0, label="contact end found" if edge == c.end_s else "contact start found")
        a.axhline(0.0, color="0.5", lw=0.6)
        a.legend(fontsize=8, loc="upper left" if edge == c.start_s else "upper right")
    ax[0].set_ylim(-0.02, 0.15)  # the cloth's foot before the jump
    ax[1].set_ylim(-0.02, 0.15)
    ax[0].set_ylabel("corrected voltage [V]")
    return _save(fig, out / "contact.png")


def step_calibration(out: Path) -> Path:
    """kCAL from the impulse; the force, then the ball's velocity and displacement."""
    from ballimpact.calibration import calibration_factor, integrate_motion
    from ballimpact.signal.conditioning import condition_voltage

    p, sim, _, _ = _ball_force()
    t, v = _recorded(_rig_chain())
    cs = condition_voltage(v, FS_HZ, polarity=1)
    c = cs.contact
    vout = float(sim.cor) * VIN_M_S
    kcal = calibration_factor(t, cs.voltage_V, c.start_s, c.end_s, p.mass_kg, VIN_M_S, vout)
    inside = (t >= c.start_s) & (t <= c.end_s)
    tc_ms = 1e3 * (t[inside] - c.start_s)
    force = kcal * cs.voltage_V[inside]
    velocity, displacement = integrate_motion(t[inside] - c.start_s, force, p.mass_kg, VIN_M_S)
    fig = Figure(figsize=(8.0, 3.1), layout="constrained")
    ax = fig.subplots(1, 3)
    ax[0].plot(tc_ms, cs.voltage_V[inside], lw=0.9)
    ax[0].set(title="before: corrected voltage", ylabel="[V]")
    ax[1].plot(tc_ms, force, lw=0.9, color="C1")
    ax[1].set(title=f"force = kCAL V, kCAL {kcal:.1f} N/V", ylabel="[N]")
    ax[2].plot(tc_ms, velocity, lw=0.9, color="C2", label="velocity [m/s]")
    ax[2].plot(tc_ms, 1e3 * displacement, lw=0.9, color="C4", label="displacement [mm]")
    ax[2].set(title="the ball's motion")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
        a.set_xlabel("time from contact start [ms]")
        a.title.set_fontsize(10)
    return _save(fig, out / "calibration.png")


def step_peak(out: Path) -> Path:
    """The peak force: the largest sample, or the middle of the range a cut ramp leaves."""
    from ballimpact.calibration import force_top
    from ballimpact.signal.conditioning import condition_voltage

    fs_low, vin = 40_000.0, 30.0  # at 30 m/s the spike is the peak; between samples at a low rate
    _, _, force_t, force = _ball_force(vin)
    chain = _rig_chain(sample_rate_hz=fs_low, plate_frequency_hz=80_000.0, plate_damping_ratio=0.7)
    t, v = _recorded(chain, vin_m_s=vin)
    cs = condition_voltage(v, fs_low, polarity=1)
    c = cs.contact
    kcal = KCAL_N_PER_V
    sampled = kcal * cs.voltage_V
    inside = (t >= c.start_s) & (t <= c.end_s)
    peak, peak_t, half = force_top(t[inside], sampled[inside], kcal * cs.noise_rms_V)
    fig = Figure(figsize=(8.0, 3.1), layout="constrained")
    ax = fig.subplots()
    ax.plot(1e3 * (force_t + chain.pretrigger_s - c.start_s), force, lw=0.8, color="0.6",
            label="the model's force (truth)")
    ax.plot(1e3 * (t[inside] - c.start_s), sampled[inside], "o", ms=3, label=f"samples at {fs_low / 1e3:.0f} kHz")
    ax.errorbar([1e3 * (peak_t - c.start_s)], [peak], yerr=[half], fmt="s", color="C3", ms=5, capsize=4,
                label="peak taken, with its range")
    ax.set(xlim=(-0.05, 1.0), xlabel="time from contact start [ms]", ylabel="force [N]",
           title=f"the pre-buckling spike: peak {peak:.0f} N (true {float(np.max(force)):.0f} N)")
    ax.title.set_fontsize(10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    return _save(fig, out / "peak.png")


STEPS = (step_spikes, step_baseline, step_plate, step_contact, step_calibration, step_peak)


def _save(fig: Figure, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=STEP_DPI)
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "generated")
    parser.add_argument("--only", choices=("demo", "steps"))
    args = parser.parse_args(argv)
    written = []
    if args.only in (None, "steps"):
        written += [step(args.out / "steps") for step in STEPS]
    if args.only in (None, "demo"):
        written += demo_figures(args.out / "demo")
    print(f"{len(written)} images in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

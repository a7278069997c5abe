"""How well the fitted model's force follows the measured one, per ball type: the numbers behind the
force-shape fit warning (ballimpact.summary.FORCE_AGREEMENT_WARNING).

For each session the impacts are processed, fitted and archived in this process (the workflow's own
functions, few bootstrap resamples), and the median over a ball's ok impacts of
``model_agreement_fraction`` (share of the contact after 0.2 ms where the model is within 10 % of the
measured peak) is printed with its lowest impact:

* the bundled demo (raw/demo-2004) and sessions of `ballimpact synth` with several seeds, at 67 and
  50 kHz: tennis-ball forces;
* sessions made by hand as tests/handmade.py does: half-sine pulses of 3.5, 4.3 and 5.5 ms, which no
  ball of the paper's model gives.

    python bench/force_shape_map.py [--quick]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))


def _agreement(session_dir: Path, work: Path) -> dict[str, tuple[float, float, int]]:
    """Per ball: (median, lowest) agreement fraction over the ok impacts [-], and their number."""
    import xarray as xr

    from ballimpact.pipeline import fit_balls, session_impacts, write_archive
    from ballimpact.session import read_session

    work.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        session_impacts(session_dir, work / "session.json", work / "impacts.csv", work / "impacts.nc")
        balls = [b for b in read_session(session_dir).meta.balls]
        with xr.open_dataset(work / "impacts.nc") as impacts:
            used = sorted(set(str(b) for b in impacts["ball_type"].values), key=balls.index)
        fit_balls(work / "impacts.nc", used, session_dir, work / "fits.nc", n_bootstrap=10, seed=0)
        write_archive(session_dir, work / "impacts.nc", [work / "fits.nc"], work / "archive.nc",
                      work / "parameters.csv")
    with xr.open_dataset(work / "archive.nc") as ds:
        share = np.asarray(ds["model_agreement_fraction"].values, dtype=float)
        ok = np.array([str(s) == "ok" for s in ds["status"].values])
        per_impact = np.array([str(b) for b in ds["ball_type"].values])
    out = {}
    for ball in used:
        use = ok & (per_impact == ball) & np.isfinite(share)
        if use.any():
            out[ball] = (float(np.median(share[use])), float(share[use].min()), int(use.sum()))
    return out


def _sessions(root: Path, quick: bool):
    """(label, session folder) of every session measured."""
    from handmade import HandmadeSpec, write_session as write_handmade
    import handmade

    from ballimpact.synth import SensorChain, SynthConfig, write_session

    yield "demo-2004 (tennis balls)", REPO / "raw" / "demo-2004"
    chains = {"67 kHz": SensorChain(), "50 kHz": SensorChain(sample_rate_hz=50_000.0)}
    for seed in (1,) if quick else (1, 2, 3):
        for name, chain in chains.items():
            sid = f"synth-{seed}-{name.replace(' ', '')}"
            folder, _ = write_session(root / sid, SynthConfig(session_id=sid, seed=seed, impacts_per_ball=6,
                                                              faults_per_kind=0, chain=chain))
            yield f"synth seed {seed}, {name} (tennis balls)", folder
    for half_sine_s in (4.3e-3,) if quick else (3.5e-3, 4.3e-3, 5.5e-3):
        handmade.HALF_SINE_S = half_sine_s
        sid = f"hand-{half_sine_s * 1e3:.1f}ms"
        folder = write_handmade(root / sid, HandmadeSpec(formats=["csv"] * 8, header_rates_hz={},
                                                         bandwidth_hz=20_000.0))
        yield f"hand-made half-sines of {half_sine_s * 1e3:.1f} ms", folder


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="one session of each kind")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        print(f"{'session':48} {'ball':>14} {'median':>7} {'lowest':>7} {'n':>3}")
        for label, folder in _sessions(root, args.quick):
            for ball, (median, lowest, n) in _agreement(folder, root / "work" / folder.name).items():
                print(f"{label:48} {ball:>14} {median:7.3f} {lowest:7.3f} {n:3d}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

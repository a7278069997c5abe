"""Benchmarks of ballimpact: model throughput, fit time, workflow wall time and memory.

    python bench/run.py            # full run, human-readable
    python bench/run.py --json     # one JSON object with every figure
    python bench/run.py --quick --json   # same keys from smaller runs (< 1 min)

Keys:
  model_impacts_per_s       batched simulate_impact, Table 2 ball 1, speeds 14-30 m/s, one process
  model_reference_c_impacts_per_s  bench/reference_model.c (scalar loop, cc -O2), same impacts, one core,
                            measured in the same run; null without a C compiler (see _note);
                            model_reference_c_max_rel_diff_tc_cor: its TC/COR against simulate_impact
  fit_seconds               fit_ball_model for every ball type of raw/demo-2004, intervals included
                            (processing the session is not timed)
  workflow_seconds_<n>      `snakemake --cores 2` wall time on a synthetic session of n impacts
  peak_memory_mb_<n>        largest resident set of any process of that run (getrusage of children)
  process_seconds_per_impact  process_impact on raw/demo-2004, one core
In --quick mode the workflow runs once, on 50 impacts; workflow_seconds_200 and _1000 are
that time plus the extra impacts' processing time (process_seconds_per_impact, shared by
2 cores), peak memory is the 50-impact run's; the model runs on 4 000 instead of 20 000
impacts. Flagged "quick": true; compare quick figures with quick figures.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
SIZES = (50, 200, 1000)
QUICK_SIZE = 50  # the one workflow run of --quick


def bench_model(n: int, repeats: int = 3) -> float:
    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    p = BALLS["pressurised"].params
    vin = np.random.default_rng(0).uniform(14, 30, n)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        best = min(best, time.perf_counter() - t0)
    return n / best


def bench_model_reference_c(n: int, repeats: int = 3, n_check: int = 8) -> dict:
    """Compile bench/reference_model.c (the scalar loop) with `cc -O2` and time it here.

    Same ball and the same speeds as bench_model (seed 0). Also returns the largest
    relative difference of its TC and COR from simulate_impact on the first n_check
    impacts (expected ~1e-14: the same arithmetic in another order). Without a C
    compiler the throughput is null, with a note.
    """
    import shutil

    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    cc = shutil.which(os.environ.get("CC", "cc"))
    if cc is None:
        return {"model_reference_c_impacts_per_s": None,
                "model_reference_c_note": f"no C compiler ({os.environ.get('CC', 'cc')}) found: reference not measured"}
    p = BALLS["pressurised"].params
    vin = np.random.default_rng(0).uniform(14, 30, n)
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "reference_model"
        build = subprocess.run([cc, "-O2", "-ffp-contract=off", "-o", str(exe),
                                str(REPO / "bench" / "reference_model.c"), "-lm"], capture_output=True, text=True)
        if build.returncode != 0:
            return {"model_reference_c_impacts_per_s": None,
                    "model_reference_c_note": f"{cc} failed to build bench/reference_model.c: {build.stderr.strip()[:200]}"}
        stdin = f"{p.mass_kg!r} {p.kb0_N_m!r} {p.ak!r} {p.a!r} {p.ac!r} {n} {repeats}\n"
        stdin += "\n".join(repr(float(v)) for v in vin) + "\n"
        out = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True).stdout.split("\n")
    rate = float(out[0].split()[1])
    ref = np.array([[float(x) for x in line.split()] for line in out[1:1 + n_check]])
    sim = simulate_impact(vin[:n_check], p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    diff = max(np.max(np.abs(sim.contact_time_s / ref[:, 0] - 1)), np.max(np.abs(sim.cor / ref[:, 1] - 1)))
    return {"model_reference_c_impacts_per_s": rate,
            "model_reference_c_max_rel_diff_tc_cor": float(diff),
            "model_reference_c_note": f"bench/reference_model.c, {cc} -O2 -ffp-contract=off, one core, {n} impacts, best of {repeats}"}


def bench_fit(session_dir: Path, n_bootstrap: int = 200) -> dict:
    """Time fit_ball_model on every ball type of a session (processing not timed)."""
    from ballimpact.archive import impacts_dataset
    from ballimpact.fitting import fit_ball_model
    from ballimpact.pipeline import fit_arrays
    from ballimpact.processing import apply_calibration_check, iter_process
    from ballimpact.session import read_session

    session = read_session(session_dir)
    t0 = time.perf_counter()
    results = list(iter_process(session))
    process_s = (time.perf_counter() - t0) / len(results)
    apply_calibration_check(results)
    ds = impacts_dataset(results)
    inputs = {key: fit_arrays(ds, key, ball.mass_kg) for key, ball in session.meta.balls.items()}
    t0 = time.perf_counter()
    for key, ball in session.meta.balls.items():
        fit_ball_model(**inputs[key], kb0_N_m=ball.kb0_N_m, n_bootstrap=n_bootstrap)
    return {"fit_seconds": time.perf_counter() - t0, "fit_ball_types": len(inputs),
            "process_seconds_per_impact": process_s}


def _run_workflow(n_impacts: int, workdir: Path) -> tuple[float, float]:
    from ballimpact.synth import SynthConfig, write_session

    raw = workdir / f"raw{n_impacts}"
    sid = f"bench{n_impacts}"
    write_session(raw / sid, SynthConfig(session_id=sid, total_impacts=n_impacts, faults_per_kind=1))
    results = workdir / f"results{n_impacts}"
    cmd = [
        str(Path(sys.executable).parent / "snakemake"), "--cores", "2", "--quiet", "all",
        "--config", f"raw_dir={raw}", f"results_dir={results}",
        "--directory", str(REPO),
    ]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"workflow failed for n={n_impacts}:\n{proc.stderr[-3000:]}")
    return wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0


def _run_isolated(n_impacts: int, workdir: Path) -> tuple[float, float]:
    # a fresh Python process per size so that ru_maxrss of children is this run's own
    code = (
        "import sys, json; sys.path.insert(0, %r); import run; "
        "print(json.dumps(run._run_workflow(%d, run.Path(%r))))" % (str(Path(__file__).parent), n_impacts, str(workdir))
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-3000:])
    wall, mem = json.loads(out.stdout.strip().splitlines()[-1])
    return wall, mem


def bench_workflow(sizes, quick: bool, process_s_per_impact: float) -> dict:
    out = {}
    with tempfile.TemporaryDirectory(prefix="ballimpact-bench-") as tmp:
        measured = {n: _run_isolated(n, Path(tmp)) for n in ((QUICK_SIZE,) if quick else sizes)}
    if quick:
        # One measured run; a larger session adds its extra impacts' processing time,
        # measured per impact in bench_fit, shared by the 2 cores. An estimate from
        # measured parts: compare quick figures only with quick figures.
        wall, mem = measured[QUICK_SIZE]
        for n in sizes:
            out[f"workflow_seconds_{n}"] = wall + (n - QUICK_SIZE) * process_s_per_impact / 2
            out[f"peak_memory_mb_{n}"] = mem
        out["workflow_measured_sizes"] = [QUICK_SIZE]
        out["workflow_estimated_sizes"] = [n for n in sizes if n != QUICK_SIZE]
    else:
        for n, (wall, mem) in measured.items():
            out[f"workflow_seconds_{n}"] = wall
            out[f"peak_memory_mb_{n}"] = mem
        ns = np.array(list(measured))
        ts = np.array([measured[n][0] for n in ns])
        out["workflow_seconds_per_impact"] = float(np.polyfit(ns, ts, 1)[0])
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="ballimpact benchmarks")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--quick", action="store_true", help="smaller runs, same keys (< 1 min)")
    ap.add_argument("--skip-workflow", action="store_true", help="only model and fit figures")
    args = ap.parse_args(argv)

    figures: dict = {"quick": args.quick}
    figures["model_impacts_per_s"] = bench_model(4000 if args.quick else 20000)
    figures.update(bench_model_reference_c(4000 if args.quick else 20000))
    figures.update(bench_fit(REPO / "raw" / "demo-2004", n_bootstrap=200))
    if not args.skip_workflow:
        figures.update(bench_workflow(SIZES, args.quick, figures["process_seconds_per_impact"]))
    if args.json:
        print(json.dumps(figures, indent=2))
    else:
        for k, v in figures.items():
            print(f"{k:32s} {v:.4g}" if isinstance(v, float) else f"{k:32s} {v}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    sys.exit(main())

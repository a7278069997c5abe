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
                            (processing the session is not timed); fit_cpu_seconds: its CPU time
  workflow_seconds_<n>      `snakemake --cores 2` wall time on a synthetic session of n impacts
  peak_memory_mb_<n>        largest resident set of any process of that run (getrusage of children)
  process_seconds_per_impact  process_impact on raw/demo-2004, one core
  bootstrap_dropped(_pct)   bootstrap resamples dropped (unconverged) over the demo's ball types
  fit_outliers              impacts the fit-outlier search named on the demo
  no_kb0_*                  the same on the demo remade by `ballimpact synth --seed 2004 --no-kb0`
                            (kB(0) extrapolated); --fit-only runs just the fit figures
  sessions_<k>x40_seconds    `snakemake --cores 2` wall time on k synthetic sessions of 40 impacts each,
                            the catalogue included (measured for k in SESSION_COUNTS)
  sessions_100x40_seconds   the same for 100 sessions, extrapolated: least-squares line
                            t = t0 + k * t_session through the measured k (extrapolate_linear);
                            sessions_seconds_per_session = t_session, sessions_fit_max_residual_s
                            = the largest misfit of that line at the measured k
  sessions_100x40_cpu_seconds  CPU time (user + sys, every process) of the run, same extrapolation;
                            sessions_100x40_idle_2core_seconds = half of it, the wall time on an
                            otherwise idle 2-core machine if both cores stay busy (a lower bound)
  sessions_<k>x40_job_cpu    that run's CPU time by rule: {rule: [jobs, CPU seconds, largest peak RSS MB]}
                            ("snakemake": its main process), recorded by bench/cpu_hook/sitecustomize.py
  model_call_cpu_ms_<n>     (--model-only, with model_impacts_per_s) CPU time of one simulate_impact call of n
                            impacts: 9 and 36 as a fit's Levenberg-Marquardt batches, 7200 as a bootstrap's
  model_impacts_per_s_<n>   (--model-only) throughput of calls of n impacts (40: a session's), model_loop_<n>
                            the loop that ran (compiled or numpy), model_vs_c_<n> its ratio to
                            model_reference_c_impacts_per_s (measured in the same run)
  model_compile_cpu_seconds (--model-only) first call of the compiled loop in a fresh process with an empty
                            numba cache (compiling); model_cache_load_cpu_seconds: the same with the cache
                            (loading, paid once by every job); numba_import_cpu_seconds: numba's import
  stage_cpu_seconds_<stage>  (--stages) CPU time of each stage of one 40-impact session in one
                            process, and of the library's imports (paid again by every job)
  catalogue_cpu_seconds_<k>  (--catalogue) CPU time of the catalogue's work (write_catalogue) over k copies of
                            one 40-impact session, in a fresh process; catalogue_peak_memory_mb_<k>: its peak RSS;
                            catalogue_<cpu_seconds|peak_memory_mb>_per_session: slope of the line through them,
                            _fit_max_residual_<s|mb>: its largest misfit, _100_extrapolated: the line at 100
  sessions_cpu_seconds_per_session  slope of the CPU line (sessions_<k>x40_cpu_seconds against k): CPU per added
                            session, all in; sessions_cpu_fit_max_residual_s: its largest misfit
  --sessions-only --counts K1 K2 ...  the many-sessions figures from runs of K1, K2, ... sessions
  load_average_1min_at_start/_end  the machine's load around the runs (other work inflates wall times);
                            sessions_wall_reliable is false when it exceeded 2.5 or the line does not rise:
                            then only the CPU figures mean something
  sessions_peak_memory_mb   largest resident set of any process of the largest measured run
  sessions_100x40_peak_memory_mb_by_process  the largest of: the per-session jobs' peak (one session each,
                            it does not grow), and the peaks of Snakemake's main process and of the catalogue
                            job, each extrapolated to 100 sessions by its own line
  sessions_job_cpu_seconds_per_session  CPU of the per-session jobs (all but snakemake and catalogue) of the
                            largest run, per session; sessions_<k>x40_snakemake/catalogue_cpu_seconds: the rest
  sessions_100x40_peak_memory_mb  that memory extrapolated to 100 sessions by the same line
  sessions_add_one_to_<k>_seconds / _cpu_seconds / _job_cpu  after the run of k sessions, one more session
                            (year<k>) is added and `snakemake --cores 2` run again: its wall and CPU time (the
                            new session's jobs, the catalogue of k + 1 sessions, Snakemake's main process);
                            sessions_add_one_to_100_<seconds|cpu_seconds>: the line through the measured k at 100
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
SESSION_COUNTS = (2, 4, 8)  # sessions of 40 impacts for the year-of-sessions figure
QUICK_SESSION_COUNTS = (1, 3)
IMPACTS_PER_SESSION = 40
TARGET_SESSIONS = 100
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


MODEL_CALL_SIZES = (9, 36, 7200)  # impacts per simulate_impact call: a fit's LM batches (9-36), a bootstrap's
MODEL_BATCH_SIZES = (40, 400, 20000)  # a session's impacts, ten sessions', the bootstrap's scale


def bench_model_batches(sizes=MODEL_BATCH_SIZES) -> dict:
    """Throughput [impacts/s] of simulate_impact called on n impacts at once (``model_impacts_per_s_<n>``).

    Calls of fewer than model.COMPILED_LOOP_MAX_IMPACTS impacts run the compiled loop, larger
    ones the numpy loop (``model_loop_<n>`` says which). Same ball and speeds as bench_model;
    CPU time of this process, the best of 5 rounds of about 0.3 s.
    """
    from ballimpact.balls import BALLS
    from ballimpact.model import COMPILED_LOOP_MAX_IMPACTS, simulate_impact

    p = BALLS["pressurised"].params
    out = {}
    for n in sizes:
        vin = np.random.default_rng(0).uniform(14, 30, n)
        t0 = time.process_time()
        simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        reps = max(1, int(0.3 / max(time.process_time() - t0, 1e-4)))
        best = np.inf
        for _ in range(5):
            t0 = time.process_time()
            for _ in range(reps):
                simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
            best = min(best, (time.process_time() - t0) / reps)
        out[f"model_impacts_per_s_{n}"] = n / best
        out[f"model_loop_{n}"] = "compiled" if n < COMPILED_LOOP_MAX_IMPACTS else "numpy"
    return out


def bench_model_compile() -> dict:
    """CPU seconds of the compiled model loop's first call in a fresh process.

    ``model_compile_cpu_seconds``: with an empty numba cache (NUMBA_CACHE_DIR a new folder),
    so numba compiles and writes its cache; ``model_cache_load_cpu_seconds``: a second
    fresh process with that cache, so numba loads it (what every job pays once);
    ``numba_import_cpu_seconds``: importing numba alone, part of the latter.
    """
    code = ("import time; t0 = time.process_time(); import numba; t1 = time.process_time(); "
            "from ballimpact.model import simulate_impact; t2 = time.process_time(); "
            "simulate_impact(20.0, 0.057, 1e4, 4e7, 1.5, 1e3); t3 = time.process_time(); "
            "print(t1 - t0, t3 - t2 + t1 - t0)")
    out = {}
    with tempfile.TemporaryDirectory(prefix="ballimpact-numba-cache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for key in ("model_compile_cpu_seconds", "model_cache_load_cpu_seconds"):
            proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
            numba_s, first_s = (float(v) for v in proc.stdout.split())
            out[key] = first_s
            out["numba_import_cpu_seconds"] = numba_s
    return out


def bench_model_calls(sizes=MODEL_CALL_SIZES, seconds: float = 0.5) -> dict:
    """CPU time [ms] of one simulate_impact call of n impacts (``model_call_cpu_ms_<n>``).

    The fits call the model on a few dozen impacts at a time (one ball type's impacts at
    the current point and its finite-difference neighbours), where the cost is the numpy
    calls of each of the ~450 time steps, not the impacts; the bootstrap and the model
    curves on thousands. Table 2 ball 1 with AK, a and AC spread by +-20 %, speeds 14-30
    m/s (seed 0); the best of 3 rounds of about ``seconds`` each.
    """
    from ballimpact.balls import BALLS
    from ballimpact.model import simulate_impact

    p = BALLS["pressurised"].params
    out = {}
    for n in sizes:
        rng = np.random.default_rng(0)
        vin = rng.uniform(14, 30, n)
        ak, a, ac = (p.ak * rng.uniform(0.8, 1.2, n), p.a * rng.uniform(0.8, 1.2, n), p.ac * rng.uniform(0.8, 1.2, n))
        t0 = time.process_time()
        simulate_impact(vin, p.mass_kg, p.kb0_N_m, ak, a, ac)
        reps = max(1, int(seconds / max(time.process_time() - t0, 1e-4)))
        best = np.inf
        for _ in range(3):
            t0 = time.process_time()
            for _ in range(reps):
                simulate_impact(vin, p.mass_kg, p.kb0_N_m, ak, a, ac)
            best = min(best, (time.process_time() - t0) / reps)
        out[f"model_call_cpu_ms_{n}"] = 1e3 * best
    return out


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
            "model_reference_c_note": (f"bench/reference_model.c, {cc} -O2 -ffp-contract=off, one core, CPU time "
                                       f"of its process, {n} impacts, best of {repeats}")}


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
    t0, c0 = time.perf_counter(), time.process_time()
    fits = {}
    for key, ball in session.meta.balls.items():
        fits[key] = fit_ball_model(**inputs[key], kb0_N_m=ball.kb0_N_m, n_bootstrap=n_bootstrap)
    # CPU seconds of this process too: the wall time grows with other work on the machine
    out = {"fit_seconds": time.perf_counter() - t0, "fit_cpu_seconds": time.process_time() - c0,
           "fit_ball_types": len(inputs), "process_seconds_per_impact": process_s}
    out.update(_fit_summary(fits, n_bootstrap, ""))
    return out


def _fit_summary(fits, n_bootstrap, prefix) -> dict:
    """Bootstrap resamples dropped and fit outliers named, over the ball types of one session."""
    dropped = sum(f.bootstrap_dropped for f in fits.values())
    return {
        f"{prefix}bootstrap_dropped": int(dropped),
        f"{prefix}bootstrap_dropped_pct": 100.0 * dropped / (n_bootstrap * len(fits)) if fits else float("nan"),
        f"{prefix}fit_outliers": int(sum(int((~f.used).sum()) for f in fits.values())),
        f"{prefix}kb0_sources": sorted({f.kb0_source for f in fits.values()}),
    }


def bench_fit_no_kb0(n_bootstrap: int = 200) -> dict:
    """The demo remade without kB(0) in session.yaml (`ballimpact synth --seed 2004 --no-kb0`),
    processed and fitted (kB(0) extrapolated): fit time, bootstrap resamples dropped."""
    from ballimpact.archive import impacts_dataset
    from ballimpact.fitting import fit_ball_model
    from ballimpact.pipeline import fit_arrays
    from ballimpact.processing import apply_calibration_check, iter_process
    from ballimpact.session import read_session

    with tempfile.TemporaryDirectory(prefix="ballimpact-nokb0-") as tmp:
        sdir = Path(tmp) / "demo-2004-no-kb0"
        subprocess.run([str(Path(sys.executable).parent / "ballimpact"), "synth", str(sdir), "--seed", "2004",
                        "--no-kb0"], check=True, capture_output=True, text=True)
        session = read_session(sdir)
        results = list(iter_process(session))
        apply_calibration_check(results)
        ds = impacts_dataset(results)
        t0, c0 = time.perf_counter(), time.process_time()
        fits = {key: fit_ball_model(**fit_arrays(ds, key, ball.mass_kg), kb0_N_m=ball.kb0_N_m,
                                    n_bootstrap=n_bootstrap)
                for key, ball in session.meta.balls.items()}
        out = {"no_kb0_fit_seconds": time.perf_counter() - t0, "no_kb0_fit_cpu_seconds": time.process_time() - c0}
    out.update(_fit_summary(fits, n_bootstrap, "no_kb0_"))
    return out


def _snakemake_wall_s(raw: Path, results: Path, what: str, env: dict | None = None) -> float:
    """Wall time [s] of `snakemake --cores 2` on raw_dir=raw, results_dir=results; RuntimeError if it fails."""
    cmd = [
        str(Path(sys.executable).parent / "snakemake"), "--cores", "2", "--quiet", "all",
        "--config", f"raw_dir={raw}", f"results_dir={results}",
        "--directory", str(REPO),
    ]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"workflow failed for {what}:\n{proc.stderr[-3000:]}")
    return wall


def _run_workflow(n_impacts: int, workdir: Path) -> tuple[float, float]:
    from ballimpact.synth import SynthConfig, write_session

    raw = workdir / f"raw{n_impacts}"
    sid = f"bench{n_impacts}"
    write_session(raw / sid, SynthConfig(session_id=sid, total_impacts=n_impacts, faults_per_kind=1))
    results = workdir / f"results{n_impacts}"
    wall = _snakemake_wall_s(raw, results, f"n={n_impacts}")
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


def extrapolate_linear(ns, ys, n_target):
    """Least-squares line y = y0 + n * slope through (ns, ys), evaluated at n_target.

    Returns (value at n_target, slope, intercept, largest absolute residual at the
    measured ns). Needs at least two distinct ns.
    """
    ns = np.asarray(ns, dtype=float)
    ys = np.asarray(ys, dtype=float)
    if ns.shape != ys.shape or np.unique(ns).size < 2:
        raise ValueError(f"need at least two distinct sizes with one value each, got ns={ns.tolist()}")
    slope, intercept = np.polyfit(ns, ys, 1)
    residual = float(np.max(np.abs(ys - (intercept + slope * ns))))
    return float(intercept + slope * n_target), float(slope), float(intercept), residual


def _write_year_session(raw: Path, k: int) -> None:
    """Synthetic 40-impact session year<k> (seed 1000 + k) into raw/, without its truth files."""
    from ballimpact.synth import SynthConfig, write_session

    sid = f"year{k:03d}"
    write_session(raw / sid, SynthConfig(session_id=sid, seed=1000 + k, total_impacts=IMPACTS_PER_SESSION,
                                         faults_per_kind=1, date=f"2026-{1 + k % 12:02d}-{1 + k // 12:02d}"))
    for truth in raw.glob("*.truth.*"):
        truth.unlink()


def _cpu_env(cpu_log: Path) -> dict:
    """The environment of a benchmarked run: bench/cpu_hook on PYTHONPATH, logging to cpu_log."""
    return dict(os.environ, BALLIMPACT_BENCH_CPU_LOG=str(cpu_log),
                PYTHONPATH=os.pathsep.join(filter(None, [str(Path(__file__).parent / "cpu_hook"),
                                                         os.environ.get("PYTHONPATH")])))


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run_sessions(n_sessions: int, workdir: Path) -> tuple:
    """`snakemake --cores 2` on n fresh 40-impact sessions, then again after one more session is added.

    Returns wall time [s], peak RSS [MB], CPU time [s] and CPU by rule of the first run, and
    wall time [s], CPU time [s] and CPU by rule of the second (the new session's jobs and
    the catalogue of n + 1 sessions).
    """
    raw = workdir / f"raw_s{n_sessions}"
    for k in range(n_sessions):
        _write_year_session(raw, k)
    results = workdir / f"results_s{n_sessions}"
    cpu_log = workdir / f"cpu_s{n_sessions}.log"
    wall = _snakemake_wall_s(raw, results, f"{n_sessions} sessions", env=_cpu_env(cpu_log))
    if not (results / "catalogue" / "catalogue.csv").is_file():
        raise RuntimeError(f"no catalogue after the run of {n_sessions} sessions")
    cpu = _children_cpu_s()
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    _write_year_session(raw, n_sessions)
    add_log = workdir / f"cpu_s{n_sessions}_add.log"
    add_wall = _snakemake_wall_s(raw, results, f"{n_sessions} sessions + 1", env=_cpu_env(add_log))
    return wall, peak, cpu, job_cpu(cpu_log), add_wall, _children_cpu_s() - cpu, job_cpu(add_log)


def job_cpu(cpu_log: Path) -> dict:
    """Rule -> [jobs, CPU seconds, largest peak RSS MB] from the lines of bench/cpu_hook
    ("snakemake" is Snakemake's own main process; a job's script is named tmp<random>.<rule>.py)."""
    out: dict = {}
    if not cpu_log.is_file():
        return out
    for line in cpu_log.read_text(encoding="utf-8").splitlines():
        cpu, mem, command = line.split("\t", 2)
        script = command.split()[0] if command.split() else "?"
        rule = script.rsplit(".", 2)[1] if script.startswith("tmp") and script.count(".") >= 2 else script
        entry = out.setdefault(rule, [0, 0.0, 0.0])
        entry[0] += 1
        entry[1] = round(entry[1] + float(cpu), 3)
        entry[2] = max(entry[2], float(mem))
    return out


def _run_sessions_isolated(n_sessions: int, workdir: Path) -> tuple:
    code = (
        "import sys, json; sys.path.insert(0, %r); import run; "
        "print(json.dumps(run._run_sessions(%d, run.Path(%r))))"
        % (str(Path(__file__).parent), n_sessions, str(workdir))
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-3000:])
    return tuple(json.loads(out.stdout.strip().splitlines()[-1]))


def bench_sessions(counts) -> dict:
    """Many small sessions: measured wall time for each count, extrapolated to 100 sessions."""
    out = {}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="ballimpact-bench-sessions-") as tmp:
        measured = {k: _run_sessions_isolated(k, Path(tmp)) for k in counts}
    for k, (wall, mem, cpu, jobs, add_wall, add_cpu, add_jobs) in measured.items():
        out[f"sessions_{k}x{IMPACTS_PER_SESSION}_seconds"] = wall
        out[f"sessions_{k}x{IMPACTS_PER_SESSION}_cpu_seconds"] = cpu
        out[f"sessions_{k}x{IMPACTS_PER_SESSION}_job_cpu"] = jobs
        out[f"sessions_add_one_to_{k}_seconds"] = add_wall
        out[f"sessions_add_one_to_{k}_cpu_seconds"] = add_cpu
        out[f"sessions_add_one_to_{k}_job_cpu"] = add_jobs
    ks = list(measured)
    # one session added to an archive of k: its own jobs do not grow with k, Snakemake's main
    # process and the catalogue do; the line through the measured k, at 100
    for what, i in (("seconds", 4), ("cpu_seconds", 5)):
        at100, slope, _, resid = extrapolate_linear(ks, [measured[k][i] for k in ks], TARGET_SESSIONS)
        out[f"sessions_add_one_to_{TARGET_SESSIONS}_{what}"] = at100
        out[f"sessions_add_one_{what}_per_archived_session"] = slope
        out[f"sessions_add_one_{what}_fit_max_residual"] = resid
    t100, slope, intercept, resid = extrapolate_linear(ks, [measured[k][0] for k in ks], TARGET_SESSIONS)
    out[f"sessions_{TARGET_SESSIONS}x{IMPACTS_PER_SESSION}_seconds"] = t100
    out["sessions_seconds_per_session"] = slope
    out["sessions_fixed_seconds"] = intercept
    out["sessions_fit_max_residual_s"] = resid
    out["sessions_measured_counts"] = ks
    # CPU time (user + sys of every process of the run) hardly depends on what else the
    # machine runs; on an otherwise idle machine with 2 cores the wall time is at least half of it
    cpu100, cpu_slope, _, cpu_resid = extrapolate_linear(ks, [measured[k][2] for k in ks], TARGET_SESSIONS)
    out["sessions_cpu_seconds_per_session"] = cpu_slope
    out["sessions_cpu_fit_max_residual_s"] = cpu_resid
    out[f"sessions_{TARGET_SESSIONS}x{IMPACTS_PER_SESSION}_cpu_seconds"] = cpu100
    out[f"sessions_{TARGET_SESSIONS}x{IMPACTS_PER_SESSION}_idle_2core_seconds"] = cpu100 / 2
    out["load_average_1min_at_start"] = load_before
    out["load_average_1min_at_end"] = os.getloadavg()[0]
    # wall times only mean something when the 2 cores were ours: no other load, a rising line
    out["sessions_wall_reliable"] = bool(max(load_before, out["load_average_1min_at_end"]) <= 2.5 and slope > 0)
    out["sessions_peak_memory_mb"] = measured[max(ks)][1]
    m100 = extrapolate_linear(ks, [measured[k][1] for k in ks], TARGET_SESSIONS)[0]
    out[f"sessions_{TARGET_SESSIONS}x{IMPACTS_PER_SESSION}_peak_memory_mb"] = max(m100, measured[max(ks)][1])
    # by process (bench/cpu_hook): the per-session jobs each hold one session, so their peak
    # does not grow with the number of sessions; only Snakemake's main process and the
    # catalogue job see every session: their peaks are extrapolated, each by its own line
    jobs = {k: measured[k][3] for k in ks}
    if all(jobs.values()):
        growing = ("snakemake", "catalogue")
        per_session = [v[2] for k in ks for rule, v in jobs[k].items() if rule not in growing]
        peaks = [max(per_session, default=0.0)]
        for rule in growing:
            if all(rule in jobs[k] for k in ks):
                peaks.append(extrapolate_linear(ks, [jobs[k][rule][2] for k in ks], TARGET_SESSIONS)[0])
        out[f"sessions_{TARGET_SESSIONS}x{IMPACTS_PER_SESSION}_peak_memory_mb_by_process"] = max(peaks)
        k = max(ks)
        session_cpu = sum(v[1] for rule, v in jobs[k].items() if rule not in growing)
        out["sessions_job_cpu_seconds_per_session"] = session_cpu / k
        for rule in growing:
            if rule in jobs[k]:
                out[f"sessions_{k}x{IMPACTS_PER_SESSION}_{rule}_cpu_seconds"] = jobs[k][rule][1]
    return out


def bench_session_stages(n_bootstrap: int = 200) -> dict:
    """CPU time [s] of each stage of one 40-impact synthetic session, all in this process.

    ``stage_cpu_seconds_<stage>``: time.process_time around each pipeline function
    (the work of the rule, without the start-up of its process); ``stage_cpu_seconds_imports``:
    importing the library's modules once (what each rule's process pays again).
    """
    t0 = time.process_time()
    from ballimpact import archive, figures, fitting, pipeline, processing, report  # noqa: F401
    from ballimpact.session import read_session
    from ballimpact.synth import SynthConfig, write_session

    out = {"stage_cpu_seconds_imports": time.process_time() - t0}
    with tempfile.TemporaryDirectory(prefix="ballimpact-bench-stages-") as tmp:
        tmp = Path(tmp)
        session, _ = write_session(tmp / "raw" / "stages", SynthConfig(
            session_id="stages", seed=1000, total_impacts=IMPACTS_PER_SESSION, faults_per_kind=1))
        w = tmp / "work"
        w.mkdir()
        balls = list(read_session(session).meta.balls)
        held, images = {}, {}
        stages = [
            ("validate", pipeline.snapshot_session, (session, w / "session.json"), {}),
            ("process", pipeline.process_chunk, (session, 0, 1, w / "chunk_0.nc"), {}),
            ("collect", pipeline.collect_impacts, (session, [w / "chunk_0.nc"], w / "impacts.csv", w / "impacts.nc"), {}),
            ("fit", pipeline.fit_balls, (w / "impacts.nc", balls, session, w / "fits.nc"),
             {"n_bootstrap": n_bootstrap, "seed": 0}),
            ("archive", pipeline.write_archive, (session, w / "impacts.nc", [w / "fits.nc"], w / "a.nc", w / "p.csv"), {}),
            # as rule session_outputs: the archive read once, the figures' pixels handed to the report
            ("figures", lambda *a, **k: pipeline.make_figures(*a, ds=held.setdefault("ds", archive.open_dataset(a[0])),
                                                              images=images, **k), (w / "a.nc", w / "figures"), {}),
            ("report", lambda *a, **k: pipeline.make_report(*a, ds=held["ds"], images=images, **k),
             (w / "a.nc", w / "figures", w / "r.pdf"), {}),
        ]
        for name, func, args, kwargs in stages:
            t0 = time.process_time()
            func(*args, **kwargs)
            out[f"stage_cpu_seconds_{name}"] = time.process_time() - t0
    return out


CATALOGUE_COUNTS = (4, 8, 16, 32)  # sessions in the catalogue for --catalogue


def _session_results(tmp: Path, n_bootstrap: int = 200) -> Path:
    """results/<id>/ (archive and parameters.csv) of one synthetic 40-impact session, by the pipeline functions."""
    from ballimpact import pipeline
    from ballimpact.session import read_session
    from ballimpact.synth import SynthConfig, write_session

    session, _ = write_session(tmp / "raw" / "cat000", SynthConfig(
        session_id="cat000", seed=1000, total_impacts=IMPACTS_PER_SESSION, faults_per_kind=1))
    out = tmp / "results" / "cat000"
    w = out / "work"
    w.mkdir(parents=True)
    pipeline.session_impacts(session, w / "session.json", out / "impacts.csv", w / "impacts.nc")
    pipeline.fit_balls(w / "impacts.nc", list(read_session(session).meta.balls), session, w / "fits.nc",
                       n_bootstrap=n_bootstrap, seed=0)
    pipeline.write_archive(session, w / "impacts.nc", [w / "fits.nc"], out / "cat000.nc", out / "parameters.csv")
    return out


def _run_catalogue(n_sessions: int, results: Path, out: Path) -> tuple[float, float]:
    """CPU time [s] and peak RSS [MB] of write_catalogue over the first n session folders, in this process."""
    from ballimpact.catalogue import write_catalogue

    dirs = sorted(p for p in results.iterdir() if p.is_dir())[:n_sessions]
    out.mkdir(parents=True, exist_ok=True)
    c0 = time.process_time()
    write_catalogue(dirs, out_csv=out / "catalogue.csv", out_nc=out / "catalogue.nc", out_pdf=out / "catalogue.pdf",
                    pools=[], n_bootstrap=200, seed=0)
    return time.process_time() - c0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def bench_catalogue(counts=CATALOGUE_COUNTS) -> dict:
    """Rule catalogue's work (write_catalogue) over k sessions, each in a fresh process.

    The sessions are copies of one synthetic 40-impact session under k names (the
    archive's session_id and date changed), so the change test finds no change:
    the cost of reading k archives, the joint fits of the change tests, the table, the
    netCDF file and the PDF. ``catalogue_cpu_seconds_<k>``, ``catalogue_peak_memory_mb_<k>``
    (largest resident set of that process).
    """
    from ballimpact import archive

    out = {}
    with tempfile.TemporaryDirectory(prefix="ballimpact-bench-catalogue-") as tmp:
        tmp = Path(tmp)
        first = _session_results(tmp)
        ds = archive.open_dataset(first / f"{first.name}.nc")
        for k in range(1, max(counts)):
            sid = f"cat{k:03d}"
            folder = first.parent / sid
            folder.mkdir()
            copy = ds.copy()
            copy.attrs["session_id"] = sid
            copy.attrs["session_date"] = f"2026-{1 + k % 12:02d}-{1 + k // 12:02d}"
            archive.write_dataset(copy, folder / f"{sid}.nc")
            (folder / "parameters.csv").write_bytes((first / "parameters.csv").read_bytes())
        for k in counts:
            code = ("import sys, json; sys.path.insert(0, %r); import run; "
                    "print(json.dumps(run._run_catalogue(%d, run.Path(%r), run.Path(%r))))"
                    % (str(Path(__file__).parent), k, str(first.parent), str(tmp / f"catalogue{k}")))
            proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
            if proc.returncode != 0:
                raise RuntimeError(proc.stderr[-3000:])
            cpu, mem = json.loads(proc.stdout.strip().splitlines()[-1])
            out[f"catalogue_cpu_seconds_{k}"] = cpu
            out[f"catalogue_peak_memory_mb_{k}"] = mem
    ks = list(counts)
    if len(set(ks)) >= 2:  # is it linear? the line through every k, its slope and largest misfit
        for what, unit in (("cpu_seconds", "s"), ("peak_memory_mb", "mb")):
            at100, slope, _, resid = extrapolate_linear(ks, [out[f"catalogue_{what}_{k}"] for k in ks], TARGET_SESSIONS)
            out[f"catalogue_{what}_per_session"] = slope
            out[f"catalogue_{what}_fit_max_residual_{unit}"] = resid
            out[f"catalogue_{what}_{TARGET_SESSIONS}_extrapolated"] = at100
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="ballimpact benchmarks")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--quick", action="store_true", help="smaller runs, same keys (< 1 min)")
    ap.add_argument("--skip-workflow", action="store_true", help="only model and fit figures")
    ap.add_argument("--fit-only", action="store_true",
                    help="only the fit figures (demo and the demo made with synth --no-kb0)")
    ap.add_argument("--model-only", action="store_true",
                    help="only the model figures: throughput by batch size against the C reference, call times, "
                         "compile and cache-load time")
    ap.add_argument("--stages", action="store_true",
                    help="only the CPU time of each stage of one 40-impact session (stage_cpu_seconds_*)")
    ap.add_argument("--sessions-only", action="store_true",
                    help="only the many-sessions figures (sessions_*: 100 sessions x 40 impacts, extrapolated)")
    ap.add_argument("--catalogue", action="store_true",
                    help="only the catalogue job's CPU time and memory at 4, 8, 16 and 32 sessions (catalogue_*)")
    ap.add_argument("--counts", type=int, nargs="+", metavar="K",
                    help="with --sessions-only: the numbers of 40-impact sessions to run (default 2 4 8, --quick 1 3)")
    args = ap.parse_args(argv)

    figures: dict = {"quick": args.quick}
    if args.model_only:
        figures["model_impacts_per_s"] = bench_model(4000 if args.quick else 20000)
        figures.update(bench_model_calls())
        figures.update(bench_model_batches())
        figures.update(bench_model_reference_c(4000 if args.quick else 20000))
        c_rate = figures.get("model_reference_c_impacts_per_s")
        for n in MODEL_BATCH_SIZES:  # against the scalar C loop of the same run
            figures[f"model_vs_c_{n}"] = figures[f"model_impacts_per_s_{n}"] / c_rate if c_rate else None
        figures.update(bench_model_compile())
        print(json.dumps(figures, indent=2) if args.json else "\n".join(f"{k:36s} {v}" for k, v in figures.items()))
        return 0
    if args.stages:
        figures.update(bench_session_stages())
        print(json.dumps(figures, indent=2) if args.json else "\n".join(f"{k:36s} {v}" for k, v in figures.items()))
        return 0
    if args.catalogue:
        figures.update(bench_catalogue())
        print(json.dumps(figures, indent=2) if args.json else "\n".join(f"{k:36s} {v}" for k, v in figures.items()))
        return 0
    if args.counts and (not args.sessions_only or len(set(args.counts)) < 2 or min(args.counts) < 1):
        ap.error("--counts needs --sessions-only and at least two different numbers of sessions >= 1")
    if args.sessions_only:
        figures.update(bench_sessions(tuple(args.counts) if args.counts else
                                      QUICK_SESSION_COUNTS if args.quick else SESSION_COUNTS))
        print(json.dumps(figures, indent=2) if args.json else "\n".join(f"{k:36s} {v}" for k, v in figures.items()))
        return 0
    if not args.fit_only:
        figures["model_impacts_per_s"] = bench_model(4000 if args.quick else 20000)
        figures.update(bench_model_reference_c(4000 if args.quick else 20000))
    figures.update(bench_fit(REPO / "raw" / "demo-2004", n_bootstrap=200))
    figures.update(bench_fit_no_kb0(n_bootstrap=200))
    if not args.skip_workflow and not args.fit_only:
        figures.update(bench_workflow(SIZES, args.quick, figures["process_seconds_per_impact"]))
        figures.update(bench_sessions(QUICK_SESSION_COUNTS if args.quick else SESSION_COUNTS))
    if args.json:
        print(json.dumps(figures, indent=2))
    else:
        for k, v in figures.items():
            print(f"{k:32s} {v:.4g}" if isinstance(v, float) else f"{k:32s} {v}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    sys.exit(main())

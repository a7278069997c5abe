"""Robustness of the per-impact processing over random zoo traces (issue 9): per-factor table of the invariant.

    python bench/robustness.py --n 2000 --seed 0      # the issue's benchmark (2 worker processes)
    python bench/robustness.py --quick                # 100 traces
    python bench/robustness.py --replay 0:17          # one trace in detail, its session folder kept

Each trace (tests/zoo.py) is written as a one-impact raw session and run
through the real ``ballimpact.processing.process_impact``; the result is judged
against the trace's truth per quantity (TC, kCAL, peak): ``ok right``, ``ok WRONG``
(TC or kCAL off by more than 1 %, peak by more than 3 %, 5 % for the
pre-buckling spike), ``withheld right`` (a number withheld that was within its
tolerance: lost) and ``withheld wrong``; and for the impact, ``faulty used`` (a
second contact of >= 5 % of the peak, a truncated contact or clipping used in a
fit). The targets: no quantity ok but wrong, no faulty trace used, and TC ok and
right for >= 98 % of the non-faulty traces on one-factor rigs and >= 85 % on
random combinations with an ideal plate or a plate at 3 kHz or above.

Prints the table, per factor class (a trace counts in every row it belongs to),
the targets' shares, the findings that withheld right numbers, TC withheld by
how many findings withheld it without an estimate of their effect, how honest
the standard uncertainties of the ok quantities are (error over uncertainty),
and the worst offenders with their SEED:INDEX for ``--replay``. Writes
bench/out/robustness-s<SEED>-n<N>.{md,csv} (per trace).
"""

from __future__ import annotations

import single_thread  # noqa: F401  (first: one BLAS thread per process, before numpy)
import argparse
import math
import multiprocessing as mp
import re
import shutil
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import zoo  # noqa: E402
from ballimpact.verdicts import unestimated  # noqa: E402

OUT = ROOT / "bench" / "out"
QUANTITIES = ("tc", "kcal", "peak")
OUTCOMES = ("ok_right", "ok_wrong", "withheld_right", "withheld_wrong")
ROW_ORDER = [
    "all", "mode random", "mode one factor",
    "rate 20-50 kHz", "rate 50-100 kHz", "rate 100-200 kHz",
    "pre 1-10 ms", "pre 10-100 ms", "post < 30 ms", "post 30-300 ms", "post 0.3-1 s",
    "tau 0.01-0.1 s given", "tau 0.01-0.1 s absent", "tau 0.1-1 s given", "tau 0.1-1 s absent",
    "tau 1-100 s given", "tau 1-100 s absent", "tau DC given", "tau DC absent",
    "hum 0, mains given", "hum 0, mains absent", "hum < 5 mV, mains given", "hum < 5 mV, mains absent",
    "hum 5-30 mV, mains given", "hum 5-30 mV, mains absent",
    "plate ideal", "plate < 3 kHz", "plate 3-10 kHz", "plate 10-30 kHz",
    "noise < 1 mV", "noise 1-5 mV", "peak < 2 V", "peak >= 2 V", "polarity -1", "spikes",
    "second none visible", "second < 5 %", "second 5-30 %", "second 30-100 %",
    "truncated", "clipped", "peak = spike", "marginal",
]
_scratch = None


def _init_worker(scratch):
    global _scratch
    _scratch = Path(scratch)


def run_one(args):
    """Make, process and judge trace (seed, index); a plain dict for the table."""
    seed, index = args
    t0 = time.perf_counter()
    tr = zoo.trace_for(seed, index)
    t1 = time.perf_counter()
    c1 = time.process_time()
    result = None
    try:
        result, j = zoo.run_trace(tr, _scratch)
        category, reason, errors, wrong, outcomes = j.category, j.reason, j.errors, j.wrong, j.outcomes
    except Exception as exc:  # a crash of process_impact is itself a finding: never hide it
        category, reason, errors, wrong, outcomes = "crash", f"{type(exc).__name__}: {exc}", {}, [], {}
    return {
        "seed": seed, "index": index, "id": f"{seed}:{index}", "category": category, "reason": reason,
        "tc_err_pct": 100 * errors.get("tc", math.nan), "kcal_err_pct": 100 * errors.get("kcal", math.nan),
        "peak_err_pct": 100 * errors.get("peak", math.nan), "wrong": " ".join(wrong),
        "fault": tr.truth.fault, "marginal": tr.truth.marginal, "measurable": tr.truth.measurable,
        "peak_is_spike": tr.truth.peak_is_spike, "labels": "|".join(zoo.factor_labels(tr.rig, tr.truth)),
        "factors": zoo.describe(tr.rig), "n_samples": tr.voltage_V.size,
        "make_s": t1 - t0, "process_s": time.perf_counter() - t1, "process_cpu_s": time.process_time() - c1,
        "tau_true_s": tr.rig.tau_s, "tau_given": tr.rig.tau_known, "tau_s": getattr(result, "tau_s", math.nan),
        "tau_se_s": getattr(result, "tau_se_s", math.nan), "tau_source": getattr(result, "tau_source", ""),
        "kinds": " ".join(dict.fromkeys(p.kind.value for p in getattr(result, "problems", []))),
        "bandwidth_given": tr.rig.bandwidth_known and tr.rig.bandwidth_hz is not None,
        "peak_note": getattr(result, "peak_note", ""),
        "codes": getattr(result, "reason_code", ""), "status": getattr(result, "status", ""),
        **{f"{q}_outcome": outcomes.get(q, "") for q in QUANTITIES},
        **{f"{q}_u_pct": 100 * _relative_u(result, q) for q in QUANTITIES},
        "tc_unestimated": " ".join(unestimated(getattr(result, "problems", []), "contact_time")),
    }


def _relative_u(result, q: str) -> float:
    """The standard uncertainty the processing gave quantity ``q`` of QUANTITIES, relative to its value [-]."""
    value, u = {"tc": ("contact_time_ms", "contact_time_u_ms"), "kcal": ("kcal_N_per_V", "kcal_u_N_per_V"),
                "peak": ("peak_force_N", "peak_force_u_N")}[q]
    v, uv = getattr(result, value, math.nan), getattr(result, u, math.nan)
    return abs(uv / v) if result is not None and v else math.nan


def time_constants(records):
    """How honest the standard errors of the estimated time constants are, on the ok traces.

    In kappa = 1 / tau [1/s] (the quantity the baseline fit estimates; 0 for a DC-coupled
    rig): z = (kappa - kappa_true) / se(kappa), whose RMS is about 1 for honest standard
    errors, by the true time constant's band.
    """
    bands = defaultdict(list)
    for r in records:
        if not (r["category"].startswith("ok_") and r["tau_source"] == "estimated" and r["tau_se_s"] > 0):
            continue
        true = float(r["tau_true_s"])
        kappa, kappa_true = 1.0 / r["tau_s"], (0.0 if math.isinf(true) else 1.0 / true)
        z = (kappa - kappa_true) / (r["tau_se_s"] / r["tau_s"] ** 2)
        band = "DC" if math.isinf(true) else "0.01-0.1 s" if true < 0.1 else "0.1-1 s" if true < 1 else "1-100 s"
        bands[band].append(z)
    if not bands:
        return ""
    lines = ["", "#### time constants estimated on the ok traces: (kappa - true) / standard error", "",
             "| true time constant | traces | RMS of z | abs(z) > 3 |", "|---|---|---|---|"]
    for band in ("0.01-0.1 s", "0.1-1 s", "1-100 s", "DC"):
        z = bands.get(band)
        if z:
            rms = math.sqrt(sum(v * v for v in z) / len(z))
            lines.append(f"| {band} | {len(z)} | {rms:.2f} | {sum(abs(v) > 3 for v in z)} |")
    return "\n".join(lines)


def table(records):
    """Per-factor counts: {row: {count name: n}} (per quantity ``<q>_<outcome>``, and ``faulty_used``)."""
    rows = defaultdict(lambda: defaultdict(int))
    for r in records:
        for label in r["labels"].split("|"):
            row = rows[label]
            row["n"] += 1
            row["crash"] += r["category"] == "crash"
            row["faulty_used"] += r["category"] == "faulty_ok"
            if r["measurable"]:
                row["measurable"] += 1
                row["used"] += r["status"] == "ok"
                for q in QUANTITIES:
                    row[f"{q}_{r[q + '_outcome']}"] += 1
    order = [k for k in ROW_ORDER if k in rows] + sorted(k for k in rows if k not in ROW_ORDER)
    return order, rows


def markdown(records, title):
    """The per-factor table: non-faulty traces used in a fit, and per quantity ok right / ok WRONG / withheld right."""
    order, rows = table(records)
    head = ["factor class", "n", "faulty used", "non-faulty", "used in fit"]
    head += [f"{q} {o}" for q in QUANTITIES for o in ("ok right", "ok WRONG", "withheld right")]
    crash = sum(r["category"] == "crash" for r in records)
    if crash:
        head.append("crash")
    lines = [f"### {title}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for k in order:
        c = rows[k]
        cells = [k, c["n"], c["faulty_used"], c["measurable"], c["used"]]
        cells += [c[f"{q}_{o}"] for q in QUANTITIES for o in ("ok_right", "ok_wrong", "withheld_right")]
        if crash:
            cells.append(c["crash"])
        lines.append("| " + " | ".join(str(x) for x in cells) + " |")
    return "\n".join(lines)


def _badness(r):
    tol = {"tc_err_pct": 1.0, "kcal_err_pct": 1.0, "peak_err_pct": 5.0 if r["peak_is_spike"] else 3.0}
    vals = [abs(r[k]) / t for k, t in tol.items() if not math.isnan(r[k])]
    return max(vals) if vals else math.inf


def target_class(r) -> str:
    """The class of a non-faulty trace the targets name: one factor, or a random combination on an ideal plate or a
    plate at 3 kHz or above, or on a lower plate."""
    labels = r["labels"].split("|")
    if "mode random" not in labels:
        return "one factor"
    low = "plate < 3 kHz" in labels
    return "random, plate < 3 kHz" if low else "random, ideal plate or >= 3 kHz"


def targets(records):
    """TC ok and right per target class, against its target, and the quantities ok but wrong."""
    goal = {"one factor": 0.98, "random, ideal plate or >= 3 kHz": 0.85, "random, plate < 3 kHz": None}
    cells = defaultdict(lambda: [0, 0])
    for r in records:
        if r["measurable"] and r["category"] != "crash":
            c = cells[target_class(r)]
            c[0] += 1
            c[1] += r["tc_outcome"] == "ok_right"
    lines = ["", "#### TC ok and right, by target class (non-faulty traces)", "",
             "| class | non-faulty | TC ok and right | target |", "|---|---|---|---|"]
    for k, target in goal.items():
        n, ok = cells.get(k, (0, 0))
        if n:
            goal_text = "-" if target is None else f">= {100 * target:.0f} %"
            lines.append(f"| {k} | {n} | {ok} ({100 * ok / n:.1f} %) | {goal_text} |")
    wrong = {q: sum(r[f"{q}_outcome"] == "ok_wrong" for r in records if r["measurable"]) for q in QUANTITIES}
    lines += ["", "ok but wrong: " + ", ".join(f"{q} {n}" for q, n in wrong.items())
              + f"; faulty used in a fit: {sum(r['category'] == 'faulty_ok' for r in records)}"]
    return "\n".join(lines)


def withheld_by_code(records, k):
    """The findings (reason codes) on non-faulty traces whose TC was withheld although right: what the lab loses."""
    codes = defaultdict(int)
    for r in records:
        if r["measurable"] and r["tc_outcome"] == "withheld_right":
            for code in (r["codes"] or "budget").split(";"):
                codes[code] += 1
    if not codes:
        return ""
    lines = ["", "#### TC withheld but right, by the codes of the findings (a trace counts under each of its codes)",
             "", "| code | traces |", "|---|---|"]
    lines += [f"| {c} | {n} |" for c, n in sorted(codes.items(), key=lambda kv: -kv[1])[:k]]
    return "\n".join(lines)


def calibration(records):
    """How honest the standard uncertainties are: on the non-faulty traces whose quantity is ok,
    z = error / standard uncertainty, by target class (about 5 % beyond 2 for an honest normal error)."""
    lines = ["", "#### ok quantities: error / standard uncertainty (honest: about 5 % beyond 2, 1 % beyond 2.6)", "",
             "| class | quantity | ok | median abs(z) | 95th percentile | beyond 2 |", "|---|---|---|---|---|---|"]
    for k in ("one factor", "random, ideal plate or >= 3 kHz", "random, plate < 3 kHz"):
        for q in QUANTITIES:
            z = sorted(abs(r[f"{q}_err_pct"]) / r[f"{q}_u_pct"] for r in records
                       if r["measurable"] and r["category"] != "crash" and target_class(r) == k
                       and r[f"{q}_outcome"].startswith("ok_") and r[f"{q}_u_pct"] > 0)
            if z:
                lines.append(f"| {k} | {q} | {len(z)} | {z[len(z) // 2]:.2f} | {z[int(0.95 * (len(z) - 1))]:.2f} | "
                             f"{100 * sum(v > 2 for v in z) / len(z):.1f} % |")
    return "\n".join(lines)


def withheld_by_vetoes(records):
    """TC withheld on non-faulty traces, by how many findings withheld it without an estimate of their effect (0:
    the budget alone), and whether it was right: what estimating one check's effect better could give back."""
    cells = defaultdict(lambda: defaultdict(int))
    for r in records:
        if r["measurable"] and r["category"] != "crash" and r["tc_outcome"].startswith("withheld"):
            n = len(r["tc_unestimated"].split())
            cells[(target_class(r), r["tc_outcome"])]["0" if n == 0 else "1" if n == 1 else "2+"] += 1
    if not cells:
        return ""
    lines = ["", "#### TC withheld, by the findings that withheld it without an estimate of their effect", "",
             "| class | TC | budget alone | one such finding | two or more |", "|---|---|---|---|---|"]
    for (k, outcome), c in sorted(cells.items()):
        lines.append(f"| {k} | {outcome.replace('_', ' ')} | {c['0']} | {c['1']} | {c['2+']} |")
    return "\n".join(lines)


def offenders(records, k):
    lines = []
    for cat in ("crash", "faulty_ok", "ok_wrong"):
        bad = [r for r in records if r["category"] == cat]
        if not bad:
            continue
        bad.sort(key=_badness, reverse=True)
        lines += ["", f"#### {cat}: {len(bad)} (worst {min(k, len(bad))}; replay with --replay SEED:INDEX)", ""]
        for r in bad[:k]:
            errs = f"TC {r['tc_err_pct']:+.2f} %, kCAL {r['kcal_err_pct']:+.2f} %, peak {r['peak_err_pct']:+.2f} %"
            extra = f" fault: {r['fault']};" if r["fault"] else ""
            extra += f" marginal: {r['marginal']};" if r["marginal"] else ""
            why = f" reason: {r['reason']}" if r["reason"] else ""
            lines.append(f"- `{r['id']}` {errs};{extra}{why}\n  {r['factors']}")
    return "\n".join(lines)


def replay(spec: str):
    seed, index = (int(x) for x in spec.split(":"))
    tr = zoo.trace_for(seed, index)
    folder = OUT / f"replay-{seed}-{index}"
    if folder.exists():
        shutil.rmtree(folder)
    zoo.write_session_folder(tr, folder, trace_format="csv")
    scratch = Path(tempfile.mkdtemp(prefix="zoo-replay-"))
    try:
        result, j = zoo.run_trace(tr, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    t = tr.truth
    print(f"trace {spec}: {zoo.describe(tr.rig)}")
    print(f"  rig: {tr.rig}")
    print(f"  truth: TC {t.tc_s * 1e3:.4f} ms, kCAL {t.kcal_N_per_V:.3f} N/V, peak {t.peak_N:.1f} N"
          f"{' (pre-buckling spike)' if t.peak_is_spike else ''}, vin {t.vin_m_s:.3f}, vout {t.vout_m_s:.3f} m/s, "
          f"contact {t.start_s * 1e3:.3f}-{t.end_s * 1e3:.3f} ms of {tr.voltage_V.size} samples, "
          f"measurable {t.measurable}, fault {t.fault!r}, marginal {t.marginal!r}, second {t.second_fraction:.3f}")
    print(f"  result: {result.status} {result.reason!r}: TC {result.contact_time_ms:.4f} ms, "
          f"kCAL {result.kcal_N_per_V:.3f} N/V, peak {result.peak_force_N:.1f} N, tau {result.tau_s:.4g} s, "
          f"hum {result.hum_amplitude_V:.4g} V, noise {result.noise_rms_V:.3g} V, plate undone "
          + (f"{result.plate_resonance_hz:.0f} Hz (damping {result.plate_damping_ratio:.3f})"
             if math.isfinite(result.plate_resonance_hz) else "none"))
    print(f"  judged: {j.category}; errors " + ", ".join(f"{k} {100 * v:+.3f} %" for k, v in j.errors.items())
          + "; " + ", ".join(f"{k} {v}" for k, v in j.outcomes.items()) + f"; codes {result.reason_code!r}")
    print(f"  session folder written to {folder.relative_to(ROOT)}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000, help="number of zoo traces")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="100 traces")
    ap.add_argument("--worst", type=int, default=15, help="offenders listed per category")
    ap.add_argument("--replay", metavar="SEED:INDEX", help="run one trace and show everything about it")
    ap.add_argument("--label", default="", help="title of the table (e.g. the branch measured)")
    args = ap.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    if args.replay:
        replay(args.replay)
        return
    n = 100 if args.quick else args.n
    t0 = time.perf_counter()
    jobs = [(args.seed, i) for i in range(n)]
    scratch = tempfile.mkdtemp(prefix="zoo-bench-")
    try:
        if args.workers > 1:
            with mp.get_context("fork").Pool(args.workers, initializer=_init_worker, initargs=(scratch,)) as pool:
                records = list(pool.imap_unordered(run_one, jobs, chunksize=4))
        else:
            _init_worker(scratch)
            records = [run_one(j) for j in jobs]
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    records.sort(key=lambda r: r["index"])
    wall = time.perf_counter() - t0
    title = (f"{args.label + ': ' if args.label else ''}{n} zoo traces, seed {args.seed} "
             f"(`python bench/robustness.py --n {n} --seed {args.seed}`)")
    summary = (f"crashes {sum(r['category'] == 'crash' for r in records)}; {wall:.0f} s wall with {args.workers} "
               f"workers, process_impact {sum(r['process_s'] for r in records) / n * 1e3:.0f} ms per trace on "
               f"average ({sum(r['process_cpu_s'] for r in records) / n * 1e3:.0f} ms CPU)")
    text = (markdown(records, title) + "\n" + targets(records) + "\n\n" + summary + "\n"
            + withheld_by_code(records, args.worst) + "\n" + withheld_by_vetoes(records) + "\n"
            + calibration(records) + "\n" + time_constants(records) + "\n"
            + offenders(records, args.worst) + "\n")
    print(text)
    stem = OUT / f"robustness-s{args.seed}-n{n}"
    stem.with_suffix(".md").write_text(text, encoding="utf-8")
    import csv

    with open(stem.with_suffix(".csv"), "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(records[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(records)
    print(f"written: {stem.with_suffix('.md').relative_to(ROOT)}, {stem.with_suffix('.csv').relative_to(ROOT)}")


if __name__ == "__main__":
    main()

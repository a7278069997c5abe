"""Coverage of the fitted parameters' 95 % intervals on model-generated data.

For each seed and ball type (Table 2 and a ball unlike Table 2): 10 impacts at random
speeds in 14-30 m/s (``--vmin`` to change the lowest speed) simulated with known
parameters, measurement noise added (TC 0.4 % relative, COR 0.003 absolute, the
scatter our processing leaves on synthetic sessions), optionally one planted outlier
per ball type (``--outlier``: TC +15 %, COR -6 % or inbound speed +4 %, in turn by
seed), then fitted with ``fit_ball_model`` (intervals only, no bootstrap). Counts how
often the true AK, a, AC, kB(20 mm) (and kB(0) when estimated) lie inside the reported
intervals, the median relative interval width, how often the planted outlier was named
and how many good impacts were removed (sessions of the four Table 2 balls with no
removal at all).

    python bench/coverage.py --seeds 100 --kb0 config|extrapolated|both --outlier no|yes|both \
        [--jsonl bench/out/records.jsonl] [--json]
    python bench/coverage.py --summarise bench/out/*.jsonl     # table from stored records
    python bench/coverage.py --noise-free [--vmin 5]           # kB(0) on noise-free impacts
    python bench/coverage.py --calibration-check [--refits 1000]  # the critical values themselves
    python bench/coverage.py --truth-world --seeds 12 [--sessions 400] [--first-seed 0]  # many sessions
    python bench/coverage.py --diagnose --seeds 20 [--first-seed 0]  # where kB(0)-fixed misses come from
    python bench/coverage.py --truth-stat --seeds 100 [--first-seed 0] --jsonl bench/out/ts.jsonl  # same sessions
    python bench/coverage.py --lr-check --seeds 12 [--sessions 400]  # likelihood ratio at the truth

With ``--jsonl`` every fit is appended as one record as soon as it is done, so a long
run can be stopped and summarised at any time.
"""

from __future__ import annotations

if __name__ == "coverage":
    # imported as the coverage package: a script run from bench/ has bench/ first on sys.path,
    # and numba (the compiled model loop) tries `import coverage`; this file is not that package
    raise ImportError("bench/coverage.py is a script, not the coverage package")

import argparse
import json
import time
import warnings

import numpy as np

from ballimpact.balls import BALLS, BallModelParameters
from ballimpact.fitting import FitError, fit_ball_model
from ballimpact.model import simulate_impact

UNLIKE_TABLE2 = BallModelParameters.from_table_units(58.0, 30.0, 40_000, 1.9, 2.5)
KINDS = ("tc+15%", "cor-6%", "vin+4%")
#: The bench's parameter sets: the four Table 2 balls and one unlike them.
PARAMETER_SETS = {k: b.params for k, b in BALLS.items()} | {"unlike_table2": UNLIKE_TABLE2}


def session(p, rng, n_impacts=10, vmin=14.0, vmax=30.0, tc_noise=0.004, cor_noise=0.003, outlier=None):
    """Impacts (vin, tc, cor) of one ball type; ``outlier`` plants one bad impact (index returned)."""
    vin = np.sort(rng.uniform(vmin, vmax, n_impacts))
    s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    tc = s.contact_time_s * (1 + tc_noise * rng.standard_normal(n_impacts))
    e = s.cor + cor_noise * rng.standard_normal(n_impacts)
    bad = None
    if outlier is not None:
        bad = int(rng.integers(n_impacts))
        if outlier == "tc+15%":
            tc[bad] *= 1.15
        elif outlier == "cor-6%":
            e[bad] *= 0.94
        else:  # the gates read the inbound speed 4 % high: vin up, COR = vout / vin down
            vin[bad] *= 1.04
            e[bad] /= 1.04
    return vin, tc, e, bad


def bench_sessions(seeds, first=0):
    """The bench's default sessions (10 impacts at 14-30 m/s, no outlier) of seeds
    ``first`` .. ``first + seeds - 1``, each ball type of :data:`PARAMETER_SETS` in turn
    from one generator per seed (so seed s draws the same impacts in every mode):
    (seed, ball key, parameters, vin [m/s], tc [s], cor [-])."""
    for seed in range(first, first + seeds):
        rng = np.random.default_rng(1000 + seed)
        for key, p in PARAMETER_SETS.items():
            vin, tc, e, _ = session(p, rng)
            yield seed, key, p, vin, tc, e


def fit_one(key, p, seed, kb0_mode, outlier, rng, vmin=14.0, n_impacts=10):
    """One ball type of one seed: a record of hits, widths and removals."""
    kind = KINDS[seed % 3] if outlier else None
    vin, tc, e, bad = session(p, rng, n_impacts, vmin=vmin, outlier=kind)
    names = ["ak", "a", "ac", "kb_20mm"] + (["kb0"] if kb0_mode == "extrapolated" else [])
    rec = {"seed": seed, "ball": key, "kb0": kb0_mode, "outlier": bool(outlier), "kind": kind}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            f = fit_ball_model(vin, tc, e, p.mass_kg, n_bootstrap=0, seed=seed,
                               kb0_N_m=p.kb0_N_m if kb0_mode == "config" else None)
    except FitError as exc:
        rec["fail"] = str(exc)
        return rec
    removed = [int(i) for i in np.flatnonzero(~f.used)]
    rec["planted_named"] = bad in removed if bad is not None else None
    rec["false_removed"] = int(sum(i != bad for i in removed))
    rec["n"] = int(vin.size)
    rec["bad"] = bad
    rec["esd_steps"] = [[int(i), float(pv)] for i, pv in f.outlier_steps]
    truth = {"ak": p.ak, "a": p.a, "ac": p.ac, "kb0": p.kb0_N_m, "kb_20mm": p.kb0_N_m + p.ak * 0.020**p.a}
    rec["hit"] = {nm: bool(getattr(f, f"{nm}_lo") <= truth[nm] <= getattr(f, f"{nm}_hi")) for nm in names}
    rec["width"] = {nm: float((getattr(f, f"{nm}_hi") - getattr(f, f"{nm}_lo")) / truth[nm]) for nm in names}
    # everything needed to judge another interval rule offline: truth, estimate, reported interval
    rec["truth"] = {nm: float(truth[nm]) for nm in names}
    rec["estimate"] = {nm: float(getattr(f, nm if nm in ("ak", "a", "ac") else f"{nm}_N_m")) for nm in names}
    rec["interval"] = {nm: [float(getattr(f, f"{nm}_lo")), float(getattr(f, f"{nm}_hi"))] for nm in names}
    if f.free_kb0_intervals:  # kB(0) extrapolated: the fit with kB(0) free alone, one half of the hull
        rec["hit_free"] = {nm: bool(f.free_kb0_intervals[nm][0] <= truth[nm] <= f.free_kb0_intervals[nm][1])
                           for nm in names}
        rec["interval_free"] = {nm: [float(v) for v in f.free_kb0_intervals[nm]] for nm in names}
    return rec


def _append(jsonl, rec):
    """Append one record to the jsonl file ``jsonl`` (nothing when None)."""
    if jsonl:
        with open(jsonl, "a") as fh:
            fh.write(json.dumps(rec) + "\n")


def run(seeds: int, modes, vmin: float = 14.0, n_impacts: int = 10, first_seed: int = 0, jsonl=None):
    """Records of every (seed, mode, ball type); modes: list of (kb0_mode, outlier)."""
    records = []
    for seed in range(first_seed, first_seed + seeds):
        for kb0_mode, outlier in modes:
            rng = np.random.default_rng(1000 + seed)
            for key, p in PARAMETER_SETS.items():
                rec = fit_one(key, p, seed, kb0_mode, outlier, rng, vmin=vmin, n_impacts=n_impacts)
                records.append(rec)
                _append(jsonl, rec)
    return records


def summarise(records):
    """Coverage per (mode, ball type, quantity), pooled, median widths, outlier figures.
    A fit recorded twice (the same seed, ball type and mode in two runs) counts once."""
    records = list({(r["seed"], r["ball"], r["kb0"], r["outlier"]): r for r in records}.values())
    out = {}
    for kb0_mode, outlier in sorted({(r["kb0"], r["outlier"]) for r in records}):
        rs = [r for r in records if r["kb0"] == kb0_mode and r["outlier"] == outlier and "hit" in r]
        seeds = sorted({r["seed"] for r in rs})
        balls = list(dict.fromkeys(r["ball"] for r in rs))
        names = list(rs[0]["hit"]) if rs else []
        cov = {b: {nm: float(np.mean([r["hit"][nm] for r in rs if r["ball"] == b])) for nm in names} for b in balls}
        pooled = {nm: float(np.mean([r["hit"][nm] for r in rs])) for nm in names}
        # the fits in which the outlier search left out no good impact (what it costs the coverage)
        kept = [r for r in rs if r.get("false_removed", 0) == 0]
        pooled_kept = {nm: float(np.mean([r["hit"][nm] for r in kept])) for nm in names} if kept else None
        width = {nm: float(np.median([r["width"][nm] for r in rs])) for nm in names}
        free = [r for r in rs if "hit_free" in r]
        pooled_free = {nm: float(np.mean([r["hit_free"][nm] for r in free])) for nm in names} if free else None
        # the smallest interval that holds the reported (straight-line) estimate and the free-kB(0) profile
        # interval: what a rule that keeps the paper's estimate could at best report
        free_est = [r for r in free if "interval_free" in r]
        pooled_free_est = {nm: float(np.mean([min(r["interval_free"][nm][0], r["estimate"][nm]) <= r["truth"][nm]
                                              <= max(r["interval_free"][nm][1], r["estimate"][nm]) for r in free_est]))
                           for nm in names} if free_est else None
        clean = []
        for s in seeds:
            t2 = [r for r in rs if r["seed"] == s and r["ball"] in BALLS]
            clean.append(all(r["false_removed"] == 0 for r in t2))
        named = [r["planted_named"] for r in rs if r["planted_named"] is not None]
        by_kind = {k: float(np.mean([r["planted_named"] for r in rs if r["kind"] == k])) for k in KINDS
                   if any(r["kind"] == k for r in rs)}
        out[f"kb0 {kb0_mode}, {'one outlier per ball' if outlier else 'no outlier'}"] = {
            "seeds": len(seeds), "fits": len(rs),
            "failures": sum(1 for r in records if r["kb0"] == kb0_mode and r["outlier"] == outlier and "fail" in r),
            "coverage": cov, "pooled_coverage": pooled, "median_relative_width": width,
            "fits_without_false_removal": len(kept), "pooled_coverage_without_false_removal": pooled_kept,
            "pooled_coverage_kb0_free_alone": pooled_free,
            "pooled_coverage_kb0_free_and_estimate": pooled_free_est,
            "sessions_without_false_removal": float(np.mean(clean)) if clean else float("nan"),
            "good_impacts_removed_per_fit": float(np.mean([r["false_removed"] for r in rs])) if rs else float("nan"),
            "planted_outlier_named": float(np.mean(named)) if named else None,
            "planted_outlier_named_by_kind": by_kind or None,
        }
    return out


def noise_free(vmin=14.0, vmax=30.0, n_impacts=10):
    """kB(0) on noise-free model impacts (evenly spaced speeds): the straight line, the
    quadratic, the reported interval and kB(20 mm), per Table 2 ball."""
    rows = []
    for key, b in BALLS.items():
        p = b.params
        vin = np.linspace(vmin, vmax, n_impacts)
        s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            f = fit_ball_model(vin, s.contact_time_s, s.cor, p.mass_kg, n_bootstrap=0)
        kb20 = p.kb0_N_m + p.ak * 0.020**p.a
        rows.append({
            "ball": key, "kb0_source": f.kb0_source, "true_kb0_kN_m": p.kb0_N_m / 1e3,
            "kb0_kN_m": f.kb0_N_m / 1e3, "kb0_error_pct": 100 * (f.kb0_N_m / p.kb0_N_m - 1),
            "linear_error_pct": 100 * (f.kb0_linear_N_m / p.kb0_N_m - 1),
            "quadratic_error_pct": 100 * (f.kb0_quadratic_N_m / p.kb0_N_m - 1),
            "kb0_lo_kN_m": f.kb0_lo / 1e3, "kb0_hi_kN_m": f.kb0_hi / 1e3,
            "kb0_inside": bool(f.kb0_lo <= p.kb0_N_m <= f.kb0_hi),
            "kb_20mm_error_pct": 100 * (f.kb_20mm_N_m / kb20 - 1),
            "kb_20mm_inside": bool(f.kb_20mm_lo <= kb20 <= f.kb_20mm_hi),
        })
        if f.free_kb0_intervals:  # the fit with kB(0) free alone (one half of the hull)
            lo, hi = f.free_kb0_intervals["kb0"]
            rows[-1].update(kb0_free_lo_kN_m=lo / 1e3, kb0_free_hi_kN_m=hi / 1e3,
                            kb0_free_inside=bool(lo <= p.kb0_N_m <= hi))
    return rows


def calibration_check(refits=1000, seed=0):
    """The profile intervals' critical values on one session per ball type (10 impacts at
    14-30 m/s, seed ``seed``, sessions fitted at the true parameters with the true scatter
    TC 0.4 %, COR 0.5 % relative): the F(1, nu) quantile (nu Satterthwaite's), the
    calibrated value of ``fit_ball_model`` (sessions fitted in the linearised model) and
    the same corrected by ``refits`` sessions refitted with the full model (its ratio to
    the linearised one shows how much the model's curvature matters). Then ``refits``
    sessions at the true parameters with the bench's noise (TC 0.4 %, COR 0.003 absolute)
    and with COR noise 0.5 % relative instead, each fitted like the data (full model): how
    often the statistic at the truth stays below each critical value (the coverage of the
    intervals in their Wald form, without the profile grid; +-0.007 at 1000 sessions)."""
    from scipy import stats

    from ballimpact import fitting as F

    rows = []
    for key, p in PARAMETER_SETS.items():
        rng = np.random.default_rng(1000 + seed)
        vin = np.sort(rng.uniform(14.0, 30.0, 10))
        mass = np.full(vin.size, p.mass_kg)
        s = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
        theta = F._to_theta(p.ak, p.a, p.ac)
        args = (vin, s.contact_time_s, s.cor, mass, p.kb0_N_m, theta, 0.004, 0.005, 0.95)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lin = F._calibrated_critical_values(*args, n_sim=0)
            full = F._calibrated_critical_values(*args, n_sim=refits)
            fun = lambda pts: F._residuals(pts, vin, s.contact_time_s, s.cor, mass, p.kb0_N_m, 0.004, 0.005)  # noqa: E731
            jac = F._jacobian(fun, theta)
            cov = np.linalg.pinv(jac.T @ jac)
            h = np.einsum("ij,jk,ik->i", jac, cov, jac)
            dof_tc, dof_cor = vin.size - h[: vin.size].sum(), vin.size - h[vin.size:].sum()
            z = np.random.default_rng(2000 + seed).standard_normal((2, refits, vin.size))
            tc_b = s.contact_time_s * (1 + 0.004 * z[0])
            cor_noise = {"absolute": s.cor + 0.003 * z[1], "relative": s.cor * (1 + 0.005 * z[1])}
            jac_raw = F._jacobian(lambda pts: F._residuals(pts, vin, s.contact_time_s, s.cor, mass, p.kb0_N_m,
                                                           1.0, 1.0), theta)
            truth_world = {}
            for kind, cor_b in cor_noise.items():
                th_b, conv, cov_b = F._refit_sessions(vin, mass, p.kb0_N_m, theta, tc_b, cor_b, 0.004, 0.005, jac_raw)
                truth_world[kind] = (th_b[conv], cov_b)
        for spec in F._quantities(3, p.kb0_N_m):
            grad = F._quantity_gradient(spec, theta)
            nu = F._satterthwaite_dof(grad, jac, vin.size, dof_tc, dof_cor)
            row = {"ball": key, "quantity": spec.key, "f_quantile": float(stats.f.ppf(0.95, 1, nu)),
                   "satterthwaite_nu": nu, "calibrated": lin[spec.key], "with_refits": full[spec.key],
                   "refit_ratio": full[spec.key] / lin[spec.key]}
            for kind, (th_b, cov_b) in truth_world.items():
                stat = (spec.fwd(th_b) - spec.fwd(theta)) ** 2 / np.einsum("p,bpq,q->b", grad, cov_b, grad)
                row[f"coverage_f_{kind}"] = float(np.mean(stat <= row["f_quantile"]))
                row[f"coverage_calibrated_{kind}"] = float(np.mean(stat <= row["calibrated"]))
            rows.append(row)
    return rows


def _truth_setup(p, vin):
    """What the truth-world modes need of one design at the true parameters ``p``: (mass [kg] per impact,
    the noise-free simulation, theta, the COR scatter relative to its mean [-], the calibrated critical
    values at TC 0.4 % and that COR scatter, the Jacobian of the unit-weight residuals at theta)."""
    from ballimpact import fitting as F

    mass = np.full(vin.size, p.mass_kg)
    st = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
    theta = F._to_theta(p.ak, p.a, p.ac)
    s_cor = 0.003 / float(np.mean(st.cor))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        crit = F._calibrated_critical_values(vin, st.contact_time_s, st.cor, mass, p.kb0_N_m, theta, 0.004,
                                             s_cor, 0.95)
        jac_raw = F._jacobian(lambda pts: F._residuals(pts, vin, st.contact_time_s, st.cor, mass, p.kb0_N_m,
                                                       1.0, 1.0), theta)
    return mass, st, theta, s_cor, crit, jac_raw


def truth_world(designs=12, sessions=400, first=0):
    """Coverage of the calibrated intervals in their Wald form, precisely: for each ball type
    and each of the bench's designs (the inbound speeds of seeds first .. first+designs-1), the
    critical values of ``fit_ball_model`` at the true parameters with the true scatter
    (TC 0.4 %, COR 0.003 / mean COR), then ``sessions`` sessions with the bench's noise
    (COR 0.003 absolute) and with COR noise of that size relative instead, each fitted
    like the data with the full model (``_refit_sessions``); how often the statistic at the
    truth stays below the critical value. Pooled per ball type and quantity: {ball:
    {kind: {quantity: coverage}}}, +-0.005 at 12 x 400 sessions."""
    from ballimpact import fitting as F

    hits = {key: {"absolute": {}, "relative": {}} for key in PARAMETER_SETS}
    for seed, key, p, vin, _, _ in bench_sessions(designs, first):
        mass, s, theta, s_cor, crit, jac_raw = _truth_setup(p, vin)
        z = np.random.default_rng(seed).standard_normal((2, sessions, vin.size))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for kind, cor_b in (("absolute", s.cor + 0.003 * z[1]), ("relative", s.cor * (1 + s_cor * z[1]))):
                th_b, conv, cov_b = F._refit_sessions(vin, mass, p.kb0_N_m, theta,
                                                      s.contact_time_s * (1 + 0.004 * z[0]), cor_b, 0.004, s_cor,
                                                      jac_raw)
                for spec in F._quantities(3, p.kb0_N_m):
                    g = F._quantity_gradient(spec, theta)
                    stat = (spec.fwd(th_b[conv]) - spec.fwd(theta)) ** 2 / np.einsum("p,bpq,q->b", g, cov_b, g)
                    hits[key][kind].setdefault(spec.key, []).extend((stat <= crit[spec.key]).tolist())
    return {key: {kind: {q: float(np.mean(v)) for q, v in d.items()} for kind, d in k.items()}
            for key, k in hits.items()}


def truth_stat(seeds=100, first=0, jsonl=None):
    """The ``--truth-world`` statistic on the bench's own sessions (``--kb0 config --outlier
    no``, the same seeds draw the same impacts): per fit, the sessions refitted like the data
    (``_refit_sessions``), the Wald statistic at the truth against the critical value at the
    truth. No profile grid, no plug-in, no outlier search; about 0.5 s per fit. Paired with
    the bench's records of the same seeds by ``--summarise`` (both record kinds in one call),
    it shows whether a shortfall of the bench comes from the intervals or from its sessions.
    Records: {seed, ball, kb0: "truth-stat", hit_truth_stat: {quantity: bool}}."""
    from ballimpact import fitting as F

    records = []
    for seed, key, p, vin, tc, e in bench_sessions(seeds, first):
        mass, st, th0, s_cor, crit, jac_raw = _truth_setup(p, vin)
        rec = {"seed": seed, "ball": key, "kb0": "truth-stat", "outlier": False}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            th_b, conv, cov_b = F._refit_sessions(vin, mass, p.kb0_N_m, th0, tc[None], e[None], 0.004, s_cor,
                                                  jac_raw)
        if not conv[0]:
            rec["fail"] = "refit did not converge"
        else:
            rec["hit_truth_stat"] = {}
            for spec in F._quantities(3, p.kb0_N_m):
                g = F._quantity_gradient(spec, th0)
                stat = float((spec.fwd(th_b[0]) - spec.fwd(th0)) ** 2 / (g @ cov_b[0] @ g))
                rec["hit_truth_stat"][spec.key] = bool(stat <= crit[spec.key])
        records.append(rec)
        _append(jsonl, rec)
    return records


def summarise_truth_stat(records):
    """Coverage of ``--truth-stat`` records, pooled and per ball type, and paired with the
    bench's kB(0)-fixed, no-outlier records of the same (seed, ball type) when given:
    {"fits", "seeds", "pooled", "per_ball", "paired": {quantity: {fits, interval, statistic,
    only_interval, only_statistic}}}."""
    ts = {(r["seed"], r["ball"]): r for r in records if r.get("kb0") == "truth-stat" and "hit_truth_stat" in r}
    bench = {(r["seed"], r["ball"]): r for r in records
             if r.get("kb0") == "config" and not r.get("outlier") and "hit" in r}
    rs = list(ts.values())
    names = list(rs[0]["hit_truth_stat"]) if rs else []
    out = {"fits": len(rs), "seeds": len({r["seed"] for r in rs}),
           "pooled": {q: float(np.mean([r["hit_truth_stat"][q] for r in rs])) for q in names},
           "per_ball": {b: {q: float(np.mean([r["hit_truth_stat"][q] for r in rs if r["ball"] == b])) for q in names}
                        for b in dict.fromkeys(r["ball"] for r in rs)}, "paired": {}}
    both = [k for k in ts if k in bench]
    for q in names:
        if not both or q not in bench[both[0]]["hit"]:
            continue
        a = np.array([ts[k]["hit_truth_stat"][q] for k in both])
        b = np.array([bench[k]["hit"][q] for k in both])
        out["paired"][q] = {"fits": len(both), "interval": float(b.mean()), "statistic": float(a.mean()),
                            "only_interval": int(np.sum(b & ~a)), "only_statistic": int(np.sum(a & ~b))}
    return out


def lr_check(designs=4, sessions=500, first=0):
    """Hypotheses (a) and (b) for the kB(0)-fixed intervals: is the statistic the intervals
    use, the profile deviance (likelihood ratio), distributed at the truth like the
    linearised statistic their critical value is calibrated with? For each ball type and
    each of the bench's designs first .. first+designs-1: ``sessions`` sessions simulated at
    the true parameters with the bench's noise (TC 0.4 % relative, COR 0.003 absolute), each fitted with the
    full model like the data (``_refit_sessions``), then its profile deviance at the true
    value of every quantity (the other parameters refitted with the full model, batched
    Levenberg-Marquardt); the critical value is ``fit_ball_model``'s at the truth. Pooled
    per quantity: coverage (deviance <= critical value), the 0.95 quantile of deviance /
    critical value (<= 1 is calibrated), and the mean and standard deviation of the signed
    root sign(q_b - q) sqrt(deviance) (0 and 1 without bias)."""
    from ballimpact import fitting as F

    acc = {}
    for seed, key, p, vin, _, _ in bench_sessions(designs, first):
        n = vin.size
        mass, st, th0, s_cor, crit, jac_raw = _truth_setup(p, vin)
        z = np.random.default_rng(5000 + seed).standard_normal((2, sessions, n))
        tc_b, cor_b = st.contact_time_s * (1 + 0.004 * z[0]), st.cor + 0.003 * z[1]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            th_b, conv, _ = F._refit_sessions(vin, mass, p.kb0_N_m, th0, tc_b, cor_b, 0.004, s_cor, jac_raw)
            # each session's scatter at its estimate, as the data's profile uses it
            tcm, corm = F._simulate(th_b, vin, mass, p.kb0_N_m)
            w = np.concatenate([np.full(n, 0.004**-2), np.full(n, s_cor**-2)])
            cov = np.linalg.pinv(jac_raw.T @ (jac_raw * w[:, None]))
            h = np.einsum("ip,pq,iq,i->i", jac_raw, cov, jac_raw, w)
            s_tc = np.sqrt(np.sum(((tcm - tc_b) / tc_b) ** 2, 1) / (n - h[:n].sum()))[:, None]
            s_co = np.sqrt(np.sum(((corm - cor_b) / cor_b) ** 2, 1) / (n - h[n:].sum()))[:, None]
            specs = F._quantities(3, p.kb0_N_m)
            q_of_row = np.repeat(np.arange(len(specs)), sessions)
            sess = np.tile(np.arange(sessions), len(specs))
            keeps = [[i for i in range(3) if i != s.drop] for s in specs]
            lo_b, hi_b = F._full_bounds(3)

            def to_theta(pts, rows):
                out = np.empty(pts.shape[:-1] + (3,))
                for j, spec in enumerate(specs):
                    sel = np.flatnonzero(q_of_row[rows] == j)
                    th = np.zeros(pts.shape[:-2] + (sel.size, 3))
                    th[..., keeps[j]] = pts[..., sel, :]
                    th[..., spec.drop] = spec.inv(float(spec.fwd(th0)), th)
                    out[..., sel, :] = th
                return out

            def resid(pts, rows):
                r = sess[rows]
                return F._residuals(to_theta(pts, rows), vin, tc_b[r], cor_b[r], mass, p.kb0_N_m, s_tc[r], s_co[r])

            p0 = np.concatenate([th_b[:, k] for k in keeps])
            lo = np.concatenate([np.broadcast_to(lo_b[k], (sessions, 2)) for k in keeps])
            hi = np.concatenate([np.broadcast_to(hi_b[k], (sessions, 2)) for k in keeps])
            pc, okc = F._batched_lm(resid, p0, lo, hi, max_iter=50)
            s_min = np.sum(F._residuals(th_b, vin, tc_b, cor_b, mass, p.kb0_N_m, s_tc, s_co) ** 2, axis=1)
            dev = np.sum(resid(pc[None], np.arange(pc.shape[0]))[0] ** 2, axis=1).reshape(len(specs), sessions)
            dev = dev - s_min
            ok = conv & okc.reshape(len(specs), sessions).all(axis=0)
        for j, spec in enumerate(specs):
            d = np.maximum(dev[j][ok], 0.0)
            sign = np.sign(spec.fwd(th_b[ok]) - spec.fwd(th0))
            a = acc.setdefault(spec.key, {"ratio": [], "root": [], "ball": []})
            a["ratio"].extend((d / crit[spec.key]).tolist())
            a["root"].extend((sign * np.sqrt(d)).tolist())
            a["ball"].extend([key] * d.size)
    return {q: {"sessions": len(a["ratio"]), "coverage": float(np.mean(np.array(a["ratio"]) <= 1.0)),
                "per_ball": {b: float(np.mean(np.array(a["ratio"])[np.array(a["ball"]) == b] <= 1.0))
                             for b in dict.fromkeys(a["ball"])},
                "q95_deviance_over_critical": float(np.quantile(a["ratio"], 0.95)),
                "signed_root_mean": float(np.mean(a["root"])), "signed_root_sd": float(np.std(a["root"]))}
            for q, a in acc.items()}


def _profile_deviance(vin, tc, e, mass, kb0, theta, s_tc, s_cor, spec, q):
    """Profile deviance S(q) - S_min of one quantity at q, the other parameters refitted to
    tight tolerance by scipy's least squares (no grid, no interpolation) [-]."""
    from scipy import optimize

    from ballimpact import fitting as F

    keep = [i for i in range(theta.size) if i != spec.drop]
    lo, hi = F._full_bounds(theta.size)

    def th_of(x):
        th = np.empty(theta.size)
        th[keep] = x
        th[spec.drop] = spec.inv(q, th)
        return th

    def fun(x):
        return F._residuals(th_of(x)[None], vin, tc, e, mass, kb0, s_tc, s_cor)[0]

    s_min = float(np.sum(F._residuals(theta[None], vin, tc, e, mass, kb0, s_tc, s_cor)[0] ** 2))
    r = optimize.least_squares(fun, theta[keep], bounds=(lo[keep], hi[keep]), method="trf", xtol=1e-10,
                               ftol=1e-12, gtol=1e-12, diff_step=1e-6)
    return float(np.sum(r.fun**2)) - s_min


def diagnose(seeds=20, first=0):
    """Where a miss of the kB(0)-fixed bench comes from, per fit of the bench's own sessions
    (outlier search off): the reported interval's hit; the exact profile deviance at the
    truth (:func:`_profile_deviance`) against the critical value used (a miss of the grid's
    interpolated crossing would show as a disagreement); the same deviance against the
    critical value computed at the truth with the true scatter (the plug-in); and the Wald
    statistic at the truth (Jacobian at the truth, the fit's scatter), the form
    ``--truth-world`` counts. Pooled coverage of each, per quantity."""
    from ballimpact import fitting as F

    rows = []
    for seed, key, p, vin, tc, e in bench_sessions(seeds, first):
        mass = np.full(vin.size, p.mass_kg)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            f = fit_ball_model(vin, tc, e, p.mass_kg, n_bootstrap=0, kb0_N_m=p.kb0_N_m, detect_outliers=False)
            theta, s_tc, s_cor = f.result.x, f.contact_time_scatter, f.cor_scatter
            crit = F._calibrated_critical_values(vin, tc, e, mass, p.kb0_N_m, theta, s_tc, s_cor, 0.95)
            th_true = F._to_theta(p.ak, p.a, p.ac)
            st = simulate_impact(vin, p.mass_kg, p.kb0_N_m, p.ak, p.a, p.ac)
            crit_true = F._calibrated_critical_values(vin, st.contact_time_s, st.cor, mass, p.kb0_N_m, th_true,
                                                      0.004, 0.003 / float(np.mean(st.cor)), 0.95)
            jac_t = F._jacobian(lambda pts: F._residuals(pts, vin, st.contact_time_s, st.cor, mass, p.kb0_N_m,
                                                         1.0, 1.0), th_true)
            w = np.concatenate([np.full(vin.size, s_tc**-2), np.full(vin.size, s_cor**-2)])
            cov_t = np.linalg.inv(jac_t.T @ (jac_t * w[:, None]))
            for spec in F._quantities(3, p.kb0_N_m):
                q = float(spec.fwd(th_true))
                g = F._quantity_gradient(spec, th_true)
                dev = _profile_deviance(vin, tc, e, mass, p.kb0_N_m, theta, s_tc, s_cor, spec, q)
                lo, hi = getattr(f, f"{spec.key}_lo"), getattr(f, f"{spec.key}_hi")
                truth = float(np.exp(q)) if spec.key != "a" else q
                rows.append({"seed": seed, "ball": key, "quantity": spec.key, "hit": bool(lo <= truth <= hi),
                             "exact": dev <= crit[spec.key], "plug_in_at_truth": dev <= crit_true[spec.key],
                             "wald_at_truth": float((spec.fwd(theta) - q) ** 2 / (g @ cov_t @ g)) <= crit[spec.key],
                             "crit_ratio": crit[spec.key] / crit_true[spec.key]})
    out = {}
    for qk in dict.fromkeys(r["quantity"] for r in rows):
        rs = [r for r in rows if r["quantity"] == qk]
        out[qk] = {"fits": len(rs), "interval": float(np.mean([r["hit"] for r in rs])),
                   "exact_deviance": float(np.mean([r["exact"] for r in rs])),
                   "interval_vs_exact_disagree": int(sum(r["hit"] != r["exact"] for r in rs)),
                   "critical_value_at_truth": float(np.mean([r["plug_in_at_truth"] for r in rs])),
                   "wald_at_truth": float(np.mean([r["wald_at_truth"] for r in rs])),
                   "critical_value_ratio_sd": float(np.std([r["crit_ratio"] for r in rs]))}
    return out


def _print(summary):
    for mode, s in summary.items():
        print(f"{mode}: {s['seeds']} seeds, {s['fits']} fits, {s['failures']} failures")
        for k, c in s["coverage"].items():
            print(f"  {k:15s} " + "  ".join(f"{nm} {v:.2f}" for nm, v in c.items()))
        print("  pooled          " + "  ".join(f"{nm} {v:.3f}" for nm, v in s["pooled_coverage"].items()))
        print("  median width    " + "  ".join(f"{nm} {v:.3f}" for nm, v in s["median_relative_width"].items()))
        if s.get("pooled_coverage_without_false_removal") and s["fits_without_false_removal"] < s["fits"]:
            print(f"  the {s['fits_without_false_removal']} fits without a good impact removed "
                  + "  ".join(f"{nm} {v:.4f}" for nm, v in s["pooled_coverage_without_false_removal"].items()))
        if s.get("pooled_coverage_kb0_free_alone"):
            print("  kB(0) free alone " + "  ".join(f"{nm} {v:.3f}" for nm, v in s["pooled_coverage_kb0_free_alone"].items()))
        if s.get("pooled_coverage_kb0_free_and_estimate"):
            print("  free + estimate  " + "  ".join(f"{nm} {v:.3f}" for nm, v in
                                                   s["pooled_coverage_kb0_free_and_estimate"].items()))
        print(f"  sessions (4 Table 2 balls) without a good impact removed: {s['sessions_without_false_removal']:.3f}")
        if s["planted_outlier_named"] is not None:
            print(f"  planted outlier named: {s['planted_outlier_named']:.3f} "
                  + ", ".join(f"{k} {v:.2f}" for k, v in s["planted_outlier_named_by_kind"].items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--kb0", choices=("config", "extrapolated", "both"), default="config")
    ap.add_argument("--outlier", choices=("no", "yes", "both"), default="no",
                    help="plant one outlier per ball type")
    ap.add_argument("--vmin", type=float, default=14.0, help="lowest inbound speed [m/s]")
    ap.add_argument("--jsonl", help="append one JSON record per fit to this file (a run can be stopped)")
    ap.add_argument("--summarise", nargs="+", metavar="JSONL", help="only summarise these record files")
    ap.add_argument("--noise-free", action="store_true",
                    help="only kB(0) of noise-free impacts, evenly spaced from --vmin to 30 m/s")
    ap.add_argument("--calibration-check", action="store_true",
                    help="only the critical values: F(1, nu), calibrated, and corrected by full refits")
    ap.add_argument("--refits", type=int, default=1000, help="full-model refits of --calibration-check")
    ap.add_argument("--truth-world", action="store_true",
                    help="only the Wald-form coverage of the calibrated intervals over --seeds designs")
    ap.add_argument("--sessions", type=int, default=400, help="sessions per design of --truth-world")
    ap.add_argument("--diagnose", action="store_true",
                    help="only where the kB(0)-fixed misses come from: grid, plug-in or the statistic")
    ap.add_argument("--truth-stat", action="store_true",
                    help="only the --truth-world statistic on the bench's own sessions (kB(0) fixed, no outlier); "
                         "--summarise pairs its records with the bench's")
    ap.add_argument("--lr-check", action="store_true",
                    help="only the profile deviance (likelihood ratio) at the truth over --seeds designs x "
                         "--sessions full-model refits against the calibrated critical value")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if args.lr_check:
        res = lr_check(args.seeds, args.sessions, args.first_seed)
        if args.json:
            print(json.dumps(res, indent=2))
        for q, r in res.items() if not args.json else []:
            print(f"{q:8s} {r['sessions']} sessions: coverage {r['coverage']:.3f}, 0.95 quantile of deviance / "
                  f"critical value {r['q95_deviance_over_critical']:.3f}, signed root mean {r['signed_root_mean']:+.3f}"
                  f" sd {r['signed_root_sd']:.3f}; per ball type "
                  + ", ".join(f"{b} {v:.3f}" for b, v in r["per_ball"].items()))
        return
    if args.truth_stat:
        records = truth_stat(args.seeds, args.first_seed, args.jsonl)
        res = summarise_truth_stat(records)
        print(json.dumps(res, indent=2) if args.json else
              f"{res['fits']} fits: " + "  ".join(f"{q} {v:.3f}" for q, v in res["pooled"].items()))
        return
    if args.diagnose:
        res = diagnose(args.seeds, args.first_seed)
        if args.json:
            print(json.dumps(res, indent=2))
        for q, r in res.items() if not args.json else []:
            print(f"{q:8s} {r['fits']} fits: interval {r['interval']:.3f}, exact profile deviance "
                  f"{r['exact_deviance']:.3f} ({r['interval_vs_exact_disagree']} disagree), critical value at the "
                  f"truth {r['critical_value_at_truth']:.3f} (ratio sd {r['critical_value_ratio_sd']:.3f}), Wald at "
                  f"the truth {r['wald_at_truth']:.3f}")
        return
    if args.truth_world:
        res = truth_world(args.seeds, args.sessions, args.first_seed)
        if args.json:
            print(json.dumps(res, indent=2))
            return
        for key, kinds in res.items():
            for kind, cov in kinds.items():
                print(f"{key:13s} COR noise {kind:8s} " + "  ".join(f"{q} {v:.3f}" for q, v in cov.items()))
        for kind in ("absolute", "relative"):
            pooled = {q: np.mean([res[k][kind][q] for k in res]) for q in next(iter(res.values()))[kind]}
            print(f"pooled        COR noise {kind:8s} " + "  ".join(f"{q} {v:.3f}" for q, v in pooled.items()))
        return
    if args.calibration_check:
        rows = calibration_check(args.refits)
        if args.json:
            print(json.dumps(rows, indent=2))
        for r in rows if not args.json else []:
            print(f"{r['ball']:13s} {r['quantity']:8s} F(1, {r['satterthwaite_nu']:4.1f}) {r['f_quantile']:.2f}  "
                  f"calibrated {r['calibrated']:.2f}  with {args.refits} full refits {r['with_refits']:.2f} "
                  f"(ratio {r['refit_ratio']:.3f}); coverage at the truth, COR noise absolute: F "
                  f"{r['coverage_f_absolute']:.3f}, calibrated {r['coverage_calibrated_absolute']:.3f}; relative: "
                  f"F {r['coverage_f_relative']:.3f}, calibrated {r['coverage_calibrated_relative']:.3f}")
        print("pooled: " + ", ".join(f"{k} {np.mean([r[k] for r in rows]):.3f}" for k in rows[0]
                                     if k.startswith("coverage")))
        return
    if args.noise_free:
        rows = noise_free(vmin=args.vmin)
        if args.json:
            print(json.dumps(rows, indent=2))
        else:
            for r in rows:
                print(f"{r['ball']:13s} kB(0) {r['kb0_source']}: {r['kb0_kN_m']:.2f} kN/m ({r['kb0_error_pct']:+.1f} %), "
                      f"interval [{r['kb0_lo_kN_m']:.2f}, {r['kb0_hi_kN_m']:.2f}] holds {r['true_kb0_kN_m']:.0f}: "
                      f"{r['kb0_inside']}; line {r['linear_error_pct']:+.1f} %, quadratic "
                      f"{r['quadratic_error_pct']:+.1f} %; kB(20 mm) {r['kb_20mm_error_pct']:+.2f} % "
                      f"(inside: {r['kb_20mm_inside']})"
                      + (f"; kB(0) free alone [{r['kb0_free_lo_kN_m']:.2f}, {r['kb0_free_hi_kN_m']:.2f}] holds it: "
                         f"{r['kb0_free_inside']}" if "kb0_free_inside" in r else ""))
        return
    if args.summarise:
        records = [json.loads(line) for path in args.summarise for line in open(path) if line.strip()]
    else:
        kb0s = ("config", "extrapolated") if args.kb0 == "both" else (args.kb0,)
        outs = (False, True) if args.outlier == "both" else (args.outlier == "yes",)
        t0 = time.perf_counter()
        records = run(args.seeds, [(k, o) for k in kb0s for o in outs], vmin=args.vmin,
                      first_seed=args.first_seed, jsonl=args.jsonl)
        print(f"({time.perf_counter() - t0:.0f} s)")
    truth = [r for r in records if r.get("kb0") == "truth-stat"]
    summary = summarise([r for r in records if r.get("kb0") != "truth-stat"])
    ts = summarise_truth_stat(records) if truth else None
    if args.json:
        print(json.dumps(summary | ({"truth_stat": ts} if ts else {}), indent=2))
        return
    _print(summary)
    if ts:
        print(f"statistic at the truth (--truth-stat), {ts['seeds']} seeds, {ts['fits']} fits: "
              + "  ".join(f"{q} {v:.3f}" for q, v in ts["pooled"].items()))
        for q, r in ts["paired"].items():
            print(f"  paired with the kB(0)-fixed bench on {r['fits']} fits: {q} interval {r['interval']:.3f}, "
                  f"statistic {r['statistic']:.3f} ({r['only_interval']} hit only by the interval, "
                  f"{r['only_statistic']} only by the statistic)")


if __name__ == "__main__":
    main()

"""The lab's catalogue across sessions: ball types matched by key, change tests, pooled fits and a ranking.

Every session's results (``results/<session>/<session>.nc`` and ``parameters.csv``)
are read back; a ball type is the same ball type in two sessions when its key
(session.yaml ``balls``) is the same. For each ball type seen in two or more
sessions, :func:`compare_sessions` tests one shared parameter set (AK, a, AC of
Eq. (4) and Eq. (7) of Goodwill & Haake 2004) against one set per session on the
impacts themselves (an F test of nested least-squares fits on the relative TC and
COR residuals). :func:`fit_pooled` fits one parameter set to a ball type's impacts
from several sessions (config ``pool``). :func:`write_catalogue` is the file edge:
``catalogue.csv``, ``catalogue.nc`` and ``catalogue.pdf``
(:mod:`ballimpact.catalogue_report`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = [
    "REFERENCE_SPEED_M_S",
    "CHANGE_ALPHA",
    "ID_COLUMNS",
    "SessionResults",
    "ChangeTest",
    "read_session_results",
    "catalogue_table",
    "session_impacts",
    "compare_sessions",
    "fit_pooled",
    "pooled_session_id",
    "ranking_table",
    "catalogue_dataset",
    "write_catalogue",
]

#: Inbound speed at which the change in TC and COR is stated and the ball types are ranked [m/s].
REFERENCE_SPEED_M_S = 20.0
#: Significance level at which a ball type is flagged as changed between sessions [-].
CHANGE_ALPHA = 0.01
#: First columns of catalogue.csv; parameters.csv's columns follow, then ``pooled_sessions``.
ID_COLUMNS = ["session_id", "session_date"]

_PER_IMPACT = ("ball_type", "status", "vin_m_s", "contact_time_ms", "cor", "impact_mass_kg", "used_in_fit")
_CURVES = (
    "model_contact_time_ms", "model_contact_time_ms_lo", "model_contact_time_ms_hi",
    "model_cor", "model_cor_lo", "model_cor_hi", "model_peak_force_N",
)


@dataclass
class SessionResults:
    """What the catalogue needs of one processed session.

    Attributes
    ----------
    session_id : str
        Session id (the results folder name).
    session_date : str
        session.yaml ``date`` (ISO text), from the archive's global attributes.
    parameters : pandas.DataFrame
        parameters.csv as written, one row per ball type.
    balls : xarray.Dataset
        The archive's per-ball variables (dims ``ball`` and ``ball x speed``).
    impacts : xarray.Dataset
        The archive's per-impact scalars (vin [m/s], TC [ms], COR [-], mass [kg], status).
    """

    session_id: str
    session_date: str
    parameters: pd.DataFrame
    balls: object
    impacts: object

    @property
    def ball_keys(self) -> list[str]:
        return [str(b) for b in self.parameters["ball"]]


@dataclass
class ChangeTest:
    """Result of :func:`compare_sessions` for one ball type.

    Attributes
    ----------
    ball : str
        Ball type key.
    sessions : list of str
        Sessions compared (those with a fit and at least one good impact).
    n_impacts : int
        Good impacts over all these sessions.
    f_statistic : float
        F = ((RSS_shared - RSS_separate) / (3 (S - 1))) / (RSS_separate / (2 n - 3 S)) [-].
    df_num, df_den : int
        Degrees of freedom of the F distribution.
    p_value : float
        P(F' > F) under "one shared parameter set" [-]; NaN when not testable.
    changed : bool
        ``p_value < alpha``.
    tc_change_ms : float
        Largest minus smallest model TC at the reference speed over the sessions [ms].
    cor_change : float
        Largest minus smallest model COR at the reference speed over the sessions [-].
    rss_shared, rss_separate : float
        Weighted residual sums of squares of the two fits [-].
    message : str
        Why the test could not be made, or "ok".
    shared_fit : object
        The shared fit (:class:`ballimpact.fitting.BallFit`), None when not made.
    """

    ball: str
    sessions: list[str]
    n_impacts: int
    f_statistic: float
    df_num: int
    df_den: int
    p_value: float
    changed: bool
    tc_change_ms: float
    cor_change: float
    rss_shared: float
    rss_separate: float
    message: str
    shared_fit: object = field(default=None, repr=False)


# ------------------------------------------------------------------------------ reading


def _text(values) -> list[str]:
    return ["" if (v is None or (isinstance(v, float) and math.isnan(v))) else
            (v.decode() if isinstance(v, bytes) else str(v)) for v in np.asarray(values).ravel()]


def read_session_results(session_results_dir) -> SessionResults:
    """Read one session's results folder (``<session>.nc`` and ``parameters.csv``).

    Parameters
    ----------
    session_results_dir : str or Path
        ``results/<session_id>``.

    Returns
    -------
    SessionResults

    Raises
    ------
    FileNotFoundError
        The archive or parameters.csv is missing (naming the file).
    ValueError
        The archive belongs to another session, or lacks a variable the catalogue needs.
    """
    import xarray as xr

    folder = Path(session_results_dir)
    session_id = folder.name
    nc_path, csv_path = folder / f"{session_id}.nc", folder / "parameters.csv"
    for path in (nc_path, csv_path):
        if not path.is_file():
            raise FileNotFoundError(f"{path}: not found (process session {session_id!r} first)")
    parameters = pd.read_csv(csv_path, keep_default_na=False, na_values=[""], dtype={"ball": str, "kb0_source": str})
    if "ball" not in parameters.columns:
        raise ValueError(f"{csv_path}: no column 'ball'")
    parameters["kb0_source"] = parameters.get("kb0_source", pd.Series([""] * len(parameters))).fillna("")
    with xr.open_dataset(nc_path, engine="netcdf4", decode_times=False, decode_timedelta=False) as opened:
        from .archive_names import current_names

        f = current_names(opened)  # an archive of an earlier version: impact_ball, ...
        archived = str(f.attrs.get("session_id", session_id))
        if archived != session_id:
            raise ValueError(f"{nc_path}: global attribute session_id is {archived!r}, not the folder name {session_id!r}")
        date = str(f.attrs.get("session_date", ""))
        missing = [v for v in ("vin_m_s", "contact_time_ms", "cor", "status", "ball_type", "mass_kg") if v not in f]
        if missing:
            raise ValueError(f"{nc_path}: variable(s) {', '.join(missing)} missing (not a ballimpact session archive)")
        ball_vars = [v for v in f.data_vars if f[v].dims in (("ball",), ("ball", "speed"))]
        balls = f[ball_vars].load() if "ball" in f.dims else xr.Dataset()
        impacts = f[[v for v in _PER_IMPACT if v in f]].load()
    for name in list(balls.variables):
        if balls[name].dtype.kind in "OSU":
            balls[name] = (balls[name].dims, np.array(_text(balls[name].values), dtype=object))
    if "ball" in balls.coords:
        balls = balls.assign_coords(ball=np.array(_text(balls["ball"].values), dtype=object))
    for name in ("ball_type", "status"):
        impacts[name] = ("impact", np.array(_text(impacts[name].values), dtype=object))
    return SessionResults(session_id, date, parameters, balls, impacts)


def catalogue_table(sessions: Sequence[SessionResults], pooled: Iterable[pd.DataFrame] = ()) -> pd.DataFrame:
    """catalogue.csv: one row per session x ball type, then the pooled rows.

    Parameters
    ----------
    sessions : sequence of SessionResults
        In catalogue order (by date, then id).
    pooled : iterable of pandas.DataFrame
        Pooled rows (frames of one row with ``session_id``, ``session_date``,
        ``pooled_sessions`` and parameters.csv's columns).

    Returns
    -------
    pandas.DataFrame
        Columns ``session_id``, ``session_date``, every parameters.csv column (in the
        order of the first session that has it; units of the paper's Table 2), and
        ``pooled_sessions`` (the sessions of a pooled row joined by ``+``, else empty).
    """
    frames = []
    columns: list[str] = []
    for s in sessions:
        for col in s.parameters.columns:
            if col not in columns:
                columns.append(col)
        frame = s.parameters.copy()
        frame.insert(0, "session_date", s.session_date)
        frame.insert(0, "session_id", s.session_id)
        frame["pooled_sessions"] = ""
        frames.append(frame)
    for frame in pooled:
        for col in frame.columns:
            if col not in columns and col not in ID_COLUMNS and col != "pooled_sessions":
                columns.append(col)
        frames.append(frame)
    order = ID_COLUMNS + columns + ["pooled_sessions"]
    if not frames:
        return pd.DataFrame(columns=order)
    table = pd.concat([f.reindex(columns=order) for f in frames], ignore_index=True)
    if "n_impacts" in table:
        table["n_impacts"] = pd.array(
            [int(v) if pd.notna(v) else pd.NA for v in table["n_impacts"]], dtype="Int64")
    for col in ("kb0_source", "pooled_sessions"):
        if col in table:
            table[col] = table[col].fillna("")
    return table


# ------------------------------------------------------------------------ the impacts


def session_impacts(session: SessionResults, ball: str) -> dict:
    """The good impacts of one ball type in one session, as ``fit_ball_model`` takes them.

    The impacts the session's own fit used: status ok, positive values, and
    ``used_in_fit`` when the archive records it.

    Parameters
    ----------
    session : SessionResults
        One session.
    ball : str
        Ball type key.

    Returns
    -------
    dict
        ``vin_m_s`` [m/s], ``contact_time_s`` [s], ``cor`` [-], ``mass_kg`` [kg] (arrays).
    """
    from .pipeline import fit_arrays

    if ball not in session.ball_keys:
        raise ValueError(f"ball {ball!r} is not in session {session.session_id!r} (balls: {', '.join(session.ball_keys)})")
    default_mass = float(session.balls["mass_kg"].sel(ball=ball))
    ds = session.impacts
    if "used_in_fit" in ds:
        used = np.array([str(v).lower() in ("true", "1", "1.0") for v in np.asarray(ds["used_in_fit"].values).ravel()])
        ds = ds.isel(impact=np.flatnonzero(used))
    return fit_arrays(ds, ball, default_mass)


def _session_params_si(session: SessionResults, ball: str):
    """(kb0 [N/m], AK [N/m^(1+a)], a [-], AC [N s/m^3]) of the session's fit, None when it failed."""
    b = session.balls.sel(ball=ball)
    values = [float(b[k]) for k in ("kb0_kN_m", "ak_kN_m", "a", "ac_kN_s_m3")]
    if not all(np.isfinite(values)):
        return None
    return values[0] * 1e3, values[1] * 1e3, values[2], values[3] * 1e3


def _curve_at(session: SessionResults, ball: str, name: str, speed_m_s: float) -> float:
    if name not in session.balls:
        return math.nan
    curve = session.balls[name].sel(ball=ball)
    speeds = np.asarray(session.balls["speed_m_s"].values, dtype=float)
    values = np.asarray(curve.values, dtype=float)
    ok = np.isfinite(values)
    if ok.sum() < 2 or not speeds[ok].min() <= speed_m_s <= speeds[ok].max():
        return math.nan
    return float(np.interp(speed_m_s, speeds[ok], values[ok]))


def _shared_kb0(sessions: Sequence[SessionResults], ball: str):
    """kB(0) [N/m] for a fit over several sessions: the config value when every session
    fixed the same one, else None (extrapolated from all the impacts)."""
    values = set()
    for s in sessions:
        b = s.balls.sel(ball=ball)
        if str(b["kb0_source"].values) != "config":
            return None
        values.add(round(float(b["kb0_kN_m"]) * 1e3, 6))
    return values.pop() if len(values) == 1 else None


def _relative_residuals(arrays: dict, params) -> tuple[np.ndarray, np.ndarray]:
    from .model import simulate_impact

    kb0, ak, a, ac = params
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sim = simulate_impact(arrays["vin_m_s"], arrays["mass_kg"], kb0, ak, a, ac)
    tc, cor = arrays["contact_time_s"], arrays["cor"]
    return (sim.contact_time_s - tc) / tc, (sim.cor - cor) / cor


def compare_sessions(sessions: Sequence[SessionResults], ball: str, *, alpha: float = CHANGE_ALPHA,
                     speed_m_s: float = REFERENCE_SPEED_M_S) -> ChangeTest:
    """Did ball type ``ball`` change between sessions? F test of nested least-squares fits.

    Separate model: each session's own fit (kB(0), AK, a, AC of Eqs. (4) and (7) of
    Goodwill & Haake 2004, as archived). Shared model: one least-squares fit of AK, a,
    AC to the impacts every session's own fit used (``used_in_fit``), all together
    (:func:`ballimpact.fitting.fit_ball_model` with no fit-outlier search, no
    intervals and no bootstrap: the test needs its point estimates and residuals only;
    kB(0) fixed when every session fixed the same value, else extrapolated from all
    the impacts). Residuals are the relative TC and COR
    residuals of every impact, each kind divided by its RMS under the separate
    model (so that TC and COR count alike). With n impacts and S sessions
    (2 n residuals, 3 parameters per set),

        F = ((RSS_shared - RSS_separate) / (3 (S - 1))) / (RSS_separate / (2 n - 3 S)),

    p = P(F(3 (S - 1), 2 n - 3 S) > F). The size of the change is the spread
    (largest minus smallest) of the sessions' model TC [ms] and COR at ``speed_m_s``.

    Parameters
    ----------
    sessions : sequence of SessionResults
        Sessions holding the ball type (others are ignored).
    ball : str
        Ball type key.
    alpha : float
        Significance level for ``changed`` [-], in (0, 1).
    speed_m_s : float
        Inbound speed at which the change is stated [m/s].

    Returns
    -------
    ChangeTest
        ``p_value`` NaN (and ``changed`` False) when fewer than two sessions have a fit.
    """
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha!r}")
    if not (isinstance(speed_m_s, (int, float)) and speed_m_s > 0):
        raise ValueError(f"speed_m_s must be a positive speed in m/s, got {speed_m_s!r}")
    from scipy import stats

    from .fitting import FitError, fit_ball_model

    used, arrays, params = [], [], []
    for s in sessions:
        if ball not in s.ball_keys:
            continue
        p = _session_params_si(s, ball)
        arr = session_impacts(s, ball)
        if p is None or arr["vin_m_s"].size == 0:
            continue
        used.append(s)
        arrays.append(arr)
        params.append(p)
    nan = math.nan
    tc20 = [_curve_at(s, ball, "model_contact_time_ms", speed_m_s) for s in used]
    cor20 = [_curve_at(s, ball, "model_cor", speed_m_s) for s in used]
    tc_change = float(np.nanmax(tc20) - np.nanmin(tc20)) if np.isfinite(tc20).sum() >= 2 else nan
    cor_change = float(np.nanmax(cor20) - np.nanmin(cor20)) if np.isfinite(cor20).sum() >= 2 else nan
    ids = [s.session_id for s in used]
    n = int(sum(a["vin_m_s"].size for a in arrays))
    n_sessions = len(used)
    df_num, df_den = 3 * (n_sessions - 1), 2 * n - 3 * n_sessions

    def untestable(message, shared=None, rss=(nan, nan), f=nan):
        return ChangeTest(ball, ids, n, f, df_num, df_den, nan, False, tc_change, cor_change,
                          rss[0], rss[1], message, shared)

    if n_sessions < 2:
        return untestable(f"in {n_sessions} session(s) with a fit: nothing to compare")
    if df_den <= 0:
        return untestable(f"{n} impacts over {n_sessions} sessions are too few for {3 * n_sessions} parameters")
    pooled = {k: np.concatenate([a[k] for a in arrays]) for k in arrays[0]}
    # every session's impacts under its own parameter set, in one call of the model
    sizes = [a["vin_m_s"].size for a in arrays]
    own = tuple(np.repeat([p[k] for p in params], sizes) for k in range(4))
    r_tc, r_cor = _relative_residuals(pooled, own)
    sigma_tc = max(float(np.sqrt(np.nanmean(r_tc**2))), 1e-6)
    sigma_cor = max(float(np.sqrt(np.nanmean(r_cor**2))), 1e-6)
    rss_sep = float(np.nansum((r_tc / sigma_tc) ** 2) + np.nansum((r_cor / sigma_cor) ** 2))
    kb0 = _shared_kb0(used, ball)
    try:
        # point estimates on the impacts the sessions' own fits used: the test needs the
        # shared fit's residuals only (no outlier search, no intervals, no bootstrap)
        shared = fit_ball_model(**pooled, kb0_N_m=kb0, n_bootstrap=0, detect_outliers=False, intervals=False)
    except FitError as exc:
        return untestable(f"shared fit failed: {exc}", rss=(nan, rss_sep))
    sh_tc, sh_cor = _relative_residuals(pooled, (shared.kb0_N_m, shared.ak, shared.a, shared.ac))
    rss_shared = float(np.nansum((sh_tc / sigma_tc) ** 2) + np.nansum((sh_cor / sigma_cor) ** 2))
    # the separate fits are each session's own optimum (weighted by that session's scatter),
    # so RSS_shared can come out a hair below RSS_separate when nothing changed: F = 0 then
    f = max(rss_shared - rss_sep, 0.0) / df_num / (rss_sep / df_den)
    p = float(stats.f.sf(f, df_num, df_den))
    return ChangeTest(ball, ids, n, float(f), df_num, df_den, p, bool(p < alpha), tc_change, cor_change,
                      rss_shared, rss_sep, "ok", shared)


# ------------------------------------------------------------------------------ pooling


def pooled_session_id(session_ids: Sequence[str]) -> str:
    """Name of a pooled row in the catalogue: ``pooled:<s1>+<s2>+...``."""
    return "pooled:" + "+".join(session_ids)


def fit_pooled(sessions: Sequence[SessionResults], ball: str, *, n_bootstrap: int = 200, seed: int = 0):
    """Fit one parameter set (kB(0), AK, a, AC; Eqs. (4)-(16) of Goodwill & Haake 2004)
    to ball type ``ball``'s good impacts from several sessions, with 95 % intervals.

    Calls :func:`ballimpact.fitting.fit_ball_model` on the impacts of all the sessions
    together; kB(0) is fixed when every session fixed the same value (session.yaml
    ``kb0_kN_m``), else extrapolated from all the impacts.

    Parameters
    ----------
    sessions : sequence of SessionResults
        The sessions to pool, at least two, each holding ``ball``.
    ball : str
        Ball type key.
    n_bootstrap : int
        Bootstrap resamples for the intervals (config ``bootstrap``).
    seed : int
        Seed of the resampling.

    Returns
    -------
    ballimpact.fitting.BallFit

    Raises
    ------
    ValueError
        Fewer than two sessions, a session twice, or a session without the ball type.
    ballimpact.fitting.FitError
        The fit failed (e.g. fewer than 3 good impacts).
    """
    ids = [s.session_id for s in sessions]
    if len(ids) < 2:
        raise ValueError(f"pooling needs at least two sessions, got {ids}")
    if len(set(ids)) != len(ids):
        raise ValueError(f"pooling lists a session twice: {ids}")
    for s in sessions:
        if ball not in s.ball_keys:
            raise ValueError(f"pool of {ball!r}: session {s.session_id!r} has no ball type {ball!r} "
                             f"(its balls: {', '.join(s.ball_keys) or 'none'})")
    from .fitting import fit_ball_model

    arrays = [session_impacts(s, ball) for s in sessions]
    pooled = {k: np.concatenate([a[k] for a in arrays]) for k in arrays[0]}
    return fit_ball_model(**pooled, kb0_N_m=_shared_kb0(sessions, ball), n_bootstrap=n_bootstrap, seed=seed)


def _pooled_entry(sessions: Sequence[SessionResults], ball: str, *, n_bootstrap: int, seed: int):
    """(catalogue row frame, per-ball dataset) of one pool."""
    from . import archive
    from .fitting import FitError

    ids = [s.session_id for s in sessions]
    label = str(sessions[-1].balls["ball_label"].sel(ball=ball).values) if "ball_label" in sessions[-1].balls else ball
    try:
        fit = fit_pooled(sessions, ball, n_bootstrap=n_bootstrap, seed=seed)
    except FitError as exc:
        n = sum(session_impacts(s, ball)["vin_m_s"].size for s in sessions)
        ds = archive.fit_dataset(ball, None, label=label, mass_kg=float(sessions[-1].balls["mass_kg"].sel(ball=ball)),
                                 n_impacts=n, message=f"pooled fit failed: {exc}")
    else:
        ds = archive.fit_dataset(ball, fit, label=label, message=f"pooled over {', '.join(ids)}")
    row = archive.parameters_table(ds)
    dates = sorted(s.session_date for s in sessions)
    row.insert(0, "session_date", dates[-1])
    row.insert(0, "session_id", pooled_session_id(ids))
    row["pooled_sessions"] = "+".join(ids)
    keep = [v for v in ds.data_vars if ds[v].dims in (("ball",), ("ball", "speed"))]
    return row, ds[keep]


# ------------------------------------------------------------------------------ ranking


def ranking_table(sessions: Sequence[SessionResults], *, speed_m_s: float = REFERENCE_SPEED_M_S) -> pd.DataFrame:
    """Ball types ranked by COR and by stiffness at ``speed_m_s``, from their latest session.

    Stiffness is the Kelvin-Voigt equivalent kB = m pi^2 / TC^2 (Eq. (2) of Goodwill
    & Haake 2004) of the fitted model's TC at ``speed_m_s``, so that it is one number
    per ball type at a stated speed.

    Parameters
    ----------
    sessions : sequence of SessionResults
        In date order; the last session holding a ball type with a fit is used.
    speed_m_s : float
        Inbound speed [m/s].

    Returns
    -------
    pandas.DataFrame
        ``ball``, ``session_id``, ``session_date``, ``cor`` [-], ``contact_time_ms`` [ms],
        ``stiffness_kN_m`` [kN/m], ``cor_rank`` (1 = most lively), ``stiffness_rank``
        (1 = stiffest); sorted by ``cor_rank``.
    """
    latest: dict[str, SessionResults] = {}
    for s in sessions:
        for ball in s.ball_keys:
            if _session_params_si(s, ball) is not None:
                latest[ball] = s
    rows = []
    for ball, s in latest.items():
        tc_ms = _curve_at(s, ball, "model_contact_time_ms", speed_m_s)
        cor = _curve_at(s, ball, "model_cor", speed_m_s)
        mass = float(s.balls["mass_kg"].sel(ball=ball))
        stiffness = mass * math.pi**2 / (tc_ms * 1e-3) ** 2 / 1e3 if tc_ms > 0 else math.nan
        rows.append({"ball": ball, "session_id": s.session_id, "session_date": s.session_date,
                     "cor": cor, "contact_time_ms": tc_ms, "stiffness_kN_m": stiffness})
    table = pd.DataFrame(rows, columns=["ball", "session_id", "session_date", "cor", "contact_time_ms",
                                        "stiffness_kN_m"])
    table["cor_rank"] = table["cor"].rank(ascending=False, method="min").astype("Int64")
    table["stiffness_rank"] = table["stiffness_kN_m"].rank(ascending=False, method="min").astype("Int64")
    return table.sort_values(["cor_rank", "ball"]).reset_index(drop=True)


# ---------------------------------------------------------------------------- the dataset


def catalogue_dataset(sessions: Sequence[SessionResults], table: pd.DataFrame, tests: Mapping[str, ChangeTest],
                      ranking: pd.DataFrame, pooled_balls: Mapping[str, object] = None):
    """catalogue.nc: parameters on ``session x ball``, model curves on ``session x ball x speed``.

    Parameters
    ----------
    sessions : sequence of SessionResults
        The sessions, in catalogue order.
    table : pandas.DataFrame
        :func:`catalogue_table` (pooled rows included).
    tests : mapping of str to ChangeTest
        Change test per ball type.
    ranking : pandas.DataFrame
        :func:`ranking_table`.
    pooled_balls : mapping of str to xarray.Dataset, optional
        Pooled row id -> its per-ball dataset (model curves).

    Returns
    -------
    xarray.Dataset
        Every numeric column of catalogue.csv as a variable on (session, ball)
        (units of the paper's Table 2), ``kb0_source`` and ``session_date`` as text,
        the model curves ``model_*`` on (session, ball, speed), and on ``ball``:
        ``change_p_value``, ``change_f_statistic``, ``changed``, ``tc_change_ms``,
        ``cor_change``, ``cor_rank``, ``stiffness_rank``, ``ranking_cor``,
        ``ranking_stiffness_kN_m``.
    """
    import xarray as xr

    from . import archive

    session_ids = list(dict.fromkeys(table["session_id"])) if len(table) else []
    ball_keys = list(dict.fromkeys(table["ball"])) if len(table) else []
    speeds = np.asarray(archive.SPEED_GRID_M_S, dtype=float)
    si = {s: i for i, s in enumerate(session_ids)}
    bi = {b: i for i, b in enumerate(ball_keys)}
    data = _table_variables(table, si, bi)
    data.update(_curve_variables(sessions, dict(pooled_balls or {}), si, bi, speeds))
    dates = dict(zip(table["session_id"], table["session_date"]))
    pooled_of = dict(zip(table["session_id"], table["pooled_sessions"]))
    data["session_date"] = ("session", np.array([str(dates[s]) for s in session_ids], dtype=object))
    data["pooled_sessions"] = ("session", np.array([str(pooled_of[s]) for s in session_ids], dtype=object))
    data.update(_per_ball_variables(tests, ranking, bi))
    ds = xr.Dataset(data, coords={
        "session": np.array(session_ids, dtype=object),
        "ball": np.array(ball_keys, dtype=object),
        "speed_m_s": ("speed", speeds),
    })
    for name, (units, long_name) in _catalogue_variable_attrs().items():
        ds[name].attrs.update(units=units, long_name=long_name)
    for name in ds.variables:  # parameters.csv columns this version does not know (added later)
        if name not in archive.VARIABLE_ATTRS and "units" not in ds[name].attrs:
            ds[name].attrs.update(units="1", long_name=name.replace("_", " "))
    ds = archive.set_variable_attrs(ds)
    ds.attrs.update({
        "title": "Catalogue of tennis ball impact sessions",
        "summary": "Fitted Goodwill & Haake (2004) ball model parameters of every session x ball type, "
                   "pooled fits, change tests between sessions and a ranking of the ball types.",
        "Conventions": "CF-1.10, ACDD-1.3",
        "references": archive.PAPER_REFERENCE,
        "reference_speed_m_s": REFERENCE_SPEED_M_S,
        "change_alpha": CHANGE_ALPHA,
    })
    return ds


def _table_variables(table: pd.DataFrame, si: Mapping[str, int], bi: Mapping[str, int]) -> dict:
    """Every column of catalogue.csv (but the ids) on (session, ball): text or float, units of the table."""
    ns, nb = len(si), len(bi)
    rows = np.array([si[s] for s in table["session_id"]], dtype=int)
    cols = np.array([bi[b] for b in table["ball"]], dtype=int)
    data = {}
    for col in table.columns:
        if col in ("session_id", "ball", "session_date", "pooled_sessions"):
            continue
        numeric = pd.to_numeric(table[col], errors="coerce")
        is_text = bool((numeric.isna() & table[col].notna() & (table[col].astype(str) != "")).any())
        is_text = is_text or col in ("kb0_source", "fit_warnings")
        if is_text:
            arr = np.full((ns, nb), "", dtype=object)
            arr[rows, cols] = ["" if pd.isna(v) else str(v) for v in table[col]]
        else:
            arr = np.full((ns, nb), np.nan)
            arr[rows, cols] = numeric.to_numpy(dtype=float, na_value=np.nan)
        data[col] = (("session", "ball"), arr)
    return data


def _curve_variables(sessions, pooled_balls, si, bi, speeds: np.ndarray) -> dict:
    """The model curves (TC [ms], COR [-], peak force [N]) on (session, ball, speed [m/s])."""
    curves = {name: np.full((len(si), len(bi), speeds.size), np.nan) for name in _CURVES}
    sources = {s.session_id: s.balls for s in sessions}
    sources.update(pooled_balls)
    for sid, balls in sources.items():
        if sid not in si or "speed_m_s" not in balls:
            continue
        if not np.allclose(np.asarray(balls["speed_m_s"].values, dtype=float), speeds):
            raise ValueError(f"session {sid!r}: its model curves are on another speed grid than "
                             f"ballimpact.archive.SPEED_GRID_M_S (reprocess it with this version)")
        for ball in [str(b) for b in balls["ball"].values]:
            if ball not in bi:
                continue
            for name in _CURVES:
                if name in balls:
                    curves[name][si[sid], bi[ball]] = np.asarray(balls[name].sel(ball=ball).values, dtype=float)
    return {name: (("session", "ball", "speed"), arr) for name, arr in curves.items()}


def _per_ball_variables(tests: Mapping[str, ChangeTest], ranking: pd.DataFrame, bi: Mapping[str, int]) -> dict:
    """The change test and the ranking of each ball type, on ``ball``."""
    nb = len(bi)
    per_ball = {k: np.full(nb, np.nan) for k in (
        "change_p_value", "change_f_statistic", "tc_change_ms", "cor_change", "ranking_cor",
        "ranking_stiffness_kN_m", "cor_rank", "stiffness_rank")}
    changed = np.full(nb, "", dtype=object)
    for ball, t in tests.items():
        if ball in bi:
            j = bi[ball]
            per_ball["change_p_value"][j] = t.p_value
            per_ball["change_f_statistic"][j] = t.f_statistic
            per_ball["tc_change_ms"][j] = t.tc_change_ms
            per_ball["cor_change"][j] = t.cor_change
            changed[j] = "untested" if not np.isfinite(t.p_value) else ("changed" if t.changed else "unchanged")
    for _, row in ranking.iterrows():
        j = bi.get(row["ball"])
        if j is not None:
            per_ball["ranking_cor"][j] = row["cor"]
            per_ball["ranking_stiffness_kN_m"][j] = row["stiffness_kN_m"]
            per_ball["cor_rank"][j] = float(row["cor_rank"]) if pd.notna(row["cor_rank"]) else np.nan
            per_ball["stiffness_rank"][j] = float(row["stiffness_rank"]) if pd.notna(row["stiffness_rank"]) else np.nan
    data = {k: ("ball", v) for k, v in per_ball.items()}
    data["changed"] = ("ball", changed)
    return data


def _catalogue_variable_attrs() -> dict[str, tuple[str, str]]:
    """units and long_name of the catalogue's own variables (the rest come from the archive's)."""
    return {
        "session": ("1", "session id (pooled rows: pooled:<s1>+<s2>...)"),
        "session_date": ("1", "session date from session.yaml (pooled rows: the latest)"),
        "pooled_sessions": ("1", "sessions of a pooled fit joined by +, empty for a session"),
        "change_p_value": ("1", "p-value of one shared parameter set against one per session (F test)"),
        "change_f_statistic": ("1", "F statistic of the change test"),
        "changed": ("1", f"changed (p < {CHANGE_ALPHA}), unchanged, or untested"),
        "tc_change_ms": ("ms", f"spread of the sessions' model TC at {REFERENCE_SPEED_M_S:g} m/s"),
        "cor_change": ("1", f"spread of the sessions' model COR at {REFERENCE_SPEED_M_S:g} m/s"),
        "ranking_cor": ("1", f"model COR at {REFERENCE_SPEED_M_S:g} m/s in the ball type's latest session"),
        "ranking_stiffness_kN_m": ("kN m-1", f"Kelvin-Voigt stiffness m pi^2/TC^2 (Eq. 2) of the model TC at "
                                             f"{REFERENCE_SPEED_M_S:g} m/s, latest session"),
        "cor_rank": ("1", "rank by COR (1 = highest)"),
        "stiffness_rank": ("1", "rank by stiffness (1 = stiffest)"),
    }


def write_catalogue(session_results_dirs: Sequence, out_csv, out_nc, out_pdf, *,
                    pools: Sequence[Mapping] | None = None, n_bootstrap: int = 200, seed: int = 0) -> dict:
    """Write catalogue.csv, catalogue.nc and catalogue.pdf from the sessions' results.

    Parameters
    ----------
    session_results_dirs : sequence of str or Path
        ``results/<session_id>`` of every session to catalogue.
    out_csv, out_nc, out_pdf : str or Path
        The three outputs (written atomically).
    pools : sequence of mapping, optional
        Config ``pool``: each ``{"ball": key, "sessions": [s1, s2, ...]}``.
    n_bootstrap : int
        Bootstrap resamples of the pooled fits' intervals.
    seed : int
        Seed of the pooled fits' resampling.

    Returns
    -------
    dict
        ``table`` (catalogue.csv), ``tests`` (ball -> ChangeTest), ``ranking``.
    """
    from . import archive
    from .atomic import atomic_path
    from .catalogue_report import write_catalogue_pdf

    if isinstance(n_bootstrap, bool) or not isinstance(n_bootstrap, int) or n_bootstrap < 0:
        raise ValueError(f"n_bootstrap must be an integer >= 0, got {n_bootstrap!r}")
    sessions = [read_session_results(d) for d in session_results_dirs]
    sessions.sort(key=lambda s: (s.session_date, s.session_id))
    by_id = {s.session_id: s for s in sessions}
    pooled_rows, pooled_balls = [], {}
    for k, pool in enumerate(pools or []):
        ball, ids = pool.get("ball"), list(pool.get("sessions") or [])
        unknown = [i for i in ids if i not in by_id]
        if unknown:
            raise ValueError(f"config pool entry {k} (ball {ball!r}): session(s) {', '.join(map(repr, unknown))} "
                             f"not processed (sessions: {', '.join(by_id)})")
        row, ds = _pooled_entry([by_id[i] for i in ids], str(ball), n_bootstrap=n_bootstrap, seed=seed)
        pooled_rows.append(row)
        pooled_balls[pooled_session_id(ids)] = ds
    table = catalogue_table(sessions, pooled_rows)
    balls = list(dict.fromkeys(b for s in sessions for b in s.ball_keys))
    tests = {ball: compare_sessions(sessions, ball) for ball in balls}
    ranking = ranking_table(sessions)
    ds = catalogue_dataset(sessions, table, tests, ranking, pooled_balls)
    for path in (out_csv, out_nc, out_pdf):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out_csv) as tmp:
        from .tables import write_csv

        write_csv(table, tmp)
    archive.write_dataset(ds, out_nc)
    write_catalogue_pdf(ds, table, tests, ranking, out_pdf)
    return {"table": table, "tests": tests, "ranking": ranking}

"""The run summary: fit warnings, parameters on a search bound, exclusions by reason, stale results."""

import json
import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from ballimpact.archive import parameters_table
from ballimpact.fitting import PARAMETER_BOUNDS, REFERENCE_DISPLACEMENT_M
from ballimpact.summary import (
    NOT_DETERMINED,
    STALE_FILE,
    clear_stale,
    fit_warnings,
    mark_stale,
    run_summary,
    session_summary,
    undetermined_parameters,
)

GOOD = {"ak_kN_m": 16000.0, "ak_lo": 12000.0, "ak_hi": 21000.0, "a": 1.65, "a_lo": 1.55, "a_hi": 1.75,
        "ac_kN_s_m3": 3.5, "ac_lo": 3.1, "ac_hi": 3.9}


def _ball_ds(rows):
    """An archive's per-ball part as rule archive writes it (only what parameters.csv reads)."""
    names = [r.pop("ball") for r in rows]
    data = {k: ("ball", np.array([r.get(k, math.nan) for r in rows], dtype=float))
            for k in ("n_impacts", "mass_kg", "kb0_kN_m", "kb0_lo", "kb0_hi", *GOOD, "contact_time_rmse_pct",
                      "cor_rmse_pct")}
    data["kb0_source"] = ("ball", np.array(["config"] * len(rows), dtype=object))
    data["fit_message"] = ("ball", np.array([r["fit_message"] for r in rows], dtype=object))
    return xr.Dataset(data, coords={"ball": np.array(names, dtype=object)})


def test_good_fit_has_empty_fit_warnings_and_its_intervals():
    table = parameters_table(_ball_ds([{"ball": "b1", **GOOD, "fit_message": "ok"}]))
    assert table.loc[0, "fit_warnings"] == ""
    assert table.loc[0, ["a_lo", "a_hi"]].tolist() == [1.55, 1.75]


def test_failed_fit_on_the_search_bounds_is_not_shown_as_intervals():
    # The case (a mistyped mass): the "95 % intervals" of a and AC were the search
    # bounds, a in [0.300, 3.149] and AC in [0.01, 100.00] kN s/m^3 (fitting.PARAMETER_BOUNDS:
    # a 0.3-4, AC 10-1e5 N s/m^3).
    a_lo, _ = PARAMETER_BOUNDS["a"]
    ac_lo, ac_hi = (b / 1e3 for b in PARAMETER_BOUNDS["ac"])
    row = {**GOOD, "ball": "b1", "a_lo": a_lo, "a_hi": 3.149, "ac_kN_s_m3": 5.0, "ac_lo": ac_lo, "ac_hi": ac_hi,
           "fit_message": "ok; AK (via kR) sits on its search bound; the data do not constrain it, treat it with "
                          "care; only 41 of 200 bootstrap refits converged; bands unreliable"}
    table = parameters_table(_ball_ds([row]))
    warnings = table.loc[0, "fit_warnings"]
    # a = 1.65 is inside its range: only its interval's lower end is the search bound's (issue 49)
    assert warnings.startswith("AK not determined (at bound); a: 95 % interval reaches the search bound: the data "
                               "bound it on one side only; AC not determined (at bound); AK (via kR) sits on its "
                               "search bound")
    assert "only 41 of 200 bootstrap refits converged" in warnings
    for key in ("ak", "ac"):
        assert table.loc[0, [f"{key}_lo", f"{key}_hi"]].isna().all(), key
    assert math.isnan(table.loc[0, "a_lo"]) and table.loc[0, "a_hi"] == 3.149
    assert table.loc[0, "a"] == GOOD["a"]  # the estimate itself stays


def test_a_value_inside_its_range_is_never_called_not_determined():
    """Issue 49: "a not determined (at bound)" was printed beside a = 1.745, well inside 0.3-4, because its
    interval reached the bound."""
    a_lo, a_hi = PARAMETER_BOUNDS["a"]
    row = {**GOOD, "ball": "b1", "a": 1.745, "a_lo": 1.21, "a_hi": a_hi, "fit_message": "ok"}
    text = parameters_table(_ball_ds([row])).loc[0, "fit_warnings"]
    assert "not determined" not in text
    assert text == "a: 95 % interval reaches the search bound: the data bound it on one side only"


def test_an_interval_four_orders_of_magnitude_wide_is_a_fit_warning():
    """Issue 49: an AK interval of [6 602, 63 974 727] was not flagged at all."""
    row = {**GOOD, "ball": "b1", "ak_kN_m": 150_000.0, "ak_lo": 6602.0, "ak_hi": 63_974_727.0, "fit_message": "ok"}
    text = parameters_table(_ball_ds([row])).loc[0, "fit_warnings"]
    assert text.startswith("AK barely determined: its 95 % interval [6,602, 6.397e+07] spans a factor 9,690 (more than 100)"), text
    good = parameters_table(_ball_ds([{**GOOD, "ball": "b1", "fit_message": "ok"}])).loc[0, "fit_warnings"]
    assert good == ""  # GOOD's AK interval spans a factor of 1.75


def test_ak_bound_follows_from_the_kr_and_a_bounds():
    kr_lo, _ = PARAMETER_BOUNDS["kr_N_m"]
    a = 2.0
    ak_on_bound = kr_lo / REFERENCE_DISPLACEMENT_M**a / 1e3  # kR = AK xR^a, in kN
    values = {**GOOD, "a": a, "ak_kN_m": ak_on_bound}
    # the value on the kR bound is only caught by the fit's message; its interval end by the global AK bound
    assert undetermined_parameters(values, "ok; AK (via kR) sits on its search bound; ...") == {"ak": NOT_DETERMINED}
    assert undetermined_parameters(GOOD, "ok") == {}


def test_fit_warnings_text():
    assert fit_warnings("ok") == ""
    assert fit_warnings("ok; only 3 impacts: the intervals are rough") == "only 3 impacts: the intervals are rough"
    assert fit_warnings("fit failed: needs at least 3 good impacts, got 2") == (
        "fit failed: needs at least 3 good impacts, got 2")
    assert fit_warnings("ok", {"ac": NOT_DETERMINED}) == "AC not determined (at bound)"


def _results(tmp_path, name="s1"):
    folder = tmp_path / name
    (folder / "work").mkdir(parents=True)
    (folder / "work" / "session.json").write_text(json.dumps({"warnings": [
        "session.yaml: unknown key(s) 'balls.b1.kb0_kn_m' (kept in raw, not used; known: ...)"]}))
    pd.DataFrame({"impact_id": ["i1", "i2", "i3", "i4"], "ball": ["b1"] * 4,
                  "status": ["ok", "excluded", "excluded", "excluded"],
                  "reason": ["", "pulse is negative: plate.polarity is +1", "pulse is negative: plate.polarity is +1",
                             "trace file not found: traces/i4.csv"]}).to_csv(folder / "impacts.csv", index=False)
    pd.DataFrame({"ball": ["b1"], "fit_warnings": ["AC not determined (at bound)"]}).to_csv(
        folder / "parameters.csv", index=False)
    (folder / "report.pdf").write_bytes(b"%PDF")
    (folder / f"{name}.nc").write_bytes(b"")
    return folder


def test_session_summary_counts_exclusions_by_reason_and_shows_warnings(tmp_path):
    lines = session_summary(_results(tmp_path))
    assert lines[0] == "  s1: 4 impacts, 1 ok, 3 excluded"
    assert "    excluded   2 x pulse is negative: plate.polarity is +1" in lines
    assert "    excluded   1 x trace file not found" in lines
    assert "    fit b1: WARNING: AC not determined (at bound)" in lines
    assert any(line.startswith("    validate warning: session.yaml: unknown key(s) 'balls.b1.kb0_kn_m'")
               for line in lines)


def test_session_summary_counts_the_ok_impacts_whose_peak_is_withheld(tmp_path):
    folder = _results(tmp_path)
    table = pd.read_csv(folder / "impacts.csv", keep_default_na=False)
    table["peak_note"] = ["peak force between samples: the force rises by 14 % of the peak ...",
                          "peak force on plate ringing: not counted, the impact is excluded", "", ""]
    table.to_csv(folder / "impacts.csv", index=False)
    lines = session_summary(folder)
    assert "    ok, peak withheld   1 x peak force between samples" in lines, lines
    assert not any("plate ringing" in line for line in lines)
    assert not any("withheld" in line for line in session_summary(_results(tmp_path / "plain")))


def test_session_level_error_and_stale_results(tmp_path):
    folder = _results(tmp_path)
    (folder / "work" / "session.json").unlink()  # Snakemake removes the output of the failed job
    error = "s1/session.yaml: key 'date' must be an ISO date\ns1/impacts.csv: line 3: ball 'x' is not defined"
    stale = mark_stale(folder, error)
    assert stale == folder / STALE_FILE
    text = stale.read_text()
    assert text.startswith("STALE:") and "impacts.csv" in text and "ball 'x' is not defined" in text
    lines = session_summary(folder, fault=error)
    assert lines[0] == "  s1: SESSION-LEVEL ERROR, not processed:"
    assert lines[1:3] == ["    error: s1/session.yaml: key 'date' must be an ISO date",
                          "    error: s1/impacts.csv: line 3: ball 'x' is not defined"]
    assert lines[3].startswith("    STALE: the results in") and lines[3].endswith(f"(see {folder / STALE_FILE})")
    clear_stale(folder)
    assert not (folder / STALE_FILE).exists()


def test_no_stale_mark_without_earlier_results(tmp_path):
    (tmp_path / "s2").mkdir()
    assert mark_stale(tmp_path / "s2", "error") is None
    assert not (tmp_path / "s2" / STALE_FILE).exists()


def test_session_fault_is_read_from_the_validate_log(tmp_path):
    folder = tmp_path / "s3" / "logs"
    folder.mkdir(parents=True)
    (folder / "validate_session.log").write_text(
        "2026-11-22 05:00:00,001 INFO x: start\n"
        "2026-11-22 05:00:00,002 ERROR ballimpact: session-level fault: first problem\nsecond problem\n")
    text = run_summary(tmp_path, ["s3"])
    assert "  s3: SESSION-LEVEL ERROR, not processed:\n    error: first problem\n    error: second problem" in text


def test_large_residual_is_a_fit_warning():
    # the mistyped mass left a TC residual of 78 % RMS; the paper's model agrees within ~5 %
    row = {**GOOD, "ball": "b1", "fit_message": "ok", "contact_time_rmse_pct": 78.0, "cor_rmse_pct": 0.5}
    text = parameters_table(_ball_ds([row])).loc[0, "fit_warnings"]
    assert text.startswith("TC residual 78.0 % RMS (> 5 %): the model does not describe these impacts")
    assert "COR residual" not in text


def _exclusions(tmp_path, reasons):
    folder = _results(tmp_path)
    pd.DataFrame({"impact_id": [f"i{k}" for k in range(len(reasons))], "ball": ["b1"] * len(reasons),
                  "status": ["excluded"] * len(reasons), "reason": reasons}).to_csv(folder / "impacts.csv",
                                                                                     index=False)
    return [line for line in session_summary(folder) if line.startswith("    excluded")]


def test_summary_labels_carry_no_stray_value_marks(tmp_path):
    """Issue 49: "inbound speed # ... outside physical bounds": a value's number and unit both go."""
    lines = _exclusions(tmp_path, ["inbound speed 0.014 m/s outside physical bounds (2.0, 80.0)",
                                   "inbound speed 0.017 m/s outside physical bounds (2.0, 80.0)",
                                   "contact time 8.60 ms outside physical bounds (1.0, 12.0)",
                                   "calibration factor 125.0 N/V is 50 % from the session median 250.0 N/V "
                                   "(robust z = 10591.7)"])
    assert lines == ["    excluded   2 x inbound speed outside physical bounds",
                     "    excluded   1 x contact time outside physical bounds",
                     "    excluded   1 x calibration factor far from the session median"], lines


def test_summary_says_why_a_trace_is_unreadable(tmp_path):
    """Issue 49: "unreadable trace" alone hid the cause (an unknown extension); the file name is left out."""
    lines = _exclusions(tmp_path, [
        "unreadable trace: raw/s1/traces/shot05.lvm: unknown trace file extension '.lvm' (expected .csv or .tdms)",
        "unreadable trace: raw/s1/traces/shot06.lvm: unknown trace file extension '.lvm' (expected .csv or .tdms)",
        "unreadable trace: /data/raw/s1/traces/b.csv: line 4: non-numeric value 'spike!'"])
    assert lines == ["    excluded   2 x unreadable trace: unknown trace file extension '.lvm' "
                     "(expected .csv or .tdms)",
                     "    excluded   1 x unreadable trace: non-numeric value 'spike!'"], lines


def test_a_model_force_unlike_the_measured_one_is_a_fit_warning():
    """Issue 49: half-sine pulses (not tennis balls) agreed with the fitted model on 25-32 % of the contact, and only
    `a` was warned about. The median impact's agreement below FORCE_AGREEMENT_WARNING is a fit warning."""
    ds = _ball_ds([{"ball": "b1", **GOOD, "fit_message": "ok"}, {"ball": "b2", **GOOD, "fit_message": "ok"}])
    ds["model_agreement_fraction"] = ("impact", [0.25, 0.32, 0.30, 0.2, 1.0, 0.99, 1.0])
    ds["ball_type"] = ("impact", np.array(["b1"] * 4 + ["b2"] * 3, dtype=object))
    ds["status"] = ("impact", np.array(["ok"] * 3 + ["excluded"] + ["ok"] * 3, dtype=object))
    table = parameters_table(ds).set_index("ball")
    assert table.loc["b1", "fit_warnings"].startswith(
        "model force unlike the measured force: within 10 % of the peak on 30 % of the contact (median impact")
    assert table.loc["b2", "fit_warnings"] == ""


@pytest.mark.slow
def test_half_sine_pulses_are_flagged_in_parameters_and_the_run_summary(tmp_path):
    """Issue 49, end to end without Snakemake: a hand-made session of half-sine pulses (tests/handmade.py) is
    processed, fitted and archived by the workflow's functions; parameters.csv and the run summary name the cause."""
    import warnings

    from handmade import HandmadeSpec, write_session

    from ballimpact.pipeline import fit_balls, session_impacts, write_archive

    folder = write_session(tmp_path / "raw" / "hand", HandmadeSpec(formats=["csv"] * 8, header_rates_hz={},
                                                                  bandwidth_hz=20_000.0))
    out = tmp_path / "results" / "hand"
    work = out / "work"
    work.mkdir(parents=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        session_impacts(folder, work / "session.json", out / "impacts.csv", work / "impacts.nc")
        fit_balls(work / "impacts.nc", ["yellow"], folder, work / "fits.nc", n_bootstrap=10, seed=0)
        write_archive(folder, work / "impacts.nc", [work / "fits.nc"], out / "hand.nc", out / "parameters.csv",
                      work / "session.json")
    (out / "report.pdf").write_bytes(b"%PDF")
    text = pd.read_csv(out / "parameters.csv", keep_default_na=False).loc[0, "fit_warnings"]
    assert text.startswith("model force unlike the measured force"), text
    assert any(line.startswith("    fit yellow: WARNING: model force unlike the measured force")
               for line in session_summary(out)), session_summary(out)


def test_the_rig_is_one_line_and_its_warnings_one_each():
    from ballimpact.summary import rig_summary

    from rigkit import ringing_archive

    assert rig_summary(ringing_archive(6)) == ["    rig: plate 3 kHz, zeta 0.05 (identified); time constant 0.8 s "
                                               "(identified)"]
    assert rig_summary(ringing_archive(6, plate="stated", warnings=["plate.resonance_hz disagrees"])) == [
        "    rig: plate 3 kHz, zeta 0.05 (stated); time constant 0.8 s (identified)",
        "    rig warning: plate.resonance_hz disagrees"]
    assert rig_summary(ringing_archive(6, plate="none"))[0].startswith("    rig: plate not identified; ")
    assert rig_summary(xr.Dataset()) == []


def test_session_summary_reads_the_rig_from_the_archive(tmp_path):
    from rigkit import ringing_archive

    folder = _results(tmp_path)
    ringing_archive(6).to_netcdf(folder / "s1.nc")
    lines = session_summary(folder)
    rig = lines.index("    rig: plate 3 kHz, zeta 0.05 (identified); time constant 0.8 s (identified)")
    assert lines[rig - 1].startswith("    fit b1:") and lines[rig + 1].startswith("    validate warning:")
    assert not any(line.startswith("    rig") for line in session_summary(_results(tmp_path / "old")))  # no rig

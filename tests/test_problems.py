"""Typed problems (ballimpact.problems): each kind is produced where it arises, and decisions test kinds, not text."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ballimpact.gates import check_gate_times
from ballimpact.problems import (
    GATE_TIME_KINDS,
    TRACE_FILE_KINDS,
    Problem,
    ProblemKind,
    has_kind,
    kind_of_message,
)
from ballimpact.processing import ImpactResult, apply_calibration_check, process_impact
from ballimpact.session import Session, read_session
from ballimpact.synth import SynthConfig, write_session


@pytest.fixture(scope="module")
def small_session(tmp_path_factory):
    """Four good synthetic impacts (one per Table 2 ball), CSV traces, no planted fault."""
    root = tmp_path_factory.mktemp("problems")
    session_dir, _ = write_session(root / "prob-1", SynthConfig(session_id="prob-1", seed=5, impacts_per_ball=1,
                                                                faults_per_kind=0, trace_format="csv"))
    return session_dir


def _kinds(problems):
    return [p.kind for p in problems]


# ----------------------------------------------------------------------------- the types


def test_problem_is_a_kind_and_a_message():
    p = Problem(ProblemKind.CLIPPING, "clipping at the ADC rails")
    assert p.kind is ProblemKind.CLIPPING and str(p) == "clipping at the ADC rails"
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.kind = ProblemKind.NO_CONTACT
    assert p == Problem(ProblemKind.CLIPPING, "clipping at the ADC rails") and len({p, p}) == 1


@pytest.mark.parametrize(("kind", "message", "error", "match"), [
    ("clipping", "clipping at the ADC rails", TypeError, "kind must be a ProblemKind"),
    (ProblemKind.CLIPPING, "", ValueError, "message must be a non-empty string"),
    (ProblemKind.CLIPPING, None, ValueError, "message must be a non-empty string"),
])
def test_problem_rejects_bad_fields(kind, message, error, match):
    with pytest.raises(error, match=match):
        Problem(kind, message)


def test_find_takes_a_problem_not_text():
    with pytest.raises(TypeError, match="must be a ballimpact.problems.Problem"):
        ImpactResult(impact_id="x", ball="b").find("no contact found")


def test_has_kind_takes_one_kind_or_several():
    found = [Problem(ProblemKind.MASS_INVALID, "non-numeric mass_g: 'x'")]
    assert has_kind(found, ProblemKind.MASS_INVALID)
    assert not has_kind(found, GATE_TIME_KINDS) and not has_kind([], ProblemKind.MASS_INVALID)


# Messages as the code writes them (copied from impacts.csv of real and synthetic runs), one per kind.
MESSAGES = {
    ProblemKind.GATE_TIME_MISSING: "missing gate time gate_in_2_s",
    ProblemKind.GATE_TIME_INVALID: "non-numeric gate time gate_out_1_s: 'abc'",
    ProblemKind.GATE_ORDER: "gate times out of order: gate_in_1_s (0.005) must be earlier than gate_in_2_s (0.004)",
    ProblemKind.GATE_INTERVAL: "rebound gate interval not positive (gate_out_1_s - gate_out_2_s = 0 s)",
    ProblemKind.MASS_INVALID: "implausible mass_g: 1500 (must be in (1, 1000) g)",
    ProblemKind.TRACE_PATH_MISSING: "missing trace path",
    ProblemKind.TRACE_PATH_ESCAPES: "trace path escapes the session folder: ../x.csv",
    ProblemKind.TRACE_PATH_UNRESOLVABLE: "trace path cannot be resolved: 'a\\x00b' (embedded null byte)",
    ProblemKind.TRACE_NOT_FOUND: "trace file not found: traces/pressurised-005.csv",
    ProblemKind.TRACE_NOT_A_FILE: "trace path is not a file: traces",
    ProblemKind.TRACE_UNREADABLE: "unreadable trace: traces/x.csv: line 7: non-numeric value 'abc'",
    ProblemKind.TRACE_UNUSABLE: "unusable trace: voltage has fewer than 64 samples",
    ProblemKind.CLIPPING: "clipping at the ADC rails",
    ProblemKind.POLARITY: "pulse is negative: plate.polarity is +1",
    ProblemKind.NO_CONTACT: "no contact found",
    ProblemKind.MULTIPLE_IMPACTS: "more than one impact in the trace (2 found: second contact at +17.0 ms, 25 % of "
                                  "the peak)",
    ProblemKind.CONTACT_TRUNCATED: "contact not entirely inside the trace (truncated trace?)",
    ProblemKind.CONTACT_UNSTABLE: "contact window not stable under the baseline fit: its ends still move by 3 samples "
                                  "after 12 iterations",
    ProblemKind.DECAY_NOT_CORRECTED: "charge-amplifier decay not corrected: estimated time constant 0.001 s is below "
                                     "the plausible 0.005 s",
    ProblemKind.UNDERSHOOT_NOT_MEASURABLE: "charge-amplifier undershoot not measurable (0.1 +/- 0.2 mV): the impulse "
                                           "may be off by up to 3 %",
    ProblemKind.BASELINE_OFF_ZERO: "corrected signal after the contact is 4.1 mV off zero (1.2 % of the peak): "
                                   "baseline or amplifier decay not removed",
    ProblemKind.BASELINE_RESIDUAL: "quiet baseline not explained by offset, drift, hum and decay: 2 mV rms above the "
                                   "white noise",
    ProblemKind.BASELINE_STEP: "step in the baseline: the corrected signal's level shifts by -10.6 mV (0.26 % of the "
                               "peak, 15.4 standard errors) between 19.5 and 26.18 ms, which offset, drift, hum and "
                               "decay do not explain; the baseline under the contact is uncertain",
    ProblemKind.CONTACT_END_UNDETERMINED: "contact start not determined: the 0.05 ms inside it hold no force",
    ProblemKind.TOO_FEW_SAMPLES: "only 7.5 samples in the contact (fewer than 10): sample rate too low",
    ProblemKind.PLATE_RINGING: "plate ringing at 8.1 kHz during the contact",
    ProblemKind.MAINS_UNRESOLVED: "mains frequency not resolved: 50 and 60 Hz hum fit the quiet baseline equally well",
    ProblemKind.CONTACT_JUMP_UNRESOLVED: "contact start between two samples: the force jumps from zero there, so TC "
                                         "is known to +-25 us only, more than 0.7 % of 3 ms (sample faster)",
    ProblemKind.NEGATIVE_FORCE: "force below zero after the contact: 2 % of the peak (9.1 noise deviations) 0.6 ms "
                                "after its end",
    ProblemKind.PEAK_ON_RINGING: "peak force on plate ringing: the force oscillates at about 20 kHz during the "
                                 "contact",
    ProblemKind.PEAK_BETWEEN_SAMPLES: "peak force between samples: the force rises by 14 % of the peak in the 43 us "
                                      "before the largest sample and may go on rising before it drops",
    ProblemKind.IMPULSE_UNRESOLVED: "impulse not known to 0.5 %: were the largest sample an electrical spike, the "
                                    "impulse would be 0.68 % off",
    ProblemKind.CLOTH_PHASE_COMPLETED: "contact start completed from the force's jump by the cloth's phase: 0.1 ms "
                                       "(2 mm at 20.0 m/s) before it, 0.08 ms before the start read on its foot",
    ProblemKind.ALIASING: "signal bandwidth 25 kHz (daq.bandwidth_hz) above half the sample rate (10 kHz): the "
                          "plate's ringing is sampled through its alias",
    ProblemKind.SPEED_OUT_OF_BOUNDS: "inbound speed 1.20 m/s outside physical bounds (2.0, 80.0)",
    ProblemKind.COR_OUT_OF_BOUNDS: "COR 1.200 outside physical bounds (0.05, 1.0)",
    ProblemKind.CONTACT_TIME_OUT_OF_BOUNDS: "contact time 0.52 ms outside physical bounds (1.0, 12.0)",
    ProblemKind.NO_CALIBRATION: "no calibration: voltage integral over the contact is not positive",
    ProblemKind.KCAL_OUT_OF_RANGE: "calibration factor 180.2 N/V outside the plate's range [250, 400] N/V "
                                   "(plate.kcal_range_N_per_V)",
    ProblemKind.KCAL_OUTLIER: "calibration factor 240.3 N/V is 33 % from the session median 180.1 N/V "
                              "(robust z = 12.0)",
    ProblemKind.TIME_CONSTANT_OUTLIER: "charge-amplifier time constant 0.0823 s estimated, unlike the session's "
                                       "4.42 s (6 impacts; 131 standard errors): the impulse and kCAL may be off by "
                                       "2.1 %; a step in the baseline within the contact taken for the decay? (give "
                                       "plate.time_constant_s)",
}


def test_every_kind_has_a_message_example():
    assert set(MESSAGES) == set(ProblemKind)


@pytest.mark.parametrize("kind", list(ProblemKind), ids=lambda k: k.value)
def test_kind_of_message_reads_a_message_back(kind):
    assert kind_of_message(MESSAGES[kind]) is kind
    assert kind_of_message("  " + MESSAGES[kind] + " ") is kind


def test_kind_of_message_unknown_text_is_none():
    assert kind_of_message("something nobody wrote") is None
    assert kind_of_message("") is None


# ----------------------------------------------------------------------------- where each kind arises
# The conditioning's kinds BASELINE_OFF_ZERO, DECAY_NOT_CORRECTED, PLATE_RINGING, TOO_FEW_SAMPLES,
# CONTACT_END_UNDETERMINED, CONTACT_JUMP_UNRESOLVED, NEGATIVE_FORCE and PEAK_ON_RINGING are produced,
# by kind, in tests/test_conditioning.py. CONTACT_UNSTABLE,
# UNDERSHOOT_NOT_MEASURABLE, BASELINE_RESIDUAL, MAINS_UNRESOLVED, CONTACT_TIME_OUT_OF_BOUNDS and
# NO_CALIBRATION need traces no cheap generator makes on purpose: only their messages are read back above.


def _rewrite_rows(session_dir, cells_by_row: dict[int, dict[str, str]]):
    """Set cells of impacts.csv rows (0-based data rows) and read the session again."""
    import csv

    path = session_dir / "impacts.csv"
    rows = list(csv.DictReader(path.open(encoding="utf-8", newline="")))
    for i, cells in cells_by_row.items():
        rows[i].update(cells)
    with path.open("w", encoding="utf-8", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return read_session(session_dir)


@pytest.mark.parametrize(("cells", "kind"), [
    (dict(gate_in_2_s=""), ProblemKind.GATE_TIME_MISSING),
    (dict(gate_in_2_s="soon"), ProblemKind.GATE_TIME_INVALID),
    (dict(gate_in_2_s="nan"), ProblemKind.GATE_TIME_INVALID),
    (dict(gate_in_1_s="-1"), ProblemKind.GATE_TIME_INVALID),
    (dict(gate_in_1_s="1e6"), ProblemKind.GATE_ORDER),
    (dict(mass_g="heavy"), ProblemKind.MASS_INVALID),
    (dict(mass_g="5000"), ProblemKind.MASS_INVALID),
    (dict(trace=""), ProblemKind.TRACE_PATH_MISSING),
    (dict(trace="../elsewhere.csv"), ProblemKind.TRACE_PATH_ESCAPES),
    (dict(trace="/etc/passwd"), ProblemKind.TRACE_PATH_ESCAPES),
    (dict(trace="traces/a\x00b.csv"), ProblemKind.TRACE_PATH_UNRESOLVABLE),
    (dict(trace="traces/" + "x" * 10_000 + ".csv"), ProblemKind.TRACE_PATH_UNRESOLVABLE),
    (dict(trace="traces/none.csv"), ProblemKind.TRACE_NOT_FOUND),
    (dict(trace="traces"), ProblemKind.TRACE_NOT_A_FILE),
])
def test_reader_gives_each_row_fault_its_kind(small_session, tmp_path, cells, kind):
    import shutil

    folder = shutil.copytree(small_session, tmp_path / small_session.name)
    session = _rewrite_rows(folder, {1: cells})
    assert _kinds(session.impacts[1].problems) == [kind]
    assert kind_of_message(session.impacts[1].problems[0].message) is kind
    assert all(not row.problems for k, row in enumerate(session.impacts) if k != 1)


def test_gate_check_gives_missing_and_interval_kinds():
    assert _kinds(check_gate_times(0.0, math.nan, 0.02, 0.03)) == [ProblemKind.GATE_TIME_MISSING]
    assert _kinds(check_gate_times(0.0, -0.005, 0.02, 0.01)) == [ProblemKind.GATE_INTERVAL] * 2


def _process(session: Session, k: int = 0, **row_changes):
    row = dataclasses.replace(session.impacts[k], **row_changes)
    return process_impact(row, session)


def test_good_impacts_have_no_problem(small_session):
    session = read_session(small_session)
    for k in range(len(session.impacts)):
        result = _process(session, k)
        assert result.status == "ok" and result.problems == [] and result.reason == ""


def test_processing_kinds_of_speed_cor_and_calibration(small_session):
    session = read_session(small_session)
    row = session.impacts[0]
    slow = _process(session, gate_in_2_s=row.gate_in_1_s + 0.1)  # 0.1 m in 0.1 s: 1 m/s inbound
    assert ProblemKind.SPEED_OUT_OF_BOUNDS in _kinds(slow.problems)
    lively = _process(session, gate_out_1_s=row.gate_out_2_s + 0.2 * (row.gate_in_2_s - row.gate_in_1_s))
    assert ProblemKind.COR_OUT_OF_BOUNDS in _kinds(lively.problems)  # rebound 5x faster than inbound
    narrow = dataclasses.replace(session, meta=dataclasses.replace(session.meta, kcal_range_N_per_V=(1.0, 2.0)))
    assert _kinds(_process(narrow).problems) == [ProblemKind.KCAL_OUT_OF_RANGE]
    # a metadata value the conditioning cannot use (the reader would refuse it): the trace is unusable
    bad_mains = dataclasses.replace(session, meta=dataclasses.replace(session.meta, mains_hz=-50.0))
    assert _kinds(_process(bad_mains).problems) == [ProblemKind.TRACE_UNUSABLE]


def test_processing_kinds_of_the_trace(small_session, tmp_path):
    import shutil

    folder = shutil.copytree(small_session, tmp_path / small_session.name)
    session = read_session(folder)
    flipped = dataclasses.replace(session, meta=dataclasses.replace(session.meta, polarity=-session.meta.polarity))
    assert _kinds(_process(flipped).problems) == [ProblemKind.POLARITY]
    trace = session.trace_path(session.impacts[0])
    lines = trace.read_text(encoding="utf-8").splitlines()
    header = [line for line in lines if line.startswith("#")] + ["voltage_V"]
    rng = np.random.default_rng(1)
    trace.write_text("\n".join(header + [f"{v:.6f}" for v in 1e-3 * rng.standard_normal(3000)]) + "\n")
    assert _kinds(_process(session).problems) == [ProblemKind.NO_CONTACT]
    trace.write_text("\n".join(header + ["0.1", "abc"] * 200) + "\n")
    assert _kinds(_process(session).problems) == [ProblemKind.TRACE_UNREADABLE]
    trace.unlink()
    assert _kinds(_process(session).problems) == [ProblemKind.TRACE_NOT_FOUND]


def test_processing_kind_of_a_truncated_contact(small_session, tmp_path):
    import shutil

    folder = shutil.copytree(small_session, tmp_path / small_session.name)
    session = read_session(folder)
    trace = session.trace_path(session.impacts[0])
    lines = trace.read_text(encoding="utf-8").splitlines()
    data = [line for line in lines if not line.startswith("#")][1:]
    values = np.array([float(v) for v in data])
    peak = int(np.argmax(values))
    header = [line for line in lines if line.startswith("#")] + ["voltage_V"]
    trace.write_text("\n".join(header + data[:peak]) + "\n")  # the trace ends at the peak of the force
    assert ProblemKind.CONTACT_TRUNCATED in _kinds(_process(session).problems)


@pytest.mark.parametrize(("fault", "kind"), [
    ("clipped", ProblemKind.CLIPPING),
    ("double_impact", ProblemKind.MULTIPLE_IMPACTS),
    ("missing_gate", ProblemKind.GATE_TIME_MISSING),
    ("missing_trace", ProblemKind.TRACE_NOT_FOUND),
])
def test_planted_faults_come_out_with_their_kind(synth_session, fault, kind):
    session_dir, truth = synth_session
    session = read_session(session_dir)
    planted = [row for row in session.impacts if truth.loc[row.impact_id, "fault"] == fault]
    assert planted
    for row in planted:
        assert kind in _kinds(process_impact(row, session).problems), row.impact_id


def test_session_kcal_outlier_is_its_kind():
    results = [ImpactResult(impact_id=f"i{k}", ball="b", kcal_N_per_V=k_cal)
               for k, k_cal in enumerate([180.0, 181.0, 179.5, 180.5, 240.0])]
    apply_calibration_check(results)
    assert [_kinds(r.problems) for r in results] == [[]] * 4 + [[ProblemKind.KCAL_OUTLIER]]
    assert results[4].status == "excluded" and results[4].reason == results[4].problems[0].message


# ----------------------------------------------------------------------------- decisions test kinds, not text


def test_reader_gate_fault_reworded_still_stops_the_repeat(small_session):
    """A gate fault the reader found is not repeated by the gate check, whatever its message says."""
    session = read_session(small_session)
    reworded = [Problem(ProblemKind.GATE_TIME_MISSING, "the far inbound gate did not fire")]
    result = _process(session, gate_in_1_s=math.nan, problems=reworded)
    assert result.problems == reworded and result.reason == "the far inbound gate did not fire"


def test_message_that_mentions_gate_time_does_not_stop_the_gate_check(small_session):
    session = read_session(small_session)
    other = [Problem(ProblemKind.MASS_INVALID, "mass_g given where a gate time was expected")]
    result = _process(session, gate_in_1_s=math.nan, problems=other)
    assert _kinds(result.problems) == [ProblemKind.MASS_INVALID, ProblemKind.GATE_TIME_MISSING]


def test_reader_trace_fault_reworded_is_not_repeated(small_session):
    session = read_session(small_session)
    reworded = [Problem(ProblemKind.TRACE_PATH_ESCAPES, "the path leaves the session folder")]
    result = _process(session, trace="../x.csv", problems=reworded)
    assert result.problems == reworded


def test_message_that_mentions_trace_does_not_hide_a_missing_trace(small_session):
    session = read_session(small_session)
    other = [Problem(ProblemKind.MASS_INVALID, "mass_g copied from the trace header is not a number")]
    result = _process(session, trace="traces/gone.csv", problems=other)
    assert _kinds(result.problems) == [ProblemKind.MASS_INVALID, ProblemKind.TRACE_NOT_FOUND]


def test_trace_file_and_gate_time_kind_sets():
    assert TRACE_FILE_KINDS == {k for k in ProblemKind if k.value.startswith("trace_")} - {
        ProblemKind.TRACE_UNREADABLE, ProblemKind.TRACE_UNUSABLE}
    assert ProblemKind.GATE_INTERVAL not in GATE_TIME_KINDS  # found by the gate check, never by the reader

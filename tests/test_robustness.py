"""The issue-9 invariant of the per-impact processing on zoo traces: ok and right, or excluded; never ok and wrong.

Every test here runs the real ``ballimpact.processing.process_impact`` on traces
of the zoo (tests/zoo.py), written as one-impact raw sessions, and judges the
result against the trace's truth (``zoo.judge``).

NOTE TO THE ALGORITHM ENGINEER (issue 9)
----------------------------------------
* The REGRESSION cases (one per class of the issue's "Why") are marked
  ``xfail(strict=True)``: they fail on the main branch of 2026-11-22. When your
  change fixes one, its strict xfail turns into an XPASS failure: remove that
  case's mark then (the entries of ``REGRESSION`` with ``fails_today=True``).
* The PROPERTY tests are marked ``xfail(strict=False)`` with the reason
  "issue 9: ...": remove the mark once they pass; they must then stay green.
* To look at one case: ``python bench/robustness.py --replay`` works for the
  benchmark's traces; a regression case is ``zoo.make_trace(
  numpy.random.default_rng(seed), mode, **overrides)``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, example, given, settings
from hypothesis import strategies as st

import zoo
from ballimpact.problems import ProblemKind
from workflow_helpers import bench_module


def _kinds(result) -> set:
    """The kinds of an impact's findings, but the cloth's phase completed (a finding of no effect on TC, reported
    wherever a start read on the foot is completed from the force's jump)."""
    return {p.kind for p in result.problems} - {ProblemKind.CLOTH_PHASE_COMPLETED}


def named(cases) -> list:
    """The cases (tuples whose first item is the case's name) as pytest params, each with its name as the id."""
    return [pytest.param(*c, id=c[0]) for c in cases]


#: Rig overrides that leave only the factor of interest: no spikes, no other fault.
CLEAN = dict(truncate="", clip_factor=0.0, spikes=(), second=None)

#: One case per class of issue 9 ("Why"): (name, seed, mode, overrides, what it is, fails_today).
#: Measured on main (2026-11-22) with tests/zoo.py: the judgement noted in each comment.
REGRESSION = [
    # Double impacts passed as ok: second contact 8-100 % of the peak, 6-20 ms after the first.
    ("double-36pc-8ms", 18, "random", dict(CLEAN, post_s=0.08, plate_hz=None, second=(0.008, 0.36, 18.0)),
     "second contact of 36 % of the peak 8 ms after the end (11.7 ms after the start): faulty_ok, "
     "TC -2.6 %, kCAL -7.2 %", True),
    ("double-8pc-4.5ms", 4, "random", dict(CLEAN, post_s=0.08, plate_hz=None, second=(0.0045, 0.08, 7.0)),
     "second contact of 8 % of the peak 4.5 ms after the end (7.8 ms after the start), 26 mV of 60 Hz "
     "hum: faulty_ok, kCAL +4.5 %", True),
    ("double-10pc-10ms", 10, "random", dict(CLEAN, post_s=0.08, plate_hz=None, second=(0.0098, 0.10, 18.8)),
     "second contact of 10 % of the peak 9.8 ms after the end: faulty_ok, TC +3.1 %", True),
    # A clear second contact of about a third of the peak, 12 ms later: ok with TC too long.
    ("second-third-12ms", 38, "random", dict(CLEAN, post_s=0.08, plate_hz=None, second=(0.0086, 0.33, 12.0)),
     "second contact of 33 % of the peak 12 ms after the start: faulty_ok, TC +7.2 %, kCAL -5.1 %", True),
    # 60 Hz mains hum with no daq.mains_hz: TC far off in one case, kCAL in another.
    ("hum-60Hz-no-mains-tc", 8, "mains", dict(mains_hz=60.0, mains_known=False, hum_V=0.0133),
     "13 mV of 60 Hz hum, mains_hz absent: ok_wrong, TC +37 %", True),
    ("hum-60Hz-no-mains-kcal", 13, "mains", dict(mains_hz=60.0, mains_known=False, hum_V=0.0259),
     "26 mV of 60 Hz hum, mains_hz absent: ok_wrong, kCAL +2.0 %", True),
    # A 0.02 s charge-amplifier time constant: TC too short, kCAL too large.
    ("tau-0.02s", 2, "tau", dict(tau_s=0.02, tau_known=False),
     "0.02 s time constant, not given: ok_wrong, TC -3.0 %, kCAL +4.0 %", True),
    # 200 kHz sampling with 25 kHz plate ringing: TC too long.
    ("ringing-25kHz-at-200kHz", 44, "plate", dict(sample_rate_hz=200e3, plate_hz=25e3, plate_zeta=0.0111),
     "25 kHz plate ringing (damping ratio 0.011) sampled at 200 kHz: ok_wrong, TC +1.6 %, peak +5.6 %", True),
    # A clean impact with a 0.1 s time constant excluded as truncated.
    ("tau-0.1s-clean", 0, "tau", dict(tau_s=0.1, tau_known=False),
     "clean impact, 0.1 s time constant: excluded 'contact not entirely inside the trace'", True),
]

#: Words an exclusion reason must hold for each fault ("names what was seen").
FAULT_WORDS = {
    "second contact": ("second contact", "more than one impact"),
    "truncated": ("truncated", "not entirely inside"),
    "clipped": ("clipping", "clipped"),
    "saturated": ("clipping below the ADC rails",),
}


#: Regression cases the processing does not fix yet (strict xfail); every case of REGRESSION is fixed
#: on the robust branch (events before baseline, exact decay model, mains detection, ringing check).
STILL_FAILING: set[str] = set()


def _regression_params():
    params = []
    for name, seed, mode, overrides, what, fails_today in REGRESSION:
        marks = ([pytest.mark.xfail(strict=True, raises=AssertionError, reason=f"issue 9, fails on main: {what}")]
                 if fails_today and name in STILL_FAILING else [])
        params.append(pytest.param(name, seed, mode, overrides, what, id=name, marks=marks))
    return params


def assert_invariant(trace, result, judgement, *, must_be_ok=False, excluded_with=None):
    """Both rules per quantity: nothing reported (status ok) is wrong, no faulty trace enters a fit, and an excluded
    impact says why. With ``must_be_ok``, the impact enters the fit with every quantity right. With
    ``excluded_with``, that text is in the reason of the exclusion, or in the note of a quantity withheld."""
    t = trace.truth
    info = (f"{judgement.category}: errors {judgement.errors}, outcomes {judgement.outcomes}, reason "
            f"{result.reason!r}, withheld {result.withheld_note!r}, truth fault {t.fault!r} marginal {t.marginal!r}; "
            f"{zoo.describe(trace.rig)}")
    assert judgement.category not in ("ok_wrong", "faulty_ok"), info
    assert not judgement.wrong, info
    if must_be_ok and not zoo.withheld_for_the_cloth_alone(result):  # the cloth's phase an undone plate may hide
        assert judgement.category == "ok_right", info
    if result.status != "ok" and not zoo.withheld_for_the_cloth_alone(result):
        assert result.reason, info
        for fault in filter(None, t.fault.split("; ")):
            assert any(w in result.reason for w in FAULT_WORDS[fault]), info
    if excluded_with is not None:
        assert excluded_with in result.reason or excluded_with in result.withheld_note, info


#: Cases whose exclusion is itself the failure the issue reports.
MUST_BE_OK = {"tau-0.1s-clean"}


@pytest.mark.parametrize("name, seed, mode, overrides, what", _regression_params())
def test_regression_case(name, seed, mode, overrides, what, tmp_path):
    trace = zoo.make_trace(np.random.default_rng(seed), mode, **overrides)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=name in MUST_BE_OK)


#: Traces of the benchmark (``python bench/robustness.py --n 2000 --seed 0``) that came out ok but
#: wrong on main of 2026-11-22 (commit 3303f6f), one per class of what was left:
#: (name, seed, index, what it was, must be ok now).
ZOO_REGRESSION = [
    ("plate-1.3kHz-swings-below-zero", 0, 69, "1.27 kHz plate (damping 0.089) alone: peak +18 %, TC +2.5 %", False),
    ("plate-23kHz-ringing-on-the-spike", 0, 904, "23 kHz plate rings after the force's jump: peak +18.9 %", False),
    ("plate-8kHz-damped-overshoot", 0, 1560, "8.1 kHz plate, damping 0.23, overshoot of the jump: peak +6.3 %",
     False),
    ("jump-20kHz", 0, 1, "20 kHz, the force jumps from zero between samples: TC +1.4 %", False),
    # ok and right from 977d5e3 to 042c839; since then excluded: its spike's samples rise by 37 % of the peak
    # and then by 13 % before the drop, so its top may be above the largest sample (peak between samples)
    ("jump-23kHz", 0, 757, "23 kHz, the force jumps from zero between samples: TC +1.2 % (now +0.5 %)", False),
    ("tail-fades-172kHz", 0, 1550, "punctured ball's 1 % tail fades into the noise: TC +1.6 %", False),
    ("tail-fades-50kHz", 0, 567, "punctured ball at 0.5 V peak, tail in the noise: TC +1.5 %", False),
    # ok but wrong on main at commit 977d5e3 (seeds 0 and 1 of the benchmark)
    ("plate-20.7kHz-rings-at-2.8-samples", 0, 552, "20.7 kHz plate at 58.6 kHz, its swings 1 and 2 samples apart: "
     "peak +10.5 %", False),
    ("spike-top-between-samples-28kHz", 1, 1140, "the spike's top between two samples at 28 kHz: peak -5.7 %", False),
    ("spike-top-between-samples-25kHz", 0, 618, "the spike's top between two samples at 25 kHz: peak -5.3 %", False),
    ("short-record-hum-no-post-baseline", 1, 1962, "11.5 ms record, 17 mV of 60 Hz hum not fittable, no quiet "
     "samples after the contact for the fit: TC +20 %", False),
    ("plate-overshoot-is-the-first-sample", 0, 952, "8.7 kHz plate at 22.9 kHz: the first sample of the contact, "
     "the plate's overshoot of the jump, is the largest: peak +9.1 %", False),
    ("lone-spike-before-the-jump", 1, 523, "a lone spike two samples before the force's jump taken as the start: "
     "TC +1.2 %", True),
    # ok but wrong with the plate's resonance undone before the record-end guard (the parent of a3f531a)
    ("plate-undone-contact-to-the-record-end", 1, 1184, "24.9 kHz plate, 5 ms post-trigger: the undone contact "
     "ran to the record's end, TC +48 %", False),
    # ok but wrong on main at commit 58169d8: one line through the low plateau and the drop after it
    ("punctured-plateau-then-drop", 1, 707, "punctured ball at 0.58 V peak, a 1 % plateau ending in a steep drop: "
     "TC +1.3 %", False),
    # ok but wrong on the way to it (never on main), when the spread check split bent feet too: a 953 Hz plate's
    # lag is a bent tail, and only the one-line refit at twice the threshold sees that the end is not determined
    ("plate-953Hz-lag-bent-tail", 1, 318, "953 Hz plate, damping 0.28, at 189 kHz: a bent tail, TC +10 %", False),
    # ok but wrong on main at 30878d7, on seed 6 (held out until then): a plate damped 0.285 rings too little for the
    # plate's checks, and the front's fit through a low-pass pressed its damping to the bound then (0.3): no evidence
    ("plate-2.4kHz-damped-0.285-lowpass", 6, 1912, "2.44 kHz plate, damping 0.285, at 51 kHz: TC +1.08 %", False),
    # ok but wrong on the way to it (never on main), with a wider limit (0.7 % of TC) for the end refit where its
    # threshold is below 0.5 % of the peak: an aliased plate's undone force passed with an end that moved 0.5-0.7 %
    ("aliased-plate-undone-end-refit", 1, 698, "22.8 kHz plate at 34.6 kHz (alias 11.8 kHz) undone: TC +1.03 %", False),
    ("aliased-plate-end-refit-seed-2", 2, 586, "22.6 kHz plate at 24.9 kHz (alias 2.3 kHz), its end refitted 0.56 % "
     "later: kCAL +1.5 %, peak -12 % when allowed", False),
    # ok but wrong on main at commit a56273e, on seed 3 (held out until then): a force with two humps
    ("plate-848Hz-two-humps", 3, 1077, "848 Hz plate, damping 0.22, at 50 kHz: the spike's ringing makes a "
     "second hump, TC -12 %, peak +27 %", False),
    # ok but wrong on main at 6efe980 (seed 3): the spike's ramp, cut by its drop between two samples, rose
    # 6.5 % of the peak per sample; the largest sample stood 5.1 % below the top (a marginal trace: its samples
    # cannot pin the top to 5 %, and the middle of the range they allow is within 2.4 %)
    ("spike-top-between-samples-50kHz", 3, 823, "punctured ball at 50 kHz, its spike's top 0.9 sample after the "
     "largest sample: peak -5.1 %", True),
]


#: Traces of the benchmark excluded for plate ringing on main at commit 3a907e8 although measurable: with the
#: plate's resonance identified and undone they must now be ok and right (name, seed, index, what).
ZOO_UNDONE = [
    ("plate-6.3kHz-damped-at-50kHz", 0, 41, "6.3 kHz plate, damping 0.157, at 50 kHz: peak on the ringing"),
    ("plate-12.4kHz-spike-at-98kHz", 0, 42, "13.6 kHz plate under a pre-buckling spike at 98 kHz"),
    ("plate-14.6kHz-at-40kHz", 0, 48, "14.6 kHz plate, damping 0.038, at 40 kHz: peak +16 % before"),
    ("plate-8kHz-at-50kHz", 0, 293, "7.7 kHz plate, damping 0.048, at 50 kHz"),
]


#: Traces of the benchmark excluded on main at 58169d8 although measurable (the exact inverse of the plate
#: amplified the noise past its guards): the undone force low-passed on a compact kernel brings them back, ok
#: and right (name, seed, index, what).
ZOO_LOWPASSED = [
    ("plate-8kHz-at-199kHz", 0, 10, "8 kHz plate, damping 0.10, at 199 kHz: undone noise 0.6 % of the peak"),
    ("plate-11.6kHz-at-132kHz", 0, 728, "11.6 kHz plate, damping 0.13, at 132 kHz: a ringing line left"),
    ("plate-18kHz-spike-at-198kHz", 0, 1412, "18 kHz plate under a pre-buckling spike at 198 kHz: TC too uncertain"),
]


#: Traces of the benchmark excluded on main at 042c839 although measurable: the instrumental-variable
#: identification was a few per cent off in fn and the undone force still rang; refined to the resonance that
#: leaves the least ringing in it, it is undone, ok and right (name, seed, index, what).
ZOO_REFINED = [
    ("plate-12.9kHz-at-199kHz-refined", 0, 350, "12.9 kHz plate, damping 0.027, identified at 12.3 kHz, 0.08"),
    ("plate-9.3kHz-at-167kHz-refined", 0, 1552, "9.3 kHz plate, damping 0.019, identified at 9.05 kHz, 0.08"),
]


#: Traces of zoo seed 704 excluded on main at cff9dbf although measurable: the plate's undoing was refused by a
#: check that sees something instead of judging what it does to TC (one case per refusal, or per fault taken for
#: one); ok and right now (name, seed, index, what).
ZOO_JUDGED_BY_EFFECT = [
    ("identifications-disagree-76kHz", 704, 1122, "two identifications 0.3 % apart on TC: now charged to its end"),
    ("lowpass-flattens-the-peak-127kHz", 704, 170, "the low-pass lowers the peak: now the peak alone is withheld"),
    ("fitted-ends-beyond-the-kernel-148kHz", 704, 900, "fitted TC shorter than the kernel explains: excess charged"),
    ("lowpass-may-hide-the-peak-82kHz", 704, 62, "an identified plate's low-pass may hide the peak: peak withheld"),
    ("lowpassed-end-checks-72kHz", 704, 136, "the low-passed force's own end check: its ends are fitted"),
    ("ringing-taken-for-a-second-contact-73kHz", 704, 1478, "the contact split by the plate's ringing: one impact"),
]


#: Zoo traces whose TC came out ok and 4.5-4.9 % wrong on a9b3ff2 (held-out seed 804, looked at since), and the TC
#: outcome now (name, seed, index, what, outcome).
ZOO_TC_OK_BUT_WRONG_MENDED = [
    ("jump-before-a-steeper-plate-swing-97kHz", 804, 1222,
     "a 27 kHz plate swings back up faster than the jump: the jump was lost, TC -4.5 % ok", "ok_right"),
    ("slow-alias-at-the-end-29kHz", 804, 124,
     "a 29.3 kHz plate at 29.2 kHz (daq.bandwidth_hz stated) aliases near zero: the end read on its tail, TC +4.9 % ok",
     "withheld_wrong"),
]

#: Zoo traces whose peak came out ok and 29-42 % high on 8e1f051 (held-out seeds 808-811, looked at since): a plate of
#: 0.56-0.69 kHz identified and refused beside a faint line above 3 kHz, which stood for what was not undone
#: (name, seed, index, what).
ZOO_PEAK_OK_BUT_WRONG_MENDED = [
    ("low-plate-refused-beside-a-line-87kHz", 809, 3210, "a 0.56 kHz plate, a 3 kHz line: peak +42 % ok"),
    ("low-plate-refused-beside-a-line-21kHz", 808, 1626, "a 0.69 kHz plate: peak +29 % ok"),
]


#: Zoo traces whose kCAL came out ok and 2.9-3.1 % low on 7fa9353 (seeds 816 and 818, held out until looked at): the
#: contact's end undetermined and found 50-127 % late, the integral taken over what followed the contact. The end's
#: findings now bias kCAL by the signal over the span the end may move, and withhold it where no span is known
#: (name, seed, index, what).
ZOO_KCAL_OK_BUT_WRONG_MENDED = [
    ("end-in-the-noise-kcal-5.5kHz", 818, 1132, "an end 0.2 ms into the noise, TC +50 %: kCAL -3.1 % ok"),
    ("end-no-line-pins-kcal", 816, 2762, "no line pins the end, TC +127 %: kCAL -2.9 % ok"),
]


_QUANTITY_MENDED = ([(*c, "peak") for c in ZOO_PEAK_OK_BUT_WRONG_MENDED]
                    + [(*c, "kcal") for c in ZOO_KCAL_OK_BUT_WRONG_MENDED])


@pytest.mark.parametrize("name, seed, index, what, quantity", _QUANTITY_MENDED, ids=[c[0] for c in _QUANTITY_MENDED])
def test_zoo_quantity_ok_but_wrong_mended(name, seed, index, what, quantity, tmp_path):
    trace = zoo.trace_for(seed, index)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    assert judgement.outcomes[quantity] == "withheld_wrong", (what, judgement.errors, result.reason)


@pytest.mark.parametrize("name, seed, index, what, outcome", ZOO_TC_OK_BUT_WRONG_MENDED,
                         ids=[c[0] for c in ZOO_TC_OK_BUT_WRONG_MENDED])
def test_zoo_tc_ok_but_wrong_mended(name, seed, index, what, outcome, tmp_path):
    trace = zoo.trace_for(seed, index)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    assert judgement.outcomes["tc"] == outcome, (what, judgement.errors, result.reason)


#: Traces of the benchmark excluded on main at 10b1d50 although measurable, for a peak between samples only (a damped
#: plate's overshoot rises steeply to it): the step response is evidence of the plate, whose resonance is then
#: identified and undone, ok and right (name, seed, index, what).
ZOO_STEP_UNDONE = [
    ("plate-9.4kHz-damped-undone-50kHz", 2, 1973, "9.4 kHz plate, damping 0.18, at 50 kHz: peak between samples"),
]
# 1:1858 (14.1 kHz plate, damping 0.23, at 43 kHz) came back ok and right this way on its own branch; with the
# low-passed ends fitted (plate.undone_end) its two identifications disagree by 0.44 % on TC, and it is excluded.

#: Traces of the benchmark excluded on main at 10b1d50 although measurable: their plate (3-13 kHz) undone, the
#: force too noisy, and low-passed, "the undone TC is known to 2-3 % only" (two kernel half-widths charged to
#: TC) or its ends not determined. The low-passed force's ends are now fitted through the plate's undoing and the
#: kernel (``plate.undone_end``): ok and right (name, seed, index, what).
ZOO_LOWPASS_ENDS = [
    ("lowpass-ends-6.9kHz-punctured", 2, 853, "6.9 kHz plate, damping 0.046, punctured ball at 50 kHz (one factor)"),
    ("lowpass-ends-3.8kHz-pressurised", 1, 1749, "3.8 kHz plate, damping 0.11, pressurised ball at 50 kHz (one "
     "factor)"),
    ("lowpass-ends-12.8kHz-pressurised", 2, 1077, "12.8 kHz plate, damping 0.03, pressurised ball at 50 kHz (one "
     "factor)"),
]

#: Traces of the benchmark excluded on main at 03757a8 although measurable: their plate identified, the exact undone
#: force "starts later than the sensed one (a foot lost in its noise)" (the sensed start read 2-7 samples early, on
#: the plate's first overshoot) or "the undone TC is known to 1 % only (noise over slope at its ends)". Its ends
#: are now fitted through the plate (``plate.undone_end`` with no low-pass), and the sensed samples before the fitted
#: start hold no foot: ok and right (name, seed, index, what).
ZOO_EXACT_ENDS = [
    ("exact-ends-12.9kHz-punctured", 2, 1469, "12.9 kHz plate, damping 0.010, punctured ball at 50 kHz (one factor): "
     "sensed start 6.7 samples early"),
    ("exact-ends-15.3kHz-pressurised", 1, 713, "15.3 kHz plate, damping 0.092, pressurised ball at 50 kHz (one "
     "factor): sensed start 2.7 samples early"),
    ("exact-ends-13.3kHz-56kHz", 1, 472, "13.3 kHz plate, damping 0.012, at 56 kHz: the undone TC known to 1.0 % only"),
]

#: Traces of the benchmark excluded on main at 03757a8 although measurable: their plate undone and low-passed, "the
#: exact undone force is too noisy to show that the low-pass keeps its peak" (its largest sample against the
#: low-passed peak). Read from fits of the samples around each (the pre-buckling ramp one-sided, then centred,
#: ``conditioning._fitted_force``), the exact undone force shows the low-pass keeps its peak: ok and right (name,
#: seed, index, what).
ZOO_FITTED_TOP = [
    ("fitted-top-8.2kHz-damped-54kHz", 0, 686, "8.2 kHz plate, damping 0.17, at 54 kHz: a loss of 4.7 % unseen"),
    ("fitted-top-16.9kHz-174kHz", 2, 26, "16.9 kHz plate, damping 0.09, at 174 kHz: a loss of 4.3 % unseen"),
    ("fitted-top-13.8kHz-spike-121kHz", 1, 1388, "13.8 kHz plate, damping 0.18, under a pre-buckling-spike peak at "
     "121 kHz: a loss of 5.3 % unseen"),
]

#: Traces of the benchmark excluded on main at 03757a8 although measurable, for a peak between samples only (a
#: damped plate's ringing from the jump rises steeply to it): that ringing, fitted, is evidence of the plate, whose
#: resonance is then identified and undone, ok and right (name, seed, index, what).
ZOO_FRONT_UNDONE = [
    ("plate-17.4kHz-front-ringing-undone", 1, 272, "17.4 kHz plate, damping 0.14, punctured ball at 146 kHz"),
    ("plate-16.3kHz-front-ringing-undone", 2, 936, "16.3 kHz plate, damping 0.12, pressurised ball at 124 kHz"),
]

#: Traces of the benchmark excluded on main at ed0c366 although measurable: "no decaying oscillation identified out
#: of the noise in the contact and the 2 ms after it" (a damped plate's short ringing drowned, in the recursion's
#: fit, by the force's own second difference over the whole contact). Identified from the free ringing after the
#: contact alone (``plate.identify_free_ringing``) and undone, ok and right (name, seed, index, what).
ZOO_FREE_RINGING = [
    ("free-ringing-3.5kHz-damped-196kHz", 2, 600, "3.5 kHz plate, damping 0.22, at 196 kHz: force below zero after"),
    ("free-ringing-3.2kHz-137kHz", 3, 388, "3.2 kHz plate, damping 0.11, at 137 kHz: force below zero after"),
    ("free-ringing-4.1kHz-129kHz", 2, 1176, "4.1 kHz plate, damping 0.15, at 129 kHz: peak on plate ringing"),
    ("free-ringing-11kHz-125kHz", 3, 752, "11 kHz plate, damping 0.098, at 125 kHz: peak between samples"),
]

#: How close the undone resonance must be to the plate's for the cases above that check it [-].
#: (ZOO_FRONT_UNDONE's identified from a short ringing: 2:936's 10.4 % high, its undone force right all the same).
UNDONE_FN_TOLERANCE = {**{c[0]: 0.1 for c in ZOO_STEP_UNDONE},
                       **{c[0]: 0.03 for c in ZOO_LOWPASS_ENDS + ZOO_EXACT_ENDS + ZOO_FREE_RINGING},
                       **{c[0]: 0.15 for c in ZOO_FRONT_UNDONE}}


@pytest.mark.parametrize("name, seed, index, what",
                         named(ZOO_UNDONE + ZOO_LOWPASSED + ZOO_REFINED + ZOO_STEP_UNDONE + ZOO_LOWPASS_ENDS
                               + ZOO_EXACT_ENDS + ZOO_FITTED_TOP + ZOO_FRONT_UNDONE + ZOO_FREE_RINGING
                               + ZOO_JUDGED_BY_EFFECT))
def test_zoo_ringing_plate_undone(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz is not None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    if name in LOWPASSED_SPIKE_EXCLUDED:  # undone, TC and kCAL right, the low-passed spike's top not known
        assert_invariant(trace, result, judgement, excluded_with="may be the pre-buckling spike")
        assert [p.kind for p in result.problems if "cloth's phase" not in p.message] == \
            [ProblemKind.PEAK_ON_RINGING], result.reason
        assert abs(judgement.errors["tc"]) < 0.01 and abs(judgement.errors["kcal"]) < 0.01, judgement.errors
    else:
        assert_invariant(trace, result, judgement, must_be_ok=True)
    assert result.plate_resonance_hz > 0  # undone
    if name in UNDONE_FN_TOLERANCE:
        assert result.plate_resonance_hz == pytest.approx(trace.rig.plate_hz, rel=UNDONE_FN_TOLERANCE[name])


#: Zoo traces whose plate's undoing was not tried on 7fa9353, because beside its ringing the amplifier's undershoot
#: was not measurable (a finding of kCAL and the peak only, which cannot fake a plate's ringing): TC withheld though
#: right. The plate is undone now, TC ok and right, and kCAL still withheld for the undershoot (name, seed, index,
#: what).
ZOO_UNDONE_BESIDE_DECAY = [
    ("undone-beside-undershoot-12kHz-54kHz", 704, 850, "12.1 kHz plate, damping 0.082, at 53.6 kHz"),
    ("undone-beside-undershoot-11.7kHz-punctured", 704, 988, "11.7 kHz plate, damping 0.057, at 64.1 kHz"),
    ("undone-beside-undershoot-26kHz-112kHz", 704, 1296, "26.4 kHz plate, damping 0.016, at 112 kHz"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_UNDONE_BESIDE_DECAY))
def test_zoo_plate_undone_beside_the_amplifier_s_decay(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)
    assert result.plate_resonance_hz > 0, (what, result.reason)  # undone
    assert judgement.outcomes["tc"] == "ok_right", (what, judgement.errors, result.reason)
    assert result.kcal_status == "withheld" and "undershoot_not_measurable" in result.reason_code, result.reason


#: Zoo traces whose plate the trace identified itself but could neither undo nor measure again in its free ringing:
#: on 8a95c2c not fitted through (TC withheld, the sensed ends' TC 1.1-1.6 % short). Their ends fitted through the
#: plate in the sensed force, with its resonance and damping charged at SENSED_OWN_FN_UNCERTAINTY and
#: SENSED_OWN_ZETA_UNCERTAINTY, give TC ok and right (name, seed, index, what).
ZOO_OWN_PLATE_UNMEASURED = [
    ("own-plate-6.8kHz-30kHz", 704, 294, "6.8 kHz plate, damping 0.027, at 30.0 kHz, sensed TC -1.16 %"),
    ("own-plate-4.9kHz-27kHz", 704, 2912, "4.9 kHz plate, damping 0.060, at 27.4 kHz, sensed TC -1.59 %"),
    ("own-plate-3.1kHz-one-factor", 704, 2365, "3.1 kHz plate, damping 0.19, at 50 kHz, sensed TC -1.11 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_OWN_PLATE_UNMEASURED))
def test_zoo_ends_fitted_through_the_trace_s_own_plate(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)
    assert judgement.outcomes["tc"] == "ok_right", (what, judgement.errors, result.reason)
    fitted = [p for p in result.problems if p.kind is ProblemKind.PLATE_RINGING and p.data.get("ends_fitted")]
    assert fitted and 0.0 < fitted[-1].effects["contact_time"] < 0.01, (what, result.reason)


def test_the_amplifier_s_decay_findings_beside_the_plate_cannot_bias_tc():
    from ballimpact.checks import check_of
    from ballimpact.signal.undone import DECAY_KINDS, PLATE_KINDS

    for kind in DECAY_KINDS:
        check = check_of(kind)
        assert not check.fault and "contact_time" not in check.biases and kind not in PLATE_KINDS, kind


#: Cases above whose peak is the pre-buckling spike of a force undone from its plate and low-passed: ok and right
#: until ``conditioning._lowpassed_spike`` (peak -0.5 % and -2.2 %), excluded since for that peak alone; the
#: kernel's loss on such a spike, 2.1 % on average over zoo seeds 0-14, reached -6.3 % on traces the other checks
#: passed (ZOO_HELD_OUT_MEASURABLE_EXCLUDED). 1:272, at 146 kHz without ``daq.bandwidth_hz`` (no v1.1 plate
#: aliases above 60 kHz), has its peak withheld since, the impact ok (processing.peak_can_be_withheld); 1:1388
#: states its plate's 13.8 kHz, identified 12 % off, so a filter rounding the front is not ruled out.
LOWPASSED_SPIKE_EXCLUDED = {"fitted-top-13.8kHz-spike-121kHz", "plate-17.4kHz-front-ringing-undone"}
LOWPASSED_SPIKE_WITHHELD = {"plate-17.4kHz-front-ringing-undone"}


#: Ideal-plate traces of the benchmark excluded on main at 58169d8 for "plate ringing at 3.0-3.4 kHz during the
#: contact" (a bump of 0.007-0.023 % of the peak on the force's own steep spectrum, at the band's edge): ok and
#: right now (name, seed, index, what).
ZOO_EDGE_BUMP = [
    ("ideal-oversize-3.0kHz-bump", 0, 1583, "oversize ball, ideal plate, 0.39 mV noise: a 3.02 kHz 'line' of 0.013 %"),
    ("ideal-pressurised-3.4kHz-bump", 1, 1841, "pressurised ball, ideal plate: a 3.39 kHz 'line' of 0.021 %"),
]


#: Traces of the benchmark still ok but wrong on main (strict xfail: this test turns red when one is fixed,
#: so that it moves to ZOO_REGRESSION): the kinds docs/robustness.md lists under "What remains".
ZOO_STILL_WRONG: list = [
    # ("plate-15.5kHz-above-nyquist", 1, 1220, ...): excluded since the first-overshoot check, ZOO_ALIAS_EXCLUDED
    # ("plate-20.5kHz-above-nyquist", 2, 710, ...): kCAL +1.9 %, peak -14.6 %; excluded since the end's bend is
    # taken without a price, for its end (the bent hinge's uncertainty), not for the alias: the class stands
    ("plate-26.4kHz-above-nyquist", 1, 248, "26.4 kHz plate sampled at 20.1 kHz, no anti-aliasing: kCAL +1.08 %"),
    # held-out seed 28 (first run on d43008f): the plate's overshoot of the jump rides on the pre-buckling spike at
    # 3.6 samples a period, its ringing hidden in the buckling drop (docs/robustness.md, "What remains")
    ("plate-10.1kHz-overshoot-on-the-spike-36kHz", 28, 896, "10.1 kHz plate at 36.3 kHz: peak +17.5 %"),
    # held-out seed 34 (first run on 8738d3e): noise 0.7 % of a 0.55 V peak and a 12.4 kHz plate at 3.9 samples a
    # period that nothing identifies; its rise puts the start 0.68 samples late (the hinge's own uncertainty 0.1), and
    # the bent hinge meets zero 1.5 samples before the fade's end: each within its budget, together TC -1.07 %
    ("noisy-fade-and-a-12.4kHz-plate-at-the-start", 34, 1810, "12.4 kHz plate at 48.7 kHz, noise 0.7 %: TC -1.07 %"),
]


#: Of those, right since per-quantity verdicts: below 60 kHz without daq.bandwidth_hz kCAL and the peak are withheld
#: (an alias moves them unseen), TC kept; and since the start read at the jump is completed by the cloth's phase
#: (TC judged from the first contact): 34:1810, its late start no longer read on the plate's rise (TC -0.84 %).
ZOO_RIGHT_NOW = {"plate-26.4kHz-above-nyquist", "plate-10.1kHz-overshoot-on-the-spike-36kHz",
                 "noisy-fade-and-a-12.4kHz-plate-at-the-start"}


@pytest.mark.parametrize("name, seed, index, what", [
    pytest.param(*c, id=c[0], marks=[] if c[0] in ZOO_RIGHT_NOW else
                 pytest.mark.xfail(strict=True, raises=AssertionError, reason=f"issue 9: {c[3]}"))
    for c in ZOO_STILL_WRONG])
def test_zoo_case_still_wrong(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index, bandwidth_known=False)  # without daq.bandwidth_hz: see ZOO_ALIASED_BANDWIDTH
    # 2:710's largest sample is 94 % of the peak: marginal, not measurable, and judged as ok and wrong all the same
    # (this line once asked for measurable only, so the strict xfail held whatever the processing did)
    assert trace.truth.measurable or trace.truth.marginal, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)


#: Held-out seeds' traces wrong when first run, excluded since (name, seed, index, text of the reason, what):
#: - 7:265 (ok but wrong on 97636b8): a heavily damped low plate (3.93 kHz, damping ratio 0.267) identified (3.85 kHz,
#:   0.20) and undone, the pre-buckling spike's peak 9.2 % low (TC +0.15 %, kCAL +0.07 %); the undone peak moves by
#:   3.2 % with the damping ratio 25 % off (``conditioning._undone_peak_spread``). A marginal trace (a spike on a
#:   resonant plate): it may be excluded, but an ok must be right.
#: - 9:476 (faulty and ok on c3dd4da): the record starts 86 % into a punctured ball's contact, whose tail (1.6 % of
#:   the peak, 0.5 ms) is below the contact threshold, and a second contact (80 % of the first) 15 ms later was
#:   measured in its place: TC +24.7 %, kCAL -21.4 % against the impact the gates timed. Force from the record's
#:   first sample on, before the contact, is an impact the record truncated (``conditioning._edge_event_problems``).
ZOO_HELD_OUT_EXCLUDED = [
    ("damped-3.9kHz-plate-spike-undone-low", 7, 265, "peak force not determined",
     "ok but wrong on 97636b8: plate undone with damping 0.20 for 0.267, peak -9.2 %"),
    ("punctured-tail-at-the-record-start", 9, 476, "force at the record's start",
     "faulty ok on c3dd4da: TC +24.7 %, kCAL -21.4 %"),
    # 11:342 (ok but wrong on acdca8c): a 667 Hz plate ringing through a 24 ms record; the fit's 60 Hz hum (28 mV
    # drawn) came out at volts and bent the baseline under the contact by more than the peak, excluded since by
    # ``conditioning._baseline_bend_problems``. With events from 0.5 % of the peak and their shoulders
    # (EVENT_FRACTION, EVENT_SHOULDER_SIGMA) the iteration settles on other windows and masks, where the hum does
    # not bend: excluded for the ringing itself (a plate below 3 kHz, marginal).
    ("hum-fit-unpinned-by-a-short-ringing-record", 11, 342, "plate ringing outlasts the contact",
     "ok but wrong on acdca8c: TC +153 %, kCAL -99 %"),
    # 13:41 (ok but wrong on 7315197): a 3.83 kHz plate at 50 kHz, undone and low-passed at 8.8 kHz; the kernel
    # took the pre-buckling spike's top (``conditioning._lowpassed_spike``)
    ("spike-top-lowered-by-the-undone-force-low-pass", 13, 41, "may be the pre-buckling spike",
     "ok but wrong on 7315197: peak -5.5 %"),
    # 11:617 (ok but wrong on 7315197): at 25.7 kHz the jump's sample is on the spike's ramp, and the one after it
    # a lower maximum whose top fell before the drop (``conditioning._peak_between_samples``)
    ("spike-top-after-the-jumps-sample-25.7kHz", 11, 617, "peak force between samples",
     "ok but wrong on 7315197: peak -7.9 %"),
    # 19:218 (faulty and ok on 806b3d6): a second contact starting 0.1 ms before the record's end, its force at
    # 6.5 % of the peak there, the samples (delayed by a 3.3 kHz plate) rising to 4 % (``_end_event_problems``)
    ("second-contact-starting-at-the-record-end", 19, 218, "force rising at the record's end",
     "faulty ok on 806b3d6: a second contact cut off by the record's end"),
]


#: Held-out measurable traces ok but wrong when first run, excluded since: the exclusion is a measurable trace
#: lost (the 2 % target's cost), the lesser failure (name, seed, index, text of the reason, what). The first three a
#: spike peak of a force undone from its plate and low-passed (``conditioning._lowpassed_spike``): over zoo seeds
#: 0-14 the 85 such peaks reported came out 2.1 % low on average, down to -6.3 %. 33:674 (ok but wrong on 8738d3e):
#: a 1.5 V electrical spike on the second sample of the jump from zero (50.7 kHz, ideal plate), whose second
#: differences there have no isolated spike's shape, taken for the peak (``conditioning._peak_between_samples``,
#: PEAK_ALONE_FRACTION); at 50.7 kHz without ``daq.bandwidth_hz`` the peak is not withheld but the impact excluded.
ZOO_HELD_OUT_MEASURABLE_EXCLUDED = [
    ("damped-11.9kHz-plate-refined-spike-low", 11, 784, "may be the pre-buckling spike",
     "ok but wrong on 7315197: damping 0.145 refined to 0.072, low-passed at 16.3 kHz, peak -6.3 %"),
    ("10.2kHz-plate-fn-6pc-off-spike-low", 14, 1538, "may be the pre-buckling spike",
     "ok but wrong on 7315197: fn identified 5.7 % high, low-passed at 14.3 kHz, peak -5.6 %"),
    ("13.2kHz-plate-fn-6pc-off-spike-low", 14, 1632, "may be the pre-buckling spike",
     "ok but wrong on 7315197: fn identified 6.2 % low, low-passed at 17.2 kHz, peak -5.2 %"),
    ("electrical-spike-on-the-jumps-second-sample", 33, 674, "the largest sample stands alone",
     "ok but wrong on 8738d3e: peak +32 %"),
]


@pytest.mark.parametrize("name, seed, index, reason, what, measurable",
                         named([(*c, False) for c in ZOO_HELD_OUT_EXCLUDED]
                               + [(*c, True) for c in ZOO_HELD_OUT_MEASURABLE_EXCLUDED]))
def test_zoo_held_out_case_excluded(name, seed, index, reason, what, measurable, tmp_path):
    trace = zoo.trace_for(seed, index)
    # faulty: excluded is right; otherwise excluded is a trace lost, ok would have to be right
    assert not (measurable and trace.truth.fault), name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with=reason)


@pytest.mark.parametrize("offset", [-1, 0, 1, 2, 3])
@pytest.mark.parametrize("amp_v", [-1.5, -0.3, 0.3, 1.5, 3.0])
def test_zoo_electrical_spike_across_the_jump_never_ok_and_wrong(offset, amp_v, tmp_path):
    """Held-out 33:674's rig (50.7 kHz, ideal plate, oversize ball at 22.5 m/s) with one electrical spike moved
    across the force's jump: from the sample before the contact to its fourth sample, either sign, 0.3-3 V (the
    peak is 2.09 V). On 8738d3e a 1.5 V spike on the jump's second sample (offset 1) passed as the peak, +32 %."""
    base = zoo.trace_for(33, 674)
    fs, n = base.sample_rate_hz, base.voltage_V.size
    k = int(math.ceil(base.truth.start_s * fs)) + offset  # offset 0: the contact's first sample
    trace = zoo.trace_for(33, 674, spikes=(((k + 0.5) / n, amp_v),))
    assert trace.truth.tc_s == base.truth.tc_s  # the same impact, another spike
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)


#: Held-out measurable traces ok but wrong when first run, ok and right since (name, seed, index, what):
#: - 25:1094 (ok but wrong on a08c763): a second contact of 1.3 % of the peak 17.8 ms after a contact, in a 36 ms
#:   record with 12 mV of hum and its harmonics; the five-harmonic hum fit took up part of it, its rest (0.6 % of
#:   the peak) stayed under the event threshold (then 1 %), and the hum bent under the contact
#:   (``conditioning._event_mask``: EVENT_FRACTION, EVENT_SHOULDER_SIGMA). Run by test_zoo_case_ok_and_right.
ZOO_HELD_OUT_RIGHT = [
    ("small-second-contact-in-a-short-hum-record", 25, 1094, "ok but wrong on a08c763: TC -0.85 %, kCAL +1.21 %"),
]


#: Aliased plates, ok but wrong without ``daq.bandwidth_hz`` (the class ZOO_STILL_WRONG keeps): stated, the
#: plate's resonance above fs/2 excludes the impact (name, seed, index, what).
ZOO_ALIASED_BANDWIDTH = [
    ("plate-20.5kHz-at-21.4kHz", 0, 1236, "ok but wrong without the key on 7a75a4b: kCAL -1.14 %"),
    ("plate-20.5kHz-at-20.6kHz", 2, 710, "ok but wrong without the key on 7a75a4b: kCAL +1.9 %, peak -14.6 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_ALIASED_BANDWIDTH))
def test_zoo_aliased_plate_excluded_when_the_bandwidth_is_given(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index, bandwidth_known=True)
    assert trace.rig.bandwidth_hz > 0.5 * trace.sample_rate_hz, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="above half the sample rate")
    assert ProblemKind.ALIASING in {p.kind for p in result.problems}


#: Measurable traces excluded for their peak alone: the pre-buckling spike's top between samples, an ideal plate
#: (``python bench/robustness.py --n 2000 --seed S`` on 7a75a4b). With ``daq.bandwidth_hz`` at fs/2 (an
#: anti-aliasing filter stated) the peak is withheld where that band limit rounds the front over at most 0.5 % of
#: TC (the 50 kHz cases, long contacts of punctured balls), and the impact is still excluded where it rounds it
#: more (the 21.5 kHz case, 1.3 %: on such a rounded front a peak problem was the only sign of a TC too long,
#: bench/antialias_map.py) (name, seed, index, withheld, what).
ZOO_PEAK_ALONE = [
    ("spike-top-between-samples-50kHz-a", 2, 1045, True, "excluded on 7a75a4b: peak between samples; TC +0.06 %"),
    ("spike-top-between-samples-50kHz-b", 2, 1309, True, "excluded on 7a75a4b: peak between samples; TC +0.06 %"),
    ("spike-top-between-samples-21.5kHz", 0, 1653, False, "excluded on 7a75a4b: peak between samples; TC -0.28 %"),
]


@pytest.mark.parametrize("name, seed, index, withheld, what", named(ZOO_PEAK_ALONE))
def test_zoo_peak_alone_withheld_when_aliasing_and_rounding_are_ruled_out(name, seed, index, withheld, what,
                                                                           tmp_path):
    from ballimpact.processing import peak_can_be_withheld

    trace = zoo.trace_for(seed, index)
    assert trace.rig.plate_hz is None and trace.truth.measurable, name
    keyless, j0 = zoo.run_trace(trace, tmp_path)  # bandwidth unknown: an alias withholds kCAL and the peak, TC kept
    assert_invariant(trace, keyless, j0, must_be_ok=True)
    assert keyless.kcal_status == keyless.peak_status == "withheld", keyless.withheld_note
    assert ProblemKind.PEAK_BETWEEN_SAMPLES in {p.kind for p in keyless.problems}
    fs = trace.sample_rate_hz
    assert peak_can_be_withheld(0.5 * fs, fs, trace.truth.tc_s) is withheld, name
    result, judgement = zoo.run_trace(trace, tmp_path, daq_extra={"bandwidth_hz": 0.5 * fs})
    if not withheld:
        assert result.status == "excluded" and result.peak_note == "", result.reason
        assert _kinds(result) == {ProblemKind.PEAK_BETWEEN_SAMPLES}, result.reason
        return
    assert _kinds(result) == {ProblemKind.PEAK_BETWEEN_SAMPLES}, result.reason
    assert judgement.category == "ok_right", (judgement.errors, result.reason)
    assert result.peak_note.startswith("peak force between samples") and result.peak_status == "withheld"
    assert abs(judgement.errors["tc"]) <= zoo.TOL_TC and abs(judgement.errors["kcal"]) <= zoo.TOL_KCAL


@pytest.mark.parametrize("name, seed, index, what, must_be_ok", named(ZOO_REGRESSION))
def test_zoo_regression_case(name, seed, index, what, must_be_ok, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable or trace.truth.marginal, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=must_be_ok)


def test_regression_cases_are_what_they_claim():
    # the truth of each case is the class it stands for (independent of the processing)
    for name, seed, mode, overrides, what, _ in REGRESSION:
        t = zoo.make_trace(np.random.default_rng(seed), mode, **overrides).truth
        if name.startswith(("double", "second")):
            assert t.fault == "second contact" and t.second_fraction >= 0.05, name
            assert 6e-3 <= overrides["second"][0] + t.tc_s <= 20e-3, name  # start-to-start delay
        else:
            assert t.measurable, (name, t.fault, t.marginal)


# ------------------------------------------------------------------ properties

#: No shrinking (each example runs the whole processing) and no example database.
PROPERTY = dict(derandomize=True, deadline=None, database=None, phases=[Phase.explicit, Phase.generate],
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
N_EXAMPLES = 40  # per property: about 10-20 s each on one core
MODES = st.sampled_from(("random",) + zoo.FACTORS)
SEEDS = st.integers(0, 2**32 - 1)


@settings(max_examples=N_EXAMPLES, **PROPERTY)
@given(seed=SEEDS, mode=MODES)
def test_process_impact_always_gives_ok_or_a_reason(seed, mode):
    # holds today: whatever the rig, a result, and an exclusion always says why
    trace = zoo.make_trace(np.random.default_rng(seed), mode)
    result, judgement = zoo.run_trace(trace)
    assert result.status in ("ok", "excluded")
    assert (result.status == "ok") == (result.reason == "")
    assert judgement.category in zoo.CATEGORIES


@settings(max_examples=N_EXAMPLES, **PROPERTY)
@given(seed=SEEDS, mode=MODES)
# found by this property under pytest-xdist (another draw of examples) on main 042c839: a 23.3 kHz rig whose
# pre-buckling spike's top fell between the samples while the smooth part of the contact later held the largest
# sample; ok with the peak 5.9 % low
@example(seed=4000, mode="sample_rate")
def test_never_ok_and_wrong(seed, mode):
    trace = zoo.make_trace(np.random.default_rng(seed), mode, truncate="", clip_factor=0.0, second=None)
    result, judgement = zoo.run_trace(trace)
    assert judgement.category != "ok_wrong", (judgement.errors, zoo.describe(trace.rig))


@settings(max_examples=N_EXAMPLES, **PROPERTY)
@given(seed=SEEDS, mode=st.sampled_from(("second_contact", "truncated", "clipped", "random")),
       fraction=st.floats(0.06, 1.0), gap_s=st.floats(1e-3, 40e-3))
def test_faulty_never_ok(seed, mode, fraction, gap_s):
    rng = np.random.default_rng(seed)
    overrides = {"post_s": 0.08}
    if mode in ("second_contact", "random"):
        overrides["second"] = (gap_s, fraction, 12.0)
    trace = zoo.make_trace(rng, mode, **overrides)
    assume(trace.truth.fault)  # always true: every such draw is faulty (tests/test_zoo.py)
    result, judgement = zoo.run_trace(trace)
    assert judgement.category != "faulty_ok", (judgement.errors, zoo.describe(trace.rig))
    assert result.status == "excluded"


def test_undone_plate_is_reported_on_the_impact(tmp_path):
    # zoo 0:41: a 6.26 kHz plate (damping 0.157) at 50 kHz; the resonance undone is on the ImpactResult
    trace = zoo.trace_for(0, 41)
    result, _ = zoo.run_trace(trace, tmp_path)
    assert result.plate_resonance_hz == pytest.approx(trace.rig.plate_hz, rel=0.03)
    assert result.plate_damping_ratio == pytest.approx(trace.rig.plate_zeta, rel=0.1)
    # an ideal plate has none
    result, _ = zoo.run_trace(zoo.trace_for(0, 1), tmp_path)
    assert math.isnan(result.plate_resonance_hz)


#: Traces of the benchmark excluded on main at 042c839 for "no quiet baseline both before and at least 2 ms
#: after the contact" although measurable: a record ending 1.9-3.2 ms after the contact. The post stretch of the
#: baseline fit now starts 0.5 ms after the contact when the 2 ms ringing guard leaves too little, and the
#: decay's standard error decides: ok and right (name, seed, index, what).
ZOO_SHORT_POST = [
    ("short-post-tau-16s-60Hz-absent", 0, 602, "2.0 ms after the contact, 16 s amplifier not given, 20 mV of "
     "60 Hz hum, mains absent"),
    ("short-post-dc-1.9ms", 1, 794, "1.9 ms after the contact, DC amplifier not given, 21.8 kHz plate"),
    ("short-post-dc-short-pre", 1, 1804, "1.8 ms pre-trigger and 3.2 ms after the contact, DC amplifier not given"),
]

#: ... and for "charge-amplifier undershoot not measurable" (or a window that did not settle over it) with no hum
#: or little: 5 hum harmonics fitted over about one period took up the undershoot's step; the fit with fewer of
#: them, of least BIC, measures it (name, seed, index, what).
ZOO_FEWER_HARMONICS = [
    ("no-hum-60Hz-given-5.5ms-pre", 1, 742, "5.5 ms pre, 16 ms post, no hum, 60 Hz given, 10 s amplifier not given"),
    ("no-hum-50Hz-given-3.4ms-pre", 0, 1346, "3.4 ms pre, 22 ms post, no hum, 50 Hz given, 24 s amplifier not given"),
    ("hum-0.7mV-3.7ms-pre", 1, 236, "3.7 ms pre, 29 ms post, 0.7 mV of 50 Hz given, 1.9 s amplifier not given"),
]


@pytest.mark.parametrize("name, seed, index, what",
                         named(ZOO_SHORT_POST + ZOO_FEWER_HARMONICS))
def test_zoo_decay_measured_in_short_records(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable, name
    assert trace.rig.tau_known is False, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    if name in PEAK_REFUSED:  # the decay is measured: no baseline or decay problem is left
        without = zoo.trace_for(seed, index, bandwidth_known=False)  # no daq.bandwidth_hz: excluded for its peak
        result, judgement = zoo.run_trace(without, tmp_path)
        assert_invariant(trace, result, judgement)
        assert not {p.kind for p in result.problems} & BASELINE_KINDS, result.reason
        assert result.problems, result.reason
        assert _kinds(result) <= {ProblemKind.PEAK_BETWEEN_SAMPLES, ProblemKind.ALIASING}, result.reason
        # its plate (6.1 kHz at 40 kHz) stated: no alias, but a band limit that rounds the front over 2 % of TC,
        # where a peak problem may be the only sign of a TC too long: still excluded, its peak not withheld
        result, judgement = zoo.run_trace(zoo.trace_for(seed, index, bandwidth_known=True), tmp_path)
        assert result.status == "excluded" and result.peak_note == "", result.reason
        assert _kinds(result) == {ProblemKind.PEAK_BETWEEN_SAMPLES}, result.reason
    else:
        assert_invariant(trace, result, judgement, must_be_ok=True)


#: Zoo traces excluded on 382429f for a problem of the peak alone, with TC and kCAL right, whose peak is withheld
#: now (processing.peak_can_be_withheld) (name, seed, index, withheld, what): aliasing is ruled out without the key
#: at twice raw-format v1.1's highest plate resonance (60 kHz) or faster, and with the key where it is the
#: resonance of the plate undone (no filter left to round the front). Below 60 kHz without the key an alias may
#: hide behind the peak (22:710, an aliased plate excluded for its peak alone, had kCAL -2.7 %).
ZOO_PEAK_WITHHELD = [
    ("keyless-72kHz-spike-top-between-samples", 0, 510, True, "8.3 kHz plate (damping 0.26): TC +0.11 %"),
    ("key-is-the-undone-4.9kHz-plate-at-85.9kHz", 0, 698, True, "rounding 1/(2 fn) 2.7 % of TC: TC -0.16 %"),
    ("keyless-34.9kHz-spike-top-between-samples", 0, 14, False, "ideal plate: an alias not ruled out"),
    ("keyless-24.6kHz-aliased-plate", 22, 710, False, "26 kHz plate: kCAL -2.7 %, peak +12 %"),
]


@pytest.mark.parametrize("name, seed, index, withheld, what", named(ZOO_PEAK_WITHHELD))
def test_zoo_peak_withheld_where_alias_is_ruled_out_and_the_band_limit_is_the_plate(name, seed, index, withheld,
                                                                                      what, tmp_path):
    trace = zoo.trace_for(seed, index)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    if withheld:
        assert (judgement.category == "ok_right" or zoo.withheld_for_the_cloth_alone(result)) and \
            result.peak_status == "withheld", (judgement.errors, result.reason)
        assert result.peak_note.startswith("peak force") or "peak force" in result.reason, result.peak_note
    else:  # without the key below 60 kHz: the peak and kCAL withheld (an alias not ruled out), TC kept
        assert result.peak_status == result.kcal_status == "withheld", result.withheld_note
        assert "peak force" in result.withheld_note + result.reason, result.withheld_note


#: Of those, excluded since commit a56273e for their peak: a lower sampled maximum after a steep rise (its top may
#: be above the largest sample; 1:236's was not, peak +0.16 %), which the samples cannot tell from a spike's.
#: Rigs of ``python bench/antialias_map.py --n 400 --seed S`` (a sigma-delta ADC's linear-phase filter at 0.40-0.45
#: fs, an ideal plate), each with ``daq.bandwidth_hz`` the filter's cut-off (name, seed, index, ok_wrong_on_main,
#: what). 2:339 was ok and wrong on be6b37c, its peak problem withheld: the filter rounds the contact's jump over
#: 1.7 % of TC, and a peak problem then withholds nothing (processing.PEAK_WITHHOLD_MAX_ROUNDING). 1:127 is ok and
#: wrong on main with the key as without it (a strict xfail, so that a fix shows): a spike's top the filter smoothed.
ANTIALIAS_CASES = [
    ("sigma-delta-8.8kHz-at-21.5kHz-peak-not-withheld", 2, 339, False, "ok and wrong on be6b37c: TC +1.5 %"),
    ("sigma-delta-12.5kHz-at-30.4kHz-tc-long", 1, 278, False, "TC +1.30 % from the jump; its start completed by "
     "the cloth's phase since, and TC judged from the first contact"),
    ("sigma-delta-11.1kHz-at-25.8kHz-spike-smoothed", 1, 127, True, "peak -5.85 %"),
]


@pytest.mark.parametrize("name, seed, index, what", [
    pytest.param(*c[:3], c[4], id=c[0], marks=[pytest.mark.xfail(strict=True, raises=AssertionError,
                                                               reason=f"issue 9: {c[4]}")] if c[3] else [])
    for c in ANTIALIAS_CASES])
@pytest.mark.filterwarnings("ignore:one_blas_thread:UserWarning")
def test_antialias_map_case(name, seed, index, what, tmp_path):
    antialias = bench_module("antialias_map")
    trace = antialias.trace_for(seed, index)
    assert trace.truth.measurable, name
    result, judgement = zoo.run_trace(trace, tmp_path, daq_extra={"bandwidth_hz": trace.rig.antialias_hz})
    assert_invariant(trace, result, judgement)


PEAK_REFUSED = {"hum-0.7mV-3.7ms-pre"}
BASELINE_KINDS = {ProblemKind.DECAY_NOT_CORRECTED, ProblemKind.UNDERSHOOT_NOT_MEASURABLE, ProblemKind.CONTACT_UNSTABLE,
                  ProblemKind.BASELINE_OFF_ZERO, ProblemKind.BASELINE_RESIDUAL, ProblemKind.MAINS_UNRESOLVED}


#: Traces of the benchmark ok but wrong on main at 10b1d50 (seed 3): a damped plate (damping 0.17-0.26) overshoots
#: the force's jump once, and that first overshoot is the peak, with too little ringing after it for the other checks;
#: the fall, the second bump and the fall after it within a period name it now (name, seed, index, what).
ZOO_STEP_RESPONSE = [
    ("plate-9.7kHz-damped-front-overshoot", 3, 700, "9.7 kHz plate, damping 0.17, at 146 kHz: peak +7.9 %"),
    ("plate-6.5kHz-damped-front-overshoot-21kHz", 3, 212, "6.5 kHz plate, damping 0.24, at 21 kHz: peak +10.4 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_STEP_RESPONSE))
def test_zoo_peak_on_the_plates_step_response(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable or trace.truth.marginal, name
    assert trace.rig.plate_hz is not None and trace.rig.plate_zeta > 0.15, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="the plate's step response")


#: Traces of the benchmark excluded on main at commit 10b1d50 for "contact end not determined to 1 %: fitted again
#: from the samples above twice the noise threshold it moves by ..." although measurable: the force steepens into
#: its end (a punctured ball's), the refit moves the end later, and the force's curve before the end pins it
#: (``ballimpact.signal.curve_end.end_from_curve``); ok and right now (name, seed, index, what).
ZOO_END_CURVE = [
    ("punctured-end-curve-50kHz", 0, 1463, "punctured ball at 50 kHz, 3.5 V peak: the end refitted 0.56 % later"),
    ("punctured-end-curve-86kHz", 0, 726, "punctured ball at 86 kHz, 0.9 V peak, 0.27 mV noise: refitted 0.76 % later"),
    ("punctured-end-curve-77kHz", 1, 1457, "punctured ball at 77 kHz (one factor: the sample rate)"),
]

#: Traces of the benchmark ok but wrong on main at commit 10b1d50 with a force that flattens into its end (convex):
#: the line through its last samples meets zero early and the refit from higher samples moved it by less than
#: 0.5 % of TC; the force's curve puts the end later, and the end is not determined (name, seed, index, what).
ZOO_CONVEX_END = [
    ("convex-end-punctured-50kHz", 2, 1489, "punctured ball, benign rig at 50 kHz: TC -1.09 %"),
    ("convex-end-26kHz-plate", 0, 1974, "26 kHz plate sampled at 33.5 kHz, no anti-aliasing: TC -1.5 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_CONVEX_END))
def test_zoo_convex_end_not_ok(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    assert result.status != "ok" and "the force's curve before it meets zero" in result.reason, result.reason


#: Traces of the benchmark ok but wrong on main at 03757a8: a damped plate rings from the force's jump and the
#: pre-buckling spike's top lands on a later maximum of that ringing (not its first overshoot, which the
#: step-response check judges); a jump and a ramp fitted through a plate name it, or the plate is undone and the
#: peak alone withheld for what the low-pass and the identification leave of it (name, seed, index, what).
ZOO_FRONT_RINGING = [
    ("plate-13.7kHz-spike-on-the-ringings-second-maximum", 3, 824,
     "13.7 kHz plate, damping 0.20, at 168 kHz: peak +5.3 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_FRONT_RINGING))
def test_zoo_peak_on_the_ringing_from_the_jump(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable and trace.truth.peak_is_spike, name
    assert trace.rig.plate_hz is not None and trace.rig.plate_zeta > 0.15, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    assert "ringing from the jump lifts the largest sample" in result.reason + result.withheld_note \
        or (result.peak_status == "withheld" and math.isfinite(result.plate_resonance_hz)), result.withheld_note


#: Traces of the benchmark excluded on main at 6efe980 for "contact end not determined to 1 %: fitted again from
#: the samples above twice the noise threshold it moves by ..." although measurable, on ideal plates: a punctured
#: ball's faint fade sampled at 130-190 kHz, where the force falls by less than CURVE_MIN_SLOPE noise deviations
#: per sample (the curve's search and slope now in the time of a sample at 50 kHz), and a concave fade whose last
#: sample out of low noise the hinge took for a jump (the curve is now fitted after such an end too); the force's
#: curve pins the end, and they are ok and right now (name, seed, index, what).
ZOO_FADE_END = [
    ("punctured-faint-fade-183kHz", 1, 636, "punctured ball at 183 kHz: the end refitted 1.6 % later"),
    ("punctured-faint-fade-162kHz", 3, 796, "punctured ball at 162 kHz: the end refitted 1.7 % later"),
    ("pressureless-end-taken-for-a-jump", 1, 763, "one factor (gain), 50 kHz: the end refitted 1.1 % later"),
    ("pressurised-end-taken-for-a-jump", 3, 1421, "one factor (second contact, 1 % of the peak), 50 kHz"),
]


@pytest.mark.parametrize("name, seed, index, what",
                         named(ZOO_EDGE_BUMP + ZOO_END_CURVE + ZOO_FADE_END))
def test_zoo_ideal_plate_case_ok_and_right(name, seed, index, what, tmp_path):
    """ZOO_EDGE_BUMP, ZOO_END_CURVE and ZOO_FADE_END: ideal-plate traces once excluded, ok and right now."""
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz is None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)


#: Traces of the benchmark excluded on main at 6efe980 although measurable: their plate (5.6-9.8 kHz, 10-22 samples
#: per period) undone, too noisy, and low-passed, "the exact undone force is too noisy to show that the low-pass keeps
#: its peak" (its unweighted fits' errors) or, at the three cutoffs tried, still ringing. The exact undone force is now
#: also read after buckling from centred fits weighted by its noise's covariance (``conditioning._fitted_top``), and
#: up to six cutoffs are tried: ok and right (name, seed, index, what).
ZOO_WEIGHTED_TOP = [
    ("weighted-top-9.8kHz-194kHz", 1, 1466, "9.8 kHz plate, damping 0.017, oversize ball at 194 kHz: a loss of 7.7 % "
     "unseen"),
    ("weighted-top-8.9kHz-192kHz", 2, 1380, "8.9 kHz plate, damping 0.033, at 192 kHz: a loss of 43 % unseen"),
    ("weighted-top-5.6kHz-53kHz", 3, 290, "5.6 kHz plate, damping 0.024, at 53 kHz: a loss of 11 % unseen"),
]
ZOO_MORE_CUTOFFS = [
    ("fourth-cutoff-6.7kHz-146kHz", 0, 488, "6.7 kHz plate, damping 0.077, at 146 kHz: low-passed to 18.3 kHz (the "
     "third cutoff tried) it still rang; low-passed to 12.9 kHz (the fourth) it passes"),
]


@pytest.mark.parametrize("name, seed, index, what",
                         named(ZOO_WEIGHTED_TOP + ZOO_MORE_CUTOFFS))
def test_zoo_noisy_undone_force_low_passed_with_its_peak_shown(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz is not None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)
    assert result.plate_resonance_hz == pytest.approx(trace.rig.plate_hz, rel=0.03)


#: Traces of the zoo's chain, a rig drawn in "plate" mode (seed) with these overrides, ok but wrong on main at
#: 6efe980: a lightly damped plate sampled 2.6-2.7 times a period, the contact's largest sample its first overshoot
#: of the force's jump, with too few samples up to it for the front's own check (name, seed, overrides, what,
#: must be ok: the plate then identified and undone, ok and right; else the peak withheld).
_ONE = (1.0, 1.0, 1.0, 1.0, 1.0)
ZOO_FIRST_OVERSHOOT = [
    ("plate-24.4kHz-first-overshoot-at-65kHz-a", 2,
     dict(ball="punctured", scale=_ONE, vin_m_s=12.9, sample_rate_hz=65.2e3, plate_hz=24390.0, plate_zeta=0.037,
          noise_V=0.004), "ok but wrong on 6efe980, peak +15.7 %", True),
    ("plate-24.4kHz-first-overshoot-at-65kHz-b", 3,
     dict(ball="punctured", scale=_ONE, vin_m_s=12.9, sample_rate_hz=65.2e3, plate_hz=24390.0, plate_zeta=0.037,
          noise_V=0.004), "ok but wrong on 6efe980, peak +15.0 %", True),
    ("plate-9.15kHz-first-overshoot-at-23.6kHz", 3,
     dict(ball="pressurised", scale=_ONE, vin_m_s=24.4, sample_rate_hz=23.6e3, plate_hz=9150.0, plate_zeta=0.134,
          noise_V=0.004), "ok but wrong on 6efe980, peak +14.9 %", False),
]


@pytest.mark.parametrize("name, seed, overrides, what, must_be_ok",
                         named(ZOO_FIRST_OVERSHOOT))
def test_zoo_peak_on_the_plates_first_overshoot(name, seed, overrides, what, must_be_ok, tmp_path):
    trace = zoo.make_trace(np.random.default_rng(seed), "plate", **overrides)
    assert trace.truth.measurable and trace.sample_rate_hz / trace.rig.plate_hz < 3.0, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=must_be_ok)
    if must_be_ok:
        assert result.plate_resonance_hz == pytest.approx(trace.rig.plate_hz, rel=0.03)
    else:  # the peak, the plate's first overshoot, withheld saying so; TC on its budget (no resonance out of the
        # noise to undo: a ringing hidden in it bounds the end, signal.effects)
        assert result.peak_status == "withheld", result.reason
        assert "the plate's first overshoot of the force's jump" in result.reason + result.withheld_note, \
            (result.reason, result.withheld_note)


#: A trace of the benchmark ok but wrong on main at 6efe980 (it was ZOO_STILL_WRONG's): a plate above fs/2, whose
#: alias's first overshoot of the force's jump the first-overshoot check finds; undoing that alias is refused, and
#: the trace is excluded (name, seed, index, what).
ZOO_ALIAS_EXCLUDED = [
    ("plate-15.5kHz-above-nyquist", 1, 1220, "15.5 kHz plate sampled at 20 kHz, no anti-aliasing: peak +11.7 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_ALIAS_EXCLUDED))
def test_zoo_alias_first_overshoot_excluded(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz > 0.5 * trace.sample_rate_hz, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="first overshoot of the force's jump")


#: Traces of the zoo's chain, a rig drawn in "plate" mode (seed) with these overrides (the rigs of
#: ``python bench/overshoot_map.py --n 400 --seed 2`` traces 2:202 and 2:113, ok but wrong there), ok but wrong on
#: main at ffc2770: a plate sampled 2.2-3.5 times a period rings from the force's jump, and the samples the contact's
#: start is read from swing with it (name, seed, overrides, what, must be ok: the plate then undone, ok and right).
_MAP_2_202 = dict(ball="punctured", scale=(1.0281, 1.0883, 0.9562, 0.9567, 1.0774), vin_m_s=11.47,
                  sample_rate_hz=55107.9, plate_hz=15764.1, plate_zeta=0.1055, noise_V=0.013255)
_MAP_2_113 = dict(ball="pressurised", scale=(1.0403, 0.9991, 1.1606, 1.0209, 0.838), vin_m_s=12.26,
                  sample_rate_hz=36443.5, plate_hz=16470.4, plate_zeta=0.0452, noise_V=0.017968)
ZOO_FAST_FRONT = [
    ("plate-15.8kHz-front-ringing-at-55kHz-a", 2, _MAP_2_202, "ok but wrong on ffc2770, TC +1.53 %", True),
    ("plate-15.8kHz-front-ringing-at-55kHz-b", 7, _MAP_2_202, "ok but wrong on ffc2770, TC +1.05 %", True),
    ("plate-16.5kHz-front-back-to-zero-at-36kHz", 4, _MAP_2_113, "ok but wrong on ffc2770, TC -1.53 %, kCAL +1.2 %",
     False),
]


@pytest.mark.parametrize("name, seed, overrides, what, must_be_ok",
                         named(ZOO_FAST_FRONT))
def test_zoo_contact_front_ringing_near_half_the_sample_rate(name, seed, overrides, what, must_be_ok, tmp_path):
    trace = zoo.make_trace(np.random.default_rng(seed), "plate", **overrides)
    assert trace.truth.measurable and 2.0 < trace.sample_rate_hz / trace.rig.plate_hz < 3.6, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=must_be_ok)
    if must_be_ok:  # undone (b: identified 13 % high, at 3.5 samples a period, and still ok and right)
        assert result.plate_resonance_hz == pytest.approx(trace.rig.plate_hz, rel=0.15)
    else:
        assert result.status == "excluded" and "contact start not determined to 1 %" in result.reason \
            and "swings back below" in result.reason, result.reason


#: Traces of bench/spike_top_map.py's rigs (the benign rig, noise 0.4 % of the peak, its spike the peak), ok but wrong
#: on main at ffc2770 (name, render seed, Rig fields, what, fixed now). A ramp after a swing of plate ringing was
#: lifted as a spike's: force_top keeps that sample now, ok and right. The spike's top between samples where
#: force_top keeps a sample (here the ramp's last sample is a lower maximum, the largest sample on the smooth part)
#: is judged by half a rise and passes: a strict xfail, so a fix shows (judging the whole rise excluded 168 right
#: traces of seeds 0-3, docs/robustness-history.md, cfca54b).
ZOO_SPIKE_TOP = [
    # with the end's bent hinge (contact._bent_corner) excluded for its end (TC known to +-1 % only; the line's
    # end had it +1.13 %), not for its peak, still -5.8 %: the class stands (docs/robustness.md, "What remains")
    ("spike-lower-maximum-at-23.9kHz", 5,
     dict(ball="pressurised", scale=(0.9567, 1.166, 1.023, 1.014, 1.089), vin_m_s=29.28, sample_rate_hz=23854.0,
          noise_V=0.01616, mode="noise"), "ok but wrong on ffc2770: peak -5.7 % (the spike's top between samples)",
     True),
    ("spike-ramp-after-a-swing-12.9kHz-plate-at-35.5kHz", 30,
     dict(ball="pressurised", scale=(0.9537, 1.025, 1.016, 1.041, 1.138), vin_m_s=29.58, sample_rate_hz=35450.0,
          plate_hz=12940.0, plate_zeta=0.294, noise_V=0.0159, mode="plate"),
     "ok but wrong on ffc2770: peak +7.3 % (a swing of ringing lifted by half a rise)", True),
]


@pytest.mark.parametrize("name, seed, fields, what", [
    pytest.param(*c[:4], id=c[0], marks=[] if c[4] else [pytest.mark.xfail(strict=True, raises=AssertionError,
                                                                          reason=f"issue 9: {c[3]}")])
    for c in ZOO_SPIKE_TOP])
def test_zoo_spike_top_between_samples(name, seed, fields, what, tmp_path):
    trace = zoo.render(zoo.Rig(**{**zoo._BENIGN, **fields}), np.random.default_rng(seed), name)
    assert trace.truth.peak_is_spike, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)


#: Traces of the zoo's chain, a rig drawn in "plate" mode (seed) with these overrides (the rig of
#: ``python bench/overshoot_map.py --n 400 --seed 5`` trace 5:210, ok but wrong there), ok but wrong on main at
#: ffc2770 and up to 7ce5de8: the resonance was identified near the truth, but the force undone with it failed its
#: checks; refined (least content near fn in the undone force, the ball's drop at buckling included), it moved to a
#: plate about 9 % higher and half as damped, whose undone force passed them with its pre-buckling spike low. With
#: the contact's end read by the bent hinge (``contact._bent_corner``), seed 4's force undone at the identified
#: plate (10.58 kHz, damping 0.144; true 10.53 kHz, 0.146) passes its checks: ok and right, peak -0.2 %; seed 6's
#: plate is not undone: excluded, its peak on the ringing (name, seed, overrides, what).
_MAP_5_210 = dict(ball="punctured", scale=(0.9745, 1.1043, 0.9424, 1.0135, 1.0417), vin_m_s=27.03,
                  sample_rate_hz=57489.6, plate_hz=10534.6, plate_zeta=0.1461, noise_V=0.004571)
ZOO_REFINED_SPIKE = [
    ("plate-10.5kHz-refined-off-spike-low-a", 4, _MAP_5_210, "ok but wrong on ffc2770, peak -6.6 %"),
    ("plate-10.5kHz-refined-off-spike-low-b", 6, _MAP_5_210, "ok but wrong on ffc2770, peak -6.9 %"),
]


@pytest.mark.parametrize("name, seed, overrides, what", named(ZOO_REFINED_SPIKE))
def test_zoo_refined_resonance_that_flattened_the_spike(name, seed, overrides, what, tmp_path):
    trace = zoo.make_trace(np.random.default_rng(seed), "plate", **overrides)
    assert trace.truth.measurable and trace.truth.peak_is_spike, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)


#: Zoo rigs rendered with other noise (``zoo.render`` with the generator [99, seed, index, draw], as
#: bench/fade_ends.py re-draws them), ok but wrong on main at ffc2770: a punctured ball's steep fall at 50 kHz, one
#: low sample on it, and the force's curve ending 0.92 % of TC early with a one-sigma uncertainty of 0.19 %; its
#: three-sigma interval sees the other end now, and the end is not determined (name, seed, index, draw, what).
ZOO_CURVE_SECOND_END = [
    ("punctured-curve-end-early-50kHz", 1, 707, 1, "zoo rig 1:707, noise draw 1: TC -1.09 %"),
]


@pytest.mark.parametrize("name, seed, index, draw, what", named(ZOO_CURVE_SECOND_END))
def test_zoo_curve_end_with_a_second_end_not_taken(name, seed, index, draw, what, tmp_path):
    rig = zoo.trace_for(seed, index).rig
    trace = zoo.render(rig, np.random.default_rng([99, seed, index, draw]), name)
    assert trace.truth.measurable and rig.plate_hz is None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="contact end not determined to 1 %")


#: Traces of bench/ideal_plate_map.py (seed 1), ok but wrong on main at ffc2770: an ideal plate at 31-46 kHz,
#: noise 0.3-0.4 % of the peak, a force that fades into the noise with about a noise deviation per sample; the line
#: through its last samples met zero 3 samples late and the refit from higher samples moved it by less than 0.5 % of
#: TC. The hinge's uncertainty of the end shows TC not known to 1 % now (name, seed, index, what).
ZOO_FADE_NOT_PINNED = [
    ("ideal-plate-fade-45.7kHz", 1, 30, "punctured ball, 45.7 kHz, noise 0.38 % of the peak: TC +1.70 %"),
    ("ideal-plate-fade-31.8kHz", 1, 385, "pressurised ball, 31.8 kHz, noise 0.39 % of the peak: TC +1.83 %"),
]

#: Traces of bench/ideal_plate_map.py (seed 1), ok but wrong on main at 06ea391: the model's force steps up from zero
#: at 2 mm of compression to 12-40 % of the peak, the hinge's line through the samples after the step met zero 0.3-0.9
#: samples before it with an uncertainty under 0.05 % of TC, and a late end made TC wrong. The start is now the middle
#: of [the line's zero, the first sample] (``contact._foot_start``, flag ``start_step``): ok and right (name, seed,
#: index, what).
ZOO_START_STEP = [
    ("ideal-plate-start-step-289", 1, 289, "pressurised ball, 20.6 kHz: TC +1.03 % on main, +0.54 % now"),
    ("ideal-plate-start-step-225", 1, 225, "pressurised ball, 48.0 kHz: TC +1.01 % on main, +0.85 % now"),
]

#: Traces of bench/ideal_plate_map.py (seed 1), ok but wrong on main at ebaf7c7: the end's bent hinge was taken only
#: where it lowered the residual by 2 noise variances, and the straight hinge's corner, late where the noise hides the
#: bend, stood. Taken wherever it lowers the residual (``contact.BEND_CHI2`` 0): 1:386 ok and right, 1:484 excluded
#: for its end's uncertainty (name, seed, index, what, must_be_ok).
ZOO_BEND_NO_PRICE = [
    ("ideal-plate-bend-386", 1, 386, "punctured ball, 54.0 kHz, noise 0.36 %: TC +1.06 % on ebaf7c7; its start "
     "completed from the jump by the cloth's phase since, TC from the first contact within its budget: ok", True),
    ("ideal-plate-bend-484", 1, 484, "pressureless ball, 55.6 kHz, noise 0.44 %: TC +1.72 % on ebaf7c7, excluded now",
     False),
]


@pytest.mark.parametrize("name, seed, index, what, must_be_ok",
                         [pytest.param(*c, False, id=c[0]) for c in ZOO_FADE_NOT_PINNED]
                         + [pytest.param(*c, True, id=c[0]) for c in ZOO_START_STEP]
                         + [pytest.param(*c, id=c[0]) for c in ZOO_BEND_NO_PRICE])
def test_zoo_ideal_plate_map_case(name, seed, index, what, must_be_ok, tmp_path):
    """ZOO_FADE_NOT_PINNED (excluded: the end's hinge does not pin TC to 1 %), ZOO_START_STEP (ok and right) and
    ZOO_BEND_NO_PRICE (either, as marked)."""
    trace = bench_module("ideal_plate_map").trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz is None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    fade = "contact time uncertain" if name == "ideal-plate-bend-386" else "the force fades into the noise there, and"
    assert_invariant(trace, result, judgement, must_be_ok=must_be_ok, excluded_with=None if must_be_ok else fade)


#: Traces of bench/lowpass_map.py (seed 1), ok but wrong on main at 39210b7: the model's force through a unit-gain
#: second-order low-pass (an amplifier's filter, or a plate on damped mounts: little or no ringing to show it) that
#: spreads the force's jump over several samples and delays its end; TC came out long by about twice the delay
#: 2 zeta / wn. The front's fit through a low-pass (``conditioning._front_lowpass``) now names it (name, seed, index,
#: what).
LOWPASS_DELAY = [
    ("lowpass-3.7kHz-110kHz", 1, 30, "3.7 kHz, damping 0.35, 110 kHz (3.3 samples): TC +1.85 % on main"),
    ("lowpass-5.7kHz-47.5kHz", 1, 140, "5.7 kHz, damping 0.55, 47.5 kHz (1.5 samples): TC +1.63 % on main"),
    ("lowpass-9.4kHz-bessel-like-75kHz", 1, 47, "9.4 kHz, damping 0.94, 75 kHz (2.4 samples): TC +1.18 % on main"),
    # a slow filter (11.7 samples of delay): with a cubic in the ideal fit and the window decimated to 40 samples,
    # the evidence was 22 residual variances, not 25, and the trace ok with TC +3.68 %
    ("lowpass-2.0kHz-85kHz", 1, 85, "2.0 kHz, damping 0.88, 84.8 kHz (11.7 samples): TC +3.68 % fitted on 40 samples"),
]


@pytest.mark.parametrize("name, seed, index, what", named(LOWPASS_DELAY))
def test_zoo_lowpass_map_case(name, seed, index, what, tmp_path):
    trace = bench_module("lowpass_map").trace_for(seed, index)
    assert trace.rig.plate_zeta >= 0.3, name  # 1:140 and 1:47 are marginal (a spike peak, fn < 10 kHz): ok must be right
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="as through a low-pass")


#: Traces of bench/two_mode_map.py, ok but wrong on 7489769: a plate of two modes (the second 1.3-4 times the first's
#: frequency, its residue -45 to +12 %) answers the force's jump with an overshoot that the one-mode fits of the
#: ringing checks do not recognise, and the largest sample, 0.02-0.08 ms into the contact, is that overshoot's top.
#: The force leaves it over 4-11 samples, where the ball's drops at once at buckling (``_peak_on_slow_fall``). On 5:243
#: the lightly damped second mode was identified and undone, and the undone force kept the first mode's overshoot
#: (name, seed, index, what the reason must name, what).
SLOW_FALL = "a ball's force drops at once"
TWO_MODE_PLATES = [
    # 2:371's overshoot top rises from a sample at 29 % of it and stands alone: named so first since d841f03
    ("two-modes-10.6+24.7kHz-54.9kHz", 2, 371, "the largest sample stands alone",
     "ok but wrong on 7489769: peak +12.25 %"),
    ("two-modes-7.5+27.0kHz-93.7kHz", 2, 385, SLOW_FALL, "ok but wrong on 7489769: peak +15.28 %"),
    ("two-modes-10.5+40.9kHz-155kHz", 2, 27, SLOW_FALL, "ok but wrong on 7489769: peak +3.72 %"),
    ("two-modes-6.1+19.5kHz-141.7kHz", 3, 301, SLOW_FALL, "ok but wrong on 7489769: peak +27.83 %"),
    ("two-modes-8.0+30.3kHz-undone-132.7kHz", 5, 243, "the undone force still shows peak force on the plate's step",
     "ok but wrong on 7489769 (the 30.3 kHz mode undone): peak +28.89 %"),
]


@pytest.mark.parametrize("name, seed, index, named_in_reason, what", named(TWO_MODE_PLATES))
def test_zoo_two_mode_plate_case(name, seed, index, named_in_reason, what, tmp_path):
    rig, rng = bench_module("two_mode_map").rig_for(seed, index)
    assert len(rig.plate_modes) == 1, name
    trace = zoo.render(rig, rng, name)
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with=named_in_reason)


#: Traces of bench/saturation_map.py, faulty but ok on 1a036a8: the amplifier's output saturated at 51-85 % of the
#: peak, well inside the ADC's range, and the flat top passed for the force's (kCAL high by the impulse cut off, the
#: peak low, TC right). The recorded top now holds many times the samples of the band just under it, where a smooth
#: force's holds about 1.4 times (``contact.detect_saturation``) (name, seed, index, what).
SATURATED_STAGE = [
    ("saturated-at-51pc-plate-14kHz-97.7kHz", 1, 0, "faulty but ok on 1a036a8: kCAL +50.6 %, peak -22.4 %"),
    ("saturated-at-54pc-tau-0.05s-25.1kHz", 1, 16, "faulty but ok on 1a036a8: kCAL +48.7 %, peak -16.0 %"),
    ("saturated-at-56pc-plate-4.6kHz-negative", 1, 59, "faulty but ok on 1a036a8: kCAL +44.5 %, peak -16.9 %"),
    ("saturated-at-83pc-175kHz-tau-estimated", 1, 50, "faulty but ok on 1a036a8: kCAL +5.9 %, peak -9.2 %"),
    ("saturated-at-85pc-24.8kHz-noise-after", 1, 60, "faulty but ok on 1a036a8: kCAL +7.0 %, peak -7.4 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(SATURATED_STAGE))
def test_zoo_saturated_stage_case(name, seed, index, what, tmp_path):
    trace, level, _ = bench_module("saturation_map").trace_for(seed, index)
    assert trace.truth.fault == "saturated" and level < 0.9, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="clipping below the ADC rails")


def test_a_flat_top_under_a_short_pretrigger_is_not_passed_unchecked(tmp_path):
    """bench/saturation_map.py trace 2:320, faulty but ok on 1a036a8 with TC -18.9 % and kCAL +99.9 %: saturated at
    58 % of the peak under a 1.2 ms pre-trigger, the record's level before its largest sample was the flat top's, no
    contact stood out of it before the baseline fit, and the contact found after a fit through the whole record went
    unchecked (with a noise estimate 15 times the truth the saturation test could not see the top either)."""
    trace, level, _ = bench_module("saturation_map").trace_for(2, 320)
    assert trace.truth.fault == "saturated" and trace.rig.pre_s < 1.5e-3
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert judgement.category == "excluded_faulty", (judgement, result.reason)
    assert result.reason.startswith("contact window not stable: no contact stands out of the record"), result.reason


def test_a_flat_top_under_hum_picked_up_after_the_amplifier_is_seen_with_the_hum_removed(tmp_path):
    """30 mV of 60 Hz hum added after the saturated stage tilts the flat top by more than the noise (0.5 mV): as
    recorded it is no flat top, with the fitted hum removed it is (the first saturation map trace, so altered)."""
    trace, _, _ = bench_module("saturation_map").trace_for(1, 0)
    rig = dataclasses.replace(trace.rig, hum_V=0.03, noise_V=0.5e-3, hum_after_saturation=True, mains_known=True,
                              mains_hz=60.0, plate_hz=None)
    trace = zoo.render(rig, np.random.default_rng(7), "hum after the saturated stage")
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="clipping below the ADC rails: the recorded signal "
                                                           "(with the hum removed")


#: Traces of bench/adc_map.py recorded by a 12-bit ADC over +-10 V (a step of 4.9 mV) under noise far below the step,
#: ok but wrong on d90f51e: the quiet record moved in whole steps, its noise was estimated at a fraction of one, and
#: a step before the contact passed for a foot of force (1:26: start 157 us early, TC +3.8 %) or the end was read off
#: the staircase (2:75, TC +2.9 %; 3:262, right on d90f51e, TC +1.1 % once the noise is floored at the step's
#: error, until the staircase check) (name, seed, index, what).
COARSE_ADC = [
    ("adc-12bit-noise-0.08mV-ideal-plate", 1, 26, "ok but wrong on d90f51e: TC +3.82 %"),
    ("adc-12bit-noise-0.3mV-plate-21kHz", 2, 75, "ok but wrong on d90f51e: TC +2.93 %"),
    ("adc-12bit-noise-0.25mV-slow-end", 3, 262, "ok but wrong with the noise floor alone: TC +1.08 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(COARSE_ADC))
def test_zoo_coarse_adc_case(name, seed, index, what, tmp_path):
    trace = bench_module("adc_map").trace_for(seed, index)
    assert trace.rig.adc_bits == 12 and trace.rig.noise_V < 0.1 * 20.0 / 2**12, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)


#: Traces of bench/burst_map.py, ok but wrong on f34ee44: an alternating burst of interference (5-6 samples, 10-34
#: noise deviations) on the contact's fade swung it to zero, and the end was found there, early (TC -22.5 to -2.0 %);
#: the force after it, the fade's rest, now stands out of the noise (name, seed, index, what).
BURST_AT_THE_END = [
    ("burst-6-samples-34sd-77kHz", 1, 314, "ok but wrong on f34ee44: TC -22.51 %"),
    ("burst-6-samples-27sd-72kHz", 1, 24, "ok but wrong on f34ee44: TC -3.37 %"),
    ("burst-6-samples-10sd-192kHz", 1, 382, "ok but wrong on f34ee44: TC -2.67 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(BURST_AT_THE_END))
def test_zoo_burst_at_the_end_case(name, seed, index, what, tmp_path):
    trace, bursts = bench_module("burst_map").trace_for(seed, index)
    assert trace.truth.measurable and any(b[1] >= 5 for b in bursts), name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="after it stands")


#: Traces of bench/step_map.py, ok but wrong on cedcc5c: the recorded level shifts once by 0.1-3 % of the peak (a
#: DAQ's or an amplifier's offset changing), and the baseline fit spread the shift over the record as drift, leaving
#: the contact's ends on a level a little off zero; or, with the decay estimated and the step 1.7 ms after the end,
#: kappa took it for the undershoot and the correction lifted the record before it into a shelf of force (name,
#: seed, index, what the reason must name, what). Since the step's effect is estimated where the time constant is
#: given (signal.effects.level_effects), 2:300 and 2:374 are kept and right (TC +0.84 % and +0.51 %, their
#: budgets under 1 %): no reason then.
BASELINE_STEPS = [
    ("step-0.43pc-17ms-before", 2, 300, None, "ok but wrong on cedcc5c: TC +1.01 %; ok and right since"),
    ("step-0.28pc-after-the-end", 1, 138, "step in the baseline", "ok but wrong on cedcc5c: TC +2.06 %"),
    ("step-0.15pc-in-the-contact-tau-given", 2, 374, None, "ok but wrong on cedcc5c: TC +2.39 %; ok and right since"),
    ("step-3.1pc-1.7ms-after-tau-estimated", 2, 95, "force is flat over the last",
     "ok but wrong on cedcc5c: TC +42.5 %, kCAL -6.2 %"),
]


@pytest.mark.parametrize("name, seed, index, named_in_reason, what", named(BASELINE_STEPS))
def test_zoo_baseline_step_case(name, seed, index, named_in_reason, what, tmp_path):
    trace, height, _ = bench_module("step_map").trace_for(seed, index)
    assert trace.truth.measurable and abs(height) >= 1e-3, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with=named_in_reason)


#: Traces of bench/spike_ends_map.py, ok but wrong on main at 257a046: a pressurised ball at 13.6 m/s, 51.7 kHz, a
#: plate of 18.5 kHz (2.8 samples a period, damping 0.094) whose first overshoot of the force's jump is the largest
#: sample, 1.3 samples after the contact start (peak +5.0 %), and an electrical spike of +0.33 V (38 noise deviations)
#: on the ringing's first trough, 3.3 samples after the start, which remove_spikes cannot tell from the ringing's
#: swings. Without the spike the trace is ok and right (conditioning._peak_on_first_overshoot sees the plate, 18.6 kHz,
#: and it is undone: peak +0.15 %); with it that check's fit through a plate left 1350 noise variances (the ideal
#: one's 3470), its own residual variance set the significance, the gain was 7.8 variances (needed: 25) and no check
#: saw the plate. Fitted with a free spike after the largest sample, the plate is seen and undone (name, seed,
#: index, what).
SPIKE_ON_FIRST_OVERSHOOT = [
    ("plate-18.5kHz-spike-on-the-ringing", 2, 349, "spike_ends_map 2:349 ok but wrong on 257a046: peak +5.0 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(SPIKE_ON_FIRST_OVERSHOOT))
def test_spike_on_the_plates_first_overshoot_ringing_hides_no_plate(name, seed, index, what, tmp_path):
    trace, where = bench_module("spike_ends_map").trace_for(seed, index)
    assert trace.truth.measurable and trace.rig.plate_hz is not None and where == "start", name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement)
    assert (judgement.category == "ok_right" or zoo.withheld_for_the_cloth_alone(result)) and \
        math.isfinite(result.plate_resonance_hz), \
        (judgement.category, result.reason)
    assert abs(result.plate_resonance_hz / trace.rig.plate_hz - 1) < 0.02, result.plate_resonance_hz


#: A trace of the zoo's chain on the rig of ``python bench/overshoot_map.py --n 400 --seed 5`` trace 5:183 (ok but
#: wrong there, kCAL +1.27 %), ok but wrong on main at ffc2770: a plate at 2.25 samples a period overshoots the force's
#: jump in one sample, two after the contact start, and the spike filter replaced that sample (the plate's own
#: response, in the impulse) by its neighbours' mean, the impulse short by about that sample's excess. Such a sample,
#: its neighbours straddling the jump, is now kept (right then: TC -0.15 %, kCAL +0.10 %), and the end is not
#: determined because an electrical spike riding on the jump would be 1.2 % of the impulse (name, seed, overrides,
#: what).
_MAP_5_183 = dict(ball="oversize", scale=(0.9796, 0.8096, 1.0556, 0.9535, 0.9671), vin_m_s=15.21,
                  sample_rate_hz=28485.2, plate_hz=12681.7, plate_zeta=0.1232, noise_V=0.01274)
ZOO_OVERSHOOT_AS_SPIKE = [
    ("plate-12.7kHz-overshoot-taken-for-a-spike", 20, _MAP_5_183, "ok but wrong on ffc2770, TC +1.17 %, kCAL +1.18 %"),
]


@pytest.mark.parametrize("name, seed, overrides, what", named(ZOO_OVERSHOOT_AS_SPIKE))
def test_zoo_plates_overshoot_taken_for_a_spike_is_excluded(name, seed, overrides, what, tmp_path):
    trace = zoo.make_trace(np.random.default_rng(seed), "plate", **overrides)
    assert trace.truth.measurable, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="single-sample spike")


#: A trace of ``python bench/overshoot_map.py --n 400 --seed 5`` (5:350), ok but wrong on main at 06ea391: a
#: punctured ball at 52.1 kHz on a 12.2 kHz plate (damping 0.05), its undone force too noisy, low-passed at 13 kHz;
#: the end fitted through the plate's undoing and the kernel lands 2.0 samples early (TC -1.04 %), while its
#: uncertainty (noise over the slope, floored at half a sample, and the fit's residual profile) allowed half a
#: sample: the noise the inverse amplified and the kernel kept is correlated over several samples, and a whole
#: stretch of the end moved together. The end's standard uncertainty from that coloured noise
#: (``plate.undone_end``'s ``noise_se``, 0.70 samples) refuses it now (name, seed, index, what).
MAP_UNDONE_END_COLOURED_NOISE = [
    ("plate-12.2kHz-lowpassed-end-2-samples-early", 5, 350, "ok but wrong on 06ea391: TC -1.04 %"),
]


@pytest.mark.parametrize("name, seed, index, what", named(MAP_UNDONE_END_COLOURED_NOISE))
def test_map_undone_end_known_to_its_coloured_noise(name, seed, index, what, tmp_path):
    rig, rng = bench_module("overshoot_map").rig_for(seed, index, True)
    trace = zoo.render(rig, rng, name)
    assert trace.truth.measurable and rig.plate_hz is not None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, excluded_with="not undone")


#: Traces of ``python bench/overshoot_map.py --n 400`` excluded on main at 06ea391 although measurable: the undone
#: force's ends fitted through the plate (and the kernel), "the undone TC is known to 1.1 % only": the end, where the
#: ball's force falls to zero as a line (no jump), was charged its noise (or residual) over its slope, floored at half
#: a sample. The fit locates it continuously from several samples: its standard uncertainty is
#: ``plate.undone_end``'s ``noise_se`` (the sensed noise as the chain colours it, tests/test_plate.py), now charged
#: instead: ok and right (name, seed, index, what).
MAP_UNDONE_LINE_ENDS = [
    ("plate-7.5kHz-lowpassed-line-end", 3, 374,
     "punctured ball, 44.9 kHz, plate 7.50 kHz (damping 0.05), low-passed at 7.94 kHz: TC known to 1.1 % only"),
    ("plate-9.3kHz-exact-fitted-line-end", 5, 301,
     "pressurised ball, 34.8 kHz, plate 9.28 kHz (damping 0.057), exact, ends fitted: TC known to 1.1 % only"),
]


@pytest.mark.parametrize("name, seed, index, what", named(MAP_UNDONE_LINE_ENDS))
def test_map_undone_line_end_known_to_its_noise(name, seed, index, what, tmp_path):
    rig, rng = bench_module("overshoot_map").rig_for(seed, index, True)
    trace = zoo.render(rig, rng, name)
    assert trace.truth.measurable and rig.plate_hz is not None, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)
    assert result.plate_resonance_hz > 0  # undone


def test_zoo_aliased_plate_start_keeps_its_half_sample(tmp_path):
    """Zoo trace 0:434: a 16.7 kHz plate sampled at 23.0 kHz (above the Nyquist frequency, no anti-aliasing filter),
    identified and undone as its 6.3 kHz alias. Its fitted start is 0.70 samples early (the chain's model is wrong at
    the sample scale for an alias) while the fit's noise says 0.14: with the start's half sample dropped too it came
    out ok and wrong (TC +1.19 %). The start keeps it (the force jumps from zero there): excluded."""
    trace = zoo.trace_for(0, 434)
    assert trace.truth.measurable and trace.rig.plate_hz > 0.5 * trace.sample_rate_hz
    result, judgement = zoo.run_trace(trace, tmp_path, trace_format="csv")
    assert_invariant(trace, result, judgement)
    assert result.status == "excluded"


#: Traces of the benchmark (``python bench/robustness.py --n 2000 --seed S``) excluded on main at 06ea391 because
#: the spike filter replaced a sample within 4 samples of a contact end, although ok and right: at 50 kHz the ball's
#: pre-buckling spike at 12 m/s is one sample after the force's jump, its neighbours the jump's ramp and the force
#: after the drop (kept now: its neighbours do not continue one curve); and an electrical spike on the force's
#: smooth fade before the end (replaced, rightly: its neighbours continue one curve). (name, seed, index, what.)
ZOO_SPIKE_AT_END = [
    ("balls-spike-at-the-jump-50kHz", 0, 1635, "oversize ball at 12.1 m/s: replaced 1.5 samples after the start, "
     "TC +0.28 %, kCAL +0.45 % (kept now: +0.08 %, +0.15 %)"),
    ("electrical-spike-before-the-end-50kHz", 3, 1755, "1.18 V, 2.6 samples before the end, replaced"),
]


@pytest.mark.parametrize("name, seed, index, what", named(ZOO_SPIKE_AT_END + ZOO_HELD_OUT_RIGHT))
def test_zoo_case_ok_and_right(name, seed, index, what, tmp_path):
    trace = zoo.trace_for(seed, index)
    assert trace.truth.measurable, name
    result, judgement = zoo.run_trace(trace, tmp_path)
    assert_invariant(trace, result, judgement, must_be_ok=True)


def test_trace_whose_time_constant_is_estimated_on_a_record_of_a_third_of_a_mains_period_gives_a_reason():
    # zoo trace 0:204 (a 3.8 kHz plate, 17 mV of hum, 6.4 ms of record): the decay is estimated; the time
    # constant's standard error once read the contact's NaN ends and raised when no contact was found. Since the
    # hum's prior (5578e54) the contact is found; its TC, 34 % off under the plate's ringing, is withheld with a
    # reason, and nothing is ok
    tr = zoo.trace_for(0, 204)
    result, judgement = zoo.run_trace(tr)
    assert result.status == "excluded" and result.contact_time_status == "withheld" and result.reason
    assert not judgement.wrong and judgement.category == "excluded_measurable"
    assert result.tau_source == "estimated" and result.tau_se_s > 0


def test_step_within_a_contact_taken_for_the_decay_is_excluded_by_the_sessions_time_constant():
    """bench/step_map.py trace 2:249: a step of -2.7 % of the peak at 0.89 TC, the time constant (5.7 s) estimated.
    Alone, the fit takes the step for the amplifier's undershoot (0.082 s) and the trace is ok with kCAL -2.8 %. In a
    session with five more shots on the same rig (no step) the session time-constant check excludes it, and only it."""
    from ballimpact.processing import apply_time_constant_check

    trace, _, _ = bench_module("step_map").trace_for(2, 249)
    rig = trace.rig
    siblings = [zoo.render(dataclasses.replace(rig, vin_m_s=vin), np.random.default_rng([2, 249, k]), f"sibling {k}")
                for k, vin in enumerate((12.0, 16.0, 20.0, 24.0, 28.0))]
    runs = [zoo.run_trace(t) for t in [trace] + siblings]
    assert [j.category for _, j in runs] == ["ok_wrong"] + ["ok_right"] * 5
    results = [r for r, _ in runs]
    median = apply_time_constant_check(results)
    assert 1 / median == pytest.approx(1 / rig.tau_s, abs=0.15)  # kappa [1/s]: each sibling's is known to 0.08-0.11
    assert [r.status for r in results] == ["excluded"] + ["ok"] * 5, [r.reason for r in results]
    assert [p.kind for p in results[0].problems if p.kind is not ProblemKind.CLOTH_PHASE_COMPLETED] == [
        ProblemKind.TIME_CONSTANT_OUTLIER]


def test_zoo_kcal_unbiased_after_a_jump_at_a_low_rate(tmp_path):
    """The model's jump at the contact start (section 3.2.4 in Goodwill & Haake 2004) anywhere between two samples.

    Zoo trace 1:248's ball through an ideal plate, without noise, hum, drift or decay, at 20 kHz, the contact placed
    at 16 sub-sample instants: its start is a jump (``start_jump``), kCAL's error follows the jump's place (+-0.4 %
    standard deviation) and must average out. The line from the last quiet sample to the first inside the contact
    covered 3/8 of a sample of the jump where it covers half a sample on average: +0.165 % on average at 3f69f28
    (``calibration.voltage_impulse``); the first sample's value held back to the start gives +0.007 %.
    """
    base = zoo.trace_for(1, 248, plate_hz=None, noise_V=1e-5, hum_V=0.0, tau_s=math.inf, drift_V_s=0.0,
                         offset_V=0.0, sample_rate_hz=20e3)
    errors = []
    for k in range(16):
        trace = zoo.render(base.rig, np.random.default_rng([7, k]))
        result, judgement = zoo.run_trace(trace, tmp_path)
        errors.append(judgement.errors["kcal"])
    assert abs(np.mean(errors)) < 0.0008, np.mean(errors)

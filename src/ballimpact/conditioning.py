"""Plate-voltage conditioning: polarity, offset, mains hum and charge-amplifier decay, without biasing the impulse.

The charge amplifier acts as a first-order high-pass with time constant tau:
``dV_meas/dt = dV_true/dt - V_meas / tau``. Integrating from the contact start
(where both are zero) gives the exact inverse used here::

    V_true(t) = V_meas(t) + (1 / tau) * integral_{start}^{t} V_meas dt'

After the contact V_true = 0, so there the measured signal obeys
``V_meas(t) = -(1 / tau) * integral_{start}^{t} V_meas dt'``: the undershoot and
its exponential recovery, for any tau (0.01 s, where the signal decays visibly
during the contact, as well as 100 s). The baseline model is therefore linear in
``kappa = 1 / tau``:

* every quiet sample: ``V = B`` with B = offset + linear drift + sin/cos at the
  mains frequency and its harmonics (one phase-continuous model for the whole
  trace);
* quiet samples after the contact: ``(V - B) + kappa * integral_{start}^{t} (V - B) dt' = 0``,
  i.e. ``V + kappa * I_V = sum_j theta_j (phi_j + kappa * I_phi_j)`` with the
  running integrals of V and of each model column phi_j.

For a given kappa this is linear in the model coefficients theta; kappa (when
``tau_s`` is not given) is the value that minimises the residual sum of squares,
found on a grid and refined, from normal equations that are quadratic in kappa
and built once per fit. The fit uses the quiet samples only: up to 100 ms of
pre-trigger and up to 50 ms after a guard for plate ringing (2 ms; 0.5 ms when
the record ends too soon for 2 ms after it), minus every event found in the
record (second contacts, with guards), with one robust pass that drops
outliers. When kappa comes out too uncertain for the impulse, the fits with
fewer hum harmonics are tried too (the least BIC wins). Single-sample spikes are replaced by the mean of their
neighbours first (except, at a contact end, a sample whose neighbours straddle the force's jump: the force's own,
kept and judged). When ``tau_s`` is given it is used exactly.

Events before baseline: each iteration decay-corrects the whole record and
marks every run that stands out of the noise (above 6 noise deviations and 0.5 %
of the peak) besides the main contact, with its shoulders (while it stays 3 noise
deviations above zero); the next fit leaves them out, so a second contact can
never bend the baseline. The contact window and the event mask are
iterated until they no longer move.

Mains: when ``mains_hz="auto"``, the fit is done without hum, with 50 Hz and
with 60 Hz harmonics on the same quiet samples and the smallest Bayesian
information criterion wins; when 50 and 60 Hz fit about equally well and their
hum differs under the contact, the impact is flagged as a problem.

Integrity checks (``ConditionedSignal.problems``, each one a reason to exclude
the impact): decay not measurable or not an amplifier decay, corrected signal
before or after the contact not flat at zero, mains frequency not resolved (or
hum in a record shorter than one mains period), a quiet residual that is more
than white noise, a step in the quiet baseline's level (the fit would spread
it over the record as drift) or across the contact when the time constant is
given, a contact that ends on a flat shelf of force (a step just after it
taken for the amplifier's undershoot), plate ringing during the contact (a
spectral line) or after it, a peak that is one of the plate's swings (or
lifted by its ringing from the force's jump), a peak between samples (the
largest sample on a steep ramp, or the first of the contact), force
below zero after the contact (the plate swinging back), a contact end that
moves when fitted again from higher samples (a tail fading into the noise), a
force jump from zero that locates an end only to half a sample when that is
more than 0.7 % of TC, too few samples across the contact, a contact window
that does not settle, and (last, on a trace nothing else excludes) a force's
jump spread over several samples by a low-pass in the chain, which delays the
contact's end.

Plate resonance: when the only problems are the plate's (ringing in or after
the contact, a peak on the ringing, force below zero after it, and the end and
peak problems such ringing causes), the resonance is identified from the
ringing and undone (``ballimpact.plate``) and every contact, end and ringing
check is done again on the undone force. It is used only when two
identifications from independent instruments both pass every check and agree
on TC and peak, and the undone force is quiet enough for its peak and ends
(see ``_plate_undone`` for every condition); otherwise the impact keeps its
problems.
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .calibration import force_top
from .contact import (ContactResult, ContactSearch, contact_threshold, detect_contact, end_standard_uncertainties,
                      finite_median, quantization_step, robust_noise)
from .model import BUCKLING_TIME_S
from .plate import (PlateResonance, identify_free_ringing, identify_plate_resonance, lowpass_spread_samples,
                    lowpass_zero_phase, refine_plate_resonance, undo_plate_resonance, undone_end, undone_noise_gain,
                    fit_front, stated_resonance, undone_impulse_response)
from .problems import Problem, ProblemKind

__all__ = ["ConditionedSignal", "ConditioningWarning", "condition_voltage", "remove_spikes"]

PRE_GUARD_S = 0.5e-3  # quiet pre-trigger ends this long before the contact start [s]
POST_GUARD_S = 2.0e-3  # quiet post stretch begins this long after the contact end (plate ringing) [s]
PRE_WINDOW_S = 0.1  # longest pre-contact stretch used for the baseline fit [s]
POST_WINDOW_S = 0.05  # longest post-contact stretch used for the baseline fit [s]
MIN_QUIET_SAMPLES = 20  # fewest samples for a pre or post baseline [samples]
MIN_PRE_SAMPLES = 8  # fewest pre-contact samples for an offset at all [samples]
MIN_POST_S = 2.0e-3  # shortest post-contact stretch for the decay [s]
SHORT_POST_GUARD_S = 0.5e-3  # a record too short for MIN_POST_S after POST_GUARD_S: the post stretch from this on ... [s]
SHORT_MIN_POST_S = 0.5e-3  # ... when it is at least this long (the decay's standard error then decides) [s]
UNDERSHOOT_SIGNIFICANCE = 5.0  # kappa must exceed this many standard errors [-]
TAU_BOUNDS_S = (0.005, 1.0e4)  # plausible charge-amplifier time constants [s]
KAPPA_CORRELATION_S = 2e-3  # kappa's standard error allows for residuals correlated over this long [s]
KAPPA_REFINE_ITERATIONS = 100  # most Newton or bisection steps refining kappa between two grid points [-]
BIAS_WARN_FRACTION = 1.0e-3  # warn when an uncorrected decay could bias the impulse by more [-]
BIAS_EXCLUDE_FRACTION = 3.0e-3  # exclude when it could bias the impulse by more [-]
MAX_ITERATIONS = 8  # contact window / baseline iterations [-]
CONVERGED_SAMPLES = 0.01  # window change that ends the iteration [samples]
UNSTABLE_SAMPLES = 0.5  # still moving by more after MAX_ITERATIONS: a problem [samples]
NYQUIST_MARGIN = 0.45  # harmonics above this fraction of the sample rate are skipped [-]
MAINS_CANDIDATES_HZ = (50.0, 60.0)  # mains frequencies tried when not given [Hz]
MAINS_AMBIGUOUS_BIC = 10.0  # 50 and 60 Hz fits closer than this in BIC are not told apart [-]
MAINS_AMBIGUOUS_FRACTION = 1.0e-3  # ... and matter when their hum differs by more under the contact [-]
ROBUST_SIGMA = 5.0  # quiet samples off the first fit by more noise deviations are dropped [-]
EVENT_SIGMA = 6.0  # an event stands this many noise deviations out of the corrected record [-]
#: ... and reaches this fraction of the main peak [-]. It was 1 % until a second contact of 1.3 % (zoo trace
#: 25:1094), half taken up by the hum fitted over a 36 ms record, stood 0.6 % out of it and bent that hum under the
#: contact. Not lower than about twice FLAT_FRACTION: an oscillation (ringing, hum not resolved) has its positive
#: swings taken for events, and the quiet residual's check must still see it (0.2 % cost a suite case that).
EVENT_FRACTION = 0.005
EVENT_GUARD_BEFORE_S = 0.5e-3  # samples this long before an event are left out of the fit [s]
EVENT_GUARD_AFTER_S = 2.0e-3  # ... and this long after it (ringing) [s]
#: An event's samples run on, either side of where it stands out as one, while the corrected record stays this many
#: noise deviations above zero [-]: the shoulders of a second contact (its rise and fall out of the noise), left
#: in the fit, bend the hum fitted under the main contact as the whole of it does.
EVENT_SHOULDER_SIGMA = 3.0
BASELINE_BEND_FRACTION = 0.1  # the fitted baseline departing from the line between its values at the contact's ends
#                                by more than this fraction of the peak under the contact is not known there [-]
EDGE_EVENT_MIN_S = 0.05e-3  # such an event from the record's first sample on for this long is a cut-off impact
#                             (at least 3 samples) [s]
SPIKE_SIGMA = 12.0  # a spike's second difference exceeds this many noise deviations [-]
SPIKE_SHAPE_TOLERANCE = 0.15  # neighbours' second differences within this fraction of h of -h/2 (0 two and three away) [-]
SPIKE_END_SAMPLES = 4.0  # a spike replaced this close to a contact end may be the force's own at its jump [samples]
SPIKE_KINK_SIGMA = 5.0  # ... unless its neighbours continue one curve: their second differences, with it replaced,
#                         within this many noise deviations of the second difference (6.6 of their own noise) [-]
SPIKE_END_SIGMA = 6.0  # within SPIKE_END_WINDOW_S of a contact end a spike on one curve needs only this many [-]
SPIKE_END_WINDOW_S = 0.35e-3  # the samples the end's hinge is fitted to (contact.FOOT_MAX_S + FOOT_PRE_S) [s]
SPIKE_END_IMPULSE = 0.005  # a sample kept at a contact end, were it electrical, is this fraction of the impulse at
#                            most: half the 1 % tolerance of kCAL (the rest of the processing's kCAL error is within
#                            0.32 % on 99 % of the ok traces of zoo seeds 0-3 at 06ea391) [-]
FLAT_WINDOW_S = 2.0e-3  # stretches of the corrected signal checked for a level off zero [s]
FLAT_FRACTION = 2.0e-3  # a level above this fraction of the peak ... [-]
FLAT_SIGMA = 5.0  # ... and this many standard errors is a problem [-]
BASELINE_STEP_WINDOWS_S = (1.0e-3, 4.0e-3, 16.0e-3)  # a line and a step fitted to this long of quiet samples on
#                                                    either side of every candidate instant ... [s]
BASELINE_STEP_GRID_S = 0.25e-3  # ... the candidates this far apart (and the first quiet sample after each gap) [s]
BASELINE_STEP_SIGMA = 7.0  # ... a step of this many standard errors (a scan of many instants) ... [-]
BASELINE_STEP_FRACTION = 5.0e-4  # ... and this fraction of the peak is a step in the baseline [-]
BASELINE_STEP_ACROSS_SIGMA = 4.5  # across the contact, with every quiet sample on either side: one test, not a scan [-]
MIN_CONTACT_SAMPLES = 20  # fewest samples across the contact [samples]
PLATEAU_END_FRACTION = 0.1  # the force over this fraction of TC before the end (PLATEAU_END_MIN samples or more) [-]
PLATEAU_END_MIN = 8  # fewest samples of that stretch [samples]
PLATEAU_END_FALL = 0.25  # ... that falls by less than this fraction of its level ... [-]
PLATEAU_END_LEVEL = 0.01  # ... at a level above this fraction of the peak and 10 standard errors: a plateau [-]
END_CHECK_S = 0.2e-3  # the samples this long inside each end of the contact ... [s]
END_CHECK_SIGMA = 3.0  # ... must average above this many standard errors [-]
RING_GAP_S = 0.1e-3  # the ringing check starts this long after the contact end [s]
RING_WINDOW_S = 1.0e-3  # ... and lasts this long [s]
RING_LINE_MIN_HZ = 3000.0  # plate resonances looked for in the contact above this [Hz]
RING_LINE_PROMINENCE = 3.8  # a spectral line this many times its neighbourhood is plate ringing [-]
RING_LINE_NOISE_FACTOR = 6.0  # ... and this many times the noise's amplitude in a bin [-]
RING_LINE_SIDE_BINS = 4  # a bump no more prominent over the median of the bins below it (at least this many) ... [-]
RING_LINE_EDGE_FRACTION = 3.0e-4  # ... and below this fraction of the peak is the force's own spectrum, no line [-]
RING_MAX_FRACTION = 0.02  # rms of the corrected signal there above this fraction of the peak: a problem [-]
FOOT_CHECK_S = 0.5e-3  # the corrected signal this long before the contact start (less a sample) ... [s]
FOOT_CHECK_SIGMA = 5.0  # ... holds no foot standing this many standard errors out of the noise [-]
SPREAD_MAX_FRACTION = 0.005  # an end that moves by more of TC when fitted from higher samples is not known [-]
CURVE_MIN_RATE_HZ = 33.0e3  # ... unless the force's curve pins it, at this sample rate or above [Hz]
CURVE_LATE_FRACTION = 2.5e-3  # the force's curve meets zero later than the end by more of TC: a convex fade [-]
JUMP_MAX_FRACTION = 0.007  # a force jump locates its contact end to half a sample; at most this fraction of TC [-]
ADC_STEP_DITHER = 0.5  # noise below this many ADC steps does not dither them: the trace moves in whole steps [-]
ADC_STEP_CROSSING = 3  # ... and each contact end is read off the force's crossing of this many steps above zero ...
ADC_STEP_MAX_FRACTION = 0.01  # ... which may take at most this fraction of TC per step (half of it: the 1 % budget) [-]
END_SE_MAX_FRACTION = 0.01  # END_SE_COVERAGE times the ends' standard uncertainty of TC at most this fraction of it [-]
END_SE_COVERAGE = 2.0  # ... the coverage factor of a 95 % interval of a normal error [-]
TURN_FRACTION = 0.02  # a turning point of the contact force is left by more than this fraction of the peak ... [-]
TURN_SIGMA = 8.0  # ... and this many noise deviations [-]
TURN_MIN_OSCILLATION = 3  # fewest turning points of an oscillation [-]
TURN_REGULARITY = 1.5  # spacings of an oscillation's turning points within this factor of each other [-]
TURN_FAST_RUN = 4  # ... or this many before the peak within one sample of each other, at most 3 apart [-]
PEAK_ON_RINGING_FRACTION = 0.015  # averaged over one period of it, the peak drops by more: not the ball's [-]
PEAK_SAMPLING_FRACTION = 0.10  # the force may rise above the largest sample by more: the peak is not known to 5 % [-]
PEAK_RAMP_FLOOR = 0.5  # ... judged on the rises from samples above this fraction of the peak (a ramp, no jump) [-]
PEAK_JUMP_FRACTION = 0.1  # the largest sample straight after one below this fraction of it: at the jump [-]
FRONT_DIP_JUMPED = 0.2  # once a sample of the front is above this fraction of the peak, ... [-]
FRONT_DIP_ZERO = 0.02  # ... a sample below this fraction of it before BUCKLING_TIME_S and FRONT_DIP_AFTER_SAMPLES
#                        more is a swing as large as the jump: no ball's force (zoo trace 33:674 with a -1.5 V
#                        electrical spike on the jump's second sample: ok, TC -1.2 %) [-]
FRONT_DIP_AFTER_SAMPLES = 2  # [samples]
PEAK_ALONE_FRACTION = 0.015  # the largest sample, risen from one below PEAK_RAMP_FLOOR of it, above every other
#                              sample by more than this fraction of it: a single-sample top (the ball's spike or an
#                              electrical one), not known; half the 3 % tolerance of the peak (zoo trace 33:674, a
#                              spike on the jump's second sample, once ok at +32 %) [-]
HUMP_SKIP_S = 0.3e-3  # a second hump is looked for this long after the contact start (the spike's phase) ... [s]
HUMP_SMOOTH_S = 0.1e-3  # ... in the force averaged over this long ... [s]
HUMP_DIP_FRACTION = 0.05  # ... a fall by more than this fraction of the peak after a maximum ... [-]
HUMP_RISE_FRACTION = 0.02  # ... then a rise by more than this fraction of it ... [-]
HUMP_SIGMA = 6.0  # ... each also this many noise deviations of the average: not the ball's force [-]
STEP_PHASE_S = 0.2e-3  # a peak this soon after the contact start (the spike's phase) is checked for ... [s]
STEP_WINDOW_S = 0.5e-3  # ... a fall, a second bump and a fall again within this long after it ... [s]
STEP_SMOOTH_S = 0.02e-3  # ... in the force averaged over this long (an odd number of samples) ... [s]
STEP_FRACTION = 5.0e-3  # ... each turn left by more than this fraction of the peak ... [-]
STEP_SIGMA = 6.0  # ... and this many noise deviations of the average ... [-]
STEP_FIRST_PERIOD = 1.0  # ... after a peak within this many of its periods of the start (the first overshoot) [-]
STEP_STEEPEST = 1.5  # a fall after the peak steeper than this times a swing's steepest is the force's own drop [-]
FALL_WINDOW_S = 0.15e-3  # a peak in the spike's phase (STEP_PHASE_S) is followed this long for its fall ... [s]
FALL_MIN_FRACTION = 0.05  # ... a fall by more than this fraction of the peak ... [-]
FALL_SIGMA = 20.0  # ... and this many noise deviations ... [-]
FALL_MAX_SAMPLES = 2  # ... spread from 10 to 90 % of it over more samples than this ... [samples]
FALL_MAX_S = 30.0e-6  # ... and longer than this: not the ball's sudden drop at buckling [s]
FRONT_PHASE_S = 0.2e-3  # a largest sample this soon (and a sample) after the contact start is checked ... [s]
FRONT_MIN_SAMPLES = 8  # ... when the contact holds this many samples up to it ... [samples]
FRONT_PRE_SAMPLES = 3  # ... by a fit from this many samples before the start to it ... [samples]
FRONT_JUMP_FRACTION = 0.05  # ... when the force is above this fraction of the peak as many samples after the start [-]
FRONT_SIGNIFICANCE = 25.0  # ... through a plate better than through an ideal one by this many variances ... [-]
FRONT_LIFT_FRACTION = 0.03  # ... whose ringing lifts the largest sample above the force by more: not the ball's [-]
OVERSHOOT_MAX_SAMPLES = 4.5  # a largest sample at most this long after the start (half a period of 2-6 samples) ... [samples]
OVERSHOOT_AFTER_SAMPLES = 10  # fewer samples up to it: fitted on this many after it, with a drop at buckling [samples]
OVERSHOOT_MAX_DAMPING = 0.35  # ... through a plate damped at most this much (more: a smoother, no ringing) [-]
OVERSHOOT_MIN_PERIOD = 2.5  # a plate fitted with fewer samples per period may be an alias: not evidence [samples]
OVERSHOOT_RISE_MAX = 1.0  # ... the jumps rising over at most this many samples (the model's: 10 us) [samples]
LOWPASS_RISE_S = 0.15e-3  # the force's rise from the contact start to this long after it (before buckling) ... [s]
LOWPASS_STEP_S = 10.0e-6  # ... and its largest rise in this long (the model's jump: its 0.01 ms step) and a sample:
LOWPASS_CONCENTRATION = 0.4  # ... less than this fraction of the rise, a jump spread: its front is fitted ... [-]
LOWPASS_WINDOW_S = 0.6e-3  # ... from the contact start to this long after it ... [s]
LOWPASS_MAX_SAMPLES = 80  # ... on every q-th sample, q the least that leaves at most this many in it (40 lost a
#: slow low-pass's evidence: bench/lowpass_map.py traces 1:85 and 2:42) [samples]
LOWPASS_DAMPING = (0.2, 0.98)  # the low-pass fitted: a second-order response of these damping ratios (one at the
#: lower bound is a plate that rings, for the plate's checks) ...
LOWPASS_DELAY_FRACTION = 2.0e-3  # ... whose delay 2 zeta / wn is more than this fraction of TC ... [-]
LOWPASS_DELAY_SAMPLES = 1.0  # ... and more than this many of the samples fitted (less: no trace in them) ... [samples]
LOWPASS_RESIDUAL = 4.0  # ... that leaves at most this many noise variances per sample (it explains the front) [-]
FAST_RING_GAP_SAMPLES = 2  # the front's ringing is read from this long after buckling (BUCKLING_TIME_S in) ... [samples]
FAST_RING_WINDOW_S = 0.3e-3  # ... over this long (at least FAST_RING_MIN_SAMPLES), less a cubic (the force) ... [s]
FAST_RING_MIN_SAMPLES = 12  # ... [samples]
FAST_RING_SIGMA = 3.0  # ... whose residual's rms above this many noise deviations ... [-]
FAST_RING_FRACTION = 5.0e-3  # ... and this fraction of the peak ... [-]
FAST_RING_MAX_PERIOD = 3.6  # ... alternating with a period of at most this many samples: the ends are not known [samples]
FAST_RING_JUMPED = 0.2  # ... when the front, once above this fraction of the peak, ... [-]
FAST_RING_ZERO = 0.02  # ... swings back below this fraction of it, or half a sample exceeds JUMP_MAX_FRACTION of TC [-]
NEGATIVE_WINDOW_S = 3.0e-3  # the corrected signal this long after the contact must not go below zero ... [s]
NEGATIVE_SMOOTH_S = 0.05e-3  # ... averaged over this long (at least one sample) ... [s]
NEGATIVE_FRACTION = 5.0e-3  # ... by more than this fraction of the peak ... [-]
NEGATIVE_SIGMA = 6.0  # ... and this many standard errors of the average [-]
PLATE_ID_AFTER_S = 2.0e-3  # the plate's ringing is identified from the contact and this long after it [s]
PLATE_ID_LAGS = (5, 8)  # two identifications, instruments this many samples back [samples]
PLATE_FREE_AFTER_S = (0.02e-3, 0.1e-3)  # ... or, where they find nothing, fits of the free ringing from this long
#                                         after the contact end (at least a sample) to PLATE_ID_AFTER_S after it [s]
PLATE_REFINE_S = (0.2e-3, 1.0e-3)  # each refined on the undone force from this long before to after the contact [s]
PLATE_AGREE_TC = 3.0e-3  # the two undone forces agree on TC to this fraction ... [-]
PLATE_AGREE_PEAK = 0.01  # ... and on the peak to this fraction, or the plate is not known well enough [-]
PLATE_TC_FRACTION = 0.01  # twice the undone contact's end uncertainty at most this fraction of TC [-]
PLATE_START_LATE = 1.0  # the undone contact may start this much later than the sensed one at most [samples]
PLATE_FOOT_SIGMA = 3.5  # ... unless the sensed force before its fitted start stays within this many standard errors [-]
PLATE_SLOPE_S = 0.1e-3  # the force's slope at an end is read over this long inside it [s]
PLATE_NOISE_FRACTION = 5.0e-3  # the undone force's noise (amplified above the resonance) at most this of the peak [-]
PLATE_LOWPASS_NOISE = 5.0e-3  # a refused undone force is low-passed until its noise is at most this of the peak [-]
PLATE_LOWPASS_PEAK = 0.01  # ... and lower the peak by at most this fraction (from its curvature there) [-]
PLATE_LOWPASS_MIN_FN = 1.0  # ... at a cutoff no lower than this times the resonance [-]
PLATE_LOWPASS_STEPS = 10  # ... trying cutoffs from fs / 2 down in this many steps of sqrt(2) [-]
PLATE_LOWPASS_TRIES = 6  # ... at most this many of them, from the first quiet enough (until one hides the peak) [-]
PLATE_LOWPASS_END_INSIDE = (6, 12)  # a low-passed force's ends fitted with this many samples inside [samples]
PLATE_EXACT_END_REACH = 6  # an exact undone force's ends fitted this many samples either side of those found [samples]
PLATE_END_JUMP_SIGMA = 10.0  # a fitted end's jump above this many residuals locates it to half a sample [-]
PLATE_FN_UNCERTAINTY = 0.01  # the resonance is known to about this fraction: how far TC moves is charged ... [-]
PLATE_END_MARGIN = 64  # ... undone again over the contact and this many samples (and 4 W) around it [samples]
PLATE_PEAK_SIGMA = 3.0  # the exact undone force's largest sample this many of its noise deviations ... [-]
PLATE_LOWPASS_SPIKE = 0.04  # ... above the low-passed peak: lost; the check must see a loss of this fraction [-]
PLATE_ZETA_UNCERTAINTY = 0.25  # the identified damping ratio is off by more than this fraction on 12 % of the zoo's
#                                undone plates (seeds 0-2, 297 of them; median 1 %, tails to 77 and 141 %) [-]
PLATE_PEAK_SPREAD = 0.015  # the undone peak moving by more than this fraction with the damping ratio that far off, or
#                            fn PLATE_FN_UNCERTAINTY off, is not known: half the peak's 3 % tolerance [-]
LOWPASS_SPIKE_FRACTION = 0.9  # a low-passed undone force's maximum in the spike's phase above this of its peak: the
#                               peak may be the spike, lowered by the kernel (and the sampling) by up to 15 % [-]
PEAK_FIT_S = 0.2e-3  # the exact undone force read at each sample from a quadratic fit over this long around it [s]
PEAK_FIT_RAMP_SAMPLES = 2  # ... up to it on the pre-buckling ramp: BUCKLING_TIME_S and this long after it [samples]
PEAK_FIT_MIN = 6  # ... of at least this many samples [samples]
PEAK_FIT_SIGMA = 3.0  # ... when its residual exceeds its expectation by at most this many of its deviations [-]
PEAK_FIT_IMPULSE_HALF = 64  # the plate's inverse's impulse response kept this far each side for the fits [samples]
PEAK_FIT_NOISE = 1.0  # the sensed noise raised by the centred fits' median residual over its expectation, from this [-]
#: Problems that plate ringing causes: checked again on the undone force.
PLATE_KINDS = frozenset({ProblemKind.PLATE_RINGING, ProblemKind.PEAK_ON_RINGING, ProblemKind.NEGATIVE_FORCE,
                         ProblemKind.PEAK_BETWEEN_SAMPLES, ProblemKind.CONTACT_END_UNDETERMINED,
                         ProblemKind.CONTACT_JUMP_UNRESOLVED,
                         ProblemKind.IMPULSE_UNRESOLVED})  # a plate's first overshoot is a single-sample top too
#: ... of which at least one must show the ringing itself.
PLATE_EVIDENCE = frozenset({ProblemKind.PLATE_RINGING, ProblemKind.PEAK_ON_RINGING, ProblemKind.NEGATIVE_FORCE})


class ConditioningWarning(UserWarning):
    """Usable but suspect conditioning (e.g. the decay could not be estimated)."""


@dataclass(frozen=True)
class ConditionedSignal:
    """A plate voltage with baseline, hum and decay removed.

    Attributes
    ----------
    voltage_V : numpy.ndarray
        Corrected voltage, polarity applied: proportional to the force, zero
        baseline [V].
    noise_rms_V : float
        Noise standard deviation of the quiet baseline (robust) [V].
    hum_amplitude_V : float
        Peak amplitude of the mains hum fundamental [V] (0 when not fitted).
    hum_harmonic_amplitudes_V : tuple of float
        Peak amplitude of the fundamental and each harmonic fitted [V].
    tau_s : float
        Charge-amplifier time constant used for the decay correction [s]; inf
        when no correction was applied, NaN when no contact was found.
    tau_source : str
        ``"estimated"``, ``"given"`` or ``"none"``.
    undershoot_V : float
        Step of the baseline just after the contact, positive downwards
        (``kappa`` times the contact's integral) [V].
    undershoot_se_V : float
        Standard error of undershoot_V [V].
    offset_V : float
        DC offset of the pre-contact baseline (polarity applied) [V].
    baseline_V : numpy.ndarray
        Offset + hum model subtracted from every sample (polarity applied) [V].
    baseline_coefficients : dict
        The fitted model: ``offset_V``, ``hum_cos_V`` and ``hum_sin_V`` (one per
        harmonic), ``hum_frequencies_hz``, ``kappa_per_s`` (1 / tau),
        ``kappa_se_per_s``, ``mains_hz`` (the mains frequency used, 0 for
        none), ``mains_source`` (``"given"``, ``"detected"`` or ``"none"``).
    contact : ContactResult
        Contact found on the corrected voltage.
    n_iterations : int
        Window/baseline iterations done [-].
    warnings : tuple of str
        Messages of the ConditioningWarnings issued.
    problems : tuple of ballimpact.problems.Problem
        Reasons the impact cannot be trusted (each names what was seen);
        empty when the conditioning passed every integrity check.
    spike_indices : tuple of int
        Samples replaced as single-sample spikes [-].
    plate : ballimpact.plate.PlateResonance or None
        The plate resonance undone in ``voltage_V`` (None when none was).
    """

    voltage_V: np.ndarray
    noise_rms_V: float
    hum_amplitude_V: float
    hum_harmonic_amplitudes_V: tuple[float, ...]
    tau_s: float
    tau_source: str
    undershoot_V: float
    undershoot_se_V: float
    offset_V: float
    baseline_V: np.ndarray
    baseline_coefficients: dict = field(repr=False)
    contact: ContactResult = field(repr=False)
    n_iterations: int = 0
    warnings: tuple[str, ...] = ()
    problems: tuple[Problem, ...] = ()
    spike_indices: tuple[int, ...] = ()
    plate: PlateResonance | None = None


@dataclass
class _BaselineFit:
    baseline: np.ndarray  # offset + hum at every sample [V]
    coef: dict
    kappa: float  # 1 / tau [1/s] (the given one, or the estimate; NaN when not estimable)
    kappa_se: float  # its standard error [1/s]
    has_post: bool  # kappa could be estimated
    noise: float  # robust noise of the quiet residuals [V]
    hum_amplitudes: tuple[float, ...]
    bic: float  # Bayesian information criterion of the fit [-]
    quiet: np.ndarray  # samples used [bool]
    pre: np.ndarray  # pre-contact quiet samples [bool]
    post: np.ndarray  # post-contact quiet samples [bool]
    no_post: str = ""  # why kappa could not be estimated (what the record lacks), "" when it could


def remove_spikes(voltage_V, noise_rms_V: float | None = None, keep=()):
    """Replace isolated single-sample spikes by the mean of their two neighbours.

    A spike of height h at sample k has second differences ``h`` at k, ``-h/2``
    at k-1 and k+1 and about 0 at k-2, k+2, k-3 and k+3; a contact, ringing or a step has
    not. Spikes are those with ``|h|`` above SPIKE_SIGMA noise deviations of the
    second difference and that shape.

    Parameters
    ----------
    voltage_V : array_like
        Voltage [V].
    noise_rms_V : float, optional
        Noise of the second difference [V]; robust estimate when omitted.
    keep : iterable of int
        Samples never replaced, whatever their shape [-] (a sample at a contact
        end that is the force's own, see :func:`_spikes_at_ends`).

    Returns
    -------
    voltage_V : numpy.ndarray
        Copy with the spikes replaced [V].
    indices : numpy.ndarray
        Replaced samples [-].
    """
    v = np.array(voltage_V, dtype=float).ravel()
    d2, s = _second_differences(v)
    if noise_rms_V is not None:
        s = float(noise_rms_V)
    return _replace_spikes(v, d2, s, keep)


def _replace_spikes(v, d2, s, keep=()):
    """:func:`remove_spikes` on v (replaced in place and returned) with its second differences d2 and their
    noise s [V] (:func:`_second_differences`); a record of fewer than 7 samples is returned as it is."""
    if v.size < 7:
        return v, np.zeros(0, dtype=int)
    if not (s > 0):
        s = float(np.min(np.diff(np.unique(v)))) if np.unique(v).size > 1 else 0.0
        if not (s > 0):
            return v, np.zeros(0, dtype=int)
    cand = np.flatnonzero(np.abs(d2[3:-3]) > SPIKE_SIGMA * s) + 3
    cand = cand[~np.isin(cand, np.asarray(tuple(keep), dtype=int))]
    if cand.size == 0:
        return v, cand
    h = d2[cand]
    tol = SPIKE_SHAPE_TOLERANCE * np.abs(h)
    shape = (np.abs(d2[cand - 1] + 0.5 * h) < tol) & (np.abs(d2[cand + 1] + 0.5 * h) < tol)
    shape &= (np.abs(d2[cand - 2]) < tol) & (np.abs(d2[cand + 2]) < tol)
    shape &= (np.abs(d2[cand - 3]) < tol) & (np.abs(d2[cand + 3]) < tol)
    idx = cand[shape]
    v[idx] = 0.5 * (v[idx - 1] + v[idx + 1])
    return v, idx


def _second_differences(v):
    """Second differences ``v[k] - (v[k-1] + v[k+1]) / 2`` (0 at both ends) [V] and their robust noise [V]."""
    d2 = np.zeros(v.size)
    d2[1:-1] = v[1:-1] - 0.5 * (v[:-2] + v[2:])
    return d2, robust_noise(d2[1:-1])


def _spike_kink(voltage_V, k: int) -> float:
    """How far sample k's neighbours are from continuing one curve through it [V].

    With sample k replaced by its neighbours' mean M, the second differences at
    k-1 and k+1 become ``v[k-1] - (v[k-2] + M) / 2`` and ``v[k+1] - (M + v[k+2]) / 2``;
    the larger magnitude is returned. An electrical spike riding on a smooth
    force (or on the baseline) leaves them at the noise and the force's own
    curvature; at the force's jump from zero (section 3.2.4 in Goodwill & Haake
    2004: no force below 2 mm of compression) the samples before k continue the
    baseline and those after it the force, and they stand about a quarter of the
    jump apart.

    Parameters
    ----------
    voltage_V : array_like
        Voltage [V].
    k : int
        Sample, 2 <= k < len - 2 [-].

    Returns
    -------
    float
        The larger corrected second difference at k-1 or k+1, in magnitude [V].
    """
    v = np.asarray(voltage_V, dtype=float)
    if not 2 <= k < v.size - 2:
        raise ValueError(f"_spike_kink needs two samples either side of sample {k} (record of {v.size})")
    m = 0.5 * (v[k - 1] + v[k + 1])
    return float(max(abs(v[k - 1] - 0.5 * (v[k - 2] + m)), abs(v[k + 1] - 0.5 * (m + v[k + 2]))))


def _regions(n, fs, start_u, end_u, pre_guard, post_guard, mask):
    idx = np.arange(n)
    pre = (idx < start_u - pre_guard) & (idx >= start_u - pre_guard - PRE_WINDOW_S * fs)
    if np.count_nonzero(pre & ~mask) < MIN_PRE_SAMPLES and math.isfinite(start_u):
        # a short pre-trigger: come closer to the contact (the cloth foot is < 0.2 ms)
        pre = (idx < start_u - min(pre_guard, 0.2e-3 * fs)) & (idx >= start_u - PRE_WINDOW_S * fs)
    post = (idx > end_u + post_guard) & (idx <= end_u + post_guard + POST_WINDOW_S * fs)
    return pre & ~mask, post & ~mask


def _fit_baseline(v, fs, frequencies, start_u, end_u, pre_guard, post_guard, mask=None, with_decay=False,
                  kappa_given=None, reduce=True, noise_floor=0.0, cache: dict | None = None) -> _BaselineFit:
    """Robust least squares of the baseline model on the quiet samples (see the module docstring).

    Pre-contact quiet samples: ``v = B`` with ``B = sum_j theta_j phi_j`` (offset,
    drift, hum). Post-contact quiet samples: ``y + kappa * integral y = 0`` with
    ``y = v - B`` integrated from the contact start, i.e.
    ``v + kappa * Iv = sum_j theta_j (phi_j + kappa * Phi_j)`` (``Iv``, ``Phi_j``
    the running integrals of v and phi_j). For a given kappa this is linear in
    theta; kappa (when not given) minimises the residual sum of squares, found
    on a grid and refined, with normal equations built once (quadratic in kappa).

    When kappa comes out too uncertain for the impulse (a decay hidden in its
    standard error could bias it by more than BIAS_EXCLUDE_FRACTION, see
    _choose_tau) and ``reduce``, the fits with fewer hum harmonics (down to
    none) are tried too: the harmonics can take up the undershoot's step in a
    short record, and the fit of least BIC is returned.

    A dict ``cache`` (one per record ``v``) holds the fits made: the window
    enters the fit only through its quiet samples and the sample its running
    integrals start from, so a window that moved by less than that (the
    iteration's last steps) gets the same fit back without refitting it.
    """
    n = v.size
    if mask is None:
        mask = np.zeros(n, dtype=bool)
    regions = _quiet_regions(n, fs, start_u, end_u, pre_guard, post_guard, mask, with_decay, kappa_given)
    if cache is not None:
        pre, post, quiet, has_post, use_post, no_post = regions
        key = (tuple(frequencies), kappa_given, noise_floor, pre.tobytes(), post.tobytes(), quiet.tobytes(),
               has_post, use_post, no_post, _integral_start(start_u) if use_post else None)
        fit = cache.get(key)
        if fit is None:
            fit = cache[key] = _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor)
    else:
        fit = _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor)
    hidden = UNDERSHOOT_SIGNIFICANCE * fit.kappa_se
    if (reduce and fit.hum_amplitudes and regions[4] and kappa_given is None and hidden > abs(fit.kappa)
            and (end_u - start_u) / fs * hidden / 2.0 > BIAS_EXCLUDE_FRACTION):
        for k in range(len(fit.hum_amplitudes)):  # the harmonics fitted are all of ``frequencies``
            alt = _fit_baseline(v, fs, list(frequencies)[:k], start_u, end_u, pre_guard, post_guard, mask, with_decay,
                                kappa_given, reduce=False, noise_floor=noise_floor, cache=cache)
            if alt.bic < fit.bic:
                fit = alt
    return fit


def _fit_quiet(v, fs, frequencies, regions, start_u, kappa_given, noise_floor) -> _BaselineFit:
    """The fit of :func:`_fit_baseline` on its quiet samples ``regions`` (:func:`_quiet_regions`), before the
    fits with fewer harmonics are tried."""
    n = v.size
    pre, post, quiet, has_post, use_post, no_post = regions
    t = np.arange(n) / fs
    qi = np.flatnonzero(quiet)
    tq = t[qi]
    span = tq[-1] - tq[0] if tq.size else 0.0
    # a full period of the fundamental is needed, or no hum is fitted at all
    freqs = list(frequencies) if frequencies and span * min(frequencies) >= 1.0 else []
    t_mid = 0.5 * (tq[0] + tq[-1]) if tq.size else 0.0
    trig = _trig(n, fs, tuple(freqs))
    phi, norms, big_phi, iv = _design(v, fs, t, t_mid, trig, tuple(freqs), qi, post[qi], start_u, use_post)
    y = v[qi]
    p = phi.shape[1]
    keep = np.ones(qi.size, dtype=bool)
    for _ in range(2):
        ne = _normal_equations(phi, big_phi, y, iv, keep)
        kappa, curv = _best_kappa(ne, kappa_given, use_post)
        rss, theta = _solve_kappa(ne, kappa)
        columns = phi + kappa * big_phi  # the model's columns at this kappa
        resid = (y + kappa * iv) - columns @ theta
        s = robust_noise(resid[keep])
        new_keep = np.abs(resid) <= ROBUST_SIGMA * max(s, 1e-300)
        if np.count_nonzero(new_keep) < max(0.8 * qi.size, p + 3) or np.array_equal(new_keep, keep):
            break
        keep = new_keep
    n_par = p + (1 if (use_post and kappa_given is None) else 0)
    n_keep = int(np.count_nonzero(keep))
    s2 = rss / max(n_keep - n_par, 1)
    coef = theta / norms
    baseline = coef[0] + coef[1] * (t - t_mid) + trig @ coef[2:]
    if use_post and kappa_given is None:
        kappa_se = math.sqrt(2.0 * s2 / curv) if curv > 0 else math.inf
        if math.isfinite(kappa_se):
            # residuals that are not white (hum over less than a period, left to the drift and the decay) carry
            # less information on kappa than their number says
            kept = slice(None) if keep.all() else keep  # a view where nothing was dropped
            kappa_se *= math.sqrt(_correlation_factor(columns[kept], (iv - big_phi @ theta)[kept], resid[kept],
                                                      max(1, int(round(KAPPA_CORRELATION_S * fs)))))
    elif kappa_given is not None:
        kappa, kappa_se = float(kappa_given), 0.0
    else:
        kappa, kappa_se = math.nan, math.nan
    pre_q = pre[qi]
    noise_sel = pre_q & keep if np.count_nonzero(pre_q & keep) >= MIN_QUIET_SAMPLES else keep
    noise = max(robust_noise(resid[noise_sel]), noise_floor)  # no less than the ADC's step / sqrt(12)
    bic = n_keep * math.log(max(rss, 1e-300) / n_keep) + n_par * math.log(n_keep) if n_keep else math.inf
    amps = tuple(float(math.hypot(coef[2 + 2 * i], coef[3 + 2 * i])) for i in range(len(freqs)))
    coef_dict = {
        "offset_V": float(coef[0] + coef[1] * (t[0] - t_mid)),
        "drift_V_per_s": float(coef[1]),
        "hum_frequencies_hz": tuple(float(f) for f in freqs),
        "hum_cos_V": tuple(float(coef[2 + 2 * i]) for i in range(len(freqs))),
        "hum_sin_V": tuple(float(coef[3 + 2 * i]) for i in range(len(freqs))),
        "kappa_per_s": float(kappa),
        "kappa_se_per_s": float(kappa_se),
    }
    return _BaselineFit(baseline, coef_dict, float(kappa), float(kappa_se), has_post or kappa_given is not None,
                        noise, amps, bic, quiet, pre, post, no_post)


def _quiet_regions(n, fs, start_u, end_u, pre_guard, post_guard, mask, with_decay, kappa_given):
    """Quiet samples of the baseline fit: (pre, post, quiet, has_post, use_post, no_post).

    Boolean masks and flags; ``no_post`` says what the record lacks when the
    decay cannot be measured ("" when it can). The post stretch starts
    post_guard after the contact; when that leaves fewer than MIN_POST_S of
    it (a short post-trigger), it starts SHORT_POST_GUARD_S after the contact
    and needs SHORT_MIN_POST_S only: the standard error of kappa then says in
    _choose_tau whether a decay hidden in the noise could bias the impulse.
    """
    pre, post = _regions(n, fs, start_u, end_u, pre_guard, post_guard, mask)
    min_post = max(MIN_QUIET_SAMPLES, int(round(MIN_POST_S * fs)))
    if with_decay and np.count_nonzero(post) < min_post and post_guard > SHORT_POST_GUARD_S * fs:
        short = _regions(n, fs, start_u, end_u, pre_guard, SHORT_POST_GUARD_S * fs, mask)[1]
        min_short = max(MIN_QUIET_SAMPLES, int(round(SHORT_MIN_POST_S * fs)))
        if np.count_nonzero(short) >= np.count_nonzero(post):
            post, min_post = short, min_short
    has_pre = np.count_nonzero(pre) >= MIN_PRE_SAMPLES
    has_post = has_pre and with_decay and np.count_nonzero(post) >= min_post
    no_post = ""
    if with_decay and not has_pre:
        no_post = (f"only {np.count_nonzero(pre)} quiet samples before the contact (at least {MIN_PRE_SAMPLES} "
                   "needed) to measure the undershoot against")
    elif with_decay and not has_post:
        no_post = (f"only {1e3 * np.count_nonzero(post) / fs:.2g} ms of quiet record after the contact (at least "
                   f"{1e3 * min_post / fs:.2g} ms from {1e3 * min(post_guard / fs, SHORT_POST_GUARD_S):.2g} ms after "
                   "its end needed) to measure the undershoot")
    if not with_decay or not has_pre:
        post = post & False if has_pre else post
    quiet = pre | post
    if np.count_nonzero(quiet) < MIN_PRE_SAMPLES:
        # no quiet stretch at all: a median offset is the best there is
        quiet = ~mask if np.count_nonzero(~mask) >= 3 else np.ones(n, dtype=bool)
        pre, post = quiet, np.zeros(n, dtype=bool)
        has_post = False
    use_post = has_post and (kappa_given is None or kappa_given > 0)
    if not has_post and has_pre and with_decay:
        quiet = pre  # the post stretch alone cannot tell an offset from the undershoot
        post = np.zeros(n, dtype=bool)
    return pre, post, quiet, has_post, use_post, no_post


def _design(v, fs, t, t_mid, trig, freqs, qi, post_q, start_u, use_post):
    """Normalised model columns at the quiet samples and, after the contact, their running integrals and v's.

    Returns (phi, norms, big_phi, iv): columns offset, drift, cos/sin per hum
    frequency (``trig``'s columns, of ``freqs`` [Hz]), scaled to unit norm
    (``norms``); their trapezoid integrals from the contact start and that of v
    at the post-contact quiet samples (zero elsewhere). The columns' integrals
    are the trapezoid rule's sums in closed form: exact for the offset and the
    drift, and for cos and sin of w t at step h, (h / 2) cot(w h / 2) times the
    change of sin (and minus that of cos) from the start, as the sum of the
    trapezoids telescopes; v's is summed.
    """
    phi = np.empty((qi.size, 2 + trig.shape[1]))
    phi[:, 0] = 1.0
    np.subtract(t[qi], t_mid, out=phi[:, 1])
    phi[:, 2:] = trig[qi]
    norms = np.sqrt(np.sum(phi * phi, axis=0))
    norms[norms == 0] = 1.0
    phi /= norms
    big_phi = np.zeros_like(phi)
    iv = np.zeros(qi.size)
    if use_post and post_q.any():
        i0 = _integral_start(start_u)
        first = int(np.argmax(post_q))
        if post_q[first:].all():  # the post stretch follows the pre one: a slice, not a mask
            post_q = slice(first, None)
        j = qi[post_q]
        h = 1.0 / fs
        cols = [t[j] - t[i0], 0.5 * ((t[j] - t_mid) ** 2 - (t[i0] - t_mid) ** 2)]
        for i, f in enumerate(freqs):
            half = math.pi * f * h
            k = 0.5 * h * math.cos(half) / math.sin(half)
            cols.append(k * (trig[j, 2 * i + 1] - trig[i0, 2 * i + 1]))
            cols.append(-k * (trig[j, 2 * i] - trig[i0, 2 * i]))
        big_phi[post_q] = np.column_stack(cols) / norms
        iv[post_q] = cumulative_trapezoid(v[i0:int(j[-1]) + 1], dx=h, initial=0.0)[j - i0]
    return phi, norms, big_phi, iv


def _normal_equations(phi, big_phi, y, iv, keep):
    """Coefficients of the normal equations, quadratic in kappa, of the kept samples."""
    a, b_, y_, i_ = (phi, big_phi, y, iv) if keep.all() else (phi[keep], big_phi[keep], y[keep], iv[keep])
    return (a.T @ a, a.T @ b_ + b_.T @ a, b_.T @ b_, a.T @ y_, a.T @ i_ + b_.T @ y_, b_.T @ i_,
            float(y_ @ y_), 2.0 * float(y_ @ i_), float(i_ @ i_))


def _solve_kappa(ne, k):
    """Residual sum of squares and coefficients for kappa = k (a scalar or an array of them)."""
    p0, p1, p2, q0, q1, q2, r0, r1, r2 = ne
    k = np.atleast_1d(np.asarray(k, dtype=float))[:, None, None]
    a = p0 + k * p1 + k * k * p2
    q = (q0 + k[:, :, 0] * q1 + k[:, :, 0] ** 2 * q2)[:, :, None]
    try:
        theta = np.linalg.solve(a, q)[:, :, 0]
    except np.linalg.LinAlgError:
        theta = (np.linalg.pinv(a, rcond=1e-12, hermitian=True) @ q)[:, :, 0]
    kk = k[:, 0, 0]
    rss = np.maximum(r0 + kk * r1 + kk * kk * r2 - np.sum(q[:, :, 0] * theta, axis=1), 0.0)
    return (float(rss[0]), theta[0]) if rss.size == 1 else (rss, theta)


def _correlation_factor(x: np.ndarray, d: np.ndarray, r: np.ndarray, lag: int) -> float:
    """How much correlated residuals widen kappa's variance [-]: at least 1.

    kappa's least-squares estimate moves with the sum of its scores ``r * w``,
    the residuals r [V] times w, the residual's derivative in kappa ``d`` [V s]
    with the other columns ``x`` projected out. Its variance is the scores'
    long-run variance, estimated with a Bartlett window of ``lag`` samples
    (Newey & West 1987) over the quiet samples in their order; the fit's own
    standard error takes the scores' variance at lag 0 (white residuals). The
    factor is their ratio, never below 1.
    """
    if r.size < 3:
        return 1.0
    try:
        w = d - x @ np.linalg.solve(x.T @ x, x.T @ d)
    except np.linalg.LinAlgError:
        w = d - x @ np.linalg.lstsq(x, d, rcond=None)[0]
    scores = r * w
    n = scores.size
    n_fft = 1 << (2 * n - 1).bit_length()  # zero-padded to a power of two: no wrap-around, and a fast transform
    acov = np.fft.irfft(np.abs(np.fft.rfft(scores, n_fft)) ** 2, n_fft)[:min(lag, n)]
    if not acov[0] > 0:
        return 1.0
    window = 1.0 - np.arange(acov.size) / (lag + 1.0)
    long_run = acov[0] + 2.0 * float(np.sum(window[1:] * acov[1:]))
    return max(1.0, long_run / float(acov[0]))


def _rss_slope(ne, k: float) -> tuple[float, float]:
    """First and second derivative of the residual sum of squares in kappa at kappa = k [V^2 s, V^2 s^2].

    With A(k) = p0 + k p1 + k^2 p2, q(k) = q0 + k q1 + k^2 q2, r(k) = r0 + k r1 + k^2 r2 and
    theta = A^-1 q, rss = r - q.theta, so rss' = r' - 2 q'.theta + theta.A'.theta, and with
    theta' = A^-1 (q' - A' theta), rss'' = r'' - 2 q''.theta - 2 q'.theta' + 2 theta'.A'.theta + theta.A''.theta.
    """
    p0, p1, p2, q0, q1, q2, r0, r1, r2 = ne
    a, a1 = p0 + k * p1 + k * k * p2, p1 + 2.0 * k * p2
    q, dq = q0 + k * q1 + k * k * q2, q1 + 2.0 * k * q2
    try:
        theta = np.linalg.solve(a, q)
        dtheta = np.linalg.solve(a, dq - a1 @ theta)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(a, rcond=1e-12, hermitian=True)
        theta = inv @ q
        dtheta = inv @ (dq - a1 @ theta)
    a1_theta = a1 @ theta
    d1 = r1 + 2.0 * k * r2 - 2.0 * float(dq @ theta) + float(theta @ a1_theta)
    d2 = (2.0 * r2 - 4.0 * float(q2 @ theta) - 2.0 * float(dq @ dtheta) + 2.0 * float(dtheta @ a1_theta)
          + 2.0 * float(theta @ p2 @ theta))
    return d1, d2


def _refine_kappa(ne, lo: float, hi: float, k0: float, xatol: float) -> float:
    """The least residual sum of squares in kappa between lo and hi [1/s], from k0: Newton's steps on its slope
    (:func:`_rss_slope`), kept inside the bracket the slope's sign narrows, bisecting where a step would leave it
    or not shrink it fast enough (``rtsafe``, Press et al., Numerical Recipes, section 9.4), to xatol [1/s]; the
    bound where the slope does not change sign between them."""
    f_lo, f_hi = _rss_slope(ne, lo)[0], _rss_slope(ne, hi)[0]
    if not f_lo < 0.0:
        return lo
    if not f_hi > 0.0:
        return hi
    k = min(max(k0, lo), hi)
    dx_old = dx = hi - lo
    for _ in range(KAPPA_REFINE_ITERATIONS):
        f, df = _rss_slope(ne, k)
        if f == 0.0:
            return k
        if f < 0.0:
            lo = k
        else:
            hi = k
        if not df > 0.0 or not lo < k - f / df < hi or abs(2.0 * f) > abs(dx_old * df):
            dx_old, dx = dx, 0.5 * (hi - lo)
            k = lo + dx
        else:
            dx_old, dx = dx, f / df
            k -= dx
        if abs(dx) < xatol or hi - lo < xatol:
            break
    return k


def _best_kappa(ne, kappa_given, use_post):
    """kappa = 1 / tau [1/s] of least residual (grid, then Newton's refinement) and the residual's second
    derivative there [V^2 s^2]."""
    if kappa_given is not None or not use_post:
        return (kappa_given if use_post else 0.0), math.nan
    k_max = 2.0 / TAU_BOUNDS_S[0]
    pos = np.geomspace(1e-4, k_max, 48)
    grid = np.concatenate([-pos[::-1], [0.0], pos])
    rss = _solve_kappa(ne, grid)[0]
    j = int(np.argmin(rss))
    lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
    k = _refine_kappa(ne, float(lo), float(hi), float(grid[j]), 1e-9 * max(abs(grid[j]), 1e-3))
    if not _solve_kappa(ne, k)[0] <= rss[j]:
        k = float(grid[j])
    # the curvature from the analytic second derivative: a central difference of the residual (steps of 1e-3 of
    # kappa) subtracts sums that agree to 1e-13 where the residual is flat, and came out up to 70 % high on zoo
    # trace 0:52 (kappa 0.15 per s), its standard error as much too small
    return k, _rss_slope(ne, k)[1]


@functools.lru_cache(maxsize=4)
def _trig(n, fs, freqs):
    """cos and sin of each frequency at the n sample times, one column each [-]."""
    t = np.arange(n) / fs
    out = np.empty((n, 2 * len(freqs)))
    for i, f in enumerate(freqs):
        out[:, 2 * i] = np.cos(2 * np.pi * f * t)
        out[:, 2 * i + 1] = np.sin(2 * np.pi * f * t)
    out.flags.writeable = False
    return out


def _rough_trend(v, n_blocks=20):
    """A robust straight line through the record (Theil-Sen on block medians) [V]."""
    n = v.size
    if n < 4 * n_blocks:
        return np.full(n, finite_median(v))
    edges = np.linspace(0, n, n_blocks + 1).astype(int)
    centres = 0.5 * (edges[:-1] + edges[1:] - 1)
    meds = np.array([finite_median(v[a:b]) for a, b in zip(edges[:-1], edges[1:])])
    i, j = np.triu_indices(n_blocks, 1)
    slope = finite_median((meds[j] - meds[i]) / (centres[j] - centres[i]))
    icpt = finite_median(meds - slope * centres)
    return icpt + slope * np.arange(n)


def _integral_start(start_u: float) -> int:
    """The sample the running integrals of the baseline fit and the decay's correction start from: the one before
    the contact's start ``start_u`` [samples], or the first."""
    return max(int(math.floor(start_u)) - 1, 0)


def _running_integral(y, fs, start_u):
    """Trapezium integral of y from the sample before start, 0 before it [V s]."""
    i0 = _integral_start(start_u)
    out = np.zeros(y.size)
    if i0 < y.size - 1:
        out[i0:] = cumulative_trapezoid(y[i0:], dx=1.0 / fs, initial=0.0)
    return out


def _decay_correct(y, running, tau):
    """Inverse first-order high-pass from the contact start: y + cumulative integral / tau; ``running`` is y's
    :func:`_running_integral` [V s], tau in [s]."""
    x = y.copy()
    if math.isfinite(tau):
        x += running / tau
    return x


def _integral_to(running, start_u, end_u) -> float:
    """Trapezium integral of y from the sample before start to the sub-sample end [V s], from y's
    :func:`_running_integral` ``running`` [V s] from the same start."""
    i0 = _integral_start(start_u)
    c = running[i0:]
    return float(np.interp(end_u - i0, np.arange(c.size), c))


def _mains_frequencies(mains_hz, n_harmonics, fs):
    return [k * mains_hz for k in range(1, n_harmonics + 1) if k * mains_hz < NYQUIST_MARGIN * fs]


def _event_threshold(noise, peak) -> float:
    """The level an event of the corrected record stands above: EVENT_SIGMA noise deviations and EVENT_FRACTION of
    the main peak (``noise`` and ``peak`` in one unit, the threshold in it)."""
    return max(EVENT_SIGMA * noise, EVENT_FRACTION * peak)


def _event_mask(x, fs, noise, contact: ContactResult, pre_guard, post_guard):
    """Samples of every event other than the main contact (runs standing out of the noise), with guards."""
    n = x.size
    peak = max(float(x[contact.peak_index]), 0.0) if contact.found else float(np.max(x))
    thr = _event_threshold(noise, peak)
    above = x > thr
    if contact.found:
        a = max(int(math.floor((contact.start_s - 0.0) * fs - pre_guard)), 0)
        b = min(int(math.ceil(contact.end_s * fs + post_guard)) + 1, n)
        above[a:b] = False
    mask = np.zeros(n, dtype=bool)
    if not above.any():
        return mask
    # each event with its shoulders: the run of samples above EVENT_SHOULDER_SIGMA noise around its core
    shoulder = x > EVENT_SHOULDER_SIGMA * noise
    if contact.found:
        shoulder[a:b] = False
    d = np.diff(np.concatenate([[0], shoulder.view(np.int8), [0]]))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    cores = np.flatnonzero(above)
    keep = np.unique(np.searchsorted(starts, cores, side="right") - 1)  # the shoulder run holding each core sample
    gb, ga = int(round(EVENT_GUARD_BEFORE_S * fs)), int(round(EVENT_GUARD_AFTER_S * fs))
    for s, e in zip(starts[keep], ends[keep]):
        mask[max(s - gb, 0):min(e + ga, n)] = True
    return mask


def condition_voltage(voltage_V, sample_rate_hz: float, *, polarity: int = 1, mains_hz: float | str | None = "auto",
                      n_harmonics: int = 3, t0_s: float = 0.0, tau_s: float | None = None,
                      pre_guard_s: float = PRE_GUARD_S, post_guard_s: float = POST_GUARD_S,
                      undo_plate: bool = True, plate: tuple | None = None, _kept: tuple | None = None,
                      _near_ends: tuple = ()) -> ConditionedSignal:
    """Remove polarity, offset, mains hum and charge-amplifier decay from a plate voltage.

    The force-plate voltage must be proportional to the force for kCAL to be
    found from the impulse (section 2 in Goodwill & Haake 2004); this removes
    what the sensor chain adds. See the module docstring for the method. The
    impulse is not biased by the amplifier's undershoot: the decay is undone
    with the time constant that returns the post-contact baseline to zero.

    Parameters
    ----------
    voltage_V : array_like
        Voltage as recorded, one sample per 1/sample_rate_hz [V].
    sample_rate_hz : float
        Sample rate [Hz].
    polarity : int
        +1 when compressive force gives positive voltage, -1 otherwise [-].
    mains_hz : float, "auto" or None
        Mains frequency [Hz], used exactly; ``"auto"`` (default) detects 50 Hz,
        60 Hz or no hum from the quiet samples; None or 0 fits no hum.
    n_harmonics : int
        Hum components fitted: the fundamental and its harmonics up to
        ``n_harmonics * mains_hz`` [-].
    t0_s : float
        Time of the first sample [s] (only for the times reported).
    tau_s : float, optional
        Known amplifier time constant [s], undone exactly; ``math.inf`` for a
        DC-coupled amplifier. Estimated from the post-contact baseline when
        omitted.
    pre_guard_s, post_guard_s : float
        Samples closer than this to the contact are left out of the baseline
        fit [s].
    undo_plate : bool
        Undo a plate resonance identified from its ringing when that ringing
        is the only problem (see the module docstring); False reports the
        ringing as a problem.
    plate : tuple of float, optional
        A stated resonance (frequency [Hz], damping ratio [-]), e.g. from a tap
        test (session.yaml ``plate.resonance_hz``, ``plate.damping_ratio``):
        undone exactly on every trace, neither identified nor refined; where the
        force so undone fails the undone force's checks, the trace is
        conditioned as without it (its plate identified where it rings).
    _kept, _near_ends : tuple of int
        Internal, set when this function calls itself again: samples at a
        contact end not to be replaced as spikes, and lower spikes near the
        ends to be replaced (see :func:`_spikes_at_ends`); None at the first
        pass.

    Returns
    -------
    ConditionedSignal
        Corrected voltage [V] with the noise [V], hum [V], tau [s], baseline
        model, the contact found on it and the integrity problems found. When
        no contact is found, only offset and hum are removed and
        ``contact.found`` is False.

    Raises
    ------
    ValueError
        For non-finite samples, fewer than 3 samples, a non-positive sample rate,
        a polarity other than +1/-1, a negative mains_hz or a non-positive tau_s.

    Warns
    -----
    ConditioningWarning
        When the decay cannot be estimated (no measurable undershoot, baseline
        after the contact above the one before it, post-contact stretch too
        short, implausible tau) and could bias the impulse by more than 0.1 %.
    """
    fs = float(sample_rate_hz)
    raw = _checked_voltage(voltage_V, sample_rate_hz, polarity, mains_hz, n_harmonics, tau_s, pre_guard_s,
                           post_guard_s)
    # work in units of the largest magnitude: no overflow for any finite input
    scale = float(np.max(np.abs(raw)))
    if not (scale > 0 and math.isfinite(scale)):
        scale = 1.0
    v_spiky = polarity * (raw / scale)
    # an ADC step above the noise: the noise is taken as no less than the step's (its error's deviation)
    adc_step = quantization_step(v_spiky)
    noise_floor = adc_step / math.sqrt(12.0)
    d2_spiky = _second_differences(v_spiky)  # the record's, with its noise (also for the spikes at the ends)
    v, spikes = _replace_spikes(v_spiky.copy(), *d2_spiky, keep=_kept or ())
    if _near_ends:
        near = np.asarray(_near_ends, dtype=int)
        v[near] = 0.5 * (v_spiky[near - 1] + v_spiky[near + 1])
        spikes = np.union1d(spikes, near)
    auto_mains = isinstance(mains_hz, str)
    if auto_mains:
        candidates = {0.0: []}
        candidates.update({f: _mains_frequencies(f, n_harmonics, fs) for f in MAINS_CANDIDATES_HZ})
    else:
        candidates = {float(mains_hz or 0.0): _mains_frequencies(mains_hz, n_harmonics, fs) if mains_hz else []}
    mains_source = "detected" if auto_mains else ("given" if mains_hz else "none")
    kappa_given = None if tau_s is None else (0.0 if math.isinf(tau_s) else 1.0 / float(tau_s))

    trend = _rough_trend(v)
    # the record before the peak holds no undershoot: its median is the level under the contact
    k_peak = int(np.argmax(v - trend))
    if k_peak >= MIN_QUIET_SAMPLES:
        trend = np.full(v.size, finite_median(v[:k_peak]))
    rough = detect_contact(v - trend, fs)
    if not rough.found:
        fits = {f: _fit_baseline(v, fs, fr, -math.inf, -math.inf, 0.0, 0.0, noise_floor=noise_floor)
                for f, fr in candidates.items()}
        mains = min(fits, key=lambda f: fits[f].bic)
        fit = fits[mains]
        y = v - fit.baseline
        contact = detect_contact(y, fs, t0_s=t0_s, noise_rms_V=fit.noise)
        # A contact that shows only once a baseline is fitted through it (its own samples included: a flat top
        # under a short pre-trigger left the record's level before its largest sample at the top,
        # bench/saturation_map.py trace 2:320) has no baseline known under it, and none of the checks below ran.
        unchecked = [Problem(ProblemKind.CONTACT_UNSTABLE,
                             "contact window not stable: no contact stands out of the record until a baseline is "
                             "fitted through the whole of it, the contact's own samples included, so the baseline "
                             "under the contact is unknown and the contact was not checked")] if contact.found else []
        return _result(y, fit, math.nan, "none", contact, 0, [], unchecked, t0_s, scale, spikes, mains,
                       mains_source)

    it = _iterate(v, fs, candidates, rough, pre_guard_s * fs, post_guard_s * fs, tau_s, kappa_given, scale, noise_floor)
    # detect_contact(it.x, fs, t0_s=t0_s, noise_rms_V=it.fit.noise, ...), sharing the last iteration's search
    contact = _curve_end_contact(it.search.result(t0_s=t0_s, spread=True, curve=True, step=True), fs, t0_s)
    at_ends, keep = _spikes_at_ends(v_spiky, d2_spiky, spikes, _kept, contact, it.x, it.fit.noise, fs, t0_s, scale)
    near_ends = _low_spikes_at_ends(v_spiky, d2_spiky, spikes, contact, fs, t0_s) if _kept is None else ()
    if keep or near_ends:  # the force's own samples at its jump kept, lower spikes at the ends replaced: again
        return condition_voltage(voltage_V, sample_rate_hz, polarity=polarity, mains_hz=mains_hz,
                                 n_harmonics=n_harmonics, t0_s=t0_s, tau_s=tau_s, pre_guard_s=pre_guard_s,
                                 post_guard_s=post_guard_s, undo_plate=undo_plate, plate=plate, _kept=keep,
                                 _near_ends=near_ends)
    messages: list[str] = []
    for msg in it.pending:
        warnings.warn(msg, ConditioningWarning, stacklevel=2 if _kept is None else 3)
        messages.append(msg)
    problems = it.problems + it.tau_problems
    problems.extend(at_ends)
    if contact.found:
        problems.extend(_integrity(it.x, fs, it.fit, contact, t0_s, scale, it.ambiguous, it.start_u, it.end_u,
                                   post_guard_s))
        problems.extend(_short_record_hum(it.x, fs, it.fit, tuple(f for f in candidates if f > 0),
                                          float(contact.peak_V), scale))
        staircase = _adc_step_problems(it.x, fs, it.fit.noise, adc_step, contact, t0_s, scale)
        staircase += _baseline_step_problems(it.x, fs, it.fit, contact, t0_s, scale, tau_given=tau_s is not None)
        problems.extend(staircase)
        stated = []  # a stated plate's peak problems (its undone force kept, the peak withheld)
        undone = None
        if undo_plate and plate is not None:  # stated (plate.resonance_hz, plate.damping_ratio): used exactly ...
            undone, stated = _stated_plate_undone(it.x, fs, it.fit, contact, t0_s, plate)
        if undo_plate and (plate is None or isinstance(undone, str)):  # ... or, refused, identified from the trace
            undone = _plate_undone(it.x, fs, it.fit, contact, problems, t0_s)
        if isinstance(undone, str):  # tried and refused: the ringing problems stay, and why the undoing did not help
            problems.append(Problem(ProblemKind.PLATE_RINGING, undone, data={"undo_refused": 1.0}))
        elif undone is not None:
            y, contact, plate, cutoff = undone
            peak_problems = (_undone_peak_spread(it.x, fs, contact, plate, cutoff, t0_s)
                             + _lowpassed_spike(y, fs, contact, plate, cutoff, t0_s) + stated)
            messages.append(f"plate resonance at {plate.frequency_hz / 1e3:.3g} kHz (damping ratio "
                            f"{plate.damping_ratio:.2g}) identified from its ringing and undone"
                            + ("" if math.isinf(cutoff) else f", low-passed at {cutoff / 1e3:.3g} kHz"))
            # the undone force's own noise: the ringing's plateau check on its final contact
            plateau = _plateau_end_problems(y, fs, robust_noise(np.diff(y)) / math.sqrt(2.0), contact, t0_s)
            return _result(y, it.fit, it.tau, it.source, contact, it.n_iter, messages,
                           at_ends + staircase + plateau + peak_problems, t0_s, scale, spikes, it.mains, mains_source,
                           it.contact_integral, plate)
        problems.extend(_plateau_end_problems(it.x, fs, it.fit.noise, contact, t0_s))
    # last, on a trace nothing else excludes or whose ends alone are in doubt (its fits cost a few ms): a low-pass
    # is then the cause to name (the spread check alone may see its slow front: lowpass map trace 1:85)
    if contact.found and all(p.kind is ProblemKind.CONTACT_END_UNDETERMINED for p in problems):
        problems = problems + _front_lowpass(it.x, fs, it.fit.noise, float(contact.peak_V),
                                             (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs,
                                             contact.contact_time_s)
    if contact.found and not problems:  # after the low-pass, which a slow fall may be too and which names TC's error
        s_u = (contact.start_s - t0_s) * fs
        xc = it.x[max(int(math.ceil(s_u)), 0):int(math.floor((contact.end_s - t0_s) * fs)) + 1]
        problems = _peak_on_slow_fall(xc, fs, it.fit.noise, float(contact.peak_V), math.ceil(s_u) - s_u)
    return _result(it.x, it.fit, it.tau, it.source, contact, it.n_iter, messages, problems, t0_s, scale, spikes,
                   it.mains, mains_source, it.contact_integral)


def _adc_step_problems(x, fs, noise, step, contact: ContactResult, t0_s, scale) -> list[Problem]:
    """Contact ends read off the staircase of an ADC whose step the noise does not dither: not known to 1 %.

    An ADC records whole steps (:func:`ballimpact.contact.quantization_step`).
    Noise of less than ADC_STEP_DITHER of a step does not dither them: where
    the force fades slowly to zero at an end, the recorded trace stays on one
    step for several samples and then drops to the next, and the line through
    the end's samples is fitted to a staircase whose errors are neither random
    nor independent. The end found was 1.2 samples late, 3 of its standard
    errors (``python bench/adc_map.py --n 400 --seed 3`` trace 3:262: 12 bits,
    noise 0.25 mV under a step of 4.9 mV, TC +1.1 %). Each end is known to
    about the time the force takes to cross a step there (read over the
    samples from the end to where it first stands ADC_STEP_CROSSING steps
    above zero): the force meets zero within half a step's crossing of the
    staircase's last edge. Where a crossing takes more than
    ADC_STEP_MAX_FRACTION of TC, that half is more than half of the 1 %
    budget, and the end is not determined to 1 % (at half that fraction the
    map's seed 1 lost 57 more of its 400 traces, every one of them right, TC
    within 0.8 %). A jump crosses many steps within a sample and passes. Not
    in the paper; see docs/robustness-history.md, "A coarse ADC".

    Parameters
    ----------
    x : numpy.ndarray
        Corrected signal [scaled V].
    fs : float
        Sample rate [Hz].
    noise : float
        Its noise, floored at the step's error [scaled V].
    step : float
        The ADC's step [scaled V] (0: none found).
    contact : ContactResult
        The contact found.
    t0_s : float
        Time of the first sample [s].
    scale : float
        Volts per scaled unit [V].

    Returns
    -------
    list of Problem
        A CONTACT_END_UNDETERMINED problem per end so read; empty otherwise.
    """
    tc = float(contact.contact_time_s)
    if not (step > 0 and noise < ADC_STEP_DITHER * step and tc > 0):
        return []
    out = []
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    for name, u, inward in (("start", s_u, 1), ("end", e_u, -1)):
        k = int(math.ceil(u)) if inward > 0 else int(math.floor(u))
        limit = int(math.floor(e_u)) if inward > 0 else int(math.ceil(s_u))
        while 0 <= k < x.size and (k - limit) * inward < 0 and x[k] <= ADC_STEP_CROSSING * step:
            k += inward
        per_step = abs(k - u) / ADC_STEP_CROSSING / fs  # [s]
        if per_step > ADC_STEP_MAX_FRACTION * tc:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {name} not determined to 1 %: the record's noise is under half its ADC step "
                               f"({1e3 * step * scale:.3g} mV) and does not dither it, and the force takes "
                               f"{1e6 * per_step:.3g} us ({100 * per_step / tc:.2g} % of TC) to cross a step at its "
                               f"{name}: the {name} is read off a staircase (record with a finer ADC range or more "
                               "bits)"))
    return out


def _spikes_at_ends(v_spiky, d2_spiky, spikes, kept, contact: ContactResult, x, noise, fs, t0_s, scale):
    """Single-sample spikes within SPIKE_END_SAMPLES of a contact end: replaced, kept or the end not determined.

    :func:`remove_spikes` replaces a sample that stands alone above its
    neighbours by their mean. At a contact end the force jumps (from zero
    below 2 mm of compression, section 3.2.4 in Goodwill & Haake 2004), and
    the force's own samples there can have that shape: a lightly damped plate
    sampled about twice a period answers the jump with a one-sample overshoot
    (replacing it took 1.2 % out of the impulse, kCAL +1.2 %, TC +1.2 %, on the
    rig of ``python bench/overshoot_map.py --n 400 --seed 5`` trace 5:183,
    tests/test_robustness.py), and at 50 kHz the ball's pre-buckling spike,
    0.03-0.04 ms long at 12 m/s, is one sample (zoo traces 0:1635 and 1:1331,
    2.3 and 2.7 V between 0.3-0.5 and 1.3-1.6 V).

    They are told apart by whether the replaced sample's neighbours continue one
    curve (:func:`_spike_kink` at most SPIKE_KINK_SIGMA noise deviations of the
    second difference): an electrical spike on the force's smooth fade or on
    the baseline leaves them so, and its replacement is right (zoo trace
    3:1755: 1.18 V, 2.7 samples before the end, 2.1 noise deviations); at the
    jump the neighbours before it continue the baseline and those after it the
    force (0:1635: 187, 1:1331: 66, 5:183: 16 noise deviations). Such samples
    are returned to be kept: the caller conditions the trace again without
    replacing them.

    A kept sample is the force's own or an electrical spike riding on the
    jump, and the samples cannot tell which. The end is not determined when
    the sample is the contact's outermost (its outer neighbour within
    EVENT_SIGMA noise deviations of zero: without it the contact might begin a
    sample later); otherwise the end rests on its neighbour, and the sample's
    excess over its neighbours' mean, were it all electrical, is charged to the
    impulse: above SPIKE_END_IMPULSE of it the end is not determined (the
    plate's overshoot of 5:183: 1.2 %; the ball's spike of 0:1635: 0.31 %).

    Parameters
    ----------
    v_spiky : numpy.ndarray
        Voltage before spike removal, in units of ``scale`` [-].
    d2_spiky : tuple
        Its second differences and their noise (:func:`_second_differences`) [-].
    spikes : array_like of int
        Samples replaced [-].
    kept : tuple of int or None
        Samples kept at the caller's second pass (None at the first) [-].
    contact : ContactResult
        Contact found on the conditioned signal.
    x : numpy.ndarray
        Conditioned signal, in units of ``scale`` [-].
    noise : float
        Its noise, in units of ``scale`` [-].
    fs, t0_s, scale : float
        Sample rate [Hz], time of the first sample [s], volts per unit [V].

    Returns
    -------
    problems : list of Problem
    keep : tuple of int
        Samples to keep at a second pass (empty when there is none to make).
    """
    if not contact.found or not (len(spikes) or kept):
        return [], ()
    first, kept = kept is None, (() if kept is None else kept)
    ends = {"start": (contact.start_s - t0_s) * fs, "end": (contact.end_s - t0_s) * fs}
    s_d2 = d2_spiky[1]
    jumps = {}
    for where, u in ends.items():
        for k in (int(k) for k in spikes if abs(int(k) - u) <= SPIKE_END_SAMPLES):
            if 2 <= k < v_spiky.size - 2 and _spike_kink(v_spiky, k) <= SPIKE_KINK_SIGMA * s_d2:
                continue  # an electrical spike on one curve: replaced right
            jumps.setdefault(k, (where, u))
    if jumps and first:
        return [], tuple(sorted(jumps))
    for k, (where, u) in jumps.items():  # a second pass that replaced another sample at a jump
        return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                        f"contact {where} not determined: a single-sample spike was replaced {k - u:+.2g} "
                        f"samples from it ({1e3 * (k - u) / fs:+.2g} ms); at the force's jump a lightly damped "
                        "plate's overshoot has that shape, so the sample may be the force's and not known")], ()
    s_u, e_u = ends["start"], ends["end"]
    a, b = max(int(math.ceil(s_u)), 0), min(int(math.floor(e_u)) + 1, x.size)
    impulse = float(np.sum(x[a:b]))  # [unit samples]
    for k in kept:
        where, u = ("start", s_u) if abs(k - s_u) <= abs(k - e_u) else ("end", e_u)
        if not 1 <= k < x.size - 1:
            continue
        outer = x[k - 1] if where == "start" else x[k + 1]
        excess = float(x[k] - 0.5 * (x[k - 1] + x[k + 1]))
        what = (f"contact {where} not determined: the sample {k - u:+.2g} samples from it "
                f"({1e3 * (k - u) / fs:+.2g} ms) stands {excess * scale:+.3g} V off its neighbours' mean, a "
                "single-sample spike's shape, where the force's curve breaks; kept as the force's (the ball's "
                "pre-buckling spike after its jump, a plate's overshoot), it may also be an electrical spike")
        if not (s_u < k < e_u) or not (outer > EVENT_SIGMA * noise):
            return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                            f"{what}, and it is the contact's outermost sample (the next one out "
                            f"{outer * scale:.3g} V, noise {noise * scale:.2g} V): were it electrical, the contact "
                            f"would {'begin a sample later' if where == 'start' else 'end a sample earlier'}")], ()
        if abs(excess) > SPIKE_END_IMPULSE * abs(impulse):
            return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                            f"{what}, and were it electrical the impulse would be "
                            f"{100 * abs(excess) / abs(impulse):.2g} % off (more than "
                            f"{100 * SPIKE_END_IMPULSE:.2g} %)")], ()
    return [], ()


def _low_spikes_at_ends(v_spiky, d2_spiky, spikes, contact: ContactResult, fs, t0_s) -> tuple:
    """Spikes below SPIKE_SIGMA near a contact end that bend the end's fit: samples to replace too [-].

    The end is a line through the force's last samples meeting zero (the
    hinge, ``ballimpact.contact``); an electrical spike of 6-12 noise
    deviations of the second difference among them, which
    :func:`remove_spikes` leaves (its threshold is for the whole record), tilts
    the line: on ``python bench/spike_ends_map.py --n 400`` trace 1:238 a
    79 mV spike (6.3 deviations) 3.4 samples before the end moved it by
    -1.85 % of TC, and on 2:45 one of 185 mV (10.7) 4.7 samples before it by
    -1.76 %, both ok. Within SPIKE_END_WINDOW_S of each end a sample above
    SPIKE_END_SIGMA deviations with the spike's shape whose neighbours
    continue one curve (:func:`_spike_kink` within SPIKE_KINK_SIGMA) is
    electrical and is replaced as the others are (2:45 is then right; 1:238's
    neighbours, off their -h/2 by 1.0 and 2.1 deviations of their own noise,
    miss the shape). The shape's tolerance is not widened for the noise: by 2
    deviations it let the bend where the force meets zero (a second difference
    at one sample, none at its neighbours) pass with the noise's help on 36 ok
    traces of zoo seeds 0-3 (TC +0.1-0.7 %, 3:261 to +1.22 %).
    """
    if not contact.found:
        return ()
    v = np.asarray(v_spiky, dtype=float)
    d2, s = d2_spiky
    if not (s > 0):
        return ()
    w = max(int(math.ceil(SPIKE_END_WINDOW_S * fs)), int(SPIKE_END_SAMPLES))
    out = []
    for u in ((contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs):
        a, b = max(int(math.floor(u)) - w, 3), min(int(math.ceil(u)) + w + 1, v.size - 3)
        for k in (a + np.flatnonzero(np.abs(d2[a:b]) > SPIKE_END_SIGMA * s)).tolist() if b > a else ():
            h = d2[k]
            if k in out or np.isin(k, spikes):
                continue
            tol = SPIKE_SHAPE_TOLERANCE * abs(h)
            if (abs(d2[k - 1] + 0.5 * h) < tol and abs(d2[k + 1] + 0.5 * h) < tol and abs(d2[k - 2]) < tol
                    and abs(d2[k + 2]) < tol and abs(d2[k - 3]) < tol and abs(d2[k + 3]) < tol
                    and _spike_kink(v, k) <= SPIKE_KINK_SIGMA * s):
                out.append(k)
    return tuple(sorted(out))


def _end_uncertainty(y, fs, noise, contact: ContactResult, s_u, e_u) -> float:
    """Standard uncertainty of TC from its two ends [samples]: noise over the force's slope at each end.

    An end where the force jumps is located to half a sample; elsewhere a line
    through the force's last samples meets zero within noise / slope samples
    (the slope read over PLATE_SLOPE_S inside the end).
    """
    m = max(int(round(PLATE_SLOPE_S * fs)), 2)
    out = []
    for where, i0, i1 in (("start", int(math.ceil(s_u)), int(math.ceil(s_u)) + m),
                          ("end", int(math.floor(e_u)), int(math.floor(e_u)) - m)):
        if f"{where}_jump" in contact.flags:
            out.append(0.5)
            continue
        if not (0 <= i0 < y.size and 0 <= i1 < y.size):
            return math.inf
        slope = abs(float(y[i1] - y[i0])) / m
        out.append(max(noise / slope, 0.5) if slope > 0 else math.inf)
    return math.hypot(*out)


def _curve_end_contact(contact: ContactResult, fs, t0_s) -> ContactResult:
    """The contact with its end from the force's curve where the hinge's end is not determined but the curve's is.

    The hinge's end moves by more than SPREAD_MAX_FRACTION of TC when fitted
    again from the samples above twice the noise threshold where the force
    fades into the noise with a bend (a line through the last samples of a
    curved fade meets zero late or early, by an amount that depends on the
    noise). The force's curve before the end (``contact.curve_end_s``, see
    :func:`ballimpact.contact.end_from_curve`) is then the end when twice its
    standard uncertainty is within the same SPREAD_MAX_FRACTION of TC; the
    contact is flagged ``end_curve`` and its end is not refitted again.

    Only where the refit moves the end later: the force then steepens into
    its end (concave, a punctured ball's), and the lower samples are nearer
    the truth. Where it moves earlier the force flattens into its end
    (convex), its last part is below the noise, and every fit through the
    samples above it, the curve's too, ends early (TC -1.1 % on zoo trace
    2:1489, whose spread passed; tests/test_contact.py).

    Only at CURVE_MIN_RATE_HZ or faster: below it, a plate of up to 30 kHz
    (raw-format v1.1) can alias below RING_LINE_MIN_HZ, where no check sees
    its ringing, and the spread check is then what stands between such a
    plate's sensed force and a wrong ok (zoo trace 2:586: 22.6 kHz at
    24.9 kHz, its end known but its peak 12 % low).
    """
    if not contact.found or not contact.end_spread_s > SPREAD_MAX_FRACTION * contact.contact_time_s \
            or fs < CURVE_MIN_RATE_HZ:
        return contact
    end_s = contact.curve_end_s
    if not (2.0 * contact.curve_end_se_s <= SPREAD_MAX_FRACTION * (end_s - contact.start_s)):  # NaN: not known
        return contact
    u_end = (end_s - t0_s) * fs
    return replace(contact, end_s=end_s, end_index=int(math.floor(u_end)), edge_end_s=min(contact.edge_end_s, end_s),
                   flags=contact.flags + ("end_curve",))


def _plate_undone(x, fs, fit: _BaselineFit, contact: ContactResult, problems, t0_s):
    """The force with the plate's resonance undone, its contact, the resonance and the low-pass used [Hz]; None
    when it is not tried; why it was refused, in words (str), when it was.

    Tried only when every problem is one plate ringing causes and one shows the
    ringing itself, on one contact that ends PLATE_ID_AFTER_S before the
    record does (the inverse's backward pass starts from rest there). The
    resonance is identified twice, from the contact (less two samples after its
    start, the force's jump) and PLATE_ID_AFTER_S after it, with instruments
    PLATE_ID_LAGS samples back (where that finds nothing, from the free ringing alone: a fit of a damped
    sinusoid from PLATE_FREE_AFTER_S after the contact's end to PLATE_ID_AFTER_S after it,
    :func:`ballimpact.plate.identify_free_ringing`); each undone force must
    pass the contact, end and ringing checks again, its noise (undoing the
    resonance amplifies the noise above it) must stay below
    PLATE_NOISE_FRACTION of the peak, twice its TC's uncertainty (noise over
    slope at each end) below PLATE_TC_FRACTION of TC, it must not pull on the
    plate (below -NEGATIVE_SIGMA noise deviations) in the contact, nor start
    more than PLATE_START_LATE samples after the sensed force (the plate
    delays the sensed force; an undone force that starts later has lost a
    low foot in its amplified noise), and the two must agree. When its ends,
    read off it, fail on their uncertainty or start late, they are fitted
    through the plate instead (:func:`ballimpact.plate.undone_end` with no
    low-pass, candidates PLATE_EXACT_END_REACH samples either side of those
    found; their uncertainty as for the low-passed force below), and a fitted
    start (this one's or a low-passed force's) later than the sensed one is a
    lost foot only when the sensed
    samples before it (the plate is causal: zero before the force) stand out
    of their noise by PLATE_FOOT_SIGMA standard errors as a level or a ramp
    up to it (the sensed start is read early where the plate's first
    overshoot passes for a foot; zoo trace 2:1469). A pull is what
    is left where the force departs from the first-order hold the inverse
    assumes (a jump between samples leaves an alternating tail decaying by the
    zeros of the sampled plate).

    When every undone force of an identification is refused, the resonance
    is refined (:func:`ballimpact.plate.refine_plate_resonance`: the fn and
    zeta near it that leave the least ringing in the undone force; the
    instrumental-variable fit is off by a few per cent in fn on noisy traces,
    and the force undone with it still rings) and tried again, with the same
    checks.

    An undone force refused by these checks is tried again through a
    zero-phase low-pass on a compact kernel (``ballimpact.plate.lowpass_zero_phase``,
    cutoffs from :func:`_plate_cutoffs`), which trades the noise amplified
    above the resonance against the force's sharp features: the same checks
    and the peak's loss to the kernel (from its curvature) at most
    PLATE_LOWPASS_PEAK. The kernel spreads each end by up to its half-width
    W, so the ends are fitted through the plate's undoing and the kernel
    (:func:`ballimpact.plate.undone_end`: a jump, a line and a parabola at
    the start, a line and a parabola at the end), with windows of
    PLATE_LOWPASS_END_INSIDE samples inside; TC's uncertainty is twice the
    ends' in quadrature, plus how far TC moves with the window and with the
    plate PLATE_FN_UNCERTAINTY off in fn. Each end's is at least what the
    fit's profile allows and at least its standard uncertainty from the
    sensed noise as the inverse and the kernel colour it (``undone_end``'s
    ``noise_se``, raised by the fit's residual where that is more than the
    noise leaves): that noise is correlated over several samples and moves a
    whole stretch of an end together (python bench/overshoot_map.py --n 400
    --seed 5 trace 5:350 came out two samples early). The start, where the
    force jumps from zero (section 3.2.4: the damping term at first contact),
    is known to half a sample at best (to its noise, or the fit's residual,
    over its slope where the fit sees no jump of PLATE_END_JUMP_SIGMA
    residuals; without that floor an aliased plate's start, zoo trace 0:434,
    came out 0.7 samples early where the fit's noise said 0.14); the end,
    where the ball's force falls to zero continuously, is located by the fit
    of the line and the parabola to it over several samples, to no interval
    between two: no half-sample floor there (which refused ends known to a
    few tenths of a sample). The fitted TC must be 0 to 2 W (+-1 sample)
    shorter than the contact found on the low-passed force.
    The force's ends are then restored from their fits (the impulse the
    kernel spread outside them is back). Nor may the low-pass hide a peak:
    the exact undone force's largest sample inside the contact at most
    PLATE_LOWPASS_PEAK and PLATE_PEAK_SIGMA of its noise above the low-passed
    peak, with that noise low enough to show a loss of PLATE_LOWPASS_SPIKE.
    """
    kinds = {p.kind for p in problems}
    if not kinds or not kinds <= PLATE_KINDS or not kinds & PLATE_EVIDENCE:
        return None
    if not _plate_can_be_undone(x, fs, contact, t0_s):
        return None
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    a = max(int(math.ceil(s_u)) + 2, 0)
    b = min(int(math.floor(e_u)) + int(round(PLATE_ID_AFTER_S * fs)), x.size)
    ra = max(int(s_u - PLATE_REFINE_S[0] * fs), 0)
    rb = min(int(e_u + PLATE_REFINE_S[1] * fs), x.size)
    found = []
    for lag, after_s in zip(PLATE_ID_LAGS, PLATE_FREE_AFTER_S):
        plate = identify_plate_resonance(x[a:b], fs, lag=lag, noise_rms=fit.noise)
        if plate is None and fit.noise > 0:  # the force drowns a damped plate's recursion: its free ringing after
            free = int(math.floor(e_u)) + max(int(round(after_s * fs)), 1)
            plate = identify_free_ringing(x[free:b], fs, fit.noise)
        if plate is None:
            return ("plate resonance not undone: no decaying oscillation identified out of the noise in the "
                    "contact and the 2 ms after it")
        hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, plate)
        if isinstance(hit, str):  # the undone force still rings or fails a check: refine the resonance, try again
            plate = refine_plate_resonance(x[ra:rb], fs, plate)
            hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, plate)
        if isinstance(hit, str):
            return (f"plate resonance at {plate.frequency_hz / 1e3:.3g} kHz (damping ratio {plate.damping_ratio:.2g}) "
                    f"not undone: {hit}")
        found.append(hit)
    (y, c, plate, cutoff), (_, c2, _, _) = found
    if abs(c.contact_time_s - c2.contact_time_s) > PLATE_AGREE_TC * c.contact_time_s \
            or abs(c.peak_V - c2.peak_V) > PLATE_AGREE_PEAK * c.peak_V:
        return (f"plate resonance at {plate.frequency_hz / 1e3:.3g} kHz not undone: two identifications of it "
                f"disagree by {100 * abs(c.contact_time_s / c2.contact_time_s - 1):.2g} % on TC and "
                f"{100 * abs(c.peak_V / c2.peak_V - 1):.2g} % on the peak")
    return y, c, plate, cutoff


def _plate_can_be_undone(x, fs, contact: ContactResult, t0_s) -> bool:
    """Whether a plate's resonance can be undone on this contact: one contact, inside the record, that ends
    PLATE_ID_AFTER_S before the record does (the inverse's backward pass starts from rest at the record's end: the
    ringing must be over). A cut or doubled contact is excluded whatever the plate."""
    if contact.n_impacts > 1 or {"contact_at_trace_start", "contact_at_trace_end"} & set(contact.flags):
        return False
    return (contact.end_s - t0_s) * fs + PLATE_ID_AFTER_S * fs <= x.size - 1


def _stated_plate_undone(x, fs, fit: _BaselineFit, contact: ContactResult, t0_s, plate: tuple):
    """The force with a stated resonance (fn [Hz], zeta [-]) undone, as :func:`_plate_undone` returns it (force,
    contact, resonance, cutoff [Hz]; why it was refused, str; None where the contact is cut or doubled, or the
    ringing is not over before the record ends), and the peak problems it leaves. The resonance is used exactly,
    neither identified nor refined; the undone force passes the same checks as an identified one
    (:func:`_undone_candidates`), except that a low-pass that may hide the peak withholds the peak alone (a
    PEAK_ON_RINGING problem) instead of refusing the force whose ends and impulse every other check passed."""
    if not _plate_can_be_undone(x, fs, contact, t0_s):
        return None, []
    s_u = (contact.start_s - t0_s) * fs
    resonance = stated_resonance(plate[0], plate[1], fs)
    peak_problems = []
    hit = _undone_candidates(x, fs, fit, contact, s_u, t0_s, resonance, peak_problems=peak_problems)
    if isinstance(hit, str):
        return (f"stated plate resonance {plate[0] / 1e3:.3g} kHz (damping ratio {plate[1]:.2g}, "
                f"plate.resonance_hz and plate.damping_ratio) not undone: {hit}"), []
    return hit, peak_problems


def _undone_peak_spread(x, fs, contact: ContactResult, plate: PlateResonance, cutoff: float, t0_s) -> list:
    """The undone peak's dependence on the identified plate: [a PEAK_ON_RINGING problem] when it moves by more than
    PLATE_PEAK_SPREAD with the damping ratio PLATE_ZETA_UNCERTAINTY off or fn PLATE_FN_UNCERTAINTY off, else [].

    The inverse of the plate, ``F = x + (2 zeta / wn) x' + x'' / wn^2`` in continuous time, builds a sharp peak
    (the pre-buckling spike, section 3.2.4 in Goodwill & Haake 2004) largely from the sensed force's slope and
    curvature, so the damping ratio the ringing gave weighs on it. That ratio is the least known of the plate's
    two numbers: zoo trace 7:265 (3.93 kHz, 0.267, identified at 3.85 kHz and 0.20) came out 9.2 % low in its
    spike's peak, TC and kCAL right. The force is undone again from the sensed signal ``x`` [V] (low-passed at
    ``cutoff`` [Hz] as the force reported was) with each parameter off in turn, and the largest sample inside the
    contact compared with the one undone with the identified plate.
    """
    a = max(int(math.ceil((contact.start_s - t0_s) * fs)), 0)
    b = min(int(math.floor((contact.end_s - t0_s) * fs)) + 1, x.size)
    if b - a < 1:
        return []

    def peak(fn, zeta):
        u = undo_plate_resonance(x, fs, fn, zeta)
        if not math.isinf(cutoff):
            u = lowpass_zero_phase(u, fs, cutoff)
        return float(np.max(u[a:b]))

    fn, zeta = plate.frequency_hz, plate.damping_ratio
    ref = peak(fn, zeta)
    if not ref > 0:
        return []
    moved = {f"the damping ratio {100 * PLATE_ZETA_UNCERTAINTY:.2g} % off": max(
                 abs(peak(fn, zeta * (1 + d)) / ref - 1) for d in (-PLATE_ZETA_UNCERTAINTY, PLATE_ZETA_UNCERTAINTY)),
             f"fn {100 * PLATE_FN_UNCERTAINTY:.2g} % off": max(
                 abs(peak(fn * (1 + d), zeta) / ref - 1) for d in (-PLATE_FN_UNCERTAINTY, PLATE_FN_UNCERTAINTY))}
    what, spread = max(moved.items(), key=lambda kv: kv[1])
    if spread <= PLATE_PEAK_SPREAD:
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force not determined: undone from the plate's resonance at {fn / 1e3:.3g} kHz (damping "
                    f"ratio {zeta:.2g}), the peak moves by {100 * spread:.2g} % with {what}; the plate's undoing "
                    "builds it from the sensed force's slope and curvature")]


def _lowpassed_spike(y, fs, contact: ContactResult, plate: PlateResonance, cutoff: float, t0_s) -> list:
    """[A PEAK_ON_RINGING problem] when the peak of a force undone from the plate and low-passed at ``cutoff``
    [Hz] may be the pre-buckling spike, else [] (``y`` the low-passed force [V]).

    The ball's force rises to a spike whose top is cut by a sudden drop at buckling (section 3.2.4 in Goodwill &
    Haake 2004; BUCKLING_TIME_S into the contact in the model), sharper than any kernel that quiets the noise the
    plate's inverse amplifies (the cutoffs run down to the resonance). The kernel lowers that top, and the exact
    undone force, noisy by construction there, cannot bound by how much (:func:`_lowpass_hides_peak` reads it from
    fits that smooth a sharp top too). Over zoo seeds 0-14, the 85 spike peaks reported from a low-passed undone
    force came out 2.1 % low on average (standard deviation 1.3 %, none more than 0.11 % high), down to -6.3 %
    (11:784, 13:41, 14:1538, 14:1632 ok and beyond the spike's 5 %; the undone but not low-passed ones +0.2 % on
    average). So where the low-passed force's largest value within the spike's phase (BUCKLING_TIME_S and the
    kernel's half-width from the start) is a maximum above LOWPASS_SPIKE_FRACTION of its peak, the peak is not
    known: a spike lowered below a later maximum may still be the peak. Zoo trace 4:6 (a 3.7 kHz plate at 47 kHz,
    low-passed at 11.8 kHz) had its low-passed spike at 90 % of the later maximum reported, and its true top 5.2 %
    above that maximum: the kernel and the sampling took 14.5 % from it. The same rule excludes forces whose spike,
    at 90-98 % of the later maximum, was not their peak (82 of the 176 traces it moved over zoo seeds 0-14; see
    docs/robustness-history.md, the round of 8a87902).
    """
    if math.isinf(cutoff):
        return []
    half, _ = lowpass_spread_samples(fs, cutoff)
    s_u = (contact.start_s - t0_s) * fs
    a = max(int(math.ceil(s_u)), 0)
    b = min(int(math.floor((contact.end_s - t0_s) * fs)) + 1, y.size)
    phase = min(int(math.floor(s_u + BUCKLING_TIME_S * fs + half)) + 1, b - 1)  # the spike's phase: y[a:phase]
    peak = float(np.max(y[a:b])) if b > a else math.nan
    if not (phase > a and peak > 0):
        return []
    k = a + int(np.argmax(y[a:phase]))
    top = float(y[k])
    if not (top >= LOWPASS_SPIKE_FRACTION * peak and top >= y[k + 1]):
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force not determined: undone from the plate's resonance at {plate.frequency_hz / 1e3:.3g} "
                    f"kHz and low-passed at {cutoff / 1e3:.3g} kHz, the force's maximum {1e3 * (k - s_u) / fs:.2g} ms "
                    f"into the contact ({100 * top / peak:.3g} % of the peak) may be the pre-buckling spike's top, "
                    "which the low-pass lowers by an amount the noisy exact undone force cannot bound (2 % on average "
                    "in the zoo, up to 15 % with the sampling's share)")]


def _undone_candidates(x, fs, fit: _BaselineFit, contact: ContactResult, s_u, t0_s, plate: PlateResonance,
                       peak_problems: list | None = None):
    """The first undone force of one resonance, exact or low-passed, that passes :func:`_undone_contact`:
    (force, its contact, the resonance, the cutoff [Hz]); when none does, what the exact one and the last
    low-passed one failed, in words (str). The cutoffs (:func:`_plate_cutoffs`) are tried from the highest down
    until one hides the peak (:func:`_lowpass_hides_peak`): a lower one would only lower the low-passed peak
    further. Given a list ``peak_problems``, a low-passed force that only hides the peak is taken, and why goes
    into that list as a PEAK_ON_RINGING problem."""
    exact = undo_plate_resonance(x, fs, plate.frequency_hz, plate.damping_ratio)
    why = []
    for cutoff in (math.inf, *_plate_cutoffs(fs, plate, fit.noise, float(contact.peak_V))):
        y = exact if math.isinf(cutoff) else lowpass_zero_phase(exact, fs, cutoff)
        c = _undone_contact(y, x, fs, fit, s_u, t0_s, cutoff, plate)
        hides = None
        if not isinstance(c, str) and not math.isinf(cutoff):
            hides = _lowpass_hides_peak(exact, fs, fit.noise, plate, c[0], t0_s)
            if hides and peak_problems is not None:
                peak_problems.append(Problem(ProblemKind.PEAK_ON_RINGING, f"peak force not known: low-passed to "
                                             f"{cutoff / 1e3:.3g} kHz after the plate was undone, {hides}"))
                return c[1], c[0], plate, cutoff
            c = hides or c
        if not isinstance(c, str):
            return c[1], c[0], plate, cutoff
        why.append(c if math.isinf(cutoff) else f"low-passed to {cutoff / 1e3:.3g} kHz, {c}")
        if hides:  # a lower cutoff only lowers the low-passed peak further below the exact force's
            break
    return "; ".join(why[:1] + why[-1:] if len(why) > 1 else why)


def _lowpass_hides_peak(exact, fs, noise, plate: PlateResonance, contact: ContactResult, t0_s) -> str | None:
    """Why a low-passed undone force with this contact hides a peak the exact undone force ``exact`` shows, in
    words; None when it does not (``noise`` the sensed noise [V]).

    The low-pass must not hide a peak the exact undone force shows (a spike
    sharper than its kernel, whose top the checks of the exact force found
    between samples): inside the contact (a sample off each end, where the
    undoing leaves a transient at a jump) the exact force read at each sample
    from a fit of the samples around it (:func:`_fitted_top`: the
    pre-buckling ramp from its start up to it, then PEAK_FIT_S centred on
    it, after buckling also weighted by the undone noise's covariance; the
    sample alone, with the undone noise, where no fit holds) at most
    PLATE_LOWPASS_PEAK and PLATE_PEAK_SIGMA of its standard error above the
    low-passed peak; and that error low enough to show a loss of
    PLATE_LOWPASS_SPIKE wherever the force may reach the peak.
    """
    i0, i1 = int(math.ceil((contact.start_s - t0_s) * fs)) + 1, int(math.floor((contact.end_s - t0_s) * fs))
    peak = float(contact.peak_V)
    if i1 <= i0 + 1:
        return "the low-passed contact holds too few samples of the exact undone force"
    top, error, alone = _fitted_top(exact, fs, noise, plate, contact, t0_s, i0, i1)
    blind = PLATE_LOWPASS_PEAK * peak + PLATE_PEAK_SIGMA * error
    lost = top - peak > blind
    unseen = (blind > PLATE_LOWPASS_SPIKE * peak) & (top + PLATE_PEAK_SIGMA * error > (1.0 + PLATE_LOWPASS_PEAK) * peak)
    if np.any(lost):
        k = int(np.argmax(np.where(lost, top - peak, -np.inf)))
        what = "largest sample" if alone[k] else "top fitted over the samples around it"
        return (f"the low-pass lowers the exact undone force's {what} by {100 * (top[k] - peak) / top[k]:.2g} % "
                "(a peak sharper than its kernel)")
    if np.any(unseen):
        return (f"the exact undone force is too noisy to show that the low-pass keeps its peak (a loss of up to "
                f"{100 * float(np.max(blind[unseen])) / peak:.2g} % would not be seen; a spike sharper than the "
                "kernel may be lost)")
    return None


def _fitted_top(exact, fs, noise, plate: PlateResonance, contact: ContactResult, t0_s, i0, i1):
    """The exact undone force read from fits at each sample of ``exact[i0:i1]`` for :func:`_lowpass_hides_peak`:
    (reading [V], its standard error [V], True where no fit holds and the error is the undone noise's)."""
    pb = min(max(int(math.floor((contact.start_s - t0_s + BUCKLING_TIME_S) * fs)) + PEAK_FIT_RAMP_SAMPLES + 1,
                 i0), i1)
    noise = noise * _fit_noise_scale(exact, fs, pb, i1, int(round(PEAK_FIT_S * fs)), noise, plate)
    sigma = noise * undone_noise_gain(fs, plate.frequency_hz, plate.damping_ratio)
    parts = [_fitted_force(exact, fs, i0, pb, pb - i0, noise, plate),
             _fitted_force(exact, fs, pb, i1, int(round(PEAK_FIT_S * fs)), noise, plate, centred=True)]
    top = np.concatenate([p[0] for p in parts])
    err = np.concatenate([p[1] for p in parts])
    # after buckling, where the ball's force is smooth, the samples are read from centred fits weighted by the
    # undone noise's covariance too, where one holds with a smaller error than the reading above or where none
    # held: the noise the inverse amplified towards the Nyquist frequency no longer hides the peak. Only from
    # where no such fit's window can reach the drop at buckling: pb, less nothing, plus the largest kernel
    # half-width of a cutoff at the resonance (the low-passed contact may start that early) and the window (a
    # weighted fit across a drop of 5-10 % of the peak holds at 1 % noise, and reads it smoothed)
    length = int(round(PEAK_FIT_S * fs)) | 1
    after = pb + int(math.ceil(0.5 * fs / plate.frequency_hz)) + length
    if after + length // 2 < i1:
        weighted = _fitted_force(exact, fs, after - length // 2, i1, length, noise, plate, centred=True,
                                 weighted=True)
        at = slice(after - i0, i1 - i0)
        w_top, w_err = weighted[0][length // 2:], weighted[1][length // 2:]
        take = np.isfinite(w_err) & ~(err[at] <= w_err)
        top[at][take], err[at][take] = w_top[take], w_err[take]
    alone = np.isnan(err)
    error = np.where(alone, sigma, err)
    return top, error, alone


def _plate_cutoffs(fs, plate: PlateResonance, noise, peak) -> list:
    """Low-passes to try on an undone force that was refused: their half-amplitude frequencies [Hz], highest first.

    From fs / 2 down in PLATE_LOWPASS_STEPS steps of sqrt(2), not below
    PLATE_LOWPASS_MIN_FN times the resonance (the force would lose what it
    holds there): the first that brings the undone force's noise (the sensed
    noise through the inverse and the low-pass) to PLATE_LOWPASS_NOISE of
    the peak, and the next PLATE_LOWPASS_TRIES - 1 below it (less noise,
    more smoothing: which one passes every check depends on the force).
    """
    if not (peak > 0 and noise >= 0):
        return []
    out = []
    cutoff = 0.5 * fs
    for _ in range(PLATE_LOWPASS_STEPS):
        cutoff /= math.sqrt(2.0)
        if cutoff < PLATE_LOWPASS_MIN_FN * plate.frequency_hz or len(out) >= PLATE_LOWPASS_TRIES:
            break
        if out or noise * undone_noise_gain(fs, plate.frequency_hz, plate.damping_ratio, cutoff) \
                <= PLATE_LOWPASS_NOISE * peak:
            out.append(cutoff)
    return out


def _smoothed_peak_loss(y, fs, sigma):
    """Fraction of its peak that a symmetric low-pass of deviation ``sigma`` samples took from a force [-].

    A unit-sum symmetric kernel of standard deviation sigma lowers a smooth
    peak by about ``sigma^2 |F''| / 2`` (F'' its second derivative there, per
    sample^2; Taylor to second order); read on the smoothed force over
    +-sigma samples (at least one), which underestimates it a little for a
    peak as sharp as the kernel.
    """
    k = int(np.argmax(y))
    h = max(int(round(sigma)), 1)
    if k - h < 0 or k + h >= y.size or not y[k] > 0:
        return math.inf
    curvature = (float(y[k + h]) - 2.0 * float(y[k]) + float(y[k - h])) / (h * h)
    return 0.5 * sigma * sigma * abs(curvature) / float(y[k])


def _undone_contact(y, x, fs, fit: _BaselineFit, s_u, t0_s, cutoff=math.inf, plate=None, fit_ends=False):
    """The contact of an undone force ``y`` and the force (a low-passed one, or with ``fit_ends`` the exact one,
    with its ends restored from their fits) when it passes every check of :func:`_plate_undone`; else what it
    failed, in words (str). The exact force whose ends read off it fail on their uncertainty or start late is
    tried again with its ends fitted through the plate."""
    c = detect_contact(y, fs, t0_s=t0_s, spread=True)
    if not c.found or not c.peak_V > 0 or c.n_impacts > 1:
        return "the undone force holds no single contact"
    if (c.end_s - t0_s) * fs + PLATE_ID_AFTER_S * fs > x.size - 1:
        return "the undone contact ends too close to the record's end"
    noise = float(c.noise_rms_V)
    if noise > PLATE_NOISE_FRACTION * float(c.peak_V):  # the largest sample of so noisy a force is a biased peak
        return f"the undone force is too noisy (noise {100 * noise / float(c.peak_V):.2g} % of the peak)"
    checked = replace(fit, noise=noise)
    cs_u, ce_u = (c.start_s - t0_s) * fs, (c.end_s - t0_s) * fs
    seen = (_end_problems(y, fs, checked, c, cs_u, ce_u, 1.0)
            + _ringing_problems(y, fs, noise, float(c.peak_V), cs_u, ce_u, cs_u, ce_u, fall=math.isinf(cutoff)))
    if seen:
        return "the undone force still shows " + seen[0].message.split(":")[0]
    bias = 0.0
    fitted = not math.isinf(cutoff) or (fit_ends and plate is not None)
    what = "low-passed force" if not math.isinf(cutoff) else "undone force"
    if fitted:  # for the exact force no kernel (W = 0): its ends fitted through the plate alone
        half_width, sigma = lowpass_spread_samples(fs, cutoff)
        loss = _smoothed_peak_loss(y, fs, sigma)
        if loss > PLATE_LOWPASS_PEAK:  # the low-pass flattens a peak sharper than its kernel
            return f"the low-pass lowers the peak by about {100 * loss:.2g} %"
        # the low-pass spreads the force by its kernel's half-width at each end: the ends are fitted through
        # the plate's undoing and the kernel (a line, or a jump from zero), twice, and the fits' difference
        # is charged to TC
        fn, zeta = plate.frequency_hz, plate.damping_ratio
        reach = 2 if not math.isinf(cutoff) else PLATE_EXACT_END_REACH
        ends = [(undone_end(y, fs, fn, zeta, cutoff, cs_u, "start", inside_samples=m, reach_samples=reach,
                            noise_rms=fit.noise),
                 undone_end(y, fs, fn, zeta, cutoff, ce_u, "end", inside_samples=m, reach_samples=reach,
                            noise_rms=fit.noise))
                for m in PLATE_LOWPASS_END_INSIDE]
        if any(e is None for pair in ends for e in pair):
            return (f"the {what}'s ends fit no line or jump from zero through the plate and the kernel "
                    f"(its {100 * 2 * half_width / (ce_u - cs_u):.2g} % spread of TC stays unknown)")
        (f_start, f_end) = ends[0]
        fs_u, fe_u = f_start.index, f_end.index
        bias = max(abs((e[1].index - e[0].index) - (fe_u - fs_u)) for e in ends[1:]) if len(ends) > 1 else 0.0
        # the plate is known to about PLATE_FN_UNCERTAINTY in fn: what it leaves ringing moves the ends
        # (undone over the contact and a margin only: the undoing's passes forget their start within a few samples)
        a = max(int(cs_u) - PLATE_END_MARGIN - 4 * int(half_width), 0)
        b = min(int(ce_u) + PLATE_END_MARGIN + 4 * int(half_width), x.size)
        for scale in (1.0 - PLATE_FN_UNCERTAINTY, 1.0 + PLATE_FN_UNCERTAINTY):
            y2 = lowpass_zero_phase(undo_plate_resonance(x[a:b], fs, fn * scale, zeta), fs, cutoff)
            pair = (undone_end(y2, fs, fn * scale, zeta, cutoff, cs_u - a, "start",
                               inside_samples=PLATE_LOWPASS_END_INSIDE[0], reach_samples=reach),
                    undone_end(y2, fs, fn * scale, zeta, cutoff, ce_u - a, "end",
                               inside_samples=PLATE_LOWPASS_END_INSIDE[0], reach_samples=reach))
            if pair[0] is None or pair[1] is None:
                return (f"the {what}'s ends fit no line or jump from zero through the kernel with the plate "
                        f"{100 * PLATE_FN_UNCERTAINTY:g} % off in fn")
            bias = max(bias, abs((pair[1].index - pair[0].index) - (fe_u - fs_u)))
        shorter = (ce_u - cs_u) - (fe_u - fs_u)  # the kernel lengthens the contact found by 0 to 2 W samples
        if not -1.0 <= shorter <= 2.0 * half_width + 2.0:
            return (f"the ends fitted through the kernel make TC {shorter:+.3g} samples shorter than the "
                    f"{what}'s contact, outside 0 to twice the kernel's half-width of {half_width:.0f} samples")
        # the ends' jump and the impulse the kernel spread outside them restored from their fits
        y = y.copy()
        for f in (f_start, f_end):
            y[f.first:f.first + f.correction.size] += f.correction
        cs_u, ce_u = fs_u, fe_u
        inside = y[int(math.ceil(cs_u)):int(math.floor(ce_u)) + 1]
        c = replace(c, start_s=t0_s + fs_u / fs, end_s=t0_s + fe_u / fs, start_index=int(math.ceil(fs_u)),
                    end_index=int(math.floor(fe_u)), peak_index=int(math.ceil(cs_u)) + int(np.argmax(inside)),
                    peak_V=float(np.max(inside)))
        # each end at least as far as the fit's residual lets it move (its profile) and at least its standard
        # uncertainty from the sensed noise as the chain colours it (correlated over several samples); the start
        # (the force jumps from zero there) to half a sample at best, to its noise over its slope (the noise there
        # the fit's residual when that is larger: what the undoing left, or a force no line fits) where the fit
        # sees no jump well out of the noise; the end (a line and a parabola falling to zero, no jump) as the
        # fit locates it
        spread = [max(0.5 if f_start.jump > PLATE_END_JUMP_SIGMA * max(noise, f_start.residual) else
                      (max(max(noise, f_start.residual) / f_start.slope, 0.5) if f_start.slope > 0 else math.inf),
                      f_start.uncertainty, f_start.noise_se),
                  max(f_end.uncertainty, f_end.noise_se) if f_end.slope > 0 else math.inf]
        uncertainty = 2.0 * math.hypot(*spread) + bias
    else:
        uncertainty = 2.0 * _end_uncertainty(y, fs, noise, c, cs_u, ce_u)
    late, tail = cs_u > s_u + PLATE_START_LATE, ""
    if not fitted and plate is not None and (late or uncertainty > PLATE_TC_FRACTION * (ce_u - cs_u)):
        # read off the exact force, its ends are its amplified noise over its slope and may lose a foot in it:
        # fitted through the plate instead (its step, ramp and parabola responses, undone)
        again = _undone_contact(y, x, fs, fit, s_u, t0_s, cutoff, plate, fit_ends=True)
        if not isinstance(again, str):
            return again
        tail = f"; its ends fitted through the plate: {again.removeprefix('the ')}"
    if uncertainty > PLATE_TC_FRACTION * (ce_u - cs_u):
        return (f"the undone TC is known to {100 * uncertainty / (ce_u - cs_u):.2g} % only ("
                + ("noise over slope at its ends" if not fitted else
                   f"{100 * bias / (ce_u - cs_u):.2g} % of it how far the ends move with the fit's window and with the "
                   f"plate {100 * PLATE_FN_UNCERTAINTY:g} % off in fn") + ")" + tail)
    inside = y[max(int(math.ceil(cs_u)), 0):max(int(math.floor(ce_u)) + 1, 0)]
    if inside.size and float(np.min(inside)) < -NEGATIVE_SIGMA * noise:
        # the force is not what this plate's inverse assumes
        return "the undone force pulls on the plate during the contact"
    if late:
        # the plate is causal: the sensed force is zero before the force starts, so a foot the undone force lost
        # stands out of the sensed noise before the undone start (from the sensed start on, back from the
        # sample before it: a level or a ramp up to it, over every length, in standard errors); a sensed start
        # early for no force there (its foot or edge fallback read into the plate's first overshoot) is no
        # lost foot when the ends are fitted through the plate
        seg = x[max(int(math.floor(s_u)) - 1, 0):max(int(math.floor(cs_u)), 0)][::-1]
        foot = _foot_sigma(seg, fit.noise) if seg.size else math.inf
        if not fitted or not foot <= PLATE_FOOT_SIGMA:
            return "the undone force starts later than the sensed one (a foot lost in its noise)" + tail
    return c, y


def _checked_voltage(voltage_V, sample_rate_hz, polarity, mains_hz, n_harmonics, tau_s, pre_guard_s, post_guard_s):
    """The arguments of :func:`condition_voltage` checked (ValueError naming the bad one); the voltage as floats."""
    fs = float(sample_rate_hz)
    if not math.isfinite(fs) or fs <= 0:
        raise ValueError(f"sample_rate_hz must be positive and finite, got {sample_rate_hz!r}")
    if polarity not in (1, -1):
        raise ValueError(f"polarity must be 1 or -1, got {polarity!r}")
    auto_mains = isinstance(mains_hz, str)
    if auto_mains and mains_hz != "auto":
        raise ValueError(f"mains_hz must be a number of Hz, 'auto' or None, got {mains_hz!r}")
    if not auto_mains and mains_hz is not None and (not math.isfinite(mains_hz) or mains_hz < 0):
        raise ValueError(f"mains_hz must be non-negative and finite, got {mains_hz!r}")
    if n_harmonics < 0:
        raise ValueError(f"n_harmonics must be non-negative, got {n_harmonics}")
    if tau_s is not None and not (tau_s > 0):
        raise ValueError(f"tau_s must be positive (math.inf for no decay), got {tau_s!r}")
    if pre_guard_s < 0 or post_guard_s < 0:
        raise ValueError(f"guards must be non-negative, got pre_guard_s={pre_guard_s}, post_guard_s={post_guard_s}")
    raw = np.asarray(voltage_V, dtype=float).ravel()
    if raw.size < 3:
        raise ValueError(f"voltage_V needs at least 3 samples, got {raw.size}")
    if not np.all(np.isfinite(raw)):
        bad = np.flatnonzero(~np.isfinite(raw))
        raise ValueError(f"voltage_V holds {bad.size} non-finite samples (first at index {bad[0]})")
    return raw


@dataclass
class _Iteration:
    """Where the window / baseline iteration of :func:`condition_voltage` ended."""

    x: np.ndarray  # decay-corrected signal [scaled V]
    fit: _BaselineFit
    tau: float
    source: str
    pending: list
    tau_problems: list
    problems: list
    mains: float
    ambiguous: tuple | None
    start_u: float
    end_u: float
    n_iter: int
    contact_integral: float
    search: ContactSearch  # the contact's search on x (with fit's noise)


def _fit_candidates(v, fs, candidates, start_u, end_u, pre_guard, post_guard, mask, kappa_given, noise_floor,
                    cache=None):
    """The baseline fit of each mains candidate; the best by BIC, its frequency, and an ambiguity (or None)."""
    fits = {f: _fit_baseline(v, fs, fr, start_u, end_u, pre_guard, post_guard, mask, True, kappa_given,
                             noise_floor=noise_floor, cache=cache)
            for f, fr in candidates.items()}
    mains = min(fits, key=lambda f: fits[f].bic)
    fit = fits[mains]
    hum = [f for f in fits if f > 0]
    ambiguous = None
    if mains > 0 and fits[mains].hum_amplitudes:
        other = [f for f in hum if f != mains][0]
        if not fits[other].hum_amplitudes:
            ambiguous = (mains, other, None)  # the quiet stretch is too short for the other frequency
        elif fits[other].bic - fit.bic < MAINS_AMBIGUOUS_BIC:
            ambiguous = (mains, other, fits[other].baseline)
    return fit, mains, ambiguous


def _iterate(v, fs, candidates, rough, pre_guard, post_guard, tau_s, kappa_given, scale, noise_floor) -> _Iteration:
    """Contact window, event mask and baseline (with the decay) fitted in turn until they stop moving."""
    start_u, end_u = rough.start_s * fs, rough.end_s * fs
    mask = np.zeros(v.size, dtype=bool)
    problems: list[Problem] = []
    mains = next(iter(candidates))
    ambiguous: tuple | None = None
    windows = [(start_u, end_u)]
    # the fits made, and the last corrected signal and its contact: a window that moved by a fraction of a sample
    # often gives the same fit and the same signal again, whose contact is then known
    cache: dict = {}
    made_from: tuple = ()  # the fit, tau and the sample the decay's integral starts at of x and search below
    for n_iter in range(1, MAX_ITERATIONS + 1):
        if len(candidates) > 1 and n_iter <= 3:
            fit, mains, ambiguous = _fit_candidates(v, fs, candidates, start_u, end_u, pre_guard, post_guard, mask,
                                                    kappa_given, noise_floor, cache)
        else:
            fit = _fit_baseline(v, fs, candidates[mains], start_u, end_u, pre_guard, post_guard, mask, True,
                                kappa_given, noise_floor=noise_floor, cache=cache)
        y = v - fit.baseline
        running = _running_integral(y, fs, start_u)
        contact_integral = _integral_to(running, start_u, end_u)
        tau, source, pending, tau_problems = _choose_tau(tau_s, fit, contact_integral, (end_u - start_u) / fs,
                                                         scale)
        i0 = _integral_start(start_u) if math.isfinite(tau) else -1
        if not (made_from and made_from[0] is fit and made_from[1:] == (tau, i0)):
            x = _decay_correct(y, running, tau)
            search = ContactSearch(x, fs, noise_rms_V=fit.noise)
            made_from = (fit, tau, i0)
        c = search.result()
        if not c.found:
            break
        new_mask = _event_mask(x, fs, fit.noise, c, pre_guard, post_guard)
        new_start, new_end = c.start_s * fs, c.end_s * fs
        moved = max(abs(new_start - start_u), abs(new_end - end_u))
        same_mask = np.array_equal(new_mask, mask)
        start_u, end_u, mask = new_start, new_end, new_mask
        windows.append((start_u, end_u))
        if moved < CONVERGED_SAMPLES and same_mask and not (len(candidates) > 1 and n_iter < 2):
            break
    else:
        if c.found and moved > UNSTABLE_SAMPLES:
            (a0, b0), (a1, b1) = windows[-2], windows[-1]
            problems.append(Problem(ProblemKind.CONTACT_UNSTABLE,
                                    f"contact window not stable under the baseline fit: its ends still move by "
                                    f"{moved:.2g} samples after {MAX_ITERATIONS} iterations (last from "
                                    f"{1e3 * a0 / fs:.4g}-{1e3 * b0 / fs:.4g} ms to {1e3 * a1 / fs:.4g}-"
                                    f"{1e3 * b1 / fs:.4g} ms of the record: the decay, drift and hum fitted "
                                    "around each window move it)"))
    return _Iteration(x, fit, tau, source, pending, tau_problems, problems, mains, ambiguous, start_u, end_u, n_iter,
                      contact_integral, search)


def _integrity(x, fs, fit: _BaselineFit, contact: ContactResult, t0_s, scale, ambiguous, start_u, end_u,
               post_guard_s=POST_GUARD_S):
    """Problems of the corrected signal, in a fixed order: levels, contact ends, ringing, mains."""
    peak = float(contact.peak_V)
    if not peak > 0:
        return []
    s_u, e_u = (contact.start_s - t0_s) * fs, (contact.end_s - t0_s) * fs
    return (_edge_event_problems(x, fs, fit.noise, peak, s_u, scale)
            + _end_event_problems(x, fs, fit.noise, peak, e_u, e_u - s_u, scale, post_guard_s)
            + _baseline_bend_problems(fit, peak, s_u, e_u, scale)
            + _level_problems(x, fs, fit, peak, scale, e_u, post_guard_s)
            + _end_problems(x, fs, fit, contact, s_u, e_u, scale, curve=True)
            + _ringing_problems(x, fs, fit.noise, peak, s_u, e_u, start_u, end_u, front=True)
            + _mains_problems(x, fs, fit, peak, scale, ambiguous, start_u, end_u))


def _baseline_bend_problems(fit: _BaselineFit, peak, s_u, e_u, scale) -> list[Problem]:
    """A fitted baseline that bends under the contact by more than BASELINE_BEND_FRACTION of the peak.

    Under the contact the baseline (offset, drift and hum) is the fit's extrapolation from the quiet samples
    around it; the mains hum's bend over a few ms of contact is a few per cent of the hum, itself a few per cent of
    the peak at most on any rig of raw-format v1.1 (tens of mV). A bend of a tenth of the peak is a fit the quiet
    samples did not pin: zoo trace 11:342 (a 667 Hz plate ringing through a 24 ms record, 60 Hz hum of 28 mV
    found by the fit at 11.6 V) came out ok with TC +153 % and kCAL -99 %. peak in [V / scale] (scale [V]); s_u,
    e_u: the contact's ends [samples].
    """
    b = fit.baseline
    a, e = max(int(math.ceil(s_u)), 0), min(int(math.floor(e_u)), b.size - 1)
    if e - a < 2 or not peak > 0:
        return []
    chord = np.interp(np.arange(a, e + 1), [a, e], [b[a], b[e]])
    bend = float(np.max(np.abs(b[a:e + 1] - chord)))
    if bend <= BASELINE_BEND_FRACTION * peak:
        return []
    amps = fit.hum_amplitudes
    hum = f" (a hum of {sum(amps) * scale * 1e3:.3g} mV fitted)" if amps else ""
    return [Problem(ProblemKind.MAINS_UNRESOLVED,
                    f"mains hum not resolved: the fitted baseline bends by {bend * scale * 1e3:.3g} mV "
                    f"({100 * bend / peak:.2g} % of the peak) under the contact{hum}; the quiet samples do not pin it "
                    "there (record longer pre- or post-trigger, or give daq.mains_hz)")]


def _edge_event_samples(fs) -> int:
    """The fewest samples an event at the record's start or end must hold: EDGE_EVENT_MIN_S at ``fs`` [Hz], and at
    least 3."""
    return max(3, int(round(EDGE_EVENT_MIN_S * fs)))


def _edge_event_problems(x, fs, noise, peak, s_u, scale) -> list[Problem]:
    """Force at the record's first samples, before the contact: an impact the record cut off.

    The corrected signal stands out of the noise as an event does (EVENT_SIGMA noise deviations and
    EVENT_FRACTION of the peak) from the record's first sample on, for EDGE_EVENT_MIN_S at least, before the
    contact's start. Such an event is a pulse whose size and length the record does not show: below the contact
    threshold it is not counted as another impact, and the baseline fit leaves it out as an event. But a contact
    cut off by a late trigger (the fall of a first impact at the record's start, a second one measured in its
    place) is exactly that, and the gates' speeds then belong to the impact not measured: zoo trace 9:476 (a
    punctured ball's tail at 1.6 % of the peak over the record's first 0.5 ms, a second contact 15 ms later)
    came out ok with TC +25 % and kCAL -21 %. Only the start: before the contact the decay's correction adds
    nothing, while after it it integrates the baseline's small errors, and a record of seconds wanders away from
    zero by its end (zoo seeds 0-9: 9 right traces excluded when the end was looked at the same way, none at the
    start); an impact after the measured one does not change what the gates timed, and one that reaches the
    contact threshold is counted by :func:`ballimpact.contact.detect_contact`. At the end, only force still
    rising at the last sample is taken for another impact (:func:`_end_event_problems`). x and noise in
    [V / scale] (scale [V]), peak likewise; s_u: the contact's start [samples].
    """
    thr = _event_threshold(noise, peak)
    need = _edge_event_samples(fs)
    seg = x[:max(int(math.floor(s_u)), 0)]
    quiet = np.flatnonzero(seg <= thr)
    run = int(quiet[0]) if quiet.size else seg.size  # samples above thr from the record's first on
    if run < need:
        return []
    top = float(np.max(seg[:run]))
    return [Problem(ProblemKind.MULTIPLE_IMPACTS,
                    f"more than one impact in the trace: force at the record's start, {run / fs * 1e3:.2g} ms of it "
                    f"before the contact, up to {top * scale * 1e3:.3g} mV ({100 * top / peak:.2g} % of the peak, "
                    f"{top / noise:.3g} noise deviations): an impact the record truncated (trigger earlier)")]


def _end_event_problems(x, fs, noise, peak, e_u, tc_u, scale, post_guard_s=POST_GUARD_S) -> list[Problem]:
    """Force rising to the record's last sample, after the contact: another impact the record cut off.

    The mirror of :func:`_edge_event_problems`, narrowed to what a contact's start looks like, for the end of a
    record wanders (the decay's correction integrates the baseline's small errors) and a plate rings after the
    contact: the corrected signal stands out as an event does (EVENT_SIGMA noise deviations and EVENT_FRACTION of
    the peak) over the record's last samples, for EDGE_EVENT_MIN_S at least and for no longer than the contact
    (a wander lasts longer), starting ``post_guard_s`` [s] or more after the contact's end, and its largest sample
    is the record's last, at the contact threshold (:func:`ballimpact.contact.contact_threshold`) or above: a
    contact rising when the record stops, whose height the record does not show
    (:func:`ballimpact.contact.detect_contact` counts a run at the record's end from 5 % of the peak). Below the
    contact threshold, zoo seeds 0-20 held two right traces whose end rose to 1.6 and 2 % of the peak (2:810, a
    0.92 s record's decay-corrected end; 15:1958, a record ending 5 ms after the contact), and no faulty one. Zoo
    trace 19:218 (a second contact starting 30.6 ms after the first, 0.1 ms before the record's end, its force at
    6.5 % of the peak there, 4 % as the 3.3 kHz plate delays it) came out ok: a faulty trace, whose second contact
    is below the contact threshold for the few samples it shows. x and noise in [V / scale] (scale [V]), peak
    likewise; e_u the contact's end and tc_u its length [samples].
    """
    thr = _event_threshold(noise, peak)
    need = _edge_event_samples(fs)
    first = int(math.ceil(e_u + post_guard_s * fs))
    seg = x[max(first, 0):]
    if seg.size < need or not seg[-1] > thr:
        return []
    quiet = np.flatnonzero(seg <= thr)
    if not quiet.size:
        return []  # no quiet sample between the contact and the record's end: the end checks judge that
    run = seg.size - 1 - int(quiet[-1])  # samples above thr up to the record's last
    if not need <= run <= tc_u or not seg[-1] >= np.max(seg[-run:]) \
            or seg[-1] < contact_threshold(noise, peak):
        return []
    top = float(seg[-1])
    return [Problem(ProblemKind.MULTIPLE_IMPACTS,
                    f"more than one impact in the trace: force rising at the record's end, {run / fs * 1e3:.2g} ms "
                    f"of it, to {top * scale * 1e3:.3g} mV ({100 * top / peak:.2g} % of the peak, {top / noise:.3g} "
                    "noise deviations) at the last sample: another impact the record cut off (record longer after "
                    "the trigger)")]


def _level_problems(x, fs, fit: _BaselineFit, peak, scale, end_u, post_guard_s=POST_GUARD_S):
    """The corrected signal off zero before or after the contact, or a quiet residual that is not white noise.

    After the contact the stretch of the baseline fit is checked; when the record
    after the contact was too short for the fit (the baseline then extrapolated
    from before the contact), the samples from post_guard_s after the contact end
    to the end of the record, when there are MIN_PRE_SAMPLES of them.
    """
    out = []
    w = max(int(round(FLAT_WINDOW_S * fs)), MIN_QUIET_SAMPLES)
    pre_idx = np.flatnonzero(fit.pre)
    post_idx = np.flatnonzero(fit.post)
    stretches = []
    if pre_idx.size >= MIN_PRE_SAMPLES:
        stretches.append(("before", pre_idx[-w:]))
    if post_idx.size >= 2 * MIN_QUIET_SAMPLES:
        stretches.append(("just after", post_idx[:w]))
        if post_idx.size > 2 * w:
            stretches.append(("later after", post_idx[-w:]))
    else:
        tail = np.arange(int(math.ceil(end_u + post_guard_s * fs)), x.size)
        if tail.size >= MIN_PRE_SAMPLES:
            stretches.append(("after", tail[:w]))
    for where, sel in stretches:
        level = float(np.mean(x[sel]))
        se = fit.noise / math.sqrt(sel.size)
        if abs(level) > FLAT_FRACTION * peak and abs(level) > FLAT_SIGMA * se:
            out.append(Problem(ProblemKind.BASELINE_OFF_ZERO,
                               f"corrected signal {where} the contact is {level * scale * 1e3:.3g} mV off zero "
                               f"({100 * abs(level) / peak:.2g} % of the peak): baseline or amplifier decay not removed"))
    # the residual of the quiet samples must be white noise: compare its rms with the noise of
    # sample-to-sample differences (blind to hum and drift)
    qi = np.flatnonzero(fit.quiet)
    if qi.size >= 2 * MIN_QUIET_SAMPLES:
        y = x[qi]
        pairs = np.flatnonzero(np.diff(qi) == 1)
        if pairs.size >= MIN_QUIET_SAMPLES:
            white = robust_noise(y[pairs + 1] - y[pairs]) / math.sqrt(2.0)
            resid = y - np.median(y)
            clipped = np.clip(resid, -ROBUST_SIGMA * white, ROBUST_SIGMA * white) if white > 0 else resid
            excess = math.sqrt(max(float(np.mean(clipped ** 2)) - white ** 2, 0.0))
            if excess > FLAT_FRACTION * peak and excess > white:
                out.append(Problem(ProblemKind.BASELINE_RESIDUAL,
                                   f"quiet baseline not explained by offset, drift, hum and decay: "
                                   f"{excess * scale * 1e3:.3g} mV rms above the white noise "
                                   f"({100 * excess / peak:.2g} % of the peak; "
                                   f"{_residual_where(y, fit.pre[qi], fit.post[qi], white, peak)})"))
    return out


def _baseline_step_problems(x, fs, fit: _BaselineFit, contact: ContactResult, t0_s, scale,
                            tau_given: bool) -> list[Problem]:
    """A step in the level of the quiet baseline, which offset, drift, hum and decay cannot explain.

    A DAQ's or an amplifier's offset can shift within the record (a relay or a light gate switching near the
    wiring, a range change). The baseline fit then spreads the shift over the record as drift, and the corrected
    signal sits a fraction of it off zero at the contact's ends: on a slow fade a shift of 0.1-0.4 % of the peak
    moved the end by 1-2.4 % of TC with every level check passed (``python bench/step_map.py``). On the fit's quiet
    samples (the contact and the events left out), clipped at ROBUST_SIGMA noise deviations so that a burst or a
    spike weighs little, a line and a step are fitted to BASELINE_STEP_WINDOWS_S on either side of candidate
    instants BASELINE_STEP_GRID_S apart (the line takes up what the global fit's drift made of the step); a step of
    BASELINE_STEP_SIGMA standard errors and BASELINE_STEP_FRACTION of the peak that still holds, half its size and
    3 standard errors, when fitted over four times as long (a small second contact below the event mask's
    EVENT_FRACTION of the peak is a hump, not a step) is a problem. At the contact the two sides are every quiet
    sample before and after it, one test at BASELINE_STEP_ACROSS_SIGMA: a step within the contact when
    ``plate.time_constant_s`` is given. With the decay estimated, kappa takes up a shift within the contact, which
    is then taken for the amplifier's undershoot: only the given time constant tells them apart."""
    peak = float(contact.peak_V)
    qi = np.flatnonzero(fit.quiet)
    if not (peak > 0 and fit.noise > 0) or qi.size < 2 * MIN_QUIET_SAMPLES:
        return []
    lim = ROBUST_SIGMA * fit.noise
    y = np.clip(x[qi], -lim, lim)
    t = qi / fs
    # prefix sums: every window's line-and-step fit in O(1)
    c = [np.concatenate([[0.0], np.cumsum(q)]) for q in (np.ones(qi.size), t, t * t, y, t * y)]
    grid = np.unique(np.concatenate([
        np.searchsorted(t, np.arange(t[0], t[-1], BASELINE_STEP_GRID_S)),
        np.flatnonzero(np.diff(qi) > 1) + 1]))  # and the first sample after every gap (the contact's, an event's)
    grid = grid[(grid > 0) & (grid < qi.size)]
    pre_n = int(np.count_nonzero(fit.pre[qi]))

    def steps(w, j):
        """(step [V / scale], standard errors) of the line-and-step fit over w quiet samples either side of j."""
        lo, hi = np.maximum(j - w, 0), np.minimum(j + w, qi.size)
        sides = []
        for a, b in ((lo, j), (j, hi)):
            n, st, stt, sy, sty = (ck[b] - ck[a] for ck in c)
            with np.errstate(invalid="ignore", divide="ignore"):
                sides.append((n, st / n, sy / n, stt - st * st / n, sty - st * sy / n))
        (nl, tl, yl, sxx_l, sxy_l), (nr, tr, yr, sxx_r, sxy_r) = sides
        sxx = sxx_l + sxx_r
        with np.errstate(invalid="ignore", divide="ignore"):
            h = (yr - yl) - (sxy_l + sxy_r) / sxx * (tr - tl)
            z = np.abs(h) / (fit.noise * np.sqrt(1.0 / nl + 1.0 / nr + (tr - tl) ** 2 / sxx))
        z[~((nl >= MIN_QUIET_SAMPLES) & (nr >= MIN_QUIET_SAMPLES) & (sxx > 0))] = 0.0
        return h, np.nan_to_num(z)

    widths = [max(int(round(w * fs)), MIN_QUIET_SAMPLES) for w in BASELINE_STEP_WINDOWS_S]
    best = None  # (standard errors, step [V / scale], last sample before, first after)
    for i, w in enumerate(widths):
        h, z = steps(w, grid)
        z[np.abs(h) < BASELINE_STEP_FRACTION * peak] = 0.0
        for k in np.argsort(z)[::-1][:8]:  # the largest few: a hump (a small second contact) is not a step
            if z[k] < BASELINE_STEP_SIGMA or (best is not None and z[k] <= best[0]):
                break
            wider = [steps(4 * w2, grid[k:k + 1]) for w2 in widths[i:]]  # the shift must hold further out
            if all(hw[0] * h[k] > 0 and abs(hw[0]) >= 0.5 * abs(h[k]) and zw[0] >= 3.0 for hw, zw in wider):
                best = (float(z[k]), float(h[k]), int(qi[grid[k] - 1]), int(qi[grid[k]]))
                break
    if tau_given and 0 < pre_n < qi.size and np.all(fit.post[qi[pre_n:]]):
        h, z = steps(qi.size, np.array([pre_n]))
        if z[0] >= BASELINE_STEP_ACROSS_SIGMA and abs(h[0]) >= BASELINE_STEP_FRACTION * peak \
                and (best is None or z[0] > best[0]):
            best = (float(z[0]), float(h[0]), int(qi[pre_n - 1]), int(qi[pre_n]))
    if best is None:
        return []
    z, d, before, after = best
    return [Problem(ProblemKind.BASELINE_STEP,
                    f"step in the baseline: the corrected signal's level shifts by {d * scale * 1e3:.3g} mV "
                    f"({100 * abs(d) / peak:.2g} % of the peak, {z:.3g} standard errors) between "
                    f"{1e3 * (before / fs + t0_s):.4g} and {1e3 * (after / fs + t0_s):.4g} ms, which offset, drift, "
                    "hum and decay do not explain; the baseline under the contact is uncertain")]


def _plateau_end_problems(x, fs, noise, contact: ContactResult, t0_s) -> list[Problem]:
    """A contact that ends on a plateau: the force flat over its last PLATEAU_END_FRACTION of TC, then gone (on the
    final force: a plate's undone, whose ringing would make any end's stretch rise and fall).

    A ball's force falls into its end (a fade to zero, or the model's drop at 2 mm of compression after a steep
    fall). A flat stretch at a level of PLATEAU_END_LEVEL of the peak or more that falls by less than
    PLATEAU_END_FALL of its level is not a ball's: it is what a step down in the baseline shortly after the contact
    leaves when the amplifier's decay is estimated, kappa taking the step for the undershoot and the decay
    correction lifting the record between the contact and the step into a shelf of force (``python
    bench/step_map.py --n 400 --seed 2`` trace 2:95: a step of -3.1 % of the peak 1.7 ms after the end, TC +42 %)."""
    peak = float(contact.peak_V)
    tc = contact.contact_time_s
    if not (peak > 0 and noise > 0 and tc > 0):
        return []
    b = int(math.floor((contact.end_s - t0_s) * fs))  # the last sample inside the contact
    n = max(int(round(PLATEAU_END_FRACTION * tc * fs)), PLATEAU_END_MIN)
    a = max(b - n, int(math.ceil((contact.start_s - t0_s) * fs)))
    if b - a < PLATEAU_END_MIN or b >= x.size:
        return []
    y = x[a:b]  # less the last sample (a jump's)
    u = np.arange(y.size) - 0.5 * (y.size - 1)
    slope = float(np.dot(u, y) / np.dot(u, u))
    level, fall = float(np.mean(y)), -slope * y.size
    if level > PLATEAU_END_LEVEL * peak and level > 10.0 * noise / math.sqrt(y.size) \
            and abs(fall) < PLATEAU_END_FALL * level:
        return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                        f"contact end not determined: the force is flat over the last {1e3 * y.size / fs:.2g} ms "
                        f"before it, at {100 * level / peak:.2g} % of the peak, falling by {100 * fall / level:+.2g} % "
                        "of that: not a ball's fade; a step down in the baseline just after the contact taken for the "
                        "amplifier's undershoot? (give plate.time_constant_s)")]
    return []


def _residual_where(y, pre, post, white, peak) -> str:
    """Where a quiet residual that is more than white noise is: after the contact only, or not (for its reason)."""
    def excess(sel):
        r = y[sel] - np.median(y[sel])
        r = np.clip(r, -ROBUST_SIGMA * white, ROBUST_SIGMA * white) if white > 0 else r
        e = math.sqrt(max(float(np.mean(r ** 2)) - white ** 2, 0.0))
        return e > FLAT_FRACTION * peak and e > white

    if np.count_nonzero(pre) >= MIN_QUIET_SAMPLES and np.count_nonzero(post) >= MIN_QUIET_SAMPLES \
            and excess(post) and not excess(pre):
        return "after the contact only: plate ringing that outlasts the guard, or a decay not resolved?"
    return "hum or drift not resolved?"


def _foot_sigma(seg, noise) -> float:
    """How far a foot stands out of white noise ``noise`` [V] in ``seg`` [V], the samples before a contact start
    nearest first: the largest, over every length n from the start back, of the level (the samples' sum over
    sqrt(n)) and of a ramp up to the start (weights n - i, over their norm), in standard errors [-]; inf with no
    noise, 0 with no samples."""
    if not seg.size:
        return 0.0
    if not noise > 0:
        return math.inf
    n = np.arange(1, seg.size + 1)
    level, ramp = np.cumsum(seg), n * np.cumsum(seg) - np.cumsum(np.arange(seg.size) * seg)  # weights 1; n - i
    return float(max(np.max(level / np.sqrt(n)), np.max(ramp / np.sqrt(n * (n + 1) * (2 * n + 1) / 6.0)))) / noise


def _end_problems(x, fs, fit: _BaselineFit, contact: ContactResult, s_u, e_u, scale, curve=False):
    """Contact ends that hold no force, are located to half a sample only or move when fitted again; with
    ``curve``, also an end that the force's curve before it (``contact.curve_end_s``) puts more than
    CURVE_LATE_FRACTION of TC later than the straight line through the last samples (``contact.line_end_s``;
    the end itself is the bent hinge's, earlier where the force's slope eases into its end): the force flattens
    into its end (a convex fade), its last part is below
    the noise, and the line through the samples above it meets zero early (zoo trace 2:1489: TC -1.1 %, its
    refit from higher samples ending earlier still, by less than SPREAD_MAX_FRACTION of TC); not after an end
    flagged as a jump (located to half a sample, there is no line through a fade there: the curve meets zero up to
    a sample after the last sample of a true jump, and after a concave fade's end taken for one). With ``curve``,
    also a foot before the start and force after the end: the corrected signal over FOOT_CHECK_S beyond either
    (less a sample) standing FOOT_CHECK_SIGMA standard errors out of the noise as a level or a ramp. After the
    end it is the fade's rest beyond an end found early, where interference swung the fade to zero
    (``python bench/burst_map.py --n 400 --seed 1`` trace 1:314: TC -22.5 %), or a baseline a little off there
    (12 right traces of the zoo's seeds 0-3 excluded, their TC within 0.6 %)."""
    out = []
    # each end must be where force begins / ends: the samples just inside it hold force
    k_end = max(int(round(END_CHECK_S * fs)), 3)
    for where, sel in (("start", np.arange(int(math.ceil(s_u)), int(math.ceil(s_u)) + k_end)),
                       ("end", np.arange(int(math.floor(e_u)) - k_end + 1, int(math.floor(e_u)) + 1))):
        sel = sel[(sel >= 0) & (sel < x.size)]
        if sel.size >= 3:
            level = float(np.mean(x[sel]))
            if level < END_CHECK_SIGMA * fit.noise / math.sqrt(sel.size):
                out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                                   f"contact {where} not determined: the {1e3 * sel.size / fs:.2g} ms inside it hold "
                                   f"no force ({level * scale * 1e3:.3g} mV, noise {fit.noise * scale * 1e3:.2g} mV)"))
    n_contact = (contact.end_s - contact.start_s) * fs
    if n_contact < MIN_CONTACT_SAMPLES:
        out.append(Problem(ProblemKind.TOO_FEW_SAMPLES,
                           f"only {n_contact:.1f} samples in the contact (fewer than {MIN_CONTACT_SAMPLES}): "
                           "sample rate too low for the contact time"))
    jumps = [w for w in ("start", "end") if f"{w}_jump" in contact.flags]
    if jumps and len(jumps) * 0.5 / fs > JUMP_MAX_FRACTION * contact.contact_time_s:
        out.append(Problem(ProblemKind.CONTACT_JUMP_UNRESOLVED,
                           f"contact {' and '.join(jumps)} between two samples: the force jumps from zero there, so "
                           f"TC is known to +-{len(jumps) * 0.5e6 / fs:.3g} us only, more than "
                           f"{100 * JUMP_MAX_FRACTION:.2g} % of {contact.contact_time_s * 1e3:.3g} ms (sample faster)"))
    out.extend(_hinge_problems(contact))
    for where, moved in (("start", contact.start_spread_s), ("end", contact.end_spread_s)):
        if where == "end" and "end_curve" in contact.flags:
            continue  # the end from the force's curve, known to SPREAD_MAX_FRACTION of TC: see _curve_end_contact
        if abs(moved) > SPREAD_MAX_FRACTION * contact.contact_time_s:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {where} not determined to 1 %: fitted again from the samples above twice the "
                               f"noise threshold it moves by {moved * 1e6:+.3g} us "
                               f"({100 * moved / contact.contact_time_s:+.2g} % of TC); the force fades into the noise "
                               "there"))
    # a foot before the start (a cloth that carries a little load before the core does) is part of the contact:
    # the corrected signal before the start (less the sample before it, which a start found a fraction of a
    # sample late leaves some force in) must hold none that stands out of the noise as a level or a ramp; and
    # force after the end (the fade's rest beyond an end found early, e.g. where interference swung it to zero)
    n_beyond = int(round(FOOT_CHECK_S * fs))
    k0, k1 = int(math.floor(s_u)) - 1, int(math.ceil(e_u)) + 1
    beyond = (("start", x[max(k0 - n_beyond, 0):max(k0, 0)][::-1], "before", "a foot of force before the rise",
               "start earlier"),
              ("end", x[k1:k1 + n_beyond], "after", "force after the end found", "end later"))
    for where, seg, side, seen, may in beyond:
        sigma = _foot_sigma(seg, fit.noise) if curve else 0.0
        if sigma > FOOT_CHECK_SIGMA:
            out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                               f"contact {where} not determined: the corrected signal in the "
                               f"{1e3 * FOOT_CHECK_S:.2g} ms {side} it stands {sigma:.3g} standard errors out of the "
                               f"noise ({seen}, or a baseline wrong there): the force may {may}",
                               data={"beyond": where}))
    # against the straight line's end (the bent hinge's sits earlier on an end whose slope eases; the threshold
    # was set on the line's)
    late = contact.curve_end_s - (contact.line_end_s if math.isfinite(contact.line_end_s) else contact.end_s)
    if "end_jump" in contact.flags:  # a jump's end is the middle of its interval: no line through a fade to judge
        late = math.nan
    if curve and late > CURVE_LATE_FRACTION * contact.contact_time_s:  # NaN: no curve, no problem
        out.append(Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                           f"contact end not determined to 1 %: the force's curve before it meets zero "
                           f"{late * 1e6:.3g} us later than the line through its last samples "
                           f"({100 * late / contact.contact_time_s:.2g} % of TC); the force flattens into the noise "
                           "there"))
    return out


def _hinge_problems(contact: ContactResult) -> list:
    """TC not known to 1 % from its ends' fits: END_SE_COVERAGE times the root sum of squares of the ends' standard
    uncertainties (``contact.start_se_s`` / ``end_se_s``, each the hinge's three-sigma interval over three, with a
    step's uniform at a ``start_step``; an end from the force's curve, ``end_curve``, its own; a jump's half sample is
    judged by CONTACT_JUMP_UNRESOLVED) above END_SE_MAX_FRACTION of TC. A force that fades into the noise with about a
    noise deviation per sample leaves its end known to a few samples: on ideal plates at 20-60 kHz with noise of
    0.1-0.5 % of the peak (bench/ideal_plate_map.py), the line through the last samples met zero up to 1.8 % of TC
    late, and was ok."""
    tc = contact.contact_time_s
    ses = dict(zip(("start", "end"), end_standard_uncertainties(contact)))
    if any(math.isnan(v) for v in ses.values()) or not tc > 0:
        return []  # no fit to judge (the other checks judge such an end)
    spread = END_SE_COVERAGE * math.hypot(ses["start"], ses["end"])
    if spread <= END_SE_MAX_FRACTION * tc:
        return []
    worst = max(ses, key=lambda k: ses[k])
    edge = "first" if worst == "start" else "last"
    curve = worst == "end" and "end_curve" in contact.flags
    what = "the force's curve before it" if curve else f"the line through its {edge} samples"
    if math.isinf(ses[worst]):
        seen = ("the force's curve before it does not pin where it meets zero" if curve else
                f"no line through its {edge} samples pins where it meets zero (any corner in the hinge's window fits)")
    else:
        seen = (f"{what} meets zero within +-{END_SE_COVERAGE * 1e6 * ses[worst]:.3g} us only "
                f"({END_SE_COVERAGE:g} times its standard uncertainty; TC known to +-{100 * spread / tc:.2g} % with "
                "the other end's)")
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact {worst} not determined to 1 %: the force fades into the noise there, and {seen}")]


def _ringing_problems(x, fs, noise, peak, s_u, e_u, start_u, end_u, front=False, fall=False):
    """Plate ringing after the contact, force below zero, a peak on ringing, a spectral line in the contact; with
    ``front`` (the sensed force), also a peak lifted by the plate's ringing from the force's jump; with ``fall`` (an
    undone force, not low-passed: its drop at buckling as sudden as the ball's), a peak no other check judged that
    the force leaves slowly (on the sensed force :func:`condition_voltage` looks for that last)."""
    out = []
    a = int(math.ceil(e_u + RING_GAP_S * fs))
    b = min(a + max(int(round(RING_WINDOW_S * fs)), 3), x.size)
    if b - a >= 3:
        ring = float(np.sqrt(np.mean(x[a:b] ** 2)))
        if ring > RING_MAX_FRACTION * peak and ring > FLAT_SIGMA * noise:
            out.append(Problem(ProblemKind.PLATE_RINGING,
                               f"plate ringing outlasts the contact ({100 * ring / peak:.2g} % of the peak rms in the "
                               f"{RING_WINDOW_S * 1e3:g} ms after it): force and ringing not separable"))
    out.extend(_negative_force(x, fs, noise, peak, e_u))
    out.extend(_peak_on_ringing(x[int(math.ceil(s_u)):int(math.floor(e_u)) + 1], fs, noise, peak))
    xc = x[max(int(math.ceil(s_u)), 0):int(math.floor(e_u)) + 1]
    # with the sample before the contact: a start inside the interval before the first sample (a jump's, a step's)
    # leaves it out of xc, and a largest sample that is the contact's first must still be judged against it
    out.extend(_peak_between_samples(x[max(int(math.ceil(s_u)) - 1, 0):int(math.floor(e_u)) + 1], fs, noise,
                                     lifted=front))
    out.extend(_second_hump(xc, fs, noise, peak))
    out.extend(_peak_on_step_response(xc, fs, noise, peak, math.ceil(s_u) - s_u))
    out.extend(_peak_on_front_ringing(x, fs, noise, peak, s_u, e_u) if front else [])
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:  # with evidence already the plate's undoing is tried
        out.extend(_peak_on_first_overshoot(x, fs, noise, peak, s_u, e_u))
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:
        out.extend(_start_on_fast_ringing(x, fs, noise, peak, s_u, e_u))
    if front and not {p.kind for p in out} & PLATE_EVIDENCE:
        out.extend(_front_dip(x, fs, peak, s_u, e_u))
    if fall and not out:  # a peak no check above judged (without ``front`` they find only plate or peak kinds)
        out.extend(_peak_on_slow_fall(xc, fs, noise, peak, math.ceil(s_u) - s_u))
    line = _ringing_line(x[max(int(math.ceil(start_u)), 0):min(int(math.floor(end_u)) + 1, x.size)], fs,
                         noise)
    if line is not None:
        f_line, amp_line, prominence = line
        out.append(Problem(ProblemKind.PLATE_RINGING,
                           f"plate ringing at {f_line / 1e3:.3g} kHz during the contact (a spectral line "
                           f"{prominence:.3g} times its neighbourhood, {100 * amp_line / peak:.2g} % of the peak): "
                           "force and plate ringing not separable",
                           data={"line_hz": f_line, "amplitude_fraction": amp_line / peak, "prominence": prominence}))
    return out


def _mains_problems(x, fs, fit: _BaselineFit, peak, scale, ambiguous, start_u, end_u):
    """50 and 60 Hz hum that fit the quiet samples alike but differ under the contact."""
    out = []
    if ambiguous is not None:
        mains, other, other_baseline = ambiguous
        a, b = max(int(math.floor(start_u)), 0), min(int(math.ceil(end_u)) + 1, x.size)
        hum = float(np.sum(fit.hum_amplitudes))
        if other_baseline is None and hum > MAINS_AMBIGUOUS_FRACTION * peak:
            tq = np.flatnonzero(fit.quiet) / fs
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains frequency not resolved: the quiet baseline spans {1e3 * (tq[-1] - tq[0]):.3g} "
                               f"ms, too short to tell {mains:g} from {other:g} Hz hum of {hum * scale * 1e3:.3g} mV "
                               "(give daq.mains_hz)"))
        diff = float(np.max(np.abs(other_baseline[a:b] - fit.baseline[a:b]))) if b > a and other_baseline is not None \
            else 0.0
        if other_baseline is not None and diff > MAINS_AMBIGUOUS_FRACTION * peak:
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains frequency not resolved: {mains:g} and {other:g} Hz hum fit the quiet baseline "
                               f"equally well and differ by {diff * scale * 1e3:.3g} mV under the contact "
                               "(give daq.mains_hz)"))
    return out


def _short_record_hum(x, fs, fit: _BaselineFit, mains_hz: tuple, peak: float, scale: float):
    """Mains hum in quiet samples that span less than one period of it: not removed, and it matters.

    The baseline fit leaves hum out when the quiet samples do not span a full
    period of the fundamental (it cannot be told from the offset and drift
    there). What it leaves is tested here: the corrected quiet samples are
    fitted with a line and the fundamental of each mains frequency in
    question; a hum of more than FLAT_FRACTION of the peak and FLAT_SIGMA
    standard errors is a problem, since under the contact it bends the
    baseline by an unknown part of itself.
    """
    if fit.coef["hum_frequencies_hz"] or not mains_hz or not peak > 0:
        return []
    qi = np.flatnonzero(fit.quiet)
    if qi.size < 2 * MIN_QUIET_SAMPLES:
        return []
    t = qi / fs
    span = float(t[-1] - t[0])
    t = t - 0.5 * (t[0] + t[-1])
    out = []
    for f in mains_hz:
        if span * f >= 1.0:
            continue
        w = 2.0 * math.pi * f * t
        a = np.column_stack([np.ones(t.size), t, np.cos(w), np.sin(w)])
        coef, *_ = np.linalg.lstsq(a, x[qi], rcond=None)
        resid = x[qi] - a @ coef
        s2 = float(resid @ resid) / max(t.size - 4, 1)
        cov = s2 * np.linalg.pinv(a.T @ a)
        amp = float(math.hypot(coef[2], coef[3]))
        se = math.sqrt(max((coef[2] ** 2 * cov[2, 2] + coef[3] ** 2 * cov[3, 3] + 2 * coef[2] * coef[3] * cov[2, 3])
                           / max(amp * amp, 1e-300), 0.0))
        if amp > FLAT_FRACTION * peak and amp > FLAT_SIGMA * se:
            out.append(Problem(ProblemKind.MAINS_UNRESOLVED,
                               f"mains hum not resolved: the quiet samples span {1e3 * span:.3g} ms, less than a period "
                               f"of {f:g} Hz, and hold a hum of about {amp * scale * 1e3:.3g} mV "
                               f"({100 * amp / peak:.2g} % of the peak) that bends the baseline under the contact "
                               "(record longer pre- or post-trigger)"))
            break
    return out


def _alike(a: float, b: float) -> bool:
    """Two spacings of turning points within a factor TURN_REGULARITY of each other."""
    return max(a, b) <= TURN_REGULARITY * min(a, b)


def _turning_points(y, h) -> list[int]:
    """Indices of the turning points of y, each left by more than h (a hysteresis; noise below h makes none)."""
    out: list[int] = []
    direction, i_ext = 0, 0
    for i in range(1, y.size):
        v = y[i]
        if direction == 0:
            if abs(v - y[0]) > h:
                direction, i_ext = (1 if v > y[0] else -1), i
        elif direction * (v - y[i_ext]) > 0:
            i_ext = i
        elif direction * (y[i_ext] - v) > h:
            out.append(i_ext)
            direction, i_ext = -direction, i
    return out


def _peak_on_ringing(xc, fs, noise, peak):
    """The peak force riding on plate ringing: the largest value is one of the plate's swings.

    Turning points of the contact force are the places it leaves by more than
    TURN_FRACTION of the peak and TURN_SIGMA noise deviations (a hysteresis:
    noise makes none). The force jumps from zero at the start (and drops at
    buckling), and a plate resonance rings after each jump. The peak is one of
    the plate's swings when it is the jump's overshoot (within one period of
    the oscillation of the start, with the oscillation going on after it) or
    when the last two or three turning points before it are spaced like the one after
    it (a ringing that began before the peak). Half a period of the
    oscillation is the spacing of the peak to the next turning point; two
    spacings are alike within a factor TURN_REGULARITY. A ringing of 2-6
    samples per period (a resonance near the Nyquist frequency) has turning
    points located to a sample only, its half-periods read 1 and 2 (or 2 and
    3) samples: the TURN_FAST_RUN spacings before the peak and the one after
    it, each at most 3 and within a sample of each other, are such a ringing,
    of half-period their mean. The ball's own spike
    before buckling comes later, after a rise with no regular turns. It
    matters when, averaged over one period of the oscillation, the peak drops
    by more than PEAK_ON_RINGING_FRACTION of the peak.
    """
    if xc.size < MIN_CONTACT_SAMPLES:
        return []
    turns = _turning_points(xc, max(TURN_FRACTION * peak, TURN_SIGMA * noise))
    i_peak = int(np.argmax(xc))
    if i_peak not in turns or len(turns) < TURN_MIN_OSCILLATION:
        return []
    j = turns.index(i_peak)
    spacing = np.diff(turns).astype(float)
    if j >= spacing.size:
        return []
    after = float(spacing[j])  # half a period of the oscillation [samples]
    # the jump's overshoot: the peak within one period of the start, an oscillation after it
    overshoot = i_peak <= 2.0 * after and spacing.size - j >= 2 and _alike(spacing[j + 1], after)
    # a peak inside a ringing that began before it: the two or three turning points before it at its spacing
    inside = j >= 2 and all(_alike(float(d), after) for d in spacing[max(j - TURN_MIN_OSCILLATION, 0):j])
    # ringing of 2-6 samples per period: its turning points are located to a sample, so its half-periods
    # read 1 and 2 (or 2 and 3) samples; a longer run of them before the peak, each within a sample
    fast = spacing[max(j - TURN_FAST_RUN, 0):j + 1]
    near_nyquist = (j >= TURN_FAST_RUN and float(np.max(fast)) <= 3.0
                    and float(np.max(fast) - np.min(fast)) <= 1.0)
    if not (overshoot or inside or near_nyquist):
        return []
    period = 2.0 * (float(np.mean(fast)) if near_nyquist and not (overshoot or inside) else after)
    k = max(int(round(period)), 1)
    averaged = np.convolve(xc, np.ones(k) / k, mode="same")
    drop = float(np.max(xc) - np.max(averaged))
    if drop > PEAK_ON_RINGING_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_ON_RINGING,
                        f"peak force on plate ringing: the force oscillates at about {fs / period / 1e3:.3g} kHz during "
                        f"the contact and its peak is one of the swings (averaged over one period it is "
                        f"{100 * drop / peak:.2g} % lower); the peak is not the ball's")]
    return []


def _peak_between_samples(xc, fs, noise, lifted=True):
    """A peak force the samples do not pin down: the force may rise above the largest sample.

    Between the largest sample and the next one the force may go on rising
    before it drops: the ball's pre-buckling spike is a steep ramp ending in a
    sudden drop (section 3.2 in Goodwill & Haake 2004). It can rise by at most
    the rise over one sample: the larger of the last two rises before the
    largest sample (a plate that smooths the ramp slows the last one), less two
    noise deviations of the difference. Only rises from a sample already above
    PEAK_RAMP_FLOOR of the peak count: the force's jump from zero (at 2 mm of
    compression in the model) is no ramp and goes on nowhere. Where in the
    interval the force drops is not known (any instant alike), so the largest
    sample misses the top by half that rise on average and by all of it at
    worst. When that rise is more than PEAK_SAMPLING_FRACTION (10 %) of the
    peak, the peak is not known to 5 % (the zoo's tolerance for the spike):
    sample faster. Nor is it
    known when the largest sample is the first of the contact (the one before
    it below PEAK_JUMP_FRACTION of it): a ball's force rises as it compresses,
    so that sample is the top of the force's jump from zero, a plate's
    overshoot of the jump, or a spike whose top fell within the first sample
    interval.
    Nor when it rises from a sample below PEAK_RAMP_FLOOR of it (no ramp
    before it) and stands more than PEAK_ALONE_FRACTION of it above every
    other sample: a single-sample top, either the ball's spike with none of
    its ramp sampled or an electrical spike riding on the force where its
    curve breaks (the jump, the drop at buckling), whose second differences
    there do not have an isolated spike's shape (:func:`remove_spikes`). Zoo
    trace 33:674 (50.7 kHz, ideal plate) was ok with a 1.5 V electrical spike
    on the jump's second sample taken for the peak, +32 %; the same spike two
    samples later, beside the drop at buckling, +45 %. Were it electrical,
    its excess over its neighbours' mean is in the impulse as well: above
    SPIKE_END_IMPULSE of the impulse that is a problem too
    (IMPULSE_UNRESOLVED, as for a sample kept at a contact end), so that a
    withheld peak never passes a kCAL that a spike moved.

    The same holds at every lower local maximum of the samples that follows
    two rises from samples above PEAK_JUMP_FRACTION of the peak (a spike's
    ramp), or the jump from zero to a sample above PEAK_RAMP_FLOOR of it and
    one rise (the jump's sample on the ramp at low rates: zoo trace 11:617,
    25.7 kHz, once ok at -7.9 %), judged by its expected top (half the larger
    rise above it) against the largest sample: a spike whose top fell
    between the samples so wholly that the largest sample is on the smooth
    part of the contact is such a
    maximum, and its top may exceed the largest sample (zoo seed 4000,
    "sample_rate": 23.3 kHz, spike 5.9 % above the largest sample, once ok).
    At the largest sample the rule is the one above (half a rise against half
    of PEAK_SAMPLING_FRACTION). A jump from zero (one rise from a sample near
    zero) or a swing of ringing (a fall before the rise) hides no top above
    it; a jump smoothed over two or three samples cannot be told from a
    spike's ramp and is judged as one.

    With ``lifted`` (the sensed force, whose peak
    :func:`ballimpact.calibration.force_top` reads), where force_top lifts the
    largest sample to the middle of the range a ramp cut by a drop can take,
    the reported top is off by up to half that range (half the last rise),
    which must also be within PEAK_SAMPLING_FRACTION / 2 of the peak. Where a
    sample is kept (the largest one when force_top does not lift it, a lower
    maximum, an undone force: ``lifted`` False) the top may be up to a whole
    rise above it, but it is judged by half a rise, on average: judging the
    whole rise there (bench/spike_top_map.py; zoo seed 4's ok spike top at
    -5.4 % was of this class) excluded 168 more measurable traces of the
    zoo's seeds 0-3, all right, and good impacts of the synthetic sessions
    (docs/robustness-history.md, cfca54b).
    """
    if xc.size < 3:
        return []
    i = int(np.argmax(xc))
    if i == 0:
        return []
    peak = float(xc[i])
    if peak > 0 and xc[i - 1] < PEAK_JUMP_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                        f"peak force between samples: the largest sample is the first of the contact (the one "
                        f"before it at {100 * xc[i - 1] / peak:.2g} % of it): the top of the force's jump from zero "
                        "or the plate's overshoot of it, not a measured maximum (sample faster)")]
    if not peak > 0:
        return []
    if i + 1 < xc.size and xc[i - 1] < PEAK_RAMP_FLOOR * peak:
        below = float(np.max(np.delete(xc, i)))
        if peak - below > PEAK_ALONE_FRACTION * peak:
            seen = (f"{1e3 * (i - 1) / fs:.2g} ms into the contact, it rises from a sample at "
                    f"{100 * xc[i - 1] / peak:.2g} % of it and stands {100 * (peak - below) / peak:.2g} % of it above "
                    "every other sample: a single-sample top, the ball's spike with its ramp unsampled or an "
                    "electrical spike where the force's curve breaks, which the samples cannot tell apart")
            out = [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                           f"peak force between samples: the largest sample stands alone: {seen} (sample faster)")]
            # were it electrical, its excess over its neighbours' mean is in the impulse too (as a sample kept at
            # a contact end: _spikes_at_ends)
            excess, impulse = float(xc[i] - 0.5 * (xc[i - 1] + xc[i + 1])), float(np.sum(xc[1:]))
            if impulse > 0 and excess > SPIKE_END_IMPULSE * impulse:
                out.append(Problem(ProblemKind.IMPULSE_UNRESOLVED,
                                   f"impulse not known to {100 * SPIKE_END_IMPULSE:.2g} %: were the largest sample an "
                                   f"electrical spike, the impulse would be {100 * excess / impulse:.2g} % off"))
            return out
    # every sampled maximum (the largest sample and each lower local maximum, e.g. a spike whose top
    # fell between the samples while the smooth part of the contact later holds the largest sample)
    # may hide a top up to one rise above it: a ramp's rises only. At the largest sample, the rises
    # from a sample already at PEAK_RAMP_FLOOR of the peak (not the jump from zero); at a lower
    # maximum, a spike's ramp starts low: a maximum after two rises, both from samples off zero
    # (PEAK_JUMP_FRACTION of the peak), or after the jump from zero to a sample already at PEAK_RAMP_FLOOR of
    # the peak and one rise from it (at 25.7 kHz the jump's sample is on the spike's ramp, and zoo trace
    # 11:617's top, between the next sample and the drop, came out ok at -7.9 %; a jump from zero spread over
    # two samples, the first of them low, is no ramp: 66 right traces of zoo seeds 0-14 were excluded when any
    # sample off zero counted); a jump from zero alone (one rise from a sample near zero) or a swing of ringing
    # (a fall before its rise) hides no top above it
    jump_floor = PEAK_JUMP_FRACTION * peak
    maxima = [k for k in range(2, xc.size - 1)
              if xc[k - 2] < xc[k - 1] <= xc[k] and xc[k] > xc[k + 1] and k != i
              and xc[k - 1] >= (jump_floor if xc[k - 2] >= jump_floor else PEAK_RAMP_FLOOR * peak)]
    # force_top's half range at the largest sample where it lifts it (0 where it keeps the sample)
    half = force_top(np.arange(xc.size) / fs, xc, noise)[2] if lifted else 0.0
    for k in (i, *maxima):
        floor = PEAK_RAMP_FLOOR * peak if k == i else jump_floor
        rises = [float(xc[j] - xc[j - 1]) for j in (k, k - 1) if j >= 1 and xc[j - 1] >= floor]
        rise = max(rises, default=0.0) - 2.0 * math.sqrt(2.0) * noise
        # the top there: half a rise above the sample on average (the drop anywhere in the interval);
        # at the largest sample this is the rise against PEAK_SAMPLING_FRACTION; where force_top lifts
        # it, also the half range of the top it reports
        lift = k == i and half > 0.0
        miss = float(xc[k]) + 0.5 * rise - peak
        if lift:
            miss = max(miss, half)
        if miss > 0.5 * PEAK_SAMPLING_FRACTION * peak:
            where = ("the largest sample" if k == i else
                     f"a sampled maximum of {100 * xc[k] / peak:.3g} % of the largest sample, "
                     f"{1e3 * (k - i) / fs:+.3g} ms from it,")
            return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                            f"peak force between samples: the force rises by {100 * rise / peak:.2g} % of the peak in "
                            f"the {1e6 / fs:.3g} us before {where} and may go on rising before it drops: "
                            f"the largest sample may miss the peak by {100 * miss / peak:.2g} % on average "
                            "(sample faster)")]
    return []


def _undone_rows(fs, plate: PlateResonance, n):
    """The plate's inverse as rows: row i is what the undone force's sample i of n takes from each sensed sample,
    from PEAK_FIT_IMPULSE_HALF before the first to as long after the last [-] (n x (n + 2 PEAK_FIT_IMPULSE_HALF))."""
    half = PEAK_FIT_IMPULSE_HALF
    h = undone_impulse_response(fs, plate.frequency_hz, plate.damping_ratio, half)  # response at lag d: h[half + d]
    lag = 2 * half + np.arange(n)[:, None] - np.arange(n + 2 * half)[None, :]
    return np.where((lag >= 0) & (lag <= 2 * half), h[np.clip(lag, 0, 2 * half)], 0.0)


def _fit_stats(rows, n, centred=False, weighted=False):
    """A quadratic fit of n samples of an undone force read at the last (the middle one when centred): its design,
    the matrix that takes the n samples to its coefficients, the matrix that whitens its residual, per unit
    sensed noise that residual's expected sum of squares and that sum's deviation, and the standard error of its
    reading at each of the n samples [-].

    The undone noise is the sensed white noise through the plate's inverse ``rows``: amplified towards the
    Nyquist frequency and correlated from sample to sample. Unweighted (ordinary least squares), the whitening
    matrix is the identity and the residual's sum of squares has the mean and deviation of that noise's
    quadratic form. Weighted, the samples count by the inverse of that noise's covariance (generalised least
    squares, as if fitted to the sensed samples: the noise the inverse amplified counts for what it is), and
    the whitened residual's sum of squares is a chi-square of n - 3 degrees of freedom."""
    design = np.vander(np.arange(n, dtype=float) - (0.5 * (n - 1) if centred else n - 1), 3, increasing=True)
    u = rows[:n, :n + 2 * PEAK_FIT_IMPULSE_HALF]
    if not weighted:
        pinv = np.linalg.pinv(design)
        ru = u - design @ (pinv @ u)  # the residual's share of each sensed sample's noise
        cov = ru @ ru.T  # the residual's covariance [noise^2]: its sum of squares has mean trace, variance 2 |cov|^2
        return design, pinv, np.eye(n), float(np.trace(cov)), math.sqrt(2.0 * float(np.sum(cov * cov))), \
            np.sqrt(np.sum((design @ (pinv @ u)) ** 2, axis=1))
    cov = u @ u.T  # the undone noise's covariance over the n samples [sensed noise^2]
    whiten = np.linalg.solve(np.linalg.cholesky(cov), np.eye(n))  # the whitened noise is white, of unit variance
    dw = whiten @ design
    inv = np.linalg.inv(dw.T @ dw)
    dof = max(n - 3, 1)
    return design, inv @ dw.T @ whiten, whiten, float(dof), math.sqrt(2.0 * dof), \
        np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", design, inv, design), 0.0))


def _fit_noise_scale(exact, fs, a, b, length, noise, plate: PlateResonance):
    """How much noisier the force undone from a plate is than the sensed noise ``noise`` [V] through the
    inverse says, read from the centred quadratic fits of ``length`` samples (made odd) over ``exact[a:b]``:
    the square root of their residuals' median sum of squares over its expectation, at least
    PEAK_FIT_NOISE [-] (what the inverse makes of a force not linear between the samples, the ADC's steps)."""
    a, b = max(int(a), 0), min(int(b), exact.size)
    length = int(length) | 1
    if b - a < length or length < PEAK_FIT_MIN or not noise > 0:
        return PEAK_FIT_NOISE
    design, pinv, whiten, expected, _, _ = _fit_stats(_undone_rows(fs, plate, length), length, centred=True)
    windows = np.lib.stride_tricks.sliding_window_view(exact[a:b], length)
    rss = np.sum(((windows - (windows @ pinv.T) @ design.T) @ whiten.T) ** 2, axis=1)
    return max(math.sqrt(float(np.median(rss)) / expected) / noise, PEAK_FIT_NOISE)


def _fitted_force(exact, fs, a, b, length, noise, plate: PlateResonance, centred=False, weighted=False):
    """A force undone from a plate read at each sample from a fit of the samples around it rather than from
    the sample alone: (reading [V], its standard error [V] or NaN where no fit holds), one per sample of
    ``exact[a:b]``.

    At sample k, a quadratic least-squares fit read at k: of
    ``exact[max(k - length + 1, a):k + 1]`` (at least PEAK_FIT_MIN samples;
    the first fit also read at the samples before its last), or centred, of
    the ``length`` samples (made odd) around k (the first and last fit also
    read at the samples off their middle). The one-sided fit never spans a
    drop after k: the ball's pre-buckling spike is a smooth ramp cut by a
    sudden drop (section 3.2.4 in Goodwill & Haake 2004), and its top is read
    from the ramp before it; the centred one, less noisy, suits the smooth
    force after buckling. The undone noise rises towards the Nyquist
    frequency and a fit averages it out: its standard error and the residual
    it should leave come from the sensed white noise ``noise`` [V] through
    the plate's inverse (its impulse response; noise correlated from sample
    to sample). A fit whose residual exceeds that expectation by
    PEAK_FIT_SIGMA of its deviation (a Gaussian quadratic form) spans a drop
    or a feature sharper than a parabola and does not hold: that sample
    keeps its own value, with a NaN error. ``weighted`` (centred fits only)
    weighs the samples by the inverse covariance of that noise (see
    :func:`_fit_stats`): a reading as if fitted to the sensed samples, whose
    error is about the sensed noise's rather than the amplified one's.
    """
    a, b = max(int(a), 0), min(int(b), exact.size)
    out = exact[a:b].astype(float)
    error = np.full(out.size, math.nan)
    length = min(int(length) | 1, out.size - 1 + out.size % 2) if centred else min(int(length), out.size)
    if length < PEAK_FIT_MIN or not noise > 0:
        return out, error
    rows = _undone_rows(fs, plate, length)
    seg = exact[a:b]

    def holds(resid, whiten, expected, spread):
        white = resid @ whiten.T
        return np.sum(white * white, axis=-1) <= (expected + PEAK_FIT_SIGMA * spread) * noise * noise

    for n in range(PEAK_FIT_MIN, 0 if centred else length):  # one-sided: the first samples from a up to them
        design, pinv, whiten, expected, spread, se = _fit_stats(rows, n)
        coef = pinv @ seg[:n]
        if holds(seg[:n] - design @ coef, whiten, expected, spread):
            at = slice(0, n) if n == PEAK_FIT_MIN else slice(n - 1, n)
            out[at], error[at] = (design @ coef)[at], noise * se[at]
    design, pinv, whiten, expected, spread, se = _fit_stats(rows, length, centred, weighted)  # `length` samples
    windows = np.lib.stride_tricks.sliding_window_view(seg, length)
    coef = windows @ pinv.T
    ok = holds(windows - coef @ design.T, whiten, expected, spread)
    at = length // 2 if centred else length - 1
    k = np.arange(windows.shape[0]) + at
    out[k[ok]], error[k[ok]] = coef[ok, 0], noise * se[at]
    if centred:  # the first and the last fit read off their middle too
        for w, span in ((0, slice(0, at)), (windows.shape[0] - 1, slice(at + 1, length))):
            if ok[w]:
                out[w + span.start:w + span.stop] = (design @ coef[w])[span]
                error[w + span.start:w + span.stop] = noise * se[span]
    return out, error


def _second_hump(xc, fs, noise, peak):
    """A contact force that falls and rises again after its first maximum: not a ball's force.

    After the pre-buckling spike (its phase, HUMP_SKIP_S after the start), the ball's
    force of the model (Eq. (14) in Goodwill & Haake 2004: kB x + (cB + cM) x' with x
    rising then falling once) has one maximum. A fall of more than HUMP_DIP_FRACTION of
    the peak after a maximum and a rise of more than HUMP_RISE_FRACTION after it, in the
    force averaged over HUMP_SMOOTH_S (which quiets the noise and ringing of a plate
    above a few kHz, left to the other checks), is a plate resonance below the band the
    ringing checks look at (3 kHz: zoo trace 3:1077, an 848 Hz plate with damping 0.22 at
    50 kHz, came out ok with TC -12 % and the peak +27 %), or a second contact inside
    the first.
    """
    skip = int(round(HUMP_SKIP_S * fs))
    w = max(int(round(HUMP_SMOOTH_S * fs)), 1)
    if not peak > 0 or xc.size - skip < 3 * w:
        return []
    y = np.convolve(xc[skip:], np.full(w, 1.0 / w), mode="valid")
    tol = HUMP_SIGMA * noise / math.sqrt(w)
    dip_min = max(HUMP_DIP_FRACTION * peak, tol)
    rise_min = max(HUMP_RISE_FRACTION * peak, tol)
    top = low = float(y[0])  # the largest average so far, and the lowest since it
    for j in range(1, y.size):
        v = float(y[j])
        if top - low > dip_min and v - low > rise_min:
            t_top = 1e3 * (skip + int(np.argmax(y[:j])) + (w - 1) / 2) / fs
            return [Problem(ProblemKind.PLATE_RINGING,
                            f"force with two humps: after its maximum at {t_top:.2g} ms into the contact it falls by "
                            f"{100 * (top - low) / peak:.2g} % of the peak and rises again by "
                            f"{100 * (v - low) / peak:.2g} % (averaged over {HUMP_SMOOTH_S * 1e3:g} ms); a ball's "
                            "force has one: a plate resonance below 3 kHz, or a second contact inside the first")]
        if v > top:
            top = low = v
        elif v < low:
            low = v
    return []


def _peak_on_step_response(xc, fs, noise, peak, lead=0.0):
    """The peak force on the plate's step response: its first overshoot of the force's jump, not the ball's.

    The ball's force jumps from zero (at 2 mm of compression in the model), rises
    to the pre-buckling spike, drops at buckling, and then rises once to its
    maximum and falls once (Eq. (14) in Goodwill & Haake 2004: kB x + (cB + cM) x'
    with x rising then falling once): after a peak in the spike's phase it has
    one minimum and no bump before the maximum that follows. A plate of a few kHz
    answers the jump with its step response: a rise over part of its period, an
    overshoot, then a damped oscillation. Heavily damped (zeta about 0.2), that one
    overshoot raises the peak by 5-20 % and the swings after it are too few and
    too unequal for :func:`_peak_on_ringing` (zoo traces 3:212, 3:672, 3:700:
    plates of 6.5-9.7 kHz, damping 0.17-0.26, at 21-146 kHz, ok with the peak
    5.6-10.4 % high).

    So, in the force averaged over STEP_SMOOTH_S, a peak within STEP_PHASE_S of
    the contact start that is followed within STEP_WINDOW_S by a fall, a rise (a
    second bump) and a fall again, each turn left by more than STEP_FRACTION of
    the peak and STEP_SIGMA noise deviations of the average (the rise after the
    last fall too, so that the fall after the ball's own maximum is none), is the
    plate's when it is its first overshoot: no turn before it, and within
    STEP_FIRST_PERIOD periods of the swing (the spacing of the two minima) of the
    contact start (``lead`` [samples]: from the start to the first sample of
    ``xc``). A fall after the peak steeper than STEP_STEEPEST times a swing's
    steepest (pi times the fall over the period, per sample; less two noise
    deviations of a difference) is the ball's own drop at buckling (sensed
    through a fast plate, or an undone one), whose ringing came after the peak.
    A peak on a later swing (a spike's top overshot by a plate that has rung
    since the jump, zoo 3:824) is not judged here.
    """
    w = 2 * int(round(0.5 * STEP_SMOOTH_S * fs)) + 1
    if not peak > 0 or xc.size < 4 * w:
        return []
    y = np.convolve(xc, np.full(w, 1.0 / w), mode="same") if w > 1 else xc
    i = int(np.argmax(y))
    if i > STEP_PHASE_S * fs:
        return []
    h = max(STEP_FRACTION * peak, STEP_SIGMA * noise / math.sqrt(w))
    seg = y[i:min(xc.size, i + int(round(STEP_WINDOW_S * fs)) + 1)]
    turns = _turning_points(seg, h)  # from the peak: a minimum, a maximum, a minimum (each confirmed)
    if len(turns) < 3:
        return []
    low1, bump, low2 = turns[:3]
    period = float(low2 - low1)  # [samples]
    if i + lead > STEP_FIRST_PERIOD * period or _turning_points(y[:i + 1], h):
        return []  # a peak later than the first overshoot, or not the first maximum
    fall = float(seg[0] - seg[low1])
    steepest = float(np.max(xc[i:i + low1] - xc[i + 1:i + low1 + 1])) - 2.0 * math.sqrt(2.0) * noise
    if steepest > STEP_STEEPEST * math.pi * fall / period:
        return []  # a swing of that period falls by at most pi fall / period a sample: the ball's force drops
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on the plate's step response: {1e3 * i / fs:.2g} ms into the contact the force "
                    f"peaks, falls by {100 * (seg[0] - seg[low1]) / peak:.2g} % of the peak, rises again by "
                    f"{100 * (seg[bump] - seg[low1]) / peak:.2g} % and falls by {100 * (seg[bump] - seg[low2]) / peak:.2g}"
                    f" % within {1e3 * low2 / fs:.2g} ms (a ball's force has no such bump): the plate's first "
                    f"overshoot of the force's jump, ringing at about {fs / (low2 - low1) / 1e3:.3g} kHz; the peak "
                    "is not the ball's")]


def _peak_on_slow_fall(xc, fs, noise, peak, lead=0.0):
    """A peak in the spike's phase that the force leaves slowly: the chain's response to the jump, not the ball's.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake 2004)
    the force jumps from zero and rises until the wall buckles, when the
    stiffness falls at once from kCONST to kB(0) + AK x^a: a largest sample in
    that phase (within STEP_PHASE_S of the start; ``lead`` [samples] from the
    start to ``xc``'s first sample) is the spike's top, and the force drops
    from it suddenly, within a sample or two of any sample rate. A fall of
    more than FALL_MIN_FRACTION of the peak (and FALL_SIGMA noise
    deviations) within FALL_WINDOW_S after it, spread from 10 to 90 % of its
    depth over more than FALL_MAX_SAMPLES samples and FALL_MAX_S, is the
    sensing chain's: the overshoot of the force's jump by a plate the ringing
    checks do not recognise (two modes, bench/two_mode_map.py: 2:371, 10.6 and
    24.7 kHz, the largest sample 0.022 ms in and 12 % above the ball's peak;
    2:27, 2:385, 3:301, +3.7 to +28 %, ok), or a smoothing that spreads the
    spike. Either way the top is not the ball's. On the zoo's ok traces whose
    peak is in that phase the fall took at most 2 samples (24.5 us at
    40.8 kHz); on those four, 4-11 (53-73 us). Run last on the sensed
    force, on a trace nothing else excludes: after
    :func:`_peak_on_first_overshoot` (a plate near fs / 2 it names as no
    evidence stays so) and after :func:`_front_lowpass` (a low-pass slows
    the fall too, and its message names TC's error:
    tests/test_robustness.py's low-pass cases). Also run on an undone force
    that is not low-passed (a low-pass spreads the drop by its kernel), on a
    peak no other check judged: where one mode is identified and undone,
    the other's overshoot stays (5:243, 8.0 and 30.3 kHz, the second
    undone: +29 %).
    """
    if not peak > 0 or xc.size < 3:
        return []
    i = int(np.argmax(xc))
    if (i + lead) / fs > STEP_PHASE_S:
        return []
    seg = xc[i:min(xc.size, i + int(round(FALL_WINDOW_S * fs)) + 1)]
    m = int(np.argmin(seg))
    drop = float(seg[0] - seg[m])
    if drop <= max(FALL_MIN_FRACTION * peak, FALL_SIGMA * noise):
        return []
    k10 = int(np.argmax(seg[:m + 1] <= seg[0] - 0.1 * drop))
    k90 = int(np.argmax(seg[:m + 1] <= seg[0] - 0.9 * drop))
    spread = k90 - k10
    if spread <= FALL_MAX_SAMPLES or spread / fs <= FALL_MAX_S:
        return []
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on the plate's step response: {1e3 * (i + lead) / fs:.2g} ms into the contact the "
                    f"force peaks and falls by {100 * drop / peak:.2g} % of the peak over {spread} samples "
                    f"({1e6 * spread / fs:.3g} us from 10 to 90 % of the fall); a ball's force drops at once as its "
                    "wall buckles: the sensing chain's answer to the force's jump (a plate's overshoot, or a "
                    "smoothing), not the ball's peak")]


def _peak_on_front_ringing(x, fs, noise, peak, s_u, e_u):
    """The peak force lifted by the plate's ringing from the force's jump: a later swing of it, not the ball's.

    In the model's pre-buckling phase (section 3.2.4 in Goodwill & Haake 2004)
    the force jumps from zero and rises smoothly to the spike, which ends in
    the drop at buckling. A plate rings from the jump; when the spike's top
    lands on a later maximum of that ringing (the first overshoot is
    :func:`_peak_on_step_response`'s too) the largest sample is lifted
    above the ball's force with nothing in the contact to show it (zoo trace
    3:824: a 13.7 kHz plate with damping 0.20 at 168 kHz, the peak 5.3 % high
    and ok). So when the contact's largest sample is within FRONT_PHASE_S
    (and a sample) of its start and FRONT_MIN_SAMPLES of the contact reach
    it, the samples from FRONT_PRE_SAMPLES before the start to it are fitted
    with a jump, a ramp and a parabola (:func:`ballimpact.plate.fit_front`),
    once through a plate (fn and zeta free, at most 0.45 fs, at least one
    period over the window) and once through an ideal plate. When the plate
    fits better by more than FRONT_SIGNIFICANCE residual variances (the
    larger of the noise's and the plate fit's own, per sample) and the
    largest sample stands more than FRONT_LIFT_FRACTION of the peak above
    the force the plate's fit finds under it, the peak is the plate's (also
    when the ball's top comes later, hidden in a trough of the ringing: the
    peak is then not measured either).

    The fit looks for the force's jump from FRONT_PRE_SAMPLES samples before
    the first contact sample to that sample: a front still below
    FRONT_JUMP_FRACTION of the peak FRONT_PRE_SAMPLES samples after it (a
    cloth's foot before the jump, as the synthetic chain's) is not the
    model's, and is not judged.
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not peak > 0 or k1 - k0 < MIN_CONTACT_SAMPLES or k0 - FRONT_PRE_SAMPLES < 0 or k1 >= x.size:
        return []
    i = k0 + int(np.argmax(x[k0:k1 + 1]))
    if i - s_u > FRONT_PHASE_S * fs + 1.0 or i - k0 + 1 < FRONT_MIN_SAMPLES:
        return []
    if x[k0 + FRONT_PRE_SAMPLES] < FRONT_JUMP_FRACTION * peak:
        return []  # no jump where the fit looks for one: a slower front (a cloth's foot) is not fitted
    plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, i, s_u)
    if plate is None:
        return []
    ideal = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, i, s_u, resonance=False)
    variance = max(noise * noise, plate.rss / max(plate.n_samples - 7, 1))
    gain = (ideal.rss - plate.rss) / variance if variance > 0 else math.inf
    lift = float(x[i] - plate.force(i))
    if gain > FRONT_SIGNIFICANCE and lift > FRONT_LIFT_FRACTION * peak:
        return [Problem(ProblemKind.PEAK_ON_RINGING,
                        f"peak force on the plate's ringing: from the contact start to its largest sample "
                        f"({1e3 * (i - s_u) / fs:.2g} ms in) the force is a jump and a ramp through a plate of about "
                        f"{plate.frequency_hz / 1e3:.3g} kHz (damping ratio {plate.damping_ratio:.2g}), with "
                        f"{ideal.rss / max(plate.rss, 1e-300):.2g} times less residual than through an ideal plate, "
                        f"whose ringing from the jump lifts the largest sample {100 * lift / peak:.2g} % of the peak "
                        "above the force; the peak is not the ball's")]
    return []


def _peak_on_first_overshoot(x, fs, noise, peak, s_u, e_u):
    """The peak force on the plate's first overshoot of the force's jump, sampled a few times per period.

    A lightly damped plate sampled 2-5 times per period answers the force's
    jump (section 3.2.4 in Goodwill & Haake 2004: zero below 2 mm of
    compression, then kCONST) with a first overshoot that lands on the
    contact's first samples and stands 5-25 % above the ball's peak (8.5 kHz
    and damping 0.11 at 25.5 kHz: +22 %). Its ringing is gone after a
    period or two, so neither :func:`_peak_on_ringing` nor
    :func:`_peak_on_step_response` sees an oscillation, and
    :func:`_peak_on_front_ringing` needs FRONT_MIN_SAMPLES up to the largest
    sample. So when the largest sample is within FRONT_PHASE_S (and a
    sample) of the start with fewer than FRONT_MIN_SAMPLES up to it, the
    window runs on to OVERSHOOT_AFTER_SAMPLES after it, past the pre-buckling
    spike: from FRONT_PRE_SAMPLES before the start it is fitted with the
    model's front and its drop at buckling (:func:`ballimpact.plate.fit_front`
    with ``drop``: a jump, a ramp that rises by at most the jump, a drop at a
    free instant and a new ramp and parabola after it; the jumps rising over
    at most OVERSHOOT_RISE_MAX samples), once through a plate (fn and zeta
    free, zeta up to plate.FRONT_DROP_MAX_DAMPING) and once through an ideal
    plate. When the plate fits better by more than FRONT_SIGNIFICANCE
    residual variances (the larger of the noise's and the plate fit's own,
    per sample), its damping is at most OVERSHOOT_MAX_DAMPING (a fit at the
    bound smooths the force's shape; it is no ringing) and the largest
    sample stands more than FRONT_LIFT_FRACTION of the peak above the force
    it finds under it, the peak is the plate's: evidence of the plate
    (PEAK_ON_RINGING), whose resonance is then identified and undone where
    that passes every check, unless the plate fitted rings with fewer than
    OVERSHOOT_MIN_PERIOD samples per period: a resonance above fs / 2 is
    sampled as its alias below it, and undone as that alias its force is
    wrong (zoo trace 2:1022: 24.9 kHz at 43.3 kHz, fitted at 19.5 kHz, the
    undone peak -5.1 %), so the peak is then named as not resolved by the
    samples (PEAK_BETWEEN_SAMPLES), which is no evidence. A ball's front
    through an ideal plate, its spike's top and its drop sampled anywhere,
    needs no plate (tests/test_conditioning.py). Not run when the checks
    before it found evidence of the plate already (its undoing is tried
    then whatever this check finds): a few ms of fits saved.

    An electrical spike on the ringing after the largest sample (added
    after the plate; :func:`remove_spikes` cannot tell it from the
    ringing's swings) raises the plate fit's own residual, which then sets
    the significance: on ``python bench/spike_ends_map.py --n 400 --seed 2``
    trace 2:349 (18.5 kHz at 51.7 kHz, a 0.33 V spike of 38 noise
    deviations on the ringing's first trough) the plate's fit left 1350
    noise variances and the ideal one 3470, a gain of 7.8 of the plate's
    residual variances, and the peak was ok 5.0 % high. So where the plate
    fits better than the ideal plate by more than FRONT_SIGNIFICANCE noise
    variances but not by its own residual, both are fitted again with a
    free spike on one sample after the largest (``fit_front``'s
    ``spike``), and the plate's is evidence when its spike stands
    EVENT_SIGMA noise deviations out and, with it, the plate's fit leaves
    at most FRONT_SIGNIFICANCE noise variances: the spike must explain the
    whole misfit (a free sample also absorbs the model's misfit of a
    ball's front, -292 and -45 deviations on zoo traces 0:842 and 1:718,
    where the fit with it still left more).
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not peak > 0 or k1 - k0 < MIN_CONTACT_SAMPLES or k0 - FRONT_PRE_SAMPLES < 0 or k1 >= x.size:
        return []
    i = k0 + int(np.argmax(x[k0:k1 + 1]))
    if i - s_u > min(FRONT_PHASE_S * fs + 1.0, OVERSHOOT_MAX_SAMPLES) or i - k0 + 1 >= FRONT_MIN_SAMPLES:
        return []  # a later peak, or one :func:`_peak_on_front_ringing` judges
    if x[k0 + FRONT_PRE_SAMPLES] < FRONT_JUMP_FRACTION * peak:
        return []
    last = min(i + OVERSHOOT_AFTER_SAMPLES, k1)
    ideal = _ideal_front_beyond_noise(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, noise, drop=True,
                                      rise_max=OVERSHOOT_RISE_MAX)
    if ideal is None:
        return []  # the ball's front through an ideal plate leaves too little for a plate to explain
    plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, drop=True, rise_max=OVERSHOOT_RISE_MAX)
    if plate is None:
        return []

    def evident(ideal, plate, n_params):  # the plate's evidence: its fit's gain, the lift; None when not evident
        variance = max(noise * noise, plate.rss / max(plate.n_samples - n_params, 1))
        gain = (ideal.rss - plate.rss) / variance if variance > 0 else math.inf
        lift = float(x[i] - plate.force(i))
        ok = gain > FRONT_SIGNIFICANCE and lift > FRONT_LIFT_FRACTION * peak and \
            plate.damping_ratio <= OVERSHOOT_MAX_DAMPING
        return lift if ok else None

    lift, spike = evident(ideal, plate, 10), ""
    if lift is None and plate.rss > FRONT_SIGNIFICANCE * noise * noise \
            and ideal.rss - plate.rss > FRONT_SIGNIFICANCE * noise * noise:
        # the plate explains the front better than the ideal plate by more than the noise, but its fit's own residual
        # (not the noise) refused the evidence: an electrical spike on the ringing after the peak (added after the
        # plate, where remove_spikes cannot tell it from the ringing's swings) may be that residual; fitted with one
        others = list(range(i + 1, last + 1))
        ideal = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, resonance=False, drop=True,
                          rise_max=OVERSHOOT_RISE_MAX, spike=others)
        if ideal is None or not ideal.rss > FRONT_SIGNIFICANCE * noise * noise:
            return []
        plate = fit_front(x, fs, k0 - FRONT_PRE_SAMPLES, last, s_u, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                          spike=others)
        if plate is None or not abs(plate.spike) > EVENT_SIGMA * noise \
                or not plate.rss <= FRONT_SIGNIFICANCE * noise * noise:
            return []  # no spike out of the noise, or one that does not leave the plate's fit at the noise
        lift = evident(ideal, plate, 11)
        spike = (f", less a single-sample spike of {plate.spike / noise:.3g} noise deviations "
                 f"{plate.spike_index - s_u:+.2g} samples from the start (an electrical one, not through the plate)")
    if lift is None:
        return []
    seen = (f"the contact's front (to {last - i} samples after it) is a jump and a ramp through a plate of about "
            f"{plate.frequency_hz / 1e3:.3g} kHz (damping ratio {plate.damping_ratio:.2g}, "
            f"{fs / plate.frequency_hz:.2g} samples per period), with {ideal.rss / max(plate.rss, 1e-300):.2g} times "
            f"less residual than through an ideal plate{spike}, whose overshoot lifts the largest sample "
            f"{100 * lift / peak:.2g} % of the peak above the force")
    if fs / plate.frequency_hz < OVERSHOOT_MIN_PERIOD:  # near fs / 2: a resonance above it looks the same
        return [Problem(ProblemKind.PEAK_BETWEEN_SAMPLES,
                        f"peak force between samples: the largest sample, {1e3 * (i - s_u) / fs:.2g} ms after the "
                        f"contact start, is a plate's first overshoot of the force's jump, ringing near half the "
                        f"sample rate (or above it, seen through its alias): {seen}; the peak is not the ball's "
                        "(sample faster)")]
    return [Problem(ProblemKind.PEAK_ON_RINGING,
                    f"peak force on plate ringing: the largest sample, {1e3 * (i - s_u) / fs:.2g} ms after the contact "
                    f"start, is the plate's first overshoot of the force's jump: {seen}; the peak is not the ball's")]


def _ideal_front_beyond_noise(x, fs, first, last, start, noise, **options):
    """The front's fit through an ideal plate (:func:`ballimpact.plate.fit_front` with ``resonance=False`` and
    ``options``), or None when it leaves at most FRONT_SIGNIFICANCE noise variances: nothing for a plate or a
    low-pass to explain. The starting grid's fit is tried first (fast): when it leaves that little, the refined
    one, whose residual is no larger, does too."""
    for refine in (False, True):
        ideal = fit_front(x, fs, first, last, start, resonance=False, refine=refine, **options)
        if ideal is None or ideal.rss <= FRONT_SIGNIFICANCE * noise * noise:
            return None
    return ideal


def _front_lowpass(x, fs, noise, peak, s_u, e_u, tc):
    """The force's jump at the contact start spread by a low-pass in the chain: the end comes late, TC long.

    The model's force jumps from zero (section 3.2.4 in Goodwill & Haake
    2004: the cloth carries no load below 2 mm of compression, then kB =
    kCONST) to 30-57 % of its peak within its 0.01 ms step. A low-pass in the
    sensor chain (a charge amplifier's filter: a second-order Butterworth has
    damping 0.71, a Bessel 0.87; or a plate on damped mounts) spreads that
    jump over its rise and delays the rest of the force by its group delay,
    2 zeta / wn. The contact's start is found at the foot of the spread jump,
    its end where the delayed and rounded fade meets zero, about twice the
    delay late: TC comes out long, and nothing rings to show it (``python
    bench/lowpass_map.py --n 400 --seed 1``: 50 of 400 ok but wrong, up to
    TC +4.2 %, on 39210b7).

    So when the force's largest rise in LOWPASS_STEP_S (at least a sample)
    within LOWPASS_RISE_S of the start is less than LOWPASS_CONCENTRATION of
    its whole rise there (a jump through an ideal plate put 0.36 or more of it
    into that step on 120 of bench/ideal_plate_map.py's rigs at 20-60 kHz;
    the gate only spares the fits, about 0.1 s each, on most traces, and the
    fits decide: at 0.5 instead of 0.4 the low-pass map kept 2 and 1 fewer
    ok-but-wrong traces on seeds 1 and 2, and the synthetic chain's front
    with a cloth's foot, 0.45, was fitted), the samples from
    FRONT_PRE_SAMPLES before the start to LOWPASS_WINDOW_S after it (every
    q-th, at most LOWPASS_MAX_SAMPLES) are fitted with the model's front and
    its drop at buckling (:func:`ballimpact.plate.fit_front` with ``drop``),
    once through a second-order response (fn up to 0.45 of the rate fitted,
    damping within LOWPASS_DAMPING) and once through an ideal plate (the jump
    rising over at most OVERSHOOT_RISE_MAX samples) with a cubic as well. The
    cubic lets the ideal plate follow a force that starts smoothly, without
    a jump, whose curve over the window is more than a parabola's (a
    half-sine's foot: tests/test_conditioning.py
    ``test_an_end_that_jumps_is_no_convex_fade``, which the low-pass fit took
    for a low-pass against the ideal plate's ramp and parabola); the
    low-pass fit gets none (there, it trades against the damping, which it
    pressed to the bound on bench/lowpass_map.py trace 1:85). The low-pass is
    seen, and TC is not known to 1 %, when its fit

    * beats the ideal one by more than FRONT_SIGNIFICANCE residual variances
      (the larger of the noise's and its own, per sample),
    * explains the front: it leaves at most LOWPASS_RESIDUAL noise variances
      per sample (an ideal plate's front that the model's shape misses by
      more than the noise is fitted better through a smoother, and left
      11-870 variances on zoo traces 2:850, 1:1149 and 0:196),
    * is damped: its damping ratio is off the lower bound, 0.2 (a plate
      damped less rings, and the plate's checks see it; at 0.3 a 2.44 kHz
      plate damped 0.285 at 51 kHz, zoo trace 6:1912, rang too little for
      them, its low-pass fit pressed to the bound, and it was ok with TC
      +1.08 %), and
    * delays by more than LOWPASS_DELAY_FRACTION of TC and LOWPASS_DELAY_SAMPLES.

    A low-pass whose delay is under a sample or two (at 20-40 kHz, near half
    the rate) leaves little trace in the samples and is not always seen (docs/robustness.md,
    "What remains"). Not in the paper.
    """
    k0 = int(math.ceil(s_u))
    k1 = int(math.floor(e_u))
    if not (peak > 0 and tc > 0) or k1 - k0 < MIN_CONTACT_SAMPLES or k1 >= x.size:
        return []
    seg = x[max(k0 - 1, 0):k0 + min(max(int(round(LOWPASS_RISE_S * fs)), 3), k1 - k0) + 1]
    m = max(1, int(math.ceil(LOWPASS_STEP_S * fs)))
    rise = float(np.max(seg) - seg[0])
    steepest = float(np.max(seg[m:] - seg[:-m]))
    if not rise > FRONT_JUMP_FRACTION * peak or steepest >= LOWPASS_CONCENTRATION * rise:
        return []  # no rise to judge, or a jump within a step: no low-pass worth a sample
    w = min(max(int(round(LOWPASS_WINDOW_S * fs)), 3), k1 - k0)
    q = max(1, int(math.ceil(w / LOWPASS_MAX_SAMPLES)))  # every q-th sample: a slow front needs no more
    first = k0 - FRONT_PRE_SAMPLES * q
    if first < 0:
        return []
    xs, fq, start = x[first:k0 + w + 1:q], fs / q, (s_u - first) / q
    within = BUCKLING_TIME_S * fq + 1.0  # the drop at buckling within 0.2 ms (and a sample) of the first sample
    ideal = _ideal_front_beyond_noise(xs, fq, 0, xs.size - 1, start, noise, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                                      drop_within=within, cubic=True)
    if ideal is None:
        return []  # the ideal plate leaves too little for a low-pass to explain
    lowpass = fit_front(xs, fq, 0, xs.size - 1, start, drop=True, rise_max=OVERSHOOT_RISE_MAX,
                        damping=LOWPASS_DAMPING, drop_within=within)
    if lowpass is None:
        return []
    variance = max(noise * noise, lowpass.rss / max(lowpass.n_samples - 10, 1))
    gain = (ideal.rss - lowpass.rss) / variance if variance > 0 else math.inf
    delay = 2.0 * lowpass.damping_ratio / (2.0 * math.pi * lowpass.frequency_hz)  # [s]
    damped = lowpass.damping_ratio > 1.05 * LOWPASS_DAMPING[0]  # off the lower bound, not pressed against it
    explained = lowpass.rss <= LOWPASS_RESIDUAL * lowpass.n_samples * noise * noise
    if not (gain > FRONT_SIGNIFICANCE and damped and explained
            and delay > max(LOWPASS_DELAY_FRACTION * tc, LOWPASS_DELAY_SAMPLES / fq)):
        return []
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact end not determined to 1 %: the force's jump at the contact start is spread over "
                    f"several samples, as through a low-pass (an amplifier's filter or a damped plate): the front "
                    f"fits a jump through a second-order response of about {lowpass.frequency_hz / 1e3:.3g} kHz "
                    f"(damping ratio {lowpass.damping_ratio:.2g}) with {ideal.rss / max(lowpass.rss, 1e-300):.3g} "
                    f"times less residual than through an ideal plate; such a low-pass delays the force by about "
                    f"{delay * 1e6:.3g} us ({100 * delay / tc:.2g} % of TC), and the contact's end as much or more "
                    "than its start (record without the filter)")]


def _start_on_fast_ringing(x, fs, noise, peak, s_u, e_u):
    """The contact's ends read off a front that rings near half the sample rate: not known to 1 %.

    The force's jump (section 3.2.4 in Goodwill & Haake 2004: zero below
    2 mm of compression) sets a lightly damped plate ringing. Sampled 2-3.6
    times per period, the ringing alternates from sample to sample with a slow
    beat, and the samples of the front are the force plus a swing of up to the
    jump: the hinge through them puts the start up to 3 samples off (one of
    them swung down to zero reads as the last quiet sample, or the rise is
    sampled as a ramp), and TC 1.4-1.7 % off in bench/overshoot_map.py's
    plates at 2.2-3.5 samples a period, while the peak, later, is right and
    no other check sees the ringing: it dies before the contact's middle
    (where :func:`_ringing_line`'s window weighs the samples) and turns too
    fast for :func:`_turning_points`. It is read after the drop at buckling
    (FAST_RING_GAP_SAMPLES after BUCKLING_TIME_S from the start, where the
    model's force is smooth) over FAST_RING_WINDOW_S: those samples less a
    cubic fitted to them leave more than FAST_RING_SIGMA noise deviations
    and FAST_RING_FRACTION of the peak in rms, ringing with a period of at
    most FAST_RING_MAX_PERIOD samples (its frequency w from ``y[n - 1] +
    y[n + 1] = 2 cos(w) y[n] + cubic(n)`` by least squares, the noise's
    power taken out of the normal equations; a decay reads cos(w) a little
    nearer -1, i.e. nearer fs / 2).
    Such ringing moves the start found by more than 1 % of TC when a sample
    of the front, once above FAST_RING_JUMPED of the peak, swings back below
    FAST_RING_ZERO of it (the ball's force never returns to zero after its
    jump: a swing as large as the jump), or when the contact holds so few
    samples that half a sample exceeds JUMP_MAX_FRACTION of TC (the rise
    sampled through the plate is its answer to a jump, located to half a
    sample at best, as :func:`_end_problems` charges a jump); otherwise the
    start is left as found (on the ok traces of the zoo's seeds 0-3 that
    ring so, the start was right: tests/test_conditioning.py). At
    OVERSHOOT_MIN_PERIOD samples per period or more it is evidence of the
    plate (PLATE_RINGING: its undoing is tried); below, or above fs / 2 seen
    through its alias, the ringing is named and the start not determined
    (CONTACT_END_UNDETERMINED, no evidence: an alias undone is wrong). Not
    in the paper; see docs/robustness-history.md, "A contact front ringing near half the sample rate".
    """
    k0, k1 = int(math.ceil(s_u)), int(math.floor(e_u))
    a = k0 + int(math.ceil(BUCKLING_TIME_S * fs)) + FAST_RING_GAP_SAMPLES
    b = min(a + max(int(round(FAST_RING_WINDOW_S * fs)), FAST_RING_MIN_SAMPLES), k1 - FAST_RING_GAP_SAMPLES)
    if not (peak > 0 and noise > 0) or a < 0 or b - a < FAST_RING_MIN_SAMPLES or b > x.size:
        return []
    y = x[a:b]
    u = np.linspace(-1.0, 1.0, y.size)
    r = y - np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyfit(u, y, 3))
    power = float(np.mean(r * r))
    rms = math.sqrt(power)
    if not (rms > FAST_RING_SIGMA * noise and rms > FAST_RING_FRACTION * peak):
        return []
    # a sinusoid of w radians a sample obeys y[n - 1] + y[n + 1] = 2 cos(w) y[n], a cubic a cubic: fitted jointly
    # (the noise's power taken out of the normal equations: no bias towards cos(w) = 0)
    mid, um = y[1:-1], u[1:-1]
    design = np.column_stack([mid, np.ones(mid.size), um, um * um, um * um * um])
    gram = design.T @ design
    gram[0, 0] -= mid.size * noise * noise
    try:
        cos_w = 0.5 * float(np.linalg.solve(gram, design.T @ (y[:-2] + y[2:]))[0])
    except np.linalg.LinAlgError:
        return []
    if not cos_w < math.cos(2.0 * math.pi / FAST_RING_MAX_PERIOD):
        return []
    period = 2.0 * math.pi / math.acos(max(cos_w, -1.0))
    # the force, once jumped, never returns to zero: a front sample back at zero is a swing as large as the jump
    front = x[max(k0 - FRONT_PRE_SAMPLES, 0):min(a, x.size)]
    jumped = np.flatnonzero(front > FAST_RING_JUMPED * peak)
    dip = jumped.size and float(np.min(front[jumped[0]:])) < FAST_RING_ZERO * peak
    # else the rise is the plate's answer to a jump: the start located to half a sample at best, as a jump's
    if not dip and 0.5 <= JUMP_MAX_FRACTION * (e_u - s_u):
        return []
    why = (f"a sample of the front swings back below {100 * FAST_RING_ZERO:g} % of the peak after the force's jump "
           "(a swing as large as the jump)" if dip else
           f"the rise is the plate's answer to the force's jump, so the start is located to half a sample at best, "
           f"{100 * 0.5 / (e_u - s_u):.2g} % of TC ({e_u - s_u:.0f} samples)")
    seen = (f"the force {1e3 * (a - s_u) / fs:.2g}-{1e3 * (b - s_u) / fs:.2g} ms into the contact swings about a "
            f"smooth curve by {100 * rms / peak:.2g} % of the peak rms ({rms / noise:.3g} noise deviations), "
            f"alternating from sample to sample (about {period:.3g} samples a period, {fs / period / 1e3:.3g} kHz): "
            f"the plate rings from the force's jump, and {why}")
    if period >= OVERSHOOT_MIN_PERIOD:
        return [Problem(ProblemKind.PLATE_RINGING,
                        f"plate ringing near half the sample rate at the contact's front: {seen}; the start is not "
                        "known to 1 % of TC")]
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact start not determined to 1 %: {seen}; the plate rings near half the sample rate (or "
                    "above it, seen through its alias: not undone) (sample faster)")]


def _front_dip(x, fs, peak, s_u, e_u):
    """A sample of the contact's front back near zero after the force's jump: the start not determined.

    The ball's force, once it has jumped from zero (section 3.2.4 in Goodwill & Haake 2004), does not return to zero
    before the ball leaves: at buckling it drops by about half (section 3.2). A sample of the front (from
    FRONT_PRE_SAMPLES before the start found, which may come after such a dip, to BUCKLING_TIME_S and
    FRONT_DIP_AFTER_SAMPLES after it) below FRONT_DIP_ZERO of the peak after one above
    FRONT_DIP_JUMPED of it is a swing as large as the jump: a negative electrical spike where the force's curve
    breaks (which :func:`remove_spikes` cannot tell from the jump) or a plate's swing, and the samples do not say
    which of the samples around it the force starts at. Zoo trace 33:674's rig with a -1.5 V spike on the jump's
    second or third sample was ok with TC -1.2 and +1.0 % (tests/test_robustness.py). :func:`_start_on_fast_ringing`
    names the plate's swing where it sees its ringing; this check runs where it did not.
    """
    k0, k1 = int(math.ceil(s_u)), int(math.floor(e_u))
    a = max(k0 - FRONT_PRE_SAMPLES, 0)  # and the samples just before it: the start may be found after such a dip
    b = min(k0 + int(math.ceil(BUCKLING_TIME_S * fs)) + FRONT_DIP_AFTER_SAMPLES, k1, x.size - 1)
    if not peak > 0 or k0 < 0 or b <= k0:
        return []
    front = x[a:b + 1]
    jumped = np.flatnonzero(front > FRONT_DIP_JUMPED * peak)
    if not jumped.size:
        return []
    j = int(jumped[0]) + int(np.argmin(front[jumped[0]:]))
    if not front[j] < FRONT_DIP_ZERO * peak:
        return []
    return [Problem(ProblemKind.CONTACT_END_UNDETERMINED,
                    f"contact start not determined: {1e3 * (a + j - s_u) / fs:+.2g} ms from it a sample falls back to "
                    f"{100 * front[j] / peak:.2g} % of the peak after one at {100 * front[jumped[0]] / peak:.2g} % "
                    "(no ball's force returns to zero before it leaves): a negative electrical spike or a plate's "
                    "swing, and the force may start on either side of it")]


def _negative_force(x, fs, noise, peak, end_u):
    """A pull on the plate after the contact: the plate's own motion (or a wrong baseline), never the ball's force.

    A ball only pushes. After it has left, a plate with a resonance near the
    contact's frequencies swings back below zero (its free response; a heavily
    damped plate still undershoots once), and the same resonance has shaped the
    force during the contact, so neither TC nor the peak can be trusted. The
    corrected signal in the NEGATIVE_WINDOW_S after the contact end, averaged
    over NEGATIVE_SMOOTH_S, must not fall below zero by more than
    NEGATIVE_FRACTION of the peak and NEGATIVE_SIGMA standard errors.
    """
    k = max(int(round(NEGATIVE_SMOOTH_S * fs)), 1)
    a = int(math.ceil(end_u))
    b = min(a + int(round(NEGATIVE_WINDOW_S * fs)), x.size)
    if b - a < k:
        return []
    avg = np.convolve(x[a:b], np.ones(k) / k, mode="valid")
    i = int(np.argmin(avg))
    low = -float(avg[i])
    se = noise / math.sqrt(k)
    if low > NEGATIVE_FRACTION * peak and low > NEGATIVE_SIGMA * se:
        return [Problem(ProblemKind.NEGATIVE_FORCE,
                        f"force below zero after the contact: {100 * low / peak:.2g} % of the peak "
                        f"({low / se if se > 0 else math.inf:.3g} "
                        f"noise deviations) {1e3 * (i + (k - 1) / 2) / fs:.2g} ms after its end; the plate rings (or "
                        "the baseline is wrong) and TC and the peak cannot be trusted")]
    return []


def _ringing_line(xc, fs, noise):
    """A plate resonance in the contact: (frequency [Hz], amplitude [V], prominence [-]) or None.

    The contact less a quartic (its smooth shape) is Hann-windowed and
    zero-padded 4x; the largest spectral amplitude between RING_LINE_MIN_HZ
    and 0.45 fs is a line when it exceeds RING_LINE_PROMINENCE times the median
    amplitude within a factor 1.6 of its frequency (the smooth contact and the
    noise have no lines), and RING_LINE_NOISE_FACTOR times the amplitude white
    noise gives a bin (``1.73 noise / sqrt(n)`` with the Hann window). The
    force's own spectrum falls steeply with frequency (as f^-2 to f^-4): one
    of its side lobes just above RING_LINE_MIN_HZ stands out of the quieter
    frequencies above it only. A bump that does not stand out of the median
    below it alone and is below RING_LINE_EDGE_FRACTION of the peak is not
    taken for a line (ideal-plate zoo traces: 0.007-0.023 % of the peak at
    3.0-3.4 kHz).
    """
    n = xc.size
    if n < MIN_CONTACT_SAMPLES:
        return None
    u = np.linspace(-1.0, 1.0, n)
    r = xc - np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyfit(u, xc, 4))
    w = np.hanning(n)
    nfft = 4 * n
    amp = 2.0 * np.abs(np.fft.rfft(r * w, nfft)) / w.sum()
    f = np.fft.rfftfreq(nfft, 1.0 / fs)
    band = np.flatnonzero((f > RING_LINE_MIN_HZ) & (f < NYQUIST_MARGIN * fs))
    if band.size < 10:
        return None
    k = int(band[np.argmax(amp[band])])
    lo, hi = np.searchsorted(f, [f[k] / 1.6, f[k] * 1.6])
    below, above = amp[lo:max(k - 12, lo)], amp[k + 12:hi]
    ref = np.concatenate([below, above])
    if ref.size < 8:
        return None
    prominence = float(amp[k] / max(np.median(ref), 1e-300))
    if prominence <= RING_LINE_PROMINENCE or amp[k] <= RING_LINE_NOISE_FACTOR * 1.73 * noise / math.sqrt(n):
        return None
    if below.size >= RING_LINE_SIDE_BINS and amp[k] <= RING_LINE_PROMINENCE * float(np.median(below)) \
            and amp[k] < RING_LINE_EDGE_FRACTION * float(np.max(xc)):
        return None  # a tiny bump on the force's own spectrum, which falls steeply above the band's edge
    return float(f[k]), float(amp[k]), prominence


def _choose_tau(tau_s, fit: _BaselineFit, integral: float, duration_s: float, scale: float):
    """Time constant for the decay correction, its source, the warnings to give and the problems found.

    A significant positive kappa gives tau = 1 / kappa (applying a noisy tau is
    unbiased; skipping it is not). A kappa that is not measurable is applied as
    found when positive (0 otherwise); the impact is a problem when the decay
    hidden in the noise could bias the impulse by more than
    BIAS_EXCLUDE_FRACTION, and a warning is given above BIAS_WARN_FRACTION.
    """
    if tau_s is not None:
        return float(tau_s), "given", [], []
    if not fit.has_post:
        msg = f"charge-amplifier decay not corrected: {fit.no_post or 'no quiet baseline to measure the undershoot'}"
        return math.inf, "none", [msg], [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg + " (give plate.time_constant_s)")]
    kappa, se = fit.kappa, fit.kappa_se
    undershoot = kappa * integral
    messages, problems = [], []
    if kappa < -UNDERSHOOT_SIGNIFICANCE * se:
        msg = (f"charge-amplifier decay not corrected: the baseline after the contact is "
               f"{-undershoot * scale * 1e3:.3g} mV above the one before it (expected an undershoot)")
        return math.inf, "none", [msg], [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg)]
    if integral > 0 and UNDERSHOOT_SIGNIFICANCE * se > abs(kappa):
        # how much could a decay hidden in the noise change the impulse?
        bias = duration_s * UNDERSHOOT_SIGNIFICANCE * se / 2.0
        if bias > BIAS_WARN_FRACTION:
            msg = (f"charge-amplifier undershoot not measurable ({undershoot * scale * 1e3:.3g} "
                   f"+/- {se * integral * scale * 1e3:.2g} mV): "
                   f"the impulse may be off by up to {bias * 100:.2g} %")
            messages.append(msg)
            if bias > BIAS_EXCLUDE_FRACTION:
                problems.append(Problem(ProblemKind.UNDERSHOOT_NOT_MEASURABLE, msg))
    if not (integral > 0 and kappa > 0):
        return math.inf, "none", messages, problems
    tau = 1.0 / kappa
    if tau > TAU_BOUNDS_S[1]:
        return math.inf, "none", messages, problems  # DC-coupled in effect: the correction is negligible
    if tau < TAU_BOUNDS_S[0]:
        msg = (f"charge-amplifier decay not corrected: estimated time constant {tau:.3g} s is below "
               f"the plausible {TAU_BOUNDS_S[0]:g} s (a baseline shift that is not the amplifier's decay?)")
        return math.inf, "none", messages + [msg], problems + [Problem(ProblemKind.DECAY_NOT_CORRECTED, msg)]
    return tau, "estimated", messages, problems


def _result(x, fit: _BaselineFit, tau, source, contact, n_iter, messages, problems, t0_s, scale, spikes, mains,
            mains_source, contact_integral=math.nan, plate=None):
    """Assemble the ConditionedSignal, back in volts."""
    coef = dict(fit.coef)
    coef["offset_V"] = coef["offset_V"] * scale
    coef["drift_V_per_s"] = coef["drift_V_per_s"] * scale
    for key in ("hum_cos_V", "hum_sin_V"):
        coef[key] = tuple(c * scale for c in coef[key])
    has_hum = bool(fit.hum_amplitudes)
    coef["mains_hz"] = float(mains) if has_hum else 0.0
    coef["mains_source"] = mains_source if has_hum or mains_source == "given" else "none"
    contact = replace(contact, peak_V=contact.peak_V * scale, noise_rms_V=contact.noise_rms_V * scale,
                      threshold_V=contact.threshold_V * scale)
    estimated = fit.has_post and math.isfinite(fit.kappa) and math.isfinite(contact_integral)
    undershoot = fit.kappa * contact_integral * scale if estimated else math.nan
    undershoot_se = fit.kappa_se * abs(contact_integral) * scale if estimated else math.nan
    with np.errstate(over="ignore"):
        return ConditionedSignal(
            voltage_V=x * scale,
            noise_rms_V=float(fit.noise * scale),
            hum_amplitude_V=float(fit.hum_amplitudes[0] * scale) if fit.hum_amplitudes else 0.0,
            hum_harmonic_amplitudes_V=tuple(a * scale for a in fit.hum_amplitudes),
            tau_s=float(tau),
            tau_source=source,
            undershoot_V=float(undershoot),
            undershoot_se_V=float(undershoot_se),
            offset_V=float(coef["offset_V"]),
            baseline_V=fit.baseline * scale,
            baseline_coefficients=coef,
            contact=contact,
            n_iterations=int(n_iter),
            warnings=tuple(messages),
            problems=tuple(dict.fromkeys(problems)),
            spike_indices=tuple(int(i) for i in spikes),
            plate=plate,
        )

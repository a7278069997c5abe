"""The exact undone force's peak read from local fits: does a low-pass of the undone force hide its peak."""

from __future__ import annotations

import math

import numpy as np

from ..model import BUCKLING_TIME_S
from .contact import ContactResult
from .plate import PlateResonance
from .undo import undone_impulse_response, undone_noise_gain

__all__ = ["lowpass_hides_peak"]

PLATE_LOWPASS_PEAK = 0.01  # ... and lower the peak by at most this fraction (from its curvature there) [-]
PLATE_PEAK_SIGMA = 3.0  # the exact undone force's largest sample this many of its noise deviations ... [-]
PLATE_LOWPASS_SPIKE = 0.04  # ... above the low-passed peak: lost; the check must see a loss of this fraction [-]
PEAK_FIT_S = 0.2e-3  # the exact undone force read at each sample from a quadratic fit over this long around it [s]
PEAK_FIT_RAMP_SAMPLES = 2  # ... up to it on the pre-buckling ramp: BUCKLING_TIME_S and this long after it [samples]
PEAK_FIT_MIN = 6  # ... of at least this many samples [samples]
PEAK_FIT_SIGMA = 3.0  # ... when its residual exceeds its expectation by at most this many of its deviations [-]
PEAK_FIT_IMPULSE_HALF = 64  # the plate's inverse's impulse response kept this far each side for the fits [samples]
PEAK_FIT_NOISE = 1.0  # the sensed noise raised by the centred fits' median residual over its expectation, from this [-]


def lowpass_hides_peak(exact, fs, noise, plate: PlateResonance, contact: ContactResult, t0_s) -> str | None:
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
    """The exact undone force read from fits at each sample of ``exact[i0:i1]`` for :func:`lowpass_hides_peak`:
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

"""Units and long names of every variable of the session archive (CF-style unit strings)."""

from __future__ import annotations

__all__ = ["AK_UNITS", "VARIABLE_ATTRS"]

#: AK's unit: kN m-(1+a), where a is the stiffness exponent of the same ball (no UDUNITS form).
AK_UNITS = "kN m-(1+a)"
_AK_UNITS = AK_UNITS

#: units and long_name of every archive variable (CF-style unit strings).
VARIABLE_ATTRS: dict[str, tuple[str, str]] = {
    # coordinates
    "impact_id": ("1", "impact identifier from the raw impacts.csv"),
    "ball": ("1", "ball type key from session.yaml"),
    "speed_m_s": ("m s-1", "inbound speed of the model curves"),
    "model_time_s": ("s", "time since first contact of the modelled 20 m/s impact"),
    "stiffness_x_m": ("m", "centre-of-mass displacement of the stiffness curve"),
    # per impact
    "ball_type": ("1", "ball type key of the impact"),
    "status": ("1", "processing status: ok or excluded"),
    "reason": ("1", "why the impact was excluded (empty when ok)"),
    "trace_file": ("1", "trace file path relative to the session folder"),
    "trace_sha256": ("1", "SHA-256 digest of the trace file"),
    "vin_m_s": ("m s-1", "inbound ball speed VB at the plate (the gate speed unless gates.distance_to_plate_m is given)"),
    "vout_m_s": ("m s-1", "rebound ball speed VB' at the plate (the gate speed unless gates.distance_to_plate_m is given)"),
    "vin_gate_m_s": ("m s-1", "inbound ball speed from the light gates, spacing / interval"),
    "vout_gate_m_s": ("m s-1", "rebound ball speed from the light gates, spacing / interval"),
    "cor": ("1", "coefficient of restitution VB'/VB"),
    "contact_time_ms": ("ms", "contact time TC"),
    "kcal_N_per_V": ("N V-1", "force-plate calibration factor kCAL of this impact"),
    "impulse_N_s": ("N s", "impulse m (VB + VB')"),
    "peak_force_N": ("N", "peak calibrated force"),
    "time_to_peak_ms": ("ms", "time from contact start to peak force"),
    "max_displacement_mm": ("mm", "largest centre-of-mass displacement during contact"),
    "kv_stiffness_kN_m": ("kN m-1", "Kelvin-Voigt stiffness kB = m pi^2 / TC^2 (Eq. 2)"),
    "kv_damping_N_s_m": ("N s m-1", "Kelvin-Voigt damping cB = -2 m ln(COR) / TC (Eq. 3)"),
    "impact_mass_kg": ("kg", "ball mass used for this impact"),
    "sample_rate_hz": ("Hz", "sample rate of the trace"),
    "noise_rms_V": ("V", "noise standard deviation of the trace's quiet baseline (robust)"),
    "hum_amplitude_V": ("V", "peak amplitude of the mains hum's fundamental removed (0 when none was fitted)"),
    "mains_frequency_hz": ("Hz", "mains frequency whose hum was removed (0 when none was)"),
    "mains_source": ("1", "where the mains frequency came from: given (daq.mains_hz), detected or none"),
    "peak_note": ("1", "why peak_force_N and time_to_peak_ms are withheld (NaN) on an ok impact: a problem of the "
                       "peak alone, with an alias and a rounded front ruled out (daq.bandwidth_hz, or sampled at "
                       "60 kHz or faster); else empty"),
    "contact_time_u_ms": ("ms", "standard uncertainty of TC, from its error budget"),
    "kcal_u_N_per_V": ("N V-1", "standard uncertainty of kCAL, from its error budget"),
    "peak_force_u_N": ("N", "standard uncertainty of the peak force, from its error budget"),
    "cor_u": ("1", "standard uncertainty of COR, from the gate timer's resolution"),
    "contact_time_status": ("1", "ok, or withheld when TC's budget exceeds 1 % or a finding cannot bound it"),
    "kcal_status": ("1", "ok, or withheld when kCAL's budget exceeds 1 % or a finding cannot bound it"),
    "peak_status": ("1", "ok, or withheld when the peak's budget exceeds 3 % (5 % spike) or kCAL is withheld"),
    "cor_status": ("1", "ok, or withheld when COR's budget exceeds 0.002"),
    "reason_code": ("1", "codes of the findings that withheld or excluded something (docs/checks.md), ;-separated"),
    "withheld_note": ("1", "on an ok impact, why each withheld quantity is withheld; else empty"),
    "check": ("1", "code of a check of the registry (docs/checks.md)"),
    "finding_count": ("1", "how many findings of this check this impact has (0: none)"),
    "finding_message": ("1", "the first finding's message (empty: none)"),
    "finding_effect_contact_time": ("1", "largest relative effect on TC the check estimated (NaN: none or unknown)"),
    "finding_effect_kcal": ("1", "largest relative effect on kCAL the check estimated (NaN: none or unknown)"),
    "finding_effect_peak": ("1", "largest relative effect on the peak the check estimated (NaN: none or unknown)"),
    "amplifier_time_constant_s": (
        "s", "charge-amplifier time constant whose decay was undone (NaN when none was: see its source)"),
    "amplifier_time_constant_se_s": (
        "s", "standard error of the time constant estimated from the trace, from the noise (and its correlation "
             "over 2 ms) and the contact's sampling (not the choice of hum model on a record of about a mains "
             "period); NaN when given or none"),
    "amplifier_time_constant_source": (
        "1", "where the time constant came from: given (plate.time_constant_s), estimated or none"),
    "plate_resonance_hz": ("Hz", "plate resonance identified from its ringing and undone (NaN when none was)"),
    "plate_damping_ratio": ("1", "damping ratio of the plate resonance undone (NaN when none was)"),
    # v1.2: the session's rig (ballimpact.rig), one value per quantity of ballimpact.rig.RIG_QUANTITIES
    "rig_quantity": ("1", "a quantity of the session's rig (ballimpact.rig.RIG_QUANTITIES)"),
    "rig_value": ("1", "the rig quantity's value for the whole session, in rig_unit (NaN: not known); its "
                       "attributes: plate_detection_z and plate_ringing_fraction of the plate's pooled fit, "
                       "plate_impacts (the impacts whose free ringing it pooled, comma-separated) and rig_warnings "
                       "(JSON list: stated keys the traces disagree with)"),
    "rig_low": ("1", "lower end of its 95 % interval, in rig_unit (the value itself when stated)"),
    "rig_high": ("1", "upper end of its 95 % interval, in rig_unit (the value itself when stated)"),
    "rig_source": ("1", "stated (session.yaml), identified (pooled over the session's impacts) or none"),
    "rig_n_impacts": ("1", "impacts the identification rests on"),
    "rig_unit": ("1", "unit of rig_value, rig_low and rig_high"),
    "rig_note": ("1", "why a rig quantity is not known, or what the traces gave beside a stated value"),
    "model_agreement_fraction": (
        "1",
        "share of the contact after 0.2 ms where the fitted model force is within 10 % of the measured peak",
    ),
    "model_rms_N": ("N", "RMS difference between fitted model and measured force over the contact"),
    "used_in_fit": ("1", "1 when this ok impact was used in its ball type's fit, 0 otherwise"),
    "fit_note": ("1", "why an ok impact was left out of the fit (fit outlier: its residuals and the test), else empty"),
    # series (impact, sample)
    "time_s": ("s", "time since contact start"),
    "voltage_V": ("V", "force-plate voltage over the contact (conditioned, polarity applied)"),
    "force_N": ("N", "calibrated contact force on the ball"),
    "velocity_m_s": ("m s-1", "ball centre-of-mass velocity towards the plate"),
    "displacement_m": ("m", "ball centre-of-mass displacement towards the plate"),
    "model_force_N": ("N", "fitted improved-model force at this impact's inbound speed (Eq. 14)"),
    "kv_force_N": ("N", "Kelvin-Voigt model force of this impact (Eqs. 1-3)"),
    # raw (impact, raw_sample)
    "raw_time_s": ("s", "time of the raw sample, from contact start when found, else from the first sample"),
    "raw_voltage_V": ("V", "raw trace voltage, polarity applied"),
    # per ball
    "ball_label": ("1", "ball label for figures"),
    "mass_kg": ("kg", "ball type mass used in the fit"),
    "n_impacts": ("1", "number of impacts used in the fit"),
    "kb0_kN_m": ("kN m-1", "stiffness at zero displacement kB(0) (Eq. 4)"),
    "kb0_source": ("1", "origin of kB(0): config or extrapolated"),
    "kb0_lo": ("kN m-1", "lower end of the 95 % interval of kB(0)"),
    "kb0_hi": ("kN m-1", "upper end of the 95 % interval of kB(0)"),
    "ak_kN_m": (_AK_UNITS, "stiffness coefficient AK, x in metres (Eq. 4)"),
    "ak_lo": (_AK_UNITS, "lower end of the 95 % interval of AK"),
    "ak_hi": (_AK_UNITS, "upper end of the 95 % interval of AK"),
    "a": ("1", "stiffness exponent a (Eq. 4)"),
    "a_lo": ("1", "lower end of the 95 % interval of a"),
    "a_hi": ("1", "upper end of the 95 % interval of a"),
    "ac_kN_s_m3": ("kN s m-3", "damping area constant AC (Eq. 7)"),
    "ac_lo": ("kN s m-3", "lower end of the 95 % interval of AC"),
    "ac_hi": ("kN s m-3", "upper end of the 95 % interval of AC"),
    "ak_a_correlation": ("1", "correlation between the AK and a estimates"),
    "contact_time_rmse_pct": ("percent", "relative RMS contact-time residual over the impacts used"),
    "cor_rmse_pct": ("percent", "relative RMS COR residual over the impacts used"),
    "fit_message": ("1", "fit status message"),
    "kb_10mm_kN_m": ("kN m-1", "structural stiffness kB at 10 mm displacement, kB(0) + AK x^a (Eq. 4)"),
    "kb_10mm_lo": ("kN m-1", "lower end of the 95 % interval of kB(10 mm)"),
    "kb_10mm_hi": ("kN m-1", "upper end of the 95 % interval of kB(10 mm)"),
    "kb_20mm_kN_m": ("kN m-1", "structural stiffness kB at 20 mm displacement, kB(0) + AK x^a (Eq. 4)"),
    "kb_20mm_lo": ("kN m-1", "lower end of the 95 % interval of kB(20 mm)"),
    "kb_20mm_hi": ("kN m-1", "upper end of the 95 % interval of kB(20 mm)"),
    "contact_time_scatter_pct": ("percent", "relative scatter of the impacts about the fitted TC curve (unbiased)"),
    "cor_scatter_pct": ("percent", "relative scatter of the impacts about the fitted COR curve (unbiased)"),
    "bootstrap_dropped": ("1", "bootstrap resamples dropped (refit not converged)"),
    "n_fit_outliers": ("1", "ok impacts of the ball type left out of the fit as fit outliers"),
    "interval_method": ("1", "how the 95 % intervals were obtained"),
    "paper_kb0_kN_m": ("kN m-1", "kB(0) of Table 2 in Goodwill & Haake 2004"),
    "paper_ak_kN_m": (_AK_UNITS, "AK of Table 2 in Goodwill & Haake 2004"),
    "paper_a": ("1", "a of Table 2 in Goodwill & Haake 2004"),
    "paper_ac_kN_s_m3": ("kN s m-3", "AC of Table 2 in Goodwill & Haake 2004"),
    "fit_vin_min_m_s": ("m s-1", "slowest inbound speed of the impacts used in the fit (model curves below: extrapolated)"),
    "fit_vin_max_m_s": ("m s-1", "fastest inbound speed of the impacts used in the fit (model curves above: extrapolated)"),
    "itf_impact_speed_m_s": ("m s-1", "impact speed of the ITF 254 cm drop test, with air drag on the fall"),
    "itf_model_cor": ("1", "fitted model COR at the ITF drop-test impact speed"),
    "itf_rebound_pred_cm": ("cm", "ITF 254 cm drop-test rebound predicted by the fitted model, with air drag"),
    "itf_rebound_pred_cm_lo": ("cm", "lower end of the 95 % bootstrap interval of the predicted ITF rebound"),
    "itf_rebound_pred_cm_hi": ("cm", "upper end of the 95 % bootstrap interval of the predicted ITF rebound"),
    "itf_rebound_cm": ("cm", "measured ITF 254 cm drop-test rebound from session.yaml (NaN when not given)"),
    "itf_drop_test_cor": ("1", "COR of the measured ITF drop test (rebound and fall with air drag)"),
    # model curves (ball, speed)
    "model_contact_time_ms": ("ms", "fitted model contact time"),
    "model_contact_time_ms_lo": ("ms", "lower end of the 95 % band of the model contact time"),
    "model_contact_time_ms_hi": ("ms", "upper end of the 95 % band of the model contact time"),
    "model_cor": ("1", "fitted model coefficient of restitution"),
    "model_cor_lo": ("1", "lower end of the 95 % band of the model COR"),
    "model_cor_hi": ("1", "upper end of the 95 % band of the model COR"),
    "model_peak_force_N": ("N", "fitted model peak force"),
    "model_contact_time_ms_pred_lo": ("ms", "lower end of the 95 % prediction band of one impact's contact time"),
    "model_contact_time_ms_pred_hi": ("ms", "upper end of the 95 % prediction band of one impact's contact time"),
    "model_cor_pred_lo": ("1", "lower end of the 95 % prediction band of one impact's COR"),
    "model_cor_pred_hi": ("1", "upper end of the 95 % prediction band of one impact's COR"),
    # components (ball, model_time)
    "comp_total_force_N": ("N", "total model force at 20 m/s (Eq. 14)"),
    "comp_stiffness_force_N": ("N", "structural stiffness force kB x at 20 m/s"),
    "comp_damping_force_N": ("N", "material damping force cB x' at 20 m/s"),
    "comp_momentum_flux_force_N": ("N", "momentum flux force cM x' at 20 m/s"),
    "comp_displacement_m": ("m", "model centre-of-mass displacement at 20 m/s"),
    # stiffness curve (ball, stiffness_x)
    "model_stiffness_kN_m": ("kN m-1", "fitted structural stiffness kB(x) (Eq. 4)"),
}

"""A session made by hand, the way a new user would make one: half-sine pulses from numpy, as CSV, TDMS and LVM.

Independent of ``ballimpact.synth``: the voltages come from :mod:`tracekit` (a half-sine force through
an independent model of the charge amplifier and ADC), the files are written here in the formats a DAQ
writes (a CSV with a ``# sample_rate_hz`` header, TDMS with DAQmx's int16 raw samples and linear scale
properties, LabVIEW's Measurement text format), and the gate times follow from the chosen speeds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from tracekit import make_trace, shape_integral

SAMPLE_RATE_HZ = 50_000.0  # [Hz] the DAQ's true rate
KCAL_N_PER_V = 250.0  # [N/V] the true calibration factor
MASS_G = 57.5  # [g] ball mass
GATE_SPACING_M = 0.1  # [m]
HALF_SINE_S = 4.3e-3  # [s] contact time of every pulse
ADC_RANGE_V = (-10.0, 10.0)  # [V]


@dataclass
class HandmadeSpec:
    """What goes into a hand-made session.

    Attributes
    ----------
    formats : list of str
        One trace per impact, "csv", "tdms" or "lvm".
    header_rates_hz : dict
        impact index -> the sample rate [Hz] its file claims (a wrong header); others claim the true rate.
    polarity_yaml : int
        plate.polarity written to session.yaml; the pulses are positive.
    gate_scale : float
        Factor on the gate times (1000: written in ms).
    extra_top : dict
        Further top-level keys of session.yaml (e.g. a misspelt one).
    balls : tuple of str
        Ball types; the impacts go round them.
    """

    formats: list = field(default_factory=lambda: ["csv", "csv", "tdms", "csv", "lvm", "tdms", "csv"])
    header_rates_hz: dict = field(default_factory=lambda: {3: 25_000.0})
    polarity_yaml: int = 1
    gate_scale: float = 1.0
    extra_top: dict = field(default_factory=dict)
    balls: tuple = ("yellow",)
    bandwidth_hz: float | None = None


def _speeds(i: int) -> tuple[float, float]:
    """Inbound [m/s] and rebound [m/s] speed of impact i."""
    vin = 14.0 + 3.0 * i
    return vin, (0.72 - 0.006 * vin) * vin


def _voltage(i: int, vin: float, vout: float) -> np.ndarray:
    """The recorded voltage [V] of impact i: a half-sine of HALF_SINE_S for m (vin + vout) at KCAL_N_PER_V."""
    impulse_N_s = MASS_G * 1e-3 * (vin + vout)
    peak_V = impulse_N_s / (KCAL_N_PER_V * shape_integral(HALF_SINE_S))
    v, _, _ = make_trace(sample_rate_hz=SAMPLE_RATE_HZ, half_sine_s=HALF_SINE_S, cloth_s=0.0, peak_V=peak_V,
                         pre_s=0.020, post_s=0.060, tau_s=2.0, offset_V=0.03, noise_V=0.001, hum_V=0.0,
                         mass_kg=MASS_G * 1e-3, vin_m_s=vin, cor=vout / vin, seed=100 + i)
    return v


def write_csv(path: Path, voltage: np.ndarray, rate_hz: float) -> None:
    """A CSV trace with a ``# sample_rate_hz`` header [Hz]."""
    body = "\n".join(f"{x:.6f}" for x in voltage)
    path.write_text(f"# sample_rate_hz: {rate_hz:g}\n# units: V\nvoltage_V\n{body}\n", encoding="utf-8")


def write_tdms_daqmx(path: Path, voltage: np.ndarray, rate_hz: float) -> None:
    """A TDMS trace as DAQmx logs one: int16 ADC codes with linear scale properties, wf_increment [s]."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    lo, hi = ADC_RANGE_V
    slope = (hi - lo) / 2**16  # [V] per code
    codes = np.clip(np.round(voltage / slope), -(2**15), 2**15 - 1).astype(np.int16)
    properties = {
        "wf_increment": 1.0 / rate_hz, "wf_start_offset": 0.0, "wf_samples": int(codes.size),
        "unit_string": "V", "NI_ChannelName": "Dev1/ai0",
        "NI_Number_Of_Scales": np.uint32(2), "NI_Scaling_Status": "unscaled",
        "NI_Scale[1]_Scale_Type": "Linear", "NI_Scale[1]_Linear_Slope": slope,
        "NI_Scale[1]_Linear_Y_Intercept": 0.0, "NI_Scale[1]_Linear_Input_Source": np.uint32(0xFFFFFFFF),
    }
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject({"name": "impact"}), GroupObject("Dev1"),
                              ChannelObject("Dev1", "Dev1/ai0", codes, properties=properties)])


def write_lvm(path: Path, voltage: np.ndarray, rate_hz: float, *, x_column: bool = True,
              decimal: str = ".") -> None:
    """A LabVIEW Measurement file (Writer_Version 2, one channel, tab-separated), Delta_X = 1/rate [s]."""
    dx = f"{1.0 / rate_hz:.7E}".replace(".", decimal)
    header = [
        "LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
        f"Decimal_Separator\t{decimal}", "Multi_Headings\tNo", f"X_Columns\t{'One' if x_column else 'No'}",
        "Time_Pref\tRelative", "Operator\tlab", "Date\t2026/11/21", "Time\t10:15:02.5",
        "***End_of_Header***\t", "\t",
        "Channels\t1\t", f"Samples\t{voltage.size}\t", "Date\t2026/11/21\t", "Time\t10:15:02.5\t",
        "Y_Unit_Label\tVolts\t", "X_Dimension\tTime\t", "X0\t0.0000000000000000E+0\t".replace(".", decimal),
        f"Delta_X\t{dx}\t", "***End_of_Header***\t",
        "X_Value\tVoltage\tComment" if x_column else "X_Value\tVoltage\tComment",
    ]
    rows = []
    for k, v in enumerate(voltage):
        value = f"{v:.6f}".replace(".", decimal)
        x = f"{k / rate_hz:.6f}".replace(".", decimal)
        rows.append(f"{x}\t{value}" if x_column else f"\t{value}")
    path.write_text("\r\n".join(header + rows) + "\r\n", encoding="utf-8")


WRITERS = {"csv": write_csv, "tdms": write_tdms_daqmx, "lvm": write_lvm}


def write_session(folder, spec: HandmadeSpec | None = None) -> Path:
    """
    Write a hand-made session folder (its name is the session id).

    Parameters
    ----------
    folder : path-like
        The session folder to create.
    spec : HandmadeSpec, optional
        What goes in; the default is the session of issue 49 (seven traces, a 25 kHz header among them).

    Returns
    -------
    pathlib.Path
        The folder.
    """
    spec = spec or HandmadeSpec()
    out = Path(folder)
    (out / "traces").mkdir(parents=True, exist_ok=True)
    rows = ["impact_id,ball,trace,gate_in_1_s,gate_in_2_s,gate_out_2_s,gate_out_1_s"]
    for i, kind in enumerate(spec.formats):
        vin, vout = _speeds(i)
        rel = f"traces/shot{i + 1:02d}.{kind}"
        WRITERS[kind](out / rel, _voltage(i, vin, vout), spec.header_rates_hz.get(i, SAMPLE_RATE_HZ))
        t_in_1 = 10.0 + 7.0 * i
        t_in_2 = t_in_1 + GATE_SPACING_M / vin
        t_out_2 = t_in_2 + 0.012
        t_out_1 = t_out_2 + GATE_SPACING_M / vout
        gates = ",".join(f"{spec.gate_scale * t:.7f}" for t in (t_in_1, t_in_2, t_out_2, t_out_1))
        rows.append(f"shot{i + 1:02d},{spec.balls[i % len(spec.balls)]},{rel},{gates}")
    (out / "impacts.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    daq = {"sample_rate_hz": SAMPLE_RATE_HZ, "adc_range_v": list(ADC_RANGE_V)}
    if spec.bandwidth_hz is not None:
        daq["bandwidth_hz"] = spec.bandwidth_hz
    doc = {
        "session_id": out.name, "date": "2026-11-21", "operator": "new user",
        "plate": {"polarity": spec.polarity_yaml}, "daq": daq,
        "gates": {"spacing_m": GATE_SPACING_M, "resolution_s": 1e-6},
        "balls": {key: {"mass_g": MASS_G} for key in spec.balls},
        **spec.extra_top,
    }
    (out / "session.yaml").write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return out


def true_contact_time_ms() -> float:
    """TC of every pulse [ms]."""
    return HALF_SINE_S * 1e3


def true_speed(i: int) -> tuple[float, float]:
    """Inbound and rebound speed [m/s] of impact i."""
    return _speeds(i)


"""The ballimpact command line."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from numpy.testing import assert_allclose

from ballimpact.cli import main

BALLIMPACT = [str(Path(sys.executable).parent / "ballimpact")]
BALL1 = ["--mass-g", "57.7", "--kb0", "21", "--ak", "16000", "--a", "1.65", "--ac", "3.5"]


def test_simulate_json_keys_and_sanity_figures(capsys):
    assert main(["simulate", *BALL1, "--vin", "20", "--vin", "28", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [set(r) for r in rows] == [{"vin_m_s", "contact_time_ms", "cor", "peak_force_N", "max_displacement_mm"}] * 2
    # README / docs/model.md check values for ball 1 at 20 m/s, to the rounding of the printed
    # figures (half a unit of the last digit)
    for key, value, atol in [("contact_time_ms", 3.72, 0.005), ("cor", 0.631, 0.0005), ("peak_force_N", 844, 0.5),
                             ("max_displacement_mm", 18.6, 0.05)]:
        assert_allclose(rows[0][key], value, rtol=0, atol=atol, err_msg=key)
    assert rows[1]["contact_time_ms"] < rows[0]["contact_time_ms"]


def test_simulate_table_output(capsys):
    assert main(["simulate", *BALL1, "--vin", "20"]) == 0
    out = capsys.readouterr().out
    assert "TC [ms]" in out and "20.00" in out


@pytest.mark.parametrize("bad, message", [("-3", "expected a positive number, got '-3'"),
                                          ("abc", "expected a number, got 'abc'")])
def test_simulate_rejects_bad_speed(bad, message, capsys):
    with pytest.raises(SystemExit):
        main(["simulate", *BALL1, "--vin", bad])
    assert message in capsys.readouterr().err


def test_synth_then_validate_names_faulty_impacts(tmp_path):
    out = tmp_path / "raw" / "s1"
    r = subprocess.run([*BALLIMPACT, "synth", str(out), "--impacts-per-ball", "2", "--faults-per-kind", "1",
                        "--balls", "pressurised", "oversize"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([*BALLIMPACT, "validate", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "trace file not found" in r.stdout and "missing gate time" in r.stdout
    assert "pressurised" in r.stdout


def test_validate_session_fault_is_one_line_no_traceback(tmp_path):
    (tmp_path / "s").mkdir()
    r = subprocess.run([*BALLIMPACT, "validate", str(tmp_path / "s")], capture_output=True, text=True)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "session.yaml" in r.stderr and len(r.stderr.strip().splitlines()) == 1

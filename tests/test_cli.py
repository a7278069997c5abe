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
    # docs/accuracy.md / docs/model.md check values for ball 1 at 20 m/s, to the rounding of the printed
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


# ------------------------------------------------------------ simulate checks its inputs (issue 14)


@pytest.mark.parametrize(("option", "bad", "message"), [
    ("--mass-g", "0.0577", "the mass is in g and must be in (1, 1000) g, got '0.0577' (in kg? 0.0577 kg = 57.7 g)"),
    ("--vin", "200", "the inbound speed must be in 2-80 m/s, got '200'"),
    ("--vin", "0.5", "the inbound speed must be in 2-80 m/s, got '0.5'"),
    ("--ak", "0", "expected a positive number, got '0'"),
    ("--ac", "-3.5", "expected a positive number, got '-3.5'"),
    ("--kb0", "0", "expected a positive number, got '0'"),
])
def test_simulate_validates_like_validate(option, bad, message, capsys):
    args = {"--mass-g": "57.7", "--kb0": "21", "--ak": "16000", "--a": "1.65", "--ac": "3.5", "--vin": "20"}
    args[option] = bad
    with pytest.raises(SystemExit) as info:
        main(["simulate", *[x for kv in args.items() for x in kv]])
    assert info.value.code == 2
    assert message in capsys.readouterr().err


def test_simulate_warns_about_an_unusual_mass(capsys):
    assert main(["simulate", "--mass-g", "150", *BALL1[2:], "--vin", "20"]) == 0
    assert "warning: --mass-g 150 g is outside the usual 40-70 g" in capsys.readouterr().err


def test_every_synth_option_has_help(capsys):
    with pytest.raises(SystemExit):
        main(["synth", "--help"])
    out = capsys.readouterr().out
    for option in ("--seed", "--balls", "--params", "--impacts-per-ball", "--faults-per-kind", "--polarity",
                   "--format", "--sample-rate-hz", "--no-kb0"):
        block = out.split(option, 1)[1].split("\n  -", 1)[0]
        assert len(block.split()) > 3, (option, block)


def test_validate_prints_every_session_problem(tmp_path):
    folder = tmp_path / "s"
    folder.mkdir()
    (folder / "session.yaml").write_text("session_id: s\ndate: x\nplate: {polarity: 3}\n")
    (folder / "impacts.csv").write_text("impact_id;ball;trace\n")
    r = subprocess.run([*BALLIMPACT, "validate", str(folder)], capture_output=True, text=True)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert all(line.startswith("error: ") for line in lines) and len(lines) >= 5, lines
    for fragment in ("key 'date'", "plate.polarity", "missing required key 'daq'", "missing required key 'gates'",
                     "missing required key 'balls'", "impacts.csv: line 1: missing required column"):
        assert any(fragment in line for line in lines), (fragment, lines)


def test_itf_predicts_the_four_table2_balls_beside_table1(capsys):
    assert main(["itf", "--json"]) == 0
    rows = {r["ball"]: r for r in json.loads(capsys.readouterr().out)}
    assert set(rows) == {"pressurised", "pressureless", "oversize", "punctured"}
    # Table 1 of the paper, as printed
    assert [rows[k]["itf_rebound_cm"] for k in ("pressurised", "pressureless", "oversize", "punctured")] == \
        [138.9, 142.2, 137.4, 103.8]
    for r in rows.values():
        assert_allclose(r["difference_cm"], r["itf_rebound_pred_cm"] - r["itf_rebound_cm"], rtol=1e-12)
        assert 20 < r["difference_cm"] < 40  # the model over-predicts the drop test (tests/test_itf.py)
        assert 6.85 < r["impact_speed_m_s"] < 6.93


def test_itf_custom_ball_and_table_output(capsys):
    assert main(["itf", *BALL1, "--measured-cm", "138.9", "--air-density", "0"]) == 0
    out = capsys.readouterr().out
    assert "custom" in out and "138.9" in out and "pred [cm]" in out
    assert main(["itf", "--mass-g", "57.7"]) == 2
    assert "need all of" in capsys.readouterr().err


def test_synth_with_drag_writes_v1_1_flight_keys(tmp_path, capsys):
    import yaml

    out = tmp_path / "raw" / "drag"
    assert main(["synth", str(out), "--balls", "pressurised", "--impacts-per-ball", "2", "--faults-per-kind", "0",
                 "--drag", "--vertical", "--gate-to-plate-m", "0.3", "--vin-range", "5", "12"]) == 0
    doc = yaml.safe_load((out / "session.yaml").read_text())
    assert doc["gates"]["distance_to_plate_m"] == 0.3
    assert doc["rig"] == {"orientation": "vertical", "air_density_kg_m3": 1.2}
    assert doc["balls"]["pressurised"]["itf_rebound_cm"] == 138.9  # Table 1
    assert main(["synth", str(tmp_path / "raw" / "bad"), "--vin-range", "12", "5"]) == 2
    assert "vin_range_m_s must satisfy" in capsys.readouterr().err
    assert main(["synth", str(tmp_path / "raw" / "near"), "--drag", "--gate-to-plate-m", "0.05"]) == 2
    assert "flight_drag needs chain.gate_to_plate_m" in capsys.readouterr().err

"""The CSV tables: what impacts.csv and parameters.csv hold and how their numbers are written."""

from __future__ import annotations

import csv
import re
from decimal import Decimal

import numpy as np
import pandas as pd
import pytest

from archive_fixture import make_archive
from ballimpact.tables import impacts_table, parameters_table, write_csv


def _significant_digits(text: str) -> int:
    digits = Decimal(text).as_tuple().digits
    return len(str(int("".join(map(str, digits))))) if any(digits) else 1


def _cells(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    return rows


def test_numbers_are_written_to_what_the_measurement_supports(tmp_path):
    """Issue 49: the CSVs carried 12 significant digits (30.0030003 m/s, COR 0.518916394208)."""
    table = pd.DataFrame({"impact_id": ["a", "b"], "vin_m_s": [30.0030003, np.nan], "cor": [0.518916394208, 0.6],
                          "contact_time_ms": [3.61760232737, 4.0], "peak_force_N": [1411.46918104, 900.0]})
    write_csv(table, tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_text().splitlines() == [
        "impact_id,vin_m_s,cor,contact_time_ms,peak_force_N",
        "a,30.003,0.5189,3.618,1411.5",  # 1 mm/s, 1e-4, 1 us, 0.1 N
        "b,,0.6000,4.000,900.0",
    ]


@pytest.mark.parametrize("which", ["impacts", "parameters"])
def test_session_tables_hold_at_most_six_significant_digits_and_round_trip(tmp_path, which):
    ds = make_archive()
    table = impacts_table(ds) if which == "impacts" else parameters_table(ds)
    write_csv(table, tmp_path / "t.csv")
    rows = _cells(tmp_path / "t.csv")
    numeric = [c for c in table.columns if pd.api.types.is_float_dtype(table[c].dtype)]
    assert numeric
    for column in numeric:
        for k, row in enumerate(rows):
            text = row[column]
            if not text:
                assert not np.isfinite(table[column].iloc[k]), (column, k)
                continue
            assert _significant_digits(text) <= 6, (column, text)
            decimals = len(text.split(".")[1]) if "." in text and "e" not in text.lower() else 0
            half_unit = 0.5 * 10.0**-decimals if "e" not in text.lower() else 5e-6 * abs(float(text))
            assert abs(float(text) - table[column].iloc[k]) <= half_unit * (1 + 1e-9) + 1e-12, (column, text)
    assert re.search(r"\d\.\d{7,}", (tmp_path / "t.csv").read_text()) is None  # no long tails of digits

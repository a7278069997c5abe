"""Helpers shared by the tests that run Snakemake."""

from __future__ import annotations

import functools
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

from ballimpact.figure_registry import FIGURE_STEMS

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
SNAKEMAKE = BIN / "snakemake"
BALLIMPACT = BIN / "ballimpact"



@functools.cache
def bench_module(name: str):
    """The script bench/<name>.py, loaded as a module (once per test session)."""
    if str(REPO / "bench") not in sys.path:  # the scripts import their siblings (single_thread) as a run would
        sys.path.insert(0, str(REPO / "bench"))
    spec = importlib.util.spec_from_file_location(f"bench_{name}", REPO / "bench" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


FINAL_FIGURES = FIGURE_STEMS  # the PNG stems of every session, from the figure registry
IMPACTS_CSV_COLUMNS = [  # docs/outputs.md, in order
    "impact_id", "ball", "status", "reason", "vin_m_s", "vout_m_s", "cor", "contact_time_ms",
    "kcal_N_per_V", "impulse_N_s", "peak_force_N", "time_to_peak_ms", "max_displacement_mm",
    "kv_stiffness_kN_m", "kv_damping_N_s_m",
    "used_in_fit", "fit_note",  # v1.1
]

def run_snakemake(*args, cwd=REPO, check=None):
    """Run the venv's snakemake; returns the CompletedProcess (stdout + stderr merged).

    A dry run (``-n``) lists every job's details, which profiles/default leaves out of a run's output
    (``quiet: [rules]``): the tests read the plan from them.
    """
    if "-n" in args and "--quiet" not in args:
        args = (*args, "--quiet", "host")
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
    proc = subprocess.run(
        [str(SNAKEMAKE), *map(str, args)],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=1800,
    )
    if check is True:
        assert proc.returncode == 0, proc.stdout
    elif check is False:
        assert proc.returncode != 0, proc.stdout
    return proc

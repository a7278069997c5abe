"""One BLAS thread per process, for scripts and test runs that process many traces in one process."""

from __future__ import annotations

import os
import sys
import warnings

#: The variables OpenBLAS, OpenMP and MKL read, once, when numpy loads them (Snakemake sets the same per job).
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """Ask for one BLAS thread in this process, unless the environment already says how many.

    The per-impact processing solves many small least-squares problems (the baseline fit's normal equations: a
    few thousand quiet samples by about a dozen columns), which OpenBLAS's threads slow down: under load,
    ``process_impact`` took 116-132 ms per zoo trace with two threads and 61-64 ms with one (docs/performance.md,
    "One BLAS thread per process"). Snakemake already sets these variables to each job's ``threads`` (1 for
    every rule of this workflow); call this before numpy is first imported in a script or test run that
    processes traces in a loop. A value already in the environment wins.

    Warns (and changes nothing that matters) when numpy is already imported: the libraries read the variables
    when they are loaded.
    """
    if "numpy" in sys.modules:
        warnings.warn("one_blas_thread() called after numpy was imported: the BLAS thread count is already fixed",
                      stacklevel=2)
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")

"""One BLAS thread per process for the bench scripts that process traces: import this before numpy.

The per-impact processing multiplies small matrices (the baseline fit's normal equations: a few thousand quiet
samples by a dozen columns) thousands of times. OpenBLAS's threads cost more than they give there: on the
2-core machine under load, `pipeline.process_chunk` of a 40-impact synthetic session took 2.77 s CPU per run
with OpenBLAS's default threads and 1.07 s with one (README, Performance). Snakemake sets these variables to
each job's `threads` (1 for every rule here), and tests/conftest.py sets them for the suite; set them yourself
(before numpy is imported) to override.
"""

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

"""One BLAS thread per process for the bench scripts that process traces: import this before numpy.

See ``ballimpact.threads.one_blas_thread`` (a value already in the environment wins).
"""

from ballimpact.threads import one_blas_thread

one_blas_thread()

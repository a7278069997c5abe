"""CPU accounting of every Python process of a benchmarked run (bench/run.py, sessions benchmark).

bench/run.py puts this folder on PYTHONPATH and names a file in BALLIMPACT_BENCH_CPU_LOG:
every Python process started then (Snakemake's main process and the script of every job)
appends one line at exit: its CPU time [s] (user + sys), its peak resident set [MB] and
its command (script name), so that the run's CPU time is split by rule.
"""

import atexit
import os
import resource
import sys

_LOG = os.environ.get("BALLIMPACT_BENCH_CPU_LOG")

if _LOG:

    def _record():
        usage = resource.getrusage(resource.RUSAGE_SELF)
        command = " ".join(os.path.basename(a) for a in sys.argv[:2])
        with open(_LOG, "a", encoding="utf-8") as f:
            f.write(f"{usage.ru_utime + usage.ru_stime:.3f}\t{usage.ru_maxrss / 1024:.0f}\t{command}\n")

    atexit.register(_record)

# The run summary printed at the end of every run (issue 14): per session, impacts ok /
# excluded by reason, fit warnings, validate warnings, session-level errors, stale results.

import sys


def _print_run_summary():
    from ballimpact.summary import run_summary

    faults = {s: info["fault"] for s, info in SESSION_INFO.items() if "fault" in info}
    try:
        text = run_summary(RESULTS_DIR, SESSIONS, faults)
    except Exception as exc:  # the summary must never hide the run's own result
        text = f"ballimpact run summary failed: {type(exc).__name__}: {exc}"
    print(text, file=sys.stderr, flush=True)


onsuccess:
    _print_run_summary()


onerror:
    _print_run_summary()

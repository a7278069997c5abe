"""What every rule function shares: the rule's log file and logger, atomic text, staging folders, argument checks."""

from __future__ import annotations

import contextlib
import logging
import shutil
import warnings
from pathlib import Path

from .atomic import atomic_path

__all__ = ["log_to_file"]

#: The rule functions' logger, named ballimpact.pipeline as before the split (the name is in the log lines).
logger = logging.getLogger("ballimpact.pipeline")


# ------------------------------------------------------------------ logging, atomic writes


@contextlib.contextmanager
def log_to_file(log_path):
    """
    Send logging and warnings to a rule's log file while the block runs.

    A :class:`ballimpact.session.SessionError` (a session-level fault) is logged and
    turned into ``SystemExit`` with its one-line message, so Snakemake shows that line
    instead of a traceback; any other exception is logged with its traceback and
    re-raised.

    Parameters
    ----------
    log_path : str or Path
        The log file (created or truncated).

    Yields
    ------
    logging.Logger
        The ``ballimpact`` logger.
    """
    from .session import SessionError

    log_path = Path(log_path)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    handler = logging.FileHandler(log_path, mode="w", encoding="utf-8")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    root = logging.getLogger()
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(logging.INFO)
    logging.captureWarnings(True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")  # every suspect-input warning reaches the log
            yield logging.getLogger("ballimpact")
    except SessionError as exc:
        logging.getLogger("ballimpact").error("session-level fault: %s", exc)
        raise SystemExit(f"error: {exc}") from None
    except BaseException:
        logging.getLogger("ballimpact").exception("failed")
        raise
    finally:
        logging.captureWarnings(False)
        root.removeHandler(handler)
        root.setLevel(old_level)
        handler.close()


def _write_text_atomic(path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _check_int(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return value


@contextlib.contextmanager
def _staging(folder: Path):
    """A job's hidden staging folder, removed when the job starts and when it ends.

    One fixed name per job: a run killed inside it leaves the folder behind, and
    the next run of the same job removes it first.
    """
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir()
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)

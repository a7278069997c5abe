"""Costly fixtures built once per test run, however many pytest-xdist workers ask for them."""

from __future__ import annotations

import os
import pickle
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from filelock import FileLock


def build_once(tmp_path_factory, name: str, build: Callable[[Path], Any]) -> Any:
    """``build(folder)``'s return value, built once per test run in a folder all workers share.

    Under pytest-xdist each worker is a process with its own session and module fixtures, so a
    fixture that runs a whole Snakemake workflow was built once per worker that needed it. The
    first worker to get here builds under a file lock in the run's shared temporary folder
    (the pattern of pytest-xdist's documentation); the others wait and load the pickled return
    value. ``--dist loadgroup`` cannot be relied on for this: with pytest 9.2 it silently stops
    grouping (pytest-dev/pytest-xdist#1386). A build that raises leaves no record, so the next
    worker builds again and fails in its own right. Tests must not change what ``build`` wrote.
    """
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # the run's folder, parent of every worker's own
    folder, record = root / f"shared-{name}", root / f"shared-{name}.pickle"
    with FileLock(str(root / f"shared-{name}.lock")):
        if record.is_file():
            return pickle.loads(record.read_bytes())
        shutil.rmtree(folder, ignore_errors=True)  # a build that failed part-way
        folder.mkdir()
        value = build(folder)
        record.write_bytes(pickle.dumps(value))
        return value

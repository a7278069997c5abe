"""Atomic file and folder writes: a result is either complete under its final name or absent."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "atomic_dir"]


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _remove_stale(path: Path, suffix: str) -> None:
    """Remove temporary files a killed writer of ``path`` left behind (``kill -9``,
    power cut). One job writes a given output at a time, so they are all stale."""
    for stale in path.parent.glob(f".{path.name}.*{suffix}"):
        if stale.is_dir():
            shutil.rmtree(stale, ignore_errors=True)
        else:
            stale.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_path(path):
    """Write a file atomically: yield a temporary path in the same folder, then rename it.

    The temporary file keeps the target's suffix (writers that infer the format from
    it, such as matplotlib or xarray, work unchanged) and gets the permissions of a
    normally created file (0666 minus the umask; ``mkstemp`` alone gives 0600). On an
    exception the temporary file is removed and the target is left untouched; an
    interrupted process leaves at most a hidden ``.<name>.*.tmp`` file, never a
    half-written file under the final name.

    Parameters
    ----------
    path : str or Path
        The final file; its folder is created when missing.

    Yields
    ------
    Path
        The temporary file to write (it does not exist yet).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(path, f".tmp{path.suffix}")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    tmp.unlink()  # writers create it themselves (some refuse to overwrite)
    try:
        yield tmp
        if not tmp.exists():
            raise RuntimeError(f"{path}: nothing was written to the temporary file {tmp}")
        tmp.chmod(0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


@contextlib.contextmanager
def atomic_dir(path):
    """Fill a folder atomically: yield an empty temporary folder beside it, then rename it.

    Parameters
    ----------
    path : str or Path
        The final folder; an existing one is replaced.

    Yields
    ------
    Path
        The temporary folder to fill.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(path, ".tmp")
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    mode_dir, mode_file = 0o777 & ~_umask(), 0o666 & ~_umask()
    try:
        yield tmp
        tmp.chmod(mode_dir)
        for child in tmp.rglob("*"):
            child.chmod(mode_dir if child.is_dir() else mode_file)
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)

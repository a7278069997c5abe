"""A raw session's files read: near-miss file names, bytes, UTF-8 text, messages on one line."""

from __future__ import annotations

from pathlib import Path

from .session_records import IMPACTS_FILE, SESSION_FILE, SessionError

__all__ = ["near_miss_name"]

#: File names a lab may give session.yaml / impacts.csv by mistake (near misses).
_NEAR_MISS_NAMES = {
    SESSION_FILE: ("session.yml", "Session.yaml", "SESSION.yaml", "session.YAML", "session.yaml.txt",
                   "session.txt", "Session.yml", "session_yaml"),
    IMPACTS_FILE: ("Impacts.csv", "IMPACTS.csv", "impacts.CSV", "impacts.csv.txt", "impacts.txt",
                   "impact.csv", "impacts.tsv", "impacts.xlsx"),
}


def _decode_utf8(data: bytes, file: str) -> str:
    """Decode UTF-8 (a BOM is dropped); SessionError naming the line of a bad byte."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise SessionError(
            f"{file}: line {line}: not valid UTF-8 (byte 0x{data[exc.start]:02x}); save the file as UTF-8"
        ) from None


def near_miss_name(folder: Path, expected: str) -> str | None:
    """
    A file in ``folder`` whose name is a likely mistake for ``expected`` (e.g. session.yml).

    Parameters
    ----------
    folder : Path
        The session folder.
    expected : str
        The file name the format requires (``session.yaml`` or ``impacts.csv``).

    Returns
    -------
    str or None
        The name found, None when there is none.
    """
    try:
        names = {p.name for p in Path(folder).iterdir() if p.is_file()}
    except OSError:
        return None
    if expected in names:
        return None
    for name in _NEAR_MISS_NAMES.get(expected, ()):
        if name in names:
            return name
    lower = {n.lower(): n for n in names}
    stem = expected.rsplit(".", 1)[0]
    for low, name in sorted(lower.items()):
        if low != expected and low.startswith(stem) and low.split(".")[0] == stem:
            return name
    return None


def _read_bytes(path: Path, file: str, what: str) -> bytes:
    if not path.exists():
        other = near_miss_name(path.parent, path.name) if path.parent.is_dir() else None
        if other is not None:
            raise SessionError(f"{file}: file not found, but {other!r} is there: rename it to {path.name!r}")
        raise SessionError(f"{file}: file not found ({what})")
    if not path.is_file():
        raise SessionError(f"{file}: is not a file ({what})")
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise SessionError(f"{file}: cannot read: {exc.strerror or exc}") from None


def _one_line(text: str) -> str:
    return " ".join(str(text).split())

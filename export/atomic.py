"""Atomic file output: write to a temporary file beside the target, then rename.

A failed or cancelled write leaves no partial file and never touches an
earlier result at the target path.  The temporary file is flushed to disk
(fsync) before the rename, so a power cut leaves either the old file or the
new one; temporaries that a killed process left behind (``.omninoise-*``
older than a day) are removed from the folder on the next write there.
"""
from __future__ import annotations

import contextlib
import os
import tempfile
import time

STALE_SECONDS = 24 * 3600   #: age after which a leftover ``.omninoise-*`` temporary is removed


@contextlib.contextmanager
def atomic_path(path: str, suffix: str | None = None):
    """Yield a temporary path in the target's folder; rename it onto ``path`` on success."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"output folder does not exist: {folder}")
    if not os.access(folder, os.W_OK):
        raise PermissionError(f"output folder is not writable: {folder}")
    if os.path.isdir(path):
        raise IsADirectoryError(f"output path is a folder, not a file: {path}")
    remove_stale(folder)
    suffix = suffix if suffix is not None else os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=partial_prefix(path), suffix=suffix, dir=folder)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; results get the usual permissions
        _fsync(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _fsync(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def partial_prefix(path: str) -> str:
    """The name prefix of the temporaries that become ``path``: ``.omninoise-NAME.`` (then random)."""
    return f".omninoise-{os.path.basename(path)}."


def _remove_temporaries(folder: str, prefix: str, max_age: float) -> list:
    """Remove the files in ``folder`` whose names start with ``prefix`` and are older than ``max_age``
    seconds (a negative age: any file); returns their names."""
    now, gone = time.time(), []
    try:
        names = [n for n in os.listdir(folder) if n.startswith(prefix)]
    except OSError:
        return gone
    for n in names:
        p = os.path.join(folder, n)
        try:
            if os.path.isfile(p) and now - os.path.getmtime(p) > max_age:
                os.remove(p)
                gone.append(n)
        except OSError:
            pass        # another process's file, or gone already
    return gone


def remove_partials(path: str) -> list:
    """Remove the temporaries of ``path`` left by writers that died (a worker killed mid-write); call it only
    when no writer of ``path`` can still be running.  Returns their names."""
    return _remove_temporaries(os.path.dirname(os.path.abspath(path)), partial_prefix(path), -1.0)


def remove_stale(folder: str, max_age: float = STALE_SECONDS) -> list:
    """Remove ``.omninoise-*`` temporaries older than ``max_age`` seconds in ``folder``; returns their names."""
    return _remove_temporaries(folder, ".omninoise-", max_age)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path: str, text: str) -> None:
    """Write ``text`` (UTF-8) atomically."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)


def write_json(path: str, doc, indent: int = 1) -> None:
    """Write ``doc`` as JSON (UTF-8) atomically."""
    import json

    write_text(path, json.dumps(doc, indent=indent))

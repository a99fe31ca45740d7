"""Atomic file output: write to a temporary file beside the target, then rename.

A failed or cancelled write leaves no partial file and never touches an
earlier result at the target path.  The temporary file is flushed to disk
(fsync) before the rename, so a power cut leaves either the old file or the
new one; temporaries that a killed process left behind (``.omninoise-*``
older than a day) are removed from the folder on the next write there.

A temporary's name fits the file system's 255-byte limit whatever the target's legal name: ``.omninoise-``, the
target's name (a long one cut, with a digest of the whole), the writer's tag (:func:`tagged`: a farm run's, so that
it removes its own workers' leftovers and no other process's), then mkstemp's random part and the suffix.

Every writer refuses NaN and infinite values (:func:`require_finite`): no output file ever holds them.
"""
from __future__ import annotations

import contextlib
import contextvars
import errno
import hashlib
import os
import tempfile
import time

import numpy as np

STALE_SECONDS = 24 * 3600   #: age after which a leftover ``.omninoise-*`` temporary is removed
NAME_PART = 96              #: at most this many characters of the target's name in a temporary's
SUFFIX_PART = 16            #: ... and of its suffix
_TAG = contextvars.ContextVar("omninoise_temporary_tag", default="")


class NonFiniteError(ValueError):
    """A result holds NaN or infinite values; nothing is written."""


#: the largest finite 16-bit half float: a value past it is written as infinite
HALF_MAX = 65504.0


def require_finite(array, path: str, half: bool = False) -> None:
    """NonFiniteError naming ``path`` unless every value of ``array`` is finite, and with ``half`` (16-bit half
    floats) within +-:data:`HALF_MAX` (the writers' last check)."""
    a = np.asarray(array)
    if a.dtype.kind in "fc" and not np.isfinite(a).all():
        bad = int(a.size - np.count_nonzero(np.isfinite(a)))
        raise NonFiniteError(f"not writing {os.path.basename(path)}: {bad} of {a.size} values are NaN or infinite "
                             "(a setting out of range?)")
    if half and a.dtype.kind in "fc" and a.size and float(np.max(np.abs(a))) > HALF_MAX:
        bad = int(np.count_nonzero(np.abs(a) > HALF_MAX))
        raise NonFiniteError(f"not writing {os.path.basename(path)}: {bad} of {a.size} values lie past {HALF_MAX:g}, "
                             "the largest 16-bit half float, and would be infinite: write 32-bit floats (no half)")


@contextlib.contextmanager
def tagged(tag: str):
    """Temporaries made in this context carry ``tag`` in their names (letters, digits, '-' and '_'): a farm's
    workers write under the farm run's tag, and :func:`remove_partials` with that tag removes only theirs."""
    if not tag or not all(c.isalnum() or c in "-_" for c in tag) or len(tag) > 32:
        raise ValueError(f"a temporary's tag is 1 to 32 letters, digits, '-' or '_', got {tag!r}")
    token = _TAG.set(tag)
    try:
        yield
    finally:
        _TAG.reset(token)


class OutputNameError(OSError):
    """An output's file name is longer than its file system allows."""


class WriteError(OSError):
    """An output could not be written (its disk full, a read error of the device): the message names the file and
    the system's reason; nothing was written and an earlier file at the path is as it was."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"cannot write {os.path.basename(path)}: {reason}")
        self.path, self.reason = path, reason


def name_limit(folder: str) -> int:
    """Bytes a file name may take in ``folder`` (or its nearest existing parent): the file system's limit, 255
    where it does not say."""
    while folder and not os.path.isdir(folder):
        parent = os.path.dirname(folder)
        if parent == folder:
            break
        folder = parent
    try:
        return int(os.pathconf(folder or ".", "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


def check_target(path: str, folder_made: bool = False) -> None:
    """Raise now what writing ``path`` would raise later: a name past the file system's limit
    (OutputNameError), a folder in the file's place (IsADirectoryError), and unless ``folder_made`` (a job makes
    its folders) a missing or read-only folder (FileNotFoundError, PermissionError)."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    name = os.path.basename(path)
    size, limit = len(os.fsencode(name)), name_limit(folder)
    if size > limit:
        raise OutputNameError(f"output name is {size} bytes, more than the {limit} this file system allows: "
                              f"{name[:40]}...")
    if os.path.isdir(path):
        raise IsADirectoryError(f"output path is a folder, not a file: {path}")
    if not folder_made:
        if not os.path.isdir(folder):
            raise FileNotFoundError(f"output folder does not exist: {folder}")
        if not os.path.isdir(os.path.dirname(path) or "."):      # 'sub/..' is a folder only where sub is one
            raise FileNotFoundError(f"output folder does not exist: {os.path.dirname(path)}")
        if not os.access(folder, os.W_OK):
            raise PermissionError(f"output folder is not writable: {folder}")


@contextlib.contextmanager
def atomic_path(path: str, suffix: str | None = None):
    """Yield a temporary path in the target's folder; rename it onto ``path`` on success."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    check_target(path)
    remove_stale(folder)
    suffix = (suffix if suffix is not None else os.path.splitext(path)[1])[-SUFFIX_PART:]
    tmp = None
    try:
        try:
            fd, tmp = tempfile.mkstemp(prefix=partial_prefix(path, _TAG.get()), suffix=suffix, dir=folder)
        except (FileNotFoundError, PermissionError) as exc:    # gone since the check, or a folder such as /proc
            raise type(exc)(f"output folder takes no new file: {folder} ({exc.strerror})") from None
        os.close(fd)
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; results get the usual permissions
        _fsync(tmp)
        os.replace(tmp, path)
    except (OSError, RuntimeError) as exc:       # OpenEXR's and OpenVDB's failures are RuntimeErrors
        why = None if isinstance(exc, WriteError) else failed_write(exc, folder)
        if why is None:
            raise
        raise WriteError(path, why) from exc
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def failed_write(exc: BaseException, folder: str) -> str | None:
    """The system's reason where ``exc``, raised while a file was written in ``folder``, is a failure to write (an
    OSError with an errno; any error where the folder's disk is now full: numpy's and OpenEXR's say it in words of
    their own, or none); None where it is something else."""
    if isinstance(exc, (FileNotFoundError, PermissionError, IsADirectoryError)):     # the folder's own, said so
        return None
    if isinstance(exc, OSError) and exc.errno is not None:
        return os.strerror(exc.errno)
    return no_space(folder)


def no_space(folder: str) -> str | None:
    """ENOSPC's reason where the disk of ``folder`` is full (:func:`disk_full`), else None."""
    return os.strerror(errno.ENOSPC) if disk_full(folder) else None


def disk_full(folder: str) -> bool:
    """Whether the file system of ``folder`` has no block left that this process may write (one of no blocks at
    all, such as /proc, is not a disk)."""
    try:
        st = os.statvfs(folder)
    except (OSError, AttributeError):       # no statvfs (Windows) or no folder: not known to be full
        return False
    return st.f_blocks > 0 and st.f_bavail == 0


def _fsync(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def partial_prefix(path: str, tag: str = "") -> str:
    """The name prefix of the temporaries that become ``path``: ``.omninoise-NAME.`` (then random), with the
    writer's ``tag`` after it where there is one; a name over NAME_PART characters is cut and ends in a digest of
    the whole."""
    name = os.path.basename(path)
    if len(name) > NAME_PART:
        name = name[:NAME_PART - 9] + "~" + hashlib.sha256(name.encode("utf-8", "surrogateescape")).hexdigest()[:8]
    return f".omninoise-{name}." + (f"{tag}." if tag else "")


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


def remove_partials(path: str, tag: str) -> list:
    """Remove the temporaries of ``path`` that writers under ``tag`` left when they died (a farm's worker killed
    mid-write); another process's temporaries of the same file carry another tag, or none, and stay.  Returns
    their names."""
    if not tag:
        raise ValueError("remove_partials needs the writers' tag: it removes only their temporaries")
    return _remove_temporaries(os.path.dirname(os.path.abspath(path)), partial_prefix(path, tag), -1.0)


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

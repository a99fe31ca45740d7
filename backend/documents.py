"""Reading the small text documents users hand in (job files, keyframe files, ramp files), within bounds.

Only a regular file is opened (a FIFO, a device or a folder is refused before it can block or stream
forever), at most :data:`MAX_DOCUMENT_BYTES` are read, the text must be UTF-8 and its nesting shallow enough
to parse; each failure is one :class:`~backend.errors.SettingError` naming the setting and the file.
"""
from __future__ import annotations

import json
import os
import stat
import tomllib

from .errors import SettingError

__all__ = ["MAX_DOCUMENT_BYTES", "read_document"]

MAX_DOCUMENT_BYTES = 16 << 20


def read_document(path: str, setting: str, kind: str):
    """The parsed contents of the TOML (``kind`` "toml") or JSON ("json") file at ``path``."""
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        raise SettingError(setting, f"file not found: {path}") from None
    except OSError as exc:
        raise SettingError(setting, f"{path}: cannot be read ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        raise SettingError(setting, f"{path} is not a regular file")
    if st.st_size > MAX_DOCUMENT_BYTES:
        raise SettingError(setting, f"{path} is {st.st_size / 2 ** 20:.0f} MiB; a {kind.upper()} document here is "
                                    f"at most {MAX_DOCUMENT_BYTES >> 20} MiB")
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_DOCUMENT_BYTES + 1)
    except OSError as exc:
        raise SettingError(setting, f"{path}: cannot be read ({exc.strerror or exc})") from None
    if len(data) > MAX_DOCUMENT_BYTES:
        raise SettingError(setting, f"{path} is more than {MAX_DOCUMENT_BYTES >> 20} MiB")
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise SettingError(setting, f"{path}: UTF-16 text; save it as UTF-8")
    try:
        text = data.decode("utf-8-sig")         # a byte-order mark, as some Windows editors write, is left out
    except UnicodeDecodeError as exc:
        raise SettingError(setting, f"{path}: not UTF-8 text (byte {exc.start})") from None
    try:
        if kind == "toml":
            return tomllib.loads(text)
        return json.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SettingError(setting, f"{path}: not valid TOML ({exc})") from None
    except json.JSONDecodeError as exc:
        raise SettingError(setting, f"{path}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    except RecursionError:
        raise SettingError(setting, f"{path}: nested too deeply to read") from None

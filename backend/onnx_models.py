"""Shipped ONNX model folders: a JSON description whose ``files`` map names to sha256, checked on load,
and onnxruntime sessions created on first use (shared by the neural noise and solid texture runtimes).

The description itself is sealed: its ``json_sha256`` is the sha256 of the rest of it in canonical form
(sorted keys, no spaces), so an edited class embedding, schedule or parameter range is refused like an edited
weight file. Writers seal with :func:`write_model_json`."""
from __future__ import annotations

import hashlib
import json
import os

__all__ = ["ModelError", "sha256_file", "load_model_json", "verify_files", "fingerprint", "SessionCache", "SEAL",
           "json_seal", "sealed", "write_model_json",
           "set_default_threads"]

_THREADS = {"default": 0}


def set_default_threads(n: int) -> None:
    """onnxruntime intra-op threads for sessions created without their own count (0: onnxruntime's
    default, one per physical core); the CLI's ``--threads`` and the add-on's preference set it."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 0:
        raise ValueError(f"threads must be a whole number >= 0, got {n!r}")
    _THREADS["default"] = n



class ModelError(RuntimeError):
    """A model folder is missing, incomplete or altered."""


def sha256_file(path: str) -> str:
    """Hex sha256 of a file, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


SEAL = "json_sha256"


def json_seal(doc: dict) -> str:
    """sha256 of ``doc`` less its seal, as canonical JSON (sorted keys, no spaces, ASCII)."""
    body = {k: v for k, v in doc.items() if k != SEAL}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def sealed(doc: dict) -> dict:
    """``doc`` with its seal (:func:`json_seal`) set."""
    return {**{k: v for k, v in doc.items() if k != SEAL}, SEAL: json_seal(doc)}


def write_model_json(path: str, doc: dict) -> None:
    """Write a model description, sealed, atomically."""
    from ..export.atomic import write_json

    write_json(path, sealed(doc))


def load_model_json(folder: str, json_name: str) -> dict:
    """``folder/json_name`` after checking every file it lists against its sha256 (ModelError if not)."""
    path = os.path.join(folder, json_name)
    if not os.path.isfile(path):
        raise ModelError(f"no {json_name} in {folder}")
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError, RecursionError) as exc:    # unreadable, not UTF-8, not JSON, nested too deep
        raise ModelError(f"{path} is not a readable model description ({type(exc).__name__}); re-install or "
                         "re-export the model") from None
    if not isinstance(doc, dict) or not isinstance(doc.get(SEAL), str):
        raise ModelError(f"{path} has no {SEAL} seal: the description cannot be verified; re-export the model")
    if json_seal(doc) != doc[SEAL]:
        raise ModelError(f"{path}: {SEAL} does not match its contents (altered or damaged description)")
    files = doc.get("files")
    if not isinstance(files, dict) or not files:
        raise ModelError(f"{path} lists no files with their sha256 ('files'): the model cannot be verified")
    verify_files(folder, files, json_name)
    return doc


def verify_files(folder: str, files: dict, json_name: str) -> None:
    """ModelError unless every ``files`` name (relative to ``folder``) exists with the sha256 ``json_name`` lists."""
    for name, digest in files.items():
        fp = os.path.join(folder, name)
        if not os.path.isfile(fp):
            raise ModelError(f"model file missing: {fp}")
        if sha256_file(fp) != digest:
            raise ModelError(f"{name}: sha256 does not match {json_name} (altered or damaged file)")


def fingerprint(files: dict) -> str:
    """One sha256 naming a model's weights: the file's own hash for a lone ``eps.onnx`` (as pinned
    before split exports), else the sha256 of its ``name=sha256`` lines, sorted."""
    if set(files) == {"eps.onnx"}:
        return files["eps.onnx"]
    text = "".join(f"{k}={v}\n" for k, v in sorted(files.items()))
    return hashlib.sha256(text.encode()).hexdigest()


class SessionCache:
    """onnxruntime sessions of a folder's .onnx files, created on first use (CPU, ``threads`` intra-op).

    ``arena=False`` returns each run's buffers to the system instead of keeping onnxruntime's CPU arena
    at its peak between runs."""

    def __init__(self, folder: str, threads: int = 0, arena: bool = True):
        self.folder, self.threads, self.arena, self._sessions = folder, threads, arena, {}

    def __call__(self, name: str):
        if name not in self._sessions:
            import onnxruntime as ort

            opts = ort.SessionOptions()
            opts.enable_cpu_mem_arena = self.arena
            threads = self.threads or _THREADS["default"]
            if threads:
                opts.intra_op_num_threads = threads
            self._sessions[name] = ort.InferenceSession(os.path.join(self.folder, name), opts,
                                                        providers=["CPUExecutionProvider"])
        return self._sessions[name]

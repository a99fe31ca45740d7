"""Shipped ONNX model folders: a JSON description whose ``files`` map names to sha256, checked on load,
and onnxruntime sessions created on first use (shared by the neural noise and solid texture runtimes)."""
from __future__ import annotations

import hashlib
import json
import os

__all__ = ["ModelError", "sha256_file", "load_model_json", "SessionCache"]


class ModelError(RuntimeError):
    """A model folder is missing, incomplete or altered."""


def sha256_file(path: str) -> str:
    """Hex sha256 of a file, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def load_model_json(folder: str, json_name: str) -> dict:
    """``folder/json_name`` after checking every file it lists against its sha256 (ModelError if not)."""
    path = os.path.join(folder, json_name)
    if not os.path.isfile(path):
        raise ModelError(f"no {json_name} in {folder}")
    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    for name, digest in doc.get("files", {}).items():
        fp = os.path.join(folder, name)
        if not os.path.isfile(fp):
            raise ModelError(f"model file missing: {fp}")
        if sha256_file(fp) != digest:
            raise ModelError(f"{name}: sha256 does not match {json_name} (altered or damaged file)")
    return doc


class SessionCache:
    """onnxruntime sessions of a folder's .onnx files, created on first use (CPU, ``threads`` intra-op)."""

    def __init__(self, folder: str, threads: int = 0):
        self.folder, self.threads, self._sessions = folder, threads, {}

    def __call__(self, name: str):
        if name not in self._sessions:
            import onnxruntime as ort

            opts = ort.SessionOptions()
            if self.threads:
                opts.intra_op_num_threads = self.threads
            self._sessions[name] = ort.InferenceSession(os.path.join(self.folder, name), opts,
                                                        providers=["CPUExecutionProvider"])
        return self._sessions[name]

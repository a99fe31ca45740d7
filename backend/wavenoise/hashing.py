"""Blender-compatible hashing (numpy port of the Jenkins *lookup3* hash).

Every random number the wave-noise evaluation draws from integer ids (direction
index, slice index, cell code) comes from :func:`white_noise4`, which computes the
value Blender's *White Noise Texture* node returns for a 4D input
``(Vector=(x, y, z), W=w)``: the float32 bit patterns of the four inputs are
hashed with lookup3 (``hash_uint4``) and mapped to ``[0, 1]`` by
``float32(h) * float32(1 / 0xFFFFFFFF)``.  Shader and geometry nodes can compute
exactly the same value, which is what lets the Wave Noise node reproduce this
engine's values rather than only its look.

All functions are vectorised; inputs broadcast against each other.
"""
from __future__ import annotations

import numpy as np

__all__ = ["hash_uint", "hash_uint2", "hash_uint3", "hash_uint4", "float_bits",
           "white_noise1", "white_noise2", "white_noise3", "white_noise4", "MAX_EXACT_ID"]

#: Integer ids are passed through float32; they are exact below this bound.
MAX_EXACT_ID = 1 << 24

_U32 = np.uint32


def _rot(x: np.ndarray, k: int) -> np.ndarray:
    return (x << _U32(k)) | (x >> _U32(32 - k))


def _mix(a, b, c):
    a = a - c; a = a ^ _rot(c, 4); c = c + b
    b = b - a; b = b ^ _rot(a, 6); a = a + c
    c = c - b; c = c ^ _rot(b, 8); b = b + a
    a = a - c; a = a ^ _rot(c, 16); c = c + b
    b = b - a; b = b ^ _rot(a, 19); a = a + c
    c = c - b; c = c ^ _rot(b, 4); b = b + a
    return a, b, c


def _final(a, b, c):
    c = c ^ b; c = c - _rot(b, 14)
    a = a ^ c; a = a - _rot(c, 11)
    b = b ^ a; b = b - _rot(a, 25)
    c = c ^ b; c = c - _rot(b, 16)
    a = a ^ c; a = a - _rot(c, 4)
    b = b ^ a; b = b - _rot(a, 14)
    c = c ^ b; c = c - _rot(b, 24)
    return c


def _init(n_words: int, shape) -> np.ndarray:
    return np.full(shape, (0xDEADBEEF + (n_words << 2) + 13) & 0xFFFFFFFF, dtype=_U32)


def _u32(x) -> np.ndarray:
    return np.asarray(x, dtype=np.uint64).astype(_U32) if not isinstance(x, np.ndarray) or x.dtype != _U32 else x


def hash_uint(kx) -> np.ndarray:
    """lookup3 hash of one uint32 word (uint32 array)."""
    kx = _u32(kx)
    a = _init(1, kx.shape); b = a.copy(); c = a.copy()
    with np.errstate(over="ignore"):
        a = a + kx
        return _final(a, b, c)


def hash_uint2(kx, ky) -> np.ndarray:
    kx, ky = np.broadcast_arrays(_u32(kx), _u32(ky))
    a = _init(2, kx.shape); b = a.copy(); c = a.copy()
    with np.errstate(over="ignore"):
        b = b + ky; a = a + kx
        return _final(a, b, c)


def hash_uint3(kx, ky, kz) -> np.ndarray:
    kx, ky, kz = np.broadcast_arrays(_u32(kx), _u32(ky), _u32(kz))
    a = _init(3, kx.shape); b = a.copy(); c = a.copy()
    with np.errstate(over="ignore"):
        c = c + kz; b = b + ky; a = a + kx
        return _final(a, b, c)


def hash_uint4(kx, ky, kz, kw) -> np.ndarray:
    kx, ky, kz, kw = np.broadcast_arrays(_u32(kx), _u32(ky), _u32(kz), _u32(kw))
    a = _init(4, kx.shape); b = a.copy(); c = a.copy()
    with np.errstate(over="ignore"):
        a = a + kx; b = b + ky; c = c + kz
        a, b, c = _mix(a, b, c)
        a = a + kw
        return _final(a, b, c)


def float_bits(x) -> np.ndarray:
    """Bit pattern of ``float32(x)`` as uint32 (``__float_as_uint``)."""
    return np.ascontiguousarray(np.asarray(x, dtype=np.float32)).view(_U32)


_INV_UMAX = np.float32(1.0) / np.float32(0xFFFFFFFF)


def _to_unit(h: np.ndarray) -> np.ndarray:
    """``uint_to_float_incl``: uint32 -> float32 in [0, 1]."""
    return h.astype(np.float32) * _INV_UMAX


def white_noise1(w) -> np.ndarray:
    """Blender White Noise Texture, 1D, Value output (float32)."""
    return _to_unit(hash_uint(float_bits(w)))


def white_noise2(x, y) -> np.ndarray:
    """Blender White Noise Texture, 2D, Value output (float32)."""
    return _to_unit(hash_uint2(float_bits(x), float_bits(y)))


def white_noise3(x, y, z) -> np.ndarray:
    """Blender White Noise Texture, 3D, Value output (float32)."""
    return _to_unit(hash_uint3(float_bits(x), float_bits(y), float_bits(z)))


def white_noise4(x, y, z, w) -> np.ndarray:
    """Blender White Noise Texture, 4D (Vector xyz + W), Value output (float32)."""
    x, y, z, w = np.broadcast_arrays(float_bits(x), float_bits(y), float_bits(z), float_bits(w))
    return _to_unit(hash_uint4(x, y, z, w))

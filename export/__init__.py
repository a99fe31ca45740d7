"""Writers for baked results: PNG, EXR (OpenEXR), OpenVDB, NumPy; all writes are atomic."""
from .atomic import NonFiniteError, OutputNameError, WriteError, atomic_path, check_target, partial_prefix, remove_partials, require_finite, tagged, write_json, write_text
from .images import (ImageError, decode, encode_srgb8, linear_to_srgb, opaque, preview_8bit, read_image, read_metadata, read_rgb, write_exr, write_image, write_npy,
                     write_png)
from .vdb import VolumeWriter, openvdb_module, read_volume

__all__ = ["ImageError", "NonFiniteError", "OutputNameError", "WriteError", "check_target", "require_finite", "tagged", "decode", "atomic_path", "partial_prefix", "remove_partials", "write_json", "write_text", "write_npy", "write_png", "write_exr", "read_image", "read_rgb", "opaque", "write_image", "preview_8bit",
           "read_metadata", "encode_srgb8", "linear_to_srgb", "VolumeWriter", "openvdb_module", "read_volume"]

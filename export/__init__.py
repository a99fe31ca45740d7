"""Writers for baked results: PNG, EXR (OpenEXR), NumPy; all writes are atomic."""
from .atomic import atomic_path
from .images import write_npy, write_png, write_exr, read_image, write_image, preview_8bit

__all__ = ["atomic_path", "write_npy", "write_png", "write_exr", "read_image", "write_image", "preview_8bit"]

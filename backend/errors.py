"""Errors with one-line messages that name the offending setting."""
import numpy as np


class SettingError(ValueError):
    """A user-facing setting is invalid.  ``str(err)`` is a one-line message."""

    def __init__(self, setting: str, message: str):
        self.setting, self.message = setting, message
        super().__init__(f"{setting}: {message}")

    def under(self, prefix: str) -> "SettingError":
        """The same error named under ``prefix``, the table its setting is a key of ("source" -> "source.KEY"),
        unless it is named so already (or ``prefix`` is empty)."""
        if not prefix or self.setting == prefix or self.setting.startswith(prefix + "."):
            return self
        return SettingError(f"{prefix}.{self.setting}", self.message)


def check_points(points, dims: tuple, dtype=None) -> np.ndarray:
    """``points`` as a contiguous ``dtype`` array (P, D) with D in ``dims`` (None: their own dtype); SettingError
    naming the points for another shape or a NaN or infinite coordinate (P = 0 passes: no point, no value)."""
    x = np.ascontiguousarray(points, dtype=dtype)
    if x.ndim != 2 or x.shape[1] not in dims:
        raise SettingError("points", f"expected shape (P, {' or '.join(map(str, dims))}), got {x.shape}")
    if not np.isfinite(x).all():
        raise SettingError("points", "the points hold NaN or infinite coordinates")
    return x

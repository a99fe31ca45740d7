"""Errors with one-line messages that name the offending setting."""


class SettingError(ValueError):
    """A user-facing setting is invalid.  ``str(err)`` is a one-line message."""

    def __init__(self, setting: str, message: str):
        self.setting, self.message = setting, message
        super().__init__(f"{setting}: {message}")

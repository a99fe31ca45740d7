"""Errors with one-line messages that name the offending setting."""


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

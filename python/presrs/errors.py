"""The exceptions presrs raises. Each carries the Rust message, which names the file, line and field."""


class PresrsError(Exception):
    """Base class of every presrs error."""


class DataError(PresrsError, ValueError):
    """The input does not fit: a shape, a value, an option, a malformed file."""


class FileError(PresrsError, OSError):
    """The operating system refused a file (missing, unreadable, not writable). ``errno`` is set for
    the common cases (2: no such file)."""


__all__ = ["PresrsError", "DataError", "FileError"]

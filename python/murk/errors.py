"""murk's exceptions. Each carries the library's one-line message; the second base lets callers
catch the usual built-in (``except ValueError``) without knowing murk.

>>> try:
...     murk.read_capture("missing.h5")
... except murk.FileError as e:   # also an OSError
...     print(e)
missing.h5: No such file or directory (os error 2)
"""


class Error(Exception):
    """Any error murk reports."""


class InputError(Error, ValueError):
    """A parameter or an in-memory capture is inconsistent (the caller's fault)."""


class FileError(Error, OSError):
    """The operating system refused (missing file, permissions, full disk)."""


class FormatError(Error, ValueError):
    """A file exists but its content is not what it claims to be."""


class LimitError(Error, ValueError):
    """A size declared by a file or requested exceeds what murk will allocate."""


class UnsupportedError(Error, ValueError):
    """Valid input that this version of murk does not handle."""

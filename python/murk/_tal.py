"""y-tal interoperability through y-tal's own HDF5 files: murk's reader and writer already map every
y-tal layout (crates/murk-io/src/tal.rs), so the conversion goes through a temporary file rather
than a second, in-memory copy of that mapping."""

import os
import tempfile

from . import _murk
from .errors import Error


def to_tal(capture):
    import tal

    with tempfile.TemporaryDirectory(prefix="murk-tal-") as d:
        path = os.path.join(d, "capture.hdf5")
        _murk.write_capture(path, capture)
        return tal.io.read_capture(path)


def from_tal(data):
    import tal

    with tempfile.TemporaryDirectory(prefix="murk-tal-") as d:
        path = os.path.join(d, "capture.hdf5")
        tal.io.write_capture(path, data)
        try:
            return _murk.read_capture(path)
        except Error as e:
            # The file is gone once this returns: name what the caller gave instead.
            raise type(e)(str(e).replace(path, "the y-tal capture")) from None

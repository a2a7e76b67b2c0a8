"""What native libraries print, kept off the terminal: posegen says one line, naming the cause.

C++ parsers (urdfdom inside pinocchio, assimp inside coal, MuJoCo's MJCF reader) write
their complaints straight to the process's stdout and stderr, several lines before
posegen's own error, and often about another cause. :func:`native_output` points both
file descriptors at a temporary file for the duration of a native call; what was
printed is then available to the caller (to name the cause in its own message) and
logged at debug level, never printed.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import sys
import tempfile
from collections.abc import Iterator

LOG = logging.getLogger(__name__)

_ERROR_WORDS = ("error", "failed", "not found", "invalid", "could not", "cannot")


class NativeOutput:
    """The text native code printed during a :func:`native_output` block (filled when the block ends)."""

    def __init__(self) -> None:
        self.text = ""

    def cause(self) -> str:
        """The first printed line that reads like an error (else the first line), as one stripped line; "" if none.

        Example:
            >>> with native_output() as printed:  # doctest: +SKIP
            ...     pin.buildModelFromXML(text)
            >>> printed.cause()  # doctest: +SKIP
            'Error: Failed to build tree: parent link [nothing] of joint [j2] not found.'

        """
        lines = [" ".join(line.split()) for line in self.text.splitlines() if line.strip()]
        found = next(
            (line for line in lines if any(w in line.lower() for w in _ERROR_WORDS)), lines[0] if lines else ""
        )
        return found[:300]


def _flush_c_streams() -> None:
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).fflush(None)


@contextlib.contextmanager
def native_output() -> Iterator[NativeOutput]:
    """Keep what native code prints on stdout and stderr during the block; yield it (filled at the block's end).

    Python's own writes in the block go there too: keep the block to the native call.
    """
    printed = NativeOutput()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            stream.flush()
    saved = [os.dup(fd) for fd in (1, 2)]
    with tempfile.TemporaryFile() as sink:
        try:
            for fd in (1, 2):
                os.dup2(sink.fileno(), fd)
            yield printed
        finally:
            _flush_c_streams()  # C's buffered stdout, before it points back at the terminal
            for fd, copy in zip((1, 2), saved, strict=True):
                os.dup2(copy, fd)
                os.close(copy)
            sink.seek(0)
            printed.text = sink.read().decode(errors="replace")
            if printed.text.strip():
                LOG.debug("native output: %s", printed.text.strip())

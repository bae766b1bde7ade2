"""What C libraries (usd-core, libpng through OpenImageIO) print on file descriptor 2, captured.

Their diagnostics are written straight to fd 2, not through Python's ``sys.stderr``; the
readers turn what matters into warnings and errors of their own, so the raw lines must not
reach the terminal.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator


@contextlib.contextmanager
def captured_stderr(lines: list[str]) -> Iterator[None]:
    """Capture what is written to fd 2 inside the block (non-blank lines appended to ``lines``).

    Examples
    --------
    >>> lines = []
    >>> with captured_stderr(lines):
    ...     _ = os.write(2, b"libpng error: IDAT: invalid distance too far back\\n")
    >>> lines
    ['libpng error: IDAT: invalid distance too far back']
    """
    try:
        fd = os.dup(2)
    except OSError:
        yield
        return
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(fd, 2)
            os.close(fd)
            tmp.seek(0)
            lines += [ln for ln in tmp.read(1 << 20).decode("utf-8", "replace").splitlines() if ln.strip()]


__all__ = ["captured_stderr"]

"""Text files in and out, with errors that name the file.

An ``OSError`` raised by a write or a close (a full disk, a quota) carries no file name,
and a ``UnicodeDecodeError`` names neither the file nor where in it the bad byte is: the
helpers here give both, so that a one-line message can say which file and where.
"""

from __future__ import annotations

import codecs
import os
from pathlib import Path

#: Bytes read at a time when looking for the first byte that is not UTF-8.
_SCAN_BYTES = 1 << 16


def utf8_problem(path: str | os.PathLike[str]) -> str | None:
    """Where the file ``path`` stops being UTF-8 text, or None when it is all UTF-8.

    The answer reads "not a UTF-8 text file (byte 0x89 at offset 0, line 1)": the first
    offending byte, its offset from the start of the file (0-based, as hex editors show)
    and its line (1-based).  The file is read in blocks: memory does not grow with it.

    Examples
    --------
    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "x.csv")
    >>> _ = open(p, "wb").write(b"id,kind\\nab\\xc3\\xa9,\\xff\\n")
    >>> utf8_problem(p)
    'not a UTF-8 text file (byte 0xff at offset 13, line 2)'
    >>> _ = open(p, "wb").write("caf\\u00e9\\n".encode())
    >>> utf8_problem(p) is None
    True
    """
    decoder = codecs.getincrementaldecoder("utf-8")()
    offset, line = 0, 1
    try:
        with open(path, "rb") as fh:
            while True:
                chunk = fh.read(_SCAN_BYTES)
                try:
                    decoder.decode(chunk, final=not chunk)
                except UnicodeDecodeError as exc:
                    # exc.object is the decoder's held-back bytes (an incomplete sequence,
                    # never a newline) followed by this chunk
                    start = offset + len(chunk) - len(exc.object)
                    line += exc.object[: exc.start].count(b"\n")
                    cut = exc.reason == "unexpected end of data"  # the file ends inside a character
                    what = "a truncated character" if cut else f"byte 0x{exc.object[exc.start]:02x}"
                    return f"not a UTF-8 text file ({what} at offset {start + exc.start}, line {line})"
                if not chunk:
                    return None
                offset += len(chunk)
                line += chunk.count(b"\n")
    except OSError:
        return None


def not_utf8(path: str | os.PathLike[str]) -> ValueError:
    """The ValueError for a file that could not be decoded as UTF-8: names it and the byte.

    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "img.png")
    >>> _ = open(p, "wb").write(b"\\x89PNG\\r\\n")
    >>> str(not_utf8(p)).endswith("img.png: not a UTF-8 text file (byte 0x89 at offset 0, line 1)")
    True
    """
    return ValueError(f"{path}: {utf8_problem(path) or 'not a UTF-8 text file'}")


def named(exc: OSError, path: str | os.PathLike[str]) -> OSError:
    """``exc`` if it names a file, else the same error (same errno, same subclass) naming ``path``.

    >>> import errno
    >>> e = named(OSError(errno.ENOSPC, "No space left on device"), "out.csv")
    >>> (e.strerror, e.filename)
    ('No space left on device', 'out.csv')
    """
    if exc.filename is not None or exc.errno is None:
        return exc
    return OSError(exc.errno, exc.strerror, os.fspath(path))  # OSError() picks the subclass by errno


def write_text(path: str | os.PathLike[str], text: str, encoding: str | None = None) -> None:
    """``Path(path).write_text(text)`` whose OSErrors (a full disk too) name ``path``.

    >>> import os, tempfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.txt")
    >>> write_text(p, "hi\\n"); open(p).read()
    'hi\\n'
    >>> try:
    ...     write_text("/dev/full", "x" * 100_000)
    ... except OSError as exc:
    ...     print(exc.filename)
    /dev/full
    """
    try:
        Path(path).write_text(text, encoding=encoding)
    except OSError as exc:
        raise named(exc, path) from None


__all__ = ["utf8_problem", "not_utf8", "named", "write_text"]

"""USD packages (``.usdz``): their members, checked before usd-core reads them.

A ``.usdz`` is a zip archive whose members are stored uncompressed and unencrypted (the
USDZ specification, https://openusd.org/release/spec_usdz.html); the first member is the
package's root layer.  usd-core reads a package by walking its *local* file headers from
the start of the file (a package without a central directory still opens), so this module
walks them the same way and checks, before usd-core maps anything, that every member is
stored (compression method 0), unencrypted, with its size in its header, of one size
(compressed = uncompressed) and lies inside the file: a member that declares more bytes
than the file holds is one clear error naming the package and the member.

Reading a member (:func:`read_member`) takes at most its declared size, which lies inside
the file: reading a package costs at most the package's own size.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass

_LOCAL = struct.Struct("<4sHHHHHIIIHH")  # local file header, 30 bytes
_SIGNATURE = b"PK\x03\x04"

#: Most members a package may have (a real package holds a layer and its textures: tens).
MAX_MEMBERS = 10000


@dataclass(frozen=True)
class Member:
    """One member of a package: its name, where its bytes start, how many there are."""

    name: str
    offset: int
    size: int


def _fail(path: str, what: str) -> ValueError:
    return ValueError(f"{path}: not a readable USD package ({what})")


def members(path: str | os.PathLike[str]) -> list[Member]:
    """The members of a ``.usdz`` package in file order, checked (see the module docstring).

    Raises
    ------
    ValueError
        One line naming the package (and the member) when it is not a package usd-core can
        read within its own size.

    Examples
    --------
    >>> import io, os, tempfile, zipfile
    >>> d = tempfile.mkdtemp()
    >>> p = os.path.join(d, "a.usdz")
    >>> with zipfile.ZipFile(p, "w", zipfile.ZIP_STORED) as z:
    ...     z.writestr("a.usda", "#usda 1.0\\n")
    >>> [(m.name, m.size) for m in members(p)]
    [('a.usda', 10)]
    >>> with zipfile.ZipFile(p, "w", zipfile.ZIP_DEFLATED) as z:
    ...     z.writestr("a.usda", "#usda 1.0\\n")
    >>> members(p)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: ...a.usdz: not a readable USD package (member 'a.usda' is compressed (method 8); a .usdz stores its members uncompressed)
    """
    path = os.fspath(path)
    out: list[Member] = []
    with open(path, "rb") as f:
        total = os.fstat(f.fileno()).st_size
        pos = 0
        while True:
            f.seek(pos)
            head = f.read(_LOCAL.size)
            if len(head) < 4 or head[:4] != _SIGNATURE:
                break
            if len(head) < _LOCAL.size:
                raise _fail(path, f"a member header at byte {pos} is cut off by the end of the file")
            _, _, flags, method, _, _, _, csize, usize, nlen, xlen = _LOCAL.unpack(head)
            raw = f.read(nlen)
            name = raw.decode("utf-8", "replace")
            if len(raw) < nlen:
                raise _fail(path, f"the name of a member at byte {pos} is cut off by the end of the file")
            if len(out) >= MAX_MEMBERS:
                raise _fail(path, f"more than {MAX_MEMBERS} members")
            if flags & 0x1:
                raise _fail(path, f"member {name!r} is encrypted")
            if method != 0:
                raise _fail(
                    path, f"member {name!r} is compressed (method {method}); a .usdz stores its members uncompressed"
                )
            if flags & 0x8 and csize == 0:  # the sizes follow the data: usd-core reads an empty member
                raise _fail(
                    path,
                    f"member {name!r} gives its size after its data (a data descriptor), which usd-core does not read",
                )
            if csize != usize:
                raise _fail(path, f"member {name!r} declares {usize} bytes stored in {csize}")
            start = pos + _LOCAL.size + nlen + xlen
            if start + csize > total:
                raise _fail(
                    path,
                    f"member {name!r} declares {csize} bytes at byte {start}, beyond the end of the file ({total} bytes)",
                )
            out.append(Member(name, start, csize))
            pos = start + csize
    if not out:
        raise _fail(path, "not a zip archive: it does not start with a member header")
    return out


def read_member(path: str | os.PathLike[str], member: Member) -> bytes:
    """The bytes of ``member`` (from :func:`members` of the same file).

    Examples
    --------
    >>> import os, tempfile, zipfile
    >>> p = os.path.join(tempfile.mkdtemp(), "a.usdz")
    >>> with zipfile.ZipFile(p, "w") as z:
    ...     z.writestr("a.mtlx", "<materialx/>")
    >>> read_member(p, members(p)[0])
    b'<materialx/>'
    """
    with open(path, "rb") as f:
        f.seek(member.offset)
        data = f.read(member.size)
    if len(data) != member.size:
        raise _fail(os.fspath(path), f"member {member.name!r} is cut off by the end of the file")
    return data


__all__ = ["Member", "members", "read_member", "MAX_MEMBERS"]

"""Publish a finished report folder without ever deleting what this tool did not write.

Rules (see ``docs/guide/safety.md``):

- ``--out DIR`` may be a new path, an empty folder, or a previous report of this tool:
  a folder holding the marker file :data:`MARKER` whose manifest lists every other
  entry in it, each a plain relative path inside the folder, and holding only plain files
  and folders (no symbolic link, pipe or device).  Anything else (user files, ``""``, the
  home folder, ``/``, a folder holding or above an input, a symbolic link, a file, a
  marker listing ``../x`` or ``/x``) raises :class:`UnsafeOutputError` (a ``ValueError``:
  one line, exit status 2) before anything is written.
- The report is built in a hidden sibling ``.DIR.tmp-XXXXXXXX`` whose mode follows the
  umask; while it is built it holds the owner stamp :data:`STAMP` (process id and host).
- Publishing holds an exclusive ``flock`` on the parent folder (concurrent runs take
  turns), checks the target again, and swaps the folders in one step with
  ``renameat2(RENAME_EXCHANGE)`` on Linux (elsewhere: a rename of the complete sibling,
  signals held).  The old report is then removed entry by entry from its manifest,
  through folder descriptors that never follow a link; anything else in it stays.
- Under the same lock, the hidden siblings that killed runs left (``.DIR.tmp-*``,
  ``.DIR.old-*`` holding the marker, or the stamp of a process that has ended) are
  removed the same way.

Example
-------
>>> import tempfile, pathlib
>>> root = pathlib.Path(tempfile.mkdtemp())
>>> stage = staging_dir(root / "rep")
>>> _ = (stage / "index.html").write_text("<p>hi</p>")
>>> publish(stage, root / "rep")
>>> sorted(p.name for p in (root / "rep").iterdir())
['.openpbr-diffuse-report', 'index.html']
>>> (root / "mine.txt").write_text("x") and None
>>> check_target(root)
Traceback (most recent call last):
...
openpbr_diffuse.report.output.UnsafeOutputError: --out ... holds files this tool did not write (mine.txt, rep); choose a new or empty folder
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import json
import os
import re
import shutil
import signal
import socket
import stat
import sys
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .. import _signals
from .._outfile import current_umask

#: Name of the marker file a report folder holds: JSON with the manifest of what was written.
MARKER = ".openpbr-diffuse-report"
#: Name of the owner stamp a staging folder holds while its report is built (JSON: pid, host).
STAMP = ".openpbr-diffuse-staging"
#: What a staging folder holds before its marker is written (the runner's layout).
_STAGED = ("index.html", "report.json", "explore.html", "images")
_IMAGES = "images"
#: The random part of a ``tempfile.mkdtemp`` name.
_RANDOM = r"[a-z0-9_]{8}"
_TOOL = "openpbr-diffuse"
_MAX_MARKER = 16 << 20
_RENAME_EXCHANGE = 2
_AT_FDCWD = -100
#: Staging folders this process made and still owns (absolute paths): the only ones
#: :func:`discard` removes.  A folder leaves the set when it is published or swapped.
_owned: set[str] = set()


class UnsafeOutputError(ValueError):
    """``--out`` names a folder this tool may not replace (nothing was touched)."""


def _valid_entry(entry: object) -> bool:
    """Whether a manifest entry is a plain relative POSIX path inside the folder.

    Example
    -------
    >>> [_valid_entry(e) for e in ("images/a.png", "../x", "/x", "a//b", "./a", "a\\\\b", 3)]
    [True, False, False, False, False, False, False]
    """
    return (
        isinstance(entry, str)
        and "\\" not in entry
        and "\x00" not in entry
        and all(part not in ("", ".", "..") for part in entry.split("/"))
    )


def _open_dir(name: str | os.PathLike, dir_fd: int | None = None) -> int:
    """A descriptor of the folder ``name``; ``OSError`` (ELOOP, ENOTDIR) if it is a link or no folder."""
    return os.open(name, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC, dir_fd=dir_fd)


def _read_small(dir_fd: int, name: str) -> bytes | None:
    """The content of the plain file ``name`` in the folder ``dir_fd`` (None: missing, a link, not a plain file)."""
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, dir_fd=dir_fd)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            return None
        data = f.read(_MAX_MARKER + 1)
    return data if len(data) <= _MAX_MARKER else None


def _lexists(dir_fd: int, name: str) -> bool:
    try:
        os.stat(name, dir_fd=dir_fd, follow_symlinks=False)
    except OSError:
        return False
    return True


def _parse_marker(raw: bytes) -> tuple[set[str] | None, str]:
    """``(entries, "")`` of a marker's content, or ``(None, why it is not this tool's marker)``."""
    try:
        data = json.loads(raw.decode("utf-8"))
    except ValueError:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        return None, f"its {MARKER} is not JSON"
    if not isinstance(data, dict) or data.get("tool") != _TOOL or not isinstance(data.get("entries"), list):
        return None, f"its {MARKER} is not this tool's"
    bad = [e for e in data["entries"] if not _valid_entry(e)]
    if bad:
        return None, f"its {MARKER} lists {repr(bad[0])[:80]}, not a path inside the folder"
    return set(data["entries"]), ""


def _marker(folder: Path) -> tuple[set[str] | None, str]:
    """The manifest of ``folder`` as :func:`_parse_marker` gives it (``(None, "")``: no marker)."""
    try:
        fd = _open_dir(folder)
    except OSError:
        return None, ""
    try:
        raw = _read_small(fd, MARKER)
        if raw is None:
            return None, f"its {MARKER} is not a plain file" if _lexists(fd, MARKER) else ""
        return _parse_marker(raw)
    finally:
        os.close(fd)


def _scan(folder: Path) -> tuple[set[str], list[str]]:
    """Every entry below ``folder`` as relative POSIX paths (links not followed), and those
    of them that a report never holds: links, pipes, devices, sockets, unreadable folders."""
    found: set[str] = set()
    odd: list[str] = []
    stack = [("", str(folder))]
    while stack:
        rel, path = stack.pop()
        try:
            with os.scandir(path) as it:
                items = list(it)
        except OSError:
            odd.append(rel or ".")
            continue
        for item in items:
            name = f"{rel}/{item.name}" if rel else item.name
            found.add(name)
            try:
                if item.is_dir(follow_symlinks=False):
                    stack.append((name, item.path))
                elif not item.is_file(follow_symlinks=False):
                    odd.append(name)
            except OSError:
                odd.append(name)
    return found, sorted(odd)


def _shown(names: Iterable[str]) -> str:
    names = list(names)
    return ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")


def _not_a_report(folder: Path) -> str:
    """Why ``folder`` is neither empty nor a previous report of this tool ("" when it is one)."""
    entries, odd = _scan(folder)
    if not entries:
        return ""
    manifest, why = _marker(folder)
    if why:
        return f"is not a report of this tool ({why})"
    foreign = entries - (manifest or set()) - {MARKER}
    if foreign:
        shown = sorted(e for e in foreign if "/" not in e) or sorted(foreign)
        return f"holds files this tool did not write ({_shown(shown)})"
    if odd:
        return f"holds {_shown(odd)}: a link, special file or unreadable folder, which no report holds"
    return ""


def check_target(out: os.PathLike | str, inputs: Iterable[os.PathLike | str] = ()) -> Path:
    """Check that ``out`` may receive a report; return its absolute path.

    Parameters
    ----------
    out : path-like
        The ``--out`` folder.
    inputs : iterable of path-like
        The input files or folders: ``out`` may not be one of them or hold one.

    Raises
    ------
    UnsafeOutputError
        ``out`` is empty, a file, a link, the home or root folder, holds an input, holds
        entries this tool did not write, a link or special file, or a marker listing a
        path outside it.

    Example
    -------
    >>> import tempfile, pathlib
    >>> check_target(pathlib.Path(tempfile.mkdtemp()) / "new").name
    'new'
    """
    if not isinstance(out, (str, os.PathLike)) or not str(out).strip():
        raise UnsafeOutputError("--out is empty; name a new or empty folder")
    given = Path(os.path.abspath(os.fspath(out)))
    if given.is_symlink():
        raise UnsafeOutputError(f"--out {given} is a symbolic link; name a folder")
    path = given.resolve()
    protected = {Path("/"), Path(os.path.expanduser("~")).resolve()}
    if os.environ.get("HOME"):
        protected.add(Path(os.environ["HOME"]).resolve())
    if path in protected:
        raise UnsafeOutputError(f"--out {path} is the home or root folder; name a new folder")
    for item in inputs:
        p = Path(os.fspath(item)).resolve()
        if p == path or path in p.parents:
            raise UnsafeOutputError(f"--out {path} holds the input {p}; name a separate folder")
    if path.exists() or path.is_symlink():
        if not path.is_dir():
            raise UnsafeOutputError(f"--out {path} exists and is not a folder")
        why = _not_a_report(path)
        if why:
            raise UnsafeOutputError(f"--out {path} {why}; choose a new or empty folder")
    return path


def _write_stamp(folder: Path) -> None:
    doc = {"tool": _TOOL, "pid": os.getpid(), "host": socket.gethostname()}
    fd = os.open(folder / STAMP, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    try:
        os.write(fd, (json.dumps(doc) + "\n").encode())
    finally:
        os.close(fd)


def staging_dir(out: os.PathLike | str) -> Path:
    """Create the hidden sibling ``.NAME.tmp-XXXXXXXX`` of ``out`` to build a report in.

    Its mode follows the umask; it holds the owner stamp :data:`STAMP` (this process's id
    and host) until :func:`publish` puts it in place, so that a later run can tell it
    from a live run's when this one is killed.

    Example
    -------
    >>> import tempfile, pathlib
    >>> stage = staging_dir(pathlib.Path(tempfile.mkdtemp()) / "rep")
    >>> stage.name.startswith(".rep.tmp-"), [p.name for p in stage.iterdir()]
    (True, ['.openpbr-diffuse-staging'])
    >>> discard(stage); stage.exists()
    False
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    _owned.add(os.path.abspath(tmp))
    os.chmod(tmp, 0o777 & ~current_umask())
    _write_stamp(tmp)
    return tmp


def discard(tmp: os.PathLike | str) -> None:
    """Remove a staging folder made by :func:`staging_dir` that this process still owns.

    A folder already published, or the previous report swapped to the staging name by
    :func:`publish`, is no longer owned and is left alone (as is a missing one).

    Example
    -------
    >>> import tempfile, pathlib
    >>> other = pathlib.Path(tempfile.mkdtemp())
    >>> discard(other); other.exists()   # not made by staging_dir: left
    True
    """
    key = os.path.abspath(tmp)
    if key not in _owned:
        return
    with _signals.blocked():
        _owned.discard(key)
        shutil.rmtree(tmp, ignore_errors=True)


def _write_marker(folder: Path) -> None:
    from .._version import __version__

    entries = sorted(_scan(folder)[0] - {MARKER, STAMP})
    doc = {"tool": _TOOL, "version": __version__, "entries": entries}
    (folder / MARKER).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")


@contextlib.contextmanager
def _locked(folder: Path) -> Iterator[None]:
    """Exclusive ``flock`` on ``folder`` itself (no lock file is left behind)."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically with ``renameat2(RENAME_EXCHANGE)``; ``False`` if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if fn(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _remove_listed(folder: Path, entries: Iterable[str]) -> bool:
    """Remove the listed entries of ``folder``, deepest first, then ``folder`` if it is empty.

    Never follows a link: ``folder`` and each folder on an entry's way are opened with
    ``O_NOFOLLOW`` relative to the previous one; a plain file is unlinked, a folder removed
    only when empty; a link, a special file, an entry that vanished or a folder that holds
    something unlisted is left.  Returns whether ``folder`` is gone.
    """
    try:
        top = _open_dir(folder)
    except OSError:
        return not os.path.lexists(folder)
    try:
        for rel in sorted(set(filter(_valid_entry, entries)), key=lambda e: (e.count("/"), e), reverse=True):
            *way, name = rel.split("/")
            fd = top
            try:
                for part in way:
                    nxt = _open_dir(part, fd)
                    if fd != top:
                        os.close(fd)
                    fd = nxt
                mode = os.stat(name, dir_fd=fd, follow_symlinks=False).st_mode
                if stat.S_ISDIR(mode):
                    os.rmdir(name, dir_fd=fd)
                elif stat.S_ISREG(mode):
                    os.unlink(name, dir_fd=fd)
            except OSError:  # ENOENT, ENOTEMPTY, ELOOP, ENOTDIR, EACCES...: the entry stays
                pass
            finally:
                if fd != top:
                    os.close(fd)
    finally:
        os.close(top)
    try:
        os.rmdir(folder)
    except OSError:
        return False
    return True


def _retire(old: Path, manifest: set[str]) -> None:
    """Remove the previous report swapped out to ``old``: only what its manifest lists."""
    if _remove_listed(old, manifest | {MARKER}):
        return
    left = sorted(_scan(old)[0]) if old.is_dir() and not old.is_symlink() else []
    sys.stderr.write(
        f"{_TOOL}: warning: kept {old} with {_shown(left)}, which this tool did not write "
        "(the new report is in place)\n"
    )


def _alive(stamp: bytes) -> bool:
    """Whether the run that wrote a staging stamp may still be running (unknown: True)."""
    try:
        doc = json.loads(stamp.decode("utf-8"))
        pid, host = int(doc["pid"]), doc["host"]
    except (ValueError, TypeError, KeyError):
        return True
    if doc.get("tool") != _TOOL or host != socket.gethostname() or pid <= 0 or pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # the process exists under another user
        return True
    return True


def _sweep(out: Path) -> None:
    """Remove what killed runs left beside ``out``; call it holding the parent folder's lock.

    A sibling ``.NAME.tmp-XXXXXXXX`` or ``.NAME.old-XXXXXXXX`` (the names ``mkdtemp`` gives)
    is the tool's when it is a real folder holding the tool's marker, or the owner stamp of
    a process of this host that has ended; a stamp of a live process, of another host or
    of this process leaves it alone.  Only the marker's entries, and for a stamped folder
    the runner's layout (``index.html``, ``report.json``, ``images/*``), are removed, as by
    :func:`_remove_listed`; anything else stays, with its folder.
    """
    pattern = re.compile(re.escape(f".{out.name}.") + f"(tmp|old)-{_RANDOM}")
    try:
        names = sorted(os.listdir(out.parent))
    except OSError:
        return
    for name in names:
        path = out.parent / name
        if not pattern.fullmatch(name) or os.path.abspath(path) in _owned:
            continue
        try:
            fd = _open_dir(path)
        except OSError:
            continue
        try:
            known: set[str] = set()
            stamp = _read_small(fd, STAMP)
            if stamp is None and _lexists(fd, STAMP):
                continue  # a stamp that cannot be read: kept
            if stamp is not None:
                if _alive(stamp):
                    continue
                known |= {STAMP, *_STAGED}
                with contextlib.suppress(OSError):
                    images = _open_dir(_IMAGES, fd)
                    try:
                        known |= {f"{_IMAGES}/{n}" for n in os.listdir(images)}
                    finally:
                        os.close(images)
            raw = _read_small(fd, MARKER)
            manifest = _parse_marker(raw)[0] if raw is not None else None
            if manifest is not None:
                known |= manifest | {MARKER}
        finally:
            os.close(fd)
        if known:
            _remove_listed(path, known)


def _held_signal() -> None:
    """Raise :class:`_signals.Terminated` for a termination signal that arrived inside the
    held step: recorded by the handler, or still pending in the signal mask."""
    _signals.check()
    pending = set(signal.sigpending()) & set(_signals.SIGNALS) if hasattr(signal, "sigpending") else set()
    if pending:
        raise _signals.Terminated(min(pending))


def publish(tmp: os.PathLike | str, out: os.PathLike | str, inputs: Iterable[os.PathLike | str] = ()) -> None:
    """Put the complete report ``tmp`` at ``out`` in one step and remove the previous one.

    Writes the marker into ``tmp``, then under an exclusive lock on the parent folder checks
    ``out`` again (:func:`check_target`), removes the leftovers of killed runs, and swaps.
    On an error before the swap ``out`` is left as it was and ``tmp`` is removed.  After the
    swap only the entries the previous report's manifest lists are removed, never through a
    link; anything else in it stays where it is (one warning line on stderr names it).

    Raises
    ------
    UnsafeOutputError
        ``out`` became unsafe to replace meanwhile.
    _signals.Terminated
        A termination signal arrived during the run, up to the swap (nothing is published;
        one still pending in the held step counts).  One that arrives after the swap lets
        the run end normally with the new report.

    Example
    -------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "rep"
    >>> for text in ("first", "second"):
    ...     stage = staging_dir(out)
    ...     _ = (stage / "index.html").write_text(text)
    ...     publish(stage, out)
    >>> (out / "index.html").read_text(), sorted(p.name for p in out.parent.iterdir())
    ('second', ['rep'])
    """
    tmp, out = Path(tmp), Path(out)
    inputs = list(inputs)
    key = os.path.abspath(tmp)
    published = False
    try:
        _write_marker(tmp)
        with _locked(out.parent), _signals.blocked():
            _signals.check()
            target = check_target(out, inputs)
            _sweep(target)
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp / STAMP)
            _held_signal()  # the last moment to stop: from here on the new report is put in place
            if not target.exists():
                os.rename(tmp, target)
                _owned.discard(key)
                published = True
                return
            manifest = _marker(target)[0] or set()
            if _exchange(tmp, target):
                _owned.discard(key)  # ``tmp`` now names the previous report: never discard it
                old = tmp
            else:
                old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
                old.rmdir()
                os.rename(target, old)
                try:
                    os.rename(tmp, target)
                except BaseException:
                    os.rename(old, target)
                    raise
                _owned.discard(key)
            published = True
            _retire(old, manifest)
    except _signals.Terminated:
        if not published:
            raise
        # the signal arrived once the new report was in place: the run ends with it
    finally:
        discard(tmp)  # only while this run still owns it, i.e. before the swap


__all__ = ["MARKER", "STAMP", "UnsafeOutputError", "check_target", "discard", "publish", "staging_dir"]

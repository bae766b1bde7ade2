"""Publish a finished report folder without ever deleting what this tool did not write.

Rules (see ``docs/guide/safety.md``):

- ``--out DIR`` may be a new path, an empty folder, or a previous report of this tool:
  a folder holding the marker file :data:`MARKER` whose manifest lists every other
  entry in it.  Anything else (user files, ``""``, the home folder, ``/``, a folder
  holding or above an input, a symbolic link, a file) raises :class:`UnsafeOutputError`
  (a ``ValueError``: one line, exit status 2) before anything is written.
- The report is built in a hidden sibling ``.DIR.tmp-XXXX`` whose mode follows the umask.
- Publishing holds an exclusive ``flock`` on the parent folder (concurrent runs take
  turns), checks the target again, and swaps the folders in one step with
  ``renameat2(RENAME_EXCHANGE)`` on Linux (elsewhere: a rename of the complete sibling,
  signals held).  The old report is then removed entry by entry from its manifest.

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
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from .. import _signals

#: Name of the marker file a report folder holds: JSON with the manifest of what was written.
MARKER = ".openpbr-diffuse-report"
_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


class UnsafeOutputError(ValueError):
    """``--out`` names a folder this tool may not replace (nothing was touched)."""


def _entries(folder: Path) -> set[str]:
    """Every file, folder and link below ``folder`` as relative POSIX paths (links not followed)."""
    found = set()
    for root, dirs, files in os.walk(folder, followlinks=False):
        rel = Path(root).relative_to(folder)
        for name in dirs + files:
            found.add((rel / name).as_posix())
    return found


def _manifest(folder: Path) -> set[str] | None:
    """The manifest of a report folder, or ``None`` when ``folder`` holds no valid marker."""
    marker = folder / MARKER
    if marker.is_symlink() or not marker.is_file():
        return None
    try:
        data = json.loads(marker.read_text(encoding="utf-8"))
        if data.get("tool") != "openpbr-diffuse" or not isinstance(data.get("entries"), list):
            return None
        return {str(e) for e in data["entries"]}
    except (OSError, ValueError, UnicodeDecodeError, AttributeError):
        return None


def _is_previous_report(folder: Path) -> bool:
    manifest = _manifest(folder)
    return manifest is not None and _entries(folder) - {MARKER} <= manifest


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
        ``out`` is empty, a file, a link, the home or root folder, holds an input, or holds
        entries this tool did not write.
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
        entries = _entries(path)
        if entries and not _is_previous_report(path):
            manifest = _manifest(path) or set()
            foreign = sorted(e for e in entries - manifest - {MARKER} if "/" not in e)
            foreign = foreign or sorted(entries - manifest - {MARKER})
            shown = ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
            raise UnsafeOutputError(
                f"--out {path} holds files this tool did not write ({shown}); choose a new or empty folder"
            )
    return path


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def staging_dir(out: os.PathLike | str) -> Path:
    """Create the hidden sibling ``.NAME.tmp-XXXX`` of ``out`` to build a report in (mode per umask)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    os.chmod(tmp, 0o777 & ~_umask())
    return tmp


def discard(tmp: os.PathLike | str) -> None:
    """Remove a staging folder made by :func:`staging_dir` (a missing one is fine)."""
    with _signals.blocked():
        shutil.rmtree(tmp, ignore_errors=True)


def _write_marker(folder: Path) -> None:
    from .._version import __version__

    entries = sorted(_entries(folder) - {MARKER})
    doc = {"tool": "openpbr-diffuse", "version": __version__, "entries": entries}
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


def _remove_report(folder: Path, manifest: set[str]) -> None:
    """Delete the listed entries of an old report, deepest first, then the folder if empty."""
    for rel in sorted(manifest | {MARKER}, key=lambda e: e.count("/"), reverse=True):
        p = folder / rel
        try:
            if p.is_dir() and not p.is_symlink():
                p.rmdir()
            else:
                p.unlink()
        except FileNotFoundError:
            pass
    with contextlib.suppress(OSError):
        folder.rmdir()


def publish(tmp: os.PathLike | str, out: os.PathLike | str, inputs: Iterable[os.PathLike | str] = ()) -> None:
    """Put the complete report ``tmp`` at ``out`` in one step and remove the previous one.

    Writes the marker into ``tmp``, then under an exclusive lock on the parent folder checks
    ``out`` again (:func:`check_target`) and swaps.  On any error ``out`` is left as it was and
    ``tmp`` is removed.

    Raises
    ------
    UnsafeOutputError
        ``out`` became unsafe to replace meanwhile.
    _signals.Terminated
        A termination signal arrived during the run (nothing is published).
    """
    tmp, out = Path(tmp), Path(out)
    inputs = list(inputs)
    try:
        _write_marker(tmp)
        with _locked(out.parent), _signals.blocked():
            _signals.check()
            target = check_target(out, inputs)
            if not target.exists():
                os.rename(tmp, target)
                return
            manifest = _manifest(target) or set()
            if _exchange(tmp, target):
                old = tmp  # the previous report now sits at the staging name
                if _entries(old) - {MARKER} <= manifest:
                    _remove_report(old, manifest)
                    return
                _exchange(tmp, target)  # something was added meanwhile: put it back
                raise UnsafeOutputError(f"--out {target} changed while the report was written; left as it was")
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
            old.rmdir()
            os.rename(target, old)
            try:
                os.rename(tmp, target)
            except BaseException:
                os.rename(old, target)
                raise
            _remove_report(old, manifest)
    finally:
        if tmp.exists() and tmp.resolve() != Path(out).resolve():
            discard(tmp)


__all__ = ["MARKER", "UnsafeOutputError", "check_target", "discard", "publish", "staging_dir"]

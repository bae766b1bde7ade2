"""Publishing a finished report folder without ever deleting what this tool did not write.

Rules (``report --out DIR``):

- ``DIR`` may be a new path, an empty folder, or a previous report of this tool: a folder
  holding the marker file :data:`MARKER` (a JSON manifest of every file and folder the tool
  wrote there) and nothing that the manifest does not list.  Anything else — a folder with
  any other file, a file, the current directory or one of its ancestors, the home folder,
  ``""`` — is refused with one line (``ValueError``: exit 2) before any work starts, and is
  not touched.
- The report is written into a hidden sibling ``.DIR.tmp-XXXX`` and swapped into place in
  one step: ``renameat2(RENAME_EXCHANGE)`` where the kernel has it (Linux), a single
  ``rename`` when ``DIR`` does not exist.  The replaced report (now under the sibling's name)
  is removed file by file from its own manifest, so a file added to it meanwhile survives.
- Concurrent runs to one ``DIR`` take an exclusive ``flock`` on the parent folder for the
  swap: each ends with a complete report in place (the last one wins) or a clear error.
- SIGINT/SIGTERM/SIGHUP are held during the swap (see :mod:`openpbr_diffuse._signals`) and
  a signal received earlier — even one a library swallowed — stops the run before the swap:
  the old report or the new one is in place, never neither, and no temporary folder stays.
- The new folder's permissions follow the umask (not ``mkdtemp``'s 0700).

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> (d / "thesis.tex").write_text("x")
1
>>> try:
...     check_target(d)
... except ValueError as e:
...     print(str(e).split(";")[0])
report: --out ... holds files this tool did not write (thesis.tex)
"""
from __future__ import annotations

import ctypes
import errno
import fcntl
import json
import os
import shutil
import tempfile
from pathlib import Path

from .. import _signals

#: The marker file of a report folder: {"tool": "openpbr-diffuse", "files": [relative paths]}.
MARKER = ".openpbr-diffuse-report"
_TOOL = "openpbr-diffuse"
_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _manifest(folder: Path) -> set[str] | None:
    """The paths a previous report lists in its marker, or None when ``folder`` is not one."""
    try:
        data = json.loads((folder / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("tool") != _TOOL or not isinstance(data.get("files"), list):
        return None
    return {str(p) for p in data["files"]} | {MARKER}


def _contents(folder: Path) -> list[str]:
    """Every file and folder below ``folder``, relative, without following symlinks."""
    out = []
    for root, dirs, files in os.walk(folder, followlinks=False):
        rel = Path(root).relative_to(folder)
        for name in dirs + files:
            out.append(str(rel / name) if str(rel) != "." else name)
    return sorted(out)


def _foreign(folder: Path) -> list[str]:
    """What ``folder`` holds that this tool did not write ([] for an empty folder)."""
    contents = _contents(folder)
    if not contents:
        return []
    listed = _manifest(folder)
    if listed is None:
        return contents
    return [c for c in contents if c not in listed]


def check_target(out: str | Path) -> Path:
    """The resolved ``--out`` folder, or ``ValueError`` when it may not be written.

    Parameters
    ----------
    out : path-like
        The requested output folder.

    Returns
    -------
    Path
        ``out`` resolved (absolute).

    Raises
    ------
    ValueError
        ``out`` is empty, a file, the current folder or an ancestor of it, the home folder,
        the filesystem root, or a folder holding anything this tool did not write.
    """
    if str(out).strip() == "":
        raise ValueError("report: --out must name a folder (got an empty string)")
    path = Path(out).expanduser().resolve()
    cwd = Path.cwd().resolve()
    home = Path.home().resolve()
    if path == Path(path.anchor) or path == home or path == cwd or path in cwd.parents:
        raise ValueError(f"report: --out {path} is the current folder, one of its parents, the home "
                         f"folder or the root; choose a new or empty folder for the report")
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        raise ValueError(f"report: --out {path} exists and is not a folder; nothing was written")
    if path.is_dir():
        foreign = _foreign(path)
        if foreign:
            shown = ", ".join(foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
            raise ValueError(f"report: --out {path} holds files this tool did not write ({shown}); "
                             f"choose a new or empty folder, or a previous report's folder")
    return path


def make_temp(out: Path) -> Path:
    """A hidden sibling folder of ``out`` to write the report into, with umask permissions."""
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(tmp, 0o777 & ~mask)
    return tmp


def _write_manifest(tmp: Path) -> None:
    files = _contents(tmp)
    (tmp / MARKER).write_text(json.dumps({"tool": _TOOL, "files": files}, indent=1) + "\n", encoding="utf-8")


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically (Linux ``renameat2``); False when the call is not available."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if fn(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP if hasattr(errno, "ENOTSUP") else errno.EINVAL):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _remove_report(folder: Path) -> None:
    """Remove a replaced report: only what its manifest lists, then the folder if empty."""
    listed = _manifest(folder)
    if listed is None:  # an empty folder that was replaced
        try:
            folder.rmdir()
        except OSError:
            pass
        return
    for rel in sorted(listed, key=lambda p: -p.count("/")):
        p = folder / rel
        try:
            if p.is_dir() and not p.is_symlink():
                p.rmdir()
            else:
                p.unlink()
        except OSError:
            pass  # absent, or a folder that now holds something else: left in place
    try:
        folder.rmdir()
    except OSError:
        pass


def publish(tmp: Path, out: Path) -> None:
    """Swap the complete report ``tmp`` into ``out`` (see the module docstring for the rules).

    Raises
    ------
    ValueError
        ``out`` changed meanwhile into something that may not be replaced (``tmp`` is removed).
    KeyboardInterrupt, openpbr_diffuse._signals.Terminated
        A termination signal was received during the run: nothing is replaced.
    """
    _write_manifest(tmp)
    _signals.raise_if_received()
    with _signals.blocked():
        fd = os.open(out.parent, os.O_RDONLY)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            _signals.raise_if_received()
            check_target(out)  # again, under the lock
            if not out.exists():
                os.rename(tmp, out)
                return
            if _exchange(tmp, out):
                _remove_report(tmp)  # tmp now holds the replaced report
                return
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            old.rmdir()
            out.rename(old)
            try:
                tmp.rename(out)
            except BaseException:
                old.rename(out)
                raise
            _remove_report(old)
        finally:
            os.close(fd)  # releases the lock


def discard(tmp: Path) -> None:
    """Remove an unfinished report folder (it holds only what this run wrote)."""
    shutil.rmtree(tmp, ignore_errors=True)


__all__ = ["MARKER", "check_target", "make_temp", "publish", "discard"]

"""Output files of the command line: one rule for every file a command writes.

``report --junit``, ``render --out``, ``colorshift --image``, ``albedo --export`` (the LUT
files), ``vectors --out`` and ``template --out`` all go through :func:`check_output_file`
(called before any work) and :func:`output_file` (which writes).  The rule (see
``docs/guide/safety.md``):

- an existing file is not replaced unless ``force``; with ``force`` only a regular file is
  (never a folder, device, FIFO or socket);
- never an input of the same run, even with ``force`` (same file: ``os.path.samefile``);
- never through a symbolic link: a link at the path is refused, even with ``force``;
- the parent folder must exist and be writable;
- the data goes to a temporary sibling ``.NAME.XXXXXXXX.tmp.SUFFIX`` (created with
  ``O_EXCL | O_NOFOLLOW``, mode per the umask), is flushed to disk, and only then takes the
  name: linked without replacing (a file created meanwhile is never clobbered) or, with
  ``force``, renamed over the old file.  On any error the temporary file is removed.

Every refusal is an :class:`OutputFileError` (a ``ValueError``) whose one-line message
names the option and the path.

Example
-------
>>> import pathlib, tempfile
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> write_output_file(d / "a.txt", "one\\n", option="--out").read_text()
'one\\n'
>>> write_output_file(d / "a.txt", "two\\n", option="--out")
Traceback (most recent call last):
...
openpbr_diffuse._outfile.OutputExistsError: --out .../a.txt exists: not overwritten (use --force to replace it)
>>> write_output_file(d / "a.txt", "two\\n", option="--out", force=True).read_text()
'two\\n'
>>> sorted(p.name for p in d.iterdir())   # no temporary file left
['a.txt']
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path

from . import _signals

PathLike = str | os.PathLike[str]

#: Characters of the target's name kept in the temporary file's name (NAME_MAX is 255).
_NAME_KEPT = 100


class OutputFileError(ValueError):
    """An output file may not be written as asked (nothing was written)."""


class OutputExistsError(OutputFileError, FileExistsError):
    """The output file exists and ``force`` was not given."""


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _is_input(target: Path, st: os.stat_result, inputs: Iterable[PathLike], input_suffixes: tuple[str, ...]) -> bool:
    """Whether the existing file ``target`` (its ``lstat``) is one of ``inputs`` or, for a
    folder among them, a file below it with one of ``input_suffixes``."""
    suffix = target.suffix.lower()
    resolved = None
    for item in inputs:
        try:
            ist = os.stat(item)
        except (OSError, ValueError):
            continue
        if (ist.st_dev, ist.st_ino) == (st.st_dev, st.st_ino):
            return True
        if stat.S_ISDIR(ist.st_mode) and suffix in input_suffixes:
            resolved = resolved or target.resolve()
            if Path(item).resolve() in resolved.parents:
                return True
    return False


def check_output_file(
    path: PathLike,
    *,
    option: str = "--out",
    force: bool = False,
    inputs: Iterable[PathLike] = (),
    input_suffixes: Iterable[str] = (),
) -> Path:
    """Check that ``path`` may receive an output file; return it as an absolute path.

    Run it before the work that produces the file, so that a refusal costs nothing.

    Parameters
    ----------
    path : path-like
        The output file.
    option : str
        The option that named it (``--out``, ``--junit``, ...): the messages start with it.
    force : bool
        Whether an existing regular file may be replaced.
    inputs : iterable of path-like
        The files (and folders) the same run reads: never written, even with ``force``.
    input_suffixes : iterable of str
        For a folder among ``inputs``: the existing files below it with one of these
        suffixes (lower case, with the dot) are inputs too.

    Raises
    ------
    OutputFileError
        ``path`` is empty, a symbolic link, a folder or other non-regular file, an input,
        an existing file without ``force`` (:class:`OutputExistsError`), or its folder is
        missing or not writable.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> check_output_file(d / "new.png", option="--out").name
    'new.png'
    >>> check_output_file(d / "no" / "x.png", option="--out")
    Traceback (most recent call last):
    ...
    openpbr_diffuse._outfile.OutputFileError: --out .../no/x.png: the folder .../no does not exist
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{option}: expected a path, got {type(path).__name__}")
    text = os.fspath(path)
    if not str(text).strip():
        raise OutputFileError(f"{option} is empty; name a file")
    if str(text).endswith(("/", os.sep)):
        raise OutputFileError(f"{option} {text} names a folder; name a file")
    target = Path(os.path.abspath(text))
    try:
        st: os.stat_result | None = os.lstat(target)
    except (FileNotFoundError, NotADirectoryError):
        st = None
    except OSError as exc:
        raise OutputFileError(f"{option} {text}: cannot be checked ({exc.strerror})") from None
    if st is not None:
        if stat.S_ISLNK(st.st_mode):
            raise OutputFileError(f"{option} {text} is a symbolic link; not written through")
        if not stat.S_ISREG(st.st_mode):
            raise OutputFileError(f"{option} {text} is {_kind(st.st_mode)}; name a file")
        if _is_input(target, st, inputs, tuple(s.lower() for s in input_suffixes)):
            raise OutputFileError(f"{option} {text} is an input of this run; choose another file")
        if not force:
            raise OutputExistsError(f"{option} {text} exists: not overwritten (use --force to replace it)")
    parent = target.parent
    if not parent.exists():
        raise OutputFileError(f"{option} {text}: the folder {parent} does not exist")
    if not parent.is_dir():
        raise OutputFileError(f"{option} {text}: {parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputFileError(f"{option} {text}: the folder {parent} is not writable")
    return target


def current_umask() -> int:
    """This process's file mode creation mask (``os.umask`` only sets it: set and set back).

    >>> old = os.umask(0o027)
    >>> current_umask() == 0o027
    True
    >>> _ = os.umask(old)
    """
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _fsync_folder(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _place(tmp: str, target: Path, force: bool, option: str, text: str) -> None:
    """Give the complete temporary file ``tmp`` the name ``target`` (signals held)."""
    with _signals.blocked():
        if force:
            os.replace(tmp, target)  # a rename: replaces a name, never writes through a link
            return
        try:
            os.link(tmp, target)  # fails if anything took the name meanwhile
        except FileExistsError:
            raise OutputExistsError(f"{option} {text} exists: not overwritten (use --force to replace it)") from None
        except OSError as exc:  # a file system without hard links
            if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EMLINK, errno.ENOSYS):
                raise
            if os.path.lexists(target):
                raise OutputExistsError(
                    f"{option} {text} exists: not overwritten (use --force to replace it)"
                ) from None
            os.rename(tmp, target)
            return
        os.unlink(tmp)


@contextlib.contextmanager
def output_file(
    path: PathLike,
    *,
    option: str = "--out",
    force: bool = False,
    inputs: Iterable[PathLike] = (),
    input_suffixes: Iterable[str] = (),
) -> Iterator[Path]:
    """Context manager: a temporary sibling of ``path`` to write; on success it becomes ``path``.

    The temporary file exists (empty) and keeps ``path``'s suffix, so writers that pick the
    format by suffix (OpenImageIO) work on it.  The checks of :func:`check_output_file` run
    on entry and again just before the file takes its name; an exception inside the block
    (or a refusal) removes the temporary file and leaves ``path`` as it was.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with output_file(d / "x.csv", option="--out") as tmp:
    ...     _ = tmp.write_text("a,b\\n")
    ...     tmp.name.startswith(".x.csv.") and tmp.suffix == ".csv"
    True
    >>> [p.name for p in d.iterdir()]
    ['x.csv']
    """
    inputs = list(inputs)
    input_suffixes = tuple(input_suffixes)
    text = os.fspath(path)

    def check() -> Path:
        return check_output_file(path, option=option, force=force, inputs=inputs, input_suffixes=input_suffixes)

    target = check()
    fd: int | None = None
    tmp: str | None = None
    try:
        with _signals.blocked():  # a signal now arrives once ``tmp`` names the file, in this ``try``
            fd, tmp = tempfile.mkstemp(
                prefix=f".{target.name[:_NAME_KEPT]}.", suffix=".tmp" + target.suffix[:16], dir=target.parent
            )
        made = os.fstat(fd)
        yield Path(tmp)
        now = os.lstat(tmp)
        if (now.st_dev, now.st_ino) != (made.st_dev, made.st_ino):
            raise OutputFileError(f"{option} {text}: the temporary file {tmp} was replaced while written")
        os.fchmod(fd, 0o666 & ~current_umask())
        os.fsync(fd)
        _signals.check()  # a signal that arrived (and was swallowed) publishes nothing
        check()
        _place(tmp, target, force, option, text)
        _fsync_folder(target.parent)
    except BaseException as exc:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        if (
            isinstance(exc, OSError)
            and exc.errno is not None
            and (tmp is None or exc.filename in (None, tmp, Path(tmp)))
        ):
            # a full disk (write, fsync) names no file, or the temporary one: name the output
            raise OSError(exc.errno, exc.strerror, text) from None
        raise
    finally:
        if fd is not None:
            os.close(fd)


def write_output_file(
    path: PathLike,
    data: str | bytes,
    *,
    option: str = "--out",
    force: bool = False,
    inputs: Iterable[PathLike] = (),
    encoding: str = "utf-8",
) -> Path:
    """Write ``data`` (text in ``encoding``, or bytes) to ``path`` by :func:`output_file`.

    Returns the absolute path written.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_output_file(d / "b.bin", b"\\x00\\x01", option="--out").read_bytes()
    b'\\x00\\x01'
    """
    raw = data.encode(encoding) if isinstance(data, str) else bytes(data)
    with output_file(path, option=option, force=force, inputs=inputs) as tmp:
        tmp.write_bytes(raw)
    return Path(os.path.abspath(os.fspath(path)))


__all__ = [
    "OutputExistsError",
    "OutputFileError",
    "check_output_file",
    "current_umask",
    "output_file",
    "write_output_file",
]

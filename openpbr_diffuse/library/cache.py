"""The results of material files kept on disk, never stale.

Location: ``--cache-dir DIR``, else ``$OPENPBR_DIFFUSE_CACHE_DIR``, else
``$XDG_CACHE_HOME/openpbr-diffuse/library`` (``~/.cache/openpbr-diffuse/library``).

An entry is found by a key made of the file's absolute path, the task (what is computed and
with which options, :class:`.worker.Task`), the code's fingerprint (:func:`code_fingerprint`:
the package's files that the work uses and the versions of usd-core, MaterialX, OpenImageIO,
numpy and numba)
and the environment that changes how files resolve (``PXR_*``, ``MATERIALX_*``, ``OCIO``).
It holds the SHA-256 of the file and of every file the result depends on (:mod:`.deps`),
and is used only while all of them are unchanged: edit a sublayer or a texture, or create a
file that was missing, and the material is evaluated again.

Entries are JSON files ``DIR/v1/<2 hex>/<key>.json``, written to a temporary sibling and
renamed into place (a reader sees the old entry or the new one, never half of one); an entry
that cannot be read or parsed is ignored (and replaced when the file is evaluated again).
Nothing else in ``DIR`` is touched; entries of files that are gone stay until the folder is
removed by hand (``rm -r DIR``: the cache holds nothing else).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from .deps import Hasher

#: Version of the entries' layout (a sub-folder of the cache folder).
LAYOUT = "v1"
#: Environment variables that change how files resolve or convert (part of the key).
ENV_PREFIXES = ("PXR_", "MATERIALX_", "OCIO")


def default_cache_dir() -> Path:
    """The cache folder when none is given (see the module docstring).

    >>> import os
    >>> old = os.environ.get("OPENPBR_DIFFUSE_CACHE_DIR")
    >>> os.environ["OPENPBR_DIFFUSE_CACHE_DIR"] = "/tmp/c"
    >>> str(default_cache_dir())
    '/tmp/c'
    >>> _ = os.environ.pop("OPENPBR_DIFFUSE_CACHE_DIR") if old is None else os.environ.update(OPENPBR_DIFFUSE_CACHE_DIR=old)
    """
    given = os.environ.get("OPENPBR_DIFFUSE_CACHE_DIR")
    if given:
        return Path(given)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "openpbr-diffuse" / "library"


#: Parts of the package that the work on a file never imports (the command line, the report
#: page, the graders, ...) and the bundled materials (inputs, hashed as such): left out of the
#: code's fingerprint, so that editing them keeps the cache.  A test runs the work on every
#: bundled file in a fresh interpreter and checks that none of them was imported.
NOT_IN_THE_WORK = ("cli", "report", "graders", "conformance", "approximations", "spectral", "materials", "__main__.py")


@functools.lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 of the package's files that the work on a file may use (every file but
    :data:`NOT_IN_THE_WORK` and caches), and of the readers' libraries' versions.

    >>> len(code_fingerprint())
    64
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if rel.parts[0] in NOT_IN_THE_WORK or not p.is_file():
            continue
        if "__pycache__" in rel.parts or p.suffix in (".pyc", ".nbi", ".nbc"):
            continue
        h.update(rel.as_posix().encode() + b"\0")
        h.update(p.read_bytes() + b"\0")
    for module in ("pxr", "MaterialX", "OpenImageIO", "numpy", "numba"):
        h.update(f"{module}={_version(module)}\0".encode())
    return h.hexdigest()


def _version(module: str) -> str:
    import importlib

    try:
        m = importlib.import_module(module)
    except ImportError:
        return "absent"
    if module == "pxr":
        from pxr import Usd

        return ".".join(str(x) for x in Usd.GetVersion())
    return str(getattr(m, "__version__", getattr(m, "VERSION_STRING", "?")))


def env_fingerprint() -> dict[str, str]:
    """The environment variables that change how files resolve (see :data:`ENV_PREFIXES`).

    >>> all(k.startswith(ENV_PREFIXES) for k in env_fingerprint())
    True
    """
    return {k: v for k, v in sorted(os.environ.items()) if k.startswith(ENV_PREFIXES)}


class Cache:
    """The cache folder ``folder`` (created when first written).

    Examples
    --------
    >>> import tempfile
    >>> from openpbr_diffuse.library.worker import Task, process_file
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> cache = Cache(tempfile.mkdtemp())
    >>> clay = str(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> cache.get(clay, Task()) is None
    True
    >>> cache.put(clay, Task(), process_file(clay, Task()))
    True
    >>> cache.get(clay, Task())["records"][0]["material"]
    'clay_rough'
    """

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.folder = Path(folder)
        self.hasher = Hasher()
        self.hits = 0
        self.misses = 0
        self.written = 0
        #: why the last entry could not be written (a read-only folder, a full disk), or None
        self.write_error: str | None = None

    def forget(self) -> None:
        """Forget the hashes remembered so far (each batch of files hashes what it looks at
        anew: a file edited between two batches is seen as edited)."""
        self.hasher = Hasher()

    def key(self, path: str, task: Any) -> str:
        """The entry's name for ``path`` and ``task`` (hex SHA-256)."""
        doc = {
            "path": os.path.abspath(path),
            "task": task.key(),
            "code": code_fingerprint(),
            "env": env_fingerprint(),
            "layout": LAYOUT,
        }
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()

    def entry_path(self, path: str, task: Any) -> Path:
        """Where the entry of ``path`` and ``task`` is stored."""
        key = self.key(path, task)
        return self.folder / LAYOUT / key[:2] / f"{key}.json"

    def get(self, path: str, task: Any) -> dict[str, Any] | None:
        """The stored payload, or None (no entry, a changed file or dependency, a bad entry)."""
        found = self._valid(path, task)
        if found is None:
            self.misses += 1
        else:
            self.hits += 1
        return found

    def holds(self, path: str, task: Any) -> bool:
        """Whether a valid entry of ``path`` and ``task`` is stored (not counted as a hit)."""
        return self._valid(path, task) is not None

    def _valid(self, path: str, task: Any) -> dict[str, Any] | None:
        try:
            entry = json.loads(self.entry_path(path, task).read_text(encoding="utf-8"))
            if entry.get("path") != os.path.abspath(path) or not isinstance(entry.get("payload"), dict):
                return None
            if entry.get("file_hash") is None or self.hasher(os.path.abspath(path)) != entry["file_hash"]:
                return None
            for dep, digest in entry["deps"]:
                if self.hasher(dep) != digest:
                    return None
            return entry["payload"]
        except (OSError, ValueError, TypeError, KeyError, AttributeError):
            return None

    def put(self, path: str, task: Any, outcome: dict[str, Any]) -> bool:
        """Store ``outcome`` (what :func:`.worker.process_file` returned) when it may be kept:
        it says so, it was computed by this code, and the file is as it was when the run
        looked at it.  Returns whether it was stored; a write that fails is skipped
        (``write_error`` says why)."""
        path = os.path.abspath(path)
        if not outcome.get("cacheable") or outcome.get("code") != code_fingerprint():
            return False
        if outcome.get("file_hash") is None or outcome["file_hash"] != self.hasher(path):
            return False
        entry = {
            "path": path,
            "file_hash": outcome["file_hash"],
            "deps": outcome["deps"],
            "payload": outcome["payload"],
        }
        target = self.entry_path(path, task)
        tmp = None
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.stem[:16]}.", suffix=".tmp", dir=target.parent)
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                json.dump(entry, fh, allow_nan=False, separators=(",", ":"))
            os.replace(tmp, target)
        except (OSError, ValueError) as exc:
            self.write_error = f"{target}: {exc}"
            if tmp is not None:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
            return False
        self.written += 1
        return True


__all__ = ["Cache", "LAYOUT", "NOT_IN_THE_WORK", "code_fingerprint", "default_cache_dir", "env_fingerprint"]

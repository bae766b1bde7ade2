"""Which files a material file's result depends on, and their content hashes.

A material's values come from its own file and from every file that file composes: USD
sublayers, references and payloads, textures, ``.mtlx`` documents referenced from USD, and
MaterialX ``xi:include``s and ``filename`` inputs.  Two sources are joined (conservatively:
a file either source names is a dependency):

- **what the readers opened** (:func:`recording`): while a file is read, the readers'
  texture lookups (``textures.info`` / ``textures.sample``), MaterialX document reads
  (``materialx.read_document``, with the documents each one includes) and the USD stage
  (``usd.open_stage``: its used layers once the file is read, variant selections applied)
  are recorded;
- **what the file names** (:func:`named_dependencies`): USD's own
  ``UsdUtils.ComputeAllDependencies`` (every layer, asset and unresolved path of the stage,
  in every variant), and for MaterialX documents their includes and ``filename`` inputs
  resolved as the readers resolve them (after ``fileprefix``, against the document's folder).

A dependency that does not exist is recorded as missing (hash ``None``): should it appear
later, the result is computed again.  A path holding ``<UDIM>`` or ``<UVTILE>`` is recorded
as the list of the tiles that match it (``glob:`` entries).  A member of a ``.usdz``
package (``pkg.usdz[tex.png]``) is the package file.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import os
import re
from collections.abc import Iterator
from typing import Any

#: Tokens of texture tile sets (MaterialX and USD); a path holding one is a glob of tiles.
TILE_TOKENS = re.compile(r"<UDIM>|<UVTILE>|<udim>|<uvtile>")
GLOB = "glob:"


def outer_file(path: str) -> str:
    """The file on disk of ``path``: a ``.usdz`` member ``pkg.usdz[a/b.png]`` is ``pkg.usdz``.

    >>> outer_file("/x/pkg.usdz[tex/a.png]"), outer_file("/x/a.png")
    ('/x/pkg.usdz', '/x/a.png')
    """
    if path.endswith("]") and "[" in path:
        return path[: path.index("[")]
    return path


def normal(path: str, folder: str | None = None) -> str:
    """``path`` as an absolute, normalised dependency entry (tiles as a ``glob:`` entry).

    >>> normal("tex/a_<UDIM>.png", "/lib")
    'glob:/lib/tex/a_*.png'
    >>> normal("/lib/pkg.usdz[t.png]")
    '/lib/pkg.usdz'
    """
    path = outer_file(os.fspath(path))
    if folder is not None and not os.path.isabs(path):
        path = os.path.join(folder, path)
    path = os.path.normpath(os.path.abspath(path))
    if TILE_TOKENS.search(path):
        return GLOB + TILE_TOKENS.sub("*", glob.escape(path))
    return path


def file_hash(path: str) -> str | None:
    """SHA-256 of a file's content (hex), ``None`` if it cannot be read; a ``glob:`` entry:
    the hash of the matching files' names and hashes.

    >>> import tempfile
    >>> d = tempfile.mkdtemp()
    >>> _ = open(os.path.join(d, "a_1001.png"), "wb").write(b"x")
    >>> file_hash(os.path.join(d, "a_1001.png")) == hashlib.sha256(b"x").hexdigest()
    True
    >>> file_hash(GLOB + os.path.join(d, "a_*.png")) != file_hash(GLOB + os.path.join(d, "b_*.png"))
    True
    >>> file_hash(os.path.join(d, "missing.png")) is None
    True
    """
    if path.startswith(GLOB):
        h = hashlib.sha256()
        for match in sorted(glob.glob(path[len(GLOB) :])):
            h.update(f"{match}\0{file_hash(match)}\0".encode("utf-8", "surrogateescape"))
        return h.hexdigest()
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    except (OSError, ValueError):
        return None
    return h.hexdigest()


class Hasher:
    """:func:`file_hash` remembered per path (one run hashes a texture shared by many files once).

    >>> h = Hasher()
    >>> h("/no/such/file") is None and len(h.known) == 1
    True
    """

    def __init__(self) -> None:
        self.known: dict[str, str | None] = {}

    def __call__(self, path: str) -> str | None:
        if path not in self.known:
            self.known[path] = file_hash(path)
        return self.known[path]


def mtime(path: str) -> float | None:
    """Modification time of a dependency entry (the newest tile of a ``glob:`` entry; the
    folder's for a missing file, so that a file appearing meanwhile counts as recent).

    >>> import tempfile
    >>> d = tempfile.mkdtemp()
    >>> mtime(os.path.join(d, "missing.png")) == os.stat(d).st_mtime
    True
    """
    if path.startswith(GLOB):
        times = [t for t in (mtime(m) for m in glob.glob(path[len(GLOB) :])) if t is not None]
        folder = mtime(os.path.dirname(path[len(GLOB) :]))
        return max(times + ([folder] if folder is not None else []), default=None)
    try:
        return os.stat(path).st_mtime
    except OSError:
        parent = os.path.dirname(path)
        return mtime(parent) if parent and parent != path else None


# ----------------------------------------------------------------------------- what the readers opened
@contextlib.contextmanager
def recording() -> Iterator[set[str]]:
    """Record the files the readers open inside the block (a set of dependency entries).

    The readers' texture lookups, MaterialX document reads and USD stages are wrapped for the
    time of the block (in this process only); a reader that no longer has one of them is
    simply not recorded there (:func:`named_dependencies` still covers it).

    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
    >>> with recording() as opened:
    ...     _ = load_materials(BUNDLED_MATERIALS / "brick_preview_textured.usda")
    >>> sorted(os.path.basename(p) for p in opened)
    ['brick_albedo.png', 'brick_preview_textured.usda']
    """
    from ..readers import materialx, textures, usd

    seen: set[str] = set()
    stages: list[Any] = []
    patched: list[tuple[Any, str, Any]] = []

    def wrap(module: Any, name: str, record: Any) -> None:
        original = getattr(module, name, None)
        if original is None:
            return

        def wrapper(*args: Any, **kwargs: Any) -> Any:
            result = original(*args, **kwargs)
            with contextlib.suppress(Exception):
                record(args, result)
            return result

        patched.append((module, name, original))
        setattr(module, name, wrapper)

    def texture(args: tuple, result: Any) -> None:
        if args and isinstance(args[0], str) and args[0]:
            seen.add(normal(args[0]))

    def document(args: tuple, doc: Any) -> None:
        path = os.fspath(args[0])
        seen.add(normal(path))
        seen.update(_includes(path, doc))

    def stage(args: tuple, result: Any) -> None:
        seen.add(normal(os.fspath(args[0])))
        stages.append(result)

    wrap(textures, "info", texture)
    wrap(textures, "sample", texture)
    wrap(materialx, "read_document", document)
    wrap(usd, "open_stage", stage)
    try:
        yield seen
        for s in stages:
            with contextlib.suppress(Exception):
                seen.update(normal(layer.realPath) for layer in s.GetUsedLayers() if layer.realPath)
    finally:
        for module, name, original in reversed(patched):
            setattr(module, name, original)
        stages.clear()


# ----------------------------------------------------------------------------- what the file names
def named_dependencies(path: str) -> set[str]:
    """The files ``path`` names (see the module docstring), as dependency entries.

    Raises
    ------
    ValueError
        The dependencies cannot be listed (the result must then not be cached).

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> sorted(os.path.basename(d) for d in named_dependencies(str(BUNDLED_MATERIALS / "brick_textured.mtlx")))
    ['brick_albedo.png', 'brick_roughness.exr']
    """
    path = os.path.abspath(path)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".mtlx":
        found = _mtlx_dependencies(path)
    else:
        found = _usd_dependencies(path)
        for dep in sorted(found):
            if dep.lower().endswith(".mtlx") and os.path.isfile(dep):
                found |= _mtlx_dependencies(dep) | {dep}
    found.discard(path)
    return found


def _usd_dependencies(path: str) -> set[str]:
    from pxr import UsdUtils

    from ..readers.usd import captured_stderr

    lines: list[str] = []
    try:
        with captured_stderr(lines):
            layers, assets, unresolved = UsdUtils.ComputeAllDependencies(path)
    except Exception as exc:  # noqa: BLE001 -- any failure: the result is not cached
        raise ValueError(f"{path}: its dependencies cannot be listed ({type(exc).__name__})") from None
    folders = {os.path.dirname(path)}
    found = set()
    for layer in layers:
        real = layer.realPath or ""
        if real:
            found.add(normal(real))
            folders.add(os.path.dirname(outer_file(real)))
    found.update(normal(a) for a in assets if a)
    for u in unresolved:
        if not u:
            continue
        if os.path.isabs(u):
            found.add(normal(u))
        else:  # anchored to a layer we cannot tell: every layer's folder is a candidate
            found.update(normal(u, folder) for folder in folders)
    return found


def _mtlx_dependencies(path: str) -> set[str]:
    import MaterialX as mx

    from ..readers import mxlib

    doc = mx.createDocument()
    try:
        mx.readFromXmlFile(doc, path)
    except Exception:  # noqa: BLE001 -- an unreadable document depends on itself only
        return set()
    found = _includes(path, doc)
    for elem in doc.traverseTree():
        if not elem.isA(mx.ValueElement) or elem.getType() != "filename":
            continue
        value = elem.getResolvedValueString() or elem.getValueString()
        if not value:
            continue
        folder = None if os.path.isabs(value) else mxlib.source_folder(path, elem.getActiveSourceUri(), doc)
        found.add(normal(value, folder))
        if folder is not None:  # also where a plain join would put it (conservative)
            found.add(normal(value, os.path.dirname(path)))
    return found


def _includes(path: str, doc: Any) -> set[str]:
    """The documents ``doc`` (read from ``path``) includes, found as MaterialX finds them."""
    from ..readers import mxlib

    found = set()
    for uri in doc.getReferencedSourceUris():
        if not uri or uri == path:
            continue
        if os.path.isabs(uri):
            found.add(normal(uri))
            continue
        folder = mxlib.source_folder(path, uri, doc)
        found.add(normal(os.path.join(folder, os.path.basename(uri))))
        found.add(normal(uri, os.path.dirname(os.path.abspath(path))))
    return found


__all__ = ["Hasher", "file_hash", "mtime", "named_dependencies", "normal", "outer_file", "recording"]

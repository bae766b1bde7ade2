"""A synthetic material library: variants of the bundled materials with other values.

For benchmarks and tests of the work over many files (``tools/bench_library.py``,
``tests/test_library_scale.py``).  Each variant is one of the bundled text files
(``.mtlx`` / ``.usda``) with its colours and roughnesses replaced by values drawn from a
seeded generator (colours and roughnesses in [0, 1]); their ``textures/`` folder is copied
beside them, so the textured ones resolve as the bundled ones do.  Files are spread over
sub-folders of :data:`PER_FOLDER`.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import numpy as np

#: Files per sub-folder of a synthetic library.
PER_FOLDER = 500
#: MaterialX inputs that get new values (colours: three values, others: one).
MTLX_INPUTS = ("base_color", "base_diffuse_roughness", "color", "roughness", "diffuse_roughness", "base")
_MTLX = re.compile(r'(<input name="(?:' + "|".join(MTLX_INPUTS) + r')" type="(float|color3)" value=")([^"]*)(")')
_USD_COLOUR = re.compile(r"(color3f inputs:diffuseColor = )\(([^)]*)\)")
_USD_FLOAT = re.compile(r"(float inputs:roughness = )([0-9.eE+-]+)")


def sources() -> list[Path]:
    """The bundled text files the variants are made from (sorted).

    >>> [p.name for p in sources()][:2]
    ['brick_preview_textured.usda', 'brick_textured.mtlx']
    """
    from ..readers import BUNDLED_MATERIALS

    return sorted(p for p in Path(BUNDLED_MATERIALS).iterdir() if p.suffix in (".mtlx", ".usda") and p.is_file())


def variant_text(text: str, rng: np.random.Generator) -> str:
    """``text`` with its colours and roughnesses replaced by values drawn from ``rng``.

    >>> t = '<input name="base_color" type="color3" value="0.5, 0.5, 0.5" />'
    >>> variant_text(t, np.random.default_rng(0)) != t
    True
    """

    def values(n: int) -> str:
        return ", ".join(f"{v:.4f}" for v in rng.uniform(0.0, 1.0, n))

    text = _MTLX.sub(lambda m: m.group(1) + values(3 if m.group(2) == "color3" else 1) + m.group(4), text)
    text = _USD_COLOUR.sub(lambda m: m.group(1) + "(" + values(3) + ")", text)
    return _USD_FLOAT.sub(lambda m: m.group(1) + values(1), text)


def write_variants(folder: str | os.PathLike[str], n: int, seed: int = 0) -> list[Path]:
    """Write ``n`` variant files into ``folder`` (created; must be empty or new); their paths.

    Raises
    ------
    ValueError
        ``n`` is not a positive integer, or ``folder`` holds files already.

    Examples
    --------
    >>> import tempfile
    >>> files = write_variants(tempfile.mkdtemp(), 3)
    >>> [f.parent.name for f in files], files[0].name
    (['v000', 'v000', 'v000'], '00000_brick_preview_textured.usda')
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    folder = Path(folder)
    if folder.exists() and any(folder.iterdir()):
        raise ValueError(f"folder {folder} is not empty; give a new or empty folder")
    rng = np.random.default_rng(seed)
    srcs = sources()
    texts = [p.read_text(encoding="utf-8") for p in srcs]
    out = []
    for i in range(n):
        sub = folder / f"v{i // PER_FOLDER:03d}"
        if not sub.exists():
            sub.mkdir(parents=True)
            textures = srcs[0].parent / "textures"
            if textures.is_dir():
                shutil.copytree(textures, sub / "textures")
        k = i % len(srcs)
        path = sub / f"{i:05d}_{srcs[k].name}"
        path.write_text(variant_text(texts[k], rng), encoding="utf-8")
        out.append(path)
    return out


__all__ = ["PER_FOLDER", "sources", "variant_text", "write_variants"]

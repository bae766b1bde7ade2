"""``openpbr-diffuse eval FILES... --jsonl OUT``: one JSON line per material of many files.

The files go through :mod:`openpbr_diffuse.library` (worker processes, cache, Dask) like the
report's materials; the lines are written in the order of the files as each file is done, to a
temporary sibling of OUT that takes OUT's name once complete (``openpbr_diffuse._outfile``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
from collections.abc import Iterator
from typing import IO, Any

import numpy as np


def _finite(x: Any) -> Any:
    """``x`` with every non-finite float as None (JSON has no NaN).

    >>> _finite({"a": [1.0, float("nan")], "b": float("inf")})
    {'a': [1.0, None], 'b': None}
    """
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    return x


def _inputs(args: argparse.Namespace) -> list[str]:
    """The given files and folders, checked before any work (one-line errors)."""
    from ..readers import MATERIAL_SUFFIXES

    paths = [args.file, *args.more]
    for p in paths:
        if not os.path.exists(p):
            raise FileNotFoundError(f"eval: no such file or folder: {p}")
        if os.path.isfile(p) and os.path.splitext(p)[1].lower() not in MATERIAL_SUFFIXES:
            raise ValueError(f"eval: {p} is not a USD or MaterialX file (expected {', '.join(MATERIAL_SUFFIXES)})")
    for v in args.variant:
        if "=" not in v:
            raise ValueError(f"eval: --variant expects SET=VALUE, got {v!r}")
    return paths


@contextlib.contextmanager
def _sink(args: argparse.Namespace, inputs: list[str]) -> Iterator[IO[str]]:
    """The stream the lines go to: stdout for ``-``, else a temporary sibling of OUT."""
    if args.jsonl == "-":
        yield sys.stdout
        return
    from .._outfile import output_file
    from ..readers import MATERIAL_SUFFIXES

    with (
        output_file(
            args.jsonl, option="--jsonl", force=args.force, inputs=inputs, input_suffixes=MATERIAL_SUFFIXES
        ) as tmp,
        open(tmp, "w", encoding="utf-8") as fh,
    ):
        yield fh


def run_jsonl(args: argparse.Namespace, ti: np.ndarray, to: np.ndarray, ph: np.ndarray) -> int:
    """Write the lines; exit status 0, or 1 when a file or a material could not be evaluated.

    >>> import tempfile
    >>> from openpbr_diffuse.cli.main import main
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> out = os.path.join(tempfile.mkdtemp(), "m.jsonl")
    >>> main(["eval", str(BUNDLED_MATERIALS / "clay_rough.mtlx"), "--jsonl", out, "--no-cache", "--no-progress"])
    0
    >>> [json.loads(line)["path"] for line in open(out)]
    ['clay_rough']
    """
    from .._outfile import check_output_file
    from ..library import Progress, Task, list_files
    from ..library.progress import mode_for
    from ..readers import MATERIAL_SUFFIXES
    from ..readers.evaluate import check_angles
    from ._library import library_options

    inputs = _inputs(args)
    for name, values in (("theta_i", ti), ("theta_o", to), ("phi", ph)):
        check_angles(name, values)
    if args.jsonl != "-":  # before any work
        check_output_file(
            args.jsonl, option="--jsonl", force=args.force, inputs=inputs, input_suffixes=MATERIAL_SUFFIXES
        )
    files = list_files(inputs)
    if not files:
        raise ValueError(f"eval: no USD or MaterialX file in {', '.join(inputs)}")
    purpose = "" if args.purpose == "all" else args.purpose
    task = Task(
        kind="eval",
        uv=tuple(float(x) for x in args.uv),
        time=args.time,
        variants=tuple(tuple(v.split("=", 1)) for v in args.variant),
        purpose=purpose,
        material=args.material,
        theta_i=tuple(float(x) for x in ti.reshape(-1)),
        theta_o=tuple(float(x) for x in to.reshape(-1)),
        phi=tuple(float(x) for x in ph.reshape(-1)),
    )
    mode = mode_for(sys.stderr, not args.no_progress)
    opts = library_options(args, mode)
    n_mats = n_bad = n_files_bad = 0
    try:
        with _sink(args, inputs) as out, Progress(len(files), mode, "eval") as progress, opts.runner() as runner:
            for o in runner.run([(f.path, task) for f in files], progress):
                f = files[o.index]
                if o.payload.get("error"):
                    n_files_bad += 1
                    lines = [
                        {"file": f.path, "relpath": f.relpath, "path": None, "name": None, "error": o.payload["error"]}
                    ]
                else:
                    lines = [{"relpath": f.relpath, "index": k, **rec} for k, rec in enumerate(o.payload["records"])]
                    n_mats += len(lines)
                    n_bad += sum(bool(rec.get("error")) for rec in o.payload["records"])
                for line in lines:
                    out.write(json.dumps(_finite(line), allow_nan=False) + "\n")
                out.flush()
    finally:
        opts.close()
    where = "stdout" if args.jsonl == "-" else args.jsonl
    text = f"eval: {n_mats} materials from {len(files) - n_files_bad} files written to {where}"
    if n_bad or n_files_bad:
        text += f"; {n_bad} materials could not be evaluated, {n_files_bad} files could not be read (see \"error\")"
    if opts.cache is not None and opts.cache.write_error:
        text += f"; the cache could not be written: {opts.cache.write_error}"
    print(text, file=sys.stderr)
    return 1 if n_bad or n_files_bad else 0


__all__ = ["run_jsonl"]

"""A chart render in a child script that leaves its linear film as a ``.npy`` array.

The LuxCore and MaterialX renderers run ``CHILD SCENE_DIR FILM.npy ARG`` under the time limit
of user code (:func:`openpbr_diffuse.graders.limits.run_limited`); the EXR is written here
from the film, and the child's last line of output (JSON) says what rendered it.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any

from ..graders.errors import GraderUnavailable


def render_film(
    child: Path, scene_dir: Path, out: Path, *, what: str, tag: str, film: str, arg: str | None = None
) -> dict[str, Any]:
    """Run ``child SCENE_DIR FILM ARG`` (``arg`` by default: the temporary folder holding FILM),
    write its film as the EXR ``out`` and return the JSON of its last output line ({} without one).

    ``what`` names the render in the time limit's messages and in the GraderUnavailable (one
    line) raised when the child fails or writes no film; ``tag`` names the temporary folder.
    """
    import numpy as np

    from ..chart.image import write_image
    from ..graders import limits

    with tempfile.TemporaryDirectory(prefix=f"openpbr-diffuse-{tag}-") as tmp:
        raw = Path(tmp) / film
        cmd = limits.script_command(child, str(scene_dir), str(raw), tmp if arg is None else arg)
        run = limits.run_limited(cmd, label=what)
        if run.returncode != 0 or not raw.is_file():
            err = run.stderr.decode(errors="replace").strip().splitlines() or ["no output"]
            raise GraderUnavailable(f"{what} failed (exit {run.returncode}): {err[-1][:400]}")
        write_image(out, np.load(raw), option="--out")
    lines = run.stdout.decode(errors="replace").strip().splitlines()
    return json.loads(lines[-1]) if lines and lines[-1].startswith("{") else {}

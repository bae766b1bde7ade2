"""Render the conformance chart in every registered renderer, grade it, write the results page.

    python tools/renderer_conformance.py [--out docs/guide/renderer-conformance.md] [--only NAME ...]

For each renderer of ``openpbr_diffuse.renderers.RENDERERS`` (Blender Cycles, EEVEE and Hydra
Storm through bpy; three.js and Babylon.js in headless Chromium): write the chart file its users
take, render scene_01 (256^2, distant light) under the time limit of user code, grade the image
as ``openpbr-diffuse check --image`` does, and write one row per renderer -- renderer, version,
chart, light, verdict, diagnosis, largest error, date.  A renderer that is not installed is
listed with the reason.  The page is this tool's output: it is replaced on every run.
"""

from __future__ import annotations

import argparse
import datetime
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "docs" / "guide" / "renderer-conformance.md"

HEADER = """# Renderer conformance

The [conformance chart](chart.md) rendered by the renderers users use, each from the chart
file its users take, and graded from the image (`openpbr-diffuse check --implementation NAME`
renders and grades one; see [Graded implementations](graded-implementations.md#renderer-conformance)
for what each result means).  Regenerate this page with

```bash
python tools/renderer_conformance.py
```
"""


def _row(s: dict, date: str) -> str:
    diag = s["diagnosis"] or ("none" if s["verdict"] == "conforms" else "no known deviation")
    near = s.get("closest")
    if s["diagnosis"] is None and near:
        diag = (
            f"closest: {near['deviation']} (residual {100 * near['residual_max_rel']:.2g} % max, "
            f"{100 * near['residual_rms_rel']:.2g} % rms, beyond the tolerance)"
        )
    if s["non_linear"]:
        diag += f"; non-linear output flagged: {s['non_linear']}"
    err = f"{s['max_rel_error']:.2g} relative ({s['max_abs_error']:.2g} absolute)"
    return (
        f"| {s['renderer']} (`{s['name']}`) | {s['version']} | {s['chart']} | {s['light']} | "
        f"{s['verdict']} | {diag} | {err} | {s['exposure']:.4g} | {s['seconds']:g} s | {date} |"
    )


#: Everything from this line on in the page is written by hand and kept on regeneration.
NOTES = "<!-- notes below: kept by tools/renderer_conformance.py -->"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(DEFAULT_OUT), help="the page to write (default: %(default)s)")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="these renderers only")
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    from openpbr_diffuse.graders.errors import GraderUnavailable
    from openpbr_diffuse.renderers import RENDERERS, render_and_grade, summary

    names = a.only or list(RENDERERS)
    date = datetime.date.today().isoformat()
    lines = [
        HEADER,
        "| renderer | version | chart | light | verdict | diagnosis | largest error | exposure | render | date |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    missing = []
    for name in names:
        try:
            r = render_and_grade(name)
        except GraderUnavailable as exc:
            missing.append(f"- `{name}`: not rendered here: {exc}")
            print(f"{name}: not rendered: {exc}", file=sys.stderr)
            continue
        s = summary(r)
        lines.append(_row(s, date))
        print(f"{name}: {s['verdict']} ({s['diagnosis']}), {s['seconds']} s")
    if missing:
        lines += ["", *missing]
    lines += [
        "",
        "Largest error: of the BRDF rows (out = tile value / (mu_i E exposure)) against EON; the",
        "exposure is calibrated on the chart's grey ramp (1 = the renderer's light units match).",
        "",
    ]
    # the notes a person wrote below the marker are kept as they are
    old = Path(a.out).read_text() if Path(a.out).is_file() else ""
    if NOTES in old:
        lines += [old[old.index(NOTES) :].rstrip("\n"), ""]
    Path(a.out).write_text("\n".join(lines))
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

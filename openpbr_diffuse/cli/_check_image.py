"""``openpbr-diffuse check --image FILE --chart FILE``: grade a rendered conformance chart.

The image is read with OpenImageIO (float: linear; 8/16-bit: decoded by its transfer,
sRGB unless the file says linear), every tile measured on its interior, the exposure
calibrated on the grey ramp, a non-linear output named, and the tiles graded as rows by
``conformance.grade`` with its diagnosis (see ``openpbr_diffuse.chart.grading``).
Exit status: 0 conforms, 1 does not, 2 unusable input.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..chart.grading import ImageGrade


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("a rendered conformance chart (openpbr-diffuse chart)")
    g.add_argument("--image", metavar="FILE", help="the rendered image of a chart scene (EXR, HDR, TIFF, PNG, ...)")
    g.add_argument("--chart", metavar="FILE", help="the scene's chart.json")
    g.add_argument(
        "--absolute", action="store_true", help="grade against the stated irradiance (no exposure calibration)"
    )
    g.add_argument("--junit", metavar="FILE", help="also write the verdict as JUnit XML (with --image)")
    g.add_argument("--force", action="store_true", help="replace the --junit FILE if it exists")


def _junit(path: str, result: ImageGrade, image: str, force: bool) -> None:
    """The image's verdict as JUnit XML: its linearity and its BRDF, one result each
    (:func:`openpbr_diffuse.result.junit_case`)."""
    import xml.etree.ElementTree as ET

    from .._outfile import write_output_file
    from ..result import junit_case, sub_check

    root = ET.Element("testsuites", name="openpbr-diffuse check --image")
    suite = ET.SubElement(root, "testsuite", name=image)
    linear = sub_check(
        "linear output",
        "fail" if result.non_linear else "pass",
        detail=f"non-linear output: {result.non_linear}" if result.non_linear else "",
    )
    g = result.grade
    brdf = sub_check(
        "brdf",
        "pass" if result.brdf_passed else "fail",
        detail="" if result.brdf_passed else f"does not conform: {g.diagnosis or ''} {g.diagnosis_detail}",
    )
    for r in (linear, brdf):
        junit_case(suite, r.to_dict(), "chart")
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
    write_output_file(path, text, option="--junit", force=force, inputs=[image])


def is_renderer(name: str | None) -> bool:
    """Whether ``--implementation NAME`` names a renderer (its chart image is graded).

    >>> is_renderer("eevee"), is_renderer("threejs"), is_renderer(None)
    (True, False, False)
    """
    from ..renderers import RENDERERS

    return name in RENDERERS


def run_renderer(args: argparse.Namespace, print_grade: Callable) -> int:
    """``check --implementation RENDERER``: render the chart's scene_01 (256^2, distant light)
    with the renderer, from the chart file its users take, and grade the image."""
    from ..graders import limits
    from ..renderers import render_and_grade

    if args.file is not None:
        raise ValueError("give FILE (vectors) or --implementation, not both")
    for opt in ("source", "glsl", "cpp", "junit"):
        if getattr(args, opt, None):
            raise ValueError(f"--{opt} is not used with --implementation {args.implementation} (a renderer)")
    if getattr(args, "timeout", None) is not None:
        limits.set_limits(timeout=args.timeout)
    r = render_and_grade(args.implementation)
    g = r.grade
    if args.json:
        print(json.dumps(r.to_dict()))
        return 0 if g.passed else 1
    verdict = "CONFORMS" if g.passed else "DOES NOT CONFORM"
    print(
        f"{r.label} {r.version}: {verdict} (chart {r.scene}, {r.resolution}x{r.resolution}, {r.light} light, "
        f"rendered in {r.seconds:.1f} s)"
    )
    for note in r.notes:
        print(f"  {note}")
    print(f"  exposure factor {g.exposure:.6g} (calibrated on the ramp); ramp residual {g.ramp_residual:.3g}")
    if g.non_linear:
        print(f"  non-linear output: {g.non_linear}")
    print_grade(g.grade, f"  {r.renderer}")
    return 0 if g.passed else 1


def run(args: argparse.Namespace, print_grade: Callable) -> int:
    from ..chart.grading import grade_image
    from ..chart.image import read_image
    from ..chart.schema import read_chart

    if args.image is None or args.chart is None:
        raise ValueError("--image FILE and --chart FILE go together (a rendered chart scene and its chart.json)")
    if args.file is not None:
        raise ValueError("give FILE (vectors) or --image/--chart, not both")
    if args.junit:
        from .._outfile import check_output_file

        check_output_file(args.junit, option="--junit", force=args.force, inputs=[args.image, args.chart])
    chart = read_chart(args.chart)
    image = read_image(args.image)
    r = grade_image(image, chart, model=args.model or "eon", absolute=args.absolute)
    if args.json:
        d = r.to_dict()
        d["file"] = str(args.image)
        d["chart"] = str(args.chart)
        print(json.dumps(d))
    else:
        verdict = "CONFORMS" if r.passed else "DOES NOT CONFORM"
        print(f"{args.image}: {verdict} ({r.n_tiles} tiles, {r.light} light, image decoded as {image.encoding})")
        how = "absolute: graded against the stated irradiance" if r.absolute else "calibrated on the ramp"
        print(
            f"  exposure factor {r.exposure:.6g} +- {r.exposure_stderr:.2g} ({how}); ramp residual {r.ramp_residual:.3g}"
        )
        if r.non_linear:
            done = "linearised with that curve, the BRDF graded after it" if r.linearised else "not linearised"
            print(f"  non-linear output: {r.non_linear} -- not a BRDF deviation: render linear ({done})")
        noisy = r.tolerance.get("noisy_tiles")
        if noisy:
            print(
                f"  {noisy['n']} noisy tiles graded apart at relative {noisy['relative']:.3g}: "
                f"{noisy['n_failed']} outside ({'pass' if noisy['passed'] else 'fail'})"
            )
        print("  BRDF on the tiles (rows: wi, wo, roughness, rho, out = value / (mu_i E exposure)):")
        print_grade(r.grade, f"  {args.chart}")
    if args.junit:
        _junit(args.junit, r, args.image, args.force)
    return 0 if r.passed else 1


__all__ = ["add_arguments", "run"]

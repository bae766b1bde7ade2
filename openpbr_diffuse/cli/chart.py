"""``openpbr-diffuse chart``: write the conformance chart, or the image a conforming renderer makes of it.

    openpbr-diffuse chart --format usd --light distant --out DIR
    openpbr-diffuse chart --format all --light furnace --out DIR --resolution 512
    openpbr-diffuse chart --expected-image OUT.exr --chart DIR/scene_01/chart.json [--model eon]

The chart is a set of scenes (DIR/scene_NN/) of flat tiles seen by an orthographic camera,
each tile tilted so that it sees its own (mu_i, mu_o, phi); a chart.json per scene gives
every tile's pixel rectangle, inputs and the light.  Grade a rendering with
``openpbr-diffuse check --image FILE --chart DIR/scene_NN/chart.json``.
"""

from __future__ import annotations

import argparse

from ..chart.layout import LIGHTS
from ..chart.write import FORMATS
from ..models import MODELS
from ._options import add_command

#: The command's line in ``openpbr-diffuse --help``.
HELP = "write the conformance chart (scenes for renderers) or its expected image"


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = add_command(subparsers, "chart", HELP, run, doc=__doc__)
    p.add_argument(
        "--format",
        choices=FORMATS + ("all",),
        action="append",
        help="scene format (repeatable; 'all' for every one)",
    )
    p.add_argument("--light", choices=LIGHTS, default="distant", help="the light (default distant)")
    p.add_argument("--out", metavar="DIR", help="folder to write the chart into (new, or empty)")
    p.add_argument(
        "--resolution", type=int, default=1024, metavar="N", help="image width = height (multiple of 16, >= 256)"
    )
    p.add_argument("--expected-image", metavar="FILE", help="write the expected image of --chart (EXR: float)")
    p.add_argument("--chart", metavar="FILE", help="a scene's chart.json (with --expected-image)")
    p.add_argument("--model", choices=MODELS, default="eon", help="the model of the expected image (default eon)")
    p.add_argument("--force", action="store_true", help="replace the --expected-image FILE if it exists")
    return p


def run(args: argparse.Namespace) -> int:
    if args.expected_image is not None:
        if args.chart is None:
            raise ValueError("--expected-image needs --chart FILE (a scene's chart.json)")
        if args.out is not None or args.format:
            raise ValueError("--expected-image and --out/--format are two uses: give one")
        from ..chart.expected import expected_image
        from ..chart.image import write_image
        from ..chart.schema import read_chart

        scene = read_chart(args.chart)
        write_image(args.expected_image, expected_image(scene, args.model), force=args.force)
        print(f"wrote {args.expected_image} ({scene['width']}x{scene['height']}, {args.model})")
        return 0
    if args.out is None:
        raise ValueError("--out DIR is required (or --expected-image FILE --chart FILE)")
    if args.chart is not None or args.force:
        raise ValueError("--chart and --force go with --expected-image")
    formats = tuple(args.format or ["all"])
    if "all" in formats:
        formats = FORMATS
    from ..chart.write import write_chart

    written = write_chart(args.out, formats=tuple(dict.fromkeys(formats)), light=args.light, resolution=args.resolution)
    n_scenes = sum(1 for p in written if p.name == "chart.json")
    print(
        f"wrote {len(written)} files, {n_scenes} scenes ({', '.join(dict.fromkeys(formats))}; {args.light} light) in {args.out}"
    )
    return 0


__all__ = ["add_parser", "run"]

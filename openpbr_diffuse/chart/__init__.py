"""The conformance chart: scenes any renderer can render, graded from their images.

:func:`.write.write_chart` writes the scenes (USD + MaterialX OpenPBR, glTF, MaterialX,
a Blender script) with one chart.json each (:mod:`.layout`, schema in
docs/reference/chart-schema.md); :func:`.expected.expected_image` computes the image a
conforming renderer makes; :func:`.grading.grade_image` grades a rendered image
(exposure, linearity, then the BRDF with the diagnosis of :mod:`openpbr_diffuse.conformance`).
"""

from .expected import expected_image, tile_values
from .grading import ImageGrade, grade_image
from .image import read_image, write_image
from .layout import SCHEMA, build_scene, build_scenes
from .schema import read_chart
from .write import FORMATS, write_chart

__all__ = [
    "SCHEMA",
    "FORMATS",
    "ImageGrade",
    "build_scene",
    "build_scenes",
    "expected_image",
    "grade_image",
    "read_chart",
    "read_image",
    "tile_values",
    "write_chart",
    "write_image",
]

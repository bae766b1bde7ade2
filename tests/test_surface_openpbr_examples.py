"""The 83 OpenPBR example materials (../shared/corpus/openpbr/examples) build surfaces, and
each reports the diffuse lobe's effective weight and selection probability at mu_o = 1
and 0.2.

The inputs are read here with MaterialX directly (not through the library's readers).
Checks: every example builds; the probabilities sum to 1; the diffuse lobe's weight is the
product of the mix factors the reference graph puts above it (the layer albedos taken
from the surface's own lobes: E_coat, E_fuzz, and E_spec from the specular lobe, or
recovered from the diffuse/base weight ratio when that lobe is inactive); and materials
that are pure metal or fully transmissive report a zero diffuse weight.
"""

import json
import math
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
EXAMPLES = SHARED / "corpus" / "openpbr" / "examples"

pytestmark = pytest.mark.corpus


def _files():
    return sorted(EXAMPLES.glob("*.mtlx")) if EXAMPLES.is_dir() else []


def read_inputs(path):
    """{input name: Python value} of the open_pbr_surface node of a .mtlx file."""
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    (node,) = [n for n in doc.getNodes() if n.getCategory() == "open_pbr_surface"]
    out = {}
    for inp in node.getInputs():
        v = inp.getValue()
        if isinstance(v, (mx.Color3, mx.Vector3)):
            v = tuple(float(c) for c in v)
        out[inp.getName()] = v
    return out


def diffuse_report(path):
    from openpbr_diffuse.nodes import OpenPBRSurface

    inputs = read_inputs(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = OpenPBRSurface(**inputs)
    rows = {}
    for mu in (1.0, 0.2):
        wo = np.array([math.sqrt(1.0 - mu * mu), 0.0, mu])
        lobes = {lb.name: lb for lb in s.lobes(wo)}
        d = lobes.get("diffuse")
        rows[mu] = (lobes, None if d is None else d.weight, 0.0 if d is None else float(d.probability))
    return inputs, s, rows


@pytest.mark.skipif(not EXAMPLES.is_dir(), reason="../shared/corpus/openpbr/examples not present")
def test_there_are_83_examples():
    assert len(_files()) == 83


@pytest.mark.skipif(not EXAMPLES.is_dir(), reason="../shared/corpus/openpbr/examples not present")
@pytest.mark.parametrize("path", _files(), ids=lambda p: p.stem)
def test_example_builds_and_reports_the_diffuse_lobe(path):
    inputs, s, rows = diffuse_report(path)
    g = lambda name: inputs.get(name, s.defaults()[name])  # noqa: E731
    for _mu, (lobes, w, P) in rows.items():
        total = sum(float(lb.probability) for lb in lobes.values())
        assert total == pytest.approx(1.0, abs=1e-12)
        if g("base_metalness") == 1.0 or g("transmission_weight") == 1.0 or g("subsurface_weight") == 1.0:
            assert w is None or np.all(w == 0.0)
            continue
        assert w is not None
        # the factors above the diffuse lobe (graph: fuzz_layer, coat_layer, base_substrate,
        # dielectric_base, dielectric_substrate, opaque_base, diffuse_bsdf weight)
        C, F = g("coat_weight"), g("fuzz_weight")
        E_c = lobes["coat"].albedo[0] if "coat" in lobes else 0.0
        E_f = lobes["fuzz"].albedo[0] if "fuzz" in lobes else 0.0
        E_s = lobes["specular"].albedo[0] if "specular" in lobes else 0.0
        above = (
            (1 - F * E_f)
            * (1 - C * E_c)
            * (1 - g("base_metalness"))
            * (1 - E_s)
            * (1 - g("transmission_weight"))
            * (1 - g("subsurface_weight"))
            * g("base_weight")
        )
        if C == 0.0:  # no coat: no attenuation or darkening either
            assert np.allclose(w, above, rtol=1e-12, atol=1e-15), path.stem
        else:  # the coat's colour and darkening factors, per channel, lie in (0, 1]
            ratio = w / above
            assert np.all((ratio > 0.0) & (ratio <= 1.0 + 1e-12)), path.stem
        assert 0.0 <= P <= 1.0


@pytest.mark.skipif(not EXAMPLES.is_dir(), reason="../shared/corpus/openpbr/examples not present")
def test_report_table(tmp_path):
    """Writes the per-example table (name, diffuse weight and P at mu_o = 1 and 0.2) as JSON
    to $OPENPBR_DIFFUSE_EXAMPLES_REPORT when set (the README's numbers), else to tmp."""
    table = []
    for path in _files():
        _, _, rows = diffuse_report(path)
        entry = {"material": path.stem}
        for mu, (_, w, P) in rows.items():
            key = f"mu_{mu:g}"
            entry[key] = {"weight": None if w is None else [round(float(v), 6) for v in w], "probability": round(P, 6)}
        table.append(entry)
    out = Path(os.environ.get("OPENPBR_DIFFUSE_EXAMPLES_REPORT", tmp_path / "examples.json"))
    out.write_text(json.dumps(table, indent=1))
    assert len(table) == 83

"""The MaterialX export: a node definition of EON as a BSDF and its ``genglsl`` implementation.

MaterialX's GLSL generator (1.39) emits a function's definition only from the file an
implementation names (``file=``); inline ``sourcecode`` is pasted as an expression.  So the
export is two files side by side: ``NAME.mtlx`` (the nodedef ``ND_openpbr_diffuse_eon_bsdf``
and its implementation) and ``NAME_genglsl.glsl`` (the GLSL export and the closure function
MaterialX calls), found by the generator next to the document.
"""

from __future__ import annotations

from pathlib import Path

#: the node's name (prefixed so as not to clash with MaterialX's own nodes)
NODE = "openpbr_diffuse_eon_bsdf"
#: the GLSL function the implementation names
FUNCTION = "mx_openpbr_diffuse_eon_bsdf"

_CLOSURE = """
// The closure MaterialX's GLSL generator calls for the node (light loop: REFLECTION; environment:
// INDIRECT).  The local frame: N, X = the component of V normal to N (so wo = (sin, 0, cos)).
void mx_openpbr_diffuse_eon_bsdf(ClosureData closureData, float weight, vec3 color, float roughness, vec3 N, inout BSDF bsdf)
{
    bsdf.throughput = vec3(0.0);
    if (weight < M_FLOAT_EPS) {
        return;
    }
    vec3 V = closureData.V;
    N = normalize(N);
    vec3 T = V - dot(V, N) * N;
    float t = length(T);
    vec3 X = t > 1e-6 ? T / t : normalize(cross(N, abs(N.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0)));
    vec3 Y = cross(N, X);
    vec3 wo = vec3(dot(V, X), dot(V, Y), dot(V, N));
    if (closureData.closureType == CLOSURE_TYPE_REFLECTION) {
        vec3 L = closureData.L;
        vec3 wi = vec3(dot(L, X), dot(L, Y), dot(L, N));
        bsdf.response = eon_f(wi, wo, roughness, color) * max(wi.z, 0.0) * closureData.occlusion * weight;
    } else if (closureData.closureType == CLOSURE_TYPE_INDIRECT) {
        bsdf.response = mx_environment_irradiance(N) * eon_albedo(max(wo.z, 0.0), roughness, color) * weight;
    }
}
"""

_DOCUMENT = """<?xml version="1.0"?>
<materialx version="1.39">
  <!--
{comment}
  -->
  <nodedef name="ND_{node}" node="{node}" bsdf="R" nodegroup="pbr" doc="EON, the energy-preserving Oren-Nayar diffuse BSDF of OpenPBR (f without the cosine; the response carries it).">
    <input name="weight" type="float" value="1.0" uimin="0.0" uimax="1.0" />
    <input name="color" type="color3" value="0.18, 0.18, 0.18" />
    <input name="roughness" type="float" value="0.0" uimin="0.0" uimax="1.0" />
    <input name="normal" type="vector3" defaultgeomprop="Nworld" />
    <output name="out" type="BSDF" />
  </nodedef>
  <implementation name="IM_{node}_genglsl" nodedef="ND_{node}" file="{glsl}" function="{function}" target="genglsl" />
</materialx>
"""


def glsl_name(mtlx_path: str | Path) -> str:
    """The name of the GLSL file written beside the ``.mtlx`` at ``mtlx_path``.

    Examples
    --------
    >>> glsl_name("out/eon.mtlx")
    'eon_genglsl.glsl'
    """
    return Path(mtlx_path).stem + "_genglsl.glsl"


def implementation_glsl(glsl_export: str) -> str:
    """The ``genglsl`` implementation file: the GLSL export plus the closure function.

    The closure types come from MaterialX's own library (the include resolves against the
    generator's source search path: the folder holding ``libraries/``).

    Examples
    --------
    >>> text = implementation_glsl("// EON\\n")
    >>> text.splitlines()[0]
    '#include "libraries/pbrlib/genglsl/lib/mx_closure_type.glsl"'
    """
    return '#include "libraries/pbrlib/genglsl/lib/mx_closure_type.glsl"\n' + glsl_export + _CLOSURE


def document(header: str, glsl: str = "eon_genglsl.glsl") -> str:
    """The ``.mtlx`` document: the nodedef and its implementation in ``glsl`` (a sibling file).

    ``header`` is the export's ``//`` header; it becomes the document's comment.

    Examples
    --------
    >>> text = document("// EON", "a_genglsl.glsl")
    >>> 'file="a_genglsl.glsl"' in text, "ND_openpbr_diffuse_eon_bsdf" in text
    (True, True)
    """
    comment = "\n".join(
        "    " + line.removeprefix("//").strip().replace("--", "-") for line in header.strip().splitlines()
    )
    return _DOCUMENT.format(comment=comment, node=NODE, glsl=glsl, function=FUNCTION)


__all__ = ["FUNCTION", "NODE", "document", "glsl_name", "implementation_glsl"]

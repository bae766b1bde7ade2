"""Render the one language-neutral source of the EON functions into GLSL, WGSL, C++ and OSL.

The source (``templates/eon.neutral``) is written in a small C-like subset that every
target can express line by line:

- types ``real`` (float or double), ``vec3r`` (three reals, ``.x .y .z``) and ``bool``;
- ``const real NAME = {KEY};`` constants, ``{KEY}`` filled from the package's own modules
  (:func:`openpbr_diffuse.export.constants.constants`);
- functions ``TYPE name(TYPE a, ...) {``; locals ``TYPE name = expr;``, never reassigned,
  parameters never assigned (WGSL and OSL parameters are read-only);
- no ``if``: ``eon_sel(c, a, b)`` (``c ? a : b``), defined by each language's prelude;
- calls to ``sqrt acos abs min max pow cos sin`` only.

A rendering is a handful of line rewrites per language (types, declarations, function
headers, math names, literal suffixes), so the five exports cannot drift apart.
"""

from __future__ import annotations

import re
from importlib import resources

#: the languages the neutral source is rendered into (mtlx embeds the GLSL rendering)
TARGETS = ("glsl", "wgsl", "cpp", "osl")

_CONST = re.compile(r"^const real (\w+) = (.*);(\s*//.*)?$")
_FUNC = re.compile(r"^(real|vec3r|bool) (\w+)\((.*)\) \{$")
_LOCAL = re.compile(r"^(\s+)(real|vec3r|bool) (\w+) = (.*)$")
_KEY = re.compile(r"\{(\w+)\}")
#: a decimal floating literal (not part of a name), for C++'s float suffix
_LITERAL = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][-+]?\d+)?|\d+[eE][-+]?\d+)(?![\w.])")
_MATH = ("sqrt", "acos", "abs", "min", "max", "pow", "cos", "sin")


def neutral_source() -> str:
    """The language-neutral source of the exported functions (package data).

    Examples
    --------
    >>> "real eon_E_F_exact(real mu, real r) {" in neutral_source()
    True
    """
    return resources.files(__package__).joinpath("templates").joinpath("eon.neutral").read_text(encoding="utf-8")


def fill(text: str, values: dict[str, str]) -> str:
    """Replace every ``{KEY}`` of ``text`` by ``values[KEY]``; a key without a value raises KeyError.

    Examples
    --------
    >>> fill("const real EON_C1 = {C1};", {"C1": "0.5"})
    'const real EON_C1 = 0.5;'
    """
    return _KEY.sub(lambda m: values[m.group(1)], text)


def _types(lang: str, precision: str) -> dict[str, str]:
    real = {"glsl": "float", "wgsl": "f32", "osl": "float", "cpp": "eon_real"}[lang]
    vec = {"glsl": "vec3", "wgsl": "vec3<f32>", "osl": "vector", "cpp": "eon_vec3"}[lang]
    boolean = "int" if lang == "osl" else "bool"
    return {"real": real, "vec3r": vec, "bool": boolean}


def _expr(lang: str, text: str) -> str:
    """Rewrite one expression (or statement) into ``lang``'s syntax."""
    vec_ctor = {"glsl": "vec3(", "wgsl": "vec3<f32>(", "osl": "vector(", "cpp": "eon_vec3_make("}[lang]
    text = re.sub(r"\bvec3r\(", vec_ctor, text)
    if lang == "cpp":
        names = {"abs": "std::fabs", "min": "std::fmin", "max": "std::fmax"}
        text = re.sub(
            r"(?<![\w:.])(" + "|".join(_MATH) + r")\(",
            lambda m: names.get(m.group(1), "std::" + m.group(1)) + "(",
            text,
        )
    if lang == "osl":
        text = re.sub(r"\b(\w+)\.([xyz])\b", lambda m: f"{m.group(1)}[{'xyz'.index(m.group(2))}]", text)
        text = re.sub(r"\btrue\b", "1", re.sub(r"\bfalse\b", "0", text))
    return text


def _suffix(text: str) -> str:
    """C++ float: ``f`` after every floating literal (code only, not the comments)."""
    code, sep, comment = text.partition("//")
    return _LITERAL.sub(lambda m: m.group(1) + "f", code) + sep + comment


def _params(lang: str, types: dict[str, str], params: str) -> str:
    out = []
    for p in (x.strip() for x in params.split(",") if x.strip()):
        t, name = p.split()
        out.append(f"{name}: {types[t]}" if lang == "wgsl" else f"{types[t]} {name}")
    return ", ".join(out)


def render(text: str, lang: str, precision: str = "float") -> str:
    """Render filled neutral source into ``lang`` ("glsl", "wgsl", "cpp" or "osl").

    Examples
    --------
    >>> print(render("real eon_half(real x) {\\n    real h = 0.5 * x;\\n    return h;\\n}", "wgsl"), end="")
    fn eon_half(x: f32) -> f32 {
        var h: f32 = 0.5 * x;
        return h;
    }
    >>> print(render("real eon_half(real x) {\\n    return 0.5 * max(x, 0.0);\\n}", "cpp"), end="")
    EON_HOST_DEVICE inline eon_real eon_half(eon_real x) {
        return 0.5f * std::fmax(x, 0.0f);
    }
    """
    if lang not in TARGETS:
        raise ValueError(f"lang: expected one of {', '.join(TARGETS)}, got {lang!r}")
    types = _types(lang, precision)
    lines = []
    for line in text.splitlines():
        m = _CONST.match(line)
        f = _FUNC.match(line)
        d = _LOCAL.match(line)
        if m:
            name, value, comment = m.group(1), m.group(2), m.group(3) or ""
            out = {
                "glsl": f"const float {name} = {value};{comment}",
                "wgsl": f"const {name}: f32 = {value};{comment}",
                "osl": f"#define {name} {value}{comment}",
                "cpp": f"static constexpr eon_real {name} = {value};{comment}",
            }[lang]
        elif f:
            ret, name, params = types[f.group(1)], f.group(2), _params(lang, types, f.group(3))
            out = {
                "wgsl": f"fn {name}({params}) -> {ret} {{",
                "cpp": f"EON_HOST_DEVICE inline {ret} {name}({params}) {{",
            }.get(lang, f"{ret} {name}({params}) {{")
        elif d:
            indent, t, name, rest = d.group(1), types[d.group(2)], d.group(3), _expr(lang, d.group(4))
            out = f"{indent}var {name}: {t} = {rest}" if lang == "wgsl" else f"{indent}{t} {name} = {rest}"
        else:
            out = _expr(lang, line)
        if lang == "cpp" and precision == "float":
            out = _suffix(out)
        lines.append(out)
    return "\n".join(lines) + "\n"


__all__ = ["TARGETS", "fill", "neutral_source", "render"]

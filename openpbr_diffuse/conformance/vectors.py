"""The conformance test vectors: inputs for another implementation, and its results read back.

A vector is one query: ``kind == "brdf"`` asks for f(wi, wo) without the cosine factor,
``kind == "albedo"`` for the directional albedo E(mu).  The default set
(:func:`default_vectors`) covers the models "lambert", "qon", "fon", "eon" and
"eon_approx" (and, on request, "qon_fujii": Fujii's QON with the interreflection tint) at
the edges where implementations disagree: grazing directions (mu = 0.01, 0.001),
backscatter (wi = wo), s = 0 (perpendicular azimuths, and one direction along the normal),
L.V < 0 (opposite azimuths: FON/EON's s <= 0 branch), directions below the horizon
(f = 0), roughness r = 0 and r = 1 (sigma = 0 and pi/2 for QON), white, chromatic and dark
colours, and the albedo down to mu = 0.001.  The edge rows (:data:`EDGE_PAIRS`, appended
after those, with ids that continue each model's numbering) ask for the exact edges: mu_i
and mu_o = 0 and 1, L.V = +-1, azimuth differences of exactly 0 and pi, roughness 0 and its
maximum, rho = 0 and 1, and the albedo at mu = 0 and 1.  A BRDF direction with z = 0 is below
the horizon (f = 0).  The albedo at exactly mu = 0 has two defensible answers: the single-sided
rule (0, which the paper's Listing 1 returns) and the grazing limit (E -> rho E_F(0) + rho_ms
(1 - E_F(0)) = rho, which this library returns); the grader accepts either
(:func:`.grade.accepted_reference`).  NaN or Inf is never accepted: it is the unguarded
(S/mu)(1 - S^3) of Eq. 13, or a horizon test ``z < 0`` where ``z <= 0`` is meant.

File format (CSV; JSON when the name ends in ``.json``): the columns :data:`COLUMNS` in that
order, blank where a column does not apply (mu for BRDF rows, directions for albedo rows,
roughness for Lambert); ``#`` lines on top carry the version.  The implementer appends
:data:`OUT_COLUMNS` (``out_r, out_g, out_b``) to each row; :func:`read_results` reads such a
file back and matches its rows to the vectors by id (a subset of the rows is allowed).

Examples
--------
>>> v = default_vectors()
>>> v.version, len(v) > 1000, sorted(map(str, set(v.kind)))
('4', True, ['albedo', 'brdf'])
>>> bool(((v.wi[:, 2] < 0.002) & (v.kind == "brdf")).any())   # grazing rows
True
"""

from __future__ import annotations

import collections
import csv
import io
import json
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._textfiles import named, not_utf8, write_text

#: Version of the default vector set; bump when its rows change.
VERSION = "4"  # 3: the edge rows (mu = 0 exactly, L.V = +-1, rho = 0) and the qon_fujii rows; 4: swapped pairs
#: Input columns, in file order.
COLUMNS = (
    "id",
    "kind",
    "model",
    "wi_x",
    "wi_y",
    "wi_z",
    "wo_x",
    "wo_y",
    "wo_z",
    "mu",
    "roughness",
    "rho_r",
    "rho_g",
    "rho_b",
)
#: Result columns the implementer appends.
OUT_COLUMNS = ("out_r", "out_g", "out_b")
FORMAT_NAME = "openpbr-diffuse conformance vectors"
#: Models covered by the default set.
VECTOR_MODELS = ("lambert", "qon", "fon", "eon", "eon_approx")
#: Models with vectors on request (``default_vectors(models)``, ``vectors --model``), not in
#: the default set: Fujii's QON (a target of its own: ``check --model qon_fujii``).
EXTRA_MODELS = ("qon_fujii",)
ALL_VECTOR_MODELS = VECTOR_MODELS + EXTRA_MODELS
#: Models with albedo rows.  Not "eon_approx": the paper's Listing 1 (E_EON with
#: exact = false) returns rho E_F~ + rho_ms (1 - E_F~) with the Eq. 14 fit E_F~, which
#: differs from the true albedo of the approximate lobe (``directional_albedo``) by up to
#: 5e-4 -- both are legitimate answers, so neither is graded.
ALBEDO_MODELS = ("lambert", "qon", "fon", "eon", "qon_fujii")
#: How far a submitted file's inputs may differ from the vectors' (float32 rounding of the
#: printed inputs passes, a different row does not).
INPUT_MATCH_TOL = 1e-5

_NUMERIC = COLUMNS[3:]


@dataclass
class VectorSet:
    """Test vectors as arrays (NaN where a column does not apply).

    Attributes: ``id``, ``kind`` ("brdf"/"albedo"), ``model`` (n,) str arrays; ``wi``,
    ``wo`` (n, 3); ``mu``, ``roughness`` (n,); ``rho`` (n, 3); ``version`` str.
    """

    id: np.ndarray
    kind: np.ndarray
    model: np.ndarray
    wi: np.ndarray
    wo: np.ndarray
    mu: np.ndarray
    roughness: np.ndarray
    rho: np.ndarray
    version: str = VERSION

    def __len__(self):
        return int(self.id.shape[0])

    def subset(self, index: NDArray[Any] | slice) -> VectorSet:
        """The rows selected by a boolean mask or an index array."""
        return VectorSet(
            self.id[index],
            self.kind[index],
            self.model[index],
            self.wi[index],
            self.wo[index],
            self.mu[index],
            self.roughness[index],
            self.rho[index],
            self.version,
        )

    def columns(self) -> dict[str, np.ndarray]:
        """{column name: (n,) array} in :data:`COLUMNS` order."""
        cols = {"id": self.id, "kind": self.kind, "model": self.model}
        for k, axis in enumerate("xyz"):
            cols[f"wi_{axis}"] = self.wi[:, k]
        for k, axis in enumerate("xyz"):
            cols[f"wo_{axis}"] = self.wo[:, k]
        cols["mu"] = self.mu
        cols["roughness"] = self.roughness
        for k, c in enumerate("rgb"):
            cols[f"rho_{c}"] = self.rho[:, k]
        return cols


def _direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))


#: theta (degrees) of mu = 0.01 and mu = 0.001.
_G1 = math.degrees(math.acos(0.01))
_G2 = math.degrees(math.acos(0.001))

#: (theta_i, theta_o, phi_i - phi_o) in degrees, and what the pair is there for.
_PAIRS = (
    (0.0, 0.0, 0.0, "both along the normal"),
    (0.0, 60.0, 0.0, "wi along the normal: s = 0"),
    (45.0, 0.0, 0.0, "wo along the normal: s = 0"),
    (30.0, 30.0, 0.0, "backscatter wi = wo"),
    (60.0, 60.0, 0.0, "backscatter wi = wo"),
    (80.0, 80.0, 0.0, "backscatter wi = wo"),
    (_G1, _G1, 0.0, "grazing backscatter, mu = 0.01"),
    (_G2, _G2, 0.0, "grazing backscatter, mu = 0.001"),
    (40.0, 70.0, 90.0, "perpendicular azimuths: s = 0"),
    (85.0, 30.0, 90.0, "perpendicular azimuths: s = 0"),
    (60.0, 60.0, 180.0, "forward: L.V = -0.5 < 0"),
    (70.0, 50.0, 180.0, "forward: L.V < 0"),
    (85.0, 85.0, 180.0, "forward grazing: L.V < 0"),
    (_G1, _G1, 180.0, "forward grazing, mu = 0.01: L.V = -1 + 2e-4"),
    (50.0, 50.0, 120.0, "L.V < 0, s < 0"),
    (20.0, 75.0, 135.0, "s < 0, L.V > 0"),
    (_G1, 30.0, 0.0, "wi grazing, mu_i = 0.01"),
    (30.0, _G2, 45.0, "wo grazing, mu_o = 0.001"),
    (_G2, 70.0, 160.0, "wi grazing, s < 0"),
    (-1.0, 40.0, 0.0, "wi below the horizon: f = 0"),
    (35.0, -1.0, 0.0, "wo below the horizon: f = 0"),
)
#: The exact edges, (wi, wo, what the pair is there for): exactly representable directions
#: (y = 0 where the azimuth difference is 0 or pi), so that float32 inputs are these exactly.
EDGE_PAIRS = (
    ((1.0, 0.0, 0.0), (0.6, 0.0, 0.8), "mu_i = 0 exactly: f = 0"),
    ((0.6, 0.0, 0.8), (0.0, 1.0, 0.0), "mu_o = 0 exactly: f = 0"),
    ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), "mu_i = mu_o = 0, L.V = -1: f = 0"),
    ((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), "mu_i = mu_o = 0, L.V = +1: f = 0"),
    ((0.0, 0.0, 1.0), (0.0, 0.0, 1.0), "mu_i = mu_o = 1"),
    ((0.6, 0.0, 0.8), (0.6, 0.0, 0.8), "L.V = +1, azimuth difference 0"),
    ((0.6, 0.0, 0.8), (0.8, 0.0, 0.6), "azimuth difference exactly 0: s > 0"),
    ((0.6, 0.0, 0.8), (-0.8, 0.0, 0.6), "azimuth difference exactly pi: L.V = 0, s < 0"),
)
#: Colours and albedo mu of the edge rows (roughness: 0 and the model's maximum).
EDGE_RHOS = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
EDGE_ALBEDO_MU = (0.0, 1.0)
_N_RANDOM_PAIRS = 12
#: Pairs of :data:`_PAIRS` (by index) and of the random pairs (index from ``len(_PAIRS)``) whose
#: swapped version (wo, wi) is added after the edge rows: reciprocity f(wi, wo) = f(wo, wi) from
#: the rows themselves (the asymmetric pairs above the horizon, grazing ones included).
SWAPPED_PAIRS = (1, 2, 8, 9, 11, 15, 16, 17, 18, 21, 22, 23, 24)
#: The colour of the swapped rows (every roughness).
SWAPPED_RHO = (0.8, 0.5, 0.2)
_RHOS = ((1.0, 1.0, 1.0), (0.8, 0.5, 0.2), (0.05, 0.3, 0.9))
_ROUGHNESS = {"r": (0.0, 0.25, 0.5, 1.0), "sigma": (0.0, 0.3, 0.8, 0.5 * math.pi)}
_ALBEDO_MU = (0.001, 0.01, 0.1, 0.3, 0.5, 0.8, 1.0)


def _pairs():
    """Direction pairs (wi, wo) of the BRDF rows: the edge cases, then seeded random ones."""
    pairs = []
    for k, (ti, to, dphi, _) in enumerate(_PAIRS):
        phi_o = 17.0 * k  # rotate each pair: implementations must not assume the xz-plane
        wi = _direction(abs(ti), phi_o + dphi)
        wo = _direction(abs(to), phi_o)
        if ti < 0:  # below the horizon: reflect a direction at 100 degrees
            wi = _direction(100.0, phi_o + 30.0)
        if to < 0:
            wo = _direction(95.0, phi_o)
        pairs.append((wi, wo))
    rng = np.random.default_rng(16)
    for _ in range(_N_RANDOM_PAIRS):
        mu = rng.uniform(0.02, 1.0, 2)
        phi = rng.uniform(0.0, 360.0, 2)
        pairs.append(
            (_direction(math.degrees(math.acos(mu[0])), phi[0]), _direction(math.degrees(math.acos(mu[1])), phi[1]))
        )
    return pairs


def _roughnesses(model: str) -> tuple[float, ...]:
    """The roughness values of a model's rows (Lambert: none, NaN)."""
    from ..models.registry import model_info

    return (math.nan,) if model == "lambert" else _ROUGHNESS[model_info(model).roughness_name]


def _albedo_points(mus: tuple[float, ...]) -> list[tuple]:
    """(wi, wo, mu) of albedo rows: no directions, the given mu."""
    none = (math.nan,) * 3
    return [(none, none, mu) for mu in mus]


def _add_rows(
    rows: list[tuple],
    count: dict[tuple[str, str], int],
    model: str,
    kind: str,
    points: list[tuple],
    roughs: tuple[float, ...],
    rhos: tuple[tuple[float, float, float], ...],
) -> None:
    """Append the rows of every (wi, wo, mu) of ``points`` x roughness x colour of one model and
    kind, their ids numbered on from ``count[model, kind]`` (which is updated)."""
    k = count.get((model, kind), 0)
    digits = 4 if kind == "brdf" else 3
    for wi, wo, mu in points:
        for r in roughs:
            for rho in rhos:
                rows.append((f"{model}-{kind}-{k:0{digits}d}", kind, model, wi, wo, mu, r, rho))
                k += 1
    count[model, kind] = k


def default_vectors(models: tuple[str, ...] | list[str] | None = None) -> VectorSet:
    """The versioned default vector set (version :data:`VERSION`), built deterministically.

    ``models``: the models whose rows to build (default :data:`VECTOR_MODELS`; any of
    :data:`ALL_VECTOR_MODELS`); a model's ids are the same whichever models are asked for.

    BRDF rows: every direction pair × roughness × colour for each model of
    :data:`VECTOR_MODELS` (Lambert: no roughness); albedo rows (models of
    :data:`ALBEDO_MODELS`): mu in {0.001, 0.01, 0.1, 0.3, 0.5, 0.8, 1} × roughness ×
    colour; then the edge rows: :data:`EDGE_PAIRS` (and the albedo at mu = 0, 1) × roughness
    {0, maximum} × rho {0, 1}.

    >>> v = default_vectors()
    >>> edge = v.subset(v.id == "eon-brdf-0396")
    >>> edge.wi.tolist(), edge.roughness.tolist(), edge.rho.tolist()
    ([[1.0, 0.0, 0.0]], [0.0], [[0.0, 0.0, 0.0]])
    """
    if models is None:
        models = VECTOR_MODELS
    if isinstance(models, str) or not all(isinstance(m, str) for m in models):
        raise TypeError(f"models must be a sequence of model names, one of {', '.join(ALL_VECTOR_MODELS)}")
    bad = [m for m in models if m not in ALL_VECTOR_MODELS]
    if bad or not models:
        raise ValueError(f"models: expected names among {', '.join(ALL_VECTOR_MODELS)}, got {list(models)!r}")
    models = tuple(m for m in ALL_VECTOR_MODELS if m in models)
    rows: list[tuple] = []
    pairs = _pairs()
    nan = math.nan
    count: dict[tuple[str, str], int] = {}  # (model, kind) -> rows so far: later blocks' ids continue the numbering
    brdf = [(wi, wo, nan) for wi, wo in pairs]
    for model in models:
        roughs = _roughnesses(model)
        _add_rows(rows, count, model, "brdf", brdf, roughs, _RHOS)
        if model in ALBEDO_MODELS:
            _add_rows(rows, count, model, "albedo", _albedo_points(_ALBEDO_MU), roughs, _RHOS)
    edge_brdf = [(wi, wo, nan) for wi, wo, _ in EDGE_PAIRS]
    for model in models:  # the edge rows, after every model's rows (ids and order kept)
        roughs = _roughnesses(model)
        edge_roughs = roughs if model == "lambert" else (0.0, roughs[-1])
        _add_rows(rows, count, model, "brdf", edge_brdf, edge_roughs, EDGE_RHOS)
        if model in ALBEDO_MODELS:
            _add_rows(rows, count, model, "albedo", _albedo_points(EDGE_ALBEDO_MU), edge_roughs, EDGE_RHOS)
    swapped = [(pairs[j][1], pairs[j][0], nan) for j in SWAPPED_PAIRS]
    for model in models:  # version 4: the swapped pairs, after the edge rows
        _add_rows(rows, count, model, "brdf", swapped, _roughnesses(model), (SWAPPED_RHO,))
    return VectorSet(
        id=np.array([r[0] for r in rows]),
        kind=np.array([r[1] for r in rows]),
        model=np.array([r[2] for r in rows]),
        wi=np.array([r[3] for r in rows], dtype=np.float64),
        wo=np.array([r[4] for r in rows], dtype=np.float64),
        mu=np.array([r[5] for r in rows]),
        roughness=np.array([r[6] for r in rows]),
        rho=np.array([r[7] for r in rows], dtype=np.float64),
        version=VERSION,
    )


# ----------------------------------------------------------------------------- writing


def _cell(v):
    if isinstance(v, (str, np.str_)):
        return str(v)
    v = float(v)
    return "" if math.isnan(v) else repr(v)


def _header_lines(vectors):
    return [
        f"{FORMAT_NAME}, version {vectors.version}",
        "kind brdf: f(wi, wo) without the cosine factor; kind albedo: directional albedo E(mu)",
        "directions in the local frame (normal +z), both pointing away from the surface; blank = not applicable",
        "roughness: r in [0, 1] for fon/eon/eon_approx, sigma in radians for qon; fill out_r,out_g,out_b "
        "(rows left blank are skipped)",
    ]


def write_vectors(
    vectors: VectorSet, path: str | Path, *, out: np.ndarray | None = None, blank_out: bool = False
) -> Path:
    """Write ``vectors`` to ``path`` (CSV, or JSON if the name ends in ``.json``).

    ``out`` (n, 3), if given, is appended as ``out_r, out_g, out_b`` (a results file);
    ``blank_out=True`` appends those columns empty (the file an implementer fills in).
    """
    path = Path(path)
    cols = vectors.columns()
    if blank_out and out is None:
        out = np.full((len(vectors), 3), np.nan)
    names = list(COLUMNS) + (list(OUT_COLUMNS) if out is not None else [])
    if out is not None:
        out = np.asarray(out, dtype=np.float64).reshape(len(vectors), 3)
        for k, name in enumerate(OUT_COLUMNS):
            cols[name] = out[:, k]
    n = len(vectors)
    if path.suffix.lower() == ".json":

        def value(name, i):
            v = cols[name][i]
            if isinstance(v, (str, np.str_)):
                return str(v)
            if not math.isfinite(float(v)):
                if name not in OUT_COLUMNS or blank_out:
                    return None
                return str(float(v))  # a result NaN stays "nan"
            return float(v)

        doc = {
            "format": FORMAT_NAME,
            "version": vectors.version,
            "notes": _header_lines(vectors)[1:],
            "columns": names,
            "rows": [{name: value(name, i) for name in names} for i in range(n)],
        }
        write_text(path, json.dumps(doc, indent=1) + "\n")
        return path
    buf = io.StringIO()
    for line in _header_lines(vectors):
        buf.write(f"# {line}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(names)
    text_cols = [cols[name] for name in names]
    n_in = len(COLUMNS)
    for i in range(n):
        w.writerow(
            [_cell(c[i]) for c in text_cols[:n_in]]
            + [("" if blank_out else repr(float(c[i]))) for c in text_cols[n_in:]]
        )
    write_text(path, buf.getvalue())
    return path


# ----------------------------------------------------------------------------- reading


class _HugeInt:
    """A JSON integer too long to be any float (read as its digit count, never converted:
    Python refuses to convert integers of more than 4300 digits at all)."""

    def __init__(self, text: str) -> None:
        self.digits = len(text.lstrip("-"))

    def __str__(self) -> str:
        return f"<a {self.digits}-digit integer>"

    __repr__ = __str__


#: JSON integers with more digits than this are beyond any float (10^309 > 1.8e308).
_MAX_INT_DIGITS = 400


def _json_int(text: str) -> int | _HugeInt:
    return int(text) if len(text) <= _MAX_INT_DIGITS else _HugeInt(text)


def _parse_number(text, column, row_label, allow_nonfinite=False):
    if text is None:
        return math.nan
    if isinstance(text, bool):
        raise ValueError(f"{row_label}: column {column} must be a number, got {text!r}")
    if isinstance(text, _HugeInt):
        raise ValueError(f"{row_label}: column {column} is too large for a float (an integer of {text.digits} digits)")
    if isinstance(text, (int, float)):
        try:
            v = float(text)
        except OverflowError:
            raise ValueError(
                f"{row_label}: column {column} is too large for a float ({len(str(text))} digits)"
            ) from None
        if not (allow_nonfinite or math.isfinite(v)):  # JSON 1e400 reads as inf
            raise ValueError(f"{row_label}: column {column} is not a finite number: {v!r}")
        return v
    if not isinstance(text, str):
        raise ValueError(f"{row_label}: column {column} must be a number, got a {type(text).__name__}")
    text = text.strip()
    if text == "":
        return math.nan
    if "_" in text:  # Python's float() reads "1_000"; a number column does not
        raise ValueError(f"{row_label}: column {column} is not a number: {text[:40]!r}")
    try:
        v = float(text)
    except ValueError:
        raise ValueError(f"{row_label}: column {column} is not a number: {text[:40]!r}") from None
    if (math.isnan(v) or math.isinf(v)) and not allow_nonfinite:
        raise ValueError(f"{row_label}: column {column} is not a finite number: {text[:40]!r}")
    return v


def _read_records(path):
    """(column names, list of {column: raw value}) of a CSV or JSON file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise not_utf8(path) from None
    except OSError as exc:
        raise named(exc, path) from None
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text, parse_int=_json_int)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
        except RecursionError:
            raise ValueError(f"{path}: not usable JSON (nested too deeply)") from None
        rows = doc.get("rows") if isinstance(doc, dict) else doc
        if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
            raise ValueError(f"{path}: expected a JSON object with a 'rows' list of objects")
        names = (
            list(doc.get("columns") or (rows[0].keys() if rows else []))
            if isinstance(doc, dict)
            else list(rows[0].keys() if rows else [])
        )
        return names, rows
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    reader = csv.reader(lines)
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise ValueError(f"{path}: empty file (no header row)") from None
    except csv.Error as exc:
        raise ValueError(f"{path}: header row is not valid CSV ({exc})") from None
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise ValueError(f"{path}: duplicated column(s) {', '.join(dup)} in the header row")
    rows = []
    lineno = 1
    while True:
        try:
            cells = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise ValueError(f"{path}: data row {lineno} is not valid CSV ({exc})") from None
        lineno += 1
        if len(cells) != len(header):
            raise ValueError(f"{path}: data row {lineno - 1} has {len(cells)} cells, the header has {len(header)}")
        rows.append(dict(zip(header, cells)))
    return header, rows


def _record_out(rec, label):
    """The three result values of one record: from ``out_r, out_g, out_b`` or an ``out`` list;
    None when the row is left blank (every result empty)."""
    raw = rec.get("out")
    if raw is not None and not (isinstance(raw, str) and not raw.strip()):
        if not isinstance(raw, list) or len(raw) != 3:
            raise ValueError(f"{label}: column out must be a list of 3 numbers, got {str(raw)[:40]!r}")
        vals = raw
        cols = ("out[0]", "out[1]", "out[2]")
    else:
        vals = [rec.get(c) for c in OUT_COLUMNS]
        cols = OUT_COLUMNS
    blank = [v is None or (isinstance(v, str) and not v.strip()) for v in vals]
    if all(blank):
        return None
    if any(blank):
        col = cols[blank.index(True)]
        raise ValueError(f"{label}: column {col} is blank while the row's other results are given")
    # "nan"/"inf" results are read (and fail the grade): a NaN is the implementation's bug
    return [_parse_number(v, c, label, allow_nonfinite=True) for v, c in zip(vals, cols)]


#: Rows read and graded at a time by :func:`iter_results` (memory is bounded by this).
CHUNK_ROWS = 50_000
#: JSON results files are parsed whole: above this size, use CSV (which is streamed).
MAX_JSON_BYTES = 256 * 1024 * 1024
#: Ids of this form name rows of the vector set; any other id is the submitter's own query,
#: graded from the inputs written in its row.
_SET_ID = re.compile(r"^(" + "|".join(ALL_VECTOR_MODELS) + r")-(brdf|albedo)-\d+$")


#: Key of a CSV record holding the line of the file where its row starts (not a column name:
#: a header cell is stripped text and cannot hold a NUL).
_LINE = "\0line"


def _csv_rows(path):
    """(header, iterator of {column: cell}) of a CSV file, read line by line; each record
    also holds, under the key ``_LINE``, the line of the file where its row starts."""
    fh = open(path, encoding="utf-8-sig", newline="")
    pending = collections.deque()  # lines handed to the reader, by number

    def lines():
        with fh:
            try:
                for lineno, ln in enumerate(fh, 1):
                    st = ln.strip()
                    if st and not st.startswith("#"):
                        pending.append(lineno)
                        yield ln
            except UnicodeDecodeError:
                raise not_utf8(path) from None
            except OSError as exc:
                raise named(exc, path) from None

    reader = csv.reader(lines())
    used = 0

    def start_line():
        """The file line where the record the reader returned last began (its lines dropped)."""
        nonlocal used
        first = pending[0] if pending else None
        for _ in range(min(reader.line_num - used, len(pending))):
            pending.popleft()
        used = reader.line_num
        return first

    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise ValueError(f"{path}: empty file (no header row)") from None
    except csv.Error as exc:
        raise ValueError(f"{path}: header row is not valid CSV ({exc})") from None
    start_line()
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise ValueError(f"{path}: duplicated column(s) {', '.join(dup)} in the header row")

    def rows():
        n = 0
        while True:
            try:
                cells = next(reader)
            except StopIteration:
                return
            except csv.Error as exc:
                at = f" (line {pending[0]})" if pending else ""
                raise ValueError(f"{path}: data row {n + 1}{at} is not valid CSV ({exc})") from None
            n += 1
            line = start_line()
            if len(cells) != len(header):
                raise ValueError(
                    f"{path}: data row {n} (line {line}) has {len(cells)} cells, the header has {len(header)}"
                )
            rec = dict(zip(header, cells))
            rec[_LINE] = line
            yield rec

    return header, rows()


def _json_rows(path):
    path = Path(path)
    if path.stat().st_size > MAX_JSON_BYTES:
        raise ValueError(
            f"{path}: JSON results files are read whole and this one is larger than "
            f"{MAX_JSON_BYTES >> 20} MB: write the results as CSV (read in chunks)"
        )
    names, records = _read_records(path)
    return names, iter(records)


def _label(path, n, rid, line=None):
    at = "" if line is None else f"line {line}, "
    return f"{path}: row {n} ({at}id {rid[:40]!r})"


def _own_row(rec, label):
    """The inputs of a row that is the submitter's own query, checked."""
    from ..models.registry import model_info

    kind, model = str(rec.get("kind", "")).strip(), str(rec.get("model", "")).strip()
    if kind not in ("brdf", "albedo"):
        raise ValueError(f"{label}: column kind must be brdf or albedo, got {kind[:40]!r}")
    if model not in ALL_VECTOR_MODELS or (kind == "albedo" and model not in ALBEDO_MODELS):
        allowed = ALL_VECTOR_MODELS if kind == "brdf" else ALBEDO_MODELS
        raise ValueError(
            f"{label}: column model must be one of {', '.join(allowed)} for kind {kind}, got {model[:40]!r}"
        )
    vals = {c: _parse_number(rec.get(c), c, label) for c in _NUMERIC}
    need = ["rho_r", "rho_g", "rho_b"] + ([] if model == "lambert" else ["roughness"])
    need += [f"w{d}_{a}" for d in "io" for a in "xyz"] if kind == "brdf" else ["mu"]
    for c in need:
        if math.isnan(vals[c]):
            raise ValueError(f"{label}: column {c} is blank; a {model} {kind} row needs it")
    if kind == "brdf":
        for d in "io":
            norm = math.sqrt(sum(vals[f"w{d}_{a}"] ** 2 for a in "xyz"))
            if abs(norm - 1.0) > 1e-4:
                raise ValueError(f"{label}: columns w{d}_x, w{d}_y, w{d}_z are not a unit vector (length {norm:.6g})")
    elif not 0.0 <= vals["mu"] <= 1.0:
        raise ValueError(f"{label}: column mu must be in [0, 1], got {vals['mu']!r}")
    if model != "lambert":
        hi = model_info(model).roughness_max
        if not 0.0 <= vals["roughness"] <= hi:
            raise ValueError(f"{label}: column roughness must be in [0, {hi:g}] for {model}, got {vals['roughness']!r}")
    for c in ("rho_r", "rho_g", "rho_b"):
        if not 0.0 <= vals[c] <= 1.0:
            raise ValueError(f"{label}: column {c} must be in [0, 1] (an albedo), got {vals[c]!r}")
    return kind, model, vals


def iter_results(
    path: str | Path, vectors: VectorSet | None = None, *, chunk_rows: int = CHUNK_ROWS
) -> Iterator[tuple[VectorSet, np.ndarray, int]]:
    """Read a submitted results file in chunks: yield ``(vectors_chunk, out, n_skipped)``.

    The rules are those of :func:`read_results`; a CSV file is read line by line, so memory
    does not grow with the file's length.  A row whose id has the form of the set's ids
    (``eon-brdf-0042``) must be that vector; a row with any other id is the submitter's own
    query, graded from its own inputs (checked: unit directions, mu in [0, 1], roughness in
    the model's range).

    Examples
    --------
    >>> import tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> p = os.path.join(d, "mine.csv")
    >>> _ = open(p, "w").write(
    ...     "id,kind,model,wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,mu,roughness,rho_r,rho_g,rho_b,out_r,out_g,out_b\\n"
    ...     "my-1,albedo,lambert,,,,,,,0.5,,0.5,0.5,0.5,0.5,0.5,0.5\\n"
    ...     "my-2,albedo,lambert,,,,,,,0.7,,0.5,0.5,0.5,,,\\n")
    >>> [(len(v), out.tolist(), n) for v, out, n in iter_results(p)]
    [(1, [[0.5, 0.5, 0.5]], 1)]
    """
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1:
        raise ValueError(f"chunk_rows must be a positive integer, got {chunk_rows!r}")
    vectors = default_vectors(ALL_VECTOR_MODELS) if vectors is None else vectors
    path = Path(path)
    if not path.is_file():
        if path.exists():
            raise ValueError(f"{path}: not a regular file")
        raise FileNotFoundError(2, "No such file or directory", str(path))
    is_csv = path.suffix.lower() != ".json"
    names, records = _csv_rows(path) if is_csv else _json_rows(path)
    names = list(names)
    index = {str(v): i for i, v in enumerate(vectors.id)}
    ref_cols = vectors.columns()
    seen = np.zeros(len(vectors), bool)
    first = True
    n = 0
    any_results = False
    while True:
        take: list[tuple[int, Any]] = []
        own: list[tuple[int, Any]] = []
        out: list[Any] = []
        skipped = 0
        for rec in records:
            if first:
                missing = [c for c in COLUMNS if c not in names and c not in rec]
                if missing:
                    raise ValueError(
                        f"{path}: missing column(s) {', '.join(missing)} (expected {', '.join(COLUMNS + OUT_COLUMNS)})"
                    )
                first = False
            n += 1
            rid = str(rec.get("id", "")).strip()
            label = _label(path, n, rid, rec.get(_LINE) if is_csv else None)
            i = index.get(rid)
            row: int | tuple[Any, ...]
            if i is None:
                if _SET_ID.match(rid) or not rid:
                    raise ValueError(f"{label}: no such vector in set version {vectors.version}")
                kind, model, vals = _own_row(rec, label)
                row = (rid, kind, model, vals)
            else:
                if seen[i]:
                    raise ValueError(f"{label}: duplicated id")
                seen[i] = True
                for col in ("kind", "model"):
                    if str(rec.get(col, "")).strip() != str(ref_cols[col][i]):
                        raise ValueError(
                            f"{label}: column {col} is {str(rec.get(col))[:40]!r}, the vector has "
                            f"{str(ref_cols[col][i])!r}"
                        )
                for col in _NUMERIC:
                    got = _parse_number(rec.get(col), col, label)
                    want = float(ref_cols[col][i])
                    if math.isnan(want) != math.isnan(got) or (
                        not math.isnan(want) and abs(got - want) > INPUT_MATCH_TOL * (1.0 + abs(want))
                    ):
                        raise ValueError(
                            f"{label}: column {col} is {got!r}, the vector has "
                            f"{'blank' if math.isnan(want) else repr(want)}: "
                            f"rows do not match the vectors"
                        )
                row = i
            vals_out = _record_out(rec, label)
            if vals_out is None:
                skipped += 1
            else:
                out.append(vals_out)
                (take if isinstance(row, int) else own).append((len(out) - 1, row))
            if len(out) + skipped >= chunk_rows:
                break
        if first:
            raise ValueError(f"{path}: no data rows")
        any_results = any_results or bool(out)
        if out or skipped:
            yield _chunk(vectors, take, own, out), np.array(out, dtype=np.float64).reshape(-1, 3), skipped
        if len(out) + skipped < chunk_rows:  # the file is read to its end
            if not any_results:
                raise ValueError(f"{path}: no row has results (fill out_r, out_g, out_b of the rows to grade)")
            return


def _chunk(vectors, take, own, out):
    """The VectorSet of a chunk's graded rows, in the file's order."""
    m = len(out)
    ids = np.empty(m, dtype=object)
    kind = np.empty(m, dtype=object)
    model = np.empty(m, dtype=object)
    wi, wo = np.full((m, 3), np.nan), np.full((m, 3), np.nan)
    mu, rough, rho = np.full(m, np.nan), np.full(m, np.nan), np.full((m, 3), np.nan)
    if take:
        pos = np.array([p for p, _ in take], dtype=np.int64)
        src = np.array([i for _, i in take], dtype=np.int64)
        ids[pos], kind[pos], model[pos] = vectors.id[src], vectors.kind[src], vectors.model[src]
        wi[pos], wo[pos], mu[pos] = vectors.wi[src], vectors.wo[src], vectors.mu[src]
        rough[pos], rho[pos] = vectors.roughness[src], vectors.rho[src]
    for p, (rid, k, mdl, v) in own:
        ids[p], kind[p], model[p] = rid, k, mdl
        wi[p] = (v["wi_x"], v["wi_y"], v["wi_z"])
        wo[p] = (v["wo_x"], v["wo_y"], v["wo_z"])
        mu[p], rough[p] = v["mu"], v["roughness"]
        rho[p] = (v["rho_r"], v["rho_g"], v["rho_b"])
    return VectorSet(ids.astype(str), kind.astype(str), model.astype(str), wi, wo, mu, rough, rho, vectors.version)


def read_results(path: str | Path, vectors: VectorSet | None = None, *, with_skipped: bool = False) -> tuple:
    """Read a submitted results file; return ``(vectors_subset, out)`` matched by id.

    ``vectors`` defaults to :func:`default_vectors` of every model (``ALL_VECTOR_MODELS``).  Every row must carry the columns
    :data:`COLUMNS`; its id must name a vector and its inputs must equal that vector's (to
    :data:`INPUT_MATCH_TOL`, so float32-printed inputs pass), or be an id of the
    submitter's own (see :func:`iter_results`).  The results are the columns
    :data:`OUT_COLUMNS` or, in JSON, either those keys or an ``"out": [r, g, b]`` list in
    each row (the file's ``"columns"`` list need not name them).  A row whose results are
    all blank is skipped (any subset of the rows may be filled); "nan" and "inf" are read as
    such: they fail the grade, they do not make the file unusable.  Rows are returned in the
    file's order; ``with_skipped=True`` returns ``(vectors_subset, out, n_skipped)``.  The
    whole file is held in memory: :func:`iter_results` reads it in chunks.

    Raises
    ------
    ValueError
        Missing or duplicated columns, malformed CSV or JSON, non-numeric values (also
        ``1_000``), unknown or duplicated ids, inputs that do not match the vectors, or no
        row with results (the message names the row and the column).
    """
    chunks = list(iter_results(path, vectors, chunk_rows=CHUNK_ROWS))
    vs = [c[0] for c in chunks if len(c[0])]
    if not vs:
        raise ValueError(f"{path}: no row has results (fill out_r, out_g, out_b of the rows to grade)")
    cat = VectorSet(  # type: ignore[misc]  # the eight array fields by position, then version
        *(  # type: ignore[arg-type]
            np.concatenate([getattr(v, f) for v in vs])
            for f in ("id", "kind", "model", "wi", "wo", "mu", "roughness", "rho")
        ),
        version=vs[0].version,
    )
    out = np.concatenate([c[1] for c in chunks])
    skipped = sum(c[2] for c in chunks)
    return (cat, out, skipped) if with_skipped else (cat, out)


__all__ = [
    "VERSION",
    "COLUMNS",
    "OUT_COLUMNS",
    "VECTOR_MODELS",
    "EXTRA_MODELS",
    "ALL_VECTOR_MODELS",
    "ALBEDO_MODELS",
    "VectorSet",
    "default_vectors",
    "write_vectors",
    "read_results",
    "iter_results",
    "CHUNK_ROWS",
]

"""The work of one material file: read it, evaluate each material, return compact records.

:func:`process_file` is what a worker process (or a Dask worker) runs for one file.  It
returns plain, JSON-ready data only (no Material, node or stage survives it), so that a
library's memory does not grow with its heavy objects, results travel between processes
cheaply and the cache stores them as they are.  Four kinds of :class:`Task`:

- ``"report"``: one record per material (the report's table row, :func:`material_record`):
  verdict, reasons, shader kind, base colour, diffuse roughness, the diffuse lobe's weight
  and selection probability and the directional albedo at theta_o = 30 deg, the albedo at
  mu = 1, 0.5, 0.2, the largest albedo over theta_o in [0, 87] deg against its allowance,
  and how far the lobe selection probabilities are from summing to 1;
- ``"eval"``: one record per material as ``eval --json`` lists it (``Material.to_dict()``
  plus ``"evaluation"`` at the task's directions);
- ``"colours"``: one record per material of its diffuse colour and roughness
  (:mod:`.colours`, what the colour-shift validation reads);
- ``"detail"``: for a few chosen materials of the file, a preview render and an albedo plot
  (PNG bytes, base64), the albedo curve and the table of resolved parameters with provenance.

usd-core and MaterialX are not safe to share between threads: the work holds a process-wide
lock, so a Dask worker running several threads still reads one file at a time.
"""

from __future__ import annotations

import base64
import math
import os
import re
import tempfile
import threading
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

#: Allowed albedo above 1 per diffuse model (QON's documented overshoot, else table accuracy).
OVERSHOOT = {"qon": 0.0152 + 2e-3, "eon": 2e-3, "lambert": 2e-3, "": 2e-3}
#: Largest |sum of the lobe selection probabilities - 1| accepted.
PROBABILITY_TOLERANCE = 1e-12
#: View angle of the table's diffuse weight, probability and albedo (degrees).
THETA_O = 30.0
#: The mu_o = cos(theta_o) at which every record carries the directional albedo.
MUS = (1.0, 0.5, 0.2)
#: Albedo curves are checked up to this theta_o (degrees; grazing tables are less accurate).
CHECKED_UP_TO = 87.0
#: Texts kept per record: the first few warnings / not-modelled inputs (their counts are kept too).
KEPT = 5
#: Characters kept of a text from a file (an error, a warning).
TEXT_CHARS = 400
#: Seconds before the start of the work within which a dependency's change makes the result
#: not cacheable (the file may have been written while it was read).
RACY_S = 1.0
#: Inputs shown in the parameter table even when they hold their default.
KEY_INPUTS = ("base_color", "base_diffuse_roughness", "base_weight", "color", "roughness")

KINDS = ("report", "eval", "detail", "colours")
VERDICTS = ("fail", "flagged", "unsupported", "pass")

_LOCK = threading.Lock()


@dataclass(frozen=True)
class Task:
    """What to compute for a file (hashable, picklable; part of the cache key).

    Parameters
    ----------
    kind : {"report", "eval", "detail", "colours"}
    n_mu : int
        Points of the albedo curve over theta_o in [0, 89] deg (report: the check; detail: the plot).
    uv, time, variants, purpose, material
        As ``load_materials`` takes them (``variants``: (set, value) pairs).
    theta_i, theta_o, phi : tuple of float
        Directions of ``eval`` (degrees).
    select : tuple of int
        ``detail``: positions of the file's materials to draw.
    size : int
        ``detail``: preview size (pixels, the height of the two spheres).

    Examples
    --------
    >>> Task(kind="detail", select=(0, 2)).key()["select"]
    [0, 2]
    >>> Task(kind="nope")
    Traceback (most recent call last):
    ...
    ValueError: kind must be one of report, eval, detail, colours, got 'nope'
    """

    kind: str = "report"
    n_mu: int = 16
    uv: tuple = (0.5, 0.5)
    time: float | None = None
    variants: tuple = ()
    purpose: str = "full"
    material: str | None = None
    theta_i: tuple = (THETA_O,)
    theta_o: tuple = (THETA_O,)
    phi: tuple = (180.0,)
    select: tuple = ()
    size: int = 32

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if not isinstance(self.n_mu, int) or not 2 <= self.n_mu <= 1000:
            raise ValueError(f"n_mu must be an integer in [2, 1000], got {self.n_mu!r}")
        if not isinstance(self.size, int) or not 8 <= self.size <= 512:
            raise ValueError(f"size must be an integer in [8, 512], got {self.size!r}")

    def key(self) -> dict[str, Any]:
        """The task as JSON-ready data (tuples as lists)."""
        d = asdict(self)
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in d.items()}


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, RecursionError):
        return "nested too deeply to read"
    text = " ".join(str(exc).split())
    if not isinstance(exc, (ValueError, TypeError, LookupError, OSError)) or not text:
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text[:TEXT_CHARS]


def _num(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _rgb(v: Any) -> list | None:
    if v is None:
        return None
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.size == 1:
        a = np.repeat(a, 3)
    if a.size < 3:
        return None
    return [_num(x) for x in a[:3]]


def shader_kind(shader_id: str) -> str:
    """A shader id as a family name: the nodedef name less ``ND_`` and its output type.

    >>> shader_kind("ND_open_pbr_surface_surfaceshader"), shader_kind("ND_standard_surface_surfaceshader_100")
    ('open_pbr_surface', 'standard_surface')
    >>> shader_kind("UsdPreviewSurface"), shader_kind("ND_oren_nayar_diffuse_bsdf"), shader_kind("")
    ('UsdPreviewSurface', 'oren_nayar_diffuse_bsdf', '(no shader)')
    """
    s = (shader_id or "").strip()
    if not s:
        return "(no shader)"
    s = re.sub(r"^ND_", "", s)
    s = re.sub(r"_surfaceshader(_\w+)?$", "", s)
    return s[:60]


def _curves(node: Any, thetas: np.ndarray) -> tuple:
    """(directional albedo E (n, 3), diffuse weight x albedo (n, 3), diffuse dict, lobe listing)."""
    from ..readers.evaluate import brdf_and_lobes

    t = np.radians(thetas)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)
    _, E, d, listing = brdf_and_lobes(node, wo, wo)
    return np.asarray(E, dtype=np.float64), np.asarray(d["contribution"], dtype=np.float64), d, listing


def empty_record() -> dict[str, Any]:
    """A record with every key of :func:`material_record` and nothing known.

    >>> r = empty_record()
    >>> r["verdict"], r["albedo"], r["reasons"]
    ('pass', None, [])
    """
    return {
        "material": None,
        "name": None,
        "shader": "",
        "kind": "",
        "node": None,
        "diffuse_model": None,
        "verdict": "pass",
        "reasons": [],
        "detail": "",
        "base_color": None,
        "roughness": None,
        "diffuse_weight": None,
        "diffuse_probability": None,
        "albedo": None,
        "albedo_mu": None,
        "albedo_max": None,
        "albedo_limit": None,
        "probability_error": None,
        "not_modelled": [],
        "n_not_modelled": 0,
        "warnings": [],
        "n_warnings": 0,
    }


def material_record(m: Any, n_mu: int) -> dict[str, Any]:
    """The report's record of one material (see the module docstring).

    ``verdict``: ``"fail"`` (not evaluated, albedo above its allowance, or lobe probabilities
    not summing to 1), ``"unsupported"`` (the shader maps onto no node of the library),
    ``"flagged"`` (evaluated and within bounds, with inputs not modelled or reader warnings),
    ``"pass"``.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
    >>> (m,) = load_materials(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> r = material_record(m, 16)
    >>> r["verdict"], r["kind"], r["roughness"], r["albedo_max"] <= r["albedo_limit"]
    ('pass', 'open_pbr_surface', 1.0, True)
    """
    rec = empty_record()
    rec.update(
        material=m.path,
        name=m.name,
        shader=m.shader_id,
        kind=shader_kind(m.shader_id),
        node=m.node_class or None,
        diffuse_model=m.diffuse_model or None,
        not_modelled=[str(u)[:TEXT_CHARS] for u in m.unsupported[:KEPT]],
        n_not_modelled=len(m.unsupported),
        warnings=[str(w)[:TEXT_CHARS] for w in m.warnings[:KEPT]],
        n_warnings=len(m.warnings),
    )
    if m.error:
        rec.update(verdict="fail", reasons=["not evaluated"], detail=str(m.error)[:TEXT_CHARS])
        return rec
    if not m.supported:
        text = "; ".join(str(u) for u in m.unsupported)
        reason = "not a surface shader" if "not a surface shader" in text else "unsupported shader"
        rec.update(verdict="unsupported", reasons=[reason], detail=text[:TEXT_CHARS])
        rec["not_modelled"], rec["n_not_modelled"] = [], 0
        return rec
    ni = m.node_inputs
    colour = ni.get("base_color", ni.get("color"))
    rough = ni.get("base_diffuse_roughness", ni.get("roughness"))
    rec["base_color"] = _rgb(colour.value) if colour is not None else None
    rec["roughness"] = _num(rough.value) if rough is not None else None
    try:
        node = m.node()
        grid = np.linspace(0.0, 89.0, n_mu)
        extra = [THETA_O] + [math.degrees(math.acos(mu)) for mu in MUS]
        E, _, d, listing = _curves(node, np.concatenate([grid, extra]))
    except Exception as exc:  # noqa: BLE001 -- one bad material never loses the others
        rec.update(verdict="fail", reasons=["not evaluated"], detail=_one_line(exc))
        return rec
    k = n_mu  # the row of THETA_O
    tol = OVERSHOOT.get(m.diffuse_model, 2e-3)
    checked = E[:n_mu][grid <= CHECKED_UP_TO]
    total = np.sum([np.asarray(lb["probability"], dtype=np.float64) for lb in listing], axis=0)
    rec["diffuse_weight"] = _rgb(d["weight"][k])
    rec["diffuse_probability"] = _num(d["probability"][k])
    rec["albedo"] = _rgb(E[k])
    rec["albedo_mu"] = {f"{mu:g}": _rgb(E[k + 1 + i]) for i, mu in enumerate(MUS)}
    rec["albedo_max"] = _num(np.max(checked)) if np.all(np.isfinite(checked)) else None
    rec["albedo_limit"] = 1.0 + tol
    rec["probability_error"] = _num(np.max(np.abs(total - 1.0))) if np.all(np.isfinite(total)) else None
    fails = []
    if rec["albedo_max"] is None or rec["albedo_max"] > rec["albedo_limit"]:
        fails.append("albedo above 1")
        rec["detail"] = (
            f"directional albedo {rec['albedo_max']} above the allowed {rec['albedo_limit']:.4g} "
            f"({m.diffuse_model or 'oren_nayar'} diffuse)"
        )
    if rec["probability_error"] is None or rec["probability_error"] > PROBABILITY_TOLERANCE:
        fails.append("lobe probabilities do not sum to 1")
        rec["detail"] = (rec["detail"] + "; " if rec["detail"] else "") + (
            f"lobe selection probabilities sum to 1 +- {rec['probability_error']}"
        )
    if fails:
        rec.update(verdict="fail", reasons=fails)
        return rec
    reasons = (["inputs not modelled"] if m.unsupported else []) + (["reader warnings"] if m.warnings else [])
    if reasons:
        rec.update(verdict="flagged", reasons=reasons, detail="; ".join(m.unsupported)[:TEXT_CHARS])
    return rec


def _fmt(v: Any) -> str:
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def albedo_png(theta: Any, E: Any, contrib: Any, title: str) -> bytes:
    """A small PNG of one material's directional albedo (solid) and its diffuse lobe's
    weight x albedo (dashed), R G B, against theta_o: a figure of its own (fixed layout).

    >>> albedo_png([0, 45, 89], np.full((3, 3), 0.8), np.full((3, 3), 0.5), "grey")[:8]
    b'\\x89PNG\\r\\n\\x1a\\n'
    """
    import io

    import matplotlib

    matplotlib.use("Agg", force=True)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3.2, 2.2), dpi=80)
    ax = fig.add_axes((0.14, 0.2, 0.82, 0.68))
    E, contrib = np.asarray(E, dtype=np.float64), np.asarray(contrib, dtype=np.float64)
    for c, colour in enumerate(("tab:red", "tab:green", "tab:blue")):
        ax.plot(theta, E[:, c], color=colour, lw=1.2)
        ax.plot(theta, contrib[:, c], color=colour, lw=1.0, ls="--")
    ax.set_xlim(0.0, 90.0)
    ax.set_ylim(0.0, 1.05)
    ax.set_xticks([0, 30, 60, 90])
    ax.set_yticks([0.0, 0.5, 1.0])
    ax.tick_params(labelsize=7)
    ax.set_xlabel("theta_o (deg)", fontsize=7, labelpad=1)
    fig.text(0.5, 0.96, title[:48], ha="center", va="top", fontsize=8)
    out = io.BytesIO()
    fig.savefig(out, format="png")
    return out.getvalue()


def material_detail(m: Any, n_mu: int, size: int) -> dict[str, Any]:
    """Preview and albedo plot (PNG, base64), albedo curve and parameter table of one
    supported material.

    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS, load_materials
    >>> (m,) = load_materials(BUNDLED_MATERIALS / "clay_rough.mtlx")
    >>> d = material_detail(m, 8, 16)
    >>> base64.b64decode(d["preview_png"])[:4], len(d["theta"]), "base_diffuse_roughness" in [row[0] for row in d["parameters"]]
    (b'\\x89PNG', 8, True)
    """
    from ..readers.preview import render_image, write_image

    theta = np.linspace(0.0, 89.0, n_mu)
    E, contrib, _, _ = _curves(m.node(), theta)
    img = render_image(m, size, supersample=1)
    with tempfile.TemporaryDirectory(prefix="openpbr-diffuse-preview-") as tmp:
        png = os.path.join(tmp, "preview.png")
        write_image(img, png)
        with open(png, "rb") as fh:
            data = fh.read()
    params = [
        [n, _fmt(p.value), p.kind, p.provenance]
        for n, p in m.parameters.items()
        if p.kind != "default" or (n in m.node_inputs and n in KEY_INPUTS)
    ]
    return {
        "material": m.path,
        "shader": m.shader_id,
        "preview_png": base64.b64encode(data).decode("ascii"),
        "albedo_png": base64.b64encode(albedo_png(theta, E, contrib, m.name)).decode("ascii"),
        "theta": theta.tolist(),
        "albedo": E.tolist(),
        "diffuse": contrib.tolist(),
        "parameters": params,
    }


def _payload(mats: list, task: Task) -> dict[str, Any]:
    from ..readers.evaluate import evaluate

    if task.kind == "report":
        return {"records": [material_record(m, task.n_mu) for m in mats], "error": None}
    if task.kind == "colours":
        from .colours import colour_record

        return {"records": [colour_record(m) for m in mats], "error": None}
    if task.kind == "eval":
        records = []
        for m in mats:
            d = m.to_dict()
            try:
                d["evaluation"] = evaluate(m, task.theta_i, task.theta_o, task.phi)
            except Exception as exc:  # noqa: BLE001 -- one bad material never loses the others
                d["evaluation"], d["error"] = None, _one_line(exc)
            records.append(d)
        return {"records": records, "error": None}
    details = []
    for i in task.select:
        if 0 <= i < len(mats) and mats[i].supported and not mats[i].error:
            try:
                details.append(dict(material_detail(mats[i], task.n_mu, task.size), index=i))
            except Exception as exc:  # noqa: BLE001 -- a picture is never worth the run
                details.append({"index": i, "material": mats[i].path, "error": _one_line(exc)})
    return {"records": details, "error": None}


def _forget_changed_textures() -> None:
    """Make the readers' texture cache (OpenImageIO's, kept for the life of the process)
    drop the files modified since it read them: a texture edited between two files, or two
    runs in one process, is read anew, never from the copy held before."""
    try:
        from ..readers import textures

        textures._system().invalidate_all(False)
    except Exception:  # noqa: BLE001 -- a reader without that cache needs nothing
        pass


def _where() -> str:
    """`` on Dask worker ADDRESS`` inside a Dask worker, else ``""``."""
    try:
        from distributed import get_worker

        return f" on Dask worker {get_worker().address}"
    except Exception:  # noqa: BLE001 -- not in a Dask worker (or no distributed)
        return ""


def process_file(path: str, task: Task) -> dict[str, Any]:
    """Do ``task`` for the material file ``path``; never raises for a problem of the file.

    Returns
    -------
    dict
        ``payload`` ({"records": [...], "error": str | None}: ``error`` when the file cannot
        be read), ``file_hash`` (SHA-256 of the file as it was before reading), ``deps``
        ([[entry, SHA-256 | None]] of every dependency, see :mod:`.deps`), ``cacheable``
        (whether the result may be stored: the file was read, its dependencies listed, and
        neither it nor a dependency changed while or shortly before it was read), ``code``
        (the code's fingerprint, :func:`.cache.code_fingerprint`) and ``elapsed_s``.

    Examples
    --------
    >>> from openpbr_diffuse.readers import BUNDLED_MATERIALS
    >>> out = process_file(str(BUNDLED_MATERIALS / "brick_textured.mtlx"), Task())
    >>> out["payload"]["records"][0]["verdict"], sorted(os.path.basename(d) for d, h in out["deps"])
    ('pass', ['brick_albedo.png', 'brick_roughness.exr'])
    >>> process_file("/no/such/file.mtlx", Task())["payload"]["error"]
    '/no/such/file.mtlx: no such file'
    """
    from ..readers import load_materials
    from .cache import code_fingerprint
    from .deps import file_hash, mtime, named_dependencies, recording

    t0 = time.perf_counter()
    start = time.time()
    path = str(os.fspath(path))
    before = file_hash(path)
    cacheable = before is not None
    with _LOCK:
        _forget_changed_textures()
        error = None
        mats: list = []
        with recording() as opened:
            try:
                mats = load_materials(
                    path,
                    time=task.time,
                    variants=dict(task.variants) or None,
                    uv=tuple(task.uv),
                    material=task.material,
                    purpose=task.purpose,
                )
                payload = _payload(mats, task)
            except Exception as exc:  # noqa: BLE001 -- reported for this file, the others go on
                error = _one_line(exc)
                if isinstance(exc, OSError) and not os.path.exists(path):
                    error += _where()
                payload = {"records": [], "error": error}
        del mats
        found = set(opened)
        if error is None:
            try:
                found |= named_dependencies(path)
            except ValueError:
                cacheable = False
        else:
            cacheable = False  # what a failed read depended on is not known
    found.discard(os.path.normpath(os.path.abspath(path)))
    deps = [[d, file_hash(d)] for d in sorted(found)]
    if cacheable:
        after = file_hash(path)
        times = [mtime(path)] + [mtime(str(d)) for d, _ in deps]
        cacheable = after == before and all(t is not None and t < start - RACY_S for t in times)
    return {
        "path": path,
        "payload": payload,
        "file_hash": before,
        "deps": deps,
        "cacheable": cacheable,
        "code": code_fingerprint(),
        "elapsed_s": time.perf_counter() - t0,
    }


def _init_worker() -> None:
    """Set up a pool worker process: the command's process handles the signals (Ctrl-C
    reaches the whole process group; a worker ignores it and ends when the pool is shut
    down), numpy's overflow warnings are not for the user."""
    import signal
    import warnings

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    warnings.simplefilter("ignore", RuntimeWarning)


__all__ = [
    "KINDS",
    "OVERSHOOT",
    "Task",
    "VERDICTS",
    "albedo_png",
    "empty_record",
    "material_detail",
    "material_record",
    "process_file",
    "shader_kind",
]

"""Report section "materials": every material of the given files (or the bundled library).

Per material: the resolved parameters with their provenance, the library node it maps onto,
the diffuse lobe's effective weight and selection probability and the material's directional
albedo at theta_o = 30 deg, the albedo curve E(theta_o) (total and the diffuse lobe's share,
``materials_<n>_albedo.png``), a preview render (directional light | furnace,
``materials_<n>_render.png``), what is not modelled and the warnings.

Checks per supported material (against properties the lobe stack must have, computed with
the material's node): the lobe selection probabilities sum to 1; the directional albedo does
not exceed 1 beyond the diffuse model's known overshoot (QON: up to 1.0152, EON-paper Fig. 5;
EON / Lambert: 2e-3, the GGX albedo-table accuracy).  Strings from the files are returned as
plain text (the runner escapes them).
"""

import re

import numpy as np

from ..model import Check, Context, Figure, SectionResult, Table

TITLE = "Materials"
KEY = "materials"

#: Allowed albedo above 1 per diffuse model (QON's documented overshoot, else table accuracy).
OVERSHOOT = {"qon": 0.0152 + 2e-3, "eon": 2e-3, "lambert": 2e-3, "": 2e-3}
THETA_O = 30.0


def _slug(k, m):
    return f"{k:02d}_" + re.sub(r"[^A-Za-z0-9]+", "_", m.name).strip("_")[:40]


def _fmt(v):
    if isinstance(v, (tuple, list)):
        return "(" + ", ".join(f"{x:.4g}" for x in v) + ")"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _albedo_curves(node, n_mu):
    """theta_o (deg), the material's albedo E (n, 3) and the diffuse lobe's weight x albedo."""
    from ...readers.evaluate import brdf_and_lobes

    theta = np.linspace(0.0, 89.0, n_mu)
    wo = np.stack([np.sin(np.radians(theta)), np.zeros_like(theta), np.cos(np.radians(theta))], axis=-1)
    _, E, d, _ = brdf_and_lobes(node, wo, wo)
    return theta, E, np.asarray(d["contribution"])


def _albedo_grid(curves, path):
    """One panel per material: albedo (solid) and diffuse lobe share (dashed), R, G, B."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(curves)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(
        rows, cols, figsize=(3.0 * cols, 2.3 * rows), dpi=80, squeeze=False, sharex=True, sharey=True
    )
    for ax, (label, theta, E, contrib) in zip(axes.flat, curves):
        for c, colour in enumerate(("tab:red", "tab:green", "tab:blue")):
            ax.plot(theta, E[:, c], color=colour, lw=1.2)
            ax.plot(theta, contrib[:, c], color=colour, lw=1.0, ls="--")
        ax.set_title(label[:34], fontsize=8)
        ax.set_ylim(0.0, 1.05)
        ax.tick_params(labelsize=7)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.text(
        0.5,
        0.005,
        "theta_o (deg); solid: directional albedo, dashed: diffuse lobe weight x albedo",
        ha="center",
        fontsize=8,
    )
    fig.subplots_adjust(left=0.05, right=0.98, top=0.95, bottom=0.08, hspace=0.45, wspace=0.12)
    fig.savefig(path)
    plt.close(fig)


def _render(m, path, size):
    from ...readers.preview import render_image, write_image

    write_image(render_image(m, size, supersample=1), str(path))


def _material_rows(mats: list) -> list:
    from ...readers.evaluate import evaluate

    rows = []
    for m in mats:
        if m.error:
            rows.append(
                [m.file, m.path, "-", "not evaluated", "-", "-", "-", "-", "-", f"error: {m.error}", len(m.warnings)]
            )
            continue
        if not m.supported:
            rows.append(
                [m.file, m.path, m.shader_id, "-", "-", "-", "-", "-", "-", "; ".join(m.unsupported), len(m.warnings)]
            )
            continue
        r = evaluate(m, [THETA_O], [THETA_O], [180.0])
        ni = m.node_inputs
        colour = ni.get("base_color", ni.get("color"))
        rough = ni.get("base_diffuse_roughness", ni.get("roughness"))
        d = r["diffuse"]
        rows.append(
            [
                m.file,
                m.path,
                m.shader_id,
                f"{m.node_class} ({m.diffuse_model})",
                _fmt(colour.value),
                _fmt(rough.value),
                _fmt(tuple(d["weight"][0])),
                f"{d['probability'][0]:.4f}",
                _fmt(tuple(r["albedo"][0])),
                "; ".join(m.unsupported) or "-",
                len(m.warnings),
            ]
        )
    return rows


def build(ctx: Context) -> SectionResult:
    from ...readers import BUNDLED_MATERIALS, find_material_files, load_materials
    from ...readers.evaluate import directions

    res = SectionResult(KEY, TITLE)
    files = find_material_files(ctx.paths or [BUNDLED_MATERIALS])
    mats = []
    unreadable = []
    for f in files:
        ctx.progress(f"materials: reading {f.name}")
        try:
            mats += load_materials(f)
        except (ValueError, TypeError, OSError) as exc:
            unreadable.append(f"{f}: {exc}")
            res.warnings.append(f"{f}: cannot be read: {exc}")
    failed = [m for m in mats if m.error]
    # an input that cannot be read, or a material that cannot be evaluated, is a failed check
    res.checks.append(
        Check(
            "every given material file is read",
            float(len(unreadable)),
            0.0,
            "<=",
            unit="unreadable files",
            reference=f"{len(files)} files",
            detail="; ".join(unreadable),
        )
    )
    res.checks.append(
        Check(
            "every material found is evaluated",
            float(len(failed)),
            0.0,
            "<=",
            unit="materials not evaluated",
            reference=f"{len(mats)} materials",
            detail="; ".join(f"{m.path}: {m.error}" for m in failed),
        )
    )
    res.notes.append(
        f"{len(mats)} materials from {len(files)} files"
        + (" (the bundled library)" if not ctx.paths else "")
        + ". Colours in ACEScg (the readers' working space); evaluated at uv (0.5, 0.5), default time and "
        f"variants. Diffuse weight, probability and albedo at theta_o = {THETA_O:g} deg; the weight includes "
        "base_weight, (1 - metalness) and the albedo scaling 1 - E_specular(mu_o)."
    )
    res.tables.append(
        Table(
            "Materials: the node each maps onto and its diffuse lobe at theta_o = 30 deg",
            [
                "file",
                "material",
                "shader",
                "node (diffuse)",
                "base colour",
                "diffuse roughness",
                "diffuse weight",
                "selection probability",
                "albedo",
                "not modelled",
                "warnings",
            ],
            _material_rows(mats),
        )
    )
    n_mu = 16 if ctx.quick else 46
    size = 32 if ctx.quick else 72
    curves = []
    for k, m in enumerate(mats):
        ctx.progress(f"materials: {m.name}")
        for w in m.warnings:
            res.warnings.append(f"{m.path}: {w}")
        if m.error:
            res.warnings.append(f"{m.path}: not evaluated: {m.error}")
        if not m.supported:
            continue
        slug = _slug(k, m)
        res.tables.append(
            Table(
                f"{m.path} ({m.shader_id}): resolved parameters",
                ["parameter", "value", "kind", "provenance"],
                [
                    [n, _fmt(p.value), p.kind, p.provenance]
                    for n, p in m.parameters.items()
                    if p.kind != "default"
                    or n in m.node_inputs
                    and n in ("base_color", "base_diffuse_roughness", "base_weight", "color", "roughness")
                ],
            )
        )
        node = m.node()
        theta, E, contrib = _albedo_curves(node, n_mu)
        curves.append((f"{k:02d} {m.name}", theta, E, contrib))
        _render(m, ctx.image_dir / f"materials_{slug}_render.png", size)
        res.figures.append(
            Figure(f"materials_{slug}_render.png", f"{m.path}: directional light (left), uniform white furnace (right)")
        )
        tol = OVERSHOOT.get(m.diffuse_model, 2e-3)
        res.checks.append(
            Check(
                f"{m.path}: directional albedo <= 1",
                float(np.max(E[theta <= 87.0])),
                1.0 + tol,
                "<=",
                reference=f"energy conservation; allowance {tol:g} for the {m.diffuse_model or 'oren_nayar'} "
                "diffuse model's known overshoot and the GGX table accuracy",
            )
        )
        wi, wo = directions(THETA_O, np.linspace(0.0, 85.0, 12), 180.0)
        if hasattr(node, "lobes"):
            total = sum(np.asarray(lb.probability) for lb in node.lobes_and_eval(wi, wo)[0])
            res.checks.append(
                Check(
                    f"{m.path}: lobe selection probabilities sum to 1",
                    float(np.max(np.abs(total - 1.0))),
                    1e-12,
                    "<=",
                    reference="OpenPBR spec, reduction to a mixture of lobes",
                )
            )
    if curves:
        ctx.progress("materials: albedo curves")
        _albedo_grid(curves, ctx.image_dir / "materials_albedo.png")
        res.figures.insert(
            0,
            Figure(
                "materials_albedo.png",
                "Directional albedo against theta_o of each material (solid, R G B) and its "
                "diffuse lobe's weight x albedo (dashed); panels numbered as the renders",
            ),
        )
    return res


__all__ = ["TITLE", "build"]

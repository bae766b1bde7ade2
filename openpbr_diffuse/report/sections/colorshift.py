"""Report section "colorshift": spectral versus RGB evaluation of EON's colour shift.

Computes with ``openpbr_diffuse.spectral`` on the 24 measured ColorChecker spectra
(colour-science's 'BabelColor Average'): the property checks against independent
references (colour-science's own ``sd_to_XYZ``, the quadrature albedo tables, the shipped
colour-shift table), the r = 1 summary per working space, the round trip of the recovery
methods and how much the recovered spectrum changes the answer, a plot and a swatch image.
The materials' diffuse colours come from the library's runner (``ctx.extra["library"]``:
worker processes and the library cache, task ``"colours"``), so a second run over an
unchanged library reads no material file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...result import Result
from .._plot import pyplot, save
from ..model import CheckTable, Context, Figure, SectionResult, Table

KEY = "colorshift"
TITLE = "Spectral versus RGB: the EON colour shift"

#: The section's checks: its rows of the static registry ``data/report_checks.tsv``.
CHECKS = CheckTable.declared("colorshift")


def _grid(quick):
    """The (roughness, mu) grid of the ColorChecker evaluation."""
    if quick:
        return np.array([0.0, 0.5, 1.0]), np.array([0.2, 1.0])
    from ...spectral.reference import TABLE_MU, TABLE_ROUGHNESS

    return np.array(TABLE_ROUGHNESS), np.array(TABLE_MU)


def _lambert_checks(res: Any, k0: int) -> list[Result]:
    """At r = 0 EON is Lambert: RGB equals spectral evaluation and there is no colour shift."""
    inside = ~res.rho_rgb_clipped
    return [
        CHECKS.check(
            "r = 0: RGB and spectral evaluation agree (EON is Lambert)",
            float(res.delta_e_rgb_vs_spectral[inside, k0].max()),
            1e-6,
            "<=",
            "Lambert limit (E = rho, linear in rho)",
            unit="dE2000",
            detail=f"{int(inside.sum())} in-gamut patches; clipped: "
            + (", ".join(n for n, c in zip(res.colours.names, res.rho_rgb_clipped) if c) or "none"),
        ),
        CHECKS.check(
            "r = 0: no colour shift", float(res.delta_e_shift[:, k0].max()), 1e-6, "<=", "Lambert limit", unit="dE2000"
        ),
    ]


def _flat_checks(res: Any, cm: Any) -> list[Result]:
    """Spectrally flat reflectance: RGB equals spectral, and its albedo is the quadrature table's."""
    import openpbr_diffuse as od

    from ...spectral import ColourSet, colour_shift

    flat = np.linspace(0.05, 1.0, 8)[:, None] * np.ones((1, cm.wavelengths.size))
    fs = ColourSet(
        [f"flat {v:.2f}" for v in flat[:, 0]],
        flat,
        cm.XYZ_to_RGB(cm.spectra_to_XYZ(flat)),
        ["flat"] * len(flat),
        np.full(len(flat), np.nan),
    )
    fr = colour_shift(fs, res.roughness, res.mu, cm)
    E_ref = od.reference_albedo("eon", res.mu[None, None, :], res.roughness[None, :, None], flat[:, None, None, :1])
    return [
        CHECKS.check(
            "spectrally flat reflectance: RGB = spectral",
            float(fr.delta_e_rgb_vs_spectral.max()),
            1e-6,
            "<=",
            "grey spectra 0.05-1",
            unit="dE2000",
        ),
        CHECKS.check(
            "flat reflectance: albedo = quadrature table",
            float(abs(fr.albedo_spectral - E_ref).max()),
            1e-5,
            "<=",
            "data/albedo_eon.csv (reference_albedo)",
        ),
    ]


def _xyz_checks(res: Any, cm: Any, colour: Any, k0: int) -> list[Result]:
    """The pipeline's XYZ against colour-science's, and white-then-tint's chromaticity."""
    sds = colour.SDS_COLOURCHECKERS["BabelColor Average"]
    XYZ_ref = np.array(
        [colour.sd_to_XYZ(sds[n], cm.cmfs, cm.illuminant_sd, method="Integration") for n in res.colours.names]
    )

    def xy(X):
        return X[..., :2] / X.sum(-1, keepdims=True)

    return [
        CHECKS.check(
            "pipeline XYZ of the patches = colour.sd_to_XYZ",
            float(abs(res.XYZ["spectral"][:, k0] - XYZ_ref[:, None]).max()),
            1e-9,
            "<=",
            "colour.sd_to_XYZ (Integration), measured spectra",
            unit="XYZ (Y = 100)",
        ),
        CHECKS.check(
            "white then tint keeps the chromaticity of rho",
            float(abs(xy(res.XYZ["white_tint"]) - xy(XYZ_ref)[:, None, None]).max()),
            1e-10,
            "<=",
            "xy of colour.sd_to_XYZ of the patch",
            unit="xy",
        ),
    ]


def _saturation_check(res: Any, k0: int) -> Result:
    """The saturation C*/L* of the chromatic patches grows strictly with r."""
    Lab = res.Lab["spectral"]
    C = np.hypot(Lab[..., 1], Lab[..., 2])
    chrom = C[:, k0, 0] > 2.0
    pos = res.mu > 0
    sat = (C / Lab[..., 0])[chrom][:, :, pos]
    bad = int((np.diff(sat, axis=1) <= 0).sum()) if len(res.roughness) > 1 else 0
    return CHECKS.check(
        "saturation C*/L* grows strictly with r (chromatic patches, mu > 0)",
        bad,
        0,
        "<=",
        "monotonicity over the roughness grid",
        unit="non-increasing steps",
        detail=f"{int(chrom.sum())} chromatic patches (C*ab > 2 at r = 0)",
    )


def _furnace_check(res: Any, cm: Any) -> Result:
    """EON's white furnace at every wavelength."""
    import openpbr_diffuse as od

    E1 = od.directional_albedo("eon", res.mu[None, :], res.roughness[:, None], np.ones(cm.wavelengths.size))
    return CHECKS.check(
        "white furnace per wavelength (rho = 1 at 81 wavelengths)",
        float(abs(E1 - 1).max()),
        1e-6,
        "<=",
        "energy conservation of EON",
    )


def _checks(res: Any, cm: Any, colour: Any) -> list[Result]:
    """The property checks of the ColorChecker result ``res`` against independent references."""
    k0 = int(np.argmin(res.roughness))
    return [
        *_lambert_checks(res, k0),
        *_flat_checks(res, cm),
        *_xyz_checks(res, cm, colour, k0),
        _saturation_check(res, k0),
        _furnace_check(res, cm),
    ]


def _table_check(quick):
    """The shipped ColorChecker colour-shift table, recomputed."""
    from ...spectral import checker, colorimetry, colour_shift
    from ...spectral import reference as ref

    header, cols = ref.load_table("lin_rec709")
    cm = colorimetry(ref.TABLE_ILLUMINANT, "lin_rec709")
    res = colour_shift(checker(cm), ref.TABLE_ROUGHNESS, ref.TABLE_MU, cm)
    fresh = {}
    for line in ref.table_lines(res)[1:]:
        vals = line.split(",")
        fresh.setdefault("v", []).append([float(v) for v in vals[1:]])
    new = np.array(fresh["v"])
    old = np.stack([cols[c] for c in ref.COLUMNS[1:]], axis=-1)
    return CHECKS.check(
        "shipped ColorChecker colour-shift table reproduced",
        float(abs(new - old).max()),
        1e-8,
        "<=",
        "openpbr_diffuse/data/colorshift_checker_lin_rec709.csv",
        detail=header.get("library", ""),
    )


def _summary_rows(name_ws, res):
    """The r = 1 summary rows of one working space, one per mu."""
    rows = []
    for mu, s in res.summary(1.0).items():
        a, b = s["delta_e_rgb_vs_spectral"], s["delta_e_shift"]
        rows.append(
            [
                name_ws,
                round(mu, 4),
                round(a["max"][0], 4),
                a["max"][1],
                "-" if a["max_in_gamut"][1] is None else f"{a['max_in_gamut'][0]:.4f} ({a['max_in_gamut'][1]})",
                f"{a['median'][0]:.4f} ({a['median'][1]})",
                round(b["max"][0], 4),
                b["max"][1],
                f"{b['median'][0]:.4f} ({b['median'][1]})",
            ]
        )
    return rows


def _recovery_table(cm, measured, quick):
    """Round trip of each method on the patches' rho_rgb, and the dE between the spectral
    albedo from the recovered spectrum and from the measured one (r = 1, mu = 1)."""
    from ...spectral import RECOVERY_METHODS, colour_shift, from_rgb

    rows = []
    inside = ~measured.rho_rgb_clipped
    rgb = np.clip(measured.rho_rgb[inside], 0, 1)
    names = [n for n, i in zip(measured.colours.names, inside) if i]
    ref = colour_shift(measured.colours, [1.0], [1.0], cm)
    for method in RECOVERY_METHODS:
        idx = np.arange(len(rgb))
        if method == "Jakob 2019":
            if quick:
                continue
            idx = idx[::6]  # ~0.1-1 s per colour: a subset
        cs = from_rgb(rgb[idx], cm, method, names=[names[i] for i in idx])
        res = colour_shift(cs, [1.0], [1.0], cm)
        meas = ref.Lab["spectral"][inside][idx, 0, 0]
        d_alb = cm.delta_E(res.Lab["spectral"][:, 0, 0], meas)
        rows.append(
            [
                method,
                len(idx),
                round(float(cs.roundtrip_delta_e.max()), 4),
                round(float(np.median(cs.roundtrip_delta_e)), 4),
                round(float(d_alb.max()), 4),
                names[idx[int(np.argmax(d_alb))]],
            ]
        )
    return rows


def _figure(ctx, res):
    """dE2000 of the colour shift and of RGB vs spectral against roughness, a line per patch."""
    plt = pyplot()
    m = int(np.argmax(res.mu))
    srgb = np.clip(res.rho_rgb, 0, 1) ** (1 / 2.2)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for p, name in enumerate(res.colours.names):
        axes[0].plot(res.roughness, res.delta_e_shift[p, :, m], color=srgb[p], lw=1.5)
        axes[1].plot(
            res.roughness,
            res.delta_e_rgb_vs_spectral[p, :, m],
            color=srgb[p],
            lw=1.5,
            ls="--" if res.rho_rgb_clipped[p] else "-",
            label=name if res.rho_rgb_clipped[p] else None,
        )
    axes[0].set(
        title=f"colour shift: spectral vs white then tint (mu = {res.mu[m]:g})",
        xlabel="roughness r",
        ylabel="CIEDE2000",
    )
    axes[1].set(title="per RGB channel vs per wavelength", xlabel="roughness r", ylabel="CIEDE2000")
    if res.rho_rgb_clipped.any():
        axes[1].legend(title="clipped to Rec.709 (dashed)", fontsize=8)
    for ax in axes:
        ax.set_facecolor("0.35")
        ax.grid(alpha=0.3)
    return Figure(
        save(fig, ctx, f"{KEY}_delta_e.png", dpi=110),
        "ColorChecker (measured spectra, D65, lin_rec709): dE2000 of the colour shift and "
        "of RGB vs spectral evaluation against roughness, one line per patch in its colour",
    )


def _material_colours(ctx, files):
    """Per file of ``files``: (colour records, None) or (None, the file's read error), read by
    the library's runner (``ctx.extra["library"]``: workers, the library cache)."""
    from ...library import LibraryOptions, Task

    opts = ctx.extra.get("library") or LibraryOptions()
    out = [(None, "not read")] * len(files)
    with opts.runner() as runner:
        for o in runner.run([(str(f), Task(kind="colours")) for f in files]):
            out[o.index] = (None, o.payload["error"]) if o.payload.get("error") else (o.payload["records"], None)
    return out


def _material_sets(ctx: Context, cm: Any, files: list) -> tuple[list, list[str]]:
    """The diffuse colours of ``files`` as colour sets, and the warnings of reading them."""
    from ...spectral import from_materials
    from ...spectral.colorsets import from_colour_records

    warnings: list[str] = []
    sets: list = []

    def add(f, read):
        try:
            cs, w = read()
        except (ValueError, OSError) as exc:
            warnings.append(f"{f}: {exc}")
            return
        warnings.extend(w)
        if len(cs):
            sets.append(cs)

    def add_run(run):
        # the colours of consecutive readable files at once; file by file when one of them
        # cannot be used (its error is then that file's warning, as for a file alone)
        try:
            cs, w = from_colour_records([r for _, recs in run for r in recs], cm)
        except (ValueError, OSError):
            for f, recs in run:
                add(f, lambda recs=recs: from_colour_records(recs, cm))
            return
        warnings.extend(w)
        if len(cs):
            sets.append(cs)

    run: list = []
    for f, (records, error) in zip(files, _material_colours(ctx, files)):
        if error is None:
            run.append((f, records))
            continue
        add_run(run)
        run = []
        # a file the work could not read is read here again, for its own error text
        add(f, lambda f=f: from_materials([f], cm))
    add_run(run)
    return sets, warnings


def _own_roughness_de(cs: Any, cm: Any) -> tuple[list, np.ndarray]:
    """Each colour's material roughness and (dE rgb vs spectral, dE shift) of EON at it (mu = 1)."""
    from ...spectral import ColourSet, colour_shift

    # one evaluation per distinct roughness (each colour's result depends on its own spectrum only)
    own_r = [cs.extra[p].get("material_diffuse_roughness") for p in range(len(cs))]
    own_de = np.empty((len(cs), 2))
    groups: dict[str, tuple[float, list[int]]] = {}
    for p, r in enumerate(own_r):
        groups.setdefault(repr(r or 0.0), (r or 0.0, []))[1].append(p)
    for r_own, idx in groups.values():
        own = colour_shift(
            ColourSet(
                [cs.names[p] for p in idx],
                cs.spectra[idx],
                cs.rho_rgb[idx],
                [cs.source[p] for p in idx],
                cs.roundtrip_delta_e[idx],
            ),
            [r_own],
            [1.0],
            cm,
        )
        own_de[idx, 0] = own.delta_e_rgb_vs_spectral[:, 0, 0]
        own_de[idx, 1] = own.delta_e_shift[:, 0, 0]
    return own_r, own_de


#: The columns of the materials' table.
_MATERIAL_COLUMNS = [
    "material",
    "file",
    "diffuse model",
    "own r",
    "dE rgb vs spectral (own r)",
    "dE shift (own r)",
    "dE rgb vs spectral (r = 1)",
    "dE shift (r = 1)",
    "upsampling round trip dE",
]


def _materials_table(ctx, cm):
    """The colour shift of the materials of ``ctx.paths`` (default: the bundled library) at
    each material's own diffuse roughness and at r = 1, mu = 1; (Table or None, warnings)."""
    from ...spectral import ColourSet, colour_shift

    try:
        from ...readers import BUNDLED_MATERIALS, find_material_files
    except ImportError as exc:
        return None, [f"materials not evaluated: openpbr_diffuse.readers unavailable ({exc})"]
    sets, warnings = _material_sets(ctx, cm, find_material_files(ctx.paths or [BUNDLED_MATERIALS]))
    if not sets:
        return None, warnings + ["no material with a diffuse colour"]
    cs = ColourSet.concat(sets)
    res = colour_shift(cs, [1.0], [1.0], cm)
    # EON at each material's own roughness
    own_r, own_de = _own_roughness_de(cs, cm)
    rows = []
    for p, name in enumerate(cs.names):
        r_own = own_r[p]
        rows.append(
            [
                name,
                Path(cs.extra[p].get("material_file", "")).name,
                cs.extra[p].get("material_diffuse_model") or "",
                "-" if r_own is None else round(r_own, 4),
                round(float(own_de[p, 0]), 4),
                round(float(own_de[p, 1]), 4),
                round(float(res.delta_e_rgb_vs_spectral[p, 0, 0]), 4),
                round(float(res.delta_e_shift[p, 0, 0]), 4),
                round(float(cs.roundtrip_delta_e[p]), 4),
            ]
        )
    table = Table(
        "Materials (diffuse colour read by openpbr_diffuse.readers, ACEScg -> lin_rec709, upsampled by "
        "Mallett 2019), mu = 1: EON at the material's own diffuse roughness (as r, whatever its diffuse "
        "model) and at r = 1",
        _MATERIAL_COLUMNS,
        rows,
    )
    return table, warnings


def _summary_table(res: Any, res_aces: Any) -> Table:
    """The ColorChecker at r = 1 in both working spaces: largest and median dE2000."""
    return Table(
        "ColorChecker at r = 1 (D65): largest and median dE2000 with patch names",
        [
            "working space",
            "mu",
            "max dE rgb vs spectral",
            "patch",
            "max in gamut (patch)",
            "median (patches)",
            "max dE shift",
            "patch",
            "median (patches)",
        ],
        _summary_rows("lin_rec709", res) + _summary_rows("acescg", res_aces),
    )


def _per_patch_table(res: Any) -> Table:
    """Each patch at the largest roughness and mu of the grid."""
    k1, m1 = int(np.argmax(res.roughness)), int(np.argmax(res.mu))
    return Table(
        f"Each patch at r = {res.roughness[k1]:g}, mu = {res.mu[m1]:g} (D65, lin_rec709; * = outside Rec.709, clipped)",
        [
            "patch",
            "dE rgb vs spectral",
            "rel. luminance diff rgb vs spectral",
            "chroma diff rgb vs spectral",
            "dE shift",
            "rel. luminance diff shift",
            "chroma diff shift",
        ],
        [
            [
                n + ("*" if res.rho_rgb_clipped[p] else ""),
                round(float(res.delta_e_rgb_vs_spectral[p, k1, m1]), 4),
                round(float(res.rel_luminance_diff_rgb_vs_spectral[p, k1, m1]), 5),
                round(float(res.chroma_diff_rgb_vs_spectral[p, k1, m1]), 4),
                round(float(res.delta_e_shift[p, k1, m1]), 4),
                round(float(res.rel_luminance_diff_shift[p, k1, m1]), 5),
                round(float(res.chroma_diff_shift[p, k1, m1]), 4),
            ]
            for p, n in enumerate(res.colours.names)
        ],
    )


def _recovery(cm: Any, quick: bool) -> Table:
    """The table of the RGB -> spectrum upsampling methods on the ColorChecker."""
    from ...spectral import checker, colour_shift

    return Table(
        "RGB -> spectrum upsampling (colour.recovery) on the in-gamut patches' rho_rgb: round trip, "
        "and dE2000 of the r = 1, mu = 1 spectral albedo from the recovered vs the measured spectrum",
        [
            "method",
            "colours",
            "max round trip dE",
            "median round trip dE",
            "max dE albedo (recovered vs measured)",
            "patch",
        ],
        _recovery_table(cm, colour_shift(checker(cm), [1.0], [1.0], cm), quick),
    )


def _swatches(ctx: Context, cm: Any) -> Figure:
    """The swatch image at r = 0 and r = 1, mu = 1."""
    from ...spectral import checker, colour_shift
    from ...spectral.swatches import write_swatches

    sw = colour_shift(checker(cm), [0.0, 1.0], [1.0], cm)
    path = write_swatches(sw, ctx.image_dir / f"{KEY}_swatches.png")
    return Figure(
        path.name,
        "Swatches at r = 0 and r = 1, mu = 1: L Lambert (rho), R RGB-evaluated, "
        "S spectral, W white then tint (sRGB display encoding)",
    )


#: The section's notes: the pipeline and how to read its numbers.
NOTES = (
    "Pipeline: measured reflectance (colour-science 'BabelColor Average', 380-730 nm / 10 nm aligned to "
    "380-780 nm / 5 nm) -> EON directional albedo per wavelength (Eq. 20) -> XYZ under D65, CIE 1931 2 degree "
    "observer (perfect reflector Y = 100) -> working-space RGB with Bradford adaptation; Lab with the "
    "illuminant's white; CIEDE2000.",
    "White then tint evaluates EON at rho = 1 (albedo 1: the white furnace) and multiplies by rho, so it "
    "equals the Lambertian colour; delta_e_shift is therefore the whole EON change of colour, darkening "
    "included (rel_luminance_diff_shift), chroma_diff_shift its chroma part.",
    "At mu = 0 E_F = 1 for every r, so there is no shift at exactly grazing view; it grows towards normal view.",
    "'cyan' lies outside linear Rec.709 (R < 0): its RGB evaluation uses rho clipped to [0, 1], which accounts "
    "for most of its RGB-vs-spectral difference; in ACEScg all 24 patches are inside.",
    "Per RGB channel the shift always raises saturation; per wavelength it need not: a spectrum whose most "
    "reflective wavelengths have another hue than its colour (a blue reflecting most in the deep red, say) can "
    "lose saturation as r grows while the per-channel evaluation says it gains (tests: "
    "test_metameric_spectrum_can_lose_saturation). All 19 chromatic ColorChecker patches gain.",
)


def build(ctx: Context) -> SectionResult:
    """The ColorChecker's checks and tables, the recovery methods, the materials and the figures."""
    from ...spectral import checker, colorimetry, colour_shift
    from ...spectral.colorimetry import _colour

    colour = _colour()
    ctx.image_dir.mkdir(parents=True, exist_ok=True)
    r, mu = _grid(ctx.quick)
    ctx.progress("colorshift: ColorChecker, lin_rec709")
    cm = colorimetry("D65", "lin_rec709")
    res = colour_shift(checker(cm), r, mu, cm)
    checks = _checks(res, cm, colour)
    ctx.progress("colorshift: reference table")
    checks.append(_table_check(ctx.quick))
    ctx.progress("colorshift: ACEScg")
    cm_aces = colorimetry("D65", "acescg")
    res_aces = colour_shift(checker(cm_aces), [0.0, 1.0], [0.2, 0.5, 1.0], cm_aces)
    summary, per_patch = _summary_table(res, res_aces), _per_patch_table(res)
    ctx.progress("colorshift: recovery methods")
    recovery = _recovery(cm, ctx.quick)
    ctx.progress("colorshift: materials")
    mat_table, warnings = _materials_table(ctx, cm)
    figures = [_figure(ctx, res)]
    ctx.progress("colorshift: swatches")
    figures.append(_swatches(ctx, cm))
    tables = [summary, per_patch, recovery] + ([mat_table] if mat_table else [])
    return SectionResult(
        KEY, TITLE, checks=checks, tables=tables, figures=figures, notes=list(NOTES), warnings=warnings
    )

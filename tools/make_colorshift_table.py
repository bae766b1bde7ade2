#!/usr/bin/env python
"""Regenerate the ColorChecker colour-shift reference tables shipped in ``openpbr_diffuse/data/``.

    python tools/make_colorshift_table.py             # both working spaces (~10 s)
    python tools/make_colorshift_table.py --out DIR   # somewhere else
    python tools/make_colorshift_table.py --check     # recompute and compare with the shipped files

The tables hold ``openpbr_diffuse.spectral.colour_shift`` of the 24 measured ColorChecker
spectra ('BabelColor Average', colour-science) on the grid of ``spectral.reference``.  As a
check independent of EON's closed form, every albedo is recomputed from the quadrature
reference tables (``reference_albedo``, data/albedo_eon.csv) and the largest difference of
each field is written into the header.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

from openpbr_diffuse import reference_albedo
from openpbr_diffuse._version import __version__
from openpbr_diffuse.spectral import checker, colorimetry, colour_shift
from openpbr_diffuse.spectral import reference as ref


def quadrature_check(res, cm):
    """Largest |difference| of the RGB albedos and the dE fields when EON's albedo per wavelength
    / channel comes from the quadrature tables instead of the closed form (Eq. 20)."""
    S, r, mu = res.colours.spectra[:, None, None, :], res.roughness[None, :, None], res.mu[None, None, :]
    spec = cm.XYZ_to_RGB(cm.spectra_to_XYZ(reference_albedo("eon", mu, r, S)))
    tint = cm.XYZ_to_RGB(cm.spectra_to_XYZ(reference_albedo("eon", mu, r, S, color_mode="white_tint")))
    rgb = reference_albedo("eon", mu, r, np.clip(res.rho_rgb, 0, 1)[:, None, None, :])
    lab = {k: cm.XYZ_to_Lab(cm.RGB_to_XYZ(v)) for k, v in (("s", spec), ("t", tint), ("r", rgb))}
    d_rgb = max(
        abs(a - b).max() for a, b in ((spec, res.albedo_spectral), (tint, res.albedo_white_tint), (rgb, res.albedo_rgb))
    )
    d_de = max(
        abs(cm.delta_E(lab["r"], lab["s"]) - res.delta_e_rgb_vs_spectral).max(),
        abs(cm.delta_E(lab["s"], lab["t"]) - res.delta_e_shift).max(),
    )
    return float(d_rgb), float(d_de)


def build(working_space):
    cm = colorimetry(ref.TABLE_ILLUMINANT, working_space)
    res = colour_shift(checker(cm), ref.TABLE_ROUGHNESS, ref.TABLE_MU, cm)
    d_rgb, d_de = quadrature_check(res, cm)
    s = cm.describe()
    shape = s["spectral_shape"]
    header = [
        f"title: openpbr-diffuse ColorChecker colour-shift reference table, working space {working_space}",
        "quantity: EON directional albedo of the 24 measured ColorChecker spectra evaluated per wavelength "
        "(albedo_spectral), per RGB channel (albedo_rgb) and white then tint (albedo_white_tint), as working-space "
        "linear RGB; CIEDE2000 differences with relative luminance (Y ratio - 1) and chroma (C*ab) differences",
        "colours: colour.SDS_COLOURCHECKERS['BabelColor Average'] (measured, 380-730 nm / 10 nm; aligned by "
        "colour-science: Sprague interpolation, constant extrapolation)",
        f"colorimetry: illuminant {s['illuminant']}, {s['observer']}, spectral shape {shape['start_nm']:g}-"
        f"{shape['end_nm']:g} nm / {shape['interval_nm']:g} nm ({shape['samples']} samples), {s['xyz_integration']}; "
        f"RGB: colour.XYZ_to_RGB to {s['working_space_colour_science']} with {s['chromatic_adaptation']}; "
        f"Lab reference white = illuminant white {[round(v, 6) for v in s['lab_reference_white_XYZ']]}",
        "method: openpbr_diffuse.spectral.colour_shift: directional_albedo('eon') closed form (Eq. 20) with the 81 "
        "spectral samples (or the 3 RGB channels) as channels; rho_rgb outside [0, 1] is clipped for albedo_rgb "
        "(rho_rgb_clipped = 1)",
        f"rows: patch x roughness r = k/8, k = 0..8 x theta_deg {list(ref.TABLE_THETA_DEG)} (mu = cos theta)",
        f"error: values rounded to {ref.DECIMALS} decimals; with the albedo per wavelength/channel taken from the "
        f"quadrature tables (reference_albedo, data/albedo_eon.csv) instead of Eq. 20: max |RGB difference| "
        f"{d_rgb:.1e}, max |dE difference| {d_de:.1e}",
        f"library: openpbr-diffuse {__version__}, colour-science {s['colour_science']}",
        "regenerate: python tools/make_colorshift_table.py",
    ]
    return ["# " + h for h in header] + ref.table_lines(res)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1].strip())
    ap.add_argument("--out", type=Path, default=ref.DATA, help="output folder (default: the package data)")
    ap.add_argument("--check", action="store_true", help="compare with the shipped files instead of writing")
    args = ap.parse_args(argv)
    status = 0
    for ws in ref.TABLE_WORKING_SPACES:
        lines = build(ws)
        if args.check:
            _, new = ref.load_table(ws, path=_tmp(lines))
            _, old = ref.load_table(ws)
            worst = max(float(abs(new[c] - old[c]).max()) for c in new if c != "patch")
            ok = new["patch"] == old["patch"] and worst <= 2 * 10.0**-ref.DECIMALS
            print(f"{ws}: max |difference| {worst:.2e} {'ok' if ok else 'DIFFERS'}")
            status |= not ok
            continue
        path = args.out / ref.table_path(ws).name
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        print(f"wrote {path} ({sum(not ln.startswith('#') for ln in lines) - 1} rows); {lines[6][2:]}", file=sys.stderr)
    return status


def _tmp(lines):
    import tempfile

    f = tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False, encoding="utf-8")
    f.write("\n".join(lines) + "\n")
    f.close()
    return f.name


if __name__ == "__main__":
    sys.exit(main())

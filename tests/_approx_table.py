"""The shipped grading table (openpbr_diffuse/data/approximation_errors.csv) as dicts by id."""

import csv
import importlib.resources


def shipped_rows():
    text = (importlib.resources.files("openpbr_diffuse") / "data" / "approximation_errors.csv").read_text()
    lines = [ln for ln in text.splitlines() if not ln.startswith("#")]
    return {r["id"]: r for r in csv.DictReader(lines)}


def header_lines():
    text = (importlib.resources.files("openpbr_diffuse") / "data" / "approximation_errors.csv").read_text()
    return [ln for ln in text.splitlines() if ln.startswith("#")]


def at(row):
    """The 'at' column ("mu_o=0.1, sigma=1.571") as a dict of floats."""
    out = {}
    for part in row["at"].split(","):
        k, v = part.strip().split("=")
        out[k] = float(v)
    return out

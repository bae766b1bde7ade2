"""The report page's table of every material: a Jinja template, its style and its script.

Rendered inside the materials section from ``report.json``'s ``"materials"`` records, worst
first (failing, flagged, unsupported, passing; then by the albedo against its allowance).
Long paths wrap (the table never scrolls sideways) and are shown relative to the path they
were found under.  A small inline script, shipped here and allowed by its SHA-256 in the
page's Content-Security-Policy (no other script can run), filters the rows by words typed
into the filter box and by verdict, and sorts by a column when its header is clicked.  The
page loads nothing from the network; every value from a file is escaped by Jinja.
"""

from __future__ import annotations

import base64
import functools
import hashlib
import re
from typing import Any

#: The filter and sort of the materials table (plain ES5, no library).
SCRIPT = """
(function () {
  "use strict";
  var table = document.getElementById("materials-table");
  if (!table) { return; }
  var body = table.tBodies[0];
  var items = Array.prototype.map.call(body.rows, function (r) {
    return {row: r, text: r.textContent.toLowerCase()};
  });
  var input = document.getElementById("materials-filter");
  var verdict = document.getElementById("materials-verdict");
  var shown = document.getElementById("materials-shown");
  var more = document.getElementById("materials-more");
  // at most `limit` matching rows are laid out (a 10^4-row table costs seconds of layout);
  // "show all" lifts the limit
  var limit = parseInt(table.getAttribute("data-page"), 10) || Infinity;
  function apply() {
    var terms = input.value.toLowerCase().split(/\\s+/).filter(Boolean);
    var want = verdict.value, n = 0;
    items.forEach(function (it) {
      var ok = !want || it.row.getAttribute("data-verdict") === want;
      for (var j = 0; ok && j < terms.length; j++) { ok = it.text.indexOf(terms[j]) >= 0; }
      if (ok) { n++; }
      var hide = !ok || n > limit;
      if (it.row.hidden !== hide) { it.row.hidden = hide; }
    });
    shown.textContent = n + " of " + items.length + " materials shown" +
      (n > limit ? " (the first " + limit + " listed)" : "");
    more.hidden = !(n > limit);
  }
  input.addEventListener("input", apply);
  verdict.addEventListener("change", apply);
  more.addEventListener("click", function () { limit = Infinity; apply(); });
  var heads = table.tHead.rows[0].cells;
  Array.prototype.forEach.call(heads, function (th, c) {
    th.addEventListener("click", function () {
      var asc = th.getAttribute("aria-sort") !== "ascending";
      Array.prototype.forEach.call(heads, function (h) { h.removeAttribute("aria-sort"); });
      th.setAttribute("aria-sort", asc ? "ascending" : "descending");
      var num = th.getAttribute("data-type") === "num";
      var keyed = items.map(function (it, i) {
        var cell = it.row.cells[c], v = cell.getAttribute("data-v");
        if (v === null) { v = cell.textContent; }
        if (num) { v = v === "" ? NaN : parseFloat(v); } else { v = v.toLowerCase(); }
        return {it: it, v: v, i: i};
      });
      keyed.sort(function (a, b) {
        var an = num && isNaN(a.v), bn = num && isNaN(b.v);
        if (an || bn) { return an === bn ? a.i - b.i : (an ? 1 : -1); }
        var d = a.v < b.v ? -1 : (a.v > b.v ? 1 : 0);
        return d === 0 ? a.i - b.i : (asc ? d : -d);
      });
      var frag = document.createDocumentFragment();
      items = keyed.map(function (k) { frag.appendChild(k.it.row); return k.it; });
      body.appendChild(frag);
      apply();  // the first rows of the new order are the ones listed
    });
  });
  apply();
})();
"""


def script_hash() -> str:
    """The CSP source that allows :data:`SCRIPT` and nothing else (``'sha256-...'``).

    >>> script_hash().startswith("'sha256-") and script_hash().endswith("='")
    True
    """
    return "'sha256-" + base64.b64encode(hashlib.sha256(SCRIPT.encode("utf-8")).digest()).decode() + "'"


STYLE = """
#section-materials table.checks td:nth-last-child(-n+2) { overflow-wrap: anywhere; }
#materials-worst { width: 100%; table-layout: fixed; font-size: .8em; }
#materials-worst td { overflow-wrap: anywhere; }
#materials-library .controls { margin: .6em 0; display: flex; gap: .8em; flex-wrap: wrap; align-items: center; }
#materials-filter { min-width: 22em; padding: .2em .4em; }
#materials-table { width: 100%; table-layout: fixed; font-size: .76em; }
#materials-table th { cursor: pointer; user-select: none; }
#materials-table th[aria-sort=ascending]::after { content: " \\25B2"; }
#materials-table th[aria-sort=descending]::after { content: " \\25BC"; }
#materials-table td, #materials-table th { overflow-wrap: anywhere; hyphens: manual; }
.material-cards { display: grid; grid-template-columns: repeat(auto-fill, minmax(360px, 1fr)); gap: .8em; }
.material-card { border: 1px solid #ddd; padding: .4em; overflow-wrap: anywhere; }
.material-card figure { margin: .3em 0; }
.material-card table { font-size: .75em; width: 100%; table-layout: fixed; }
#materials-table .sw { display: inline-block; width: .9em; height: .9em; border: 1px solid #888; vertical-align: middle; margin-right: .3em; }
"""

#: Rows of the materials table laid out at first (and per filter): the rest are in the page,
#: hidden until a filter matches them or "show all" (laying out 10^4 rows costs seconds).
PAGE = 500

#: Column headers and their widths (%), in the table's order.
COLUMNS = (
    ("verdict", 6, "text"),
    ("file", 14, "text"),
    ("material", 12, "text"),
    ("shader kind", 8, "text"),
    ("node (diffuse)", 8, "text"),
    ("base colour", 9, "num"),
    ("diffuse rough\u00adness", 6, "num"),
    ("albedo at 30\u00b0", 8, "num"),
    ("largest albedo / allowance", 7, "num"),
    ("diffuse weight, probability at 30\u00b0", 8, "num"),
    ("reasons / detail", 10, "text"),
    ("warn\u00adings", 4, "num"),
)

TEMPLATE = """{% if lib.worst %}<table id="materials-worst" class="data"><caption>{{ lib.worst.caption }}</caption>
<colgroup>{% for w in (7, 20, 15, 10, 10, 13, 25) %}<col style="width: {{ w }}%">{% endfor %}</colgroup>
<tr>{% for c in lib.worst.columns %}<th>{{ c }}</th>{% endfor %}</tr>
{% for row in lib.worst.rows %}<tr>{% for v in row %}<td{% if loop.first %} class="{{ verdict_class(v) }}"{% endif %}>{{ v }}</td>{% endfor %}</tr>
{% endfor %}</table>{% endif %}
{% if lib.cards %}<h3>Previews and albedo plots ({{ lib.cards | length }} materials)</h3>
<div class="material-cards">{% for c in lib.cards %}<div class="material-card">
{% for f in c.figures %}<figure><img src="{{ f.file }}" alt="{{ f.caption }}" loading="eager"><figcaption>{{ f.caption }}</figcaption></figure>{% endfor %}
{% if c.table %}<details><summary>resolved parameters</summary><table class="data"><caption>{{ c.table.caption }}</caption>
<tr>{% for col in c.table.columns %}<th>{{ col }}</th>{% endfor %}</tr>
{% for row in c.table.rows %}<tr>{% for v in row %}<td>{{ v }}</td>{% endfor %}</tr>{% endfor %}</table></details>{% endif %}
</div>{% endfor %}</div>{% endif %}
<div id="materials-library">
<h3>Every material ({{ rows | length }})</h3>
<div class="controls"><input id="materials-filter" type="search" placeholder="filter: words found in any column" aria-label="filter the materials">
<select id="materials-verdict" aria-label="verdict"><option value="">every verdict</option>
{% for v in verdicts %}<option value="{{ v }}">{{ v }}</option>{% endfor %}</select>
<span id="materials-shown">{{ rows | length }} materials</span>
<button id="materials-more" type="button"{% if rows | length <= page %} hidden{% endif %}>show all</button></div>
<table id="materials-table" class="data" data-page="{{ page }}"><caption>Materials, worst first (click a header to sort{% if rows | length > page %}; the first {{ page }} listed until a filter or "show all"{% endif %})</caption>
<colgroup>{% for name, width, kind in columns %}<col style="width: {{ width }}%">{% endfor %}</colgroup>
<thead><tr>{% for name, width, kind in columns %}<th data-type="{{ kind }}">{{ name }}</th>{% endfor %}</tr></thead>
<tbody>
{% for r in rows %}<tr data-verdict="{{ r.verdict }}"{% if loop.index > page %} hidden{% endif %}><td class="{{ verdict_class(r.verdict) }}">{{ r.verdict }}</td>
<td>{{ r.relpath }}</td><td>{{ r.material or '-' }}</td><td>{{ r.kind }}</td>
<td>{{ r.node or '-' }}{% if r.diffuse_model %} ({{ r.diffuse_model }}){% endif %}</td>
<td data-v="{{ mean(r.base_color) }}">{% if r.base_color %}<span class="sw" style="background: {{ swatch(r.base_color) }}"></span>{{ r.base_color | vec }}{% else %}-{% endif %}</td>
<td class="num" data-v="{{ num_value(r.roughness) }}">{{ r.roughness | num }}</td>
<td data-v="{{ mean(r.albedo) }}">{{ r.albedo | vec }}</td>
<td class="num" data-v="{{ num_value(excess(r)) }}">{{ r.albedo_max | num }} / {{ r.albedo_limit | num }}</td>
<td data-v="{{ mean(r.diffuse_weight) }}">{{ r.diffuse_weight | vec }}, {{ r.diffuse_probability | num }}</td>
<td>{{ r.reasons | join(', ') }}{% if r.detail %}: {{ r.detail }}{% endif %}</td>
<td class="num" data-v="{{ r.n_warnings or 0 }}" title="{{ (r.warnings or []) | join(' | ') }}">{{ r.n_warnings or 0 }}</td></tr>
{% endfor %}</tbody></table>
</div>
"""


@functools.lru_cache(maxsize=1)
def _to_srgb_linear() -> Any:
    """The matrix from ACEScg to linear sRGB (Rec.709 primaries)."""
    import numpy as np

    from ..readers.colorspace import matrix

    return np.linalg.inv(matrix("lin_rec709"))


def swatch(acescg: Any) -> str:
    """A CSS colour of an ACEScg triple (to sRGB, clipped), for the table's swatches.

    >>> swatch([1.0, 1.0, 1.0]), swatch([0.0, 0.0, 0.0]), swatch(None)
    ('rgb(255, 255, 255)', 'rgb(0, 0, 0)', 'transparent')
    """
    import numpy as np

    if not acescg or any(v is None for v in acescg):
        return "transparent"
    lin = np.clip(_to_srgb_linear() @ np.asarray(acescg, dtype=np.float64), 0.0, 1.0)
    enc = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    r, g, b = (int(round(float(x) * 255)) for x in enc)
    return f"rgb({r}, {g}, {b})"


def mean(v: Any) -> str:
    """A sort value: the mean of a triple, "" when missing.

    >>> mean([0.1, 0.2, 0.3]), mean(None)
    ('0.2', '')
    """
    if not v or any(x is None for x in v):
        return ""
    return f"{sum(v) / len(v):.6g}"


def num_value(v: Any) -> str:
    """A sort value of a number ("" when missing or not finite).

    >>> num_value(0.5), num_value(None), num_value(float("-inf"))
    ('0.5', '', '')
    """
    import math

    if v is None or not math.isfinite(float(v)):
        return ""
    return f"{float(v):.6g}"


#: Caption ending of a drawn material's parameter table, and start of the worst-materials
#: table's caption (the section's, see sections/materials.py).
PARAMETERS = ": resolved parameters"
WORST = "The worst "
_DRAWN = re.compile(r"materials_(\d+)_.*_(render|albedo)\.png$")


def parts(section: dict[str, Any]) -> dict[str, Any]:
    """The materials section split for the page: its summary ``tables``, the ``worst``
    materials' table (laid out to wrap long paths), its other ``figures`` (the
    distributions) and ``cards`` (per drawn material: its render and albedo
    figures and its parameter table, matched by the number the section gives each: the
    images ``materials_<nn>_..._render.png`` / ``_albedo.png``, the table's caption
    ``"<nn> <material> (<shader>): resolved parameters"``).

    >>> s = {"tables": [{"caption": "Materials by verdict"}, {"caption": "00 /M (x): resolved parameters"}],
    ...      "figures": [{"file": "images/materials_distributions.png"}, {"file": "images/materials_00_M_render.png"},
    ...                  {"file": "images/materials_00_M_albedo.png"}]}
    >>> p = parts(s)
    >>> [t["caption"] for t in p["tables"]], len(p["figures"]), len(p["cards"][0]["figures"]), p["cards"][0]["table"] is not None
    (['Materials by verdict'], 1, 2, True)
    """
    tables, params, worst = [], {}, None
    for t in section.get("tables", []):
        number = t["caption"].split(" ", 1)[0]
        if t["caption"].endswith(PARAMETERS) and number.isdigit():
            params[number] = t
        elif t["caption"].startswith(WORST) and worst is None:
            worst = t
        else:
            tables.append(t)
    figures: list = []
    cards: dict[str, dict[str, Any]] = {}
    for f in section.get("figures", []):
        m = _DRAWN.search(f["file"])
        if m is None:
            figures.append(f)
            continue
        cards.setdefault(m.group(1), {"figures": [], "table": params.get(m.group(1))})["figures"].append(f)
    return {"tables": tables, "worst": worst, "figures": figures, "cards": list(cards.values())}


def context(doc: dict[str, Any]) -> dict[str, Any]:
    """What the template needs, from a report document: the records worst first and helpers.

    >>> c = context({"materials": [{"verdict": "pass", "file": "a", "index": 0}, {"verdict": "fail", "file": "b", "index": 0}]})
    >>> [r["verdict"] for r in c["rows"]]
    ['fail', 'pass']
    """
    from ..library.summary import excess, worst_key
    from ..library.worker import VERDICTS

    return {
        "parts": parts,
        "rows": sorted(doc.get("materials") or [], key=worst_key),
        "page": PAGE,
        "verdicts": VERDICTS,
        "columns": COLUMNS,
        "swatch": swatch,
        "mean": mean,
        "num_value": num_value,
        "excess": excess,
        "verdict_class": lambda v: {"pass": "pass", "fail": "fail"}.get(v, "na"),
    }


__all__ = ["COLUMNS", "PARAMETERS", "WORST", "SCRIPT", "STYLE", "TEMPLATE", "context", "parts", "script_hash", "swatch"]

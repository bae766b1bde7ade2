"""The report page: ``report.json``'s document rendered to one offline HTML file.

Rendered with Jinja2 with autoescaping on for every value: material names, file paths,
documentation strings and any other text that can come from a user's file reach the page
only escaped.  The page loads nothing from the network (inline CSS; the images are files in
``images/`` beside it).  Its one script, the filter and sort of the materials table
(:mod:`.library_html`, present when the report lists materials), is allowed by its SHA-256
in the page's Content-Security-Policy: no other script can run.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="default-src 'none'; img-src 'self' data: file:; style-src 'unsafe-inline'; script-src {{ script_hash }}">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>openpbr-diffuse conformance report</title>
<style>
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1200px; color: #222; line-height: 1.4; padding: 0 1em; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: .2em; margin-top: 2em; }
table { border-collapse: collapse; margin: .6em 0 1.2em; font-size: .85em; }
th, td { border: 1px solid #ccc; padding: .2em .5em; text-align: left; vertical-align: top; overflow-wrap: anywhere; }
table { max-width: 100%; } code, .meta { overflow-wrap: anywhere; } pre { white-space: pre-wrap; overflow-wrap: anywhere; }
.warntier { color: #8a6100; font-weight: 600; }
#start { background: #f4f7fb; border: 1px solid #cfd8e3; padding: .5em .8em; }
th { background: #f3f3f3; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
.pass { color: #17692b; font-weight: 600; } .fail, .error { color: #b00020; font-weight: 600; }
.na { color: #777; font-weight: 600; }
.badge { display: inline-block; padding: 0 .5em; border-radius: .3em; font-size: .8em; vertical-align: middle; border: 1px solid currentColor; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .85em; color: #444; }
.warn { background: #fff6d6; border-left: 4px solid #e0a800; padding: .3em .6em; margin: .3em 0; }
.meta { color: #555; font-size: .9em; }
caption { text-align: left; font-weight: 600; padding: .2em 0; }
{{ library_style | safe }}</style>
</head>
<body>
<h1>openpbr-diffuse conformance report</h1>
<p class="meta">openpbr-diffuse {{ doc.version }} &middot; generated {{ doc.generated }} &middot;
{{ "quick run" if doc.quick else "full run" }} &middot; {{ doc.elapsed_s | num }} s &middot;
materials: {% for p in doc.paths %}<code>{{ p }}</code>{% if not loop.last %}, {% endif %}{% else %}none{% endfor %}</p>
{% set skipped = quick_skipped(doc) %}{% if skipped %}<p id="quick-skipped" class="warn">Quick run: not run here, and run by the full report
(<code>openpbr-diffuse report</code>): {% for key, title, n in skipped %}<a href="#section-{{ key }}">{{ title }}</a> ({{ n }} check{{ 's' if n != 1 }}){% if not loop.last %}, {% endif %}{% endfor %}.</p>{% endif %}
{% set ut = doc.implementation %}
{% if ut %}<section id="under-test" data-status="{{ ut.status }}">
<p id="headline" class="{{ ut.status | tier_class }}">{{ ut.headline }}</p>
<p id="verdict-line" class="{{ ut.status | tier_class }}">Verdict: <strong>{{ ut.verdict_line }}</strong></p>
<table id="verdicts"><caption>Implementation under test: {{ ut.name }}</caption>
<tr><th>quantity</th><th>verdict</th><th>diagnosis</th><th>largest abs error</th><th>worst row (largest error / tolerance)</th><th>rows failing</th></tr>
{% for v in ut.verdicts %}<tr data-id="{{ v.id }}"><td>{{ v.label }}</td>
<td class="{{ v.status | tier_class }}">{{ v.status }}</td>
<td>{{ v.sentence }}</td><td class="num">{{ v.max_abs_error | num }}</td><td>{{ v.where }}</td>
<td class="num">{{ v.n_failed }} / {{ v.n }}</td></tr>
{% endfor %}</table>
{% for v in ut.verdicts if v.checks %}<table class="data checks"><caption>{{ v.label }}: checks</caption>
<tr><th>id</th><th>status</th><th>measured</th><th>threshold</th><th>detail</th></tr>
{% for c in v.checks %}<tr data-id="{{ c.id }}"><td><code>{{ c.id }}</code></td>
<td class="{{ {'pass': 'pass', 'fail': 'fail', 'warn': 'warntier'}.get(c.status, 'na') }}">{{ c.status }}</td>
<td class="num">{{ c.measured | num }}</td><td class="num">{{ c.threshold | num }}</td><td>{{ c.detail }}</td></tr>
{% endfor %}</table>{% endfor %}
{% for n in ut.notes %}<p class="meta">{{ n }}</p>{% endfor %}
{% for f in ut.figures %}<figure><img src="{{ f.file }}" alt="{{ f.caption }}" loading="eager">
<figcaption>{{ f.caption }}</figcaption></figure>{% endfor %}
{% for v in ut.verdicts if v.regions %}<table class="data regions"><caption>{{ v.label }}: by region</caption>
<tr><th>region</th><th>errors</th></tr>{% for r in v.regions %}<tr><td>{{ r[0] }}</td><td>{{ r[1] }}</td></tr>{% endfor %}</table>{% endfor %}
{% for v in ut.verdicts if v.worst and v.status == 'does not conform' %}<table class="data worst"><caption>{{ v.label }}: worst rows</caption>
<tr><th>id</th><th>wi</th><th>wo</th><th>mu</th><th>roughness</th><th>rho</th><th>expected</th><th>got</th><th>error / tolerance</th></tr>
{% for w in v.worst %}<tr><td>{{ w.id }}</td><td>{{ w.wi | vec }}</td><td>{{ w.wo | vec }}</td><td class="num">{{ w.mu | num }}</td>
<td class="num">{{ w.roughness | num }}</td><td>{{ w.rho | vec }}</td><td>{{ w.expected | vec }}</td><td>{{ w.got | vec }}</td>
<td class="num">{{ w.normalised_error | num }}</td></tr>{% endfor %}</table>{% endfor %}
</section>
<h2 id="evidence">The library's own evidence (counted separately)</h2>
{% else %}<p id="headline" class="na">No implementation under test: this report shows the reference's own evidence. Use --glsl/--cpp/--vectors/--implementation to grade yours.</p>
<div id="start"><p>To grade your own BRDF (a GLSL function <code>vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho)</code>):</p>
<pre><code>openpbr-diffuse template glsl --out mine.glsl     # a starting file
openpbr-diffuse report --glsl mine.glsl --function f</code></pre>
<p>The guide: &ldquo;The conformance report&rdquo; of the documentation (<code>docs/guide/report.md</code> in the
source; <code>openpbr-diffuse report --help</code>).</p></div>
{% endif %}
{% if doc.explorer %}<p id="explorer-link">Lobe explorer (WebGL2, offline): <a href="{{ doc.explorer.file }}">{{ doc.explorer.file }}</a>:
the EON lobe, Lambert and QON computed by the GLSL export{% if doc.explorer.subject %}, and your <code>{{ doc.explorer.function }}</code>
({{ doc.explorer.subject }}) beside the reference with |theirs &minus; reference|{% endif %}, at sliders for r, &rho;, &theta;<sub>o</sub> and the light.</p>{% endif %}
{% if doc.evidence.n_checks == 0 %}<p id="overall" class="na">The reference's evidence: not run (no check ran{% if doc.select %}; --select {{ doc.select | join(' ') }}{% endif %}).</p>
{% else %}<p id="overall" class="{{ 'pass' if doc.passed else 'fail' }}">The reference's evidence: {{ "ALL CHECKS PASS" if doc.passed else "SOME CHECKS FAIL" }}:
{{ doc.evidence.n_checks - doc.evidence.n_failed }} of {{ doc.evidence.n_checks }} checks pass{% if doc.evidence.n_not_run %}; {{ doc.evidence.n_not_run }} not run{% endif %}.</p>{% endif %}
<table id="summary"><caption>Sections</caption>
<tr><th>section</th><th>status</th><th>checks passed</th><th>time (s)</th></tr>
{% for s in doc.sections %}<tr><td><a href="#section-{{ s.key }}">{{ s.title }}</a></td>
<td class="{{ status_class(s.status) }}">{{ s.status }}</td>
<td class="num">{% if s.status == 'not run' %}{{ s.not_run | not_run }}{% elif s.status == 'findings' %}{{ s.findings or 0 }} finding{{ 's' if s.findings != 1 }} ({{ s.lists | length }} implementation{{ 's' if s.lists | length != 1 }} graded){% else %}{{ s.checks | selectattr('passed') | list | length }} / {{ s.checks | rejectattr('status', 'equalto', 'not run') | list | length }}{% endif %}</td>
<td class="num">{{ s.elapsed_s | num }}</td></tr>
{% endfor %}</table>
{% for s in doc.sections %}
<section id="section-{{ s.key }}" class="report-section" data-key="{{ s.key }}" data-status="{{ s.status }}">
<h2>{{ s.title }} <span class="badge {{ status_class(s.status) }}">{{ s.status }}</span></h2>
{% if s.error %}<p class="warn">Section failed: {{ s.error }}</p>{% endif %}
{% if s.not_run %}<p class="warn not-run">{{ s.not_run if s.not_run.startswith('not run') else 'Not run: ' ~ s.not_run }}</p>{% endif %}
{% for n in s.notes %}<p>{{ n }}</p>{% endfor %}
{% for w in s.warnings %}<p class="warn">{{ w }}</p>{% endfor %}
{% if s.findings is number %}<p class="findings"><strong>{{ s.findings }} finding{{ 's' if s.findings != 1 }}</strong> (quantities that do not conform) among {{ s.lists | length }} implementation{{ 's' if s.lists | length != 1 }} graded.</p>{% endif %}
{% for l in s.lists %}<h3>{{ l.title }}</h3><ul class="items">{% for i in l["items"] %}<li>{{ i }}</li>{% endfor %}</ul>{% endfor %}
{% if s.checks %}<table class="checks"><caption>Checks</caption>
<tr><th>id</th><th>check</th><th>measured</th><th>threshold</th><th>result</th><th>reference</th><th>detail</th></tr>
{% for c in s.checks %}<tr data-id="{{ c.id }}"><td><code>{{ c.id }}</code></td><td>{{ c.name }}</td><td class="num">{{ c.measured | num }}{% if c.unit %} {{ c.unit }}{% endif %}</td>
<td class="num">{% if c.comparison == '==' %}{{ c.expected | num }} &plusmn; {{ c.threshold | num }}{% else %}{{ c.comparison }} {{ c.threshold | num }}{% endif %}</td>
<td class="{{ status_class(c.status) }}">{{ {'pass': 'pass', 'fail': 'FAIL'}.get(c.status, c.not_run | not_run) }}</td>
<td>{{ c.reference }}</td><td>{{ c.detail }}</td></tr>
{% endfor %}</table>{% endif %}
{% set lib = library_parts(s) if s.key == 'materials' and doc.materials else none %}
{% for t in (lib.tables if lib else s.tables) %}<table class="data"><caption>{{ t.caption }}</caption>
<tr>{% for c in t.columns %}<th>{{ c }}</th>{% endfor %}</tr>
{% for row in t.rows %}<tr>{% for v in row %}<td{% if v is number %} class="num"{% endif %}>{{ v | num }}</td>{% endfor %}</tr>
{% endfor %}</table>{% endfor %}
{% for f in (lib.figures if lib else s.figures) %}<figure><img src="{{ f.file }}" alt="{{ f.caption }}" loading="eager">
<figcaption>{{ f.caption }}</figcaption></figure>{% endfor %}
{% if lib %}{% include "materials" %}{% endif %}
</section>
{% endfor %}
{% if doc.materials %}<script>{{ library_script | safe }}</script>{% endif %}
</body>
</html>
"""


def _num(v):
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return str(v)
        if v == 0.0:
            return "0"
        a = abs(v)
        return f"{v:.4g}" if 1e-3 <= a < 1e5 else f"{v:.3e}"
    return v


def _vec(v):
    if v is None:
        return "—"
    return "(" + ", ".join(str(_num(float(x))) for x in v) + ")"


def _not_run(reason):
    """A "not run" cell: the reason, prefixed with "not run: " unless it says so itself."""
    reason = reason or ""
    return reason if reason.startswith("not run") else f"not run: {reason}"


def quick_skipped(doc: dict) -> list:
    """(key, title, number of checks) of each section that left checks out as ``report --quick`` does.

    >>> from openpbr_diffuse.report.model import QUICK_NOT_RUN
    >>> quick_skipped({"sections": [{"key": "layered", "title": "Layered", "checks": [{"not_run": QUICK_NOT_RUN}]}]})
    [('layered', 'Layered', 1)]
    """
    from .model import QUICK_NOT_RUN

    out = []
    for s in doc.get("sections", []):
        n = sum(1 for c in s.get("checks", []) if c.get("not_run") == QUICK_NOT_RUN)
        if n:
            out.append((s["key"], s["title"], n))
    return out


def _tier_class(status):
    """The CSS class of an implementation's tier."""
    return {"conforms": "pass", "conforms with warnings": "warntier", "could not run": "na"}.get(status, "fail")


def _status_class(status):
    return {"pass": "pass", "fail": "fail", "error": "error"}.get(status, "na")


def render_html(doc: dict, image_dir: Path | None = None) -> str:
    """The page for a report document (as in ``report.json``), every string escaped.

    Figures whose file is missing from ``image_dir`` are dropped with a warning on their
    section (the page never shows a broken image).

    Examples
    --------
    >>> doc = {"version": "x", "generated": "now", "quick": True, "elapsed_s": 1.0, "paths": [],
    ...        "passed": True, "n_checks": 0, "n_failed": 0,
    ...        "sections": [{"key": "k", "title": "<b>T</b>", "status": "pass", "elapsed_s": 0.0,
    ...                      "error": None, "notes": [], "warnings": [], "checks": [],
    ...                      "tables": [], "figures": []}]}
    >>> "&lt;b&gt;T&lt;/b&gt;" in render_html(doc), "<b>T</b>" in render_html(doc)
    (True, False)
    """
    from jinja2 import DictLoader, Environment

    from . import library_html

    doc = dict(doc)
    if image_dir is not None:
        sections = []
        for s in doc.get("sections", []):
            s = dict(s)
            keep: list[Any] = []
            missing: list[Any] = []
            for f in s.get("figures", []):
                (keep if (Path(image_dir) / Path(f["file"]).name).is_file() else missing).append(f)
            s["figures"] = keep
            s["warnings"] = list(s.get("warnings", [])) + [f"image not written: {f['file']}" for f in missing]
            sections.append(s)
        doc["sections"] = sections
    env = Environment(
        autoescape=True, trim_blocks=False, lstrip_blocks=False, loader=DictLoader({"materials": library_html.TEMPLATE})
    )
    env.filters["num"] = _num
    env.filters["vec"] = _vec
    env.filters["not_run"] = _not_run
    env.filters["tier_class"] = _tier_class
    doc.setdefault("implementation", None)
    doc.setdefault("evidence", {"n_checks": doc.get("n_checks", 0), "n_failed": doc.get("n_failed", 0), "n_not_run": 0})
    template = env.from_string(_TEMPLATE)
    lib = library_html.context(doc)
    return template.render(
        doc=doc,
        status_class=_status_class,
        quick_skipped=quick_skipped,
        script_hash=library_html.script_hash(),
        library_style=library_html.STYLE,
        library_script=library_html.SCRIPT,
        library_parts=lib.pop("parts"),
        **lib,
    )


__all__ = ["render_html", "quick_skipped"]

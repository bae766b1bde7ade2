"""A library's records summarised: counts, the worst materials, what to draw, distributions.

Every function here takes the report's per-material records (:func:`.worker.material_record`
plus ``file``, ``relpath`` and ``index``) and costs one pass over them; what it returns
does not grow with the library (bounded tables, fixed histogram bins), except
:func:`distributions`' value arrays (a float per material).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np

from .worker import MUS, VERDICTS

#: Rank of each verdict in "worst first" order.
RANK = {v: k for k, v in enumerate(VERDICTS)}
#: The verdict of a file that could not be read (its one record stands for the file).
FILE_NOT_READ = "file not read"


def excess(rec: dict[str, Any]) -> float:
    """How far a record's largest albedo is above its allowance (negative: below; -inf: none).

    >>> excess({"albedo_max": 1.01, "albedo_limit": 1.002}) > 0, excess({})
    (True, -inf)
    """
    a, lim = rec.get("albedo_max"), rec.get("albedo_limit")
    return float(a) - float(lim) if a is not None and lim is not None else float("-inf")


def worst_key(rec: dict[str, Any]) -> tuple:
    """Sort key, worst first: verdict (fail, flagged, unsupported, pass), then the albedo's
    excess over its allowance (largest first), then file and position.

    >>> recs = [{"verdict": "pass", "albedo_max": 0.9, "albedo_limit": 1.002, "file": "a", "index": 0},
    ...         {"verdict": "pass", "albedo_max": 0.99, "albedo_limit": 1.002, "file": "b", "index": 0},
    ...         {"verdict": "fail", "file": "c", "index": 0}]
    >>> [r["file"] for r in sorted(recs, key=worst_key)]
    ['c', 'b', 'a']
    """
    return (RANK.get(rec.get("verdict", "pass"), len(RANK)), -excess(rec), rec.get("file", ""), rec.get("index", 0))


def by_verdict(records: Sequence[dict[str, Any]]) -> list[list[Any]]:
    """[[verdict, materials]] in the order of :data:`.worker.VERDICTS` (files not read apart).

    >>> by_verdict([{"verdict": "pass"}, {"verdict": "fail", "reasons": [FILE_NOT_READ]}])
    [['fail', 0], ['flagged', 0], ['unsupported', 0], ['pass', 1], ['file not read', 1]]
    """
    c = Counter(r["verdict"] for r in records if FILE_NOT_READ not in r.get("reasons", ()))
    unread = sum(FILE_NOT_READ in r.get("reasons", ()) for r in records)
    return [[v, c.get(v, 0)] for v in VERDICTS] + [[FILE_NOT_READ, unread]]


def by_kind(records: Sequence[dict[str, Any]], limit: int = 30) -> list[list[Any]]:
    """[[shader kind, materials, fail, flagged, unsupported, pass]], most frequent first; the
    kinds beyond ``limit`` are summed in one row "(other kinds)".

    >>> by_kind([{"kind": "a", "verdict": "pass"}, {"kind": "a", "verdict": "fail"}, {"kind": "b", "verdict": "pass"}])
    [['a', 2, 1, 0, 0, 1], ['b', 1, 0, 0, 0, 1]]
    """
    table: dict[str, Counter] = {}
    for r in records:
        table.setdefault(r.get("kind") or "(none)", Counter())[r["verdict"]] += 1
    rows: list[list[Any]] = sorted(
        ([k, sum(c.values()), *(c.get(v, 0) for v in VERDICTS)] for k, c in table.items()),
        key=lambda row: (-int(row[1]), str(row[0])),
    )
    if len(rows) > limit:
        rest = rows[limit - 1 :]
        rows = rows[: limit - 1] + [["(other kinds)"] + [sum(r[j] for r in rest) for j in range(1, 6)]]
    return rows


def by_reason(records: Sequence[dict[str, Any]]) -> list[list[Any]]:
    """[[reason, materials]], most frequent first (a material may have several reasons).

    >>> by_reason([{"reasons": ["a", "b"]}, {"reasons": ["b"]}, {"reasons": []}])
    [['b', 2], ['a', 1]]
    """
    c = Counter(reason for r in records for reason in r.get("reasons", ()))
    return [[k, n] for k, n in sorted(c.items(), key=lambda kv: (-kv[1], kv[0]))]


def drawable(rec: dict[str, Any]) -> bool:
    """Whether a record's material was evaluated (it has an albedo curve and a preview).

    >>> drawable({"material": "/M", "albedo": [0.5, 0.5, 0.5]}), drawable({"material": "/M", "albedo": None})
    (True, False)
    """
    return rec.get("albedo") is not None and rec.get("material") is not None


def chosen_for_figures(records: Sequence[dict[str, Any]], cap: int) -> list[int]:
    """Positions (in ``records``) of at most ``cap`` materials to draw: the drawable ones,
    failing first, then flagged, then in file order.

    >>> recs = [{"verdict": "pass", "albedo": [1, 1, 1], "material": "/a"},
    ...         {"verdict": "flagged", "albedo": [1, 1, 1], "material": "/b"},
    ...         {"verdict": "fail", "albedo": None, "material": "/c"}]
    >>> chosen_for_figures(recs, 1), chosen_for_figures(recs, 5)
    ([1], [1, 0])
    """
    order = sorted(
        (k for k, r in enumerate(records) if drawable(r)), key=lambda k: (RANK.get(records[k]["verdict"], 9), k)
    )
    return order[: max(0, int(cap))]


def distributions(records: Sequence[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Value arrays of the evaluated materials: ``roughness`` (n,), ``base_color`` (n, 3),
    and ``albedo_mu=<mu>`` (n,) the mean of R, G, B of the directional albedo at each mu of
    :data:`.worker.MUS`.

    >>> d = distributions([{"roughness": 0.5, "base_color": [0.1, 0.2, 0.3],
    ...                     "albedo_mu": {"1": [0.3, 0.3, 0.3], "0.5": [0.2, 0.2, 0.2], "0.2": [0.1, 0.1, 0.1]}}])
    >>> d["roughness"].tolist(), d["base_color"].shape, round(float(d["albedo_mu=0.5"][0]), 6)
    ([0.5], (1, 3), 0.2)
    """

    def values(get: Any, shape: tuple) -> np.ndarray:
        out = [v for v in (get(r) for r in records) if v is not None and None not in np.atleast_1d(v)]
        return np.asarray(out, dtype=np.float64).reshape((-1, *shape))

    d = {
        "roughness": values(lambda r: r.get("roughness"), ()),
        "base_color": values(lambda r: r.get("base_color"), (3,)),
    }
    for mu in MUS:
        key = f"{mu:g}"
        a = values(lambda r, key=key: (r.get("albedo_mu") or {}).get(key), (3,))
        d[f"albedo_mu={key}"] = a.mean(axis=1)
    return d


__all__ = [
    "FILE_NOT_READ",
    "RANK",
    "by_kind",
    "by_reason",
    "by_verdict",
    "chosen_for_figures",
    "distributions",
    "drawable",
    "excess",
    "worst_key",
]

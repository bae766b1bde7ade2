"""The table of sampling strategies (EON paper Section 3.1, Fig. 10).

Every strategy samples ``wi`` given ``wo`` in the local frame (normal +z) and reports the
solid-angle pdf.  ``roughness`` is EON's r in [0, 1] for all of them (cosine and uniform
ignore it).
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class StrategyInfo:
    name: str
    id: int
    covers_hemisphere: bool  # pdf > 0 wherever f_EON > 0 (unbiased for EON)
    below_horizon: bool  # may return directions with z < 0 (their weight is 0)
    description: str


_STRATEGIES = (
    ("cosine", True, False, "cosine-weighted hemisphere, pdf = mu_i/pi (Eq. 21)"),
    ("uniform", True, False, "uniform hemisphere, pdf = 1/(2 pi)"),
    ("ltc", False, True, "general LTC fit (Listing 2); the lobe extends below the horizon"),
    ("ltc_nonneg", True, False, "LTC with d = 0 (the 'non-negative' variant of Fig. 10)"),
    ("cltc", False, False, "clipped LTC (Eq. 27-28, Listing 3); misses a lune near grazing"),
    ("eon", True, False, "CLTC + uniform, one-sample MIS (Listing 4): the EON sampler"),
)

INFO = {s[0]: StrategyInfo(s[0], i, *s[1:]) for i, s in enumerate(_STRATEGIES)}

#: The public tuple of strategy names.
STRATEGIES = tuple(INFO)

COSINE, UNIFORM, LTC, LTC_NONNEG, CLTC, EON = (INFO[n].id for n in STRATEGIES)


def strategy_info(strategy: object) -> StrategyInfo:
    """Look a strategy up by name; ValueError/TypeError naming ``strategy`` otherwise."""
    if not isinstance(strategy, str):
        raise TypeError(f"strategy must be a string, one of {', '.join(STRATEGIES)}; got {type(strategy).__name__}")
    try:
        return INFO[strategy]
    except KeyError:
        raise ValueError(
            f"strategy: unknown sampling strategy {strategy!r}; expected one of {', '.join(STRATEGIES)}"
        ) from None

"""The value tolerance of the conformance grade, in a module of its own so that the grade and
the property checks (which the grade calls) both read it without importing each other.

>>> from openpbr_diffuse.conformance.tolerance import ABS_TOL, REL_TOL
>>> ABS_TOL + REL_TOL * 0.5   # the tolerance at a value of 0.5
5.1e-05
"""

#: relative part of the per-value tolerance |out - ref| <= ABS_TOL + REL_TOL |ref|
REL_TOL = 1e-4
#: absolute part of the per-value tolerance
ABS_TOL = 1e-6

__all__ = ["ABS_TOL", "REL_TOL"]

"""The seeds' real-time approximations, implemented as published and graded against exact
quantities.

- ``gotanda2012``: Gotanda 2012 Eq. 20-25 (simplified / shininess / improved Oren-Nayar) and
  the SH scales Eq. 27-29.
- ``kulla_conty``: table-based energy compensation (Kulla-Conty, as in patapom's "Energy
  Compensation Pt. 2"): f_ms from the reference tables, the rho factor, ZH fits for SH
  environment light, LTC fits for area lights.
- ``sh``: order-2 SH lighting of any lobe with the exact transfer computed by quadrature.
- ``grading``: the rows of ``data/approximation_errors.csv`` (``tools/grade_approximations.py``).
"""

from . import gotanda2012, kulla_conty, sh

__all__ = ["gotanda2012", "kulla_conty", "sh"]

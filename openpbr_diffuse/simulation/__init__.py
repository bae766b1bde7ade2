"""Physical ground truth: Monte Carlo light transport on a rough Lambertian microsurface.

- ``vcavity``: Oren & Nayar's V-groove geometry with all interreflections
- ``smith``: Heitz et al. 2016's random walk on a Smith microsurface (Beckmann, GGX)
- ``api``: ``simulate_albedo``, ``simulate_average_albedo``, ``simulate_brdf``
- ``grading``: the shipped grading tables of the library's models against the simulation
"""

from . import api
from .api import *  # noqa: F403  (the names of ``api.__all__``)

__all__ = list(api.__all__)

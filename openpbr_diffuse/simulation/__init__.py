"""Physical ground truth: Monte Carlo light transport on a rough Lambertian microsurface.

- ``vcavity``: Oren & Nayar's V-groove geometry with all interreflections
- ``smith``: Heitz et al. 2016's random walk on a Smith microsurface (Beckmann, GGX)
- ``api``: ``simulate_albedo``, ``simulate_average_albedo``, ``simulate_brdf``
- ``grading``: the shipped grading tables of the library's models against the simulation
"""

from .api import (
    CHUNK_PATHS,
    GEOMETRIES,
    MAX_BOUNCES,
    AlbedoEstimate,
    BRDFEstimate,
    simulate_albedo,
    simulate_average_albedo,
    simulate_brdf,
)

__all__ = [
    "GEOMETRIES",
    "CHUNK_PATHS",
    "MAX_BOUNCES",
    "AlbedoEstimate",
    "BRDFEstimate",
    "simulate_albedo",
    "simulate_average_albedo",
    "simulate_brdf",
]

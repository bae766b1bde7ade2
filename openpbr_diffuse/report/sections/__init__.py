"""The report's sections, in page order: each a module with ``TITLE`` and ``build(ctx)``.

- models: model properties (white furnace, reciprocity, Lambert limit, energy; Fig. 2, 5-6)
- albedo: closed forms against the reference tables, the Eq. 14 fit's error
- sampling: chi-square, pdf normalisation, variance curves (Fig. 10-12)
- colorshift: spectral versus RGB, the EON colour shift
- materials: each material of the given files
- implementations: the test vectors, the grader and its self-test on the known deviations
- graders: real implementations graded by running their own code (issue 12)
- approximations: the seeds' real-time approximations (Gotanda, table compensation, SH)
- simulation: the microsurface ground truth
- layered: the diffuse lobe under a dielectric layer against the layered-surface simulation
- timings: the paper's Table 1 on this machine
"""

SECTIONS = (
    "models",
    "albedo",
    "sampling",
    "colorshift",
    "materials",
    "implementations",
    "graders",
    "approximations",
    "simulation",
    "layered",
    "timings",
)

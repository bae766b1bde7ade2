"""Conformance of other implementations: test vectors, known deviations, grading.

- :mod:`.vectors`: the versioned set of test inputs (``default_vectors()``), its CSV/JSON
  writer and the reader of submitted result files;
- :mod:`.deviations`: the known deviations of published implementations, each as a
  predictor of what such an implementation returns for the vectors;
- :mod:`.grade`: ``grade(vectors, out)`` -> :class:`~.grade.Grade` (errors, pass/fail at a
  stated tolerance, worst rows, diagnosis by fitting each known deviation).
"""

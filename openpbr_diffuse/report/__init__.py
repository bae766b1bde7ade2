"""The conformance report: ``openpbr-diffuse report`` (HTML + JSON + images).

Each section is a module of :mod:`openpbr_diffuse.report.sections` with ``TITLE`` and
``build(ctx) -> SectionResult`` (see :mod:`.model`); the runner calls them in the order of
``sections.SECTIONS`` and renders the results.
"""

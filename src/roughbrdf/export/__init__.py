"""Exports of models and fits to the tools where BRDFs are used (``docs/export.md``).

One module per target: :mod:`~roughbrdf.export.zemax` (Zemax OpticStudio tabular BSDF, the
model sampled on a grid relative to the specular direction) and :mod:`~roughbrdf.export.mitsuba`
(Mitsuba 3 scene-description dicts and XML ``<bsdf>`` elements).
"""

"""Models: one module per published model, plus Lambertian, generic microfacet and sums.

The stray-light scatter models of the optical codes are in :mod:`.straylight` (ABg,
Harvey–Shack) and :mod:`.kcorr` (K-correlation / Rayleigh–Rice); ``docs/straylight.md``.

``base`` (the :class:`Model` class and its evaluation interface, the registry), ``parameters``
(:class:`Parameter`), ``sum`` (:class:`SumModel`), ``factory`` (:func:`model` by name or
``"a+b"``, specs, and the naming a fit uses: :func:`as_model`, :func:`model_label`,
:func:`is_auto`), and one module per model.
"""

from .base import MODELS, Model, PreparedGeometry, SumModel, register
from .coated import Coated
from .coated_conductor import CoatedConductor
from .factory import (
    as_model,
    available,
    from_spec,
    is_auto,
    model,
    model_label,
    resolve_names,
    spec_text,
)
from .kcorr import KCorrelation
from .lambertian import Lambertian
from .microfacet import Microfacet
from .oren_nayar import OrenNayar
from .parameters import Parameter
from .renhorn_boreman import RenhornBoreman2008
from .straylight import ABg, HarveyShack
from .torrance_sparrow import TorranceSparrow1967
from .trowbridge_reitz import TrowbridgeReitz1975

__all__ = [
    "MODELS",
    "Model",
    "Parameter",
    "PreparedGeometry",
    "SumModel",
    "as_model",
    "available",
    "from_spec",
    "is_auto",
    "model",
    "model_label",
    "register",
    "resolve_names",
    "spec_text",
    "ABg",
    "Coated",
    "CoatedConductor",
    "HarveyShack",
    "KCorrelation",
    "Lambertian",
    "Microfacet",
    "OrenNayar",
    "RenhornBoreman2008",
    "TorranceSparrow1967",
    "TrowbridgeReitz1975",
]

"""Models: one module per published model, plus Lambertian, generic microfacet and sums.

``base`` (the :class:`Model` class and its evaluation interface, the registry), ``parameters``
(:class:`Parameter`), ``sum`` (:class:`SumModel`), ``factory`` (:func:`model` by name or
``"a+b"``), and one module per model.
"""

from .base import MODELS, Model, PreparedGeometry, SumModel, register
from .coated import Coated
from .factory import available, from_spec, model, resolve_names, spec_text
from .lambertian import Lambertian
from .microfacet import Microfacet
from .oren_nayar import OrenNayar
from .parameters import Parameter
from .renhorn_boreman import RenhornBoreman2008
from .torrance_sparrow import TorranceSparrow1967
from .trowbridge_reitz import TrowbridgeReitz1975

__all__ = [
    "MODELS",
    "Model",
    "Parameter",
    "PreparedGeometry",
    "SumModel",
    "available",
    "from_spec",
    "model",
    "register",
    "resolve_names",
    "spec_text",
    "Coated",
    "Lambertian",
    "Microfacet",
    "OrenNayar",
    "RenhornBoreman2008",
    "TorranceSparrow1967",
    "TrowbridgeReitz1975",
]

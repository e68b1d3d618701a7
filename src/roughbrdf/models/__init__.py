"""Models: one module per published model, plus Lambertian, generic microfacet and sums."""

from .base import MODELS, Model, Parameter, SumModel, available, model, register
from .lambertian import Lambertian
from .microfacet import Microfacet
from .renhorn_boreman import RenhornBoreman2008
from .torrance_sparrow import TorranceSparrow1967
from .trowbridge_reitz import TrowbridgeReitz1975

__all__ = [
    "MODELS",
    "Model",
    "Parameter",
    "SumModel",
    "available",
    "model",
    "register",
    "Lambertian",
    "Microfacet",
    "RenhornBoreman2008",
    "TorranceSparrow1967",
    "TrowbridgeReitz1975",
]

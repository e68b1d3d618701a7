"""roughbrdf: physically based reflection from rough surfaces.

Exact implementations of Torrance & Sparrow (1967), Trowbridge & Reitz (1975) and
Renhorn & Boreman (2008), and the modern microfacet family built from the same parts, evaluated
with compiled kernels on NumPy arrays; fitted to measured data; reproducing the papers.

Conventions: radians; mean-surface normal +z; source on -x; ``phi = 0`` forward (specular) side.
See ``roughbrdf.geometry`` for the conversions to each paper's own angles.
"""

from . import distributions, fresnel, geometry, shadowing
from .fitting import FitResult, fit
from .integrate import albedo, reciprocity_error
from .io import read, write
from .models import Model, Parameter, SumModel, available, model

__version__ = "0.1.0"

__all__ = [
    "albedo",
    "available",
    "distributions",
    "fit",
    "FitResult",
    "fresnel",
    "geometry",
    "model",
    "Model",
    "Parameter",
    "read",
    "reciprocity_error",
    "shadowing",
    "SumModel",
    "write",
]

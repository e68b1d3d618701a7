"""roughbrdf: physically based reflection from rough surfaces.

Exact implementations of Torrance & Sparrow (1967), Trowbridge & Reitz (1975) and
Renhorn & Boreman (2008), and the modern microfacet family built from the same parts, evaluated
with compiled kernels on NumPy arrays; fitted to measured data; reproducing the papers.

Conventions: radians; mean-surface normal +z; source on -x; ``phi = 0`` forward (specular) side.
See ``roughbrdf.geometry`` for the conversions to each paper's own angles.

Importing the package is cheap: every public name is loaded on first use (PEP 562 module
``__getattr__``), so ``import roughbrdf`` loads neither Numba, SciPy nor Matplotlib, and
``rb.model("tr75")`` loads the models but not SciPy (the fitting machinery) or Matplotlib.
"""

import os as _os

# Numba's OpenMP threading layer lets idle workers spin-wait by default; on a busy or shared
# machine the spinning threads starve every other thread, including the next parallel loop
# (measured on a 2-core box under load: one 13k-sample TR75 evaluation 16 ms instead of 0.17 ms,
# single-threaded code 2x slower). Passive waiting costs nothing on an idle machine. Must be set
# before the OpenMP runtime starts; a value set by the user wins. (Added by the fitting work.)
# Set here, at package import, so that it precedes the first compiled call whatever it is.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import sys as _sys  # noqa: E402
import types as _types  # noqa: E402
from typing import TYPE_CHECKING as _TYPE_CHECKING  # noqa: E402

if _TYPE_CHECKING:  # for type checkers and IDEs; at run time the names load on first use
    from . import diffuse, distributions, fresnel, geometry, shadowing
    from .catalogue import fit_catalogue
    from .explore.notebook import explore
    from .export import export_mitsuba, export_to, export_zemax
    from .fitting import FitOptions, FitResult, compare, fit
    from .fitting.load import load_fit
    from .integrate import albedo, reciprocity_error
    from .io import read, write
    from .measurement import Measurement
    from .models import Model, Parameter, SumModel, available, model

__version__ = "0.1.0"

__all__ = [
    "albedo",
    "available",
    "compare",
    "diffuse",
    "distributions",
    "explore",
    "export_mitsuba",
    "export_to",
    "export_zemax",
    "fit",
    "fit_catalogue",
    "FitOptions",
    "FitResult",
    "fresnel",
    "geometry",
    "load_fit",
    "Measurement",
    "model",
    "Model",
    "Parameter",
    "read",
    "reciprocity_error",
    "shadowing",
    "SumModel",
    "write",
]

#: public name -> submodule that defines it (loaded on first access)
_ATTRS = {
    "FitOptions": "fitting",
    "FitResult": "fitting",
    "fit": "fitting",
    "compare": "fitting",
    "load_fit": "fitting.load",
    "fit_catalogue": "catalogue",
    "export_to": "export",
    "export_mitsuba": "export",
    "export_zemax": "export",
    "albedo": "integrate",
    "reciprocity_error": "integrate",
    "read": "io",
    "write": "io",
    "Measurement": "measurement",
    "Model": "models",
    "Parameter": "models",
    "SumModel": "models",
    "available": "models",
    "model": "models",
}

#: submodules reachable as attributes (``rb.geometry``) without importing them first: the public
#: ones of ``__all__`` and those an eager ``import roughbrdf`` used to load as a side effect
_SUBMODULES = frozenset({
    "catalogue", "diffuse", "distributions", "explore", "export", "fresnel", "geometry",
    "shadowing", "fitting", "integrate", "io", "measurement", "models", "mueller", "plot_mueller",
    "polarization", "quantity", "registry", "special", "stokes",
})


class _ExplorePackage(_types.ModuleType):
    """The subpackage :mod:`roughbrdf.explore`, callable: ``rb.explore(model_or_fit,
    measurement)`` is :func:`roughbrdf.explore.notebook.explore` (the notebook explorer).

    ``rb.explore`` names both the function and the subpackage: importing a submodule
    (``import roughbrdf.explore.figures``) binds the subpackage as the package's attribute
    ``explore``, which would hide a function of that name. The subpackage is therefore made
    callable instead (:class:`_Package` swaps its class when it is bound), so that
    ``rb.explore(...)`` and ``rb.explore.figures`` both work whatever was imported first.
    """

    def __call__(self, *args, **kwargs):
        from .explore.notebook import explore

        return explore(*args, **kwargs)

    @property
    def __signature__(self):
        """The signature of :func:`~roughbrdf.explore.notebook.explore` (``inspect``, IDEs)."""
        import inspect

        from .explore.notebook import explore

        return inspect.signature(explore)


def _load_renderings() -> None:
    """Register the notebook HTML of models and measurements (:mod:`roughbrdf.html_repr`)."""
    import importlib

    importlib.import_module(f"{__name__}.html_repr")


class _Package(_types.ModuleType):
    """This package's module type: binds the subpackage ``explore`` callable
    (:class:`_ExplorePackage`), and gives :mod:`roughbrdf.rich_display` the loader of the
    notebook renderings when it is bound (imported): the models and the measurement, low in
    the layers, display through it without importing :mod:`roughbrdf.html_repr`, which is
    higher (it shows fit results); the face names every layer, so the hook lives here and
    ``import roughbrdf`` still loads nothing."""

    def __setattr__(self, name: str, value: object) -> None:
        if name == "explore" and type(value) is _types.ModuleType:
            value.__class__ = _ExplorePackage
        elif name == "rich_display" and isinstance(value, _types.ModuleType):
            value.set_loader(_load_renderings)
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    """Load a public name (or a submodule) on first access and keep it in the module."""
    import importlib

    if name in _ATTRS:
        value = getattr(importlib.import_module(f"{__name__}.{_ATTRS[name]}"), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
        if name == "explore" and type(value) is _types.ModuleType:  # bound before the swap
            value.__class__ = _ExplorePackage
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | _SUBMODULES)

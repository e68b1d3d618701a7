"""Model base class, named parameters, sums of models and the model registry.

A model is pure: parameters in, values out. It knows nothing about fitting; a fitter reads
``parameters`` (value, bounds, unit) and rebuilds the model with :meth:`Model.with_values`.

Every model supplies one compiled scalar function ``point(theta_i, theta_r, phi, gamma, p, flag)``
returning the BRDF (``flag = 0``) or the BRIDF ``f_r cos(theta_r)`` (``flag = 1``) for the packed
numeric parameter tuple ``p`` (:meth:`Model._pack`); :func:`roughbrdf._jit.evaluate` broadcasts it
over NumPy arrays in parallel.
"""

from __future__ import annotations

import copy
import difflib
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .. import _jit
from ..fresnel import polarization_angle
from ..geometry import check_angles

__all__ = ["Parameter", "Model", "SumModel", "register", "model", "available", "MODELS"]


@dataclass(frozen=True)
class Parameter:
    """A named model parameter.

    Attributes
    ----------
    name : str
    value : float or None
        ``None`` switches an optional part off (e.g. TS67 ``n=None`` gives F = 1).
    bounds : (float, float)
        Default search range for fits (finite, inside the physical domain).
    unit : str
    description : str
    domain : (float, bool, float, bool)
        Physical domain ``(low, low_inclusive, high, high_inclusive)``; values outside raise.
    optional : bool
        Whether ``None`` is accepted.
    """

    name: str
    value: float | None
    bounds: tuple[float, float]
    unit: str = ""
    description: str = ""
    domain: tuple[float, bool, float, bool] = (-math.inf, False, math.inf, False)
    optional: bool = False

    def check(self, value: Any) -> float | None:
        """Validate ``value`` against the domain; return it as float (or None)."""
        if value is None:
            if self.optional:
                return None
            raise ValueError(f"parameter {self.name!r} cannot be None")
        try:
            v = float(value)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"parameter {self.name!r} must be a number, got {value!r}") from exc
        lo, lo_inc, hi, hi_inc = self.domain
        ok = (math.isfinite(v) and (v >= lo if lo_inc else v > lo)
              and (v <= hi if hi_inc else v < hi))
        if not ok:
            lo_s = ("[" if lo_inc else "(") + f"{lo:g}"
            hi_s = f"{hi:g}" + ("]" if hi_inc else ")")
            raise ValueError(
                f"parameter {self.name!r} = {value!r} is outside its physical domain "
                f"{lo_s}, {hi_s}" + (f" ({self.description})" if self.description else "")
            )
        return v


def positive(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
             **kw: Any) -> Parameter:
    """A parameter that must be > 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, False, math.inf, False), **kw)


def nonnegative(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
                **kw: Any) -> Parameter:
    """A parameter that must be >= 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, True, math.inf, False), **kw)


def unit_interval(name: str, default: float, desc: str) -> Parameter:
    """A reflectance-like parameter in [0, 1]."""
    return Parameter(name, default, (0.0, 1.0), "1", desc, (0.0, True, 1.0, True))


def _canon(name: str) -> str:
    return str(name).strip().lower().replace("_", "-").replace(" ", "-")


def _unknown(kind: str, name: str, known: Iterable[str]) -> ValueError:
    known = list(known)
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
    return ValueError(f"unknown {kind} {name!r}{hint} (known: {', '.join(known)})")


def polarization_array(polarization: Any) -> np.ndarray:
    """Polarization argument -> array of TR75 ``gamma`` angles (NaN = unpolarized)."""
    if polarization is None or isinstance(polarization, str | float | int):
        return np.asarray(polarization_angle(polarization), dtype=np.float64)
    arr = np.asarray(polarization)
    if arr.dtype.kind in "US":
        return np.vectorize(polarization_angle, otypes=[np.float64])(arr)
    arr = _jit.as_float_array(arr, "polarization")
    if np.isinf(arr).any():
        bad = arr[np.isinf(arr)].flat[0]
        raise ValueError(f"polarization angle gamma must be finite, got {bad!r}")
    return arr  # NaN entries mean unpolarized


class Model:
    """Base class of every BRDF model.

    Subclasses define ``name``, ``short`` (prefix in sums), ``reference``, ``PARAMETERS`` (a tuple
    of :class:`Parameter` with default values), optional ``OPTIONS`` (non-numeric settings with
    defaults), ``grazing_incidence`` (whether theta_i = pi/2 is allowed), and ``_point`` and
    ``_pack`` (and optionally ``_drive``, see :mod:`roughbrdf._jit`).
    """

    name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    short: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    PARAMETERS: ClassVar[tuple[Parameter, ...]] = ()
    OPTIONS: ClassVar[dict[str, Any]] = {}
    grazing_incidence: ClassVar[bool] = False
    reciprocal: ClassVar[bool] = True
    _point: ClassVar[Callable | None] = None
    #: optional module-level parallel loop over ``_point`` (``roughbrdf._jit.driver``): the
    #: vectorized, disk-cached fast path; without it the generic driver is used.
    _drive: ClassVar[Callable | None] = None

    def __init__(self, **kwargs: Any) -> None:
        specs = {p.name: p for p in self._parameter_specs()}
        options = dict(self._option_defaults())
        values: dict[str, float | None] = {n: p.value for n, p in specs.items()}
        for key, val in kwargs.items():
            if key in specs:
                values[key] = specs[key].check(val)
            elif key in options:
                options[key] = val
            else:
                raise _unknown(f"parameter for model {self.name!r}", key,
                               [*specs, *options])
        self._options = self._check_options(options)
        self._specs = self._parameter_specs()
        self._values = values
        self._validate()

    # -- hooks ----------------------------------------------------------------------------------
    def _parameter_specs(self) -> tuple[Parameter, ...]:
        return self.PARAMETERS

    def _option_defaults(self) -> dict[str, Any]:
        return dict(self.OPTIONS)

    def _check_options(self, options: dict[str, Any]) -> dict[str, Any]:
        return options

    def _validate(self) -> None:
        """Cross-parameter checks (after each parameter passed its own domain check)."""

    def _pack(self) -> tuple:
        raise NotImplementedError

    # -- parameters -----------------------------------------------------------------------------
    @property
    def params(self) -> dict[str, float | None]:
        """``{name: value}`` of the numeric parameters."""
        return dict(self._values)

    @property
    def options(self) -> dict[str, Any]:
        """Non-numeric settings (distribution, shadowing, readings)."""
        return dict(self._options)

    @property
    def parameters(self) -> list[Parameter]:
        """The parameters as :class:`Parameter` objects (value, bounds, unit, description)."""
        return [replace(p, value=self._values[p.name]) for p in self._specs]

    @property
    def param_names(self) -> list[str]:
        return [p.name for p in self._specs]

    def with_params(self, **updates: Any) -> Model:
        """A copy with some parameters (or options) changed."""
        kw = {**self._options, **self._values, **updates}
        return type(self)(**kw)

    def with_values(self, names: Sequence[str], values: Sequence[float]) -> Model:
        """A copy with the named parameters set to ``values`` (validated)."""
        new = copy.copy(self)
        new._values = dict(self._values)
        specs = {p.name: p for p in self._specs}
        for nm, v in zip(names, values, strict=True):
            if nm not in specs:
                raise _unknown(f"parameter for model {self.name!r}", nm, specs)
            new._values[nm] = specs[nm].check(v)
        new._validate()
        return new

    # -- evaluation -----------------------------------------------------------------------------
    def _evaluate(self, ti: np.ndarray, tr: np.ndarray, phi: np.ndarray, gamma: np.ndarray,
                  flag: int, term: str | None = None) -> np.ndarray | float:
        """Evaluate on already validated float arrays (used by fitters)."""
        if term is not None:
            raise ValueError(f"model {self.name!r} has no separate terms; got term={term!r}")
        cls = type(self)
        return _jit.evaluate(cls._point, ti, tr, phi, gamma, self._pack(), flag, cls._drive)

    def _prepare(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                 polarization: Any) -> tuple[np.ndarray, ...]:
        ti, tr, ph = check_angles(theta_i, theta_r, phi,
                                  grazing_incidence=self.grazing_incidence)
        return ti, tr, ph, polarization_array(polarization)

    def brdf(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
             polarization: Any = None, *, term: str | None = None) -> np.ndarray | float:
        """Standard BRDF ``f_r`` in sr⁻¹ (radiance / irradiance).

        Parameters
        ----------
        theta_i, theta_r : array_like
            Incidence and reflection zenith angles, radians, in [0, pi/2] (``theta_i < pi/2``
            for models that divide by ``cos theta_i``).
        phi : array_like
            Azimuth of the reflected ray, radians, 0 on the forward (specular) side.
        polarization : None, "unpolarized", "s", "p", float or array
            Incident polarization: TR75's angle ``gamma`` of the electric field from the plane
            of incidence (radians); arrays give one polarization per sample.
        term : str, optional
            A single term of a model that has several (e.g. RB08 ``"surface"``).

        Returns
        -------
        numpy.ndarray or float
            Broadcast shape of the inputs; a float if every input was a scalar.
        """
        return self._evaluate(*self._prepare(theta_i, theta_r, phi, polarization), 0, term)

    def bridf(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
              polarization: Any = None, *, term: str | None = None) -> np.ndarray | float:
        """TR75's BRIDF ``f_r cos(theta_r)`` in sr⁻¹ (finite at theta_r = pi/2)."""
        return self._evaluate(*self._prepare(theta_i, theta_r, phi, polarization), 1, term)

    __call__ = brdf

    # -- composition and description ------------------------------------------------------------
    def __add__(self, other: Model) -> SumModel:
        if not isinstance(other, Model):
            return NotImplemented
        return SumModel([*_components(self), *_components(other)])

    def to_dict(self) -> dict[str, Any]:
        """``{"model": name, "params": {...}, "options": {...}}``; round-trips via :func:`model`."""
        return {"model": self.name, "params": self.params, "options": self.options}

    def describe(self) -> str:
        """Multi-line human-readable description of the model and its parameters."""
        lines = [f"{self.name}  ({self.reference})"]
        for k, v in self._options.items():
            lines.append(f"  option {k} = {v!r}")
        for p in self.parameters:
            lines.append(f"  {p.name:<10} = {p.value!s:<12} [{p.unit}]  {p.description}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in {**self._options, **self._values}.items())
        return f"rb.model({self.name!r}, {args})"


def _components(m: Model) -> list[Model]:
    return list(m.components) if isinstance(m, SumModel) else [m]


class SumModel(Model):
    """Sum of models; parameter names are prefixed ``<short>_<name>`` (``<short><i>_`` if repeated).
    """

    name = "sum"
    short = "sum"

    def __init__(self, components: Sequence[Model]) -> None:  # noqa: D107
        self.components = [copy.copy(c) for c in components]
        counts: dict[str, int] = {}
        for c in self.components:
            counts[c.short] = counts.get(c.short, 0) + 1
        seen: dict[str, int] = {}
        self.prefixes = []
        for c in self.components:
            if counts[c.short] > 1:
                seen[c.short] = seen.get(c.short, 0) + 1
                self.prefixes.append(f"{c.short}{seen[c.short]}_")
            else:
                self.prefixes.append(f"{c.short}_")
        self.grazing_incidence = all(c.grazing_incidence for c in self.components)  # type: ignore[misc]
        self.reciprocal = all(c.reciprocal for c in self.components)  # type: ignore[misc]
        self._options = {}
        self._refresh()

    def _refresh(self) -> None:
        self._specs = tuple(replace(p, name=pre + p.name) for c, pre in
                            zip(self.components, self.prefixes, strict=True) for p in c.parameters)
        self._values = {p.name: p.value for p in self._specs}

    def _split(self, name: str) -> tuple[int, str]:
        for i, pre in enumerate(self.prefixes):
            if name.startswith(pre) and name[len(pre):] in self.components[i].params:
                return i, name[len(pre):]
        raise _unknown("parameter for this sum of models", name, [p.name for p in self._specs])

    def with_values(self, names: Sequence[str], values: Sequence[float]) -> SumModel:
        groups: dict[int, tuple[list[str], list[float]]] = {}
        for nm, v in zip(names, values, strict=True):
            i, base = self._split(nm)
            groups.setdefault(i, ([], []))[0].append(base)
            groups[i][1].append(v)
        new = copy.copy(self)
        new.components = [c.with_values(*groups[i]) if i in groups else c
                          for i, c in enumerate(self.components)]
        new._refresh()
        return new

    def with_params(self, **updates: Any) -> SumModel:
        return self.with_values(list(updates), list(updates.values()))

    def _evaluate(self, ti, tr, phi, gamma, flag, term=None):
        parts = []
        for c in self.components:
            if term is None:
                parts.append(c._evaluate(ti, tr, phi, gamma, flag, None))
            elif term in getattr(c, "TERMS", ()):
                parts.append(c._evaluate(ti, tr, phi, gamma, flag, term))
            elif term in (c.short, c.name):
                parts.append(c._evaluate(ti, tr, phi, gamma, flag, None))
        if not parts:
            raise ValueError(f"no component of this sum has a term {term!r}")
        return sum(parts[1:], parts[0])

    def to_dict(self) -> dict[str, Any]:
        return {"model": "sum", "components": [c.to_dict() for c in self.components]}

    def describe(self) -> str:
        return "\n".join(f"[{pre[:-1]}] " + c.describe() for c, pre in
                         zip(self.components, self.prefixes, strict=True))

    @property
    def reference(self) -> str:  # type: ignore[override]
        return "; ".join(c.reference for c in self.components)

    def __repr__(self) -> str:
        return " + ".join(repr(c) for c in self.components)


# --------------------------------------------------------------------------------------------
# registry
# --------------------------------------------------------------------------------------------
MODELS: dict[str, type[Model]] = {}


def register(cls: type[Model]) -> type[Model]:
    """Class decorator: register a model under its ``name`` and ``aliases``."""
    for key in (cls.name, *cls.aliases):
        MODELS[_canon(key)] = cls
    return cls


def available() -> list[str]:
    """Canonical names of the registered models."""
    seen: list[str] = []
    for cls in MODELS.values():
        if cls.name not in seen:
            seen.append(cls.name)
    return seen


def model(name: str | dict, **params: Any) -> Model:
    """Build a registered model by name (case-insensitive; aliases accepted).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    >>> round(m.bridf(0.0, 0.0, 0.0), 5)      # TR75 cement, normal incidence and view
    0.13402
    """
    if isinstance(name, dict):  # from to_dict()
        spec = dict(name)
        if spec.get("model") == "sum":
            parts = [model(c) for c in spec["components"]]
            out = parts[0]
            for p in parts[1:]:
                out = out + p
            return out
        return model(spec["model"], **spec.get("options", {}), **spec.get("params", {}), **params)
    key = _canon(name)
    if key not in MODELS:
        raise _unknown("model", str(name), available())
    return MODELS[key](**params)

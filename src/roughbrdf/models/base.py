"""The model base class and its one public evaluation interface; sums of models; the registry.

A model is pure: parameters in, values out. It knows nothing about fitting; a fitter reads
``parameters`` (value, bounds, unit) and rebuilds the model with :meth:`Model.with_values`.

Evaluation
----------
:meth:`Model.evaluate` is the one public evaluation method: angles (radians, the library's
frame, ``docs/models.md`` §1.1), a :class:`~roughbrdf.quantity.Quantity` and a
:class:`~roughbrdf.polarization.Polarization` (or anything :meth:`Polarization.parse` takes).
:meth:`Model.brdf` and :meth:`Model.bridf` are shorthands. For repeated calls on the same
samples (a fit), :meth:`Model.prepare` validates and broadcasts the inputs once and
:meth:`Model.evaluate_prepared` evaluates on the result.

Every model supplies one compiled scalar function ``point(theta_i, theta_r, phi, gamma, p, flag)``
returning the BRDF (``flag = 0``) or ``f_r cos(theta_r)`` (``flag = 1``) for the packed numeric
parameter tuple ``p`` (``_pack``), and a module-level parallel loop over it (``_drive``, a
:func:`roughbrdf._kernels.driver`); :func:`roughbrdf._kernels.evaluate` broadcasts NumPy inputs
onto it.

A polarimetric setting (an incident Stokes vector, an analyzer row) is evaluated through
:meth:`Model.mueller` by :func:`roughbrdf.models.polarimetry.evaluate_stokes`, which
:meth:`Model.evaluate` calls.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .. import _kernels
from ..errors import ArgumentError
from ..geometry import check_angles, check_broadcast
from ..polarization import Polarization
from ..quantity import Quantity
from ..registry import Registry, unknown_name
from .parameters import Parameter, ReadOnlyDict
from .polarimetry import evaluate_stokes

__all__ = ["Model", "NoMuellerMatrix", "PreparedGeometry", "SumModel", "components", "MODELS",
           "register", "require_index"]


class NoMuellerMatrix(NotImplementedError, ValueError):
    """The model has no Mueller matrix (:meth:`Model.mueller`). A ``NotImplementedError`` for
    Python and, since asking for one is a usage error, a ``ValueError`` (the command line's
    exit status 2)."""


@dataclass(frozen=True)
class PreparedGeometry:
    """Validated, broadcastable float64 inputs of an evaluation (:meth:`Model.prepare`).

    Attributes
    ----------
    theta_i, theta_r, phi : numpy.ndarray
        Angles in radians (checked against the model's domain; ``phi`` reduced).
    gamma : numpy.ndarray
        TR75's polarization angle per sample, NaN = unpolarized
        (:class:`~roughbrdf.polarization.Polarization`).
    """

    theta_i: np.ndarray
    theta_r: np.ndarray
    phi: np.ndarray
    gamma: np.ndarray

    @property
    def shape(self) -> tuple[int, ...]:
        """The broadcast shape of the samples."""
        return np.broadcast_shapes(self.theta_i.shape, self.theta_r.shape, self.phi.shape,
                                   self.gamma.shape)

    def specular(self) -> PreparedGeometry:
        """The specular direction (``theta_r = theta_i``, ``phi = 0``) of each sample."""
        return PreparedGeometry(self.theta_i, self.theta_i, np.zeros_like(self.theta_i),
                                self.gamma)


class Model:
    """Base class of every BRDF model.

    Subclasses define ``name``, ``short`` (prefix in sums), ``reference``, ``PARAMETERS`` (a tuple
    of :class:`Parameter` with default values), optional ``OPTIONS`` (non-numeric settings with
    defaults), ``grazing_incidence`` (whether theta_i = pi/2 is allowed), ``_pack`` (the numeric
    parameters as a tuple of floats) and ``_drive`` (the compiled driver, see
    :mod:`roughbrdf._kernels.compile`); a model with its own evaluation path overrides
    ``_kernel`` instead.

    A model is an **immutable value**: its parameters and options are set when it is built
    (validated against each parameter's physical domain) and never change afterwards. A sum
    keeps copies of its components, a fit keeps the model it started from and the fitted one,
    and compiled evaluations pack the values once; changing a model in place would silently
    leave those out of step. So assignment raises instead of doing nothing:
    ``m.params["e"] = 0.1`` (and ``m.options[...] = ...``) raises ``TypeError`` and ``m.e = 0.1``
    (any attribute named like a parameter or option) raises ``AttributeError``, both naming
    :meth:`with_params`, which returns a validated copy.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("lambertian", rho=0.5)
    >>> m.rho = 0.2
    Traceback (most recent call last):
    ...
    AttributeError: cannot set 'rho' on a lambertian model: ... use m = m.with_params(rho=...) ...
    >>> m.with_params(rho=0.2).params
    {'rho': 0.2}
    """

    name: ClassVar[str] = ""
    aliases: ClassVar[tuple[str, ...]] = ()
    short: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    PARAMETERS: ClassVar[tuple[Parameter, ...]] = ()
    OPTIONS: ClassVar[dict[str, Any]] = {}
    grazing_incidence: ClassVar[bool] = False
    reciprocal: ClassVar[bool] = True
    TERMS: ClassVar[tuple[str, ...]] = ()
    #: the module-level parallel loop over the model's scalar kernel
    #: (:func:`roughbrdf._kernels.driver`): vectorized and cached on disk
    _drive: ClassVar[Callable | None] = None

    def __init__(self, **kwargs: Any) -> None:
        # options first: a model's parameters may depend on them (coated ``lobes``, ``diffuse``)
        options = dict(self._option_defaults())
        options.update({k: v for k, v in kwargs.items() if k in options})
        self._options = self._check_options(options)
        self._specs = self._parameter_specs()
        specs = {p.name: p for p in self._specs}
        values: dict[str, float | None] = {n: p.value for n, p in specs.items()}
        for key, val in kwargs.items():
            if key in specs:
                values[key] = specs[key].check(val)
            elif key not in options:
                raise unknown_name(f"parameter for model {self.name!r}", key,
                                   [*specs, *options])
        self._values = values
        self._validate()

    # -- hooks ----------------------------------------------------------------------------------
    def _parameter_specs(self) -> tuple[Parameter, ...]:
        """The parameters for the model's options (``self._options`` is set when called)."""
        return self.PARAMETERS

    def _option_defaults(self) -> dict[str, Any]:
        return dict(self.OPTIONS)

    def _check_options(self, options: dict[str, Any]) -> dict[str, Any]:
        return options

    def _validate(self) -> None:
        """Cross-parameter checks (after each parameter passed its own domain check)."""

    def _pack(self) -> tuple:
        raise NotImplementedError

    # -- immutability ---------------------------------------------------------------------------
    def _guarded_names(self) -> set[str]:
        """Names whose assignment would look like changing the model: every parameter and
        option (for a sum, also the components' plain names), ``params`` and ``options``."""
        d = self.__dict__
        names = {p.name for p in type(self).PARAMETERS} | set(type(self).OPTIONS)
        names |= {p.name for p in d.get("_specs", ())} | set(d.get("_options", ()))
        for c in d.get("components", ()):
            names |= c._guarded_names()
        return names | {"params", "options", "parameters", "param_names"}

    def __setattr__(self, name: str, value: Any) -> None:
        if not name.startswith("_") and name in self._guarded_names():
            what = name if name not in ("params", "options", "parameters", "param_names") \
                else "name"
            raise AttributeError(
                f"cannot set {name!r} on a {self.name} model: models are immutable values; "
                f"use m = m.with_params({what}=...) for a validated copy")
        object.__setattr__(self, name, value)

    # -- parameters -----------------------------------------------------------------------------
    @property
    def params(self) -> ReadOnlyDict:
        """``{name: value}`` of the numeric parameters, read-only (see the class notes; a
        changed copy of the model is :meth:`with_params`, a changeable dict ``dict(m.params)``).
        """
        return ReadOnlyDict(self._values, "model parameters")

    def _floats(self) -> dict[str, float]:
        """The parameters that are set (not ``None``), as floats: what ``_pack`` packs."""
        return {k: v for k, v in self._values.items() if v is not None}

    @property
    def options(self) -> ReadOnlyDict:
        """Non-numeric settings (distribution, shadowing, readings), read-only."""
        return ReadOnlyDict(self._options, "model options")

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """The parameters as (frozen) :class:`Parameter` objects (value, bounds, unit,
        description, domain)."""
        return tuple(replace(p, value=self._values[p.name]) for p in self._specs)

    @property
    def param_names(self) -> list[str]:
        return [p.name for p in self._specs]

    @property
    def conserves_energy(self) -> bool:
        """Whether every parameter value of the domain keeps the albedo at most 1 (to
        ``1e-3``), by construction (``docs/models.md`` §10.4): the fits' energy constraint
        then has nothing to check. False unless a model says so."""
        return False

    def with_params(self, **updates: Any) -> Model:
        """A copy with some parameters (or options) changed.

        Parameters that a changed option removes (e.g. ``alpha2`` when a coated model goes
        from ``lobes=2`` to ``lobes=1``) are dropped; the ones it adds take their defaults.
        """
        options = {**self._options, **{k: v for k, v in updates.items() if k in self._options}}
        names = set(type(self)(**options).param_names) if options != self._options \
            else set(self._values)
        kept = {k: v for k, v in self._values.items() if k in names}
        return type(self)(**{**options, **kept, **updates})

    def with_values(self, names: Sequence[str], values: Sequence[float]) -> Model:
        """A copy with the named parameters set to ``values`` (validated)."""
        new = copy.copy(self)
        new._values = dict(self._values)
        specs = {p.name: p for p in self._specs}
        for nm, v in zip(names, values, strict=True):
            if nm not in specs:
                raise unknown_name(f"parameter for model {self.name!r}", nm, specs)
            new._values[nm] = specs[nm].check(v)
        new._validate()
        return new

    # -- evaluation -----------------------------------------------------------------------------
    def prepare(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
                polarization: Any = None) -> PreparedGeometry:
        """Validate and convert the inputs once, for repeated :meth:`evaluate_prepared` calls.

        Raises :class:`~roughbrdf.errors.ArgumentError` (a ``ValueError``) naming the argument
        and the offending value for angles that are not numbers (``None`` included) or outside
        the hemisphere (or ``theta_i = pi/2`` where the model is not defined there), for a bad
        polarization, and naming both arrays and their shapes when they do not broadcast.
        """
        ti, tr, ph = check_angles(theta_i, theta_r, phi,
                                  grazing_incidence=self.grazing_incidence)
        gamma = Polarization.parse(polarization).kernel_gamma()  # refuses Stokes/analyzer
        if gamma.ndim:
            check_broadcast(theta_i=ti, theta_r=tr, phi=ph, polarization=gamma)
        return PreparedGeometry(ti, tr, ph, gamma)

    def evaluate_prepared(self, geometry: PreparedGeometry, quantity: Quantity | str = "brdf",
                          *, term: str | None = None) -> np.ndarray | float:
        """Evaluate on inputs from :meth:`prepare` (see :meth:`evaluate` for ``quantity``)."""
        q = Quantity.parse(quantity)
        if q is Quantity.RELATIVE:
            num = self._kernel(geometry, 0, term)
            return num / self._kernel(geometry.specular(), 0, term)
        return self._kernel(geometry, 1 if q.cosine_weighted else 0, term)

    def evaluate(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike, *,
                 quantity: Quantity | str = "brdf", polarization: Any = None,
                 term: str | None = None) -> np.ndarray | float:
        """The model's value of ``quantity`` at the given geometries.

        Parameters
        ----------
        theta_i, theta_r : array_like
            Incidence and reflection zenith angles, radians, in [0, pi/2] (``theta_i < pi/2``
            for models that divide by ``cos theta_i``).
        phi : array_like
            Azimuth of the reflected ray, radians, 0 on the forward (specular) side.
        quantity : Quantity or str
            ``"brdf"`` (f_r, sr⁻¹), ``"brdf_cos"``/``"bridf"`` (f_r cos theta_r, sr⁻¹) or
            ``"relative"`` (f_r divided by f_r at the specular direction ``theta_r = theta_i,
            phi = 0`` of the same incidence; TS67 Eq. 23, ``docs/models.md`` §2.3).
        polarization : Polarization, None, "unpolarized", "s", "p", float or array
            Incident polarization (:class:`~roughbrdf.polarization.Polarization`): TR75's angle
            ``gamma`` of the electric field from the plane of incidence (radians); arrays give
            one polarization per sample. ``Polarization(stokes=S, analyzer=a)`` gives an
            incident Stokes vector and a detector row instead: the result is ``a · (M S)``
            with ``M`` = :meth:`mueller` (``docs/polarization.md``).
        term : str, optional
            A single term of a model that has several (e.g. RB08 ``"surface"``), or a
            component of a sum by its prefix.

        Returns
        -------
        numpy.ndarray or float
            Broadcast shape of the inputs; a float if every input was a scalar.

        Examples
        --------
        >>> import roughbrdf as rb
        >>> m = rb.model("lambertian", rho=0.5)
        >>> round(m.evaluate(0.3, 0.0, 0.0, quantity="brdf_cos"), 6)   # rho cos(0)/pi
        0.159155
        """
        pol = Polarization.parse(polarization)
        if pol.is_polarimetric:  # Stokes vector in, analyzer out: through self.mueller
            return evaluate_stokes(self, theta_i, theta_r, phi, pol, quantity=quantity,
                                   term=term)
        g = self.prepare(theta_i, theta_r, phi, pol)
        return self.evaluate_prepared(g, quantity, term=term)

    def brdf(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
             polarization: Any = None, *, term: str | None = None) -> np.ndarray | float:
        """Standard BRDF ``f_r`` in sr⁻¹: ``evaluate(..., quantity="brdf")``."""
        return self.evaluate(theta_i, theta_r, phi, quantity=Quantity.BRDF,
                             polarization=polarization, term=term)

    def bridf(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike,
              polarization: Any = None, *, term: str | None = None) -> np.ndarray | float:
        """TR75's BRIDF ``f_r cos(theta_r)`` in sr⁻¹ (finite at theta_r = pi/2)."""
        return self.evaluate(theta_i, theta_r, phi, quantity=Quantity.BRIDF,
                             polarization=polarization, term=term)

    __call__ = brdf

    def _kernel(self, g: PreparedGeometry, flag: int, term: str | None) -> np.ndarray | float:
        """The compiled evaluation (``flag`` 0: f_r, 1: f_r cos theta_r); models with terms or
        their own drivers override it."""
        if term is not None:
            raise ArgumentError("term", f"model {self.name!r} has no separate terms",
                                value=term)
        drive = type(self)._drive
        if drive is None:  # pragma: no cover - every registered model has a driver
            raise NotImplementedError(f"model {self.name!r} has no compiled driver")
        return _kernels.evaluate(drive, g.theta_i, g.theta_r, g.phi, g.gamma, self._pack(), flag)

    # -- Mueller matrices -----------------------------------------------------------------------
    def mueller(self, theta_i: ArrayLike, theta_r: ArrayLike, phi: ArrayLike, *,
                basis: str = "psps", term: str | None = None) -> np.ndarray:
        """The BRDF Mueller matrix in sr⁻¹, shape ``broadcast shape + (4, 4)``.

        ``S_r = M S_i`` for Stokes vectors ``[I, Q, U, V]`` (columns) of the incident
        irradiance and the reflected radiance; ``M[..., 0, 0]`` is the unpolarized
        :meth:`brdf`. Conventions (SCATMECH's: ``Q > 0`` is s, ``V > 0`` counter-clockwise
        seen looking toward the source) and bases in :mod:`roughbrdf.mueller`;
        ``docs/models.md`` §11.

        Parameters
        ----------
        theta_i, theta_r, phi : array_like
            Angles in radians as for :meth:`evaluate` (validated the same way).
        basis : {"psps", "xyxy"}
            ``"psps"``: the s/p basis of each direction (SCATMECH ``psps``); ``"xyxy"``: the
            reflected basis rotated by ``phi``, regular at the normal (SCATMECH ``xyxy``).
        term : str, optional
            A component of a sum, by its prefix (as for :meth:`evaluate`).

        Returns
        -------
        numpy.ndarray
            Shape ``broadcast shape + (4, 4)`` (``(4, 4)`` for scalar angles), sr⁻¹.

        Raises
        ------
        roughbrdf.errors.ArgumentError
            Bad angles or basis; a model whose Fresnel factor is switched off (``n=None``).
        NoMuellerMatrix
            (a ``NotImplementedError`` and a ``ValueError``) A model without a Mueller matrix
            (RB08: its Fresnel factor is macroscopic and unpolarized by construction,
            ``docs/models.md`` §4.9).

        Examples
        --------
        >>> import numpy as np, roughbrdf as rb
        >>> m = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=1.5, k=0.0)
        >>> M = m.mueller([0.2, 0.4], 0.5, 1.0)
        >>> M.shape
        (2, 4, 4)
        >>> bool(np.allclose(M[..., 0, 0], m.brdf([0.2, 0.4], 0.5, 1.0)))
        True
        """
        g = self.prepare(theta_i, theta_r, phi)
        from ..mueller import basis_code  # the Mueller machinery loads only when used

        return self._mueller(g, basis_code(basis), term)

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        """The Mueller matrix hook (``basis``: a :mod:`roughbrdf.mueller` code); models with
        one override it."""
        raise NoMuellerMatrix(
            f"model {self.name!r} has no Mueller matrix: the facet models (microfacet, "
            f"torrance-sparrow-1967, trowbridge-reitz-1975, coated), lambertian, oren-nayar "
            f"and their sums have one")

    def _mueller_drive(self, drive: Callable, g: PreparedGeometry, params: tuple, basis: int,
                       term: str | None) -> np.ndarray:
        """Run a compiled Mueller driver ``drive(a, b, c, g, params, basis, out)`` (out of shape
        ``(size, 4, 4)``) on prepared angles; ``term`` must be ``None`` as for ``_kernel``."""
        if term is not None:
            raise ArgumentError("term", f"model {self.name!r} has no separate terms",
                                value=term)
        nan = np.asarray(np.nan)  # the polarization slot of the driver: unused
        return np.asarray(_kernels.evaluate(drive, g.theta_i, g.theta_r, g.phi, nan, params,
                                            basis, out_shape=(4, 4)))

    def _mueller_depolarizer(self, g: PreparedGeometry, term: str | None) -> np.ndarray:
        """An ideal depolarizer times the unpolarized BRDF (Lambertian-like terms)."""
        from ..mueller import depolarizer

        return depolarizer(self._kernel(g, 0, term))

    # -- composition and description ------------------------------------------------------------
    def __add__(self, other: Model) -> SumModel:
        if not isinstance(other, Model):
            return NotImplemented
        return SumModel([*components(self), *components(other)])

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

    def _repr_html_(self) -> str:
        """Jupyter's rich display: name, reference, parameters, options
        (:func:`roughbrdf.html_repr.model_html`, registered from above:
        :mod:`roughbrdf.rich_display`; a sum, one block per component)."""
        from ..rich_display import html

        return html("model", self)


def require_index(model: Model) -> None:
    """Raise :class:`~roughbrdf.errors.ArgumentError` naming ``n`` for a model built with
    ``n=None`` (``F = 1``), which has no polarization physics, hence no Mueller matrix."""
    if model.params["n"] is None:
        raise ArgumentError("n", f"model {model.name!r} was built with n=None (F = 1): a "
                            "facet without a complex index has no polarization physics and no "
                            "Mueller matrix; give n (and k)", value=None)


# --------------------------------------------------------------------------------------------
# sums of models: m1 + m2 adds BRDFs; parameter names are prefixed per component
# --------------------------------------------------------------------------------------------
def components(m: Model) -> list[Model]:
    """The terms of ``m``: its components if it is a sum, else ``[m]``."""
    return list(m.components) if isinstance(m, SumModel) else [m]


class SumModel(Model):
    """Sum of models; parameter names are prefixed ``<short>_<name>`` (``<short><i>_`` if repeated).
    """

    name = "sum"
    short = "sum"

    def __init__(self, components: Sequence[Model]) -> None:  # noqa: D107
        self.components = tuple(copy.copy(c) for c in components)
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
        raise unknown_name("parameter for this sum of models", name, [p.name for p in self._specs])

    def with_values(self, names: Sequence[str], values: Sequence[float]) -> SumModel:
        groups: dict[int, tuple[list[str], list[float]]] = {}
        for nm, v in zip(names, values, strict=True):
            i, base = self._split(nm)
            groups.setdefault(i, ([], []))[0].append(base)
            groups[i][1].append(v)
        new = copy.copy(self)
        new.components = tuple(c.with_values(*groups[i]) if i in groups else c
                               for i, c in enumerate(self.components))
        new._refresh()
        return new

    def with_params(self, **updates: Any) -> SumModel:
        return self.with_values(list(updates), list(updates.values()))

    def _kernel(self, g: PreparedGeometry, flag: int, term: str | None
                ) -> np.ndarray | float:
        q = Quantity.BRDF_COS if flag else Quantity.BRDF
        parts = []
        for c, pre in zip(self.components, self.prefixes, strict=True):
            if term is None:
                parts.append(c.evaluate_prepared(g, q))
            elif term in c.TERMS:
                parts.append(c.evaluate_prepared(g, q, term=term))
            elif term in (c.short, c.name, pre[:-1]):
                parts.append(c.evaluate_prepared(g, q))
        if not parts:
            raise ArgumentError("term", "no component of this sum has this term", value=term)
        return sum(parts[1:], parts[0])

    def _mueller(self, g: PreparedGeometry, basis: int, term: str | None) -> np.ndarray:
        # the components' matrices added, with the term selection of _kernel
        parts = []
        for c, pre in zip(self.components, self.prefixes, strict=True):
            if term is None:
                parts.append(c._mueller(g, basis, None))
            elif term in c.TERMS:
                parts.append(c._mueller(g, basis, term))
            elif term in (c.short, c.name, pre[:-1]):
                parts.append(c._mueller(g, basis, None))
        if not parts:
            raise ArgumentError("term", "no component of this sum has this term", value=term)
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
#: every registered model class by canonical name and alias
MODELS: Registry[type[Model]] = Registry("model")


def register(cls: type[Model]) -> type[Model]:
    """Class decorator: register a model under its ``name`` and ``aliases``."""
    MODELS.add(cls.name, cls, cls.aliases)
    return cls

"""Named model parameters: value, search bounds, unit, description and physical domain.

Reflectance-like parameters
---------------------------
Every parameter that is the directional-hemispherical reflectance (albedo) of a part of a model
has **one** physical domain, :data:`REFLECTANCE_DOMAIN` = ``[0, 1]``, built by
:func:`reflectance` and marked ``kind="reflectance"``: Lambertian ``rho``, TR75 ``rho_L``, TS67
``rho_d`` (its diffuse part is ``rho_d/pi``), RB08 ``bulk`` and ``retro`` (the bulk and retro
parts reflect ``(1 - sigma_s) bulk`` and ``(1 - sigma_s) retro``). 0 switches the part off; above
1 the part alone would reflect more light than it receives. Scales that are not a part's
reflectance keep their own domains: microfacet ``ks`` (a free scale of the specular term, 1 for
a physical surface; larger for data of unknown scale), TS67 ``g`` (a ratio), and RB08 ``rho``,
``rho_r`` (lobe widths).

Read-only values
----------------
:class:`ReadOnlyDict` is what :attr:`Model.params <roughbrdf.models.Model.params>` and
:attr:`Model.options <roughbrdf.models.Model.options>` return: a ``dict`` (JSON, ``==``, ``**``
and ``dict(...)`` work) whose item assignment raises ``TypeError`` pointing to
``with_params``, so that ``m.params["e"] = 0.1`` cannot silently do nothing.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, NoReturn

from ..errors import ArgumentError

__all__ = ["Parameter", "option_flag", "REFLECTANCE_DOMAIN", "ReadOnlyDict", "nonnegative",
           "positive", "reflectance"]

#: the one physical domain of every reflectance-like parameter, ``[0, 1]``
#: (``(low, low_inclusive, high, high_inclusive)``)
REFLECTANCE_DOMAIN: tuple[float, bool, float, bool] = (0.0, True, 1.0, True)


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
    kind : str
        ``"reflectance"`` for the directional-hemispherical reflectance of a part of the model
        (domain :data:`REFLECTANCE_DOMAIN`, see the module notes), else ``""``.
    neutral : float or None
        A value inside the search range where the parameter's part of the model can vanish
        (TR75's ``n = 1`` with ``k = 0``: the index matched, no Fresnel reflection): a fit's
        end near it is tried on it (:func:`~roughbrdf.fitting.solvers.stationary.snap`), as an
        end near a bound is. None: no such value.
    """

    name: str
    value: float | None
    bounds: tuple[float, float]
    unit: str = ""
    description: str = ""
    domain: tuple[float, bool, float, bool] = (-math.inf, False, math.inf, False)
    optional: bool = False
    kind: str = ""
    neutral: float | None = None

    def check(self, value: Any) -> float | None:
        """Validate ``value`` against the domain; return it as float (or None).

        Raises
        ------
        roughbrdf.errors.ArgumentError
            (a ``ValueError``) naming the parameter and the value: ``None`` for a parameter
            that is not optional, something that is not a real number, or a value outside the
            physical domain.
        """
        if value is None:
            if self.optional:
                return None
            raise ArgumentError(self.name, f"parameter {self.name!r} cannot be None (it is not "
                                f"optional)", value=None)
        if isinstance(value, numbers.Complex) and not isinstance(value, numbers.Real):
            raise ArgumentError(self.name, f"parameter {self.name!r} must be a real number",
                                value=value)
        try:
            v = float(value)
        except (TypeError, ValueError, OverflowError):
            raise ArgumentError(self.name, f"parameter {self.name!r} must be a number",
                                value=value) from None
        lo, lo_inc, hi, hi_inc = self.domain
        ok = (math.isfinite(v) and (v >= lo if lo_inc else v > lo)
              and (v <= hi if hi_inc else v < hi))
        if not ok:
            raise ArgumentError(
                self.name, f"parameter {self.name!r} is outside its physical domain "
                f"{self.domain_text()}" + (f" ({self.description})" if self.description else ""),
                value=v)
        return v

    def domain_text(self) -> str:
        """The domain as an interval, e.g. ``"[0, 1]"`` or ``"(0, inf)"``."""
        lo, lo_inc, hi, hi_inc = self.domain
        return ("[" if lo_inc else "(") + f"{lo:g}, {hi:g}" + ("]" if hi_inc else ")")


def positive(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
             **kw: Any) -> Parameter:
    """A parameter that must be > 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, False, math.inf, False), **kw)


def nonnegative(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str,
                **kw: Any) -> Parameter:
    """A parameter that must be >= 0."""
    return Parameter(name, default, bounds, unit, desc, (0.0, True, math.inf, False), **kw)


def reflectance(name: str, default: float, desc: str,
                bounds: tuple[float, float] = (0.0, 1.0)) -> Parameter:
    """A reflectance-like parameter: domain :data:`REFLECTANCE_DOMAIN` (``[0, 1]``), unit 1.

    ``bounds`` is the default search range of fits (inside ``[0, 1]``).

    Examples
    --------
    >>> p = reflectance("rho", 0.5, "directional-hemispherical reflectance")
    >>> p.domain == REFLECTANCE_DOMAIN, p.kind, p.check(1.0)
    (True, 'reflectance', 1.0)
    """
    return Parameter(name, default, bounds, "1", desc, REFLECTANCE_DOMAIN, kind="reflectance")



class ReadOnlyDict(dict):
    """A ``dict`` that cannot be changed in place: what ``Model.params`` and ``Model.options``
    return.

    Models are immutable values (shared by sums, fits and results), so changing a copy of
    their values would do nothing; assignment raises ``TypeError`` naming
    ``with_params`` instead. ``dict(view)`` gives an ordinary, changeable copy.

    Examples
    --------
    >>> d = ReadOnlyDict({"e": 0.68}, owner="model parameters")
    >>> d["e"] = 0.1
    Traceback (most recent call last):
    ...
    TypeError: model parameters are read-only: ... use m = m.with_params(e=...) for a changed copy
    >>> d == {"e": 0.68}, dict(d) | {"e": 0.1}
    (True, {'e': 0.1})
    """

    def __init__(self, data: Any = (), owner: str = "model parameters") -> None:
        super().__init__(data)
        self._owner = owner

    def _refuse(self, key: Any = None) -> NoReturn:
        hint = f"{key}=..." if isinstance(key, str) and key.isidentifier() else "name=..."
        raise TypeError(f"{self._owner} are read-only: a model is an immutable value; use "
                        f"m = m.with_params({hint}) for a changed copy")

    def __setitem__(self, key: Any, value: Any) -> NoReturn:
        self._refuse(key)

    def __delitem__(self, key: Any) -> NoReturn:
        self._refuse(key)

    def __ior__(self, other: Any) -> NoReturn:  # type: ignore[misc]
        self._refuse()

    def clear(self) -> NoReturn:
        self._refuse()

    def pop(self, key: Any, *default: Any) -> NoReturn:
        self._refuse(key)

    def popitem(self) -> NoReturn:
        self._refuse()

    def setdefault(self, key: Any, default: Any = None) -> NoReturn:
        self._refuse(key)

    def update(self, *args: Any, **kwargs: Any) -> NoReturn:
        self._refuse(next(iter(kwargs), None))

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (dict(self), self._owner))

    def __copy__(self) -> ReadOnlyDict:
        return type(self)(self, self._owner)

    def __deepcopy__(self, memo: dict) -> ReadOnlyDict:
        import copy

        return type(self)(copy.deepcopy(dict(self), memo), self._owner)


def option_flag(value: Any, name: str) -> bool:
    """A model's boolean option given as a bool or as ``"true"``/``"false"``/``"1"``/``"0"``
    (a spec or the command line gives text); a ValueError naming the option otherwise.

    Examples
    --------
    >>> option_flag("True", "diffuse"), option_flag(False, "diffuse")
    (True, False)
    >>> option_flag("yes", "diffuse")
    Traceback (most recent call last):
    ...
    ValueError: diffuse must be true or false, got 'yes'
    """
    if isinstance(value, str) and value.strip().lower() in ("true", "false", "1", "0"):
        value = value.strip().lower() in ("true", "1")
    if not isinstance(value, bool):
        raise ValueError(f"{name} must be true or false, got {value!r}")
    return value

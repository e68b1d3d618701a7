"""Building models by name: ``rb.model("tr75")``, sums from ``"tr75+lambertian"``, and the
mapping of user-typed parameter names onto a model's (prefixed) names."""

from __future__ import annotations

from typing import Any

from ..registry import unknown_name
from .base import MODELS, Model, SumModel

__all__ = ["available", "model", "resolve_names"]


def available() -> list[str]:
    """Canonical names of the registered models."""
    return MODELS.names()


def model(name: str | dict, **params: Any) -> Model:
    """Build a registered model by name (case-insensitive; aliases accepted), or a sum.

    ``name`` may be ``"NAME+NAME+..."``: the sum of the named models, with each setting given
    either by its prefixed name (``tr75_e``, as :attr:`Model.params` of the sum shows it) or by
    a plain parameter or option name that belongs to exactly one component
    (``distribution="beckmann"``). A dict from :meth:`Model.to_dict` rebuilds that model.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33)
    >>> round(m.bridf(0.0, 0.0, 0.0), 5)      # TR75 cement, normal incidence and view
    0.13402
    >>> s = rb.model("tr75+lambertian", tr75_e=0.3, rho=0.1)
    >>> s.params["tr75_e"], s.params["lambertian_rho"]
    (0.3, 0.1)
    """
    if isinstance(name, dict):  # from to_dict()
        return _from_dict(name, params)
    names = [s.strip() for s in str(name).split("+")]
    if not all(names):
        raise ValueError(f"bad model {name!r}: expected NAME or NAME+NAME")
    if len(names) == 1:
        return MODELS.get(names[0])(**params)
    return _sum_from_names(str(name), names, params)


def _from_dict(spec: dict, params: dict[str, Any]) -> Model:
    spec = dict(spec)
    if spec.get("model") == "sum":
        parts = [model(c) for c in spec["components"]]
        return SumModel(parts)
    return model(spec["model"], **spec.get("options", {}), **spec.get("params", {}), **params)


def _sum_from_names(spec: str, names: list[str], params: dict[str, Any]) -> SumModel:
    defaults = [model(n) for n in names]
    total = SumModel(defaults)
    per: list[dict[str, Any]] = [{} for _ in names]
    for key, val in params.items():
        hit = [i for i, pre in enumerate(total.prefixes)
               if key.startswith(pre) and key[len(pre):] in defaults[i].params]
        if hit:
            per[hit[0]][key[len(total.prefixes[hit[0]]):]] = val
            continue
        hit = [i for i, d in enumerate(defaults) if key in d.params or key in d.options]
        if len(hit) == 1:
            per[hit[0]][key] = val
        elif not hit:
            raise unknown_name("parameter", key, total.param_names)
        else:
            raise ValueError(f"{key!r} is ambiguous in {spec}; use one of "
                             + ", ".join(total.prefixes[i] + key for i in hit))
    return SumModel([model(n, **kw) for n, kw in zip(names, per, strict=True)])


def resolve_names(m: Model, names: list[str]) -> list[str]:
    """Map user-typed parameter names to ``m``'s own (plain names allowed in sums).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> resolve_names(rb.model("tr75+lambertian"), ["e", "lambertian_rho"])
    ['tr75_e', 'lambertian_rho']
    """
    out = []
    prefixes = m.prefixes if isinstance(m, SumModel) else []
    for nm in names:
        if nm in m.param_names:
            out.append(nm)
            continue
        hit = [pre + nm for pre in prefixes if pre + nm in m.param_names]
        if len(hit) == 1:
            out.append(hit[0])
        elif hit:
            raise ValueError(f"{nm!r} is ambiguous; use one of {', '.join(hit)}")
        else:
            raise unknown_name("parameter", nm, m.param_names)
    return out

"""Building and naming models: ``rb.model("tr75")``, sums from ``"tr75+lambertian"``, one-line
specs (:func:`from_spec`, :func:`spec_text`), the mapping of user-typed parameter names onto a
model's (prefixed) names, and what a fit is given as its model (:func:`as_model`,
:func:`model_label`, the ``"auto"`` pseudo-model: :func:`is_auto`)."""

from __future__ import annotations

from typing import Any

from ..registry import unknown_name
from .base import MODELS, Model, SumModel

__all__ = ["AUTO", "as_model", "available", "from_spec", "is_auto", "model", "model_label",
           "resolve_names", "spec_text", "split_specs"]

#: the pseudo-model of ``rb.fit("auto", ...)``: the candidates of model choice, best by
#: cross-validation
AUTO = "auto"


def available() -> list[str]:
    """Canonical names of the registered models."""
    return MODELS.names()


def model(name: str | dict, **params: Any) -> Model:
    """Build a registered model by name (case-insensitive; aliases accepted), or a sum.

    ``name`` may be a spec with settings, ``"coated(lobes=2)"`` (:func:`from_spec`), or
    ``"NAME+NAME+..."``: the sum of the named models, with each setting given
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
    if "(" in str(name):  # a spec with settings, "coated(lobes=2)" (from_spec)
        built = from_spec(str(name))
        return built.with_params(**params) if params else built
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
        # options by the class's declared OPTIONS: a model may leave an option at its
        # default out of .options (coated "interface")
        hit = [i for i, d in enumerate(defaults)
               if key in d.params or key in d.options or key in type(d).OPTIONS]
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


def _split_top(text: str, sep: str) -> list[str]:
    """``text`` split at ``sep`` outside parentheses."""
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if ch == sep and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    return [*parts, cur]


def _value(text: str) -> Any:
    """A setting typed in a spec: int, float, true/false/none, else the text."""
    t = text.strip()
    low = t.lower()
    if low in ("true", "false"):
        return low == "true"
    if low == "none":
        return None
    for conv in (int, float):
        try:
            return conv(t)
        except ValueError:
            pass
    return t


def from_spec(text: str) -> Model:
    """A model from a one-line spec: ``NAME(key=value, ...)``, sums joined by ``+``.

    The form :func:`spec_text` writes, and what ``roughbrdf compare --models`` takes
    (candidates separated by ``;`` or ``,`` outside parentheses there).

    Examples
    --------
    >>> m = from_spec("coated(lobes=2, distribution=beckmann)")
    >>> m.options["lobes"], m.options["distribution"]
    (2, 'beckmann')
    >>> from_spec("tr75 + lambertian(rho=0.1)").params["lambertian_rho"]
    0.1
    """
    terms = [t.strip() for t in _split_top(str(text), "+")]
    parts = []
    for term in terms:
        name, _, rest = term.partition("(")
        if not name.strip() or (rest and not rest.rstrip().endswith(")")):
            raise ValueError(f"bad model spec {text!r}: expected NAME or NAME(key=value, ...), "
                             f"sums joined by '+'")
        kwargs: dict[str, Any] = {}
        for item in _split_top(rest.rstrip()[:-1], ",") if rest else []:
            if not item.strip():
                continue
            key, eq, val = item.partition("=")
            if not eq or not key.strip():
                raise ValueError(f"bad setting {item.strip()!r} in model spec {text!r}: "
                                 f"expected key=value")
            kwargs[key.strip()] = _value(val)
        parts.append(model(name.strip(), **kwargs))
    return parts[0] if len(parts) == 1 else SumModel(parts)


def spec_text(m: Model) -> str:
    """The short spec of a model: its name and the options that differ from the defaults.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> spec_text(rb.model("coated", lobes=2, distribution="beckmann"))
    'coated(distribution=beckmann, lobes=2)'
    >>> spec_text(rb.model("tr75") + rb.model("lambertian"))
    'trowbridge-reitz-1975+lambertian'
    """
    if isinstance(m, SumModel):
        return "+".join(spec_text(c) for c in m.components)
    default = type(m)().options
    changed = [f"{k}={v}" for k, v in m.options.items() if default.get(k) != v]
    return m.name + (f"({', '.join(changed)})" if changed else "")


def split_specs(text: str) -> list[str]:
    """Model specs separated by ``;`` or by ``,`` outside parentheses.

    Examples
    --------
    >>> split_specs("tr75, coated(lobes=2, distribution=beckmann);lambertian")
    ['tr75', 'coated(lobes=2, distribution=beckmann)', 'lambertian']
    """
    out = []
    for part in str(text).split(";"):
        out += [s.strip() for s in _split_top(part, ",") if s.strip()]
    return out


def is_auto(model: object) -> bool:
    """Whether ``model`` is the ``"auto"`` pseudo-model (any case, spaces around ignored).

    Examples
    --------
    >>> is_auto(" Auto "), is_auto("tr75"), is_auto(None)
    (True, False, False)
    """
    return isinstance(model, str) and model.strip().lower() == AUTO


def as_model(model: Model | str) -> Model:
    """``model`` itself, or the model of that name or spec (``"a+b"``, ``"coated(lobes=2)"``)."""
    if isinstance(model, str):
        model = from_spec(model)
    if not isinstance(model, Model):
        raise TypeError(f"model must be a roughbrdf Model or a model name, got {type(model)}")
    return model


def model_label(m: Model) -> str:
    """``"a+b"`` for a sum, else the model's name.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> model_label(rb.model("trowbridge-reitz-1975") + rb.model("lambertian"))
    'trowbridge-reitz-1975+lambertian'
    """
    comps = getattr(m, "components", None)
    return "+".join(c.name for c in comps) if comps else m.name

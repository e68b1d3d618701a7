"""What ``roughbrdf explore`` shows: the inputs of a run (:class:`Session`) and the model the
page's controls describe.

A :class:`Session` holds a measurement (``FILE``), a model (``--model SPEC -p ...``) and a
fit's models (``--fit DIR``), any of them absent, and the one error that stopped loading
(shown in the terminal and on the page, never a traceback). Angles are radians here as in the
library; the page shows parameters whose unit is an angle in degrees, as the command line does
(:func:`roughbrdf.wording.cli_unit`). Nothing here imports Dash.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model, Parameter

__all__ = ["Session", "load_session", "option_choices", "shown_value", "shown_unit",
           "model_from_controls", "slider_range"]

#: the unit of parameters shown in degrees on the page
ANGLE_UNIT = "rad"
#: the command line options that loading errors name (:func:`load_session`)
CLI_OPTIONS = {"format": "--format"}


@dataclass
class Session:
    """The inputs of one ``roughbrdf explore`` run.

    Attributes
    ----------
    model : Model or None
        The model the controls start from (``--model``, else the fit's first channel).
    measurement : Measurement or None
    fit_models : dict of str to Model
        The fitted model of each channel of ``--fit`` (empty without one).
    fit_report : str
        The fit's report text ("" without one).
    out : pathlib.Path or None
        The one folder exports go into (``--out``); None refuses exports.
    error : str
        What stopped loading ("" when all went well).
    label : str
        What the page's title names (the file, the fit folder, the model).
    """

    model: Model | None = None
    measurement: Measurement | None = None
    fit_models: dict[str, Model] = field(default_factory=dict)
    fit_report: str = ""
    out: Path | None = None
    error: str = ""
    label: str = "roughbrdf explore"


def _fit_inputs(fit_dir: str) -> tuple[dict[str, Model], Measurement, str]:
    """The fitted models, the measurement and the report of a fit folder: ``rb.load_fit`` when
    the library has it, else ``fit.json`` and the measurement at its recorded path; the
    folder checked first (:func:`roughbrdf.result_check.check_result_folder`)."""
    import roughbrdf as rb

    from ..result_check import check_result_folder

    where = Path(fit_dir)
    # one whole set (a cut-off write recovered) or refused, worded for the command line (the
    # options load_session words its errors with)
    check_result_folder(where if where.is_dir() else where.parent, options=CLI_OPTIONS)

    loader = getattr(rb, "load_fit", None)
    if loader is not None:
        res = loader(fit_dir)
        models = {str(c.channel): c.model for c in res.channels}
        return models, res.measurement, res.report()
    from ..fitting.results.fit_json import fitted_models, read_fit_json

    content, folder = read_fit_json(fit_dir)
    models = fitted_models(fit_dir)
    recorded = content.get("file_abspath") or str(folder / str(content["file"]))
    if not Path(recorded).is_file():
        raise FileNotFoundError(f"--fit {fit_dir}: the fit's measurement {recorded} is gone "
                                "(moved or deleted); the fit cannot be shown with its data")
    options = {k: content[k] for k in ("quantity",) if content.get(k)}
    try:
        meas = rb.read(recorded, **options)
    except ValueError:  # the file says its quantity itself
        meas = rb.read(recorded)
    report = folder / "report.txt"
    return models, meas, report.read_text(encoding="utf-8") if report.is_file() else ""


def load_session(file: str | None = None, *, fit_dir: str | None = None,
                 model: str | None = None, params: dict[str, Any] | None = None,
                 out: str | None = None, format: str | None = None) -> Session:
    """Load the inputs of a run; an error becomes :attr:`Session.error` (one line, the
    command line's wording: :func:`roughbrdf.wording.error_message`).

    Examples
    --------
    >>> s = load_session(model="lambertian", params={"rho": 0.3})
    >>> s.model.params, s.error
    ({'rho': 0.3}, '')
    >>> load_session("no/such/file.astm").error
    'no/such/file.astm: no such file'
    """
    import roughbrdf as rb

    from ..wording import error_message, model_in_degrees

    session = Session(out=Path(out).resolve() if out else None)
    labels = [f"fit {fit_dir}"] * (fit_dir is not None) + [str(file)] * (file is not None) \
        + [str(model)] * (model is not None)
    session.label = " - ".join(labels) or session.label
    try:
        if fit_dir is not None:
            session.fit_models, session.measurement, session.fit_report = _fit_inputs(fit_dir)
            session.model = next(iter(session.fit_models.values()))
        if file is not None:
            session.measurement = rb.read(file, format=format)
        if model is not None:
            session.model = model_in_degrees(model, params)
    except Exception as exc:  # noqa: BLE001 - every failure is the page's one message
        session.error = error_message(exc, CLI_OPTIONS)
    return session


def option_choices(model: Model) -> dict[str, list[Any]]:
    """The values each option of ``model`` may take: ``{option: [values]}``.

    Candidates are the registered distributions and shadowing functions, the coated
    ``lobes`` and ``diffuse`` kinds and booleans; each is kept only if the model accepts it
    with its other options as they are (the model's own checks decide). A sum has no options
    of its own here.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> option_choices(rb.model("coated"))["lobes"]
    [1, 2, 3]
    """
    from .. import distributions, shadowing

    current = dict(model.options)
    if not current or getattr(model, "components", None):
        return {}
    candidates: dict[str, list[Any]] = {"distribution": distributions.names(),
                                        "shadowing": shadowing.names(), "lobes": [1, 2, 3],
                                        "diffuse": ["lambertian", "oren-nayar"]}
    out: dict[str, list[Any]] = {}
    for name, value in current.items():
        pool = [True, False] if isinstance(value, bool) else candidates.get(name, [value])
        kept = []
        for cand in pool:
            try:
                type(model)(**{**current, name: cand})
            except (ValueError, TypeError):  # the model refuses it with these options
                continue
            kept.append(cand)
        out[name] = kept if value in kept else [value, *kept]
    return out


def shown_unit(p: Parameter) -> str:
    """The unit the page shows (``deg`` for angles, ``1`` dimensionless)."""
    return "deg" if p.unit == ANGLE_UNIT else (p.unit or "1")


def shown_value(p: Parameter, value: float | None) -> float | None:
    """A value of ``p`` as the page shows it (radians -> degrees)."""
    if value is None or p.unit != ANGLE_UNIT:
        return value
    return math.degrees(value)


def slider_range(p: Parameter) -> tuple[float, float]:
    """The slider's ends: the parameter's search bounds, as shown."""
    lo, hi = p.bounds
    a, b = shown_value(p, lo), shown_value(p, hi)
    return float(a if a is not None else lo), float(b if b is not None else hi)


def model_from_controls(base: Model, values: dict[str, Any], options: dict[str, Any]
                        ) -> tuple[Model, dict[str, str]]:
    """``base`` with the page's ``options`` and parameter ``values`` (as shown: angles in
    degrees; "" or None for an optional part switched off); and ``{name: message}`` for each
    value the parameter refuses (those keep ``base``'s value).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m, bad = model_from_controls(rb.model("lambertian"), {"rho": 1.5}, {})
    >>> m.params["rho"], sorted(bad)
    (0.5, ['rho'])
    """
    model = base.with_params(**options) if options and dict(base.options) != {
        **base.options, **options} else base
    specs = {p.name: p for p in model.parameters}
    good: dict[str, float | None] = {}
    bad: dict[str, str] = {}
    for name, raw in values.items():
        p = specs.get(name)
        if p is None:  # a control of parameters an option change removed
            continue
        try:
            value = None if raw in (None, "") else float(raw)
            if value is not None and p.unit == ANGLE_UNIT:
                value = math.radians(value)
            good[name] = p.check(value)
        except (ValueError, TypeError) as exc:
            bad[name] = " ".join(str(exc).split()).replace("physical domain", "domain") \
                if p.unit != ANGLE_UNIT else _degrees_message(p, raw)
    try:
        return model.with_params(**good), bad
    except (ValueError, TypeError) as exc:  # a cross-parameter check of the model
        bad["model"] = " ".join(str(exc).split())
        return model, bad


def _degrees_message(p: Parameter, raw: Any) -> str:
    lo, lo_inc, hi, hi_inc = p.domain
    lo_d = math.degrees(lo) if math.isfinite(lo) else lo
    hi_d = math.degrees(hi) if math.isfinite(hi) else hi
    interval = ("[" if lo_inc else "(") + f"{lo_d:g}, {hi_d:g}" + ("]" if hi_inc else ")")
    return f"parameter {p.name!r} is outside its domain {interval} deg, got {raw!r}"

"""``rb.load_fit``: the :class:`~roughbrdf.fitting.results.result.FitResult` of a saved fit folder.

A fit folder (:meth:`FitResult.save <roughbrdf.fitting.results.result.FitResult.save>`, ``roughbrdf
fit
FILE --out DIR``) holds ``fit.json``: the model of each channel, its parameters, standard errors,
correlations, figures of merit and message, the fit's options and the input file as it was
(``file``, ``file_abspath``, ``file_sha256``; ``docs/fitting.md``, "Output files").
:func:`load_fit` reads it back, re-reads the measurement from the recorded path and rebuilds the
result: :meth:`~roughbrdf.fitting.results.result.FitResult.report`,
:meth:`~roughbrdf.fitting.results.result.FitResult.predict` and
:meth:`~roughbrdf.fitting.results.result.FitResult.plot` work as on the fit itself.

What ``fit.json`` does not hold is rebuilt or left empty, and said so:

* the fitted samples (``index``, ``data``, ``fitted``, ``residual``) are selected again from the
  measurement with the recorded options (:func:`~roughbrdf.fitting.problem.data.prepare_channel`),
  the
  model evaluated there and the loss's residuals recomputed; a count that differs from the
  recorded ``n_points`` (weights given as an array are not in ``fit.json``) gives an
  :class:`InputChangedWarning`;
* the covariance is ``correl * stderr * stderr`` (NaN where a standard error is not known);
* the local fits (``starts``) are as many entries as the options record, without their start
  and end points; the model choice of a ``"auto"`` fit is not rebuilt (``model_choice`` is
  None: its table stays in ``fit.json`` and ``report.txt``).

A per-incidence fit (``fit.json`` with ``"per_incidence": true``) and a Mueller-matrix fit are
refused with a message saying what to do instead.

Before anything is read, the folder is checked as every reader of a results folder checks it
(:func:`roughbrdf.result_check.check_result_folder`): a write into it that a kill cut off (its
commit journal) is completed or undone, so that ``fit.json`` is of the same set as the rest; a
folder another live run is writing into, one with a journal that cannot be written, or one
where a file no longer has the SHA-256 its manifest records is refused
(:class:`~roughbrdf.result_check.ResultFolderRefused`).
"""

from __future__ import annotations

import errno
import json
import math
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ArgumentError
from ..instrument import Aperture
from .energy import EnergyConstraint
from .problem.data import Comparison, DataOptions, prepare_channel
from .problem.objective import Objective, ObjectiveSpec
from .results.fit_json import MAX_FIT_JSON_BYTES, channel_model, read_fit_json
from .results.result import ChannelFit, FitResult

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model

__all__ = ["InputChangedWarning", "load_fit"]


class InputChangedWarning(UserWarning):
    """The input of a saved fit is not what the fit read: its SHA-256 differs from the
    recorded ``file_sha256``, or its samples no longer give the recorded number of fitted
    points. The loaded result then compares the saved model with other data than it was
    fitted to."""


def load_fit(fit: str | os.PathLike, *, measurement: Measurement | str | os.PathLike | None
             = None) -> FitResult:
    """The :class:`~roughbrdf.fitting.results.result.FitResult` of a saved fit folder.

    Parameters
    ----------
    fit : str or path-like
        The fit's folder or its ``fit.json``.
    measurement : Measurement, str or path-like, optional
        The input, when it is not (or no longer) at the recorded path: a measurement, or the
        path of a file to read. Default: the file recorded in ``fit.json`` (``file_abspath``,
        else ``file``, as given or relative to the fit's folder), read again.

    Returns
    -------
    FitResult
        Channels with their parameters, standard errors, correlations, success, message and
        figures of merit as saved; the model, loss, options and aperture of the fit; the
        measurement re-read (module notes for what is rebuilt).

    Raises
    ------
    FileNotFoundError
        No ``fit.json``; or the recorded input file is gone (the message names the paths
        recorded and how to pass the file instead).
    ValueError
        A file that is not a fit's JSON; a per-incidence or Mueller-matrix fit (the message
        says what to use); a recorded value roughbrdf cannot rebuild.
    roughbrdf.result_check.ResultFolderRefused
        (a ``ValueError``) The folder is not one whole set roughbrdf wrote and cannot be made
        one: another run is writing into it, a cut-off write cannot be recovered (the folder
        is read-only), or a file was changed after roughbrdf wrote it (module notes).

    Warns
    -----
    InputChangedWarning
        The input file's SHA-256 differs from the recorded one (the file changed since the
        fit), or the samples selected again are not as many as the fit's.

    Examples
    --------
    >>> import tempfile, numpy as np, roughbrdf as rb
    >>> g = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))
    >>> meas = rb.Measurement(*g, rb.model("lambertian", rho=0.3).brdf(*g))
    >>> res = rb.fit("lambertian", meas, starts=1, progress=False)
    >>> folder = tempfile.mkdtemp()
    >>> _ = res.save(folder, plots=False)
    >>> back = rb.load_fit(folder, measurement=meas)   # no file behind it: given
    >>> back.params == res.params, back.report() == res.report()
    (True, True)
    """
    from ..result_check import check_result_folder

    path = Path(fit)
    path = path / "fit.json" if path.is_dir() else path
    check_result_folder(path.parent)  # one whole set (a cut-off write recovered) or refused
    try:
        content, folder = read_fit_json(path)
    except ValueError:
        _refuse_other_kinds(path)
        raise
    _refuse_other_kinds(path, content)
    meas = _measurement(content, folder, path, measurement)
    channels = [_channel(content, chan, meas, path) for chan in content["channels"]]
    ap = content.get("aperture")
    name = content["model"]
    return FitResult(
        channels=channels, measurement=meas,
        model_name=name if isinstance(name, str) else str(name.get("model", name)),
        loss=str(content.get("loss") or "relative"),
        compared=str(content.get("compared") or Comparison.of(meas).compared),
        relative_to=content.get("relative_to"), options=_options(content),
        elapsed=_number(content.get("elapsed_s"), 0.0),
        aperture=None if ap is None else float(ap["half_angle_rad"]),
        aperture_points=19 if ap is None else int(ap.get("points", 19)),
        source={k: content.get(k) for k in ("file", "file_abspath", "file_sha256")})


def _refuse_other_kinds(path: Path, content: dict[str, Any] | None = None) -> None:
    """Refuse (``ValueError`` naming ``path``) a per-incidence fit and a Mueller-matrix fit,
    saying what reads them; nothing for other content (or a file that is no JSON object)."""
    if content is None:
        try:
            if path.stat().st_size > MAX_FIT_JSON_BYTES:
                return
            content = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):  # read_fit_json's own error stands
            return
    if not isinstance(content, dict):
        return
    if content.get("per_incidence"):
        raise ValueError(
            f"{path}: a per-incidence fit (one parameter set per incidence, `roughbrdf fit "
            f"--per-incidence`), not one FitResult: read its rows with json.load (rb.export_to "
            f"takes that dict), or refit with "
            f"roughbrdf.fitting.kinds.per_incidence.fit_per_incidence")
    opts = content.get("options")
    if isinstance(opts, dict) and opts.get("mueller") is not None:
        raise ValueError(
            f"{path}: a Mueller-matrix fit, which load_fit does not rebuild; its fitted model "
            f"is roughbrdf.fitting.results.fit_json.fitted_models({str(path.parent)!r})")


def _options(content: dict[str, Any]) -> dict[str, Any]:
    """The recorded ``options`` of the fit (an empty dict when there are none)."""
    opts = content.get("options")
    return dict(opts) if isinstance(opts, dict) else {}


def _number(v: Any, default: float) -> float:
    """``v`` as a float, ``default`` for None (null: NaN in ``fit.json``) or not a number."""
    try:
        return float(v) if v is not None else default
    except (TypeError, ValueError):
        return default


def _measurement(content: dict[str, Any], folder: Path, path: Path, given: Any) -> Measurement:
    """The fit's input: ``given`` (a measurement or a path), else the recorded file read
    again, with a warning when its SHA-256 changed."""
    from ..measurement import Measurement

    if isinstance(given, Measurement):
        return given
    recorded = [content.get("file_abspath"), content.get("file")]
    if given is not None:
        file = Path(given)
        if not file.is_file():
            raise FileNotFoundError(errno.ENOENT, f"measurement: no such file (for the fit "
                                    f"{path})", str(file))
    else:
        file = _recorded_file(recorded, folder, path)
    from ..io import read
    from ..output import file_sha256

    quantity = content.get("quantity")
    # the quantity the fit read: supplied for files that do not say it (a file that says
    # another raises, which means it is not the file the fit read)
    meas = read(file, quantity=quantity) if quantity else read(file)
    named = content.get("file")
    if given is None and named and Path(named).resolve() == file.resolve():
        meas.meta["file"] = str(named)  # as the fit recorded it (fit.json's "file" round-trips)
    sha = content.get("file_sha256")
    if sha and given is None and file_sha256(file) != sha:
        warnings.warn(f"{file}: its SHA-256 differs from the one {path} recorded ({sha}): "
                      f"the file changed since the fit; the result compares the saved model "
                      f"with the file as it is now", InputChangedWarning, stacklevel=3)
    return meas


def _recorded_file(recorded: list[Any], folder: Path, path: Path) -> Path:
    """The first recorded input path that is a file (``file`` also relative to the fit's
    folder); ``FileNotFoundError`` naming what was recorded when none is."""
    names = [str(r) for r in recorded if r]
    if not names:
        raise FileNotFoundError(
            errno.ENOENT, f"{path} records no input file (the fit was of a measurement made in "
            f"Python): pass it, rb.load_fit(..., measurement=meas)", str(path))
    candidates = [Path(n) for n in names] + [folder / n for n in names if not Path(n).is_absolute()]
    for c in candidates:
        if c.is_file():
            return c
    shown = " or ".join(dict.fromkeys(names))
    raise FileNotFoundError(
        errno.ENOENT, f"the input file of the fit {path} is gone: it recorded {shown}; "
        f"pass the file where it is now, rb.load_fit(..., measurement=PATH)", names[0])


def _channel(content: dict[str, Any], chan: dict[str, Any], meas: Measurement,
             path: Path) -> ChannelFit:
    """One :class:`ChannelFit` from its ``fit.json`` entry and the measurement."""
    model = channel_model(content, chan)
    label = str(chan["channel"])
    try:
        j = meas.channel_index(label)
    except (KeyError, ValueError, IndexError):
        raise ArgumentError("measurement", f"has no channel {label!r}, which the fit {path} "
                            f"fitted (channels: {', '.join(meas.channels)})") from None
    free = [str(n) for n in chan.get("free") or []]
    metrics = chan.get("metrics") or {}
    stderr = {k: (None if v is None and k not in free else _number(v, math.nan))
              for k, v in (chan.get("stderr") or {}).items()}
    correl = {str(k): {str(o): _number(c, math.nan) for o, c in v.items()}
              for k, v in (chan.get("correl") or {}).items() if isinstance(v, dict)}
    opts = _options(content)
    free_scale = bool(opts.get("free_scale", False))
    scale = _number(chan.get("scale"), 1.0)
    samples: dict[str, Any] = _samples(content, model, meas, j, free, scale, free_scale)
    n_points = int(metrics.get("n_points", samples["index"].size))
    if n_points != samples["index"].size:
        warnings.warn(f"{path}, channel {label!r}: the fit used {n_points} samples, the "
                      f"measurement now gives {samples['index'].size} with the recorded "
                      f"options", InputChangedWarning, stacklevel=4)
    names = free + (["scale"] if free_scale else [])
    se = {**stderr, "scale": _number(chan.get("scale_stderr"), math.nan)}
    return ChannelFit(
        channel=label, model=model, params=dict(model.params), free=free,
        init={k: _number(v, math.nan) for k, v in (chan.get("init") or {}).items()},
        bounds={k: (float(v[0]), float(v[1])) for k, v in (chan.get("bounds") or {}).items()},
        stderr=stderr, correl=correl, covar=_covariance(names, se, correl), scale=scale,
        scale_stderr=_number(chan.get("scale_stderr"), 0.0), success=bool(chan.get("success")),
        message=str(chan.get("message", "")),
        **_metrics(metrics),
        n_points=n_points, n_varys=int(metrics.get("n_varys", len(names))),
        excluded={str(k): int(v) for k, v in (chan.get("excluded") or {}).items()},
        nfev=int(chan.get("nfev") or 0), starts=_starts(opts.get("starts")),
        elapsed=_number(chan.get("elapsed_s"), 0.0), free_scale=free_scale,
        at_bound={str(k): str(v) for k, v in (chan.get("at_bound") or {}).items()},
        energy_constraint=_energy(chan.get("energy_constraint")),
        one_sided=_one_sided(chan.get("one_sided_95")),
        intervals=_intervals(chan.get("profile_intervals")), **samples)


def _one_sided(rec: Any) -> dict[str, float | None]:
    """The recorded one-sided limits (``{name: u}``, null where the data did not bound it);
    a record that is not a mapping gives none."""
    if not isinstance(rec, dict):
        return {}
    return {str(k): None if v is None else _number(v, math.nan) for k, v in rec.items()}


def _intervals(rec: Any) -> dict[str, dict[str, tuple[float | None, float | None]]]:
    """The recorded profile intervals (``{name: {level: [lo, hi]}}``, null for a side the
    data did not bound); what is not such a record is left out."""
    out: dict[str, dict[str, tuple[float | None, float | None]]] = {}
    for name, by in (rec or {}).items() if isinstance(rec, dict) else ():
        if not isinstance(by, dict):
            continue
        out[str(name)] = {str(lv): (_side(v, 0), _side(v, 1)) for lv, v in by.items()
                          if isinstance(v, list) and len(v) == 2}
    return out


def _side(v: list[Any], i: int) -> float | None:
    """One end of a recorded interval: None where it is null."""
    return None if v[i] is None else _number(v[i], math.nan)


def _metrics(metrics: dict[str, Any]) -> dict[str, Any]:
    """The recorded figures of merit (NaN where null)."""
    return {k: _number(metrics.get(k), math.nan)
            for k in ("sigma", "rms_log", "chi2", "redchi", "aic", "bic")}


def _starts(n: Any) -> list[dict[str, Any]]:
    """``n`` entries standing for the local fits the options record (their start and end
    points are not in ``fit.json``)."""
    count = int(n) if isinstance(n, int) and n > 0 else 0
    return [{"x0": None, "x": None, "cost": math.nan, "stage": "single",
             "origin": "not recorded in fit.json"} for _ in range(count)]


def _energy(rec: Any) -> EnergyConstraint | None:
    """The channel's :class:`~roughbrdf.fitting.energy.EnergyConstraint` as recorded (None:
    the constraint did not run, or the record is not one)."""
    if not isinstance(rec, dict):
        return None
    try:
        return EnergyConstraint(
            bool(rec["active"]), [float(t) for t in rec["theta_deg"]],
            _number(rec.get("max_albedo"), math.nan), bool(rec["satisfied"]),
            _number(rec.get("unconstrained_max_albedo"), math.nan), int(rec["rounds"]),
            _number(rec.get("elapsed_s"), 0.0))
    except (KeyError, TypeError, ValueError):  # an older or hand-edited record: left out
        return None


def _samples(content: dict[str, Any], model: Model, meas: Measurement, j: int,
             free: list[str], scale: float, free_scale: bool) -> dict[str, np.ndarray]:
    """``index``, ``data``, ``fitted`` and ``residual`` of channel ``j``: the samples the
    recorded options select (:func:`~roughbrdf.fitting.problem.data.prepare_channel`), the fitted
    model there (through the aperture) and the loss's residuals at the recorded scale."""
    opts = _options(content)
    ap = content.get("aperture")
    aperture = None if ap is None else Aperture.parse(ap["half_angle_rad"], ap.get("points", 19))
    loss = str(content.get("loss") or "relative")
    weights = opts.get("weights")
    data_opts = DataOptions(
        Comparison.of(meas, content.get("relative_to")), loss,
        weights if weights == "uncertainty" else None,  # an array is not in fit.json
        str(opts.get("nonfinite", "raise")), str(opts.get("negative", "auto")), aperture,
        opts.get("theta_r_max"), opts.get("source_exclusion"),
        str(opts.get("extrapolated", "drop")))
    data = prepare_channel(model, meas, j, data_opts)
    lo = np.full(len(free), -np.inf)
    spec = ObjectiveSpec(model, free, lo, -lo, loss=loss,
                         quantity=data_opts.comparison.quantity, free_scale=free_scale,
                         fixed_scale=scale)
    obj = Objective(spec, data)
    fitted = data.geometry.evaluate(model, spec.quantity)
    return {"index": data.index, "data": data.values, "fitted": fitted,
            "residual": obj.residual_of(fitted, scale)}


def _covariance(names: list[str], stderr: dict[str, Any], correl: dict[str, dict[str, float]]
                ) -> np.ndarray:
    """``cov[a, b] = correl[a][b] stderr[a] stderr[b]`` (1 on the diagonal); NaN where a
    standard error or a correlation is not recorded."""
    se = np.array([_number(stderr.get(n), math.nan) for n in names])
    rho = np.full((len(names), len(names)), math.nan)
    for a, na in enumerate(names):
        rho[a, a] = 1.0
        for b, nb in enumerate(names):
            if b != a:
                rho[a, b] = correl.get(na, {}).get(nb, correl.get(nb, {}).get(na, math.nan))
    return rho * np.outer(se, se)

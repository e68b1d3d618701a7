"""One parameter set per incidence, and the rows an optical code's catalog keeps.

``docs/straylight.md`` ("Fits per incidence"). Stray-light codes hold a scatter model as rows
of parameters at a few incidences: Zemax OpticStudio's ABg catalog takes up to
:data:`MAX_ROWS` rows per name, "intermediate angles of incidence are linearly interpolated in
cosine space", the first row serves every smaller incidence and the last every larger one
(OpticStudio help, "ABg Scatter Data Catalogs"). :func:`fit_per_incidence` fits the model to
each measured incidence on its own (:func:`roughbrdf.fit` with every option, the energy
constraint included: TIS <= 1), then :func:`choose_rows` keeps at most ``max_rows`` of those
rows, chosen to minimise, over the measured incidences, the worst relative TIS error of the
interpolated parameters against each incidence's own fit, then the r.m.s. of ``ln(data /
model)`` (both reported, :class:`PerIncidenceFit`).

The choice: with no more incidences than rows, every row (both errors are those of the fits
themselves); else greedily from the first and last incidence, adding the row that lowers the
(worst TIS error, rms-log) pair most, until ``max_rows``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import ArgumentError
from ..problem.options import FitOptions
from .channels import fit_model

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ...models import Model
    from ..results.result import FitResult

__all__ = ["MAX_ROWS", "IncidenceRow", "PerIncidenceFit", "choose_rows", "fit_per_incidence",
           "interpolate_params"]

#: Zemax OpticStudio's ABg catalog: "Up to 10 data rows may be defined for each ABg data name"
MAX_ROWS = 10


@dataclass
class IncidenceRow:
    """The fit of one measured incidence.

    Attributes
    ----------
    theta_i : float
        The incidence (radians).
    result : FitResult
        :func:`roughbrdf.fit` on that incidence's samples (every channel).
    tis : dict of str to float
        Each channel's TIS (directional-hemispherical reflectance, :func:`roughbrdf.albedo`) of
        its fitted model at ``theta_i``.
    """

    theta_i: float
    result: FitResult
    tis: dict[str, float]

    def params(self, channel: str) -> dict[str, float]:
        """The fitted parameters of ``channel``."""
        return {k: float(v) for k, v in self.result[channel].params.items() if v is not None}


@dataclass
class PerIncidenceFit:
    """:func:`fit_per_incidence`'s result: every incidence's row and the rows kept.

    Attributes
    ----------
    model_name : str
        The model fitted.
    rows : list of IncidenceRow
        One per measured incidence, by increasing incidence.
    chosen : list of int
        Positions in ``rows`` of the rows kept (at most ``max_rows``).
    tis_error : dict of str to float
        Per channel, the worst relative TIS error at the measured incidences of the model with
        the kept rows interpolated (linearly in ``cos theta_i``), against each row's own TIS.
    rms_log : dict of str to float
        Per channel, the r.m.s. of ``ln(data / model)`` of every positive sample with the kept
        rows interpolated.
    """

    model_name: str
    rows: list[IncidenceRow]
    chosen: list[int]
    tis_error: dict[str, float] = field(default_factory=dict)
    rms_log: dict[str, float] = field(default_factory=dict)

    @property
    def channels(self) -> list[str]:
        """The channels fitted."""
        return [c.channel for c in self.rows[0].result.channels]

    @property
    def success(self) -> bool:
        """Every row's fit converged."""
        return all(r.result.success for r in self.rows)

    def model_at(self, theta_i: float, channel: str | None = None) -> Model:
        """The model with the kept rows' parameters interpolated at ``theta_i`` (radians):
        linearly in ``cos theta_i``, the first row's below it, the last row's above."""
        ch = channel or self.channels[0]
        kept = [self.rows[k] for k in self.chosen]
        values = interpolate_params([r.theta_i for r in kept], [r.params(ch) for r in kept],
                                    theta_i)
        return kept[0].result[ch].model.with_params(**values)

    def to_dict(self) -> dict[str, Any]:
        """The rows and the choice, for ``fit.json``: angles in degrees and radians."""
        rows = []
        for k, r in enumerate(self.rows):
            rows.append({"theta_i_deg": math.degrees(r.theta_i), "theta_i_rad": r.theta_i,
                         "kept": k in self.chosen, "success": r.result.success,
                         "channels": {c.channel: {"params": dict(c.params),
                                                  "stderr": dict(c.stderr),
                                                  "tis": r.tis[c.channel],
                                                  "rms_log": c.rms_log,
                                                  "message": c.message}
                                      for c in r.result.channels}})
        return {"model": self.model_name, "per_incidence": True, "rows": rows,
                "interpolation": "linear in cos(theta_i); first row below, last row above",
                "tis_error": self.tis_error, "rms_log": self.rms_log}

    def save(self, out_dir: str | os.PathLike, *, overwrite: bool = False) -> list[Path]:
        """Write ``fit.json`` (:meth:`to_dict`, with the measurement's file) and ``report.txt``
        (:meth:`report`) into ``out_dir`` as one set (:class:`roughbrdf.output.ResultFolder`:
        an earlier run's results or a file of those names refused unless ``overwrite``)."""
        from ...output import ResultFolder
        from ..problem.data import input_source

        doc = {**self.to_dict(), **input_source(self.rows[0].result.measurement)}
        files = {"fit.json": json.dumps(doc, indent=2, default=float) + "\n",
                 "report.txt": self.report()}
        with ResultFolder(out_dir, overwrite=overwrite) as out:
            out.check(list(files))
            for name, content in files.items():
                out.add(name, content)
        return [out.path / n for n in files]

    def report(self) -> str:
        """A text table per channel: each row's incidence, parameters and TIS, and the two
        errors of the kept rows."""
        lines = [f"model {self.model_name}, one parameter set per incidence "
                 f"({len(self.chosen)} of {len(self.rows)} rows kept; interpolated linearly "
                 "in cos theta_i)"]
        for ch in self.channels:
            names = list(self.rows[0].params(ch))
            lines.append(f"channel {ch}")
            lines.append("  kept  theta_i (deg)  " + "  ".join(f"{n:>12s}" for n in names)
                         + "           TIS")
            for k, r in enumerate(self.rows):
                p = r.params(ch)
                lines.append(f"  {'yes' if k in self.chosen else ' no':>4s}  "
                             f"{math.degrees(r.theta_i):13.3f}  "
                             + "  ".join(f"{p[n]:12.6g}" for n in names)
                             + f"  {r.tis[ch]:12.6f}")
            lines.append(f"  worst relative TIS error at the measured incidences "
                         f"{self.tis_error[ch]:.3g}; rms-log of the data {self.rms_log[ch]:.4g}")
        return "\n".join(lines) + "\n"


def interpolate_params(theta: Sequence[float], params: Sequence[dict[str, float]],
                       theta_i: float) -> dict[str, float]:
    """Parameters at ``theta_i`` from rows at incidences ``theta`` (radians, increasing):
    linear in ``cos theta_i`` between rows, the first row's below the first incidence and the
    last row's above the last (Zemax's ABg catalog rule).

    Examples
    --------
    >>> rows = [{"A": 1.0}, {"A": 3.0}]
    >>> t = [0.0, math.pi / 3]                      # cos: 1 and 0.5
    >>> interpolate_params(t, rows, math.acos(0.75))["A"]   # half way in cosine
    2.0
    >>> interpolate_params(t, rows, 1.4)["A"]       # beyond the last row: the last row
    3.0
    """
    c = np.cos(np.asarray(theta, dtype=float))[::-1]  # increasing cosines for np.interp
    ci = math.cos(theta_i)
    out = {}
    for name in params[0]:
        v = np.array([p[name] for p in params], dtype=float)[::-1]
        out[name] = float(np.interp(ci, c, v))  # np.interp holds the end values outside
    return out


def _at(meas: Measurement, theta_i: float) -> np.ndarray:
    """The samples of incidence ``theta_i`` (``Measurement.incidences`` rounds to 1e-6 rad)."""
    return np.abs(meas.theta_i - theta_i) < 1e-6


def _errors(rows: list[IncidenceRow], chosen: list[int], meas: Measurement,
            channel: str) -> tuple[float, float]:
    """(worst relative TIS error, rms-log) of the rows ``chosen`` interpolated, at every
    measured incidence of ``channel`` (on the samples each incidence's fit used)."""
    from ...integrate import albedo

    kept = [rows[k] for k in chosen]
    theta = [r.theta_i for r in kept]
    params = [r.params(channel) for r in kept]
    base = kept[0].result[channel].model
    col = meas.channel_index(channel)
    worst, sq, n = 0.0, 0.0, 0
    for r in rows:
        model = base.with_params(**interpolate_params(theta, params, r.theta_i))
        tis = float(albedo(model, r.theta_i))
        own = r.tis[channel]
        # a row whose own TIS is 0 (no scatter): the absolute error stands in
        worst = max(worst, abs(tis - own) / own if own > 0 else abs(tis))
        # the samples the row's fit used (its fit domain: not the extrapolated ones it left out)
        sub, fit = r.result.measurement, r.result[channel]
        idx = fit.index
        x = sub.values[idx, col] * fit.scale
        f = np.asarray(model.brdf(sub.theta_i[idx], sub.theta_r[idx], sub.phi[idx]))
        ok = (x > 0) & (f > 0) & np.isfinite(f)  # ln needs both positive
        sq += float(np.sum(np.log(x[ok] / f[ok]) ** 2))
        n += int(ok.sum())
    return worst, math.sqrt(sq / n) if n else math.nan


def choose_rows(rows: list[IncidenceRow], meas: Measurement, max_rows: int = MAX_ROWS
                ) -> tuple[list[int], dict[str, float], dict[str, float]]:
    """The rows to keep (module notes) and their (worst TIS error, rms-log) per channel;
    the criterion over channels is the worst channel's."""
    channels = [c.channel for c in rows[0].result.channels]

    def score(chosen: list[int]) -> tuple[float, float]:
        e = [_errors(rows, chosen, meas, ch) for ch in channels]
        return max(t for t, _ in e), max(r for _, r in e)

    if len(rows) <= max_rows:
        chosen = list(range(len(rows)))
    else:
        chosen = sorted({0, len(rows) - 1})
        while len(chosen) < max_rows:
            trial = [(score(sorted([*chosen, k])), k) for k in range(len(rows))
                     if k not in chosen]
            chosen = sorted([*chosen, min(trial)[1]])
    errs = {ch: _errors(rows, chosen, meas, ch) for ch in channels}
    return chosen, {ch: e[0] for ch, e in errs.items()}, {ch: e[1] for ch, e in errs.items()}


def fit_per_incidence(model: Model | str, measurement: Measurement, *, max_rows: int = MAX_ROWS,
                      options: FitOptions | None = None, **keywords: Any) -> PerIncidenceFit:
    """Fit ``model`` to each measured incidence on its own and keep at most ``max_rows`` rows
    (module notes). ``options`` / ``keywords`` as for :func:`roughbrdf.fit` (``"auto"`` is
    refused: a catalog holds one model).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([10.0, 40.0]),
    ...               np.radians(np.arange(0.0, 80.0, 10.0)), [0.0, np.pi], indexing="ij"))
    >>> truth = rb.model("lambertian", rho=0.4)
    >>> meas = rb.Measurement(ti, tr, ph, truth.brdf(ti, tr, ph))
    >>> res = fit_per_incidence("lambertian", meas, starts=1, progress=False)
    >>> [round(r.params("value")["rho"], 6) for r in res.rows], res.chosen
    ([0.4, 0.4], [0, 1])
    """
    from ...integrate import albedo
    from ...models.factory import as_model, is_auto

    if isinstance(model, str) and is_auto(model):
        raise ArgumentError("model", "a per-incidence fit holds one model: name it", value=model)
    if not isinstance(max_rows, int) or max_rows < 2:
        raise ArgumentError("max_rows", "must be an integer >= 2", value=max_rows)
    opts = FitOptions.of(options, keywords, caller="fit_per_incidence")
    if opts.intervals == "profile":  # each row is a fit_model fit: no profiles there
        raise ArgumentError("intervals", "a per-incidence fit has no profile intervals",
                            value=opts.intervals)
    start = as_model(model)
    angles = np.sort(measurement.incidences())
    if angles.size < 1:
        raise ArgumentError("measurement", "holds no sample", value=measurement.n_samples)
    rows = []
    for t in angles:
        sel = _at(measurement, float(t))
        t = float(np.mean(measurement.theta_i[sel]))  # the incidence itself, not rounded
        res = fit_model(start, measurement.subset(sel), opts)
        tis = {c.channel: float(albedo(c.model, t)) for c in res.channels}
        rows.append(IncidenceRow(t, res, tis))
    chosen, tis_error, rms_log = choose_rows(rows, measurement, max_rows)
    name = rows[0].result.model_name
    return PerIncidenceFit(name, rows, chosen, tis_error, rms_log)

"""What a fit returns: :class:`ChannelFit` per channel and :class:`FitResult` for the whole fit.

``FitResult`` gives the fitted model as the fit compared it with the data
(:meth:`FitResult.predict`, through the instrument aperture if the fit had one), the ``fit.json``
content (:meth:`FitResult.to_dict`, :meth:`FitResult.to_json`), the text report
(:mod:`roughbrdf.fitting.results.report`), the plots (:meth:`FitResult.plot`, drawn by
:mod:`roughbrdf.plot` through the fit's aperture) and :meth:`FitResult.save`. The keys of
``fit.json`` are listed in ``docs/fitting.md`` ("Output files").
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from ...instrument import Aperture, aperture_average
from ...jsonsafe import clean_json
from ...mpl_load import load_matplotlib
from ...quantity import Quantity
from ..problem.data import input_source
from .fit_json import channel_model, check_fit_channels, fitted_models, read_fit_json
from .physical import non_physical, physical_range
from .plausibility import Plausibility, channel_plausibility
from .statistics import Covariance, GoodnessOfFit, bound_and_undetermined, limit_kinds

if TYPE_CHECKING:
    from ...measurement import Measurement
    from ...models import Model
    from ..problem.objective import Objective
    from ..solvers.search import SearchOutcome

__all__ = ["ChannelFit", "FitResult", "channel_model", "check_fit_channels", "fitted_models",
           "input_source", "read_fit_json"]

# the reading of a saved fit lives in .fit_json; these names stay here too, where the docs of
# earlier releases point (roughbrdf.fitting.results.result.fitted_models)


@dataclass
class ChannelFit:
    """The fit of one channel (lmfit ``MinimizerResult``-like).

    Attributes
    ----------
    channel : str
        Channel label.
    model : Model
        The fitted model.
    params : dict
        Every parameter of the model (fitted, fixed and switched off) -> value.
    free : list of str
        Names of the fitted parameters.
    init : dict
        Starting values of the free parameters (the model's values before the fit).
    bounds : dict
        ``name -> (low, high)`` used for the free parameters.
    stderr : dict
        ``name -> standard error`` (``None`` for fixed parameters, ``nan`` if not estimable,
        at a bound or undetermined: without effect at the optimum, named in ``message``).
    at_bound : dict
        ``name -> "lower" | "upper"`` for the free parameters at a bound, undetermined ones
        aside (:func:`~roughbrdf.fitting.results.statistics.bound_and_undetermined`): no standard
        error nor correlations; the others' covariance is computed with them held there.
        :attr:`limits` tells a physical edge from a search limit.
    one_sided : dict
        ``name -> u`` for the parameters on a physical limit, with ``intervals="profile"``: the
        one-sided 95 % limit from the profile of the cost (None: not bounded within the search
        range; :mod:`~roughbrdf.fitting.results.one_sided`); empty otherwise and for joint,
        Mueller and energy-constrained fits.
    intervals : dict
        ``name -> {"68": (lo, hi), "95": (lo, hi)}``: profile intervals, with
        ``intervals="profile"`` (:mod:`~roughbrdf.fitting.results.intervals`; a side None where
        the data do not bound it within the search range); else empty.
    correl : dict
        ``name -> {other: correlation}`` among the free parameters (and ``"scale"``).
    covar : numpy.ndarray
        Covariance of ``free`` (+ ``scale`` last if it is free); NaN rows and columns for the
        parameters at a bound.
    scale, scale_stderr : float
        The data scale ``K`` (``x -> K x``; 1 and 0 when the data are absolute).
    success : bool
    message : str
    sigma : float
        TR75 sigma: r.m.s. of ``(K x - f)/f`` over the fitted samples (Eq. 34).
    rms_log : float
        r.m.s. of ``ln(K x) - ln f`` over the fitted samples with ``x > 0``.
    chi2, redchi, aic, bic : float
        ``sum(r^2)`` of the loss residuals, ``chi2/(N - n_varys)``, and lmfit's
        ``N ln(chi2/N) + 2 n_varys`` and ``N ln(chi2/N) + ln(N) n_varys``.
    n_points, n_varys : int
    excluded : dict
        Samples left out or changed, by reason (``nonfinite``, ``negative``, ``clipped``,
        ``zero_weight``, ``model_domain``: model not finite there, ``horizon``: theta_r = 90 deg
        with BRDF cos data and the relative or log loss).
    nfev : int
        Model evaluations (each one vectorized over all samples of the stage).
    starts : list of dict
        Every local fit: ``{"x0", "x", "cost", "stage": "explore"|"full"|"single", "origin"}``
        (:class:`~roughbrdf.fitting.solvers.search.SearchOutcome`); the ``stage != "full"`` ones are
        the ``starts`` asked for, the ``"full"`` ones their polish on all samples.
    elapsed : float
        Seconds.
    index : numpy.ndarray
        Indices (into the measurement) of the fitted samples.
    data : numpy.ndarray
        The fitted values (after ``negative="clip"``), in the measurement's own scale.
    fitted : numpy.ndarray
        The model at those samples (the quantity compared; averaged over the aperture when the
        fit had one).
    residual : numpy.ndarray
        The loss residuals at the optimum.
    """

    channel: str
    model: Model
    params: dict[str, float | None]
    free: list[str]
    init: dict[str, float]
    bounds: dict[str, tuple[float, float]]
    stderr: dict[str, float | None]
    correl: dict[str, dict[str, float]]
    covar: np.ndarray
    scale: float
    scale_stderr: float
    success: bool
    message: str
    sigma: float
    rms_log: float
    chi2: float
    redchi: float
    aic: float
    bic: float
    n_points: int
    n_varys: int
    excluded: dict[str, int]
    nfev: int
    starts: list[dict[str, Any]]
    elapsed: float
    free_scale: bool
    index: np.ndarray = field(repr=False)
    data: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)
    residual: np.ndarray = field(repr=False)
    at_bound: dict[str, str] = field(default_factory=dict)
    #: the :class:`~.plausibility.Plausibility` (:meth:`FitResult.plausibility`)
    plausibility: Plausibility | None = field(default=None, repr=False)
    #: what the energy constraint did (:class:`~roughbrdf.fitting.energy.EnergyConstraint`)
    energy_constraint: Any = field(default=None, repr=False)
    #: ``{name: u}``: the one-sided limits (:attr:`one_sided` above)
    one_sided: dict[str, float | None] = field(default_factory=dict)
    #: profile intervals (:attr:`intervals` above)
    intervals: dict[str, dict[str, tuple[float | None, float | None]]] = field(
        default_factory=dict)

    @property
    def limits(self) -> dict[str, str]:
        """``{name: "physical-lower" | "search-upper" ...}`` of the parameters :attr:`at_bound`
        (:func:`~roughbrdf.fitting.results.statistics.limit_kinds`)."""
        return limit_kinds(self.at_bound, self.bounds, self.model.parameters,
                           {nm: physical_range(self.model, nm) for nm in self.bounds})

    @property
    def metrics(self) -> dict[str, float | int]:
        """The figures of merit, as in ``fit.json``."""
        return {"sigma": self.sigma, "rms_log": self.rms_log, "chi2": self.chi2,
                "redchi": self.redchi, "aic": self.aic, "bic": self.bic,
                "n_points": self.n_points, "n_varys": self.n_varys}

    @classmethod
    def from_search(cls, obj: Objective, outcome: SearchOutcome, elapsed: float, *,
                    statistics: bool = True) -> ChannelFit:
        """The channel's result at the search's optimum: statistics on all samples of ``obj``
        (:mod:`~roughbrdf.fitting.results.statistics`); ``statistics=False`` as
        :meth:`fields_at_optimum`'s."""
        f = obj.values(outcome.theta)
        return cls(**cls.fields_at_optimum(obj, outcome, elapsed, f, obj.data.values, f,
                                           statistics=statistics))

    @staticmethod
    def fields_at_optimum(obj: Objective, outcome: SearchOutcome, elapsed: float,
                          f: np.ndarray, data: np.ndarray, fitted: np.ndarray, *,
                          statistics: bool = True) -> dict[str, Any]:
        """The fields of a :class:`ChannelFit` at the search's optimum, from the model values
        ``f`` of ``obj`` there; ``data`` and ``fitted`` are what the figures of merit (sigma,
        rms-log) compare (the measured and model values; for Mueller data their m00).
        ``statistics=False`` (a cross-validation fold, whose parameters only predict the
        left-out incidence): no covariance, no bound or undetermined flags (NaN errors),
        which saves the ``2 k`` model evaluations of the central-difference Jacobian."""
        spec, theta = obj.spec, outcome.theta
        fitted_model = spec.model_at(theta)
        k = obj.scale(f)
        r = obj.residual_of(f, k)
        gof = GoodnessOfFit.of(r, data, fitted, scale=k, n_varys=spec.n_varys,
                               floor=obj.floor)
        bound: dict[str, str] = {}
        none: list[str] = []
        if statistics:
            bound, none, jac = bound_and_undetermined(obj, theta, k, r)
            cov = Covariance.at_optimum(obj, theta, f, k, chi2=gof.chi2, dof=gof.dof,
                                        held=[*bound, *none], jac=jac)
        else:
            cov = Covariance.unestimated(spec, "; no covariance (a cross-validation fold)")
        sd = cov.stderr()
        stderr: dict[str, float | None] = dict.fromkeys(spec.model.param_names)
        stderr.update({nm: float(s) for nm, s in zip(cov.names, sd, strict=True) if nm != "scale"})
        res = outcome.result
        message = (res.message.rstrip(".") if res is not None else "no local fit finished") \
            + cov.note + (f"; at a bound: {', '.join(bound)}" if bound else "") \
            + (f"; no effect at the optimum (undetermined): {', '.join(none)}" if none else "")
        return dict(
            channel=obj.data.label, model=fitted_model, params=fitted_model.params,
            free=list(spec.free), init=spec.start_values(),
            bounds={nm: (float(a), float(b))
                    for nm, a, b in zip(spec.free, spec.lower, spec.upper, strict=True)},
            stderr=stderr, correl=cov.correl(), covar=cov.matrix, scale=float(k),
            scale_stderr=float(sd[-1]) if spec.free_scale else 0.0,
            success=bool(res.success) if res is not None else False, message=message,
            sigma=gof.sigma, rms_log=gof.rms_log, chi2=gof.chi2, redchi=gof.redchi,
            aic=gof.aic, bic=gof.bic, n_points=gof.n_points, n_varys=gof.n_varys,
            excluded=obj.data.excluded, nfev=obj.nfev + outcome.explore_nfev,
            starts=outcome.tried, free_scale=spec.free_scale, at_bound=bound, elapsed=elapsed,
            index=obj.data.index, data=data, fitted=fitted, residual=r)

    def to_dict(self) -> dict[str, Any]:
        """This channel's entry of ``fit.json`` (before NaN -> null)."""
        return {"channel": self.channel, "params": self.params, "stderr": self.stderr,
                "at_bound": self.at_bound, "limits": self.limits, "success": bool(self.success),
                "metrics": self.metrics, "non_physical_range": non_physical(self),
                "message": self.message, "free": self.free, "init": self.init,
                "bounds": {k: list(v) for k, v in self.bounds.items()}, "scale": self.scale,
                "scale_stderr": self.scale_stderr, "correl": self.correl,
                "excluded": self.excluded, "nfev": self.nfev, "elapsed_s": self.elapsed,
                "model_spec": self.model.to_dict(), "energy_constraint": None
                if self.energy_constraint is None else self.energy_constraint.to_dict(),
                "one_sided_95": dict(self.one_sided),
                "profile_intervals": {nm: {lv: list(v) for lv, v in by.items()}
                                      for nm, by in self.intervals.items()}}


@dataclass
class FitResult:
    """Result of :func:`roughbrdf.fit`: one :class:`ChannelFit` per fitted channel.

    ``aperture`` / ``aperture_points`` record the instrument aperture the fit used (None: none;
    :attr:`instrument` gives it as an :class:`~roughbrdf.instrument.Aperture`); :meth:`predict`
    evaluates the fitted model the way the fit compared it with the data. ``res[label]`` or
    ``res[i]`` gives a channel. For a fit of a single channel, ``model``, ``params``, ``stderr``,
    ``correl``, ``sigma``, ``rms_log`` and ``message`` are that channel's; with several channels
    they raise and point to ``res[...]``. ``success`` is true when every channel succeeded.
    """

    channels: list[ChannelFit]
    measurement: Measurement = field(repr=False)
    model_name: str
    loss: str
    compared: str
    relative_to: str | None
    options: dict[str, Any]
    elapsed: float
    #: instrument aperture of the fit (half-angle, radians; None: none) and its stencil size; kept
    #: so that predictions and plots average the model the same way (:meth:`predict`, :meth:`plot`)
    aperture: float | None = None
    aperture_points: int = 19
    #: the input file as it was when the fit ran: ``{"file", "file_abspath", "file_sha256"}``
    #: (:func:`input_source`; None: taken from the measurement when needed)
    source: dict[str, str | None] | None = field(default=None, repr=False)
    #: with ``rb.fit("auto", ...)``: the :class:`~roughbrdf.fitting.choice.compare.ModelComparison`
    #: of the candidates this fit was chosen from (``fit.json``'s ``model_choice``)
    model_choice: Any = field(default=None, repr=False)

    # single-channel shortcuts -------------------------------------------------------------------
    def _one(self, what: str) -> ChannelFit:
        if len(self.channels) != 1:
            labels = ", ".join(repr(c.channel) for c in self.channels)
            raise AttributeError(
                f"this fit has {len(self.channels)} channels ({labels}); use "
                f"res[channel].{what} or res.channels[i].{what}")
        return self.channels[0]

    @property
    def model(self) -> Model:
        return self._one("model").model

    @property
    def params(self) -> dict[str, float | None]:
        return self._one("params").params

    @property
    def stderr(self) -> dict[str, float | None]:
        return self._one("stderr").stderr

    @property
    def correl(self) -> dict[str, dict[str, float]]:
        return self._one("correl").correl

    @property
    def sigma(self) -> float:
        return self._one("sigma").sigma

    @property
    def rms_log(self) -> float:
        return self._one("rms_log").rms_log

    @property
    def message(self) -> str:
        return self._one("message").message

    @property
    def success(self) -> bool:
        return all(c.success for c in self.channels)

    @property
    def at_search_limit(self) -> bool:
        """Whether a parameter of some channel ended on a search limit (not a result)."""
        return bool(self.search_limits)

    @property
    def search_limits(self) -> list[str]:
        """The parameters that ended on a search limit in some channel, sorted (where the
        search stopped, not a result: ``docs/fitting.md``, "Parameters at a bound")."""
        return sorted({nm for c in self.channels for nm, k in c.limits.items()
                       if k.startswith("search")})

    @property
    def gains_energy(self) -> bool:
        """Whether some channel's model reflects more than it receives (albedo > 1)."""
        return any(self.plausibility(i).gains_energy for i in range(len(self.channels)))

    def plausibility(self, channel: int | str = 0) -> Plausibility:
        """The albedo and peak ratios of a channel (:mod:`~roughbrdf.fitting.results.plausibility`),
        computed once."""
        c = self[channel]
        if c.plausibility is None:
            c.plausibility = channel_plausibility(c, self.measurement.theta_i[c.index])
        return c.plausibility

    @property
    def instrument(self) -> Aperture | None:
        """The fit's aperture as an :class:`~roughbrdf.instrument.Aperture` (None: none)."""
        return None if self.aperture is None else Aperture(self.aperture, self.aperture_points)

    def __getitem__(self, key: int | str) -> ChannelFit:
        if isinstance(key, str):
            for c in self.channels:
                if c.channel == key:
                    return c
            raise KeyError(f"no channel {key!r}; fitted: {[c.channel for c in self.channels]}")
        return self.channels[key]

    def __len__(self) -> int:
        return len(self.channels)

    def __iter__(self):
        return iter(self.channels)

    def predict(self, theta_i: Any, theta_r: Any, phi: Any, *, channel: int | str = 0,
                polarization: Any = None, aperture: bool = True) -> np.ndarray | float:
        """The fitted model of ``channel`` as compared with the data: the quantity ``compared``
        (BRDF or BRDF cos theta_r), averaged over the fit's aperture (``aperture=False``: at the
        given directions only). On the model's absolute scale; relative data are ``K x``."""
        c = self[channel]
        q = Quantity.parse(self.compared).compared_with()
        return aperture_average(c.model, theta_i, theta_r, phi,
                                self.instrument if aperture else None, quantity=q,
                                polarization=polarization)

    # output ---------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The ``fit.json`` content (keys ``model``, ``file``, ``file_abspath``,
        ``file_sha256``, ``loss``, ``channels`` ...; ``docs/fitting.md``, "Output files").

        ``file`` is the path as the measurement recorded it, ``file_abspath`` the absolute path
        and ``file_sha256`` the SHA-256 of the file's bytes when the fit ran (both None when
        the measurement did not come from a file that could be read), so that a later reader
        finds the input from any folder and can tell whether it has changed since.
        """
        meta = self.measurement.meta
        ap = self.instrument
        src = self.source if self.source is not None else input_source(self.measurement)
        return clean_json({
            "model": self.model_name, "file": meta.get("file"),
            "file_abspath": src.get("file_abspath"), "file_sha256": src.get("file_sha256"),
            "loss": self.loss,
            "quantity": self.measurement.quantity, "compared": self.compared,
            "relative_to": self.relative_to, "sample": meta.get("sample"),
            "options": self.options, "aperture": None if ap is None else ap.to_dict(),
            "elapsed_s": self.elapsed,
            "channels": [{**c.to_dict(), **self.plausibility(i).to_dict()}
                         for i, c in enumerate(self.channels)],
            "model_choice": None if self.model_choice is None else self.model_choice.to_dict(),
        })

    def to_json(self, path: str | os.PathLike | None = None, *, indent: int = 2,
                overwrite: bool = False) -> str:
        """JSON text of :meth:`to_dict` (strict JSON: NaN written as ``null``); optionally saved
        to ``path`` (atomically, :func:`roughbrdf.output.atomic_write`; an existing file is
        replaced only with ``overwrite=True``, else ``FileExistsError``)."""
        text = json.dumps(self.to_dict(), indent=indent, allow_nan=False)
        if path is not None:
            from ...output import atomic_write

            atomic_write(path, text + "\n", overwrite=overwrite)
        return text

    def report(self, *, min_correl: float = 0.1, angles: str = "rad") -> str:
        """lmfit-style text report of every channel (:func:`~.report.report`); parameters
        whose unit is an angle in ``angles`` (``"rad"`` or ``"deg"``)."""
        from .report import report

        return report(self, min_correl=min_correl, angles=angles)

    def __str__(self) -> str:
        return self.report()

    def _repr_html_(self) -> str:
        """Jupyter's rich display (:func:`roughbrdf.html_repr.fit_html`)."""
        from ...html_repr import fit_html

        return fit_html(self)

    def plot_data(self, channel: int | str = 0) -> tuple[Model, Measurement]:
        """The fitted model and the fitted samples of one channel on the model's absolute scale.

        Relative data are multiplied by the fitted ``K`` and labelled with the quantity they were
        compared with (``brdf`` or ``bridf``), so that data and model share one axis.
        """
        c = self[channel]
        meas = self.measurement.subset(c.index).select_channel(c.channel)
        meas = replace(meas, values=(c.scale * c.data)[:, None],
                       quantity=Quantity.parse(self.compared).compared_with(),
                       uncertainty=None, meta=dict(meas.meta))
        return c.model, meas

    def plot(self, channel: int | str = 0, *, fig: Any = None) -> tuple[Any, Any]:
        """Data vs model (in-plane slices), the residual map of each incidence and a note of the
        samples the fit left out (:func:`roughbrdf.plot_fit.plot_fit`, the fit's aperture: the
        model drawn as the fit compared it). Returns ``(fig, (ax_comparison,
        ax_residuals))``; a new figure is a pyplot-free :class:`matplotlib.figure.Figure`."""
        from ...plot_fit import plot_fit
        from ..problem.data import excluded_text

        model, meas = self.plot_data(channel)
        c = self[channel]
        note = (f"{c.n_points} of {self.measurement.n_samples} samples drawn: those the fit "
                f"used; left out: {excluded_text(c.excluded)}")
        return plot_fit(model, meas, aperture=self.instrument, note=note, fig=fig,
                        title=f"{self.model_name} [{c.channel}], loss {self.loss}")

    def plot_names(self) -> list[str]:
        """File names :meth:`save` gives the per-channel plots (``fit_<channel>.png``)."""
        out = []
        for c in self.channels:
            safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in c.channel)
            out.append(f"fit_{safe or 'channel'}.png")
        return out

    def save(self, out_dir: str | os.PathLike, *, plots: bool = True, overwrite: bool = False,
             dpi: int = 110, report_angles: str = "rad") -> list[Path]:
        """Write ``fit.json``, ``report.txt`` and one ``fit_<channel>.png`` per channel, as one set.

        Everything goes through :class:`roughbrdf.output.ResultFolder`: the folder may exist,
        but a folder that holds results already (an earlier run's, listed in its manifest) or
        any file of these names is refused with ``FileExistsError`` *before* anything is drawn
        or written, unless ``overwrite=True`` (the CLI's ``--force``); even then a file of the
        same name that roughbrdf did not write is never replaced. The files are staged and
        committed together at the end: an error or Ctrl-C leaves the folder as it was (the
        previous complete set), never a mix, never a 0-byte file.

        ``out_dir``: the folder (created if needed); ``plots``: draw ``fit_<channel>.png``
        (:meth:`plot`); ``overwrite``: replace the set of results in ``out_dir`` (stale files of
        the old set are removed); ``dpi``: of the PNGs; ``report_angles`` (``"rad"``,
        ``"deg"``): unit of the angle parameters in ``report.txt`` (fit.json holds radians).

        Returns
        -------
        list of pathlib.Path
            The paths written: ``fit.json``, ``report.txt``, then the PNGs.
        """
        from ...output import ResultFolder

        files = self.files(plots=plots, dpi=dpi, report_angles=report_angles)
        with ResultFolder(out_dir, overwrite=overwrite) as out:
            out.check(list(files))  # refuse before the (slow) drawing
            for name, content in files.items():
                out.add(name, content, binary=callable(content))
        return [out.path / n for n in files]

    def files(self, *, plots: bool = True, dpi: int = 110, report_angles: str = "rad"
              ) -> dict[str, Any]:
        """The set :meth:`save` writes, for a :class:`~roughbrdf.output.ResultFolder`:
        ``{"fit.json": text, "report.txt": text, "fit_<channel>.png": writer}``; each PNG
        writer draws its figure only when it is written (``report_angles``: as for
        :meth:`save`)."""
        text = self.report(angles=report_angles)
        files: dict[str, Any] = {"fit.json": self.to_json() + "\n",
                                 "report.txt": text if text.endswith("\n") else text + "\n"}
        if plots:
            for i, name in enumerate(self.plot_names()):
                files[name] = _png_writer(self, i, dpi)
            if self.model_choice is not None:
                files["compare.png"] = _figure_writer(self.model_choice.plot, dpi)
        return files


def _png_writer(result: FitResult, channel: int, dpi: int) -> Callable[[IO[bytes]], None]:
    """A function drawing ``result``'s figure of ``channel`` as PNG into the open (staged)
    file it is given."""
    def write(fh: IO[bytes]) -> None:
        load_matplotlib()  # Ctrl-C held while its compiled modules load
        fig, _ = result.plot(channel)
        fig.savefig(fh, format="png", dpi=dpi, metadata={"Software": "roughbrdf"})
    return write


def _figure_writer(draw: Callable[[], Any], dpi: int) -> Callable[[IO[bytes]], None]:
    """A function drawing the figure ``draw()`` returns as PNG into the file it is given."""
    def write(fh: IO[bytes]) -> None:
        load_matplotlib()  # Ctrl-C held while its compiled modules load
        draw().savefig(fh, format="png", dpi=dpi, metadata={"Software": "roughbrdf"})
    return write

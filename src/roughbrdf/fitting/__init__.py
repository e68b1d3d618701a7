"""Fitting models to measurements: :func:`fit`, :class:`FitOptions` and :class:`FitResult`
(``docs/fitting.md``).

Data flows one way: file -> :func:`roughbrdf.read` -> :class:`~roughbrdf.measurement.Measurement`
-> :func:`fit` -> :class:`FitResult` -> report, JSON, plots. Models know nothing about fitting: the
fitter reads ``model.parameters`` (value, bounds) and rebuilds the model with
``model.with_values``. Each channel is fitted on its own; ``scipy.optimize.least_squares``
(trust-region reflective, box bounds) minimizes the sum of squared residuals, one per sample:
``(K x - f)/f`` by default, whose r.m.s. is TR75's sigma (Eq. 34).

This package face only re-exports. One job per module:

=========================================  ===================================================
:mod:`~roughbrdf.fitting.fit`              :func:`fit`: options from keywords; routes Mueller
                                           data, ``"auto"`` and a named model
:mod:`~roughbrdf.fitting.options`          :class:`FitOptions`: every option, typed, checked
                                           once when made
:mod:`~roughbrdf.fitting.plan`             what needs the model or data, checked before any
                                           work: free parameters, bounds, the data scale ``K``
:mod:`~roughbrdf.fitting.channels`         the fit of one named model: channel by channel or
                                           jointly, Mueller data to ``polarimetric``
:mod:`~roughbrdf.fitting.data`             one channel's samples: the compared quantity, what
                                           is left out (and counted), the weights
:mod:`~roughbrdf.fitting.objective`        the weighted residuals (the loss's,
                                           :class:`roughbrdf.quantity.Loss`) and the compiled
                                           finite-difference Jacobians
:mod:`~roughbrdf.fitting.search`           Sobol screening, multistart exploration, polish
:mod:`~roughbrdf.fitting.joint`            joint fits of several channels
:mod:`~roughbrdf.fitting.polarimetric`     Mueller-matrix data, all elements at once
:mod:`~roughbrdf.fitting.compare`          model choice: ``compare``, CV, ranking
:mod:`~roughbrdf.fitting.auto`             ``fit_auto``: the candidates in two stages, a
                                           candidate far behind skipped after one channel
:mod:`~roughbrdf.fitting.statistics`       covariance, stderr, correlations, chi2, AIC/BIC,
                                           sigma, rms-log
:mod:`~roughbrdf.fitting.result`           :class:`ChannelFit`, :class:`FitResult`, JSON,
                                           plots, saving
:mod:`~roughbrdf.fitting.report`           the text report
:mod:`~roughbrdf.fitting.threads`          one BLAS thread during a fit (threadpoolctl)
:mod:`roughbrdf.instrument`                the instrument aperture (cone average)
=========================================  ===================================================

Importing this package loads neither SciPy nor Matplotlib: they are imported when a fit runs
or a plot is drawn.
"""

from __future__ import annotations

from ..instrument import APERTURE_POINTS, aperture_average, aperture_stencil
from ..quantity import LOSSES, Loss
from .auto import fit_auto
from .compare import AUTO_CANDIDATES, ModelComparison, compare
from .data import ChannelData
from .fit import fit
from .objective import Objective, ObjectiveSpec
from .options import FitOptions
from .plan import FitPlan
from .plausibility import EnergyWarning
from .result import ChannelFit, FitResult

__all__ = ["fit", "FitOptions", "compare", "fit_auto", "AUTO_CANDIDATES", "ModelComparison",
           "FitResult", "ChannelFit", "FitPlan", "LOSSES", "Loss", "APERTURE_POINTS",
           "aperture_stencil", "aperture_average", "ChannelData", "Objective", "ObjectiveSpec",
           "EnergyWarning"]

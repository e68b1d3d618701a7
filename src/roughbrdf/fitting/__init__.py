"""Fitting models to measurements: :func:`fit`, :class:`FitOptions` and :class:`FitResult`
(``docs/fitting.md``).

Data flows one way: file -> :func:`roughbrdf.read` -> :class:`~roughbrdf.measurement.Measurement`
-> :func:`fit` -> :class:`FitResult` -> report, JSON, plots. Models know nothing about fitting: the
fitter reads ``model.parameters`` (value, bounds) and rebuilds the model with
``model.with_values``. Each channel is fitted on its own; ``scipy.optimize.least_squares``
(trust-region reflective, box bounds) minimizes the sum of squared residuals, one per sample:
``(K x - f)/f`` by default, whose r.m.s. is TR75's sigma (Eq. 34).

This package face only re-exports. Its inner rooms, lowest first (a room imports only the
rooms before it; ``tests/test_layers.py`` holds the order):

======================  ===================================================================
room                    what it holds
======================  ===================================================================
:mod:`.problem`         one channel's samples (``data``), residuals and Jacobians
                        (``objective``), :class:`FitOptions` (``options``), the search
                        settings (``search_options``), the plan checked before any work
                        (``plan``), the channels' wavelengths (``wavelengths``)
:mod:`.solvers`         the global search (``search``), bounded and constrained
                        Levenberg-Marquardt (``bounded``, ``constrained``), first-order
                        optimality (``stationary``), one BLAS thread (``threads``)
:mod:`.results`         :class:`FitResult` and :class:`ChannelFit` (``result``), covariance
                        and goodness of fit (``statistics``), the report (``report``),
                        albedo and peak checks (``plausibility``), parameter ranges
                        (``physical``)
:mod:`.energy`          the energy constraint (albedo <= 1) of a channel's fit
:mod:`.kinds`           channel by channel (``channels``), joint (``joint``), Mueller data
                        (``polarimetric``), per incidence (``per_incidence``)
:mod:`.choice`          ``compare`` and the held-out score (``compare``), ``--model auto``
                        (``auto``)
:mod:`.load`            a saved fit folder read back as a :class:`FitResult`
:mod:`.fit`             :func:`fit`: options from keywords; routes Mueller data,
                        ``"auto"`` and a named model
======================  ===================================================================

Importing this package loads neither SciPy nor Matplotlib: they are imported when a fit runs
or a plot is drawn.
"""

from __future__ import annotations

from ..instrument import APERTURE_POINTS, aperture_average, aperture_stencil
from ..quantity import LOSSES, Loss
from .choice.auto import fit_auto
from .choice.compare import AUTO_CANDIDATES, ModelComparison, compare
from .fit import fit
from .problem.data import ChannelData
from .problem.objective import Objective, ObjectiveSpec
from .problem.options import FitOptions
from .problem.plan import FitPlan
from .results.plausibility import EnergyWarning
from .results.result import ChannelFit, FitResult

__all__ = ["fit", "FitOptions", "compare", "fit_auto", "AUTO_CANDIDATES", "ModelComparison",
           "FitResult", "ChannelFit", "FitPlan", "LOSSES", "Loss", "APERTURE_POINTS",
           "aperture_stencil", "aperture_average", "ChannelData", "Objective", "ObjectiveSpec",
           "EnergyWarning"]

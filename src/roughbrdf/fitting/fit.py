"""``rb.fit``: the one entry point of fitting, and where it routes (``docs/fitting.md``).

:func:`fit` turns its keywords into a :class:`~roughbrdf.fitting.problem.options.FitOptions` (or
takes
one, ``options=``) and sends the work on: Mueller data to
:func:`~roughbrdf.fitting.kinds.polarimetric.fit_mueller` and a named model to
:func:`~roughbrdf.fitting.kinds.channels.fit_model`, ``"auto"`` to model choice
(:func:`~roughbrdf.fitting.choice.auto.fit_auto`). No module of the package imports this one:
model choice fits its candidates through :mod:`~roughbrdf.fitting.kinds.channels`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError
from ..models.factory import is_auto
from .choice.auto import fit_auto
from .kinds.channels import fit_model, is_mueller, refuse_polarimetric_weight
from .problem.options import FitOptions
from .results.intervals import add_profiles

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model
    from .results.result import FitResult

__all__ = ["fit"]


def fit(model: Model | str, measurement: Measurement, *, options: FitOptions | None = None,
        **keywords: Any) -> FitResult:
    """Fit ``model`` to ``measurement``, each channel on its own.

    Parameters
    ----------
    model : Model or str
        Model with starting values (``rb.model(...)``; sums allowed), a registered name or
        spec (``"coated(lobes=2)"``), or ``"auto"``: fit the candidates of
        :data:`~roughbrdf.fitting.choice.compare.AUTO_CANDIDATES` and keep the best by
        cross-validation (BIC beside it), with
        every candidate's figures and a leave-one-incidence-out score in ``model_choice``
        (:func:`~roughbrdf.fitting.choice.auto.fit_auto`; ``fix`` and ``bounds`` do not apply).
    measurement : Measurement
        The data (:func:`roughbrdf.read`).
    options : FitOptions, optional
        The options, typed (:class:`~roughbrdf.fitting.problem.options.FitOptions`, which documents
        each one); default: the defaults.
    **keywords
        The options by name, replacing those of ``options``: ``channel``, ``loss``,
        ``weights``, ``fix``, ``bounds``, ``starts``, ``seed``, ``nonfinite``, ``negative``,
        ``relative_to``, ``free_scale``, ``scale``, ``screen``, ``subsample``, ``polish``,
        ``max_nfev``, ``aperture``, ``aperture_points``, ``theta_r_max``,
        ``source_exclusion``, ``extrapolated``, ``joint``, ``shared``,
        ``polarimetric_weight``, ``progress``
        (:class:`~roughbrdf.fitting.problem.options.FitOptions`).

    Returns
    -------
    FitResult
        For Mueller data a :class:`~roughbrdf.fitting.kinds.polarimetric.MuellerFitResult`: every
        element is fitted at once (one channel, ``"mueller"``; ``docs/fitting.md``,
        "Polarimetric data").

    Raises
    ------
    TypeError
        A keyword that is no option; a measurement that is not a Measurement.
    ValueError
        Unknown loss or option, every parameter fixed, no data left in a channel, non-finite
        values with ``nonfinite="raise"``, non-positive values for the log loss with
        ``negative="keep"``, an aperture that is negative, not finite or >= pi/2, a
        ``theta_r_max`` or ``source_exclusion`` outside [0, pi/2] or [0, pi], bounds that
        do not contain the starting value or leave a parameter's physical domain. Errors
        about an argument are :class:`~roughbrdf.errors.ArgumentError` (naming the argument,
        the value and, where there is one, the fix; ``err.render(options)`` words them for
        the command line).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> g = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))
    >>> meas = rb.Measurement(*g, rb.model("lambertian", rho=0.3).brdf(*g))
    >>> opts = rb.FitOptions(starts=1, progress=False)
    >>> round(rb.fit("lambertian", meas, options=opts)[0].params["rho"], 6)
    0.3
    """
    opts = FitOptions.of(options, keywords)
    if is_auto(model) and not is_mueller(measurement):  # Mueller fits refuse "auto"
        refuse_polarimetric_weight(opts)
        return fit_auto(measurement, options=opts)  # the kept fit's profiles if asked
    if is_mueller(measurement) and opts.intervals == "profile":
        raise ArgumentError("intervals", "profile intervals are for BRDF channels fitted on "
                            "their own, not Mueller elements", value=opts.intervals)
    res = fit_model(model, measurement, opts)
    if opts.joint or is_mueller(measurement):
        return res
    # with intervals='profile': one-sided limits and profile intervals (results.intervals)
    return add_profiles(res, measurement, opts)

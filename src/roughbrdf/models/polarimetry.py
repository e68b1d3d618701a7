"""Polarimetric evaluation of a model: an incident Stokes vector in, an analyzer row out.

:meth:`roughbrdf.models.Model.evaluate` runs :func:`evaluate_stokes` when its polarization
:attr:`~roughbrdf.polarization.Polarization.is_polarimetric` (a Stokes vector or an analyzer is
set): the value is ``a . (M S)`` with ``M`` the model's Mueller matrix
(:meth:`roughbrdf.models.Model.mueller`, conventions of :mod:`roughbrdf.mueller`), ``S`` the
incident Stokes vector and ``a`` the detector's row (``docs/polarization.md``).

This module sits beside :mod:`roughbrdf.models.base` and imports neither it nor anything that
imports it at run time: :mod:`roughbrdf.polarization` (the argument type) and
:mod:`roughbrdf.stokes` (the vectors) stay below the models.

Examples
--------
>>> import roughbrdf as rb
>>> from roughbrdf.polarization import Polarization
>>> m = rb.model("microfacet", distribution="beckmann", alpha=0.3, n=0.2, k=3.0)
>>> pol = Polarization(stokes=[1.0, 0.0, 0.0, 0.0])          # natural light, total intensity
>>> bool(abs(evaluate_stokes(m, 0.5, 0.5, 0.0, pol) - m.brdf(0.5, 0.5, 0.0)) < 1e-12)
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..geometry import check_broadcast
from ..quantity import Quantity

if TYPE_CHECKING:
    from ..polarization import Polarization

__all__ = ["evaluate_stokes"]


def evaluate_stokes(model: Any, theta_i: Any, theta_r: Any, phi: Any,
                    polarization: Polarization, *, quantity: Quantity | str = "brdf",
                    term: str | None = None) -> np.ndarray | float:
    """``a . (M S)``: the analyzer-weighted reflected value for an incident Stokes vector.

    ``M`` is ``model.mueller(theta_i, theta_r, phi, basis=polarization.basis, term=term)``
    (sr⁻¹), ``S`` :meth:`Polarization.incident_stokes
    <roughbrdf.polarization.Polarization.incident_stokes>` and ``a`` the analyzer (None: the
    total intensity ``(M S)[0]``). ``quantity`` as in :meth:`roughbrdf.models.Model.evaluate`:
    ``brdf``, ``brdf_cos``/``bridf`` (times ``cos theta_r``) or ``relative`` (divided by the
    same at the specular direction). This is what ``Model.evaluate`` runs when the
    polarization :attr:`~roughbrdf.polarization.Polarization.is_polarimetric`.

    Returns
    -------
    numpy.ndarray or float
        The broadcast shape of the angles and the leading axes of ``stokes`` and
        ``analyzer``; a float when that is ``()``.
    """
    q = Quantity.parse(quantity)
    value = _detected(model, theta_i, theta_r, phi, polarization, term)
    if q is Quantity.RELATIVE:
        ti = np.asarray(theta_i, dtype=float)
        value = value / _detected(model, ti, ti, np.zeros_like(ti), polarization, term)
    elif q.cosine_weighted:
        value = value * np.cos(np.asarray(theta_r, dtype=float))
    return float(value) if np.ndim(value) == 0 else value


def _detected(model: Any, theta_i: Any, theta_r: Any, phi: Any, pol: Polarization,
              term: str | None) -> np.ndarray:
    """``a . (M S)`` (or ``(M S)[0]``), broadcast over the angles, ``stokes`` and
    ``analyzer``."""
    mat = np.asarray(model.mueller(theta_i, theta_r, phi, basis=pol.basis, term=term),
                     dtype=float)
    s_in = pol.incident_stokes()
    shapes = {"angles": mat.shape[:-2], "stokes": s_in.shape[:-1]}
    if pol.analyzer is not None:
        shapes["analyzer"] = pol.analyzer.shape[:-1]
    check_broadcast(**{k: np.broadcast_to(0.0, v) for k, v in shapes.items()})
    out = np.matmul(mat, s_in[..., None])[..., 0]
    if pol.analyzer is None:
        return out[..., 0]
    return np.sum(pol.analyzer * out, axis=-1)

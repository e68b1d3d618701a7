"""Fitting models to measurements: :func:`fit` and :class:`FitResult`.

Data flows one way: file -> :func:`roughbrdf.read` -> :class:`~roughbrdf.measurement.Measurement`
-> :func:`fit` -> :class:`FitResult` -> report, JSON, plots. Models know nothing about fitting: the
fitter reads ``model.parameters`` (value, bounds) and rebuilds the model with
``model.with_values``.

What is minimized
-----------------
For each channel, ``scipy.optimize.least_squares`` (``method="trf"``, box bounds) minimizes
``sum(r_i^2)`` with one residual per sample:

``relative`` (default)
    ``r = w (x - f)/f`` -- Trowbridge & Reitz's measure; the r.m.s. of ``(x - f)/f`` is their
    ``sigma`` (TR75 Eq. 34, MODELS.md §3.9).
``log``
    ``r = w (ln x - ln f)``.
``absolute``
    ``r = w (x - f)``.

``x`` is the measured value, ``f`` the model value of the *same quantity*: the model BRDF for
``brdf`` data, BRDF·cos(theta_r) (TR75's BRIDF) for ``brdf_cos``/``bridf`` data. A ``relative``
measurement has no absolute scale: it is compared with the model BRDF or BRIDF (option
``relative_to``; default ``measurement.meta["relative_to"]`` if the file says, else ``"brdf"``)
through a free scale ``K`` (``x -> K x``), solved in closed form at every residual evaluation
(MODELS.md §3.9 reading (a)); for the relative loss ``K = sum(w^2 q)/sum(w^2 q^2)`` with
``q = x/f``, which minimizes TR75's sigma exactly. ``K`` is therefore not an optimizer variable,
but it is counted as a fitted parameter in the statistics, and its standard error is reported.

Global search and speed
-----------------------
Each channel is fitted on its own. ``starts`` local fits are run: one from the model's current
values, the others from scrambled Sobol points in the bounds of the free parameters
(:class:`scipy.stats.qmc.Sobol`): ``screen`` Sobol points are evaluated once each and the best
ones, kept apart from each other, are used. When several channels are fitted, the best point of
the previous channel is one more start (a warm start; every channel still gets all its own
starts). When a channel has more than ``subsample`` samples, the local fits from the starts run on
a fixed random subsample of that size, and the ``polish`` best distinct end points are then
refined on all samples; the best of those is the result. The Jacobian is a forward finite
difference computed through the compiled model kernel: one vectorized model evaluation per free
parameter (never a Python loop over samples). The final covariance uses a central-difference
Jacobian on all samples. OpenBLAS runs single-threaded during a fit (:class:`_SingleThreadBLAS`).
``docs/fitting.md`` has the benchmarks.

Instrument aperture
-------------------
A real gonioreflectometer does not measure the BRDF at one direction: its detector (and source)
see a small cone, which flattens the top of a peak narrower than the cone (the CEA gray tape's
retro peak). With ``aperture=a`` (radians) the model prediction for each sample is the average of
the model over a **uniform cone of half-angle** ``a`` (uniform in solid angle, i.e. a spherical
cap) **about the measured reflection direction** ``w_r``; ``theta_i`` is kept. The cone stands for
the combined angular response of source and detector (for a peak that depends on the angle
between ``w_r`` and a fixed direction, a source cone acts like a detector cone of the same size).
The average is a fixed cubature rule (:func:`aperture_stencil`): the cone axis plus rings, at
``u = (1 - cos beta)/(1 - cos a)`` (uniform on [0, 1] over the cap) given by Gauss-Radau nodes
with the node ``u = 0`` (the axis), and equally spaced azimuths on each ring. ``aperture_points``
chooses the rule:

====  ======================  ==============================================================
 S    rings x points          exact (to round-off) for polynomials of the direction vector's
                              components of degree <= (flat-disk limit: degree in the plane)
====  ======================  ==============================================================
 7    1 x 6 (Radon's rule)    2   (5)
 19   2 x 9 (default)         4   (8)
 37   3 x 12                  6   (11)
====  ======================  ==============================================================

so a constant and any quadratic function of direction are averaged exactly by every rule. The
perturbed angles are built once per fit with NumPy, and the model is evaluated on all ``N x S``
directions in one call of the compiled kernel, then averaged over ``S`` (the Jacobian uses the
same path): a fit costs about ``S`` times more. Directions of the cone below the surface are
clipped to the horizon. ``aperture=None`` or ``0`` is the plain fit, unchanged.
:func:`aperture_average` gives the same average for any model and geometry, and
:meth:`FitResult.predict` the fitted model as the fit compared it with the data.

Uncertainties
-------------
``covar = (J^T J)^-1 * chi2/(N - n_varys)``, with ``J`` the Jacobian of the residuals at the optimum
(free parameters, plus the scale ``K`` when it is free), i.e. scaled by the residual variance as
lmfit does by default (``scale_covar=True``): the stderr assume the residuals' spread is the noise.
``stderr = sqrt(diag(covar))``; ``correl`` is ``covar`` normalized. A singular ``J^T J`` gives
``nan`` stderr and says so in the message.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc

from .measurement import Measurement
from .models import Model, PreparedGeometry
from .models import model as _make_model

__all__ = ["fit", "FitResult", "ChannelFit", "LOSSES", "APERTURE_POINTS",
           "aperture_stencil", "aperture_average"]

#: residual definitions accepted by :func:`fit`
LOSSES = ("relative", "log", "absolute")

_EPS_STEP = math.sqrt(np.finfo(float).eps)  # forward-difference step (relative)
_CENTRAL_STEP = np.finfo(float).eps ** (1.0 / 3.0)  # central-difference step (relative)
# Floor applied to model values before dividing or taking logs, relative to the largest |x|:
# a model value of exactly 0 (e.g. an underflowed Beckmann lobe) must not give inf.
_F_FLOOR = 1e-12
# Residuals that are still not finite (a model that overflows at some trial parameters) are
# replaced by this value, so that the optimizer sees a large, finite cost and steps back.
_BAD_RESIDUAL = 1e6
# Tolerance of the local fits of the exploration stage: they only need to find the basin, the
# polish on all samples converges tightly (1e-9).
_EXPLORE_TOL = 1e-4
_SCREEN_DIST = 0.15
_POLISH_TOL = 1e-8
_X_SCALE = "jac"


# ---------------------------------------------------------------------------------------------
# BLAS threads
# ---------------------------------------------------------------------------------------------
_BLAS_FUNCS = (("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
               ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
               ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
               ("openblas_get_num_threads", "openblas_set_num_threads"))


def _openblas_handles() -> list[tuple[Any, Any]]:
    """(get, set) thread-count functions of every OpenBLAS loaded in this process (Linux)."""
    import ctypes

    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as fh:
            paths = {ln.split()[-1] for ln in fh if "openblas" in ln.lower() and "/" in ln}
    except OSError:
        return []
    out = []
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for get_name, set_name in _BLAS_FUNCS:
            get, set_ = getattr(lib, get_name, None), getattr(lib, set_name, None)
            if get is not None and set_ is not None:
                get.restype = ctypes.c_int
                set_.argtypes = [ctypes.c_int]
                out.append((get, set_))
                break
    return out


class _SingleThreadBLAS:
    """Run a block with OpenBLAS limited to one thread; the previous counts are restored.

    The matrices of a fit are N x p with p <= ~15 (Jacobian products, a thin SVD per step):
    memory-bound work that BLAS threads do not speed up, while on a busy machine their
    spin-waiting makes each of ``least_squares``' small BLAS calls take milliseconds (measured:
    a 13k-sample TR75 fit spent 3x longer in SciPy's trust-region step than in the model). What
    threadpoolctl does, without the dependency; a no-op where OpenBLAS is not found.
    """

    def __enter__(self) -> _SingleThreadBLAS:
        self.saved = []
        for get, set_ in _openblas_handles():
            try:
                n = int(get())
                if n > 1:
                    set_(1)
                    self.saved.append((set_, n))
            except Exception:  # noqa: BLE001 - never let thread tuning break a fit
                continue
        return self

    def __exit__(self, *exc: Any) -> None:
        for set_, n in self.saved:
            set_(n)


# ---------------------------------------------------------------------------------------------
# instrument aperture: cubature over a uniform cone of directions
# ---------------------------------------------------------------------------------------------
#: stencil sizes accepted by ``aperture_points`` -> (rings, points per ring)
APERTURE_POINTS = {7: (1, 6), 19: (2, 9), 37: (3, 12)}


def _radau01(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Radau rule on [0, 1] with the node 0 and ``m`` interior nodes (exact to degree 2m)."""
    from numpy.polynomial import legendre as leg

    # on [-1, 1] with the node -1: the other nodes are the roots of (P_m + P_{m+1})/(1 + x)
    c = np.zeros(m + 2)
    c[m] = c[m + 1] = 1.0
    q, _ = np.polynomial.polynomial.polydiv(leg.leg2poly(c), [1.0, 1.0])
    x = np.sort(np.real(np.polynomial.polynomial.polyroots(q)))
    u = np.concatenate([[0.0], 0.5 * (x + 1.0)])
    # weights from the moments int_0^1 u^k du = 1/(k+1), k = 0..m (the rule is then exact to 2m)
    vander = np.vander(u, m + 1, increasing=True).T
    w = np.linalg.solve(vander, 1.0 / np.arange(1, m + 2))
    return u, w


def aperture_stencil(aperture: float, points: int = 19
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubature rule for the average over a uniform cone of half-angle ``aperture`` (radians).

    Returns ``(beta, psi, weight)``, each of shape ``(points,)``: the polar angle of each node
    from the cone axis, its azimuth about the axis, and weights summing to 1. The nodes are the
    axis plus ``rings`` rings (``APERTURE_POINTS``) at Gauss-Radau values of
    ``u = (1 - cos beta)/(1 - cos aperture)``; see the module notes for the accuracy.
    """
    if points not in APERTURE_POINTS:
        raise ValueError(f"aperture_points must be one of {sorted(APERTURE_POINTS)}, "
                         f"got {points!r}")
    rings, per = APERTURE_POINTS[points]
    u, wu = _radau01(rings)
    one_minus_cos = 2.0 * math.sin(0.5 * aperture) ** 2  # 1 - cos(a) without cancellation
    beta = [0.0]
    psi = [0.0]
    wt = [wu[0]]
    for r in range(1, rings + 1):
        b = math.acos(1.0 - u[r] * one_minus_cos)
        offset = math.pi / per if r % 2 == 0 else 0.0  # alternate rings are staggered
        for k in range(per):
            beta.append(b)
            psi.append(offset + 2.0 * math.pi * k / per)
            wt.append(wu[r] / per)
    return np.array(beta), np.array(psi), np.array(wt)


def _aperture_directions(theta_r: np.ndarray, phi: np.ndarray, aperture: float, points: int
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(theta_r, phi)`` of the stencil nodes about each reflection direction, shape (N, S),
    and the weights (S,)."""
    from . import geometry

    beta, psi, wt = aperture_stencil(aperture, points)
    tr = np.asarray(theta_r, dtype=float)[:, None]
    ph = np.asarray(phi, dtype=float)[:, None]
    zero = np.zeros_like(tr)
    w_i, w_r = geometry.unit_vectors(zero, tr, ph)  # (N, 1, 3); w_i only for the conversion
    # orthonormal frame about w_r: d w_r/d theta_r and d w_r/d phi / sin(theta_r); both are
    # defined at the pole, so the cone is right for theta_r = 0 too
    e1 = np.stack([np.cos(tr) * np.cos(ph), np.cos(tr) * np.sin(ph), -np.sin(tr)], axis=-1)
    e2 = np.stack([-np.sin(ph), np.cos(ph), zero], axis=-1)
    cb, sb = np.cos(beta)[:, None], np.sin(beta)[:, None]
    cp, sp = np.cos(psi)[:, None], np.sin(psi)[:, None]
    w = cb * w_r + sb * (cp * e1 + sp * e2)  # (N, S, 3)
    _, tr_s, ph_s = geometry.angles_from_vectors(np.broadcast_to(w_i, w.shape), w)
    # Horizon guard: near grazing reflection part of the cone lies below the surface, where no
    # model is defined (theta_r > 90 deg). Those nodes are clipped to the horizon (theta_r =
    # 90 deg, same azimuth): BRDF cos theta_r is 0 there for every model, and a model whose
    # BRDF is infinite at the horizon makes the sample "model_domain" (left out and counted).
    tr_s = np.minimum(tr_s, 0.5 * math.pi)
    return tr_s, ph_s, wt


def _check_aperture(aperture: Any, points: Any) -> float | None:
    """The aperture half-angle as a float, or None for no aperture (None or 0)."""
    if aperture is None:
        return None
    try:
        a = float(aperture)
    except (TypeError, ValueError):
        raise ValueError(f"aperture must be None or a half-angle in radians, got "
                         f"{aperture!r}") from None
    if not (math.isfinite(a) and 0.0 <= a < 0.5 * math.pi):
        raise ValueError(f"aperture must be a half-angle in radians with 0 <= aperture < pi/2, "
                         f"got {aperture!r}")
    if points not in APERTURE_POINTS:
        raise ValueError(f"aperture_points must be one of {sorted(APERTURE_POINTS)}, "
                         f"got {points!r}")
    return a if a > 0.0 else None


def aperture_average(model: Model, theta_i: Any, theta_r: Any, phi: Any,
                     aperture: float | None, *, points: int = 19, quantity: str = "brdf",
                     polarization: Any = None) -> np.ndarray | float:
    """Average of ``model`` over a uniform cone of half-angle ``aperture`` about each ``w_r``.

    What an instrument of that angular response would read; the prediction :func:`fit` compares
    with the data when given ``aperture``. ``quantity`` is ``"brdf"`` or ``"bridf"`` (BRDF
    cos theta_r, averaged as such). ``aperture=None`` or 0 gives the model itself.
    """
    a = _check_aperture(aperture, points)
    if quantity not in ("brdf", "bridf"):
        raise ValueError(f"quantity must be 'brdf' or 'bridf', got {quantity!r}")
    g = model.prepare(theta_i, theta_r, phi, polarization)
    ti, tr, ph, gam = g.theta_i, g.theta_r, g.phi, g.gamma
    if a is None:
        return model.evaluate_prepared(g, quantity)
    ti, tr, ph, gam = np.broadcast_arrays(ti, tr, ph, gam)
    shape = ti.shape
    tr_s, ph_s, wt = _aperture_directions(tr.ravel(), ph.ravel(), a, points)
    ti_s = np.broadcast_to(ti.reshape(-1, 1), tr_s.shape)
    gam_s = np.broadcast_to(gam.reshape(-1, 1), tr_s.shape)
    f = np.asarray(model.evaluate_prepared(PreparedGeometry(
        np.ascontiguousarray(ti_s), tr_s, ph_s, np.ascontiguousarray(gam_s)), quantity),
        dtype=float)
    out = f.reshape(tr_s.shape) @ wt
    return float(out[0]) if shape == () else out.reshape(shape)


# ---------------------------------------------------------------------------------------------
# one channel's objective
# ---------------------------------------------------------------------------------------------
class _Objective:
    """Residuals of one channel (or a subsample of it) as a function of the free parameters."""

    def __init__(self, base: Model, free: list[str], lo: np.ndarray, hi: np.ndarray,
                 ti: np.ndarray, tr: np.ndarray, ph: np.ndarray, gamma: np.ndarray,
                 x: np.ndarray, w: np.ndarray | None, flag: int, loss: str, free_scale: bool,
                 fixed_scale: float = 1.0, stencil: np.ndarray | None = None):
        self.base, self.free, self.lo, self.hi = base, free, lo, hi
        self.flag = flag
        # with an aperture: ti, tr, ph are (N, S) (the stencil's directions about each sample),
        # flattened here for one kernel call; ``stencil`` holds the S weights
        self.stencil = stencil
        if stencil is not None:
            shape = (x.size, stencil.size)
            ti, tr, ph = (np.ascontiguousarray(np.broadcast_to(a, shape)).ravel()
                          for a in (ti, tr, ph))
            if np.ndim(gamma):
                gamma = np.ascontiguousarray(np.broadcast_to(gamma[:, None], shape)).ravel()
        self.ti, self.tr, self.ph = ti, tr, ph
        self.gamma = gamma
        self.x, self.w, self.loss, self.free_scale = x, w, loss, free_scale
        self.fixed_scale = fixed_scale
        self.w2 = None if w is None else w * w
        self.floor = _F_FLOOR * max(float(np.max(np.abs(x))), 1e-300)
        self.logx = np.log(x) if loss == "log" else None
        self.n = x.size
        self.nfev = 0
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    # model ------------------------------------------------------------------------------------
    def model_at(self, theta: np.ndarray) -> Model:
        return self.base.with_values(self.free, [float(t) for t in theta])

    def values(self, theta: np.ndarray) -> np.ndarray:
        """Model values at the samples (one call of the compiled kernel); with an aperture, the
        weighted average over the stencil of each sample."""
        self.nfev += 1
        f = np.asarray(self.model_at(theta).evaluate_prepared(
            PreparedGeometry(self.ti, self.tr, self.ph, self.gamma),
            "brdf_cos" if self.flag else "brdf"), dtype=float)
        if self.stencil is not None:
            f = f.reshape(self.n, self.stencil.size) @ self.stencil
        return f

    # residuals --------------------------------------------------------------------------------
    def _sum(self, a: np.ndarray) -> float:
        return float(a.sum() if self.w2 is None else (self.w2 * a).sum())

    def scale(self, f: np.ndarray) -> float:
        """Closed-form scale K of the data (``x -> K x``) for the model values ``f``."""
        if not self.free_scale:
            return self.fixed_scale
        fs = np.maximum(f, self.floor)
        x = self.x
        if self.loss == "relative":
            q = x / fs
            den = self._sum(q * q)
            k = self._sum(q) / den if den > 0 else 1.0
        elif self.loss == "absolute":
            den = self._sum(x * x)
            k = self._sum(x * fs) / den if den > 0 else 1.0
        else:  # log: ln K = weighted mean of (ln f - ln x)
            wsum = float(self.n if self.w2 is None else self.w2.sum())
            k = math.exp(self._sum(np.log(fs) - self.logx) / wsum)
        return k if math.isfinite(k) and k > 0 else 1.0

    def residual_of(self, f: np.ndarray, k: float | None = None) -> np.ndarray:
        if k is None:
            k = self.scale(f)
        fs = np.maximum(f, self.floor)
        if self.loss == "relative":
            r = (k * self.x) / fs - 1.0
        elif self.loss == "absolute":
            r = k * self.x - f
        else:
            r = self.logx + math.log(k) - np.log(fs)
        if self.w is not None:
            r = r * self.w
        if not np.isfinite(r).all():
            r = np.where(np.isfinite(r), r, _BAD_RESIDUAL)
        return r

    def fun(self, theta: np.ndarray) -> np.ndarray:
        r = self.residual_of(self.values(theta))
        self._last = (np.array(theta, dtype=float), r)
        return r

    def _step(self, theta: np.ndarray, j: int, rel: float) -> float:
        span = self.hi[j] - self.lo[j]
        h = rel * max(abs(theta[j]), 1e-3 * span if math.isfinite(span) else 1e-3, 1e-8)
        if theta[j] + h > self.hi[j]:
            h = -h
        return h

    def jac(self, theta: np.ndarray, k: float | None = None) -> np.ndarray:
        """Forward-difference Jacobian: one compiled model evaluation per free parameter.

        With ``k=None`` the scale is re-solved at each perturbed point (the Jacobian of the
        profiled residual the optimizer sees); with ``k`` given it is held fixed.
        """
        theta = np.asarray(theta, dtype=float)
        if k is None and self._last is not None and np.array_equal(self._last[0], theta):
            r0 = self._last[1]
        else:
            r0 = self.residual_of(self.values(theta), k)
        out = np.empty((self.n, theta.size))
        for j in range(theta.size):
            h = self._step(theta, j, _EPS_STEP)
            t = theta.copy()
            t[j] += h
            out[:, j] = (self.residual_of(self.values(t), k) - r0) / h
        return out

    def jac_central(self, theta: np.ndarray, k: float) -> np.ndarray:
        """Central-difference Jacobian at fixed scale ``k`` (for the covariance)."""
        out = np.empty((self.n, theta.size))
        for j in range(theta.size):
            h = abs(self._step(theta, j, _CENTRAL_STEP))
            lo_ok = theta[j] - h >= self.lo[j]
            hi_ok = theta[j] + h <= self.hi[j]
            tp, tm = theta.copy(), theta.copy()
            if lo_ok and hi_ok:
                tp[j] += h
                tm[j] -= h
                d = 2 * h
            elif hi_ok:
                tp[j] += h
                d = h
            else:
                tm[j] -= h
                d = h
            out[:, j] = (self.residual_of(self.values(tp), k)
                         - self.residual_of(self.values(tm), k)) / d
        return out

    def scale_column(self, f: np.ndarray, k: float) -> np.ndarray:
        """d r / d K at fixed model values (analytic)."""
        fs = np.maximum(f, self.floor)
        if self.loss == "relative":
            col = self.x / fs
        elif self.loss == "absolute":
            col = self.x.copy()
        else:
            col = np.full(self.n, 1.0 / k)
        return col if self.w is None else col * self.w


# ---------------------------------------------------------------------------------------------
# results
# ---------------------------------------------------------------------------------------------
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
        ``name -> standard error`` (``None`` for fixed parameters, ``nan`` if not estimable).
    correl : dict
        ``name -> {other: correlation}`` among the free parameters (and ``"scale"``).
    covar : numpy.ndarray
        Covariance of ``free`` (+ ``scale`` last if it is free).
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
        Every start: ``{"x0": ..., "cost": ..., "stage": "explore"|"full"}``.
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

    @property
    def metrics(self) -> dict[str, float | int]:
        """The figures of merit, as in ``fit.json``."""
        return {"sigma": self.sigma, "rms_log": self.rms_log, "chi2": self.chi2,
                "redchi": self.redchi, "aic": self.aic, "bic": self.bic,
                "n_points": self.n_points, "n_varys": self.n_varys}


def _clean(v: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars -> Python."""
    if isinstance(v, dict):
        return {str(k): _clean(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_clean(x) for x in v]
    if isinstance(v, np.ndarray):
        return _clean(v.tolist())
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, float | np.floating):
        v = float(v)
        return v if math.isfinite(v) else None
    return v


def _fmt(v: float | None, digits: int = 6) -> str:
    if v is None:
        return "None"
    if not math.isfinite(v):
        return str(v)
    return f"{v:.{digits}g}"


@dataclass
class FitResult:
    """Result of :func:`fit`: one :class:`ChannelFit` per fitted channel.

    ``aperture`` / ``aperture_points`` record the instrument aperture the fit used (None: none);
    :meth:`predict` evaluates the fitted model the way the fit compared it with the data.
    ``res[label]`` or ``res[i]`` gives a channel. For a fit of a single channel, ``model``,
    ``params``, ``stderr``, ``correl``, ``sigma``, ``rms_log`` and ``message`` are that channel's;
    with several channels they raise and point to ``res[...]``. ``success`` is true when every
    channel succeeded.
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
    #: so that predictions and plots can average the model the same way (:meth:`predict`)
    aperture: float | None = None
    aperture_points: int = 19

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
        c = self[channel] if isinstance(channel, str) else self.channels[channel]
        q = "bridf" if self.compared in ("bridf", "brdf_cos") else "brdf"
        return aperture_average(c.model, theta_i, theta_r, phi,
                                self.aperture if aperture else None,
                                points=self.aperture_points, quantity=q,
                                polarization=polarization)

    # output ---------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The ``fit.json`` content (keys ``model``, ``file``, ``loss``, ``channels`` ...)."""
        meta = self.measurement.meta
        chans = []
        for c in self.channels:
            chans.append({
                "channel": c.channel,
                "params": c.params,
                "stderr": c.stderr,
                "success": bool(c.success),
                "metrics": c.metrics,
                "message": c.message,
                "free": c.free,
                "init": c.init,
                "bounds": {k: list(v) for k, v in c.bounds.items()},
                "scale": c.scale,
                "scale_stderr": c.scale_stderr,
                "correl": c.correl,
                "excluded": c.excluded,
                "nfev": c.nfev,
                "elapsed_s": c.elapsed,
                "model_spec": c.model.to_dict(),
            })
        return _clean({
            "model": self.model_name,
            "file": meta.get("file"),
            "loss": self.loss,
            "quantity": self.measurement.quantity,
            "compared": self.compared,
            "relative_to": self.relative_to,
            "sample": meta.get("sample"),
            "options": self.options,
            "aperture": None if self.aperture is None else {
                "half_angle_rad": self.aperture,
                "half_angle_deg": math.degrees(self.aperture),
                "points": self.aperture_points,
                "convention": "model averaged over a uniform cone (solid angle) of this "
                              "half-angle about the measured reflection direction"},
            "elapsed_s": self.elapsed,
            "channels": chans,
        })

    def to_json(self, path: str | None = None, *, indent: int = 2) -> str:
        """JSON text of :meth:`to_dict` (strict JSON: NaN written as ``null``); optionally saved."""
        text = json.dumps(self.to_dict(), indent=indent, allow_nan=False)
        if path is not None:
            with open(path, "w", encoding="utf-8") as fh:
                fh.write(text + "\n")
        return text

    def report(self, *, min_correl: float = 0.1) -> str:
        """lmfit-style text report of every channel."""
        meta = self.measurement.meta
        src = meta.get("file") or meta.get("sample") or "<measurement in memory>"
        loss_txt = {"relative": "relative, (x - f)/f  (TR75 Eq. 34)",
                    "log": "log, ln x - ln f", "absolute": "absolute, x - f"}[self.loss]
        comp = f"model {self.compared}"
        if self.relative_to:
            comp += " (relative data: free scale K, x -> K x, closed form)"
        lines = [f"[[Fit]] {self.model_name} to {src}",
                 f"    data quantity      = {self.measurement.quantity}",
                 f"    compared with      = {comp}",
                 f"    loss               = {loss_txt}",
                 "    aperture           = " + (
                     "none (model at each measured direction)" if self.aperture is None else
                     f"{math.degrees(self.aperture):.4g} deg half-angle, uniform cone about "
                     f"w_r ({self.aperture_points}-point stencil)"),
                 f"    channels           = {len(self.channels)}",
                 f"    time               = {self.elapsed:.3g} s"]
        for c in self.channels:
            lines.append("")
            lines.append(f"[[Channel {c.channel}]]")
            exc = _excluded_text(c.excluded)
            nst = len([s for s in c.starts if s["stage"] != "full"])
            lines += [
                f"    success            = {c.success}  ({c.message})",
                f"    # data points      = {c.n_points}  (left out / changed: {exc})",
                f"    # variables        = {c.n_varys}"
                + ("  (including the scale K)" if c.free_scale else ""),
                f"    # starts           = {nst}",
                f"    # model evals      = {c.nfev}",
                f"    chi-square         = {_fmt(c.chi2)}",
                f"    reduced chi-square = {_fmt(c.redchi)}",
                f"    Akaike info crit   = {_fmt(c.aic)}",
                f"    Bayesian info crit = {_fmt(c.bic)}",
                f"    TR75 sigma         = {_fmt(c.sigma, 4)}   (r.m.s. of (Kx - f)/f)",
                f"    r.m.s. log resid.  = {_fmt(c.rms_log, 4)}",
                "[[Variables]]",
            ]
            width = max(len(n) for n in [*c.params, "scale K"])
            for name, val in c.params.items():
                if name in c.free:
                    se = c.stderr.get(name)
                    if se is not None and math.isfinite(se) and val:
                        pct = f" ({100 * se / abs(val):.2f}%)"
                    else:
                        pct = ""
                    lo, hi = c.bounds[name]
                    txt = (f"{_fmt(val, 7)} +/- {_fmt(se, 4)}{pct} (init = {_fmt(c.init[name])}, "
                           f"bounds [{_fmt(lo)}, {_fmt(hi)}])")
                elif val is None:
                    txt = "None (switched off)"
                else:
                    txt = f"{_fmt(val, 7)} (fixed)"
                lines.append(f"    {name:<{width}}: {txt}")
            if c.free_scale:
                lines.append(f"    {'scale K':<{width}}: {_fmt(c.scale, 7)} +/- "
                             f"{_fmt(c.scale_stderr, 4)} (closed form)")
            elif c.scale != 1.0:
                lines.append(f"    {'scale K':<{width}}: {_fmt(c.scale, 7)} (given)")
            pairs = []
            names = list(c.correl)
            for i, a in enumerate(names):
                for b in names[i + 1:]:
                    v = c.correl[a].get(b)
                    if v is not None and math.isfinite(v) and abs(v) >= min_correl:
                        pairs.append((abs(v), a, b, v))
            if pairs:
                lines.append(f"[[Correlations]] (unreported correlations are < {min_correl:.3f})")
                for _, a, b, v in sorted(pairs, reverse=True):
                    lines.append(f"    C({a}, {b}) = {v:+.4f}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.report()

    def plot_data(self, channel: int | str = 0) -> tuple[Model, Measurement]:
        """The fitted model and the fitted samples of one channel on the model's absolute scale.

        Relative data are multiplied by the fitted ``K`` and labelled with the quantity they were
        compared with (``brdf`` or ``bridf``), so that data and model share one axis.
        """
        c = self[channel] if isinstance(channel, str) else self.channels[channel]
        meas = self.measurement.subset(c.index).select_channel(c.channel)
        q = self.compared if self.compared in ("brdf", "bridf") else self.measurement.quantity
        meas = replace(meas, values=(c.scale * c.data)[:, None],
                       quantity="bridf" if q in ("bridf", "brdf_cos") else "brdf",
                       uncertainty=None, meta=dict(meas.meta))
        return c.model, meas

    def plot(self, channel: int | str = 0, *, fig: Any = None) -> tuple[Any, Any]:
        """Data vs model (in-plane slices per incidence) and the residual map of one channel.

        Uses :func:`roughbrdf.plot.plot_comparison` and :func:`roughbrdf.plot.plot_residual_map`;
        returns ``(fig, (ax_comparison, ax_residuals))``. Both draw the fitted model at each
        direction, not averaged over the fit's aperture (the plot module does not know it yet;
        ``self.aperture`` and :meth:`predict` are there for it): with an aperture, a sharp peak
        shows above the data it was fitted to.
        """
        import matplotlib.pyplot as plt

        from . import plot as rbplot

        model, meas = self.plot_data(channel)
        if fig is None:
            fig = plt.figure(figsize=(12, 5))
        ax1 = fig.add_subplot(1, 2, 1)
        ax2 = fig.add_subplot(1, 2, 2)
        rbplot.plot_comparison(model, meas, channel=0, ax=ax1)
        rbplot.plot_residual_map(model, meas, channel=0, ax=ax2)
        fig.tight_layout()
        return fig, (ax1, ax2)

    def plot_names(self) -> list[str]:
        """File names :meth:`save` gives the per-channel plots (``fit_<channel>.png``)."""
        out = []
        for c in self.channels:
            safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in c.channel)
            out.append(f"fit_{safe or 'channel'}.png")
        return out

    def save(self, out_dir: str | Any, *, plots: bool = True, force: bool = False,
             dpi: int = 110) -> list[Any]:
        """Write ``fit.json``, ``report.txt`` and one ``fit_<channel>.png`` per channel.

        ``out_dir`` may exist. Files roughbrdf wrote there before are replaced; any other file of
        the same name stops the call with ``FileExistsError`` before anything is written, unless
        ``force=True`` (see :mod:`roughbrdf._outdir`). Returns the paths written.
        """
        from ._outdir import OutputDir

        out = OutputDir(out_dir, force=force)
        names = ["fit.json", "report.txt", *(self.plot_names() if plots else [])]
        out.check(names)
        written = [out.file("fit.json")]
        self.to_json(str(written[0]))
        written.append(out.write_text("report.txt", self.report()))
        if plots:
            import matplotlib.pyplot as plt

            for i, name in enumerate(self.plot_names()):
                fig, _ = self.plot(i)
                path = out.file(name)
                fig.savefig(path, dpi=dpi, metadata={"Software": "roughbrdf"})
                plt.close(fig)
                written.append(path)
        return written


# ---------------------------------------------------------------------------------------------
# the fit
# ---------------------------------------------------------------------------------------------
def _model_label(m: Model) -> str:
    comps = getattr(m, "components", None)
    return "+".join(c.name for c in comps) if comps else m.name


def _screen(obj: _Objective, cand: np.ndarray, k: int, lo: np.ndarray, hi: np.ndarray
            ) -> list[np.ndarray]:
    """The ``k`` best of the candidate points by cost (one model evaluation each), skipping
    points closer than ``_SCREEN_DIST`` (in units of the bounds) to a better one already kept."""
    if k <= 0 or cand.shape[0] == 0:
        return []
    if cand.shape[0] <= k:
        return list(cand)
    costs = np.array([float(np.sum(obj.fun(c) ** 2)) for c in cand])
    order = np.argsort(costs, kind="stable")
    u = (cand - lo) / (hi - lo)
    kept: list[int] = []
    for i in order:
        if all(np.max(np.abs(u[i] - u[j])) >= _SCREEN_DIST for j in kept):
            kept.append(int(i))
        if len(kept) == k:
            break
    for i in order:  # too few far-apart points: fill up with the next best
        if len(kept) == k:
            break
        if int(i) not in kept:
            kept.append(int(i))
    return [cand[i] for i in kept]


def _sobol(d: int, n: int, seed: Any) -> np.ndarray:
    if n <= 0:
        return np.empty((0, d))
    sampler = qmc.Sobol(d, scramble=True, seed=seed)
    m = max(0, math.ceil(math.log2(n)))
    return sampler.random_base2(m)[:n]


def _resolve_quantity(meas: Measurement, relative_to: str | None) -> tuple[int, str, str | None]:
    """(flag, compared quantity name, relative_to) for the measurement's quantity."""
    q = meas.quantity
    if q == "brdf":
        return 0, "brdf", None
    if q in ("brdf_cos", "bridf"):
        return 1, "bridf", None
    rel = relative_to or meas.meta.get("relative_to") or "brdf"
    rel = {"brdf_cos": "bridf"}.get(str(rel).lower(), str(rel).lower())
    if rel not in ("brdf", "bridf"):
        raise ValueError(f"relative_to must be 'brdf' or 'bridf' (what the relative values are "
                         f"proportional to), got {rel!r}")
    return (1 if rel == "bridf" else 0), rel, rel


def _free_parameters(model: Model, fix: Iterable[str], bounds: Mapping[str, Sequence[float]] | None
                     ) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    names = model.param_names
    fix = [fix] if isinstance(fix, str) else list(fix)
    for nm in [*fix, *(bounds or {})]:
        if nm not in names:
            model.with_values([nm], [0.0])  # raises the registry's "unknown parameter" error
    specs = {p.name: p for p in model.parameters}
    free = [n for n in names if n not in fix and specs[n].value is not None]
    if not free:
        off = [n for n in names if specs[n].value is None]
        extra = f" ({', '.join(off)} switched off by None)" if off else ""
        raise ValueError(f"every parameter of {_model_label(model)} is fixed{extra}: nothing to "
                         f"fit; free at least one of {names}")
    lo = np.empty(len(free))
    hi = np.empty(len(free))
    x0 = np.empty(len(free))
    for j, nm in enumerate(free):
        b = (bounds or {}).get(nm, specs[nm].bounds)
        lo[j], hi[j] = float(b[0]), float(b[1])
        if not lo[j] < hi[j]:
            raise ValueError(f"bounds of {nm!r} must satisfy low < high, got {tuple(b)}")
        x0[j] = float(specs[nm].value)
        if not lo[j] <= x0[j] <= hi[j]:
            raise ValueError(f"starting value {nm} = {x0[j]:g} is outside its bounds "
                             f"[{lo[j]:g}, {hi[j]:g}]; pass bounds={{{nm!r}: (low, high)}} or "
                             f"another starting value")
    return free, lo, hi, x0


def _channel_weights(weights: Any, meas: Measurement, j: int, x: np.ndarray, loss: str
                     ) -> np.ndarray | None:
    if weights is None:
        return None
    n = meas.n_samples
    if isinstance(weights, str):
        if weights != "uncertainty":
            raise ValueError(f"weights must be None, an array or 'uncertainty', got {weights!r}")
        if meas.uncertainty is None:
            raise ValueError("weights='uncertainty' but the measurement has no uncertainty")
        u = meas.uncertainty[:, j]
        with np.errstate(divide="ignore", invalid="ignore"):
            # absolute: 1/u; relative and log: x/u, the inverse relative uncertainty
            w = 1.0 / u if loss == "absolute" else np.abs(x) / u
        return np.where(np.isfinite(w) & (u > 0), w, 0.0)
    w = np.asarray(weights, dtype=float)
    if w.ndim == 2:
        if w.shape != meas.values.shape:
            raise ValueError(f"weights of shape {w.shape} do not match the values "
                             f"{meas.values.shape}")
        w = w[:, j]
    w = np.broadcast_to(w, (n,)).astype(float)
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("weights must be finite and >= 0")
    return w


_EXCLUDED_WORDS = {"nonfinite": "non-finite", "negative": "negative (dropped)",
                   "clipped": "negative (clipped)", "zero_weight": "of zero weight",
                   "model_domain": "where the model is not finite or not defined",
                   "horizon": "at theta_r = 90 deg (BRDF cos theta_r = 0 for every model)"}


def _excluded_text(excluded: dict[str, int]) -> str:
    return ", ".join(f"{v} {_EXCLUDED_WORDS.get(k, k)}" for k, v in excluded.items() if v) \
        or "none"


def _where(meas: Measurement, label: str) -> str:
    f = meas.meta.get("file")
    return f"{f}, channel {label!r}" if f else f"channel {label!r}"


def _prepare_channel(model: Model, meas: Measurement, j: int, flag: int, loss: str, weights: Any,
                     nonfinite: str, negative: str, aperture: float | None = None,
                     aperture_points: int = 19):
    """Select the samples of channel ``j`` that enter the fit; count everything left out."""
    label = meas.channels[j]
    x = meas.values[:, j].astype(float).copy()
    keep = np.ones(x.size, dtype=bool)
    excluded = {"nonfinite": 0, "negative": 0, "clipped": 0, "zero_weight": 0,
                "model_domain": 0, "horizon": 0}
    bad = ~np.isfinite(x)
    if bad.any():
        if nonfinite == "raise":
            rows = np.flatnonzero(bad)
            show = ", ".join(str(r) for r in rows[:8]) + (" ..." if rows.size > 8 else "")
            raise ValueError(f"{_where(meas, label)}: {rows.size} non-finite value(s) at "
                             f"sample(s) {show}; pass nonfinite='drop' to fit without them")
        keep &= ~bad
        excluded["nonfinite"] = int(bad.sum())
    # the log loss cannot use zeros either: "negative" handling covers x <= 0 there
    neg = np.isfinite(x) & ((x <= 0) if loss == "log" else (x < 0))
    if neg.any():
        if negative == "keep":
            if loss == "log":
                raise ValueError(f"{_where(meas, label)}: the log loss needs positive values "
                                 f"but {int(neg.sum())} are <= 0; pass negative='drop' or "
                                 f"negative='clip'")
        elif negative == "drop":
            keep &= ~neg
            excluded["negative"] = int(neg.sum())
        else:  # clip
            pos = x[np.isfinite(x) & (x > 0)]
            x[neg] = (pos.min() if pos.size else 1.0) if loss == "log" else 0.0
            excluded["clipped"] = int(neg.sum())
    w = _channel_weights(weights, meas, j, x, loss)
    if w is not None:
        zero = keep & (w == 0)
        excluded["zero_weight"] = int(zero.sum())
        keep &= w > 0
    if not model.grazing_incidence:
        graze = keep & (meas.theta_i >= 0.5 * math.pi)
        excluded["model_domain"] += int(graze.sum())
        keep &= ~graze
    if flag == 1 and loss != "absolute":
        # BRDF cos(theta_r) of every model is 0 at theta_r = 90 deg: a measured value there (a
        # noise floor) has no relative or logarithmic residual
        horizon = keep & (np.cos(meas.theta_r) <= 1e-12)
        excluded["horizon"] = int(horizon.sum())
        keep &= ~horizon
    # samples where the model itself is not finite at the starting values (e.g. the BRDF of the
    # unshadowed TR75 model at theta_r = 90 deg, which is +inf): these cannot be fitted. With
    # an aperture, the model averaged over the cone (as the fit will compare it) is checked.
    idx = np.flatnonzero(keep)
    if idx.size:
        gam = (np.asarray(np.nan) if meas.polarization is None
               else np.ascontiguousarray(meas.polarization[idx]))
        geo, stencil = _geometry(meas, idx, aperture, aperture_points)
        f0 = _Objective(model, [], np.empty(0), np.empty(0), *geo, gam, x[idx], None, flag,
                        "absolute", False, 1.0, stencil).values(np.empty(0))
        ok = np.isfinite(f0)
        if not ok.all():
            excluded["model_domain"] += int((~ok).sum())
            keep[idx[~ok]] = False
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        total = int(x.size)
        raise ValueError(f"{_where(meas, label)}: no data to fit ({total} samples; left out: "
                         + _excluded_text(excluded) + ")"
                         if total else f"{_where(meas, label)}: no data to fit (0 samples)")
    return idx, x[idx], (None if w is None else w[idx]), excluded


def _covariance(obj: _Objective, theta: np.ndarray, k: float, chi2: float, dof: int
                ) -> tuple[np.ndarray, list[str], str]:
    f = obj.values(theta)
    cols = [obj.jac_central(theta, k)]
    names = list(obj.free)
    if obj.free_scale:
        cols.append(obj.scale_column(f, k)[:, None])
        names.append("scale")
    jmat = np.hstack(cols)
    note = ""
    p = jmat.shape[1]
    try:
        _, s, vt = np.linalg.svd(jmat, full_matrices=False)
        if not np.all(np.isfinite(s)) or s[0] == 0 or s[-1] <= s[0] * 1e-12:
            raise np.linalg.LinAlgError("singular")
        inv = (vt.T / (s * s)) @ vt
        cov = inv * (chi2 / max(dof, 1))
    except np.linalg.LinAlgError:
        cov = np.full((p, p), np.nan)
        note = "; covariance not estimated (singular J^T J: a parameter has no effect)"
    return cov, names, note


def fit(model: Model | str, measurement: Measurement, *,
        channel: int | str | Sequence | None = None, loss: str = "relative",
        weights: Any = None, fix: Iterable[str] = (),
        bounds: Mapping[str, Sequence[float]] | None = None, starts: int = 8,
        seed: int | None = 0, nonfinite: str = "raise", negative: str = "keep",
        relative_to: str | None = None, free_scale: bool | None = None,
        scale: float | None = None,
        screen: int = 64, subsample: int | None = 1000, polish: int = 2,
        max_nfev: int | None = None, aperture: float | None = None,
        aperture_points: int = 19,
        progress: bool | None = None) -> FitResult:
    """Fit ``model`` to ``measurement``, each channel on its own.

    Parameters
    ----------
    model : Model or str
        Model with starting values (``rb.model(...)``; sums allowed), or a registered name.
    measurement : Measurement
        The data (:func:`roughbrdf.read`).
    channel : int, str, list or None
        Channel(s) to fit (labels or positions); ``None`` fits every channel.
    loss : {"relative", "log", "absolute"}
        Residual: ``(x - f)/f`` (TR75 Eq. 34), ``ln x - ln f`` or ``x - f``; see the module notes.
    weights : None, array or "uncertainty"
        Multiplies each residual; shape (N,) or (N, C). ``"uncertainty"`` uses the measurement's
        uncertainty ``u``: ``1/u`` for the absolute loss, ``x/u`` for the relative and log losses.
        Samples of weight 0 are left out (and counted).
    fix : iterable of str
        Parameters kept at the model's value. Parameters whose value is ``None`` (parts switched
        off, e.g. TS67 ``n=None``) are never fitted.
    bounds : dict, optional
        ``name -> (low, high)``, overriding the model's default search ranges.
    starts : int
        Local fits per channel: one from the model's values, then ``starts - 1`` from Sobol
        points in the bounds (``starts=1`` is a plain local fit from the model's values).
    screen : int
        Number of Sobol points in the bounds whose cost is evaluated (one model evaluation
        each) to choose the ``starts - 1`` starting points: the lowest-cost ones, kept at least
        0.15 of the bounds apart.
    seed : int or None
        Seed of the scrambled Sobol sequence and of the subsample (results are reproducible).
    nonfinite : {"raise", "drop"}
        What to do with NaN/inf measured values.
    negative : {"keep", "drop", "clip"}
        What to do with negative measured values (non-positive ones for ``loss="log"``, where
        ``keep`` raises). ``clip`` sets them to 0 (to the smallest positive value for the log
        loss). Counts are reported in ``excluded``.
    relative_to : {"brdf", "bridf"}, optional
        For ``relative`` data: the model quantity the values are proportional to. Default
        ``measurement.meta["relative_to"]`` if the reader found it, else ``"brdf"``.
    free_scale : bool, optional
        Fit a free scale ``K`` of the data in closed form. Default: only for ``relative`` data.
        A model with an overall scale parameter of its own (TS67 ``rho_d``, microfacet ``ks``
        alone) cannot tell it from ``K``: fix that parameter when fitting relative data.
    scale : float, optional
        A known data scale ``K`` (``x -> K x``) instead of a fitted one, e.g. for relative data
        whose absolute calibration is known; the fit is then the absolute fit.
    subsample : int or None
        Above this many samples, the starts are explored on a fixed random subsample and the
        ``polish`` best end points refined on all samples. ``None`` uses all samples throughout.
    polish : int
        Number of explored end points refined on the full data.
    max_nfev : int, optional
        Limit of function evaluations per local fit (``least_squares``).
    aperture : float or None
        Instrument angular response: half-angle (radians) of a uniform cone about the measured
        reflection direction. Each sample is compared with the model averaged over that cone
        (see the module notes, "Instrument aperture"); ``None`` or 0: the model at the sample's
        direction. Must satisfy ``0 <= aperture < pi/2``.
    aperture_points : {7, 19, 37}
        Size of the cubature rule over the cone (:func:`aperture_stencil`); the fit costs about
        that many times more model evaluations.
    progress : bool or None
        Show a tqdm progress bar; ``None`` shows it only on an interactive terminal.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Unknown loss or option, every parameter fixed, no data left in a channel, non-finite
        values with ``nonfinite="raise"``, non-positive values for the log loss with
        ``negative="keep"``, an aperture that is negative, not finite or >= pi/2.
    """
    t_start = time.perf_counter()
    if isinstance(model, str):
        model = _make_model(model)
    if not isinstance(model, Model):
        raise TypeError(f"model must be a roughbrdf Model or a model name, got {type(model)}")
    if not isinstance(measurement, Measurement):
        raise TypeError(f"measurement must be a roughbrdf Measurement, got {type(measurement)}")
    if loss not in LOSSES:
        raise ValueError(f"unknown loss {loss!r}; choose one of {', '.join(LOSSES)}")
    if nonfinite not in ("raise", "drop"):
        raise ValueError(f"nonfinite must be 'raise' or 'drop', got {nonfinite!r}")
    if negative not in ("keep", "drop", "clip"):
        raise ValueError(f"negative must be 'keep', 'drop' or 'clip', got {negative!r}")
    starts = int(starts)
    if starts < 1:
        raise ValueError(f"starts must be >= 1, got {starts}")
    polish = max(1, int(polish))
    ap = _check_aperture(aperture, aperture_points)
    meas = measurement
    flag, compared, rel = _resolve_quantity(meas, relative_to)
    if scale is not None:
        fixed_scale = float(scale)
        if not (math.isfinite(fixed_scale) and fixed_scale > 0):
            raise ValueError(f"scale must be finite and > 0, got {scale!r}")
        if free_scale:
            raise ValueError("give either scale= (a known data scale) or free_scale=True")
        free_scale = False
    else:
        fixed_scale = 1.0
    if free_scale is None:
        free_scale = meas.quantity == "relative"
    free, lo, hi, x0 = _free_parameters(model, fix, bounds)
    if channel is None:
        chans = list(range(len(meas.channels)))
    elif isinstance(channel, list | tuple):
        chans = [meas.channel_index(c) for c in channel]
    else:
        chans = [meas.channel_index(channel)]
    if not chans:
        raise ValueError("no channel to fit")
    rng = np.random.default_rng(seed)
    n_screen = max(starts - 1, int(screen)) if starts > 1 else 0
    sobol = _sobol(len(free), n_screen, seed)
    sobol_x = lo + sobol * (hi - lo)

    # prepare every channel first, so that bad input fails before any work
    prepared = [_prepare_channel(model, meas, j, flag, loss, weights, nonfinite, negative, ap,
                                 aperture_points) for j in chans]
    n_varys = len(free) + (1 if free_scale else 0)
    for j, (idx, _, _, _) in zip(chans, prepared, strict=True):
        if idx.size <= n_varys:
            raise ValueError(f"{_where(meas, meas.channels[j])}: {idx.size} samples for "
                             f"{n_varys} fitted parameters; need more data than parameters")

    pbar = None
    if progress is None:
        progress = bool(getattr(sys.stderr, "isatty", lambda: False)())
    if progress:
        from tqdm.auto import tqdm

        pbar = tqdm(total=len(chans) * starts, desc=f"fit {_model_label(model)}", unit="start",
                    leave=False)
    results: list[ChannelFit] = []
    warm: np.ndarray | None = None
    blas = _SingleThreadBLAS().__enter__()
    try:
        for j, (idx, x, w, excluded) in zip(chans, prepared, strict=True):
            t0 = time.perf_counter()
            label = meas.channels[j]
            if pbar is not None:
                pbar.set_postfix_str(label)
            gam = (np.asarray(np.nan) if meas.polarization is None
                   else np.ascontiguousarray(meas.polarization[idx]))
            geo, stencil = _geometry(meas, idx, ap, aperture_points)
            full = _Objective(model, free, lo, hi, *geo, gam, x, w, flag, loss, free_scale,
                              fixed_scale, stencil)
            if subsample is not None and idx.size > subsample:
                sub = np.sort(rng.choice(idx.size, size=int(subsample), replace=False))
                explore = _Objective(model, free, lo, hi, *(g[sub] for g in geo),
                                     gam if gam.ndim == 0 else gam[sub], x[sub],
                                     None if w is None else w[sub], flag, loss, free_scale,
                                     fixed_scale, stencil)
            else:
                explore = full
            points = [x0] + ([warm] if warm is not None else []) + _screen(
                explore, sobol_x, starts - 1, lo, hi)
            kw = {"method": "trf", "x_scale": _X_SCALE, "max_nfev": max_nfev}
            tried: list[dict[str, Any]] = []
            ends: list[tuple[float, np.ndarray, Any]] = []
            for p0 in points:
                p0 = np.clip(p0, lo, hi)
                res = least_squares(explore.fun, p0, jac=explore.jac, bounds=(lo, hi),
                                    ftol=_EXPLORE_TOL, xtol=_EXPLORE_TOL, gtol=_EXPLORE_TOL, **kw)
                tried.append({"x0": p0.tolist(), "x": res.x.tolist(), "cost": float(res.cost),
                              "stage": "explore" if explore is not full else "single"})
                ends.append((float(res.cost), res.x, res))
                if pbar is not None:
                    pbar.update(1)
            ends.sort(key=lambda e: e[0])
            if explore is full:
                best_cost, best_x, best = ends[0]
            else:
                chosen: list[np.ndarray] = []
                for _, xe, _ in ends:
                    span = hi - lo
                    if all(np.max(np.abs(xe - c) / span) > 1e-3 for c in chosen):
                        chosen.append(xe)
                    if len(chosen) == polish:
                        break
                best_cost, best_x, best = math.inf, chosen[0], None
                for xe in chosen:
                    res = least_squares(full.fun, xe, jac=full.jac, bounds=(lo, hi),
                                        ftol=_POLISH_TOL, xtol=_POLISH_TOL, gtol=_POLISH_TOL, **kw)
                    tried.append({"x0": xe.tolist(), "x": res.x.tolist(),
                                  "cost": float(res.cost), "stage": "full"})
                    if res.cost < best_cost:
                        best_cost, best_x, best = float(res.cost), res.x, res
            warm = best_x.copy()
            results.append(_finish(model, full, best_x, best, label, idx, x, excluded, free, lo,
                                   hi, x0, tried, time.perf_counter() - t0,
                                   0 if explore is full else explore.nfev))
    finally:
        blas.__exit__(None, None, None)
        if pbar is not None:
            pbar.close()

    return FitResult(channels=results, measurement=meas, model_name=_model_label(model),
                     loss=loss, compared=compared, relative_to=rel,
                     options={"starts": starts, "seed": seed, "subsample": subsample,
                              "polish": polish, "nonfinite": nonfinite, "negative": negative,
                              "free_scale": bool(free_scale),
                              "scale": scale,
                              "aperture": ap,
                              "aperture_points": aperture_points if ap is not None else None,
                              "fix": sorted(set(model.param_names) - set(free)),
                              "weights": None if weights is None else
                              (weights if isinstance(weights, str) else "array")},
                     elapsed=time.perf_counter() - t_start, aperture=ap,
                     aperture_points=int(aperture_points))


def _geometry(meas: Measurement, idx: np.ndarray, aperture: float | None, points: int
              ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], np.ndarray | None]:
    """``(theta_i, theta_r, phi)`` of the fitted samples, and the stencil weights: without an
    aperture each array is (N,) and the weights None; with one, ``theta_i`` is (N, 1) and
    ``theta_r``, ``phi`` are (N, S), the stencil's directions about each sample (built once)."""
    ti = np.ascontiguousarray(meas.theta_i[idx])
    tr = np.ascontiguousarray(meas.theta_r[idx])
    ph = np.ascontiguousarray(meas.phi[idx])
    if aperture is None:
        return (ti, tr, ph), None
    tr_s, ph_s, wt = _aperture_directions(tr, ph, aperture, points)
    return (ti[:, None], tr_s, ph_s), wt


def _finish(model: Model, obj: _Objective, theta: np.ndarray, res: Any, label: str,
            idx: np.ndarray, x: np.ndarray, excluded: dict[str, int], free: list[str],
            lo: np.ndarray, hi: np.ndarray, x0: np.ndarray, tried: list[dict[str, Any]],
            elapsed: float, extra_nfev: int) -> ChannelFit:
    fitted_model = obj.model_at(theta)
    f = obj.values(theta)
    k = obj.scale(f)
    r = obj.residual_of(f, k)
    n = r.size
    n_varys = len(free) + (1 if obj.free_scale else 0)
    chi2 = float(r @ r)
    dof = n - n_varys
    redchi = chi2 / dof if dof > 0 else math.nan
    lchi = math.log(chi2 / n) if chi2 > 0 else -math.inf
    aic = n * lchi + 2 * n_varys
    bic = n * lchi + math.log(n) * n_varys
    fs = np.maximum(f, obj.floor)
    rel = (k * x - f) / fs
    sigma = float(np.sqrt(np.mean(rel * rel)))
    pos = (x > 0) & (f > 0)
    rms_log = (float(np.sqrt(np.mean((np.log(k * x[pos]) - np.log(f[pos])) ** 2)))
               if pos.any() else math.nan)
    cov, names, note = _covariance(obj, theta, k, chi2, dof)
    sd = np.sqrt(np.where(np.diag(cov) >= 0, np.diag(cov), np.nan))
    stderr: dict[str, float | None] = {nm: None for nm in model.param_names}
    for nm, s in zip(names, sd, strict=True):
        if nm != "scale":
            stderr[nm] = float(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(sd, sd)
    correl = {a: {b: float(corr[i, m]) for m, b in enumerate(names) if m != i}
              for i, a in enumerate(names)}
    scale_se = float(sd[-1]) if obj.free_scale else 0.0
    success = bool(res.success) if res is not None else False
    message = (res.message.rstrip(".") if res is not None else "no local fit finished") + note
    if np.any(np.isclose(theta, lo, rtol=0, atol=1e-9 * (hi - lo))
              | np.isclose(theta, hi, rtol=0, atol=1e-9 * (hi - lo))):
        at = [nm for nm, t, a, b in zip(free, theta, lo, hi, strict=True)
              if abs(t - a) <= 1e-9 * (b - a) or abs(t - b) <= 1e-9 * (b - a)]
        message += f"; at a bound: {', '.join(at)}"
    return ChannelFit(
        channel=label, model=fitted_model, params=fitted_model.params, free=list(free),
        init={nm: float(v) for nm, v in zip(free, x0, strict=True)},
        bounds={nm: (float(a), float(b)) for nm, a, b in zip(free, lo, hi, strict=True)},
        stderr=stderr, correl=correl, covar=cov, scale=float(k), scale_stderr=scale_se,
        success=success, message=message, sigma=sigma, rms_log=rms_log, chi2=chi2,
        redchi=redchi, aic=aic, bic=bic, n_points=int(n), n_varys=n_varys, excluded=excluded,
        nfev=obj.nfev + extra_nfev, starts=tried, free_scale=obj.free_scale,
        elapsed=elapsed, index=idx, data=x, fitted=f, residual=r)


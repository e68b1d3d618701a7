"""The microfacet distribution (NDF) and projected area (sigma) of an RGL file.

The adaptive parameterization of Dupuy & Jakob 2018 warps the half-vector domain by the
material's visible-normal distribution, and Mitsuba's ``measured`` plugin multiplies the
stored values by ``D(m) / (4 sigma(w_i))`` (``src/bsdfs/measured.cpp``, the ``jacobian``
flag). Two sources of ``D``:

* **exact** - the ``microfacet`` model's own distribution
  (:func:`roughbrdf.distributions.evaluate`), when the BRDF is that one lobe;
* **power iteration** - every other model (coated, TR75, RB08, the stray-light models, sums):
  ``D`` retrieved from the model's back-scattering ``f(w, w)`` by the fixed-point iteration
  of Dupuy, Heitz, Iehl, Poulin & Ostromoukhov 2015, "Extracting microfacet-based BRDF
  parameters from arbitrary materials with power iterations" (EGSR): for a microfacet BRDF
  with Smith masking, ``f(w, w) = F D(w) / (4 sigma(w)^2)`` with
  ``sigma(w) = int D(m) <w, m>+ dm``, so ``D`` is the fixed point of
  ``D <- f(w, w) sigma_D(w)^2`` normalized to ``int D cos = 1``.

Both are tables on the ``u = sqrt(2 theta / pi)`` grid (:mod:`roughbrdf.io.rgl_tensor`),
linear in ``u`` between nodes as Mitsuba interpolates them; ``sigma`` is integrated from that
interpolant, so the file's ``D`` and ``sigma`` agree with each other.

Examples
--------
>>> import roughbrdf as rb
>>> u, d, source = ndf_table([rb.model("lambertian", rho=0.5)], 64)
>>> source
'power iteration (Dupuy et al. 2015) on the back-scattering f(w, w)'
>>> s = sigma_table(u, d, u)
>>> bool(abs(s[0] - 1.0) < 1e-3)  # sigma(normal) = int D cos = 1
True
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ...io.rgl_tensor import u_to_theta

__all__ = ["ndf_table", "sigma_table", "EXACT_SOURCE", "POWER_SOURCE"]

EXACT_SOURCE = "exact (the model's microfacet distribution)"
POWER_SOURCE = "power iteration (Dupuy et al. 2015) on the back-scattering f(w, w)"

#: quadrature nodes (midpoints in u) of the sigma and normalization integrals
_QUAD = 4096
#: the highest zenith at which the model is evaluated for the back-scattering (a model may
#: be undefined at exactly 90 deg; the table's last node copies this value)
_THETA_TOP = math.radians(89.5)
#: iterations of the power iteration (Dupuy et al. 2015 report convergence within ~10)
_ITERATIONS = 30
#: D is floored at this fraction of its peak: the file's values are divided by D, and a D of
#: zero (a far tail underflowing, or a model with no back-scattering there) would make them
#: infinite where the BRDF is not zero
_FLOOR = 1e-7


def _exact(models: list) -> Callable[[np.ndarray], np.ndarray] | None:
    """``cos -> D`` when every channel is the ``microfacet`` model with one distribution and
    one ``alpha`` (the channels differ in Fresnel or scale only), None otherwise."""
    kinds = {(getattr(m, "name", None), str(m.options.get("distribution")),
              float(m.params.get("alpha", np.nan))) for m in models}
    if len(kinds) != 1:
        return None
    kind, name, alpha = kinds.pop()
    if kind != "microfacet":
        return None
    from ... import distributions

    return lambda c: distributions.evaluate(name, c, alpha)


def _phi_integral(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``int_0^{2 pi} max(0, a cos(phi) + b) dphi`` for ``a >= 0`` (closed form)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        # a = 0 (the normal, or m at the normal): the integrand is constant, the "full" branch
        # below; the clip and the max keep the unused branch free of NaN where |b| >= a
        ratio = np.clip(np.divide(-b, a, out=np.zeros_like(b), where=a > 0), -1.0, 1.0)
        part = 2.0 * (b * np.arccos(ratio) + np.sqrt(np.maximum(a * a - b * b, 0.0)))
    full = np.where(b > 0, 2 * np.pi * b, 0.0)
    return np.where(a > np.abs(b), part, full)


def _kernel(u_out: np.ndarray) -> np.ndarray:
    """``K[o, q]``: the weight of the quadrature node ``q`` (midpoints in ``u``) in
    ``sigma(theta_o)``, the azimuth integral of ``<w, m>+`` in closed form times
    ``dm = sin(theta) dtheta dphi`` with ``dtheta = pi u du`` - geometry only, so that an
    iteration reuses it."""
    uq = (np.arange(_QUAD) + 0.5) / _QUAD
    tq = u_to_theta(uq)
    to = u_to_theta(np.asarray(u_out, float))[:, None]
    a = np.sin(to) * np.sin(tq)[None, :]
    b = np.cos(to) * np.cos(tq)[None, :]
    return _phi_integral(a, b) * (np.sin(tq) * np.pi * uq / _QUAD)[None, :]


def sigma_table(u_nodes: np.ndarray, d_nodes: np.ndarray, u_out: np.ndarray,
                kernel: np.ndarray | None = None) -> np.ndarray:
    """``sigma(theta) = int D(m) <w, m>+ dm`` at the zeniths ``u_to_theta(u_out)``, for the
    isotropic ``D`` interpolated linearly in ``u`` from ``(u_nodes, d_nodes)`` (``kernel``:
    :func:`_kernel` of ``u_out``, if already computed)."""
    uq = (np.arange(_QUAD) + 0.5) / _QUAD
    k = _kernel(u_out) if kernel is None else kernel
    return k @ np.interp(uq, u_nodes, d_nodes)


def _normalized(u: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``d`` floored (:data:`_FLOOR`) and scaled so that ``int D cos(theta) dm = 1``."""
    d = np.maximum(d, _FLOOR * float(np.max(d)))
    return d / float(sigma_table(u, d, np.zeros(1))[0])  # sigma at the normal = int D cos


def ndf_table(models: list, n: int) -> tuple[np.ndarray, np.ndarray, str]:
    """``(u, D(u), source)``: the isotropic NDF of the channels' ``models`` at ``n`` nodes of
    ``u`` in [0, 1], normalized (``int D cos = 1``), and where it came from
    (:data:`EXACT_SOURCE` or :data:`POWER_SOURCE`; the power iteration runs on the channels'
    mean back-scattering: one NDF serves every channel).

    Raises
    ------
    ValueError
        The model scatters nothing back towards the source at any angle (the power iteration
        has nothing to start from).
    """
    u = np.linspace(0.0, 1.0, n)
    theta = np.minimum(u_to_theta(u), _THETA_TOP)
    exact = _exact(models)
    if exact is not None:
        # NaN/inf (a distribution's far tail or rounding) carry no density: 0, then floored
        d = np.nan_to_num(np.asarray(exact(np.cos(theta)), float), nan=0.0, posinf=0.0)
        if np.max(d) > 0:
            return u, _normalized(u, d), EXACT_SOURCE
    return u, power_iteration(models, u), POWER_SOURCE


def power_iteration(models: list, u: np.ndarray) -> np.ndarray:
    """The NDF (normalized, on the nodes ``u``) retrieved from the channels' mean
    back-scattering ``f(w, w)`` by the power iteration of Dupuy et al. 2015.

    For a microfacet BRDF with separable Smith masking and ``F = 1`` it is that BRDF's own
    distribution (``f(w, w) = D(w) / (4 sigma(w)^2)`` exactly).

    Examples
    --------
    >>> import numpy as np, roughbrdf as rb
    >>> m = rb.model("microfacet", alpha=0.3, n=None, k=None, shadowing="smith-separable")
    >>> u, exact, _ = ndf_table([m], 128)
    >>> found = power_iteration([m], u)
    >>> bool(np.max(np.abs(found / exact - 1)[:100]) < 0.01)
    True
    """
    theta = np.minimum(u_to_theta(u), _THETA_TOP)
    # NaN/inf/negative back-scatter (a model undefined there, rounding) carries no density
    retro = np.mean([np.nan_to_num(np.asarray(m.brdf(theta, theta, np.pi), float), nan=0.0,
                                   posinf=0.0) for m in models], axis=0)
    retro = np.maximum(retro, 0.0)
    if not np.max(retro) > 0:
        raise ValueError(f"{models[0]!r} scatters nothing back towards the source: no NDF can be "
                         "retrieved by power iteration")
    d = _normalized(u, retro * np.cos(theta) ** 2)  # start: f(w, w) cos^2 (Dupuy et al.)
    kernel = _kernel(u)
    for _ in range(_ITERATIONS):
        sigma = sigma_table(u, d, u, kernel)
        new = _normalized(u, retro * sigma ** 2)
        done = np.max(np.abs(new - d)) <= 1e-6 * np.max(d)
        d = new
        if done:
            break
    return d

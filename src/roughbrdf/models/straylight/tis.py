"""Total integrated scatter (TIS) of the shift-invariant stray-light models, ABg and Harvey–Shack.

The TIS is the directional-hemispherical reflectance ``∫ BSDF cos(theta_r) dΩ_r``. In
direction-cosine space ``β = sin(theta_r) (cos phi, sin phi)`` the projected solid angle is
``cos(theta_r) dΩ_r = d²β`` over the unit disk (Stover, *Optical Scattering*, 3rd ed., §1.5;
Zemax OpticStudio help, "Scatter Models"), so for a BSDF ``F(|β - β0|)`` that depends only on the
distance to the specular point ``β0 = (sin theta_i, 0)``::

    TIS(theta_i) = ∫_{|β| < 1} F(|β - β0|) d²β = ∫_0^{2π} G(R(ψ)) dψ,
    G(r) = ∫_0^r F(ρ) ρ dρ,
    R(ψ) = sqrt(1 - s² sin²ψ) - s cos ψ,          s = sin(theta_i),

polar coordinates ``(ρ, ψ)`` centred on ``β0``, ``R(ψ)`` the distance from ``β0`` to the unit
circle along ``ψ`` (ψ = 0 towards the near rim). This is exact; what remains is 1-D quadrature.

Quadrature (why hand-written: the lobe can be 1e-6 wide in ``ρ`` and cut by the rim; generic
adaptive cubature handles that slowly and without a guarantee)
----------------------------------------------------------------------------------------
* ``ψ``: ``R`` is symmetric (``ψ -> -ψ``), so ``2 ∫_0^π``. ``R(ψ)`` is smooth but, near grazing
  incidence, changes on the scale ``cos(theta_i)`` around ``ψ = π/2`` (exactly a kink there at
  ``theta_i = π/2``). Composite Gauss–Legendre (12 nodes a panel) on 30 panels split at
  ``π/2`` and graded geometrically towards it (widths ``π/4, π/8, ..., ~1e-4``).
* ``G`` of Harvey–Shack is closed form (:func:`harvey_shack_radial`). ``G`` of ABg (a
  hypergeometric function that SciPy's ``hyp2f1`` evaluates poorly for ``|z| >> 1`` at the
  degenerate parameters ``g = 1, 2``) is integrated in ``ln ρ`` with 10-node Gauss–Legendre
  panels no wider than ``min(0.5, 1.5/|g|)`` (the integrand ``A ρ²/(B + ρ^g)`` is analytic in
  a strip of half-width ``π/|g|`` around the real ``ln ρ`` axis), from
  ``ρ_min = 1e-7 min(B^(1/g), r)``: nodes are graded on the lobe's own scale ``B^(1/g)``, so
  a very sharp lobe (``B = 1e-12``) is resolved; ``[0, ρ_min]`` adds ``F(ρ_min) ρ_min²/2``.
  Since ``R(ψ)`` increases with ``ψ`` on ``[0, π]``, ``G(R(ψ_k))`` is accumulated from one
  ``ψ`` node to the next.

Accuracy: checked against the exact normal-incidence forms (``2π G(1)``, closed form for both
models), the constant ABg (``g = 0``: ``π A/(B+1)`` at every incidence), the plane forms below
and :func:`roughbrdf.albedo` (tests/models/test_straylight_abg_hs.py states the ranges).

Plane closed forms (the unit disk replaced by the whole plane, an upper bound of the TIS,
reached when the lobe is far from the rim)::

    ABg:          2π² A B^(2/g - 1) / (g sin(2π/g)),     converges for g > 2
    Harvey–Shack: 2π b0 L² / (-S - 2),                   converges for S < -2
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange
from numpy.typing import ArrayLike

from ..._kernels import driver, jit
from ...errors import ArgumentError
from ...geometry import check_zenith

__all__ = ["ABG_B_MIN", "abg_bsdf", "abg_tis", "abg_tis_plane", "check_abg",
           "check_harvey_shack", "harvey_shack_bsdf", "harvey_shack_radial", "harvey_shack_tis",
           "harvey_shack_tis_plane"]

#: Zemax OpticStudio's rule: "B must be greater than 1E-12 unless g = 0.0" (help page
#: "Available Scatter Models", ABg Model Scattering)
ABG_B_MIN = 1e-12


# --------------------------------------------------------------------------------------------
# parameter rules (the models' cross-parameter checks use them too)
# --------------------------------------------------------------------------------------------
def _real(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ArgumentError(name, f"parameter {name!r} must be a real number",
                            value=value) from None
    if not math.isfinite(v):
        raise ArgumentError(name, f"parameter {name!r} must be finite", value=v)
    return v


def check_abg(A: float, B: float, g: float) -> tuple[float, float, float]:
    """Validate ABg parameters with Zemax's rules; return them as floats.

    ``A >= 0``; ``B >= 0`` and ``B > 1e-12`` unless ``g = 0`` (:data:`ABG_B_MIN`); ``g`` any
    finite number. Raises :class:`~roughbrdf.errors.ArgumentError` naming the parameter.

    Examples
    --------
    >>> check_abg(0.0025, 0.001, 1.8)
    (0.0025, 0.001, 1.8)
    >>> check_abg(1.0, 0.0, 2.0)
    Traceback (most recent call last):
    ...
    roughbrdf.errors.ArgumentError: B = 0.0: parameter 'B' must be greater than 1e-12 unless ...
    """
    a, b, gg = _real("A", A), _real("B", B), _real("g", g)
    if a < 0.0:
        raise ArgumentError("A", "parameter 'A' must be >= 0 (Zemax's ABg rule)", value=a)
    if b < 0.0 or (gg != 0.0 and b <= ABG_B_MIN):
        raise ArgumentError("B", f"parameter 'B' must be greater than {ABG_B_MIN:g} unless g = 0 "
                            f"(then B >= 0; Zemax's ABg rule), here g = {gg!r}", value=b)
    return a, b, gg


def check_harvey_shack(b0: float, L: float, S: float) -> tuple[float, float, float]:
    """Validate Harvey–Shack parameters with FRED's rules (``b0 > 0``, ``L > 0``, ``S < 0``).

    Examples
    --------
    >>> check_harvey_shack(0.1, 0.01, -1.5)
    (0.1, 0.01, -1.5)
    """
    out = []
    for name, v, what in (("b0", b0, "> 0"), ("L", L, "> 0"), ("S", S, "< 0")):
        x = _real(name, v)
        if (x >= 0.0) if name == "S" else (x <= 0.0):
            raise ArgumentError(name, f"parameter {name!r} must be {what} (FRED's Harvey-Shack "
                                "rule)", value=x)
        out.append(x)
    return out[0], out[1], out[2]


# --------------------------------------------------------------------------------------------
# the BSDFs of the distance d = |β - β0| (shared with the models' point functions)
# --------------------------------------------------------------------------------------------
@jit(inline=True)
def abg_bsdf(d, a, b, g):
    """ABg BSDF ``A / (B + d^g)`` (sr⁻¹) at ``d = |β - β0| >= 0`` (Zemax, FRED)."""
    if g == 0.0:  # constant A/(B + 1); also avoids 0**0 and 0 * log(0) below
        return a / (b + 1.0)
    if d == 0.0:  # the limit: d^g -> 0 (g > 0) or inf (g < 0); 0.0 ** -g would raise in Python
        return a / b if g > 0.0 else 0.0
    return a / (b + d ** g)


@jit(inline=True)
def harvey_shack_bsdf(d, b0, L, S):
    """Harvey–Shack BSDF ``b0 (1 + (d/L)²)^(S/2)`` (sr⁻¹) at ``d = |β - β0|`` (FRED)."""
    q = d / L
    return b0 * (1.0 + q * q) ** (0.5 * S)


@jit
def harvey_shack_radial(r, b0, L, S):
    """``G(r) = ∫_0^r F(ρ) ρ dρ`` of Harvey–Shack, closed form.

    ``b0 L²/2 · ((1 + r²/L²)^p - 1)/p`` with ``p = (S + 2)/2``, and ``b0 L²/2 · ln(1 + r²/L²)``
    at ``p = 0`` (``S = -2``), written with ``expm1``/``log1p`` so that it is continuous and
    accurate through ``S = -2``.
    """
    q = r / L
    y = math.log1p(q * q)
    p = 0.5 * (S + 2.0)
    if p == 0.0:  # the S = -2 limit of expm1(p y)/p
        return 0.5 * b0 * L * L * y
    return 0.5 * b0 * L * L * math.expm1(p * y) / p


# --------------------------------------------------------------------------------------------
# quadrature rules
# --------------------------------------------------------------------------------------------
def _psi_rule(levels: int = 14, order: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss–Legendre nodes/weights on [0, pi], split at pi/2 and graded towards it
    (ascending nodes: the ABg accumulation relies on it)."""
    x, w = np.polynomial.legendre.leggauss(order)
    half = 0.5 * math.pi
    d = half * 0.5 ** np.arange(levels + 1)
    edges = np.concatenate([half - d, [half], (half + d)[::-1]])
    nodes = [0.5 * (b - a) * x + 0.5 * (a + b) for a, b in zip(edges[:-1], edges[1:],
                                                                strict=True)]
    weights = [0.5 * (b - a) * w for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return np.concatenate(nodes), np.concatenate(weights)


_PSI_X, _PSI_W = _psi_rule()
_LN_X, _LN_W = np.polynomial.legendre.leggauss(10)


@jit
def _radius(s, c, psi):
    """``R(ψ)``: distance from ``β0 = (s, 0)`` to the unit circle along ``ψ`` (``c² = 1 - s²``),
    without the cancellation of ``sqrt(1 - s² sin²ψ) - s cos ψ`` for ``cos ψ > 0``."""
    cp = math.cos(psi)
    q = math.sqrt(c * c + s * s * cp * cp)
    if cp > 0.0:
        return c * c / (q + s * cp)
    return q - s * cp


@jit
def _abg_segment(r0, r1, a, b, g, lx, lw):
    """``∫_{r0}^{r1} F(ρ) ρ dρ`` of ABg, ``0 < r0 <= r1``, Gauss–Legendre panels in ``ln ρ``."""
    t0, t1 = math.log(r0), math.log(r1)
    if t1 <= t0:
        return 0.0
    h = min(0.5, 1.5 / abs(g)) if g != 0.0 else 0.5  # panel width vs the strip pi/|g|
    n = max(1, int(math.ceil((t1 - t0) / h)))
    step = (t1 - t0) / n
    total = 0.0
    for j in range(n):
        mid = t0 + (j + 0.5) * step
        for k in range(lx.size):
            rho = math.exp(mid + 0.5 * step * lx[k])
            total += lw[k] * abg_bsdf(rho, a, b, g) * rho * rho
    return 0.5 * step * total


@jit
def _abg_radial(r, a, b, g, lx, lw):
    """``G(r) = ∫_0^r F(ρ) ρ dρ`` of ABg (``r > 0``), graded on the lobe scale ``B^(1/g)``."""
    if g == 0.0:  # constant BSDF: exact
        return a / (b + 1.0) * 0.5 * r * r
    w = b ** (1.0 / g)  # the lobe's width in rho: d^g = B there
    # 1e-7 below the lobe (relative error of the [0, rho_min] piece ~ 1e-7^g * tiny area);
    # not below 1e-20 r (w underflows for small |g|: the integrand is then ~ rho, the piece
    # below 1e-20 r is 1e-40 of the rest)
    lo = max(1e-7 * min(w, r), 1e-20 * r)
    head = abg_bsdf(lo, a, b, g) * 0.5 * lo * lo
    return head + _abg_segment(lo, r, a, b, g, lx, lw)


@jit
def _abg_tis_point(ti, a, b, g, px, pw, lx, lw):
    s, c = math.sin(ti), math.cos(ti)
    total = 0.0
    acc = 0.0
    prev = 0.0
    for k in range(px.size):
        r = _radius(s, c, px[k])
        if r <= 0.0:  # theta_i = pi/2, psi < pi/2: beta0 on the rim, nothing inside
            acc = 0.0
        elif prev <= 0.0:
            acc = _abg_radial(r, a, b, g, lx, lw)
        else:  # R increases with psi: accumulate G from the previous node
            acc += _abg_segment(prev, r, a, b, g, lx, lw)
        prev = r
        total += pw[k] * acc
    return 2.0 * total


@jit
def _hs_tis_point(ti, b0, L, S, px, pw):
    s, c = math.sin(ti), math.cos(ti)
    total = 0.0
    for k in range(px.size):
        r = _radius(s, c, px[k])
        if r > 0.0:  # r = 0 only at theta_i = pi/2 for psi < pi/2: G(0) = 0
            total += pw[k] * harvey_shack_radial(r, b0, L, S)
    return 2.0 * total


@driver
def _abg_tis_drive(t, a, b, g, px, pw, lx, lw, out):  # pragma: no cover - compiled
    for i in prange(out.size):
        out[i] = _abg_tis_point(t[i], a, b, g, px, pw, lx, lw)


@driver
def _hs_tis_drive(t, b0, L, S, px, pw, out):  # pragma: no cover - compiled
    for i in prange(out.size):
        out[i] = _hs_tis_point(t[i], b0, L, S, px, pw)


def _shaped(ti: np.ndarray, out: np.ndarray) -> np.ndarray | float:
    return float(out[0]) if ti.ndim == 0 else out.reshape(ti.shape)


# --------------------------------------------------------------------------------------------
# public TIS functions
# --------------------------------------------------------------------------------------------
def abg_tis(theta_i: ArrayLike, A: float, B: float, g: float) -> np.ndarray | float:
    """TIS of the ABg model on the unit disk (directional-hemispherical reflectance).

    Parameters
    ----------
    theta_i : array_like
        Incidence zenith angles, radians, in ``[0, pi/2]``.
    A, B, g : float
        ABg parameters (Zemax's rules, :func:`check_abg`).

    Returns
    -------
    numpy.ndarray or float
        The shape of ``theta_i`` (a float for a scalar).

    Examples
    --------
    >>> import math
    >>> round(abg_tis(0.7, 0.3, 0.5, 0.0) / (math.pi * 0.3 / 1.5), 12)   # g = 0: pi A/(B+1)
    1.0
    """
    a, b, gg = check_abg(A, B, g)
    ti = check_zenith(theta_i, "theta_i")
    flat = np.ascontiguousarray(ti, dtype=np.float64).reshape(-1)
    out = np.empty(flat.size)
    if flat.size:
        _abg_tis_drive(flat, a, b, gg, _PSI_X, _PSI_W, _LN_X, _LN_W, out)
    return _shaped(ti, out)


def harvey_shack_tis(theta_i: ArrayLike, b0: float, L: float, S: float) -> np.ndarray | float:
    """TIS of FRED's Harvey–Shack model on the unit disk.

    At normal incidence it is ``2π G(1)`` (:func:`harvey_shack_radial`), closed form.

    Examples
    --------
    >>> import math
    >>> t = harvey_shack_tis(0.0, 0.1, 0.01, -1.5)
    >>> round(t / (2 * math.pi * harvey_shack_radial(1.0, 0.1, 0.01, -1.5)), 12)
    1.0
    """
    p = check_harvey_shack(b0, L, S)
    ti = check_zenith(theta_i, "theta_i")
    flat = np.ascontiguousarray(ti, dtype=np.float64).reshape(-1)
    out = np.empty(flat.size)
    if flat.size:
        _hs_tis_drive(flat, p[0], p[1], p[2], _PSI_X, _PSI_W, out)
    return _shaped(ti, out)


def abg_tis_plane(A: float, B: float, g: float) -> float:
    """ABg TIS with the unit disk replaced by the plane: ``2π² A B^(2/g-1) / (g sin(2π/g))``.

    From ``∫_0^∞ u^(a-1)/(1+u) du = π/sin(πa)`` (``0 < a < 1``) with ``u = ρ^g/B``,
    ``a = 2/g``; converges only for ``g > 2`` (else :class:`~roughbrdf.errors.ArgumentError`
    naming ``g``). An upper bound of :func:`abg_tis`, reached when the lobe is far from the rim.

    Examples
    --------
    >>> round(abg_tis_plane(1.0, 1.0, 4.0), 10) == round(math.pi ** 2 / 2, 10)
    True
    """
    a, b, gg = check_abg(A, B, g)
    if gg <= 2.0:
        raise ArgumentError("g", "the plane integral of the ABg BSDF converges only for g > 2",
                            value=gg)
    return 2.0 * math.pi ** 2 * a * b ** (2.0 / gg - 1.0) / (gg * math.sin(2.0 * math.pi / gg))


def harvey_shack_tis_plane(b0: float, L: float, S: float) -> float:
    """Harvey–Shack TIS over the plane: ``2π b0 L² / (-S - 2)``, converges for ``S < -2``.

    ``2π G(∞)`` of :func:`harvey_shack_radial`; :class:`~roughbrdf.errors.ArgumentError`
    naming ``S`` otherwise.

    Examples
    --------
    >>> round(harvey_shack_tis_plane(1.0, 0.1, -3.0), 12) == round(2 * math.pi * 0.01, 12)
    True
    """
    bb, ll, ss = check_harvey_shack(b0, L, S)
    if ss >= -2.0:
        raise ArgumentError("S", "the plane integral of the Harvey-Shack BSDF converges only "
                            "for S < -2", value=ss)
    return 2.0 * math.pi * bb * ll * ll / (-ss - 2.0)

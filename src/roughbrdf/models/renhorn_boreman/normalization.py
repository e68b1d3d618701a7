"""The numeric normalization of RB08 (``normalization="numeric"``): ``N = 1/I`` per incidence.

``I(theta_i)`` is the unit-disk integral of the cosine-width, V-shadowed lobe of Eqs. 12/15
(docs/models.md §4.12), reduced to one radial integral and taken by Gauss-Legendre panels
(:func:`lobe_integral`). :class:`NumericNormalization` turns it into per-sample values and owns
the caches that make a fit's thousands of evaluations cheap: exact values per distinct
incidence, interpolation tables for many incidences, and the distinct incidences of the last
few ``theta_i`` arrays. :data:`NUMERIC_N` is the one instance the model uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ... import _kernels, special
from ... import shadowing as shd
from ..._kernels import jit
from .kernel import rb08_norm_ufunc

__all__ = ["NUMERIC_N", "NumericNormalization", "lobe_integral", "numeric_n"]

#: Gauss-Legendre nodes and weights on [-1, 1] of one panel of :func:`lobe_integral`
_GL_X, _GL_W = np.polynomial.legendre.leggauss(12)
#: where V = Q(a, x) turns over: x = a + z sqrt(a) (Q falls from 1 to 0 around x = a, over a
#: width sqrt(a)); panel edges are placed at the s = sin(theta) of these x
_V_TURN_Z = np.array([-4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0, 8.0, 16.0])
_MIN_PANELS = 8  # uniform panels on each side of the peak
_U_PER_PANEL = 3.0  # and at most this much of u per panel (u_max ~ ln(2/eps) for a sharp peak)
_U_LARGE = 700.0  # beyond it sinh, cosh are taken as exp(u)/2 (they overflow at 710)


@jit
def _lobe_radial(u, side, a0, ci, v0, eps, rho2, scale, a, st):
    """Integrand of :func:`lobe_integral` per unit ``u``, at ``s = a0 + side eps sinh(u)``.

    ``2 pi s ds / sqrt(((s - a0)^2 + c)((s + a0)^2 + c))`` with ``ds = eps cosh(u) du``,
    divided by ``2 pi``, written with ``(s - a0)^2 + c = (eps cosh u)^2 (tanh^2 u + q)``:
    ``eps^2`` itself underflows when V(sin theta_i) is below ~1e-150, ``q`` does not.
    """
    if u > _U_LARGE:  # eps below ~1e-300: the exponential asymptote, eps in the exponent
        dx = side * 0.5 * math.exp(u + math.log(eps))
        sech = 2.0 * math.exp(-u)
    else:
        dx = side * eps * math.sinh(u)
        sech = 1.0 / math.cosh(u)
    s = min(1.0, a0 + dx)
    cs = math.sqrt(max(0.0, (1.0 - s) * (1.0 + s)))  # max: s = 1 may round (1 - s)(1 + s) < 0
    vs = shd.rb08_v(s, scale, a, st)
    h = (ci + cs) * sech / (2.0 * ci)
    # q = c(s)/(eps cosh u)^2 = h^2 V(s)/V(a0), which overflows where V(a0) is subnormal and
    # the width term dwarfs the distance to the peak
    num = h * h * vs
    if num >= 1e300 * v0:
        return 0.0  # q = num/v0 would overflow: the integrand is below 1e-150 of the total
    q = num / v0
    th = math.tanh(u)
    c = 0.25 * (ci + cs) * (ci + cs) * v0 * vs * rho2
    return s / math.sqrt((th * th + q) * ((s + a0) * (s + a0) + c))


@jit(inline=True)
def _asinh_ratio(x, eps):
    # asinh(x/eps) for x, eps > 0 without forming x/eps, which overflows for a subnormal eps:
    # asinh(r) = ln(2r) to double precision for r > 1e300 (ln r > 690.8)
    lr = math.log(x) - math.log(eps)
    return lr + math.log(2.0) if lr > 690.8 else math.asinh(x / eps)


@jit
def _lobe_edges(a0, eps, span, umax, side, scale, a):
    """Sorted panel edges in ``x`` on [0, 1] for one side of the peak (see lobe_integral)."""
    npan = max(_MIN_PANELS, int(math.ceil(umax / _U_PER_PANEL)))
    edges = np.empty(npan + 1 + _V_TURN_Z.size + 64)
    m = 0
    for k in range(npan + 1):
        edges[m] = k / npan
        m += 1
    pts = np.empty(_V_TURN_Z.size + 64)
    npts = 0
    if scale > 0.0:  # scale = 0: w = inf, V = 1, no turn-over
        for z in _V_TURN_Z:
            xq = a + z * math.sqrt(a)
            if xq > 0.0:
                pts[npts] = math.sqrt(xq / scale)
                npts += 1
    if side < 0.0:
        # near grazing, cos(theta_s) ~ sqrt(1 - s) varies on the scale 1 - a0 next to the
        # peak: edges at distances (1 - a0) 4^k from it (the max keeps the loop finite when
        # sin(theta_i) rounds to 1)
        d = max(1.0 - a0, 1e-17)
        while d < a0 and npts < pts.size:
            pts[npts] = a0 - d
            npts += 1
            d *= 4.0
    for k in range(npts):
        dist = (pts[k] - a0) * side
        if 0.0 < dist < span:
            r = _asinh_ratio(dist, eps) / umax
            edges[m] = 1.0 - math.sqrt(max(0.0, 1.0 - r)) if side > 0.0 else r
            m += 1
    return np.sort(edges[:m])


@jit
def _lobe_side(a0, ci, v0, rho, scale, a, st, side):
    """``∫ s ds / sqrt(((s - a0)^2 + c)((s + a0)^2 + c))`` from ``a0`` to 1 (side 1) or to 0
    (side -1), in ``s = a0 + side eps sinh(u)``, ``eps = cos(theta_i) V(a0) rho`` (the width
    at the peak); on the rim side ``u = u_max (1 - (1 - x)^2)``, which makes the square root
    of ``cos theta_s`` at ``s = 1`` smooth in ``x``; on the other ``u = u_max x``."""
    span = 1.0 - a0 if side > 0.0 else a0
    if not span > 0.0:
        return 0.0  # normal incidence: nothing below the peak
    eps = ci * v0 * rho
    umax = _asinh_ratio(span, eps)
    edges = _lobe_edges(a0, eps, span, umax, side, scale, a)
    total = 0.0
    for k in range(edges.size - 1):
        half = 0.5 * (edges[k + 1] - edges[k])
        mid = 0.5 * (edges[k + 1] + edges[k])
        for j in range(_GL_X.size):
            x = mid + half * _GL_X[j]
            if side > 0.0:
                u = umax * (1.0 - (1.0 - x) * (1.0 - x))
                du = 2.0 * umax * (1.0 - x)
            else:
                u = umax * x
                du = umax
            total += half * _GL_W[j] * du * _lobe_radial(u, side, a0, ci, v0, eps, rho * rho,
                                                         scale, a, st)
    return total


@_kernels.ufunc(5)
def _lobe_integral_ufunc(ti, rho, scale, a, st):
    a0, ci = math.sin(ti), math.cos(ti)
    v0 = shd.rb08_v(a0, scale, a, st)
    if not ci * v0 * rho > 0.0:
        return math.inf  # zero width at the peak: the disk integral diverges
    return 2.0 * math.pi * (_lobe_side(a0, ci, v0, rho, scale, a, st, 1.0)
                            + _lobe_side(a0, ci, v0, rho, scale, a, st, -1.0))


def lobe_integral(theta_i, rho: float, w: float, n: float) -> np.ndarray:
    """``I = ∫∫_{alpha²+beta²<=1} dalpha dbeta / D(alpha - alpha0; rho, w, n)`` per incidence.

    The unit-disk integral of the cosine-width, V-shadowed lobe of Eqs. 12/15 (without sigma,
    N and Vm), so that ``N = 1/I`` normalizes it exactly (``normalization="numeric"``). The
    same ``I`` serves the retro lobe (its mirror image, with rho_r, w_r, n_r); ``w = inf``
    drops V (the amplitude retro lobe).

    Method: ``D = (alpha - alpha0)^2 + beta^2 + c(s)``, where the width term
    ``c(s) = (cos theta_i + cos theta_s)^2 V(alpha0) V(s) rho^2/4`` depends on
    ``s = sqrt(alpha^2 + beta^2) = sin theta_s`` only. In polar coordinates about the origin
    the azimuthal integral is elementary, ``∫_0^{2pi} dphi/(A - B cos phi) = 2pi/sqrt(A^2 -
    B^2)``, which leaves one radial integral, exactly::

        I = 2 pi ∫_0^1 s ds / sqrt(((s - alpha0)^2 + c(s)) ((s + alpha0)^2 + c(s)))

    It is taken on each side of the peak ``s = alpha0`` in ``s - alpha0 = ±eps sinh(u)``
    (``eps = cos theta_i V(alpha0) rho``, the width at the peak: smooth in ``u`` whatever the
    width) by composite 12-point Gauss-Legendre panels: 8 uniform ones (more for a peak
    narrower than ~1e-3), plus edges where V turns over (sharp for large n or small w) and,
    below the peak, at distances ``(1 - alpha0) 4^k`` from it (near grazing incidence).
    ~300-6000 integrand evaluations, ~0.02 ms per incidence. Relative accuracy against a
    16x finer quadrature: <= 2e-11 up to 89.99 deg (rho 0.005-2, w 0.05-2, n 0-50, tested),
    ~1e-7 within 1e-4 deg of grazing (where ``1 - sin theta`` itself loses the digits).
    (What it replaced, and why: CHANGELOG, "History of the numerical changes".)
    """
    ti = np.asarray(theta_i, dtype=np.float64)
    a = 1.0 + n
    scale = a / (w * w)  # w = inf: scale = 0 and V = Q(a, 0) = 1
    return np.atleast_1d(_lobe_integral_ufunc(ti, float(rho), scale, a, special.stirlerr(a)))


# nodes in z = log(cos theta_i): every 0.5 deg up to 89 deg, then cos theta_i geometric to 1e-5
_Z_NODES = np.unique(np.log(np.concatenate([
    np.geomspace(1e-5, math.cos(math.radians(89.0)), 80),
    np.cos(np.radians(np.linspace(0.0, 89.0, 179)))])))


class NumericNormalization:
    """Per-sample numeric N of the RB08 lobes, and the caches it keeps (all bounded).

    Parameters
    ----------
    max_values : int
        Exact values ``1/I`` kept, keyed on ``(rho, w, n, theta_i)``; the cache is emptied
        before it would grow beyond this.
    max_exact : int
        Most distinct incidences computed exactly (each by quadrature, ~0.02 ms); with more,
        the values are interpolated from a table of the lobe (:meth:`table`).
    max_tables : int
        Interpolation tables kept, keyed on ``(rho, w, n)`` (~5 ms each to build); emptied when
        a new one would come on top of more than this.
    max_index : int
        ``theta_i`` arrays whose distinct incidences are remembered (a fit evaluates the same
        array thousands of times).
    """

    def __init__(self, *, max_values: int = 200_000, max_exact: int = 256,
                 max_tables: int = 64, max_index: int = 4) -> None:
        self.max_values = max_values
        self.max_exact = max_exact
        self.max_tables = max_tables
        self.max_index = max_index
        self._values: dict[tuple, float] = {}
        self._tables: dict[tuple, Any] = {}
        #: id -> (the array, a copy of its values, its index)
        self._index: dict[int, tuple[np.ndarray, np.ndarray, Any]] = {}

    def sizes(self) -> dict[str, int]:
        """Entries in each cache: ``{"values": ..., "tables": ..., "index": ...}``."""
        return {"values": len(self._values), "tables": len(self._tables),
                "index": len(self._index)}

    def clear(self) -> None:
        """Empty every cache."""
        self._values.clear()
        self._tables.clear()
        self._index.clear()

    def __call__(self, ti: np.ndarray, lobes: list[tuple[float, float, float] | None]
                 ) -> list[np.ndarray | None]:
        """Per-sample numeric normalization ``1/I(theta_i)`` (shape of ``ti``) of each lobe
        ``(rho, w, n)`` (None: not wanted), the distinct incidences found once for all of them."""
        index = self.incidence_index(ti)
        out: list[np.ndarray | None] = []
        for lobe in lobes:
            if lobe is None:
                out.append(None)
            elif index is None:
                out.append(self.table(*lobe)(ti.reshape(-1)).reshape(ti.shape))
            else:
                out.append(self.exact(index[0], *lobe)[index[1]])
        return out

    def incidence_index(self, ti: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """``(distinct incidences, index of each sample into them)``, or None when there are
        more than ``max_exact`` (then the table is interpolated). Remembered for the last few
        arrays, checked against a copy of their values (~10 us instead of a sort, ~70 us for a
        Mini-Diff channel)."""
        got = self._index.get(id(ti))
        if got is not None and got[0] is ti and np.array_equal(got[1], ti):
            return got[2]
        flat = ti.reshape(-1)
        index = None
        # many distinct incidences (e.g. random geometries) show up in a subsample already:
        # skip the full sort then and interpolate every sample directly
        sub = flat[:: max(1, flat.size // 4096)]
        if sub.size == flat.size or np.unique(sub).size <= self.max_exact:
            uniq, inv = np.unique(flat, return_inverse=True)
            if uniq.size <= self.max_exact:
                index = (uniq, inv.reshape(ti.shape))
        if len(self._index) >= self.max_index:
            self._index.clear()  # bounded: a new array on top of max_index empties the memo
        self._index[id(ti)] = (ti, ti.copy(), index)
        return index

    def exact(self, uniq: np.ndarray, rho: float, w: float, n: float) -> np.ndarray:
        """``1/I`` for each distinct incidence, from the cache or by quadrature."""
        vals = np.empty(uniq.size)
        missing = []
        for j, t in enumerate(uniq):
            got = self._values.get((rho, w, n, float(t)))
            if got is None:
                missing.append(j)
            else:
                vals[j] = got
        if missing:
            ints = lobe_integral(uniq[missing], rho, w, n)
            if len(self._values) + len(missing) > self.max_values:
                self._values.clear()  # bounded: empty rather than grow beyond max_values
            for j, i_val in zip(missing, ints, strict=True):
                vals[j] = 1.0 / i_val
                self._values[(rho, w, n, float(uniq[j]))] = vals[j]
        return vals

    def table(self, rho: float, w: float, n: float) -> Callable[[np.ndarray], np.ndarray]:
        """Interpolant of the numeric N over theta_i in [0, pi/2), for many distinct incidences.

        Interpolated: the ratio ``N_numeric / N(alpha0, rho_eff)`` to the specular-width
        analytic N (smooth, close to 1), by a cubic spline in ``z = log(cos theta_i)`` (an even,
        smooth function of theta_i near 0 and logarithmic near grazing), on 258 nodes computed
        exactly (every 0.5 deg to 89 deg, then geometric in ``cos theta_i`` down to 1e-5);
        relative error ~1e-7 at most (tested). Incidences with ``cos theta_i < 1e-5`` (within
        0.0006 deg of grazing), and those where the analytic N is 0, are computed exactly.
        """
        key = (rho, w, n)
        interp = self._tables.get(key)
        if interp is None:
            interp = self._build_table(rho, w, n)
            if len(self._tables) > self.max_tables:
                self._tables.clear()  # bounded: empty rather than keep every lobe seen
            self._tables[key] = interp
        return interp

    def _build_table(self, rho: float, w: float, n: float
                     ) -> Callable[[np.ndarray], np.ndarray]:
        """The interpolant of :meth:`table` (258 exact values, ~5 ms)."""
        from scipy.interpolate import CubicSpline

        th = np.arccos(np.exp(_Z_NODES))
        exact = 1.0 / lobe_integral(th, rho, w, n)
        analytic = _analytic_specular_width(th, rho, w, n)
        # where rho_eff = rho cos(theta_i) V(sin theta_i) underflows (V below ~1e-160: large n,
        # sin theta_i beyond w) the analytic N is 0 and the ratio undefined: those incidences are
        # computed exactly, and the ratio at their nodes is continued from the others (it then
        # only shapes the spline). Node 0 (theta_i = 0, V = 1) is always valid.
        ok = analytic > 0.0
        ratio = np.empty_like(exact)
        ratio[ok] = exact[ok] / analytic[ok]
        ratio[~ok] = np.interp(_Z_NODES[~ok], _Z_NODES[ok], ratio[ok])
        spline = CubicSpline(_Z_NODES, ratio)

        def interp(theta: np.ndarray) -> np.ndarray:
            ci = np.cos(theta)
            scale = _analytic_specular_width(theta, rho, w, n)
            out = spline(np.log(np.maximum(ci, 1e-5))) * scale
            edge = (ci < 1e-5) | ~(scale > 0.0)
            if edge.any():
                out[edge] = self.exact(theta[edge], rho, w, n)
            return out

        return interp


def _analytic_specular_width(theta, rho, w, n):
    theta = np.asarray(theta, dtype=np.float64)
    a0 = np.sin(theta)
    ci = np.cos(theta)
    v0 = 1.0 if w == math.inf else shd.V(a0, w, n)  # w = inf: no shadowing (V = 1)
    # a subnormal rho_eff (V underflowing) overflows ln(arg) to inf: N = 0, its limit
    with np.errstate(over="ignore"):
        return rb08_norm_ufunc(ci * ci, a0 * a0, rho * ci * v0)


#: the numeric N of every RB08 model of the process (its caches are shared by all of them)
NUMERIC_N = NumericNormalization()


def numeric_n(ti: np.ndarray, lobes: list[tuple[float, float, float] | None]
              ) -> list[np.ndarray | None]:
    """:data:`NUMERIC_N` of ``(ti, lobes)``: per-sample ``1/I(theta_i)`` of each lobe."""
    return NUMERIC_N(ti, lobes)

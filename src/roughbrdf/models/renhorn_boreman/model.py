"""The RB08 model class, :class:`RenhornBoreman2008`, with its parameters and options.

The readings of the reconstructed equations (docs/models.md §4) are options; their values and
aliases are :data:`OPTION_VALUES`. Evaluation packs the parameters for the compiled kernel
(:mod:`~roughbrdf.models.renhorn_boreman.kernel`) and, with ``normalization="numeric"``, asks
:mod:`~roughbrdf.models.renhorn_boreman.normalization` for the per-sample N.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from ... import special
from ...fresnel import check_index
from ...registry import Registry
from ..base import Model, PreparedGeometry, register
from ..parameters import Parameter, nonnegative, positive, reflectance
from .kernel import NORM_CODES, POL_WEIGHT, RETRO_CODES, TERM_CODES, WEIGHT_CODES, ZETA_CODES, run
from .normalization import numeric_n

__all__ = ["OPTION_VALUES", "RenhornBoreman2008"]


def _option(name: str, values: dict[str, tuple[str, ...]]) -> Registry[str]:
    reg: Registry[str] = Registry(f"value {{name}} for option {name!r} of model "
                                  "'renhorn-boreman-2008'")
    for canonical, aliases in values.items():
        reg.add(canonical, canonical, aliases)
    return reg


#: the readings (options) of the reconstructed model and their aliases (docs/models.md §4)
OPTION_VALUES: dict[str, Registry[str]] = {
    "zeta": _option("zeta", {"angle": ("z-a",), "cosine": ("z-b",),
                             "zenith-difference": ("z-c",)}),
    "surface_weight": _option("surface_weight", {"geometric-mean": ("sqrt", "q=1/2"),
                                                 "product": ("q=1",), "transmission": ()}),
    "normalization": _option("normalization", {"literal": (), "specular-width": (),
                                               "numeric": ()}),
    "retro_shadowing": _option("retro_shadowing", {"width": (), "amplitude": ("acceptance",)}),
    "polarization": _option("polarization", {"unpolarized": ("natural", "none"),
                                             "s": ("te", "perpendicular"),
                                             "p": ("tm", "parallel")}),
}


def _horner_ok(n: float) -> bool:
    # V by the vectorizable finite sum: integer n up to special.INT_HORNER_MAX
    return float(n).is_integer() and n <= special.INT_HORNER_MAX


def _real(name: str, default: float, bounds: tuple[float, float], unit: str, desc: str
          ) -> Parameter:
    return Parameter(name, default, bounds, unit, desc)


@register
class RenhornBoreman2008(Model):
    """Renhorn & Boreman (2008) analytical rough-surface BRDF: surface, bulk and retro terms.

    I. G. E. Renhorn and G. D. Boreman, "Analytical fitting model for rough-surface BRDF",
    Opt. Express 16(17), 12892 (2008), Eqs. 5-20, as reconstructed in docs/models.md §4. Only the
    flattened equations of the paper survive, so some parts are *our reading*; every alternative
    reading is an option.

    Parameters (the fourteen of the abstract, docs/models.md §4.11)
    ----------------------------------------------------------
    rho : float > 0
        Surface-lobe width: half width at half maximum of the Lorentzian in direction-cosine
        space (an inverse correlation length). *Certain* (Eqs. 5-15).
    w : float > 0
        Shadowing cut-off of ``V`` in ``sin theta`` units (Eq. 10). *Certain.*
    n : float >= 0
        Shadowing sharpness of ``V`` (0: ``exp(-chi^2/w^2)``, Eq. 11; large: a step at ``w``).
        *Certain.*
    w_a, w_b : float (any sign)
        Amplitude and angular decay of the masking multiplier ``Vm``,
        ``B = exp(-w_a zeta exp(-w_b alpha^2))`` (Eq. 13). *Certain* as symbols; the signs are our
        convention (any lost sign is absorbed by the sign of the parameter).
    gamma : float >= 0
        Amplitude of Vm's incidence weight ``E0 = exp(-gamma zeta0 exp(-delta zeta0^2))``.
        *Certain* as a symbol; ``gamma >= 0`` keeps ``E0 <= 1`` and hence ``Vm > 0``.
    delta : float (any sign)
        Decay of Vm's incidence weight. *Certain* as a symbol.
    n_eff, k_eff : float
        Effective complex index ``n_eff + i k_eff`` of the Fresnel factor (Eqs. 16-17). *Certain.*
    bulk, retro : float in [0, 1]
        Strengths of the bulk (Lambertian) and retro terms, ``sigma_bulk = (1 - sigma_s) bulk``,
        ``sigma_retro = (1 - sigma_s) retro`` (Eqs. 19-20). *Certain* as strengths; the bulk
        term's Lambertian shape is *our reading* (the shapes were defined in the lost prose).
        Both are reflectances of a part (before the Fresnel weight ``1 - sigma_s``), so their
        domain is ``[0, 1]`` like every reflectance-like parameter
        (:data:`~roughbrdf.models.parameters.REFLECTANCE_DOMAIN`).
    rho_r, w_r, n_r : float
        Retro lobe width and its own shadowing pair. *Our reading:* ``rho_r`` is probable (a
        retro lobe needs a width), ``w_r``, ``n_r`` speculative (docs/models.md §4.11).

    Options (the alternative readings; defaults are docs/models.md's recommendations)
    ----------------------------------------------------------------------------
    zeta : {"angle", "cosine", "zenith-difference"}
        What Vm's ``zeta``, ``zeta0`` are (§4.8): ``"angle"`` ``zeta = arcsin(sin theta_s cos
        phi)``, ``zeta0 = theta_i`` (radians); ``"cosine"`` ``zeta = alpha``, ``zeta0 =
        alpha0``; ``"zenith-difference"`` ``zeta = theta_s - theta_i``, ``zeta0 = theta_i`` and
        ``sin^2 theta_s`` in B's exponent (our choice: the reading is then azimuthally symmetric).
    surface_weight : {"geometric-mean", "product", "transmission"}
        The bracket of Eqs. 19-20, ``1 - sigma_s``: ``sigma_s = sqrt(R(alpha0) R(alpha, beta))``
        (q = 1/2), ``R(alpha0) R(alpha, beta)`` (q = 1), or the two-bracket transmission
        ``1 - sigma_s = [1 - R(alpha0)][1 - R(alpha, beta)]``. The printed identity
        ``sigma_bulk/bulk = sigma_retro/retro = 1 - sigma_s`` holds for all three.
    normalization : {"literal", "specular-width", "numeric"}
        The ``N`` of Eqs. 9-15 (§4.12): ``"literal"`` ``N(alpha0, rho)`` as printed (then sigma
        is not the lobe's hemispherical reflectance: 1.0-3.3x at rho = 0.1-0.3, theta_i <= 75
        deg); ``"specular-width"`` ``N(alpha0, rho cos theta_i V(sin theta_i))``, the width at the
        peak (within ~5 %); ``"numeric"`` ``N = 1/∫∫_disk dalpha dbeta/D`` by quadrature
        (:func:`lobe_integral`), so that with constant sigma and Vm = 1 the lobe's hemispherical
        integral is exactly sigma. Numeric N is computed per distinct ``theta_i`` (a 1-D
        radial quadrature, ~0.02 ms each, cached) when there are at most 256 of them, else
        interpolated from a table of 258 exact values (cubic spline in ``log cos theta_i``,
        relative error ~1e-7; built once per (rho, w, n) in ~5 ms and cached).
    polarization : {"unpolarized", "s", "p"}
        Which Fresnel reflectance of Eqs. 16-17 is R: ``(R_s + R_p)/2``, ``R_s`` or ``R_p``. A
        per-call ``brdf(..., polarization=...)`` overrides it: ``"s"`` (gamma = pi/2), ``"p"``
        (gamma = 0) or an angle gamma of the incident field from the plane of incidence gives
        ``R = R_s sin^2 gamma + R_p cos^2 gamma`` (TR75 Eq. 24 with eta = 0, the Fresnel factor
        being taken at macroscopic angles), used for both ``R(alpha0)`` and ``R(alpha, beta)``;
        ``None``/NaN uses the option.
    retro_shadowing : {"width", "amplitude"}
        Where the retro lobe's own shadowing pair ``V(sin theta_i, w_r, n_r) V(sin theta_s,
        w_r, n_r)`` acts. Parameters 13-14 (``w_r``, ``n_r``) are *speculative* (docs/models.md
        §4.10-4.11: the retro shape was in the lost prose), so both are *our reading*.
        ``"width"`` (default, docs/models.md §4.10): the surface lobe mirrored to the retro point,
        the pair multiplying ``rho_r^2`` in the width term as V does in Eq. 12. Its retro peak
        ``BRDF cos theta_s = (1 - R(theta_i)) retro N(alpha0, rho_r)/(cos theta_i V(sin
        theta_i)^2 rho_r^2)`` can only *grow* with incidence (V <= 1 decreasing; for
        ``n_eff >= 1`` the peak at 15 deg is at most ~0.5x the one at 60 deg over the bounds),
        unless the effective index is below ``sin theta_i`` (a total-internal-reflection
        artefact of the Fresnel factor). ``"amplitude"``: the pair multiplies the retro
        *strength* and the width term is ``(cos theta_i + cos theta_s)^2 rho_r^2/4``: the
        acceptance-angle cut-off of bead and prism retro-reflectors, whose retro peak falls
        steeply beyond the acceptance angle ``~w_r`` (in ``sin theta``). Measured
        retro-reflectors need it: the CEA gray tape's retro peak BRDF cos falls 72.5 -> 42.5 ->
        1.1 at 15, 30, 60 deg. The ``normalization`` options then use the amplitude lobe's own
        width: ``"specular-width"`` ``N(alpha0, rho_r cos theta_i)``, ``"numeric"`` the disk
        integral of the lobe without V (the retro term's hemispherical integral is then
        ``~(1 - sigma_s) retro V(sin theta_i)^2``: V cuts off the strength).

    Notes
    -----
    * The Fresnel factor is evaluated at the macroscopic angles ``theta_i`` and ``theta_s``
      (Eqs. 16-17 written in the direction cosine are exactly the standard Fresnel equations,
      docs/models.md §4.9), with :func:`roughbrdf.fresnel.fresnel_sp`.
    * **Not reciprocal** (docs/models.md §4.13): the denominators and ``sigma_s`` (q = 1/2) are
      symmetric in ``(theta_i, theta_s)``, but ``N(alpha0, rho)`` depends on the incidence only
      and Vm distinguishes incidence from scattering, so ``f(i, s) != f(s, i)`` in general. Energy
      conservation is not guaranteed either (the model is a fitting function).
    * Evaluated over the full hemisphere (out of the plane of incidence too). Finite everywhere
      for ``theta_i < pi/2``, including normal incidence, ``theta_s = pi/2``, the specular and the
      retro points. ``theta_i = pi/2`` is rejected: there ``cos theta_i + cos theta_s`` and hence
      the width term vanish at the specular and retro points on the rim, the lobes become
      ``1/distance^2`` singularities with an infinite hemispherical integral, and the BRDF is not
      defined (it is finite for any ``theta_i`` below pi/2). If ``V(sin theta_i)`` underflows
      to 0 (extremely sharp shadowing, ``n`` in the hundreds with ``sin theta_i > w``) the same
      happens at the peak, which then returns ``inf`` (never NaN).
    * ``term="surface" | "bulk" | "retro"`` evaluates one term alone.
    * The sigma of Eqs. 5-15 is ``sigma_surface`` itself (no separate free scale, docs/models.md
      §4.10): the 14 parameters of the abstract are then exactly the list above.
    * Defaults: a matte-paint-like surface, no published values being available: index 1.5
      (R = 4 % at normal incidence), a broad weak gloss lobe (rho = 0.3, w = 0.9, n = 4), a
      strong bulk term (bulk = 0.85), a faint retro lobe (retro = 0.02, rho_r = 0.2) and Vm
      switched off (w_a = 0). Directional-hemispherical reflectance 0.87 at normal incidence,
      0.89 at 60 deg with ``normalization="specular-width"``; with the literal N it exceeds 1
      beyond ~60 deg (1.75 at 80 deg: the lobe's integral grows as in docs/models.md §4.12).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> m = rb.model("rb08")
    >>> f = m.brdf(0.5, 0.5, 0.0)             # specular point
    >>> parts = [m.brdf(0.5, 0.5, 0.0, term=t) for t in ("surface", "bulk", "retro")]
    >>> abs(sum(parts) - f) < 1e-12
    True
    """

    name = "renhorn-boreman-2008"
    aliases = ("rb08", "renhorn-boreman")
    short = "rb08"
    reference = "Renhorn & Boreman, Opt. Express 16(17), 12892 (2008)"
    PARAMETERS = (
        positive("rho", 0.3, (0.005, 2.0), "1",
                 "surface lobe width (HWHM in direction-cosine space), Eqs. 5-15"),
        positive("w", 0.9, (0.05, 2.0), "1", "shadowing cut-off of V, in sin(theta), Eq. 10"),
        nonnegative("n", 4.0, (0.0, 50.0), "1", "shadowing sharpness of V, Eq. 10"),
        _real("w_a", 0.0, (-5.0, 5.0), "1/rad", "Vm amplitude, B = exp(-w_a zeta exp(-w_b a^2))"),
        _real("w_b", 1.0, (-5.0, 5.0), "1", "Vm angular decay (exponent of alpha^2), Eq. 13"),
        nonnegative("gamma", 1.0, (0.0, 10.0), "1/rad",
                    "Vm incidence weight amplitude, E0 = exp(-gamma z0 exp(-delta z0^2))"),
        _real("delta", 0.0, (-5.0, 5.0), "1/rad^2", "Vm incidence weight decay, Eq. 13"),
        positive("n_eff", 1.5, (0.2, 5.0), "1", "effective refractive index, Eqs. 16-17"),
        nonnegative("k_eff", 0.0, (0.0, 10.0), "1", "effective extinction index, Eqs. 16-17"),
        reflectance("bulk", 0.85,
                    "bulk (Lambertian) strength, sigma_bulk = (1 - sigma_s) bulk, Eq. 19"),
        reflectance("retro", 0.02,
                    "retro-reflection strength, sigma_retro = (1 - sigma_s) retro, Eq. 20"),
        positive("rho_r", 0.2, (0.005, 2.0), "1", "retro lobe width (our reading)"),
        positive("w_r", 0.9, (0.05, 2.0), "1", "retro shadowing cut-off (our reading)"),
        nonnegative("n_r", 4.0, (0.0, 50.0), "1", "retro shadowing sharpness (our reading)"),
    )
    OPTIONS = {"zeta": "angle", "surface_weight": "geometric-mean", "normalization": "literal",
               "polarization": "unpolarized", "retro_shadowing": "width"}
    #: set by :meth:`with_general_kernel`
    _force_general: bool = False
    TERMS = ("surface", "bulk", "retro")
    grazing_incidence = False
    reciprocal = False

    def _check_options(self, options: dict[str, Any]) -> dict[str, Any]:
        return {key: OPTION_VALUES[key].canonical("unpolarized" if val is None else val)
                for key, val in options.items()}

    def _validate(self) -> None:
        v = self._floats()
        check_index(v["n_eff"], v["k_eff"])

    def _pack(self, term: int = 0) -> tuple:
        v = self._floats()
        o = self._options
        a_s = 1.0 + v["n"]
        a_r = 1.0 + v["n_r"]
        return (v["rho"], v["w"], v["n"], v["w_a"], v["w_b"], v["gamma"], v["delta"],
                v["n_eff"], v["k_eff"], v["bulk"], v["retro"], v["rho_r"], v["w_r"], v["n_r"],
                float(ZETA_CODES[o["zeta"]]), float(WEIGHT_CODES[o["surface_weight"]]),
                float(NORM_CODES[o["normalization"]]), POL_WEIGHT[o["polarization"]],
                float(term),
                a_s, a_s / (v["w"] * v["w"]), special.stirlerr(a_s),
                a_r, a_r / (v["w_r"] * v["w_r"]), special.stirlerr(a_r),
                1.0 if (v["w_r"], v["n_r"]) == (v["w"], v["n"]) else 0.0,
                1.0 if self.uses_fast_kernel else 0.0,
                float(RETRO_CODES[o["retro_shadowing"]]))

    @property
    def uses_fast_kernel(self) -> bool:
        """Whether evaluation takes the vectorized kernel: integer ``n`` and ``n_r`` up to
        ``special.INT_HORNER_MAX``, unless made with :meth:`with_general_kernel`."""
        v = self._floats()
        return not self._force_general and _horner_ok(v["n"]) and _horner_ok(v["n_r"])

    def with_general_kernel(self) -> RenhornBoreman2008:
        """A copy that always runs the general kernel (series / continued fraction for V, any
        real ``n``): the reference the vectorized kernel is checked against (to ~1e-13)."""
        new = copy.copy(self)
        new._force_general = True
        return new

    def _numeric_lobes(self, term: str | None) -> list[tuple[float, float, float] | None]:
        """``(rho, w, n)`` of the surface and retro lobes whose numeric N ``term`` needs (None:
        not needed; the amplitude retro lobe has no V in its width: ``w = inf``)."""
        v = self._floats()
        surface = (v["rho"], v["w"], v["n"]) if term in (None, "surface") else None
        retro = None
        if term in (None, "retro") and v["retro"] != 0.0:
            amp = self._options["retro_shadowing"] == "amplitude"
            retro = (v["rho_r"], math.inf, 0.0) if amp else (v["rho_r"], v["w_r"], v["n_r"])
        return [surface, retro]

    def _kernel(self, g: PreparedGeometry, flag: int, term: str | None
                ) -> np.ndarray | float:
        ti, tr, phi, gamma = g.theta_i, g.theta_r, g.phi, g.gamma
        if term not in TERM_CODES:
            raise ValueError(f"model {self.name!r} has terms {self.TERMS}; got term={term!r}")
        p = self._pack(TERM_CODES[term])
        ns = nr = None
        if self._options["normalization"] == "numeric":
            ns, nr = numeric_n(np.asarray(ti, dtype=np.float64), self._numeric_lobes(term))
        return run(np.asarray(ti, dtype=np.float64), np.asarray(tr, dtype=np.float64),
                   np.asarray(phi, dtype=np.float64), np.asarray(gamma, dtype=np.float64),
                   p, flag, ns, nr, general=self._force_general)

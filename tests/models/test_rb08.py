"""Renhorn & Boreman (2008), RB08: the docs/models.md §4.14 targets and the model's contract.

The reference numbers come from docs/models.md §4 (computed there by an independent NumPy/SciPy
implementation). ``ref_terms`` below is a second, plain NumPy/SciPy transcription of the
docs/models.md §4/§8 formulas as printed (literal N of Eq. 6, literal Eq. 13 with Sgn, Eqs. 16-17 in
complex arithmetic, ``scipy.special.gammaincc``); the compiled kernel is checked against it.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis_profiles import jit_disabled
from scipy import integrate, special

import roughbrdf as rb
from roughbrdf import special as rbs
from roughbrdf.fresnel import fresnel_sp
from roughbrdf.models import renhorn_boreman as rbm
from roughbrdf.models.renhorn_boreman import kernel as rbk

deg = np.radians
HALF_PI = math.pi / 2
#: NUMBA_DISABLE_JIT=1 (make test-nojit): the kernels run as plain Python (100 to 1000 times
#: slower); the heaviest tests below check the same identities, to the same tolerances, on
#: smaller grids there
NOJIT = jit_disabled(os.environ)
RETRO_SHADOWING = ("width", "amplitude")
P_NAMES = ["rho", "w", "n", "w_a", "w_b", "gamma", "delta", "n_eff", "k_eff", "bulk", "retro",
           "rho_r", "w_r", "n_r"]
# a parameter set that switches every part on (Vm, real n, separate retro shadowing)
FULL = dict(rho=0.25, w=0.7, n=3.5, w_a=0.4, w_b=1.5, gamma=0.8, delta=0.6, n_eff=1.6,
            k_eff=0.3, bulk=0.6, retro=0.15, rho_r=0.15, w_r=0.8, n_r=2.0)


def random_geometry(n, seed=0, ti_max=1.55):
    rng = np.random.default_rng(seed)
    return (rng.uniform(0, ti_max, n), rng.uniform(0, HALF_PI, n),
            rng.uniform(-math.pi, math.pi, n))


# ------------------------------------------------------------------------------------------
# independent NumPy/SciPy reference (docs/models.md §4, §8)
# ------------------------------------------------------------------------------------------
def fresnel_eq16_17(alpha, n_eff, k_eff):
    """RB08 Eqs. 16-17 written literally (complex arithmetic): (R_s, R_p) at sine alpha."""
    nt = complex(n_eff, k_eff)
    alpha = np.asarray(alpha, dtype=complex)
    c = np.sqrt(1 - alpha**2)
    t = np.sqrt(1 - alpha**2 / nt**2)
    r_s = np.abs((c - nt * t) / (c + nt * t)) ** 2
    r_p = np.abs((-nt * c + t) / (nt * c + t)) ** 2
    return r_s, r_p


def n_literal(a0, rho):
    """Eq. 6 as printed (docs/models.md §4.5)."""
    return 1.0 / (math.pi * np.log((1 - a0**2 + rho**2 + np.sqrt(
        rho**4 + 2 * a0**2 * rho**2 + 2 * rho**2 + (1 - a0**2) ** 2)) / (2 * rho**2)))


def vm_literal(zeta, zeta0, alpha, w_a, w_b, gamma, delta):
    """Eq. 13 as printed, with Sgn, recommended signs (docs/models.md §4.8)."""
    e0 = np.exp(-gamma * zeta0 * np.exp(-delta * zeta0**2))
    b = np.exp(-w_a * zeta * np.exp(-w_b * alpha**2))
    sg = np.sign(zeta)
    return 0.5 * (1 - e0) * (sg + 1) + b * (0.5 * (1 - sg) + 0.5 * e0 * (sg + 1))


def ref_terms(ti, ts, phi, p, zeta="angle", weight="geometric-mean", norm="literal",
              pol="unpolarized", retro_shadowing="width"):
    """(surface, bulk, retro, parts) of RB08 by docs/models.md §8 (``parts``: sigma_s, D, N, Vm...).

    ``retro_shadowing="amplitude"``: the retro V pair multiplies the retro strength instead of
    its width term (the model's option of that name).
    """
    a0, ci = np.sin(ti), np.cos(ti)
    s, cs = np.sin(ts), np.cos(ts)
    a, b = s * np.cos(phi), s * np.sin(phi)

    def refl(x):
        r_s, r_p = fresnel_eq16_17(x, p["n_eff"], p["k_eff"])
        return {"unpolarized": 0.5 * (r_s + r_p), "s": r_s, "p": r_p}[pol]

    r0, rs = refl(a0), refl(s)
    if weight == "geometric-mean":
        sig = np.sqrt(r0 * rs)
    elif weight == "product":
        sig = r0 * rs
    else:
        sig = 1 - (1 - r0) * (1 - rs)

    def v(chi, w, n):
        return special.gammaincc(1 + n, (1 + n) * chi**2 / w**2)

    h2 = 0.25 * (ci + cs) ** 2
    d = (a - a0) ** 2 + b**2 + h2 * v(a0, p["w"], p["n"]) * v(s, p["w"], p["n"]) * p["rho"] ** 2
    v_r = v(a0, p["w_r"], p["n_r"]) * v(s, p["w_r"], p["n_r"])
    amp = retro_shadowing == "amplitude"
    d_r = (a + a0) ** 2 + b**2 + h2 * (1.0 if amp else v_r) * p["rho_r"] ** 2
    if norm == "literal":
        n_s, n_r = n_literal(a0, p["rho"]), n_literal(a0, p["rho_r"])
    else:  # specular-width
        n_s = n_literal(a0, p["rho"] * ci * v(a0, p["w"], p["n"]))
        n_r = n_literal(a0, p["rho_r"] * ci * (1.0 if amp else v(a0, p["w_r"], p["n_r"])))
    if zeta == "angle":
        z, z0, al = np.arcsin(a), ti, a
    elif zeta == "cosine":
        z, z0, al = a, a0, a
    else:
        z, z0, al = ts - ti, ti, s
    vm = vm_literal(z, z0, al, p["w_a"], p["w_b"], p["gamma"], p["delta"])
    surf = sig * n_s * vm / d
    bulk = (1 - sig) * p["bulk"] / math.pi
    retro = (1 - sig) * p["retro"] * n_r * (v_r if amp else 1.0) / d_r
    return surf, bulk, retro, {"sigma": sig, "d": d, "d_r": d_r, "n_s": n_s, "n_r": n_r,
                               "vm": vm, "v_r": v_r}


# ------------------------------------------------------------------------------------------
# §4.5: N normalizes the basic lobe over the unit disk
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("a0", [0.0, 0.3, 0.7, 0.95])
@pytest.mark.parametrize("rho", [0.05, 0.2, 0.6])
def test_eq6_normalizes_basic_lobe(a0, rho):
    # ∫∫_disk N/((alpha - a0)^2 + beta^2 + rho^2): polar coordinates about the peak, the radial
    # integral in closed form, the azimuthal one by adaptive quadrature
    def radial(psi):
        c = math.cos(psi)
        rmax = -a0 * c + math.sqrt(1 - a0 * a0 * math.sin(psi) ** 2)
        return 0.5 * math.log1p(rmax * rmax / (rho * rho))

    disk, _ = integrate.quad(radial, 0.0, 2 * math.pi, epsabs=1e-13, epsrel=1e-13, limit=200)
    n = rbm.rb08_norm(1 - a0 * a0, a0 * a0, rho)
    assert n * disk == pytest.approx(1.0, abs=1e-8)
    assert n == pytest.approx(n_literal(a0, rho), rel=1e-13)  # stable form = printed form
    if a0 == 0.0:  # docs/models.md §4.5: 1/(pi ln((1 + rho^2)/rho^2))
        assert n == pytest.approx(1 / (math.pi * math.log((1 + rho**2) / rho**2)), rel=1e-14)


def test_norm_stable_for_wide_and_narrow_lobes():
    for rho in (1e-6, 1e-3, 10.0, 1e3):
        for a0 in (0.0, 0.5, 0.999):
            got = rbm.rb08_norm(1 - a0 * a0, a0 * a0, rho)
            # N = 1/(pi log(arg)), evaluated here in extended care with log1p of arg - 1
            ci2, r2 = 1 - a0 * a0, rho * rho
            arg_m1 = (ci2 - r2 + math.sqrt((ci2 + r2) ** 2 + 4 * a0 * a0 * r2)) / (2 * r2)
            if rho < 1:
                expect = 1 / (math.pi * math.log1p(arg_m1))
                assert got == pytest.approx(expect, rel=1e-12)
            assert math.isfinite(got) and got > 0
    assert rbm.rb08_norm(0.75, 0.25, 0.0) == 0.0  # rho -> 0: the log diverges


# ------------------------------------------------------------------------------------------
# §4.7: V = Q(1+n, (1+n) chi^2/w^2), the incomplete gamma inside the kernel
# ------------------------------------------------------------------------------------------
def test_v_identities():
    chi = np.linspace(0, 1, 101)
    for w in (0.2, 0.8, 1.5):
        for n in (0.0, 0.5, 4.0, 37.3):
            assert rb.shadowing.V(0.0, w, n) == 1.0  # V(0) = 1
            v = rb.shadowing.V(chi, w, n)
            assert np.all(np.diff(v) <= 0)  # decreasing in chi
        # Eq. 11 (to the rounding of the argument, x = chi^2/w^2 <= 25: a few ulp)
        np.testing.assert_allclose(rb.shadowing.V(chi, w, 0.0), np.exp(-chi**2 / w**2),
                                   rtol=1e-14)


def test_v_step_limit_for_large_n():
    # docs/models.md §4.7, computed: n = 500, w = 0.8 gives 1, 1, 1, 1, 0.494, 0.000
    got = rb.shadowing.V([0, 0.2, 0.4, 0.6, 0.8, 1.0], 0.8, 500)
    np.testing.assert_allclose(got, [1, 1, 1, 1, 0.494, 0.000], atol=5e-4)
    # V(w) -> 1/2: the median of a gamma variable is a - 1/3 + ..., so
    # V(w) = Q(a, a) = 1/2 - 1/(3 sqrt(2 pi a)) + O(1/a)
    prev = 1.0
    for n in (5, 50, 500, 5000, 50000):
        dev = abs(float(rb.shadowing.V(0.8, 0.8, n)) - 0.5)
        assert dev == pytest.approx(1 / (3 * math.sqrt(2 * math.pi * (1 + n))), rel=0.2)
        assert dev < prev
        prev = dev
    # step: far from w the values go to 1 and 0
    assert rb.shadowing.V(0.7, 0.8, 50000) == pytest.approx(1.0, abs=1e-12)
    assert rb.shadowing.V(0.9, 0.8, 50000) == pytest.approx(0.0, abs=1e-12)


def test_incomplete_gamma_against_scipy():
    rng = np.random.default_rng(7)
    avals = [1.0, 1.5, 2.0, 3.7, 5.0, 14.9, 15.0, 15.5, 30.0, 64.0, 65.0, 100.0, 250.3, 501.0,
             777.7, 1000.0]
    for a in avals:
        x = np.abs(np.concatenate([np.linspace(0, 3 * a + 40, 1500),
                                   a + math.sqrt(a) * rng.normal(0, 3, 1500),
                                   [1e-300, 1e-12, 1e-3, a - 1, a, a + 1]]))
        ref = special.gammaincc(a, x)
        got = rbs.gammaincc(a, x)
        ok = ref > 1e-30  # deeper in the tail the problem's own conditioning (|x - a| ulps)
        rtol = 1e-12 if a <= 500 else 2e-12  # dominates both implementations
        np.testing.assert_allclose(got[ok], ref[ok], rtol=rtol, atol=0)
        assert np.all(got[~ok] < 1e-29)
    assert rbs.gammaincc(3.0, np.inf) == 0.0
    with pytest.raises(ValueError, match="a must"):
        rbs.gammaincc(0.0, 1.0)
    with pytest.raises(ValueError, match="x must"):
        rbs.gammaincc(1.0, -1.0)


def test_integer_horner_path_against_scipy():
    x = np.linspace(0, 120, 3001)
    for n in range(rbs.INT_HORNER_MAX + 1):
        a = n + 1.0
        got = np.array([rbs.gammaincc_int(a, xx) for xx in x])
        np.testing.assert_allclose(got, special.gammaincc(a, x), rtol=5e-14)
        # deep tail (Q ~ 1e-280): the conditioning |x - a| ulp of the problem itself; beyond
        # x = 708 e^-x is subnormal (documented: Q < ~1e-290 loses digits, 0 beyond x = 745)
        assert rbs.gammaincc_int(a, 700.0) == pytest.approx(special.gammaincc(a, 700.0),
                                                             rel=1e-12)
        assert rbs.gammaincc_int(a, 746.0) == 0.0


@pytest.mark.parametrize("fn, ref, lo, hi, ulps", [
    (rbs.vexp, np.exp, -745.0, 709.0, 1),
    (rbs.vlog, np.log, 1e-300, 1e300, 1),
    (rbs.vlog1p, np.log1p, 0.0, 1e30, 2),
    (rbs.vasin, np.arcsin, -1.0, 1.0, 2),
])
def test_vectorizable_elementary_functions(fn, ref, lo, hi, ulps):
    rng = np.random.default_rng(3)
    if fn is rbs.vlog or fn is rbs.vlog1p:
        x = np.exp(rng.uniform(math.log(max(lo, 1e-300)), math.log(hi), 20000))
        x = np.concatenate([x, rng.uniform(0, 2, 5000)])
    else:
        x = np.concatenate([rng.uniform(lo, hi, 20000), rng.uniform(-1, 1, 5000) * min(hi, 1)])
    got = np.array([fn(v) for v in x])
    want = ref(x)
    nz = want != 0
    err = np.abs(got[nz] - want[nz]) / np.spacing(np.abs(want[nz]))
    assert err.max() <= ulps
    # special values
    assert rbs.vexp(-1000.0) == 0.0 and rbs.vexp(1000.0) == math.inf
    assert math.isnan(rbs.vexp(math.nan)) and rbs.vexp(0.0) == 1.0
    assert rbs.vlog(0.0) == -math.inf and math.isnan(rbs.vlog(-1.0))
    assert rbs.vlog(5e-324) == pytest.approx(math.log(5e-324), rel=1e-15)
    assert rbs.vlog1p(0.0) == 0.0 and rbs.vlog1p(1e-300) == 1e-300
    assert rbs.vlog1p(math.inf) == math.inf
    assert rbs.vasin(1.0) == pytest.approx(HALF_PI, rel=1e-16) and math.isnan(rbs.vasin(1.5))


# ------------------------------------------------------------------------------------------
# §4.8: Vm, piecewise identities and continuity
# ------------------------------------------------------------------------------------------
def test_vm_piecewise_identities_and_continuity():
    rng = np.random.default_rng(11)
    for _ in range(50):
        w_a, w_b, delta = rng.uniform(-3, 3, 3)
        gamma = rng.uniform(0, 3)
        zeta0 = rng.uniform(0, HALF_PI)
        z = rng.uniform(-HALF_PI, HALF_PI, 200)
        al = np.sin(z)
        got = rb.shadowing.Vm(z, zeta0, w_a, w_b, gamma, delta)
        e0 = math.exp(-gamma * zeta0 * math.exp(-delta * zeta0**2))
        b = np.exp(-w_a * z * np.exp(-w_b * al**2))
        expect = np.where(z < 0, b, 1 - e0 * (1 - b))  # docs/models.md §4.8 piecewise form
        np.testing.assert_allclose(got, expect, rtol=1e-14)
        np.testing.assert_allclose(got, vm_literal(z, zeta0, al, w_a, w_b, gamma, delta),
                                   rtol=1e-14)  # = Eq. 13 as printed
        assert 0 < e0 <= 1 and np.all(got > 0)
        # Vm(0) = 1 (Sgn 0 = 0) and continuity across zeta = 0
        assert rb.shadowing.Vm(0.0, zeta0, w_a, w_b, gamma, delta) == 1.0
        for eps in (1e-6, 1e-9, 1e-12):
            for side in (-eps, eps):
                v = rb.shadowing.Vm(side, zeta0, w_a, w_b, gamma, delta)
                assert v == pytest.approx(1.0, abs=10 * abs(w_a) * eps + 1e-15)
    # alpha given explicitly (the direction-cosine reading)
    assert rb.shadowing.Vm(0.3, 0.2, 1.0, 2.0, 0.5, 0.1, alpha=0.3) == pytest.approx(
        vm_literal(0.3, 0.2, 0.3, 1.0, 2.0, 0.5, 0.1), rel=1e-15)
    with pytest.raises(ValueError, match="zeta0"):
        rb.shadowing.Vm(0.1, math.nan, 1, 1, 1, 1)
    for kwargs, name in [((0.5, -1.0, 1.0), "w"), ((0.5, 0.8, -1.0), "n"),
                         ((math.inf, 0.8, 1.0), "chi")]:
        with pytest.raises(ValueError, match=name):
            rb.shadowing.V(*kwargs)


# ------------------------------------------------------------------------------------------
# §4.9: Eqs. 16-17 are the core Fresnel
# ------------------------------------------------------------------------------------------
def test_eq16_17_equal_core_fresnel():
    alpha = np.linspace(0, 1, 201)
    worst = 0.0
    for n_eff in (0.2, 0.7, 1.0, 1.33, 1.5, 2.4, 5.0):
        for k_eff in (0.0, 0.01, 0.5, 3.0, 10.0):
            with np.errstate(invalid="ignore"):  # 0/0 of the literal form at alpha = 1, n = 1
                r_s, r_p = fresnel_eq16_17(alpha, n_eff, k_eff)
            if n_eff == 1.0 and k_eff == 0.0:  # index matched: R = 0 (the limit)
                r_s, r_p = np.nan_to_num(r_s), np.nan_to_num(r_p)
            core = np.array([fresnel_sp(math.sqrt(1 - x * x), n_eff, k_eff) for x in alpha])
            worst = max(worst, np.abs(core[:, 0] - r_s).max(), np.abs(core[:, 1] - r_p).max())
            r0 = abs((complex(n_eff, k_eff) - 1) / (complex(n_eff, k_eff) + 1)) ** 2
            assert r_s[0] == pytest.approx(r0, abs=1e-15) and r_p[0] == pytest.approx(r0,
                                                                                      abs=1e-15)
    assert worst < 1e-14


# ------------------------------------------------------------------------------------------
# the kernel against the independent reference, every option
# ------------------------------------------------------------------------------------------
OPTION_SETS = [
    {},
    {"zeta": "cosine", "surface_weight": "product"},
    {"zeta": "zenith-difference", "surface_weight": "transmission", "polarization": "s"},
    {"normalization": "specular-width", "polarization": "p"},
    {"retro_shadowing": "amplitude"},
    {"retro_shadowing": "amplitude", "normalization": "specular-width", "zeta": "cosine"},
]


@pytest.mark.parametrize("opts", OPTION_SETS, ids=lambda o: ",".join(o.values()) or "defaults")
@pytest.mark.parametrize("params", [{}, FULL, dict(FULL, n=4.0, n_r=4.0, w_r=0.7)],
                         ids=["defaults", "full", "full-integer-n"])
def test_kernel_matches_reference(opts, params):
    m = rb.model("rb08", **opts, **params)
    ti, ts, ph = random_geometry(3000, seed=5)
    surf, bulk, retro, _ = ref_terms(ti, ts, ph, m.params, **{
        "zeta": m.options["zeta"], "weight": m.options["surface_weight"],
        "norm": m.options["normalization"], "pol": m.options["polarization"],
        "retro_shadowing": m.options["retro_shadowing"]})
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="surface"), surf, rtol=1e-11)
    # bulk and retro carry 1 - sigma_s, small where R -> 1 (s polarization near grazing);
    # there the literal Eqs. 16-17 of the reference, written with the sine alpha (cos = sqrt(1 -
    # alpha^2)), lose digits: hence the absolute tolerance
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="bulk"), bulk, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="retro"), retro, rtol=1e-11,
                               atol=1e-12)
    np.testing.assert_allclose(m.brdf(ti, ts, ph), surf + bulk + retro, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(m.bridf(ti, ts, ph), (surf + bulk + retro) * np.cos(ts),
                               rtol=1e-11, atol=1e-12)


def test_fast_and_general_kernels_agree():
    # integer n runs the vectorized kernel; forcing the general one (series/continued
    # fraction, per-chunk incidence cache) must give the same numbers
    ti, ts, ph = random_geometry(5000, seed=9)
    for params, retro_shadowing in itertools.product(
            ({}, dict(FULL, n=4.0, n_r=2.0), dict(FULL, n=0.0, n_r=16.0)), RETRO_SHADOWING):
        m = rb.model("rb08", retro_shadowing=retro_shadowing, **params)
        assert m.uses_fast_kernel
        fast = m.brdf(ti, ts, ph)
        general = m.with_general_kernel().brdf(ti, ts, ph)
        np.testing.assert_allclose(fast, general, rtol=1e-13)
        # scalar theta_i (incidence hoisted out of the loop) = the same numbers
        np.testing.assert_allclose(m.brdf(0.7, ts, ph), m.brdf(np.full(5000, 0.7), ts, ph),
                                   rtol=1e-15)
    assert not rb.model("rb08", n=4.5).uses_fast_kernel
    assert not rb.model("rb08", n_r=17.0).uses_fast_kernel


def minidiff_like_geometry(n_tr=91, n_ph=46, n_again=4000):
    """A Mini-Diff-like grid: 4 incidences x ``n_tr`` reflection zeniths (0 to 90 deg: 1 deg
    apart by default) x ``n_ph`` azimuths, in the order of the files (theta_i outermost), its
    first ``n_again`` samples repeated shuffled so that angles also recur out of order."""
    ti, tr, ph = np.meshgrid(deg([0.0, 20.0, 40.0, 60.0]), deg(np.linspace(0.0, 90.0, n_tr)),
                             np.linspace(-math.pi, math.pi, n_ph), indexing="ij")
    ti, tr, ph = ti.ravel(), tr.ravel(), ph.ravel()
    perm = np.random.default_rng(3).permutation(n_again)
    return (np.concatenate([ti, ti[perm]]), np.concatenate([tr, tr[perm]]),
            np.concatenate([ph, ph[perm]]))


@pytest.mark.parametrize("opts", OPTION_SETS + [{"normalization": "numeric"},
                                                {"normalization": "numeric",
                                                 "retro_shadowing": "amplitude"}],
                         ids=lambda o: ",".join(o.values()) or "defaults")
def test_tabulated_kernel_equals_general_kernel(opts, monkeypatch):
    # Real n (and the numeric N) run the tabulated kernel: V once per distinct angle through
    # a memo, then the vectorized loop. The reference is the general kernel, which computes V
    # per sample: the same numbers (bit for bit
    # on the data measured; 1e-13 allows for FMA contraction). Without the JIT (plain Python,
    # 77 s a case on the full grid) the same grid layout 10 deg x 45 deg apart (360 samples,
    # 180 of them again shuffled) and 300 random directions: the same comparison.
    used = []
    run = rbk._kernels.run_driver
    monkeypatch.setattr(rbk._kernels, "run_driver",
                        lambda drive, *args: (used.append(drive), run(drive, *args))[1])
    ti, ts, ph = minidiff_like_geometry(10, 9, 180) if NOJIT else minidiff_like_geometry()
    rti, rts, rph = random_geometry(300 if NOJIT else 3000, seed=11)
    for params in (FULL, dict(FULL, w_r=FULL["w"], n_r=FULL["n"]),
                   dict(FULL, w=0.05, n=49.7, w_r=1.9, n_r=0.3, rho=0.005),
                   dict(FULL, n=4.0, n_r=2.0)):
        m = rb.model("rb08", **opts, **params)
        ref = m.with_general_kernel()
        for term in (None, "surface", "retro"):
            used.clear()
            np.testing.assert_allclose(m.brdf(ti, ts, ph, term=term),
                                       ref.brdf(ti, ts, ph, term=term), rtol=1e-13, atol=0)
            assert used == [rbk._rb08_tab, rbk._rb08_general] or (
                m.uses_fast_kernel and opts.get("normalization") != "numeric")
        np.testing.assert_allclose(m.bridf(rti, rts, rph), ref.bridf(rti, rts, rph),
                                   rtol=1e-13, atol=0)
        np.testing.assert_allclose(m.brdf(0.3, ts, ph), ref.brdf(0.3, ts, ph), rtol=1e-13)
    # per-sample polarization still takes the general kernel
    used.clear()
    rb.model("rb08", **FULL).brdf(rti, rts, rph, polarization=rph)
    assert used == [rbk._rb08_general]


_PURE_PYTHON_RB08 = """
import json, numpy as np, roughbrdf as rb, numba
from roughbrdf.models import renhorn_boreman as rbm
assert numba.config.DISABLE_JIT
ti = np.repeat(np.radians([0.0, 20.0, 60.0]), 4)
tr = np.tile([0.0, 0.4, 1.2, 1.5707963267948966], 3)
ph = np.tile([0.0, 1.0, 3.141592653589793, -2.0], 3)
full = json.loads('FULL')
out = {}
for norm in ("literal", "numeric"):
    m = rb.model("rb08", normalization=norm, **full)
    out[norm] = [m.bridf(ti, tr, ph).tolist(), m.with_general_kernel().bridf(ti, tr, ph).tolist()]
out["I"] = rbm.lobe_integral(np.radians([0.0, 30.0, 89.9]), 0.02, 0.1, 40.0).tolist()
print(json.dumps(out))
"""


def test_pure_python_mode_agrees_real_n():
    # NUMBA_DISABLE_JIT=1 (pure Python, for debugging and coverage): the tabulated and general
    # kernels and the numeric N give the numbers of the compiled code
    code = _PURE_PYTHON_RB08.replace("FULL", json.dumps(FULL))
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    ti = np.repeat(deg([0.0, 20.0, 60.0]), 4)
    tr = np.tile([0.0, 0.4, 1.2, HALF_PI], 3)
    ph = np.tile([0.0, 1.0, math.pi, -2.0], 3)
    for norm in ("literal", "numeric"):
        m = rb.model("rb08", normalization=norm, **FULL)
        np.testing.assert_allclose(pure[norm][0], m.bridf(ti, tr, ph), rtol=1e-13)
        np.testing.assert_allclose(pure[norm][1], m.bridf(ti, tr, ph), rtol=1e-13)
    np.testing.assert_allclose(pure["I"], rbm.lobe_integral(deg([0.0, 30.0, 89.9]), 0.02, 0.1,
                                                            40.0), rtol=1e-13)


# ------------------------------------------------------------------------------------------
# §4.10 energy split: sigma_bulk/bulk = sigma_retro/retro = 1 - sigma_surface
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("weight", ["geometric-mean", "product", "transmission"])
@pytest.mark.parametrize("pol", ["unpolarized", "s", "p"])
def test_energy_split_identity(weight, pol):
    m = rb.model("rb08", surface_weight=weight, polarization=pol, **FULL)
    ti, ts, ph = random_geometry(2000, seed=2)
    ti = np.concatenate([ti, [0.0, 0.5, 0.5, 1.2, 0.0]])
    ts = np.concatenate([ts, [0.0, 0.5, 0.5, HALF_PI, HALF_PI]])
    ph = np.concatenate([ph, [0.0, 0.0, math.pi, 1.0, 2.0]])
    surf, bulk, retro = (m.brdf(ti, ts, ph, term=t) for t in ("surface", "bulk", "retro"))
    _, _, _, parts = ref_terms(ti, ts, ph, m.params, weight=weight, pol=pol)
    sigma_surface = surf * parts["d"] / (parts["n_s"] * parts["vm"])
    sigma_bulk = bulk * math.pi
    sigma_retro = retro * parts["d_r"] / parts["n_r"]
    # atol: where R -> 1 at grazing, 1 - sigma_surface is ~1e-16 and only round-off is left
    np.testing.assert_allclose(sigma_bulk / FULL["bulk"], 1 - sigma_surface, rtol=1e-11,
                               atol=1e-14)
    np.testing.assert_allclose(sigma_retro / FULL["retro"], 1 - sigma_surface, rtol=1e-11,
                               atol=1e-14)
    np.testing.assert_allclose(sigma_surface, parts["sigma"], rtol=1e-11)
    if weight == "geometric-mean":  # at the specular point sigma_s = R(theta_i)
        r_s, r_p = fresnel_eq16_17(math.sin(0.5), FULL["n_eff"], FULL["k_eff"])
        r = {"unpolarized": 0.5 * (r_s + r_p), "s": r_s, "p": r_p}[pol]
        assert sigma_surface[-4] == pytest.approx(float(r), rel=1e-12)


# ------------------------------------------------------------------------------------------
# §4.12 normalization table: ∫ BRDF cos(theta_s) dΩ of the surface lobe with sigma = 1
# ------------------------------------------------------------------------------------------
def unit_sigma(rho, normalization):
    # sigma_surface = 1: a perfect conductor (R = 1 - 4e-16 at every angle), no bulk or retro
    # term, Vm = 1 (w_a = 0); w = 0.9, n = 4 as in docs/models.md §4.12
    return rb.model("rb08", rho=rho, w=0.9, n=4, w_a=0.0, n_eff=1.0, k_eff=1e8, bulk=0.0,
                    retro=0.0, normalization=normalization)


TABLE_412 = {  # theta_i -> (rho 0.1 literal, rho 0.1 effective, rho 0.3 literal, 0.3 effective)
    0: (1.005, 1.005, 1.043, 1.043),
    30: (1.083, 1.008, 1.189, 1.053),
    60: (1.778, 0.999, 2.271, 0.989),
    75: (2.595, 0.998, 3.275, 0.978),
}


#: rb.albedo's grid for the §4.12 table: its default (73728 samples an incidence); without the
#: JIT (117 s on the default grid) 6144 samples, which give the default grid's albedos to 4e-6
#: on these lobes (measured), far inside the table's 3 decimals
GRID_412 = dict(n_psi=64, n_panels=12, order=8) if NOJIT else {}


def test_section_412_normalization_table():
    th = deg(sorted(TABLE_412))
    want = np.array([TABLE_412[k] for k in sorted(TABLE_412)])
    assert unit_sigma(0.1, "literal").brdf(0.3, 0.3, 0.0, term="bulk") == 0.0
    got = np.column_stack([
        rb.albedo(unit_sigma(0.1, "literal"), th, **GRID_412),
        rb.albedo(unit_sigma(0.1, "specular-width"), th, **GRID_412),
        rb.albedo(unit_sigma(0.3, "literal"), th, **GRID_412),
        rb.albedo(unit_sigma(0.3, "specular-width"), th, **GRID_412),
    ])
    np.testing.assert_allclose(got, want, atol=0.01)


#: rb.albedo's grid for the numeric N: 384 x 32 panels, its own error far below 2e-4; without the
#: JIT (90 s a case) 128 x 16 panels (6 times fewer samples), its error 4.5e-5 at most on these
#: lobes (measured against 384 x 32: rho = 0.05 at 85 deg), still 4 times inside 2e-4
GRID_NUMERIC = dict(n_psi=128, n_panels=16) if NOJIT else dict(n_psi=384, n_panels=32)


@pytest.mark.parametrize("rho", [0.05, 0.3, 1.0])
def test_numeric_normalization_integrates_to_sigma(rho):
    th = deg([0.0, 30.0, 60.0, 75.0, 85.0])
    got = rb.albedo(unit_sigma(rho, "numeric"), th, **GRID_NUMERIC)
    np.testing.assert_allclose(got, 1.0, atol=2e-4)


# lobe_integral as of commit 7d30e94, the implementation the 1-D radial reduction replaced: a
# 2-D Gauss-Legendre quadrature about the peak in polar coordinates (n_psi=12, n_u=24,
# order=12; ~1e-11 accurate on these cases against a 10x finer one), at theta_i = 0, 20, 45,
# 70, 85 deg. The new one must give the same numbers.
LOBE_INTEGRAL_2D = {
    (0.3, 0.9, 4.0): [8.171756882918835, 8.254631205234094, 9.54136418253562, 13.901866174583354,
                      16.35378455892606],
    (0.02, 0.6, 0.0): [24.60508092095523, 26.631299829366114, 33.306040174593484,
                       39.99146328403988, 41.90139082869345],
    (1.5, 1.2, 7.5): [1.5415821009970982, 1.5860317167125144, 1.8072215383458166,
                      2.5519912287872164, 3.7016499948370747],
    (1.0, 0.8, 500.0): [3.1381054538344464, 3.3487848485351166, 5.0908607686678895,
                        201.40937736756604, 374.0833755980192],
    (0.2, 0.7, 2.5): [10.535552220030995, 10.836792249481462, 15.696343840481413,
                      25.796964808543457, 29.194341369576627],
}


def test_lobe_integral_equals_previous_2d_quadrature():
    th = deg([0.0, 20.0, 45.0, 70.0, 85.0])
    for (rho, w, n), want in LOBE_INTEGRAL_2D.items():
        # 2e-10: the 2-D quadrature's own error on the n = 500 lobe at 70-85 deg
        np.testing.assert_allclose(rbm.lobe_integral(th, rho, w, n), want, rtol=5e-10)


def radial_integral_quad(ti, rho, w, n):
    """``I = 2 pi ∫_0^1 s ds/sqrt(((s - a0)^2 + c)((s + a0)^2 + c))`` by adaptive QUADPACK
    (``scipy.integrate.quad``), V by ``scipy.special.gammaincc``; breakpoints at the peak, at
    multiples of its width eps and where V turns over (only for eps >= 1e-6: QUADPACK loses
    narrower peaks)."""
    a0, ci = math.sin(ti), math.cos(ti)

    def v(s):
        return special.gammaincc(1 + n, (1 + n) * s * s / (w * w))

    v0 = v(a0)
    eps = ci * v0 * rho
    assert eps >= 1e-6

    def f(s):
        cs = math.sqrt(max(0.0, 1.0 - s * s))
        c = 0.25 * (ci + cs) ** 2 * v0 * v(s) * rho * rho
        return s / math.sqrt(((s - a0) ** 2 + c) * ((s + a0) ** 2 + c))

    pts = {a0 + k * eps * 10.0**j for j in range(8) for k in (-1, 1)}
    pts |= {w * math.sqrt(max(0.0, 1 + z / math.sqrt(1 + n))) for z in (-3, -1, 0, 1, 3, 6)}
    pts = sorted(x for x in pts if 0 < x < 1)
    val, _ = integrate.quad(f, 0, 1, points=pts, limit=2000, epsabs=0, epsrel=1e-13)
    return 2 * math.pi * val


@pytest.mark.parametrize("rho,w,n", [(0.005, 0.05, 50.0), (2.0, 0.05, 50.0), (0.1, 0.3, 30.5),
                                     (0.005, 2.0, 0.0), (1.0, 0.8, 500.0), (0.05, 1.5, 12.25),
                                     (0.5, 0.05, 0.3)])
def test_lobe_integral_against_adaptive_quadrature(rho, w, n):
    # the sharp turn-over of V (w = 0.05, n = 50), where the 2-D quadrature erred by 6e-3, and
    # a very narrow peak (rho = 0.005), against an independent adaptive quadrature
    for ti in deg([0.0, 1.0, 20.0, 40.0, 60.0, 80.0]):
        v0 = special.gammaincc(1 + n, (1 + n) * math.sin(ti) ** 2 / w**2)
        if math.cos(ti) * v0 * rho < 1e-6:
            continue
        got = rbm.lobe_integral(ti, rho, w, n)[0]
        assert got == pytest.approx(radial_integral_quad(ti, rho, w, n), rel=5e-11), ti


def test_lobe_integral_narrow_peak_log_law():
    # V(sin theta_i) ~1e-40..1e-300 (sharp shadowing beyond w): the width at the peak, eps,
    # is far below any other scale and I = C - 2 pi ln(eps) exactly (the peak's Lorentzian
    # integrates to a logarithm, and rho enters through eps only). No quadrature resolves
    # such a peak adaptively; the sinh map does. (The 2-D quadrature returned NaN or inf
    # below V ~1e-150.)
    for w, n, t in [(0.3, 30.5, 40.0), (0.05, 0.3, 40.0), (0.8, 500.0, 80.0), (0.1, 40.0, 20.0)]:
        i1, i2, i3 = (rbm.lobe_integral(deg(t), rho, w, n)[0] for rho in (0.01, 0.1, 1.0))
        assert i1 - i2 == pytest.approx(2 * math.pi * math.log(10), rel=1e-11)
        assert i2 - i3 == pytest.approx(2 * math.pi * math.log(10), rel=1e-11)
    # V(sin 60 deg) = 2.4e-319 is subnormal (16 significant bits, eps fewer): the log law then
    # holds only to the rounding of eps, ~1e-3, but the integral stays finite and ordered
    i1, i2, i3 = (rbm.lobe_integral(deg(60.0), rho, 0.1779, 36.26)[0] for rho in (0.01, 0.1, 1))
    assert i1 - i2 == pytest.approx(2 * math.pi * math.log(10), rel=3e-3)
    assert i2 - i3 == pytest.approx(2 * math.pi * math.log(10), rel=3e-3)


def test_lobe_integral_finite_over_the_bounds():
    # random lobes over the fit bounds, incidences to 89.99 deg: finite and positive, or inf
    # where the width at the peak eps = cos(theta_i) V(sin theta_i) rho underflows to 0 (the
    # kernel's lobe is then inf at its peak too); no NaN, no overflow or invalid operation.
    # Without the JIT the first 60 of the 300 lobes (72 s for 300 in plain Python).
    rng = np.random.default_rng(5)
    th = deg(np.concatenate([[0.0, 1e-6, 20.0, 40.0, 60.0, 85.0, 89.99],
                             rng.uniform(0.0, 89.99, 13)]))
    with np.errstate(over="raise", invalid="raise", divide="raise"):
        for _ in range(60 if NOJIT else 300):
            rho, w = np.exp(rng.uniform(np.log([0.005, 0.05]), np.log([2.0, 2.0])))
            n = float(rng.choice([0.0, rng.uniform(0.0, 50.0), 50.0]))
            i = rbm.lobe_integral(th, rho, w, n)
            eps = np.cos(th) * rb.shadowing.V(np.sin(th), w, n) * rho
            assert np.all(np.where(eps > 0, np.isfinite(i) & (i > 0), i == math.inf))


def test_numeric_normalization_follows_changed_incidences():
    # the distinct incidences of a theta_i array are remembered between evaluations (a fit
    # evaluates one array thousands of times): an array changed in place must not reuse them
    m = rb.model("rb08", normalization="numeric", **FULL)
    g = m.prepare(np.repeat(deg([0.0, 20.0, 40.0]), 3), np.full(9, 0.3), np.full(9, 0.5))
    first = m.evaluate_prepared(g)
    g.theta_i[:] = np.repeat(deg([10.0, 30.0, 50.0]), 3)
    np.testing.assert_array_equal(m.evaluate_prepared(g),
                                  m.brdf(np.repeat(deg([10.0, 30.0, 50.0]), 3), 0.3, 0.5))
    assert not np.array_equal(first, m.evaluate_prepared(g))


def test_numeric_table_path_matches_exact():
    m = rb.model("rb08", normalization="numeric", rho=0.2, retro=0.1, rho_r=0.3, n_r=2)
    ti = np.linspace(0, deg(89.9), 600)  # > 256 distinct incidences: the interpolated table
    ts, ph = np.full(600, 0.4), np.full(600, 2.0)
    table = m.brdf(ti, ts, ph)
    exact = np.array([m.brdf(t, 0.4, 2.0) for t in ti[::37]])  # one incidence: exact
    np.testing.assert_allclose(table[::37], exact, rtol=5e-7)


# ------------------------------------------------------------------------------------------
# Hypothesis: non-negativity and phi -> -phi symmetry over parameters and options
# ------------------------------------------------------------------------------------------
def _param_strategy():
    specs = {p.name: p for p in rb.model("rb08").parameters}
    return st.fixed_dictionaries({
        nm: st.floats(max(specs[nm].bounds[0], 1e-3) if specs[nm].domain[0] == 0.0
                      and not specs[nm].domain[1] else specs[nm].bounds[0],
                      specs[nm].bounds[1], allow_nan=False)
        for nm in P_NAMES})


OPTIONS = st.fixed_dictionaries({
    "zeta": st.sampled_from(["angle", "cosine", "zenith-difference"]),
    "surface_weight": st.sampled_from(["geometric-mean", "product", "transmission"]),
    "normalization": st.sampled_from(["literal", "specular-width"]),
    "polarization": st.sampled_from(["unpolarized", "s", "p"]),
    "retro_shadowing": st.sampled_from(list(RETRO_SHADOWING)),
})


@settings(max_examples=60, deadline=None)
@given(params=_param_strategy(), opts=OPTIONS, seed=st.integers(0, 2**31),
       integer_n=st.booleans())
def test_hypothesis_non_negative_and_phi_symmetric(params, opts, seed, integer_n):
    if integer_n:  # exercise the vectorized kernel as well as the general one
        params = dict(params, n=float(round(params["n"] % 17)),
                      n_r=float(round(params["n_r"] % 17)))
    m = rb.model("rb08", **params, **opts)
    ti, ts, ph = random_geometry(64, seed=seed % 1000)
    ti[:4] = [0.0, 1.5, 0.7, np.nextafter(HALF_PI, 0)]
    ts[:4] = [0.0, 1.5, 0.7, HALF_PI]
    f = m.brdf(ti, ts, ph)
    assert not np.isnan(f).any()
    assert (f >= 0).all()
    np.testing.assert_allclose(m.brdf(ti, ts, -ph), f, rtol=1e-12, atol=0)
    for t in ("surface", "bulk", "retro"):
        assert (m.brdf(ti, ts, ph, term=t) >= 0).all()


# ------------------------------------------------------------------------------------------
# retro_shadowing: where the speculative retro pair (w_r, n_r) acts (docs/models.md §4.10-4.11)
# ------------------------------------------------------------------------------------------
def test_retro_shadowing_option_default_unchanged_and_validated():
    m = rb.model("rb08", **FULL)
    assert m.options["retro_shadowing"] == "width"
    ti, ts, ph = random_geometry(400, seed=11)
    explicit = rb.model("rb08", retro_shadowing="width", **FULL)
    np.testing.assert_array_equal(explicit.brdf(ti, ts, ph), m.brdf(ti, ts, ph))
    amp = rb.model("rb08", retro_shadowing="Amplitude", **FULL)
    assert amp.options["retro_shadowing"] == "amplitude"
    assert rb.model("rb08", retro_shadowing="acceptance").options["retro_shadowing"] == (
        "amplitude")
    assert rb.model(amp.to_dict()).options["retro_shadowing"] == "amplitude"
    # only the retro term changes
    for t in ("surface", "bulk"):
        np.testing.assert_array_equal(amp.brdf(ti, ts, ph, term=t), m.brdf(ti, ts, ph, term=t))
    assert not np.allclose(amp.brdf(ti, ts, ph, term="retro"), m.brdf(ti, ts, ph, term="retro"))
    with pytest.raises(ValueError, match="retro_shadowing"):
        rb.model("rb08", retro_shadowing="both")


def _amplitude_retro_numpy(ti, ts, ph, p):
    """The amplitude reading written out in NumPy (independent of ref_terms and the kernel):
    (1 - sqrt(R(sin ti) R(sin ts))) retro N(sin ti, rho_r) V(sin ti) V(sin ts)
    / [(alpha + alpha0)^2 + beta^2 + (cos ti + cos ts)^2 rho_r^2 / 4]."""
    nt = complex(p["n_eff"], p["k_eff"])

    def refl(th):  # unpolarized Fresnel reflectance at the angle th (angle form)
        c = np.cos(th).astype(complex)
        t = np.sqrt(1 - np.sin(th).astype(complex) ** 2 / nt**2)
        return 0.5 * (np.abs((c - nt * t) / (c + nt * t)) ** 2
                      + np.abs((nt * c - t) / (nt * c + t)) ** 2)

    def v(chi):
        return special.gammaincc(1 + p["n_r"], (1 + p["n_r"]) * chi**2 / p["w_r"] ** 2)

    a0 = np.sin(ti)
    al, be = np.sin(ts) * np.cos(ph), np.sin(ts) * np.sin(ph)
    den = (al + a0) ** 2 + be**2 + 0.25 * (np.cos(ti) + np.cos(ts)) ** 2 * p["rho_r"] ** 2
    return ((1 - np.sqrt(refl(ti) * refl(ts))) * p["retro"] * n_literal(a0, p["rho_r"])
            * v(a0) * v(np.sin(ts)) / den)


@pytest.mark.parametrize("params", [FULL, dict(FULL, n=4.0, n_r=2.0), dict(FULL, w_a=0.0,
                                                                             w_r=0.7, n_r=3.5)],
                         ids=["general", "fast", "fast-lean"])
def test_retro_amplitude_identity_against_numpy(params):
    m = rb.model("rb08", retro_shadowing="amplitude", **params)
    # retro peaks, near them, out of the plane, forward, normal incidence, grazing exit
    ti = deg(np.array([15.0, 30.0, 60.0, 30.0, 30.0, 45.0, 0.0, 70.0, 50.0]))
    ts = deg(np.array([15.0, 30.0, 60.0, 31.0, 30.0, 20.0, 10.0, 89.0, 90.0]))
    ph = np.array([math.pi, math.pi, math.pi, math.pi, 3.0, 0.0, 1.0, -2.5, 2.0])
    want = _amplitude_retro_numpy(ti, ts, ph, m.params)
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="retro"), want, rtol=1e-11, atol=1e-15)
    # at the retro peak: BRDF cos = (1 - R(theta_i)) retro N V(sin theta_i)^2 / (cos ti rho_r^2)
    p = m.params
    r_s, r_p = fresnel_eq16_17(np.sin(ti[:3]), p["n_eff"], p["k_eff"])
    v0 = special.gammaincc(1 + p["n_r"], (1 + p["n_r"]) * np.sin(ti[:3]) ** 2 / p["w_r"] ** 2)
    peak = ((1 - 0.5 * (r_s + r_p)) * p["retro"] * n_literal(np.sin(ti[:3]), p["rho_r"])
            * v0**2 / (np.cos(ti[:3]) * p["rho_r"] ** 2))
    np.testing.assert_allclose(m.bridf(ti[:3], ti[:3], math.pi, term="retro"), peak,
                               rtol=1e-10)
    # the pair is exactly the factor between the two readings, given the same width term
    wid = rb.model("rb08", **dict(params, w_r=1e9, n_r=0.0))  # V = 1 to 1e-18
    v_pair = (special.gammaincc(1 + p["n_r"], (1 + p["n_r"]) * np.sin(ti) ** 2 / p["w_r"] ** 2)
              * special.gammaincc(1 + p["n_r"], (1 + p["n_r"]) * np.sin(ts) ** 2
                                  / p["w_r"] ** 2))
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="retro"),
                               v_pair * wid.brdf(ti, ts, ph, term="retro"), rtol=1e-11)


def test_retro_amplitude_numeric_normalization_uses_unshadowed_lobe():
    # numeric N of the amplitude retro lobe: 1/∫∫_disk dalpha dbeta / D with no V in D
    p = dict(FULL, n_eff=1.0, k_eff=0.0, rho_r=0.3)  # R = 0: 1 - sigma_s = 1
    m = rb.model("rb08", retro_shadowing="amplitude", normalization="numeric", **p)
    ti = 0.5
    a0, ci = math.sin(ti), math.cos(ti)

    def inv_d(be, al):
        cs = math.sqrt(max(0.0, 1.0 - al * al - be * be))
        return 1.0 / ((al + a0) ** 2 + be**2 + 0.25 * (ci + cs) ** 2 * p["rho_r"] ** 2)

    integral, _ = integrate.dblquad(inv_d, -1.0, 1.0, lambda al: -math.sqrt(1 - al * al),
                                    lambda al: math.sqrt(1 - al * al), epsabs=1e-11,
                                    epsrel=1e-11)
    ts, ph = np.array([0.5, 0.3, 1.0]), np.array([math.pi, 2.0, 0.3])
    lit = rb.model("rb08", retro_shadowing="amplitude", **p)  # literal N, same shape
    n_lit = n_literal(a0, p["rho_r"])
    np.testing.assert_allclose(m.brdf(ti, ts, ph, term="retro"),
                               lit.brdf(ti, ts, ph, term="retro") / (n_lit * integral),
                               rtol=1e-8)
    # specular-width: N(alpha0, rho_r cos theta_i), the amplitude lobe's width at its peak
    sw = rb.model("rb08", retro_shadowing="amplitude", normalization="specular-width", **p)
    np.testing.assert_allclose(sw.brdf(ti, ts, ph, term="retro"),
                               lit.brdf(ti, ts, ph, term="retro")
                               * n_literal(a0, p["rho_r"] * ci) / n_lit, rtol=1e-12)


def test_retro_peak_versus_incidence_width_rises_amplitude_can_fall():
    # the reason for the option: with the width reading the retro peak BRDF cos grows with
    # incidence (1/(cos ti V(sin ti)^2)), with the amplitude reading V(sin ti)^2 cuts it off
    # like the measured CEA gray tape (72.5, 42.5, 1.13 at 15, 30, 60 deg)
    th = deg(np.array([15.0, 30.0, 60.0]))
    p = dict(rho_r=0.02, w_r=0.64, n_r=2.5, n_eff=1.5, k_eff=0.0, retro=0.8)
    width = rb.model("rb08", **p).bridf(th, th, math.pi, term="retro")
    amp = rb.model("rb08", retro_shadowing="amplitude", **p).bridf(th, th, math.pi,
                                                                   term="retro")
    assert np.all(np.diff(width) > 0)
    assert np.all(np.diff(amp) < 0) and amp[0] / amp[2] > 30


# ------------------------------------------------------------------------------------------
# reciprocity: the model is not reciprocal (§4.13), and says so
# ------------------------------------------------------------------------------------------
def test_not_reciprocal():
    m = rb.model("rb08")
    assert m.reciprocal is False
    # N(alpha0, rho) depends on the incidence only: swapping theta_i and theta_s changes the
    # value even in the plane of incidence, with Vm = 1 (w_a = 0) and sigma symmetric (q = 1/2)
    err = rb.reciprocity_error(m, deg([10.0, 20.0, 60.0]), deg([60.0, 70.0, 10.0]), 0.0)
    assert np.all(err > 0.02)  # the (symmetric) bulk term dominates at the defaults
    # the denominator and sigma_s are symmetric: with Vm = 1 the surface ratio is the ratio of
    # the N's; Vm (w_a != 0) distinguishes incidence from scattering on top of that
    ti, ts = deg(25.0), deg(55.0)
    n = rbm.rb08_norm
    ratio = n(math.cos(ti) ** 2, math.sin(ti) ** 2, 0.3) / n(math.cos(ts) ** 2,
                                                            math.sin(ts) ** 2, 0.3)
    m2 = rb.model("rb08", w_a=0.5, gamma=1.0)
    for model, vm_on in ((m, False), (m2, True)):
        a = model.brdf(ti, ts, 0.3, term="surface")
        b = model.brdf(ts, ti, 0.3, term="surface")
        if vm_on:
            assert abs(a / b / ratio - 1) > 0.05
        else:
            assert a / b == pytest.approx(ratio, rel=1e-12)


# ------------------------------------------------------------------------------------------
# parameters, options, terms, polarization, broadcasting, invalid input
# ------------------------------------------------------------------------------------------
def test_registry_parameters_and_docs():
    for name in ("renhorn-boreman-2008", "rb08", "Renhorn-Boreman", "RB08"):
        assert isinstance(rb.model(name), rbm.RenhornBoreman2008)
    m = rb.model("rb08")
    assert m.param_names == P_NAMES
    assert m.short == "rb08" and m.TERMS == ("surface", "bulk", "retro")
    for p in m.parameters:
        assert p.unit and p.description and p.bounds[0] < p.bounds[1]
        assert p.bounds[0] <= p.value <= p.bounds[1]
    doc = rbm.RenhornBoreman2008.__doc__
    for word in ("Certain", "our reading", "Not reciprocal", "12892", "pi/2"):
        assert word.lower() in doc.lower(), word
    assert m.options == {"zeta": "angle", "surface_weight": "geometric-mean",
                         "normalization": "literal", "polarization": "unpolarized",
                         "retro_shadowing": "width"}
    assert rb.model(m.to_dict()).brdf(0.3, 0.4, 0.5) == m.brdf(0.3, 0.4, 0.5)
    # option spellings: underscores, case
    m2 = rb.model("rb08", zeta="Zenith_Difference", normalization="SPECULAR_WIDTH")
    assert m2.options["zeta"] == "zenith-difference"
    assert m2.options["normalization"] == "specular-width"


def test_default_surface_is_matte_paint_like():
    m = rb.model("rb08")
    # mostly diffuse: directional-hemispherical reflectance ~0.8, a weak gloss lobe
    alb = rb.albedo(m, deg([0.0, 45.0]))
    assert np.all((alb > 0.7) & (alb < 1.0))
    spec = m.brdf(deg(45), deg(45), 0.0)
    diffuse = m.brdf(deg(45), deg(10), math.pi / 2)
    assert 1.0 < spec / diffuse < 5.0


@pytest.mark.parametrize("name, bad", [
    ("rho", 0.0), ("rho", -0.1), ("w", 0.0), ("w", -1.0), ("n", -0.5), ("bulk", -0.1),
    ("retro", -1e-3), ("rho_r", 0.0), ("w_r", -0.2), ("n_r", -1.0), ("gamma", -0.5),
    ("n_eff", 0.0), ("k_eff", -0.1), ("rho", math.nan), ("w_a", math.inf),
])
def test_bad_parameter_raises_naming_it(name, bad):
    with pytest.raises(ValueError, match=repr(name)):
        rb.model("rb08", **{name: bad})
    with pytest.raises(ValueError, match=repr(name)):
        rb.model("rb08").with_values([name], [bad])


@pytest.mark.parametrize("option, bad", [("zeta", "sine"), ("surface_weight", "mean"),
                                         ("normalization", "exact"), ("polarization", "x"),
                                         ("retro_shadowing", "strength")])
def test_bad_option_raises_naming_it(option, bad):
    with pytest.raises(ValueError, match=rf"'{option}'.*{bad}|{bad}.*'{option}'"):
        rb.model("rb08", **{option: bad})


def test_unknown_keyword_and_term():
    with pytest.raises(ValueError, match="sigma"):
        rb.model("rb08", sigma=1.0)
    m = rb.model("rb08")
    with pytest.raises(ValueError, match="specular"):
        m.brdf(0.3, 0.3, 0.0, term="specular")


def test_terms_sum_and_sum_model_routing():
    m = rb.model("rb08", **FULL)
    ti, ts, ph = random_geometry(500, seed=4)
    parts = [m.brdf(ti, ts, ph, term=t) for t in m.TERMS]
    np.testing.assert_allclose(sum(parts), m.brdf(ti, ts, ph), rtol=1e-14)
    np.testing.assert_allclose(sum(m.bridf(ti, ts, ph, term=t) for t in m.TERMS),
                               m.bridf(ti, ts, ph), rtol=1e-14)
    s = m + rb.model("lambertian", rho=0.2)
    np.testing.assert_allclose(s.brdf(ti, ts, ph, term="retro"), parts[2], rtol=1e-15)
    np.testing.assert_allclose(s.brdf(ti, ts, ph), m.brdf(ti, ts, ph) + 0.2 / math.pi,
                               rtol=1e-14)
    # zero strengths give exactly zero terms
    z = rb.model("rb08", bulk=0.0, retro=0.0)
    assert z.brdf(0.4, 0.4, math.pi, term="retro") == 0.0
    assert z.brdf(0.4, 0.1, 1.0, term="bulk") == 0.0


def test_polarization_option_and_per_call_argument():
    ti, ts, ph = random_geometry(300, seed=8)
    base = rb.model("rb08", **FULL)
    s_opt = rb.model("rb08", polarization="s", **FULL)
    p_opt = rb.model("rb08", polarization="p", **FULL)
    np.testing.assert_allclose(base.brdf(ti, ts, ph, polarization="s"), s_opt.brdf(ti, ts, ph),
                               rtol=1e-15)
    np.testing.assert_allclose(base.brdf(ti, ts, ph, polarization=HALF_PI),
                               s_opt.brdf(ti, ts, ph), rtol=1e-15)
    np.testing.assert_allclose(s_opt.brdf(ti, ts, ph, polarization=0.0), p_opt.brdf(ti, ts, ph),
                               rtol=1e-15)
    np.testing.assert_allclose(p_opt.brdf(ti, ts, ph, polarization=None), p_opt.brdf(ti, ts, ph),
                               rtol=0)
    # one angle per sample; NaN entries use the option
    gam = np.where(np.arange(300) % 3 == 0, math.nan, np.where(np.arange(300) % 3 == 1,
                                                               HALF_PI, 0.0))
    mixed = p_opt.brdf(ti, ts, ph, polarization=gam)
    want = np.where(np.arange(300) % 3 == 1, s_opt.brdf(ti, ts, ph), p_opt.brdf(ti, ts, ph))
    np.testing.assert_allclose(mixed, want, rtol=1e-15)
    # a general angle: R = R_s sin^2 g + R_p cos^2 g in both Fresnel factors
    g = 0.6
    r = [fresnel_eq16_17(x, FULL["n_eff"], FULL["k_eff"]) for x in (math.sin(0.5),
                                                                     math.sin(0.9))]
    r0, rs = ((a * math.sin(g) ** 2 + b * math.cos(g) ** 2) for a, b in r)
    bulk = base.brdf(0.5, 0.9, 1.0, polarization=g, term="bulk")
    assert bulk == pytest.approx((1 - math.sqrt(r0 * rs)) * FULL["bulk"] / math.pi, rel=1e-12)


def test_n_dimensional_broadcasting():
    for params in ({}, dict(FULL)):
        m = rb.model("rb08", **params)
        rng = np.random.default_rng(1)
        ti = rng.uniform(0, 1.5, (3, 1, 1, 2))
        ts = rng.uniform(0, HALF_PI, (1, 4, 1, 1))
        ph = rng.uniform(-3, 3, (5, 1))
        got = m.brdf(ti, ts, ph)
        assert got.shape == (3, 4, 5, 2)
        a, b, c = np.broadcast_arrays(ti, ts, ph)
        loop = np.array([m.brdf(x, y, z) for x, y, z in zip(a.ravel(), b.ravel(), c.ravel(),
                                                            strict=True)])
        np.testing.assert_allclose(got.ravel(), loop, rtol=1e-14)
        for t in m.TERMS:
            assert m.brdf(ti, ts, ph, term=t).shape == (3, 4, 5, 2)
        assert isinstance(m.brdf(0.1, 0.2, 0.3), float)
        assert m.brdf(np.zeros((0, 3)), 0.2, 0.0).shape == (0, 3)


@pytest.mark.parametrize("which", ["theta_i", "theta_r", "phi"])
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nan_and_inf_angles_raise(which, bad):
    args = {"theta_i": np.array([0.2, 0.3]), "theta_r": 0.4, "phi": 0.1}
    args[which] = np.array([0.2, bad])
    with pytest.raises(ValueError, match=which):
        rb.model("rb08").brdf(**args)


def test_grazing_incidence_rejected():
    m = rb.model("rb08")
    assert m.grazing_incidence is False
    with pytest.raises(ValueError, match="theta_i"):
        m.brdf(HALF_PI, 0.3, 0.0)
    # just below grazing: finite everywhere, the lobes very narrow but finite
    ti = np.nextafter(HALF_PI, 0.0)
    f = m.brdf(ti, np.array([ti, ti, 1.0, HALF_PI]), np.array([0.0, math.pi, 0.5, 0.0]))
    assert np.all(np.isfinite(f)) and np.all(f > 0)


def test_special_points_finite_all_options():
    ti = np.array([0.0, 0.0, 0.5, 0.5, 0.5, 1.2, 1.2, 1.5, 1e-12, 0.5])
    ts = np.array([0.0, HALF_PI, 0.5, 0.5, HALF_PI, 1.2, 1.2, 1.5, 1e-12, 0.0])
    ph = np.array([0.0, 1.0, 0.0, math.pi, 0.3, 0.0, -math.pi, 0.0, HALF_PI, 2.0])
    for opts in OPTION_SETS + [{"normalization": "numeric"},
                               {"normalization": "numeric", "retro_shadowing": "amplitude"}]:
        for params in ({}, FULL):
            m = rb.model("rb08", **opts, **params)
            for f in (m.brdf(ti, ts, ph), m.bridf(ti, ts, ph)):
                assert np.all(np.isfinite(f)) and np.all(f >= 0), (opts, params, f)
            assert m.bridf(0.4, HALF_PI, 0.2) == 0.0


def test_vanishing_width_gives_inf_not_nan():
    # extremely sharp shadowing: V(sin theta_i) underflows to 0, the lobe's width vanishes and
    # its peak is the limit +inf (documented); every other direction stays finite
    m = rb.model("rb08", w=0.3, n=500, w_r=0.3, n_r=500)
    assert float(rb.shadowing.V(math.sin(1.2), 0.3, 500)) == 0.0
    f = m.brdf(1.2, np.array([1.2, 1.2, 1.1]), np.array([0.0, math.pi, 0.0]))
    assert f[0] == math.inf and np.isfinite(f[2])
    assert f[1] > 1e20  # the retro peak: phi = pi is not exact in floating point (sin pi != 0)
    assert m.bridf(1.2, 1.2, 0.0) == math.inf


# ------------------------------------------------------------------------------------------
# real data (../shared/data; skipped without it): the default search on a Mini-Diff paint
# ------------------------------------------------------------------------------------------
#: the fit with the bulk and retro terms switched off: bulk = retro = 0, fixed, and the retro
#: lobe's width and shadowing pair, which then do nothing
BULK_RETRO_OFF = ("bulk", "retro", "rho_r", "w_r", "n_r")


@pytest.mark.jit_heavy(reason="two whole 14-parameter fits of a measured paint: over 5 min in "
                       "plain Python")
@pytest.mark.parametrize("name,normalization", [("C2_Black", "literal"),
                                                ("C2_Black", "numeric"),
                                                ("C12_OliveDrab", "literal")])
def test_default_fit_reaches_the_bulk_retro_off_fit(shared_data, name, normalization):
    # The model with bulk = retro = 0 is a special case of the full one, so the default
    # multistart of the full model must do at least as well as a fit of that special case.
    # Measured (benchmarks/bench_fit.py, channel 465 nm): chi2 1512 vs 2069 (C2_Black,
    # literal N), 1468 vs 1998 (numeric N), 283 vs 564 (C12_OliveDrab); the fit of the 14
    # parameters takes ~1-2 s here (the numeric-N one took 40-77 s before 2026-12).
    meas = rb.read(shared_data / "minidiff" / f"{name}.astm")
    full = rb.fit(rb.model("rb08", normalization=normalization), meas, channel=0,
                  progress=False).channels[0]
    off = rb.fit(rb.model("rb08", normalization=normalization, bulk=0.0, retro=0.0), meas,
                 channel=0, fix=BULK_RETRO_OFF, progress=False).channels[0]
    assert off.params["bulk"] == off.params["retro"] == 0.0
    assert full.chi2 <= off.chi2, (full.chi2, off.chi2)
    assert math.isfinite(full.chi2) and full.n_points == off.n_points

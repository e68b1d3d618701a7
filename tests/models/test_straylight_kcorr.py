"""The K-correlation (ABC PSD) Rayleigh–Rice model (``roughbrdf.models.kcorr``).

Where the expected numbers come from:

* NIST SCATMECH ``Microroughness_BRDF_Model`` + ``ABC_PSD_Function``, built from source
  (``tests/data/scatmech/README_microroughness_abc.md``): 300 geometries x (s, p, unpolarized)
  and 150 full Mueller matrices in two bases;
* identities of the model's definition ``(16 pi^2/lambda^4) cos ti cos tr Q S_2(|beta -
  beta_0|/lambda)``: shift invariance of the PSD part, the lambda^-4 law, Q at the specular
  direction = the Fresnel reflectance (``rb.fresnel.reflectance``, an independent
  real-arithmetic implementation), reciprocity;
* the PSD's moments by ``scipy.integrate.quad`` (independent of the closed forms);
* the TIS quadrature against ``rb.albedo`` (an independent quadrature in angles) and against
  the small-roughness closed form (Davies; Bennett & Porteus).
"""

from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis_profiles import jit_disabled
from scipy import integrate, special

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.models import kcorr  # registers "k-correlation"

#: NUMBA_DISABLE_JIT=1 (make test-nojit): the kernels run as plain Python, 100 to 1000 times
#: slower; the heaviest test below runs on fewer cases there
NOJIT = jit_disabled(os.environ)

DATA = Path(__file__).resolve().parents[1] / "data" / "scatmech"
LAM = 0.6328
#: the SCATMECH cases (README_microroughness_abc.md)
CASES = {"si": (3.88, 0.019), "al": (1.2, 7.26)}
PSD = {"A": 2e-4, "B": 3.0, "C": 3.3}


def _rows(name: str) -> list[dict[str, str]]:
    with open(DATA / name, encoding="utf-8") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def _angles(rows: list[dict[str, str]]) -> tuple[np.ndarray, ...]:
    return tuple(np.radians([float(r[c]) for r in rows])
                 for c in ("theta_i_deg", "theta_r_deg", "phi_deg"))


def _model(**kw) -> rb.models.Model:
    base = {"A": 1e-4, "B": 4.0, "C": 3.0, "n": 1.5, "k": 0.0, "wavelength": LAM}
    return rb.model("k-correlation", **{**base, **kw})


# ------------------------------------------------------------------------------------------
# SCATMECH agreement
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("case", sorted(CASES))
def test_equals_scatmech_s_p_unpolarized(case):
    rows = [r for r in _rows("microroughness_abc.csv") if r["case"] == case]
    assert len(rows) == 150
    ti, tr, ph = _angles(rows)
    assert (np.sin(tr) * np.sin(ph) != 0).sum() > 50  # out of the plane of incidence
    n, k = CASES[case]
    m = rb.model("kcorr", **PSD, n=n, k=k, wavelength=LAM)
    for col, pol in (("brdf_s", "s"), ("brdf_p", "p"), ("brdf_unpolarized", None)):
        ref = np.array([float(r[col]) for r in rows])
        np.testing.assert_allclose(m.brdf(ti, tr, ph, polarization=pol), ref, rtol=1e-6,
                                   atol=0, err_msg=col)


@pytest.mark.parametrize("basis", ["psps", "xyxy"])
def test_mueller_equals_scatmech(basis):
    rows = [r for r in _rows("microroughness_abc_mueller.csv") if r["basis"] == basis]
    ti, tr, ph = _angles(rows)
    ref = np.array([[float(r[f"m{i}{j}"]) for i in range(4) for j in range(4)]
                    for r in rows]).reshape(-1, 4, 4)
    m = rb.model("abc", **PSD, n=CASES["si"][0], k=CASES["si"][1], wavelength=LAM)
    got = m.mueller(ti, tr, ph, basis=basis)
    err = np.abs(got - ref).max(axis=(1, 2)) / ref[:, 0, 0]
    assert err.max() < 1e-6
    # m00 is the scalar unpolarized BRDF; s = m00 + m01, p = m00 - m01 (roughbrdf.mueller)
    np.testing.assert_allclose(got[:, 0, 0], m.brdf(ti, tr, ph), rtol=1e-13)
    if basis == "psps":
        np.testing.assert_allclose(got[:, 0, 0] + got[:, 0, 1], m.brdf(ti, tr, ph, "s"),
                                   rtol=1e-12)


def test_linear_polarization_angle_is_the_mueller_row():
    # gamma: Stokes (1, -cos 2g, sin 2g, 0) in psps (roughbrdf.mueller): the cross terms
    m = _model(n=0.3, k=3.1)
    ti, tr, ph, g = 0.4, 0.9, 1.1, 0.7
    M = m.mueller(ti, tr, ph)
    want = M[0] @ np.array([1.0, -math.cos(2 * g), math.sin(2 * g), 0.0])
    assert m.brdf(ti, tr, ph, polarization=g) == pytest.approx(want, rel=1e-12)


# ------------------------------------------------------------------------------------------
# identities of the definition
# ------------------------------------------------------------------------------------------
def _geometry_from_beta(ti, dbx, dby):
    bx, by = np.sin(ti) + dbx, dby
    bm = np.hypot(bx, by)
    return np.arcsin(bm), np.arctan2(by, bx)


def test_psd_part_is_shift_invariant_in_beta():
    # brdf(C) / brdf(C = 0) = S_2(f)/A depends on beta - beta_0 only: the same shift from
    # different specular points gives the same ratio, (1 + (B f)^2)^(-C/2)
    rng = np.random.default_rng(7)
    d = rng.uniform(-0.15, 0.15, size=(2, 40))
    m, white = _model(C=3.7, B=2.5), _model(C=0.0, B=2.5)
    ratios = []
    for ti in (0.1, 0.5, 0.8):
        tr, ph = _geometry_from_beta(ti, d[0], d[1])
        ratios.append(m.brdf(ti, tr, ph, "s") / white.brdf(ti, tr, ph, "s"))
    f = np.hypot(d[0], d[1]) / LAM
    np.testing.assert_allclose(ratios[0], (1 + (2.5 * f) ** 2) ** (-3.7 / 2), rtol=1e-12)
    np.testing.assert_allclose(ratios[1], ratios[0], rtol=1e-12)
    np.testing.assert_allclose(ratios[2], ratios[0], rtol=1e-12)


def test_wavelength_scaling():
    ti, tr, ph = np.array([0.1, 0.6]), np.array([0.3, 1.2]), np.array([0.0, 2.0])
    # white PSD (C = 0): exactly lambda^-4
    w1, w2 = _model(C=0.0, wavelength=0.5), _model(C=0.0, wavelength=1.0)
    np.testing.assert_allclose(w1.brdf(ti, tr, ph) / w2.brdf(ti, tr, ph), 16.0, rtol=1e-13)
    # any PSD: f = |d beta|/lambda, so lambda^4 f_r is a function of B/lambda
    a, b = _model(wavelength=0.5, B=2.0), _model(wavelength=1.5, B=6.0)
    np.testing.assert_allclose(a.brdf(ti, tr, ph) * 0.5**4, b.brdf(ti, tr, ph) * 1.5**4,
                               rtol=1e-13)


@pytest.mark.parametrize("n,k", [(1.5, 0.0), (3.88, 0.019), (0.2, 3.4), (0.7, 0.0)])
def test_q_at_normal_incidence_is_fresnel(n, k):
    # ti = tr = 0, any phi: Q_s = Q_p = R(0) = |(n + ik - 1)/(n + ik + 1)|^2; with C = 0 the
    # BRDF is (16 pi^2/lambda^4) A Q
    m = _model(n=n, k=k, C=0.0)
    scale = 16 * math.pi**2 / LAM**4 * m.params["A"]
    r0 = abs((complex(n, k) - 1) / (complex(n, k) + 1)) ** 2
    ph = np.linspace(-3, 3, 7)
    for pol in ("s", "p", None):
        np.testing.assert_allclose(m.brdf(0.0, 0.0, ph, pol) / scale, r0, rtol=1e-12)
    assert float(rb.fresnel.reflectance(1.0, n, k)) == pytest.approx(r0, rel=1e-12)


@pytest.mark.parametrize("n,k", [(1.5, 0.0), (3.88, 0.019), (0.2, 3.4)])
def test_q_at_the_specular_direction_is_fresnel(n, k):
    # at beta = beta_0 (tr = ti, phi = 0): ss = -r_s, pp = -r_p, ps = sp = 0
    m = _model(n=n, k=k, C=0.0)
    ti = np.linspace(0.0, 1.5, 9)
    q = {p: m.brdf(ti, ti, 0.0, p) / (16 * math.pi**2 / LAM**4 * 1e-4 * np.cos(ti) ** 2)
         for p in ("s", "p")}
    np.testing.assert_allclose(q["s"], rb.fresnel.reflectance(np.cos(ti), n, k, "s"),
                               rtol=1e-11)
    np.testing.assert_allclose(q["p"], rb.fresnel.reflectance(np.cos(ti), n, k, "p"),
                               rtol=1e-11)


def test_unpolarized_is_the_mean_of_s_and_p():
    rng = np.random.default_rng(11)
    ti, tr = rng.uniform(0, 1.5, (2, 30))
    ph = rng.uniform(-math.pi, math.pi, 30)
    m = _model(n=0.3, k=3.0)
    np.testing.assert_allclose(m.brdf(ti, tr, ph),
                               0.5 * (m.brdf(ti, tr, ph, "s") + m.brdf(ti, tr, ph, "p")),
                               rtol=1e-13)


def test_reciprocal_and_mirror_symmetric():
    rng = np.random.default_rng(3)
    ti, tr = rng.uniform(0, 1.5, (2, 50))
    ph = rng.uniform(-math.pi, math.pi, 50)
    m = _model(n=0.3, k=3.0)
    np.testing.assert_allclose(m.brdf(ti, tr, ph), m.brdf(tr, ti, ph), rtol=1e-12)
    for pol in ("s", "p", None):
        np.testing.assert_allclose(m.brdf(ti, tr, ph, pol), m.brdf(ti, tr, -ph, pol),
                                   rtol=1e-12)
    np.testing.assert_allclose(m.bridf(ti, tr, ph), m.brdf(ti, tr, ph) * np.cos(tr),
                               rtol=1e-13)


def test_limits_and_special_geometries():
    m = _model()
    h = math.pi / 2
    ti = np.array([0.0, 0.0, h, 0.3, 1.2, h])
    tr = np.array([0.0, h, 0.5, 0.3, h, h])
    ph = np.array([0.0, 1.0, math.pi, 0.0, -math.pi, 0.0])
    for f in (m.brdf(ti, tr, ph), m.bridf(ti, tr, ph), m.brdf(ti, tr, ph, "p")):
        assert np.isfinite(f).all() and (f >= 0).all()
    # cos ti cos tr factor: 0 at grazing incidence or view (cos(pi/2) = 6e-17 in floats)
    peak = m.brdf(0.4, 0.4, 0.0)
    assert m.brdf(h, 0.4, 0.0) < 1e-15 * peak and m.brdf(0.4, h, 0.0) < 1e-15 * peak
    # index-matched interface (n + ik = 1): no scatter, also at the horizon
    assert np.all(_model(n=1.0).brdf(ti, tr, ph) == 0.0)


# ------------------------------------------------------------------------------------------
# PSD metrology
# ------------------------------------------------------------------------------------------
def _quad(fn, lo, hi):
    return integrate.quad(fn, lo, hi, limit=400, epsabs=0, epsrel=1e-12)[0]


@pytest.mark.parametrize("c", [1.2, 2.0, 2.5, 4.0, 5.5])
def test_sigma_rms_band_is_the_psd_integral(c):
    a, b = 3e-4, 7.0
    lo, hi = 0.05, 2.0
    want = 2 * math.pi * _quad(lambda f: float(kcorr.abc_psd(f, a, b, c)) * f, lo, hi)
    assert kcorr.sigma_rms(a, b, c, lo, hi) ** 2 == pytest.approx(want, rel=1e-9)
    slope = 2 * math.pi * _quad(lambda f: (2 * math.pi * f) ** 2
                                * float(kcorr.abc_psd(f, a, b, c)) * f, lo, hi)
    assert kcorr.rms_slope(a, b, c, lo, hi) ** 2 == pytest.approx(slope, rel=1e-9)


def test_total_sigma_and_slope_closed_forms():
    a, b, c = 3e-4, 7.0, 5.0
    tot = 2 * math.pi * _quad(lambda f: float(kcorr.abc_psd(f, a, b, c)) * f, 0, np.inf)
    assert kcorr.sigma_rms(a, b, c) ** 2 == pytest.approx(tot, rel=1e-9)
    assert kcorr.sigma_rms(a, b, c) ** 2 == pytest.approx(2 * math.pi * a / (b * b * (c - 2)))
    assert kcorr.rms_slope(a, b, c) ** 2 == pytest.approx(
        16 * math.pi**3 * a / (b**4 * (c - 2) * (c - 4)), rel=1e-12)
    with pytest.raises(ArgumentError) as e:
        kcorr.sigma_rms(a, b, 2.0)
    assert e.value.argument == "C"
    with pytest.raises(ArgumentError) as e:
        kcorr.rms_slope(a, b, 4.0)
    assert e.value.argument == "C"
    m = _model(C=1.5)
    assert m.metrology()["sigma_rms"] is None
    assert m.metrology(0.0, 1.0)["sigma_rms"] == pytest.approx(m.sigma_rms(0.0, 1.0))


def test_metrology_round_trip_and_exponential_correlation():
    a, b, c = kcorr.abc_from_metrology(0.0015, 2.2, 3.0)
    assert kcorr.sigma_rms(a, b, c) == pytest.approx(0.0015, rel=1e-12)
    assert kcorr.correlation_length(b) == pytest.approx(2.2, rel=1e-12)
    # C = 3 is the 2-D transform of sigma^2 exp(-r/l): S_2(f) = 2 pi int ACF J0(2 pi f r) r dr
    sigma, ell, f = 0.0015, 2.2, 0.13
    hankel = 2 * math.pi * _quad(lambda r: sigma**2 * math.exp(-r / ell)
                                 * special.j0(2 * math.pi * f * r) * r, 0, 80 * ell)
    assert float(kcorr.abc_psd(f, a, b, c)) == pytest.approx(hankel, rel=1e-7)


def test_profile_psd_conversion():
    # S_1(f) = int S_2(sqrt(f^2 + fy^2)) dfy for an isotropic surface
    a, b, c = 2e-4, 5.0, 3.4
    a1, b1, c1 = kcorr.abc_1d_from_2d(a, b, c)
    for f in (0.0, 0.1, 0.7):
        s1 = 2 * _quad(lambda fy, f=f: float(kcorr.abc_psd(math.hypot(f, fy), a, b, c)),
                       0, np.inf)
        assert a1 / (1 + (b1 * f) ** 2) ** (c1 / 2) == pytest.approx(s1, rel=1e-8)
    back = kcorr.abc_2d_from_1d(a1, b1, c1)
    np.testing.assert_allclose(back, (a, b, c), rtol=1e-12)


def test_band_of_a_measurement():
    m = _model(wavelength=0.5)
    ti = np.radians(30.0)
    tr = np.radians([0.0, 30.0, 60.0])
    lo, hi = m.band(ti, tr, 0.0)
    assert lo == 0.0  # the specular sample
    assert hi == pytest.approx(math.sin(ti) / 0.5, rel=1e-12)  # |0 - sin 30°|/lambda
    assert m.sigma_rms(lo, hi) < m.sigma_rms()


# ------------------------------------------------------------------------------------------
# TIS
# ------------------------------------------------------------------------------------------
TI = np.radians([0.0, 30.0, 60.0, 80.0])
#: the (B/lambda, C) cases of test_tis_equals_albedo: every pair (ids "C-B/lambda"), at the
#: incidences TI; without the JIT (make test-nojit: about 60 s a case in plain Python) the 4
#: pairs of the diagonal, each B/lambda and each C once, at normal and the most grazing
#: incidence (TIS_TI). Measured (JIT): tis and rb.albedo agree to 8e-7 or better on every
#: pair, so the diagonal's are as tight as the others' against rtol 1e-4.
TIS_TI = TI[[0, -1]] if NOJIT else TI
TIS_B_OVER_LAM = (0.5, 5.0, 50.0, 500.0)
TIS_C = (0.5, 2.0, 3.0, 6.0)
TIS_CASES = [pytest.param(b, c, id=f"{c}-{b}") for i, c in enumerate(TIS_C)
             for j, b in enumerate(TIS_B_OVER_LAM) if i == j or not NOJIT]


@pytest.mark.parametrize(("b_over_lam", "c"), TIS_CASES)
def test_tis_equals_albedo(b_over_lam, c):
    for n, k, pols in ((1.5, 0.0, ("s", "p", None)), (0.2, 3.4, (None,))):
        m = _model(B=b_over_lam * LAM, C=c, n=n, k=k)
        for pol in pols:
            np.testing.assert_allclose(kcorr.tis(m, TIS_TI, polarization=pol),
                                       rb.albedo(m, TIS_TI, polarization=pol), rtol=1e-4,
                                       err_msg=f"{pol}")


def test_tis_converged():
    m = _model(B=0.5 * LAM, C=0.5)
    ti = np.radians([0.0, 60.0, 89.0])
    fine = kcorr.tis(m, ti, polarization="s", n_psi=512, n_radial=1024)
    np.testing.assert_allclose(kcorr.tis(m, ti, polarization="s"), fine, rtol=5e-6)


@pytest.mark.parametrize("pol", ["s", "p", None])
def test_tis_small_roughness_limit(pol):
    # (4 pi sigma cos ti/lambda)^2 R(ti) where the PSD lies near the specular point: error
    # about the PSD fraction beyond the horizon + O((lambda/B)^2) (module notes of .tis)
    ti = np.radians([0.0, 30.0, 60.0])
    m = _model(B=100 * LAM, C=4.0, n=0.2, k=3.4)
    got = kcorr.tis(m, ti, polarization=pol)
    lim = kcorr.tis_smooth_limit(m, ti, polarization=pol)
    tail = (1 + (100 * (1 - np.sin(ti))) ** 2) ** (1 - 4.0 / 2)
    assert np.all(np.abs(got / lim - 1) < 2 * tail + 1e-3)
    # and it fails where it should: a short correlation length
    short = _model(B=0.5 * LAM, C=4.0)
    assert abs(kcorr.tis(short, 0.0) / kcorr.tis_smooth_limit(short, 0.0) - 1) > 0.1
    # SCATMECH's default PSD (A = 0.01, B = 362, C = 2.5): its f^-2.5 tail beyond the horizon
    # at normal incidence is (1 + (B/lambda)^2)^(-1/4) = 4.2 % of sigma^2 (docs figure)
    slow = _model(A=0.01, B=362.0, C=2.5, n=4.05, k=0.05)
    ratio = kcorr.tis(slow, 0.0) / kcorr.tis_smooth_limit(slow, 0.0)
    assert ratio == pytest.approx(1 - (1 + (362.0 / LAM) ** 2) ** -0.25, abs=2e-3)


def test_tis_bad_inputs():
    m = _model()
    with pytest.raises(ArgumentError) as e:
        kcorr.tis(rb.model("lambertian"), 0.1)
    assert e.value.argument == "model"
    for bad in (np.nan, np.inf, -0.1, 2.0):
        with pytest.raises(ArgumentError) as e:
            kcorr.tis(m, [0.1, bad])
        assert e.value.argument == "theta_i"
    with pytest.raises(ArgumentError) as e:
        kcorr.tis(m, 0.1, n_radial=1)
    assert e.value.argument == "n_radial"
    with pytest.raises(ArgumentError) as e:
        kcorr.tis_smooth_limit(_model(C=2.0), 0.1)
    assert e.value.argument == "C"
    assert kcorr.tis(m, np.zeros((2, 3))).shape == (2, 3)


# ------------------------------------------------------------------------------------------
# inputs, errors, registration
# ------------------------------------------------------------------------------------------
def test_n_dimensional_inputs():
    m = _model()
    ti = np.linspace(0, 1.2, 2)[:, None, None]
    tr = np.linspace(0, 1.5, 3)[None, :, None]
    ph = np.linspace(-3, 3, 4)
    f = m.brdf(ti, tr, ph, "p")
    assert f.shape == (2, 3, 4)
    for idx in [(0, 0, 0), (1, 2, 3), (1, 1, 2)]:
        assert f[idx] == m.brdf(float(ti[idx[0], 0, 0]), float(tr[0, idx[1], 0]),
                                float(ph[idx[2]]), "p")
    assert m.mueller(ti, tr, ph).shape == (2, 3, 4, 4, 4)
    assert isinstance(m.brdf(0.1, 0.2, 0.3), float)
    pol = np.array([0.0, math.pi / 2])  # one polarization per sample: p, s
    np.testing.assert_allclose(m.brdf(0.3, np.array([0.5, 0.5]), 0.4, pol),
                               [m.brdf(0.3, 0.5, 0.4, "p"), m.brdf(0.3, 0.5, 0.4, "s")],
                               rtol=1e-14)


@pytest.mark.parametrize("arg,bad", [("theta_i", np.nan), ("theta_r", np.inf),
                                     ("phi", np.nan), ("theta_r", -0.2), ("theta_i", 1.7)])
def test_bad_angles_named(arg, bad):
    m = _model()
    angles = {"theta_i": [0.1, 0.2], "theta_r": [0.3, 0.4], "phi": [0.0, 1.0]}
    angles[arg] = [0.1, bad]
    with pytest.raises(ArgumentError) as e:
        m.brdf(angles["theta_i"], angles["theta_r"], angles["phi"])
    assert e.value.argument == arg


@pytest.mark.parametrize("name,bad", [("A", np.nan), ("A", -1.0), ("B", 0.0), ("B", np.inf),
                                      ("C", -0.5), ("n", 0.0), ("k", -0.1), ("n", None)])
def test_bad_parameters_named(name, bad):
    with pytest.raises(ArgumentError) as e:
        _model(**{name: bad})
    assert e.value.argument == name


def test_wavelength_is_required_and_checked():
    m = rb.model("k-correlation", A=1e-4)
    for call in (lambda: m.brdf(0.1, 0.2, 0.0), lambda: m.mueller(0.1, 0.2, 0.0),
                 lambda: kcorr.tis(m, 0.1), lambda: m.band(0.1, 0.2, 0.0)):
        with pytest.raises(ArgumentError) as e:
            call()
        assert e.value.argument == "wavelength"
    assert m.with_params(wavelength="630nm").options["wavelength"] == 0.63
    assert _model(wavelength="0.6328 um").options["wavelength"] == 0.6328
    for bad in (630.0, "630", "630 parsecs", -0.5, np.nan, True, "nm"):
        with pytest.raises(ArgumentError) as e:
            _model(wavelength=bad)
        assert e.value.argument == "wavelength"


def test_registered_names_and_round_trip():
    for name in ("k-correlation", "kcorr", "abc", "K-Correlation"):
        assert type(rb.model(name)) is kcorr.KCorrelation
    m = _model(n=0.3, k=3.0)
    again = rb.model(m.to_dict())
    assert again.params == m.params and again.options == m.options
    assert again.brdf(0.2, 0.5, 1.0) == m.brdf(0.2, 0.5, 1.0)
    assert {p.name: p.unit for p in m.parameters} == {"A": "um^4", "B": "um", "C": "1",
                                                      "n": "1", "k": "1"}
    assert "SCATMECH" in m.reference
    text = _model(A=1e-5, B=5.0, C=3.0).describe()
    assert "sigma_rms = 0.00158533 um" in text and "rms slope = diverges (C <= 4)" in text


def test_pure_python_mode_agrees():
    code = textwrap.dedent("""
        import json, numpy as np, roughbrdf as rb, numba
        from roughbrdf.models import kcorr
        assert numba.config.DISABLE_JIT
        m = rb.model("kcorr", A=2e-4, B=3.0, C=3.3, n=3.88, k=0.019, wavelength=0.6328)
        ti = np.array([0.0, 0.3, 1.2, 1.5707963267948966]); tr = np.array([0.0, 0.4, 1.5, 0.2])
        ph = np.array([0.0, 1.0, 3.0, -2.0])
        print(json.dumps([m.brdf(ti, tr, ph).tolist(), m.brdf(ti, tr, ph, "s").tolist(),
                          m.mueller(ti, tr, ph, basis="xyxy").tolist(),
                          kcorr.tis(m, [0.1, 0.9], n_psi=16, n_radial=8).tolist()]))
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    import json

    pure = json.loads(res.stdout.strip().splitlines()[-1])
    m = rb.model("kcorr", **PSD, n=3.88, k=0.019, wavelength=LAM)
    ti = np.array([0.0, 0.3, 1.2, math.pi / 2])
    tr = np.array([0.0, 0.4, 1.5, 0.2])
    ph = np.array([0.0, 1.0, 3.0, -2.0])
    np.testing.assert_allclose(pure[0], m.brdf(ti, tr, ph), rtol=1e-13)
    np.testing.assert_allclose(pure[1], m.brdf(ti, tr, ph, "s"), rtol=1e-13)
    mm = m.mueller(ti, tr, ph, basis="xyxy")
    # elements that vanish analytically come out as round-off, FMA-contracted or not
    atol = 1e-14 * mm[..., :1, :1]
    assert np.all(np.abs(np.array(pure[2]) - mm) <= 1e-12 * np.abs(mm) + atol)
    np.testing.assert_allclose(pure[3], kcorr.tis(m, [0.1, 0.9], n_psi=16, n_radial=8),
                               rtol=1e-12)

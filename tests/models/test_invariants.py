"""Invariants checked on every registered model (and on variants of their options).

Physics identities (no reference numbers needed): non-negativity, the phi -> -phi symmetry of
isotropic surfaces (docs/models.md §1.3), Helmholtz reciprocity for models whose ``reciprocal`` is
True, ``bridf = brdf cos(theta_r)`` (docs/models.md §1.2), broadcasting of n-dimensional inputs, no
NaN anywhere on the closed hemisphere (including exactly normal, grazing, specular and retro
geometries), and ValueError naming the parameter and the value for invalid inputs.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import roughbrdf as rb

HALF_PI = math.pi / 2
#: what a model cannot be evaluated without (K-correlation: the wavelength, in um)
REQUIRED = {"k-correlation": {"wavelength": 0.633}}


def _configs() -> list[tuple[str, dict]]:
    """Every registered model at its defaults, plus option variants of the core models."""
    out = [(name, dict(REQUIRED.get(name, {}))) for name in rb.available()]
    out += [
        ("trowbridge-reitz-1975", {"shadowing": "v-groove"}),
        ("trowbridge-reitz-1975", {"e": 0.05, "n": 1.5, "k": 0.0, "rho_L": 0.0}),
        ("trowbridge-reitz-1975", {"e": 1.6, "n": 0.7, "k": 1.3, "rho_L": 0.5}),
        ("torrance-sparrow-1967", {"n": 0.77, "k": 6.08, "g": 2.0}),
        ("torrance-sparrow-1967", {"n": 1.74, "k": 0.0, "c": 0.01}),
    ]
    for dist in rb.distributions.names():
        shadows = ["none", "v-groove"]
        if rb.distributions.get(dist).smith:
            shadows += ["smith-separable", "smith-height-correlated"]
        alpha = {"gaussian-angle": 0.05, "sirohi": 6.93}.get(dist, 0.3)
        for s in shadows:
            out.append(("microfacet", {"distribution": dist, "shadowing": s, "alpha": alpha}))
    out.append(("microfacet", {"n": None, "k": None, "alpha": 0.05, "shadowing": "none"}))
    out.append(("microfacet", {"n": 0.2, "k": 3.0, "alpha": 1.5}))
    return out


CONFIGS = _configs()
IDS = [name + "".join(f"-{k}={v}" for k, v in kw.items()) for name, kw in CONFIGS]


@pytest.fixture(params=range(len(CONFIGS)), ids=IDS, scope="module")
def model(request):
    name, kw = CONFIGS[request.param]
    return rb.model(name, **kw)


def _ti_max(m) -> float:
    """Largest allowed theta_i: pi/2, or just below it for models dividing by cos(theta_i)."""
    return HALF_PI if m.grazing_incidence else np.nextafter(HALF_PI, 0.0)


def test_the_core_models_are_registered():
    for name in ["lambertian", "microfacet", "torrance-sparrow-1967", "trowbridge-reitz-1975"]:
        assert name in rb.available()


# ------------------------------------------------------------------------------------------
# random geometries (Hypothesis)
# ------------------------------------------------------------------------------------------
ZENITH = st.floats(0.0, HALF_PI, allow_nan=False)
AZIMUTH = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False)


def geometry_batch(size=64):
    return st.tuples(hnp.arrays(np.float64, size, elements=ZENITH),
                     hnp.arrays(np.float64, size, elements=ZENITH),
                     hnp.arrays(np.float64, size, elements=AZIMUTH))


def _clip_ti(m, ti):
    return np.minimum(ti, _ti_max(m))


@settings(max_examples=5, deadline=None)
@given(geo=geometry_batch())
def test_non_negative_and_no_nan(model, geo):
    ti, tr, ph = geo
    ti = _clip_ti(model, ti)
    for f in (model.brdf(ti, tr, ph), model.bridf(ti, tr, ph)):
        assert not np.isnan(f).any()
        assert (f >= 0).all()


@settings(max_examples=5, deadline=None)
@given(geo=geometry_batch())
def test_phi_symmetry(model, geo):
    # isotropic surfaces: phi -> -phi never changes a value (docs/models.md §1.3)
    ti, tr, ph = geo
    ti = _clip_ti(model, ti)
    np.testing.assert_allclose(model.brdf(ti, tr, -ph), model.brdf(ti, tr, ph), rtol=1e-11)


@settings(max_examples=5, deadline=None)
@given(geo=geometry_batch())
def test_periodic_in_phi(model, geo):
    ti, tr, ph = geo
    ti = _clip_ti(model, ti)
    # phi + 2 pi is phi only to ~1e-15 rad; near the forward grazing pair (w_i ~ -w_r, where
    # the half vector turns fast) that rounding is amplified, so keep |w_i + w_r| > 1e-2 there
    wi, wr = rb.geometry.unit_vectors(ti, tr, ph)
    ok = np.linalg.norm(wi + wr, axis=-1) > 1e-2
    a = model.bridf(ti, tr, ph + 2 * math.pi)
    b = model.bridf(ti, tr, ph)
    np.testing.assert_allclose(a[ok], b[ok], rtol=1e-9, atol=1e-300)


@settings(max_examples=5, deadline=None)
@given(geo=geometry_batch())
def test_reciprocity(model, geo):
    if not model.reciprocal:
        pytest.skip(f"{model.name} is not reciprocal (model.reciprocal is False)")
    ti, tr, ph = geo
    ti, tr = _clip_ti(model, ti), _clip_ti(model, tr)
    a = model.brdf(ti, tr, ph)
    b = model.brdf(tr, ti, ph)
    finite = np.isfinite(a) | np.isfinite(b)
    np.testing.assert_allclose(a[finite], b[finite], rtol=1e-10)
    assert np.all(rb.reciprocity_error(model, ti, tr, ph)[finite] < 1e-10)


@settings(max_examples=4, deadline=None)
@given(geo=geometry_batch())
def test_bridf_is_brdf_times_cos(model, geo):
    ti, tr, ph = geo
    ti = _clip_ti(model, ti)
    tr = np.minimum(tr, 1.5)  # away from the horizon, where brdf may be inf (TR75)
    np.testing.assert_allclose(model.bridf(ti, tr, ph), model.brdf(ti, tr, ph) * np.cos(tr),
                               rtol=1e-12, atol=1e-300)


def test_n_dimensional_broadcasting(model):
    rng = np.random.default_rng(0)
    ti = rng.uniform(0, 1.5, (2, 1, 3))
    tr = rng.uniform(0, HALF_PI, (1, 4, 1))
    ph = rng.uniform(-np.pi, np.pi, (3,))
    got = model.brdf(ti, tr, ph)
    assert got.shape == (2, 4, 3)
    a, b, c = np.broadcast_arrays(ti, tr, ph)
    loop = np.array([model.brdf(x, y, z) for x, y, z in zip(a.ravel(), b.ravel(), c.ravel(),
                                                            strict=True)]).reshape(2, 4, 3)
    np.testing.assert_allclose(got, loop, rtol=1e-14)
    # the same through non-contiguous views and lists
    got_t = model.brdf(np.asfortranarray(a), b[:, ::-1, :][:, ::-1, :], c.tolist())
    np.testing.assert_allclose(got_t, got, rtol=1e-15)
    # scalars give a Python float; 0-size arrays give an empty result
    assert isinstance(model.brdf(0.1, 0.2, 0.3), float)
    assert model.brdf(np.zeros((0, 2)), 0.3, 0.0).shape == (0, 2)


# ------------------------------------------------------------------------------------------
# special geometries: exactly normal, grazing, specular, retro
# ------------------------------------------------------------------------------------------
def _special_geometries(m):
    tis = [0.0, 1e-9, 0.3, math.pi / 4, 1.2, HALF_PI - 1e-9, _ti_max(m)]
    out = []
    for ti in tis:
        trs = [0.0, 1e-9, ti, 1.0, HALF_PI - 1e-9, HALF_PI]
        for tr in trs:
            for ph in (0.0, math.pi, -math.pi, HALF_PI, 1e-12, math.pi - 1e-12):
                out.append((ti, tr, ph))
    return np.array(out).T


def test_no_nan_special_geometries(model):
    ti, tr, ph = _special_geometries(model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning from the kernels either
        brdf = model.brdf(ti, tr, ph)
        bridf = model.bridf(ti, tr, ph)
    assert not np.isnan(brdf).any(), list(zip(ti[np.isnan(brdf)], tr[np.isnan(brdf)],
                                              strict=True))
    assert not np.isnan(bridf).any()
    assert (brdf >= 0).all() and (bridf >= 0).all()
    # The BRIDF stays finite (for TR75 too, whose BRDF is inf at the horizon). The only
    # exception: models without shadowing diverge as 1/cos(theta_i) at grazing incidence
    # (docs/models.md §3.13), and return that limit, inf, where cos(theta_i) rounds to 0.
    unshadowed = (model.name in ("trowbridge-reitz-1975", "microfacet")
                  and model.options.get("shadowing") == "none")
    grazing_i = np.cos(ti) < 1e-15
    assert np.isfinite(bridf[~grazing_i]).all()
    if not unshadowed:
        assert np.isfinite(bridf).all()
    # models with shadowing stay finite at theta_r = pi/2 (TS67 via the branch formulas)
    if not unshadowed and model.name != "renhorn-boreman-2008":
        assert np.isfinite(brdf).all()


def test_horizon_value_is_the_limit(model):
    # at theta_r = pi/2 the models return the limit of the values just above the horizon
    ti = np.array([0.0, 0.4, 1.0, 1.4])
    for ph in (0.0, 1.0, math.pi):
        at = model.brdf(ti, HALF_PI, ph)
        near = model.brdf(ti, HALF_PI - 1e-10, ph)
        fin = np.isfinite(at)
        # a limit of 0 approached like cos(theta_r) (Rayleigh-Rice: cos theta_r in the
        # BRDF): 1e-10 rad above the horizon the value is 1e-10 of the model's scale
        scale = float(np.max(model.brdf(ti, 0.5, ph)))
        np.testing.assert_allclose(at[fin], near[fin], rtol=1e-5, atol=1e-9 * scale)
        # an infinite limit (no shadowing) is approached as 1/cos(theta_r)
        far = model.brdf(ti[~fin], HALF_PI - 1e-6, ph)
        assert np.all(near[~fin] > 1e3 * far)


# ------------------------------------------------------------------------------------------
# invalid inputs
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", rb.available())
def test_invalid_zenith_raises(name):
    model = rb.model(name, **REQUIRED.get(name, {}))
    for which in ("theta_i", "theta_r"):
        for bad in (-0.1, HALF_PI + 0.01, math.nan, math.inf, -math.inf):
            args = {"theta_i": 0.3, "theta_r": 0.4, "phi": 0.0}
            args[which] = np.array([0.1, bad, 0.2])
            for method in (model.brdf, model.bridf):
                with pytest.raises(ValueError) as exc:
                    method(**args)
                msg = str(exc.value)
                assert which in msg and repr(float(bad)) in msg, msg


def test_grazing_incidence_rejected_where_model_divides_by_cos(model):
    if model.grazing_incidence:
        assert np.isfinite(model.brdf(HALF_PI, 0.3, 0.0))
        return
    with pytest.raises(ValueError, match="theta_i"):
        model.brdf(HALF_PI, 0.3, 0.0)


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_invalid_phi_raises(model, bad):
    with pytest.raises(ValueError, match=r"phi.*" + repr(bad)):
        model.brdf(0.3, 0.4, bad)


def test_large_phi_is_reduced(model):
    # azimuths far outside [-pi, pi] are periodic too (beyond the kernels' sin/cos range)
    ph = np.array([1.0, 1.0 + 2e6 * math.pi, 1.0 - 2e8 * math.pi])
    got = model.bridf(0.3, 0.4, ph)
    np.testing.assert_allclose(got, got[0], rtol=1e-6)


def test_unknown_parameter_raises(model):
    with pytest.raises(ValueError, match="unknown parameter.*'bogus'"):
        rb.model(model.name, bogus=1.0)
    with pytest.raises(ValueError, match="bogus"):
        model.with_params(bogus=1.0)


def test_parameter_outside_domain_names_it(model):
    for p in model.parameters:
        lo, lo_inc, hi, hi_inc = p.domain
        bad = lo if not lo_inc and np.isfinite(lo) else (lo - 1.0 if np.isfinite(lo) else None)
        if bad is None:
            continue
        with pytest.raises(ValueError) as exc:
            model.with_params(**{p.name: bad})
        assert repr(p.name) in str(exc.value) and repr(bad) in str(exc.value)
        with pytest.raises(ValueError, match=repr(p.name)):
            model.with_params(**{p.name: math.nan})


def test_parameters_carry_metadata(model):
    for p in model.parameters:
        assert isinstance(p, rb.Parameter)
        assert p.name in model.params and p.value == model.params[p.name]
        lo, hi = p.bounds
        assert lo < hi and np.isfinite(lo) and np.isfinite(hi)
        assert isinstance(p.unit, str) and p.description


def test_to_dict_round_trip(model):
    again = rb.model(model.to_dict())
    assert again.params == model.params and again.options == model.options
    ti, tr, ph = _special_geometries(model)
    np.testing.assert_array_equal(again.bridf(ti, tr, ph), model.bridf(ti, tr, ph))


# ------------------------------------------------------------------------------------------
# NUMBA_DISABLE_JIT=1 gives the same numbers (pure Python, for debugging and coverage)
# ------------------------------------------------------------------------------------------
def test_pure_python_mode_agrees():
    code = textwrap.dedent("""
        import json, numpy as np, roughbrdf as rb
        import numba
        assert numba.config.DISABLE_JIT
        ti = np.array([0.0, 0.3, 1.2, 1.5]); tr = np.array([0.0, 0.4, 1.2, 1.5707963267948966])
        ph = np.array([0.0, 1.0, 3.141592653589793, -2.0])
        out = {}
        for name, kw in [("trowbridge-reitz-1975", {}), ("torrance-sparrow-1967", {"n": 1.5}),
                         ("microfacet", {}), ("lambertian", {})]:
            m = rb.model(name, **kw)
            out[name] = [m.bridf(ti, tr, ph).tolist(), m.bridf(ti, tr, ph, "s").tolist()]
        out["g"] = rb.shadowing.g_over_cos_r(ti, tr, ph).tolist()
        out["f"] = rb.fresnel.reflectance(np.cos(ti), 1.5, 0.3, "p").tolist()
        print(json.dumps(out))
    """)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, check=True)
    import json

    pure = json.loads(res.stdout.strip().splitlines()[-1])
    ti = np.array([0.0, 0.3, 1.2, 1.5])
    tr = np.array([0.0, 0.4, 1.2, HALF_PI])
    ph = np.array([0.0, 1.0, math.pi, -2.0])
    for name, kw in [("trowbridge-reitz-1975", {}), ("torrance-sparrow-1967", {"n": 1.5}),
                     ("microfacet", {}), ("lambertian", {})]:
        m = rb.model(name, **kw)
        np.testing.assert_allclose(pure[name][0], m.bridf(ti, tr, ph), rtol=1e-13)
        np.testing.assert_allclose(pure[name][1], m.bridf(ti, tr, ph, "s"), rtol=1e-13)
    np.testing.assert_allclose(pure["g"], rb.shadowing.g_over_cos_r(ti, tr, ph), rtol=1e-13)
    np.testing.assert_allclose(pure["f"], rb.fresnel.reflectance(np.cos(ti), 1.5, 0.3, "p"),
                               rtol=1e-13)

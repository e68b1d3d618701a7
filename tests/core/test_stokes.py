"""Stokes vectors in and out: roughbrdf.stokes and Polarization(stokes=,
analyzer=).

Conventions are those written in src/roughbrdf/mueller.py (SCATMECH's): Q > 0 is s, TR75's gamma
is the Jones vector (sin gamma, cos gamma) in psps, V > 0 is the Jones vector (1, i). The expected
numbers come from those definitions (Stokes from Jones), from textbook Fresnel values (glass
n = 1.5 at 45 deg: R_s = 0.0920, R_p = 0.0085, docs/models.md §1.4), Brewster's law
(tan theta_B = n) and the scalar kernels of the library (bit-compatibility to round-off).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf import stokes as st
from roughbrdf.errors import ArgumentError
from roughbrdf.instrument import aperture_average
from roughbrdf.polarization import Polarization

RNG = np.random.default_rng(20261201)
N = 300
TI = RNG.uniform(0.0, 1.4, N)
TR = RNG.uniform(0.0, 1.5, N)
PHI = RNG.uniform(-math.pi, math.pi, N)
GAMMA = RNG.uniform(-3.0, 3.0, N)

MODELS = {
    "microfacet-metal": lambda: rb.model("microfacet", distribution="beckmann", alpha=0.3,
                                         n=0.2, k=3.0),
    "microfacet-glass": lambda: rb.model("microfacet", alpha=0.4, n=1.5, k=0.0),
    "ts67": lambda: rb.model("torrance-sparrow-1967", n=1.6, k=0.3),
    "tr75+lambertian": lambda: (rb.model("trowbridge-reitz-1975", e=0.5, n=1.4, k=0.2)
                                + rb.model("lambertian", rho=0.3)),
    "coated": lambda: rb.model("coated"),
}


def _jones_stokes(e1: complex, e2: complex) -> np.ndarray:
    """Stokes vector of a Jones vector, by the definitions of mueller.py's module notes."""
    return np.array([abs(e1) ** 2 + abs(e2) ** 2, abs(e1) ** 2 - abs(e2) ** 2,
                     2 * (np.conj(e1) * e2).real, 2 * (np.conj(e1) * e2).imag])


# --------------------------------------------------------------------------------------------
# states
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("gamma", [0.0, 0.3, math.pi / 4, math.pi / 2, 2.0, -1.1])
def test_linear_is_the_jones_vector_of_tr75_gamma(gamma):
    # mueller.py: gamma is the Jones vector (sin gamma, cos gamma) on (s, p)
    expected = _jones_stokes(math.sin(gamma), math.cos(gamma))
    assert np.allclose(st.linear(gamma), expected, rtol=0, atol=1e-15)


def test_named_states():
    assert st.s().tolist() == _jones_stokes(1, 0).tolist() == [1, 1, 0, 0]
    assert st.p().tolist() == _jones_stokes(0, 1).tolist() == [1, -1, 0, 0]
    assert np.allclose(st.circular("ccw"), _jones_stokes(1 / math.sqrt(2), 1j / math.sqrt(2)))
    assert st.circular("left").tolist() == st.circular("ccw").tolist()
    assert st.circular("cw").tolist() == st.circular("right").tolist() == [1, 0, 0, -1]
    assert st.unpolarized().tolist() == [1, 0, 0, 0]
    with pytest.raises(ArgumentError, match="sense"):
        st.circular("clockwise-ish")


def test_degree_and_angle():
    assert st.dolp(st.linear(0.7)) == pytest.approx(1.0)
    assert st.aolp(st.linear(0.7)) == pytest.approx(0.7)
    assert st.aolp(st.linear(0.7 + math.pi)) == pytest.approx(0.7)  # modulo pi
    assert st.aolp(st.linear(-0.2)) == pytest.approx(math.pi - 0.2)
    assert math.isnan(st.aolp(st.unpolarized())) and math.isnan(st.aolp(st.circular()))
    assert st.docp(st.circular()) == 1.0 and st.dolp(st.circular()) == 0.0
    partial = np.array([2.0, 0.6, -0.8, 1.0])  # |(Q, U)| = 1, |(Q, U, V)| = sqrt(2)
    assert st.dolp(partial) == pytest.approx(0.5)
    assert st.dop(partial) == pytest.approx(math.sqrt(2) / 2)
    assert st.docp(partial) == pytest.approx(0.5)
    assert math.isnan(st.dolp([0.0, 0.0, 0.0, 0.0]))  # no light: no degree
    arr = st.dolp(np.stack([st.s(), st.unpolarized()]))
    assert arr.tolist() == [1.0, 0.0]


def test_rotation():
    g = np.linspace(-2, 2, 9)
    assert np.allclose(st.rotate_stokes(st.linear(g), 0.35), st.linear(g - 0.35))
    v = np.array([1.0, 0.1, -0.4, 0.3])
    twice = st.rotate_stokes(st.rotate_stokes(v, 0.2), 0.5)
    assert np.allclose(twice, st.rotate_stokes(v, 0.7))
    assert np.allclose(st.rotate_stokes(v, math.pi), v)  # a half turn changes no state
    assert st.rotate_stokes(v, 1.1)[[0, 3]].tolist() == [1.0, 0.3]  # I and V unchanged
    assert np.allclose(st.rotation_matrix(0.4) @ st.rotation_matrix(-0.4), np.eye(4))


def test_analyzer_row_is_an_ideal_polarizer():
    # Malus: a polarizer at gamma_a passes cos^2(gamma - gamma_a) of linear light at gamma
    for ga, g in [(0.0, 0.3), (1.0, -0.4), (math.pi / 2, 0.0)]:
        assert st.analyzer_row(st.linear(ga)) @ st.linear(g) == pytest.approx(
            math.cos(g - ga) ** 2, abs=1e-15)
    assert np.allclose(st.analyzer_row(st.s()) + st.analyzer_row(st.p()), [1, 0, 0, 0])
    assert st.analyzer_row([2.0, 0.0, 0.0, 2.0]).tolist() == [0.5, 0.0, 0.0, 0.5]
    with pytest.raises(ArgumentError, match="state"):
        st.analyzer_row(st.unpolarized())


# --------------------------------------------------------------------------------------------
# the Stokes path of Model.evaluate, against the scalar kernels
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(MODELS))
def test_mueller_times_linear_is_the_scalar_brdf(name):
    m = MODELS[name]()
    scalar = m.brdf(TI, TR, PHI, polarization=GAMMA)
    mat = m.mueller(TI, TR, PHI)
    via = (mat @ st.linear(GAMMA)[..., None])[..., 0, 0]
    assert np.allclose(via, scalar, rtol=1e-12, atol=0)
    stokes_path = m.brdf(TI, TR, PHI, polarization=Polarization(stokes=st.linear(GAMMA)))
    assert np.allclose(stokes_path, scalar, rtol=1e-12, atol=0)
    for name_, vec in (("s", st.s()), ("p", st.p()), (None, st.unpolarized())):
        assert np.allclose(m.brdf(TI, TR, PHI, polarization=Polarization(stokes=vec)),
                           m.brdf(TI, TR, PHI, polarization=name_), rtol=1e-12, atol=0)


@pytest.mark.parametrize("quantity", ["brdf", "bridf", "brdf_cos", "relative"])
def test_stokes_path_quantities(quantity):
    m = MODELS["microfacet-metal"]()
    ti, tr, ph = TI[:50], TR[:50], PHI[:50]
    scalar = m.evaluate(ti, tr, ph, quantity=quantity, polarization=GAMMA[:50])
    pol = Polarization.from_stokes(st.linear(GAMMA[:50]))
    assert np.allclose(m.evaluate(ti, tr, ph, quantity=quantity, polarization=pol), scalar,
                       rtol=1e-12, atol=0)


def test_scalar_paths_never_use_the_mueller_matrix(monkeypatch):
    # "s", "p", gamma and unpolarized stay on the compiled scalar kernels: bit-identical
    m = MODELS["microfacet-metal"]()
    before = {p: m.brdf(TI, TR, PHI, polarization=p) for p in (None, "s", "p", 0.4)}
    before["array"] = m.brdf(TI, TR, PHI, polarization=GAMMA)

    def refuse(*args, **kwargs):
        raise AssertionError("the scalar path called model.mueller")

    monkeypatch.setattr(type(m), "mueller", refuse)
    for p in (None, "s", "p", 0.4):
        assert np.array_equal(m.brdf(TI, TR, PHI, polarization=p), before[p])
    assert np.array_equal(m.brdf(TI, TR, PHI, polarization=GAMMA), before["array"])


def test_analyzer_at_the_specular_direction_textbook_glass():
    # At the specular direction of an in-plane geometry the facet is the mean surface:
    # M = f [[A, B, 0, 0], [B, A, 0, 0], [0, 0, C, S], [0, 0, -S, C]], A = (Rs + Rp)/2,
    # B = (Rs - Rp)/2. Glass n = 1.5 at 45 deg (textbook): R_s = 0.0920, R_p = 0.0085.
    m = rb.model("microfacet", alpha=0.3, n=1.5, k=0.0)
    t = math.radians(45.0)
    unpol = m.brdf(t, t, 0.0)
    rs, rp = 0.0920, 0.0085
    through_s = m.brdf(t, t, 0.0, polarization=Polarization(
        stokes=st.linear(math.pi / 4), analyzer=st.analyzer_row(st.s())))
    # (1/2)(A + B) f / (A f) = R_s/(R_s + R_p)
    assert through_s / unpol == pytest.approx(rs / (rs + rp), rel=2e-3)
    out = st.reflected_stokes(m, t, t, 0.0, st.unpolarized())
    assert st.dolp(out) == pytest.approx((rs - rp) / (rs + rp), rel=2e-3)
    assert st.aolp(out) == pytest.approx(math.pi / 2)  # more s than p: gamma = pi/2
    crossed = m.brdf(t, t, 0.0, polarization=Polarization(
        stokes=st.s(), analyzer=st.analyzer_row(st.p())))
    assert abs(crossed) <= 1e-15 * unpol  # in the plane of incidence s stays s


def test_brewster_angle_reflects_s_only():
    # tan theta_B = n: R_p = 0, the specular reflection of natural light is purely s
    m = rb.model("microfacet", alpha=0.2, n=1.5, k=0.0)
    tb = math.atan(1.5)
    out = st.reflected_stokes(m, tb, tb, 0.0, st.unpolarized())
    assert st.dolp(out) == pytest.approx(1.0, abs=1e-12)
    assert out[1] == pytest.approx(out[0], rel=1e-12)  # Q = I: s


def test_normal_reflection_reverses_the_circular_state():
    # mueller.fresnel_mueller at normal incidence is R diag(1, 1, -1, -1): V changes sign
    m = rb.model("microfacet", alpha=0.3, n=1.5, k=0.0)
    out = st.reflected_stokes(m, 1e-4, 1e-4, 0.0, st.circular("ccw"))
    assert st.docp(out) == pytest.approx(-1.0, abs=1e-6)


def test_per_sample_stokes_and_analyzer_broadcast():
    m = MODELS["microfacet-metal"]()
    s_in = st.linear(GAMMA[:20])
    a = st.analyzer_row(st.linear(GAMMA[20:40]))
    val = m.brdf(TI[:20], TR[:20], PHI[:20], polarization=Polarization(stokes=s_in, analyzer=a))
    mat = m.mueller(TI[:20], TR[:20], PHI[:20])
    ref = np.einsum("ni,nij,nj->n", a, mat, s_in)
    assert val.shape == (20,) and np.allclose(val, ref, rtol=1e-13)
    grid = m.brdf(TI[:20, None], TR[:20, None], PHI[:20, None],
                  polarization=Polarization(stokes=st.linear(np.array([0.0, 1.0, 2.0]))))
    assert grid.shape == (20, 3)
    assert isinstance(m.brdf(0.3, 0.4, 0.5, polarization=Polarization(stokes=st.s())), float)
    with pytest.raises(ArgumentError, match="stokes"):
        m.brdf(TI[:20], TR[:20], PHI[:20], polarization=Polarization(stokes=s_in[:7]))
    out = st.reflected_stokes(m, TI[:20], TR[:20], PHI[:20], s_in)
    assert out.shape == (20, 4) and np.allclose(out[:, 0], m.brdf(
        TI[:20], TR[:20], PHI[:20], polarization=GAMMA[:20]), rtol=1e-12)


def test_xyxy_basis_evaluation_agrees_with_psps():
    m = MODELS["microfacet-glass"]()
    ti, tr, ph = TI[:40], TR[:40], PHI[:40]
    s_in = st.linear(GAMMA[:40])  # the incident bases coincide
    a_psps = st.analyzer_row(st.linear(GAMMA[40:80]))
    # the same detector in xyxy: a row transforms as a Stokes vector (orthogonal change)
    a_xyxy = st.change_basis(a_psps, ti, tr, ph, source="psps", target="xyxy")
    v_psps = m.brdf(ti, tr, ph, polarization=Polarization(stokes=s_in, analyzer=a_psps))
    v_xyxy = m.brdf(ti, tr, ph, polarization=Polarization(stokes=s_in, analyzer=a_xyxy,
                                                          basis="xyxy"))
    assert np.allclose(v_xyxy, v_psps, rtol=1e-12, atol=1e-15)


# --------------------------------------------------------------------------------------------
# refusals
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, argument", [
    ({"stokes": [1.0, 0.0, 0.0]}, "stokes"),
    ({"stokes": [1.0, 1.0, 1.0, 0.0]}, "stokes"),           # |(Q, U, V)| > I: no such light
    ({"stokes": [-1.0, 0.0, 0.0, 0.0]}, "stokes"),
    ({"stokes": [1.0, np.nan, 0.0, 0.0]}, "stokes"),
    ({"stokes": ["1", "0", "0", "0"]}, "stokes"),
    ({"analyzer": [0.5, 0.0, -0.6, 0.0]}, "analyzer"),      # a negative reading for some light
    ({"stokes": [1.0, 0.0, 0.0, 0.0], "gamma": np.asarray(0.2)}, "stokes"),
    ({"stokes": [1.0, 0.0, 0.0, 0.0], "basis": "xy"}, "basis"),
    ({"basis": "xyxy", "analyzer": [1.0, 0.0, 0.0, 0.0]}, "basis"),
])
def test_bad_polarimetric_settings(kwargs, argument):
    with pytest.raises(ArgumentError) as err:
        Polarization(**kwargs)
    assert err.value.argument == argument


def test_paths_without_a_stokes_path_refuse():
    m = MODELS["microfacet-metal"]()
    pol = Polarization(stokes=st.circular())
    with pytest.raises(ArgumentError) as err:
        m.prepare(0.3, 0.4, 0.5, pol)
    assert err.value.argument == "polarization"
    with pytest.raises(ArgumentError) as err:
        aperture_average(m, 0.3, 0.4, 0.5, 0.02, polarization=pol)
    assert err.value.argument == "polarization"
    assert Polarization(stokes=[1.0, 1.0 + 1e-12, 0.0, 0.0]).stokes is not None  # rounding


# --------------------------------------------------------------------------------------------
# frames
# --------------------------------------------------------------------------------------------
def _field_stokes(field: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """Stokes vector of a complex 3-d field on the axes (e1, e2) (mueller.py definitions)."""
    return _jones_stokes(complex(field @ e1), complex(field @ e2))


@pytest.mark.parametrize("beam", ["incident", "reflected"])
@pytest.mark.parametrize("basis", ["psps", "xyxy"])
@pytest.mark.parametrize("left", [False, True])
def test_from_frame_against_the_field(beam, basis, left):
    # a polarimeter with axes x_u (its reference, Q > 0) and y_u measures a field; the same
    # field read on our axes must be from_frame of its reading
    rng = np.random.default_rng(5)
    for _ in range(5):
        ti, tr, ph = rng.uniform(0.05, 1.3), rng.uniform(0.05, 1.3), rng.uniform(-3, 3)
        e1, e2, k = st.basis_vectors(ti, tr, ph, beam=beam, basis=basis)
        ref = rng.normal(size=3)
        xu = ref - (ref @ k) * k
        xu /= np.linalg.norm(xu)
        yu = np.cross(xu, k) if left else np.cross(k, xu)
        amp = rng.normal(size=2) + 1j * rng.normal(size=2)
        field = amp[0] * xu + amp[1] * yu
        user = _field_stokes(field, xu, yu)
        ours = _field_stokes(field, e1, e2)
        got = st.from_frame(user, ref, ti, tr, ph, beam=beam, basis=basis, left_handed=left)
        assert np.allclose(got, ours, rtol=0, atol=1e-12 * ours[0])
        back = st.to_frame(ours, ref, ti, tr, ph, beam=beam, basis=basis, left_handed=left)
        assert np.allclose(back, user, rtol=0, atol=1e-12 * ours[0])


def test_reference_angle_and_refusal():
    # the lab vertical z seen across the incident beam is p_i: gamma = 0
    assert st.reference_angle([0.0, 0.0, 1.0], 0.5, 0.1, 0.0) == pytest.approx(0.0)
    assert st.reference_angle([0.0, 1.0, 0.0], 0.5, 0.1, 0.0) == pytest.approx(math.pi / 2)
    with pytest.raises(ArgumentError) as err:  # along the incident beam
        st.reference_angle([math.sin(0.5), 0.0, -math.cos(0.5)], 0.5, 0.1, 0.0)
    assert err.value.argument == "reference"


def test_change_basis_matches_the_model_bases():
    m = MODELS["microfacet-metal"]()
    ti, tr, ph = TI[:30], TR[:30], PHI[:30]
    out_psps = st.reflected_stokes(m, ti, tr, ph, st.linear(GAMMA[:30]))
    out_xyxy = st.reflected_stokes(m, ti, tr, ph, st.linear(GAMMA[:30]), basis="xyxy")
    conv = st.change_basis(out_psps, ti, tr, ph, source="psps", target="xyxy")
    assert np.allclose(conv, out_xyxy, rtol=0, atol=1e-12 * np.abs(out_xyxy).max())
    assert np.allclose(st.change_basis(conv, ti, tr, ph), out_psps, rtol=0,
                       atol=1e-12 * np.abs(out_psps).max())
    same = st.change_basis(st.linear(0.3), 0.4, 0.5, 0.6, beam="incident")
    assert np.allclose(same, st.linear(0.3))


def test_mueller_from_frames_undoes_a_lab_measurement():
    # a lab polarimeter with vertical references on both arms would measure
    # M_lab[:, j] = to_frame(M from_frame(e_j)); mueller_from_frames returns M
    m = MODELS["microfacet-metal"]()
    ti, tr, ph = 0.5, 0.7, 0.9
    mat = m.mueller(ti, tr, ph)
    z = [0.0, 0.0, 1.0]
    cols = [st.to_frame(mat @ st.from_frame(e, z, ti, tr, ph, beam="incident"), z, ti, tr, ph,
                        beam="reflected") for e in np.eye(4)]
    lab = np.stack(cols, axis=-1)
    assert not np.allclose(lab, mat)  # the lab frames are not ours here
    assert np.allclose(st.mueller_from_frames(lab, z, z, ti, tr, ph), mat, rtol=0,
                       atol=1e-12 * mat[0, 0])

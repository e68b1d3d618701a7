"""Traps in the Python API, closed, and the library side of messages in the user's terms.

Each trap is reproduced here:

* ``m.params['e'] = 0.1`` and ``m.e = -1`` silently did nothing: now they raise, naming
  ``with_params`` (models are immutable values: ``Model``'s docstring says why);
* ``None`` as an angle was reported as "got np.float64(nan)": now the argument and ``None``;
* a shape mismatch did not name the arguments: now both, with their shapes;
* TS67 ``rho_d=2`` and RB08 ``bulk=2`` were accepted while Lambertian ``rho=1.5`` was rejected:
  every reflectance-like parameter now has the one domain ``[0, 1]``;
* errors told the user a Python spelling: they are :class:`~roughbrdf.errors.ArgumentError` now,
  Python-worded by ``str`` and CLI-worded (options, degrees) by ``render``.
"""

from __future__ import annotations

import copy
import json
import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.measurement import Measurement
from roughbrdf.models.parameters import REFLECTANCE_DOMAIN, ReadOnlyDict

HALF_PI = 0.5 * math.pi
MODEL_NAMES = rb.available()
#: what a model cannot be evaluated without (K-correlation: the wavelength, in um)
REQUIRED = {"k-correlation": {"wavelength": 0.633}}


def _model(name):
    return rb.model(name, **REQUIRED.get(name, {}))

#: every reflectance-like parameter (a part's directional-hemispherical reflectance), by model;
#: docs/models.md: Lambertian rho and TR75 rho_L (Eq. 32), TS67 rho_d (its diffuse part is
#: rho_d/pi), RB08 bulk and retro (Eqs. 19-20). Not: microfacet ks (a free scale), TS67 g (a
#: ratio), RB08 rho and rho_r (lobe widths).
REFLECTANCES = {"lambertian": {"rho"}, "trowbridge-reitz-1975": {"rho_L"},
                "torrance-sparrow-1967": {"rho_d"}, "renhorn-boreman-2008": {"bulk", "retro"},
                "microfacet": set(), "coated": {"rho"}, "oren-nayar": {"rho"},
                # metallic paint: none by default (its pigment d, rho come with diffuse=True)
                "coated-conductor": set(),
                # the stray-light models: a scale A or b0 (sr^-1), no reflectance
                "abg": set(), "harvey-shack": set(), "k-correlation": set()}


# ---------------------------------------------------------------------------------------------
# parameters: settable only through with_params (a validated copy), assignment raises
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", MODEL_NAMES)
def test_params_item_assignment_raises_and_names_with_params(name):
    m = _model(name)
    p = next(iter(m.params))
    before = dict(m.params)
    for change in (lambda d: d.__setitem__(p, 0.1), lambda d: d.update({p: 0.1}),
                   lambda d: d.pop(p), lambda d: d.__delitem__(p), lambda d: d.clear(),
                   lambda d: d.setdefault("x", 1.0), lambda d: d.popitem()):
        with pytest.raises(TypeError, match=r"read-only.*with_params"):
            change(m.params)
    if m.options:
        opt = next(iter(m.options))
        with pytest.raises(TypeError, match=rf"model options are read-only.*with_params\({opt}="):
            m.options[opt] = "x"
    assert m.params == before


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_attribute_named_like_a_parameter_or_option_raises(name):
    m = _model(name)
    for attr in [*m.params, *m.options]:
        with pytest.raises(AttributeError, match=rf"cannot set '{attr}'.*with_params\({attr}="):
            setattr(m, attr, -1)
        assert attr not in vars(m)
    for attr in ("params", "options"):
        with pytest.raises(AttributeError, match="with_params"):
            setattr(m, attr, {})


def test_assigning_a_parameter_raises_naming_with_params():
    m = rb.model("trowbridge-reitz-1975", e=0.68)
    with pytest.raises(TypeError, match=r"with_params\(e=\.\.\.\)"):
        m.params["e"] = 0.1
    with pytest.raises(AttributeError, match=r"with_params\(e=\.\.\.\)"):
        m.e = -1
    assert m.params["e"] == 0.68 and m.bridf(0.1, 0.1, 0.0) == rb.model("tr75").bridf(0.1, 0.1, 0)
    # the way to change a parameter: a validated copy
    assert m.with_params(e=0.1).params["e"] == 0.1
    with pytest.raises(ValueError, match="'e'"):
        m.with_params(e=-1)


def test_sums_guard_prefixed_and_plain_names():
    s = rb.model("tr75+lambertian")
    for attr in ("tr75_e", "lambertian_rho", "e", "rho", "shadowing"):
        with pytest.raises(AttributeError, match="with_params"):
            setattr(s, attr, 0.5)
    with pytest.raises(TypeError, match="with_params"):
        s.params["lambertian_rho"] = 0.5
    assert isinstance(s.components, tuple)  # no silent append to a sum's parts


def test_read_only_values_still_behave_like_dicts():
    m = rb.model("microfacet", distribution="beckmann")
    assert isinstance(m.params, dict) and isinstance(m.params, ReadOnlyDict)
    d = dict(m.params)
    d["alpha"] = 0.5  # a plain copy is changeable
    assert json.loads(json.dumps(m.params)) == m.params
    assert {**m.params} == m.params and (m.params | {"alpha": 0.5})["alpha"] == 0.5
    for clone in (copy.copy(m.params), copy.deepcopy(m.params), pickle.loads(pickle.dumps(
            m.params))):
        assert clone == m.params and isinstance(clone, ReadOnlyDict)
        with pytest.raises(TypeError):
            clone["alpha"] = 0.5
    assert isinstance(m.parameters, tuple)
    # models themselves still copy and pickle
    for clone in (copy.copy(m), copy.deepcopy(m), pickle.loads(pickle.dumps(m))):
        assert clone.params == m.params and clone.options == m.options
    assert rb.model(m.to_dict()).params == m.params


# ---------------------------------------------------------------------------------------------
# argument errors name the argument, None included; shapes name both arrays
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["theta_i", "theta_r", "phi"])
def test_none_angle_is_named_not_reported_as_nan(which):
    args = {"theta_i": 0.3, "theta_r": 0.4, "phi": 0.0, which: None}
    with pytest.raises(ArgumentError) as exc:
        rb.model("tr75").brdf(**args)
    msg = str(exc.value)
    assert msg.startswith(f"{which} = None:") and "must be a number or an array" in msg, msg
    assert "nan" not in msg and "np.float64" not in msg
    assert exc.value.argument == which


def test_none_inside_an_array_is_named():
    with pytest.raises(ArgumentError, match=r"theta_r = \[0\.1, None\].*found None"):
        rb.model("lambertian").brdf(0.1, [0.1, None], 0.0)


def test_shape_mismatch_names_both_arrays():
    m = rb.model("ts67")
    with pytest.raises(ArgumentError, match=r"theta_i \(3,\) and theta_r \(4,\) do not "
                                            r"broadcast"):
        m.brdf(np.zeros(3), np.zeros(4), 0.0)
    with pytest.raises(ArgumentError, match=r"theta_r \(2, 3\) and phi \(4,\) do not broadcast"):
        m.brdf(0.1, np.zeros((2, 3)), np.zeros(4))
    with pytest.raises(ArgumentError, match=r"theta_i \(3,\) and polarization \(2,\)"):
        m.brdf(np.zeros(3), 0.1, 0.0, polarization=np.zeros(2))


def test_values_shown_as_python_numbers():
    # np.float64 values used to show as "np.float64(nan)"
    with pytest.raises(ArgumentError) as exc:
        rb.model("tr75").brdf(np.array([0.1, np.nan]), 0.2, 0.0)
    assert "theta_i = nan rad" in str(exc.value) and "np.float64" not in str(exc.value)


def test_angle_errors_render_in_degrees_for_the_cli():
    with pytest.raises(ArgumentError) as exc:
        rb.model("tr75").brdf(0.3, 2.0, 0.0)
    err = exc.value
    assert err.unit == "rad" and str(err).startswith("theta_r = 2.0 rad: must be in [0, pi/2]")
    assert err.render({"theta_r": "--theta-r"}).startswith("--theta-r 114.6 (degrees): ")


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_phi_and_gamma_stay_periodic(name):
    m = _model(name)
    base = m.brdf(0.3, 0.5, 0.7, polarization=0.4)
    for k in (-3, 1, 100):
        assert m.brdf(0.3, 0.5, 0.7 + 2 * math.pi * k, polarization=0.4) == pytest.approx(
            base, rel=1e-9)
        assert m.brdf(0.3, 0.5, 0.7, polarization=0.4 + math.pi * k) == pytest.approx(
            base, rel=1e-9)


# ---------------------------------------------------------------------------------------------
# reflectance-like parameters: one domain, [0, 1], in every model
# ---------------------------------------------------------------------------------------------
def test_reflectance_parameters_share_one_domain():
    assert set(REFLECTANCES) == set(MODEL_NAMES)
    for name in MODEL_NAMES:
        specs = _model(name).parameters
        found = {p.name for p in specs if p.kind == "reflectance"}
        assert found == REFLECTANCES[name], name
        for p in specs:
            if p.kind == "reflectance":
                assert p.domain == REFLECTANCE_DOMAIN and p.unit == "1"
                assert 0.0 <= p.bounds[0] < p.bounds[1] <= 1.0


@pytest.mark.parametrize("name, param", [(n, p) for n, ps in REFLECTANCES.items()
                                         for p in sorted(ps)])  # sets: one order everywhere
@pytest.mark.parametrize("bad", [2.0, 1.5, 1.0 + 1e-12, -1e-12, math.nan, math.inf])
def test_reflectance_outside_unit_interval_is_refused_everywhere(name, param, bad):
    # TS67 rho_d=2 and RB08 bulk=2 used to be accepted, Lambertian rho=1.5 refused
    with pytest.raises(ArgumentError, match=rf"parameter '{param}' is outside its physical "
                                            r"domain \[0, 1\]"):
        rb.model(name, **{param: bad})
    with pytest.raises(ArgumentError, match=rf"'{param}'"):
        _model(name).with_params(**{param: bad})


@pytest.mark.parametrize("name, param", [(n, p) for n, ps in REFLECTANCES.items()
                                         for p in sorted(ps)])  # sets: one order everywhere
def test_reflectance_edges_are_accepted(name, param):
    for ok in (0.0, 1.0):
        assert rb.model(name, **{param: ok}).params[param] == ok


def test_scales_that_are_not_reflectances_keep_their_domains():
    assert rb.model("microfacet", ks=5.0).params["ks"] == 5.0  # a free scale of the data
    assert rb.model("ts67", g=40.0).params["g"] == 40.0  # a ratio
    assert rb.model("rb08", rho=1.5).params["rho"] == 1.5  # a lobe width


def test_parameter_errors_name_parameter_and_value():
    with pytest.raises(ArgumentError) as exc:
        rb.model("tr75", e=None)
    assert exc.value.argument == "e" and "'e' cannot be None" in str(exc.value)
    with pytest.raises(ArgumentError, match=r"e = 'wide': parameter 'e' must be a number"):
        rb.model("tr75", e="wide")
    with pytest.raises(ArgumentError, match=r"'e' must be a real number"):
        rb.model("tr75", e=1 + 2j)
    with pytest.raises(ArgumentError, match=r"'k' given without 'n'"):
        rb.model("ts67", n=None, k=0.5)
    assert rb.model("ts67", n=None).params["n"] is None  # optional parts stay switchable


# ---------------------------------------------------------------------------------------------
# Hypothesis: random bad arguments -> ValueError/TypeError naming the argument, nothing else
# ---------------------------------------------------------------------------------------------
BAD_ANGLE = st.one_of(
    st.none(), st.text(max_size=5), st.binary(max_size=3), st.complex_numbers(allow_nan=False),
    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
    st.integers(min_value=10**309, max_value=10**400),
    st.floats(allow_nan=True, allow_infinity=True).filter(
        lambda x: not (0.0 <= x <= HALF_PI)),
    st.lists(st.one_of(st.none(), st.text(max_size=2), st.floats(-1e3, -1e-3)), min_size=1,
             max_size=3),
    st.just([0.1, [0.2, 0.3]]), st.just(object()),
)
BAD_PHI = st.one_of(
    st.none(), st.text(max_size=5), st.complex_numbers(allow_nan=False),
    st.sampled_from([math.nan, math.inf, -math.inf]), st.just([0.1, None]),
    st.just([[0.1], [0.2, 0.3]]), st.integers(min_value=10**309, max_value=10**400),
)
BAD_POLARIZATION = st.one_of(
    st.text(min_size=1, max_size=6).filter(
        lambda s: s.strip().lower() not in {"s", "p", "te", "tm", "unpolarized", "natural",
                                            "circular", "perpendicular", "parallel"}),
    st.binary(min_size=1, max_size=3), st.complex_numbers(allow_nan=False).filter(
        lambda z: z.imag != 0), st.sampled_from([math.inf, -math.inf]),
    st.dictionaries(st.text(max_size=2), st.integers(), min_size=1, max_size=2),
    st.integers(min_value=10**309, max_value=10**400), st.just([0.1, [0.2]]),
)


@settings(max_examples=80, deadline=None)
@given(name=st.sampled_from(MODEL_NAMES), which=st.sampled_from(["theta_i", "theta_r", "phi"]),
       data=st.data())
def test_hypothesis_bad_angles_raise_naming_the_argument(name, which, data):
    bad = data.draw(BAD_PHI if which == "phi" else BAD_ANGLE)
    args = {"theta_i": 0.3, "theta_r": 0.4, "phi": 0.1, which: bad}
    with pytest.raises((ValueError, TypeError)) as exc:
        _model(name).brdf(**args)
    assert which in str(exc.value), (bad, str(exc.value))


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(MODEL_NAMES), bad=BAD_POLARIZATION)
def test_hypothesis_bad_polarization_raises_naming_it(name, bad):
    with pytest.raises((ValueError, TypeError)) as exc:
        _model(name).brdf(0.3, 0.4, 0.1, polarization=bad)
    assert "polarization" in str(exc.value), (bad, str(exc.value))


BAD_VALUE = st.one_of(
    st.none(), st.text(min_size=1, max_size=4).filter(lambda s: not _is_number(s)),
    st.complex_numbers(allow_nan=False).filter(lambda z: z.imag != 0),
    st.sampled_from([math.nan, math.inf, -math.inf, -1.0, -1e-9, 1e300]),
    st.lists(st.floats(), min_size=2, max_size=3), st.just({}),
    st.integers(min_value=10**309, max_value=10**400),
)


def _is_number(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


@settings(max_examples=120, deadline=None)
@given(name=st.sampled_from(MODEL_NAMES), data=st.data())
def test_hypothesis_bad_parameter_values_raise_naming_the_parameter(name, data):
    m = _model(name)
    param = data.draw(st.sampled_from(m.param_names))
    bad = data.draw(BAD_VALUE)
    spec = next(p for p in m.parameters if p.name == param)
    if bad is None and spec.optional:
        return
    try:
        v = float(bad)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        v = None
    if v is not None and math.isfinite(v):
        lo, lo_inc, hi, hi_inc = spec.domain
        if (v >= lo if lo_inc else v > lo) and (v <= hi if hi_inc else v < hi):
            return  # inside the domain: not a bad value for this parameter
    with pytest.raises(ArgumentError) as exc:
        m.with_params(**{param: bad})
    assert exc.value.argument == param and f"'{param}'" in str(exc.value)


JUNK = st.one_of(st.text(min_size=1, max_size=3), st.just(object()), st.just(math.nan),
                 st.just(1 + 2j), st.just([0.1, None]))
#: bad values of each fit option (None where None is not allowed)
BAD_OPTIONS = {
    "starts": st.one_of(st.none(), JUNK, st.integers(-5, 0), st.just(2.5)),
    "screen": st.one_of(st.none(), JUNK, st.integers(-5, -1)),
    "subsample": st.one_of(JUNK, st.integers(-5, 0)),
    "max_nfev": st.one_of(JUNK, st.integers(-5, 0)),
    "seed": st.one_of(JUNK, st.just(2.5)),
    "loss": st.one_of(st.none(), JUNK, st.just(["log"])),
    "nonfinite": st.one_of(st.none(), JUNK, st.just({})),
    "negative": st.one_of(st.none(), JUNK, st.just({})),
    "aperture": st.one_of(JUNK, st.just(-0.1), st.just(HALF_PI), st.just(10**400)),
    "aperture_points": st.one_of(st.none(), JUNK, st.sampled_from([-3, 0, 8, 19.5, True])),
    "weights": st.one_of(JUNK, st.just([-1.0, 1.0, 1.0, 1.0]), st.just([1.0, 2.0])),
    "bounds": st.one_of(JUNK, st.just({"e": (0, 1)}), st.just({"rho": "x"}),
                        st.just({"rho": (0.5, 0.1)}), st.just({"rho": (-1, 0.5)})),
    "fix": st.one_of(st.just(["e"]), st.just(5), st.just(["rho"])),
    "scale": st.one_of(JUNK, st.just(0.0), st.just(-2.0), st.just(math.inf)),
    "theta_r_max": st.one_of(JUNK, st.just(-0.1), st.just(HALF_PI + 0.01), st.just(True)),
    "source_exclusion": st.one_of(JUNK, st.just(-0.1), st.just(4.0), st.just(math.inf)),
}


@settings(max_examples=80, deadline=None)
@given(data=st.data(), option=st.sampled_from(sorted(BAD_OPTIONS)))
def test_hypothesis_bad_fit_options_raise_naming_the_option(data, option):
    bad = data.draw(BAD_OPTIONS[option])
    meas = Measurement([0.1, 0.2, 0.3, 0.4], [0.2, 0.3, 0.4, 0.5], [0.0, 0.0, 1.0, 2.0],
                       [0.1, 0.1, 0.1, 0.1])
    kw = {option: bad}
    if option == "aperture_points":
        kw["aperture"] = 0.01  # the rule's size is checked where there is an aperture
    with pytest.raises((ValueError, TypeError)) as exc:
        rb.fit(rb.model("lambertian"), meas, starts=1, progress=False, **kw)
    assert option in str(exc.value), (option, bad, str(exc.value))


# ---------------------------------------------------------------------------------------------
# messages, library side: ArgumentError worded for Python by str, for the CLI by render
# ---------------------------------------------------------------------------------------------
CLI = {"negative": "--negative", "nonfinite": "--nonfinite", "bounds": "--bounds",
       "aperture": "--aperture", "starts": "--starts"}


def _meas(values, **kw):
    ti, tr = np.meshgrid(np.radians([10, 30, 50]), np.radians([0, 20, 40, 60]), indexing="ij")
    return Measurement(ti.ravel(), tr.ravel(), np.zeros(ti.size), values, **kw)


def test_negative_values_for_the_log_loss_name_the_option():
    v = np.full(12, 0.1)
    v[2] = -0.01
    with pytest.raises(ArgumentError) as exc:  # keep: asked for, and impossible
        rb.fit("lambertian", _meas(v, meta={"file": "x.csv"}), loss="log", negative="keep",
               progress=False)
    err = exc.value
    assert err.argument == "negative" and str(err).endswith("; pass negative='drop'")
    assert "x.csv" in str(err)
    assert err.render(CLI).endswith("; pass --negative drop") and "negative=" not in \
        err.render(CLI)
    # the default, negative="auto": dropped and counted
    res = rb.fit("lambertian", _meas(v), loss="log", starts=1, progress=False)
    assert res.channels[0].excluded["negative"] == 1 and res.options["negative"] == "drop"


def test_nonfinite_values_name_the_option():
    v = np.full(12, 0.1)
    v[3] = np.nan
    with pytest.raises(ArgumentError) as exc:
        rb.fit("lambertian", _meas(v), progress=False)
    assert str(exc.value).endswith("; pass nonfinite='drop'")
    assert exc.value.render(CLI).endswith("; pass --nonfinite drop")


def test_start_outside_bounds_names_the_bounds_for_each_interface():
    with pytest.raises(ArgumentError) as exc:
        rb.fit(rb.model("ts67", g=60.0), _meas(np.full(12, 0.1)), progress=False)
    err = exc.value
    assert "starting value g = 60 is outside its bounds [0, 50]" in str(err)
    assert str(err).endswith("pass bounds={'g': (low, high)}")
    assert err.render(CLI).endswith("pass --bounds g=LOW:HIGH") and "{" not in err.render(CLI)


def test_bounds_must_stay_in_the_physical_domain():
    # a reflectance may not be searched beyond 1: the fit would hit values the model refuses
    with pytest.raises(ArgumentError, match=r"bounds of 'rho' \[0, 2\] leave its physical "
                                            r"domain \[0, 1\]"):
        rb.fit("lambertian", _meas(np.full(12, 0.1)), bounds={"rho": (0.0, 2.0)},
               progress=False)
    with pytest.raises(ArgumentError, match=r"bounds of 'rho' must be two numbers"):
        rb.fit("lambertian", _meas(np.full(12, 0.1)), bounds={"rho": "wide"}, progress=False)


def test_aperture_error_in_radians_for_python_degrees_for_the_cli():
    with pytest.raises(ArgumentError) as exc:
        rb.fit("lambertian", _meas(np.full(12, 0.1)), aperture=2.0, progress=False)
    err = exc.value
    assert str(err).startswith("aperture = 2.0 rad: ") and "90 deg" in str(err)
    assert err.render(CLI).startswith("--aperture 114.6 (degrees): ")


def test_bad_starts_names_the_option():
    with pytest.raises(ArgumentError) as exc:
        rb.fit("lambertian", _meas(np.full(12, 0.1)), starts=0, progress=False)
    assert exc.value.argument == "starts" and "starts must be >= 1" in str(exc.value)

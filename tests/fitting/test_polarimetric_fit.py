"""Polarimetric data: Mueller elements in a Measurement, in CSV, and rb.fit.

The acceptance test: synthetic Mueller data of a rough metal (microfacet, Beckmann alpha = 0.3,
n + ik = 0.2 + 3i) with noise. Its unpolarized BRDF hardly tells n from k: a second index with the
same normal-incidence reflectance (TR75 Eq. 22, docs/models.md §1.4) changes m00 by a few per cent
but the normalized elements by tens of per cent. The fit of m00 alone finds n and k almost fully
correlated; the fit of all the elements recovers both (within 3 standard errors) with a small
correlation. Every number compared comes from the fits themselves.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting.kinds.polarimetric import MuellerFitResult
from roughbrdf.io import FormatError
from roughbrdf.measurement import MUELLER_ELEMENTS, Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

TRUE = {"alpha": 0.3, "n": 0.2, "k": 3.0}
SIGMA_M00 = 0.02  # relative noise of m00
SIGMA_NORM = 0.01  # absolute noise of the normalized elements
FIT = {"fix": ["ks"], "bounds": {"n": (0.05, 5.0)}, "weights": "uncertainty", "starts": 4}


def _metal(**kw: float) -> rb.models.Model:
    return rb.model("microfacet", distribution="beckmann", **{**TRUE, **kw})


def _same_r0_k(n: float) -> float:
    """The k giving index n + ik the normal-incidence reflectance of the true index
    (TR75 Eq. 22: R(0) = ((n - 1)^2 + k^2)/((n + 1)^2 + k^2))."""
    r0 = ((TRUE["n"] - 1) ** 2 + TRUE["k"] ** 2) / ((TRUE["n"] + 1) ** 2 + TRUE["k"] ** 2)
    return math.sqrt((r0 * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r0))


PARTNER = {"n": 0.5, "k": _same_r0_k(0.5)}


def _geometry(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Samples around the specular lobe at 20, 45 and 70 deg incidence, where m00 is within
    1e-3 of its peak (a goniometer's dynamic range)."""
    rng = np.random.default_rng(seed)
    ti = np.repeat(np.radians([20.0, 45.0, 70.0]), 40)
    tr = np.clip(ti + rng.normal(0.0, math.radians(20.0), ti.size), 0.0, math.radians(85.0))
    ph = np.mod(rng.normal(0.0, math.radians(40.0), ti.size) + math.pi, 2 * math.pi) - math.pi
    m00 = _metal().brdf(ti, tr, ph)
    keep = m00 > 1e-3 * m00.max()
    return ti[keep], tr[keep], ph[keep]


def _synthetic(seed: int = 0, kind: str = "normalized") -> Measurement:
    ti, tr, ph = _geometry(seed)
    rng = np.random.default_rng(seed + 100)
    mat = _metal().mueller(ti, tr, ph).reshape(-1, 16)
    norm = mat[:, 1:] / mat[:, :1]
    m00 = mat[:, 0] * (1.0 + SIGMA_M00 * rng.standard_normal(ti.size))
    elements = norm + SIGMA_NORM * rng.standard_normal(norm.shape)
    unc = np.column_stack([SIGMA_M00 * mat[:, 0], np.full(norm.shape, SIGMA_NORM)])
    meas = Measurement(ti, tr, ph, np.column_stack([m00, elements]),
                       channels=list(MUELLER_ELEMENTS), mueller="normalized", uncertainty=unc,
                       meta={"sample": "synthetic rough metal"})
    if kind == "absolute":
        absolute = meas.mueller_array("absolute").reshape(-1, 16)
        unc_abs = unc.copy()
        unc_abs[:, 1:] *= m00[:, None]
        meas = Measurement(ti, tr, ph, absolute, channels=list(MUELLER_ELEMENTS),
                           mueller="absolute", uncertainty=unc_abs)
    return meas


@pytest.fixture(scope="module")
def data() -> Measurement:
    return _synthetic()


@pytest.fixture(scope="module")
def fits(data: Measurement) -> tuple[rb.FitResult, rb.FitResult]:
    """The Mueller fit and the fit of m00 alone, both from the same-R(0) partner index."""
    start = _metal(**PARTNER)
    pol = rb.fit(start, data, **FIT)
    m00 = data.select_channel("m00")
    plain = Measurement(m00.theta_i, m00.theta_r, m00.phi, m00.values,
                        uncertainty=m00.uncertainty)
    return pol, rb.fit(start, plain, **FIT)


# --------------------------------------------------------------------------------------------
# acceptance: n and k from polarimetric data, not from the unpolarized BRDF
# --------------------------------------------------------------------------------------------
def test_the_two_indices_are_nearly_the_same_unpolarized(data):
    ti, tr, ph = data.theta_i, data.theta_r, data.phi
    truth = _metal().mueller(ti, tr, ph).reshape(-1, 16)
    other = _metal(**PARTNER).mueller(ti, tr, ph).reshape(-1, 16)
    d00 = np.max(np.abs(other[:, 0] / truth[:, 0] - 1.0))
    dnorm = np.max(np.abs(other[:, 1:] / other[:, :1] - truth[:, 1:] / truth[:, :1]))
    assert d00 < 0.05  # a few per cent: 2 sigma of the m00 noise
    assert dnorm > 0.3  # 30 sigma of the elements' noise


def test_mueller_fit_recovers_n_and_k(fits):
    pol, plain = fits
    c, u = pol["mueller"], plain[0]
    assert c.success and not c.at_bound
    for name in ("n", "k", "alpha"):
        assert abs(c.params[name] - TRUE[name]) < 3.0 * c.stderr[name], name
    assert 0.8 < c.redchi < 1.25  # weights from the uncertainties: a proper chi-square
    corr_pol, corr_plain = c.correl["n"]["k"], u.correl["n"]["k"]
    print(f"Mueller fit: n = {c.params['n']:.4f} +/- {c.stderr['n']:.4f}, "
          f"k = {c.params['k']:.4f} +/- {c.stderr['k']:.4f}, C(n, k) = {corr_pol:+.3f}; "
          f"m00 alone: n = {u.params['n']:.4f} +/- {u.stderr['n']:.4f}, "
          f"k = {u.params['k']:.4f} +/- {u.stderr['k']:.4f}, C(n, k) = {corr_plain:+.4f}")
    assert abs(corr_plain) > 0.98  # the unpolarized fit cannot separate n and k
    assert abs(corr_pol) < 0.3
    assert u.stderr["n"] > 5 * c.stderr["n"] and u.stderr["k"] > 20 * c.stderr["k"]


def test_result_report_and_json_say_what_was_fitted(fits, tmp_path):
    pol, _ = fits
    assert isinstance(pol, MuellerFitResult) and [c.channel for c in pol] == ["mueller"]
    c = pol["mueller"]
    assert c.elements == list(MUELLER_ELEMENTS[1:])
    n = c.data.size
    assert c.n_points == 16 * n and c.residual.size == 16 * n
    assert c.chi2 == pytest.approx(c.chi2_m00 + c.chi2_normalized)
    assert c.normalized_fitted.shape == (n, 15) and c.fitted.shape == (n,)
    text = pol.report()
    assert ("polarimetric       = Mueller elements (normalized, basis psps): m00 by the loss "
            "above, the 15 other elements as m_ij/m00") in text
    assert "[[Mueller elements]]" in text and "[[Channel mueller]]" in text
    content = json.loads(pol.to_json())
    mu = content["options"]["mueller"]
    assert mu["kind"] == "normalized" and mu["basis"] == "psps" and len(mu["elements"]) == 15
    assert mu["polarimetric_weight"] == 1.0
    chan = content["channels"][0]
    assert chan["channel"] == "mueller" and set(chan["mueller"]["rms_normalized"]) >= {"m22"}
    assert "chi2_normalized" in chan["metrics"]
    written = pol.save(tmp_path / "out")
    assert [p.name for p in written] == ["fit.json", "report.txt", "fit_mueller.png"]


def test_absolute_elements_fit_like_normalized(data, fits):
    # the same numbers stored as absolute elements: unweighted, the same residuals (to
    # round-off); weighted, the uncertainties of m_ij/m00 are propagated from those of m_ij and
    # m00 (an extra term), so the optimum moves, well within its standard error
    plain = {k: v for k, v in FIT.items() if k != "weights"}
    absolute = _synthetic(kind="absolute")
    ref = rb.fit(_metal(**PARTNER), data, **plain)
    res = rb.fit(_metal(**PARTNER), absolute, **plain)
    for name in ("alpha", "n", "k"):
        assert res.params[name] == pytest.approx(ref.params[name], rel=1e-8)
    weighted, pol = rb.fit(_metal(**PARTNER), absolute, **FIT), fits[0]
    for name in ("alpha", "n", "k"):
        assert abs(weighted.params[name] - pol.params[name]) < 0.1 * pol.stderr[name]


def test_relative_m00_still_fixes_the_index(data):
    # m00 known only up to a scale (relative data): K is free, the elements fix n and k
    rel = Measurement(data.theta_i, data.theta_r, data.phi,
                      data.values * np.r_[7.3, np.ones(15)], channels=data.channels,
                      quantity="relative", mueller="normalized",
                      uncertainty=data.uncertainty * np.r_[7.3, np.ones(15)])
    res = rb.fit(_metal(**PARTNER), rel, **FIT)
    c = res["mueller"]
    assert c.free_scale and c.scale == pytest.approx(1 / 7.3, rel=0.01)
    for name in ("n", "k"):
        assert abs(c.params[name] - TRUE[name]) < 3.0 * c.stderr[name]


def test_partial_polarimeter_and_weight(data):
    # only the first row and m22/m33 (a linear-analyzer instrument), unweighted, weight 2
    sub = data.select_channels(["m00", "m01", "m02", "m22", "m33"])
    res = rb.fit(_metal(**PARTNER), sub, fix=["ks"], bounds={"n": (0.05, 5.0)}, starts=4,
                 polarimetric_weight=2.0)
    c = res["mueller"]
    assert c.elements == ["m01", "m02", "m22", "m33"] and c.polarimetric_weight == 2.0
    assert c.n_points == 5 * c.data.size
    assert abs(c.params["n"] - TRUE["n"]) < 0.05 and abs(c.params["k"] - TRUE["k"]) < 0.1


def test_samples_left_out_and_refusals(data):
    bad = data.values.copy()
    bad[0, 0] = -1.0  # m00 <= 0: the normalized elements mean nothing there
    bad[1, 5] = np.nan
    meas = Measurement(data.theta_i, data.theta_r, data.phi, bad, channels=data.channels,
                       mueller="normalized")
    with pytest.raises(ArgumentError) as err:
        rb.fit(_metal(), meas, fix=["ks"], starts=1)
    assert err.value.argument == "negative" and err.value.fix == "drop"
    with pytest.raises(ArgumentError) as err:
        rb.fit(_metal(), meas, fix=["ks"], starts=1, negative="drop")
    assert err.value.argument == "nonfinite"
    res = rb.fit(_metal(), meas, fix=["ks"], starts=1, negative="drop", nonfinite="drop")
    assert res["mueller"].excluded["negative"] == 1 and res["mueller"].excluded["nonfinite"] == 1
    assert res["mueller"].data.size == data.n_samples - 2
    for kwargs, argument in [({"channel": "m01"}, "channel"), ({"joint": True}, "joint"),
                             ({"polarimetric_weight": -1.0}, "polarimetric_weight")]:
        with pytest.raises(ArgumentError) as err:
            rb.fit(_metal(), data, fix=["ks"], starts=1, **kwargs)
        assert err.value.argument == argument
    with pytest.raises(ArgumentError) as err:
        rb.fit("auto", data)
    assert err.value.argument == "model"
    plain = Measurement(data.theta_i, data.theta_r, data.phi, data.values[:, 0])
    with pytest.raises(ArgumentError) as err:
        rb.fit(_metal(), plain, polarimetric_weight=2.0)
    assert err.value.argument == "polarimetric_weight"


# --------------------------------------------------------------------------------------------
# the Measurement and the CSV format
# --------------------------------------------------------------------------------------------
def test_measurement_declaration():
    one = dict(theta_i=[0.3], theta_r=[0.3], phi=[0.0])
    m = Measurement(**one, values=[[2.0, 0.5, -1.5]], channels=["m00", "m22", "m01"],
                    mueller="Normalized")
    assert m.mueller == "normalized" and m.mueller_basis == "psps" and m.is_mueller
    full = m.mueller_array("absolute")[0]
    assert full[0, 0] == 2.0 and full[2, 2] == 1.0 and full[0, 1] == -3.0
    assert np.isnan(full[3, 3])
    assert m.mueller_array("normalized")[0, 0, 0] == 1.0
    assert m.validate()["m01"]["beyond_m00"] == 1  # |m01/m00| = 1.5 > 1: not physical
    assert "1 with |m01| > m00" in m.summary()
    assert m.as_quantity("brdf_cos").values[0].tolist() == pytest.approx(
        [2.0 * math.cos(0.3), 0.5, -1.5])  # only m00 carries the unit
    with pytest.raises(ArgumentError) as err:
        m.select_channel("m22")
    assert err.value.argument == "channel"
    assert m.select_channels(["m00", "m22"]).channels == ["m00", "m22"]
    for kwargs, argument in [
        ({"channels": ["m00", "465nm"], "mueller": "absolute"}, "channels"),
        ({"channels": ["m01", "m10"], "mueller": "absolute"}, "channels"),
        ({"channels": ["m00", "m01"], "mueller": "relative"}, "mueller"),
        ({"channels": ["m00", "m01"], "mueller": "absolute", "mueller_basis": "xy"},
         "mueller_basis"),
        ({"channels": ["m00", "m01"], "mueller_basis": "psps"}, "mueller_basis"),
        ({"channels": ["m00", "m01"], "mueller": "absolute", "polarization": [0.0]},
         "polarization"),
    ]:
        with pytest.raises(ArgumentError) as err:
            Measurement(**one, values=[[1.0, 0.1]], **kwargs)
        assert err.value.argument == argument


def test_csv_round_trip(tmp_path, data):
    path = tmp_path / "mueller.csv"
    rb.write(data, path)
    head = path.read_text().splitlines()[:6]
    assert "# mueller: normalized" in head and "# mueller_basis: psps" in head
    back = rb.read(path)
    assert back.mueller == "normalized" and back.mueller_basis == "psps"
    assert back.channels == data.channels
    assert np.array_equal(back.values, data.values)
    assert np.array_equal(back.uncertainty, data.uncertainty)
    assert "mueller" not in back.meta  # an attribute, not provenance
    again = tmp_path / "again.csv"
    rb.write(back, again)
    assert rb.read(again).mueller == "normalized"
    plain = Measurement([0.1], [0.2], [0.0], [[1.0, 2.0]], channels=["m00", "m01"])
    with pytest.raises(ValueError, match="Mueller element name"):
        rb.write(plain, tmp_path / "plain.csv")


GOOD = """# roughbrdf-csv 1
# angles: deg
# quantity: brdf
# mueller: {kind}
{basis}theta_i,theta_r,phi,{cols}
30,30,0,{vals}
"""


@pytest.mark.parametrize("kind, basis, cols, vals, line, message", [
    (None, "", "m00,m01", "1,0.1", 4, "declare them with a header line '# mueller:"),
    ("absolute", "", "m00,m01,465nm", "1,0.1,2", 5, "not elements: ['465nm']"),
    ("absolute", "", "m01,m10", "1,0.1", 5, "m00 is missing"),
    ("relative", "", "m00,m01", "1,0.1", 4, "is not one of absolute, normalized"),
    ("normalized", "# mueller_basis: sp\n", "m00,m01", "1,0.1", 5, "mueller_basis 'sp'"),
    ("normalized", "", "m00,m01,polarization", "1,0.1,s", 5, "contradict each other"),
    (None, "# mueller_basis: xyxy\n", "brdf", "1", 4, "without '# mueller:"),
])
def test_csv_refuses_contradictions(tmp_path, kind, basis, cols, vals, line, message):
    text = GOOD.format(kind=kind, basis=basis, cols=cols, vals=vals)
    if kind is None:
        text = text.replace("# mueller: None\n", "")
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(FormatError) as err:
        rb.read(path)
    assert message in str(err.value) and err.value.line == line


def test_csv_basis_declared(tmp_path):
    path = tmp_path / "xy.csv"
    path.write_text(GOOD.format(kind="absolute", basis="# Mueller_Basis: XYXY\n",
                                cols="m00,m33", vals="1,-0.5"))
    m = rb.read(path)
    assert m.mueller == "absolute" and m.mueller_basis == "xyxy"
    assert m.mueller_array("normalized")[0, 3, 3] == -0.5


def test_aperture_and_subsample(data):
    # the Mueller matrices are averaged over the aperture stencil like the BRDF; a subsample
    # explores, all samples polish
    res = rb.fit(_metal(**PARTNER), data, aperture=math.radians(0.5), subsample=40, polish=1,
                 **FIT)
    c = res["mueller"]
    assert res.aperture == pytest.approx(math.radians(0.5))
    assert [s["stage"] for s in c.starts].count("full") == 1
    for name in ("n", "k"):
        assert abs(c.params[name] - TRUE[name]) < 3.0 * c.stderr[name]


def test_cli_fit_of_a_mueller_csv(tmp_path, data):
    from typer.testing import CliRunner

    from roughbrdf.cli import app

    path = tmp_path / "metal.csv"
    rb.write(data, path)
    out = tmp_path / "fit"
    result = CliRunner().invoke(app, ["fit", str(path), "--model", "microfacet", "-p",
                                      "distribution=beckmann", "-p", "n=0.5", "-p", "k=6",
                                      "--fix", "ks", "--bounds", "n=0.05:5", "--starts", "2",
                                      "--out", str(out), "--no-plots"])
    assert result.exit_code == 0, result.output
    content = json.loads((out / "fit.json").read_text())
    assert content["options"]["mueller"]["kind"] == "normalized"
    assert abs(content["channels"][0]["params"]["n"] - TRUE["n"]) < 0.05


@pytest.mark.parametrize("name", ["m.astm", "m.dat", "m.bsdf"])
def test_mueller_data_are_written_as_csv_only(tmp_path, data, name):
    # the other formats would write m01..m33 as plain BRDF channels (io.write refuses)
    with pytest.raises(ValueError, match="Mueller elements .* CSV only"):
        rb.write(data, tmp_path / name)
    assert not (tmp_path / name).exists()


def test_albedo_refuses_a_stokes_polarization():
    # the albedo integrates the scalar kernel: a Stokes vector would be dropped silently
    with pytest.raises(ArgumentError, match="Stokes"):
        rb.albedo(rb.model("lambertian"), 0.3,
                  polarization=rb.polarization.Polarization(stokes=[1.0, 1.0, 0.0, 0.0]))


def test_tr75_flat_trough_is_lifted_by_polarimetric_data():
    """TR75's own n-k trough (docs/fitting.md: correlation -0.999 on the silver paint): the
    unpolarized BRDF of TR75 hardly tells n from k, its Mueller matrix does. Synthetic data
    from TR75 (e = 0.25, n = 0.4, k = 1.5, rho_L = 0.06; 2 % noise on m00, 0.01 on the
    normalized elements) fitted from n = 1, k = 0.5: the truth within 4 stderr for the Mueller
    fit; |C(n, k)| and the stderrs of n and k several times larger for m00 alone (the numbers
    are the fits' own: 0.27 against 0.97, stderr of k 0.0014 against 0.027 with seed 3)."""
    truth = rb.model("trowbridge-reitz-1975", e=0.25, n=0.4, k=1.5, rho_L=0.06)
    rng = np.random.default_rng(3)
    ti = np.repeat(np.radians([15.0, 35.0, 55.0, 75.0]), 60)
    tr = np.clip(ti + rng.normal(0, math.radians(20), ti.size), 0, math.radians(85))
    ph = np.mod(rng.normal(0, math.radians(45), ti.size) + math.pi, 2 * math.pi) - math.pi
    mat = truth.mueller(ti, tr, ph).reshape(-1, 16)
    m00 = mat[:, 0] * (1 + 0.02 * rng.standard_normal(ti.size))
    elements = mat[:, 1:] / mat[:, :1] + 0.01 * rng.standard_normal((ti.size, 15))
    unc = np.column_stack([0.02 * mat[:, 0], np.full((ti.size, 15), 0.01)])
    meas = Measurement(ti, tr, ph, np.column_stack([m00, elements]),
                       channels=list(MUELLER_ELEMENTS), mueller="normalized", uncertainty=unc)
    start = truth.with_params(n=1.0, k=0.5)
    opts = {"weights": "uncertainty", "starts": 4, "progress": False}
    pol = rb.fit(start, meas, **opts).channels[0]
    # unconstrained like the Mueller fit (the truth reflects 1.5 at 85 deg; the energy
    # constraint of a plain fit would move it off the trough this test compares)
    plain = rb.fit(start, Measurement(ti, tr, ph, m00, uncertainty=unc[:, 0]), **opts,
                   energy_constraint=False).channels[0]
    for name, true in (("n", 0.4), ("k", 1.5), ("e", 0.25)):
        assert abs(pol.params[name] - true) < 4 * pol.stderr[name], (name, pol.params)
    assert abs(plain.correl["n"]["k"]) > 0.9 > 0.5 > abs(pol.correl["n"]["k"])
    assert plain.stderr["n"] > 4 * pol.stderr["n"] and plain.stderr["k"] > 10 * pol.stderr["k"]

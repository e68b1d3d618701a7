"""The robust loss: soft-L1 on log residuals, from the user's side.

``rb.fit(..., loss="robust")`` minimizes ``sum(w² 2c² (sqrt(1 + r²/c²) - 1))`` with ``r`` the
log residual and ``c = 0.1`` (``docs/fitting.md``, "What is minimized" and "Choosing the loss");
its scale for relative data is the 1-D minimum of that cost.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

import roughbrdf as rb
from roughbrdf.cli import main
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting import LOSSES, Loss
from roughbrdf.quantity import ROBUST_SCALE, relative_scale

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

C = ROBUST_SCALE


def soft_l1(r: np.ndarray) -> np.ndarray:
    """The soft-L1 cost of log residuals ``r`` at the scale ``c``."""
    return 2 * C**2 * (np.sqrt(1 + (r / C) ** 2) - 1)


def test_robust_is_a_loss_that_needs_positive_data():
    assert "robust" in LOSSES and Loss.parse("robust") is Loss.ROBUST
    assert Loss.ROBUST.positive_data and Loss.ROBUST.ratio
    assert C == 0.1
    assert "soft-L1" in Loss.ROBUST.text and "0.1" in Loss.ROBUST.text


def test_the_squared_residual_is_the_soft_l1_cost_of_the_log_residual():
    f = np.ones(9)
    r_log = np.array([-30.0, -3.0, -0.3, -1e-9, 0.0, 1e-9, 0.05, 2.0, 40.0])
    x = np.exp(r_log)
    r_log = np.log(x)                                       # exactly the log loss's residual
    np.testing.assert_array_equal(Loss.LOG.residual(x, f, floor=0.0), r_log)
    r = Loss.ROBUST.residual(x, f, floor=0.0)
    np.testing.assert_allclose(r**2, soft_l1(r_log), rtol=1e-12, atol=1e-15)
    assert np.array_equal(np.sign(r), np.sign(r_log))
    # quadratic near 0 (the log loss), linear far out: r'^2 ~ 2 c |r|
    np.testing.assert_allclose(r[3:6], r_log[3:6], rtol=1e-9)
    assert r[-1] ** 2 == pytest.approx(2 * C * 40.0, rel=0.01)
    # a scale K enters like the log loss's: ln(K x) - ln f
    k = 1.7
    np.testing.assert_allclose(Loss.ROBUST.residual(x, f, k=k, floor=0.0) ** 2,
                               soft_l1(r_log + np.log(k)), rtol=1e-12)


@pytest.mark.parametrize("k", [0.03, 1.0, 12.0])
def test_the_scale_derivative_is_that_of_a_finite_difference(k):
    rng = np.random.default_rng(4)
    f = rng.uniform(0.1, 3.0, 40)
    x = f * np.exp(rng.normal(0.0, 0.5, 40)) / k
    analytic = Loss.ROBUST.scale_derivative(x, f, k, 0.0)
    h = 1e-6 * k
    numeric = (Loss.ROBUST.residual(x, f, k=k + h, floor=0.0)
               - Loss.ROBUST.residual(x, f, k=k - h, floor=0.0)) / (2 * h)
    np.testing.assert_allclose(analytic, numeric, rtol=1e-6)


@pytest.mark.parametrize("weighted", [False, True])
def test_the_closed_form_scale_is_the_minimum_of_the_cost(weighted):
    rng = np.random.default_rng(7)
    model = rng.uniform(0.01, 5.0, 300)
    data = 0.25 * model * np.exp(rng.normal(0.0, 0.05, 300))
    data[:30] *= rng.uniform(5, 50, 30)                     # glints: 10 % outliers
    w = rng.uniform(0.5, 2.0, 300) if weighted else np.ones(300)

    def cost(t):
        return float(np.sum(w**2 * soft_l1(t + np.log(data) - np.log(model))))

    best = minimize_scalar(cost, bounds=(np.log(0.01), np.log(100.0)), method="bounded",
                           options={"xatol": 1e-12}).x
    k = relative_scale(data, model, weights=w if weighted else None, loss="robust")
    assert np.log(k) == pytest.approx(best, abs=1e-7)
    assert k == pytest.approx(4.0, rel=0.02)                # the outliers barely move it
    assert relative_scale(data, model, loss="log") < 3.0     # the log loss's mean does
    # the derivative of the cost in K is 0 there
    r = Loss.ROBUST.residual(data, model, k=k, floor=0.0) * w
    dr = Loss.ROBUST.scale_derivative(data, model, k, 0.0) * w
    assert abs(float(np.dot(r, dr))) < 1e-9 * float(np.dot(r, r))


def _glinting_microfacet(seed: int, quantity: str = "brdf", scale: float = 1.0):
    """A microfacet surface (alpha 0.2, ks 0.5) measured with 2 % noise and 8 % glints."""
    ti, tr, ph = np.meshgrid(np.radians([0, 20, 40]), np.radians(np.arange(0, 80, 4)),
                             np.radians([0, 90, 180]), indexing="ij")
    ti, tr, ph = ti.ravel(), tr.ravel(), ph.ravel()
    truth = rb.model("microfacet").with_params(alpha=0.2, n=1.5, k=0.0, ks=0.5)
    rng = np.random.default_rng(seed)
    x = truth.brdf(ti, tr, ph) * np.exp(0.02 * rng.standard_normal(ti.size))
    glint = rng.random(ti.size) < 0.08
    x[glint] *= rng.uniform(3, 10, glint.sum())
    return rb.Measurement(ti, tr, ph, scale * x[:, None], quantity=quantity)


def test_a_fit_with_outliers_recovers_the_truth_better_than_the_log_loss():
    meas = _glinting_microfacet(3)
    err = {}
    for loss in ("log", "robust"):
        res = rb.fit("microfacet", meas, loss=loss, fix=["n", "k"], starts=2, progress=False)
        assert res.success
        err[loss] = max(abs(res.params["alpha"] - 0.2) / 0.2,
                        abs(res.params["ks"] - 0.5) / 0.5)
    assert err["robust"] < 0.03 < 0.1 < err["log"]           # log: ks about 18 % high


def test_relative_data_get_their_scale_back_despite_outliers():
    meas = _glinting_microfacet(5, quantity="relative", scale=7.0)
    res = rb.fit("microfacet", meas, loss="robust", fix=["n", "k", "ks"], starts=2,
                 progress=False)                             # ks stays at its default, 1
    assert res[0].scale == pytest.approx(1 / (7.0 * 0.5), rel=0.03)
    assert res.params["alpha"] == pytest.approx(0.2, rel=0.03)
    assert "loss               = robust, soft-L1" in res.report()


def test_non_positive_data_are_treated_as_by_the_log_loss():
    meas = _glinting_microfacet(1)
    meas.values[:3, 0] = [0.0, -1e-4, -2e-4]
    with pytest.raises(ArgumentError) as err:
        rb.fit("microfacet", meas, loss="robust", fix=["n", "k"], starts=1, negative="keep",
               progress=False)
    assert err.value.argument == "negative" and "3 are <= 0" in str(err.value)
    res = rb.fit("microfacet", meas, loss="robust", fix=["n", "k"], starts=1, negative="drop",
                 progress=False)
    assert res[0].excluded["negative"] == 3


def test_the_cli_takes_robust_and_lists_it(tmp_path, capsys):
    meas = _glinting_microfacet(2)
    src = tmp_path / "glints.csv"
    rb.write(meas, src)
    code = main(["fit", str(src), "-m", "microfacet", "--loss", "robust", "--starts", "1",
                 "--fix", "n", "--fix", "k", "--out", str(tmp_path / "fit"), "-q"])
    assert code in (0, 1), capsys.readouterr().err     # 1: a search limit, results written
    assert "robust, soft-L1" in (tmp_path / "fit" / "report.txt").read_text()
    assert main(["fit", str(src), "-m", "microfacet", "--loss", "soft", "--out",
                 str(tmp_path / "x")]) == 2
    assert "relative, log, absolute, robust" in capsys.readouterr().err


@pytest.mark.parametrize("r", [0.0, 0.03, -0.1, 0.4, -2.0])
def test_the_curvature_factor_is_the_costs_over_the_gauss_newton_one(r):
    # rho''(r) of the cost sum(r'^2) = soft_l1(r), by central differences, over 2 r'(r)^2
    # (the Gauss-Newton curvature of r'^2), r'(r) from the residual's own finite difference
    h = 1e-4
    rho2 = (soft_l1(np.array([r + h])) - 2 * soft_l1(np.array([r]))
            + soft_l1(np.array([r - h])))[0] / h**2
    res = Loss.ROBUST.residual(np.exp(np.array([r - h, r + h])), np.ones(2), floor=0.0)
    gn = 2 * ((res[1] - res[0]) / (2 * h)) ** 2
    x = np.exp(np.array([r]))
    assert Loss.ROBUST.curvature(x, np.ones(1), 1.0, 0.0)[0] == pytest.approx(rho2 / gn,
                                                                           rel=1e-4)
    for loss in (Loss.LOG, Loss.RELATIVE, Loss.ABSOLUTE):
        assert loss.curvature(x, np.ones(1), 1.0, 0.0).tolist() == [1.0]


def test_the_robust_stderr_is_hubers_variance_of_a_location_estimate():
    # A Lambertian fit of rho by the robust loss is an M-estimate of the location ln rho of
    # the log data: at its optimum sum(psi(r_i)) = 0 and the cost's Hessian is exactly
    # sum(psi'(r_i))/rho^2 (psi = r/s, psi' = 1/s^3, s = sqrt(1 + r^2/c^2)), so the sandwich
    # is Huber's (1981, Robust Statistics, Eq. 6.2.16) with the HC1 factor N/(N - 1):
    # var(rho) = N/(N-1) rho^2 sum(psi^2) / (sum(psi'))^2
    g = [a.ravel() for a in np.meshgrid(np.radians([0, 30, 60]), np.radians(np.arange(0, 81, 5)),
                                         np.radians([0, 90, 180]), indexing="ij")]
    rng = np.random.default_rng(7)
    x = 0.4 / np.pi * np.exp(0.08 * rng.standard_normal(g[0].size))
    x[rng.random(x.size) < 0.1] *= 4.0                       # outliers, where psi' is small
    (c,) = rb.fit("lambertian", rb.Measurement(*g, x), progress=False).channels
    rho = c.params["rho"]
    r = np.log(x) - np.log(rho / np.pi)
    s = np.sqrt(1 + (r / C) ** 2)
    # the optimum: the score is 0 (the Newton step left in ln rho is below 1e-4)
    assert abs(np.sum(r / s) / np.sum(s**-3)) < 1e-4
    n = x.size
    want = np.sqrt(n / (n - 1) * rho**2 * np.sum((r / s) ** 2) / np.sum(s**-3) ** 2)
    assert c.stderr["rho"] == pytest.approx(want, rel=1e-4)
    # the Gauss-Newton bread sum(r'(r)^2) alone would give a smaller error
    gn = np.sqrt(n / (n - 1) * rho**2 * np.sum((r / s) ** 2)
                 / np.sum((1 + s) / (2 * s**2)) ** 2)
    assert gn < 0.9 * want

"""The bounded Levenberg-Marquardt of the polish (``fitting/solvers/bounded.py``) and the polish
rounds
(``fitting/search.polish_fit``); docs/fitting.md, "Polish".

Expected values come from the Karush-Kuhn-Tucker conditions of a bounded least-squares problem,
from closed-form optima (Rosenbrock's residuals, a linear model), and from NumPy's ``lstsq``.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.fitting.solvers import search
from roughbrdf.fitting.solvers.bounded import LAMBDA_MAX, BoundedResult, bounded_lm, bounded_step

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="whole fits of the measured paints: many minutes each in plain Python")


class Residuals:
    """A duck-typed objective (``fun``, ``jac``, ``spec.lower/upper``) that counts calls."""

    def __init__(self, fun, jac, lower, upper):
        self._fun, self._jac = fun, jac
        self.spec = SimpleNamespace(lower=np.asarray(lower, float),
                                    upper=np.asarray(upper, float))
        self.calls = 0

    def fun(self, x):
        self.calls += 1
        return np.asarray(self._fun(np.asarray(x, float)), float)

    def jac(self, x, *_):
        return np.asarray(self._jac(np.asarray(x, float)), float)


def rosenbrock(lower=(-2.0, -2.0), upper=(2.0, 2.0), offset=0.5):
    """Rosenbrock's residuals (10 (y - x^2), 1 - x) plus a constant ``offset``: the unbounded
    minimum is (1, 1) with cost offset^2 / 2."""
    return Residuals(lambda v: [10.0 * (v[1] - v[0] ** 2), 1.0 - v[0], offset],
                     lambda v: [[-20.0 * v[0], 10.0], [-1.0, 0.0], [0.0, 0.0]], lower, upper)


def kkt_violation(jac, f, x, p, lower, upper, damping=None):
    """The largest violation of the optimality conditions of the bounded step: the model's
    gradient is zero for a free variable, >= 0 on its lower bound and <= 0 on its upper one."""
    g = jac.T @ (f + jac @ p) + (0.0 if damping is None else damping * p)
    y, tol = x + p, 1e-9 * (upper - lower)
    at_lo, at_hi = y <= lower + tol, y >= upper - tol
    free = ~(at_lo | at_hi)
    return max(np.max(np.abs(g[free]), initial=0.0), np.max(-g[at_lo], initial=0.0),
               np.max(g[at_hi], initial=0.0))


# --- bounded_step ---------------------------------------------------------------------------


def test_bounded_step_without_active_bounds_is_the_gauss_newton_step():
    rng = np.random.default_rng(1)
    jac, f = rng.normal(size=(40, 5)), rng.normal(size=40)
    x, lo, hi = np.zeros(5), np.full(5, -1e6), np.full(5, 1e6)
    p, pred = bounded_step(jac, f, x, lo, hi)
    expect = np.linalg.lstsq(jac, -f, rcond=None)[0]  # the unbounded Gauss-Newton step
    np.testing.assert_allclose(p, expect, rtol=1e-9, atol=1e-12)
    # the predicted decrease is 1/2 |f|^2 - 1/2 |f + J p|^2, computed directly
    assert pred == pytest.approx(0.5 * f @ f - 0.5 * np.sum((f + jac @ p) ** 2), rel=1e-12)


def test_bounded_step_with_damping_is_the_ridge_step():
    rng = np.random.default_rng(2)
    jac, f = rng.normal(size=(30, 4)), rng.normal(size=30)
    d = np.array([0.5, 1.0, 2.0, 4.0])
    p, _ = bounded_step(jac, f, np.zeros(4), np.full(4, -1e6), np.full(4, 1e6), d)
    # normal equations of 1/2 |f + J p|^2 + 1/2 sum(d p^2)
    np.testing.assert_allclose(p, np.linalg.solve(jac.T @ jac + np.diag(d), -jac.T @ f),
                               rtol=1e-9)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("damped", [False, True])
def test_bounded_step_satisfies_the_kkt_conditions(seed, damped):
    rng = np.random.default_rng(seed)
    jac, f = rng.normal(size=(25, 6)), 3.0 * rng.normal(size=25)
    lo, hi = -rng.uniform(0.0, 0.3, 6), rng.uniform(0.0, 0.3, 6)  # tight: some bounds bind
    x = rng.uniform(lo, hi)
    x[0] = lo[0]  # a variable already on its bound
    d = rng.uniform(0.1, 1.0, 6) if damped else None
    p, pred = bounded_step(jac, f, x, lo, hi, d)
    eps = 1e-15  # x + (lower - x) is lower only to round-off; bounded_lm clips x + p
    assert np.all(x + p >= lo - eps) and np.all(x + p <= hi + eps)
    assert kkt_violation(jac, f, x, p, lo, hi, d) < 1e-8 * np.abs(jac.T @ f).max()
    assert pred >= 0.0  # p = 0 is feasible, so the optimum is no worse


def test_bounded_step_documented_example_lands_on_the_bound():
    jac = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    f = np.array([-2.0, 1.0, 1.0])
    p, pred = bounded_step(jac, f, np.zeros(2), np.array([-5.0, -0.5]), np.full(2, 5.0))
    assert p[1] == -0.5  # exactly on the bound, not near it
    assert p[0] == pytest.approx(2.0, abs=1e-12)
    # 1/2 (4 + 1 + 1) - 1/2 (0 + 0.25 + 1)
    assert pred == pytest.approx(2.375, abs=1e-12)


def test_bounded_step_with_coincident_bounds_and_an_ineffective_parameter():
    jac = np.array([[1.0, 0.0, 2.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]])  # column 1 is zero
    f = np.array([1.0, -2.0, 0.5])
    lo, hi = np.array([-1.0, -1.0, 0.3]), np.array([1.0, 1.0, 0.3])  # x3 cannot move
    p, pred = bounded_step(jac, f, np.array([0.0, 0.0, 0.3]), lo, hi)
    assert np.isfinite(p).all() and np.isfinite(pred)
    assert p[2] == 0.0
    assert pred >= 0.0


# --- bounded_lm -----------------------------------------------------------------------------


def test_bounded_lm_finds_the_interior_minimum():
    obj = rosenbrock()
    out = bounded_lm(obj, np.array([-1.2, 1.0]), 1e-12)
    assert isinstance(out, BoundedResult) and out.status == 1 and out.success
    np.testing.assert_allclose(out.x, [1.0, 1.0], atol=1e-6)
    assert out.cost == pytest.approx(0.125, rel=1e-10)  # offset^2 / 2
    assert out.nfev == obj.calls


def test_bounded_lm_lands_exactly_on_an_active_bound():
    # with x <= 0.5 the minimum is x = 0.5, y = x^2 = 0.25 (the first residual vanishes)
    from scipy.optimize import least_squares

    obj = rosenbrock(upper=(0.5, 2.0))
    out = bounded_lm(obj, np.array([-1.2, 1.0]), 1e-12)
    assert out.status == 1
    assert out.x[0] == 0.5  # on the bound itself
    assert out.x[1] == pytest.approx(0.25, abs=1e-9)
    # trf (the explore stage) keeps its iterates strictly inside the box
    trf = least_squares(obj.fun, [-1.2, 1.0], jac=obj.jac, method="trf",
                        bounds=(obj.spec.lower, obj.spec.upper), ftol=1e-12, xtol=1e-12)
    assert trf.x[0] < 0.5
    assert out.cost <= trf.cost


def test_bounded_lm_budget_zero_cost_and_start_outside_the_box():
    out = bounded_lm(rosenbrock(), np.array([-1.2, 1.0]), 1e-12, max_nfev=3)
    assert out.status == 0 and out.nfev == 3 and not out.success
    assert "max_nfev" in out.message
    start_cost = 0.5 * float(np.sum(rosenbrock().fun(np.array([-1.2, 1.0])) ** 2))
    assert out.cost <= start_cost  # only decreases are accepted
    assert bounded_lm(rosenbrock(), np.array([-1.2, 1.0]), 1e-12, max_nfev=10).cost < start_cost
    exact = rosenbrock(offset=0.0)  # zero residual at (1, 1)
    out = bounded_lm(exact, np.array([0.5, 0.5]), 1e-12)
    assert out.status in (1, 2) and out.cost < 1e-20
    # a start beyond the box is clipped into it, never evaluated outside
    out = bounded_lm(rosenbrock(upper=(0.5, 2.0)), np.array([3.0, 9.0]), 1e-12)
    assert out.x[0] <= 0.5 and out.x[1] <= 2.0


def test_bounded_lm_reports_a_point_where_no_step_helps():
    # residuals that cannot be lowered from the start by any representable step: a Jacobian
    # that points the wrong way, so every trial step raises the cost until lambda > LAMBDA_MAX
    obj = Residuals(lambda v: [1.0 + v[0] ** 2], lambda v: [[-1.0]], [-1.0], [1.0])
    out = bounded_lm(obj, np.array([0.0]), 1e-12)
    assert out.status == 3 and not out.success and out.x[0] == 0.0 and out.cost == 0.5
    assert LAMBDA_MAX > 1e10


def test_bounded_lm_leaves_an_ineffective_parameter_alone():
    obj = Residuals(lambda v: [v[0] - 0.3, 2.0 * (v[0] - 0.3), 0.1],
                    lambda v: [[1.0, 0.0], [2.0, 0.0], [0.0, 0.0]], [-1.0, -1.0], [1.0, 1.0])
    out = bounded_lm(obj, np.array([0.9, 0.7]), 1e-12)
    assert out.status == 1
    # converged: 1/2 (1 + 4) dx^2 <= 1e-12 cost (cost = 0.005), so |dx| <= 4.5e-8
    assert out.x[0] == pytest.approx(0.3, abs=4.5e-8) and out.x[1] == 0.7


# --- polish_fit: the rounds of trf and the bounded steps -----------------------------------


def test_polish_that_converges_in_trf_is_one_least_squares_call():
    from roughbrdf.fitting import ChannelData, Objective, ObjectiveSpec

    t_i, t_r, p = np.meshgrid(np.radians([10, 40, 70]), np.radians(np.arange(0, 86, 10)),
                              np.radians([0, 90, 180]), indexing="ij")
    truth = rb.model("torrance-sparrow-1967", n=None, k=None, g=2.0, c=0.08, rho_d=0.3)
    data = ChannelData.from_arrays(t_i.ravel(), t_r.ravel(), p.ravel(),
                                   truth.brdf(t_i.ravel(), t_r.ravel(), p.ravel()))
    start = rb.model("torrance-sparrow-1967", n=None, k=None, g=1.0, c=0.1, rho_d=0.3)
    spec = ObjectiveSpec(start, ["g", "c"], [0.0, 0.0], [10.0, 1.0], loss="absolute",
                         free_scale=False, fixed_scale=1.0)
    obj = Objective(spec, data)
    x0 = np.array([1.0, 0.1])
    polished = search.polish_fit(obj, x0, None)
    single = search.local_fit(obj, x0, search.POLISH_TOL, None)
    assert polished.status > 0 and single.nfev < search.POLISH_ROUND
    assert np.array_equal(polished.x, single.x)  # the same call: bit for bit
    np.testing.assert_allclose(polished.x, [2.0, 0.08], rtol=1e-6)  # the model's own values


def test_polish_hands_a_creeping_fit_to_the_bounded_steps(monkeypatch):
    monkeypatch.setattr(search, "POLISH_ROUND", 5)  # trf needs more than 5 here
    obj = rosenbrock(upper=(0.5, 2.0))
    out = search.polish_fit(obj, np.array([-1.2, 1.0]), None)
    assert isinstance(out, BoundedResult) and out.status == 1
    # converged at POLISH_TOL: 1/2 (10 dy)^2 <= 1e-8 * cost (cost = 0.125), so |dy| <= 5e-6
    assert out.x[0] == 0.5 and out.x[1] == pytest.approx(0.25, abs=5e-6)


def test_polish_respects_max_nfev_over_all_rounds(monkeypatch):
    monkeypatch.setattr(search, "POLISH_ROUND", 2)
    obj = rosenbrock(upper=(0.5, 2.0))
    out = search.polish_fit(obj, np.array([-1.2, 1.0]), 7)
    assert obj.calls <= 7
    assert out.status == 0 or out.success


def test_rb08_paint_polish_reaches_the_bound_trf_crept_towards(shared_data):
    """C8_Silver 465 nm, RB08 with the literal normalization (docs/fitting.md, "Polish"): trf
    polishes alone crept towards n_eff = 5 and stopped by their ftol test short of it, after
    some 30,000 evaluations (the measurement behind it: CHANGELOG). With the bounded steps
    n_eff does not stop short of its bound: it is on it exactly or clear of it (more than 1 %
    of its box away), within half the evaluations. Which basin the 8 starts find (n_eff on its
    bound 5 at chi2 = 239.358, or 4.81 at 239.61) depends on the search, not on the polish."""
    if "renhorn-boreman-2008" not in rb.available():
        pytest.skip("RB08 model not available")
    meas = rb.read(shared_data / "minidiff" / "C8_Silver.astm")
    # loss="relative", no energy constraint: the unconstrained relative loss of the
    # measurement behind it; this tests the polish, not the constraint
    ch = rb.fit(rb.model("renhorn-boreman-2008", normalization="literal"), meas, channel=0,
                loss="relative", energy_constraint=False, progress=False).channels[0]
    assert ch.success
    assert ch.chi2 < 239.7  # one of the two basins above, not a point on the way
    # n_eff, which trf crept towards its bound 5: on it exactly, or clear of it (an optimum
    # inside; other parameters may have a genuine optimum just inside a bound, as retro 6e-4)
    lo, hi = ch.bounds["n_eff"]
    assert ch.params["n_eff"] == hi or hi - ch.params["n_eff"] > 0.01 * (hi - lo)
    assert ch.nfev < 15000


def test_snap_tries_a_neutral_value_only_where_the_cost_allows_and_no_bound_is_nearer():
    """``stationary.snap`` with neutral values (``Parameter.neutral``, TR75's ``n = 1``): an end
    on a quartic valley around it moves onto it (the cost rises by ~1e-24, far below
    ``SNAP_COST``); a determined parameter as near it does not (its minimum 2e-3 away: the
    value costs 4e-6 of the cost more, above ``SNAP_COST``); an end farther than ``SNAP_DIST``
    of its box is not tried; an end nearer a bound is left to the bound."""
    from roughbrdf.fitting.solvers.stationary import SNAP_COST, SNAP_DIST, snap

    lo, hi, pts = np.zeros(1), np.full(1, 2.0), np.array([1.0])
    quartic = lambda x: float(1.0 + (x[0] - 1.0) ** 4)  # noqa: E731
    x, c, n = snap(np.array([1.0 + 1e-6]), quartic(np.array([1.0 + 1e-6])), lo, hi, quartic,
                   points=pts)
    assert x[0] == 1.0 and n == 1
    # determined elsewhere: the minimum at 1.002, the cost at 1 is 4e-6 above (> SNAP_COST)
    quad = lambda x: float(1.0 + (x[0] - 1.002) ** 2)  # noqa: E731
    assert 4e-6 > SNAP_COST
    x, c, n = snap(np.array([1.002]), quad(np.array([1.002])), lo, hi, quad, points=pts)
    assert x[0] == 1.002 and n == 1
    # farther than SNAP_DIST of the box (width 2): not tried
    far = 1.0 + 2.0 * SNAP_DIST * 1.5
    assert snap(np.array([far]), quartic(np.array([far])), lo, hi, quartic, points=pts)[2] == 0
    # a neutral value next to a bound: the bound settles the end (tried on 0.0, not 0.001)
    x, _, _ = snap(np.array([1e-9]), 1.0, lo, hi, lambda x: 1.0, points=np.array([0.001]))
    assert x[0] == 0.0


def test_tr75_declares_n_1_its_neutral_value_inside_the_search_box():
    """TR75's ``n = 1`` (with ``k = 0``: F = 0, Fresnel's Eq. with the index matched) is where
    its lobe vanishes: the fit's objective offers it to ``snap``; a box that excludes it, none."""
    from roughbrdf.fitting.problem.objective import ObjectiveSpec

    m = rb.model("tr75", k=0.0)
    assert float(np.max(m.with_params(n=1.0, rho_L=0.0).brdf(*np.radians([[30.0], [30.0],
                                                                          [180.0]])))) == 0.0
    spec = ObjectiveSpec(m, ["e", "n", "k"], [0.02, 0.2, 0.0], [3.0, 5.0, 10.0])
    assert np.isnan(spec.snap_points()[[0, 2]]).all() and spec.snap_points()[1] == 1.0
    assert np.isnan(ObjectiveSpec(m, ["n"], [1.2], [5.0]).snap_points()).all()

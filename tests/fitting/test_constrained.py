"""The constrained Levenberg–Marquardt of the energy refit (``fitting/solvers/constrained.py``).

Expected values come from closed forms (an equality-constrained linear least-squares problem
solved with its Lagrange multiplier) and from another solver (SciPy's SLSQP on the same
quadratic program); the refit's convergence from synthetic TR75 sets whose penalty refit used
to stop on its evaluation budget.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.optimize import minimize

import roughbrdf as rb
from roughbrdf.fitting.results.plausibility import (
    ENERGY_TOLERANCE,
    EXPORT_INCIDENCES_DEG,
    EnergyWarning,
)
from roughbrdf.fitting.solvers.bounded import GaussNewtonModel
from roughbrdf.fitting.solvers.constrained import Limits, constrained_lm, finite_limits, lsi_step

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

THETA = np.radians(EXPORT_INCIDENCES_DEG)
#: the convergence test of tol = 1e-12 bounds the predicted cost decrease by tol * cost: the
#: end point is within about sqrt(tol) (residual units, here those of the parameters) of the
#: optimum
SQRT_TOL = 1e-5


def _slsqp_qp(jac, f, damping, lo, hi, gmat, h):
    """The same step by SciPy's SLSQP (an independent quadratic-programming solver)."""
    def q(p):
        r = f + jac @ p
        return 0.5 * r @ r + 0.5 * np.sum(damping * p * p)

    def grad(p):
        return jac.T @ (f + jac @ p) + damping * p

    cons = [{"type": "ineq", "fun": lambda p: h - gmat @ p, "jac": lambda p: -gmat}]
    res = minimize(q, np.zeros(jac.shape[1]), jac=grad, bounds=list(zip(lo, hi, strict=True)),
                   constraints=cons, method="SLSQP", options={"ftol": 1e-15, "maxiter": 500})
    return res.x


@pytest.mark.parametrize("seed", range(8))
def test_lsi_step_agrees_with_slsqp(seed):
    rng = np.random.default_rng(seed)
    k, m = 4, 3
    jac = rng.standard_normal((12, k))
    f = rng.standard_normal(12) * 3
    damping = np.full(k, 1e-3)
    lo, hi = -np.abs(rng.standard_normal(k)) - 0.2, np.abs(rng.standard_normal(k)) + 0.2
    gmat = rng.standard_normal((m, k))
    h = np.abs(rng.standard_normal(m)) * 0.3  # p = 0 is feasible
    p, mu = lsi_step(GaussNewtonModel.of(jac, f), damping, lo, hi, gmat, h)
    ref = _slsqp_qp(jac, f, damping, lo, hi, gmat, h)
    np.testing.assert_allclose(p, ref, atol=2e-6)
    assert np.all(gmat @ p <= h + 1e-9) and np.all(p >= lo - 1e-12) and np.all(p <= hi + 1e-12)
    # multipliers: non-negative, zero on the inactive rows (complementary slackness)
    assert np.all(mu >= 0) and np.all(mu[gmat @ p < h - 1e-7] < 1e-8)


def test_lsi_step_refuses_conflicting_constraints():
    model = GaussNewtonModel.of(np.eye(2), np.zeros(2))
    # p1 <= -1 and -p1 <= -1 (p1 >= 1): no step satisfies both
    gmat, h = np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-1.0, -1.0])
    assert lsi_step(model, np.full(2, 1e-6), np.full(2, -5.0), np.full(2, 5.0), gmat, h) is None


class _Line:
    """y = a x + b on 5 points, absolute residuals (a linear least-squares problem), with the
    three members :func:`constrained_lm` reads of an Objective: ``spec`` bounds, ``fun``,
    ``jac``."""

    x = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    y = np.array([1.0, 2.9, 5.2, 7.1, 8.8])

    class spec:  # noqa: N801 - stands in for an ObjectiveSpec's bounds
        lower, upper = np.full(2, -10.0), np.full(2, 10.0)

    def fun(self, theta):
        return theta[0] * self.x + theta[1] - self.y

    def jac(self, theta, k=None):
        return np.column_stack([self.x, np.ones_like(self.x)])


def test_constrained_lm_meets_the_lagrange_solution():
    # a + b <= 2; the unconstrained line has a + b = 3.0
    lim = Limits(lambda t: np.array([t[0] + t[1] - 2.0]), lambda t, g: np.array([[1.0, 1.0]]))
    out = constrained_lm(_Line(), lim, np.array([0.0, 0.0]), 1e-12)
    # Lagrange: [A^T A, c; c^T, 0] [t; l] = [A^T y; 2], c = (1, 1)
    a = np.column_stack([_Line.x, np.ones_like(_Line.x)])
    kkt = np.block([[a.T @ a, np.ones((2, 1))], [np.ones((1, 2)), np.zeros((1, 1))]])
    ref = np.linalg.solve(kkt, np.concatenate([a.T @ _Line.y, [2.0]]))[:2]
    assert out.success, out.message
    # converged: the predicted decrease is below tol * cost, the step below ~sqrt(tol)
    np.testing.assert_allclose(out.x, ref, atol=SQRT_TOL)


def test_constrained_lm_from_an_infeasible_start_with_a_bound():
    # start far outside a + b <= 2, with b bounded below by 1.5: the optimum on the constraint
    # and the bound is a = 0.5, b = 1.5
    line = _Line()
    line.spec = type("S", (), {"lower": np.array([-10.0, 1.5]), "upper": np.full(2, 10.0)})
    lim = Limits(lambda t: np.array([t[0] + t[1] - 2.0]), lambda t, g: np.array([[1.0, 1.0]]))
    out = constrained_lm(line, lim, np.array([5.0, 5.0]), 1e-12)
    assert out.success, out.message
    np.testing.assert_allclose(out.x, [0.5, 1.5], atol=SQRT_TOL)


def test_constrained_lm_keeps_an_inactive_constraint_out_of_the_way():
    lim = Limits(lambda t: np.array([t[0] + t[1] - 50.0]), lambda t, g: np.array([[1.0, 1.0]]))
    out = constrained_lm(_Line(), lim, np.array([0.0, 0.0]), 1e-12)
    assert out.success
    np.testing.assert_allclose(out.x, np.polyfit(_Line.x, _Line.y, 1), atol=SQRT_TOL)


def test_finite_limits_counts_overflow_as_violated():
    g = finite_limits(np.array([np.nan, np.inf, -0.5]))
    assert g[0] > 1e3 and g[1] > 1e3 and g[2] == -0.5


def _synthetic_tr75(seed):
    """The catalogue tests' sets: a TR75 truth that gains energy at grazing incidence (albedo
    about 6 at 89 deg), 2 % noise, 32 samples at 20 and 45 deg."""
    rng = np.random.default_rng(seed)
    ti, tr, ph = (a.ravel() for a in np.meshgrid(
        np.radians([20.0, 45.0]), np.radians(np.arange(0.0, 80.0, 10.0)), [0.0, np.pi],
        indexing="ij"))
    m = rb.model("tr75", e=rng.uniform(0.4, 0.9), rho_L=rng.uniform(0.1, 0.4))
    v = m.brdf(ti, tr, ph) * (1 + 0.02 * rng.standard_normal(ti.size))
    return rb.Measurement(ti, tr, ph, v)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_energy_refit_converges_on_small_synthetic_sets(seed):
    # the penalty refit stopped on its budget here ("maximum number of function evaluations")
    meas = _synthetic_tr75(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", EnergyWarning)
        res = rb.fit("tr75", meas, starts=2, progress=False)
    c = res.channels[0]
    assert c.success, c.message
    assert c.energy_constraint is not None and c.energy_constraint.satisfied
    assert rb.albedo(c.model, THETA).max() <= 1 + ENERGY_TOLERANCE
    assert not res.gains_energy

"""``NUMBA_DISABLE_JIT=1`` keeps working: the kernels run as plain Python and give the compiled
numbers (the debugging and coverage mode, ``make test-nojit``).

One subprocess with the JIT off evaluates every registered model, an albedo and one small fit
on synthetic data; this process, with the JIT on (or off, under ``make test-nojit``: then both
sides are plain Python), computes the same and compares. It fails when the plain-Python path
breaks (a part that only compiles, a division that only the compiled code survives, a driver
that no longer falls back to a loop) or drifts from the compiled one. The coated models are
left to ``tests/models/test_coated.py`` (``test_pure_python_mode_agrees``): their first
plain-Python evaluation builds their tables, about 15 s.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from typing import Any

import numpy as np

import roughbrdf as rb
from roughbrdf.fitting.kinds.channels import fit_model
from roughbrdf.fitting.problem.options import FitOptions
from roughbrdf.measurement import Measurement

#: models whose first plain-Python evaluation builds tables (module notes)
SKIPPED = ("coated", "coated-conductor")
#: what a model cannot be evaluated without (K-correlation: the wavelength, in um)
REQUIRED: dict[str, dict[str, float]] = {"k-correlation": {"wavelength": 0.633}}
#: four geometries: normal, oblique, near the specular plane's back, grazing exit
TI = [0.0, 0.3, 1.2, 1.5]
TR = [0.0, 0.4, 1.2, 0.5 * math.pi]
PH = [0.0, 1.0, math.pi, -2.0]
#: the albedo's models, incidences and a coarse quadrature (the same on both sides)
ALBEDO_MODELS = ("trowbridge-reitz-1975", "microfacet", "oren-nayar")
ALBEDO_THETA = [0.3, 1.2]
ALBEDO_GRID = {"n_psi": 16, "n_panels": 6, "order": 6}
#: the small fit: TS67 (no Fresnel factor) on 81 noisy synthetic samples, one start
TS67_TRUE = {"g": 2.0, "c": 0.08, "rho_d": 0.3}
TS67_START = {"g": 0.7, "c": 0.04, "rho_d": 0.6}
FIT_OPTIONS = {"starts": 1, "screen": 4, "polish": 1, "energy_constraint": False}


def _run_all() -> dict[str, Any]:
    """Every figure the test compares, computed in this process (its source is also the
    subprocess's: the same code on both sides)."""
    ti, tr, ph = (np.array(v) for v in (TI, TR, PH))
    models = {}
    for name in rb.available():
        if name in SKIPPED:
            continue
        m = rb.model(name, **REQUIRED.get(name, {}))
        models[name] = [m.brdf(ti, tr, ph).tolist(), m.bridf(ti, tr, ph, "s").tolist()]
    albedo = {name: np.atleast_1d(rb.albedo(rb.model(name), ALBEDO_THETA, **ALBEDO_GRID)).tolist()
              for name in ALBEDO_MODELS}
    g_i, g_r, g_p = np.meshgrid(np.radians([10, 40, 70]), np.radians(np.arange(0, 86, 10)),
                                np.radians([0, 90, 180]), indexing="ij")
    g_i, g_r, g_p = g_i.ravel(), g_r.ravel(), g_p.ravel()
    f = rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_TRUE).brdf(g_i, g_r, g_p)
    noisy = f * (1 + 0.05 * np.random.default_rng(1).standard_normal(f.size))
    meas = Measurement(g_i, g_r, g_p, noisy, quantity="brdf")
    # fit_model without the energy check: rb.fit's albedo at 10 incidences alone is about 7e5
    # model evaluations (~40 s of plain Python); the albedo is compared above
    res = fit_model(rb.model("torrance-sparrow-1967", n=None, k=None, **TS67_START), meas,
                    FitOptions(**FIT_OPTIONS), check_energy=False)
    c = res.channels[0]
    fit = {"params": {k: c.params[k] for k in TS67_TRUE},
           "stderr": {k: c.stderr[k] for k in TS67_TRUE}, "success": bool(res.success)}
    return {"models": models, "albedo": albedo, "fit": fit}


_CHILD = textwrap.dedent("""
    import json, sys
    import numba
    from roughbrdf import _kernels
    assert numba.config.DISABLE_JIT and _kernels.DISABLE_JIT, "the JIT is on"
    sys.path.insert(0, {here!r})
    import test_no_jit
    print(json.dumps(test_no_jit._run_all()))
""")


def test_plain_python_kernels_give_the_compiled_numbers():
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    code = _CHILD.format(here=os.path.dirname(os.path.abspath(__file__)))
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-4000:]
    pure = json.loads(res.stdout.strip().splitlines()[-1])
    here = _run_all()
    assert sorted(pure["models"]) == sorted(here["models"])
    assert len(pure["models"]) >= 9  # every registered model but the coated ones
    for name, (brdf, bridf) in here["models"].items():
        # the compiled kernels fuse a*b + c into one FMA (contract): a few ulp apart at most
        np.testing.assert_allclose(pure["models"][name][0], brdf, rtol=1e-12, err_msg=name)
        np.testing.assert_allclose(pure["models"][name][1], bridf, rtol=1e-12, err_msg=name)
    for name, a in here["albedo"].items():
        np.testing.assert_allclose(pure["albedo"][name], a, rtol=1e-12, err_msg=name)
    # the fit: both succeed and recover the truth; the two searches may take other steps
    # where a cost rounds differently, so they agree within a small part of a standard
    # error, not to the last bit
    assert pure["fit"]["success"] and here["fit"]["success"]
    for k, truth in TS67_TRUE.items():
        p, q, se = pure["fit"]["params"][k], here["fit"]["params"][k], here["fit"]["stderr"][k]
        assert abs(p - q) <= 1e-3 * se, (k, p, q, se)
        assert abs(q - truth) <= 4 * se, (k, q, truth, se)


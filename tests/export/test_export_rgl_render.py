"""A rendered sphere from an RGL file against the model evaluated directly (issue 29).

``scripts/render_rgl.py`` renders a sphere (constant environment and a point light, Mitsuba 3
``scalar_rgb``, ``direct`` integrator) with Mitsuba's ``measured`` plugin reading the exported
file and with a Python Mitsuba BSDF that evaluates the model (``brdf * cos(theta_o)``;
sampling: GGX visible normals and cosine-weighted); ``docs/export.md`` shows the 96 x 96
figure of a shared paint. Here the same code runs small (32 x 32, 16 spp, about 5 s a
render pair) on a synthetic coated model (always) and on the coated fit of C8_Silver at
525 nm that the figure shows (a few seconds to fit; skipped without ../shared/data).

The bound (the issue's): the relative RMSE (``sqrt(mean((a-b)^2)) / mean(b)`` over the pixels
wholly inside the sphere) of rgl against direct is at most twice that of two seeds of the
direct render. Measured with Mitsuba 3.9.1 (2026-12-06, 608 pixels): rgl-vs-direct 0.070
(seed 1), 0.071 (seed 2) and 0.095 (rgl seed 1, direct seed 2: independent noise; the same
seed shares the pixel and emitter samples) against 0.113 between the direct render's seeds: a
ratio of at most 0.84, the bound 2. The means over the sphere agree within 0.4 % (0.2101 and
0.2108).
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from mitsuba_support import mitsuba_variant

import roughbrdf as rb

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="RGL exports and fits: minutes in plain Python")

mi = pytest.importorskip("mitsuba", reason="the mitsuba package (test extra) is not installed "
                         "or cannot be imported on this platform", exc_type=ImportError)

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "render_rgl.py"
MODEL = rb.model("coated", alpha=0.2, n=1.5, rho=0.3)


@pytest.fixture(scope="module")
def render_rgl():
    """``scripts/render_rgl.py`` as a module."""
    spec = importlib.util.spec_from_file_location("render_rgl", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["render_rgl"] = module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop("render_rgl", None)


@pytest.fixture(autouse=True)
def scalar_rgb():
    """Mitsuba's ``scalar_rgb`` for each test, the variant before it restored after."""
    with mitsuba_variant(mi, "scalar_rgb"):
        yield


def test_the_python_plugin_is_the_model_and_agrees_with_the_file(render_rgl, tmp_path):
    """The plugin's ``eval`` is ``brdf * cos(theta_o)`` in the test suite's direction mapping
    (checked against Mitsuba's ``measured`` reading the exported file: median relative
    difference <= 1 %), and ``sample``'s weight is ``eval / pdf`` with ``pdf`` its own."""
    from roughbrdf.export.rgl import to_rgl

    plugin = render_rgl.model_bsdf(MODEL)
    done = to_rgl(MODEL, tmp_path / "m.bsdf")
    measured = mi.load_dict({"type": "measured", "filename": str(done.path)})
    rng = np.random.default_rng(3)
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    got, ref, table = [], [], []
    for _ in range(200):
        ti, to = np.arccos(rng.uniform(math.cos(1.3), 1.0, 2))
        pi, po = rng.uniform(-math.pi, math.pi, 2)
        wi = [math.sin(ti) * math.cos(pi), math.sin(ti) * math.sin(pi), math.cos(ti)]
        wo = [math.sin(to) * math.cos(po), math.sin(to) * math.sin(po), math.cos(to)]
        si.wi = mi.Vector3f(*wi)
        got.append(plugin.eval(ctx, si, mi.Vector3f(*wo))[0])
        table.append(measured.eval(ctx, si, mi.Vector3f(*wo))[0])
        ref.append(render_rgl.model_eval(MODEL, np.array([wi]), np.array([wo]))[0])
        bs, w = plugin.sample(ctx, si, 0.5, mi.Point2f(*rng.uniform(0, 1, 2)))
        f = plugin.eval(ctx, si, bs.wo)[0]
        assert bs.pdf == pytest.approx(plugin.pdf(ctx, si, bs.wo), rel=1e-6)
        assert w[0] == pytest.approx(f / bs.pdf, rel=1e-5)
    got, ref, table = map(np.array, (got, ref, table))
    np.testing.assert_allclose(got, ref, rtol=1e-5)
    # phi = 0 forward: the same mapping as tests/export/test_export_rgl.py (wi at azimuth pi)
    ti, to, phi = render_rgl.angles(np.array([[-0.6, 0, 0.8]]), np.array([[0.6, 0, 0.8]]))
    assert phi[0] == pytest.approx(0.0, abs=1e-12) and ti[0] == pytest.approx(to[0])
    assert np.median(np.abs(table / got - 1)) <= 0.01


def check_bound(c) -> None:
    """The issue's bound on every rgl-direct pair, and what makes the comparison sound."""
    noise = c.table["direct seed 1 vs direct seed 2 (noise)"]
    for pair in ("rgl seed 1 vs direct seed 1", "rgl seed 2 vs direct seed 2",
                 "rgl seed 1 vs direct seed 2"):
        assert c.table[pair] <= 2 * noise, (pair, c.table)
    # the replay found every direction pair the record pass noted
    assert c.notes["direct1_counts"]["misses"] == 0 == c.notes["direct2_counts"]["misses"]
    assert c.notes["mean_rgl"] == pytest.approx(c.notes["mean_direct"], rel=0.01), c.notes
    assert c.notes["pixels"] > 500  # the sphere fills the frame (608 pixels at 32 x 32)


def test_rendered_rgl_file_within_twice_the_seed_noise(render_rgl, tmp_path):
    check_bound(render_rgl.compare(MODEL, size=32, spp=16, folder=tmp_path))


def test_rendered_paint_fit_within_twice_the_seed_noise(render_rgl, shared_data, tmp_path):
    """The figure's material: the coated fit of C8_Silver at 525 nm, its FitResult exported.
    Measured (as above): rgl-vs-direct 0.046 (seed 1), 0.049 (seed 2), 0.091 (independent
    seeds) against 0.098 between the direct render's seeds (ratio <= 0.92); means 0.4684 and
    0.4688. The 96 x 96, 512 spp figures are in docs/export.md."""
    paint = rb.read(shared_data / "minidiff" / "C8_Silver.astm")
    fit = rb.fit("coated", paint, channel="525nm", starts=1, progress=False)
    check_bound(render_rgl.compare(fit.channels[0].model, fit, size=32, spp=16,
                                   folder=tmp_path))

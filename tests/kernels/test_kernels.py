"""The kernel layer: the cache-locator patch, lazily built ufuncs, broadcasting with trailing
output shapes."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf import _kernels
from roughbrdf._kernels import broadcast


def test_cache_locator_patch_is_installed():
    # pyproject.toml bounds numba from above because the cache key that follows the parts is
    # installed through Numba's internal locator list; this fails if a Numba release moves it
    if _kernels.DISABLE_JIT:
        pytest.skip("no compilation, so no cache, under NUMBA_DISABLE_JIT=1")
    from numba.core import caching

    assert _kernels.locator_installed()
    names = [c.__name__ for c in caching.CacheImpl._locator_classes[:3]]
    assert all(n.startswith("Roughbrdf") for n in names), names


def test_cache_key_covers_the_parts():
    # a model kernel's cache key includes a stamp of every module with compiled parts, so an
    # edit of fresnel.py invalidates the TR75 kernel compiled from it
    from roughbrdf._kernels import cache

    files = cache.part_files()
    for part in ("fresnel.py", "geometry.py", "distributions.py", "shadowing.py", "vmath.py"):
        assert any(f.endswith(part) for f in files), part
    assert not any("/models/" in f for f in files)


def test_ufuncs_are_built_on_first_call_not_at_import():
    code = textwrap.dedent("""
        import roughbrdf.fresnel as fr
        from roughbrdf._kernels.compile import LazyUfunc
        lazy = [v for v in vars(fr).values() if isinstance(v, LazyUfunc)]
        assert lazy, "no lazily built ufuncs found"
        assert not any(v.built for v in lazy)
        fr.reflectance(0.5, 1.5)
        assert any(v.built for v in lazy)
        print(len(lazy))
    """)
    if _kernels.DISABLE_JIT:
        # under NUMBA_DISABLE_JIT=1 (inherited by the subprocess) nothing is compiled, so there
        # is nothing to build lazily: ufunc() returns numpy.vectorize wrappers instead of
        # LazyUfunc (compile.py). What stands is the fallback's promise, checked instead: a
        # float scalar for scalars, float64 arrays of the broadcast shape for arrays.
        code = textwrap.dedent("""
            import numpy as np
            import roughbrdf.fresnel as fr
            from roughbrdf._kernels.compile import LazyUfunc
            assert not any(isinstance(v, LazyUfunc) for v in vars(fr).values())
            r = fr.reflectance(0.5, 1.5)
            assert np.ndim(r) == 0 and 0.0 < float(r) < 1.0, r
            a = fr.reflectance(np.array([[0.1], [0.5]]), np.array([1.3, 1.5, 1.7]))
            assert a.shape == (2, 3) and a.dtype == np.float64, (a.shape, a.dtype)
            print(1)
        """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert int(out.stdout) >= 1


def _fill_pairs(a, b, c, g, p, flag, out):
    # a stand-in driver with a trailing output shape (2,): (theta_i + theta_r, p[0] * phi)
    a, b, c = np.broadcast_arrays(a, b, c)
    out[:, 0] = (a + b).ravel()
    out[:, 1] = (p[0] * c).ravel()


def test_evaluate_broadcasts_and_appends_trailing_shape():
    ti = np.zeros((3, 1))
    tr = np.array([0.1, 0.2])
    phi = np.array(0.5)
    out = broadcast.evaluate(_fill_pairs, ti, tr, phi, np.array(np.nan), (2.0,), 0,
                             out_shape=(2,))
    assert out.shape == (3, 2, 2)
    np.testing.assert_array_equal(out[..., 0], np.broadcast_to(tr, (3, 2)))
    np.testing.assert_array_equal(out[..., 1], 1.0)  # 2 * 0.5
    scalar = broadcast.evaluate(_fill_pairs, np.array(0.1), np.array(0.2), phi,
                                np.array(np.nan), (2.0,), 0, out_shape=(2,))
    assert scalar.shape == (2,)


def test_evaluate_empty_and_scalar():
    m = rb.model("lambertian", rho=0.5)
    assert m.brdf(np.empty((0, 3)), 0.0, 0.0).shape == (0, 3)
    assert isinstance(m.brdf(0.1, 0.2, 0.3), float)


def test_broadcast_strided_zero_stride_for_one_value():
    arr, stride = broadcast.broadcast_strided(np.array([[2.0]]), (4, 5))
    assert stride == 0 and arr.shape == (1,)
    arr, stride = broadcast.broadcast_strided(np.arange(5.0), (4, 5))
    assert stride == 1 and arr.shape == (20,) and arr[7] == 2.0


def test_as_float_array_names_the_argument():
    with pytest.raises(ValueError, match="theta_r must be numeric"):
        broadcast.as_float_array("abc", "theta_r")

"""Start-up: what ``import roughbrdf``, ``roughbrdf --help`` and a first evaluation import.

No timing here (times are figures: ``benchmarks/bench_startup.py``, ``docs/benchmarks.md``);
these tests pin *what* is loaded, in a fresh interpreter each, so that the heavy packages
(Numba, SciPy, Matplotlib) load only when something needs them.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

import roughbrdf as rb

HEAVY = ("numba", "scipy", "matplotlib")
#: what evaluating a model never needs (Numba itself imports scipy and scipy.linalg)
NOT_FOR_EVALUATION = ("scipy.optimize", "scipy.stats", "matplotlib", "roughbrdf.fitting",
                      "roughbrdf.plot", "roughbrdf.io", "roughbrdf.cli")

_REPORT = ("import json, sys; "
           "print(json.dumps(sorted(m for m in sys.modules if m.startswith(('numba', 'scipy', "
           "'matplotlib', 'numpy', 'roughbrdf')))))")


def loaded_after(code: str, env: dict[str, str] | None = None) -> set[str]:
    """Modules (of the packages of interest) loaded after running ``code`` in a new process."""
    proc = subprocess.run([sys.executable, "-c", f"{code}\n{_REPORT}"], capture_output=True,
                          text=True, env={**os.environ, **(env or {})}, check=False)
    assert proc.returncode == 0, proc.stderr
    return set(json.loads(proc.stdout.strip().splitlines()[-1]))


def _packages(mods: set[str]) -> set[str]:
    return {m.split(".")[0] for m in mods}


def _cli(*args: str) -> str:
    return ("import sys\nfrom roughbrdf.cli import main\n"
            f"sys.argv = ['roughbrdf', *{list(args)!r}]\n"
            "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n")


def test_import_loads_nothing_heavy():
    mods = loaded_after("import roughbrdf")
    assert not _packages(mods) & set(HEAVY), sorted(mods)
    assert "numpy" not in _packages(mods)
    assert mods <= {"roughbrdf"}, sorted(mods)


@pytest.mark.parametrize("args", [("--help",), ("fit", "--help"), ("eval", "--help"),
                                  ("convert", "--help"), ("plot", "--help"),
                                  ("reproduce", "--help"), ("models", "--help")])
def test_cli_help_loads_nothing_heavy(args):
    mods = loaded_after(_cli(*args))
    assert not _packages(mods) & {*HEAVY, "numpy"}, sorted(mods)


def test_model_evaluation_loads_no_fitting_io_or_plotting():
    mods = loaded_after('import roughbrdf as rb\nrb.model("tr75").brdf(0.5, 0.5, 0.0)')
    assert "numba" in mods and "roughbrdf.models" in mods
    assert not mods & set(NOT_FOR_EVALUATION), sorted(mods & set(NOT_FOR_EVALUATION))


def test_fit_loads_its_machinery_on_first_use():
    mods = loaded_after("from roughbrdf import fit, FitResult")
    assert "roughbrdf.fitting" in mods
    assert "matplotlib" not in mods  # figures are drawn (and Matplotlib loaded) on demand


def test_every_public_name_resolves_and_is_listed():
    assert set(rb.__all__) <= set(dir(rb))
    for name in rb.__all__:
        assert getattr(rb, name) is not None, name
    from roughbrdf import Measurement, albedo, fit, model  # noqa: F401 - the import is the test

    assert rb.fit is fit and rb.model is model
    assert callable(rb.read) and callable(rb.write) and callable(rb.available)
    assert rb.geometry.__name__ == "roughbrdf.geometry"
    assert isinstance(rb.__version__, str)
    with pytest.raises(AttributeError, match="no_such_name"):
        rb.no_such_name  # noqa: B018


def test_star_import_gives_all_public_names():
    ns: dict = {}
    exec("from roughbrdf import *", ns)
    assert set(rb.__all__) <= set(ns)


def test_star_import_in_a_fresh_process():
    mods = loaded_after("from roughbrdf import *\nassert callable(fit) and callable(model)")
    assert "roughbrdf.fitting" in mods


def test_omp_wait_policy_set_at_import_unless_the_user_set_it():
    code = "import os, roughbrdf\nprint(os.environ['OMP_WAIT_POLICY'])\n"
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    for given, expected in ((None, "PASSIVE"), ("ACTIVE", "ACTIVE")):
        e = dict(env) if given is None else {**env, "OMP_WAIT_POLICY": given}
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              env=e, check=True)
        assert proc.stdout.strip() == expected


def test_numba_disable_jit_still_evaluates():
    code = ('import roughbrdf as rb\n'
            'print(repr(float(rb.model("tr75").brdf(0.5, 0.5, 0.0))))\n')
    out = []
    for env in ({"NUMBA_DISABLE_JIT": "1"}, {}):
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              env={**os.environ, **env}, check=True)
        out.append(float(proc.stdout.strip()))
    assert out[0] == pytest.approx(out[1], rel=1e-12)


def test_convert_help_lists_the_measurement_quantities():
    from roughbrdf.cli.convert import HELP_QUANTITIES
    from roughbrdf.measurement import QUANTITIES

    assert tuple(HELP_QUANTITIES) == tuple(QUANTITIES)

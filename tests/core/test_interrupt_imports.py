"""A Ctrl-C while Matplotlib's compiled modules load is held until they are loaded
(:func:`roughbrdf.mpl_load.load_matplotlib`).

Why: a Ctrl-C 0.15 s into saving a fit's figures once landed while those modules initialized and
the interpreter aborted at exit ("Fatal Python error: PyThreadState_Get", exit -6 instead of 130;
``tests/cli/test_cli_safety.py``). The test is deterministic: in a fresh interpreter an import
hook sends SIGINT to the process the moment ``matplotlib.figure`` starts loading; held, the
import finishes and ``KeyboardInterrupt`` comes right after it, and the interpreter exits
cleanly. Without the hold the same script ends with the interrupt inside the import (the control
case below).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import importlib.abc, os, signal, sys

    class Strike(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path, target=None):
            if name == "matplotlib.figure":
                sys.meta_path.remove(self)
                os.kill(os.getpid(), signal.SIGINT)  # delivered at the next bytecode
            return None

    from roughbrdf.mpl_load import load_matplotlib
    sys.meta_path.insert(0, Strike())
    try:
        {call}
    except KeyboardInterrupt:
        loaded = all(m in sys.modules for m in ("matplotlib.figure", "PIL.PngImagePlugin"))
        print("interrupted after the imports" if loaded else "interrupted inside them")
""")


def _run(call: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", SCRIPT.format(call=call)], capture_output=True,
                          text=True, timeout=120)


def test_ctrl_c_waits_for_the_compiled_modules():
    out = _run("load_matplotlib()")
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "interrupted after the imports", out.stderr


def test_without_the_hold_it_strikes_inside_the_import():
    """The control: the same script importing directly is interrupted mid-import (so the test
    above can fail)."""
    out = _run("import matplotlib.backends.backend_agg, matplotlib.figure, PIL.PngImagePlugin")
    assert out.stdout.strip() == "interrupted inside them", (out.stdout, out.stderr)

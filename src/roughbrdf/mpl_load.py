"""Matplotlib's compiled modules, loaded with Ctrl-C held (:func:`load_matplotlib`).

Every figure roughbrdf draws (``roughbrdf.plot``, a fit's saved figures) loads them through
this module first: ``docs/fitting.md``, "Output files", and the command line's promise that
Ctrl-C ends a run cleanly at any moment.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .interrupts import held_interrupts

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["load_matplotlib"]


def load_matplotlib() -> type[Figure]:
    """Import the compiled parts of Matplotlib a figure and its PNG need (``figure``, the Agg
    backend, Pillow's PNG writer), Ctrl-C held while they load; the ``Figure`` class.

    A Ctrl-C that lands while a compiled module initializes can leave it half made, and the
    interpreter then aborted at exit ("Fatal Python error: PyThreadState_Get", exit -6 instead
    of 130: ``tests/cli/test_cli_safety.py``, Ctrl-C 0.15 s into saving a fit's figures), as it
    did for SciPy's Sobol tables (:func:`roughbrdf.fitting.solvers.search.sobol_points`). Held,
    the interrupt comes right after the imports. Only a lookup once they are loaded.

    Examples
    --------
    >>> load_matplotlib().__name__
    'Figure'
    """
    with held_interrupts():
        import matplotlib.backends.backend_agg  # noqa: F401
        import matplotlib.figure  # noqa: F401
        import PIL.PngImagePlugin  # noqa: F401
        from matplotlib.figure import Figure as FigureClass
    return FigureClass

"""A local web explorer for measurements, models and fits (``roughbrdf explore``,
``docs/explore.md``), built on Dash (Plotly).

Light at import: nothing here imports Dash or Plotly (``pip install roughbrdf[explore]``);
:mod:`~roughbrdf.explore.server` and :mod:`~roughbrdf.explore.security` need only Werkzeug
(installed with Dash), :mod:`~roughbrdf.explore.app` builds the Dash application,
:mod:`~roughbrdf.explore.figures` draws the views.
"""

from __future__ import annotations

import importlib.util as _util

__all__: list[str] = []

if _util.find_spec(f"{__name__}.notebook") is not None:  # the notebook front end, when present
    from .notebook import explore  # noqa: F401

    __all__.append("explore")

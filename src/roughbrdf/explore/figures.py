"""The explorer's figures: pure functions from a Model and/or a Measurement to Plotly figures.

No Dash here: the browser application (:mod:`roughbrdf.explore.app`) and the notebook view
(:mod:`roughbrdf.explore.notebook`) draw the same figures. Importing this module imports
Plotly; ``import roughbrdf`` does not import it.

=========================  ==================================================================
function                   what it draws
=========================  ==================================================================
:func:`lobe_3d`            the lobe over the hemisphere in 3-D, BRDF or BRDF·cos θr (sr⁻¹),
                           linear or log radius, specular and retro directions marked
:func:`plane_cuts`         in-plane (φ = 0°/180°) and cross-plane (φ = ±90°) cuts on a
                           signed θr axis [deg]: data, model per incidence, ln(data/model)
:func:`hemisphere_maps`    projected-disk maps at one incidence: data, model, data/model
:func:`albedo_curve`       albedo (TIS) [1] against incidence [deg], the line at 1, a warning
                           when the model gains energy
:func:`mueller_maps`       the 16 normalized Mueller elements m_ij/m00 and the DoLP [1]
:func:`compare_lobes`      two lobes overlaid or side by side, on one radius scale
:func:`figure_values`      the numbers drawn, per trace (for tests and the page's read-back)
=========================  ==================================================================

Conventions: every angle argument in radians (the library's), degrees on every angle axis and
in the hover text; the library's frame (``phi = 0`` the forward/specular side, ``phi = pi``
toward the source; ``docs/models.md`` §1.1); every value with its unit (sr⁻¹, or [1] for
dimensionless ones); every title names the model (:func:`roughbrdf.models.model_label`), the
incidence and the channel where they apply. Models are evaluated with the compiled kernels on
whole grids (one ``model.evaluate`` per figure part, no loop over samples). Bad input raises
:class:`~roughbrdf.errors.ArgumentError` naming the argument.
"""

from __future__ import annotations

import base64
from typing import Any

import numpy as np

from .figures_albedo import WARNING_NAME, albedo_curve
from .figures_cuts import plane_cuts
from .figures_lobe import compare_lobes, lobe_3d
from .figures_maps import hemisphere_maps, mueller_maps

__all__ = ["WARNING_NAME", "albedo_curve", "compare_lobes", "figure_values",
           "hemisphere_maps", "lobe_3d", "mueller_maps", "plane_cuts"]

_AXES = ("x", "y", "z")


def _array(value: Any) -> np.ndarray | None:
    """A trace's array as NumPy: plain lists, or Plotly's typed-array form of ``to_dict()``
    / ``to_plotly_json()`` (``{"dtype", "bdata": base64, "shape"}``, what a page holds)."""
    if value is None:
        return None
    if isinstance(value, dict) and "bdata" in value:
        arr = np.frombuffer(base64.b64decode(value["bdata"]), dtype=np.dtype(value["dtype"]))
        shape = value.get("shape")  # "9, 13" from Plotly, a list from some serializers
        if shape is not None and shape != "":
            arr = arr.reshape([int(s) for s in str(shape).split(",")] if isinstance(shape, str)
                              else [int(s) for s in shape])
        return arr.astype(float)
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):  # text values (categorical axes): as they are
        return np.asarray(value, dtype=object)


def figure_values(fig: Any) -> dict[str, dict[str, np.ndarray]]:
    """The numbers a figure draws, per trace name.

    For each trace: ``x``, ``y`` (and ``z``) as drawn (a heat map's ``z`` is its colour:
    ``log10`` of the value in a logarithmic map), ``color`` for coloured markers, and every
    column of its ``customdata`` under the name ``meta["fields"]`` gives it (e.g.
    ``theta_r_deg``, ``phi_deg``, ``value``: the value in its unit, before any colour or
    radius mapping). Repeated names get `` #2``, `` #3``, ... .

    Parameters
    ----------
    fig : plotly.graph_objects.Figure or dict
        A figure, or its ``to_dict()`` / ``to_plotly_json()`` form (what a page holds).

    Returns
    -------
    dict of str -> dict of str -> numpy.ndarray

    Examples
    --------
    >>> import roughbrdf as rb
    >>> v = figure_values(albedo_curve(rb.model("lambertian", rho=0.5), incidences_deg=[10]))
    >>> sorted(v), v["albedo"]["theta_i_deg"].tolist()
    (['albedo', 'albedo = 1'], [10.0])
    """
    data = fig["data"] if isinstance(fig, dict) else fig.data
    out: dict[str, dict[str, np.ndarray]] = {}
    for i, trace in enumerate(data):
        get = trace.get if isinstance(trace, dict) else (lambda k, t=trace: getattr(t, k, None))
        name = get("name") or f"trace {i}"
        key, k = name, 1
        while key in out:
            k += 1
            key = f"{name} #{k}"
        entry: dict[str, np.ndarray] = {}
        for axis in _AXES:
            arr = _array(get(axis))
            if arr is not None:
                entry[axis] = arr
        marker = get("marker")
        color = marker.get("color") if isinstance(marker, dict) else \
            getattr(marker, "color", None)
        if color is not None and not isinstance(color, str):
            entry["color"] = np.asarray(_array(color), dtype=float)
        meta, cd = get("meta"), _array(get("customdata"))
        fields = meta.get("fields") if isinstance(meta, dict) else None
        if fields and cd is not None:
            arr = np.asarray(cd, dtype=float)
            for j, f in enumerate(fields):
                entry[f] = arr[..., j]
        out[key] = entry
    return out

"""ALTA text data files (Belcour, Pacanowski et al., ``.dat`` / ``.alta``).

Layout::

    #SAMPLE "Gray tape"                 <- optional metadata (#SAMPLE, #ORIGIN, #URL ...)
    #DIM 3 1                            <- input dimension, output dimension (channels)
    #VS 0                               <- optional confidence interval kind (0, 1 or 2)
    #PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI
    #PARAM_OUT INV_STERADIAN            <- INV_STERADIAN (BRDF) or INV_STERADIAN_COSINE_FACTOR
    0.2618  0.0000  -0.2618  0.1293     <- x0 x1 x2 value [confidence]

Each row holds DIM[0] inputs, DIM[1] outputs and, per ``#VS``: nothing (0), a half-width per
output (1), or lower and upper bounds per output (2). The half-width (or half the bound
interval) becomes ``Measurement.uncertainty``.

Input parametrizations (ALTA's cartesian convention: light L at azimuth 0 in the x-z plane,
view V; ``Δφ = φ_v - φ_l``):

* ``ISOTROPIC_TL_TV_PROJ_DPHI``: ``x0 = theta_l``, ``x1 = theta_v cos Δφ``,
  ``x2 = theta_v sin Δφ``; so ``theta_v = hypot(x1, x2)``, ``Δφ = atan2(x2, x1)``.
* ``ISOTROPIC_TV_TL_DPHI``: ``(theta_v, theta_l, Δφ)``.
* ``SPHERICAL_TL_PL_TV_PV``: ``(theta_l, phi_l, theta_v, phi_v)``.
* ``RUSIN_TH_TD_PD``: Rusinkiewicz ``(theta_h, theta_d, phi_d)``, through
  :func:`roughbrdf.geometry.from_rusinkiewicz` (ALTA takes ``d`` from the view vector, MERL from
  the light; the two differ by ``phi_d -> phi_d + pi``, the same BRDF value by reciprocity).

ALTA's ``Δφ = 0`` is the **source** side (the retro direction is ``(θl, +θl, 0)``), the opposite
of this library's ``phi = 0``. The mapping is the rotation that puts the source at azimuth pi
(:func:`roughbrdf.geometry.angles_from_vectors`): ``phi = Δφ + pi`` wrapped into (-pi, pi], i.e.
``|phi| = pi - |Δφ|`` (the mirror image ``phi = pi - Δφ`` gives the same value on an isotropic
surface). Verified on ``retro-gray-tape.dat``: the retro peaks land at ``theta_r = theta_i``,
``phi = pi``. ``Measurement.original`` keeps ``x0, x1, x2`` (``x3`` for 4-D inputs) untouched.

Outputs: ``#PARAM_OUT INV_STERADIAN`` -> ``brdf``; ``INV_STERADIAN_COSINE_FACTOR`` ->
``brdf_cos`` (BRDF · cos theta_v). A missing or other ``PARAM_OUT`` is an error that asks for
``quantity=`` (CLI ``--quantity``); ``retro-gray-tape.dat`` is such a file (it holds
BRDF · cos theta_v).
"""

from __future__ import annotations

import math
import os
import shlex
from typing import Any

import numpy as np

from ..geometry import from_rusinkiewicz
from ..measurement import QUANTITIES, Measurement
from ._common import (
    HALF_PI,
    ZENITH_SLACK,
    FormatError,
    azimuth_rows,
    begin_read,
    check_zenith_rows,
    common_frame_from_spherical,
    parse_rows,
)

__all__ = ["read", "write", "EXTENSIONS", "PARAM_IN"]

EXTENSIONS = (".dat", ".alta")

#: supported input parametrizations and their dimension
PARAM_IN = {"ISOTROPIC_TL_TV_PROJ_DPHI": 3, "ISOTROPIC_TV_TL_DPHI": 3,
            "SPHERICAL_TL_PL_TV_PV": 4, "RUSIN_TH_TD_PD": 3}
_PARAM_OUT = {"INV_STERADIAN": "brdf", "INV_STERADIAN_COSINE_FACTOR": "brdf_cos"}
_QUANTITY_OUT = {"brdf": "INV_STERADIAN", "brdf_cos": "INV_STERADIAN_COSINE_FACTOR",
                 "bridf": "INV_STERADIAN_COSINE_FACTOR"}


def _unquote(text: str) -> str:
    try:
        parts = shlex.split(text)
    except ValueError:
        return text.strip()
    return " ".join(parts)


def read(path: str | os.PathLike, *, quantity: str | None = None, **options: Any) -> Measurement:
    """Read an ALTA text file into a :class:`~roughbrdf.measurement.Measurement`.

    Parameters
    ----------
    quantity : str, optional
        What the values hold when the file has no ``#PARAM_OUT`` (or to state it explicitly;
        it must then agree with the file's declaration).
    """
    path, lines = begin_read("alta", path, options, quantity)
    header: dict[str, str] = {}
    hline: dict[str, int] = {}
    texts: list[str] = []
    linenos: list[int] = []
    for i, raw in enumerate(lines):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            key, _, val = s[1:].strip().partition(" ")
            if key:
                header[key.upper()] = val.strip()
                hline[key.upper()] = i + 1
            continue
        texts.append(s)
        linenos.append(i + 1)

    if "DIM" not in header:
        raise FormatError("no #DIM line (e.g. '#DIM 3 1'); this does not look like an ALTA "
                          "data file", path, 1)
    try:
        nin, nout = (int(t) for t in header["DIM"].split()[:2])
    except ValueError:
        raise FormatError(f"#DIM must hold two integers, got {header['DIM']!r}", path,
                          hline["DIM"]) from None
    pin = header.get("PARAM_IN", "").split()[0] if header.get("PARAM_IN") else ""
    if not pin:
        raise FormatError("no #PARAM_IN line: the angle parametrization is unknown "
                          f"(supported: {', '.join(PARAM_IN)})", path, hline["DIM"])
    if pin not in PARAM_IN:
        raise FormatError(f"#PARAM_IN {pin} is not supported (supported: "
                          f"{', '.join(PARAM_IN)})", path, hline["PARAM_IN"])
    if PARAM_IN[pin] != nin:
        raise FormatError(f"#PARAM_IN {pin} has {PARAM_IN[pin]} inputs but #DIM says {nin}",
                          path, hline["DIM"])
    if nout < 1:
        raise FormatError(f"#DIM declares {nout} outputs", path, hline["DIM"])
    vs = 0
    if "VS" in header:
        try:
            vs = int(header["VS"].split()[0])
        except (ValueError, IndexError):
            raise FormatError(f"#VS must be 0, 1 or 2, got {header['VS']!r}", path,
                              hline["VS"]) from None
        if vs not in (0, 1, 2):
            raise FormatError(f"#VS must be 0, 1 or 2, got {vs}", path, hline["VS"])

    # --- quantity ---------------------------------------------------------------------------
    pout = header.get("PARAM_OUT", "").split()[0] if header.get("PARAM_OUT") else ""
    declared = _PARAM_OUT.get(pout)
    if pout and declared is None and quantity is None:
        raise FormatError(f"#PARAM_OUT {pout} is not a BRDF unit (INV_STERADIAN or "
                          "INV_STERADIAN_COSINE_FACTOR); say what the values hold with "
                          f"quantity= (CLI: --quantity), one of {QUANTITIES}", path,
                          hline["PARAM_OUT"])
    if not pout and quantity is None:
        raise FormatError("no #PARAM_OUT line, so the unit of the values is unknown: say what "
                          "they hold with quantity= (CLI: --quantity): 'brdf' (INV_STERADIAN) "
                          "or 'brdf_cos' (INV_STERADIAN_COSINE_FACTOR, BRDF x cos theta_v)",
                          path, None)
    if quantity is not None and declared is not None:
        same = {quantity, declared} <= {"brdf_cos", "bridf"} or quantity == declared
        if not same:
            raise FormatError(f"quantity={quantity!r} contradicts #PARAM_OUT {pout} "
                              f"({declared})", path, hline["PARAM_OUT"])
    q = quantity or declared
    assert q is not None

    # --- rows -------------------------------------------------------------------------------
    if not texts:
        raise FormatError("no data rows after the header", path, len(lines) + 1)
    per_row = nin + nout * (1 + vs)
    data = parse_rows(texts, linenos, per_row, path, sep=None,
                      what=f"values (#DIM {nin} {nout}, #VS {vs})")
    ln = np.asarray(linenos)
    if "SAMPLE_COUNT" in header:
        try:
            declared_n = int(header["SAMPLE_COUNT"].split()[0])
        except ValueError:
            declared_n = None
        if declared_n is not None and declared_n > data.shape[0]:
            raise FormatError(f"truncated file: #SAMPLE_COUNT is {declared_n} but only "
                              f"{data.shape[0]} rows follow", path, len(lines) + 1)
    x = data[:, :nin]
    for j in range(nin):
        azimuth_rows(x[:, j], f"x{j}", ln, path)  # angles must be finite (names the line)
    values = data[:, nin:nin + nout]
    uncertainty = None
    if vs == 1:
        uncertainty = np.abs(data[:, nin + nout:nin + 2 * nout])
    elif vs == 2:
        lo = data[:, nin + nout:nin + 3 * nout:2]
        hi = data[:, nin + nout + 1:nin + 3 * nout:2]
        uncertainty = 0.5 * np.abs(hi - lo)

    # --- geometry ---------------------------------------------------------------------------
    original = {f"x{j}": x[:, j].copy() for j in range(nin)}
    if pin == "ISOTROPIC_TL_TV_PROJ_DPHI":
        tl = check_zenith_rows(x[:, 0], "theta_l (x0)", ln, path)
        tv_raw = np.hypot(x[:, 1], x[:, 2])
        tv = check_zenith_rows(tv_raw, "theta_v = hypot(x1, x2)", ln, path)
        dphi = np.arctan2(x[:, 2], x[:, 1])
        theta_i, theta_r, phi = common_frame_from_spherical(tl, np.zeros_like(tl), tv, dphi)
    elif pin == "ISOTROPIC_TV_TL_DPHI":
        tv = check_zenith_rows(x[:, 0], "theta_v (x0)", ln, path)
        tl = check_zenith_rows(x[:, 1], "theta_l (x1)", ln, path)
        theta_i, theta_r, phi = common_frame_from_spherical(tl, x[:, 2], tv, np.zeros_like(tv))
    elif pin == "SPHERICAL_TL_PL_TV_PV":
        tl = check_zenith_rows(x[:, 0], "theta_l (x0)", ln, path)
        tv = check_zenith_rows(x[:, 2], "theta_v (x2)", ln, path)
        theta_i, theta_r, phi = common_frame_from_spherical(tl, x[:, 1], tv, x[:, 3])
    else:  # RUSIN_TH_TD_PD
        theta_i, theta_r, phi = from_rusinkiewicz(x[:, 0], x[:, 1], x[:, 2])
        below = ~np.isfinite(theta_i)
        if below.any():
            k = int(np.flatnonzero(below)[0])
            raise FormatError(f"(theta_h, theta_d, phi_d) = {tuple(x[k])} puts a direction "
                              f"below the horizon ({int(below.sum())} such rows)", path,
                              int(ln[k]))
        theta_i = np.clip(theta_i, 0.0, HALF_PI)
        theta_r = np.clip(theta_r, 0.0, HALF_PI)

    channels = ["value"] if nout == 1 else [f"c{j}" for j in range(nout)]
    if header.get("CHANNELS"):  # written by roughbrdf: one label per output
        labels = header["CHANNELS"].split()
        if len(labels) != nout:
            raise FormatError(f"#CHANNELS lists {len(labels)} labels for {nout} outputs", path,
                              hline["CHANNELS"])
        channels = labels
    sample = _unquote(header["SAMPLE"]) if header.get("SAMPLE") else None
    meta: dict[str, Any] = {
        "file": str(path),
        "format": "alta",
        "sample": sample,
        "instrument": _unquote(header["ORIGIN"]) if header.get("ORIGIN") else None,
        "date": _unquote(header["DATE"]) if header.get("DATE") else None,
        "url": header.get("URL"),
        "param_in": pin,
        "param_out": pout or None,
        "quantity_source": f"#PARAM_OUT {pout}" if declared else "option quantity=",
        "vs": vs,
        "original_units": "rad",
        "zenith_clip_tolerance": ZENITH_SLACK,
        "header": dict(header),
    }
    return Measurement(theta_i=theta_i, theta_r=theta_r, phi=phi, values=values,
                       channels=channels, quantity=q, uncertainty=uncertainty,
                       original=original, meta=meta)


def write(measurement: Measurement, path: str | os.PathLike) -> None:
    """Write an ALTA text file: ``#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI``, one output per channel.

    ``brdf`` -> ``#PARAM_OUT INV_STERADIAN``; ``brdf_cos``/``bridf`` ->
    ``INV_STERADIAN_COSINE_FACTOR``. A ``relative`` measurement has no ALTA unit and is refused
    (convert it, or write CSV). Uncertainties are written as ``#VS 1`` half-widths.
    Per-sample polarization cannot be stored in ALTA and is refused unless all unpolarized.
    """
    m = measurement
    if m.quantity not in _QUANTITY_OUT:
        raise ValueError(f"ALTA files hold INV_STERADIAN or INV_STERADIAN_COSINE_FACTOR; a "
                         f"{m.quantity!r} measurement cannot be written (use CSV)")
    if m.polarization is not None and np.isfinite(m.polarization).any():
        raise ValueError("ALTA files cannot hold per-sample polarization; write CSV, or select "
                         "one polarization (Measurement.with_polarization) and drop it")
    # library frame -> ALTA: light at azimuth 0, so Δφ = phi - pi (the inverse rotation)
    dphi = m.phi - math.pi
    x1 = m.theta_r * np.cos(dphi)
    x2 = m.theta_r * np.sin(dphi)
    cols = [m.theta_i, x1, x2, m.values]
    vs = 0
    if m.uncertainty is not None:
        cols.append(m.uncertainty)
        vs = 1
    table = np.column_stack(cols)
    lines = []
    if m.meta.get("sample"):
        lines.append(f'#SAMPLE "{m.meta["sample"]}"')
    if m.meta.get("instrument"):
        lines.append(f'#ORIGIN "{m.meta["instrument"]}"')
    if m.meta.get("date"):
        lines.append(f'#DATE "{m.meta["date"]}"')
    lines += [f"#DIM 3 {m.n_channels}", f"#VS {vs}", "#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI",
              f"#PARAM_OUT {_QUANTITY_OUT[m.quantity]}"]
    if m.n_channels > 1:
        lines.append("#CHANNELS " + " ".join(m.channels))
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")
        np.savetxt(fh, table, delimiter="  ", fmt="%.17g")


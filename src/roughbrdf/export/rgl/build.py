"""The fields of an RGL measured-BSDF file, computed from a model (one per channel).

The layout is the one Mitsuba 3's ``measured`` plugin reads (``src/bsdfs/measured.cpp``) and
pbrt-v4's ``MeasuredBxDF`` (``src/pbrt/bxdfs.cpp``), from Dupuy & Jakob 2018 (see
:mod:`roughbrdf.io.rgl_tensor` for the container and the parameterization):

=============  ==========================================  ==================================
field          shape                                       holds
=============  ==========================================  ==================================
theta_i        ``(n_theta_i,)`` float32                    incidence zeniths (radians)
phi_i          ``(1,)`` float32                            incident azimuth 0 (isotropic)
ndf            ``(2, n_ndf)`` float32                      ``D`` on the ``u`` grid
sigma          ``(2, n_sigma)`` float32                    ``sigma(w_i)`` on the ``u`` grid
vndf           ``(1, n_theta_i, n_vndf, n_vndf)`` float32  ``D <w_i, m>+`` times ``du/dm``
luminance      ``(1, n_theta_i, n, n)`` float32            the samples' luminance (sampling)
rgb / spectra  ``(1, n_theta_i, channels, n, n)`` float32  the samples (see below)
wavelengths    ``(channels,)`` float32                     nm (spectral files only)
description    ``(bytes,)`` uint8                          what the file holds, and how made
jacobian       ``(1,)`` uint8                              1
=============  ==========================================  ==================================

The last two axes of ``vndf`` are (azimuth ``v``, zenith ``u``) of the half vector, the
azimuth relative to the incident one; those of ``luminance`` and the samples are (``y``,
``x``) of the sample space. With ``jacobian = 1`` Mitsuba's ``eval`` returns
``sample * D(m) / (4 sigma(w_i))``; so each sample is ``f_r cos(theta_o) 4 sigma(w_i) / D(m)``
with ``D`` and ``sigma`` as Mitsuba interpolates them: Mitsuba returns exactly
``f_r cos(theta_o)`` at the grid's nodes, and between them an interpolation of a quantity far
smoother than the BRDF (a microfacet BRDF's ``F G / G_1``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io.rgl_tensor import bilinear, sample_marginal, theta_to_u, u_to_theta, v_to_phi
from .ndf import ndf_table, sigma_table

__all__ = ["Resolution", "build_fields"]

#: the share of the warp given to a uniform distribution of normals: the grid follows
#: ``D + GUARD / pi`` (``1 / pi`` is the uniform NDF), so that a narrow lobe's far tails and a
#: diffuse part still get nodes (a warp by ``D`` alone packs them into the grid's last rows,
#: where the interpolation of a steep tail fails)
GUARD = 0.1
#: the luminance of linear sRGB / Rec. 709 primaries (CIE Y row of the sRGB matrix)
_Y_RGB = np.array([0.2126, 0.7152, 0.0722])


@dataclass(frozen=True)
class Resolution:
    """Grid sizes of an RGL file.

    Attributes
    ----------
    theta_i : int
        Incidence zeniths, uniform from 0 to ``theta_i_max`` (Mitsuba interpolates
        linearly between them and holds the last beyond it).
    samples : int
        Samples per side of the sample-space grid (``samples**2`` per incidence and channel).
    vndf : int
        Nodes per side of the visible-normal table that warps that grid.
    ndf : int
        Nodes of the NDF and sigma tables (zenith, ``u``).
    theta_i_max : float
        The last incidence zenith, radians.

    Examples
    --------
    >>> Resolution(samples=64).samples, Resolution().theta_i
    (64, 24)
    >>> Resolution(samples=1).check()
    Traceback (most recent call last):
    ...
    ValueError: resolution samples must be an integer >= 2, got 1
    """

    theta_i: int = 24
    samples: int = 48
    vndf: int = 64
    ndf: int = 256
    theta_i_max: float = float(np.radians(88.0))

    def check(self) -> None:
        """Raise a ``ValueError`` naming the field that is too small or out of range."""
        for name in ("theta_i", "samples", "vndf", "ndf"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 2:
                raise ValueError(f"resolution {name} must be an integer >= 2, got {value!r}")
        if not 0 < self.theta_i_max < np.pi / 2:
            raise ValueError(f"resolution theta_i_max must be in (0, pi/2) radians, got "
                             f"{self.theta_i_max!r}")


def _vndf_slice(theta_i: float, u: np.ndarray, d: np.ndarray, n: int) -> np.ndarray:
    """The visible-normal density of ``D`` (here ``D + GUARD / pi``) at incidence ``theta_i``
    on an ``n x n`` (v, u) grid, in the unit coordinates: ``D(m) <w_i, m>+`` times
    ``|dm / du dv| / (2 pi^2) = u sin(theta)`` (Mitsuba's ``Marginal2D`` normalizes it)."""
    x = np.linspace(0.0, 1.0, n)
    tm = u_to_theta(x)[None, :]
    pm = v_to_phi(np.linspace(0.0, 1.0, n))[:, None]
    dot = np.sin(theta_i) * np.sin(tm) * np.cos(pm) + np.cos(theta_i) * np.cos(tm)
    return np.interp(x, u, d)[None, :] * np.maximum(dot, 0.0) * x[None, :] * np.sin(tm)


def _geometry(theta_i: float, vndf: np.ndarray, n: int) -> dict[str, np.ndarray]:
    """The ``n x n`` sample-space nodes at incidence ``theta_i`` (incident azimuth 0) warped by
    ``vndf``: the half vector's ``u`` and the reflected direction in the library's angles
    (``theta_r``, ``phi`` from the forward side), ``cos_o`` (<= 0: below the horizon)."""
    s = np.linspace(0.0, 1.0, n)
    sx, sy = np.meshgrid(s, s)  # [row = y, col = x]
    x, y = sample_marginal(vndf, sx.ravel(), sy.ravel())
    tm, pm = u_to_theta(x), v_to_phi(y)
    m = np.stack([np.sin(tm) * np.cos(pm), np.sin(tm) * np.sin(pm), np.cos(tm)])
    wi = np.array([np.sin(theta_i), 0.0, np.cos(theta_i)])[:, None]
    wo = 2.0 * (wi * m).sum(axis=0) * m - wi
    cos_o = wo[2]
    theta_r = np.arccos(np.clip(cos_o, -1.0, 1.0))  # |z| may round beyond 1: NaN otherwise
    # the incident direction's azimuth is 0, so the forward (specular) side is at pi
    phi = np.angle(-(wo[0] + 1j * wo[1]))
    # below the horizon (cos_o <= 0) the node holds 0 and the model is not evaluated; theta_r
    # is capped only so that every entry is a valid zenith
    return {"u": x, "theta_r": np.minimum(theta_r, np.pi / 2), "phi": phi, "cos_o": cos_o}


def build_fields(models: list, res: Resolution, *, rgb: bool, mix: np.ndarray | None = None,
                 wavelengths: list[float] | None = None,
                 description: str = "") -> tuple[dict[str, np.ndarray], str]:
    """The tensor-file fields (name -> array) of the isotropic BRDF given by ``models``, and
    the NDF's source.

    Parameters
    ----------
    models : list of Model
        One per channel: three (R, G, B) for an RGB file, one per wavelength otherwise.
    res : Resolution
    rgb : bool
        An RGB file (field ``rgb``) or a spectral one (``spectra`` and ``wavelengths``).
    mix : array, optional
        ``(file channels, models)``: each file channel a linear combination of the models'
        values (default: the identity).
    wavelengths : list of float, optional
        The channels' wavelengths (nm) of a spectral file.
    description : str
        The text of the ``description`` field (the NDF's source is appended).

    Returns
    -------
    fields : dict of str to ndarray
        In the layout of the table above, for :func:`roughbrdf.io.rgl_tensor.encode`.
    source : str
        Where the NDF came from (:data:`~roughbrdf.export.rgl.ndf.EXACT_SOURCE` or
        :data:`~roughbrdf.export.rgl.ndf.POWER_SOURCE`).

    Examples
    --------
    >>> import roughbrdf as rb
    >>> small = Resolution(theta_i=3, samples=8, vndf=16, ndf=32)
    >>> fields, source = build_fields([rb.model("lambertian", rho=0.5)] * 3, small, rgb=True)
    >>> fields["rgb"].shape, fields["vndf"].shape, source.split()[0]
    ((1, 3, 3, 8, 8), (1, 3, 16, 16), 'power')
    """
    res.check()
    u, d, source = ndf_table(models, res.ndf)
    u_sigma = np.linspace(0.0, 1.0, res.ndf)
    sigma = sigma_table(u, d, u_sigma)
    theta_i = np.linspace(0.0, res.theta_i_max, res.theta_i)
    warp = d + GUARD / np.pi
    vndf = np.stack([_vndf_slice(t, u, warp, res.vndf) for t in theta_i])
    geo = [_geometry(t, vndf[k], res.samples) for k, t in enumerate(theta_i)]
    ti = np.concatenate([np.full(g["u"].shape, t) for g, t in zip(geo, theta_i, strict=True)])
    tr, ph, cos_o, um = (np.concatenate([g[k] for g in geo])
                         for k in ("theta_r", "phi", "cos_o", "u"))
    above = cos_o > 0
    # the D and sigma Mitsuba will multiply by, interpolated as it does (bilinear in u)
    d_m = np.interp(um, u, d)
    sig = bilinear(np.stack([sigma, sigma]), theta_to_u(ti), np.zeros_like(ti))
    values = np.zeros((len(models), ti.size))  # f_r cos(theta_o)
    for c, model in enumerate(models):  # one vectorized evaluation per channel
        f = np.asarray(model.brdf(ti[above], tr[above], ph[above]), float)
        # a model undefined at a node (NaN, e.g. exactly grazing) or infinite there (a delta)
        # has no finite table value: 0 keeps the tables (and the warps built from them) finite
        values[c, above] = np.nan_to_num(f, nan=0.0, posinf=0.0) * cos_o[above]
    values = np.maximum(values, 0.0)  # a model's rounding below 0 is no reflectance
    if mix is not None:
        values = np.asarray(mix, float) @ values
    n_out = values.shape[0]
    shape = (1, res.theta_i, res.samples, res.samples)
    # sampling: Mitsuba's pdf of w_o is luminance(s) vndf(u) / (2 pi^2 u sin 4 <w_i, m>),
    # proportional to f_r cos / warp(m) * warp(m) = f_r cos when luminance = (f_r cos) / warp
    lum = ((_Y_RGB @ values) if rgb else values.mean(axis=0)) / np.interp(um, u, warp)
    values = values * (4.0 * sig / d_m)  # the stored samples: times 4 sigma / D (jacobian)
    lum = lum.reshape(shape)
    empty = lum.reshape(res.theta_i, -1).max(axis=1) <= 0
    lum[0, empty] = 1.0  # a black incidence: uniform sampling (a zero density cannot be warped)
    samples = values.reshape(n_out, *shape).transpose(1, 2, 0, 3, 4)
    text = (description + "; " if description else "") + f"NDF: {source}."
    fields = {
        "description": np.frombuffer(text.encode(), np.uint8).copy(),
        "jacobian": np.array([1], np.uint8),
        "theta_i": theta_i.astype(np.float32),
        "phi_i": np.zeros(1, np.float32),
        "ndf": np.stack([d, d]).astype(np.float32),
        "sigma": np.stack([sigma, sigma]).astype(np.float32),
        "vndf": vndf[None].astype(np.float32),
        "luminance": lum.astype(np.float32),
    }
    if rgb:
        fields["rgb"] = samples.astype(np.float32)
    else:
        fields["spectra"] = samples.astype(np.float32)
        fields["wavelengths"] = np.asarray(wavelengths, np.float32)
    return fields, source

"""The RGL "tensor file" container and the adaptive parameterization of Dupuy & Jakob 2018.

Dupuy & Jakob 2018, "An adaptive parameterization for efficient material acquisition and
rendering" (ACM TOG 37(6), SIGGRAPH Asia), store a measured BRDF in a *tensor file*: named
little-endian arrays. This module holds the parts that the reader
(:mod:`roughbrdf.io.rgl`) and the writer (:mod:`roughbrdf.export.rgl`) share; it is written
from the layout that Mitsuba 3 reads (``src/core/tensor.cpp``, ``src/bsdfs/measured.cpp``,
``include/mitsuba/core/distr_2d.h``), checked against pbrt-v4's ``MeasuredBxDF``
(``src/pbrt/bxdfs.{h,cpp}``).

The container: the 12 bytes ``b"tensor_file\\0"``, a version (two bytes, 1 and 0), the number
of fields (uint32); per field its name (uint16 length and the bytes), the number of
dimensions (uint16), the type code (uint8: Mitsuba's ``struct_jit`` codes, 1 uint8 ... 10
float32, 11 float64), the byte offset of the data (uint64) and the shape (uint64 each); the
data of every field follows, C order.

The parameterization (``measured.cpp``): a half vector ``m`` at zenith ``theta`` and azimuth
``phi`` has the unit coordinates ``u = sqrt(2 theta / pi)`` and ``v = (phi + pi) / (2 pi)``
(isotropic files: ``phi`` relative to the incident azimuth); the reflectance samples lie on a
uniform grid of a second unit square, the *sample space*, which Mitsuba's continuous
``Marginal2D`` warp built from the visible-normal distribution (``vndf``) maps to ``(u, v)``.
:func:`sample_marginal` is that warp (the exact inverse CDF of the bilinear interpolant), in
NumPy.

Examples
--------
>>> import numpy as np
>>> blob = encode({"theta_i": np.array([0.0, 0.5], np.float32),
...                "jacobian": np.array([1], np.uint8)})
>>> blob[:11]
b'tensor_file'
>>> fields = decode(blob)
>>> fields["theta_i"].tolist(), fields["jacobian"].tolist()
([0.0, 0.5], [1])
"""

from __future__ import annotations

import struct

import numpy as np

__all__ = ["MAGIC", "decode", "encode", "is_tensor_file", "bilinear", "sample_marginal",
           "u_to_theta", "theta_to_u", "v_to_phi", "phi_to_v"]

#: the first 12 bytes of every tensor file
MAGIC = b"tensor_file\0"

#: numpy dtype -> Mitsuba's struct_jit type code (``mitsuba.Struct.Type``)
_CODES: dict[np.dtype, int] = {
    np.dtype(t): code for code, t in enumerate(
        (np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.uint64, np.int64,
         np.float16, np.float32, np.float64), start=1)}
_DTYPES: dict[int, np.dtype] = {code: dt.newbyteorder("<") for dt, code in _CODES.items()}


def is_tensor_file(head: bytes) -> bool:
    """Whether ``head`` (a file's first bytes) starts like a tensor file."""
    return head[:len(MAGIC)] == MAGIC


def encode(fields: dict[str, np.ndarray]) -> bytes:
    """The tensor file holding ``fields`` (name -> array, in this order), as bytes.

    Each field's data starts at a multiple of 8 bytes (Mitsuba maps the file into memory and
    reads the arrays in place; alignment keeps those reads aligned)."""
    arrays = {}
    for name, value in fields.items():
        arr = np.ascontiguousarray(value)
        if arr.dtype not in _CODES:
            raise TypeError(f"field {name!r}: dtype {arr.dtype} has no tensor-file code")
        arrays[name] = arr.astype(arr.dtype.newbyteorder("<"), copy=False)
    header = len(MAGIC) + 2 + 4 + sum(2 + len(n.encode()) + 2 + 1 + 8 + 8 * a.ndim
                                      for n, a in arrays.items())
    offset = _align(header)
    head = bytearray(MAGIC + bytes([1, 0]) + struct.pack("<I", len(arrays)))
    body = bytearray()
    for name, arr in arrays.items():
        raw = name.encode()
        head += struct.pack("<H", len(raw)) + raw
        head += struct.pack("<HBQ", arr.ndim, _CODES[np.dtype(arr.dtype.newbyteorder("="))],
                            offset + len(body))
        head += struct.pack(f"<{arr.ndim}Q", *arr.shape)
        body += arr.tobytes()
        body += bytes(_align(len(body)) - len(body))
    head += bytes(offset - len(head))
    return bytes(head + body)


def decode(blob: bytes) -> dict[str, np.ndarray]:
    """The fields of a tensor file's bytes; a ``ValueError`` saying what is wrong otherwise."""
    if not is_tensor_file(blob):
        raise ValueError("not a tensor file (it does not start with 'tensor_file')")
    if len(blob) < len(MAGIC) + 6:
        raise ValueError("truncated tensor file (no field count)")
    if blob[13] != 0:
        raise ValueError(f"unknown tensor-file version {blob[12]}.{blob[13]}")
    (count,) = struct.unpack_from("<I", blob, 14)
    pos, fields = 18, {}
    try:
        for _ in range(count):
            (length,) = struct.unpack_from("<H", blob, pos)
            name = blob[pos + 2:pos + 2 + length].decode()
            pos += 2 + length
            ndim, code, offset = struct.unpack_from("<HBQ", blob, pos)
            pos += 11
            shape = struct.unpack_from(f"<{ndim}Q", blob, pos)
            pos += 8 * ndim
            if code not in _DTYPES:
                raise ValueError(f"field {name!r}: unknown type code {code}")
            dt = _DTYPES[code]
            n = int(np.prod(shape, dtype=np.int64))
            if offset + n * dt.itemsize > len(blob):
                raise ValueError(f"field {name!r}: data beyond the end of the file (truncated?)")
            fields[name] = np.frombuffer(blob, dt, n, offset).reshape(shape).astype(
                dt.newbyteorder("="))
    except struct.error:
        raise ValueError("truncated tensor file (inside the field table)") from None
    return fields


def _align(n: int) -> int:
    return (n + 7) // 8 * 8


# ------------------------------------------------------------------------------------------
# the parameterization (measured.cpp: u2theta, theta2u, u2phi, phi2u)
# ------------------------------------------------------------------------------------------
def u_to_theta(u):
    """Zenith (radians) of the unit coordinate ``u``: ``u**2 pi / 2``."""
    return np.square(u) * (np.pi / 2)


def theta_to_u(theta):
    """Unit coordinate of a zenith: ``sqrt(2 theta / pi)``."""
    # a zenith a rounding below 0 (acos of a float just above 1) is the normal, not a NaN
    return np.sqrt(np.maximum(theta, 0.0) * (2 / np.pi))


def v_to_phi(v):
    """Azimuth (radians, -pi .. pi) of the unit coordinate ``v``."""
    return (2 * np.asarray(v) - 1) * np.pi


def phi_to_v(phi):
    """Unit coordinate (0 .. 1) of an azimuth (radians), wrapped."""
    v = (np.asarray(phi) + np.pi) / (2 * np.pi)
    return v - np.floor(v)


def bilinear(table: np.ndarray, x, y) -> np.ndarray:
    """``table[row, col]`` on the unit square's vertex grid, interpolated bilinearly at
    ``(x, y)`` (x along the columns) - Mitsuba's ``Marginal2D::eval`` without normalization."""
    h, w = table.shape
    # outside the square (rounding) the edge's value, and the last cell holds the far edge:
    # Mitsuba's clamps, so that both read the same value there
    px = np.clip(np.asarray(x, float), 0.0, 1.0) * (w - 1)
    py = np.clip(np.asarray(y, float), 0.0, 1.0) * (h - 1)
    ix = np.minimum(px.astype(np.int64), w - 2)
    iy = np.minimum(py.astype(np.int64), h - 2)
    fx, fy = px - ix, py - iy
    top = table[iy, ix] * (1 - fx) + table[iy, ix + 1] * fx
    bottom = table[iy + 1, ix] * (1 - fx) + table[iy + 1, ix + 1] * fx
    return top * (1 - fy) + bottom * fy


def _segment(t, scale: float, v0, v1):
    """The ``x`` in [0, 1] where the integral of ``lerp(v0, v1, .)`` over [0, x], divided by
    ``scale``, reaches ``t``: the root of ``(v1 - v0) x^2 / 2 + v0 x = t scale`` in the form
    without cancellation (``x = 2 t scale / (v0 + sqrt(v0^2 + 2 t scale (v1 - v0)))``)."""
    two_t = 2.0 * t * scale
    disc = np.sqrt(np.maximum(v0 * v0 + two_t * (v1 - v0), 0.0))  # rounding below 0 only
    den = v0 + disc
    # den == 0: both ends 0 (an empty cell, reached only by rounding): its start
    x = np.divide(two_t, den, out=np.zeros_like(den), where=den > 0)
    return np.clip(x, 0.0, 1.0)  # rounding may step a hair outside the cell


def sample_marginal(data: np.ndarray, sx, sy) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's continuous ``Marginal2D::sample`` for one 2D slice, vectorized.

    ``data[row, col]`` is a density on the unit square's vertex grid, interpolated
    bilinearly; the uniform points ``(sx, sy)`` go to the points ``(x, y)`` of that density by
    the exact inverse CDF: first ``y`` from the marginal (the rows' trapezoid integrals,
    linear between rows), then ``x`` from the conditional at that ``y``.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = sample_marginal(np.ones((3, 4)), np.array([0.25]), np.array([0.5]))
    >>> x.round(12).tolist(), y.round(12).tolist()
    ([0.25], [0.5])
    """
    v = np.asarray(data, float)
    h, w = v.shape
    cond = np.cumsum((v[:, :-1] + v[:, 1:]) * (0.5 / (w - 1)), axis=1)  # (h, w-1)
    rows = cond[:, -1]
    marg = np.cumsum((rows[:-1] + rows[1:]) * (0.5 / (h - 1)))
    total = marg[-1]
    if not total > 0:
        raise ValueError("sample_marginal: the density is zero everywhere")
    v, cond, rows, marg = v / total, cond / total, rows / total, marg / total
    # Mitsuba clamps the uniform sample to [eps, 1 - eps] (float32 eps) before warping
    eps = float(np.finfo(np.float32).eps) / 2
    sy = np.clip(np.asarray(sy, float), eps, 1 - eps)
    sx = np.clip(np.asarray(sx, float), eps, 1 - eps)
    # the first row whose CDF reaches sy; sy above the last entry (rounding): the last row
    row = np.minimum(np.searchsorted(marg, sy, side="left"), h - 2)
    below = np.where(row > 0, marg[np.maximum(row - 1, 0)], 0.0)
    r0, r1 = rows[row], rows[row + 1]
    fy = _segment(sy - below, float(h - 1), r0, r1)
    sx = sx * (r0 + (r1 - r0) * fy)
    crow = cond[row] * (1 - fy)[:, None] + cond[row + 1] * fy[:, None]  # (n, w-1)
    col = np.minimum((crow < sx[:, None]).sum(axis=1), w - 2)  # as for the row
    left = np.where(col > 0, np.take_along_axis(crow, np.maximum(col - 1, 0)[:, None],
                                                axis=1)[:, 0], 0.0)
    c0 = v[row, col] * (1 - fy) + v[row + 1, col] * fy
    c1 = v[row, col + 1] * (1 - fy) + v[row + 1, col + 1] * fy
    fx = _segment(sx - left, float(w - 1), c0, c1)
    return (col + fx) / (w - 1), (row + fy) / (h - 1)

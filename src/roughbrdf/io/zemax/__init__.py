"""Zemax OpticStudio tabular BSDF files (``.bsdf``; Radiant Imaging's "BSDF Data Interchange"
format, read by OpticStudio's BSDF scatter model).

Layout (``#`` lines are comments, anywhere)::

    Source  Measured
    Symmetry  PlaneSymmetrical        <- or Asymmetrical / Asymmetrical4D
    SpectralContent  Monochrome
    ScatterType  BRDF
    SampleRotation  1                 <- each keyword with its count N, then N angles (degrees)
    0
    AngleOfIncidence  4
    15  30  50  70
    ScatterAzimuth  19
    0  10  20  ...  180
    ScatterRadial  12
    0  5  10  15  20  30  40  50  60  70  80  90

    Monochrome
    DataBegin
    TIS  0.1345                       <- one block per sample rotation, then per incidence:
    6.375E-02  6.180E-02  ...         <- one row per ScatterAzimuth, one value per ScatterRadial
    ...
    DataEnd

Sources: Zemax knowledge base, "Zemax Tabular BSDF data file format" (R. Rykowski, reviewed by
S. Auriol; https://support.zemax.com/hc/en-us/articles/1500005486801) and its 2008 original
"BSDF Data Interchange File Format Specification"
(http://www.zemax.com/kb/articles/229/1/BSDF-Data-Interchange-File-Format-Specification);
"How to use tabular BSDF data to define the surface scattering distribution"
(https://support.zemax.com/hc/en-us/articles/1500005576362).

Conventions (each pinned by a test in ``tests/io/test_io_zemax.py``):

* **AngleOfIncidence** is, in Zemax's words, "a misnomer: this angle actually represents the
  specular reflected or transmitted angle". For a BRDF the specular angle equals the angle of
  incidence, so ``theta_i = AngleOfIncidence``.
* **ScatterRadial** is the angle between the scattered direction and the specular direction
  ("Radial 0 deg is defined at the angle of specular reflection, with increasing Radial angles
  extending outward") - a true angle on the sphere, not the projected distance
  ``|beta - beta0|`` of direction cosines that OpticStudio's ABg model uses. It runs past 90 deg
  (up to ``90 + AngleOfIncidence`` toward the normal); directions beyond the horizon hold no
  BRDF.
* **ScatterAzimuth** is measured about the specular direction: "Azimuth 0 deg is defined by
  pointing from the angle of specular reflection towards the axis normal to the sample, with
  Azimuth angles increasing in a counter-clockwise fashion" (seen from above the sample).
  In the library's frame (specular direction ``s = (sin t, 0, cos t)``, source on -x) the
  scattered direction at radial ``r``, azimuth ``a`` is::

      w = cos r s + sin r (cos a u0 + sin a v),  u0 = (-cos t, 0, sin t),  v = s x u0 = (0, -1, 0)

  (:func:`roughbrdf.geometry.specular_to_common` and its inverse
  :func:`~roughbrdf.geometry.common_to_specular`; at normal incidence azimuth 0 points to the
  source side, ``phi = pi``, the limit of ``u0``). This is also the specular coordinate
  system of libbsdf (K. Ryo, ``SpecularCoordinateSystem``, MPL-2.0, which reads these files),
  and it is what public measured files obey: in the University of Arizona LOFT group's files
  (MIT licence; ``tests/data/zemax``) every non-zero value maps to ``theta_r <= 80`` deg and
  every zero to ``theta_r > 80`` deg (their cut-off) only with this convention; with the
  azimuth origin reversed, non-zero values would fall below the horizon.
* **Symmetry** ``PlaneSymmetrical``: the data are symmetric about the plane of incidence, so
  only azimuths 0-180 deg are given (the other half is their mirror image; this reader returns
  the samples of the file, ``phi <= 0`` by the handedness above, and isotropic models do not
  depend on the sign of ``phi``); ``Asymmetrical``/``Asymmetrical4D``: azimuths 0-360 deg.
* **SampleRotation** turns the sample about its normal (anisotropic samples). The library's
  models are isotropic and its frame has no sample rotation: a file with one rotation (any
  value) is read as it is (the value is kept in ``meta`` and ``original``); a file with several
  needs ``sample_rotation=`` (one of them, radians) or ``sample_rotation="all"`` (every sample,
  ``original["sample_rotation"]`` tells them apart).
* **TIS** is the total integrated scatter at that incidence, the directional-hemispherical
  reflectance of the scattered light ``int f cos(theta_r) d omega``
  (:func:`roughbrdf.albedo`). The reader keeps the file's values (``meta["zemax_tis"]``,
  shape ``(rotations, incidences)``) without using them; :func:`table_integral` computes the
  table's own integral. (Zemax's example BrownVinyl, TIS 0.1345 at 15 deg, is close to the
  cosine-weighted integral of its table, 0.129 - its radial angles stop at 80 deg - and far
  from ``int f d omega``, 0.215; some public files compute TIS otherwise.)
* Values are the BRDF in sr⁻¹ (``ScatterType BRDF``; BTDF and XYZ/tristimulus files are
  refused).

Reading: each (rotation, incidence, azimuth, radial) node is a sample; nodes below the horizon
are not BRDF geometries and are left out (counted in ``meta["zemax_below_horizon"]``, with
``meta["zemax_below_horizon_nonzero"]`` of them holding a non-zero value); nodes that are the
same direction as an earlier node (radial 0 at every azimuth: the specular direction; azimuth
360 = azimuth 0) are kept once when they hold the same value (``meta["zemax_duplicates"]``).
The file's angles (degrees) are kept in ``original`` with each node's flat index
(``zemax_index``), and the grid and TIS values in ``meta``, so that :func:`write` puts every
sample back where it was: reading and writing a ``.bsdf`` is exact.

Writing a measurement that is not on a Zemax grid (or lacks part of one) would bin, average
or fill samples: :func:`write` refuses it unless ``resample=True`` and then returns a
:class:`ZemaxWriteReport` of what it did (the rule of :mod:`roughbrdf.io.merl`). Models and
fits are written by :func:`roughbrdf.export.zemax.to_zemax`.

Layout: :mod:`~roughbrdf.io.zemax.format` (the grid :class:`ZemaxGrid`, the table
:class:`ZemaxTable`, :func:`table_integral`, :func:`grid_from_radians`,
:func:`normalize_symmetry` and the format's constants), :mod:`~roughbrdf.io.zemax.reader`
(:func:`read_table`, :func:`read`) and :mod:`~roughbrdf.io.zemax.writer` (:func:`write_table`,
:func:`plan`, :func:`write`, :class:`ZemaxWriteReport`, :func:`header_field`); the specular
frame is :mod:`roughbrdf.geometry`'s. Every name is importable from here.
"""

from __future__ import annotations

from ...geometry import common_to_specular, specular_to_common
from .format import COUNTED as COUNTED
from .format import (
    EXTENSIONS,
    SYMMETRIES,
    ZemaxGrid,
    ZemaxTable,
    grid_from_radians,
    normalize_symmetry,
    table_integral,
)
from .format import GRID_TOL as GRID_TOL
from .format import HORIZON_EPS as HORIZON_EPS
from .reader import kept_nodes as kept_nodes
from .reader import read, read_table
from .writer import WRITES as WRITES
from .writer import (
    ZemaxWriteReport,
    default_measurement_grid,
    header_field,
    plan,
    write,
    write_table,
)

__all__ = ["read", "write", "read_table", "write_table", "table_integral", "plan",
           "specular_to_common", "common_to_specular", "grid_from_radians",
           "default_measurement_grid", "normalize_symmetry", "header_field", "ZemaxGrid",
           "ZemaxTable", "ZemaxWriteReport", "EXTENSIONS", "SYMMETRIES"]

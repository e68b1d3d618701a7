"""Stray-light scatter models of the optical codes: ABg, Harvey–Shack, and their TIS.

Importing this package registers :class:`ABg` (``"abg"``) and :class:`HarveyShack`
(``"harvey-shack"``, ``"hs"``) with :func:`roughbrdf.model`. ``docs/straylight.md``.
"""

from .abg import ABg, beta_distance
from .harvey_shack import HarveyShack
from .tis import (
    abg_tis,
    abg_tis_plane,
    check_abg,
    check_harvey_shack,
    harvey_shack_radial,
    harvey_shack_tis,
    harvey_shack_tis_plane,
)

__all__ = ["ABg", "HarveyShack", "abg_tis", "abg_tis_plane", "beta_distance", "check_abg",
           "check_harvey_shack", "harvey_shack_radial", "harvey_shack_tis",
           "harvey_shack_tis_plane"]

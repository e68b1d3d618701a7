"""libbsdf's reflectance of roughbrdf's LightTools and Zemax exports, for
``tests/export/test_export_tables.py`` (its ``LIBBSDF`` figures).

libbsdf (K. Ryo, MPL-2.0, https://github.com/KimuraRyo/libbsdf) is not a dependency of
roughbrdf: build it once, with the small reader program beside this script
(``scripts/libbsdf_reflectance.cpp``), and pass the program::

    apt-get install -y libeigen3-dev          # Debian's Eigen 3.4.0 (3.4.0-4)
    git clone https://github.com/KimuraRyo/libbsdf src
    git -C src checkout eb62dc164b6c6d6b107f720aef17dc0b6b2eda23
    cmake -S src -B build -DCMAKE_BUILD_TYPE=Release -DLIBBSDF_BUILD_APPLICATIONS=OFF \\
          -DLIBBSDF_USE_OPENMP=OFF
    make -C build libbsdf
    g++ -std=c++17 -O2 -msse3 -Isrc/include -I/usr/include/eigen3 \\
        scripts/libbsdf_reflectance.cpp build/liblibbsdf.a -o libbsdf_reflectance
    ROUGHBRDF_SHARED_DATA=../shared/data python scripts/libbsdf_tables.py ./libbsdf_reflectance

It writes the four must-show files of issue 29 with the default grid into a scratch folder -
ABg (A = 0.02, B = 1e-3, g = 1.8) and the coated fit of C2_Black at 525 nm
(``rb.fit("coated", ..., channel="525nm", starts=1)``), each to LightTools and Zemax - and
prints, per file and incidence, roughbrdf's TIS and table integral and libbsdf's two figures:
``lb::computeReflectance`` on the file's own nodes and with its default 360 x 360 specular
divisions of the interpolated table (the program's comment says how each integrates).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import roughbrdf as rb
from roughbrdf.export.lighttools import to_lighttools
from roughbrdf.export.zemax import to_zemax


def models() -> dict[str, rb.Model]:
    """The must-show models: ABg and the coated fit of C2_Black (525 nm)."""
    data = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", "../shared/data"))
    paint = rb.read(data / "minidiff" / "C2_Black.astm")
    fit = rb.fit("coated", paint, channel="525nm", starts=1)
    return {"abg": rb.model("abg", A=0.02, B=0.001, g=1.8), "c2_black": fit.channels[0].model}


def main(program: str) -> None:
    warnings.simplefilter("error")  # the default grids meet TIS: no warning expected
    with tempfile.TemporaryDirectory() as scratch:
        for name, model in models().items():
            print(f"# {name}: {model!r}")
            for fmt, write in (("lighttools", to_lighttools), ("zemax", to_zemax)):
                done = write(model, Path(scratch) / f"{name}_{fmt}.bsdf")
                f = done if fmt == "lighttools" else done[0]
                tis = np.ravel(f.tis["value"] if fmt == "lighttools" else f.tis)
                own = np.ravel(f.integral["value"] if fmt == "lighttools" else f.integral)
                out = subprocess.run([program, fmt, str(f.path)], capture_output=True,
                                     text=True, check=True).stdout.split("\n")
                print(f"# {fmt} grid {f.grid.shape}: AOI TIS table_integral libbsdf_nodes "
                      "libbsdf_360")
                for line, t, i in zip([s for s in out if s], tis, own, strict=True):
                    _, aoi, nodes, spec = line.split()
                    print(f"{name} {fmt} {float(aoi):g} {t:.6f} {i:.6f} {float(nodes):.6f} "
                          f"{float(spec):.6f}")


if __name__ == "__main__":
    main(sys.argv[1])

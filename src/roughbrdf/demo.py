"""The main job (``make demo``): two checks against the papers, then a full fit.

``python -m roughbrdf.demo --out out``

1. TS67 Fig. 8 (Eq. 23, F = 1, g = 2/3, c = 0.05/deg): the forward-peak table, computed with
   ``rb.model("torrance-sparrow-1967").relative``, next to docs/models.md §2.7.
2. TR75 Table 1: directional-hemispherical reflectance at normal incidence of the six fitted
   surfaces, computed with ``rb.albedo``, next to docs/models.md §3.10 and the paper's estimates.
3. The fitting job, the same as ``roughbrdf fit`` on a user file: the measurement embedded in the
   package (``roughbrdf/data/tr75_cement.csv``, a relative BRIDF of TR75's cement at TR75's own
   measurement design with 10 % noise; see ``roughbrdf/data/make_default.py``) is fitted with the
   TR75 model from a neutral start; the recovered parameters are printed next to the true ones,
   with TR75's sigma, and ``fit.json``, ``report.txt`` and the plot are written to ``--out``.

Everything goes into ``--out`` as one set (:class:`roughbrdf.output.ResultFolder`): a folder
that holds results already is refused before any work unless ``--force`` (``make demo`` passes
it for its own ``out/``), files roughbrdf did not write are never replaced, and an error or
Ctrl-C leaves the folder as it was. Exit status as ``roughbrdf`` (:mod:`roughbrdf.cli`): 0, 1 if
the fit did not converge, 2 refused or bad input, 3 an error of the operating system, 130
interrupted.
"""

from __future__ import annotations

import argparse
import math
import sys
from importlib import resources
from pathlib import Path
from typing import Any, cast

import numpy as np

import roughbrdf as rb

from .output import ResultFolder

#: the embedded default measurement and the parameters it was generated from
DEFAULT_FILE = "tr75_cement.csv"
TRUE = {"e": 0.68, "n": 1.00, "k": 0.9, "rho_L": 0.33}
#: neutral starting values (not the truth): the multistart also searches the whole bounds
START = {"e": 0.3, "n": 1.5, "k": 0.1, "rho_L": 0.5}

# docs/models.md §2.7, Fig. 8 (F = 1, g = 2/3, c = 0.05/deg): psi -> (theta_max, ratio at max,
# ratio at theta = 0, at 89.99 deg, at -60 deg)
TS67_FIG8 = {10: (13.3, 1.002, 0.970, 0.610, 0.627), 30: (43.0, 1.031, 0.762, 0.678, 0.533),
             45: (75.0, 1.318, 0.543, 0.979, 0.429), 60: (80.0, 1.904, 0.311, 1.819, 0.273),
             75: (90.0, 3.19, 0.095, 3.194, 0.091)}

# docs/models.md §3.10, TR75 Table 1: name -> (e, n, k, rho_L, interface DHR, total DHR, paper)
TR75_TABLE1 = {
    "3M Black Velvet (min 1)": (0.89, 1.60, 0.00, 0.020, 0.031, 0.051, "order of 4 %"),
    "3M Black Velvet (min 2)": (0.88, 1.62, 0.3, 0.022, 0.040, 0.062, "order of 4 %"),
    "soiled olive drab": (0.24, 1.0, 0.4, 0.06, 0.038, 0.097, "order of 5 %"),
    "cement": (0.68, 1.00, 0.9, 0.33, 0.120, 0.450, "order of 50 %"),
    "plywood": (0.51, 0.9, 1.9, 0.40, 0.399, 0.799, "order of 70 %"),
    "grass": (1.6, 0.7, 1.3, 0.5, 0.112, 0.612, "order of 60 %"),
}


def default_measurement_path() -> Path:
    """Path of the embedded default measurement (inside the installed package)."""
    return Path(str(resources.files("roughbrdf") / "data" / DEFAULT_FILE))


def ts67_fig8_table() -> str:
    """TS67 Fig. 8 forward-peak table, computed vs docs/models.md §2.7."""
    # TS67 has .relative (Eq. 23); rb.model is typed as returning the base Model
    ts = cast(Any, rb.model("torrance-sparrow-1967", g=2 / 3, c=0.05, n=None, k=None))
    theta = np.radians(np.append(np.arange(0.0, 89.99, 0.05), 89.99))
    lines = ["TS67 Fig. 8: relative reflectance, Eq. 23 (F = 1, g = 2/3, c = 0.05/deg), "
             "plane of incidence",
             "  computed (this library) | docs/models.md §2.7",
             f"  {'psi':>4} {'theta_max':>9} {'at max':>7} {'at 0':>6} {'at 89.99':>8} "
             f"{'at -60':>6} | {'theta_max':>9} {'at max':>7} {'at 0':>6} {'at 89.99':>8} "
             f"{'at -60':>6}"]
    for psi, ref in TS67_FIG8.items():
        p = math.radians(psi)
        r = np.asarray(ts.relative(p, theta, 0.0))
        i = int(np.argmax(r))
        r0 = float(ts.relative(p, 0.0, 0.0))
        r89 = float(ts.relative(p, math.radians(89.99), 0.0))
        rm60 = float(ts.relative(p, math.radians(60.0), math.pi))
        tmax = math.degrees(theta[i])
        tmax_s = "->90" if tmax > 89.9 else f"{tmax:.1f}"
        lines.append(f"  {psi:>4} {tmax_s:>9} {r[i]:>7.3f} {r0:>6.3f} {r89:>8.3f} {rm60:>6.3f} | "
                     f"{ref[0]:>9.1f} {ref[1]:>7.3f} {ref[2]:>6.3f} {ref[3]:>8.3f} {ref[4]:>6.3f}")
    lines.append("  (psi = 75: the ratio keeps rising to grazing; max over theta <= 89.99 deg; "
                 "docs/models.md rounds it to 3.19)")
    return "\n".join(lines)


def tr75_table1_dhr() -> str:
    """TR75 Table 1 surfaces: DHR at normal incidence (unpolarized) vs docs/models.md §3.10."""
    lines = ["TR75 Table 1: directional-hemispherical reflectance at normal incidence "
             "(rb.albedo, unpolarized)",
             f"  {'surface':<24} {'e':>5} {'n':>5} {'k':>4} {'rho_L':>6} | {'interface':>9} "
             f"{'total':>6} | {'models.md':>9} {'total':>6} | paper's estimate"]
    for name, (e, n, k, rho, ref_i, ref_t, paper) in TR75_TABLE1.items():
        m = rb.model("trowbridge-reitz-1975", e=e, n=n, k=k, rho_L=rho)
        total = float(rb.albedo(m, 0.0))
        interface = float(rb.albedo(m.with_params(rho_L=0.0), 0.0))
        lines.append(f"  {name:<24} {e:>5.2f} {n:>5.2f} {k:>4.1f} {rho:>6.3f} | "
                     f"{interface:>9.3f} {total:>6.3f} | {ref_i:>9.3f} {ref_t:>6.3f} | {paper}")
    cement = rb.model("trowbridge-reitz-1975", **TRUE)
    betas = (0, 30, 60, 80)
    dhr = np.atleast_1d(rb.albedo(cement, np.radians(betas)))
    lines.append("  cement DHR vs incidence beta (no shadowing, rises with beta): "
                 + ", ".join(f"{b} deg {v:.3f}" for b, v in zip(betas, dhr, strict=True))
                 + "  (docs/models.md: 0.450, 0.464, 0.548, 0.919)")
    return "\n".join(lines)


def recovered_table(res: rb.FitResult) -> str:
    """Recovered parameters next to the true ones, with stderr and the deviation in stderr."""
    c = res.channels[0]
    lines = [f"  {'parameter':<9} {'true':>7} {'start':>7} {'fitted':>9} {'stderr':>8} "
             f"{'(fit-true)/stderr':>17}"]
    for name, truth in TRUE.items():
        v, se = c.params[name], c.stderr[name]
        if v is None:  # a part switched off (never for TR75)
            continue
        se = math.nan if se is None else se
        z = (v - truth) / se if math.isfinite(se) and se > 0 else math.nan
        lines.append(f"  {name:<9} {truth:>7.3f} {START[name]:>7.3f} {v:>9.4f} {se:>8.4f} "
                     f"{z:>+17.2f}")
    lines.append(f"  TR75 sigma = {c.sigma:.4f} (the data carry 10 % noise: sigma ~ 0.10 "
                 f"expected); r.m.s. log residual = {c.rms_log:.4f}; scale K = {c.scale:.4g}")
    return "\n".join(lines)


#: the files of the demo, all in one folder
TABLE_FILES = ("ts67_fig8.txt", "tr75_table1_dhr.txt", "recovered.txt")


def main(argv: list[str] | None = None) -> int:
    """Run the demo; returns the exit status (0, or 1 if the fit did not converge)."""
    ap = argparse.ArgumentParser(prog="python -m roughbrdf.demo",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="out", help="output folder (default: out)")
    ap.add_argument("--starts", type=int, default=8, help="multistart points (default 8)")
    ap.add_argument("--force", action="store_true",
                    help="replace the results of an earlier run in --out (files roughbrdf did "
                         "not write are never replaced)")
    args = ap.parse_args(argv)
    out = ResultFolder(args.out, overwrite=args.force)
    out.check([*TABLE_FILES, "fit.json", "report.txt", "fit_relative.png"])  # before any work

    t1 = ts67_fig8_table()
    print(t1, end="\n\n", flush=True)
    t2 = tr75_table1_dhr()
    print(t2, end="\n\n", flush=True)

    path = default_measurement_path()
    meas = rb.read(path)
    print(f"Fitting the embedded default measurement: {meas.summary()}", flush=True)
    # energy_constraint=False: TR75's own fits were unconstrained (this one's albedo reaches
    # 1.46 at 85 deg; the constrained refit would change the recovered parameters);
    # loss="relative": TR75's own loss, whose r.m.s. is the sigma the paper reports (Eq. 34)
    res = rb.fit(rb.model("trowbridge-reitz-1975", **START), meas, starts=args.starts,
                 energy_constraint=False, loss="relative")
    print(res.report(), end="\n\n")
    t3 = "Recovered vs true (TR75 Table 1, cement):\n" + recovered_table(res)
    print(t3)
    with out:
        for name, text in zip(TABLE_FILES, (t1, t2, t3), strict=True):
            out.add(name, text + "\n")
        for name, content in res.files().items():
            out.add(name, content, binary=callable(content))
    print(f"\nwrote {', '.join(sorted(out.previous()))} into {out.path}/")
    return 0 if res.success else 1


def _console() -> int:
    """``python -m roughbrdf.demo``: :func:`main` with the errors and Ctrl-C of the CLI (one
    line on stderr, the exit statuses of :mod:`roughbrdf.cli`; a bug keeps its traceback)."""
    from .cli import EXIT_BUG, EXIT_INTERRUPTED
    from .cli.common import error_message, exit_status
    from .interrupts import interrupted, watch

    with watch():
        try:
            code = main()
        except KeyboardInterrupt:
            code = EXIT_INTERRUPTED
        except Exception as exc:
            code = exit_status(exc)
            if code == EXIT_BUG:
                raise
            print(f"error: {error_message(exc, {'overwrite': '--force'}, code)}",
                  file=sys.stderr)
        if interrupted() or code == EXIT_INTERRUPTED:
            print("interrupted", file=sys.stderr)
            code = EXIT_INTERRUPTED
    return code


if __name__ == "__main__":
    sys.exit(_console())

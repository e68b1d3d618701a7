"""``roughbrdf plot``: plot a model (in-plane, polar or hemisphere) or a fit's comparison.

``--out FILE.png`` is written atomically and never replaces a file unless ``--force``
(:func:`roughbrdf.output.atomic_write`). ``--fit DIR`` without ``--out`` adds
``comparison_<channel>.png`` to the fit's results in DIR (:class:`roughbrdf.output.ResultFolder`
with ``extend=True``: a later ``roughbrdf fit --force`` into DIR replaces them with the rest).
The measurement of the fit is found from any folder (``fit.json``'s ``file``, else
``file_abspath``, else ``file`` beside ``fit.json``); a warning says when it has changed since
the fit (``file_sha256``). The fit's folder is checked first, as every reader of a results
folder checks it (:func:`roughbrdf.result_check.check_result_folder`): a write cut off by a kill
is completed or undone, a folder being written or changed since roughbrdf wrote it is refused.
"""

from __future__ import annotations

import errno
import math
import re
from pathlib import Path
from typing import Annotated, Any

import typer

from .common import PLOT_OPTIONS, cli_model, degree_range, handled, parse_params
from .options import OptionError, pick_channel, unknown_value

KINDS = ("in-plane", "polar", "hemisphere", "mueller", "mueller-plane", "dolp")

#: the library's argument names -> this verb's options (errors name the options)
OPTIONS = PLOT_OPTIONS


def _check_out(path: Path, force: bool) -> None:
    from ..output import OverwriteRefused

    if path.is_dir():
        raise IsADirectoryError(errno.EISDIR, "a folder; --out names the PNG file to write",
                                str(path))
    if path.suffix.lower() != ".png":
        raise ValueError(f"--out must be a .png file, got {str(path)!r}")
    if path.exists() and not force:
        raise OverwriteRefused(path, single=True)


def _png(fig: Any, dpi: int = 100) -> Any:
    """A writer of ``fig`` as PNG into an open binary file."""
    return lambda fh: fig.savefig(fh, format="png", dpi=dpi)


def _write_png(fig: Any, path: Path, force: bool) -> Path:
    """``fig`` to ``path`` atomically (the folder is created if needed)."""
    from ..output import atomic_write, ensure_folder

    ensure_folder(path.parent if str(path.parent) else Path("."))
    return atomic_write(path, _png(fig), overwrite=force, binary=True)


def check_elevation(elevation: float) -> float:
    """``--elevation DEG`` (the reflection elevation of ``--kind polar``) -> radians; refused
    outside 0 <= DEG <= 90 (also NaN), whatever the kind, before anything is drawn.

    Examples
    --------
    >>> check_elevation(200)
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: --elevation 200: must be a reflection elevation in ...
    """
    if not (math.isfinite(elevation) and 0 <= elevation <= 90):  # else worded in radians
        raise OptionError("--elevation", f"--elevation {elevation:g}: must be a reflection "
                                         f"elevation in degrees, 0 <= DEG <= 90")
    return math.radians(elevation)


def _model_figure(m: Any, kind: str, ti: Any, elevation: float, quantity: str,
                  log: bool | None):
    """The figure of model ``m`` (``ti``: incidences in radians, ``elevation`` in degrees)."""
    import numpy as np

    from .. import plot as rbplot

    if kind in ("mueller", "mueller-plane", "dolp"):
        return _polarimetric_figure(m, kind, ti)
    if kind == "in-plane":
        if np.any(ti >= 0.5 * math.pi):
            raise ValueError("--theta-i must be below 90 degrees")
        return rbplot.plot_in_plane(m, ti, quantity=quantity, log=bool(log))
    if ti.size != 1:
        raise ValueError(f"--kind {kind} takes one --theta-i, got {ti.size}")
    if kind == "polar":
        return rbplot.plot_polar(m, float(ti[0]), check_elevation(elevation), label=m.name)
    return rbplot.plot_hemisphere(m, float(ti[0]), quantity=quantity,
                                  log=True if log is None else log)


def _polarimetric_figure(m: Any, kind: str, ti: Any):
    """The Mueller-matrix and DoLP figures (:mod:`roughbrdf.plot_mueller`)."""
    import numpy as np

    from .. import plot_mueller

    if np.any(ti >= 0.5 * math.pi):
        raise ValueError("--theta-i must be below 90 degrees")
    if kind == "mueller-plane":
        return plot_mueller.plot_mueller_in_plane(m, ti)
    if ti.size != 1:
        raise ValueError(f"--kind {kind} takes one --theta-i, got {ti.size}")
    if kind == "mueller":
        return plot_mueller.plot_mueller_hemisphere(m, float(ti[0]))
    return plot_mueller.plot_dolp(m, float(ti[0]))


def _fit_aperture(fit: dict[str, Any]):
    """The instrument aperture the fit used (``fit.json`` ``aperture``), or None."""
    from ..instrument import Aperture

    ap = fit.get("aperture")
    if not isinstance(ap, dict):
        return None
    return Aperture.parse(ap["half_angle_rad"], ap.get("points", 19))


def _input_file(fit: dict[str, Any], base: Path) -> tuple[Path, bool]:
    """The fit's measurement file and whether it has changed since the fit.

    ``file`` as recorded (relative to the current folder), else ``file_abspath``, else ``file``
    beside fit.json; with ``file_sha256`` the first candidate whose contents match wins.
    """
    given = Path(str(fit["file"]))
    candidates = [given]
    if not given.is_absolute():
        if fit.get("file_abspath"):
            candidates.append(Path(str(fit["file_abspath"])))
        candidates.append(base / given)
    found = [c for c in dict.fromkeys(candidates) if c.is_file()]
    if not found:
        raise FileNotFoundError(f"{base / 'fit.json'}: the fit's measurement file "
                                f"{fit['file']!r} is not found or is not a file (looked in "
                                f"{', '.join(str(c) for c in candidates)})")
    digest = fit.get("file_sha256")
    if not digest:
        return found[0], False  # a fit.json of an older roughbrdf
    from ..output import file_sha256

    for c in found:
        if file_sha256(c) == digest:
            return c, False
    return found[0], True


def _fit_measurement(fit: dict[str, Any], base: Path):
    from dataclasses import replace

    from .. import io as rbio

    path, changed = _input_file(fit, base)
    if changed:
        typer.echo(f"warning: {path} has changed since the fit (its SHA-256 differs from "
                   f"fit.json's file_sha256); plotting the fit against the file as it is now",
                   err=True)
    try:
        meas = rbio.read(path)
    except ValueError:
        q = fit.get("quantity")
        if not q:
            raise
        meas = rbio.read(path, quantity=q)  # e.g. ALTA files without #PARAM_OUT
    if meas.quantity == "relative" and fit.get("relative_to"):
        meas = replace(meas, meta={**meas.meta, "relative_to": fit["relative_to"]})
    return meas


def _safe(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(label)) or "channel"


def _fit_channels(fit: dict[str, Any], channel: str | None, out: Path | None
                  ) -> list[dict[str, Any]]:
    """The channels of ``fit`` to draw (``--channel``), checked against ``--out``."""
    chans = fit["channels"]
    if channel is not None:  # a label or an index, as for every verb's --channel
        chans = [chans[pick_channel([str(c.get("channel")) for c in chans], channel)]]
    if out is not None and len(chans) > 1:
        raise ValueError("--out names one file but the fit has several channels; pick one with "
                         "--channel or omit --out (files go into the fit directory)")
    return chans


def _fit_samples(fit: dict[str, Any], chan: dict[str, Any], meas: Any, ch: int, model: Any,
                 aperture: Any) -> tuple[Any, str]:
    """The samples of channel ``ch`` the fit used, as it compared them, and a note of those left
    out and why.

    The selection is the fit's own (:func:`roughbrdf.fitting.problem.data.prepare_channel` with the
    options of ``fit.json``); the values are multiplied by the fitted scale ``K`` and labelled
    with the compared quantity, as :meth:`FitResult.plot_data
    <roughbrdf.fitting.FitResult.plot_data>` does.
    """
    from dataclasses import replace

    from ..fitting.problem.data import Comparison, DataOptions, excluded_text, prepare_channel
    from ..quantity import Quantity

    o = fit.get("options")
    if not isinstance(o, dict):  # a fit.json of an older roughbrdf, or edited: the defaults
        o = {}
    weights = o.get("weights")
    opts = DataOptions(Comparison.of(meas, fit.get("relative_to")), fit.get("loss") or "relative",
                       "uncertainty" if weights == "uncertainty" else None,
                       o.get("nonfinite") or "raise", o.get("negative") or "keep", aperture,
                       o.get("theta_r_max"), o.get("source_exclusion"),
                       o.get("extrapolated") or "drop")
    data = prepare_channel(model, meas, ch, opts)
    sub = meas.subset(data.index).select_channel(ch)
    scale = float(chan.get("scale") or 1.0)
    sub = replace(sub, values=(scale * data.values)[:, None], uncertainty=None,
                  quantity=Quantity.parse(fit.get("compared") or "brdf").compared_with(),
                  meta=dict(sub.meta))
    note = (f"{data.n} of {meas.n_samples} samples drawn: those the fit used; left out: "
            f"{excluded_text(data.excluded)}")
    if weights == "array":  # fit.json does not record a weights array: its zeros are unknown
        note += " (the fit's weights are not recorded: samples of weight 0 are drawn too)"
    return sub, note


def _fit_figure(fit: dict[str, Any], fit_dir: Path, meas: Any, chan: dict[str, Any],
                aperture: Any) -> Any:
    """Data vs model and the residual maps of one channel of the fit, on the fit's samples."""
    from .. import plot_fit
    from ..fitting.results.fit_json import channel_model

    model = channel_model(fit, chan)
    label = chan.get("channel")
    ch = meas.channel_index(label) if str(label) in meas.channels else 0
    sub, note = _fit_samples(fit, chan, meas, ch, model, aperture)
    fig, _axes = plot_fit.plot_fit(
        model, sub, aperture=aperture, note=note,
        title=f"fit {fit_dir}: {fit['model']} to {Path(str(fit['file'])).name} [{label}], "
              f"loss {fit.get('loss', '?')}")
    return fig


def _fit_figures(fit_dir: Path, out: Path | None, channel: str | None, force: bool
                 ) -> list[Path]:
    """Draw the comparison of each channel of the fit in ``fit_dir``: into ``out``, or added to
    the fit's results in its folder; everything is checked before the drawing."""
    from ..fitting.results.fit_json import check_fit_channels, read_fit_json
    from ..output import ResultFolder
    from ..result_check import check_result_folder

    # one whole set (a cut-off write recovered) or refused, before fit.json is trusted
    check_result_folder(fit_dir if fit_dir.is_dir() else fit_dir.parent, options=OPTIONS)
    fit, base = read_fit_json(fit_dir, channels=False)
    _input_file(fit, base)  # the measurement named first: without it nothing can be drawn
    check_fit_channels(fit, fit_dir / "fit.json" if fit_dir.is_dir() else fit_dir)
    chans = _fit_channels(fit, channel, out)
    if out is not None:
        _check_out(out, force)
        meas = _fit_measurement(fit, base)
        fig = _fit_figure(fit, fit_dir, meas, chans[0], _fit_aperture(fit))
        return [_write_png(fig, out, force)]
    names = [f"comparison_{_safe(str(c.get('channel')))}.png" for c in chans]
    folder = ResultFolder(base, overwrite=force, extend=True)
    folder.check(names)
    meas = _fit_measurement(fit, base)
    aperture = _fit_aperture(fit)
    with folder:
        for c, name in zip(chans, names, strict=True):
            folder.add(name, _png(_fit_figure(fit, fit_dir, meas, c, aperture)), binary=True)
    return [base / n for n in names]


def register(app: typer.Typer) -> None:
    @app.command("plot")
    def plot_cmd(
        model: Annotated[str | None, typer.Argument(
            help="model name, e.g. trowbridge-reitz-1975")] = None,
        param: Annotated[list[str] | None, typer.Option(
            "-p", "--param",
            help="name=value (repeatable; angles such as sigma in degrees)")] = None,
        kind: Annotated[str, typer.Option(
            help="in-plane, polar, hemisphere; mueller (16 elements over the hemisphere), "
                 "mueller-plane (in the plane of incidence) or dolp")] = "in-plane",
        theta_i: Annotated[str, typer.Option(
            "--theta-i", help="incidence, DEG or START:STOP:STEP (one value for "
                              "polar/hemisphere)")] = "0:60:20",
        elevation: Annotated[float, typer.Option(
            help="polar: reflection elevation (TR75 theta), DEG")] = 45.0,
        quantity: Annotated[str, typer.Option(
            help="output: the quantity plotted, brdf, brdf_cos (= bridf), bridf or relative "
                 "(to the specular value)")] = "brdf",
        log: Annotated[bool | None, typer.Option(
            "--log/--linear", help="logarithmic value axis/colours")] = None,
        fit: Annotated[Path | None, typer.Option(
            help="a fit directory (with fit.json): plot data vs model and the residual "
                 "map")] = None,
        channel: Annotated[str | None, typer.Option(help="with --fit: one channel")] = None,
        out: Annotated[Path | None, typer.Option("--out", "-o", help="output PNG file")] = None,
        force: Annotated[bool, typer.Option(
            help="replace an existing --out file, or the comparison figures of an earlier "
                 "plot --fit")] = False,
    ) -> None:
        """Plot a model (MODEL -p name=value ...) or a fit (--fit DIR) to a PNG file.

        Angles are in degrees. Examples:

          roughbrdf plot trowbridge-reitz-1975 -p e=0.3 -p n=1.5 -p k=0 -p rho_L=0.1
          --theta-i 0:60:30 --log --out tr.png

          roughbrdf plot --fit fitdir          (writes fitdir/comparison_<channel>.png)
        """
        with handled(OPTIONS):
            import matplotlib

            matplotlib.use("Agg")
            for p in _plot(model, parse_params(param), kind, theta_i, elevation, quantity, log,
                           fit, channel, out, force):
                typer.echo(f"wrote {p}")


def _plot(model: str | None, params: dict[str, Any], kind: str, theta_i: str, elevation: float,
          quantity: str, log: bool | None, fit: Path | None, channel: str | None,
          out: Path | None, force: bool) -> list[Path]:
    """The work of ``roughbrdf plot``; returns the files written."""
    from ..quantity import Quantity

    if fit is not None:
        if model is not None:
            raise ValueError("give either MODEL or --fit DIR, not both")
        return _fit_figures(fit, out, channel, force)
    if model is None:
        raise ValueError("give a MODEL name (see `roughbrdf models`) or --fit DIR")
    if out is None:
        raise ValueError("--out FILE.png is required")
    if kind not in KINDS:
        raise unknown_value("--kind", kind, KINDS)
    q = Quantity.parse(quantity, "--quantity").value
    check_elevation(elevation)  # every option checked before --out and the drawing
    m = cli_model(model, params, "MODEL")  # -p angles (Oren-Nayar sigma) in degrees
    ti = degree_range(theta_i, "--theta-i")
    _check_out(out, force)
    fig, _ax = _model_figure(m, kind, ti, elevation, q, log)
    return [_write_png(fig, out, force)]

"""Exports of models and fits to the tools where BRDFs are used (``docs/export.md``).

One module (or package) per target: :mod:`~roughbrdf.export.zemax` (Zemax OpticStudio tabular
BSDF, the model sampled on a grid relative to the specular direction) and
:mod:`~roughbrdf.export.mitsuba` (Mitsuba 3 scene-description dicts and XML ``<bsdf>``
elements). :func:`export` writes any of them to a file by the project's output rules (no file
replaced unless ``overwrite=True``; each written atomically), which is what ``roughbrdf
export`` runs. At the top level: ``rb.export_to`` (:func:`export`), ``rb.export_zemax`` and
``rb.export_mitsuba``. (``rb.export`` is this package.)

``export_zemax`` *is* :func:`roughbrdf.export.zemax.to_zemax` and ``export_mitsuba`` *is*
:func:`roughbrdf.export.mitsuba.export_mitsuba` (the same function objects, with their
signatures and docstrings), loaded on first use (PEP 562 module ``__getattr__``) so that
``import roughbrdf.export`` loads no NumPy.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ArgumentError

if TYPE_CHECKING:  # for type checkers and IDEs; at run time the two load on first use
    from .mitsuba import export_mitsuba
    from .zemax import to_zemax as export_zemax

__all__ = ["ENERGY_NOTE_KEY", "TARGETS", "ExportResult", "export", "export_mitsuba", "export_to",
           "export_zemax", "target_name"]

#: ``to=`` -> what is written
TARGETS = {
    "zemax": "Zemax OpticStudio tabular BSDF (.bsdf), one file per channel",
    "mitsuba": "Mitsuba 3 scene-description dict as JSON (mitsuba.load_dict(json.load(f)))",
    "mitsuba-xml": "Mitsuba 3 XML <bsdf> element (a document mitsuba.load_string loads)",
    "lighttools": "LightTools BSDF (.bsdf), one file per channel",
    "zemax-abg": "Zemax OpticStudio ABg catalog values (.txt table to enter; ABg fits only)",
    "rgl": "RGL measured-BSDF tensor file (.bsdf; Mitsuba 3 'measured', Dupuy & Jakob 2018)",
}


@dataclass
class ExportResult:
    """What :func:`export` wrote.

    Attributes
    ----------
    target : str
    paths : list of pathlib.Path
        The files written.
    report : str
        How the export went: the Zemax files' TIS and table integrals, or how each Mitsuba
        term was mapped and how far Mitsuba's values are from the model's.
    detail : object
        The target's own record (:class:`~roughbrdf.export.zemax.ZemaxExport` or
        :class:`~roughbrdf.export.mitsuba.MitsubaExport`).
    """

    target: str
    paths: list[Path]
    report: str
    detail: Any = field(repr=False, default=None)


def target_name(to: str) -> str:
    """The canonical target of ``to`` (aliases: opticstudio, bsdf, xml, json...); an
    :class:`~roughbrdf.errors.ArgumentError` naming ``to`` otherwise."""
    key = str(to).strip().lower().replace("_", "-")
    key = {"opticstudio": "zemax", "bsdf": "zemax", "xml": "mitsuba-xml",
           "mitsuba-dict": "mitsuba", "json": "mitsuba", "abg": "zemax-abg",
           "lt": "lighttools"}.get(key, key)
    if key not in TARGETS:
        raise ArgumentError("to", f"unknown target; choose one of {', '.join(TARGETS)}",
                            value=to)
    return key


def export(source: Any, out: str | os.PathLike, *, to: str, overwrite: bool = False,
           channel: int | str | None = None, **options: Any) -> ExportResult:
    """Write a model or a fit for another tool.

    Parameters
    ----------
    source : Model, FitResult or mapping
        A model (``rb.model``), a fit (``rb.fit``), or ``{channel: model}``
        (:func:`roughbrdf.fitting.results.fit_json.fitted_models` reads one from a fit's folder).
    out : str or path-like
        The file (``.bsdf``, ``.json`` or ``.xml`` added without a suffix). A fit whose
        channels are not one BSDF gives one file per channel, ``<stem>_<channel><suffix>``
        beside it (Mitsuba: where the channels differ in more than colours).
    to : {"zemax", "mitsuba", "mitsuba-xml", "lighttools", "zemax-abg", "rgl"}
        The target (:data:`TARGETS`): also LightTools BSDF files
        (:func:`~roughbrdf.export.lighttools.to_lighttools`), the Zemax ABg catalog
        values of an ABg fit (:func:`~roughbrdf.export.abg_catalog.write_abg_catalog`; a
        per-incidence fit writes its kept rows) and an RGL measured-BSDF file, all channels
        in one (:func:`~roughbrdf.export.rgl.to_rgl`).
    overwrite : bool
        Replace existing files (default: refuse, before writing anything).
    channel : int or str, optional
        One channel of a fit.
    **options
        The target's own: Zemax and LightTools ``angles_of_incidence``, ``radial``,
        ``azimuth`` (radians), ``symmetry``, ``polarization``
        (:func:`~roughbrdf.export.zemax.to_zemax`,
        :func:`~roughbrdf.export.lighttools.to_lighttools`: a grid refined until each table's
        own integral is within 0.5 % of its TIS, or the ``radial``/``azimuth`` given, with a
        :class:`~roughbrdf.export.grids.TableAccuracyWarning` when they miss it); Mitsuba
        ``rgb``, ``fit``, ``theta_max`` (:func:`~roughbrdf.export.mitsuba.export_mitsuba`);
        RGL ``color``, ``resolution``, ``description`` (:func:`~roughbrdf.export.rgl.to_rgl`);
        all ``allow_energy_gain``: a model whose albedo exceeds ``1 + 1e-3`` at an incidence
        of 0, 5, ... 85, 89 deg is refused (an :class:`~roughbrdf.errors.ArgumentError`
        naming the albedo and the incidence) unless it is True, which the file records (a
        Zemax header comment, an XML comment, the JSON key :data:`ENERGY_NOTE_KEY`, the RGL
        file's ``description``).

    Returns
    -------
    ExportResult

    Examples
    --------
    >>> import roughbrdf as rb, tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> res = rb.export_to(rb.model("lambertian", rho=0.25), folder / "paint.xml",
    ...                    to="mitsuba-xml")
    >>> print(res.paths[0].read_text().strip())
    <bsdf type="diffuse" version="3.0.0">
      <float name="reflectance" value="0.25" />
    </bsdf>
    >>> rb.export_to(rb.model("lambertian"), folder / "paint.xml", to="mitsuba-xml")
    Traceback (most recent call last):
    ...
    roughbrdf.output.OverwriteRefused: ...paint.xml exists; not overwriting it (pass overwrite=True)
    """
    target = target_name(to)
    if target == "rgl":
        from .rgl import to_rgl

        rgl = to_rgl(source, out, channel=channel, overwrite=overwrite, **options)
        return ExportResult(target, [rgl.path], rgl.text(), rgl)
    if target in ("lighttools", "zemax-abg"):
        paths, lines = _write_straylight(target, source, Path(out), channel, overwrite, options)
        return ExportResult(target, paths, "\n".join(lines))
    if target == "zemax":
        from .zemax import to_zemax

        tables = to_zemax(source, out, channel=channel, overwrite=overwrite, **options)
        return ExportResult(target, list(tables.paths), tables.text(), tables)
    from .mitsuba import export_mitsuba

    done = export_mitsuba(source, channel=channel, **options)
    suffix = ".json" if target == "mitsuba" else ".xml"
    base = Path(out) if Path(out).suffix else Path(out).with_suffix(suffix)
    if done.rule == "per-channel":  # one BSDF per channel: one file each, each loadable
        files = {base.with_name(f"{base.stem}_{_safe(label)}{base.suffix}"):
                 (bsdf, done.note_lines(label)) for label, bsdf in done.bsdf.items()}
    else:
        files = {base: (done.bsdf, done.note_lines())}
    text = "\n".join([done.summary(), *done.note_lines()])
    return ExportResult(target, _write_mitsuba(files, target, overwrite), text, done)


def _channel_models(source: Any, channel: Any) -> list[tuple[str | None, Any, Any]]:
    """``[(label, source, channel)]`` to write one file each (label None: the file named
    ``out`` itself): a model or a per-incidence fit as it is; a fit or ``{channel: model}``
    one per channel (or ``channel`` alone)."""
    from ..fitting.results.result import FitResult

    if isinstance(source, FitResult):
        labels = [c.channel for c in source.channels]
        if channel is not None or len(labels) == 1:
            return [(None, source, channel)]
        return [(lab, source, lab) for lab in labels]
    if isinstance(source, dict) and source.get("per_incidence"):  # a saved per-incidence fit
        return [(None, source, channel)]
    if isinstance(source, dict):
        labels = [str(k) for k in source]
        if channel is not None:
            if str(channel) not in labels:
                raise ArgumentError("channel", f"not a channel of the fit ({', '.join(labels)})",
                                    value=channel)
            return [(None, source[str(channel)], None)]
        if len(labels) == 1:
            return [(None, next(iter(source.values())), None)]
        return [(str(lab), m, None) for lab, m in source.items()]
    return [(None, source, channel)]


def _write_straylight(target: str, source: Any, out: Path, channel: Any, overwrite: bool,
                      options: dict[str, Any]) -> tuple[list[Path], list[str]]:
    """The LightTools file(s) (:func:`~roughbrdf.export.lighttools.to_lighttools`) or the Zemax
    ABg table(s) (:func:`~roughbrdf.export.abg_catalog.write_abg_catalog`), one per channel
    (``<stem>_<channel><suffix>``); every target checked before the first is written. Returns
    the paths and the report: one ``wrote`` line per file (a LightTools file's with its grid
    and how close its integral is to TIS)."""
    from ..output import refuse_existing

    suffix = ".bsdf" if target == "lighttools" else ".txt"
    base = out if out.suffix else out.with_suffix(suffix)
    items = _channel_models(source, channel)
    paths = [base if lab is None else base.with_name(f"{base.stem}_{_safe(lab)}{base.suffix}")
             for lab, _, _ in items]
    for p in paths:
        refuse_existing(p, overwrite)
    done, lines = [], []
    for (lab, obj, ch), path in zip(items, paths, strict=True):
        if target == "lighttools":
            from .lighttools import to_lighttools

            written = to_lighttools(obj, path, channel=ch, overwrite=overwrite, **options)
            done.append(written.path)
            lines.append(written.text())
        else:
            from .abg_catalog import write_abg_catalog

            opts = dict(options)
            if lab is not None and "name" not in opts:  # one catalog name per channel
                opts["name"] = _safe(f"{base.stem}_{lab}")[:31]
            done.append(write_abg_catalog(obj, path, channel=ch, overwrite=overwrite, **opts))
            lines.append(f"wrote {done[-1]}")
    return done, lines


def _safe(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]+", "_", str(label)).strip("._") or "channel"


#: the key of a Mitsuba JSON export recording ``allow_energy_gain=True`` (remove it before
#: ``mitsuba.load_dict``: Mitsuba refuses a property no plugin reads)
ENERGY_NOTE_KEY = "roughbrdf_allow_energy_gain"


def _write_mitsuba(files: dict[Path, tuple[dict[str, Any], list[str]]], target: str,
                   overwrite: bool) -> list[Path]:
    """Each BSDF as a Mitsuba document: the dict as JSON (``mitsuba.load_dict(json.load(f))``)
    or an XML ``<bsdf version="3.0.0">`` (``mitsuba.load_file``/``load_string``); every file
    checked before the first is written, each written atomically. The notes (the record of
    ``allow_energy_gain=True``) go in XML comments before the element, or in the JSON key
    :data:`ENERGY_NOTE_KEY`."""
    from ..output import atomic_write, refuse_existing
    from .mitsuba.exporting import xml_comments
    from .mitsuba.xml_writer import xml_text

    for path in files:
        refuse_existing(path, overwrite)
    for path, (bsdf, notes) in files.items():
        if target == "mitsuba":
            text = json.dumps({**bsdf, ENERGY_NOTE_KEY: notes} if notes else bsdf, indent=2,
                              allow_nan=False)
        else:
            text = xml_comments(notes) + xml_text(bsdf, version="3.0.0")
        atomic_write(path, text + "\n", overwrite=overwrite)
    return list(files)

#: ``rb.export_to``: ``rb.export`` is this package
export_to = export

#: the public names that are a target module's function, loaded on first use
_LAZY = ("export_zemax", "export_mitsuba")


def __getattr__(name: str) -> Any:
    """``export_zemax`` (:func:`roughbrdf.export.zemax.to_zemax` itself) and ``export_mitsuba``
    (:func:`roughbrdf.export.mitsuba.export_mitsuba` itself), imported on first access."""
    found: Any
    if name == "export_zemax":
        from .zemax import to_zemax

        found = to_zemax
    elif name == "export_mitsuba":
        from .mitsuba import export_mitsuba

        found = export_mitsuba
    else:  # any other name: the usual error of a missing module attribute
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = found  # later accesses find it without coming here
    return found


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})

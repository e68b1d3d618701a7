"""Reading a saved fit's ``fit.json``: checked before anything is rebuilt from it.

:func:`read_fit_json` refuses what is not a fit's JSON (naming the file and what is wrong),
:func:`channel_model` rebuilds one channel's model (older files included) and
:func:`fitted_models` gives ``{channel: model}`` of a results folder after
:func:`roughbrdf.result_check.check_result_folder` (a folder left mid-write is recovered or
refused first). Used by :func:`roughbrdf.fitting.load.load_fit` and the ``--fit`` options of
``plot``, ``export`` and ``explore``. The keys are listed in ``docs/fitting.md`` ("Output
files").
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...instrument import Aperture

if TYPE_CHECKING:
    from ...models import Model

__all__ = ["MAX_FIT_JSON_BYTES", "channel_model", "check_fit_channels", "fitted_models",
           "read_fit_json"]

#: the largest ``fit.json`` read (a fit's is a few kB per channel; a device or a huge file
#: given by mistake must not be read into memory)
MAX_FIT_JSON_BYTES = 64 * 2**20


def read_fit_json(fit: str | os.PathLike, *, channels: bool = True
                  ) -> tuple[dict[str, Any], Path]:
    """The content of a fit's ``fit.json`` (``fit`` is the file or its folder) and its folder.

    Raises ``FileNotFoundError`` without one, ``ValueError`` naming the file and what is wrong
    when it is not a fit's JSON: not an object, a key missing or of the wrong type, an aperture
    that is not one; and with ``channels`` (:func:`check_fit_channels`) a channel without
    ``params``, with values that are not finite numbers, or a model that cannot be rebuilt.
    """
    path = Path(fit)
    path = path / "fit.json" if path.is_dir() else path
    if not path.is_file():  # also a device (/dev/zero): never read
        raise FileNotFoundError(f"{path}: no fit.json (run `roughbrdf fit FILE --out DIR` first)")
    if path.stat().st_size > MAX_FIT_JSON_BYTES:
        raise ValueError(f"{path}: {path.stat().st_size} bytes, too large for a fit.json")
    try:
        content = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as exc:  # bad JSON or UTF-8, a 5000-digit number, nesting
        raise ValueError(f"{path}: not valid JSON ({' '.join(str(exc).split())})") from exc
    problem = _fit_json_problem(content)
    if problem:
        raise ValueError(f"{path}: not a fit's JSON: {problem}")
    if channels:
        check_fit_channels(content, path)
    return content, path.parent


def check_fit_channels(content: dict[str, Any], path: str | os.PathLike) -> None:
    """Refuse (``ValueError`` naming ``path``) channels of a ``fit.json`` ``content`` that are
    not a fit's: not a non-empty list of objects with ``channel`` and ``params`` (finite
    numbers or null), or whose model cannot be rebuilt (:func:`channel_model`)."""
    problem = _channels_problem(content["channels"])
    if problem:
        raise ValueError(f"{path}: not a fit's JSON: {problem}")
    for i, chan in enumerate(content["channels"]):
        try:  # rebuilt now, so that a bad value is named here and not deep in a plot
            channel_model(content, chan)
        except (ValueError, TypeError, KeyError, AttributeError, OverflowError,
                RecursionError) as exc:
            raise ValueError(f"{path}: channel {i} ({chan['channel']!r}): not a model "
                             f"roughbrdf can rebuild: {' '.join(str(exc).split())}") from None


def _fit_json_problem(content: Any) -> str:
    """What makes ``content`` not the content of a ``fit.json``, channels aside ("" if nothing)."""
    if not isinstance(content, dict):
        return f"a JSON {type(content).__name__}, not an object"
    for key in ("model", "file", "channels"):
        if key not in content:
            return f"missing key {key!r}"
    if not isinstance(content["model"], dict | str) or not content["model"]:
        return f"'model' must be a model name or spec, got {content['model']!r:.60}"
    for key in ("file", "file_abspath", "file_sha256", "quantity", "relative_to", "loss"):
        if content.get(key) is not None and not isinstance(content[key], str):
            return f"{key!r} must be text, got {content[key]!r:.60}"
    ap = content.get("aperture")
    if ap is not None:
        if not isinstance(ap, dict) or "half_angle_rad" not in ap:
            return f"'aperture' must be null or an object with 'half_angle_rad', got {ap!r:.60}"
        try:
            Aperture.parse(ap["half_angle_rad"], ap.get("points", 19))
        except (ValueError, TypeError, OverflowError) as exc:
            return f"'aperture' {ap!r:.60}: {exc}"
    return ""


def _channels_problem(chans: Any) -> str:
    """What makes ``chans`` not the ``channels`` of a ``fit.json`` ("" when nothing)."""
    def number(v: Any) -> bool:  # finite, and an int within the float range
        return type(v) in (int, float) and abs(v) < 1e308 and math.isfinite(float(v))

    if not isinstance(chans, list) or not chans:
        return "'channels' must be a non-empty list"
    for i, c in enumerate(chans):
        params = c.get("params") if isinstance(c, dict) else None
        if not isinstance(c, dict) or not isinstance(c.get("channel"), str | int) \
                or not isinstance(params, dict):
            return f"channel {i} must be an object with 'channel' and 'params', got {c!r:.60}"
        bad = [k for k, v in params.items() if v is not None and not number(v)]
        if bad:
            return (f"channel {i} ({c['channel']!r}): parameter {bad[0]!r} = "
                    f"{params[bad[0]]!r:.40} is not a finite number")
        if c.get("model_spec") is not None and not isinstance(c["model_spec"], dict):
            return f"channel {i} ({c['channel']!r}): 'model_spec' must be an object"
    return ""


def channel_model(fit: dict[str, Any], chan: dict[str, Any]) -> Model:
    """The fitted model of one channel entry of ``fit.json`` (its ``model_spec``; a fit.json
    of an older roughbrdf: the model's name and the channel's ``params``)."""
    from ...models import model as make_model
    from ...models.coated import legacy_spec  # coated ks of roughbrdf 0.1.0: weights="free"

    spec = chan.get("model_spec")
    if not isinstance(spec, dict):  # an older fit.json: the model's name and the params
        name, params = fit["model"], chan.get("params") or {}
        spec = ({**name, "params": {**name.get("params", {}), **params}}
                if isinstance(name, dict) else {"model": str(name), "params": params})
    return make_model(legacy_spec(spec))


def fitted_models(fit: str | os.PathLike) -> dict[str, Model]:
    """``{channel: model}`` of a saved fit (``fit.json`` or its folder), checked as load_fit's."""
    from ...result_check import check_result_folder

    check_result_folder(fit if Path(fit).is_dir() else Path(fit).parent)
    content, _ = read_fit_json(fit)
    return {str(c["channel"]): channel_model(content, c) for c in content["channels"]}

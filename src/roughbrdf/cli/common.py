"""Helpers shared by the CLI verbs: errors and exit statuses, ``-p name=value``, degree ranges.

Like every module of :mod:`roughbrdf.cli`, this one imports nothing heavy at module level (NumPy,
the models, SciPy, Matplotlib are imported inside the functions that use them), so that
``roughbrdf --help`` and the argument checks stay fast; ``tests/core/test_startup.py`` checks it.

Every verb runs its work inside :func:`handled`, which turns an exception into one line on
stderr and the exit status of :mod:`roughbrdf.cli` (2 usage or input, 3 operating system, 4 a
bug, 130 interrupted; 143 and 129 for SIGTERM and SIGHUP), names CLI options in library
errors about arguments (:class:`roughbrdf.errors.ArgumentError`,
:class:`roughbrdf.output.OverwriteRefused`) and shows the traceback only with
``roughbrdf --debug``.

Each verb has its table of options here (:data:`FIT_OPTIONS`, :data:`CONVERT_OPTIONS`, ...):
library messages in Python terms (``starts must be >= 1``, ``pass format=``, ``angles='deg'``)
are worded with the options of the verb that was run (:func:`argument_text`, :func:`cli_text`).
Angles are degrees at this edge: the ranges of :func:`degree_range` (at most
:data:`MAX_RANGE_POINTS` values) and the model parameters whose unit is an angle
(:func:`cli_model`, :func:`cli_parameter_lines`).
"""

from __future__ import annotations

import contextlib
import math
import sys
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING

import typer

# the wording of errors and the degrees of model settings are shared with the explorer (a lower
# layer), so they live in roughbrdf.wording; re-exported here under their names
from ..wording import ANGLE_UNIT as ANGLE_UNIT
from ..wording import EXIT_OS, interrupted_status, model_in_degrees, radian_settings
from ..wording import angle_names as angle_names
from ..wording import argument_text as argument_text
from ..wording import cli_number as cli_number
from ..wording import cli_text as cli_text
from ..wording import cli_unit as cli_unit
from ..wording import error_message as error_message
from ..wording import exit_status as exit_status
from ..wording import shown_name as shown_name
from . import Run, interrupt_line
from .options import OptionError, naming

if TYPE_CHECKING:
    import numpy as np

    from ..measurement import Measurement
    from ..models import Model

#: the options of each verb: ``{Python argument name: CLI option}``, one table per verb. Errors
#: of the library name Python arguments (:class:`~roughbrdf.errors.ArgumentError`, and messages
#: of the readers such as ``pass angles=``); :func:`handled` words them with the table of the
#: verb that was run, so that a message names an option of that verb (``fit`` has
#: ``--format``, ``convert`` has ``--from/--to``).
EVAL_OPTIONS = {"theta_i": "--theta-i", "theta_r": "--theta-r", "phi": "--phi",
                "polarization": "--polarization", "gamma": "--polarization",
                "quantity": "--quantity"}
FIT_OPTIONS = {"model": "--model", "fix": "--fix", "bounds": "--bounds", "channel": "--channel",
               "loss": "--loss", "starts": "--starts", "quantity": "--quantity",
               "relative_to": "--relative-to", "format": "--format", "angles": "--angles-in",
               "nonfinite": "--nonfinite", "negative": "--negative", "seed": "--seed",
               "free_scale": "--free-scale", "aperture": "--aperture", "out_dir": "--out",
               "theta_r_max": "--theta-r-max", "source_exclusion": "--source-exclusion",
               "overwrite": "--force", "plots": "--plots/--no-plots", "joint": "--joint",
               "shared": "--shared", "extrapolated": "--keep-extrapolated",
               "candidates": "--models", "cv": "--cv/--no-cv", "wavelength": "--wavelength",
               "max_rows": "--max-rows", "intervals": "--intervals"}
COMPARE_OPTIONS = {"candidates": "--models", "models": "--models", "cv": "--cv/--no-cv",
                   "channel": "--channel", "loss": "--loss", "starts": "--starts",
                   "joint": "--joint", "quantity": "--quantity", "angles": "--angles-in",
                   "format": "--format", "aperture": "--aperture",
                   "theta_r_max": "--theta-r-max", "source_exclusion": "--source-exclusion",
                   "extrapolated": "--keep-extrapolated", "negative": "--negative",
                   "seed": "--seed", "plots": "--plots/--no-plots", "overwrite": "--force",
                   "out_dir": "--out", "wavelength": "--wavelength"}
PLOT_OPTIONS = {"theta_i": "--theta-i", "elevation": "--elevation", "quantity": "--quantity",
                "kind": "--kind", "log": "--log/--linear", "channel": "--channel",
                "overwrite": "--force", "path": "--out"}
EXPORT_OPTIONS = {"to": "--to", "channel": "--channel", "overwrite": "--force",
                  "fit": "--fit-closest", "angles_of_incidence": "--incidences",
                  "radial": "--radial", "azimuth": "--azimuth", "symmetry": "--symmetry",
                  "rgb": "--rgb/--no-rgb", "theta_max": "--theta-max", "out": "--out"}
CONVERT_OPTIONS = {"quantity": "--quantity", "angles": "--angles-in", "stride": "--stride",
                   "overwrite": "--force", "resample": "--resample", "path": "OUT",
                   "channel": "--channel", "format": "--from/--to"}
REPRODUCE_OPTIONS = {"paper": "--paper", "out": "--out", "overwrite": "--force",
                     "data_dir": "--data"}

#: the largest number of values one range option (``START:STOP:STEP``) may give: a typo such
#: as ``0:90:1e-7`` would otherwise take the memory of the machine
MAX_RANGE_POINTS = 100_000

#: exceptions Typer shows by itself (usage errors, exits)
_TYPER_OWN: tuple[type[BaseException], ...] = (
    typer.Exit, typer.Abort,
    *(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException"))


@contextlib.contextmanager
def handled(options: Mapping[str, str] | None = None) -> Iterator[None]:
    """Run a verb's work: every error becomes one line on stderr and an exit status.

    Parameters
    ----------
    options : mapping of str to str
        The verb's ``{Python argument name: CLI option}`` (``{"theta_i": "--theta-i"}``), used
        to word :class:`~roughbrdf.errors.ArgumentError` (and ``"overwrite"``: ``"--force"``
        for :class:`~roughbrdf.output.OverwriteRefused`).

    Ctrl-C ends the run with status 130 and ``interrupted``, also when a library swallowed it
    (:func:`roughbrdf.interrupts.watch`); SIGTERM and SIGHUP the same way, with 143 and 129
    (:func:`roughbrdf.cli.interrupted_status`).
    """
    from ..interrupts import raise_if_interrupted, watch

    with watch():
        try:
            yield
            raise_if_interrupted()  # a Ctrl-C swallowed after the last safe point
        except _TYPER_OWN:
            raise
        except KeyboardInterrupt as exc:
            Run.interrupt_reported = True
            typer.echo(interrupt_line(), err=True)
            raise typer.Exit(interrupted_status()) from exc
        except BrokenPipeError as exc:  # stdout's reader went away (`| head`): nothing to say
            _silence_stdout()
            raise typer.Exit(EXIT_OS) from exc
        except Exception as exc:
            code = exit_status(exc)
            if Run.debug:
                import traceback

                traceback.print_exception(exc, file=sys.stderr)
            typer.echo(f"error: {error_message(exc, options, code)}", err=True)
            raise typer.Exit(code) from exc


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the final flush cannot fail again."""
    import os

    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
    except (OSError, ValueError):  # no file descriptor (captured output)
        pass


def parse_params(items: list[str] | None) -> dict[str, float | None | str]:
    """``["e=0.5", "n=None", "distribution=ggx"]`` -> dict (numbers where they parse)."""
    out: dict[str, float | None | str] = {}
    for item in items or []:
        if "=" not in item:  # a ValueError, not Typer's: one line inside handled()
            raise ValueError(f"-p/--param: expected name=value, got {item!r}")
        key, val = item.split("=", 1)
        key, val = key.strip(), val.strip()
        if val.lower() == "none":
            out[key] = None
            continue
        try:
            out[key] = float(val)
        except ValueError:
            out[key] = val
    return out


def degree_range(text: str, name: str) -> np.ndarray:
    """``"30"`` or ``"0:90:5"`` (start:stop:step, stop inclusive) in degrees -> radians.

    Raises ``ValueError`` naming the option ``name`` and the text for anything but finite
    numbers, a zero step, a step that never reaches STOP (an empty range) and a range of more
    than :data:`MAX_RANGE_POINTS` values.

    Examples
    --------
    >>> [round(float(x), 4) for x in degree_range("90:0:-45", "--theta-r")]
    [1.5708, 0.7854, 0.0]
    >>> degree_range("0:inf:1", "--theta-r")
    Traceback (most recent call last):
    ...
    ValueError: --theta-r '0:inf:1': START, STOP and STEP must be finite numbers of degrees
    """
    import numpy as np

    try:
        parts = [float(x) for x in text.split(":")]
    except ValueError:
        raise ValueError(f"{name} {text!r}: expected DEG or START:STOP:STEP (degrees)") from None
    if len(parts) not in (1, 3):
        raise ValueError(f"{name} {text!r}: expected DEG or START:STOP:STEP (degrees)")
    if not all(math.isfinite(x) for x in parts):  # nan/inf: no angle, no count of points
        what = "DEG must be a finite number" if len(parts) == 1 else \
            "START, STOP and STEP must be finite numbers"
        raise ValueError(f"{name} {text!r}: {what} of degrees")
    if len(parts) == 1:
        return np.radians(np.array(parts))
    start, stop, step = parts
    if step == 0:  # would never reach STOP
        raise ValueError(f"{name} {text!r}: STEP must not be 0")
    count = math.floor((stop - start) / step + 1e-9) + 1
    if count <= 0:  # the step goes away from STOP
        raise ValueError(f"{name} {text!r}: empty range (STEP {step:g} goes away from STOP; "
                         f"use a {'negative' if stop < start else 'positive'} STEP)")
    if count > MAX_RANGE_POINTS:  # a typo of STEP must not exhaust the memory
        raise ValueError(f"{name} {text!r}: {count:.4g} values, more than the limit of "
                         f"{MAX_RANGE_POINTS} per range; use a larger STEP")
    return np.radians(start + step * np.arange(count))


def cli_model(spec: str, params: Mapping[str, object] | None = None,
              option: str | None = None) -> Model:
    """``roughbrdf.model(spec, **params)`` with ``-p`` settings as the CLI gives them: a
    parameter whose unit is an angle (Oren-Nayar ``sigma``, also in ``coated(diffuse=
    "oren-nayar")`` and in sums, by plain or prefixed name) in degrees
    (:func:`roughbrdf.wording.model_in_degrees`).

    With ``option`` (how the verb takes the spec: ``"--model"``, ``"MODEL"``) an error names
    what is wrong: the spec (``option``) or a ``-p`` setting (``-p/--param``)
    (:class:`~roughbrdf.cli.options.OptionError`); without it the library's error passes.

    Examples
    --------
    >>> round(cli_model("oren-nayar", {"sigma": 20.0}).params["sigma"], 6)
    0.349066
    >>> cli_model("lambertian", {"rho": "x"}, "MODEL")
    Traceback (most recent call last):
    ...
    roughbrdf.cli.options.OptionError: -p/--param: rho = 'x': parameter 'rho' must be a number
    """
    from .. import models as _models

    if option is None:
        return model_in_degrees(spec, params)
    given = dict(params or {})
    try:
        first = _models.model(spec, **given)  # names and units (angles in degrees pass the
    except ValueError as exc:  # sign checks of their domains just as well)
        raise _model_error(spec, option, exc, bool(given)) from exc
    converted = radian_settings(first, given)
    if converted is None:
        return first
    with naming("-p/--param"):  # an angle's value outside its domain
        return _models.model(spec, **converted)


def _model_error(spec: str, option: str, exc: ValueError, settings: bool) -> OptionError:
    """The error of a model that could not be made: of the spec (``option``) when the spec
    alone fails too, else of the ``-p`` settings."""
    from .. import models as _models

    if settings:
        try:
            _models.model(spec)
        except ValueError:  # the spec itself is wrong
            pass
        else:
            return OptionError("-p/--param", str(exc))
    return OptionError(option, str(exc))


def cli_parameter_lines(model: Model) -> list[str]:
    """The parameter lines of :meth:`Model.describe <roughbrdf.models.Model.describe>` as the
    CLI shows them: angles in degrees, ``[deg]``."""
    lines = []
    for p in model.parameters:
        value = cli_number(p.unit, p.value)
        shown = f"{value:.6g}" if isinstance(value, float) and p.unit == ANGLE_UNIT else value
        lines.append(f"  {p.name:<10} = {shown!s:<12} [{cli_unit(p.unit)}]  {p.description}")
    return lines


def check_channels(meas: Measurement, channels: list[str] | None) -> list[int]:
    """The positions of ``--channel`` labels (or indices) in ``meas``; an unknown one is refused
    naming it and listing the channels of the file.

    Examples
    --------
    >>> from roughbrdf.measurement import Measurement
    >>> m = Measurement([0.1], [0.2], [0.0], [[1.0, 2.0]], channels=["465nm", "525nm"])
    >>> check_channels(m, ["525"])
    [1]
    >>> check_channels(m, ["550"])
    Traceback (most recent call last):
    ...
    ValueError: --channel: unknown channel '550' (channels: 465nm, 525nm)
    """
    out = []
    for c in channels or []:
        try:
            out.append(meas.channel_index(c))
        except (ValueError, TypeError):  # the measurement's own words do not list them all
            raise ValueError(f"--channel: unknown channel {c!r} (channels: "
                             f"{', '.join(meas.channels)})") from None
    return out

"""Errors about a caller's arguments, worded in the terms of the interface that was used.

The library speaks Python (argument names, radians); the command line speaks CLI (option
names, degrees). An :class:`ArgumentError` records *which* argument was wrong, the offending
value and, where there is one, the value that would fix it; :meth:`ArgumentError.render` words
it for either side, so the same check serves both (``str(err)`` is the Python wording).

Examples
--------
>>> err = ArgumentError("negative", "3 samples are negative", fix="drop")
>>> str(err)
"3 samples are negative; pass negative='drop'"
>>> err.render({"negative": "--negative"})
'3 samples are negative; pass --negative drop'
>>> err = ArgumentError("aperture", "must be below 90 deg", value=2.0, unit="rad")
>>> str(err)
'aperture = 2.0 rad: must be below 90 deg'
>>> err.render({"aperture": "--aperture"})
'--aperture 114.6 (degrees): must be below 90 deg'
>>> import pickle
>>> str(pickle.loads(pickle.dumps(err))) == str(err)
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["ArgumentError"]

class _Unset:
    """Marker of an argument not given (a class: it pickles by reference, keeping identity)."""


_UNSET: Any = _Unset


class ArgumentError(ValueError):
    """A bad argument: its name, the value, and optionally the value that would fix it.

    Parameters
    ----------
    argument : str
        The Python argument (or parameter) name, e.g. ``"theta_r"``, ``"negative"``.
    message : str
        What is wrong, without naming the argument or the fix (they are added per interface).
    value : object, optional
        The offending value (shown as given; angles in radians with ``unit="rad"``).
    fix : object, optional
        A value of the argument that would make the call work (``"drop"``).
    unit : {"rad", None}
        ``"rad"`` for an angle: the CLI shows it in degrees.
    """

    def __init__(self, argument: str, message: str, *, value: Any = _UNSET, fix: Any = _UNSET,
                 unit: str | None = None) -> None:
        self.argument = argument
        self.message = message
        self.value = value
        self.fix = fix
        self.unit = unit
        super().__init__(self.render())

    def __reduce__(self) -> tuple[Any, ...]:
        # picklable (errors cross process boundaries, e.g. from worker processes): rebuild
        # from the same fields
        return (_rebuild, (self.argument, self.message, self.value, self.fix, self.unit))

    def render(self, options: Mapping[str, str] | None = None) -> str:
        """The message naming the argument as ``options[argument]`` (a CLI option, shown in
        CLI style with degrees) or, without ``options``, as the Python argument."""
        cli = options is not None and self.argument in options
        name = options[self.argument] if cli and options is not None else self.argument
        head = ""
        if self.value is not _UNSET:
            head = f"{name} {_cli_value(self.value, self.unit)}" if cli else (
                f"{name} = {self.value!r}" + (f" {self.unit}" if self.unit else ""))
            head += ": "
        text = head + self.message
        if self.fix is True and cli:  # a flag: "pass --fit-closest", not "... True"
            text += f"; pass {name}"
        elif self.fix is not _UNSET:
            text += f"; pass {name} {self.fix}" if cli else f"; pass {name}={self.fix!r}"
        return text


def _rebuild(argument: str, message: str, value: Any, fix: Any, unit: str | None
             ) -> ArgumentError:
    kw: dict[str, Any] = {"unit": unit}
    if value is not _UNSET:
        kw["value"] = value
    if fix is not _UNSET:
        kw["fix"] = fix
    return ArgumentError(argument, message, **kw)


def _cli_value(value: Any, unit: str | None) -> str:
    if unit == "rad":
        try:
            return f"{math.degrees(float(value)):.4g} (degrees)"
        except (TypeError, ValueError):
            return repr(value)
    return str(value)

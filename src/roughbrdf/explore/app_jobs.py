"""The explorer's two actions that act beyond the page: a fit in the background and an export.

:class:`FitJob` runs :func:`roughbrdf.fit` in a daemon thread, one channel after the other
(each channel is one ``rb.fit(..., channel=label)``), so that the page can show the progress
(channels done) and cancel: at once for the page, the channel being fitted finishing in the
background (a fit cannot be stopped midway from another thread) with its result dropped; the
report text of each channel is shown when it is done. :func:`export_model` writes the current
model with :func:`roughbrdf.export.export` into the one folder named at start-up (``--out``)
and nowhere else: the page gives a file *name*, never a path; nothing is replaced (the
project's output rules, :mod:`roughbrdf.output`: refused if it exists, written atomically).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..models import Model

__all__ = ["FitJob", "export_model", "EVAL_LOCK", "evaluation", "EXPORT_TARGETS"]

#: the export targets the page offers
EXPORT_TARGETS = ("zemax", "mitsuba", "mitsuba-xml")

#: serializes the page's model evaluations (Numba's ``workqueue`` threading layer, used where
#: neither OpenMP nor TBB is available, must not be entered from two threads at once)
EVAL_LOCK = threading.RLock()


def _needs_lock() -> bool:
    """Whether evaluations from two threads must be serialized (Numba's workqueue layer)."""
    try:
        import numba

        return str(numba.threading_layer()) == "workqueue"
    except (ImportError, ValueError):  # no parallel region run yet: be safe
        return True


@contextlib.contextmanager
def evaluation(fit: bool = False) -> Iterator[None]:
    """Hold :data:`EVAL_LOCK` for a redraw; a fit holds it only where Numba needs it (the
    page keeps redrawing during a fit under OpenMP or TBB)."""
    if fit and not _needs_lock():
        yield
        return
    with EVAL_LOCK:
        yield


class FitJob:
    """A fit of ``model`` to ``measurement`` running in a background thread.

    Attributes
    ----------
    done, total : int
        Channels fitted, channels to fit.
    reports : list of str
        The report of each channel fitted.
    models : dict of str to Model
        The fitted model of each channel fitted.
    error : str
        Why the fit stopped ("" if it did not fail).
    state : {"running", "finished", "cancelled", "failed"}
    """

    def __init__(self, model: Model, measurement: Measurement, **options: Any) -> None:
        self.model, self.measurement, self.options = model, measurement, options
        self.channels = list(measurement.channels)
        self.done, self.total = 0, len(self.channels)
        self.reports: list[str] = []
        self.models: dict[str, Model] = {}
        self.error = ""
        self.state = "running"
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._run, name="roughbrdf-explore-fit",
                                        daemon=True)

    def start(self) -> FitJob:
        self._thread.start()
        return self

    def cancel(self) -> None:
        """Cancel now: the job is ``"cancelled"`` at once and nothing more is recorded; a
        channel being fitted finishes in the background (a fit cannot be stopped midway) and
        its result is dropped."""
        self._cancel.set()
        if self.state == "running":
            self.state = "cancelled"

    def join(self, timeout: float | None = None) -> None:
        self._thread.join(timeout)

    @property
    def report(self) -> str:
        return "\n\n".join(self.reports)

    def _run(self) -> None:
        import roughbrdf as rb

        from ..wording import error_message

        try:
            for label in self.channels:
                if self._cancel.is_set():
                    return
                with evaluation(fit=True):
                    res = rb.fit(self.model, self.measurement, channel=label, progress=False,
                                 **self.options)
                if self._cancel.is_set():  # cancelled while this channel was fitted: dropped
                    return
                self.models[label] = res.channels[0].model
                self.reports.append(res.report())
                self.done += 1
            self.state = "finished"
        except Exception as exc:  # noqa: BLE001 - shown on the page as one line
            if not self._cancel.is_set():
                self.error = error_message(exc)
                self.state = "failed"

    def status(self) -> str:
        """One line for the page."""
        if self.state == "running":
            return f"fitting: {self.done} of {self.total} channels done"
        if self.state == "failed":
            return f"fit failed: {self.error}"
        if self.state == "cancelled":
            return (f"fit cancelled after {self.done} of {self.total} channels (a channel "
                    "being fitted finishes in the background; its result is dropped)")
        return f"fit finished: {self.done} of {self.total} channels"


def export_model(model: Model, out: Path | None, name: str, to: str) -> str:
    """Write ``model`` as ``out/name`` for target ``to``; what happened, for the page.

    Raises
    ------
    ValueError
        Without an ``out`` folder, for a name that is not a plain file name (a folder part,
        ``..``, a hidden name), or a target the page does not offer.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> export_model(rb.model("lambertian"), None, "paint", "mitsuba")
    Traceback (most recent call last):
    ...
    ValueError: export is off: start roughbrdf explore with --out DIR to export
    """
    from ..export import export

    if out is None:
        raise ValueError("export is off: start roughbrdf explore with --out DIR to export")
    name = str(name or "").strip()
    if not name or name != Path(name).name or name.startswith(".") or "\\" in name \
            or "/" in name or "\x00" in name:
        raise ValueError(f"export name {name!r}: give a plain file name (no folder, not "
                         "hidden); files go into the --out folder only")
    if to not in EXPORT_TARGETS:
        raise ValueError(f"export target {to!r}: choose one of {', '.join(EXPORT_TARGETS)}")
    target = out / name
    if target.resolve().parent != out.resolve():  # a link or a name that leaves the folder
        raise ValueError(f"export name {name!r}: the file would not be in {out}")
    with evaluation():
        res = export(model, target, to=to, overwrite=False)
    for path in res.paths:
        if Path(path).resolve().parent != out.resolve():  # never expected: say so loudly
            raise RuntimeError(f"export wrote {path} outside {out}")
    return res.report + "\nwrote " + ", ".join(str(p) for p in res.paths)

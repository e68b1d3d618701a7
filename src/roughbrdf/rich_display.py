"""Notebook renderings of the package's objects, registered from above.

Jupyter shows an object by its ``_repr_html_`` (IPython's rich display protocol). A model and a
measurement are low in the package's layers, and the builders of their HTML
(:mod:`roughbrdf.html_repr`) sit higher: they also show fit results. So the low objects do not
import the builders; their ``_repr_html_`` asks this registry for the HTML of their *kind*
(:func:`html`), and :mod:`roughbrdf.html_repr` registers its builders when it is imported
(:func:`register_html`).

This module imports nothing of the package. The first display that finds no builder runs the
loader that the package face (``roughbrdf/__init__.py``) installs when this module is bound as
its attribute (:func:`set_loader`): it imports :mod:`roughbrdf.html_repr`. Without a builder
(no loader, or none registered for the kind) the object's ``repr`` is shown, escaped.

Examples
--------
>>> register_html("toy", lambda obj: f"<b>{obj}</b>")
>>> html("toy", 3)
'<b>3</b>'
>>> html("nothing registered", "<x>")
'<pre>&#x27;&lt;x&gt;&#x27;</pre>'
>>> del _RENDERERS["toy"]
"""

from __future__ import annotations

from collections.abc import Callable
from html import escape
from typing import Any

__all__ = ["html", "register_html", "set_loader"]

#: kind (``"model"``, ``"measurement"``) -> the function returning an object's HTML fragment
_RENDERERS: dict[str, Callable[[Any], str]] = {}
#: what registers the builders, run once by the first display that finds none
_LOADER: list[Callable[[], object]] = []


def register_html(kind: str, render: Callable[[Any], str]) -> None:
    """Show the objects of ``kind`` in notebooks as ``render(obj)`` (an HTML fragment)."""
    _RENDERERS[kind] = render


def set_loader(load: Callable[[], object]) -> None:
    """Run ``load`` (which registers the builders) before the first display that needs one."""
    _LOADER[:] = [load]


def html(kind: str, obj: object) -> str:
    """The HTML fragment of ``obj``, an object of ``kind``: its registered builder's, else its
    ``repr`` escaped in a ``<pre>`` block.

    Parameters
    ----------
    kind : str
        What ``obj`` is (``"model"``, ``"measurement"``): the key of its builder.
    obj : object
        The object to show.

    Returns
    -------
    str
        An HTML fragment.
    """
    if kind not in _RENDERERS and _LOADER:
        _LOADER[0]()
        _LOADER.clear()  # once loaded, a kind still missing has no builder
    render = _RENDERERS.get(kind)
    if render is None:
        return f"<pre>{escape(repr(obj))}</pre>"
    return render(obj)

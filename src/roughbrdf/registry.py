"""One registry: names with aliases, looked up case-insensitively, with close-match hints.

Models, facet distributions, shadowing functions and the models' named options all register
their entries here, so every name a user types is resolved the same way: case and the
characters ``_``/space are ignored (``"Trowbridge_Reitz"`` is ``"trowbridge-reitz"``), aliases
map to the canonical entry, and an unknown name raises ``ValueError`` listing the known names
and the closest matches.

Examples
--------
>>> from roughbrdf.registry import Registry
>>> colours = Registry("colour")
>>> colours.add("red", 1, aliases=("rouge",))
1
>>> colours.get("ROUGE")
1
>>> colours.canonical("Rouge")
'red'
>>> colours.get("rde")
Traceback (most recent call last):
...
ValueError: unknown colour 'rde'; did you mean 'red'? (known: red)
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Iterator, Mapping
from typing import Generic, TypeVar

__all__ = ["Registry", "canon", "unknown_name"]

T = TypeVar("T")


def canon(name: object) -> str:
    """The lookup key of a name: stripped, lower case, ``_`` and spaces as ``-``."""
    return str(name).strip().lower().replace("_", "-").replace(" ", "-")


def unknown_name(kind: str, name: object, known: Iterable[str],
                 aliases: Mapping[str, str] | None = None) -> ValueError:
    """The ``ValueError`` for an unknown ``name`` of ``kind``: lists the ``known`` names and
    suggests the closest of them, then the closest ``aliases`` (``{alias: canonical name}``)
    of any other entry, each with the name it stands for."""
    known = list(known)
    key = canon(name)
    names = {canon(k): k for k in known}
    hints = [names[c] for c in difflib.get_close_matches(key, list(names), n=3, cutoff=0.5)]
    shown = [repr(h) for h in hints]
    other = {canon(a): c for a, c in (aliases or {}).items() if c not in hints and a not in names}
    for a in difflib.get_close_matches(key, list(other), n=3, cutoff=0.5):
        shown.append(f"{a!r} ({other[a]})")
    shown = shown[:3]
    hint = f"; did you mean {', '.join(shown)}?" if shown else ""
    what = kind.replace("{name}", repr(name)) if "{name}" in kind else f"{kind} {name!r}"
    return ValueError(f"unknown {what}{hint} (known: {', '.join(known)})")


class Registry(Generic[T]):
    """Entries of one kind by canonical name and aliases.

    Parameters
    ----------
    kind : str
        What the entries are, for error messages (``"model"``, ``"distribution"``); a
        ``{name}`` in it marks where the unknown name goes (default: at the end).
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T] = {}
        self._names: dict[str, str] = {}  # key (canonical name or alias) -> canonical name

    def add(self, name: str, entry: T, aliases: Iterable[str] = ()) -> T:
        """Register ``entry`` under ``name`` and ``aliases``; returns ``entry``."""
        keys = [canon(key) for key in (name, *aliases)]
        for key, k in zip((name, *aliases), keys, strict=True):
            if self._names.get(k, name) != name:  # checked first: a refused entry adds nothing
                raise ValueError(f"{self.kind} name {key!r} is already taken by "
                                 f"{self._names[k]!r}")
        self._entries[name] = entry
        self._names.update(dict.fromkeys(keys, name))
        return entry

    def canonical(self, name: object) -> str:
        """The canonical name for ``name`` or one of its aliases."""
        try:
            return self._names[canon(name)]
        except KeyError:
            raise unknown_name(self.kind, name, self.names(), self._names) from None

    def get(self, name: object) -> T:
        """The entry for ``name`` (case-insensitive; aliases accepted)."""
        return self._entries[self.canonical(name)]

    def names(self) -> list[str]:
        """Canonical names, in registration order."""
        return list(self._entries)

    def aliases(self, name: str) -> list[str]:
        """The other keys that resolve to ``name``'s entry (lower case)."""
        target = self.canonical(name)
        return [k for k, v in self._names.items() if v == target and k != canon(target)]

    def __contains__(self, name: object) -> bool:
        return canon(name) in self._names

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

"""Sums of models: ``m1 + m2`` adds BRDFs; parameter names are prefixed per component."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..quantity import Quantity
from ..registry import unknown_name
from .base import Model, PreparedGeometry

__all__ = ["SumModel", "components"]


def components(m: Model) -> list[Model]:
    """The terms of ``m``: its components if it is a sum, else ``[m]``."""
    return list(m.components) if isinstance(m, SumModel) else [m]


class SumModel(Model):
    """Sum of models; parameter names are prefixed ``<short>_<name>`` (``<short><i>_`` if repeated).
    """

    name = "sum"
    short = "sum"

    def __init__(self, components: Sequence[Model]) -> None:  # noqa: D107
        self.components = [copy.copy(c) for c in components]
        counts: dict[str, int] = {}
        for c in self.components:
            counts[c.short] = counts.get(c.short, 0) + 1
        seen: dict[str, int] = {}
        self.prefixes = []
        for c in self.components:
            if counts[c.short] > 1:
                seen[c.short] = seen.get(c.short, 0) + 1
                self.prefixes.append(f"{c.short}{seen[c.short]}_")
            else:
                self.prefixes.append(f"{c.short}_")
        self.grazing_incidence = all(c.grazing_incidence for c in self.components)  # type: ignore[misc]
        self.reciprocal = all(c.reciprocal for c in self.components)  # type: ignore[misc]
        self._options = {}
        self._refresh()

    def _refresh(self) -> None:
        self._specs = tuple(replace(p, name=pre + p.name) for c, pre in
                            zip(self.components, self.prefixes, strict=True) for p in c.parameters)
        self._values = {p.name: p.value for p in self._specs}

    def _split(self, name: str) -> tuple[int, str]:
        for i, pre in enumerate(self.prefixes):
            if name.startswith(pre) and name[len(pre):] in self.components[i].params:
                return i, name[len(pre):]
        raise unknown_name("parameter for this sum of models", name, [p.name for p in self._specs])

    def with_values(self, names: Sequence[str], values: Sequence[float]) -> SumModel:
        groups: dict[int, tuple[list[str], list[float]]] = {}
        for nm, v in zip(names, values, strict=True):
            i, base = self._split(nm)
            groups.setdefault(i, ([], []))[0].append(base)
            groups[i][1].append(v)
        new = copy.copy(self)
        new.components = [c.with_values(*groups[i]) if i in groups else c
                          for i, c in enumerate(self.components)]
        new._refresh()
        return new

    def with_params(self, **updates: Any) -> SumModel:
        return self.with_values(list(updates), list(updates.values()))

    def _kernel(self, g: PreparedGeometry, flag: int, term: str | None
                ) -> np.ndarray | float:
        q = Quantity.BRDF_COS if flag else Quantity.BRDF
        parts = []
        for c, pre in zip(self.components, self.prefixes, strict=True):
            if term is None:
                parts.append(c.evaluate_prepared(g, q))
            elif term in c.TERMS:
                parts.append(c.evaluate_prepared(g, q, term=term))
            elif term in (c.short, c.name, pre[:-1]):
                parts.append(c.evaluate_prepared(g, q))
        if not parts:
            raise ValueError(f"no component of this sum has a term {term!r}")
        return sum(parts[1:], parts[0])

    def to_dict(self) -> dict[str, Any]:
        return {"model": "sum", "components": [c.to_dict() for c in self.components]}

    def describe(self) -> str:
        return "\n".join(f"[{pre[:-1]}] " + c.describe() for c, pre in
                         zip(self.components, self.prefixes, strict=True))

    @property
    def reference(self) -> str:  # type: ignore[override]
        return "; ".join(c.reference for c in self.components)

    def __repr__(self) -> str:
        return " + ".join(repr(c) for c in self.components)

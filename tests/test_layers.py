"""The layers of ``src/roughbrdf`` point down, read from the source with ``ast`` (nothing is
imported).

The package is built in layers (:data:`LAYERS`, lowest first; the README's "Architecture"
lists them): a module may import a module of its own layer or of a lower one, never of a higher
one. Every import counts: at module level, inside functions and under ``if TYPE_CHECKING:``
(a type is a dependency too). ``import roughbrdf as rb`` (the package face and its lazy
attributes) counts as an import of each ``rb.name`` used: the module that defines ``name``
(the face's ``_ATTRS``) or the submodule ``roughbrdf.name``. The face itself,
``roughbrdf/__init__.py``, is exempt: it names everything on purpose, lazily. A package's
``__init__.py`` belongs to its package's layer.

Every module has exactly one layer: a module no entry of :data:`LAYERS` covers, or that two
cover, fails the test (a new top-level module is placed as low as its own imports allow).
"""

from __future__ import annotations

import ast
from collections.abc import Collection, Iterator, Mapping
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src"
PACKAGE = SRC / "roughbrdf"
TOP = "roughbrdf"

#: the layers, lowest first: (layer, its rooms), each room a module or a subpackage (with all
#: its modules) of ``roughbrdf``
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    # utilities that import nothing of the package above this layer: errors, interrupts (the
    # kernels check them), JSON, the registries, atomic output and its journal, Matplotlib's
    # modules loaded with Ctrl-C held
    ("base", ("errors", "interrupts", "jsonsafe", "journal", "output", "registry",
              "result_check", "rich_display", "mpl_load")),
    ("kernels", ("_kernels",)),
    ("physics", ("geometry_frames", "geometry", "special", "fresnel", "distributions",
                 "shadowing", "diffuse", "mueller", "stokes", "polarization", "quantity")),
    # the models and the measurement, with what needs no more than them: the integrals, the
    # instrument, the extrapolation, the plots, the default data's maker
    ("models", ("models", "measurement", "integrate", "instrument", "extrapolation", "plot",
                "plot_fit", "plot_mueller", "data.make_default")),
    ("io", ("io",)),
    # the fit, with the notebook HTML (it shows fit results) and the papers' reproductions
    # (they read and fit)
    ("fitting", ("fitting", "html_repr", "reproduce")),
    ("export", ("export",)),
    # the catalogue, with the one-line wording of errors shared by the explorer and the CLI
    ("catalogue", ("catalogue", "wording")),
    ("explore", ("explore",)),
    ("cli", ("cli", "demo")),
)

#: the inner rooms of ``roughbrdf.fitting``, lowest first (``roughbrdf/fitting/__init__.py``
#: lists what each holds): a room imports only the rooms before it (the package face,
#: ``roughbrdf.fitting`` itself, re-exports and is exempt)
FITTING_ROOMS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("problem", ("fitting.problem",)),
    ("solvers", ("fitting.solvers",)),
    ("results", ("fitting.results",)),
    ("energy", ("fitting.energy",)),
    ("kinds", ("fitting.kinds",)),
    ("choice", ("fitting.choice",)),
    ("load", ("fitting.load",)),
    ("fit", ("fitting.fit",)),
)


# --------------------------------------------------------------------------------------------
# the checker (pure functions of parsed source, tested on synthetic modules below)
# --------------------------------------------------------------------------------------------
def layers_of(module: str, layers: tuple[tuple[str, tuple[str, ...]], ...] = LAYERS
              ) -> list[str]:
    """The layers whose rooms cover ``module`` (a dotted name): exactly one when placed."""
    return [layer for layer, rooms in layers for room in rooms
            if module == f"{TOP}.{room}" or module.startswith(f"{TOP}.{room}.")]


def _from_base(module: str, node: ast.ImportFrom, packages: Collection[str]) -> str:
    """The absolute module an ``ImportFrom`` in ``module`` names (``from ..x import y``)."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if module not in packages:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _face_target(name: str, modules: Collection[str], face: Mapping[str, str]) -> str | None:
    """The module ``roughbrdf.<name>`` stands for: the one defining a lazy attribute of the
    face, or the submodule of that name; ``None`` for anything else (``__version__``)."""
    if name in face:
        return f"{TOP}.{face[name]}"
    return f"{TOP}.{name}" if f"{TOP}.{name}" in modules else None


def _face_uses(tree: ast.AST, bound: set[str], modules: Collection[str],
               face: Mapping[str, str]) -> Iterator[str]:
    """The modules named through the face: each ``rb.name`` where ``rb`` is bound to it."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) \
                and node.value.id in bound:
            target = _face_target(node.attr, modules, face)
            if target is not None:
                yield target


def imports_of(module: str, tree: ast.AST, modules: Collection[str],
               packages: Collection[str], face: Mapping[str, str]) -> set[str]:
    """Every package module ``module`` imports, anywhere in ``tree`` (module level, functions,
    ``TYPE_CHECKING``): a name imported from a package counts as the package, a submodule as
    the submodule, a name of the face (``from roughbrdf import fit``, ``rb.fit``) as the
    module that defines it."""
    out: set[str] = set()
    bound: set[str] = set()  # local names of the face (``import roughbrdf as rb``)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == TOP or alias.name.startswith(f"{TOP}."):
                    out.add(alias.name)
                    if alias.asname is None or alias.name == TOP:
                        bound.add(alias.asname or TOP)
        elif isinstance(node, ast.ImportFrom):
            base = _from_base(module, node, packages)
            for alias in node.names:
                if f"{base}.{alias.name}" in modules:
                    out.add(f"{base}.{alias.name}")
                elif base == TOP:
                    out.add(_face_target(alias.name, modules, face) or TOP)
                else:
                    out.add(base)
    out.update(_face_uses(tree, bound, modules, face))
    return {m for m in out if m in modules and m not in (module, TOP)}


def upward_imports(trees: Mapping[str, ast.AST], packages: Collection[str],
                   face: Mapping[str, str],
                   layers: tuple[tuple[str, tuple[str, ...]], ...] = LAYERS) -> list[str]:
    """Each import of a higher layer, as ``importer -> imported (layer a -> layer b)``
    (every module must be placed: :func:`unplaced`)."""
    rank = {layer: i for i, (layer, _) in enumerate(layers)}
    bad = []
    for module, tree in sorted(trees.items()):
        if module == TOP:  # the face: lazy attributes naming every layer on purpose
            continue
        mine = layers_of(module, layers)
        for target in sorted(imports_of(module, tree, trees, packages, face)):
            theirs = layers_of(target, layers)
            if len(mine) != 1 or len(theirs) != 1:  # unplaced: reported by unplaced()
                continue
            if rank[theirs[0]] > rank[mine[0]]:
                bad.append(f"{module} -> {target} ({mine[0]} -> {theirs[0]})")
    return bad


def unplaced(modules: Collection[str],
             layers: tuple[tuple[str, tuple[str, ...]], ...] = LAYERS) -> dict[str, list[str]]:
    """The modules (the face excepted) in no layer or in more than one, with their layers."""
    return {m: found for m in sorted(modules) if m != TOP
            and len(found := layers_of(m, layers)) != 1}


# --------------------------------------------------------------------------------------------
# the package
# --------------------------------------------------------------------------------------------
def _package() -> tuple[dict[str, ast.AST], set[str]]:
    """Dotted module name -> parsed source, and the names that are packages."""
    trees: dict[str, ast.AST] = {}
    packages = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
            packages.add(".".join(parts))
        trees[".".join(parts)] = ast.parse(path.read_text(encoding="utf-8"))
    return trees, packages


def _face_attributes(tree: ast.AST) -> dict[str, str]:
    """The face's lazy attributes: public name -> submodule (its ``_ATTRS``)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_ATTRS"
                                                for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("roughbrdf/__init__.py defines no _ATTRS")


TREES, PACKAGES = _package()
FACE = _face_attributes(TREES[TOP])


def test_every_module_has_exactly_one_layer():
    assert not unplaced(TREES), f"modules in no layer or in several: {unplaced(TREES)}"


def test_every_room_names_a_module():
    rooms = [room for _, rs in LAYERS for room in rs]
    assert len(rooms) == len(set(rooms)), rooms
    missing = [room for room in rooms if f"{TOP}.{room}" not in TREES]
    assert not missing, f"rooms of LAYERS that are no module: {missing}"


def test_imports_point_down():
    bad = upward_imports(TREES, PACKAGES, FACE)
    assert not bad, "upward imports:\n" + "\n".join(bad)


def test_the_fitting_rooms_point_down():
    inner = {m: t for m, t in TREES.items() if m.startswith(f"{TOP}.fitting.")}
    assert not unplaced(inner, FITTING_ROOMS), unplaced(inner, FITTING_ROOMS)
    bad = upward_imports(inner, PACKAGES, FACE, FITTING_ROOMS)
    assert not bad, "upward imports between the rooms of fitting:\n" + "\n".join(bad)


# --------------------------------------------------------------------------------------------
# the checker itself
# --------------------------------------------------------------------------------------------
_TOY_LAYERS = (("low", ("low", "util")), ("high", ("high",)))


def _toy(sources: dict[str, str]) -> dict[str, ast.AST]:
    return {f"{TOP}.{name}" if name else TOP: ast.parse(text) for name, text in sources.items()}


def test_the_checker_finds_an_upward_import():
    trees = _toy({"low": "def f():\n    from .high import g\n",
                  "high": "from . import low\nfrom roughbrdf.util import x\n", "util": ""})
    assert upward_imports(trees, set(), {}, _TOY_LAYERS) == [
        "roughbrdf.low -> roughbrdf.high (low -> high)"]


def test_the_checker_counts_type_checking_and_the_face():
    trees = _toy({"": "from .high import h\n",  # the face: exempt
                  "low": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                         "    from roughbrdf.high import H\n",
                  "util": "import roughbrdf as rb\n\ndef f():\n    return rb.h()\n",
                  "high": ""})
    assert upward_imports(trees, set(), {"h": "high"}, _TOY_LAYERS) == [
        "roughbrdf.low -> roughbrdf.high (low -> high)",
        "roughbrdf.util -> roughbrdf.high (low -> high)"]


def test_the_checker_resolves_packages_and_submodules():
    trees = _toy({"low": "from .high import part\n", "util": "import roughbrdf.high.part\n",
                  "high": "from . import part\n", "high.part": "from .. import low\n"})
    assert upward_imports(trees, {"roughbrdf.high"}, {}, _TOY_LAYERS) == [
        "roughbrdf.low -> roughbrdf.high.part (low -> high)",
        "roughbrdf.util -> roughbrdf.high.part (low -> high)"]


def test_the_checker_refuses_an_unplaced_module():
    assert unplaced({"roughbrdf.low", "roughbrdf.extra", "roughbrdf"}, _TOY_LAYERS) == {
        "roughbrdf.extra": []}
    assert unplaced({"roughbrdf.low"}, (*_TOY_LAYERS, ("again", ("low",)))) == {
        "roughbrdf.low": ["low", "again"]}

"""The house rules of ``src/roughbrdf``, read from the source with ``ast`` (nothing is imported).

* no module over 600 lines;
* no function whose body (docstring excluded) is over 80 lines;
* no private name (``_name``: a function, class or value) imported from another module --
  private *modules* of the package (``_kernels``, ``io/_common``) are fine;
* no import cycle among modules at run time, counting imports inside functions and not those
  under ``if TYPE_CHECKING:``;
* the fit options declared in exactly one place
  (:class:`roughbrdf.fitting.problem.options.FitOptions`):
  no other function spells out their list as its own parameters.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "src"
PACKAGE = SRC / "roughbrdf"
MAX_LINES = 600
MAX_BODY = 80
#: a function with this many fit options among its own parameters re-declares the list
MAX_OPTION_PARAMS = 5


def _modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8")) for name, path in MODULES.items()}


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _resolve(module: str, node: ast.ImportFrom) -> str:
    """The absolute module an ``ImportFrom`` in ``module`` names (``from ..x import y``)."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if not _is_package(module):
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _runtime_imports(tree: ast.AST) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement that runs (at import time or in a function), skipping the bodies
    of ``if TYPE_CHECKING:``."""
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _edges(module: str) -> set[str]:
    """The package modules ``module`` imports at run time (a name imported from a package
    counts as an import of the package's ``__init__``, a submodule as the submodule)."""
    out: set[str] = set()
    for node in _runtime_imports(TREES[module]):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            base = _resolve(module, node)
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base
                       for a in node.names]
        out.update(t for t in targets if t in MODULES and t != module)
    return out


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _body_lines(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    body = fn.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    if not body:
        return 0
    return (body[-1].end_lineno or body[-1].lineno) - body[0].lineno + 1


def test_no_module_over_600_lines():
    long = {name: n for name, path in MODULES.items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_no_function_body_over_80_lines():
    long = [f"{name}:{fn.name} ({_body_lines(fn)} lines)" for name, tree in TREES.items()
            for fn in ast.walk(tree)
            if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef)
            and _body_lines(fn) > MAX_BODY]
    assert not long, f"function bodies over {MAX_BODY} lines: {long}"


def test_no_private_name_imported_from_another_module():
    bad = []
    for name, tree in TREES.items():
        for node in ast.walk(tree):
            if not isinstance(node, ast.ImportFrom) or node.module == "__future__":
                continue
            base = _resolve(name, node)
            for alias in node.names:
                private = alias.name.startswith("_") and not alias.name.startswith("__")
                is_module = f"{base}.{alias.name}" in MODULES
                if private and not is_module and base.startswith("roughbrdf"):
                    bad.append(f"{name}: {alias.name} from {base}")
    assert not bad, f"private names imported across modules: {bad}"


def test_no_import_cycle_at_run_time():
    graph = {m: _edges(m) for m in MODULES}
    assert not _cycles(graph), f"import cycles at run time: {_cycles(graph)}"


def test_the_cycle_finder_finds_cycles():
    # the checker itself: a two-module loop and a self-import (not a cycle)
    assert _cycles({"a": {"b"}, "b": {"a"}, "c": set()}) == [["a", "b"]]
    assert _cycles({"a": set(), "b": {"a"}}) == []


def _fit_option_names() -> set[str]:
    path = PACKAGE / "fitting" / "problem" / "options.py"
    if not path.exists():
        pytest.fail("roughbrdf/fitting/problem/options.py (the one FitOptions) does not exist")
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef) and node.name == "FitOptions":
            return {s.target.id for s in node.body
                    if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)}
    pytest.fail("no class FitOptions in roughbrdf/fitting/problem/options.py")


def test_fit_options_declared_in_one_place():
    names = _fit_option_names()
    assert len(names) >= 20, sorted(names)  # loss, weights, fix, bounds, starts, seed, ...
    spelled = []
    for mod, tree in TREES.items():
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            a = fn.args
            params = {p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs]}
            if len(params & names) >= MAX_OPTION_PARAMS:
                spelled.append(f"{mod}:{fn.name} ({', '.join(sorted(params & names))})")
    assert not spelled, f"functions that spell out the fit options again: {spelled}"

"""Rules of the suite itself: no test asserts on elapsed time.

A time taken depends on the machine and its load, so an assertion on it fails on a loaded
machine without anything being wrong. A test
asserts on what the time stood for (a page that is paged, rows parsed in one block); speed
figures belong to ``benchmarks/`` (``benchmarks/bench_suite_figures.py``).

:func:`timed_assertions` reads a test module with :mod:`ast` and reports every ``assert`` (and
every ``if ...: pytest.fail(...)``) whose condition orders (``<``, ``<=``, ``>``, ``>=``) a
*timing value* against anything but the literal 0:

* a call of a clock: ``time.perf_counter()``, ``time.monotonic()``, ``time.time()``,
  ``time.process_time()`` (their ``_ns`` forms, ``thread_time``), ``timeit.timeit`` /
  ``repeat`` / ``default_timer``, however imported;
* a name assigned from a timing value in the same function (``t0 = time.perf_counter()``,
  ``elapsed = time.perf_counter() - t0``), followed through further assignments;
* a name, attribute or string subscript named like a time span: ``elapsed``, ``duration``,
  ``seconds``, ``took``, ``t0``/``t1``, ``start_time``... (also with a suffix: ``elapsed_s``).

Equality (``res.elapsed == pytest.approx(...)``: bookkeeping, not speed), ``0 < elapsed`` and
hang guards outside assertions (``while time.monotonic() < deadline``) are not reported.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

#: the suite: tests/ and its folders (tests/<subpackage>/, tests/core/)
TESTS = Path(__file__).parent
#: the clocks, by module
CLOCKS = {
    "time": {"perf_counter", "perf_counter_ns", "monotonic", "monotonic_ns", "time", "time_ns",
             "process_time", "process_time_ns", "thread_time", "thread_time_ns"},
    "timeit": {"timeit", "repeat", "default_timer"},
}
#: names of time spans
TIME_NAME = re.compile(r"^_?(elapsed|duration|seconds|secs|took|runtime|wall_?time|t[01]|"
                       r"t_?(start|end|begin|stop)|(start|end|stop)_?time)(_\w*)?$", re.I)
ORDERING = (ast.Lt, ast.LtE, ast.Gt, ast.GtE)


def _clock_bindings(tree: ast.AST) -> tuple[set[str], set[str]]:
    """Names bound to the clock modules (``import time as t``) and to clock functions
    (``from time import perf_counter``)."""
    modules, functions = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules |= {a.asname or a.name for a in node.names if a.name in CLOCKS}
        elif isinstance(node, ast.ImportFrom) and node.module in CLOCKS:
            functions |= {a.asname or a.name for a in node.names
                          if a.name in CLOCKS[node.module]}
    return modules, functions


class _Scope:
    """The timing values of one function (or of the module's top level)."""

    def __init__(self, body: ast.AST, modules: set[str], functions: set[str]) -> None:
        self.modules, self.functions = modules, functions
        self.names: set[str] = set()
        assigned = [(targets, value) for targets, value in _assignments(body)]
        changed = True
        while changed:  # follow t0 -> elapsed -> ... until nothing new
            changed = False
            for targets, value in assigned:
                if self.is_timing(value) and not targets <= self.names:
                    self.names |= targets
                    changed = True

    def is_timing(self, expr: ast.AST) -> bool:
        """Whether ``expr`` is, or is computed from, a timing value."""
        for node in ast.walk(expr):
            if isinstance(node, ast.Call) and self._is_clock(node.func):
                return True
            if isinstance(node, ast.Name) and (node.id in self.names
                                               or TIME_NAME.match(node.id)):
                return True
            if isinstance(node, ast.Attribute) and TIME_NAME.match(node.attr):
                return True
            if (isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant)
                    and isinstance(node.slice.value, str) and TIME_NAME.match(node.slice.value)):
                return True
        return False

    def _is_clock(self, func: ast.AST) -> bool:
        if isinstance(func, ast.Name):
            return func.id in self.functions
        return (isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name)
                and func.value.id in self.modules
                and any(func.attr in names for names in CLOCKS.values()))


def _assignments(body: ast.AST) -> list[tuple[set[str], ast.AST]]:
    out = []
    for node in ast.walk(body):
        if isinstance(node, ast.Assign):
            out.append(({n.id for t in node.targets for n in ast.walk(t)
                         if isinstance(n, ast.Name)}, node.value))
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)) and node.value is not None:
            if isinstance(node.target, ast.Name):
                out.append(({node.target.id}, node.value))
        elif isinstance(node, ast.NamedExpr):
            out.append(({node.target.id}, node.value))
    return out


def _is_zero(expr: ast.AST) -> bool:
    return isinstance(expr, ast.Constant) and expr.value == 0 and expr.value is not False


def _orders_a_timing(test: ast.AST, scope: _Scope) -> bool:
    for node in ast.walk(test):
        if not isinstance(node, ast.Compare):
            continue
        operands = [node.left, *node.comparators]
        for op, left, right in zip(node.ops, operands[:-1], operands[1:], strict=True):
            if not isinstance(op, ORDERING):
                continue
            timed = [scope.is_timing(left), scope.is_timing(right)]
            if timed == [True, True] or (timed[0] and not _is_zero(right)) or (
                    timed[1] and not _is_zero(left)):
                return True
    return False


def _fails(body: list[ast.stmt]) -> bool:
    """Whether a block calls ``pytest.fail`` (an ``if`` that is an assertion)."""
    return any(isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
               and n.func.attr == "fail" for stmt in body for n in ast.walk(stmt))


def timed_assertions(source: str, filename: str = "<test>") -> list[str]:
    """``"file:line: text"`` of every assertion on elapsed time in ``source``."""
    tree = ast.parse(source, filename)
    modules, functions = _clock_bindings(tree)
    scopes = [n for n in ast.walk(tree)
              if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    found: list[tuple[int, str]] = []
    for scope_node in [tree, *scopes]:
        scope = _Scope(scope_node, modules, functions)
        own = scope_node.body if scope_node is not tree else [
            s for s in tree.body if not isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef,
                                                       ast.ClassDef))]
        for stmt in own:
            for node in _own_statements(stmt):
                test = None
                if isinstance(node, ast.Assert):
                    test = node.test
                elif isinstance(node, ast.If) and _fails(node.body):
                    test = node.test
                if test is not None and _orders_a_timing(test, scope):
                    found.append((node.lineno, f"{filename}:{node.lineno}: {ast.unparse(test)}"))
    return [hit for _, hit in sorted(set(found))]


def _own_statements(stmt: ast.AST) -> list[ast.AST]:
    """``stmt`` and the statements nested in it, not those of nested functions (their own
    scope) or classes."""
    out, todo = [], [stmt]
    while todo:
        node = todo.pop()
        out.append(node)
        for child in ast.iter_child_nodes(node):
            if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef,
                                      ast.Lambda)):
                todo.append(child)
    return out


# --------------------------------------------------------------------------------------------
# the rule on the suite
# --------------------------------------------------------------------------------------------
def test_no_test_asserts_on_elapsed_time():
    found = [hit for path in sorted(TESTS.rglob("*.py"))
             for hit in timed_assertions(path.read_text(encoding="utf-8"),
                                         path.relative_to(TESTS).as_posix())]
    assert found == [], "assert on what the time stood for; figures go to benchmarks/:\n" + \
        "\n".join(found)


# --------------------------------------------------------------------------------------------
# the rule itself: what it reports and what it leaves alone
# --------------------------------------------------------------------------------------------
TIMED = {
    "summary (was in test_catalogue_summary.py)": """
import time
def test_x(tmp_path):
    t0 = time.perf_counter()
    write(tmp_path)
    elapsed = time.perf_counter() - t0
    assert size < 200 and elapsed < 20, elapsed
""",
    "browser (was in test_catalogue_summary.py)": """
import time
def test_x(browser):
    t0 = time.perf_counter()
    open(browser)
    opened = time.perf_counter() - t0
    t0 = time.perf_counter()
    click()
    sorted_in = time.perf_counter() - t0
    assert opened < 15 and sorted_in < 5, (opened, sorted_in)
""",
    "a deadline inside an assert (was in test_catalogue_summary.py)": """
import time
def _open(driver):
    deadline = time.monotonic() + 20
    while not ready():
        assert time.monotonic() < deadline, "the page's script did not finish"
""",
    "ALTA read (was in test_io_alta.py)": """
import time
def test_x():
    t0 = time.perf_counter()
    m = read()
    assert time.perf_counter() - t0 < 0.5
""",
    "from-import, alias, reversed, if/fail": """
from time import perf_counter as clock
import time as t
def test_x():
    start = clock()
    run()
    if 2.0 <= clock() - start:
        pytest.fail("too slow")
    begin = t.monotonic()
    assert 3 * (t.monotonic() - begin) >= 1
""",
    "relative speed, no constant": """
import timeit
def test_x():
    fast = timeit.timeit(f, number=10)
    slow = timeit.timeit(g, number=10)
    assert fast * 3 < slow
""",
    "a name or field of a time span": """
def test_x(res, row):
    assert res.duration <=1.0
    assert row["elapsed_s"] < 5
    assert took <2
""",
}

NOT_TIMED = {
    "equality of recorded times (test_compare.py)": """
def test_x(res, choice):
    assert res.elapsed == pytest.approx(sum(c.elapsed for c in choice.candidates))
""",
    "a time recorded as positive": """
def test_x(res):
    assert res.elapsed > 0 and 0 <= res.duration
""",
    "hang guards in loops (test_catalogue.py, test_cli_safety.py)": """
import time
def test_x(p):
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and p.poll() is None:
        time.sleep(0.1)
    give_up = time.monotonic() + 300
    while not ready():
        if time.monotonic() > give_up:
            break
    assert p.returncode == 0
""",
    "figures printed, not asserted": """
import time
def test_x():
    t0 = time.monotonic()
    run()
    duration = time.monotonic() - t0
    print(f"took {duration:.2f} s")
    assert code == 0, duration
""",
    "ordinary comparisons, a local function named time": """
def time():
    return 3
def test_x(m, values, counts):
    assert time() < 5 and m.n_samples > 100 and values.max() <= 1
    assert len(counts) >= 2 and counts["theta_i"] < 90
""",
}


@pytest.mark.parametrize("name", sorted(TIMED))
def test_the_rule_reports_timed_assertions(name):
    assert timed_assertions(TIMED[name]), name


@pytest.mark.parametrize("name", sorted(NOT_TIMED))
def test_the_rule_leaves_other_comparisons_alone(name):
    assert timed_assertions(NOT_TIMED[name]) == [], name


def test_the_rule_reports_each_of_several():
    hits = timed_assertions(TIMED["from-import, alias, reversed, if/fail"], "f.py")
    assert [h.split(":")[1] for h in hits] == ["7", "10"], hits

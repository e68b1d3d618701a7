"""SIGTERM and SIGHUP end ``fit``, ``fit-batch`` and ``explore`` as Ctrl-C does.

A timeout, a batch system (SLURM) or a service manager (systemd) stops a program with SIGTERM;
a closed terminal sends SIGHUP. Each ends the command cleanly: one line (``interrupted
(SIGTERM)``), exit status 128 + the signal's number (143, 129), nothing half-written, no lock
or temporary file left, and a local cluster's worker processes stopped.

The signal is sent from inside the program at a chosen point (the first local fit of the
search, the first rename of the output commit, the cluster's start), never by timing, except
for the explorer's server, which is signalled once it has printed its address.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.demo import default_measurement_path

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

SOURCE = str(default_measurement_path())
#: a bound on one subprocess: only against a hung test
HANG = 300

#: run the console entry point with a signal sent to this process (or its group) at a point
_AT = textwrap.dedent("""
    import os, signal, sys
    from roughbrdf.cli import main

    sig = getattr(signal, os.environ["SIGNAL"])
    where = os.environ["WHERE"]

    def send():
        if where == "group":
            os.killpg(os.getpgid(0), sig)
        else:
            os.kill(os.getpid(), sig)

    if where == "search":  # inside the fit: the first local fit of the search
        from roughbrdf.fitting.solvers import search
        original = search.local_fit

        def local_fit(*args, **kwargs):
            send()
            return original(*args, **kwargs)

        search.local_fit = local_fit
    elif where == "commit":  # inside the output's commit: its first rename
        import roughbrdf.output as output
        original = os.replace
        state = []

        def replace(*args, **kwargs):
            if not state:
                state.append(1)
                send()
            return original(*args, **kwargs)

        output.os.replace = replace
    elif where == "group":  # the cluster started: the whole process group, as a terminal
        from roughbrdf.catalogue import run
        run.STARTED_HOOKS.append(lambda cluster: send())
    sys.exit(main(sys.argv[1:]))
""")


def _run(args: list[str], sig: str, where: str) -> subprocess.CompletedProcess[str]:
    proc = subprocess.Popen([sys.executable, "-c", _AT, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            env={**os.environ, "SIGNAL": sig, "WHERE": where})
    try:
        out, err = proc.communicate(timeout=HANG)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    _group_gone(proc.pid)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _group_gone(pgid: int) -> None:
    """No process of the group is left (a worker would outlive its client otherwise)."""
    for _ in range(100):
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    raise AssertionError(f"a process of group {pgid} is still running")


def _no_leftovers(folder: Path) -> None:
    """No temporary file, lock or journal of roughbrdf's under ``folder``."""
    if folder.exists():
        names = [p.name for p in folder.rglob("*")]
        assert not [n for n in names if n.startswith(".roughbrdf-tmp")
                    or n == ".roughbrdf-lock"], names


STATUS = {"SIGTERM": 128 + signal.SIGTERM, "SIGHUP": 128 + signal.SIGHUP}


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_fit_during_the_search_ends_cleanly(tmp_path, sig):
    out = tmp_path / "fit"
    done = _run(["fit", SOURCE, "--model", "tr75", "--out", str(out), "--no-plots"], sig,
                "search")
    assert done.returncode == STATUS[sig], done.stderr
    assert done.stderr.strip().splitlines() == [f"interrupted ({sig})"], done.stderr
    assert not out.exists() or not any(out.iterdir())  # nothing written, not half of it


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_fit_during_the_commit_leaves_one_whole_set(tmp_path, sig):
    out = tmp_path / "fit"
    done = _run(["fit", SOURCE, "--model", "tr75", "--out", str(out), "--no-plots",
                 "--starts", "1"], sig, "commit")
    # the commit holds the signal to its end: the set is whole, and the run says it was
    # interrupted (the status of a run the signal ended)
    assert done.returncode == STATUS[sig], done.stderr
    assert done.stderr.strip().splitlines()[-1] == f"interrupted ({sig})", done.stderr
    _no_leftovers(out)
    res = rb.load_fit(out)  # reads one whole set (checks the journal and the hashes)
    assert res.channels and np.isfinite(res.channels[0].sigma)


def test_fit_batch_sigterm_stops_the_cluster_and_leaves_no_lock(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    for j in range(3):
        rb.write(rb.Measurement(ti, tr, ph, rb.model("tr75", e=0.5 + 0.1 * j, rho_L=0.2)
                                .brdf(ti, tr, ph)), data / f"s{j}.csv")
    out = tmp_path / "cat"
    done = _run(["fit-batch", str(data), "--model", "tr75", "--out", str(out), "--workers",
                 "2", "--starts", "1", "-q"], "SIGTERM", "group")
    assert done.returncode == 143, done.stderr
    assert done.stderr.strip().splitlines() == ["interrupted (SIGTERM)"], done.stderr
    _no_leftovers(out)
    _no_leftovers(data)


def test_explore_sigterm_is_143(tmp_path):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.pop("DISPLAY", None)
    proc = subprocess.Popen([sys.executable, "-m", "roughbrdf.cli", "explore", "--model",
                             "lambertian", "--no-browser"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline().strip()  # the address: the server listens
        assert line.startswith("http://"), (line, proc.poll())
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143, err
    assert err.strip().splitlines()[-1] == "interrupted (SIGTERM)" and "Traceback" not in err

"""Catalogues: ``rb.fit_catalogue`` and ``roughbrdf fit-batch`` on real
``dask.distributed`` clusters: a ``LocalCluster`` of 2 worker processes started by the call, and
an existing cluster reached by its scheduler address.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.catalogue import fit_catalogue
from roughbrdf.catalogue.resume import TASK_FILE
from roughbrdf.cli import app
from roughbrdf.output import LOCK, MANIFEST, TMP_PREFIX

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="catalogues: every row is a whole fit (~40 s or more in plain Python)")

pytest.importorskip("distributed")

runner = CliRunner()
_SCRIPT = os.path.join(os.path.dirname(sys.executable), "roughbrdf")
CLI = [_SCRIPT] if os.access(_SCRIPT, os.X_OK) else [sys.executable, "-m", "roughbrdf.cli"]
#: energy_constraint=False: these tests are about the catalogue's mechanics, and with it off
#: every row takes the not-ok path (status "gains-energy", exit 1) through the runners. The
#: constrained refit of these same synthetic sets is tested in tests/fitting/test_constrained.py (it
#: converges, with the albedo <= 1), the constraint's CLI in tests/fitting/test_energy_constraint.py
OPTS = {"starts": 2, "energy_constraint": False}
#: the status of a TR75 row: TR75 has no shadowing, its albedo exceeds 1 near grazing
#: incidence (unconstrained: the fit is written; fit-batch exits 1)
FITTED = "gains-energy"


def _write_synthetic(folder, n: int, seed: int = 1) -> list[str]:
    """``n`` distinct small TR75 files (random roughness, 2 % noise) on a coarse geometry."""
    rng = np.random.default_rng(seed)
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    paths = []
    for k in range(n):
        m = rb.model("tr75", e=rng.uniform(0.4, 0.9), rho_L=rng.uniform(0.1, 0.4))
        v = m.brdf(ti, tr, ph) * (1 + 0.02 * rng.standard_normal(ti.size))
        p = folder / f"s{k}.csv"
        rb.write(rb.Measurement(ti, tr, ph, v), p)
        paths.append(str(p))
    return paths


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return _write_synthetic(tmp_path_factory.mktemp("data"), 3)


@pytest.fixture(scope="module")
def cluster():
    """An existing cluster (2 single-threaded worker processes), reached by its address."""
    from distributed import LocalCluster

    from roughbrdf.catalogue.run import close_local

    c = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        yield c
    finally:  # bounded: a plain close can wait for ever once a worker was killed (CI, load)
        close_local(c)


def _same_as_rb_fit(rows, paths):
    by_file = {r["file"]: r for r in rows}
    for p in paths:
        ref = rb.fit("tr75", rb.read(p), progress=False, **OPTS)
        row = by_file[p]
        assert row["status"] == FITTED
        for name, value in ref.params.items():
            assert row["params"][name] == pytest.approx(value, rel=1e-10, abs=0), name
        assert row["sigma"] == pytest.approx(ref.sigma, rel=1e-10)
        assert row["sha256"] == ref.to_dict()["file_sha256"]


def test_local_cluster_matches_rb_fit(files, tmp_path):
    keys = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    before = {k: os.environ.get(k) for k in keys}
    res = fit_catalogue(files, "tr75", tmp_path / "cat", n_workers=2, plots=False,
                        progress=False, **OPTS)
    # the workers' one-thread settings must not leak into the caller's environment
    # (distributed's nannies write them into os.environ: catalogue.run puts it back)
    assert {k: os.environ.get(k) for k in keys} == before
    _same_as_rb_fit(res.rows, files)
    assert not res.failed and len(res.rows) == 3
    with open(tmp_path / "cat" / "catalogue.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert [t["file"] for t in table] == files
    assert {"param_e", "stderr_e", "sha256", "fit_dir", "n_excluded"} <= set(table[0])
    doc = json.loads((tmp_path / "cat" / "catalogue.json").read_text())
    assert [r["params"] for r in doc["rows"]] == [r["params"] for r in res.rows]
    for r in res.rows:  # the usual fit folder per input
        fit = json.loads((tmp_path / "cat" / r["fit_dir"] / "fit.json").read_text())
        assert fit["channels"][0]["params"] == r["params"]


def test_scheduler_address_matches_rb_fit(files, cluster, tmp_path):
    res = fit_catalogue(files, "tr75", tmp_path / "cat", scheduler=cluster.scheduler_address,
                        progress=False, **OPTS)
    _same_as_rb_fit(res.rows, files)
    for r in res.rows:  # plots by default: each row names its figure
        assert (tmp_path / "cat" / r["figure"]).read_bytes().startswith(b"\x89PNG")


def test_malformed_file_among_good_ones(files, cluster, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("garbage\n1,2\n")
    got = runner.invoke(app, ["fit-batch", *files, str(bad), "-m", "tr75", "--starts", "2",
                              "--no-energy-constraint", "--no-plots", "-o",
                              str(tmp_path / "cat"), "--scheduler",
                              cluster.scheduler_address])
    assert got.exit_code == 1, got.output
    assert f"failed: {bad}: FormatError" in got.output
    rows = json.loads((tmp_path / "cat" / "catalogue.json").read_text())["rows"]
    status = {r["file"]: (r["status"], r["error"]) for r in rows}
    assert status[str(bad)][0] == "failed" and "missing column" in status[str(bad)][1]
    assert all(status[f] == (FITTED, None) for f in files)


def test_resume_and_overwrite_refusal(cluster, tmp_path):
    paths = _write_synthetic(tmp_path, 3, seed=7)
    out = tmp_path / "cat"
    cmd = ["fit-batch", str(tmp_path / "*.csv"), "-m", "tr75", "--starts", "2", "--no-plots",
           "--no-energy-constraint", "-o", str(out), "--scheduler", cluster.scheduler_address]
    assert runner.invoke(app, cmd).exit_code == 1  # TR75 gains energy: written, exit 1
    first = json.loads((out / "catalogue.json").read_text())["rows"]
    again = runner.invoke(app, cmd)  # results there: refused before any work
    assert again.exit_code == 2 and "--force" in again.output
    rb.write(rb.read(paths[2]).subset(np.arange(20)), tmp_path / "changed.tmp", format="csv")
    shutil.move(tmp_path / "changed.tmp", paths[2])  # the third file changes
    got = runner.invoke(app, [*cmd, "--resume"])
    assert got.exit_code == 1, got.output
    rows = json.loads((out / "catalogue.json").read_text())["rows"]
    assert [r["status"] for r in rows] == ["skipped (resume)"] * 2 + [FITTED]
    assert rows[0]["params"] == first[0]["params"] and rows[2]["n_points"] == 20
    with_options = runner.invoke(app, [*cmd, "--resume", "--starts", "3"])  # options changed
    assert with_options.exit_code == 1
    rows = json.loads((out / "catalogue.json").read_text())["rows"]
    assert [r["status"] for r in rows] == [FITTED] * 3
    assert runner.invoke(app, [*cmd, "--force"]).exit_code == 1


@pytest.mark.parametrize("to", ["process", "group"])
def test_interrupted_run(tmp_path, to):
    """SIGINT to the command (``kill -INT``) or to its process group, workers included (Ctrl-C
    in a terminal)."""
    paths = _write_synthetic(tmp_path, 8, seed=3)
    out = tmp_path / "cat"
    p = subprocess.Popen([*CLI, "fit-batch", *paths, "-m", "tr75", "--starts", "24",
                          "--no-plots", "-q", "--workers", "2", "-o", str(out)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and p.poll() is None:
        if len(list(out.glob(f"*/{MANIFEST}"))) >= 1:
            break
        time.sleep(0.05)
    assert p.poll() is None, "the run ended before it could be interrupted"
    if to == "group":
        os.killpg(p.pid, signal.SIGINT)
    else:
        p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        pytest.fail("fit-batch still running 60 s after SIGINT")
    assert p.returncode == 130, err
    assert err.strip().splitlines()[-1] == "interrupted", err
    assert "Traceback" not in err, err
    assert not (out / "catalogue.csv").exists() and not (out / "catalogue.json").exists()
    finished = 0
    for sub in (d for d in out.iterdir() if d.is_dir()):
        names = {f.name for f in sub.iterdir()}
        assert not [n for n in names if n.startswith(TMP_PREFIX) or n == LOCK], names
        if MANIFEST in names:
            finished += 1
            assert {"fit.json", "report.txt", TASK_FILE} <= names
            assert set(json.loads((sub / MANIFEST).read_text())) == names - {MANIFEST}
    assert 1 <= finished < len(paths)
    assert not (out / LOCK).exists()


def _die_once(task):
    """``run_task``, but the first call ends its worker process (as a crash would)."""
    from pathlib import Path

    from roughbrdf.catalogue.tasks import run_task

    marker = Path(task.folder).parent / "died"
    if not marker.exists():
        marker.write_text("x")
        os._exit(1)
    return run_task(task)


def test_worker_death_is_retried(files, cluster, tmp_path, monkeypatch):
    import cloudpickle

    import roughbrdf.catalogue.run as run

    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        monkeypatch.setattr(run, "run_task", _die_once)
        res = fit_catalogue(files[:1], "tr75", tmp_path / "cat", plots=False, progress=False,
                            scheduler=cluster.scheduler_address, **OPTS)
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert (tmp_path / "cat" / "died").exists()
    _same_as_rb_fit(res.rows, files[:1])


def test_time_limit(files, cluster, tmp_path):
    res = fit_catalogue(files[:1], "tr75", tmp_path / "cat", scheduler=cluster.scheduler_address,
                        plots=False, progress=False, time_limit=0.01, starts=64)
    (row,) = res.rows
    assert row["status"] == "failed" and "time limit of 0.01 s" in row["error"]


def test_help_loads_neither_dask_nor_numpy():
    code = ("import sys\nfrom roughbrdf.cli import main\n"
            "sys.argv = ['roughbrdf', 'fit-batch', '--help']\n"
            "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'dask', 'distributed', 'numpy', 'numba', 'scipy'}))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert proc.stdout.strip().splitlines()[-1] == "[]"


def _dead_pid() -> int:
    """The process id of a process that has ended (a killed worker's, for the clean-up)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(proc.stdout)


def test_resume_cleans_what_killed_workers_left(files, cluster, tmp_path):
    # a worker killed mid-save (--time-limit restart, OOM kill) leaves its temporary files and
    # its lock in the fit folder; --resume removes them, in skipped folders and re-fitted ones
    from roughbrdf.catalogue.resume import TASK_FILE
    from roughbrdf.output import LOCK, TMP_PREFIX

    out = tmp_path / "cat"
    first = fit_catalogue(files[:2], "tr75", out, scheduler=cluster.scheduler_address,
                          plots=False, progress=False, **OPTS)
    folders = sorted({r["fit_dir"] for r in first.rows})
    assert len(folders) == 2
    pid = _dead_pid()
    for name in folders:
        (out / name / f"{TMP_PREFIX}{pid}-fit.json.part").write_text("half")
        (out / name / LOCK).write_text(f"{pid}\n")
    (out / folders[1] / TASK_FILE).unlink()  # an incomplete result: fitted again
    res = fit_catalogue(files[:2], "tr75", out, scheduler=cluster.scheduler_address,
                        plots=False, progress=False, resume=True, **OPTS)
    assert [r["status"] for r in res.rows if r["fit_dir"] == folders[0]][0].startswith(
        "skipped")
    assert not [r for r in res.rows if r["file"].endswith("s1.csv")][0]["status"].startswith(
        "skipped")
    for name in folders:
        left = sorted(p.name for p in (out / name).iterdir() if p.name.startswith("."))
        assert left == [".roughbrdf-outputs"], (name, left)


def test_an_interrupted_teardown_mutes_the_event_loops_loggers_and_restores_them(capsys):
    # catalogue.run.connect: while an interrupted run is torn down, distributed's own loop
    # callbacks can fail (a NameError in distributed.utils.sync's cancel under a loaded
    # machine), which tornado logs with a traceback; muted then, as they were after
    import logging

    from roughbrdf.catalogue import run

    log = logging.getLogger("tornado.application")
    log.disabled = False
    before = run._mute(run.TEARDOWN_LOGGERS)
    assert before["tornado.application"] is False
    log.error("Exception in callback: Traceback (most recent call last)")
    assert "Traceback" not in capsys.readouterr().err
    run._unmute(before)
    assert not any(logging.getLogger(nm).disabled for nm in run.TEARDOWN_LOGGERS
                   if not before[nm])


def test_the_sync_cancel_race_is_dropped_from_tornados_log_and_nothing_else(caplog):
    """distributed.utils.sync's ``cancel`` callback raising NameError (Ctrl-C reached ``sync``
    before its future existed; CI saw its traceback before "interrupted" once): dropped by
    ``run.SyncCancelFilter`` while a cluster's client is open; other errors are printed."""
    import logging
    import sys
    import types

    from roughbrdf.catalogue import run

    # a function named cancel in a file under "distributed", failing as distributed's does
    src = "def cancel():\n    if future is not None:\n        pass\n    future = 1\n"
    mod = types.ModuleType("fake_sync")
    exec(compile(src, "/x/site-packages/distributed/utils.py", "exec"), mod.__dict__)
    log = logging.getLogger("tornado.application")
    with run.sync_cancel_quiet():
        try:
            mod.cancel()
        except NameError:
            log.error("Exception in callback (cancel)", exc_info=sys.exc_info())
        try:
            {}["missing"]
        except KeyError:
            log.error("Exception in callback (other)", exc_info=sys.exc_info())
    logged = [r.getMessage() for r in caplog.records if r.name == "tornado.application"]
    assert logged == ["Exception in callback (other)"]
    assert not log.filters  # removed with the client

"""The local cluster of ``fit-batch``, closed to others and quiet:
a second local client without the cluster's credentials is refused, no HTTP port listens, the
workers' profiler is off, Ctrl-C at the start is quiet (one line, exit 130), and a bad option
exits 2 naming the CLI option before any cluster starts. Real ``dask.distributed`` clusters of
worker processes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.catalogue import fit_catalogue, run
from roughbrdf.cli import main
from roughbrdf.errors import ArgumentError

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="catalogues: every row is a whole fit (~40 s or more in plain Python)")

pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    ti, tr, ph = (a.ravel() for a in np.meshgrid(np.radians([20.0, 45.0]),
                                                 np.radians(np.arange(0.0, 80.0, 10.0)),
                                                 [0.0, np.pi], indexing="ij"))
    p = tmp_path_factory.mktemp("data") / "s.csv"
    rb.write(rb.Measurement(ti, tr, ph, rb.model("tr75", e=0.6, rho_L=0.2).brdf(ti, tr, ph)), p)
    return str(p)


def _listening_ports(pid: int) -> set[int]:
    import psutil

    procs = [psutil.Process(pid), *psutil.Process(pid).children(recursive=True)]
    ports = set()
    for p in procs:
        for c in p.net_connections(kind="inet"):
            if c.status == psutil.CONN_LISTEN:
                ports.add(c.laddr.port)
    return ports


#: another process's client, without the cluster's credentials: prints "refused" for each
#: address it cannot use (run in its own process: a refused ``Client`` left to the garbage
#: collector can deadlock the next ``Client`` made in the same process, distributed's
#: ``LoopRunner``; seen in CI)
_OTHER_CLIENT = textwrap.dedent("""
    import os, sys
    from distributed import Client

    for address in sys.argv[1:]:
        try:
            with Client(address, timeout="3s") as other:
                other.run(os.getpid)
            print("connected", address)
        except Exception:  # refused: TLS, or no certificate
            print("refused", address)
""")


def test_cluster_refuses_other_clients_no_http_profiler_off(data, tmp_path, monkeypatch):
    import dask

    seen: dict = {}

    def probe(client):
        addr = client.scheduler.address
        seen["address"] = addr
        plain = [addr, addr.replace("tls://", "tcp://")]
        other = subprocess.run([sys.executable, "-c", _OTHER_CLIENT, *plain],
                               capture_output=True, text=True, timeout=300)
        seen["other"] = other.stdout.split()
        seen["profile"] = client.run(
            lambda: dask.config.get("distributed.worker.profile.enabled"))
        seen["profile_env"] = client.run(
            lambda: os.environ.get("DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED"))
        info = client.scheduler_info()
        comm = {int(addr.rsplit(":", 1)[1])}
        for address, w in info["workers"].items():
            comm.add(int(address.rsplit(":", 1)[1]))
            if w.get("nanny"):
                comm.add(int(w["nanny"].rsplit(":", 1)[1]))
        seen["comm"] = comm
        seen["listening"] = _listening_ports(os.getpid())

    monkeypatch.setattr(run, "CONNECTED_HOOKS", [probe])
    res = fit_catalogue([data], "tr75", tmp_path / "cat", n_workers=1, plots=False, starts=1,
                        progress=False)
    assert not res.failed  # (TR75 fitted under the energy constraint: "ok" rows)
    assert seen["address"].startswith("tls://127.0.0.1:")
    tcp = seen["address"].replace("tls://", "tcp://")
    assert seen["other"] == ["refused", seen["address"], "refused", tcp], seen["other"]
    assert set(seen["profile"].values()) == {False}
    assert set(seen["profile_env"].values()) == {"False"}
    # every listening socket of this process and its workers is a (TLS) comm of the cluster
    assert seen["listening"] <= seen["comm"], seen
    assert 8787 not in seen["listening"]


_CTRL_C = textwrap.dedent("""
    import os, signal, sys
    from roughbrdf.catalogue import run
    from roughbrdf.cli import main

    def ctrl_c(cluster):  # what a terminal does: SIGINT to the whole process group
        os.killpg(os.getpgid(0), signal.SIGINT)

    run.STARTED_HOOKS.append(ctrl_c)
    sys.exit(main(sys.argv[1:]))
""")


def test_ctrl_c_at_start_is_one_line_exit_130(data, tmp_path):
    out = tmp_path / "cat"
    proc = subprocess.run([sys.executable, "-c", _CTRL_C, "fit-batch", data, "--model", "tr75",
                           "--out", str(out), "--workers", "2", "--starts", "1", "-q"],
                          capture_output=True, text=True, timeout=300, start_new_session=True,
                          env={**os.environ, "PYTHONWARNINGS": "default"})
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr.strip() == "interrupted", proc.stderr
    assert not (out / "catalogue.csv").exists()


_CTRL_C_DURING_START = textwrap.dedent("""
    import os, signal, sys, threading
    from roughbrdf.catalogue import run
    from roughbrdf.cli import main

    delay = float(os.environ["CTRL_C_DELAY"])
    start = run.start_local

    def start_local(*args, **kwargs):  # Ctrl-C from the terminal, DELAY s into the start
        threading.Timer(delay, os.killpg, (os.getpgid(0), signal.SIGINT)).start()
        return start(*args, **kwargs)

    run.start_local = start_local
    sys.exit(main(sys.argv[1:]))
""")


@pytest.mark.parametrize("delay", [0.0, 0.4, 1.2, 2.5])
def test_ctrl_c_during_start_is_one_line_and_stops_the_workers(data, tmp_path, delay):
    # Ctrl-C reaches the whole process group at any instant of the cluster's start (before
    # the scheduler, while the workers spawn or import, after they are up): one line, exit
    # 130, and no process of the group is left (the workers were stopped, not orphaned)
    out = tmp_path / "cat"
    proc = subprocess.Popen(
        [sys.executable, "-c", _CTRL_C_DURING_START, "fit-batch", data, "--model", "tr75",
         "--out", str(out), "--workers", "2", "--starts", "1", "-q"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        env={**os.environ, "CTRL_C_DELAY": str(delay), "PYTHONWARNINGS": "default"})
    try:
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    lines = stderr.strip().splitlines()
    # a start that finished before the signal fits and exits 0 (the data are tiny): both
    # are fine, what is checked is the interrupted case's one line
    assert proc.returncode in (0, 130), stderr
    if proc.returncode == 130:
        assert lines == ["interrupted"], stderr
        assert not (out / "catalogue.csv").exists()
    alive = None
    for _ in range(100):  # the workers' exit follows the client's by a moment
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            alive = False
            break
        alive = True
        import time

        time.sleep(0.1)
    assert alive is False, "a worker process of the interrupted start is still running"


@pytest.mark.parametrize(("options", "message"), [
    (["--starts", "0"], "error: --starts must be >= 1 (got 0)"),
    (["--loss", "x"], "error: --loss: unknown value 'x' (choose from auto, relative, log, "
                     "absolute, robust)"),
    (["--seed", "-1"], "error: --seed must be >= 0 (got -1)"),
    (["--format", "zz"], "error: --format: unknown value 'zz' (choose from astm, alta, merl, "
                         "csv, zemax, lighttools, rgl)"),
    (["--relative-to", "zz"], "error: --relative-to: unknown value 'zz' (choose from brdf, "
                              "bridf)"),
    (["--negative", "zz"], "error: --negative zz: must be 'auto', 'keep', 'drop' or 'clip'"),
    (["--time-limit", "0"], "error: --time-limit must be a number of seconds > 0 (got 0)"),
])
def test_bad_option_exits_2_before_any_cluster(data, tmp_path, monkeypatch, capsys, options,
                                               message):
    def no_cluster(*args, **kwargs):
        raise AssertionError("connect was called")

    monkeypatch.setattr(run, "connect", no_cluster)
    code = main(["fit-batch", data, "--model", "tr75", "--out", str(tmp_path / "cat"), "-q",
                 *options])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and err.startswith(message), err
    assert not (tmp_path / "cat").exists()


@pytest.mark.parametrize(("options", "argument"), [
    ({"starts": 0}, "starts"), ({"loss": "x"}, "loss"), ({"seed": -1}, "seed"),
    ({"subsample": 0}, "subsample"), ({"fix": ["zz"]}, "fix"),
    ({"bounds": {"e": (3.0, 1.0)}}, "bounds"), ({"strats": 2}, "strats"),
    ({"channel": [1.5]}, "channel"), ({"shared": ["e"]}, "shared"),
    ({"retries": -1}, "retries"),
])
def test_library_checks_options_before_any_cluster(data, tmp_path, monkeypatch, options,
                                                   argument):
    def no_cluster(*args, **kwargs):
        raise AssertionError("connect was called")

    monkeypatch.setattr(run, "connect", no_cluster)
    with pytest.raises(ArgumentError) as err:
        fit_catalogue([data], "tr75", tmp_path / "cat", progress=False, **options)
    assert err.value.argument == argument
    assert not (tmp_path / "cat").exists()


def test_close_local_kills_the_workers_of_a_cluster_that_does_not_close():
    # a cluster whose close times out (a nanny that no longer answers): its worker processes are
    # killed and the call returns; another child of the caller's is left alone
    from types import SimpleNamespace

    from roughbrdf.catalogue.run import close_local

    worker = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    closed: list = []

    def hangs(timeout):
        closed.append(timeout)
        raise TimeoutError("close timed out")

    try:
        cluster = SimpleNamespace(workers={"w": SimpleNamespace(pid=worker.pid), "x": object()},
                                  close=hangs)
        close_local(cluster, timeout=0.5)
        assert closed == [0.5]
        assert worker.wait(10) == -signal.SIGKILL
        assert other.poll() is None
    finally:
        for p in (worker, other):
            p.kill()
            p.wait()

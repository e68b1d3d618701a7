"""``roughbrdf explore``'s server: real HTTP requests to a server on a free port.

The guard (``roughbrdf.explore.security``): a request without the run's token is 403, a
foreign Host or Origin is 403, the token in the address becomes a cookie; the bind: loopback
only unless ``--host``, a busy ``--port`` is exit 2 naming it, Ctrl-C is 130 (a subprocess and
SIGINT); the inputs: a bad file, a fit whose input is gone, one message in the terminal and on
the page, no traceback; exports land only in the ``--out`` folder. The browser side is
``tests/explore/test_explore_browser.py``.
"""

from __future__ import annotations

import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("dash", reason="the explore extra (pip install roughbrdf[explore])")

import roughbrdf as rb  # noqa: E402
from roughbrdf.cli import main  # noqa: E402
from roughbrdf.explore.app import build_app  # noqa: E402
from roughbrdf.explore.app_jobs import FitJob, export_model  # noqa: E402
from roughbrdf.explore.app_state import load_session, model_from_controls  # noqa: E402
from roughbrdf.explore.security import TOKEN_HEADER, Guard, cookie_name  # noqa: E402
from roughbrdf.explore.server import bind, exposure_note  # noqa: E402

DATA = Path(__file__).parents[1] / "data"
ZEMAX = DATA / "zemax" / "AnoBlackNiTEonINVAR.bsdf"
#: seconds a subprocess server may take to print its address before the test gives up (a hung
#: start-up, not a speed figure)
START = 120


def _request(port: int, path: str = "/", *, host: str | None = None,
             headers: dict[str, str] | None = None, method: str = "GET",
             body: bytes | None = None) -> tuple[int, dict[str, str], bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    try:
        conn.putrequest(method, path, skip_host=True)
        conn.putheader("Host", f"127.0.0.1:{port}" if host is None else host)
        for k, v in (headers or {}).items():
            conn.putheader(k, v)
        if body is not None:
            conn.putheader("Content-Length", str(len(body)))
        conn.endheaders(body)
        resp = conn.getresponse()
        return resp.status, {k.lower(): v for k, v in resp.getheaders()}, resp.read()
    finally:
        conn.close()


@pytest.fixture(scope="module")
def served() -> Iterator[Any]:
    """The real application for a model alone, served in a thread on a free port."""
    session = load_session(model="lambertian", params={"rho": 0.3})
    server = bind(build_app(session).server, port=0)
    server.start_thread()
    try:
        yield server
    finally:
        server.shutdown()


def _cookie(server: Any) -> dict[str, str]:
    return {"Cookie": f"{cookie_name(server.port)}={server.token}"}


# --------------------------------------------------------------------------------------------
# the token, the Host and the Origin
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["/", "/_dash-layout", "/_dash-dependencies",
                                  "/_dash-component-suites/dash/deps/react@18.min.js",
                                  "/_favicon.ico", "/nowhere"])
def test_without_the_token_every_request_is_403(served: Any, path: str) -> None:
    status, _, body = _request(served.port, path)
    assert status == 403, (path, status)
    assert b"token" in body and b"rho" not in body


def test_a_wrong_token_is_403_in_query_cookie_and_header(served: Any) -> None:
    wrong = served.token[:-1] + ("A" if served.token[-1] != "A" else "B")
    assert _request(served.port, f"/?token={wrong}")[0] == 403
    assert _request(served.port, "/", headers={"Cookie": f"{cookie_name(served.port)}="
                                                         f"{wrong}"})[0] == 403
    assert _request(served.port, "/", headers={TOKEN_HEADER: wrong})[0] == 403
    # the cookie of another port's server does not open this one
    other = {"Cookie": f"{cookie_name(served.port + 1)}={served.token}"}
    assert _request(served.port, "/", headers=other)[0] == 403


def test_the_token_in_the_address_becomes_a_cookie(served: Any) -> None:
    status, headers, _ = _request(served.port, f"/?token={served.token}")
    assert status == 303 and headers["location"] == "/"  # the token leaves the address
    cookie = headers["set-cookie"]
    assert cookie.startswith(f"{cookie_name(served.port)}={served.token};")
    assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
    status, _, page = _request(served.port, "/", headers=_cookie(served))
    assert status == 200 and b"react-entry-point" in page
    assert _request(served.port, "/_dash-layout", headers={TOKEN_HEADER: served.token})[0] == 200


@pytest.mark.parametrize("host", ["evil.example:{port}", "127.0.0.1:{other}", "127.0.0.1",
                                  "localhost.evil.example:{port}", "", "[::1]:{other}"])
def test_a_foreign_host_is_refused(served: Any, host: str) -> None:
    value = host.format(port=served.port, other=served.port + 1)
    status, _, body = _request(served.port, "/", host=value, headers=_cookie(served))
    assert status == 403, value
    assert b"Host" in body


def test_localhost_is_the_same_loopback_host(served: Any) -> None:
    assert _request(served.port, "/", host=f"localhost:{served.port}",
                    headers=_cookie(served))[0] == 200


@pytest.mark.parametrize("origin", ["http://evil.example", "http://127.0.0.1:{other}",
                                    "https://127.0.0.1:{port}", "null"])
def test_a_foreign_origin_is_refused(served: Any, origin: str) -> None:
    value = origin.format(port=served.port, other=served.port + 1)
    body = json.dumps({"output": "x", "inputs": []}).encode()
    status, _, text = _request(served.port, "/_dash-update-component", method="POST",
                               body=body, headers={**_cookie(served), "Origin": value,
                                                   "Content-Type": "application/json"})
    assert status == 403, value
    assert b"Origin" in text


def test_the_own_origin_passes(served: Any) -> None:
    status, _, _ = _request(served.port, "/_dash-layout", headers={
        **_cookie(served), "Origin": f"http://127.0.0.1:{served.port}"})
    assert status == 200


def test_the_page_references_no_external_address(served: Any) -> None:
    """Offline: every script and style of the page comes from this server."""
    pages = [_request(served.port, p, headers=_cookie(served))[2].decode()
             for p in ("/", "/_dash-layout", "/_dash-dependencies")]
    for text in pages:
        assert not re.findall(r"(?:https?:)?//[a-z0-9.-]+\.[a-z]{2,}", text, re.I), text[:200]
    scripts = re.findall(r'<script src="([^"]+)"', pages[0])
    assert scripts and all(s.startswith("/_dash-component-suites/") for s in scripts)
    for src in scripts:  # and they are all served from the installed packages
        assert _request(served.port, src, headers=_cookie(served))[0] == 200, src


def test_the_guard_refuses_an_empty_token() -> None:
    with pytest.raises(ValueError, match="token"):
        Guard(lambda e, s: [b""], token="", host="127.0.0.1", port=1)


# --------------------------------------------------------------------------------------------
# the bind
# --------------------------------------------------------------------------------------------
def _other_address() -> str | None:
    """A non-loopback address of this machine, if it has one (no packet is sent)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect(("192.0.2.1", 9))  # TEST-NET-1 (RFC 5737): only picks the route
            addr = s.getsockname()[0]
        except OSError:
            return None
    return None if addr.startswith("127.") else addr


def test_binds_loopback_only_by_default(served: Any) -> None:
    assert served.host == "127.0.0.1"
    assert served._wsgi.socket.getsockname()[0] == "127.0.0.1"
    other = _other_address()
    if other is None:
        pytest.skip("this machine has no non-loopback address to try")
    with pytest.raises(OSError), socket.create_connection((other, served.port), timeout=5):
        pass


def test_exposure_is_said_only_beyond_loopback() -> None:
    assert exposure_note("127.0.0.1") == "" and exposure_note("localhost") == ""
    note = exposure_note("0.0.0.0")
    assert "every network interface" in note and "not encrypted" in note


def test_a_busy_port_is_a_usage_error_naming_it(capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        code = main(["explore", "--model", "lambertian", "--port", str(port), "--no-browser"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"--port {port}" in err and "in use" in err and "Traceback" not in err


def test_a_port_out_of_range_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["explore", "--model", "lambertian", "--port", "70000", "--no-browser"])
    assert code == 2 and "--port" in capsys.readouterr().err


def test_nothing_to_explore_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["explore", "--no-browser"]) == 2
    assert "nothing to explore" in capsys.readouterr().err
    assert main(["explore", "-p", "rho=0.2", str(ZEMAX), "--no-browser"]) == 2
    assert "give --model" in capsys.readouterr().err


def test_a_host_that_is_not_here_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["explore", "--model", "lambertian", "--host", "192.0.2.1", "--no-browser"])
    err = capsys.readouterr().err
    assert code == 2 and "--host '192.0.2.1'" in err, err


# --------------------------------------------------------------------------------------------
# the command line: address, Ctrl-C, bad input
# --------------------------------------------------------------------------------------------
def _start(*args: str, cwd: Path | None = None) -> tuple[subprocess.Popen[str], str]:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    proc = subprocess.Popen([sys.executable, "-m", "roughbrdf.cli", "explore", *args,
                             "--no-browser"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, cwd=cwd)
    give_up = time.monotonic() + START
    line = ""
    assert proc.stdout is not None
    while time.monotonic() < give_up and not line:
        line = proc.stdout.readline().strip()
        if proc.poll() is not None:
            break
    if not line.startswith("http://"):
        proc.kill()
        raise AssertionError(f"no address printed: {line!r} {proc.communicate()[1]}")
    return proc, line


def _stop(proc: subprocess.Popen[str]) -> tuple[int, str]:
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    return proc.returncode, err


def test_ctrl_c_stops_the_server_with_130() -> None:
    proc, url = _start("--model", "lambertian")
    m = re.fullmatch(r"http://127\.0\.0\.1:(\d+)/\?token=([\w-]{40,})", url)
    assert m, url
    port, token = int(m[1]), m[2]
    assert _request(port, f"/?token={token}")[0] == 303
    assert _request(port, "/")[0] == 403
    code, err = _stop(proc)
    assert code == 130, err
    assert err.strip().splitlines()[-1] == "interrupted" and "Traceback" not in err
    with pytest.raises(OSError):  # the port is closed
        socket.create_connection(("127.0.0.1", port), timeout=5).close()


@pytest.mark.parametrize("case", ["bad file", "fit input gone"])
def test_a_bad_input_is_one_message_in_the_terminal_and_the_page(tmp_path: Path,
                                                                 case: str) -> None:
    if case == "bad file":
        culprit = tmp_path / "broken.astm"
        culprit.write_text("this is not an ASTM file\n1 2 3\n")
        args = [str(culprit)]
    else:
        folder, culprit = _fit_folder(tmp_path)
        culprit.unlink()
        args = ["--fit", str(folder)]
    proc, url = _start(*args)
    port, token = int(url.split(":")[2].split("/")[0]), url.split("token=")[1]
    status, _, layout = _request(port, "/_dash-layout", headers={TOKEN_HEADER: token})
    code, err = _stop(proc)
    assert status == 200
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and str(culprit.name) in errors[0], err
    assert "Traceback" not in err and code == 130
    text = json.dumps(json.loads(layout))
    assert text.count("error: ") == 1 and culprit.name in text
    banner = json.loads(layout)["props"]["children"][1]["props"]
    assert banner["id"] == "banner" and banner["children"] == errors[0]


def _fit_folder(tmp_path: Path) -> tuple[Path, Path]:
    data = tmp_path / "in" / "ano.bsdf"
    data.parent.mkdir()
    shutil.copy(ZEMAX, data)
    meas = rb.read(data)
    res = rb.fit(rb.model("lambertian"), meas, starts=1, progress=False)
    folder = tmp_path / "fit"
    res.save(folder, plots=False)
    return folder, data


def test_a_fit_whose_input_is_gone_is_one_message(tmp_path: Path) -> None:
    folder, data = _fit_folder(tmp_path)
    ok = load_session(fit_dir=str(folder))
    assert ok.error == "" and ok.measurement is not None and "lambertian" in ok.fit_report
    assert ok.model is not None and ok.model.params == ok.fit_models["value"].params
    data.unlink()
    gone = load_session(fit_dir=str(folder))
    assert gone.error and str(data) in gone.error and "gone" in gone.error
    assert "\n" not in gone.error and "Traceback" not in gone.error


def test_session_errors_are_one_line() -> None:
    assert load_session("no/such/file.astm").error == "no/such/file.astm: no such file"
    assert "no-such-model" in load_session(model="no-such-model").error


# --------------------------------------------------------------------------------------------
# controls, fit, export
# --------------------------------------------------------------------------------------------
def test_a_typed_value_outside_the_domain_keeps_the_model_and_says_why() -> None:
    base = rb.model("oren-nayar")
    model, bad = model_from_controls(base, {"sigma": -5.0, "rho": 0.25}, {})
    assert model.params["rho"] == 0.25 and model.params["sigma"] == base.params["sigma"]
    assert "sigma" in bad["sigma"] and "deg" in bad["sigma"]
    model, bad = model_from_controls(base, {"sigma": 20.0}, {})  # degrees on the page
    assert bad == {} and model.params["sigma"] == pytest.approx(0.3490658503988659)


@pytest.mark.jit_heavy(reason="exports check 19 albedos: 2 min in plain Python")
def test_exports_land_only_in_the_out_folder(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    model = rb.model("lambertian", rho=0.3)
    for name in ("../escape", "/tmp/abs", "sub/x", ".hidden", "", "a\\b"):
        with pytest.raises(ValueError, match="file name|would not be in"):
            export_model(model, out, name, "mitsuba")
    (tmp_path / "link").symlink_to(tmp_path)
    with pytest.raises(ValueError, match="export is off"):
        export_model(model, None, "paint", "mitsuba")
    text = export_model(model, out, "paint", "mitsuba")
    assert sorted(p.name for p in out.iterdir()) == ["paint.json"] and "wrote" in text
    export_model(model, out, "paint", "zemax")
    assert sorted(p.name for p in out.iterdir()) == ["paint.bsdf", "paint.json"]
    with pytest.raises(FileExistsError):  # the output rules: never replaced
        export_model(model, out, "paint", "mitsuba")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "out"]


def test_the_fit_job_reports_and_can_be_cancelled() -> None:
    meas = rb.read(ZEMAX)
    job = FitJob(rb.model("lambertian"), meas, starts=1).start()
    job.join(300)
    assert job.state == "finished" and job.done == job.total == 1, job.error
    assert "rho" in job.report and set(job.models) == {"value"}
    stopped = FitJob(rb.model("lambertian"), meas, starts=1)
    stopped.cancel()
    stopped.start().join(60)
    assert stopped.state == "cancelled" and stopped.done == 0
    running = FitJob(rb.model("lambertian"), meas, starts=1).start()
    running.cancel()  # while the channel is fitted: cancelled at once, its result dropped
    assert running.state == "cancelled" and running.status().startswith("fit cancelled")
    running.join(300)
    assert running.state == "cancelled" and running.models == {} and running.reports == []


def test_explore_help_loads_no_dash() -> None:
    code = ("import sys\nfrom roughbrdf.cli import main\n"
            "sys.argv = ['roughbrdf', 'explore', '--help']\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('dash', 'plotly', 'flask', 'werkzeug')))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 0, proc.stderr
    assert "--fit" in proc.stdout and proc.stdout.strip().splitlines()[-1] == "[]"
    proc = subprocess.run([sys.executable, "-c", "import roughbrdf, roughbrdf.explore, sys; "
                           "print([m for m in sys.modules if m.startswith(('dash', 'plotly'))"
                           "])"], capture_output=True, text=True, check=False)
    assert proc.stdout.strip() == "[]", proc.stderr


def test_a_wildcard_host_takes_ip_literals_and_own_names_only() -> None:
    """``--host 0.0.0.0``: the Host may be any address of the machine (an IP literal) or its
    own name, never a foreign name (DNS rebinding); the token is still needed."""
    server = bind(lambda env, start: (start("200 OK", []), [b"ok"])[1], host="0.0.0.0")
    server.start_thread()
    try:
        token = {TOKEN_HEADER: server.token}
        assert _request(server.port, "/", host=f"127.0.0.1:{server.port}", headers=token)[0] \
            == 200
        assert _request(server.port, "/", host=f"{socket.gethostname()}:{server.port}",
                        headers=token)[0] == 200
        assert _request(server.port, "/", host=f"evil.example:{server.port}",
                        headers=token)[0] == 403
        assert _request(server.port, "/", host=f"127.0.0.1:{server.port}")[0] == 403
    finally:
        server.shutdown()


def test_an_explicit_host_says_what_it_exposes() -> None:
    proc, url = _start("--model", "lambertian", "--host", "0.0.0.0")
    code, err = _stop(proc)
    assert url.startswith("http://0.0.0.0:") and code == 130
    assert "--host 0.0.0.0: listening on every network interface" in err, err
    proc, url = _start("--model", "lambertian", "--host", "127.0.0.1")
    code, err = _stop(proc)
    assert url.startswith("http://127.0.0.1:") and "listening on" not in err and code == 130

"""CLI messages in the terms of the verb used:
one line on stderr naming the option and the value, exit 2, never an internal error.

Each test runs ``roughbrdf.cli.main([...])`` as a user would and reads stderr with ``capsys``.
"""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.cli import main
from roughbrdf.demo import default_measurement_path
from roughbrdf.measurement import Measurement

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

DEFAULT = default_measurement_path()


def _run(capsys, *args) -> tuple[int, str]:
    """Exit status and stderr of ``roughbrdf ARGS``."""
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


def _one_line(err: str) -> str:
    """The one line of an error, checked to be one line and no traceback."""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    assert lines[0].startswith("error: "), err
    return lines[0]


def _absolute_csv(tmp_path, channels=("465nm", "525nm", "630nm")):
    """A small absolute-BRDF CSV file (three channels) written by the library."""
    ti, tr = np.meshgrid(np.radians([10.0, 30.0, 50.0]), np.radians(np.arange(0.0, 80.0, 10.0)))
    ti, tr = ti.ravel(), tr.ravel()
    m = rb.model("tr75")
    v = np.asarray(m.brdf(ti, tr, np.zeros_like(ti)))
    meas = Measurement(ti, tr, np.zeros_like(ti), np.column_stack([v * (1 + 0.1 * j) for j in
                                                                   range(len(channels))]),
                       channels=list(channels), quantity="brdf")
    path = tmp_path / "abs.csv"
    rb.io.write(meas, path)
    return path


# --------------------------------------------------------------------------------------------
# eval: ranges and numbers
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("option", ["--theta-i", "--theta-r", "--phi"])
@pytest.mark.parametrize("value", ["0:inf:1", "nan", "inf", "0:90:0", "0:90:-1", "0:1e9:1",
                                   "0:nan:5", "a:b:c", "1:2"])
def test_eval_bad_range_is_one_line_naming_option(capsys, option, value):
    code, err = _run(capsys, "eval", "tr75", option, value)
    line = _one_line(err)
    assert code == 2
    assert option in line and repr(value) in line


def test_eval_range_limit_is_said(capsys):
    code, err = _run(capsys, "eval", "tr75", "--theta-r", "0:10:1e-4")  # 100001 values
    line = _one_line(err)
    assert code == 2 and "limit" in line and "100000" in line
    # a descending range is a range (not refused as a "negative step")
    code = main(["eval", "tr75", "--theta-r", "60:0:-30"])
    out = capsys.readouterr().out
    assert code == 0
    assert [row.split(",")[1] for row in out.splitlines()[1:]] == ["60", "30", "0"]


def test_eval_grid_limit(capsys):
    code, err = _run(capsys, "eval", "tr75", "--theta-i", "0:10:0.01", "--theta-r",
                     "0:10:0.01")  # 1001 x 1001 x 1 points
    line = _one_line(err)
    assert code == 2 and "--theta-i x --theta-r x --phi" in line and "1000000" in line


@pytest.mark.parametrize("value", ["nan", "inf", "-5", "1e9"])
def test_plot_elevation_in_degrees(capsys, tmp_path, value):
    code, err = _run(capsys, "plot", "tr75", "--kind", "polar", "--theta-i", "30",
                     "--elevation", value, "--out", tmp_path / "p.png")
    line = _one_line(err)
    assert code == 2 and "--elevation" in line and "degrees" in line and " rad" not in line
    assert not (tmp_path / "p.png").exists()


def test_param_without_equals_is_one_line(capsys):
    code, err = _run(capsys, "eval", "tr75", "-p", "e0.5")
    line = _one_line(err)
    assert code == 2 and "-p/--param" in line and "'e0.5'" in line


# --------------------------------------------------------------------------------------------
# fit / compare: options named
# --------------------------------------------------------------------------------------------
def test_relative_to_refused_for_absolute_data(capsys, tmp_path):
    path = _absolute_csv(tmp_path)
    code, err = _run(capsys, "fit", path, "-m", "tr75", "--relative-to", "brfd", "--starts",
                     "1", "--no-plots", "-q", "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and "--relative-to" in line and "'brfd'" in line
    assert "'brdf'" in line and "'bridf'" in line
    assert not (tmp_path / "o").exists()


def test_relative_to_unknown_for_relative_data_names_option(capsys, tmp_path):
    code, err = _run(capsys, "fit", DEFAULT, "-m", "tr75", "--relative-to", "xyz",
                     "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and line.startswith("error: --relative-to") and "'xyz'" in line


def test_folder_given_to_fit(capsys, tmp_path):
    folder = tmp_path / "measurements"
    folder.mkdir()
    code, err = _run(capsys, "fit", folder, "-m", "tr75", "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and str(folder) in line and "folder" in line and "fit-batch" in line
    assert "format=" not in line and "--from" not in line and "(none)" not in line


def test_folder_given_to_compare(capsys, tmp_path):
    code, err = _run(capsys, "compare", tmp_path, "--models", "tr75")
    line = _one_line(err)
    assert code == 2 and "folder" in line and "format=" not in line


def test_folder_given_to_convert(capsys, tmp_path):
    code, err = _run(capsys, "convert", tmp_path, tmp_path / "out.csv")
    line = _one_line(err)
    assert code == 2 and "is a folder" in line and "(none)" not in line


def test_unknown_extension_names_format_option_of_fit(capsys, tmp_path):
    path = tmp_path / "data.xyz"
    path.write_text("1 2 3\n")
    code, err = _run(capsys, "fit", path, "-m", "tr75", "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and "--format" in line
    assert "format=" not in line and "--from/--to" not in line


def test_unknown_extension_names_from_option_of_convert(capsys, tmp_path):
    path = tmp_path / "data.xyz"
    path.write_text("1 2 3\n")
    code, err = _run(capsys, "convert", path, tmp_path / "out.csv")
    line = _one_line(err)
    assert code == 2 and "--from/--to" in line and "format=" not in line


def test_csv_without_angle_unit_names_angles_in(capsys, tmp_path):
    path = tmp_path / "noangles.csv"
    path.write_text(DEFAULT.read_text().replace("# angles: deg\n", ""))
    code, err = _run(capsys, "fit", path, "-m", "tr75", "--starts", "1", "--no-plots", "-q",
                     "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and "--angles-in" in line and "angles=" not in line


def test_unknown_channel_lists_channels(capsys, tmp_path):
    path = _absolute_csv(tmp_path)
    code, err = _run(capsys, "fit", path, "-m", "tr75", "--channel", "550", "--out",
                     tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and "--channel" in line and "'550'" in line
    assert "(channels: 465nm, 525nm, 630nm)" in line


def test_unknown_channel_at_compare_lists_channels(capsys, tmp_path):
    path = _absolute_csv(tmp_path)
    code, err = _run(capsys, "compare", path, "--models", "tr75", "--channel", "550")
    line = _one_line(err)
    assert code == 2 and "'550'" in line and "(channels: 465nm, 525nm, 630nm)" in line


@pytest.mark.parametrize("verb", ["fit", "compare"])
def test_starts_names_option(capsys, tmp_path, verb):
    extra = ["-m", "tr75"] if verb == "fit" else ["--models", "tr75"]
    code, err = _run(capsys, verb, DEFAULT, *extra, "--starts", "0", "--out", tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and line.startswith("error: --starts") and "0" in line
    assert "error: starts" not in line


@pytest.mark.parametrize("verb", ["fit", "compare"])
def test_loss_names_option_and_choices(capsys, tmp_path, verb):
    extra = ["-m", "tr75"] if verb == "fit" else ["--models", "tr75"]
    code, err = _run(capsys, verb, DEFAULT, *extra, "--loss", "squared", "--out",
                     tmp_path / "o")
    line = _one_line(err)
    assert code == 2 and "--loss" in line and "'squared'" in line
    assert "relative, log, absolute, robust" in line


# --------------------------------------------------------------------------------------------
# a hostile fit.json at plot --fit and export --fit
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fit_json(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("fit") / "base"
    # TR75's albedo exceeds 1 near grazing incidence (unconstrained): written, exit 1
    assert main(["fit", str(DEFAULT), "-m", "tr75", "--starts", "1", "--no-plots", "-q",
                 "--no-energy-constraint", "--out", str(out)]) == 1
    return json.loads((out / "fit.json").read_text())


def _hostile(base: dict) -> dict[str, object]:
    """Name -> a fit.json content (or raw text) that is not a fit's."""
    out: dict[str, object] = {"a list": [1, 2], "a number": 3, "no channels key":
                              {"model": "tr75", "file": "x.csv"}}
    c = copy.deepcopy(base)
    c["channels"][0]["params"]["e"] = "abc"
    c["channels"][0].pop("model_spec")
    out["a string parameter"] = c
    c = copy.deepcopy(base)
    c["channels"][0].pop("params")
    out["a channel without params"] = c
    c = copy.deepcopy(base)
    c["channels"][0]["model_spec"]["params"]["e"] = 1e308 * 10
    out["an infinite parameter"] = c
    c = copy.deepcopy(base)
    c["channels"][0]["model_spec"]["params"]["e"] = 10 ** 400
    out["a huge integer"] = c
    c = copy.deepcopy(base)
    c["channels"] = {}
    out["channels not a list"] = c
    c = copy.deepcopy(base)
    c["channels"] = ["x"]
    out["a channel not an object"] = c
    c = copy.deepcopy(base)
    c["aperture"] = {"points": 19}
    out["an aperture without angle"] = c
    c = copy.deepcopy(base)
    c["channels"][0]["model_spec"] = {"model": "sum", "components": "ab"}
    out["a bad model spec"] = c
    c = copy.deepcopy(base)
    c["model"] = ["tr75"]
    out["a model that is a list"] = c
    out["NaN"] = json.dumps(base).replace('"e": ', '"e": NaN, "was": ', 1)
    out["5000 digits"] = '{"model": 1' + "0" * 5000 + "}"
    out["not JSON"] = "{model: tr75"
    out["not UTF-8"] = b"\xff\xfe{}"
    return out


@pytest.mark.parametrize("verb", ["plot", "export"])
def test_hostile_fit_json_is_one_line(capsys, tmp_path, fit_json, verb):
    for name, content in _hostile(fit_json).items():
        d = tmp_path / name.replace(" ", "_")
        d.mkdir()
        f = d / "fit.json"
        if isinstance(content, bytes):
            f.write_bytes(content)
        else:
            f.write_text(content if isinstance(content, str) else json.dumps(content))
        args = (["plot", "--fit", d, "--out", tmp_path / "p.png"] if verb == "plot" else
                ["export", "--fit", d, "--to", "mitsuba", "--out", tmp_path / "m.json"])
        code, err = _run(capsys, *args)
        line = _one_line(err)
        assert code == 2, (name, err)
        assert "fit.json" in line, (name, line)


@pytest.mark.parametrize("where", ["folder", "device"])
def test_fit_json_file_that_is_not_a_file(capsys, tmp_path, fit_json, where):
    c = copy.deepcopy(fit_json)
    c["file"] = str(tmp_path) if where == "folder" else "/dev/zero"
    c["file_abspath"] = None
    d = tmp_path / "fit"
    d.mkdir()
    (d / "fit.json").write_text(json.dumps(c))
    code, err = _run(capsys, "plot", "--fit", d, "--out", tmp_path / "p.png")
    line = _one_line(err)
    assert code == 2 and "fit.json" in line and repr(c["file"]) in line


@pytest.mark.parametrize(("args", "start"), [
    # what the parser refuses before a verb runs: an option's value of the wrong type, an
    # unknown option, a missing argument or option (Typer's own messages, made one line)
    (["fit", DEFAULT, "--starts", "x"], "error: --starts: invalid value 'x': "),
    (["fit-batch", DEFAULT, "--workers", "y", "--out", "o"], "error: --workers: invalid value 'y'"),
    (["fit", DEFAULT, "--nosuch"], "error: --nosuch: no such option"),
    (["fit"], "error: FILE: missing (a required argument)"),
    (["compare", DEFAULT, "--seed", "-1"], "error: --seed"),
    (["fit", DEFAULT, "--model", "tr75", "--out", "o", "--fix", "e=0.5"],
     "error: --fix e=0.5: a parameter name is expected"),
    (["fit", DEFAULT, "--model", "tr75", "--out", "o", "--fix", "zz"], "error: --fix"),
    (["fit", DEFAULT, "--model", "tr75", "--out", "o", "--angles-in", "grad"],
     "error: --angles-in: unknown angle unit 'grad'"),
])
def test_parser_errors_are_one_line_naming_the_option(capsys, tmp_path, monkeypatch, args,
                                                      start):
    monkeypatch.chdir(tmp_path)  # nothing is written; a relative --out would land here
    code, err = _run(capsys, *args)
    assert code == 2, err
    line = _one_line(err)
    assert line.startswith(start), line
    assert "Usage:" not in err and "╭" not in err  # no usage block, no framed panel
    assert not any(tmp_path.iterdir())

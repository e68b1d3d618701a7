"""The notebook path: ``_repr_html_`` of a model, a measurement and a fit, and ``rb.explore``.

No Jupyter runs here: IPython displays an object by calling its ``_repr_html_`` or
``_repr_mimebundle_`` (the rich display protocol), and these tests call them the same way. The
HTML must be well formed (parsed with :mod:`html.parser`, every tag closed in order), hold the
values it shows (the model's own numbers, formatted as :func:`roughbrdf.html_repr.number`
formats them), escape every text, and, for the explorer, carry plotly.js inline exactly once and
load no script from anywhere.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import roughbrdf as rb
from roughbrdf.errors import ArgumentError
from roughbrdf.html_repr import number

pytest.importorskip("plotly")

DATA = Path(__file__).parents[1] / "data" / "zemax" / "AnoBlackNiTEonINVAR.bsdf"
#: HTML elements without an end tag
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source",
        "track", "wbr"}


class _Checker(HTMLParser):
    """Collects the text and checks that every element is closed, in order."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.text: list[str] = []
        self.tags: list[tuple[str, dict[str, str | None]]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:]}")
        else:
            self.stack.pop()

    def handle_data(self, data):
        if self.stack and self.stack[-1] != "script":
            self.text.append(data)


def parsed(text: str) -> _Checker:
    """The checker after ``text``; fails unless every tag is balanced."""
    p = _Checker()
    p.feed(text)
    p.close()
    assert not p.errors, p.errors[:3]
    assert not p.stack, f"unclosed: {p.stack}"
    return p


def cells(text: str) -> list[str]:
    """The text pieces of an HTML fragment (table cells, titles), unescaped."""
    return [t.strip() for t in parsed(text).text if t.strip()]


# --------------------------------------------------------------------------------------------
# _repr_html_
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("model", [
    rb.model("lambertian", rho=0.25),
    rb.model("trowbridge-reitz-1975", e=0.68, n=1.0, k=0.9, rho_L=0.33),
    rb.model("microfacet", distribution="beckmann", alpha=0.3, n=1.5, k=0.0),
    rb.model("torrance-sparrow-1967", n=None, k=None),
])
def test_model_html_holds_every_parameter(model):
    text = model._repr_html_()
    got = cells(text)
    assert f"{model.name} model" in got
    for p in model.parameters:  # name, value, unit, bounds and domain of each, in cells
        assert p.name in got and number(p.value) in got, p.name
        assert f"[{number(p.bounds[0])}, {number(p.bounds[1])}]" in got
        assert p.domain_text() in got
        assert (p.unit or "1") in got
    for k, v in model.options.items():
        assert k in got and repr(v) in got
    assert model.reference in got


def test_sum_model_html_has_each_component_and_the_prefixed_names():
    m = rb.model("lambertian", rho=0.2) + rb.model("tr75", e=0.4)
    got = cells(m._repr_html_())
    assert "sum of models: lambertian + trowbridge-reitz-1975" in got
    for name, v in m.params.items():
        assert name in got and number(v) in got
    assert "lambertian_*: lambertian" in got


def test_measurement_html():
    t = np.radians([10.0, 10.0, 45.0])
    meas = rb.Measurement(t, [0.1, 0.2, 0.3], [0.0, 0.0, 1.0], [[1.0, 2.0]] * 3,
                          channels=["465nm", "a<b>&c"], quantity="bridf",
                          meta={"file": "x<y>.astm", "sample": "paint \"A\""})
    text = meas._repr_html_()
    got = cells(text)
    assert "3" in got and "465nm, a<b>&c" in got and "bridf" in got
    assert "10, 45" in got  # the incidences in degrees (radians(10) -> 10 exactly at 6 digits)
    assert "x<y>.astm" in got and 'paint "A"' in got
    assert "a&lt;b&gt;&amp;c" in text and "a<b>" not in text  # escaped in the markup
    assert "x&lt;y&gt;.astm" in text


def test_measurement_html_of_mueller_data_and_no_samples():
    m = rb.Measurement([0.5], [0.5], [0.0], [[0.8, 0.1]], channels=["m00", "m01"],
                       mueller="normalized")
    assert "normalized, basis psps" in cells(m._repr_html_())
    empty = rb.Measurement([], [], [], np.empty((0, 1)))
    got = cells(empty._repr_html_())
    assert "0" in got and "none" in got


@pytest.fixture(scope="module")
def fitted() -> rb.FitResult:
    return rb.fit("tr75", rb.read(DATA), starts=1, progress=False, loss="relative")


@pytest.mark.jit_heavy(reason="a TR75 fit of a measured file: over 5 min in plain Python")
def test_fit_html_holds_parameters_stderr_and_figures_of_merit(fitted):
    text = fitted._repr_html_()
    got = cells(text)
    c = fitted[0]
    assert "Fit" in got and fitted.model_name in got and fitted.loss in got
    for name, v in c.params.items():
        assert name in got and number(v) in got
        if c.stderr[name] is not None:
            assert number(c.stderr[name], 4) in got
    assert number(c.sigma, 4) in got and number(c.rms_log, 4) in got
    assert number(fitted.plausibility(0).max_albedo, 4) in got
    assert str(c.success) in got and c.message in got
    assert f"{c.n_points} / {c.n_varys}" in got


def test_fit_html_escapes_channel_labels():
    g = np.radians(np.mgrid[0:61:30, 0:81:20, 0:181:90].reshape(3, -1))
    v = rb.model("lambertian", rho=0.3).brdf(*g)
    meas = rb.Measurement(*g, v, channels=["<script>x</script>"])
    res = rb.fit("lambertian", meas, starts=1, progress=False)
    text = res._repr_html_()
    assert "<script" not in text and "&lt;script&gt;" in text
    assert "0.3" in cells(text)  # rho fitted to the synthetic truth, 6 significant digits


@pytest.mark.jit_heavy(reason="a TR75 fit of a measured file: over 5 min in plain Python")
def test_loaded_fit_has_the_same_html(fitted, tmp_path):
    fitted.save(tmp_path, plots=False)
    assert rb.load_fit(tmp_path)._repr_html_() == fitted._repr_html_()


# --------------------------------------------------------------------------------------------
# rb.explore
# --------------------------------------------------------------------------------------------
SCRIPT_SRC = re.compile(r"<script[^>]*\ssrc\s*=", re.I)


def _figure_divs(text: str) -> list[str]:
    return [a["id"] for tag, a in parsed(text).tags if tag == "div" and a.get("id")
            and re.fullmatch(r"roughbrdf-explore-[0-9a-f]+-\d+", a["id"] or "")]


@pytest.mark.jit_heavy(reason="the explorer's albedo curve: ~3 min in plain Python")
def test_mime_bundle_of_a_model_renders_offline():
    m = rb.model("lambertian", rho=0.4)
    ex = rb.explore(m, resolution=11)
    bundle = ex._repr_mimebundle_()
    assert set(bundle) == {"text/html", "text/plain"}
    html = bundle["text/html"]
    figs = ex.figures()
    assert len(_figure_divs(html)) == len(figs) == 5  # lobe, cuts, maps, albedo, Mueller
    assert html.count("Plotly.newPlot(") == len(figs)
    assert not SCRIPT_SRC.search(html)  # nothing loaded from a URL (or a file)
    assert "require.config" not in html and "requirejs" not in html
    # plotly.js inline exactly once: its licence header starts the bundle
    assert len(re.findall(r"\* plotly\.js v\d", html)) == 1
    # each figure's data, as Plotly serializes them (base64 typed arrays), are in the page
    from plotly.io.json import to_json_plotly

    for fig in figs:
        assert to_json_plotly(fig.to_plotly_json()["data"]) in html
    # and the lobe's values are the model's: rho/pi sr^-1 everywhere (Lambertian)
    from roughbrdf.explore.figures import figure_values

    lobe = figure_values(figs[0])["lambertian"]
    np.testing.assert_allclose(np.asarray(lobe["value"], dtype=float), 0.4 / math.pi,
                               rtol=1e-12)
    assert "0.4" in cells(ex.model._repr_html_())
    assert bundle["text/plain"] == "Explorer: model lambertian at theta_i = 30 deg\nno measurement"


@pytest.mark.jit_heavy(reason="a TR75 fit of a measured file: over 5 min in plain Python")
def test_explore_a_fit_draws_its_model_and_data(fitted):
    ex = rb.explore(fitted, resolution=11)
    assert ex.model is fitted[0].model and ex.measurement is fitted.measurement
    assert ex.channel == "value" and ex.fit is fitted
    # the measured incidence nearest 30 deg (the file's 30.0001 deg)
    assert math.degrees(ex.theta_i) == pytest.approx(30.0, abs=1e-3)
    html = ex._repr_mimebundle_()["text/html"]
    got = cells(html)  # the fit's table, outside the figures' scripts
    assert number(fitted.params["e"]) in got and number(fitted[0].sigma, 4) in got
    assert len(_figure_divs(html)) == len(ex.figures())
    from roughbrdf.explore.figures import figure_values

    cuts = figure_values(ex.figures()[1])
    drawn = np.concatenate([np.asarray(v["value"], dtype=float) for k, v in cuts.items()
                            if k.startswith("data ")])
    # every data point drawn is one of the file's values (absolute BRDF data: K = 1)
    assert drawn.size and np.isin(drawn, fitted.measurement.values[:, 0]).all()
    assert "data: " + str(fitted.measurement.meta["file"]) in ex._repr_mimebundle_()["text/plain"]


def test_explore_a_measurement_alone():
    meas = rb.read(DATA)
    ex = rb.explore(meas, resolution=11)
    assert ex.model is None and len(ex.figures()) == 2
    bundle = ex._repr_mimebundle_()
    assert bundle["text/plain"].startswith("Explorer: measurement at theta_i = 30 deg")
    assert len(_figure_divs(bundle["text/html"])) == 2
    assert "714" in cells(bundle["text/html"])  # the measurement's table: its samples


@pytest.mark.jit_heavy(reason="the explorer's albedo curve: over 5 min in plain Python")
def test_explore_options_and_models_without_mueller():
    ts = rb.model("torrance-sparrow-1967", n=None, k=None)  # F = 1: no Mueller matrix
    assert len(rb.explore(ts, resolution=11).figures()) == 4
    ex = rb.explore("lambertian", theta_i=0.2, resolution=11)
    assert ex.model.name == "lambertian" and ex.theta_i == 0.2
    g = np.radians(np.mgrid[10:61:50, 0:81:40, 0:181:180].reshape(3, -1))
    two = rb.Measurement(*g, np.ones((g.shape[1], 2)), channels=["a", "b"])
    assert rb.explore(rb.model("lambertian"), two, channel=1, resolution=11).channel == "b"
    html = rb.explore(ts, resolution=11).to_html(include_plotlyjs=False)
    assert not re.findall(r"\* plotly\.js v\d", html)


@pytest.mark.parametrize("args, kwargs, argument", [
    ((42,), {}, "model_or_fit"),
    ((None,), {}, "model_or_fit"),
    (("lambertian", "file.astm"), {}, "measurement"),
    (("lambertian",), {"theta_i": 2.0}, "theta_i"),
    (("lambertian",), {"theta_i": math.nan}, "theta_i"),
    (("lambertian",), {"theta_i": -0.1}, "theta_i"),
    (("lambertian",), {"theta_i": "30"}, "theta_i"),
    (("lambertian",), {"theta_i": math.pi / 2}, "theta_i"),
    (("lambertian",), {"resolution": 2}, "resolution"),
    (("lambertian",), {"resolution": 10.5}, "resolution"),
])
def test_bad_arguments_are_named(args, kwargs, argument):
    with pytest.raises(ArgumentError) as err:
        rb.explore(*args, **kwargs)
    assert err.value.argument == argument


def test_two_measurements_are_refused():
    meas = rb.Measurement([0.1], [0.2], [0.0], [1.0])
    with pytest.raises(ArgumentError, match="give the model first"):
        rb.explore(meas, meas)


@pytest.mark.parametrize("first", [
    "import roughbrdf.explore.figures as f\nassert callable(f.lobe_3d)",
    "import roughbrdf.explore",
    "",
])
def test_rb_explore_is_callable_whatever_was_imported_first(first):
    code = (f"{first}\nimport sys, roughbrdf as rb\n"
            "ex = rb.explore(rb.model('lambertian'), resolution=5)\n"
            "assert type(ex).__name__ == 'Explorer'\n"
            "assert rb.explore.notebook.explore is not None\n"
            "print('ok')\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr


def test_importing_the_notebook_front_end_loads_no_plotting_library():
    code = ("import sys, roughbrdf as rb\nrb.explore\nimport roughbrdf.explore.notebook\n"
            "bad = [m for m in sys.modules if m.split('.')[0] in ('plotly', 'dash', "
            "'matplotlib')]\nprint(bad)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert proc.stdout.strip() == "[]"

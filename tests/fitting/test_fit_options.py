"""The fit options as one typed object (``rb.FitOptions``), the loss type (``Loss``), the
model naming of a fit (``is_auto``) and the CLI's shared options (``roughbrdf.cli.options``).

From the user's side: ``rb.fit(model, meas, loss=...)`` and ``rb.fit(model, meas,
options=rb.FitOptions(loss=...))`` are the same fit, bit for bit; the options are checked when
they are made; the help of ``fit``, ``compare`` and ``fit-batch`` still lists every option.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.errors import ArgumentError
from roughbrdf.fitting import LOSSES, FitOptions, Loss
from roughbrdf.measurement import Measurement
from roughbrdf.models import is_auto
from roughbrdf.quantity import LOSSES as QUANTITY_LOSSES
from roughbrdf.quantity import relative_scale

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")


def _measurement(channels: int = 1) -> Measurement:
    g = np.radians(np.mgrid[10:61:25, 0:81:10, 0:181:45].reshape(3, -1))
    truth = rb.model("coated", n=1.5, rho=0.3, alpha=0.25)
    base = truth.brdf(*g)
    noise = 1.0 + 0.03 * np.sin(np.arange(base.size))  # deterministic, not a perfect fit
    values = np.stack([base * noise * (1 + 0.1 * c) for c in range(channels)], axis=1)
    return Measurement(*g, values, channels=[f"c{c}" for c in range(channels)])


def _fit_json(res) -> dict:
    out = json.loads(res.to_json())
    out.pop("elapsed_s", None)
    for c in out["channels"]:
        c.pop("elapsed_s", None)
    return out


# ---------------------------------------------------------------------------------------------
# keywords and the typed path: the same fit, bit for bit
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kw", [
    {"loss": "log", "starts": 2, "seed": 3},
    {"loss": "absolute", "starts": 2, "fix": ["n"], "bounds": {"alpha": (0.05, 0.8)}},
    {"starts": 2, "aperture": 0.01, "aperture_points": 7, "theta_r_max": 1.3},
])
def test_keywords_and_options_give_the_same_fit_bit_for_bit(kw):
    meas = _measurement(channels=2)
    by_keywords = rb.fit("coated", meas, progress=False, **kw)
    typed = rb.fit("coated", meas, options=rb.FitOptions(progress=False, **kw))
    for a, b in zip(by_keywords.channels, typed.channels, strict=True):
        assert a.params == b.params  # exactly: no rounding
        assert np.array_equal(a.residual, b.residual)
    assert _fit_json(by_keywords) == _fit_json(typed)


def test_keywords_replace_fields_of_the_options():
    meas = _measurement()
    opts = FitOptions(starts=1, loss="log", progress=False)
    a = rb.fit("lambertian", meas, options=opts, loss="relative")
    b = rb.fit("lambertian", meas, starts=1, loss="relative", progress=False)
    assert a[0].params == b[0].params and a.loss == "relative"


def test_compare_takes_the_options_too():
    meas = _measurement()
    by_keywords = rb.compare(meas, ["lambertian", "coated"], cv=False, starts=1)
    typed = rb.compare(meas, ["lambertian", "coated"], cv=False,
                       options=FitOptions(starts=1, progress=False))
    assert [c.label for c in by_keywords.candidates] == [c.label for c in typed.candidates]
    assert [c.bic for c in by_keywords.candidates] == [c.bic for c in typed.candidates]


def test_an_unknown_keyword_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="unexpected keyword argument 'stars'"):
        rb.fit("lambertian", _measurement(), stars=2)


# ---------------------------------------------------------------------------------------------
# FitOptions: frozen, checked once when made, replace
# ---------------------------------------------------------------------------------------------
def test_options_are_frozen_and_replace_makes_a_checked_copy():
    opts = FitOptions(starts=2)
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.starts = 3  # type: ignore[misc]
    assert opts.replace(starts=5).starts == 5 and opts.starts == 2
    assert dataclasses.replace(opts, loss="log").loss == "log"
    with pytest.raises(ArgumentError) as err:
        opts.replace(starts=0)
    assert err.value.argument == "starts"


@pytest.mark.parametrize("kw, argument, text", [
    ({"loss": "squared"}, "loss", "unknown loss 'squared'; choose one of auto, relative, log"),
    ({"starts": 0}, "starts", "starts must be >= 1"),
    ({"negative": "nope"}, "negative", "must be 'auto', 'keep', 'drop' or 'clip'"),
    ({"nonfinite": 1}, "nonfinite", "must be 'raise' or 'drop'"),
    ({"extrapolated": "yes"}, "extrapolated", "must be 'drop' or 'keep'"),
    ({"aperture": -0.1}, "aperture", "aperture"),
    ({"theta_r_max": 2.0}, "theta_r_max", "must be an angle in [0, 90] deg"),
    ({"scale": 0.0}, "scale", "scale must be finite and > 0"),
    ({"joint": "yes"}, "joint", "must be True or False"),
    ({"shared": ["alpha"]}, "shared", "only a joint fit shares parameters"),
    ({"polarimetric_weight": -1.0}, "polarimetric_weight", "must be a finite number >= 0"),
    ({"wavelength": "630"}, "wavelength", "must be a number and a unit"),
])
def test_a_bad_option_raises_when_the_options_are_made(kw, argument, text):
    with pytest.raises(ArgumentError) as err:
        FitOptions(**kw)
    assert err.value.argument == argument and text in str(err.value)


def test_every_option_of_fit_is_a_field_with_the_same_default():
    fields = {f.name: f.default for f in dataclasses.fields(FitOptions)}
    assert fields["loss"] == "auto" and fields["starts"] == 8 and fields["seed"] == 0
    assert fields["subsample"] == 1000 and fields["aperture_points"] == 19
    assert len(fields) == 28 and fields["energy_constraint"] is True
    assert fields["wavelength"] is None and fields["intervals"] == "wald"
    assert "model" not in fields and "measurement" not in fields
    assert FitOptions().changed() == {} and FitOptions(fix=[]).changed() == {}


# ---------------------------------------------------------------------------------------------
# Loss: the names, the residuals of docs/fitting.md, the closed-form scale
# ---------------------------------------------------------------------------------------------
def test_loss_names_and_parse():
    assert LOSSES == QUANTITY_LOSSES == tuple(loss.value for loss in Loss)
    assert Loss.parse("log") is Loss.LOG and Loss.parse(Loss.ABSOLUTE) is Loss.ABSOLUTE
    assert Loss.LOG.positive_data and not Loss.RELATIVE.positive_data
    with pytest.raises(ArgumentError) as err:
        Loss.parse("Relative")
    assert err.value.argument == "loss"


def test_loss_residuals_are_those_of_the_docs():
    x = np.array([0.5, 1.0, 2.0, 4.0])
    f = np.array([1.0, 1.0, 1.5, 3.0])
    k = 1.25
    np.testing.assert_allclose(Loss.RELATIVE.residual(x, f, k=k, floor=0.0), (k * x - f) / f)
    np.testing.assert_allclose(Loss.LOG.residual(x, f, k=k, floor=0.0),
                               np.log(k * x) - np.log(f))
    np.testing.assert_allclose(Loss.ABSOLUTE.residual(x, f, k=k, floor=0.0), k * x - f)
    # a model value of 0 is floored before dividing (1e-12 of the largest |x|)
    floor = Loss.floor(x)
    assert floor == pytest.approx(4e-12)
    assert math.isfinite(Loss.RELATIVE.residual(x, np.zeros(4), floor=floor).max())


@pytest.mark.parametrize("loss", LOSSES)
def test_the_closed_form_scale_zeroes_the_derivative_of_the_cost(loss):
    rng = np.random.default_rng(1)
    f = rng.uniform(0.5, 2.0, 20)
    x = 0.4 * f * rng.uniform(0.9, 1.1, 20)
    k = relative_scale(x, f, loss=loss)
    kind = Loss.parse(loss)
    r = kind.residual(x, f, k=k, floor=0.0)
    dr = kind.scale_derivative(x, f, k, 0.0)
    assert abs(float(np.dot(r, dr))) < 1e-10  # d/dK sum(r^2) = 2 r . dr/dK = 0 at the optimum
    assert k == kind.closed_form(x, f, None)


# ---------------------------------------------------------------------------------------------
# the "auto" pseudo-model, by one test
# ---------------------------------------------------------------------------------------------
def test_is_auto():
    assert is_auto("auto") and is_auto(" AUTO ")
    assert not is_auto("coated") and not is_auto(rb.model("lambertian")) and not is_auto(None)


# ---------------------------------------------------------------------------------------------
# the CLI's shared options: declared once, every flag still in each verb's help
# ---------------------------------------------------------------------------------------------
def _flags(annotation) -> list[str]:
    info = annotation.__metadata__[0]
    # in Annotated, typer.Option's first positional argument (stored as `default`) is a name
    first = (info.default,) if isinstance(info.default, str) else ()
    decls = [d for d in (*first, *(info.param_decls or ())) if d.startswith("--")]
    return [d.split("/")[0] for d in decls]


@pytest.mark.parametrize("verb, own", [
    ("fit", ["--model", "--out", "--force", "--quiet"]),
    ("compare", ["--models", "--out", "--force"]),
    ("fit-batch", ["--model", "--out", "--workers", "--scheduler", "--resume", "--time-limit",
                   "--force", "--quiet"]),
])
def test_each_verb_shows_every_shared_option_in_its_help(verb, own):
    import roughbrdf.cli.compare as compare_cli
    import roughbrdf.cli.fit as fit_cli
    import roughbrdf.cli.fit_batch as batch_cli
    from roughbrdf.cli.options import TABLE

    order = {"fit": fit_cli.FIT_ORDER, "compare": compare_cli.COMPARE_ORDER,
             "fit-batch": batch_cli.BATCH_ORDER}[verb]
    res = CliRunner().invoke(app, [verb, "--help"], env={"COLUMNS": "250"})
    assert res.exit_code == 0, res.output
    shared = [name for name in order if name in TABLE]
    assert len(shared) >= 15 if verb != "compare" else len(shared) >= 13
    for name in shared:
        annotation, _default = TABLE[name]
        flags = _flags(annotation) or ["--" + name.replace("_", "-")]
        for flag in flags:
            assert flag in res.output, (verb, flag)
    for flag in own:
        assert flag in res.output, (verb, flag)
    assert "[default: auto]" in res.output and "[default: 8]" in res.output

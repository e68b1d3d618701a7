"""Zemax and LightTools files share ``.bsdf``: ``rb.read`` tells them apart by content.

The files: the committed Zemax examples (``tests/data/zemax/``, LOFT bsdf-tools) and the
LightTools files of ``tests/data/lighttools/`` (pinned by libbsdf's reader, see its README).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

import roughbrdf as rb
from roughbrdf.cli import app
from roughbrdf.io import FormatError, format_for

DATA = Path(__file__).parents[1] / "data"
ZEMAX = sorted((DATA / "zemax").glob("*.bsdf"))
LIGHTTOOLS = sorted((DATA / "lighttools").glob("*.bsdf"))


@pytest.mark.parametrize("path", ZEMAX + LIGHTTOOLS, ids=lambda p: p.name)
def test_read_tells_the_formats_apart_by_content(path):
    kind = "zemax" if path.parent.name == "zemax" else "lighttools"
    m = rb.read(path)
    assert m.meta["format"] == kind and m.n_samples > 0


@pytest.mark.parametrize("path", [ZEMAX[0], LIGHTTOOLS[0]], ids=lambda p: p.name)
def test_a_file_without_the_extension_is_sniffed(tmp_path, path):
    copy = tmp_path / "measured.data"
    shutil.copy(path, copy)
    kind = "zemax" if path.parent.name == "zemax" else "lighttools"
    assert format_for(copy) == kind
    assert rb.read(copy).meta["format"] == kind


def test_format_overrides_and_a_wrong_one_fails_naming_the_file():
    assert rb.read(LIGHTTOOLS[0], format="lighttools").meta["format"] == "lighttools"
    with pytest.raises(FormatError) as err:
        rb.read(LIGHTTOOLS[0], format="zemax")
    assert LIGHTTOOLS[0].name in str(err.value)


def test_a_new_bsdf_is_written_as_zemax_unless_told(tmp_path):
    m = rb.read(LIGHTTOOLS[0])
    assert format_for(tmp_path / "new.bsdf") == "zemax"
    assert format_for(tmp_path / "new.bsdf", "lighttools") == "lighttools"
    rb.write(m, tmp_path / "lt.bsdf", format="lighttools")
    assert rb.read(tmp_path / "lt.bsdf").meta["format"] == "lighttools"


def test_cli_format_option(tmp_path):
    runner = CliRunner()
    got = runner.invoke(app, ["convert", str(LIGHTTOOLS[0]), str(tmp_path / "out.csv"),
                              "--from", "lighttools"])
    assert got.exit_code == 0, got.output
    assert rb.read(tmp_path / "out.csv").n_samples == rb.read(LIGHTTOOLS[0]).n_samples

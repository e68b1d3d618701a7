"""A results folder's manifest is trusted only as far as it is roughbrdf's: names outside the
folder, a symbolic link for a manifest, a manifest that is no list of names, a listed name that
is a link out of the folder are refused naming the manifest, and never acted upon; a listed
file the user changed since is refused by ``--force`` naming it (never replaced, never removed).
"""

from __future__ import annotations

import json
import os

import pytest

from roughbrdf.cli import main
from roughbrdf.demo import default_measurement_path
from roughbrdf.output import MANIFEST, ManifestRefused, OverwriteRefused, ResultFolder

#: too slow without the JIT: make test-nojit deselects them (-m 'not jit_heavy')
pytestmark = pytest.mark.jit_heavy(
    reason="fits: each fit's plausibility albedo alone takes ~40 s in plain Python")

FIT = ["fit", str(default_measurement_path()), "-m", "lambertian"]


def _victim(tmp_path):
    """A file outside the results folder that a crafted manifest names."""
    victim = tmp_path / "outside.txt"
    victim.write_text("precious")
    return victim


def _results(tmp_path, manifest) -> os.PathLike:
    """A received results folder: a fit.json and the manifest ``manifest`` (JSON data)."""
    out = tmp_path / "received"
    out.mkdir(parents=True)
    (out / "fit.json").write_text("{}")
    (out / MANIFEST).write_text(json.dumps(manifest))
    return out


def _crafted(tmp_path):
    """(case id, results folder) for each manifest roughbrdf must not act on."""
    victim = _victim(tmp_path)
    yield "dotdot", _results(tmp_path / "a", ["fit.json", "../../outside.txt"])
    yield "absolute", _results(tmp_path / "b", ["fit.json", str(victim)])
    link = _results(tmp_path / "c", ["fit.json"])
    (link / "notes.txt").write_text("mine")
    shared = tmp_path / "shared-manifest.json"
    shared.write_text(json.dumps(["notes.txt"]))
    (link / MANIFEST).unlink()
    (link / MANIFEST).symlink_to(shared)
    yield "symlink manifest", link
    yield "not a list", _results(tmp_path / "d", "fit.json")
    yield "bad hash", _results(tmp_path / "e", {"fit.json": 5})
    out = _results(tmp_path / "f", ["fit.json", "link.txt"])
    (out / "link.txt").symlink_to(victim)
    yield "link to outside", out


def _tree(root) -> dict[str, bytes]:
    return {str(p.relative_to(root)): (os.readlink(p).encode() if p.is_symlink()
                                       else p.read_bytes())
            for p in sorted(root.rglob("*")) if p.is_symlink() or p.is_file()}


def test_fit_force_refuses_a_crafted_manifest_and_deletes_nothing(tmp_path, capsys):
    for case, out in _crafted(tmp_path):
        before = _tree(tmp_path)
        code = main([*FIT, "--out", str(out), "--force"])
        err = capsys.readouterr().err
        assert code == 2, (case, err)
        assert f"{out / MANIFEST}:" in err and "will not act" in err, (case, err)
        assert _tree(tmp_path) == before, case  # outside files, and the folder, untouched
        assert (tmp_path / "outside.txt").read_text() == "precious"


def test_result_folder_overwrite_refuses_a_crafted_manifest(tmp_path):
    for case, out in _crafted(tmp_path):
        before = _tree(tmp_path)
        with pytest.raises(ManifestRefused) as err, \
                ResultFolder(out, overwrite=True) as folder:
            folder.add("report.txt", "new")
        assert err.value.record == out / MANIFEST, case
        assert isinstance(err.value, OverwriteRefused)
        assert str(out / MANIFEST) in str(err.value), case
        assert _tree(tmp_path) == before, case


def test_force_refuses_a_result_the_user_changed_naming_it(tmp_path, capsys):
    out = tmp_path / "fit"
    assert main([*FIT, "--out", str(out)]) == 0
    (out / "report.txt").write_text("my notes on this fit\n")
    capsys.readouterr()
    assert main([*FIT, "--out", str(out), "--force"]) == 2
    err = capsys.readouterr().err
    assert "report.txt" in err and "changed since roughbrdf wrote it" in err, err
    assert (out / "report.txt").read_text() == "my notes on this fit\n"


def test_overwrite_never_removes_a_stale_file_the_user_changed(tmp_path):
    with ResultFolder(tmp_path) as out:
        out.add("a.txt", "A")
        out.add("b.txt", "B")
    (tmp_path / "b.txt").write_text("edited")
    with pytest.raises(OverwriteRefused, match=r"b\.txt \(changed since"), \
            ResultFolder(tmp_path, overwrite=True) as out:
        out.add("a.txt", "A2")
    assert (tmp_path / "b.txt").read_text() == "edited"
    assert (tmp_path / "a.txt").read_text() == "A"
    # a manifest of an older version (names only, hashes unknown) is still read and obeyed
    (tmp_path / "b.txt").unlink()
    (tmp_path / MANIFEST).write_text(json.dumps(["a.txt"]))
    with ResultFolder(tmp_path, overwrite=True) as out:
        out.add("c.txt", "C")
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "c.txt"]


def test_a_listed_name_that_is_now_a_folder_is_refused_untouched(tmp_path):
    (tmp_path / "plots").mkdir()
    (tmp_path / "plots" / "mine.png").write_bytes(b"png")
    (tmp_path / MANIFEST).write_text(json.dumps(["plots"]))  # an older version's manifest
    with pytest.raises(OverwriteRefused, match=r"plots \(changed since"), \
            ResultFolder(tmp_path, overwrite=True) as out:
        out.add("fit.json", "{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == [MANIFEST, "plots"]
    assert (tmp_path / "plots" / "mine.png").read_bytes() == b"png"

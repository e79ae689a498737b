"""Figures are injected: the stage functions take ``draw`` (the library never imports viz),
call it inside the staged output folder, and list what it wrote; a failing drawer
publishes nothing."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.plants.fit import analytic_plants


def test_draw_writes_inside_the_staged_folder_and_is_listed(tmp_path):
    seen = {}

    def draw(folder, ap):
        seen["folder"] = folder
        seen["name"] = ap.aircraft.name
        (folder / "mine.txt").write_text(ap.aircraft.name)
        return ["mine.txt"]

    analytic_plants("roskam", tmp_path / "out", draw=draw)
    assert seen["folder"] != tmp_path / "out"  # the staging folder, published afterwards
    assert (tmp_path / "out" / "mine.txt").read_text() == seen["name"]
    files = json.loads((tmp_path / "out" / "manifest.json").read_text())["files"]
    assert "mine.txt" in files and "analytic_bode.png" not in files


def test_no_draw_no_figures(tmp_path):
    analytic_plants("roskam", tmp_path / "out")
    assert not list((tmp_path / "out").glob("*.png"))


def test_a_failing_drawer_publishes_nothing(tmp_path):
    def draw(folder, ap):
        (folder / "half.png").write_bytes(b"x")
        raise HesspipeError("drawing failed")

    with pytest.raises(HesspipeError, match="drawing failed"):
        analytic_plants("roskam", tmp_path / "out", draw=draw)
    assert not (tmp_path / "out").exists()


def test_the_stages_import_no_figures():
    # (python-control itself imports matplotlib; what matters is that no stage reaches for hesspipe.viz)
    code = ("import sys; from hesspipe.plants import fit; from hesspipe.flight import approach, closed_loop; "
            "from hesspipe.pilots import compare; print(any(m.startswith('hesspipe.viz') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"

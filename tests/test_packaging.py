"""A plain (non-editable) install works from any folder: the configuration folders
``aircraft/`` and ``pipeline/`` travel inside the wheel (setup.py) and
:func:`hesspipe.core.config.data_dir` finds them there."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "src", "aircraft", "pipeline")


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel built from a copy of the checkout, unpacked into a bare folder."""
    pytest.importorskip("wheel", reason="the test extra installs wheel to build without download")
    tmp = tmp_path_factory.mktemp("pkg")
    src = tmp / "src-copy"
    src.mkdir()
    for name in SOURCES:
        (shutil.copytree if (ROOT / name).is_dir() else shutil.copy2)(
            ROOT / name, src / name, **({"ignore": shutil.ignore_patterns("__pycache__", "*.egg-info")}
                                        if (ROOT / name).is_dir() else {}))
    dist = tmp / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
                    "-q", "-w", str(dist)], check=True, capture_output=True)
    wheel = next(dist.glob("hesspipe-*.whl"))
    site = tmp / "site"
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
        z.extractall(site)
    return site, names


def _run(site: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    # The unpacked wheel comes first on the path, ahead of the checkout's editable install.
    env = {**os.environ, "PYTHONPATH": str(site)}
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)


def test_wheel_carries_the_configuration_folders(installed):
    _, names = installed
    for name in ("hesspipe/_data/aircraft/737.toml", "hesspipe/_data/aircraft/roskam.toml",
                 "hesspipe/_data/pipeline/default.toml", "hesspipe/_data/pipeline/stages.toml"):
        assert name in names


def test_installed_package_finds_its_data_and_flies_from_another_folder(installed, tmp_path):
    site, _ = installed
    where = _run(site, tmp_path, "-c", "import hesspipe.core.config as c; print(c.__file__); "
                                      "print(c.data_dir('aircraft'))")
    assert where.returncode == 0, where.stderr
    module, folder = where.stdout.split()
    assert module.startswith(str(site)) and folder == str(site / "hesspipe" / "_data" / "aircraft")
    done = _run(site, tmp_path, "-m", "hesspipe.cli", "flight", "--aircraft", "737", "--out", "fl")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "fl" / "trim.json").is_file() and (tmp_path / "fl" / "wind.csv").is_file()

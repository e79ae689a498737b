"""Figures use matplotlib's object API: hesspipe leaves the user's backend alone."""

from __future__ import annotations

import os
import subprocess
import sys


def test_importing_and_drawing_keeps_the_users_backend(tmp_path):
    code = (
        "import matplotlib\n"
        "matplotlib.use('svg')\n"
        "import hesspipe.viz as v\n"
        "fig, ax = v.subplots(1, 1, figsize=(3, 2))\n"
        "ax.plot([0, 1], [0, 1])\n"
        f"v.save_figure(fig, {str(tmp_path / 'f.png')!r}, synthetic=True)\n"
        "import sys\n"
        "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)\n")
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["svg", "False"]
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

"""Build hook: the user-editable configuration folders travel inside the package.

``aircraft/`` and ``pipeline/`` stay at the top of the checkout, where users read
and edit them; a plain (non-editable) install copies them into
``hesspipe/_data/`` so that :func:`hesspipe.config.data_dir` finds them from any
working folder. Everything else is declared in pyproject.toml.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

DATA_FOLDERS = ("aircraft", "pipeline")


class BuildPyWithData(build_py):
    def run(self):
        super().run()
        here = Path(__file__).resolve().parent
        for name in DATA_FOLDERS:
            target = Path(self.build_lib) / "hesspipe" / "_data" / name
            target.mkdir(parents=True, exist_ok=True)
            for src in sorted((here / name).glob("*.toml")):
                self.copy_file(str(src), str(target / src.name))


setup(cmdclass={"build_py": BuildPyWithData})

"""Every public function, class and method of the covered modules has a numpydoc docstring.

A public name is one without a leading underscore, at module level or defined in the
body of a public class (dunder methods aside). Each needs a docstring; one that takes
parameters (other than ``self``/``cls``) needs a ``Parameters`` section. A class's
parameters are its constructor's: its own ``__init__`` arguments or, for a dataclass
or NamedTuple, its fields, which its docstring may list under ``Attributes`` instead.

The source is read as text (``ast``), so nothing is imported. To cover more of the
package, add its modules to :data:`COVERED` (a folder name covers all its modules).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import hesspipe

PACKAGE = Path(hesspipe.__file__).parent

#: Folders (all their modules) and single modules (path relative to the package).
#: Everything but ``cli``: the command-line layer is documented by its argparse help.
COVERED = ("core", "pilot", "flight", "plants", "identification", "pilots", "diagnose",
           "pipeline", "viz", "humanlike")
#: Left out for now (being rewritten elsewhere); the lead extends COVERED to them later.
EXCLUDED = ()


def _files() -> list[Path]:
    out = []
    for entry in COVERED:
        path = PACKAGE / entry
        out.extend(sorted(path.rglob("*.py")) if path.is_dir() else [path])
    return [p for p in out if str(p.relative_to(PACKAGE)) not in EXCLUDED]


def _params(fn: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> list[str]:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    if method and names and names[0] in ("self", "cls") and not _is_static(fn):
        names = names[1:]
    names += [x.arg for x in (a.vararg, a.kwarg) if x is not None]
    return names


def _is_static(fn) -> bool:
    return any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in fn.decorator_list)


def _is_property(fn) -> bool:
    return any((isinstance(d, ast.Name) and d.id in ("property", "cached_property"))
               or (isinstance(d, ast.Attribute) and d.attr in ("setter", "cached_property"))
               for d in fn.decorator_list)


def _is_overload(fn) -> bool:
    return any((isinstance(d, ast.Name) and d.id == "overload")
               or (isinstance(d, ast.Attribute) and d.attr == "overload") for d in fn.decorator_list)


def _fields(cls: ast.ClassDef) -> list[str]:
    """Annotated class-level names (dataclass / NamedTuple fields), ClassVar aside."""
    return [n.target.id for n in cls.body
            if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)
            and "ClassVar" not in ast.unparse(n.annotation)]


def _has_section(doc: str, *names: str) -> bool:
    lines = [ln.strip() for ln in doc.splitlines()]
    return any(ln in names and i + 1 < len(lines) and set(lines[i + 1]) == {"-"}
               for i, ln in enumerate(lines))


def _problems(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    where = str(path.relative_to(PACKAGE))
    out = []

    def check_function(fn, qual: str, method: bool):
        if fn.name.startswith("_") or _is_overload(fn):
            return
        doc = ast.get_docstring(fn)
        if not doc:
            out.append(f"{where}: {qual}: no docstring")
        elif not _is_property(fn) and _params(fn, method) and not _has_section(doc, "Parameters"):
            out.append(f"{where}: {qual}: no Parameters section")

    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            check_function(node, node.name, method=False)
        elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            doc = ast.get_docstring(node)
            init = next((n for n in node.body if isinstance(n, ast.FunctionDef) and n.name == "__init__"),
                        None)
            if not doc:
                out.append(f"{where}: {node.name}: no docstring")
            elif init is not None and _params(init, method=True):
                if not (_has_section(doc, "Parameters")
                        or _has_section(ast.get_docstring(init) or "", "Parameters")):
                    out.append(f"{where}: {node.name}: no Parameters section")
            elif init is None and _fields(node) and not _has_section(doc, "Parameters", "Attributes"):
                out.append(f"{where}: {node.name}: no Parameters (or Attributes) section")
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    check_function(item, f"{node.name}.{item.name}", method=True)
    return out


def test_covered_modules_exist():
    for entry in COVERED + EXCLUDED:
        assert (PACKAGE / entry).exists(), entry


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_public_callables_have_numpydoc(path):
    problems = _problems(path)
    assert not problems, "\n".join(problems)


def test_checker_finds_missing_docs(tmp_path):
    """The checker itself: it flags what it should and passes what it should."""
    src = tmp_path / "m.py"
    src.write_text('def a(x):\n    """One line."""\n\n'
                   'def b():\n    pass\n\n'
                   'def _c(x):\n    pass\n\n'
                   'def d(x):\n    """One line.\n\n    Parameters\n    ----------\n    x : float\n        m.\n    """\n\n'
                   'class E:\n    """E."""\n    def f(self):\n        """F."""\n    def g(self, y):\n        pass\n'
                   '    @property\n    def h(self):\n        """H."""\n\n'
                   'class F:\n    """F."""\n    x: float\n', encoding="utf-8")
    got = _problems_at(src)
    assert got == ["a: no Parameters section", "b: no docstring", "E.g: no docstring",
                   "F: no Parameters (or Attributes) section"]


def _problems_at(path: Path) -> list[str]:
    global PACKAGE
    saved, PACKAGE = PACKAGE, path.parent
    try:
        return [p.split(": ", 1)[1] for p in _problems(path)]
    finally:
        PACKAGE = saved


def test_fitness_states_its_units():
    from hesspipe.identification import spectra

    for fn in (spectra.fitness, spectra.rms_difference):
        assert "control^2/Hz" in fn.__doc__, fn.__name__

"""Catalogue of output-folder, write-failure, orphan and late-validation cases (issue 10,
items 4-8), and a property of the whole CLI.

Every case of :data:`CASES` is one row: the input (a setup that builds files and returns
the command line), the expected exit status and a pattern of the message; the runner
checks the rest for every row: no traceback, one stderr line, no leftover (no file
appears that was not there before, for a refused command) and no file lost (every file
that was there is still there with the same bytes).

The CLI property (:func:`test_every_command_refuses_a_read_only_folder` and
:func:`test_every_command_refuses_a_file_as_output_folder`) runs every command of
``hesspipe.cli.COMMANDS``: a command without an argument builder in
:data:`BUILDERS` fails the test, so commands added later are covered.

Read-only folders: as root, ``chmod`` does not stop writes, so the command runs in a
forked child that first drops the capability to override permission bits (CAP_DAC_OVERRIDE):
a real EACCES from the kernel, not a monkeypatched function. As another user, ``chmod 555``
is enough.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

import hesspipe.viz  # noqa: F401  - matplotlib configured before any fork (no cache warning in a child)
from hesspipe.cli import COMMANDS, build_parser, main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Run, read_run, write_plants, write_run
from hesspipe.core.io import MARKER, STAGING_PREFIX, TMP_PREFIX
from pilot_data import plants as paper_plants
from proc_helpers import drop_write_override, sigterm_when_ready

# -- inputs ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def inputs():
    """Small valid inputs of every command, in a folder any user may read."""
    from hesspipe.flight.approach import FlightConfig, fly

    base = Path(tempfile.mkdtemp(prefix="hesspipe-catalogue-"))
    os.chmod(base, 0o755)
    write_plants(base / "plants.json", paper_plants())
    runs = base / "runs"
    runs.mkdir()
    for i in range(2):
        rng = np.random.default_rng(i)
        n = 1100
        write_run(runs / f"p{i}.csv", Run(time=0.02 * np.arange(n), disturbance=rng.standard_normal(n),
                                          output=rng.standard_normal(n), control=rng.standard_normal(n),
                                          reference=np.zeros(n), id=f"p{i}", synthetic=True))
    fly("737", FlightConfig(duration_s=30.0), base / "flight", seed=0)
    for p in base.rglob("*"):
        os.chmod(p, 0o755 if p.is_dir() else 0o644)
    yield base
    shutil.rmtree(base, ignore_errors=True)


#: Per command: ``builder(inputs, out) -> argv`` where `out` is the folder the command
#: writes into (for a command that writes files, the folder of its --json file). Add a
#: line here for every new command.
BUILDERS: dict[str, Callable[[Path, Path], list[str]]] = {
    "run": lambda i, out: ["run", "--out", str(out)],
    "status": lambda i, out: ["status", "--out", str(out)],
    "flight": lambda i, out: ["flight", "--out", str(out)],
    "plants": lambda i, out: ["plants", "--flight", str(i / "flight"), "--out", str(out)],
    "identify": lambda i, out: ["identify", str(i / "runs" / "p0.csv"), "--plants", str(i / "plants.json"),
                                "--json", str(out / "r.json")],
    "synth-pilots": lambda i, out: ["synth-pilots", "--plants", str(i / "plants.json"), "--n", "1",
                                    "--duration", "25", "--out", str(out)],
    "pilots": lambda i, out: ["pilots", str(i / "runs"), "--plants", str(i / "plants.json"),
                                      "--workers", "1", "--json", str(out / "c.json")],
    "diagnose": lambda i, out: ["diagnose", str(i / "runs" / "p0.csv"), "--plants", str(i / "plants.json"),
                                "--json", str(out / "d.json")],
    "fly-pilot": lambda i, out: ["fly-pilot", "--plants", str(i / "plants.json"), "--out", str(out)],
    "frf": lambda i, out: ["frf", str(i / "runs" / "p0.csv"), "--plants", str(i / "plants.json"),
                           "--json", str(out / "f.json")],
    "conditions": lambda i, out: ["conditions", str(i / "runs"), str(i / "runs"), "--plants",
                                  str(i / "plants.json"), "--json", str(out / "c.json")],
}

#: Commands that only read (a read-only output folder is fine for them).
READ_ONLY_COMMANDS = {"status"}


def command_names() -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    # One name per command: an alias (compare-pilots for pilots) maps to the same parser.
    names = list({id(p): name for name, p in reversed(sub.choices.items())}.values())[::-1]
    assert len(names) == len(COMMANDS)
    return names


def test_every_command_with_an_output_file_declares_its_inputs():
    """An output file must not be an input (cli._outputs.check_outputs_apart): a command with
    --json, --figure or --df-figure that does not say which options are its inputs fails here."""
    from hesspipe.cli._outputs import OUTPUT_FILES

    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    for name in command_names():
        parser = sub.choices[name]
        dests = {a.dest for a in parser._actions}
        if dests & set(OUTPUT_FILES):
            declared = parser.get_default("_inputs")
            assert declared and set(declared) <= dests, name


def test_every_command_has_an_argument_builder():
    missing = sorted(set(command_names()) - set(BUILDERS))
    assert not missing, f"add an argument builder for {missing} to BUILDERS in {__file__}"


# -- running a command and checking the generic properties --------------------------------------

def _call(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def _call_unprivileged(argv, ro: Path) -> tuple[int, str, str]:
    """`main(argv)` in a forked child for which `ro` (mode 555) is really read-only.

    Returns (98, "", why) when the child could not be made so.
    """
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # child
        try:
            os.close(read)
            if os.geteuid() == 0:
                drop_write_override()
            try:
                (ro / "probe").write_text("x")
                result = (98, "", "the folder stayed writable")
            except PermissionError:
                result = _call(argv)
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            result = (99, "", f"child failed: {type(exc).__name__}: {exc}")
        with os.fdopen(write, "w") as fh:
            json.dump(result, fh)
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as fh:
        data = fh.read()
    deadline = time.monotonic() + 60
    while not os.waitpid(pid, os.WNOHANG)[0]:
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            pytest.fail(f"{argv}: the child did not end")
        time.sleep(0.01)
    result = tuple(json.loads(data))
    if result[0] == 98:
        pytest.skip(f"cannot make a folder read-only for a child of this process: {result[2]}")
    return result


def _snapshot(root: Path) -> dict[str, bytes | None]:
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else None)
            for p in sorted(root.rglob("*"))}


def _one_line_error(code, err, *, pattern=".", exit_code=1):
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert code == exit_code, (code, err)
    assert len(lines) == 1, err
    assert lines[0].startswith("hesspipe: error: "), err
    assert re.search(pattern, lines[0]), (pattern, lines[0])


@pytest.fixture
def ro_folder():
    """An empty folder this test process's command cannot write to (see module doc)."""
    base = Path(tempfile.mkdtemp(prefix="hesspipe-ro-"))
    os.chmod(base, 0o755)
    ro = base / "ro"
    ro.mkdir()
    os.chmod(ro, 0o555)
    yield ro
    os.chmod(ro, 0o755)
    shutil.rmtree(base, ignore_errors=True)


@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_every_command_refuses_a_read_only_folder(name, inputs, ro_folder):
    if name not in command_names():
        pytest.skip(f"no command {name!r} on this branch")
    argv = BUILDERS[name](inputs, ro_folder)
    before = _snapshot(inputs)
    start = time.monotonic()
    code, out, err = _call_unprivileged(argv, ro_folder)
    if name in READ_ONLY_COMMANDS:  # reading a read-only folder is no error
        assert code == 0 and "Traceback" not in err and not err.strip(), err
    else:
        _one_line_error(code, err, pattern=r"cannot write \((Permission denied|Read-only file system)\)")
        assert str(ro_folder) in err
        # Checked before any computation: well under the command's work (seconds).
        assert time.monotonic() - start < 15
    assert list(ro_folder.iterdir()) == []
    assert _snapshot(inputs) == before


@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_every_command_refuses_a_file_as_output_folder(name, inputs, tmp_path):
    if name not in command_names():
        pytest.skip(f"no command {name!r} on this branch")
    blocker = tmp_path / "a-file"
    blocker.write_text("mine\n")
    code, out, err = _call(BUILDERS[name](inputs, blocker))
    _one_line_error(code, err, pattern=r"a-file.*(not a folder|is a file)")
    assert blocker.read_text() == "mine\n" and sorted(tmp_path.iterdir()) == [blocker]


#: The other output options, into a read-only folder (the property above uses --json/--out).
OTHER_OUTPUTS = {
    "identify --figure": lambda i, ro: BUILDERS["identify"](i, ro)[:-2] + ["--figure", str(ro / "x.png")],
    "diagnose --figure": lambda i, ro: BUILDERS["diagnose"](i, ro)[:-2] + ["--figure", str(ro / "x.png")],
    "pilots --figures": lambda i, ro: BUILDERS["pilots"](i, ro)[:-2] + ["--figures", str(ro)],
    "plants --analytic": lambda i, ro: ["plants", "--analytic", "roskam", "--out", str(ro / "a")],
    "identify --df-figure": lambda i, ro: BUILDERS["identify"](i, ro)[:-2] + ["--df-figure", str(ro / "x.png")],
}


@pytest.mark.parametrize("name", sorted(OTHER_OUTPUTS))
def test_other_outputs_refuse_a_read_only_folder(name, inputs, ro_folder):
    code, out, err = _call_unprivileged(OTHER_OUTPUTS[name](inputs, ro_folder), ro_folder)
    _one_line_error(code, err, pattern=r"cannot write \((Permission denied|Read-only file system)\)")
    assert list(ro_folder.iterdir()) == []


def test_read_only_folder_really_refuses_writes(ro_folder):
    """The mechanism of the property tests: the child cannot write into `ro_folder`."""
    code, out, err = _call_unprivileged(["synth-pilots", "--plants", "/nonexistent.json", "--n", "1",
                                         "--out", str(ro_folder / "x")], ro_folder)
    assert code == 1 and "cannot write" in err
    assert list(ro_folder.iterdir()) == []


# -- the catalogue --------------------------------------------------------------------------

@dataclass(frozen=True)
class Case:
    """One row: `setup(tmp, inputs)` builds files and returns the argv; the command must
    exit with `exit` and (for a refusal) print one line matching `message`."""

    name: str
    setup: Callable[[Path, Path], list[str]]
    exit: int
    message: str


def _config(tmp: Path, text: str | bytes) -> Path:
    path = tmp / "c.toml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    return path


def _flight_copy(tmp: Path, inputs: Path) -> Path:
    shutil.copytree(inputs / "flight", tmp / "flight")
    return tmp / "flight"


def _copy(path: Path, tmp: Path) -> Path:
    """A copy of an input file or folder in `tmp` (the row's own files)."""
    (shutil.copytree if path.is_dir() else shutil.copy)(path, tmp / path.name)
    return tmp / path.name


def _user_folder(tmp: Path) -> Path:
    mine = tmp / "mine"
    mine.mkdir()
    (mine / "report.md").write_text("my own notes\n")
    return mine


def _user_pilot_in_cohort(tmp: Path, inputs: Path) -> list[str]:
    from hesspipe.core.io import _write_marker

    cohort = tmp / "cohort"
    cohort.mkdir()
    _write_marker(cohort, "cohort", [])
    (cohort / "pilot01.csv").write_text("my own pilot01\n")
    return ["synth-pilots", "--plants", str(inputs / "plants.json"), "--n", "1", "--duration", "25",
            "--out", str(cohort)]


CASES = [
    # item 4: files the tool did not write
    Case("run --out a user's folder holding report.md",
         lambda t, i: ["run", "--out", str(_user_folder(t))], 1,
         r"mine: folder is not empty and was not written by hesspipe .*choose another folder"),
    Case("plants --out the flight folder",
         lambda t, i: ["plants", "--flight", str(_flight_copy(t, i)), "--out", str(t / "flight")], 1,
         r"flight: holds hesspipe's flight output; choose another folder for the plants output"),
    Case("flight --out a pipeline run's root",
         lambda t, i: ["flight", "--out", str(_run_root(t))], 1,
         r"holds hesspipe's run output; choose another folder for the flight output"),
    Case("synth-pilots over a user's file in a cohort folder",
         _user_pilot_in_cohort, 1,
         r"pilot01.csv: exists and was not written by hesspipe; move it away"),
    # item 6: tracebacks before
    Case("identify --json <folder>",
         lambda t, i: BUILDERS["identify"](i, t)[:-2] + ["--json", str(t)], 1, r": is a folder; expected a file name"),
    Case("pilots --json <folder>",
         lambda t, i: BUILDERS["pilots"](i, t)[:-2] + ["--json", str(t)], 1, r": is a folder; expected a file name"),
    Case("diagnose --figure x.xyz",
         lambda t, i: BUILDERS["diagnose"](i, t)[:-2] + ["--figure", str(t / "x.xyz")], 1,
         r"x.xyz: unknown image format '.xyz'; expected one of .*\.png"),
    Case("identify --figure x.xyz",
         lambda t, i: BUILDERS["identify"](i, t)[:-2] + ["--figure", str(t / "x.xyz")], 1,
         r"x.xyz: unknown image format"),
    Case("identify --df-figure x.xyz: before the fit and the JSON",
         lambda t, i: BUILDERS["identify"](i, t) + ["--df-figure", str(t / "x.xyz")], 1,
         r"x.xyz: unknown image format '.xyz'; expected one of .*\.png"),
    Case("identify --df-figure <folder>: before the fit and the JSON",
         lambda t, i: BUILDERS["identify"](i, t) + ["--df-figure", str(t)], 1, r": is a folder; expected a file name"),
    # an output file that is one of the command's inputs
    Case("frf --json its own run",
         lambda t, i: ["frf", str(_copy(i / "runs" / "p0.csv", t)), "--plants", str(i / "plants.json"),
                       "--json", str(t / "p0.csv")], 1,
         r"p0.csv: is an input of this command; expected another path for the JSON output$"),
    Case("identify --figure its plants file",
         lambda t, i: ["identify", str(i / "runs" / "p0.csv"), "--plants", str(_copy(i / "plants.json", t)),
                       "--figure", str(t / "plants.json")], 1,
         r"plants.json: is an input of this command; expected another path for the figure$"),
    Case("pilots --json a run of its folder",
         lambda t, i: ["pilots", str(_copy(i / "runs", t)), "--plants", str(i / "plants.json"),
                       "--json", str(t / "runs" / "p1.csv")], 1,
         r"p1.csv: is an input of this command; expected another path for the JSON output$"),
    Case("[flight] aircraft = 5",
         lambda t, i: ["run", "--config", str(_config(t, "[flight]\naircraft = 5\n")), "--out", str(t / "o")], 1,
         r"c.toml: field 'flight.aircraft': expected a string, got 5"),
    Case("[analytic] model = 5",
         lambda t, i: ["status", "--config", str(_config(t, "[analytic]\nmodel = 5\n")), "--out", str(t / "o")], 1,
         r"c.toml: field 'analytic.model': expected a string, got 5"),
    Case("[diagnose] run = 5",
         lambda t, i: ["run", "--config", str(_config(t, "[diagnose]\nrun = 5\n")), "--out", str(t / "o")], 1,
         r"c.toml: field 'diagnose.run': expected a string, got 5"),
    Case("binary TOML",
         lambda t, i: ["status", "--config", str(_config(t, bytes(range(256)))), "--out", str(t / "o")], 1,
         r"c.toml: not a TOML text file \(not UTF-8 at byte \d+\)"),
    Case("BOM-prefixed TOML is accepted",
         lambda t, i: ["status", "--config", str(_config(t, b"\xef\xbb\xbfseed = 2\r\n[pilots]\r\nn = 3\r\n")),
                       "--out", str(t / "o")], 0, ""),
    Case("manifest.json holding 5",
         lambda t, i: ["status", "--out", str(_run_root(t, manifest=b"5"))], 0, ""),
    Case("malformed --scheduler address",
         lambda t, i: BUILDERS["pilots"](i, t) + ["--scheduler", "tcp://127.0.0.1:abc"], 1,
         r"--scheduler: expected a Dask scheduler address like tcp://HOST:PORT .*got 'tcp://127.0.0.1:abc'"),
    Case("[pilots] scheduler malformed",
         lambda t, i: ["run", "--config", str(_config(t, '[pilots]\nscheduler = "nonsense"\n')), "--out",
                       str(t / "o")], 1,
         r"c.toml: field 'pilots.scheduler': expected a Dask scheduler address"),
    # item 8: every table checked before the first stage
    Case("[diagnose] model unknown",
         lambda t, i: ["run", "--config", str(_config(t, '[diagnose]\nmodel = "orignal"\n')), "--out",
                       str(t / "o")], 1,
         r"c.toml: field 'diagnose.model': unknown model 'orignal'"),
    Case("[diagnose] candidates unknown",
         lambda t, i: ["run", "--config", str(_config(t, '[diagnose]\ncandidates = ["motion", "remnant"]\n')),
                       "--out", str(t / "o")], 1,
         r"c.toml: field 'diagnose.candidates': unknown effect 'motion'"),
    Case("[flight] aircraft unknown",
         lambda t, i: ["run", "--config", str(_config(t, '[flight]\naircraft = "A380"\n')), "--out",
                       str(t / "o")], 1,
         r"c.toml: field 'flight.aircraft': unknown aircraft 'A380'"),
    Case("[diagnose] run missing",
         lambda t, i: ["run", "--config", str(_config(t, '[diagnose]\nrun = "nowhere.csv"\n')), "--out",
                       str(t / "o")], 1,
         r"nowhere.csv"),
]


def _run_root(tmp: Path, manifest: bytes | None = None) -> Path:
    """A pipeline root as `hesspipe run` leaves it (marker and stage folders, no science)."""
    from hesspipe.core.io import _write_marker

    root = tmp / "out"
    root.mkdir()
    _write_marker(root, "run", [])
    if manifest is not None:
        (root / "flight").mkdir()
        _write_marker(root / "flight", "flight", ["manifest.json"])
        (root / "flight" / "manifest.json").write_bytes(manifest)
    return root


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_catalogue(case, inputs, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    work = tmp_path / "w"
    work.mkdir()
    argv = case.setup(work, inputs)
    before, inputs_before = _snapshot(work), _snapshot(inputs)
    code, out, err = _call(argv)
    assert "Traceback" not in err, err
    if case.exit == 0:
        assert code == 0, err
        assert not err.strip(), err
    else:
        _one_line_error(code, err, pattern=case.message, exit_code=case.exit)
        assert _snapshot(work) == before, "a refused command changed files"  # no leftover, none lost
    after = _snapshot(work)
    assert {k: v for k, v in after.items() if k in before} == before  # no file lost
    assert _snapshot(inputs) == inputs_before


def test_manifest_holding_5_reads_as_an_incomplete_stage(tmp_path, capsys):
    root = _run_root(tmp_path, manifest=b"5")
    assert main(["status", "--out", str(root)]) == 0
    assert "flight    stale  no complete run" in capsys.readouterr().out


# -- item 4: nothing deleted that the tool did not create -------------------------------------

def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_only_hesspipe_leftovers_of_dead_runs_are_removed(inputs, tmp_path):
    out = tmp_path / "cohort"
    argv = ["synth-pilots", "--plants", str(inputs / "plants.json"), "--n", "1", "--duration", "25",
            "--out", str(out)]
    assert _call(argv)[0] == 0
    # The user's hidden files that look like temporary files, and their own staging folder.
    (out / ".notes.tmp1").write_text("user")
    (out / ".x.tmp.csv").write_text("user")
    (out / ".staging-mine").mkdir()
    (out / ".staging-mine" / "keep.txt").write_text("user")
    # What a killed hesspipe run leaves: prefixed names carrying the dead process's id.
    dead = _dead_pid()
    (out / f"{STAGING_PREFIX}{dead}-abc").mkdir()
    (out / f"{STAGING_PREFIX}{dead}-abc" / "pilot01.csv").write_text("half")
    (out / f"{TMP_PREFIX}{dead}-xyz-pilot01.csv").write_text("half")
    # ... and a live one's (this process): never touched.
    live = out / f"{STAGING_PREFIX}{os.getpid()}-live"
    live.mkdir()
    assert _call(argv)[0] == 0
    names = sorted(p.name for p in out.iterdir())
    assert ".notes.tmp1" in names and ".x.tmp.csv" in names and ".staging-mine" in names
    assert (out / ".staging-mine" / "keep.txt").read_text() == "user"
    assert f"{STAGING_PREFIX}{dead}-abc" not in names and f"{TMP_PREFIX}{dead}-xyz-pilot01.csv" not in names
    assert live.is_dir()


def test_pipeline_stage_keeps_user_hidden_files(tmp_path):
    """The engine's stage start no longer sweeps `.*.tmp*` and `.staging-*` of the output tree."""
    from hesspipe.pipeline.engine import Pipeline, Stage

    def write(ctx):
        (ctx.out_dir / "out.txt").write_text("x")

    stages = [Stage("a", (), write), Stage("report", ("a",), write, folder=".")]
    Pipeline(stages, {}, tmp_path).run()
    for folder in (tmp_path, tmp_path / "a"):
        (folder / ".mine.tmp.txt").write_text("user")
        (folder / ".staging-user").mkdir()
    Pipeline(stages, {"a": {"v": 2}}, tmp_path).run()
    for folder in (tmp_path, tmp_path / "a"):
        assert (folder / ".mine.tmp.txt").read_text() == "user" and (folder / ".staging-user").is_dir()


def test_marker_is_written_first_and_lists_owned_files(inputs, tmp_path):
    out = tmp_path / "co"
    assert _call(["synth-pilots", "--plants", str(inputs / "plants.json"), "--n", "2", "--duration", "25",
                  "--out", str(out)])[0] == 0
    marker = json.loads((out / MARKER).read_text())
    assert marker["hesspipe_output"] == "cohort"
    assert marker["files"] == sorted(p.name for p in out.iterdir() if p.name != MARKER)


# -- item 5: a folder is published whole ------------------------------------------------------

def test_synth_pilots_into_an_old_cohort_leaves_no_stale_pilot(inputs, tmp_path):
    out = tmp_path / "cohort"
    base = ["synth-pilots", "--plants", str(inputs / "plants.json"), "--duration", "25", "--out", str(out)]
    assert _call(base + ["--n", "3"])[0] == 0
    (out / "notes.txt").write_text("mine")  # the user's file: not hesspipe's, kept
    assert _call(base + ["--n", "2"])[0] == 0
    assert sorted(p.name for p in out.glob("*.csv")) == ["pilot01.csv", "pilot02.csv"]
    assert not (out / "pilot03.truth.json").exists()
    assert (out / "notes.txt").read_text() == "mine"
    from hesspipe.pilots.compare import list_runs

    assert [p.name for p in list_runs(out)] == ["pilot01.csv", "pilot02.csv"]


def test_diagnose_stage_reads_the_run_the_pilots_stage_declared(tmp_path):
    """A CSV put by hand beside the cohort is not diagnosed (the run is taken by id)."""
    from hesspipe.pipeline.stages import _diagnose_run

    pilots = tmp_path / "pilots"
    (pilots / "cohort").mkdir(parents=True)
    (pilots / "cohort" / "pilot01.csv").write_text("x")
    (pilots / "cohort" / "a_foreign.csv").write_text("x")  # sorts first
    (pilots / "comparison.json").write_text(json.dumps({"pilots": [{"id": "pilot01",
                                                                   "source": "cohort/pilot01.csv"}]}))

    class Ctx:
        section = {}
        config = {"pilots": {"data": ""}}
        upstream = {"pilots": pilots}

    chosen = pilots / "cohort" / "pilot01.csv"
    assert _diagnose_run(Ctx) == (chosen, str(chosen))
    (pilots / "comparison.json").write_text(json.dumps({"pilots": []}))
    with pytest.raises(HesspipeError, match=r"comparison.json: the pilots stage compared no runs"):
        _diagnose_run(Ctx)


# -- item 6: results are not lost, the file system's refusals are one line ---------------------

def test_outputs_are_checked_before_identifying(inputs, tmp_path, monkeypatch):
    import hesspipe.identification.fit

    def boom(*a, **k):
        raise AssertionError("identification ran before the output path was checked")

    monkeypatch.setattr(hesspipe.identification.fit, "identify", boom)
    blocker = tmp_path / "f"
    blocker.write_text("")
    code, out, err = _call(BUILDERS["identify"](inputs, blocker))
    _one_line_error(code, err, pattern="is a file")


def test_unforeseen_os_error_is_one_line(monkeypatch, tmp_path):
    import errno

    import hesspipe.cli.status as status_cmd

    def full(args):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "x.json"))

    monkeypatch.setattr(status_cmd, "_status", full)
    code, out, err = _call(["status", "--out", str(tmp_path)])
    _one_line_error(code, err, pattern=r"x.json: No space left on device$")


def test_write_refused_mid_way_is_a_one_line_error_naming_the_file(tmp_path, monkeypatch):
    """A write that fails after the checks (disk full) names the file; nothing is left."""
    import errno

    from hesspipe.core.io import write_text

    def full(self, *a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(HesspipeError, match=r"r.md: cannot write \(No space left on device\)"):
        write_text(tmp_path / "r.md", "x")
    assert list(tmp_path.iterdir()) == []


def test_scheduler_that_is_not_dask_times_out(monkeypatch):
    """A port where something else listens accepts the connection and never answers."""
    pytest.importorskip("distributed")
    from hesspipe.pilots.batch import run_batch

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    held = []
    threading.Thread(target=lambda: [held.append(server.accept()) for _ in range(4)], daemon=True).start()
    start = time.monotonic()
    try:
        with pytest.raises(HesspipeError, match=r"cannot connect to a Dask scheduler"):
            run_batch(abs, [1], scheduler=f"tcp://127.0.0.1:{server.getsockname()[1]}", connect_timeout=1)
    finally:
        server.close()
    assert time.monotonic() - start < 10


# -- item 7: SIGTERM leaves no worker behind ---------------------------------------------------

@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc to list child processes")
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_a_stopped_command_leaves_no_worker(inputs, tmp_path, sig):
    # SIGKILL: the command cannot stop its pool; the workers see their parent gone.
    runs = tmp_path / "runs"
    runs.mkdir()
    base = read_run(inputs / "runs" / "p0.csv")
    for i in range(4):  # real identifications: several seconds each, so the pool is busy
        # Four records, not four copies of one (a copied record is refused).
        write_run(runs / f"p{i}.csv", dataclasses.replace(base, control=base.control * (1 + 0.01 * i)))
    err_file = tmp_path / "stderr.txt"
    code, orphans = sigterm_when_ready(
        [sys.executable, "-m", "hesspipe.cli", "pilots", str(runs), "--plants",
         str(inputs / "plants.json"), "--workers", "2", "--json", str(tmp_path / "c.json")],
        err_file, lambda workers, err: len(workers) >= 2, settle_s=0.3, sig=getattr(signal, sig))
    err = err_file.read_text()
    assert not orphans, "worker processes outlived the command"
    assert not (tmp_path / "c.json").exists()
    if sig == "SIGTERM":
        assert code == 128 + signal.SIGTERM, err
        assert err.strip().splitlines()[-1] == "hesspipe: terminated" and "Traceback" not in err, err


@pytest.mark.parametrize("where", ["read-only", "file"])
def test_a_write_without_a_prior_check_is_still_one_line(where, ro_folder, tmp_path):
    """The root of every write (hesspipe.core.io.atomic_path) turns the file system's refusal
    into one line naming the file, for writers that do not check up front."""
    from hesspipe.core.io import write_json

    if where == "file":
        blocker = tmp_path / "a-file"
        blocker.write_text("mine\n")
        with pytest.raises(HesspipeError, match=r"x.json: cannot create it: .*a-file is a file, not a folder"):
            write_json(blocker / "x.json", {})
        assert blocker.read_text() == "mine\n"
        return
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        msg = "no error"
        try:
            if os.geteuid() == 0:
                drop_write_override()
            write_json(ro_folder / "x.json", {})
        except HesspipeError as exc:
            msg = str(exc)
        except BaseException as exc:  # noqa: BLE001
            msg = f"{type(exc).__name__}: {exc}"
        os.write(write, msg.encode())
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as fh:
        msg = fh.read()
    os.waitpid(pid, 0)
    assert re.fullmatch(r".*x.json: cannot write \((Permission denied|Read-only file system)\); choose a "
                        r"location you can write to", msg), msg
    assert list(ro_folder.iterdir()) == []


def test_an_output_folder_of_an_older_hesspipe_is_still_recognised(tmp_path):
    """Folders written before markers existed are known by their manifests naming the stage."""
    from hesspipe.pipeline.engine import Pipeline, Stage

    def write(ctx):
        (ctx.out_dir / "out.txt").write_text(str(ctx.section))

    stages = [Stage("a", (), write), Stage("report", ("a",), write, folder=".")]
    Pipeline(stages, {}, tmp_path).run()
    for marker in tmp_path.rglob(MARKER):
        marker.unlink()
    (tmp_path / "a" / "mine.txt").write_text("user")
    outcomes = Pipeline(stages, {"a": {"v": 2}}, tmp_path).run()
    assert [o.action for o in outcomes] == ["ran", "ran"]
    assert (tmp_path / "a" / "out.txt").read_text() == "{'v': 2}"
    assert (tmp_path / "a" / "mine.txt").read_text() == "user"
    assert (tmp_path / MARKER).exists() and (tmp_path / "a" / MARKER).exists()


@pytest.mark.parametrize("argv, status", [
    (["plants", "--analytic", "roskam", "--out", "{t}/out"], 0),
    # python-control loads matplotlib: checking a folder's outputs loads it before any work.
    (["pilots", "{t}/empty", "--plants", "{t}/p.json", "--json", "{t}/out/c.json"], 1),
])
def test_a_command_writes_nothing_outside_its_output_folder(tmp_path, argv, status):
    """matplotlib's configuration and font list (~/.config, ~/.cache) go to a folder of the
    command's own, removed when it ends: a fresh home and temporary folder stay empty, and a
    folder a killed command left there (its process gone) is removed."""
    home, tmp = tmp_path / "home", tmp_path / "tmp"
    for d in (home, tmp, tmp_path / "empty"):
        d.mkdir()
    left = tmp / "hesspipe-matplotlib-999999999-abcd"
    left.mkdir()
    (left / "fontlist.json").write_text("{}")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("MPL", "XDG_"))}
    env.update(HOME=str(home), TMPDIR=str(tmp))
    proc = subprocess.run([sys.executable, "-m", "hesspipe.cli", *[a.format(t=tmp_path) for a in argv]],
                          capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert proc.returncode == status, proc.stderr
    if status == 0:
        assert (tmp_path / "out" / "analytic_bode.png").is_file()
    assert list(home.iterdir()) == [] and list(tmp.iterdir()) == []
    assert {p.name for p in tmp_path.iterdir()} == {"empty", "home", "tmp"} | ({"out"} if status == 0 else set())

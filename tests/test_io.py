"""Atomic output and config field checking."""

import json
import math
import shutil

import numpy as np
import pytest

from hesspipe.core.config import Fields, load_toml, merge
from hesspipe.core.errors import HesspipeError
from hesspipe.core.io import atomic_path, staged_output, to_json, write_json


def test_atomic_path_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "x.csv"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError
    assert list(tmp_path.iterdir()) == []


def test_staged_output_publishes_all_or_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError):
        with staged_output(out) as stage:
            (stage / "a.txt").write_text("a")
            raise RuntimeError
    assert not out.exists()  # created by the call, so removed again
    with staged_output(out) as stage:
        (stage / "sub").mkdir()
        (stage / "sub" / "b.txt").write_text("b")
        (stage / "manifest.json").write_text("{}")
    assert sorted(p.name for p in out.rglob("*") if p.is_file()) == [".hesspipe-output", "b.txt",
                                                                      "manifest.json"]
    assert not [p for p in out.iterdir() if p.name.startswith(".hesspipe-staging")]


class _Killed(BaseException):
    """What SIGKILL does to a publication, as far as the folder can tell: it stops."""


def _publish_two_runs(out, monkeypatch, *, stop_after=None, signal_at=None):
    """Make the next publications stop (or send this process a signal) after their
    `stop_after`-th file moved into place (the marker's writes not counted)."""
    import os

    from hesspipe.core import io

    moved = []
    real = os.replace

    def replace(src, dst):
        real(src, dst)
        if str(dst).endswith(io.MARKER):
            return
        moved.append(dst)
        if stop_after is not None and len(moved) == stop_after:
            raise _Killed
        if signal_at is not None and len(moved) == signal_at[0]:
            os.kill(os.getpid(), signal_at[1])
    monkeypatch.setattr(io.os, "replace", replace)
    return moved


def test_a_publication_killed_midway_is_refused_as_input_until_published_whole(tmp_path, monkeypatch):
    from hesspipe.core.io import read_bytes

    out = tmp_path / "out"
    with staged_output(out, "flight") as stage:
        for name in "abc":
            (stage / f"{name}.txt").write_text("run 1")
    _publish_two_runs(out, monkeypatch, stop_after=2)
    with pytest.raises(_Killed):
        with staged_output(out, "flight") as stage:
            for name in "abc":
                (stage / f"{name}.txt").write_text("run 2")
    assert [(out / f"{n}.txt").read_text() for n in "abc"] == ["run 2", "run 2", "run 1"]
    with pytest.raises(HesspipeError, match=r"c.txt: .*out holds a hesspipe flight output whose writing was "
                                             r"stopped midway \(its .hesspipe-output file says so.* run the "
                                             r"command that wrote it again"):
        read_bytes(out / "c.txt", "a text file")
    # A file in a sub-folder of it, one with a complete marker of its own too (a cohort in
    # pilots/cohort/), is refused; a file beside it reached through it is not.
    (out / "sub").mkdir()
    (out / "sub" / "d.txt").write_text("run 2")
    (out / "sub" / ".hesspipe-output").write_text(json.dumps({"hesspipe_output": "cohort", "files": ["d.txt"]}))
    with pytest.raises(HesspipeError, match="stopped midway"):
        read_bytes(out / "sub" / "d.txt", "a text file")
    (tmp_path / "own.txt").write_text("mine")
    assert read_bytes(out / ".." / "own.txt", "a text file") == b"mine"
    shutil.rmtree(out / "sub")
    monkeypatch.undo()
    with staged_output(out, "flight") as stage:
        for name in "abc":
            (stage / f"{name}.txt").write_text("run 3")
    assert read_bytes(out / "c.txt", "a text file") == b"run 3"


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_a_signal_during_publication_waits_for_the_whole_folder(tmp_path, monkeypatch, sig):
    import signal

    out = tmp_path / "out"

    class Stopped(BaseException):
        pass

    def stop(signum, frame):
        raise Stopped
    previous = signal.signal(getattr(signal, sig), stop)
    try:
        _publish_two_runs(out, monkeypatch, signal_at=(1, getattr(signal, sig)))
        with pytest.raises(Stopped):
            with staged_output(out, "cohort") as stage:
                for name in "abc":
                    (stage / f"{name}.txt").write_text("run 1")
    finally:
        signal.signal(getattr(signal, sig), previous)
    assert [(out / f"{n}.txt").read_text() for n in "abc"] == ["run 1"] * 3
    assert "publishing" not in json.loads((out / ".hesspipe-output").read_text())


def test_a_killed_write_of_a_file_leaves_nothing_for_long(tmp_path):
    # A --json file's folder is the user's: the temporary file of a write killed before its
    # rename (a dead process's id in its name) goes with the next write of that file.
    dead = tmp_path / ".hesspipe-tmp-999999999-abcd-c.json"
    other = tmp_path / ".hesspipe-tmp-999999999-abcd-d.json"
    dead.write_text("{")
    other.write_text("{")
    write_json(tmp_path / "c.json", {"a": 1})
    assert not dead.exists() and other.exists()


def test_json_handles_numpy_and_nonfinite(tmp_path):
    obj = {"a": np.float64(1.5), "b": np.arange(3), "c": math.nan, "d": [np.inf]}
    assert json.loads(to_json(obj)) == {"a": 1.5, "b": [0, 1, 2], "c": None, "d": [None]}
    write_json(tmp_path / "o.json", obj)
    assert json.loads((tmp_path / "o.json").read_text())["b"] == [0, 1, 2]


def test_fields_messages_name_file_and_field():
    f = Fields({"vc_kts": "fast", "n": 2.5, "mode": "x"}, "a.toml", "approach")
    with pytest.raises(HesspipeError, match=r"a.toml: field 'approach.vc_kts': expected a number > 0, got 'fast'"):
        f.number("vc_kts", min=0, strict_min=True)
    with pytest.raises(HesspipeError, match=r"field 'approach.n': expected an integer"):
        f.integer("n")
    with pytest.raises(HesspipeError, match=r"expected one of 'a', 'b', got 'x'"):
        f.string("mode", choices=("a", "b"))
    with pytest.raises(HesspipeError, match=r"field 'approach.missing': expected a number, missing"):
        f.number("missing")
    assert f.number("absent", 3.0) == 3.0


def test_fields_reject_unknown():
    f = Fields({"a": 1, "typo": 2}, "c.toml")
    f.number("a")
    with pytest.raises(HesspipeError, match="field 'typo': unknown field"):
        f.reject_unknown()


def test_load_toml_errors(tmp_path):
    with pytest.raises(HesspipeError, match="file not found"):
        load_toml(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("a = [\n")
    with pytest.raises(HesspipeError, match="bad.toml: not valid TOML"):
        load_toml(bad)


def test_merge_is_deep():
    assert merge({"a": {"x": 1, "y": 2}, "b": 1}, {"a": {"y": 3}}) == {"a": {"x": 1, "y": 3}, "b": 1}


def test_atomic_file_gets_ordinary_permissions(tmp_path):
    import os

    write_json(tmp_path / "p.json", {})
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "p.json").stat().st_mode & 0o777 == 0o666 & ~umask


def test_fields_optional_values_and_string_lists():
    f = Fields({"names": ["a", "b"], "bad": ["a", 3]}, "s.toml", "pilots")
    assert f.number("absent", None) is None and f.integer("absent2", None) is None
    assert f.strings("names") == ("a", "b")
    assert f.strings("none", None) is None
    with pytest.raises(HesspipeError, match=r"field 'pilots.bad': expected a list of non-empty strings"):
        f.strings("bad")
    with pytest.raises(HesspipeError, match=r"expected a list of names from 'a'"):
        f.strings("names", choices=("a",))


def test_a_stop_whose_exception_was_swallowed_publishes_nothing(tmp_path):
    # Raised inside an at-fork handler (logging's, as a worker pool forks), a signal's
    # exception is only printed as "Exception ignored": a loaded CI machine saw SIGTERM during
    # the pilots stage let `hesspipe run` finish and publish. The handler's record (core.stops)
    # is acted on where the stage would be published.
    import signal

    from hesspipe.core import stops

    class Stopped(BaseException):
        pass

    def handler(signum, frame):
        stops.request(signum)
        raise Stopped

    out = tmp_path / "out"
    previous = signal.signal(signal.SIGTERM, handler)
    try:
        with pytest.raises(Stopped):
            with staged_output(out, "cohort") as stage:
                (stage / "a.txt").write_text("x")
                try:
                    signal.raise_signal(signal.SIGTERM)
                except Stopped:
                    pass   # swallowed, as "Exception ignored" does
                (stage / "b.txt").write_text("y")
    finally:
        signal.signal(signal.SIGTERM, previous)
        stops.clear()
    assert not out.exists()
    with staged_output(out, "cohort") as stage:   # nothing recorded: published as ever
        (stage / "a.txt").write_text("x")
    assert (out / "a.txt").read_text() == "x"


def test_the_command_line_ends_on_a_swallowed_sigterm_without_publishing(tmp_path, monkeypatch, capsys):
    import signal

    import hesspipe.plants.fit as fit
    from hesspipe.cli import main

    real = fit.write_plants

    def swallowing(*args, **kw):
        try:
            signal.raise_signal(signal.SIGTERM)
        except KeyboardInterrupt:
            pass   # swallowed (the CLI's Terminated is a KeyboardInterrupt)
        return real(*args, **kw)

    monkeypatch.setattr(fit, "write_plants", swallowing)
    out = tmp_path / "plants"
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--no-figures"]) == 128 + signal.SIGTERM
    assert capsys.readouterr().err.strip().splitlines()[-1] == "hesspipe: terminated"
    assert not out.exists()
    monkeypatch.setattr(fit, "write_plants", real)
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--no-figures"]) == 0   # nothing left over

"""The pipeline engine: freshness, forced re-runs, resumption, manifests.

These tests drive the engine with small stages of their own (each writes a
file derived from its configuration and its upstream's output) so the
re-run logic is pinned independently of the science stages, which
tests/test_run.py exercises end to end.
"""

import json

import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.pipeline.engine import Pipeline, Stage, load_stages

CALLS = []


def _writer(name):
    def run(ctx):
        CALLS.append(name)
        text = json.dumps(ctx.section, sort_keys=True)
        for ext in ctx.config.get("external", []):
            text += open(ext).read()
        for up, folder in sorted(ctx.upstream.items()):
            text += (folder / "out.txt").read_text()
        if ctx.section.get("explode"):
            (ctx.out_dir / "out.txt").write_text("half")
            raise HesspipeError("stage failed on purpose")
        (ctx.out_dir / "out.txt").write_text(f"{name}:{text}\n")
    return run


def stages(ext=None):
    return [
        Stage("a", (), _writer("a"), (lambda s, c: [ext]) if ext else (lambda s, c: [])),
        Stage("b", ("a",), _writer("b")),
        Stage("c", ("b",), _writer("c")),
        Stage("side", (), _writer("side")),
    ]


@pytest.fixture(autouse=True)
def _clear():
    CALLS.clear()


def ran(outcomes):
    return [o.name for o in outcomes if o.action == "ran"]


def test_first_run_runs_all_second_runs_none(tmp_path):
    cfg = {"seed": 1, "a": {"x": 1}}
    assert ran(Pipeline(stages(), cfg, tmp_path).run()) == ["a", "b", "c", "side"]
    assert ran(Pipeline(stages(), cfg, tmp_path).run()) == []
    assert all(s.state == "fresh" for s in Pipeline(stages(), cfg, tmp_path).status())


def test_config_change_reruns_stage_and_downstream_only(tmp_path):
    Pipeline(stages(), {"a": {"x": 1}}, tmp_path).run()
    p = Pipeline(stages(), {"a": {"x": 2}}, tmp_path)
    status = {s.name: s for s in p.status()}
    assert status["a"].reason == "configuration changed"
    assert status["b"].state == "stale" and status["side"].state == "fresh"
    assert ran(p.run()) == ["a", "b", "c"]


def test_seed_change_reruns_everything(tmp_path):
    Pipeline(stages(), {"seed": 1}, tmp_path).run()
    assert ran(Pipeline(stages(), {"seed": 2}, tmp_path).run()) == ["a", "b", "c", "side"]


def test_external_input_change(tmp_path):
    ext = tmp_path / "aircraft.toml"
    ext.write_text("a = 1\n")
    cfg = {"external": [str(ext)]}
    Pipeline(stages(ext), cfg, tmp_path / "out").run()
    ext.write_text("a = 2\n")
    st = {s.name: s for s in Pipeline(stages(ext), cfg, tmp_path / "out").status()}
    assert st["a"].reason == f"input {ext} changed"
    assert ran(Pipeline(stages(ext), cfg, tmp_path / "out").run()) == ["a", "b", "c"]


def test_force_and_from(tmp_path):
    Pipeline(stages(), {}, tmp_path).run()
    # Forcing a stage whose output is unchanged does not cascade.
    assert ran(Pipeline(stages(), {}, tmp_path).run(force=["b"])) == ["b"]
    assert ran(Pipeline(stages(), {}, tmp_path).run(from_stage="b")) == ["b", "c"]
    with pytest.raises(HesspipeError, match="unknown stage 'nope'"):
        Pipeline(stages(), {}, tmp_path).run(from_stage="nope")


def test_modified_output_makes_stage_stale(tmp_path):
    Pipeline(stages(), {}, tmp_path).run()
    (tmp_path / "b" / "out.txt").write_text("tampered")
    st = {s.name: s for s in Pipeline(stages(), {}, tmp_path).status()}
    assert st["b"].reason == "outputs missing or modified"
    assert ran(Pipeline(stages(), {}, tmp_path).run()) == ["b"]


def test_failed_stage_publishes_nothing_and_next_run_resumes(tmp_path):
    Pipeline(stages(), {"b": {"v": 1}}, tmp_path).run()
    before = (tmp_path / "b" / "out.txt").read_text()
    with pytest.raises(HesspipeError):
        Pipeline(stages(), {"b": {"v": 2, "explode": True}}, tmp_path).run()
    # The old output is untouched, no half file, and the stage is no longer fresh.
    assert (tmp_path / "b" / "out.txt").read_text() == before
    assert not (tmp_path / "b" / "manifest.json").exists()
    assert not [p for p in (tmp_path / "b").iterdir() if p.name.startswith(".hesspipe-staging")]
    CALLS.clear()
    assert ran(Pipeline(stages(), {"b": {"v": 1}}, tmp_path).run()) == ["b"]


def test_manifest_records_provenance(tmp_path):
    Pipeline(stages(), {"seed": 3, "a": {"x": 1}}, tmp_path, source="cfg.toml").run()
    m = json.loads((tmp_path / "b" / "manifest.json").read_text())
    assert m["seed"] == 3 and m["config_file"] == "cfg.toml"
    assert set(m["versions"]) >= {"hesspipe", "jsbsim", "numpy", "scipy", "control"}
    assert m["outputs"]["out.txt"].startswith("sha256:")
    assert m["fingerprint_parts"]["inputs"]["upstream"]["a"]["out.txt"].startswith("sha256:")
    assert m["wall_time_s"] >= 0


def test_cycle_and_unknown_need_rejected(tmp_path):
    noop = _writer("x")
    with pytest.raises(HesspipeError, match="cycle"):
        Pipeline([Stage("a", ("b",), noop), Stage("b", ("a",), noop)], {}, tmp_path)
    with pytest.raises(HesspipeError, match="unknown stage 'z'"):
        Pipeline([Stage("a", ("z",), noop)], {}, tmp_path)


def test_load_stages_errors_name_file_and_field(tmp_path):
    bad = tmp_path / "stages.toml"
    bad.write_text('[[stage]]\nname = "a"\nrun = "hesspipe.nothing:here"\n')
    with pytest.raises(HesspipeError, match=r"stages.toml: field 'stage\[0\].run'"):
        load_stages(bad)
    bad.write_text('[[stage]]\nname = "a"\nrun = "tests:x"\ncolour = 1\n')
    with pytest.raises(HesspipeError, match="field 'stage\\[0\\].colour': unknown field|run"):
        load_stages(bad)


def test_stage_publishing_into_the_root(tmp_path):
    st = stages() + [Stage("report", ("c",), _writer("report"), folder=".")]
    Pipeline(st, {}, tmp_path).run()
    assert (tmp_path / "out.txt").read_text().startswith("report:")
    assert (tmp_path / "report" / "manifest.json").exists()
    assert ran(Pipeline(st, {}, tmp_path).run()) == []
    (tmp_path / "out.txt").unlink()
    assert ran(Pipeline(st, {}, tmp_path).run()) == ["report"]


def test_before_hook_runs_once_and_only_when_something_runs(tmp_path):
    calls = []
    Pipeline(stages(), {}, tmp_path).run(before=lambda: calls.append(1))
    assert calls == [1]
    Pipeline(stages(), {}, tmp_path).run(before=lambda: calls.append(2))
    assert calls == [1]

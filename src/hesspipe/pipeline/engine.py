"""The pipeline engine: declared stages, freshness, provenance, resumable runs.

A stage is fresh when its ``manifest.json`` exists and records the same
*fingerprint* the stage would have now. The fingerprint hashes

* the stage's configuration table (and the global seed),
* the code version (hesspipe's version and a hash of its source files),
* the bytes of every input: upstream stages' outputs and external files
  (an aircraft TOML, a folder of pilot recordings).

A stage runs again only when one of those changed, its outputs are missing
or modified, or the user asked (``force`` / ``from_stage``). Before a stage
runs its old manifest is removed, and the new one is written only after all
outputs are in place, so a run killed at any point leaves no stage looking
fresh when it is not; the next run picks up at the first stale stage.

We keep this engine small instead of adopting a workflow tool: the stages
form a short chain, and what users need — "why is this stale?" in one line,
configuration tables and code version as dependencies — is a few dozen
lines here but custom plugins in doit or snakemake.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping, Sequence

from .. import __version__
from ..core.config import Fields, load_toml
from ..core.errors import HesspipeError
from ..core.io import (
    STAGING_PREFIX,
    check_output_dir,
    mark_output_dir,
    output_publishing,
    remove_leftovers,
    staged_output,
    write_json,
)
from ..core.provenance import file_hash, versions

MANIFEST = "manifest.json"

#: Kind of output (see hesspipe.core.io) of a pipeline run's root folder.
ROOT_KIND = "run"

#: Settings that say how a stage computes, not what: its outputs do not depend on them
#: (``tests/test_run.py::test_workers_change_how_not_what``), so changing them leaves the
#: stage up to date.
HOW_NOT_WHAT = frozenset({"workers", "scheduler"})


@dataclass(frozen=True)
class StageContext:
    """What a stage function receives.

    Attributes
    ----------
    name : str
        Stage name.
    section : dict
        The stage's configuration table.
    config : dict
        The whole configuration (read-only by convention).
    seed : int
        The pipeline seed.
    out_dir : Path
        Where the stage writes: a staging folder, published when it returns.
    upstream : dict
        Stage name → published folder of each stage it needs.
    source : str
        The configuration file (for error messages).
    """

    name: str
    section: dict
    config: dict
    seed: int
    out_dir: Path
    upstream: dict
    source: str


@dataclass(frozen=True)
class Stage:
    """A declared stage.

    Attributes
    ----------
    name : str
    needs : tuple of str
        Upstream stages whose outputs are this stage's inputs.
    run : callable
        ``run(ctx: StageContext) -> None``, writes into ``ctx.out_dir``.
    external_inputs : callable
        ``external_inputs(section, config) -> list[Path]``: files outside the
        pipeline's folder that the stage reads (hashed into the fingerprint).
    description : str
    folder : str
        Where its outputs go, relative to the output root (default: the
        stage's name; ``"."`` publishes into the root itself, as the report
        does). The manifest is always ``<root>/<name>/manifest.json``.
    """

    name: str
    needs: tuple[str, ...]
    run: Callable[[StageContext], None]
    external_inputs: Callable[[dict, dict], list] = lambda section, config: []
    description: str = ""
    folder: str = ""


@dataclass(frozen=True)
class StageStatus:
    """Freshness of one stage: ``state`` is "fresh" or "stale", ``reason`` says why.

    Attributes
    ----------
    name : str
        The stage.
    state : {"fresh", "stale"}
    reason : str
        Why, for the user.
    """

    name: str
    state: str
    reason: str


@dataclass(frozen=True)
class StageOutcome:
    """What :func:`run_pipeline` did with one stage ("ran" or "skipped").

    Attributes
    ----------
    name : str
        The stage.
    action : {"ran", "skipped"}
    reason : str
        Why.
    wall_time_s : float
        Time it took, s (0 if skipped).
    """

    name: str
    action: str
    reason: str
    wall_time_s: float = 0.0


def code_hash() -> str:
    """Hash of hesspipe's version and every ``.py`` file of the package."""
    h = hashlib.sha256(__version__.encode())
    root = Path(__file__).resolve().parent
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return "sha256:" + h.hexdigest()


def _canonical(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def _output_hashes(folder: Path) -> dict[str, str]:
    """Hashes of every file a stage wrote into its staging `folder`."""
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if path.is_file() and rel.name != MANIFEST and not rel.parts[0].startswith(STAGING_PREFIX):
            out[str(rel)] = file_hash(path)
    return out


def _outputs_intact(folder: Path, recorded: Mapping[str, str]) -> bool:
    """True if every recorded output is in `folder` with its recorded hash."""
    for rel, digest in recorded.items():
        path = folder / rel
        if not path.is_file() or file_hash(path) != digest:
            return False
    return True


def _external_hashes(paths: Sequence) -> dict[str, str]:
    out = {}
    for p in paths:
        p = Path(p)
        files = sorted(q for q in p.rglob("*") if q.is_file()) if p.is_dir() else [p]
        for q in files:
            if not q.exists():
                raise HesspipeError(f"{q}: input file not found")
            out[str(q)] = file_hash(q)
    return out


def _read_manifest(folder: Path) -> dict | None:
    """The manifest in `folder`, or None if there is none or it is not a manifest
    (unreadable, not JSON, not an object, or with outputs that are not a mapping)."""
    try:
        data = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("outputs", {}), dict):
        return None
    return data


def _order(stages: Sequence[Stage]) -> list[Stage]:
    by_name = {s.name: s for s in stages}
    done: list[Stage] = []
    seen: set[str] = set()

    def visit(stage: Stage, trail: tuple[str, ...]):
        if stage.name in seen:
            return
        if stage.name in trail:
            raise HesspipeError(f"pipeline: stages form a cycle: {' -> '.join(trail + (stage.name,))}")
        for need in stage.needs:
            if need not in by_name:
                raise HesspipeError(f"pipeline: stage '{stage.name}' needs unknown stage '{need}'")
            visit(by_name[need], trail + (stage.name,))
        seen.add(stage.name)
        done.append(stage)

    for s in stages:
        visit(s, ())
    return done


class Pipeline:
    """Stages, a configuration and an output folder.

    Parameters
    ----------
    stages : sequence of Stage
    config : dict
        Whole configuration; stage ``name`` reads table ``config[name]``.
    out_root : path
        Each stage writes to ``out_root / stage.name``.
    source : str
        Name of the configuration file, for messages.
    """

    def __init__(self, stages: Sequence[Stage], config: Mapping, out_root, source: str = "<config>"):
        self.stages = _order(stages)
        self.config = dict(config)
        self.out_root = Path(out_root)
        self.source = source
        self.seed = int(self.config.get("seed", 0))
        self._code = code_hash()

    def names(self) -> list[str]:
        """The stages' names in run order."""
        return [s.name for s in self.stages]

    def _stage(self, name: str) -> Stage:
        for s in self.stages:
            if s.name == name:
                return s
        raise HesspipeError(f"unknown stage '{name}'; expected one of {', '.join(self.names())}")

    def folder(self, name: str) -> Path:
        """Folder of stage `name`'s manifest (and, by default, its outputs).

        Parameters
        ----------
        name : str
            A stage's name.
        """
        return self.out_root / name

    def output_folder(self, name: str) -> Path:
        """Folder stage `name` publishes its outputs into.

        Parameters
        ----------
        name : str
            A stage's name.
        """
        return (self.out_root / (self._stage(name).folder or name)).resolve()

    def downstream(self, name: str) -> list[str]:
        """`name` and every stage that depends on it, in run order.

        Parameters
        ----------
        name : str
            A stage's name.
        """
        self._stage(name)
        hit = {name}
        for s in self.stages:
            if hit & set(s.needs):
                hit.add(s.name)
        return [s.name for s in self.stages if s.name in hit]

    def _fingerprint_parts(self, stage: Stage) -> dict:
        section = {k: v for k, v in self.config.get(stage.name, {}).items() if k not in HOW_NOT_WHAT}
        upstream = {}
        for need in stage.needs:
            manifest = _read_manifest(self.folder(need)) or {}
            upstream[need] = manifest.get("outputs", {})
        return {
            "config": json.loads(_canonical({"section": section, "seed": self.seed})),
            "code": self._code,
            "inputs": {"upstream": upstream,
                       "external": _external_hashes(stage.external_inputs(section, self.config))},
        }

    def _why_stale(self, stage: Stage, parts: dict) -> str | None:
        folder = self.folder(stage.name)
        manifest = _read_manifest(folder)
        if manifest is None or "fingerprint" not in manifest:
            return "never completed" if not folder.exists() else "no complete run (interrupted or never run)"
        if output_publishing(folder):
            return "no complete run (stopped while its files were moved into place)"
        old = manifest.get("fingerprint_parts", {})
        if old.get("code") != parts["code"]:
            return "code version changed"
        if old.get("config") != parts["config"]:
            return "configuration changed"
        for key in ("upstream", "external"):
            a, b = old.get("inputs", {}).get(key, {}), parts["inputs"][key]
            if a != b:
                if key == "upstream":
                    changed = sorted(n for n in set(a) | set(b) if a.get(n) != b.get(n))
                    return f"outputs of stage '{changed[0]}' changed"
                changed = sorted(n for n in set(a) | set(b) if a.get(n) != b.get(n))
                return f"input {changed[0]} changed"
        if not _outputs_intact(self.output_folder(stage.name), manifest.get("outputs", {})):
            return "outputs missing or modified"
        return None

    def status(self) -> list[StageStatus]:
        """Freshness of every stage, as it would be decided by :meth:`run`."""
        check_output_dir(self.out_root, ROOT_KIND, write=False)
        out, stale = [], set()
        for stage in self.stages:
            upstream_stale = [n for n in stage.needs if n in stale]
            reason = self._why_stale(stage, self._fingerprint_parts(stage))
            if reason is None and upstream_stale:
                reason = f"upstream stage '{upstream_stale[0]}' is stale"
            if reason:
                stale.add(stage.name)
            out.append(StageStatus(stage.name, "stale" if reason else "fresh", reason or "up to date"))
        return out

    def run(self, *, force: Sequence[str] = (), from_stage: str | None = None,
            progress: Callable[[str], None] | None = None,
            before: Callable[[], None] | None = None) -> list[StageOutcome]:
        """Run every stale stage (and the forced ones) in order.

        Parameters
        ----------
        force : sequence of str
            Stages to re-run even if fresh (their dependents re-run only if
            the outputs change).
        from_stage : str, optional
            Re-run this stage and everything downstream of it.
        progress : callable, optional
            Called with a line of text as each stage starts and ends.
        before : callable, optional
            Called once before the first stage that runs (not at all when
            everything is fresh), e.g. to check the whole configuration.
        """
        forced = {self._stage(n).name for n in force}
        if from_stage is not None:
            forced |= set(self.downstream(from_stage))
        check_output_dir(self.out_root, ROOT_KIND, write=False)
        self._tidy()
        outcomes = []
        claimed = False
        for stage in self.stages:
            try:
                parts = self._fingerprint_parts(stage)
            except HesspipeError:
                if before is not None:   # a missing input is a configuration's mistake: name its field
                    before()
                raise
            reason = self._why_stale(stage, parts)
            if reason is None and stage.name in forced:
                reason = "forced"
            if reason is None:
                outcomes.append(StageOutcome(stage.name, "skipped", "up to date"))
                if progress:
                    progress(f"{stage.name}: up to date")
                continue
            if before is not None:
                before()
                before = None
            if not claimed:
                self._claim()
                claimed = True
            if progress:
                progress(f"{stage.name}: running ({reason})")
            wall = self._execute(stage, parts)
            outcomes.append(StageOutcome(stage.name, "ran", reason, wall))
            if progress:
                progress(f"{stage.name}: done in {wall:.1f} s")
        return outcomes

    def _tidy(self) -> None:
        """Remove what a killed run left in the output folders (dead processes' staging).

        A run killed between publishing a stage's manifest and removing its emptied
        staging folder leaves that folder behind in a stage that is now fresh and will
        not run again, so leftovers are cleared here, not only when a stage runs.
        """
        for folder in {self.out_root, *(self.output_folder(s.name) for s in self.stages)}:
            try:
                remove_leftovers(folder)
            except OSError:  # a read-only output is still readable; nothing to tidy then
                pass

    def _claim(self) -> None:
        """Check every folder the stages write before the first one runs, and mark the root.

        A non-empty folder that is not hesspipe's, another kind of hesspipe output, a
        file in the way or a folder that cannot be written fails here, before any work.
        """
        mark_output_dir(self.out_root, ROOT_KIND)
        for stage in self.stages:
            target = self.output_folder(stage.name)
            check_output_dir(target, self._kind(stage))
            if target.is_dir():
                # Marked now: a folder an older hesspipe wrote is recognised by its manifest,
                # which the stage removes when it starts.
                mark_output_dir(target, self._kind(stage))
            if self.folder(stage.name).resolve() != target:
                check_output_dir(self.folder(stage.name), stage.name)

    def _kind(self, stage: Stage) -> str:
        """The kind of output a stage's folder holds: its name, or "run" for the root."""
        return ROOT_KIND if self.output_folder(stage.name) == self.out_root.resolve() else stage.name

    def _execute(self, stage: Stage, parts: dict) -> float:
        folder = self.folder(stage.name)
        target = self.output_folder(stage.name)
        # The manifest is published with the outputs (last), at its place relative to them.
        manifest_rel = Path(os.path.relpath(folder.resolve(), target)) / MANIFEST
        if ".." in manifest_rel.parts:
            raise HesspipeError(f"pipeline: stage '{stage.name}': its folder must be inside the "
                                "output folder")
        # Invalidate first: from here until the new manifest lands the stage is not fresh.
        (folder / MANIFEST).unlink(missing_ok=True)
        start = time.perf_counter()
        section = self.config.get(stage.name, {})
        # staged_output publishes the folder whole: outputs of an earlier run that this
        # run did not produce are removed, so they are never mistaken for new ones.
        with staged_output(target, kind=self._kind(stage)) as staging:
            ctx = StageContext(name=stage.name, section=dict(section), config=self.config,
                               seed=self.seed, out_dir=staging,
                               upstream={n: self.output_folder(n) for n in stage.needs},
                               source=self.source)
            stage.run(ctx)
            inner = _read_manifest(staging)
            outputs = _output_hashes(staging)
            wall = time.perf_counter() - start
            record = {
                "stage": stage.name,
                "description": stage.description,
                "fingerprint": hashlib.sha256(_canonical(parts).encode()).hexdigest(),
                "fingerprint_parts": parts,
                "config": section,
                "seed": self.seed,
                "config_file": self.source,
                "versions": versions(),
                "wall_time_s": round(wall, 3),
                "output_folder": str(target),
                "outputs": outputs,
                # A stage's own manifest.json, if it writes one, is folded in here.
                "stage_manifest": inner,
            }
            write_json(staging / manifest_rel, record)
        return wall


def _resolve(ref: str, source: str, field: str) -> Callable:
    from importlib import import_module

    module, _, attr = ref.partition(":")
    try:
        return getattr(import_module(module), attr)
    except (ImportError, AttributeError):
        raise HesspipeError(f"{source}: field '{field}': expected 'module:function' naming an "
                            f"importable function, got {ref!r}") from None


def load_stages(path) -> list[Stage]:
    """Read the declared stages (``pipeline/stages.toml``).

    Each ``[[stage]]`` table has ``name``, ``needs`` (list of stage names),
    ``run`` (``"module:function"`` taking a :class:`StageContext`),
    optionally ``inputs`` (``"module:function"`` returning external input
    paths) and ``description``; ``outputs`` documents the files it writes.

    Parameters
    ----------
    path : str or Path
        The stages file.
    """

    data = load_toml(path)
    tables = data.get("stage")
    if not isinstance(tables, list) or not tables:
        raise HesspipeError(f"{path}: field 'stage': expected one or more [[stage]] tables")
    stages = []
    for i, table in enumerate(tables):
        f = Fields(table, path, f"stage[{i}]")
        name = f.string("name")
        needs = table.get("needs", [])
        f.used.add("needs")
        if not isinstance(needs, list) or not all(isinstance(n, str) for n in needs):
            raise f.error("needs", "a list of stage names", needs)
        run = _resolve(f.string("run"), str(path), f"stage[{i}].run")
        inputs_ref = f.string("inputs", "")
        inputs = _resolve(inputs_ref, str(path), f"stage[{i}].inputs") if inputs_ref else (
            lambda section, config: [])
        description = f.string("description", "")
        folder = f.string("folder", "")
        f.used.add("outputs")
        f.reject_unknown()
        stages.append(Stage(name, tuple(needs), run, inputs, description, folder))
    return stages

"""The concrete pipeline stages: each wires one library call into the engine.

The stages are declared in ``pipeline/stages.toml``; each ``run`` entry
names one of the functions below, which receive a
:class:`~hesspipe.pipeline.engine.StageContext`. Heavy imports stay inside the
functions so that ``hesspipe status`` and an up-to-date ``hesspipe run``
start quickly.
"""

from __future__ import annotations

# Each stage function imports its stage's package when it runs, so that `hesspipe status`
# and a pipeline of some stages load only what they need.
import json
from pathlib import Path

from ..core.config import Fields, aircraft_file, data_dir, load_toml, merge
from ..core.errors import HesspipeError
from .engine import Pipeline, load_stages

SECTIONS = ("flight", "plants", "analytic", "pilots", "diagnose", "report")


def load_config(path=None, *, aircraft=None, seed=None) -> tuple[dict, str]:
    """Load ``pipeline/default.toml`` merged with the user's file and overrides.

    Relative paths in the user's file (``[pilots] data`` and ``plants``, ``[diagnose] run``)
    are resolved against its folder.

    Parameters
    ----------
    path : str or Path, optional
        The user's TOML file (None: the defaults only). Its top level may hold
        ``seed`` and the tables of :data:`SECTIONS`.
    aircraft : str, optional
        Overrides ``[flight] aircraft``.
    seed : int, optional
        Overrides the top-level ``seed`` (0 <= seed <= ``MAX_SEED``).

    Returns
    -------
    config : dict
        The merged configuration.
    source : str
        A name for it (the user's file, else the default file), for messages
        and manifests.

    Raises
    ------
    HesspipeError
        Unknown section, bad seed, a section that is not a table, or a
        pipeline-level name or path (:data:`PATH_FIELDS`) that is not a string.
    """
    default_path = data_dir("pipeline") / "default.toml"
    config = load_toml(default_path)
    source = str(default_path)
    if path:
        user = load_toml(path)
        source = str(path)
        unknown = sorted(set(user) - set(SECTIONS) - {"seed"})
        if unknown:
            raise HesspipeError(f"{path}: field '{unknown[0]}': unknown section; expected seed or one of "
                                f"{', '.join(SECTIONS)}")
        for section, key in (("pilots", "data"), ("pilots", "plants"), ("diagnose", "run")):
            value = user.get(section, {}).get(key) if isinstance(user.get(section), dict) else None
            if isinstance(value, str) and value and not Path(value).is_absolute():
                user[section][key] = str((Path(path).parent / value).resolve())
        config = merge(config, user)
    if aircraft is not None:
        config = merge(config, {"flight": {"aircraft": aircraft}})
    if seed is not None:
        config["seed"] = seed
    from ..core.seeds import MAX_SEED

    Fields(config, source).integer("seed", 0, min=0, max=MAX_SEED)
    for name in SECTIONS:
        if not isinstance(config.get(name, {}), dict):
            raise HesspipeError(f"{source}: field '{name}': expected a table")
    # The pipeline-level names and paths are read before any stage's own check (for the
    # fingerprints, also by `status`), so their types are checked here.
    for section, key in PATH_FIELDS:
        value = config[section].get(key) if section in config else None
        if value is not None and not isinstance(value, str):
            raise Fields(config[section], source, section).error(key, "a string", value)
    return config, source


#: (table, field) of the names and paths the pipeline itself reads.
PATH_FIELDS = (("flight", "aircraft"), ("analytic", "model"), ("pilots", "data"), ("pilots", "plants"),
               ("diagnose", "run"), ("diagnose", "model"))


def _in_field(source: str, field: str, check, value):
    """Return ``check(value)``; re-raise its error as one naming `source` and `field`."""
    try:
        return check(value)
    except HesspipeError as exc:
        raise HesspipeError(f"{source}: field '{field}': {exc}") from None


def validate(config: dict, source: str) -> None:
    """Check every stage's table before anything runs, so a typo in the last stage's
    table fails in a second, not after the first stages have run.

    Parameters
    ----------
    config : dict
        The configuration from :func:`load_config`.
    source : str
        Its name, used in error messages.

    Raises
    ------
    HesspipeError
        Naming `source` and the first bad field.
    """
    from ..core.formats import read_file_runs, read_plants
    from ..diagnose.settings import DiagnoseConfig
    from ..diagnose.workflow import resolve_candidates
    from ..pilot.hess import model_from_name
    from ..pilots.batch import check_scheduler_address
    from ..pilots.compare import PilotsConfig, list_runs
    from ..pilots.verdict import pilot_groups
    from ..plants.analytic import load_analytic
    from ..plants.settings import AnalyticConfig, PlantsConfig

    flight_settings(config, source)
    PlantsConfig.from_table(config.get("plants", {}), source)
    analytic = AnalyticConfig.from_table(config.get("analytic", {}), source)
    _in_field(source, "analytic.model", load_analytic, analytic.model)
    pilots = PilotsConfig.from_table(config.get("pilots", {}), source)
    if pilots.scheduler:
        check_scheduler_address(pilots.scheduler, f"{source}: field 'pilots.scheduler'")
    # The data's own files are read by the pilots stage, after flight and plants have run:
    # a path that is not there (or plants that do not read) fails here, before any of them.
    if pilots.data and not Path(pilots.data).exists():
        raise HesspipeError(f"{source}: field 'pilots.data': expected a folder or file of runs, "
                            f"{pilots.data} not found")
    if pilots.plants:
        _in_field(source, "pilots.plants", read_plants, pilots.plants)   # as the stages read it
    runs = _in_field(source, "pilots.data", list_runs, pilots.data) if pilots.data else []   # none there
    if runs and pilots.pilot_id:
        # A pattern that misses a file name failed after flight, plants and analytic had run.
        _in_field(source, "pilots.pilot_id", lambda pattern: pilot_groups([p.stem for p in runs], pattern),
                  pilots.pilot_id)
    if runs and (pilots.columns or pilots.sample_rate):
        # The data's first run read as the pilots stage reads it: a misspelt column name fails
        # here, not after flight and plants (any other fault of that file would fail the
        # stage too).
        first = runs[0]
        _in_field(source, "pilots.columns" if pilots.columns else "pilots.sample_rate",
                  lambda c: read_file_runs(first, columns=c, resample=pilots.resample,
                                           sample_rate=pilots.sample_rate), pilots.columns)
    table, (run, model) = _split(config.get("diagnose", {}), "run", "model")
    diagnose = DiagnoseConfig.from_table(table, source)
    _in_field(source, "diagnose.model", model_from_name, model or "original")
    _in_field(source, "diagnose.candidates",
              lambda c: resolve_candidates(model_from_name(model or "original"), c, diagnose),
              diagnose.candidates)
    if run and not Path(run).is_file():
        raise HesspipeError(f"{source}: field 'diagnose.run': expected a run CSV file, {run} not found")
    Fields(config.get("report", {}), source, "report").reject_unknown()


def flight_settings(config: dict, source: str) -> tuple:
    """The aircraft and the settings of a configuration's ``[flight]`` table, both checked.

    Read as the flight stage reads them, for ``hesspipe run`` (:func:`validate`) and for the
    commands that take the same file (``flight --config``, ``fly-pilot --config``).

    Parameters
    ----------
    config : dict
        The configuration from :func:`load_config`.
    source : str
        Its name, used in error messages.

    Returns
    -------
    aircraft : str
        ``[flight] aircraft`` (default ``"737"``).
    settings : FlightConfig
        The rest of the table.

    Raises
    ------
    HesspipeError
        Naming `source` and the bad field (an unknown aircraft among them).
    """
    from ..flight.aircraft import DEFAULT_AIRCRAFT, load_aircraft
    from ..flight.approach import FlightConfig

    table, (aircraft,) = _split(config.get("flight", {}), "aircraft")
    settings = FlightConfig.from_table(table, source)
    _in_field(source, "flight.aircraft", load_aircraft, aircraft or DEFAULT_AIRCRAFT)
    return aircraft or DEFAULT_AIRCRAFT, settings


def build_pipeline(config_path=None, out="hesspipe-out", *, aircraft=None, seed=None) -> Pipeline:
    """The pipeline of ``pipeline/stages.toml`` on the given configuration.

    Parameters
    ----------
    config_path : str or Path, optional
        The user's TOML file (None: the defaults only); see :func:`load_config`.
    out : str or Path
        Output root folder.
    aircraft : str, optional
        Overrides ``[flight] aircraft``.
    seed : int, optional
        Overrides the configuration's ``seed``.

    Returns
    -------
    Pipeline
    """
    config, source = load_config(config_path, aircraft=aircraft, seed=seed)
    data = config.get("pilots", {}).get("data")
    if isinstance(data, str) and data and Path(data).resolve() == Path(out).resolve():
        raise HesspipeError(f"{source}: field 'pilots.data': {data} is the output folder too; expected the "
                            "outputs in a folder of their own (the report and the stages' folders beside "
                            "the runs)")
    return Pipeline(load_stages(data_dir("pipeline") / "stages.toml"), config, out, source)


def _split(section: dict, *keys: str) -> tuple[dict, list]:
    """Remove the pipeline-level `keys` from a stage table before the stage's own parser sees it."""
    rest = dict(section)
    return rest, [rest.pop(k, None) for k in keys]


# -- flight -------------------------------------------------------------------------------

def flight_inputs(section: dict, config: dict) -> list:
    """External input of the flight stage: its aircraft file, if it exists.

    Parameters
    ----------
    section : dict
        The stage's configuration table.
    config : dict
        The whole configuration (unused).

    Returns
    -------
    list of Path
        ``[aircraft_file(name)]`` of ``section["aircraft"]`` (default ``"737"``),
        or empty when no such file exists (the stage's check reports it).
    """
    path = aircraft_file(section.get("aircraft", "737"))
    return [path] if path.exists() else []


def flight(ctx) -> None:
    """Stage one: :func:`hesspipe.flight.approach.fly` with the ``[flight]`` table.

    Writes ``trim.json``, ``wind.csv``, ``aileron.csv`` and their figures into
    ``ctx.out_dir``; the aircraft defaults to ``"737"``.

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.
    """
    from ..flight.approach import FlightConfig, fly
    from ..viz.flight import draw_flight

    table, (aircraft,) = _split(ctx.section, "aircraft")
    fly(aircraft or "737", FlightConfig.from_table(table, ctx.source), ctx.out_dir, ctx.seed, draw=draw_flight)


# -- plants -------------------------------------------------------------------------------

def plants(ctx) -> None:
    """Stage two: :func:`hesspipe.plants.fit.fit_plants` on the flight stage's records.

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.
    """
    from ..plants.fit import fit_plants
    from ..plants.settings import PlantsConfig
    from ..viz.plants import draw_plants

    fit_plants(ctx.upstream["flight"], ctx.out_dir, PlantsConfig.from_table(ctx.section, ctx.source),
               draw=draw_plants)


def analytic_inputs(section: dict, config: dict) -> list:
    """External input of the analytic stage: its aircraft file, if it exists.

    Parameters
    ----------
    section : dict
        The stage's configuration table.
    config : dict
        The whole configuration (unused).

    Returns
    -------
    list of Path
        ``[aircraft_file(name)]`` of ``section["model"]`` (default ``"roskam"``),
        or empty when no such file exists.
    """
    path = aircraft_file(section.get("model", "roskam"))
    return [path] if path.exists() else []


def analytic(ctx) -> None:
    """The paper's analytic aircraft as plants: :func:`hesspipe.plants.fit.analytic_plants`.

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.
    """
    from ..plants.fit import analytic_plants
    from ..plants.settings import AnalyticConfig
    from ..viz.plants import draw_analytic

    config = AnalyticConfig.from_table(ctx.section, ctx.source)
    analytic_plants(config.model, ctx.out_dir, config, draw=draw_analytic)


# -- pilots -------------------------------------------------------------------------------

def pilots_inputs(section: dict, config: dict) -> list:
    """External inputs of the pilots stage: the ``[pilots] data`` folder and ``plants`` file, if set.

    Parameters
    ----------
    section : dict
        The stage's configuration table.
    config : dict
        The whole configuration (unused).

    Returns
    -------
    list of Path
        The run files the stage reads from ``data`` (a folder's, as
        :func:`hesspipe.pilots.compare.list_runs` lists them: not a notes file, a
        ``.DS_Store`` or an output folder beside them) and ``Path(plants)``; empty for the
        synthetic cohort (``data`` unset).
    """
    # The light listing, not hesspipe.pilots.compare: an up-to-date run computes this
    # fingerprint and nothing else, and the readers' imports were most of its 4 s.
    from ..core._listing import list_runs

    data, plants = (section.get(k) for k in ("data", "plants"))
    runs = list_runs(data) if isinstance(data, str) and data and Path(data).exists() else (
        [Path(data)] if isinstance(data, str) and data else [])
    return runs + ([Path(plants)] if isinstance(plants, str) and plants else [])


BUILT_IN_DISPLAY = "compensatory"
"""The display of the pilots stage's built-in cohort (JSBSim-flown or frequency-domain): its
model pilots see the error e = r - y and nothing else. Where the stage makes the cohort and the
table does not set ``display``, the pilots and diagnose stages judge it on this display, not on
the default ``either`` meant for recordings whose display is not known: the pursuit fits would
only look for a feedforward the pilots were not built with (they were half of ``hesspipe
run``'s CPU)."""


def _built_in_display(ctx, table: str, config):
    # `config` (a stage's frozen settings) on BUILT_IN_DISPLAY where the pilots stage makes the
    # cohort (no [pilots] data), the run judged is the cohort's (no [diagnose] run) and the
    # stage's table leaves the display unset.
    from dataclasses import replace

    own = ctx.config.get(table, {})
    if ctx.config.get("pilots", {}).get("data") or (table == "diagnose" and own.get("run")) or "display" in own:
        return config
    return replace(config, display=BUILT_IN_DISPLAY)


def _study_plants(ctx):
    """The plants the pilots' runs are identified and diagnosed with: ``[pilots] plants``
    (a data folder's own task), else the plants stage's."""
    from ..core.formats import read_plants

    own = ctx.config.get("pilots", {}).get("plants")
    return read_plants(own if isinstance(own, str) and own else ctx.upstream["plants"] / "plants.json")


def pilots(ctx) -> None:
    """Stage three: identify every pilot run with each model configuration.

    Without ``[pilots] data`` a SYNTHETIC cohort is made (flown in JSBSim with
    ``simulator = "jsbsim"``, else the frequency-domain model), then
    :func:`hesspipe.pilots.compare.run_study` writes the comparison.

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.

    Raises
    ------
    HesspipeError
        If any run failed, naming each.
    """
    from ..pilots.compare import PilotsConfig, run_study
    from ..viz.compare import draw_comparison

    config = _built_in_display(ctx, "pilots", PilotsConfig.from_table(ctx.section, ctx.source))
    plants_ = _study_plants(ctx)
    if not config.data and config.simulator == "jsbsim":
        from ..pilots.flown import fly_pipeline_cohort

        config = fly_pipeline_cohort(config, plants_, ctx)
    result = run_study(config, plants_, ctx.out_dir, seed=ctx.seed, progress=False, draw=draw_comparison)
    if not result.ok:
        failed = ", ".join(f"{f.id} ({_config_terms(f.error)})" for f in result.failures)
        raise HesspipeError(f"pilots: {len(result.failures)} run(s) failed: {failed}")


def _config_terms(message: str) -> str:
    """The library's setting names as the configuration spells them ([pilots] resample, columns)."""
    import re

    message = message.replace("set resample", "set [pilots] resample = true")
    message = message.replace("(sample_rate)", "([pilots] sample_rate = HZ)")
    return re.sub(r"with columns (\S+)", r'with [pilots] columns = "\1"', message)


# -- diagnose -----------------------------------------------------------------------------

def _diagnose_run(ctx) -> tuple[Path, str]:
    """The file of the run to diagnose and the run's source: ``[diagnose] run``, or the first
    run the pilots stage compared (``PATH#k`` in a file holding several).

    The run is taken by id from the pilots stage's ``comparison.json`` (one of its
    outputs, so in this stage's fingerprint), never by listing a folder: a file put
    beside the cohort by hand is not a pilot of the study.
    """
    chosen = ctx.section.get("run", "")
    if chosen:
        return Path(chosen), str(chosen)
    folder = ctx.upstream["pilots"]
    try:
        record = json.loads((folder / "comparison.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        record = None
    pilots = record.get("pilots") if isinstance(record, dict) else None
    if not pilots:
        raise HesspipeError(f"{folder / 'comparison.json'}: the pilots stage compared no runs; "
                            "set [diagnose] run = \"FILE\"")
    source = Path(pilots[0]["source"])
    source = source if source.is_absolute() else folder / source
    path = source
    while not path.is_file() and "#" in path.name:   # PATH#k, PATH#PERSON#RUN: a run of a file
        path = path.with_name(path.name.rpartition("#")[0])
    return (path if path.is_file() else source), str(source)


def diagnose(ctx) -> None:
    """Diagnose one run: ``diagnosis.json``, ``diagnosis.md`` and ``diagnosis.png``.

    The run is ``[diagnose] run``, else the first run of the pilots stage's
    ``comparison.json``; it is read with ``[pilots] columns``/``resample`` and diagnosed
    with the pilots' plants (``[pilots] plants``, else the plants stage's).

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.
    """
    from ..core.formats import read_file_runs
    from ..core.io import write_json, write_text
    from ..core.paper import WELCH_SEGMENT
    from ..diagnose.report import format_report
    from ..diagnose.settings import DiagnoseConfig
    from ..diagnose.workflow import diagnose as run_diagnose
    from ..viz.diagnose import plot_diagnosis

    table, (_, model) = _split(ctx.section, "run", "model")
    config = _built_in_display(ctx, "diagnose", DiagnoseConfig.from_table(table, ctx.source))
    pilots_cfg = ctx.config.get("pilots", {})  # the runs' format settings ([pilots] columns, resample)
    path, source = _diagnose_run(ctx)
    try:
        runs = read_file_runs(path, min_samples=WELCH_SEGMENT, columns=pilots_cfg.get("columns") or None,
                              resample=bool(pilots_cfg.get("resample", False)),
                              sample_rate=pilots_cfg.get("sample_rate"))
        # A file holding several runs: the one the pilots stage compared first, else its first.
        run = next((r for r in runs if r.source == source), runs[0])
    except HesspipeError as exc:
        raise HesspipeError(_config_terms(str(exc))) from None
    result = run_diagnose(run, _study_plants(ctx), model=model or "original", seed=ctx.seed, config=config)
    write_json(ctx.out_dir / "diagnosis.json", result.to_dict())
    write_text(ctx.out_dir / "diagnosis.md", format_report(result) + "\n")
    plot_diagnosis(result, ctx.out_dir / "diagnosis.png")


def diagnose_inputs(section: dict, config: dict) -> list:
    """External inputs of the diagnose stage: the ``[diagnose] run`` file and the
    ``[pilots] plants`` file, if set.

    Parameters
    ----------
    section : dict
        The stage's configuration table.
    config : dict
        The whole configuration (its ``[pilots] plants``).

    Returns
    -------
    list of Path
        ``Path(run)`` and ``Path(plants)`` where set; empty when the run comes from the
        pilots stage and the plants from the plants stage.
    """
    run, own = section.get("run"), config.get("pilots", {}).get("plants")
    return [Path(x) for x in (run, own) if isinstance(x, str) and x]


# -- report -------------------------------------------------------------------------------

def report(ctx) -> None:
    """The final stage: ``report.md`` from every upstream stage's outputs.

    Parameters
    ----------
    ctx : StageContext
        The stage's table (``ctx.section``), seed, staging folder
        (``ctx.out_dir``) and upstream folders.
    """
    from ..core.io import write_text
    from .report import build_report

    Fields(ctx.section, ctx.source, "report").reject_unknown()  # nothing to configure yet
    root = ctx.out_dir.parent
    text = build_report(ctx.upstream, root, config_file=ctx.source, seed=ctx.seed)
    write_text(ctx.out_dir / "report.md", text)

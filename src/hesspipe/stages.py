"""The concrete pipeline stages: each wires one library call into the engine.

The stages are declared in ``pipeline/stages.toml``; each ``run`` entry
names one of the functions below, which receive a
:class:`~hesspipe.pipeline.StageContext`. Heavy imports stay inside the
functions so that ``hesspipe status`` and an up-to-date ``hesspipe run``
start quickly.
"""

from __future__ import annotations

from pathlib import Path

from .config import Fields, aircraft_file, data_dir, load_toml, merge
from .errors import HesspipeError
from .pipeline import Pipeline, load_stages

SECTIONS = ("flight", "plants", "analytic", "pilots", "diagnose", "report")


def load_config(path=None, *, aircraft=None, seed=None) -> tuple[dict, str]:
    """Load ``pipeline/default.toml`` merged with the user's file and overrides.

    Returns the configuration and a name for it (for messages/manifests).
    Relative paths in the user's file are resolved against its folder.
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
        for section, key in (("pilots", "data"), ("diagnose", "run")):
            value = user.get(section, {}).get(key) if isinstance(user.get(section), dict) else None
            if isinstance(value, str) and value and not Path(value).is_absolute():
                user[section][key] = str((Path(path).parent / value).resolve())
        config = merge(config, user)
    if aircraft is not None:
        config = merge(config, {"flight": {"aircraft": aircraft}})
    if seed is not None:
        config["seed"] = seed
    Fields(config, source).integer("seed", 0, min=0)
    for name in SECTIONS:
        if not isinstance(config.get(name, {}), dict):
            raise HesspipeError(f"{source}: field '{name}': expected a table")
    return config, source


def validate(config: dict, source: str) -> None:
    """Check every stage's table before anything runs, so a typo in the last stage's
    table fails in a second, not after the first stages have run."""
    from .compare import PilotsConfig
    from .discrepancy import DiagnoseConfig
    from .flight import FlightConfig
    from .plants import AnalyticConfig, PlantsConfig

    FlightConfig.from_table(_split(config.get("flight", {}), "aircraft")[0], source)
    PlantsConfig.from_table(config.get("plants", {}), source)
    AnalyticConfig.from_table(config.get("analytic", {}), source)
    PilotsConfig.from_table(config.get("pilots", {}), source)
    DiagnoseConfig.from_table(_split(config.get("diagnose", {}), "run", "model")[0], source)
    Fields(config.get("report", {}), source, "report").reject_unknown()


def build_pipeline(config_path=None, out="hesspipe-out", *, aircraft=None, seed=None) -> Pipeline:
    """The pipeline of ``pipeline/stages.toml`` on the given configuration."""
    config, source = load_config(config_path, aircraft=aircraft, seed=seed)
    return Pipeline(load_stages(data_dir("pipeline") / "stages.toml"), config, out, source)


def _split(section: dict, *keys: str) -> tuple[dict, list]:
    """Remove the pipeline-level `keys` from a stage table before the stage's own parser sees it."""
    rest = dict(section)
    return rest, [rest.pop(k, None) for k in keys]


# -- flight -------------------------------------------------------------------------------

def flight_inputs(section: dict, config: dict) -> list:
    path = aircraft_file(section.get("aircraft", "737"))
    return [path] if path.exists() else []


def flight(ctx) -> None:
    from .flight import FlightConfig, fly

    table, (aircraft,) = _split(ctx.section, "aircraft")
    fly(aircraft or "737", FlightConfig.from_table(table, ctx.source), ctx.out_dir, ctx.seed)


# -- plants -------------------------------------------------------------------------------

def plants(ctx) -> None:
    from .plants import PlantsConfig, fit_plants

    fit_plants(ctx.upstream["flight"], ctx.out_dir, PlantsConfig.from_table(ctx.section, ctx.source))


def analytic_inputs(section: dict, config: dict) -> list:
    path = aircraft_file(section.get("model", "roskam"))
    return [path] if path.exists() else []


def analytic(ctx) -> None:
    from .plants import AnalyticConfig, analytic_plants

    config = AnalyticConfig.from_table(ctx.section, ctx.source)
    analytic_plants(config.model, ctx.out_dir, config)


# -- pilots -------------------------------------------------------------------------------

def pilots_inputs(section: dict, config: dict) -> list:
    data = section.get("data")
    return [Path(data)] if isinstance(data, str) and data else []


def pilots(ctx) -> None:
    from .compare import PilotsConfig, run_study
    from .formats import read_plants

    config = PilotsConfig.from_table(ctx.section, ctx.source)
    plants_ = read_plants(ctx.upstream["plants"] / "plants.json")
    if not config.data and config.simulator == "jsbsim":
        from .pilotflight import fly_pipeline_cohort

        config = fly_pipeline_cohort(config, plants_, ctx)
    result = run_study(config, plants_, ctx.out_dir, seed=ctx.seed, progress=False)
    if not result.ok:
        failed = ", ".join(f"{f.id} ({f.error})" for f in result.failures)
        raise HesspipeError(f"pilots: {len(result.failures)} run(s) failed: {failed}")


# -- diagnose -----------------------------------------------------------------------------

def _diagnose_run(ctx) -> Path:
    """The run to diagnose: ``[diagnose] run`` or the first run of the pilots stage."""
    chosen = ctx.section.get("run", "")
    if chosen:
        return Path(chosen)
    pilots_cfg = ctx.config.get("pilots", {})
    folder = Path(pilots_cfg["data"]) if pilots_cfg.get("data") else ctx.upstream["pilots"] / "cohort"
    runs = sorted(p for p in folder.glob("*.csv"))
    if not runs:
        raise HesspipeError(f"{folder}: no *.csv runs to diagnose; set [diagnose] run = \"FILE\"")
    return runs[0]


def diagnose(ctx) -> None:
    from .discrepancy import SEGMENT, DiagnoseConfig, diagnose as run_diagnose, format_report
    from .formats import read_plants, read_run
    from .io import write_json, write_text
    from .viz.diagnose import plot_diagnosis

    table, (_, model) = _split(ctx.section, "run", "model")
    config = DiagnoseConfig.from_table(table, ctx.source)
    run = read_run(_diagnose_run(ctx), min_samples=SEGMENT)
    result = run_diagnose(run, read_plants(ctx.upstream["plants"] / "plants.json"),
                          model=model or "original", seed=ctx.seed, config=config)
    write_json(ctx.out_dir / "diagnosis.json", result.to_dict())
    write_text(ctx.out_dir / "diagnosis.md", format_report(result) + "\n")
    plot_diagnosis(result, ctx.out_dir / "diagnosis.png")


def diagnose_inputs(section: dict, config: dict) -> list:
    run = section.get("run")
    return [Path(run)] if isinstance(run, str) and run else []


# -- report -------------------------------------------------------------------------------

def report(ctx) -> None:
    from .io import write_text
    from .report import build_report

    Fields(ctx.section, ctx.source, "report").reject_unknown()  # nothing to configure yet
    root = ctx.out_dir.parent
    text = build_report(ctx.upstream, root, config_file=ctx.source, seed=ctx.seed)
    write_text(ctx.out_dir / "report.md", text)

"""The concrete pipeline stages: each wires one library call into the engine.

The stages are declared in ``pipeline/stages.toml``; each ``run`` entry
names one of the functions below, which receive a
:class:`~hesspipe.pipeline.StageContext`. Heavy imports stay inside the
functions so that ``hesspipe status`` and an up-to-date ``hesspipe run``
start quickly.
"""

from __future__ import annotations

from pathlib import Path

from .config import Fields, data_dir, load_toml, merge
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
        data = user.get("pilots", {}).get("data") if isinstance(user.get("pilots"), dict) else None
        if isinstance(data, str) and data and not Path(data).is_absolute():
            user["pilots"]["data"] = str((Path(path).parent / data).resolve())
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


def build_pipeline(config_path=None, out="hesspipe-out", *, aircraft=None, seed=None) -> Pipeline:
    """The pipeline of ``pipeline/stages.toml`` on the given configuration."""
    config, source = load_config(config_path, aircraft=aircraft, seed=seed)
    return Pipeline(load_stages(data_dir("pipeline") / "stages.toml"), config, out, source)


def _split(section: dict, *keys: str) -> tuple[dict, list]:
    """Remove the pipeline-level `keys` from a stage table before the stage's own parser sees it."""
    rest = dict(section)
    return rest, [rest.pop(k, None) for k in keys]


def _aircraft_file(name: str) -> Path:
    return data_dir("aircraft") / f"{name}.toml"


# -- flight -------------------------------------------------------------------------------

def flight_inputs(section: dict, config: dict) -> list:
    path = _aircraft_file(section.get("aircraft", "737"))
    return [path] if path.exists() else []


def flight(ctx) -> None:
    from .flight import FlightConfig, fly

    table, (aircraft,) = _split(ctx.section, "aircraft")
    fly(aircraft or "737", FlightConfig.from_table(table, ctx.source), ctx.out_dir, ctx.seed)

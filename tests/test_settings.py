"""Each stage's settings: one frozen dataclass, validated on construction, that TOML,
the command line and Python all build (hesspipe.core.config.Settings)."""

from __future__ import annotations

import dataclasses

import pytest

from hesspipe.core.config import FieldError, Settings
from hesspipe.core.errors import HesspipeError
from hesspipe.diagnose.settings import DiagnoseConfig
from hesspipe.flight.approach import FlightConfig
from hesspipe.pilots.settings import CompareSettings, PilotsConfig
from hesspipe.plants.settings import AnalyticConfig, PlantsConfig

# (class, table, a bad field, its bad value, what the message says is expected)
BAD = [
    (FlightConfig, "flight", "duration_s", -1.0, "a number > 0"),
    (FlightConfig, "flight", "record_every", 1.5, "an integer >= 1"),
    (PlantsConfig, "plants", "criterion", "aicc", "one of 'aic', 'bic', 'fpe'"),
    (PlantsConfig, "plants", "check_band_hz", (2.0, 1.0), "[low, high] with 0 < low < high"),
    (AnalyticConfig, "analytic", "control", "half", "one of 'rolling', 'full'"),
    (PilotsConfig, "pilots", "optimizer", "newton", "one of 'apid', 'scipy', 'differential_evolution'"),
    (PilotsConfig, "pilots", "effects", ("warp",), "unknown effect 'warp'"),
    (PilotsConfig, "pilots", "n", 0, "an integer >= 1"),
    (CompareSettings, None, "restarts", 0, "an integer >= 1"),
    (CompareSettings, None, "seed", -1, "an integer >= 0"),
    (DiagnoseConfig, "diagnose", "alpha", 5, "a number > 0 and <= 0.5"),
    (DiagnoseConfig, "diagnose", "weighting", "bogus", "one of 'random-share', 'uniform'"),
]


@pytest.mark.parametrize("cls, table, field, value, expected", BAD,
                         ids=[f"{c.__name__}.{f}" for c, _, f, _, _ in BAD])
def test_a_bad_value_from_python_names_the_field(cls, table, field, value, expected):
    with pytest.raises(HesspipeError) as info:
        cls(**{field: value})
    message = str(info.value)
    assert message.startswith(f"{cls.__name__}: field '{field}': ") and expected in message
    assert "--" not in message and "\n" not in message  # the library's terms, one line
    assert isinstance(info.value, FieldError) and info.value.field == field
    # dataclasses.replace (how the command line sets its flags) runs the same checks
    with pytest.raises(FieldError, match=f"field '{field}'"):
        dataclasses.replace(cls(), **{field: value})


@pytest.mark.parametrize("cls, table, field, value, expected", [b for b in BAD if b[1]],
                         ids=[f"{c.__name__}.{f}" for c, t, f, _, _ in BAD if t])
def test_the_same_bad_value_from_toml_names_the_file_and_table(cls, table, field, value, expected):
    toml_value = list(value) if isinstance(value, tuple) else value
    with pytest.raises(HesspipeError) as info:
        cls.from_table({field: toml_value}, "pipeline/x.toml")
    message = str(info.value)
    assert message.startswith(f"pipeline/x.toml: field '{table}.{field}': ") and expected in message


GOOD = [
    (FlightConfig, {"duration_s": 30, "record_every": 2, "record_terrain_ft": 100}),
    (PlantsConfig, {"decimate": 4, "check_band_hz": [0.02, 1.5], "slow_roots": "reflect"}),
    (AnalyticConfig, {"control": "full", "disturbance": "rolling"}),
    (PilotsConfig, {"n": 3, "band_hz": [0, 4], "effects": ["motion_feedback", "remnant"], "seed": 7,
                    "km_fixed": 0.2, "criterion": "paper", "optimizer": "scipy"}),
    (DiagnoseConfig, {"alpha": 0.05, "free": ["Ke", "K1"], "gain_levels": [0.3, 0.7],
                      "band_edges_hz": [0, 1, 5], "candidates": ["extra_delay"]}),
]


@pytest.mark.parametrize("cls, table", GOOD, ids=[c.__name__ for c, _ in GOOD])
def test_toml_and_python_build_equal_objects(cls, table):
    # Python spells lists as lists or tuples and numbers as int or float; all normalise alike.
    from_toml = cls.from_table(table, "x.toml")
    from_python = cls(**table)
    assert from_toml == from_python and hash(from_toml) == hash(from_python)
    assert from_toml != cls()  # the table was not ignored
    assert cls.from_table({}, "x.toml") == cls()
    with pytest.raises(dataclasses.FrozenInstanceError):
        from_python.__setattr__(next(iter(table)), None)


@pytest.mark.parametrize("cls", [FlightConfig, PlantsConfig, AnalyticConfig, PilotsConfig, DiagnoseConfig])
def test_unknown_toml_keys_are_refused(cls):
    assert issubclass(cls, Settings)
    with pytest.raises(HesspipeError, match=r"^x.toml: field 't.typo': unknown field \(known here: "):
        cls.from_table({"typo": 1}, "x.toml", "t")


def test_pilots_table_and_compare_settings_share_one_set_of_checks():
    config = PilotsConfig(seed=None, restarts=3, band_hz=(0, 4), criterion="paper")
    settings = config.settings(seed=11)  # the pipeline's seed when the table has none
    assert settings == CompareSettings(seed=11, restarts=3, band=(0.0, 4.0), criterion="paper")
    assert PilotsConfig(seed=5).settings(seed=11).seed == 5
    for cls, band in ((PilotsConfig, "band_hz"), (CompareSettings, "band")):
        with pytest.raises(FieldError, match=rf"^{cls.__name__}: field '{band}': expected \[low, high\] Hz"):
            cls(**{band: (3.0, 1.0)})


def test_numpy_scalars_from_python_are_accepted():
    np = pytest.importorskip("numpy")
    assert PlantsConfig(decimate=np.int64(4), validation_fraction=np.float64(0.25)) == \
        PlantsConfig(decimate=4, validation_fraction=0.25)
    assert type(PlantsConfig(decimate=np.int64(4)).decimate) is int

"""pipeline/default.toml says what the code does: each table equals the code's defaults.

The file is what users copy and edit, so it must list the real defaults; these
tests fail when a default changes in one place and not the other.
"""

import pytest

from hesspipe.core.config import data_dir, load_toml
from hesspipe.pipeline.stages import SECTIONS, load_config

DEFAULT = data_dir("pipeline") / "default.toml"


@pytest.fixture(scope="module")
def table():
    return load_toml(DEFAULT)


def test_every_section_is_present(table):
    assert set(SECTIONS) - {"report"} <= set(table)


def test_flight(table):
    from hesspipe.flight.approach import FlightConfig

    section = {k: v for k, v in table["flight"].items() if k != "aircraft"}
    assert FlightConfig.from_table(section, DEFAULT) == FlightConfig.from_table({}, DEFAULT)
    assert table["flight"]["aircraft"] == "737"


def test_plants_and_analytic(table):
    from hesspipe.plants.settings import AnalyticConfig, PlantsConfig

    assert PlantsConfig.from_table(table["plants"], DEFAULT) == PlantsConfig()
    assert AnalyticConfig.from_table(table["analytic"], DEFAULT) == AnalyticConfig()


def test_pilots(table):
    from hesspipe.pilots.compare import PilotsConfig

    assert PilotsConfig.from_table(table["pilots"], DEFAULT) == PilotsConfig()
    # the default cohort flies JSBSim; the linear frequency-domain cohort is the option
    assert table["pilots"]["simulator"] == PilotsConfig().simulator == "jsbsim"
    assert PilotsConfig.from_table({"simulator": "fft"}, DEFAULT).simulator == "fft"


def test_diagnose(table):
    from hesspipe.diagnose.settings import DiagnoseConfig

    section = {k: v for k, v in table["diagnose"].items() if k not in ("run", "model")}
    assert DiagnoseConfig.from_table(section, DEFAULT) == DiagnoseConfig()


def test_user_file_merges_over_defaults(tmp_path):
    user = tmp_path / "mine.toml"
    user.write_text('seed = 7\n[pilots]\nn = 3\ndata = "runs"\n')
    config, source = load_config(user)
    assert source == str(user) and config["seed"] == 7 and config["pilots"]["n"] == 3
    assert config["pilots"]["data"] == str(tmp_path / "runs")  # relative to the file
    assert config["flight"]["aircraft"] == "737"  # untouched defaults stay


def test_the_built_in_cohort_is_judged_on_its_own_display(tmp_path):
    # The defaults leave `display` unset: the cohort the pilots stage makes (its pilots see the
    # error) is judged compensatory, a user's data or a chosen run on the settings' default
    # ("either", display not known), and a display the user sets is kept.
    from types import SimpleNamespace

    from hesspipe.core.choices import DEFAULT_DISPLAY
    from hesspipe.diagnose.settings import DiagnoseConfig
    from hesspipe.pilots.compare import PilotsConfig
    from hesspipe.pipeline.stages import BUILT_IN_DISPLAY, _built_in_display

    assert BUILT_IN_DISPLAY == "compensatory" != DEFAULT_DISPLAY

    def judged(user: str) -> tuple[str, str]:
        mine = tmp_path / "mine.toml"
        mine.write_text(user)
        config, _ = load_config(mine)
        ctx = SimpleNamespace(config=config)
        return (_built_in_display(ctx, "pilots", PilotsConfig()).display,
                _built_in_display(ctx, "diagnose", DiagnoseConfig()).display)

    assert "display" not in load_config()[0]["pilots"]
    assert judged("") == (BUILT_IN_DISPLAY, BUILT_IN_DISPLAY)
    assert judged('[pilots]\ndata = "runs"\n') == (DEFAULT_DISPLAY, DEFAULT_DISPLAY)
    assert judged('[diagnose]\nrun = "one.csv"\n') == (BUILT_IN_DISPLAY, DEFAULT_DISPLAY)
    assert judged('[pilots]\ndisplay = "either"\n') == (DEFAULT_DISPLAY, BUILT_IN_DISPLAY)

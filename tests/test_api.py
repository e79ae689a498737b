"""``import hesspipe`` gives the researcher's API, documented, without loading the heavy parts."""

from __future__ import annotations

import subprocess
import sys

import hesspipe

REQUIRED = ("read_run", "read_file_runs", "read_plants", "fly", "fit_plants", "PilotModel", "simulate", "identify",
            "estimate_frf", "average_frf", "compare_pilots", "compare_conditions", "diagnose", "DiagnoseConfig")


def test_api_names_are_exported_and_documented():
    for name in REQUIRED:
        assert name in hesspipe.__all__
        obj = getattr(hesspipe, name)
        doc = obj.__doc__ or ""
        assert doc.strip(), name
        if callable(obj) and not isinstance(obj, type):
            assert "Parameters" in doc, f"{name}: no numpydoc Parameters section"
    for name in hesspipe.__all__:
        getattr(hesspipe, name)  # every exported name resolves


def test_diagnose_is_the_stage_package_and_its_function():
    import hesspipe.diagnose.workflow as workflow  # importing a submodule keeps the package callable

    assert hesspipe.diagnose is sys.modules["hesspipe.diagnose"]
    assert hesspipe.diagnose.diagnose is workflow.diagnose
    from hesspipe.diagnose.examples import hidden_effect_run, validation_plants
    from hesspipe.diagnose.report import format_report
    from hesspipe.diagnose.settings import DiagnoseConfig

    plants = validation_plants()
    run = hidden_effect_run(plants, None, seed=3, duration=30.0)
    cfg = DiagnoseConfig(candidates=("remnant",), grid=3, starts=1)
    a = hesspipe.diagnose(run, plants, config=cfg)
    b = workflow.diagnose(run, plants, config=cfg)
    assert a.named_effects == b.named_effects and a.gap_after == b.gap_after
    assert format_report(a) == format_report(b)


def test_every_package_export_resolves():
    import importlib

    for package in ("core", "pilot", "flight", "plants", "identification", "pilots", "diagnose", "pipeline"):
        module = importlib.import_module(f"hesspipe.{package}")
        for name in getattr(module, "__all__", ()):
            assert getattr(module, name) is not None, (package, name)


def test_each_stage_is_a_package_with_its_entry_point_documented():
    import importlib

    for package, name in (("flight", "fly"), ("plants", "fit_plants"), ("pilots", "compare_pilots"),
                          ("diagnose", "diagnose"), ("identification", "identify"), ("pilot", "simulate")):
        module = importlib.import_module(f"hesspipe.{package}")
        assert name in module.__all__, (package, name)
        assert "Parameters" in (getattr(module, name).__doc__ or ""), (package, name)


def test_import_is_light():
    code = ("import sys, hesspipe\n"
            "print(sorted(m for m in ('scipy', 'control', 'jsbsim', 'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_command_line_start_up_loads_no_numeric_module():
    code = ("import sys\n"
            "from hesspipe.cli import build_parser\n"
            "build_parser()\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'control', 'jsbsim', 'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"

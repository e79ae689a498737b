"""CLI shell: usage errors, one-line user errors, fast start."""

import subprocess
import sys

import pytest

from hesspipe.cli import main


def test_help_lists_commands(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for name in ("run", "status"):
        assert name in out


def test_unknown_command_is_one_line_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["fly-me-to-the-moon"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "invalid choice" in err


def test_a_misspelt_required_option_is_named_not_reported_missing(capsys):
    # "--plnats" read "the following arguments are required: --plants", naming neither the
    # misspelling nor the fix.
    with pytest.raises(SystemExit) as exc:
        main(["diagnose", "run.csv", "--plnats", "p.json"])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err == ("hesspipe diagnose: error: unrecognized option --plnats (did you mean --plants?) "
                   "(see 'hesspipe diagnose --help')")
    with pytest.raises(SystemExit):
        main(["diagnose", "run.csv"])                           # really missing: said as before
    assert "the following arguments are required: --plants" in capsys.readouterr().err


def test_a_misspelt_optional_option_is_named_by_its_command(capsys):
    # "--confg" read "hesspipe: error: unrecognized arguments: --confg x.toml", from the
    # top-level parser, which knows none of the command's options.
    with pytest.raises(SystemExit) as exc:
        main(["run", "--confg", "x.toml"])
    assert exc.value.code == 2
    assert capsys.readouterr().err.strip() == ("hesspipe run: error: unrecognized option --confg (did you mean "
                                               "--config?) (see 'hesspipe run --help')")
    with pytest.raises(SystemExit):
        main(["run", "--bogus"])                                # nothing near it: no guess
    assert capsys.readouterr().err.strip() == ("hesspipe run: error: unrecognized option --bogus "
                                               "(see 'hesspipe run --help')")


def test_bad_config_is_one_line_exit_1(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[wind]\nspeed = 3\n")
    assert main(["status", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert err == f"hesspipe: error: {cfg}: field 'wind': unknown section; expected seed or one of " \
                  "flight, plants, analytic, pilots, diagnose, report"


def test_cli_import_stays_light():
    # `hesspipe status` and an up-to-date `hesspipe run` must start fast:
    # the heavy numerical stack is imported only by the stages that run.
    code = ("import sys, hesspipe.cli; heavy = {'jsbsim', 'control', 'matplotlib', 'pandas', 'scipy'};"
            "print(sorted(heavy & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_an_up_to_date_runs_data_listing_stays_light(tmp_path):
    # An up-to-date `hesspipe run` computes the stages' input fingerprints and nothing else;
    # listing a data folder's runs for the pilots stage's must not load the readers (it was
    # 4 s of a 4.4 s re-run when it imported hesspipe.pilots.compare).
    (tmp_path / "s1_run.csv").write_text("time,disturbance,output,control\n0,0,0,0\n")
    (tmp_path / "notes.md").write_text("not a run\n")
    code = ("import sys; from hesspipe.pipeline.stages import pilots_inputs;"
            f"runs = pilots_inputs({{'data': {str(tmp_path)!r}, 'plants': ''}}, {{}});"
            "heavy = {'jsbsim', 'control', 'matplotlib', 'pandas', 'scipy'};"
            "print([p.name for p in runs], sorted(heavy & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['s1_run.csv'] []"


def test_forcing_choices_are_the_librarys_forcings():
    from hesspipe.cli._options import FORCING_CHOICES
    from hesspipe.flight.target import FORCINGS

    assert FORCING_CHOICES == tuple(FORCINGS)


@pytest.mark.parametrize("command", ["run", "status"])
def test_an_unknown_aircraft_flag_is_blamed_on_the_flag(command, tmp_path, capsys):
    """The value came from the command line, not from pipeline/default.toml (nor from --config)."""
    cfg = tmp_path / "c.toml"
    cfg.write_text('[flight]\naircraft = "B747"\n')
    for extra in ([], ["--config", str(cfg)]):
        out = tmp_path / "o"
        assert main([command, "--aircraft", "7377", "--out", str(out), *extra]) == 1
        err = capsys.readouterr().err
        assert err.startswith("hesspipe: error: --aircraft: unknown aircraft '7377'; expected one of: 737"), err
        assert err.count("\n") == 1 and ".toml" not in err and not out.exists()

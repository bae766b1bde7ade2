"""The console entry point: version, dispatch, and the one-line / exit-2 error contract."""

import subprocess
import sys

import pytest

from openpbr_diffuse import __version__
from openpbr_diffuse.cli.main import main


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert __version__ in capsys.readouterr().out


@pytest.mark.parametrize("argv", [[], ["no-such-command"], ["albedo"]])
def test_usage_errors_are_one_line_exit_2(argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("openpbr-diffuse") and "\n" not in err


def test_console_script_runs_as_module():
    out = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse.cli.main", "--version"], capture_output=True, text=True, check=True
    )
    assert __version__ in out.stdout


def test_usage_error_of_a_subcommand_is_one_line_under_python_m():
    """A sub-command's UsageError (albedo: --export with a query option) under `python -m`."""
    run = subprocess.run(
        [sys.executable, "-m", "openpbr_diffuse.cli.main", "albedo", "eon", "--export", "x", "--mu", "0.5"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2, run.stderr
    assert run.stderr.count("\n") == 1 and "Traceback" not in run.stderr


@pytest.mark.parametrize(("setting", "colours"), [(None, False), ("", True)])
def test_the_command_line_does_not_colour_numbas_typing_messages(setting, colours):
    """The command line turns off numba's message highlighting (it would colour thousands of
    failed typing attempts while compiling), unless the user's environment says otherwise."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING"}
    if setting is not None:
        env["NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING"] = setting
    code = (
        "import sys; sys.argv = ['-m']; import openpbr_diffuse, numba.core.errors as e; "
        "print(type(e.termcolor()).__name__)"
    )
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    import importlib.util

    colours = colours and importlib.util.find_spec("colorama") is not None  # numba colours with colorama only
    assert out.strip() == ("HighlightColorScheme" if colours else "NOPColorScheme")

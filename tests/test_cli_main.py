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
    out = subprocess.run([sys.executable, "-m", "openpbr_diffuse.cli.main", "--version"],
                         capture_output=True, text=True, check=True)
    assert __version__ in out.stdout

"""The Examples sections of the spectral package's docstrings run as written."""

import doctest
import importlib

import pytest

MODULES = [
    "openpbr_diffuse.spectral.colorimetry",
    "openpbr_diffuse.spectral.recovery",
    "openpbr_diffuse.spectral.colorsets",
    "openpbr_diffuse.spectral.validation",
    "openpbr_diffuse.spectral.reference",
]


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_import_is_lazy():
    """Importing the package (and the CLI parser) does not import colour-science."""
    import subprocess
    import sys

    code = (
        "import sys, openpbr_diffuse.spectral, openpbr_diffuse.cli.main as m; m.build_parser(); "
        "print('colour' in sys.modules, 'OpenImageIO' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_colour_plotting_still_importable_after_lazy_import():
    import subprocess
    import sys

    code = (
        "from openpbr_diffuse.spectral.colorimetry import _colour; c = _colour(); "
        "import colour.plotting; print(hasattr(colour.plotting, 'plot_single_sd'))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"


def test_missing_colour_science_is_one_clear_line():
    """Without colour-science the CLI says what to install (one line, exit 2)."""
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['colour'] = None\n"
        "from openpbr_diffuse.cli.main import main\n"
        "sys.exit(main(['colorshift', '--roughness', '1', '--mu', '1']))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert "pip install 'colour-science" in out.stderr

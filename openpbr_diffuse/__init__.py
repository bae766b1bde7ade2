"""openpbr-diffuse: reference implementation and conformance validator for the rough
diffuse lobe of OpenPBR (EON) and the Oren-Nayar family it replaces.

Conventions: local shading frame with the normal +z; ``wi`` (to the light) and ``wo`` (to
the viewer) point away from the surface; BRDF values exclude the cosine factor; arrays
broadcast over leading axes with the colour channel axis last.
"""

from . import _signals

_signals.install_for_start_up()  # the command line only: Ctrl-C while importing exits cleanly
if _signals.is_command_line():
    # numba colours the message of every typing attempt that fails, and its compiler makes
    # thousands while it types a function (each a colorama set-up and tear-down): a few per
    # cent of a command's first run.  The command line shows none of those messages.
    import os as _os

    _os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")
from ._version import __version__  # noqa: E402
from .albedo.tables import reference_albedo, reference_average_albedo
from .models import COLOR_MODES, MODELS, average_albedo, directional_albedo, evaluate
from .nodes import OpenPBRSurface, OrenNayarDiffuseBSDF
from .readers import BUNDLED_MATERIALS, load_materials
from .sampling import STRATEGIES, pdf, sample, sample_rng
from .simulation import simulate_albedo, simulate_average_albedo, simulate_brdf

__all__ = [
    "__version__",
    "MODELS",
    "COLOR_MODES",
    "evaluate",
    "directional_albedo",
    "average_albedo",
    "reference_albedo",
    "reference_average_albedo",
    "STRATEGIES",
    "sample",
    "pdf",
    "sample_rng",
    "OrenNayarDiffuseBSDF",
    "OpenPBRSurface",
    "load_materials",
    "BUNDLED_MATERIALS",
    "simulate_albedo",
    "simulate_average_albedo",
    "simulate_brdf",
]

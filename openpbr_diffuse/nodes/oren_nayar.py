"""MaterialX ``oren_nayar_diffuse_bsdf`` (nodedef ``ND_oren_nayar_diffuse_bsdf``).

Inputs (read from the MaterialX library, see ``materialx_defs``): ``weight``, ``color``,
``roughness``, ``normal`` and the uniform ``energy_compensation``.  As in MaterialX:

- energy_compensation = false: qualitative Oren-Nayar (EON paper Eq. 1-4) with
  sigma = roughness (radians), sampled with cosine-weighted directions (Eq. 21);
- energy_compensation = true: EON (EON paper Eq. 16-20) with r = roughness, sampled with
  the paper's CLTC + uniform MIS sampler (Listing 4).

The node's BSDF is weight * f(color) (RGB).  Directions are world-space when a ``normal``
is given (the local frame is built from it, ``frame.Frame``), else local (normal +z).
"""

import inspect
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from .. import sampling
from ..models import directional_albedo, evaluate
from ..models.registry import INFO
from ._node import NodeMeta, bind_inputs, convert_input, node_signature
from .frame import Frame
from .materialx_defs import nodedef_inputs


class OrenNayarDiffuseBSDF(metaclass=NodeMeta):
    """The MaterialX Oren-Nayar diffuse BSDF node.

    Parameters (names, types and defaults are those of ``ND_oren_nayar_diffuse_bsdf``)
    ----------
    weight : float or array (...), default 1.0
        Multiplier of the BSDF, in [0, 1] (the nodedef's range).
    color : color3, array (..., 3), default (0.18, 0.18, 0.18)
        Single-scattering albedo rho per channel, in [0, 1].
    roughness : float or array (...), default 0.0
        sigma in radians, [0, pi/2], without energy compensation; EON's r in [0, 1] with.
    energy_compensation : bool, default False
        False: QON; True: EON.
    normal : array (..., 3), optional (keyword only; MaterialX default: Nworld)
        World-space unit shading normal.  Without it, directions are local (normal +z).

    Leading axes of the inputs broadcast with those of the directions.

    Examples
    --------
    >>> import numpy as np
    >>> node = OrenNayarDiffuseBSDF(color=(0.5, 0.5, 0.5), roughness=1.0, energy_compensation=True)
    >>> wo = np.array([0.0, 0.0, 1.0])
    >>> bool(np.allclose(node.albedo(wo), directional_albedo("eon", 1.0, 1.0, 0.5)))
    True
    """

    NODEDEF = "ND_oren_nayar_diffuse_bsdf"

    @classmethod
    def signature(cls) -> inspect.Signature:
        return node_signature(cls.NODEDEF)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        values = bind_inputs(type(self), args, kwargs)
        defs = nodedef_inputs(self.NODEDEF)
        conv = {name: convert_input(defs[name], v) for name, v in values.items()}
        self.energy_compensation = conv["energy_compensation"]
        self.weight = conv["weight"]
        self.color = conv["color"]
        info = INFO[self.model]
        unit = "r" if info.roughness_name == "r" else "sigma, radians"
        self.roughness = ar.in_range(
            "roughness",
            conv["roughness"],
            np.float64,
            0.0,
            info.roughness_max,
            f" for energy_compensation={str(self.energy_compensation).lower()} ({self.model.upper()}, {unit})",
        )
        ar.rho_array("color", self.color, np.float64)  # albedo per channel in [0, 1]
        self.normal = conv["normal"]
        self.frame = Frame(self.normal)

    @property
    def inputs(self) -> dict[str, Any]:
        """The node's input values by MaterialX name."""
        return {
            "weight": self.weight,
            "color": self.color,
            "roughness": self.roughness,
            "normal": self.normal,
            "energy_compensation": self.energy_compensation,
        }

    @property
    def model(self) -> str:
        """The lobe model of ``openpbr_diffuse.models``: "eon" or "qon"."""
        return "eon" if self.energy_compensation else "qon"

    @property
    def strategy(self) -> str:
        """The sampling strategy of ``openpbr_diffuse.sampling``: "eon" or "cosine"."""
        return "eon" if self.energy_compensation else "cosine"

    def _sampling_roughness(self):
        # cosine sampling ignores roughness; QON's sigma may exceed EON's r range
        return self.roughness if self.energy_compensation else 0.0

    def _local(self, name, w):
        return self.frame.to_local(ar.directions(name, w, np.float64))

    # ------------------------------------------------------------------ verbs
    def eval(self, wi: ArrayLike, wo: ArrayLike) -> NDArray[Any]:
        """BSDF value weight * f(wi, wo) without the cosine factor, shape (..., 3).

        f = 0 when either direction is at or below the surface.
        """
        dtype = ar.result_dtype(wi, wo)
        f = evaluate(self.model, self._local("wi", wi), self._local("wo", wo), self.roughness, self.color)
        return (self.weight[..., None] * f).astype(dtype, copy=False)

    def albedo(self, wo: ArrayLike) -> NDArray[Any]:
        """Directional albedo weight * E(mu_o) (closed form, EON Eq. 20 / QON Eq. 8), (..., 3).

        0 for wo at or below the horizon (the BSDF is 0 there).
        """
        dtype = ar.result_dtype(wo)
        mu = self._local("wo", wo)[..., 2]
        E = directional_albedo(self.model, np.clip(mu, 0.0, 1.0), self.roughness, self.color)
        return np.where((mu > 0.0)[..., None], self.weight[..., None] * E, 0.0).astype(dtype, copy=False)

    def sample(self, wo: ArrayLike, u: ArrayLike) -> tuple[NDArray[Any], NDArray[Any]]:
        """Sample wi given wo with u (..., 2) in [0, 1): returns (wi, pdf).

        wi is world-space if the node has a normal.  pdf = 0 marks "no sample" (wo below
        the horizon).
        """
        dtype = ar.result_dtype(wo, u)
        wi, p = sampling.sample(
            self.strategy, self._local("wo", wo), self._sampling_roughness(), ar.as_float("u", u, np.float64)
        )
        return self.frame.to_world(wi).astype(dtype, copy=False), p.astype(dtype, copy=False)

    def pdf(self, wo: ArrayLike, wi: ArrayLike) -> NDArray[Any]:
        """Solid-angle pdf of ``sample`` producing wi given wo."""
        dtype = ar.result_dtype(wo, wi)
        p = sampling.pdf(self.strategy, self._local("wo", wo), self._local("wi", wi), self._sampling_roughness())
        return p.astype(dtype, copy=False)

    def __repr__(self) -> str:
        return (
            f"OrenNayarDiffuseBSDF(weight={self.weight.tolist()}, color={self.color.tolist()}, "
            f"roughness={self.roughness.tolist()}, energy_compensation={self.energy_compensation}"
            + (", normal=..." if self.normal is not None else "")
            + ")"
        )

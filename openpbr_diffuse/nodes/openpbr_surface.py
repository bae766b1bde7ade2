"""OpenPBR Surface 1.1 as a mixture of lobes around the diffuse lobe, with albedo-based lobe
selection (OpenPBR spec, "Reduction to a mixture of lobes"), compiled.

Inputs and defaults are those of MaterialX ``ND_open_pbr_surface_surfaceshader``, read from
the library (``materialx_defs``).  The layering and mixing follow the reference graph
(``open_pbr_surface.mtlx``, node names in brackets); local frame, normal +z, mu_o = wo.z:

    f = F f_fuzz + (1 - F E_fuzz) [ C f_coat + (1 - C E_coat) A D f_base ]          (fuzz_layer, coat_layer)
    f_base = M f_metal + (1 - M) [ f_specular + (1 - E_spec) f_substrate ]         (base_substrate, dielectric_base)
    f_substrate = T f_transmission + (1 - T) [ S f_subsurface + (1 - S) base_weight f_diffuse ]

with F = fuzz_weight, C = coat_weight, M = base_metalness, T = transmission_weight,
S = subsurface_weight and every E the directional albedo at mu_o of the (untinted) layer
lobe above: a layer passes 1 - weight E(mu_o) to what lies beneath ("albedo scaling", the
graph's ``layer`` nodes).  The lobes:

- diffuse [diffuse_bsdf]: EON, rho = base_color, r = base_diffuse_roughness (``diffuse_model``
  "qon" or "lambert" swap the model, for Standard Surface and UsdPreviewSurface graphs);
- specular [dielectric_reflection]: GGX (height-correlated Smith G2, alpha = r^2), exact
  Fresnel of the modulated index whose F0 is specular_weight F0(eta_s), tint specular_color.
  Under a coat the index is eta_s = mix(specular_ior, specular_ior/coat_ior (inverted when < 1),
  C) and the roughness mix(r_s, min(1, 2 r_c^4 + r_s^4)^(1/4), C) [eta_s,
  effective_specular_roughness]; the metal uses the same roughness;
- metal [metal_bsdf]: GGX with the F82-tint Fresnel, F0 = base_weight base_color, tint
  specular_color, weight specular_weight;
- coat [coat_bsdf]: GGX dielectric with coat_ior and coat_roughness; beneath it the base is
  multiplied by A = mix(1, coat_color, C) [coat_attenuation] and the darkening
  D = mix(1, (1 - K)/(1 - E_base K), C coat_darkening), K = 1 - (1 - F0(coat_ior))/coat_ior^2,
  E_base = mix(mix(base_color, subsurface_color, S), specular_weight base_color, M)
  [base_darkening];
- fuzz [fuzz_bsdf]: the Zeltner 2022 LTC sheen (``microfacet.sheen``), tint fuzz_color,
  roughness fuzz_roughness;
- transmission [dielectric_transmission]: *approximated* as the GGX lobe of the base
  specular mirrored below the surface, normalised to albedo 1 and tinted by
  transmission_color (1 when transmission_depth > 0, as the graph): its weight and albedo
  are exact for the mixture (the dielectric transmits 1 - E_spec), its shape ignores
  refraction (exact in direction for thin walls and index-matched interfaces);
- subsurface [subsurface_bsdf]: *approximated* as a Lambertian reflection of albedo
  subsurface_color (the spec's definition of subsurface_color: the albedo of the
  subsurface medium); with geometry_thin_walled [subsurface_thin_walled] the graph's
  0.5/0.5 mix of a QON reflection (sigma = base_diffuse_roughness) weighted
  subsurface_color (1 - g) and a Lambertian translucency ("subsurface_transmission")
  weighted subsurface_color (1 + g), g = subsurface_scatter_anisotropy.

Multiple scattering (``multiscatter=True``): each GGX lobe is multiplied by
1 + F0 (1 - E1(mu_o))/E1(mu_o) (Turquin 2019), a factor of wo only, so the albedos stay
exact and a white surface preserves energy.  Albedo scaling is the spec's own
non-reciprocal form (weights depend on wo only), kept because it makes ``albedo`` exact and
the white furnace hold.

Lobe selection: ``lobes(wo)`` gives each active lobe's weight w_k (RGB), albedo E_k (RGB) of
its own BSDF f_k (``lobe_eval``; eval = sum_k w_k f_k) and probability
P_k = |w_k * E_k| / sum_j |w_j * E_j|, |.| the RGB length ("length", OpenPBR-viewer) or the
largest component ("max", adobe/openpbr-bsdf); "uniform" (1/K) is for comparisons.
``sample`` picks lobe k with P_k and samples it (EON diffuse: the EON sampler; QON,
Lambert, subsurface: cosine; GGX: visible normals, Heitz 2018, or the plain NDF; fuzz: its
LTC); ``pdf`` is the one-sample mixture pdf sum_k P_k pdf_k over the whole sphere.

The inputs used are declared once (``surface_inputs.MODELLING``, with the nodedef's types):
transmission_depth > 0 switches the transmission tint off, as the graph.  Not modelled
(accepted, listed in ``ignored_inputs`` with a warning when set): anisotropy, thin film,
emission, geometry_opacity, the transmission volume (scatter, its anisotropy, dispersion),
subsurface radius, and the tangent / coat-normal inputs.  specular_ior or coat_ior < 1: total internal reflection is
not modelled, the Fresnel factor of the reciprocal index (same F0) is used, with a warning.
The F82-tint Fresnel is the published formula, unclamped (warned when it dips below 0).

Speed: every verb is one compiled driver (``_surface_drivers``) that runs blocks of rows one
lobe at a time, each pass a vectorised loop (``_surface_passes``; the lobes themselves are the
modules of ``nodes.lobes``, assembled by ``_surface_kernels``); the material's inputs are packed once into a parameter vector per
material.  Building a surface from plain
Python numbers and 3-tuples skips NumPy's input conversion (same checks, same values), and
``lobes`` at one direction of one material calls the serial driver directly.
"""

import dataclasses
import functools
import inspect
import math
import warnings
from collections.abc import Iterable, Mapping
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _arrays as ar
from ..microfacet import ggx
from . import _surface_drivers as sd
from . import _surface_kernels as sk
from . import surface_inputs
from ._node import NodeMeta, bind_inputs, convert_input, is_default, node_signature
from ._surface_params import D_EON, D_LAMBERT, D_QON
from .frame import Frame
from .materialx_defs import nodedef_inputs

#: The inputs this model uses (``surface_inputs.MODELLING``); every other input of the
#: nodedef is reported when set.
MODELLED = surface_inputs.MODELLED + sk.LOBE_INPUTS

#: Inputs whose nodedef ui maximum is a UI range, not a validity bound: OpenPBR's own example
#: metals use an F82 tint above 1 (cesium 1.394, rubidium 1.096) and subsurface radius
#: scales above 1 (milk, petroleum).  They are accepted up to any finite value.
UNBOUNDED_ABOVE = ("specular_color", "subsurface_radius_scale")

SELECTIONS = ("length", "max", "uniform")
LOBE_NAMES = sk.LOBE_NAMES
#: diffuse_model -> kernel model id
DIFFUSE_MODELS = {"eon": D_EON, "qon": D_QON, "lambert": D_LAMBERT}
_OPTIONS = (("selection", "length"), ("specular_sampling", "vndf"), ("multiscatter", True), ("diffuse_model", "eon"))
_OPTION_NAMES = tuple(n for n, _ in _OPTIONS)
_MODELLED = frozenset(MODELLED)


class IgnoredInputWarning(UserWarning):
    """An OpenPBR input this model does not use was set (it has no effect)."""


class Lobe(NamedTuple):
    """One lobe of the mixture at given outgoing directions.

    weight : (..., 3) RGB mixture weight w_k (includes the layer and mix factors)
    albedo : (..., 3) directional albedo E_k(wo) of the lobe's own BSDF
    probability : (...) selection probability P_k
    """

    name: str
    weight: np.ndarray
    albedo: np.ndarray
    probability: np.ndarray


class _Flags(NamedTuple):
    active: int
    dmodel: int
    sel: int
    ms: bool
    vndf: bool


def pack_parameters(p: Mapping[str, Any], changed: Iterable[str] | None = None) -> tuple[NDArray[np.float64], int, int]:
    """(parameter rows (..., N_PARAMS), active-lobe mask, warning bits) of the compiled path
    from the converted inputs ``p`` (float arrays (...), colours (..., 3)): the derived
    values of the reference graph, computed once per material (``_surface_kernels.pack_drive``).
    ``changed``: the names that differ from the nodedef defaults (None: any may)."""
    raw = _one_material(p, changed)
    lead = ()
    if raw is None:
        vals = [np.float64(bool(p[n])) if n in _BOOLEAN else p[n] for n, _ in sk.RAW]
        lead = np.broadcast_shapes(*(np.shape(v)[:-1] if w == 3 else np.shape(v) for v, (_, w) in zip(vals, sk.RAW)))
        raw = np.concatenate(
            [
                np.broadcast_to(v if w == 3 else np.asarray(v)[..., None], lead + (w,))
                for v, (_, w) in zip(vals, sk.RAW)
            ],
            axis=-1,
        )
        raw = np.ascontiguousarray(raw, dtype=np.float64).reshape(-1)
    out = np.empty(lead + (sk.N_PARAMS,))
    mask, warn = sk.pack_drive(raw, out.reshape(-1) if lead else out, *sd.tables())
    return out, mask, warn


#: the boolean inputs of the packed row (packed as 0.0 / 1.0)
_BOOLEAN = frozenset(n for n, _ in sk.RAW if nodedef_inputs(surface_inputs.NODEDEF)[n].type == "boolean")
#: offset and width of each RAW input in the flat row
_RAW_AT: dict[str, tuple[int, int]] = {}
for _n, _w in sk.RAW:
    _RAW_AT[_n] = (sum(w for _, w in sk.RAW[: len(_RAW_AT)]), _w)


def _one_material(p, changed):
    """The RAW values as one float64 row (N_RAW,) when every input is a single value, else
    None.  Starts from the defaults' row when only ``changed`` names differ from them."""
    if changed is None:
        flat, names = np.zeros(sk.N_RAW), _RAW_AT
    else:
        flat, names = _interface(OpenPBRSurface.NODEDEF).raw.copy(), changed
    for n in names:
        at = _RAW_AT.get(n)
        if at is None:  # not an input of the compiled path
            continue
        a, w = at
        v = p[n]
        if type(v) is np.float64:  # what ``_convert`` gives a plain float input
            flat[a] = v
        elif n in _BOOLEAN:
            flat[a] = float(bool(v))
        elif w == 1 and np.ndim(v) == 0:
            flat[a] = float(v)
        elif w == 3 and np.shape(v) == (3,):
            flat[a : a + 3] = v
        else:
            return None
    return flat


_WARNINGS = {
    sk.W_SPEC_TIR: "specular_ior < 1: total internal reflection is not modelled; the Fresnel factor of the "
    "reciprocal index (same F0) is used",
    sk.W_COAT_TIR: "coat_ior < 1: total internal reflection is not modelled; the Fresnel factor of the "
    "reciprocal index (same F0) is used",
    sk.W_F82_NEGATIVE: "the F82-tint Fresnel of this metal is negative at some angles (dark base_color with a "
    "dark specular_color): the published formula is used unclamped, so the metal lobe and "
    "its albedo can be negative",
}


@functools.cache
def _signature(nodedef):
    return node_signature(nodedef, _OPTIONS, keyword_only=True)


def _validity(idef):
    """The nodedef entry with the range the input is checked against (see UNBOUNDED_ABOVE)."""
    return dataclasses.replace(idef, uimax=None) if idef.name in UNBOUNDED_ABOVE else idef


def _bounds(idef):
    """(width, lo, hi) of a float (width 1, lo and hi floats) or color3 input (width 3, lo
    and hi per component): its range, -inf / inf where the nodedef sets no bound."""
    width = 1 if idef.type == "float" else 3

    def bound(b, unbounded):
        if width == 1:
            return unbounded if b is None else b
        return (unbounded,) * 3 if b is None else b if isinstance(b, tuple) else (b,) * 3

    return width, bound(idef.uimin, -math.inf), bound(idef.uimax, math.inf)


class _Interface(NamedTuple):
    """What every construction reads, built once per nodedef and process (``_interface``)."""

    checked: dict  # name -> InputDef, with the range the input is checked against
    defaults: dict  # name -> converted default (arrays read-only)
    accepted: frozenset  # the input and option names
    bounds: dict  # name -> ``_bounds`` of the float and color3 inputs (``_convert``)
    raw: np.ndarray  # the defaults' RAW row (``_one_material``), read-only


@functools.cache
def _interface(nodedef):
    """The ``_Interface`` of the nodedef."""
    checked = {n: _validity(d) for n, d in nodedef_inputs(nodedef).items()}
    defaults = {}
    for n, d in checked.items():
        v = convert_input(d, d.default)
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
        defaults[n] = v
    bounds = {n: _bounds(d) for n, d in checked.items() if d.type in ("float", "color3")}
    raw = _one_material(defaults, None)
    raw.flags.writeable = False
    return _Interface(checked, defaults, frozenset(checked).union(_OPTION_NAMES), bounds, raw)


_PLAIN = (float, int)


def _in(lo, hi, v):
    """v (a plain number) finite and in [lo, hi]."""
    return math.isfinite(v) and lo <= v <= hi


def _convert(iface, name, v):
    """``convert_input`` with a fast path for plain Python numbers (float inputs) and
    3-tuples / lists of them (color3) that are finite and in range (``_bounds``), the
    common case when building many materials: np.float64 or a float64 (3,) array, the
    values ``convert_input`` gives.  Anything else, and every error message, goes through
    ``convert_input``."""
    bounds = iface.bounds.get(name)
    if bounds is not None:
        width, lo, hi = bounds
        if width == 1:
            if type(v) in _PLAIN and _in(lo, hi, v):
                return np.float64(v)
        elif (type(v) is tuple or type(v) is list) and len(v) == 3:
            a, b, c = v
            if (
                type(a) in _PLAIN
                and type(b) in _PLAIN
                and type(c) in _PLAIN
                and _in(lo[0], hi[0], a)
                and _in(lo[1], hi[1], b)
                and _in(lo[2], hi[2], c)
            ):
                return np.array(v, dtype=np.float64)
    return convert_input(iface.checked[name], v)


@functools.cache
def _slots(mask):
    """(slots, names) of the lobes in an active-lobe mask."""
    slots = tuple(k for k in range(len(LOBE_NAMES)) if mask & (1 << k))
    return slots, tuple(LOBE_NAMES[k] for k in slots)


#: ``Lobe(name, weight, albedo, probability)`` from a tuple of the four, without the
#: NamedTuple's Python-level ``__new__`` (``lobes`` builds one per active lobe per call)
_new_lobe = functools.partial(tuple.__new__, Lobe)


@functools.cache
def _flags(mask, diffuse_model, selection, multiscatter, specular_sampling):
    """The kernels' ``_Flags`` of an active-lobe mask and the (checked) options."""
    return _Flags(
        mask,
        DIFFUSE_MODELS[diffuse_model],
        SELECTIONS.index(selection),
        bool(multiscatter),
        specular_sampling == "vndf",
    )


class OpenPBRSurface(metaclass=NodeMeta):
    """OpenPBR Surface: diffuse, specular, metal, transmission, subsurface, coat and fuzz lobes.

    Parameters
    ----------
    **inputs
        OpenPBR input names of ``ND_open_pbr_surface_surfaceshader`` (keyword only), with
        the nodedef's defaults; values outside its ui range raise ValueError.  Float inputs
        may be arrays (...) and colours (..., 3) broadcasting with the directions' leading
        axes.  ``geometry_normal`` (world space) makes all directions world-space.
    selection : {"length", "max", "uniform"}
        Lobe-selection rule (see module docstring).
    specular_sampling : {"vndf", "ndf"}
        GGX sampling: visible normals (Heitz 2018) or the plain NDF.
    multiscatter : bool
        Multiple-scattering compensation of the GGX lobes (default True).
    diffuse_model : {"eon", "qon", "lambert"}
        The diffuse lobe: "eon" (OpenPBR: EON with r = base_diffuse_roughness, EON
        sampler), "qon" (Standard Surface's graph: QON with sigma = base_diffuse_roughness
        in radians, cosine sampling) or "lambert" (UsdPreviewSurface; cosine sampling).

    Raises
    ------
    ValueError
        Unknown input names (named in the message), out-of-range values.

    Examples
    --------
    >>> import numpy as np
    >>> s = OpenPBRSurface(base_color=(1.0, 1.0, 1.0), base_diffuse_roughness=0.5)
    >>> wo = np.array([0.6, 0.0, 0.8])
    >>> [lobe.name for lobe in s.lobes(wo)]
    ['diffuse', 'specular']
    >>> round(float(s.albedo(wo)[0]), 6)     # white base: energy preserved
    1.0
    >>> coated = OpenPBRSurface(coat_weight=1.0, fuzz_weight=0.5)
    >>> [lobe.name for lobe in coated.lobes(wo)]
    ['diffuse', 'specular', 'coat', 'fuzz']
    """

    NODEDEF = "ND_open_pbr_surface_surfaceshader"

    @classmethod
    def signature(cls) -> inspect.Signature:
        return _signature(cls.NODEDEF)

    @classmethod
    def defaults(cls) -> dict[str, object]:
        """Default value of every input, by name (None: supplied by the renderer)."""
        return {n: d.default for n, d in _interface(cls.NODEDEF).checked.items()}

    def __init__(self, **kwargs: Any) -> None:
        iface = _interface(self.NODEDEF)
        if not iface.accepted.issuperset(kwargs):
            bind_inputs(type(self), (), kwargs)  # raises, naming the unknown names
        self._set_options(kwargs)
        self.inputs = dict(iface.defaults)
        self._given = tuple(kwargs)
        for n, v in kwargs.items():
            self.inputs[n] = _convert(iface, n, v)
        self._ignored = {
            n: self.inputs[n] for n in kwargs if n not in _MODELLED and not is_default(iface.checked[n], self.inputs[n])
        }
        if self._ignored:
            warnings.warn(
                f"OpenPBRSurface does not model these inputs; they have no effect: {', '.join(self._ignored)}",
                IgnoredInputWarning,
                stacklevel=2,
            )
        self._setup()

    def _set_options(self, kwargs):
        """Take the options (selection, specular_sampling, ...) out of ``kwargs`` and check them."""
        for n, default in _OPTIONS:
            setattr(self, n, kwargs.pop(n, default))
        if self.selection not in SELECTIONS:
            raise ValueError(f"selection must be one of {', '.join(SELECTIONS)}; got {self.selection!r}")
        if self.specular_sampling not in ggx.SAMPLING_METHODS:
            raise ValueError(
                f"specular_sampling must be one of {', '.join(ggx.SAMPLING_METHODS)}; got {self.specular_sampling!r}"
            )
        if not isinstance(self.multiscatter, (bool, np.bool_)):
            raise TypeError(f"multiscatter must be a bool, got {type(self.multiscatter).__name__}")
        if self.diffuse_model not in DIFFUSE_MODELS:
            raise ValueError(f"diffuse_model must be one of {', '.join(DIFFUSE_MODELS)}; got {self.diffuse_model!r}")

    # ------------------------------------------------------------------ parameters
    def _setup(self):
        p = self.inputs
        self.frame = Frame(p["geometry_normal"])
        self.params, mask, warn = pack_parameters(p, self._given)
        if warn:
            for bit, text in _WARNINGS.items():
                if warn & bit:
                    warnings.warn(text, UserWarning, stacklevel=3)
        if not mask:
            mask = 1 << sk.DIFFUSE  # a black surface: keep one lobe (f = 0 everywhere)
        self._slots, self.active = _slots(mask)
        self._flags = _flags(mask, self.diffuse_model, self.selection, self.multiscatter, self.specular_sampling)

    @property
    def ignored_inputs(self) -> dict[str, Any]:
        """{name: value} of the set inputs this model does not use (thin film, emission, ...)."""
        return dict(self._ignored)

    def _local(self, name: str, w: ArrayLike) -> NDArray[np.float64]:
        # one float64 direction (a renderer's query): the same unit check as
        # ``_arrays.directions``, without its array machinery
        if type(w) is np.ndarray and w.shape == (3,) and w.dtype == np.float64:
            x, y, z = w.tolist()
            if abs(x * x + y * y + z * z - 1.0) <= ar.UNIT_TOL:
                return self.frame.to_local(w)
        return self.frame.to_local(ar.directions(name, w, np.float64))

    def _lead(self, **shapes):
        if self.params.ndim == 1 and not any(shapes.values()):  # one material, one row
            return ()
        return ar.broadcast_leading(material=self.params.shape[:-1], **shapes)

    # ------------------------------------------------------------------ verbs
    def lobes(self, wo: ArrayLike) -> list[Lobe]:
        """The active lobes at wo: list of ``Lobe(name, weight, albedo, probability)``.

        Probabilities sum to 1 and are proportional to |w_k * E_k| (see ``selection``).
        """
        wo = self._local("wo", wo)
        lead = self._lead(wo=wo.shape[:-1])
        return self._lobe_list(lead, *sd.lobes_rows(self._flags, self.params, wo, lead))

    def lobes_and_eval(self, wi: ArrayLike, wo: ArrayLike) -> tuple[list[Lobe], NDArray[Any]]:
        """(``lobes(wo)``, ``eval(wi, wo)``) computed in one pass over the rows: what a
        material's evaluation needs (its lobes, its albedo sum_k w_k E_k, its BSDF), with
        the shared per-row state of wo computed once.  Equal to the two calls' results to
        rounding (the same formulas, compiled into one driver); the lobes' arrays have the
        leading shape of wi, wo and the material broadcast together, as ``eval``'s result.

        Example
        -------
        >>> import numpy as np
        >>> s = OpenPBRSurface(base_color=(0.8, 0.5, 0.3))
        >>> wo = np.array([0.0, 0.0, 1.0])
        >>> lobes, f = s.lobes_and_eval(wo, wo)
        >>> bool(np.allclose(f, s.eval(wo, wo), rtol=1e-14)), [lb.name for lb in lobes]
        (True, ['diffuse', 'specular'])
        """
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        lead = self._lead(wi=wi.shape[:-1], wo=wo.shape[:-1])
        W, E, P, f = sd.lobes_rows(self._flags, self.params, wo, lead, wi)
        return self._lobe_list(lead, W, E, P), f.astype(dtype, copy=False)

    def _lobe_list(self, lead, W, E, P):
        if lead:
            W, E, P = np.moveaxis(W, -2, 0), np.moveaxis(E, -2, 0), np.moveaxis(P, -1, 0)  # lobe axis first
        return [_new_lobe((LOBE_NAMES[k], W[k], E[k], P[k, ...])) for k in self._slots]

    def lobe_eval(self, name: str, wi: ArrayLike, wo: ArrayLike) -> NDArray[Any]:
        """The BSDF f_k of one lobe (its weight w_k not applied), shape (..., 3).

        ``eval`` is sum_k w_k f_k over ``lobes``; ``Lobe.albedo`` is the albedo of f_k.
        """
        if name not in self.active:
            raise ValueError(f"name: {name!r} is not an active lobe of this surface; active: {', '.join(self.active)}")
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        lead = self._lead(wi=wi.shape[:-1], wo=wo.shape[:-1])
        return sd.eval_rows(self._flags, self.params, wi, wo, lead, LOBE_NAMES.index(name)).astype(dtype, copy=False)

    def eval(self, wi: ArrayLike, wo: ArrayLike) -> NDArray[Any]:
        """BSDF value sum_k w_k(wo) f_k(wi, wo) without the cosine factor, shape (..., 3).

        wi below the surface is valid: the transmission and translucency lobes live there
        (their throughput uses |wi.z|).
        """
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        lead = self._lead(wi=wi.shape[:-1], wo=wo.shape[:-1])
        return sd.eval_rows(self._flags, self.params, wi, wo, lead).astype(dtype, copy=False)

    def albedo(self, wo: ArrayLike) -> NDArray[Any]:
        """Directional albedo sum_k w_k E_k(wo) (reflected and transmitted), shape (..., 3)."""
        dtype = ar.result_dtype(wo)
        wo = self._local("wo", wo)
        return sd.albedo_rows(self._flags, self.params, wo, self._lead(wo=wo.shape[:-1])).astype(dtype, copy=False)

    def pdf(self, wo: ArrayLike, wi: ArrayLike) -> NDArray[Any]:
        """One-sample mixture pdf sum_k P_k(wo) pdf_k(wi | wo) (solid angle, whole sphere)."""
        dtype = ar.result_dtype(wo, wi)
        wo, wi = self._local("wo", wo), self._local("wi", wi)
        lead = self._lead(wo=wo.shape[:-1], wi=wi.shape[:-1])
        return sd.pdf_rows(self._flags, self.params, wo, wi, lead).astype(dtype, copy=False)

    def sample(self, wo: ArrayLike, u: ArrayLike) -> tuple[NDArray[Any], NDArray[Any]]:
        """Pick a lobe with probability P_k and sample it: returns (wi, pdf).

        Parameters
        ----------
        wo : array (..., 3)
        u : array (..., 3) or (..., 2), uniform numbers in [0, 1)
            (..., 3): u[..., 0] picks the lobe, u[..., 1:] sample it.  (..., 2): u[..., 0]
            picks the lobe and is then rescaled to [0, 1) inside the chosen lobe's interval
            of the CDF, (u0 - C_{k-1})/P_k, and reused with u[..., 1] (a single-lobe
            surface then samples exactly as that lobe with the same u).

        Returns
        -------
        wi : (..., 3)
            May lie below the horizon (GGX reflections, where f = 0; transmission).  The
            hemisphere lobes (diffuse, subsurface, fuzz) never return wi.z = 0: |wi.z| is
            floored at the smallest normal float64, which only rounding reaches.
        pdf : (...)
            The mixture pdf ``pdf(wo, wi)`` of the returned wi (the same computation, to
            the bit); 0 marks a failed sample (to be discarded): wo below the horizon, or
            with ``specular_sampling="ndf"`` a microfacet normal facing away from wo.
        """
        dtype = ar.result_dtype(wo, u)
        wo = self._local("wo", wo)
        u = ar.in_range("u", u, np.float64, 0.0, 1.0, " (uniform random numbers)", hi_open=True)
        if u.ndim == 0 or u.shape[-1] not in (2, 3):
            raise ValueError(f"u must have shape (..., 3) or (..., 2), got shape {u.shape}")
        lead = self._lead(wo=wo.shape[:-1], u=u.shape[:-1])
        wi, pdf = sd.sample_rows(self._flags, self.params, wo, u, lead)
        return self.frame.to_world(wi).astype(dtype, copy=False), pdf.astype(dtype, copy=False)

    def __repr__(self) -> str:
        set_ = {n: v for n, v in self.inputs.items() if not is_default(nodedef_inputs(self.NODEDEF)[n], v)}
        return f"OpenPBRSurface({', '.join(f'{n}={np.asarray(v).tolist()}' for n, v in set_.items())})"

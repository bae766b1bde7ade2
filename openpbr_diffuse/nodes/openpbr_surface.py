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

Not modelled (accepted, listed in ``ignored_inputs`` with a warning when set): anisotropy,
thin film, emission, geometry_opacity, the transmission volume (scatter, its anisotropy,
dispersion; transmission_depth > 0 only switches the tint off), subsurface radius, and the
tangent / coat-normal inputs.  specular_ior or coat_ior < 1: total internal reflection is
not modelled, the Fresnel factor of the reciprocal index (same F0) is used, with a warning.
The F82-tint Fresnel is the published formula, unclamped (warned when it dips below 0).

Speed: every verb is one compiled loop over rows (``_surface_kernels``); the material's
inputs are packed once into a parameter vector per material.
"""
import dataclasses
import functools
import math
import warnings
from typing import NamedTuple

import numpy as np

from .. import _arrays as ar
from ..microfacet import ggx
from . import _surface_kernels as sk
from ._node import NodeMeta, bind_inputs, convert_input, is_default, node_signature
from .frame import Frame
from .materialx_defs import nodedef_inputs

#: The inputs this model uses; every other input of the nodedef is reported when set.
MODELLED = ("base_weight", "base_color", "base_diffuse_roughness", "base_metalness",
            "specular_weight", "specular_color", "specular_roughness", "specular_ior",
            "transmission_weight", "transmission_color",
            "subsurface_weight", "subsurface_color", "subsurface_scatter_anisotropy",
            "coat_weight", "coat_color", "coat_roughness", "coat_ior", "coat_darkening",
            "fuzz_weight", "fuzz_color", "fuzz_roughness",
            "geometry_thin_walled", "geometry_normal")

#: Inputs whose nodedef ui maximum is a UI range, not a validity bound: OpenPBR's own example
#: metals use an F82 tint above 1 (cesium 1.394, rubidium 1.096) and subsurface radius
#: scales above 1 (milk, petroleum).  They are accepted up to any finite value.
UNBOUNDED_ABOVE = ("specular_color", "subsurface_radius_scale")

SELECTIONS = ("length", "max", "uniform")
LOBE_NAMES = sk.LOBE_NAMES
#: diffuse_model -> kernel model id
DIFFUSE_MODELS = {"eon": sk.D_EON, "qon": sk.D_QON, "lambert": sk.D_LAMBERT}
_OPTIONS = (("selection", "length"), ("specular_sampling", "vndf"), ("multiscatter", True),
            ("diffuse_model", "eon"))
_OPTION_NAMES = tuple(n for n, _ in _OPTIONS)


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


def pack_parameters(p, changed=None):
    """(parameter rows (..., N_PARAMS), active-lobe mask, warning bits) of the compiled path
    from the converted inputs ``p`` (float arrays (...), colours (..., 3)): the derived
    values of the reference graph, computed once per material (``_surface_kernels.pack_drive``).
    ``changed``: the names that differ from the nodedef defaults (None: any may)."""
    flat = _one_material(p, changed)
    if flat is not None:
        lead = ()
        raw = np.array(flat)
    else:
        vals = [p[n] if n != "geometry_thin_walled" else np.float64(bool(p[n])) for n, _ in sk.RAW]
        lead = np.broadcast_shapes(*(np.shape(v)[:-1] if w == 3 else np.shape(v) for v, (_, w) in zip(vals, sk.RAW)))
        raw = np.concatenate([np.broadcast_to(v if w == 3 else np.asarray(v)[..., None], lead + (w,))
                              for v, (_, w) in zip(vals, sk.RAW)], axis=-1)
    out = np.empty(lead + (sk.N_PARAMS,))
    C, R = sk.tables()
    mask, warn = sk.pack_drive(np.ascontiguousarray(raw, dtype=np.float64).reshape(-1), out.reshape(-1),
                               C.shape[0] - 2, R.shape[0] - 2, R.shape[1] - 2, R)
    return out, mask, warn


#: offset and width of each RAW input in the flat row
_RAW_AT = {}
for _n, _w in sk.RAW:
    _RAW_AT[_n] = (sum(w for _, w in sk.RAW[:len(_RAW_AT)]), _w)


@functools.cache
def _default_raw(nodedef):
    return _one_material(_interface(nodedef)[1], None)


def _one_material(p, changed):
    """The RAW values as one flat list of floats when every input is a single value, else
    None.  Starts from the defaults' row when only ``changed`` names differ from them."""
    if changed is None:
        flat, names = [0.0] * sk.N_RAW, _RAW_AT
    else:
        flat, names = list(_default_raw(OpenPBRSurface.NODEDEF)), [n for n in changed if n in _RAW_AT]
    for n in names:
        a, w = _RAW_AT[n]
        v = p[n]
        if n == "geometry_thin_walled":
            flat[a] = float(bool(v))
        elif w == 1 and np.ndim(v) == 0:
            flat[a] = float(v)
        elif w == 3 and np.shape(v) == (3,):
            flat[a:a + 3] = v.tolist()
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


@functools.cache
def _interface(nodedef):
    """(checked defs, converted defaults) of the nodedef, built once per process."""
    checked = {n: _validity(d) for n, d in nodedef_inputs(nodedef).items()}
    defaults = {}
    for n, d in checked.items():
        v = convert_input(d, d.default)
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
        defaults[n] = v
    return checked, defaults


def _in(lo, hi, v):
    return math.isfinite(v) and (lo is None or v >= lo) and (hi is None or v <= hi)


def _convert(idef, v):
    """``convert_input`` with a fast path for plain Python numbers and 3-tuples in range
    (the common case when building many materials); anything else, and every error
    message, goes through ``convert_input``."""
    t = idef.type
    if t == "float" and type(v) in (float, int):
        if _in(idef.uimin, idef.uimax, v):
            return np.float64(v)
    elif t == "color3" and type(v) in (tuple, list) and len(v) == 3 and all(type(c) in (float, int) for c in v):
        lo, hi = idef.uimin, idef.uimax
        at = lambda b, k: b[k] if isinstance(b, tuple) else b   # noqa: E731  (per component or shared)
        if all(_in(at(lo, k), at(hi, k), v[k]) for k in range(3)):
            return np.array(v, dtype=np.float64)
    return convert_input(idef, v)


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
    def signature(cls):
        return _signature(cls.NODEDEF)

    @classmethod
    def defaults(cls):
        """Default value of every input, by name (None: supplied by the renderer)."""
        return {n: d.default for n, d in _interface(cls.NODEDEF)[0].items()}

    def __init__(self, **kwargs):
        checked, defaults = _interface(self.NODEDEF)
        unknown = [n for n in kwargs if n not in checked and n not in _OPTION_NAMES]
        if unknown:
            bind_inputs(type(self), (), kwargs)   # raises, naming them
        options = dict(_OPTIONS)
        for n in _OPTION_NAMES:
            if n in kwargs:
                options[n] = kwargs.pop(n)
        self.selection = options["selection"]
        self.specular_sampling = options["specular_sampling"]
        self.multiscatter = options["multiscatter"]
        self.diffuse_model = options["diffuse_model"]
        if self.selection not in SELECTIONS:
            raise ValueError(f"selection must be one of {', '.join(SELECTIONS)}; got {self.selection!r}")
        if self.specular_sampling not in ggx.SAMPLING_METHODS:
            raise ValueError(f"specular_sampling must be one of {', '.join(ggx.SAMPLING_METHODS)}; "
                             f"got {self.specular_sampling!r}")
        if not isinstance(self.multiscatter, (bool, np.bool_)):
            raise TypeError(f"multiscatter must be a bool, got {type(self.multiscatter).__name__}")
        if self.diffuse_model not in DIFFUSE_MODELS:
            raise ValueError(f"diffuse_model must be one of {', '.join(DIFFUSE_MODELS)}; got {self.diffuse_model!r}")
        self.inputs = dict(defaults)
        self._given = tuple(kwargs)
        for n, v in kwargs.items():
            self.inputs[n] = _convert(checked[n], v)
        self._ignored = {n: self.inputs[n] for n in kwargs
                         if n not in MODELLED and not is_default(checked[n], self.inputs[n])}
        if self._ignored:
            warnings.warn(f"OpenPBRSurface does not model these inputs; they have no effect: "
                          f"{', '.join(self._ignored)}", IgnoredInputWarning, stacklevel=2)
        self._setup()

    # ------------------------------------------------------------------ parameters
    def _setup(self):
        p = self.inputs
        self.frame = Frame(p["geometry_normal"])
        self.params, mask, warn = pack_parameters(p, self._given)
        for bit, text in _WARNINGS.items():
            if warn & bit:
                warnings.warn(text, UserWarning, stacklevel=3)
        if not mask:
            mask = 1 << sk.DIFFUSE      # a black surface: keep one lobe (f = 0 everywhere)
        self._slots = tuple(k for k in range(len(LOBE_NAMES)) if mask & (1 << k))
        self.active = tuple(LOBE_NAMES[k] for k in self._slots)
        self._flags = _Flags(mask, DIFFUSE_MODELS[self.diffuse_model], SELECTIONS.index(self.selection),
                             bool(self.multiscatter), self.specular_sampling == "vndf")

    @property
    def ignored_inputs(self):
        """{name: value} of the set inputs this model does not use (thin film, emission, ...)."""
        return dict(self._ignored)

    def _local(self, name, w):
        # one float64 direction (a renderer's query): the same unit check as
        # ``_arrays.directions``, without its array machinery
        if type(w) is np.ndarray and w.shape == (3,) and w.dtype == np.float64:
            x, y, z = w.tolist()
            if abs(x * x + y * y + z * z - 1.0) <= ar.UNIT_TOL:
                return self.frame.to_local(w)
        return self.frame.to_local(ar.directions(name, w, np.float64))

    def _lead(self, **shapes):
        if self.params.ndim == 1 and all(not s for s in shapes.values()):   # one material, one row
            return ()
        return ar.broadcast_leading(material=self.params.shape[:-1], **shapes)

    # ------------------------------------------------------------------ verbs
    def lobes(self, wo):
        """The active lobes at wo: list of ``Lobe(name, weight, albedo, probability)``.

        Probabilities sum to 1 and are proportional to |w_k * E_k| (see ``selection``).
        """
        wo = self._local("wo", wo)
        lead = self._lead(wo=wo.shape[:-1])
        W, E, P = sk.lobes_rows(self._flags, self.params, wo, lead)
        return [Lobe(LOBE_NAMES[k], W[..., k, :], E[..., k, :], P[..., k]) for k in self._slots]

    def lobe_eval(self, name, wi, wo):
        """The BSDF f_k of one lobe (its weight w_k not applied), shape (..., 3).

        ``eval`` is sum_k w_k f_k over ``lobes``; ``Lobe.albedo`` is the albedo of f_k.
        """
        if name not in self.active:
            raise ValueError(f"name: {name!r} is not an active lobe of this surface; "
                             f"active: {', '.join(self.active)}")
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        lead = self._lead(wi=wi.shape[:-1], wo=wo.shape[:-1])
        return sk.eval_rows(self._flags, self.params, wi, wo, lead, LOBE_NAMES.index(name)).astype(dtype, copy=False)

    def eval(self, wi, wo):
        """BSDF value sum_k w_k(wo) f_k(wi, wo) without the cosine factor, shape (..., 3).

        wi below the surface is valid: the transmission and translucency lobes live there
        (their throughput uses |wi.z|).
        """
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        lead = self._lead(wi=wi.shape[:-1], wo=wo.shape[:-1])
        return sk.eval_rows(self._flags, self.params, wi, wo, lead).astype(dtype, copy=False)

    def albedo(self, wo):
        """Directional albedo sum_k w_k E_k(wo) (reflected and transmitted), shape (..., 3)."""
        dtype = ar.result_dtype(wo)
        wo = self._local("wo", wo)
        return sk.albedo_rows(self._flags, self.params, wo, self._lead(wo=wo.shape[:-1])).astype(dtype, copy=False)

    def pdf(self, wo, wi):
        """One-sample mixture pdf sum_k P_k(wo) pdf_k(wi | wo) (solid angle, whole sphere)."""
        dtype = ar.result_dtype(wo, wi)
        wo, wi = self._local("wo", wo), self._local("wi", wi)
        lead = self._lead(wo=wo.shape[:-1], wi=wi.shape[:-1])
        return sk.pdf_rows(self._flags, self.params, wo, wi, lead).astype(dtype, copy=False)

    def sample(self, wo, u):
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
            May lie below the horizon (GGX reflections, where f = 0; transmission).
        pdf : (...)
            The mixture pdf ``pdf(wo, wi)``, with the chosen lobe's term from its sampler;
            0 marks a failed sample (to be discarded): wo below the horizon, or with
            ``specular_sampling="ndf"`` a microfacet normal facing away from wo.
        """
        dtype = ar.result_dtype(wo, u)
        wo = self._local("wo", wo)
        u = ar.in_range("u", u, np.float64, 0.0, 1.0, " (uniform random numbers)", hi_open=True)
        if u.ndim == 0 or u.shape[-1] not in (2, 3):
            raise ValueError(f"u must have shape (..., 3) or (..., 2), got shape {u.shape}")
        lead = self._lead(wo=wo.shape[:-1], u=u.shape[:-1])
        wi, pdf = sk.sample_rows(self._flags, self.params, wo, u, lead)
        return self.frame.to_world(wi).astype(dtype, copy=False), pdf.astype(dtype, copy=False)

    def __repr__(self):
        set_ = {n: v for n, v in self.inputs.items()
                if not is_default(nodedef_inputs(self.NODEDEF)[n], v)}
        return f"OpenPBRSurface({', '.join(f'{n}={np.asarray(v).tolist()}' for n, v in set_.items())})"

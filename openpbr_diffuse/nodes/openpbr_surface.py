"""The base substrate of OpenPBR Surface 1.1 as a mixture of lobes, with albedo-based lobe
selection (OpenPBR spec, "Reduction to a mixture of lobes").

Inputs and defaults are those of MaterialX ``ND_open_pbr_surface_surfaceshader``, read from
the library (``materialx_defs``).  The modelled part (local frame, normal +z; mu_o = wo.z):

    f = M f_metal + (1 - M) [ f_specular + (1 - E_specular(mu_o)) f_diffuse ]

- diffuse (spec "Glossy-diffuse", reference graph node ``diffuse_bsdf``): EON with
  rho = base_color, r = base_diffuse_roughness, weight base_weight -- the
  ``OrenNayarDiffuseBSDF`` node with energy_compensation = true;
- specular (spec "Specular", graph ``dielectric_reflection``): GGX, Smith height-correlated
  G2, alpha = max(specular_roughness^2, ALPHA_MIN), the exact dielectric Fresnel of the
  modulated index eta' whose F0 is specular_weight * F0(specular_ior) (clamped to 0.99999,
  as the graph does), tinted by specular_color;
- metal (spec "Metal", graph ``metal_bsdf``): the same GGX lobe with the F82-tint Fresnel,
  F0 = base_weight * base_color, tint = specular_color, weight specular_weight;
- M = base_metalness mixes metal and dielectric.

Albedo scaling (spec "Glossy-diffuse"): the diffuse lobe under the specular layer is
weighted by 1 - E_specular(mu_o), E_specular the (untinted) albedo of the specular lobe from
the shipped table, so that the base reflects E_spec + (1 - E_spec) E_diffuse, E_diffuse the
EON albedo with rho = base_color (the spec's definition of base_color): with a white
diffuse the layer preserves energy.  This is the spec's own non-reciprocal form (the weight
depends on wo only; for the default material f(wi, wo) and f(wo, wi) differ by 8 % at the
median and up to 35 % near grazing), kept because it makes ``albedo`` exact and the white
furnace hold; the symmetric form (1 - E(mu_i))(1 - E(mu_o))/(1 - <E>) is reciprocal but
preserves energy only over a Lambertian substrate, and its albedo has no closed form.
specular_color < 1 tints the reflection only (the spec's "non-physical tint"), so it
removes energy rather than passing it to the diffuse.

Multiple scattering (``multiscatter=True``, default): the single-scattering GGX lobes lose
1 - E1(mu_o) of the energy (E1: albedo with F = 1).  Both GGX lobes are multiplied by
1 + F0 (1 - E1(mu_o))/E1(mu_o) (Turquin 2019, "Practical multiple scattering compensation
for microfacet models", with F0 for the average Fresnel; MaterialX's GLSL backend applies a
factor of the same form): a factor of wo only, so the albedo stays exact, and a white
metal preserves energy too.  ``multiscatter=False`` gives the
plain single-scattering lobes.

Lobe selection: ``lobes(wo)`` gives each lobe's weight w_k (RGB), albedo E_k (RGB) of its
own BRDF f_k (``lobe_eval``; eval = sum_k w_k f_k) and
probability P_k = |w_k * E_k| / sum_j |w_j * E_j|, with |.| the RGB vector length
("length", OpenPBR-viewer) or its largest component ("max", adobe/openpbr-bsdf); "uniform"
(1/K) is there for comparisons.  ``sample`` picks lobe k with P_k and samples it (EON
diffuse: the EON sampler; GGX: visible normals, Heitz 2018, or the plain NDF); ``pdf`` is
the one-sample mixture pdf sum_k P_k pdf_k (it integrates to 1 over the sphere: GGX
reflections may fall below the horizon, where f = 0; with NDF sampling it integrates to the
probability that the sampler succeeds, see ``sample``).

Not modelled (accepted, reported in ``ignored_inputs`` and with a warning when not at
their defaults): coat, fuzz, transmission, subsurface, thin film, emission, anisotropy,
geometry_opacity, thin-walled mode and the tangent/coat-normal inputs.
specular_ior < 1 (with specular_weight > 0): total internal reflection is not modelled; the
Fresnel factor of 1/eta' (the same F0) is used, with a warning.  The F82-tint Fresnel is the
published formula, unclamped: with a dark base_color and a dark specular_color it dips
below 0 at some angles (a warning says so).
"""
import warnings
from typing import NamedTuple

import numpy as np

from .. import _arrays as ar
from ..microfacet import fresnel, ggx
from ..microfacet import tables
from ._node import NodeMeta, bind_inputs, convert_input, is_default, node_signature
from .frame import Frame
from .materialx_defs import nodedef_inputs
from .oren_nayar import OrenNayarDiffuseBSDF

#: The inputs this model uses; every other input of the nodedef is reported when set.
MODELLED = ("base_weight", "base_color", "base_diffuse_roughness", "base_metalness",
            "specular_weight", "specular_color", "specular_roughness", "specular_ior",
            "geometry_normal")

SELECTIONS = ("length", "max", "uniform")
LOBE_NAMES = ("diffuse", "specular", "metal")
_OPTIONS = (("selection", "length"), ("specular_sampling", "vndf"), ("multiscatter", True))


class IgnoredInputWarning(UserWarning):
    """An OpenPBR input outside the modelled base substrate was set (it has no effect)."""


class Lobe(NamedTuple):
    """One lobe of the mixture at given outgoing directions.

    weight : (..., 3) RGB mixture weight w_k (includes base_metalness, the albedo scaling)
    albedo : (..., 3) directional albedo E_k(wo) of the lobe's own BRDF
    probability : (...) selection probability P_k
    """
    name: str
    weight: np.ndarray
    albedo: np.ndarray
    probability: np.ndarray


class OpenPBRSurface(metaclass=NodeMeta):
    """OpenPBR Surface base substrate: EON diffuse + dielectric GGX specular + F82 metal.

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
    """

    NODEDEF = "ND_open_pbr_surface_surfaceshader"

    @classmethod
    def signature(cls):
        return node_signature(cls.NODEDEF, _OPTIONS, keyword_only=True)

    @classmethod
    def defaults(cls):
        """Default value of every input, by name (None: supplied by the renderer)."""
        return {n: d.default for n, d in nodedef_inputs(cls.NODEDEF).items()}

    def __init__(self, **kwargs):
        values = bind_inputs(type(self), (), kwargs)
        self.selection = values.pop("selection")
        self.specular_sampling = values.pop("specular_sampling")
        self.multiscatter = values.pop("multiscatter")
        if self.selection not in SELECTIONS:
            raise ValueError(f"selection must be one of {', '.join(SELECTIONS)}; got {self.selection!r}")
        if self.specular_sampling not in ggx.SAMPLING_METHODS:
            raise ValueError(f"specular_sampling must be one of {', '.join(ggx.SAMPLING_METHODS)}; "
                             f"got {self.specular_sampling!r}")
        if not isinstance(self.multiscatter, (bool, np.bool_)):
            raise TypeError(f"multiscatter must be a bool, got {type(self.multiscatter).__name__}")
        defs = nodedef_inputs(self.NODEDEF)
        self.inputs = {n: convert_input(defs[n], v) for n, v in values.items()}
        self._ignored = {n: v for n, v in self.inputs.items()
                         if n not in MODELLED and not is_default(defs[n], v)}
        if self._ignored:
            warnings.warn(f"OpenPBRSurface models the base substrate only; these inputs have no effect: "
                          f"{', '.join(self._ignored)}", IgnoredInputWarning, stacklevel=2)
        self._setup()

    # ------------------------------------------------------------------ parameters
    def _setup(self):
        p = self.inputs
        self.frame = Frame(p["geometry_normal"])
        self.metalness = p["base_metalness"]
        self.roughness = p["specular_roughness"]
        self.alpha = ggx.alpha_of(self.roughness)
        x = fresnel.modulated_ior_parameter(p["specular_weight"], p["specular_ior"])
        if np.any(x < 0.0):
            warnings.warn("specular_ior < 1: total internal reflection is not modelled; the Fresnel "
                          "factor of the reciprocal index (same F0) is used", UserWarning, stacklevel=3)
        self.x = np.abs(x)                       # sqrt(F0) of the modulated index, eta' >= 1
        self.eta = fresnel.eta_of_parameter(self.x)
        self.metal_f0 = p["base_weight"][..., None] * p["base_color"]
        self.diffuse = OrenNayarDiffuseBSDF(1.0, p["base_color"], p["base_diffuse_roughness"], True)
        dielectric = np.any(self.metalness < 1.0)
        self.active = tuple(name for name, on in (
            ("diffuse", dielectric and np.any(p["base_weight"] > 0.0)),
            ("specular", dielectric and np.any(self.x > 0.0) and np.any(p["specular_color"] > 0.0)),
            ("metal", np.any(self.metalness > 0.0) and np.any(p["specular_weight"] > 0.0)),
        ) if on) or ("diffuse",)
        if "metal" in self.active:
            c = np.linspace(0.0, 1.0, 257).reshape((257,) + (1,) * self.metal_f0.ndim)
            if np.any(fresnel.fresnel_f82_tint(c, self.metal_f0, p["specular_color"]) < 0.0):
                warnings.warn("the F82-tint Fresnel of this metal is negative at some angles (dark "
                              "base_color with a dark specular_color): the published formula is used "
                              "unclamped, so the metal lobe and its albedo can be negative", UserWarning,
                              stacklevel=3)

    @property
    def ignored_inputs(self):
        """{name: value} of the set inputs this model does not use (coat, fuzz, ...)."""
        return dict(self._ignored)

    def _local(self, name, w):
        return self.frame.to_local(ar.directions(name, w, np.float64))

    def _ms(self, mu_o, f0, channels=False):
        """Multiple-scattering factor 1 + F0 (1 - E1(mu_o))/E1(mu_o) (Turquin 2019), or 1.

        ``channels``: f0 has a trailing RGB axis (the metal), mu_o has not.
        """
        E1 = tables.ggx_albedo(mu_o, self.roughness)
        if channels:
            E1 = E1[..., None]
        if not self.multiscatter:
            return np.ones_like(E1 * f0)
        return 1.0 + f0 * ((1.0 - E1) / E1)

    def _specular_albedo(self, mu_o):
        """E_specular(mu_o) (untinted, with the multiple-scattering factor), shape (...)."""
        if "specular" not in self.active:
            return np.zeros(np.shape(mu_o))
        E = tables.dielectric_albedo(mu_o, self.roughness, self.x)
        return E * self._ms(mu_o, np.square(self.x))

    # ------------------------------------------------------------------ lobes
    def _lobes_local(self, wo):
        """[(name, weight, albedo)] at local wo, weights/albedos (..., 3); zero below the horizon."""
        mu = wo[..., 2]
        above = (mu > 0.0)[..., None]
        muc = np.clip(mu, 0.0, 1.0)
        p = self.inputs
        one_m = (1.0 - self.metalness)[..., None]
        out = []
        for name in self.active:
            if name == "diffuse":
                w = one_m * p["base_weight"][..., None] * (1.0 - self._specular_albedo(muc))[..., None]
                E = self.diffuse.albedo(wo)
            elif name == "specular":
                w = one_m * p["specular_color"]
                E = np.broadcast_to(self._specular_albedo(muc)[..., None], np.shape(muc) + (3,))
            else:
                w = (self.metalness * p["specular_weight"])[..., None] * np.ones(3)
                E = (tables.f82_albedo(muc, self.roughness, self.metal_f0, p["specular_color"])
                     * self._ms(muc, self.metal_f0, channels=True))
            w, E = np.broadcast_arrays(w, np.where(above, E, 0.0))
            out.append((name, w, E))
        return out

    def _probabilities(self, lobes):
        """P_k (K, ...) from [(name, w, E)]."""
        lead = np.broadcast_shapes(*(w.shape[:-1] for _, w, _ in lobes))
        K = len(lobes)
        if K == 1 or self.selection == "uniform":
            return np.full((K,) + lead, 1.0 / K)
        s = np.stack([np.broadcast_to(w * E, lead + (3,)) for _, w, E in lobes])
        if self.selection == "length":
            s = np.sqrt(np.einsum("k...c,k...c->k...", s, s))
        else:
            s = np.max(np.abs(s), axis=-1)
        total = s.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            P = s / total
        # a black surface (every w E = 0): any valid distribution; f = 0 anyway
        return np.where(total > 0.0, P, 1.0 / K)

    def lobes(self, wo):
        """The active lobes at wo: list of ``Lobe(name, weight, albedo, probability)``.

        Probabilities sum to 1 and are proportional to |w_k * E_k| (see ``selection``).
        """
        lobes = self._lobes_local(self._local("wo", wo))
        P = self._probabilities(lobes)
        return [Lobe(n, w, E, P[k]) for k, (n, w, E) in enumerate(lobes)]

    # ------------------------------------------------------------------ lobe BRDFs and pdfs
    def _lobe_brdf(self, name, wi, wo):
        """The lobe's own BRDF (..., 3) (weights not applied), local directions."""
        if name == "diffuse":
            return self.diffuse.eval(wi, wo)
        m, c = ggx.microfacet_terms(wi, wo, self.alpha)
        mu_o = np.clip(wo[..., 2], 0.0, 1.0)
        if name == "specular":
            F = fresnel.fresnel_dielectric(c, self.eta) * self._ms(mu_o, np.square(self.x))
            return np.broadcast_to((F * m)[..., None], np.shape(m) + (3,))
        F = fresnel.fresnel_f82_tint(c, self.metal_f0, self.inputs["specular_color"])
        return F * self._ms(mu_o, self.metal_f0, channels=True) * m[..., None]

    def _lobe_pdf(self, name, wi, wo):
        if name == "diffuse":
            return self.diffuse.pdf(wo, wi)
        return ggx.reflection_pdf(wo, wi, self.alpha, self.specular_sampling)

    # ------------------------------------------------------------------ verbs
    def lobe_eval(self, name, wi, wo):
        """The BRDF f_k of one lobe (its weight w_k not applied), shape (..., 3).

        ``eval`` is sum_k w_k f_k over ``lobes``; ``Lobe.albedo`` is the albedo of f_k.
        """
        if name not in self.active:
            raise ValueError(f"name: {name!r} is not an active lobe of this surface; "
                             f"active: {', '.join(self.active)}")
        dtype = ar.result_dtype(wi, wo)
        f = self._lobe_brdf(name, self._local("wi", wi), self._local("wo", wo))
        return np.asarray(f).astype(dtype, copy=False)

    def eval(self, wi, wo):
        """BSDF value sum_k w_k(wo) f_k(wi, wo) without the cosine factor, shape (..., 3)."""
        dtype = ar.result_dtype(wi, wo)
        wi, wo = self._local("wi", wi), self._local("wo", wo)
        total = 0.0
        for name, w, _ in self._lobes_local(wo):
            total = total + w * self._lobe_brdf(name, wi, wo)
        return np.asarray(total).astype(dtype, copy=False)

    def albedo(self, wo):
        """Directional albedo sum_k w_k E_k(wo), shape (..., 3)."""
        dtype = ar.result_dtype(wo)
        total = 0.0
        for _, w, E in self._lobes_local(self._local("wo", wo)):
            total = total + w * E
        return np.asarray(total).astype(dtype, copy=False)

    def _lobe_pdfs(self, wo, wi, lobes):
        """pdf_k(wi | wo) of every lobe, stacked: (K, ...)."""
        pdfs = [self._lobe_pdf(name, wi, wo) for name, _, _ in lobes]
        return np.stack(np.broadcast_arrays(*pdfs))

    @staticmethod
    def _mixture(P, pdfs):
        total = 0.0
        for k in range(len(pdfs)):
            total = total + P[k] * pdfs[k]
        return total

    def pdf(self, wo, wi):
        """One-sample mixture pdf sum_k P_k(wo) pdf_k(wi | wo) (solid angle)."""
        dtype = ar.result_dtype(wo, wi)
        wo, wi = self._local("wo", wo), self._local("wi", wi)
        lobes = self._lobes_local(wo)
        pdf = self._mixture(self._probabilities(lobes), self._lobe_pdfs(wo, wi, lobes))
        return np.asarray(pdf).astype(dtype, copy=False)

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
            May lie below the horizon (GGX reflections): f = 0 there.
        pdf : (...)
            The mixture pdf ``pdf(wo, wi)``; 0 marks a failed sample (to be discarded):
            wo below the horizon, or with ``specular_sampling="ndf"`` a microfacet normal
            facing away from wo (NDF sampling is defective there: its pdf integrates to the
            success probability, and the estimator stays unbiased with failed samples
            counted as 0).
        """
        dtype = ar.result_dtype(wo, u)
        wo = self._local("wo", wo)
        u = ar.in_range("u", u, np.float64, 0.0, 1.0, " (uniform random numbers)", hi_open=True)
        if u.ndim == 0 or u.shape[-1] not in (2, 3):
            raise ValueError(f"u must have shape (..., 3) or (..., 2), got shape {u.shape}")
        lobes = self._lobes_local(wo)
        P = self._probabilities(lobes)
        lead = ar.broadcast_leading(wo=wo.shape[:-1], u=u.shape[:-1], probabilities=P.shape[1:])
        K = len(lobes)
        P = np.broadcast_to(P.reshape((K,) + (1,) * (len(lead) + 1 - P.ndim) + P.shape[1:]),
                            (K,) + lead).reshape(K, -1)
        uf = ar.flat(u, lead, u.shape[-1])
        wof = ar.flat(wo, lead, 3)
        cdf = np.cumsum(P, axis=0)
        sel = uf[:, 0]
        k = np.minimum((sel[None, :] >= cdf).sum(axis=0), len(lobes) - 1)
        if u.shape[-1] == 3:
            u1, u2 = uf[:, 1], uf[:, 2]
        else:
            n = np.arange(len(sel))
            lo = np.where(k > 0, cdf[np.maximum(k - 1, 0), n], 0.0)
            Pk = P[k, n]
            # Pk = 0 only when rounding leaves the CDF's end below u0: any u1 will do
            with np.errstate(invalid="ignore", divide="ignore"):
                u1 = np.where(Pk > 0.0, np.clip((sel - lo) / Pk, 0.0, np.nextafter(1.0, 0.0)), 0.0)
            u2 = uf[:, 1]
        wi = np.empty_like(wof)
        # pdf of the chosen lobe at its own sample: 0 marks a failed sample (wo below the
        # horizon; an NDF-sampled h facing away from wo), which must stay discarded rather
        # than be credited to another lobe's density
        own = np.empty(len(sel))
        for j, (name, _, _) in enumerate(lobes):
            idx = np.flatnonzero(k == j)
            if idx.size == 0:
                continue
            if name == "diffuse":
                diff = self._diffuse_at(idx, lead)
                wi[idx], own[idx] = diff.sample(wof[idx], np.stack([u1[idx], u2[idx]], axis=-1))
            else:
                a = ar.flat(np.asarray(self.alpha), lead)[idx]
                wi[idx], own[idx] = ggx.sample_reflection(wof[idx], a, u1[idx], u2[idx], self.specular_sampling)
        # the mixture pdf, with the chosen lobe's term from its sampler (as OpenPBR-viewer
        # does): equal to pdf(wo, wi) to rounding, and exactly the lobe's own pdf when the
        # surface has one lobe
        wi = wi.reshape(lead + (3,))
        pdfs = np.broadcast_to(self._lobe_pdfs(wo, wi, lobes), (K,) + lead).reshape(K, -1).copy()
        pdfs[k, np.arange(len(sel))] = own
        pdf = np.where(own > 0.0, self._mixture(P, pdfs), 0.0).reshape(lead)
        return self.frame.to_world(wi).astype(dtype, copy=False), np.asarray(pdf).astype(dtype, copy=False)

    def _diffuse_at(self, idx, lead):
        """The diffuse lobe restricted to flat indices idx of the broadcast shape lead."""
        p = self.inputs
        return OrenNayarDiffuseBSDF(1.0, ar.flat(p["base_color"], lead, 3)[idx],
                                    ar.flat(p["base_diffuse_roughness"], lead)[idx], True)

    def __repr__(self):
        set_ = {n: v for n, v in self.inputs.items()
                if not is_default(nodedef_inputs(self.NODEDEF)[n], v)}
        return f"OpenPBRSurface({', '.join(f'{n}={np.asarray(v).tolist()}' for n, v in set_.items())})"

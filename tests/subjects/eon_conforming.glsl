// EON, the energy-preserving Oren-Nayar lobe, written from the paper's equations:
// Portsmouth, Kutz, Hill, "EON: A practical energy-preserving rough diffuse BRDF",
// JCGT 14(1), 2025 (Eq. 10-13 for FON and its exact albedo, Eq. 15 for the average
// albedo, Eq. 16-20 for the multiple-scattering term).
//
// A test subject of openpbr-diffuse with the template signatures: local shading frame, normal +z,
// wi towards the light and wo towards the viewer, both pointing away from the surface; f
// without the cosine factor; roughness r in [0, 1]; rho linear RGB.
//
//   openpbr-diffuse check --glsl eon_conforming.glsl --function f --albedo-function albedo

const float EON_PI = 3.14159265358979;
const float EON_C1 = 0.5 - 2.0 / (3.0 * EON_PI);          // Eq. 11: A_F = 1 / (1 + C1 r)
const float EON_C2 = 2.0 / 3.0 - 28.0 / (15.0 * EON_PI);  // Eq. 15: <E_F> = A_F (1 + C2 r)
const float EON_EPS = 1e-7;                                // Listing 1's guard of f_ms

// Eq. 12-13, the exact directional albedo of the FON lobe.  (S / mu)(1 - S^3) is written
// S mu (1 + S + S^2) / (1 + S), since 1 - S^3 = (1 - S)(1 + S + S^2) and 1 - S = mu^2 / (1 + S):
// finite at mu = 0, where E_F = 1.
float eon_EF(float mu, float r)
{
    float S = sqrt(max(0.0, 1.0 - mu * mu));
    float GF = S * (acos(clamp(mu, -1.0, 1.0)) - S * mu)
             + (2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S);
    return (1.0 + r * GF / EON_PI) / (1.0 + EON_C1 * r);
}

// Eq. 15 and 17: <E_F> and the multiple-scattering albedo rho_ms.
float eon_EF_avg(float r)
{
    return (1.0 + EON_C2 * r) / (1.0 + EON_C1 * r);
}

vec3 eon_rho_ms(vec3 rho, float avg)
{
    return rho * rho * avg / (vec3(1.0) - rho * (1.0 - avg));
}

vec3 f(vec3 wi, vec3 wo, float roughness, vec3 rho)
{
    if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);      // single-sided
    float r = roughness;
    float mu_i = wi.z, mu_o = wo.z;
    float LdotV = dot(wi, wo);
    float s = LdotV - mu_i * mu_o;                          // Eq. 10
    float s_over_t = s > 0.0 ? s / max(mu_i, mu_o) : s;
    float AF = 1.0 / (1.0 + EON_C1 * r);
    vec3 f_ss = rho / EON_PI * AF * (1.0 + r * s_over_t);  // FON, Eq. 10-11
    float avg = eon_EF_avg(r);
    vec3 rho_ms = eon_rho_ms(rho, avg);
    vec3 f_ms = rho_ms / EON_PI * max(EON_EPS, 1.0 - eon_EF(mu_o, r)) * max(EON_EPS, 1.0 - eon_EF(mu_i, r))
              / max(EON_EPS, 1.0 - avg);                    // Eq. 16
    return f_ss + f_ms;
}

vec3 albedo(float mu, float roughness, vec3 rho)
{
    float r = roughness;
    float EF = eon_EF(mu, r);
    vec3 rho_ms = eon_rho_ms(rho, eon_EF_avg(r));
    return rho * EF + rho_ms * (1.0 - EF);                  // Eq. 20
}

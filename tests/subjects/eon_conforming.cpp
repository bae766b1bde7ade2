// EON, the energy-preserving Oren-Nayar lobe, written from the paper's equations:
// Portsmouth, Kutz, Hill, "EON: A practical energy-preserving rough diffuse BRDF",
// JCGT 14(1), 2025 (Eq. 10-13 for FON and its exact albedo, Eq. 15 for the average
// albedo, Eq. 16-20 for the multiple-scattering term).
//
// A test subject of openpbr-diffuse with the template signatures (C++17, GLM): local shading
// frame, normal +z, wi towards the light and wo towards the viewer, both pointing away from the
// surface; f without the cosine factor; roughness r in [0, 1]; rho linear RGB.
//
//   openpbr-diffuse check --cpp eon_conforming.cpp --function f --albedo-function albedo
#include <algorithm>
#include <cmath>
#include <glm/glm.hpp>

static const float EON_PI = 3.14159265358979f;
static const float EON_C1 = 0.5f - 2.0f / (3.0f * EON_PI);          // Eq. 11: A_F = 1 / (1 + C1 r)
static const float EON_C2 = 2.0f / 3.0f - 28.0f / (15.0f * EON_PI); // Eq. 15: <E_F> = A_F (1 + C2 r)
static const float EON_EPS = 1e-7f;                                  // Listing 1's guard of f_ms

// Eq. 12-13, the exact directional albedo of the FON lobe, with (S / mu)(1 - S^3) written
// S mu (1 + S + S^2) / (1 + S): finite at mu = 0, where E_F = 1.
static float eon_EF(float mu, float r)
{
    const float S = std::sqrt(std::max(0.0f, 1.0f - mu * mu));
    const float GF = S * (std::acos(std::min(1.0f, std::max(-1.0f, mu))) - S * mu)
                   + (2.0f / 3.0f) * (S * mu * (1.0f + S + S * S) / (1.0f + S) - S);
    return (1.0f + r * GF / EON_PI) / (1.0f + EON_C1 * r);
}

// Eq. 15 and 17: <E_F> and the multiple-scattering albedo rho_ms.
static float eon_EF_avg(float r)
{
    return (1.0f + EON_C2 * r) / (1.0f + EON_C1 * r);
}

static glm::vec3 eon_rho_ms(glm::vec3 rho, float avg)
{
    return rho * rho * avg / (glm::vec3(1.0f) - rho * (1.0f - avg));
}

glm::vec3 f(glm::vec3 wi, glm::vec3 wo, float roughness, glm::vec3 rho)
{
    if (wi.z <= 0.0f || wo.z <= 0.0f) return glm::vec3(0.0f);      // single-sided
    float r = roughness;
    float mu_i = wi.z, mu_o = wo.z;
    float LdotV = glm::dot(wi, wo);
    const float s = LdotV - mu_i * mu_o;                            // Eq. 10
    const float s_over_t = s > 0.0f ? s / std::max(mu_i, mu_o) : s;
    const float AF = 1.0f / (1.0f + EON_C1 * r);
    glm::vec3 f_ss = rho / EON_PI * AF * (1.0f + r * s_over_t);    // FON, Eq. 10-11
    const float avg = eon_EF_avg(r);
    glm::vec3 rho_ms = eon_rho_ms(rho, avg);
    glm::vec3 f_ms = rho_ms / EON_PI * std::max(EON_EPS, 1.0f - eon_EF(mu_o, r))
                   * std::max(EON_EPS, 1.0f - eon_EF(mu_i, r)) / std::max(EON_EPS, 1.0f - avg);   // Eq. 16
    return f_ss + f_ms;
}

glm::vec3 albedo(float mu, float roughness, glm::vec3 rho)
{
    float r = roughness;
    const float EF = eon_EF(mu, r);
    glm::vec3 rho_ms = eon_rho_ms(rho, eon_EF_avg(r));
    return rho * EF + rho_ms * (1.0f - EF);                         // Eq. 20
}

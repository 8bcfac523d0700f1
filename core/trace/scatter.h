// How a surface scatters light, for CPU and GPU: the materials of core/geometry/mesh.h
// (Lambertian, plain glazing, and Radiance's plastic, metal, trans and glass, grey) as the
// parts of one scattering event.
//
// At a hit the material gives, for the angle of incidence, the albedo of each part:
//   diffuse   Lambertian reflection
//   lobe      the isotropic Ward lobe of core/trace/ward.h (roughness above kMirrorRoughness)
//   mirror    mirror reflection (a lobe of roughness at most kMirrorRoughness, as Radiance
//             treats it, or glass's Fresnel reflection)
//   straight  straight-through transmission (glazing, glass, trans's specular transmission)
//   through   Lambertian transmission (trans)
// A path picks one part with probability albedo / total and goes on by it. Parts with a
// density (diffuse, lobe, through) are the smooth ones: a mode may connect a vertex to a light
// (next-event estimation, two_stage_modes.h) through them, and Value gives what a connection
// carries and the density with which Sample would have drawn the same direction, for multiple
// importance sampling. Mirror and straight are delta parts: no connection reaches them, and
// the direction they give has density 0 ("no other technique").
//
// A direction drawn from a smooth part weighs pi f |cos| / (pi p), f the smooth parts' BRDF
// and BTDF together and p their mixture's density (the one-sample mixture estimator): a
// Lambertian surface weighs its total albedo, a lobe its Ward estimator. A delta part weighs
// the total albedo.
#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"
#include "core/trace/glass.h"
#include "core/trace/lobe_energy.h"
#include "core/trace/philox.h"
#include "core/trace/sampling.h"
#include "core/trace/ward.h"

namespace fenestra {

// Surface properties as the tracer sees them (grey). The Lambertian case sets reflectance
// only; plain glazing adds transmittance; Radiance's materials set the rest
// (PrepareTraceGeometry converts core/geometry/mesh.h's Material).
struct TraceMaterial {
  float reflectance;               // Lambertian reflectance
  float transmittance;             // straight-through transmittance; < 0 = opaque
  float specular = 0.0f;           // reflectance of the specular part (lobe or mirror)
  float roughness = 0.0f;          // the lobe's roughness (Ward's alpha)
  float through = 0.0f;            // Lambertian transmittance
  float glass = 0.0f;              // > 0: Radiance glass of this transmissivity (its t_n):
                                   // mirror reflection and straight transmission by the angle
  bool straight_scatters = false;  // straight transmission counts as a scattering event (trans)
  LobeEnergy energy = {};          // what the lobe loses and gets back (lobe_energy.h)
};

// Roughness at or below which a lobe is a mirror: Radiance's, alpha^2 <= 1e-6 (normal.c).
inline constexpr float kMirrorRoughness = 1e-3f;

// The parts of a material at one point and angle of incidence.
struct SurfaceScatter {
  Vec3f normal;  // unit, on the side the light arrived from
  Vec3f view;    // unit, back along the arriving ray
  float diffuse = 0, lobe = 0, mirror = 0, straight = 0, through = 0;
  float alpha = 0;  // the lobe's roughness
  float total = 0;  // sum of the parts
  bool straight_scatters = false;
  const LobeEnergy* energy = nullptr;  // the lobe's, when it has one
  float kept = 1.0f;  // E(mu_v): the share of the lobe's light (and draws) in Ward's lobe

  // Whether any part has a density, so that next-event estimation can reach it.
  FENESTRA_CPU_GPU bool Smooth() const { return diffuse + lobe + through > 0.0f; }

  // pi f(view, l) |cos l| of the smooth parts for unit `l` (on either side), and in `pdf` the
  // solid-angle density with which Sample draws l.
  FENESTRA_CPU_GPU float Value(Vec3f l, float* pdf) const {
    const float cos_l = Dot(normal, l);
    *pdf = 0.0f;
    if (!(total > 0.0f)) return 0.0f;
    const float inverse_total = 1.0f / total;
    if (cos_l > 0.0f) {
      float value = diffuse * cos_l;
      *pdf = diffuse * inverse_total * cos_l * kInvPi;
      if (lobe > 0.0f) {
        // Ward's lobe, drawn with probability E(mu_v), and the light it loses, drawn in
        // proportion to Lost(mu_l) mu_l (lobe_energy.h)
        const WardLobe ward{0.0f, lobe, alpha};
        float lobe_value = kPiF * ward.Lobe(normal, view, l);
        float lobe_pdf = kept * ward.LobePdf(normal, view, l);
        if (energy->Compensates()) {
          lobe_value += lobe * (1.0f - kept) * energy->Lost(cos_l) / (1.0f - energy->average);
          lobe_pdf += (1.0f - kept) * energy->LostDensity(cos_l);
        }
        value += lobe_value * cos_l;
        *pdf += lobe * inverse_total * lobe_pdf;
      }
      return value;
    }
    if (cos_l < 0.0f && through > 0.0f) {
      *pdf = through * inverse_total * -cos_l * kInvPi;
      return through * -cos_l;
    }
    return 0.0f;
  }

  static constexpr float kInvPi = 0.318309886183790672f;
};

// What Sample drew.
struct ScatterSample {
  Vec3f direction;  // unit
  float factor;     // multiplies the path's weight (0: the path ends)
  float pdf;        // of `direction` among the smooth parts; 0 after a delta part
  bool straight;    // went straight through
  bool through;     // left on the far side (straight or Lambertian transmission)
  bool scatters;    // counts as a reflection (everything but a plain straight pass)
};

// The parts of `m` where a ray arriving along -view meets a surface of unit normal `normal`
// (turned to the ray's side). The result points into `m` (its lobe's energy table), so `m` must
// outlive it: a temporary is refused (the overload below).
FENESTRA_CPU_GPU inline SurfaceScatter ScatterAt(const TraceMaterial& m, Vec3f normal, Vec3f view) {
  SurfaceScatter s;
  s.normal = normal;
  s.view = view;
  if (m.glass > 0.0f) {
    const GlassPane pane{m.glass};
    const float c = Dot(normal, view);
    s.mirror = pane.Reflectance(c);
    s.straight = pane.Transmittance(c);
  } else {
    s.diffuse = m.reflectance;
    s.straight = m.transmittance > 0.0f ? m.transmittance : 0.0f;
    s.through = m.through;
    (m.roughness > kMirrorRoughness ? s.lobe : s.mirror) = m.specular;
    s.alpha = m.roughness;
    if (s.lobe > 0.0f) {
      s.energy = &m.energy;
      s.kept = m.energy.Compensates() ? m.energy.At(Dot(normal, view)) : 1.0f;
    }
    s.straight_scatters = m.straight_scatters;
  }
  s.total = s.diffuse + s.lobe + s.mirror + s.straight + s.through;
  return s;
}

FENESTRA_CPU_GPU SurfaceScatter ScatterAt(const TraceMaterial&& m, Vec3f normal,
                                          Vec3f view) = delete;

// One part of `s` drawn with u.u[3] and a direction from it with u.u[0], u.u[1].
FENESTRA_CPU_GPU inline ScatterSample Sample(const SurfaceScatter& s, const Uniform4& u) {
  ScatterSample out{s.view, 0.0f, 0.0f, false, false, true};
  float pick = u.u[3] * s.total;
  if (pick < s.straight) {
    out.direction = -s.view;
    out.factor = s.total;
    out.straight = out.through = true;
    out.scatters = s.straight_scatters;
    return out;
  }
  pick -= s.straight;
  if (pick < s.mirror) {
    out.direction = s.normal * (2.0f * Dot(s.normal, s.view)) - s.view;
    out.factor = Dot(s.normal, out.direction) > 0.0f ? s.total : 0.0f;
    return out;
  }
  pick -= s.mirror;
  if (pick < s.through) {
    out.direction = SampleCosineHemisphere(-s.normal, u.u[0], u.u[1]);
    out.through = true;
  } else if (pick - s.through < s.lobe) {
    // Ward's lobe with probability E(mu_v) (the rest of u3's interval), else its lost light
    if (pick - s.through < s.lobe * s.kept) {
      Vec3f t, b;
      OrthonormalBasis(s.normal, &t, &b);
      float weight;
      out.direction = WardLobe{0.0f, s.lobe, s.alpha}.SampleLobe(s.normal, t, b, s.view, u.u[0],
                                                                 u.u[1], &weight);
      if (!(weight > 0.0f)) return out;  // below the surface: nothing
      out.direction = Normalize(out.direction);
    } else {
      // The lost light, by Lost(mu_l) mu_l
      const float mu = s.energy->SampleLostCosine(u.u[0]);
      const float sine = sqrtf(fmaxf(0.0f, 1.0f - mu * mu)), phi = 2.0f * kPiF * u.u[1];
      Vec3f t, b;
      OrthonormalBasis(s.normal, &t, &b);
      out.direction = Normalize(t * (sine * cosf(phi)) + b * (sine * sinf(phi)) + s.normal * mu);
    }
  } else {
    out.direction = SampleCosineHemisphere(s.normal, u.u[0], u.u[1]);
  }
  // The mixture estimator; a purely Lambertian part skips the evaluation (value / pdf = total)
  if (s.lobe > 0.0f) {
    const float value = s.Value(out.direction, &out.pdf);
    out.factor = out.pdf > 0.0f ? value / (kPiF * out.pdf) : 0.0f;
  } else {
    const float cos_l = Dot(s.normal, out.direction);
    out.pdf =
        (out.through ? s.through : s.diffuse) / s.total * fabsf(cos_l) * SurfaceScatter::kInvPi;
    out.factor = s.total;
  }
  return out;
}

// The straight-through transmittance of `m` at an angle of incidence of cosine `c` (the direct
// sun's lines through glazing).
FENESTRA_CPU_GPU inline float StraightTransmittance(const TraceMaterial& m, float c) {
  if (m.glass > 0.0f) return GlassPane{m.glass}.Transmittance(fabsf(c));
  return m.transmittance > 0.0f ? m.transmittance : 0.0f;
}

}  // namespace fenestra

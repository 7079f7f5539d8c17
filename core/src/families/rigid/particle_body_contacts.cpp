// Cloth and shape particles against rigid bodies, two-way (the math is in
// particle_body_contacts.hpp).
#include "particle_body_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "body_correction.hpp"
#include "body_shape.hpp"
#include "body_solid.hpp"
#include "seiche/phase.hpp"

namespace seiche {

using rigid::RigidBody;
using rigid::SolidSurface;
using rigid::Vec3d;

namespace {

bool touches_bodies(Material m) { return m == Material::Cloth || m == Material::Shape; }

}  // namespace

bool ParticleBodyContacts::needed(const SceneDef& scene) {
  return !scene.rigid_bodies.empty() && (!scene.cloths.empty() || !scene.shapes.empty());
}

ParticleBodyContacts::ParticleBodyContacts(const SceneDef& scene, ParticleStore& store,
                                           std::vector<RigidBody>& bodies, rigid::BodyMeshFields& mesh_fields)
    : store_(store), bodies_(bodies) {
  for (std::size_t k = 0; k < scene.rigid_bodies.size(); ++k) {
    const RigidBodyDef& def = scene.rigid_bodies[k];
    const rigid::ShapeDims dims = rigid::body_shape_def(def);
    if (dims.shape == rigid::BodyShape::Mesh) mesh_sdfs_.push_back(mesh_fields.get(k));
    const MeshSdf* sdf = dims.shape == rigid::BodyShape::Mesh ? mesh_sdfs_.back().get() : nullptr;
    solids_.push_back({rigid::body_solid(dims, sdf), rigid::mass_properties(dims).extent});
    body_friction_.push_back(double(def.friction));
  }
  for (const ClothDef& c : scene.cloths) cloth_friction_.push_back(double(c.friction));
}

void ParticleBodyContacts::add_passes(std::vector<Pass>& passes) {
  passes.push_back({"particle-body pairs", Stage::Neighbors, pass_order::kParticleBodyPairs, true,
                    [this](const StepContext&) { find_candidates(); }});
  passes.push_back({"particle-body contacts", Stage::Iterate, pass_order::kParticleBodyContacts,
                    true, [this](const StepContext&) { solve(); }});
}

void ParticleBodyContacts::find_candidates() {
  candidates_.clear();
  const ParticleStore& s = store_;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!touches_bodies(phase_material(s.phase[i]))) continue;
    const Vec3d p{double(s.px[i]), double(s.py[i]), double(s.pz[i])};
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
      const Solid& solid = solids_[k];
      const double margin = kReachRadii * double(s.radius[i]) + kReachFraction * solid.extent;
      const Vec3d d = p - bodies_[k].x;
      const double reach = solid.extent + margin;
      if (!(dot(d, d) < reach * reach)) continue;
      // Within reach of the solid itself (a mesh's field is asked only near its band: its
      // bounding ball is the test).
      rigid::SurfacePenetration pen;
      if (solid.surface.shape == ColliderDef::Shape::Mesh ||
          rigid::penetration(solid.surface, rotate_back(bodies_[k].q, d),
                             double(s.radius[i]) + margin, pen))
        candidates_.push_back({std::uint32_t(i), std::uint32_t(k)});
    }
  }
}

void ParticleBodyContacts::solve() {
  ParticleStore& s = store_;
  for (const Candidate& c : candidates_) {
    const std::size_t i = c.particle;
    RigidBody& b = bodies_[c.body];
    const double radius = double(s.radius[i]);
    const Vec3d p{double(s.px[i]), double(s.py[i]), double(s.pz[i])};
    const Vec3d from_centre = p - b.x;
    const double bound = solids_[c.body].extent + radius;  // the ball that holds the solid's reach
    if (!(dot(from_centre, from_centre) < bound * bound)) continue;
    rigid::SurfacePenetration pen;
    if (!rigid::penetration(solids_[c.body].surface, rotate_back(b.q, from_centre), radius, pen))
      continue;
    const double depth = pen.depth;
    const Vec3d n = rotate(b.q, pen.normal);
    const Vec3d lever = p - (radius - depth) * n - b.x;
    const double w_p = double(s.w[i]);
    const double w_normal = w_p + rigid::positional_inverse_mass(b, lever, n);
    if (!(w_normal > 0.0)) continue;  // a pinned particle on a fixed body
    const double lambda = depth / w_normal;
    Vec3d moved = (w_p * lambda) * n;
    rigid::apply_positional_impulse(b, lever, -lambda * n);

    // Friction on the slip relative to the body point under the ball.
    const Material material = phase_material(s.phase[i]);
    const double mu = material == Material::Cloth
                          ? std::sqrt(body_friction_[c.body] * cloth_friction_[s.phase[i] >> 8])
                          : body_friction_[c.body];
    if (mu > 0.0) {
      const Vec3d local = rotate_back(b.q, lever);
      const Vec3d body_motion = b.world_point(local) - (b.x_prev + rotate(b.q_prev, local));
      const Vec3d particle_motion =
          p + moved - Vec3d{double(s.x[i]), double(s.y[i]), double(s.z[i])};
      const Vec3d slip = particle_motion - body_motion;
      const Vec3d slip_t = slip - dot(slip, n) * n;
      const double slip_length = length(slip_t);
      if (slip_length > 0.0) {
        const Vec3d t = (1.0 / slip_length) * slip_t;
        const double keep = slip_length <= mu * depth ? 1.0 : mu * depth / slip_length;
        const double w_tangent = w_p + rigid::positional_inverse_mass(b, lever, t);
        if (w_tangent > 0.0) {
          const double lambda_t = keep * slip_length / w_tangent;
          moved -= (w_p * lambda_t) * t;
          rigid::apply_positional_impulse(b, lever, lambda_t * t);
        }
      }
    }
    s.px[i] = float(p.x + moved.x), s.py[i] = float(p.y + moved.y), s.pz[i] = float(p.z + moved.z);
  }
}

}  // namespace seiche

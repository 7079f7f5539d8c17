// The family registry's rows (family_registry.hpp says how Simulation runs them). A new family
// adds its row here: its section, its phase and a builder that adds nothing when the scene
// lacks the section.
#include "family_registry.hpp"

#include "families/cloth/cloth_family.hpp"
#include "seiche/body_exporter.hpp"
#include "seiche/cloth_obj_exporter.hpp"
#include "families/collider/collider_family.hpp"
#include "families/contact/contact_family.hpp"
#include "families/distance/distance_family.hpp"
#include "families/fluid/fluid_family.hpp"
#include "families/fluid_body/fluid_body_family.hpp"
#include "families/motion/motion_family.hpp"
#include "families/rigid/particle_body_contacts.hpp"
#include "families/rigid/rigid_family.hpp"
#include "families/shape/shape_family.hpp"

namespace seiche {

std::size_t FamilyBuild::add_particles(std::size_t n) {
  const std::size_t first = store.size();
  store.resize(first + n);
  for (std::size_t k = first; k < first + n; ++k) store.id[k] = std::int32_t(k);
  return first;
}

namespace {

using Phase = FamilyRow::Phase;

void build_motion(FamilyBuild& b) { b.add(std::make_unique<MotionFamily>(b.store, b.scene.solver)); }

// Raw particles: their store index is their index in "particles" (distance constraints name
// them by it). No family of their own: the motion and the colliders move them, and the raw
// distance constraints (an OnParticles row) join them.
void build_raw_particles(FamilyBuild& b) {
  const std::size_t first = b.add_particles(b.scene.particles.size());
  ParticleStore& s = b.store;
  for (std::size_t k = 0; k < b.scene.particles.size(); ++k) {
    const ParticleDef& p = b.scene.particles[k];
    const std::size_t i = first + k;
    s.x[i] = p.x[0], s.y[i] = p.x[1], s.z[i] = p.x[2];
    s.vx[i] = p.v[0], s.vy[i] = p.v[1], s.vz[i] = p.v[2];
    s.w[i] = p.mass > 0.0f ? 1.0f / p.mass : 0.0f;
    s.phase[i] = make_phase(Material::Free);
    s.radius[i] = 0.0f;
  }
}

void build_fluid(FamilyBuild& b) {
  if (b.scene.fluids.empty()) return;
  const std::size_t first = b.add_particles(FluidFamily::particle_count(b.scene));
  b.add(std::make_unique<FluidFamily>(b.scene, b.store, first, b.reorder));
}

void build_cloth(FamilyBuild& b) {
  if (b.scene.cloths.empty()) return;
  auto cloth = std::make_unique<ClothFamily>(b.scene, b.store);  // builds the meshes
  const std::size_t first = b.add_particles(cloth->particle_count());
  b.add(std::move(cloth)).create(first);
}

void build_shapes(FamilyBuild& b) {
  if (b.scene.shapes.empty()) return;
  const std::size_t first = b.add_particles(ShapeFamily::particle_count(b.scene));
  b.add(std::make_unique<ShapeFamily>(b.scene, b.store, first));
}

void build_contact(FamilyBuild& b) {
  if (!ParticleContactStage::needed(b.scene)) return;
  const ClothFamily* cloth = b.find<ClothFamily>();
  const FluidFamily* fluid = b.find<FluidFamily>();
  b.add(std::make_unique<ContactFamily>(cloth ? &cloth->solver() : nullptr, b.scene, b.store,
                                        fluid ? &fluid->neighborhood() : nullptr,
                                        fluid ? fluid->solver().particle_radius() : 0.0f));
}

void build_distance(FamilyBuild& b) {
  if (b.scene.distance_constraints.empty()) return;
  b.add(std::make_unique<DistanceFamily>(b.scene, b.store));
}

void build_colliders(FamilyBuild& b) { b.add(std::make_unique<ColliderFamily>(b.scene, b.store)); }

// Rigid bodies are not particles: they have their own state, and their joints join only them.
// Their contacts share the mesh colliders' fields that the colliders' row built.
void build_rigid(FamilyBuild& b) {
  if (b.scene.rigid_bodies.empty()) return;
  const ColliderFamily* colliders = b.find<ColliderFamily>();
  b.add(std::make_unique<RigidFamily>(
      b.scene, colliders ? std::span(colliders->mesh_fields()) : std::span<const std::shared_ptr<const MeshSdf>>()));
}

// Cloth and shape particles against the bodies, two-way: only where both are in the scene.
void build_particle_body_contacts(FamilyBuild& b) {
  RigidFamily* rigid = b.find<RigidFamily>();
  if (rigid == nullptr || !ParticleBodyContacts::needed(b.scene)) return;
  b.add(std::make_unique<ParticleBodyContacts>(b.scene, b.store, rigid->bodies(), rigid->body_mesh_fields()));
}

// Bodies and shapes in fluid: their boundary particles in the fluid's density (only with fluid
// and bodies or shapes).
void build_fluid_body(FamilyBuild& b) {
  FluidFamily* fluid = b.find<FluidFamily>();
  RigidFamily* rigid = b.find<RigidFamily>();
  const ShapeFamily* shapes = b.find<ShapeFamily>();
  if (fluid == nullptr || (rigid == nullptr && shapes == nullptr)) return;
  b.add(std::make_unique<FluidBodyFamily>(b.scene, b.store, *fluid, rigid, shapes ? shapes->first_id() : 0));
}

constexpr FamilyRow kRows[] = {
    {"motion", Phase::Particles, build_motion},
    {"particles", Phase::Particles, build_raw_particles},
    {"fluids", Phase::Particles, build_fluid},
    {"cloths", Phase::Particles, build_cloth, make_cloth_obj_exporter},
    {"shapes", Phase::Particles, build_shapes},
    {"cloths", Phase::OnParticles, build_contact},
    {"distance_constraints", Phase::OnParticles, build_distance},
    {"colliders", Phase::OnParticles, build_colliders},
    {"rigid_bodies", Phase::OnParticles, build_rigid, make_body_exporter},
    {"rigid_bodies", Phase::OnParticles, build_particle_body_contacts},
    {"rigid_bodies", Phase::OnParticles, build_fluid_body},
};

}  // namespace

std::span<const FamilyRow> family_rows() { return kRows; }

std::vector<std::unique_ptr<FrameExporter>> family_exporters(const SceneDef& scene) {
  std::vector<std::unique_ptr<FrameExporter>> exporters;
  for (const FamilyRow& row : kRows)
    if (row.exporter != nullptr)
      if (auto e = row.exporter(scene)) exporters.push_back(std::move(e));
  return exporters;
}

}  // namespace seiche

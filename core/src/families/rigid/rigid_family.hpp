// Rigid bodies and the joints between them (scene sections "rigid_bodies" and "joints"): bodies
// with their own state in double precision (rigid_body.hpp), not particles, integrated per
// substep as in Müller et al. 2020, and joints solved as an extra pass of the iterations
// (joint.hpp), their corrections through the bodies' generalized inverse masses
// (body_correction.hpp).
//
// What the family holds and where:
//   bodies   position, orientation, velocity, angular velocity (state: checkpoint chunk
//            "rigid.bodies"); mass and inertia (rebuilt from the scene on a resume)
//   joints   their connector points and axes in the bodies' frames (from the scene); their
//            multipliers and motors' start angles and positions live within a substep, so are
//            not state, but for the tree solve's (joint_tree.hpp: its geometric stiffness reads the
//            previous substep's; checkpoint chunk "rigid.joint_trees", present with a tree)
// Passes: "body predict" (Predict, kBodyPredict) and "body update" (Update, kBodyUpdate);
// with joints, a reset (BeginSubstep, kJointReset) and "joints" every iteration (kJoints);
// contacts with the static world (world_contacts.hpp): "body contacts" every iteration
// (kBodyContacts, after the joints) and "body contact velocities" after the update
// (kBodyContactVelocities: dynamic friction and restitution); their multipliers live within a
// substep (reset in the predict pass), so are not state either. Contacts between bodies
// (body_contacts.hpp, where two bodies not on one joint can touch) run in the same two passes,
// after those with the world (whose touches tell which bodies rest on it); no state either.
// Error rows: "joint_drift" (each joint's positional error, JointSolver::error, relative to its
// length), "joint_angle_error" (radians; hinge, fixed, slider and universal joints), "body_energy" (|E - E_0| / E_0, E the bodies' kinetic plus
// gravitational energy, zero at the domain's lowest corner as for the particles).
// With a fluid, the fluid_body family (families/fluid_body/) couples the bodies and the fluid
// both ways through bodies().
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "body_contacts.hpp"
#include "body_solid.hpp"
#include "joint.hpp"
#include "loop/family.hpp"
#include "rigid_body.hpp"
#include "world_contacts.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/scene.hpp"

namespace seiche {

class RigidFamily final : public Family {
 public:
  /// `mesh_fields`: the fields of the scene's mesh colliders, built by the collider family
  /// (ColliderFamily::mesh_fields()), shared by the bodies' contacts with them (none needed in a
  /// scene without mesh colliders; std::invalid_argument when they do not match).
  explicit RigidFamily(const SceneDef& scene, std::span<const std::shared_ptr<const MeshSdf>> mesh_fields = {});

  void add_passes(std::vector<Pass>& passes) override;
  void measure(FrameMetrics& m) override;
  void save_state(CheckpointChunks& chunks) const override;
  void restore_state(const CheckpointChunks& chunks) override;

  const std::vector<rigid::RigidBody>& bodies() const { return bodies_; }
  /// The bodies, for the passes of other families that move them (particle_body_contacts.hpp,
  /// fluid_body/fluid_body_family.hpp).
  std::vector<rigid::RigidBody>& bodies() { return bodies_; }
  /// The mesh bodies' fields, built on first request and shared by whatever touches the bodies.
  rigid::BodyMeshFields& body_mesh_fields() { return body_mesh_fields_; }
  const rigid::JointSolver& joints() const { return joints_; }
  /// Every body's position, orientation and velocities now, in scene order.
  std::vector<BodyPose> poses() const;
  /// The bodies' kinetic plus gravitational energy (J), zero at the domain's lowest corner.
  double energy() const;

 private:
  void predict();
  void update();

  std::vector<rigid::RigidBody> bodies_;
  rigid::JointSolver joints_;
  rigid::WorldContacts contacts_;  // with the domain's walls and the colliders
  rigid::BodyMeshFields body_mesh_fields_;  // before body_contacts_, which reads it
  rigid::BodyContacts body_contacts_;  // between bodies
  rigid::Vec3d gravity_;
  rigid::Vec3d lowest_corner_;
  double h_;             // the substep (s), in double: frame_dt / substeps
  double start_energy_;  // E_0, for the energy row
};

}  // namespace seiche

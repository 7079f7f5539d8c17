// The scene definition: plain structs with documented defaults and units. The JSON scene format
// (docs/scene-format.md) maps 1:1 onto these structs: a key's name is the member's name, and a
// key left out takes the default written here. Each struct's keys (unit, range, documentation)
// are declared once, in the key table of its section's reader (core/src/scene/ for solver,
// domain and output; core/src/families/<family>/<family>_reader.cpp for the others), from which
// the loader checks the input and docs/scene-format.md's key tables are generated.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace seiche {

using Vec3 = std::array<float, 3>;

struct ClothMesh;      // core/src/families/cloth/cloth_mesh.hpp
struct ClothTopology;  // core/src/families/cloth/cloth_mesh.hpp
namespace rigid {
struct BodyMesh;  // core/src/families/rigid/body_mesh.hpp
}
struct ShapeSites;     // core/src/families/shape/shape_sites.hpp

/// "solver": time stepping and the fluid solver's numerical settings.
struct SolverDef {
  double frame_dt = 1.0 / 60.0;  ///< s, time per output frame
  int substeps = 8;              ///< XPBD substeps per frame (1..10000)
  int iterations = 2;            ///< constraint iterations per substep (1..10000), at least
  /// The fluid's mean density error (a fraction, in [0, 1)) the iterations aim for: after the
  /// first `iterations`, a substep iterates on while the mean of max(rho / rho0 - 1, 0) over the
  /// fluid, measured at the start of its last iteration, exceeds it; 0 = exactly `iterations`.
  float density_tolerance = 0.01f;
  int max_iterations = 32;       ///< cap of those extra iterations (1..10000; never below iterations)
  Vec3 gravity{0.0f, -9.81f, 0.0f};  ///< m/s^2
  /// PBF constraint-force mixing epsilon, relative to the lambda denominator of a particle with
  /// a full rest neighborhood (dimensionless, >= 0): larger is softer and more stable. Below
  /// about 0.3 a single iteration per substep overshoots (Jacobi) and gains energy; tall fluid
  /// columns need 2 iterations even at 0.3.
  float relaxation = 0.3f;
  /// Artificial pressure s_corr = -k (W(r) / W(dq h))^n / D0 against tensile instability (PBF
  /// eq. 13; D0 as for relaxation), a push per iteration given for a substep of 1/480 s and
  /// scaled by (dt 480)^2, at most 1: the same force at any shorter substep.
  float tensile_k = 0.05f;  ///< k, in units of D0 as for relaxation (>= 0; 0 turns it off)
  int tensile_n = 4;        ///< n, an integer in 1..8
  float tensile_dq = 0.2f;  ///< dq as a fraction of the kernel radius, in (0, 1)
  /// Velocity damping c (1/s, >= 0): v *= exp(-c dt) every substep; 0 = off (no pass).
  float damping = 0.0f;
  /// Spanning forests of the raw distance constraints solved exactly every iteration before
  /// their Gauss-Seidel sweep (0..3; 0 = Gauss-Seidel only), grown from the pinned particles
  /// (core/src/families/distance/distance_solver.hpp). Absent: one over the connected pieces
  /// without loops, none over those with loops.
  std::optional<int> distance_forests;
  /// The exact solve of the ball joints along spanning trees of the rigid bodies, every
  /// iteration (core/src/families/rigid/joint_tree.hpp); false: every joint iterative.
  bool joint_trees = true;
};

/// "domain": the box that holds every particle. Particles are projected back inside it.
struct DomainDef {
  Vec3 min{0.0f, 0.0f, 0.0f};  ///< m
  Vec3 max{1.0f, 1.0f, 1.0f};  ///< m, > min on every axis
  float friction = 0.0f;       ///< Coulomb friction coefficient of the walls (>= 0)
};

struct BoxDef {
  Vec3 min{0.0f, 0.0f, 0.0f};  ///< m
  Vec3 max{0.0f, 0.0f, 0.0f};  ///< m, >= min on every axis
};

/// One block of "fluids": a box filled with particles on a lattice. All fluid blocks of a scene
/// share one fluid material: spacing, kernel_radius, rest_density, viscosity and vorticity must
/// agree. A block holds 1 to 50 million particles and lies inside the domain.
struct FluidDef {
  /// Required. Lattice sites at (i + 0.5) * spacing from box.min, floor(extent / spacing + 1e-4)
  /// of them per axis.
  BoxDef box;
  /// m, particle spacing (> 0). Particle mass: rest_density / (sum of W over the lattice), the
  /// mass that makes the initial lattice exactly rest density (about rest_density spacing^3).
  float spacing = 0.02f;
  float kernel_radius = 2.0f;     ///< SPH smoothing radius h in units of spacing (1.5..4)
  float rest_density = 1000.0f;   ///< kg/m^3 (> 0)
  float viscosity = 0.01f;        ///< XSPH viscosity coefficient c, dimensionless in [0, 1]; 0 = off
  float vorticity = 0.0f;         ///< vorticity confinement strength epsilon (m/s, >= 0); 0 = off
  Vec3 velocity{0.0f, 0.0f, 0.0f};  ///< m/s, initial velocity of every particle of the block
};

/// "mesh" of a cloth: a triangle mesh read from an OBJ file (polygons are fanned into
/// triangles), placed by x_world = x_file * scale + translate.
struct ClothMeshDef {
  std::string file;                  ///< required; relative paths are relative to the scene file
  Vec3 translate{0.0f, 0.0f, 0.0f};  ///< m
  float scale = 1.0f;                ///< > 0
};

/// One entry of "rigid_bodies": a rigid body with its own state (position, orientation, linear
/// and angular velocity; core/src/families/rigid/), not particles. Its mass and its inertia
/// tensor (diagonal in the body frame) follow from shape, size and density. At rest orientation
/// a box's edges lie along x, y, z, a capsule's axis along y, and a mesh lies as in its file (its
/// body frame is its principal axes: body_mesh.hpp).
struct RigidBodyDef {
  std::string name;                   ///< required, unique ignoring case, not "world"
  std::string shape = "box";          ///< "box", "sphere", "capsule" or "mesh"
  Vec3 size{0.1f, 0.1f, 0.1f};        ///< box: edge lengths along the body's x, y, z (m, > 0)
  float radius = 0.05f;               ///< sphere, capsule (m, > 0)
  float length = 0.1f;                ///< capsule: length of its cylinder, along the body's y (m, > 0)
  float density = 1000.0f;            ///< kg/m^3 in (0, 1e5]
  Vec3 position{0.0f, 0.0f, 0.0f};    ///< m, required: the centre of mass, inside the domain
  Vec3 axis{0.0f, 1.0f, 0.0f};        ///< orientation: `angle` degrees about `axis` (world frame)
  float angle = 0.0f;                 ///< degrees
  Vec3 velocity{0.0f, 0.0f, 0.0f};    ///< m/s, of the centre of mass
  Vec3 angular_velocity{0.0f, 0.0f, 0.0f};  ///< rad/s, world frame
  bool fixed = false;                 ///< never moves (infinite mass): an anchor for joints
  /// mesh: a closed OBJ (file and scale; translate is not a key: `position` places the mesh's
  /// centre of mass); its mass properties from the mesh (core/src/families/rigid/body_mesh.hpp)
  ClothMeshDef mesh;
  /// Not a key: a mesh body's mesh as the loader read it (once), in the body frame with its mass
  /// properties. Null for the other shapes or a definition made in code (then read from the file).
  std::shared_ptr<const rigid::BodyMesh> loaded_mesh;
  /// Contacts with the domain's walls and the colliders (families/rigid/world_contacts.hpp); each
  /// coefficient mixed with the surface's `friction` as sqrt(mu_body mu_surface).
  float friction = 0.5f;              ///< static (Coulomb) friction coefficient (>= 0)
  float dynamic_friction = 0.4f;      ///< dynamic (sliding) friction coefficient (>= 0)
  float restitution = 0.0f;           ///< the share of the normal speed a bounce keeps, in [0, 1]
};

/// One entry of "joints": a joint between two rigid bodies, or a body and the world (XPBD with
/// compliance, from connector points; core/src/families/rigid/joint.hpp). Anchors and axis are
/// given in the world frame at the start; each body keeps them in its own frame.
struct JointDef {
  std::string type = "ball";          ///< "ball", "hinge", "fixed", "distance", "slider" or "universal"
  std::string body_a = "world";       ///< a body's name or "world"
  std::string body_b;                 ///< required: a body's name
  Vec3 anchor{0.0f, 0.0f, 0.0f};      ///< m, required: the connector point (of body_a for distance)
  Vec3 anchor_b{0.0f, 0.0f, 0.0f};    ///< distance: body_b's point (m), when has_anchor_b; else anchor
  Vec3 axis{0.0f, 0.0f, 1.0f};        ///< hinge, slider, universal (body_a's): the axis, world frame at the start (not zero)
  Vec3 axis_b{1.0f, 0.0f, 0.0f};      ///< universal, required: body_b's axis, world frame at the start, perpendicular to axis
  /// hinge: the range of the angle of body_b about the axis relative to body_a, degrees from the
  /// start (lower <= upper, in [-180, 180]); only when has_limits.
  std::array<float, 2> limits{-180.0f, 180.0f};
  /// distance: the range of |P_b - P_a| (m, 0 <= min <= max), when has_distance; else the
  /// distance at the start, both ways (a rod).
  std::array<float, 2> distance{0.0f, 0.0f};
  /// slider: the range of body_b's travel along the axis from the start (m, lower <= upper),
  /// when has_travel; else free along the axis.
  std::array<float, 2> travel{0.0f, 0.0f};
  float target_angle = 0.0f;          ///< hinge motor: degrees, when has_target_angle
  float target_velocity = 0.0f;       ///< hinge motor: degrees/s; slider motor: m/s; when has_target_velocity
  float target_position = 0.0f;       ///< slider motor: m along the axis from the start, when has_target_position
  float compliance = 0.0f;            ///< m/N and rad/(N m) (>= 0); 0 = rigid
  float motor_compliance = 0.0f;      ///< hinge: rad/(N m), slider: m/N (>= 0); 0 = a rigid drive
  // Not keys: which of the optional keys the scene gave.
  bool has_anchor_b = false;
  bool has_limits = false;
  bool has_distance = false;
  bool has_travel = false;
  bool has_target_angle = false;
  bool has_target_velocity = false;
  bool has_target_position = false;
};

/// One entry of "particles": a raw particle (for raw constraints and worked examples).
struct ParticleDef {
  Vec3 x{0.0f, 0.0f, 0.0f};  ///< m, required, inside the domain
  Vec3 v{0.0f, 0.0f, 0.0f};  ///< m/s
  float mass = 1.0f;         ///< kg: 0 pins the particle, else >= 1e-12
};

/// One entry of "distance_constraints": |x_i - x_j| = rest_length, XPBD with compliance.
/// i and j (both required, i != j) index "particles" (in file order).
struct DistanceConstraintDef {
  int i = -1;
  int j = -1;
  /// m (>= 0). Absent in the scene: stored as -1, meaning "the initial distance between i and j";
  /// an explicit negative value in a scene is an error.
  float rest_length = -1.0f;
  float compliance = 0.0f;  ///< m/N (inverse stiffness, >= 0); 0 = infinitely stiff
};

/// "sheet" of a cloth: a regular grid of resolution[0] x resolution[1] vertices spanning
/// `size` from `origin` in the plane `plane` (its first axis takes size[0] and resolution[0]),
/// each grid cell split into two triangles along alternating diagonals. Vertex (i, j) has index
/// j * resolution[0] + i and UV (i / (resolution[0] - 1), j / (resolution[1] - 1)).
struct SheetDef {
  Vec3 origin{0.0f, 0.0f, 0.0f};          ///< m, required
  std::array<float, 2> size{1.0f, 1.0f};  ///< m, > 0
  std::array<int, 2> resolution{32, 32};  ///< vertices per side, 2..4096
  std::string plane = "xz";  ///< two distinct axes of x, y, z: "xz" is horizontal, "xy" upright
};

/// One entry of "shapes": a body of particles on a cubic lattice (a box filled as a fluid block
/// is, a sphere, or a closed OBJ mesh voxelized at the spacing), kept in its rest shape by shape
/// matching: one cluster per body, or overlapping region clusters (cluster_half_width > 0);
/// rigid at stiffness 1, soft below, linear with linear_blend, plastic with creep.
struct ShapeDef {
  enum class Kind { Box, Sphere, Mesh };
  Kind kind = Kind::Box;            ///< which of "box", "sphere", "mesh" the entry has (exactly one)
  BoxDef box;                       ///< box: sites at (i + 0.5) spacing from box.min
  Vec3 center{0.0f, 0.0f, 0.0f};    ///< sphere: centre (m); sites at center + i spacing
  float radius = 0.0f;              ///< sphere: radius (m, > 0, required)
  ClothMeshDef mesh;                ///< mesh: a closed OBJ; sites at its field's samples inside it
  float spacing = 0.05f;            ///< m (> 0); each particle's collision radius is half of it
  float density = 1000.0f;          ///< kg/m^3 in (0, 1e5]: each particle weighs density spacing^3 (>= 1e-12 kg)
  float stiffness = 1.0f;           ///< in (0, 1]: 1 is rigid, less pulls part way each iteration
  bool stiffness_per_substep = false;  ///< stiffness is what a substep removes, at any iteration count
  float linear_blend = 0.0f;        ///< in [0, 1]: beta of the goal beta A + (1 - beta) R
  float yield = 0.0f;               ///< >= 0: ||S - I||_F above which the rest shape flows
  float creep = 0.0f;               ///< 1/s (>= 0): rate of plastic flow; 0 is elastic
  float max_plastic_strain = 1.0f;  ///< > 0: bound on ||Sp - I||_F
  int cluster_half_width = 0;       ///< lattice cells (>= 0); 0: the body is one cluster
  Vec3 velocity{0.0f, 0.0f, 0.0f};  ///< m/s, initial velocity of every particle
  /// Not a key: a mesh shape's lattice sites as the loader voxelized them (reading the OBJ once),
  /// so that the family does not read the file again. Null for a box, a sphere, or a definition
  /// made in code (the family then voxelizes the file).
  std::shared_ptr<const ShapeSites> loaded_sites;
};

/// One entry of "cloths": exactly one of "sheet" and "mesh", plus the material.
struct ClothDef {
  std::string name;  ///< output file stem <name>.%04d.obj; absent: "cloth<index>"
  std::optional<SheetDef> sheet;
  std::optional<ClothMeshDef> mesh;
  float mass_per_area = 0.2f;       ///< kg/m^2 (> 0); a vertex gets a third of its triangles' mass
  float thickness = 0.005f;         ///< m (> 0): contact distance of self and cloth-cloth contacts
  float stretch_compliance = 0.0f;  ///< m/N (>= 0), XPBD compliance of every edge; 0 = inextensible
  /// 1/(N m) (> 0): the inverse of the bending stiffness B; 1e4 (B = 1e-4 N m) bends like cotton.
  float bend_compliance = 1e4f;
  std::string bending = "dihedral"; ///< "dihedral" or "isometric"
  bool tethers = false;             ///< long-range attachments to the pinned vertices
  /// Spanning forests of the edges (0..3) whose stretch constraints are solved exactly, in linear
  /// time, every iteration before the Gauss-Seidel sweep: the first grows from the pins and
  /// carries the cloth's weight to them; each further one takes edges the others left.
  /// Absent (the default): 1 for a cloth with pins (`pins` or a `pin_box` that holds a vertex),
  /// 0 (Gauss-Seidel only, no cost) otherwise.
  std::optional<int> stretch_forests;
  bool self_collision = false;      ///< particle contacts between non-adjacent vertices
  float friction = 0.3f;            ///< Coulomb friction of the cloth's contacts (>= 0)
  std::vector<int> pins;            ///< vertex indices pinned (mass 0)
  std::optional<BoxDef> pin_box;    ///< vertices inside this box (rest positions) are pinned too
  Vec3 velocity{0.0f, 0.0f, 0.0f};  ///< m/s, initial velocity of every vertex

  /// Not a key: the mesh (sheet or OBJ) and its topology as the loader built them to check the
  /// cloth, so that the cloth solver does not build them again. Null in a definition made in
  /// code; the solver then builds them.
  std::shared_ptr<const ClothMesh> loaded_mesh;
  std::shared_ptr<const ClothTopology> loaded_topology;
};

/// One entry of "colliders": exactly one of "plane", "box", "sphere", "capsule", "mesh", plus a
/// friction value.
struct ColliderDef {
  enum class Shape { Plane, Box, Sphere, Capsule, Mesh };
  Shape shape = Shape::Plane;
  Vec3 point{0.0f, 0.0f, 0.0f};   ///< plane: a point on it (m)
  Vec3 normal{0.0f, 1.0f, 0.0f};  ///< plane: points into the free side (normalized on load)
  BoxDef box;                     ///< box: solid axis-aligned box (m)
  Vec3 center{0.0f, 0.0f, 0.0f};  ///< sphere: center (m)
  float radius = 0.0f;            ///< sphere, capsule: radius (m, > 0, required)
  Vec3 end_a{0.0f, 0.0f, 0.0f};   ///< capsule: one end of its axis (m)
  Vec3 end_b{0.0f, 0.0f, 0.0f};   ///< capsule: the other end (m)
  ClothMeshDef mesh;              ///< mesh: a closed OBJ triangle mesh, placed like a cloth's
  float voxel_size = 0.0f;        ///< mesh: SDF sample spacing (m); 0 = 1/64 of its largest side
  float friction = 0.0f;          ///< Coulomb friction coefficient (>= 0)
  /// Not a key: a mesh collider's OBJ as the loader read it to check it, so that the collider's
  /// SDF does not read it again. Null in a definition made in code; the SDF then reads the file.
  std::shared_ptr<const ClothMesh> loaded_mesh;
};

/// "output": what a run or a bake writes (the command line overrides frames).
struct OutputDef {
  int frames = 60;           ///< number of frames to simulate (>= 1)
  int checkpoint_every = 10; ///< bake: frames between checkpoints of the simulation state (>= 1)
  bool particles = true;     ///< bake: the particle files per frame (`seiche run` always writes them)
  /// The particle files' formats, from "particle_formats": ["ply", "vtp"] (at least one).
  bool particles_ply = true;  ///< "ply": particles.%04d.ply
  bool particles_vtp = false; ///< "vtp": particles.%04d.vtp and their series particles.pvd (ParaView)
  /// bake: the grids of <name>.%04d.vdb, from "vdb": ["surface", "density", "points", "v"];
  /// none = no .vdb files.
  bool vdb_surface = true;   ///< "surface": narrow-band level set of the fluid
  bool vdb_density = true;   ///< "density": fog volume from the level set
  bool vdb_points = false;   ///< "points": VDB Points with attributes v and id
  bool vdb_velocity = false; ///< "v": velocity grid for motion blur
  bool mesh = false;         ///< bake: <name>.%04d.obj surface mesh per frame
  bool body_meshes = true;   ///< <body name>.%04d.obj: every rigid body's surface in the world per frame
  float voxel_size = 0.0f;   ///< m; 0 = automatic (half the fluid spacing)
  bool anisotropic = false;  ///< Yu & Turk 2013 anisotropic surface instead of spheres
  bool half_float = false;   ///< store float grids as 16-bit halves
  std::string compression = "blosc";  ///< "blosc", "zip" or "none"

  bool any_vdb() const { return vdb_surface || vdb_density || vdb_points || vdb_velocity; }
  bool needs_surface() const { return vdb_surface || vdb_density || mesh; }
};

struct SceneDef {
  std::string name = "scene";  ///< "name" (non-empty); absent: the file's stem, or "scene" for text
  SolverDef solver;
  DomainDef domain;
  OutputDef output;
  std::vector<FluidDef> fluids;
  std::vector<ParticleDef> particles;
  std::vector<DistanceConstraintDef> distance_constraints;
  std::vector<ColliderDef> colliders;
  std::vector<ClothDef> cloths;
  std::vector<ShapeDef> shapes;
  std::vector<RigidBodyDef> rigid_bodies;
  std::vector<JointDef> joints;
  /// The scene file's folder: relative OBJ paths are resolved against it ("" for scene text).
  std::string base_dir;
};

}  // namespace seiche

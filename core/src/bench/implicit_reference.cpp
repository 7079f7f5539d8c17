#include "implicit_reference.hpp"

#include "families/cloth/cloth_solver.hpp"
#include "families/distance/distance_solver.hpp"

namespace seiche {

namespace {

void add_springs(const kernels::DistanceConstraints& c, ImplicitEulerSystem& s) {
  for (std::size_t k = 0; k < c.size(); ++k)
    s.springs.push_back({c.i[k], c.j[k], double(c.rest_length[k]), double(c.compliance[k])});
}

}  // namespace

std::string implicit_reference_unsupported(const SceneDef& scene) {
  if (!scene.fluids.empty()) return "the scene has fluid";
  if (!scene.colliders.empty()) return "the scene has colliders (the reference has no contacts)";
  if (scene.cloths.size() > 1) return "the scene has more than one cloth (they collide; the reference has no contacts)";
  if (scene.solver.damping != 0.0f) return "solver.damping is not 0";
  for (const ClothDef& c : scene.cloths) {
    if (c.bending != "isometric") return "a cloth has dihedral bending (the reference models isometric bending)";
    if (c.tethers) return "a cloth has tethers (inequality constraints)";
    if (c.self_collision) return "a cloth has self-collision (the reference has no contacts)";
  }
  return {};
}

ImplicitReferenceSystem implicit_reference_system(const Simulation& sim) {
  ImplicitReferenceSystem r;
  const ParticleStore& p = sim.particles();
  ImplicitEulerSystem& s = r.system;
  for (std::size_t k = 0; k < p.size(); ++k) {
    s.x.insert(s.x.end(), {double(p.x[k]), double(p.y[k]), double(p.z[k])});
    s.v.insert(s.v.end(), {double(p.vx[k]), double(p.vy[k]), double(p.vz[k])});
    s.inv_mass.push_back(double(p.w[k]));
    r.id_of_index.push_back(p.id[k]);
  }
  if (const DistanceSolver* d = sim.distance()) add_springs(d->constraints(), s);
  if (const ClothSolver* cloth = sim.cloth()) {
    add_springs(cloth->stretch(), s);
    const kernels::IsometricBending& b = cloth->isometric();
    for (std::size_t h = 0; h < b.size(); ++h)
      s.hinges.push_back({{b.hinges.a[h], b.hinges.b[h], b.hinges.c[h], b.hinges.d[h]},
                          {double(b.k[0][h]), double(b.k[1][h]), double(b.k[2][h]), double(b.k[3][h])},
                          double(b.hinges.compliance[h])});
  }
  for (int a = 0; a < 3; ++a) s.gravity[a] = sim.scene().solver.gravity[a];
  return r;
}

}  // namespace seiche

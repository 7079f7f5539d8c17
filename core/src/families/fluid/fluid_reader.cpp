// The "fluids" section: the key table of a fluid block, its reader, and the rules across blocks
// and sections (a block holds particles, lies inside the domain, shares the first block's
// material).
#include "fluid_reader.hpp"

#include <cmath>

#include <fmt/format.h>

#include "scene/shared_keys.hpp"

namespace seiche::detail {

namespace {

constexpr double kMaxParticlesPerFluid = 50e6;  // a larger block is a typo in spacing or box
constexpr double kMaxParticles = 50e6;          // all blocks together (32-bit neighbor offsets)
// At 1 spacing the lattice neighbors sit exactly at r = h and the constraint has no gradient;
// past 4 a particle has some 270 neighbors, far past any useful accuracy.
constexpr double kMinKernelRadius = 1.5, kMaxKernelRadius = 4.0;
constexpr double kLatticeTolerance = 1e-4;  // of a spacing, absorbs rounding of box edges
constexpr double kMaxRestDensity = 1e5;  // kg/m^3: over 4x osmium, the densest element (22.6 t/m^3)
constexpr double kMaxVorticity = 100;    // m/s: typical 0.01-1; past 100 swirls outrun any liquid flow

const KeyTable<FluidDef>& fluid_keys() {
  using K = Key<FluidDef>;
  static const KeyTable<FluidDef> keys{
      nested<FluidDef>("box", "object")
          .required()
          .unit("m")
          .doc("the block: `{\"min\": vec3, \"max\": vec3}`, each defaulting to `[0, 0, 0]`, `min` ≤ "
               "`max` on every axis"),
      K("spacing", &FluidDef::spacing, Range::above(0)).unit("m").doc("particle spacing"),
      K("kernel_radius", &FluidDef::kernel_radius, Range::closed(kMinKernelRadius, kMaxKernelRadius))
          .unit("spacings")
          .doc("SPH smoothing radius h, in units of `spacing` (2: about 30 neighbors)"),
      K("rest_density", &FluidDef::rest_density, Range::left_open(0, kMaxRestDensity))
          .unit("kg/m³")
          .doc("rest density ρ₀"),
      K("viscosity", &FluidDef::viscosity, Range::closed(0, 1))
          .doc("XSPH viscosity coefficient c; 0 = off"),
      K("vorticity", &FluidDef::vorticity, Range::closed(0, kMaxVorticity))
          .unit("m/s")
          .doc("vorticity confinement strength ε; 0 = off"),
      K("velocity", &FluidDef::velocity).unit("m/s").doc("initial velocity of every particle of the block"),
  };
  return keys;
}

void read_fluid(JsonReader r, SceneDef& scene) {
  FluidDef f;
  read_keys(r, fluid_keys(), f);  // "box" is required: asked for after the optional keys
  f.box = read_box(r.object("box"));
  r.finish();
  scene.fluids.push_back(f);
}

void check_fluids(SceneDef& scene, const std::string& file) {
  double total = 0;
  const std::string domain = format_domain(scene.domain);
  for (std::size_t k = 0; k < scene.fluids.size(); ++k) {
    const FluidDef& f = scene.fluids[k];
    const std::string path = element_path("fluids", k);
    const std::string box_path = path + ".box";

    // Lattice sites sit at (i + 0.5) * spacing from box.min, floor(extent / spacing) per axis.
    double count = 1;
    for (int a = 0; a < 3; ++a) {
      const double extent = double(f.box.max[a]) - double(f.box.min[a]);
      const double n = std::floor(extent / f.spacing + kLatticeTolerance);
      if (n < 1)
        fail(file, box_path, fmt::format("holds no particles: along {} it is {} m thick, less than one spacing ({} m)",
                                         kAxis[a], static_cast<float>(extent), f.spacing));
      count *= n;
    }
    if (count > kMaxParticlesPerFluid)
      fail(file, box_path, fmt::format("would hold {:.0f} particles at spacing {} m; the limit is {:.0f} per block",
                                       count, f.spacing, kMaxParticlesPerFluid));
    total += count;
    if (total > kMaxParticles)
      fail(file, box_path, fmt::format("brings the fluid to {:.0f} particles; the limit is {:.0f} in all", total,
                                       kMaxParticles));
    if (!inside(f.box.min, scene.domain) || !inside(f.box.max, scene.domain))
      fail(file, box_path, fmt::format("{}..{} reaches outside the domain {}", format_vec(f.box.min),
                                       format_vec(f.box.max), domain));

    // One material per scene: the solver keeps a single kernel radius and rest density.
    const FluidDef& first = scene.fluids.front();
    const auto same = [&](const char* key, float mine, float theirs) {
      if (mine != theirs)
        fail(file, path + "." + key,
             fmt::format("{} differs from fluids[0] ({}); all fluids of a scene share one material", mine, theirs));
    };
    same("spacing", f.spacing, first.spacing);
    same("kernel_radius", f.kernel_radius, first.kernel_radius);
    same("rest_density", f.rest_density, first.rest_density);
    same("viscosity", f.viscosity, first.viscosity);
    same("vorticity", f.vorticity, first.vorticity);
  }
}

}  // namespace

SceneSection fluids_section() {
  return {"fluids", true, "blocks of fluid particles", read_fluid, check_fluids,
          [] { return std::vector<KeyTableDoc>{{"fluids", key_docs(fluid_keys())}}; }};
}

}  // namespace seiche::detail

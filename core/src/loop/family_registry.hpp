// The family registry: one row per constraint family, the builder side of the scene's sections
// (the reader side is core/src/scene/section_registry.cpp). Simulation builds a scene's families
// by running the rows:
//   1. the Particles rows, in table order: each creates its particles at the end of the store
//      (their ids are the creation order, the order of every export), so a new family's rows
//      go after the existing ones and leave their ids alone;
//   2. every particle created outside the domain is moved to its nearest point in it;
//   3. the OnParticles rows, in table order: families over particles that exist (contacts, raw
//      distance constraints, whose rest lengths are the distances after step 2, colliders), and
//      the rigid bodies, which are not particles (their own state, joined only by their joints).
// A row whose section the scene lacks adds nothing: a family absent from a scene costs nothing.
// The order of the families built is the order of their error rows in reports, and breaks ties
// between equal pass keys (pass_order in family.hpp). A row may also name the family's exporter
// (family_exporters(), frame_exporter.hpp).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "family.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/scene.hpp"

namespace seiche {

/// What a row's builder works with.
class FamilyBuild {
 public:
  using Reorder = std::function<void(std::span<const std::uint32_t> order)>;
  FamilyBuild(const SceneDef& scene, ParticleStore& store, std::vector<std::unique_ptr<Family>>& families,
              Reorder reorder)
      : scene(scene), store(store), reorder(std::move(reorder)), families_(families) {}

  const SceneDef& scene;
  ParticleStore& store;
  /// Reorders the store and remaps every family's indices (the fluid's neighbor stage).
  Reorder reorder;

  /// Appends n zero particles (w = 0) with ids = their store indices; returns the first index.
  /// After the row, the registry sets their predicted positions to the positions it wrote.
  std::size_t add_particles(std::size_t n);
  /// Adds a family; returns it.
  template <class F>
  F& add(std::unique_ptr<F> family) {
    F& f = *family;
    families_.push_back(std::move(family));
    return f;
  }
  /// A family an earlier row built, or null.
  template <class F>
  F* find() const {
    for (const auto& f : families_)
      if (auto* typed = dynamic_cast<F*>(f.get())) return typed;
    return nullptr;
  }

 private:
  std::vector<std::unique_ptr<Family>>& families_;
};

struct FamilyRow {
  enum class Phase { Particles, OnParticles };
  const char* name;  ///< the scene section it builds from ("motion": every scene)
  Phase phase;
  void (*build)(FamilyBuild& build);
  /// The family's frame files besides the PLY every bake writes (the cloths' OBJ, the bodies' JSON lines), or null when
  /// it has none; the maker returns null when the scene lacks the section.
  std::unique_ptr<FrameExporter> (*exporter)(const SceneDef& scene) = nullptr;
};

/// Every row, in table order.
std::span<const FamilyRow> family_rows();

}  // namespace seiche

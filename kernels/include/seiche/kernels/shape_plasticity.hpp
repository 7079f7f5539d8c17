// Plastic flow of shape-matched clusters (Müller, Heidelberger, Teschner and Gross 2005,
// section 4.4): a cluster deformed past its yield takes part of the deformation into its rest
// shape, so that it stays dented. Once per substep, on the final positions, per plastic cluster
// (creep > 0), with its rest offsets Sp q_i (shape_fit.hpp):
//   A  = Apq Mqq^-1, det A = 1       (the best linear map from the plastic rest shape to now)
//   R  = rot(Apq),  S = sym(R^T A)   (the stretch: S = I for a rigid motion)
//   if ||S - I||_F > yield:
//     Sp <- (I + dt creep (S - I)) Sp
//     if ||Sp - I||_F > max_strain:  Sp <- I + max_strain (Sp - I) / ||Sp - I||_F
//     Sp <- Sp / det(Sp)^(1/3)       (the rest volume is kept)
// Below the yield Sp is not touched: it stays the identity to the bit. Where the linear map is
// undefined (flat, linear or coincident clusters, inverted: shape_matching.hpp) or the update is
// not finite or not orientation-preserving, Sp is kept. Clusters are independent (one per task):
// the same bits at any thread count. The rotation state is read as the search's start only.
#pragma once

#include "seiche/kernels/particle_view.hpp"
#include "seiche/kernels/shape_matching.hpp"

namespace seiche::kernels {

/// One plastic step of length dt (s) of every plastic cluster, on the predicted positions.
void update_shape_plasticity(const ParticleView& p, ShapeClusters& clusters, float dt);

/// ||S - I||_F of cluster c now (0 where the linear map is undefined): the strain the yield is
/// compared with, for tests and reports.
double shape_strain(const ParticleView& p, const ShapeClusters& clusters, std::size_t c);

}  // namespace seiche::kernels

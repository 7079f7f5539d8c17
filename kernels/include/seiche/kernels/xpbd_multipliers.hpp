// How an XPBD solve starts from its constraints' multipliers (lambda). XPBD accumulates lambda
// over the iterations of a substep and starts every substep from lambda = 0 (Macklin et al.
// 2016). Restart is that start folded into the substep's first solve: it computes with
// lambda = 0 and writes lambda = 0 + dlambda, without reading the stored multipliers, so they
// need no reset pass (and the result is the same, bit for bit, as a reset followed by Accumulate).
#pragma once

namespace seiche::kernels {

enum class Multipliers {
  Accumulate,  ///< lambda += dlambda, from the stored lambda
  Restart,     ///< lambda = 0 + dlambda: the substep's first solve of these constraints
};

}  // namespace seiche::kernels

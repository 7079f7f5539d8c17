// What the kernels were compiled for: the CPU family, the SIMD instruction set xsimd chose, its
// float lane count and whether a multiply-add is fused. Benchmark figures and golden hashes are
// meaningless without it: `seiche --version`, the run summary, the run report and bake.json
// record it.
#pragma once

#include <cstddef>
#include <string>

namespace seiche::kernels {

struct SimdInfo {
  /// "x86-64" or "aarch64": builds of one family and one kind of multiply-add compute the same
  /// bits (docs/design.md, "The determinism contract"); other families compute their own.
  std::string family;
  std::string arch;  ///< xsimd's architecture name: "avx512bw", "fma3+avx2", "sse2", "neon64"
  std::size_t float_lanes;  ///< floats per batch (a lane is a particle or a constraint)
  bool fused_multiply_add;  ///< whether the kernels' multiply-adds round once (FMA) or twice
};

SimdInfo simd_info();

/// One line: "avx512bw, 16 float lanes, fused multiply-add".
std::string simd_description();

}  // namespace seiche::kernels

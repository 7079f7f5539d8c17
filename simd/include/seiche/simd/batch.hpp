// The SIMD layer's types (internal to kernels/ and neighbor/): the rules every kernel follows.
//
// Kernels are written once against these types: a batch holds kLanes floats, and every
// width-dependent constant derives from kLanes. xsimd picks the widest instruction set the
// compiler targets (SSE2: 4 lanes, AVX2: 8, AVX-512: 16, NEON: 4).
//
// Same bits on every width and every x86-64 machine. A lane's arithmetic must not depend on how
// many lanes a batch has, and every operation must round the same way on every instruction set:
// - the basic operations, sqrt and division are correctly rounded on every x86 instruction set;
// - a multiply-add is written out as multiply_add (intrinsics.hpp) where the kernel wants one,
//   and `-ffp-contract=off` keeps the compiler from fusing anything else, so a multiply-add is
//   fused on every instruction set that has FMA (x86-64-v3 and up, AArch64) and only there
//   (xsimd 8.1's own fma is not fused on AVX-512: it falls back to a multiply and an add);
// - no unary minus on a batch: xsimd 8.1 computes it as 0 - x on AVX-512 (so -(+0) is +0 there
//   and -0 everywhere else); negate() flips the sign on every instruction set, as -x does for a
//   float;
// - no xsimd math function but sqrt (its atan2, exp... use its fma, see above): atan2 is ours
//   (math.hpp);
// - no hardware reciprocal or reciprocal-square-root estimate: their precision differs between
//   SSE/AVX (12 bits) and AVX-512 (14 bits), and between Intel and AMD for the same instruction.
//   A kernel that needs 1/sqrt(x) divides by the correctly rounded sqrt.
//   (xsimd 8.1's AVX-512 rsqrt does not even compile with g++ 12: it calls _mm512_rsqrt23_ps.)
// No horizontal operation (a sum across lanes) is allowed in a kernel's arithmetic: its order
// would depend on the width. What needs intrinsics (the record transposes, lane compaction, the
// fused multiply-add) lives in intrinsics.hpp, and only there.
//
// AArch64 builds compile and run, with bits of their own: xsimd 8.1's NEON float division and
// sqrt are hardware estimates refined by Newton steps, not correctly rounded. bake.json records
// the architecture family, and a resume across families is refused.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <xsimd/xsimd.hpp>

#if defined(__GNUC__)
#define SEICHE_INLINE __attribute__((always_inline))
#else
#define SEICHE_INLINE
#endif

namespace seiche::simd {

/// The instruction set the kernels are compiled for (an xsimd architecture tag).
using Arch = xsimd::default_arch;
using Floats = xsimd::batch<float, Arch>;
using Mask = xsimd::batch_bool<float, Arch>;
/// Unsigned 32-bit lanes, as many as Floats has (particle and constraint indices).
using Ints = xsimd::batch<std::uint32_t, Arch>;
inline constexpr std::size_t kLanes = Floats::size;
static_assert(Ints::size == kLanes, "index lanes must match float lanes");
static_assert(kLanes <= 32, "lane masks are kept in 32 bits");

/// Hides where v comes from from the optimizer (an empty asm that "may change" it), so that it
/// neither reuses values computed from it earlier nor keeps them live: for addresses that are
/// cheaper to recompute than to keep in registers across a long computation.
template <class T>
SEICHE_INLINE inline void opaque(T& v) {
#if defined(__GNUC__)
  asm("" : "+r"(v));
#endif
}

/// The widest instruction set of at most 256 bits: Arch, except in an AVX-512 build, where it is
/// AVX2 (with FMA, when the build has it), which every AVX-512 machine has. Two uses:
/// - the neighbor list's compare-and-pack loops (integers: the same on every width), where 16
///   lanes do not pay: a list is built from ~85 candidates per group and ~28 neighbors per
///   particle, so 16 lanes pad more (96 lanes for 85 candidates, 88 with 8), every 64-byte store
///   of packed indices straddles two cache lines, and the compare mask makes a round trip through
///   a general register before the compress. Measured on Zen 5 (docs/performance.md, "AVX2 and
///   AVX-512"): the grid rebuild and query took 1.01-1.05x the AVX2 build's time with 16 lanes,
///   1.00-1.03x with 8;
/// - the bending metric's double-precision atan2 (xsimd's, kernels/src/hinges.cpp): run on the
///   same instruction set in AVX2 and AVX-512 builds, it gives them the same bits (the rule
///   "no xsimd math function" is about instruction sets that differ).
using Arch256 = std::conditional_t<
    std::is_base_of_v<xsimd::avx512f, Arch>,
    std::conditional_t<xsimd::fma3<xsimd::avx2>::supported(), xsimd::fma3<xsimd::avx2>, xsimd::avx2>,
    Arch>;

/// 0, 1, ..., n - 1 for the n lanes of instruction set A.
template <class A = Arch>
inline xsimd::batch<std::uint32_t, A> lane_index() {
  using I = xsimd::batch<std::uint32_t, A>;
  alignas(64) std::uint32_t lanes[I::size];
  for (std::size_t l = 0; l < I::size; ++l) lanes[l] = std::uint32_t(l);
  return I::load_aligned(lanes);
}

/// -x, the same on every instruction set: -0 - x is x with its sign flipped, zeros included.
inline Floats negate(const Floats& x) { return Floats(-0.0f) - x; }
/// The float twin of negate (kernels' templates run on floats as their scalar references).
inline float negate(float x) { return -x; }

}  // namespace seiche::simd

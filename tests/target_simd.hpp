// What this build's -march allows, read from the compiler's own macros, independently of xsimd
// and of the kernels: the widest SIMD's name (a part of xsimd's architecture name), its float
// lanes, and whether it has a fused multiply-add. The tests hold the kernels' own report
// (kernels::simd_info) against these.
#pragma once

#include <cstddef>

namespace target_simd {

#if defined(__AVX512F__)
inline constexpr const char* kTargetSimd = "avx512";
inline constexpr std::size_t kTargetLanes = 16;
#elif defined(__AVX__)
inline constexpr const char* kTargetSimd = "avx";
inline constexpr std::size_t kTargetLanes = 8;
#elif defined(__SSE2__)
inline constexpr const char* kTargetSimd = "sse";
inline constexpr std::size_t kTargetLanes = 4;
#elif defined(__ARM_NEON)
inline constexpr const char* kTargetSimd = "neon";
inline constexpr std::size_t kTargetLanes = 4;
#else
inline constexpr const char* kTargetSimd = "(a SIMD these tests do not know)";
inline constexpr std::size_t kTargetLanes = 0;
#endif

// AVX-512F has FMA instructions of its own (also with -mno-fma); AArch64 always has them.
#if defined(__FMA__) || defined(__AVX512F__) || defined(__aarch64__)
inline constexpr bool kTargetFma = true;
#else
inline constexpr bool kTargetFma = false;
#endif

}  // namespace target_simd

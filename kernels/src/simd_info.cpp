#include "seiche/kernels/simd_info.hpp"

#include <xsimd/xsimd.hpp>

#include "seiche/simd/intrinsics.hpp"

namespace seiche::kernels {

namespace {

// Whether simd::multiply_add rounds once. 1 + 2^-12 squared is 1 + 2^-11 + 2^-24; its float
// product rounds the 2^-24 away (a tie, to even), so (a a) - 1 is 2^-11 unfused and
// 2^-11 + 2^-24 fused. The inputs come through volatile so the test runs on the hardware.
bool multiply_add_is_fused() {
  volatile float a_in = 1.0f + 1.0f / 4096.0f, c_in = -1.0f;
  const simd::Floats a(a_in), c(c_in);
  const float r = simd::multiply_add(a, a, c).get(0);
  return r != 1.0f / 2048.0f;
}

const char* cpu_family() {
#if defined(__x86_64__)
  return "x86-64";
#elif defined(__aarch64__)
  return "aarch64";
#else
  return "other";
#endif
}

}  // namespace

SimdInfo simd_info() {
  return {cpu_family(), simd::Arch::name(), simd::kLanes, multiply_add_is_fused()};
}

std::string simd_description() {
  const SimdInfo s = simd_info();
  return s.arch + ", " + std::to_string(s.float_lanes) + " float lanes, " +
         (s.fused_multiply_add ? "fused multiply-add" : "unfused multiply-add");
}

}  // namespace seiche::kernels

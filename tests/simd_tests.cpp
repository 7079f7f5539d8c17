// The SIMD layer (simd/), for the width this build uses: every instruction-set version of an
// operation against its generic version (the oracle, correct for any width), the multiply-add's
// rounding against the exact fused result, and atan2 against the C library and its scalar twin.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "seiche/kernels/simd_info.hpp"
#include "seiche/simd/batch.hpp"
#include "seiche/simd/intrinsics.hpp"
#include "seiche/simd/math.hpp"
#include "target_simd.hpp"

namespace {

using namespace seiche::simd;

struct alignas(16) Record {
  float v[4];
};

std::vector<float> lane_values(const Floats& b) {
  std::vector<float> out(kLanes);
  b.store_unaligned(out.data());
  return out;
}

bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

TEST(Simd, WidthAndFusedMultiplyAddAreReported) {
  const seiche::kernels::SimdInfo info = seiche::kernels::simd_info();
  EXPECT_EQ(info.float_lanes, kLanes);
  EXPECT_EQ(info.float_lanes, target_simd::kTargetLanes);
  EXPECT_NE(info.arch.find(target_simd::kTargetSimd), std::string::npos) << info.arch;
  EXPECT_EQ(info.fused_multiply_add, target_simd::kTargetFma);
  EXPECT_EQ(info.arch, std::string(Arch::name()));
  std::cout << "[ simd ] " << seiche::kernels::simd_description() << "\n";
}

TEST(Simd, Gather4MatchesTheGenericVersion) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(-10.0f, 10.0f);
  std::vector<Record> records(257);
  for (Record& r : records)
    for (float& v : r.v) v = value(rng);
  std::uniform_int_distribution<std::size_t> pick(0, records.size() - 1);
  for (int trial = 0; trial < 200; ++trial) {
    std::size_t index[kLanes];
    for (std::size_t& i : index) i = pick(rng);
    auto at = [&](std::size_t l) { return index[l]; };
    const Gathered4 fast = gather4(records.data(), at);
    const Gathered4 oracle = detail::gather4<Arch>(records.data(), at, xsimd::generic{});
    const Floats* f[4] = {&fast.x, &fast.y, &fast.z, &fast.w};
    const Floats* o[4] = {&oracle.x, &oracle.y, &oracle.z, &oracle.w};
    for (int c = 0; c < 4; ++c) {
      const auto a = lane_values(*f[c]), b = lane_values(*o[c]);
      for (std::size_t l = 0; l < kLanes; ++l) {
        ASSERT_TRUE(same_bits(a[l], b[l])) << "component " << c << " lane " << l;
        ASSERT_TRUE(same_bits(a[l], records[index[l]].v[c]));
      }
    }
  }
}

TEST(Simd, Scatter4WritesTheActiveLanesOnly) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> value(-10.0f, 10.0f);
  for (std::size_t active = 1; active <= kLanes; ++active) {
    // Distinct targets (a permutation of a range), as the colored solves guarantee.
    std::vector<std::size_t> index(kLanes);
    for (std::size_t l = 0; l < kLanes; ++l) index[l] = (l * 7 + active) % (2 * kLanes + 1);
    alignas(64) float c[4][kLanes];
    for (auto& column : c)
      for (float& v : column) v = value(rng);
    const Floats x = Floats::load_aligned(c[0]), y = Floats::load_aligned(c[1]),
                 z = Floats::load_aligned(c[2]), w = Floats::load_aligned(c[3]);
    std::vector<Record> fast(2 * kLanes + 1, Record{{-1, -1, -1, -1}}), oracle = fast;
    auto at = [&](std::size_t l) { return index[l]; };
    scatter4(fast.data(), at, x, y, z, w, active);
    detail::scatter4<Arch>(oracle.data(), at, x, y, z, w, active, xsimd::generic{});
    ASSERT_EQ(std::memcmp(fast.data(), oracle.data(), fast.size() * sizeof(Record)), 0)
        << "active " << active;
    for (std::size_t l = 0; l < active; ++l)
      for (int k = 0; k < 4; ++k) ASSERT_EQ(fast[index[l]].v[k], c[k][l]);
  }
}

// Every lane pattern (all 2^n for n lanes, up to 16): the bits of a compare, the left-packed
// floats and indices, and (for Arch) keep_if; for the kernels' batches (Arch) and the neighbor
// list's (Arch256, 8 lanes in an AVX-512 build).
template <class A>
void check_lane_operations() {
  using F = xsimd::batch<float, A>;
  using I = xsimd::batch<std::uint32_t, A>;
  constexpr std::size_t n = F::size;
  alignas(64) float values[n];
  alignas(64) std::uint32_t ids[n];
  for (std::size_t l = 0; l < n; ++l) values[l] = float(l) + 0.5f, ids[l] = std::uint32_t(1000 + l);
  const F v = F::load_aligned(values);
  const I j = I::load_aligned(ids);
  const std::uint32_t patterns = std::uint32_t(1) << n;
  for (std::uint32_t bits = 0; bits < patterns; ++bits) {
    alignas(64) float threshold[n];
    alignas(64) std::uint32_t id_threshold[n];
    for (std::size_t l = 0; l < n; ++l) {
      const bool set = bits >> l & 1;
      threshold[l] = set ? values[l] + 1.0f : values[l] - 1.0f;  // v < threshold where set
      id_threshold[l] = set ? ids[l] + 1 : ids[l];               // j < id_threshold where set
    }
    const auto m = v < F::load_aligned(threshold);
    const auto im = j < I::load_aligned(id_threshold);
    ASSERT_EQ(lane_bits(m), bits);
    ASSERT_EQ(lane_bits(m), detail::lane_bits<A>(m, xsimd::generic{}));
    ASSERT_EQ(lane_bits(im), bits);

    float packed[2 * n], packed_oracle[2 * n];
    std::uint32_t packed_ids[2 * n], packed_ids_oracle[2 * n];
    left_pack<A>(bits).store(packed, v);
    left_pack<A>(bits).store(packed_ids, j);
    detail::left_pack<A>(bits, xsimd::generic{}).store(packed_oracle, v);
    detail::left_pack<A>(bits, xsimd::generic{}).store(packed_ids_oracle, j);
    const int count = std::popcount(bits);
    for (int k = 0, l = 0; k < count; ++k, ++l) {
      while (!(bits >> l & 1)) ++l;
      ASSERT_EQ(packed[k], values[l]) << "bits " << bits;
      ASSERT_EQ(packed[k], packed_oracle[k]);
      ASSERT_EQ(packed_ids[k], ids[l]);
      ASSERT_EQ(packed_ids[k], packed_ids_oracle[k]);
    }

    if constexpr (std::is_same_v<A, Arch>) {
      const auto kept = lane_values(keep_if(m, v));
      const auto kept_oracle = lane_values(detail::keep_if<Arch>(m, v, xsimd::generic{}));
      for (std::size_t l = 0; l < n; ++l) {
        ASSERT_TRUE(same_bits(kept[l], kept_oracle[l]));
        ASSERT_EQ(kept[l], (bits >> l & 1) ? values[l] : 0.0f);
      }
    }
  }
}

TEST(Simd, LaneBitsLeftPackAndKeepIfMatchTheGenericVersions) { check_lane_operations<Arch>(); }
TEST(Simd, TheNeighborListsLaneOperationsMatchTheGenericVersions) {
  std::cout << "[ simd ] neighbor list: " << Arch256::name() << ", "
            << xsimd::batch<float, Arch256>::size << " lanes\n";
  check_lane_operations<Arch256>();
}

TEST(Simd, StreamCopyCopiesEveryLengthAndAlignment) {
  std::vector<std::uint32_t> src(4096 + 64), dst(src.size());
  for (std::size_t k = 0; k < src.size(); ++k) src[k] = std::uint32_t(k * 2654435761u);
  for (std::size_t offset = 0; offset < 17; ++offset)
    for (std::size_t count : {0u, 1u, 63u, 64u, 129u, 1000u, 4096u}) {
      std::fill(dst.begin(), dst.end(), 0xdeadbeefu);
      stream_copy(dst.data() + offset, src.data(), count);
      for (std::size_t k = 0; k < dst.size(); ++k) {
        const bool inside = k >= offset && k < offset + count;
        ASSERT_EQ(dst[k], inside ? src[k - offset] : 0xdeadbeefu)
            << offset << " " << count << " " << k;
      }
    }
}

// multiply_add rounds once where the build has FMA (the exact product plus z, rounded: what
// std::fma computes) and twice where it has not, in every lane, and its scalar twin agrees.
TEST(Simd, MultiplyAddRoundsAsTheBuildSays) {
  const bool fused = target_simd::kTargetFma;  // from the compiler, not from the kernels' report
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> value(-2.0f, 2.0f);
  int differ = 0;  // inputs where the fused and unfused results differ: the test has teeth
  for (int trial = 0; trial < 2000; ++trial) {
    alignas(64) float x[kLanes], y[kLanes], z[kLanes];
    for (std::size_t l = 0; l < kLanes; ++l)
      x[l] = value(rng), y[l] = value(rng), z[l] = value(rng);
    const auto r = lane_values(
        multiply_add(Floats::load_aligned(x), Floats::load_aligned(y), Floats::load_aligned(z)));
    const auto s = lane_values(
        mul_sub_from(Floats::load_aligned(x), Floats::load_aligned(y), Floats::load_aligned(z)));
    for (std::size_t l = 0; l < kLanes; ++l) {
      volatile float product = x[l] * y[l];  // rounded on its own
      const float once = std::fma(x[l], y[l], z[l]), twice = product + z[l];
      const float once_sub = std::fma(-x[l], y[l], z[l]), twice_sub = z[l] - product;
      differ += once != twice;
      ASSERT_TRUE(same_bits(r[l], fused ? once : twice)) << x[l] << " " << y[l] << " " << z[l];
      ASSERT_TRUE(same_bits(s[l], fused ? once_sub : twice_sub));
      ASSERT_TRUE(same_bits(multiply_add(x[l], y[l], z[l]), r[l]));
    }
  }
  EXPECT_GT(differ, 100);
}

// negate flips the sign bit of zeros too, as -x does for a float (xsimd 8.1's AVX-512 unary minus
// computes 0 - x, which turns -(+0) into +0).
TEST(Simd, NegateFlipsTheSignOfZerosOnEveryWidth) {
  for (float v : {0.0f, -0.0f, 1.5f, -2.5f, std::numeric_limits<float>::infinity()}) {
    const auto r = lane_values(negate(Floats(v)));
    for (std::size_t l = 0; l < kLanes; ++l) ASSERT_TRUE(same_bits(r[l], -v)) << v;
    ASSERT_TRUE(same_bits(negate(v), -v));
  }
}

// atan2 against the C library (in double) over every quadrant, the axes, tiny and huge ratios,
// and the reduction's boundary tan(pi/8); the batch and its scalar twin give the same bits.
TEST(Simd, Atan2IsAccurateAndTheSameForBatchesAndFloats) {
  std::vector<float> ys, xs;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> angle(-3.2f, 3.2f), scale(-20.0f, 20.0f);
  for (int k = 0; k < 20000; ++k) {
    const float a = angle(rng), r = std::exp2(scale(rng));
    ys.push_back(r * std::sin(a)), xs.push_back(r * std::cos(a));
  }
  for (float t = 0.40f; t < 0.43f; t += 1e-4f) ys.push_back(t), xs.push_back(1.0f);  // tan(pi/8)
  for (float v : {1.0f, -1.0f, 1e-30f, -1e-30f, 3.0f})
    for (float u : {0.0f, 1.0f, -1.0f, 1e30f, -1e-30f})
      ys.push_back(v), xs.push_back(u), ys.push_back(u), xs.push_back(v);
  ys.push_back(0.0f), xs.push_back(0.0f);
  while (ys.size() % kLanes) ys.push_back(1.0f), xs.push_back(2.0f);

  double worst_ulps = 0.0;
  for (std::size_t i = 0; i < ys.size(); i += kLanes) {
    const auto r = lane_values(
        seiche::simd::atan2(Floats::load_unaligned(&ys[i]), Floats::load_unaligned(&xs[i])));
    for (std::size_t l = 0; l < kLanes; ++l) {
      const float y = ys[i + l], x = xs[i + l];
      ASSERT_TRUE(same_bits(r[l], seiche::simd::atan2(y, x)))
          << y << " " << x << " lane " << l << ": " << r[l] << " vs " << seiche::simd::atan2(y, x);
      const double exact = std::atan2(double(y), double(x));
      const double ulp = std::max(
          double(std::nextafter(std::abs(float(exact)), INFINITY)) - std::abs(float(exact)),
          double(std::numeric_limits<float>::denorm_min()));
      worst_ulps = std::max(worst_ulps, std::abs(double(r[l]) - exact) / ulp);
    }
  }
  std::cout << "[ simd ] atan2: worst error " << worst_ulps << " ulp over " << ys.size()
            << " inputs\n";
  EXPECT_LT(worst_ulps, 3.0);
}

}  // namespace

// The SIMD layer's intrinsics: the only code in Seiche that uses them.
//
//   multiply_add         x y + z rounded once where the instruction set has FMA (with
//                        mul_sub_from and accumulate, the kernels' only multiply-adds)
//   gather4 / scatter4   kLanes 16-byte records (x, y, z, w) <-> four batches, one 16-byte load or
//                        store per record and a transpose in registers (the neighbor passes and
//                        the colored constraint solves; xsimd 8's gather is a scalar loop, and
//                        hardware gathers are slower than this on AVX2 and AVX-512 anyway)
//   lane_bits            a compare mask as bits, bit l = lane l
//   left_pack            the selected lanes of a batch stored contiguously (the neighbor list's
//                        candidate and list compaction)
//   keep_if              v where a mask is set, else 0
//   stream_copy          a copy whose stores bypass the caches (lists far larger than them)
//
// Every operation has a generic version, correct for any width, and faster ones for the
// instruction sets named by their tag parameter: overload resolution on Arch{} picks the most
// specific version for the instruction set xsimd chose (xsimd's own dispatch idiom), never a
// preprocessor test. The tag-specific versions are templates on the tag, so only the one chosen
// is ever compiled; the x86 ones are declared only on x86 and the AArch64 one only on AArch64,
// where their intrinsics exist.
// All but the multiply-adds only move bits, so they cannot change a result; the multiply-adds
// round once on every instruction set with FMA, twice on those without (x86-64 baseline, AVX).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "seiche/simd/batch.hpp"

#if defined(__x86_64__) || defined(__i386__)  // the x86 family: its intrinsics header exists
#include <immintrin.h>
#define SEICHE_SIMD_X86 1
#else
#define SEICHE_SIMD_X86 0
#endif
#if defined(__aarch64__)  // the AArch64 family: its intrinsics header exists
#include <arm_neon.h>
#define SEICHE_SIMD_AARCH64 1
#else
#define SEICHE_SIMD_AARCH64 0
#endif

namespace seiche::simd {

/// kLanes records transposed: lane l of x, y, z, w holds the components of the l-th record.
struct Gathered4 {
  Floats x, y, z, w;
};

namespace detail {

template <class Record>
SEICHE_INLINE inline const float* floats_of(const Record* records, std::size_t i) {
  static_assert(sizeof(Record) == 16 && alignof(Record) >= 16, "records are 16 aligned bytes");
  return reinterpret_cast<const float*>(records + i);
}
template <class Record>
SEICHE_INLINE inline float* floats_of(Record* records, std::size_t i) {
  static_assert(sizeof(Record) == 16 && alignof(Record) >= 16, "records are 16 aligned bytes");
  return reinterpret_cast<float*>(records + i);
}

// ---- generic versions: any width -------------------------------------------------------------

// xsimd's fma: one instruction on its FMA3 and NEON architectures, a multiply and an add where
// the instruction set has no FMA.
template <class A>
SEICHE_INLINE inline Floats multiply_add(const Floats& x, const Floats& y, const Floats& z,
                                         const xsimd::generic&) {
  return xsimd::fma(x, y, z);
}
template <class A>
SEICHE_INLINE inline Floats mul_sub_from(const Floats& x, const Floats& y, const Floats& z,
                                         const xsimd::generic&) {
  return xsimd::fnma(x, y, z);
}

template <class A, class Record, class Index>
SEICHE_INLINE inline Gathered4 gather4(const Record* records, const Index& index,
                                       const xsimd::generic&) {
  static_assert(sizeof(Record) == 16, "records are 16 bytes");
  alignas(64) float c[4][kLanes];
  for (std::size_t l = 0; l < kLanes; ++l) {
    float r[4];
    std::memcpy(r, &records[index(l)], sizeof r);  // the record's 16 bytes as 4 floats
    c[0][l] = r[0], c[1][l] = r[1], c[2][l] = r[2], c[3][l] = r[3];
  }
  return {Floats::load_aligned(c[0]), Floats::load_aligned(c[1]), Floats::load_aligned(c[2]),
          Floats::load_aligned(c[3])};
}

template <class A, class Record, class Index>
SEICHE_INLINE inline void scatter4(Record* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active, const xsimd::generic&) {
  alignas(64) float c[4][kLanes];
  static_assert(sizeof(Record) == 16, "records are 16 bytes");
  x.store_aligned(c[0]), y.store_aligned(c[1]), z.store_aligned(c[2]), w.store_aligned(c[3]);
  for (std::size_t l = 0; l < active; ++l) {
    const float r[4] = {c[0][l], c[1][l], c[2][l], c[3][l]};
    std::memcpy(&records[index(l)], r, sizeof r);
  }
}

template <class A, class T>
SEICHE_INLINE inline std::uint32_t lane_bits(const xsimd::batch_bool<T, A>& m,
                                             const xsimd::generic&) {
  constexpr std::size_t n = xsimd::batch_bool<T, A>::size;
  alignas(64) bool lanes[n];
  m.store_aligned(lanes);
  std::uint32_t bits = 0;
  for (std::size_t l = 0; l < n; ++l) bits |= std::uint32_t(lanes[l]) << l;
  return bits;
}

template <class A>
struct LeftPackGeneric {
  std::uint32_t bits;
  template <class T>
  SEICHE_INLINE void store(T* out, const xsimd::batch<T, A>& v) const {
    alignas(64) T lanes[xsimd::batch<T, A>::size];
    v.store_aligned(lanes);
    std::size_t k = 0;
    for (std::uint32_t b = bits; b != 0; b &= b - 1) out[k++] = lanes[std::countr_zero(b)];
  }
};
template <class A>
SEICHE_INLINE inline LeftPackGeneric<A> left_pack(std::uint32_t bits, const xsimd::generic&) {
  return {bits};
}

template <class A>
SEICHE_INLINE inline Floats keep_if(const Mask& m, const Floats& v, const xsimd::generic&) {
  return xsimd::select(m, v, Floats(0.0f));
}

template <class A>
inline void stream_copy(std::uint32_t* dst, const std::uint32_t* src, std::size_t count,
                        const xsimd::generic&) {
  std::copy_n(src, count, dst);
}

#if SEICHE_SIMD_X86

// ---- x86: SSE2 (4 lanes), AVX (8), AVX2 (8, integer permutes), AVX-512F (16) -------------------

// Non-temporal copy in Bytes-wide stores: a head up to the first aligned address, the body
// streamed, the tail copied, then a fence so later loads see the data.
template <std::size_t Bytes, class Stream>
inline void stream_copy_x86(std::uint32_t* dst, const std::uint32_t* src, std::size_t count,
                            Stream stream) {
  constexpr std::size_t kPer = Bytes / sizeof(std::uint32_t);
  if (count < 8 * kPer) return void(std::copy_n(src, count, dst));
  const std::size_t misaligned = reinterpret_cast<std::uintptr_t>(dst) & (Bytes - 1);
  const std::size_t head = ((Bytes - misaligned) & (Bytes - 1)) / sizeof(std::uint32_t);
  std::copy_n(src, head, dst);
  src += head, dst += head, count -= head;
  std::size_t k = 0;
  for (; k + kPer <= count; k += kPer) stream(dst + k, src + k);
  std::copy_n(src + k, count - k, dst + k);
  _mm_sfence();
}

// SSE2: 4 lanes.
template <class A, class Record, class Index>
SEICHE_INLINE inline Gathered4 gather4(const Record* records, const Index& index,
                                       const xsimd::sse2&) {
  using F = xsimd::batch<float, A>;
  __m128 a = _mm_load_ps(floats_of(records, index(0))),
         b = _mm_load_ps(floats_of(records, index(1)));
  __m128 c = _mm_load_ps(floats_of(records, index(2))),
         d = _mm_load_ps(floats_of(records, index(3)));
  _MM_TRANSPOSE4_PS(a, b, c, d);
  return {F(a), F(b), F(c), F(d)};
}
template <class A, class Record, class Index>
SEICHE_INLINE inline void scatter4(Record* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active, const xsimd::sse2&) {
  using F = xsimd::batch<float, A>;
  __m128 a = F(x), b = F(y), c = F(z), d = F(w);
  _MM_TRANSPOSE4_PS(a, b, c, d);
  const __m128 r[4] = {a, b, c, d};
  for (std::size_t l = 0; l < active; ++l) _mm_store_ps(floats_of(records, index(l)), r[l]);
}
template <class A, class T>
SEICHE_INLINE inline std::uint32_t lane_bits(const xsimd::batch_bool<T, A>& m, const xsimd::sse2&) {
  if constexpr (std::is_same_v<T, float>)
    return std::uint32_t(_mm_movemask_ps(m));
  else
    return std::uint32_t(_mm_movemask_ps(_mm_castsi128_ps(m)));
}
template <class A>
SEICHE_INLINE inline Floats keep_if(const Mask& m, const Floats& v, const xsimd::sse2&) {
  using F = xsimd::batch<float, A>;
  return F(_mm_and_ps(xsimd::batch_bool<float, A>(m), F(v)));
}
template <class A>
inline void stream_copy(std::uint32_t* dst, const std::uint32_t* src, std::size_t count,
                        const xsimd::sse2&) {
  stream_copy_x86<16>(dst, src, count, [](std::uint32_t* d, const std::uint32_t* s) {
    _mm_stream_si128(reinterpret_cast<__m128i*>(d),
                     _mm_loadu_si128(reinterpret_cast<const __m128i*>(s)));
  });
}

// AVX: 8 lanes. Records a and b go to the low and high 128-bit halves of a row; a 4 x 4
// transpose per half then gives lanes 0-3 and 4-7.
template <class A, class Record, class Index>
SEICHE_INLINE inline Gathered4 gather4(const Record* records, const Index& index,
                                       const xsimd::avx&) {
  using F = xsimd::batch<float, A>;
  auto row = [&](std::size_t a, std::size_t b) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(floats_of(records, index(a)))),
                                _mm_load_ps(floats_of(records, index(b))), 1);
  };
  const __m256 r04 = row(0, 4), r15 = row(1, 5), r26 = row(2, 6), r37 = row(3, 7);
  const __m256 t0 = _mm256_unpacklo_ps(r04, r15);  // x0 x1 y0 y1 | x4 x5 y4 y5
  const __m256 t1 = _mm256_unpackhi_ps(r04, r15);  // z0 z1 w0 w1 | z4 z5 w4 w5
  const __m256 t2 = _mm256_unpacklo_ps(r26, r37);  // x2 x3 y2 y3 | x6 x7 y6 y7
  const __m256 t3 = _mm256_unpackhi_ps(r26, r37);  // z2 z3 w2 w3 | z6 z7 w6 w7
  return {F(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0))),
          F(_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2))),
          F(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))),
          F(_mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2)))};
}
template <class A, class Record, class Index>
SEICHE_INLINE inline void scatter4(Record* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active, const xsimd::avx&) {
  using F = xsimd::batch<float, A>;
  const __m256 t0 = _mm256_unpacklo_ps(F(x), F(y));  // x0 y0 x1 y1 | x4 y4 x5 y5
  const __m256 t1 = _mm256_unpackhi_ps(F(x), F(y));  // x2 y2 x3 y3 | x6 y6 x7 y7
  const __m256 t2 = _mm256_unpacklo_ps(F(z), F(w));  // z0 w0 z1 w1 | z4 w4 z5 w5
  const __m256 t3 = _mm256_unpackhi_ps(F(z), F(w));  // z2 w2 z3 w3 | z6 w6 z7 w7
  const __m256 r[4] = {_mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)),   // records 0 | 4
                       _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)),   // records 1 | 5
                       _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)),   // records 2 | 6
                       _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2))};  // records 3 | 7
  for (std::size_t l = 0; l < 4 && l < active; ++l)
    _mm_store_ps(floats_of(records, index(l)), _mm256_castps256_ps128(r[l]));
  for (std::size_t l = 4; l < active; ++l)
    _mm_store_ps(floats_of(records, index(l)), _mm256_extractf128_ps(r[l - 4], 1));
}
template <class A, class T>
SEICHE_INLINE inline std::uint32_t lane_bits(const xsimd::batch_bool<T, A>& m, const xsimd::avx&) {
  if constexpr (std::is_same_v<T, float>)
    return std::uint32_t(_mm256_movemask_ps(m));
  else
    return std::uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(m)));
}
template <class A>
SEICHE_INLINE inline Floats keep_if(const Mask& m, const Floats& v, const xsimd::avx&) {
  using F = xsimd::batch<float, A>;
  return F(_mm256_and_ps(xsimd::batch_bool<float, A>(m), F(v)));
}
template <class A>
inline void stream_copy(std::uint32_t* dst, const std::uint32_t* src, std::size_t count,
                        const xsimd::avx&) {
  stream_copy_x86<32>(dst, src, count, [](std::uint32_t* d, const std::uint32_t* s) {
    _mm256_stream_si256(reinterpret_cast<__m256i*>(d),
                        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(s)));
  });
}

// AVX2: left packing by one lane permute, its indices from a table (byte k of entry `bits` is
// the k-th set lane).
template <class A>
struct LeftPackAvx2 {
  static constexpr std::array<std::uint64_t, 256> kLanesOfBits = [] {
    std::array<std::uint64_t, 256> t{};
    for (unsigned bits = 0; bits < 256; ++bits)
      for (unsigned l = 0, k = 0; l < 8; ++l)
        if (bits >> l & 1) t[bits] |= std::uint64_t(l) << (8 * k++);
    return t;
  }();
  __m256i lanes;
  SEICHE_INLINE void store(float* out, const xsimd::batch<float, A>& v) const {
    _mm256_storeu_ps(out, _mm256_permutevar8x32_ps(v, lanes));
  }
  SEICHE_INLINE void store(std::uint32_t* out, const xsimd::batch<std::uint32_t, A>& v) const {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_permutevar8x32_epi32(v, lanes));
  }
};
template <class A>
SEICHE_INLINE inline LeftPackAvx2<A> left_pack(std::uint32_t bits, const xsimd::avx2&) {
  return {
      _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(std::int64_t(LeftPackAvx2<A>::kLanesOfBits[bits])))};
}

// AVX-512F: 16 lanes. xsimd 8.1 has no AVX-512 fma (it multiplies and adds): the instruction.
template <class A>
SEICHE_INLINE inline Floats multiply_add(const Floats& x, const Floats& y, const Floats& z,
                                         const xsimd::avx512f&) {
  using F = xsimd::batch<float, A>;
  return F(_mm512_fmadd_ps(F(x), F(y), F(z)));
}
template <class A>
SEICHE_INLINE inline Floats mul_sub_from(const Floats& x, const Floats& y, const Floats& z,
                                         const xsimd::avx512f&) {
  using F = xsimd::batch<float, A>;
  return F(_mm512_fnmadd_ps(F(x), F(y), F(z)));
}
// Records a, b, c, d go to the four 128-bit quarters of a row; the AVX
// transpose then works per quarter. Compaction is the compress instruction, to a register and
// then stored whole (compress straight to memory is microcoded and slow on AMD Zen 4).
template <class A, class Record, class Index>
SEICHE_INLINE inline Gathered4 gather4(const Record* records, const Index& index,
                                       const xsimd::avx512f&) {
  using F = xsimd::batch<float, A>;
  auto row = [&](std::size_t a) {  // records a, a + 4, a + 8, a + 12
    __m512 r = _mm512_castps128_ps512(_mm_load_ps(floats_of(records, index(a))));
    r = _mm512_insertf32x4(r, _mm_load_ps(floats_of(records, index(a + 4))), 1);
    r = _mm512_insertf32x4(r, _mm_load_ps(floats_of(records, index(a + 8))), 2);
    return _mm512_insertf32x4(r, _mm_load_ps(floats_of(records, index(a + 12))), 3);
  };
  const __m512 r0 = row(0), r1 = row(1), r2 = row(2), r3 = row(3);
  const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  return {F(_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0))),
          F(_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2))),
          F(_mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0))),
          F(_mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2)))};
}
template <class A, class Record, class Index>
SEICHE_INLINE inline void scatter4(Record* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active, const xsimd::avx512f&) {
  using F = xsimd::batch<float, A>;
  const __m512 t0 = _mm512_unpacklo_ps(F(x), F(y)), t1 = _mm512_unpackhi_ps(F(x), F(y));
  const __m512 t2 = _mm512_unpacklo_ps(F(z), F(w)), t3 = _mm512_unpackhi_ps(F(z), F(w));
  const __m512 r[4] = {_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)),   // records 0 4 8 12
                       _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)),   // records 1 5 9 13
                       _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)),   // records 2 6 10 14
                       _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2))};  // records 3 7 11 15
  auto put = [&](std::size_t l, __m128 v) {
    if (l < active) _mm_store_ps(floats_of(records, index(l)), v);
  };
  for (std::size_t l = 0; l < 4; ++l) {
    put(l, _mm512_castps512_ps128(r[l]));
    put(l + 4, _mm512_extractf32x4_ps(r[l], 1));
    put(l + 8, _mm512_extractf32x4_ps(r[l], 2));
    put(l + 12, _mm512_extractf32x4_ps(r[l], 3));
  }
}
template <class A, class T>
SEICHE_INLINE inline std::uint32_t lane_bits(const xsimd::batch_bool<T, A>& m,
                                             const xsimd::avx512f&) {
  static_assert(sizeof(T) == 4);
  return std::uint32_t(__mmask16(m));  // already a mask register
}
template <class A>
struct LeftPackAvx512 {
  __mmask16 mask;
  SEICHE_INLINE void store(float* out, const xsimd::batch<float, A>& v) const {
    _mm512_storeu_ps(out, _mm512_maskz_compress_ps(mask, v));
  }
  SEICHE_INLINE void store(std::uint32_t* out, const xsimd::batch<std::uint32_t, A>& v) const {
    _mm512_storeu_si512(out, _mm512_maskz_compress_epi32(mask, v));
  }
};
template <class A>
SEICHE_INLINE inline LeftPackAvx512<A> left_pack(std::uint32_t bits, const xsimd::avx512f&) {
  return {__mmask16(bits)};
}
template <class A>
SEICHE_INLINE inline Floats keep_if(const Mask& m, const Floats& v, const xsimd::avx512f&) {
  using F = xsimd::batch<float, A>;
  return F(_mm512_maskz_mov_ps(xsimd::batch_bool<float, A>(m), F(v)));
}
template <class A>
inline void stream_copy(std::uint32_t* dst, const std::uint32_t* src, std::size_t count,
                        const xsimd::avx512f&) {
  stream_copy_x86<64>(dst, src, count, [](std::uint32_t* d, const std::uint32_t* s) {
    _mm512_stream_si512(reinterpret_cast<__m512i*>(d), _mm512_loadu_si512(s));
  });
}

#endif  // SEICHE_SIMD_X86

#if SEICHE_SIMD_AARCH64

// ---- AArch64: NEON (4 lanes) ----------------------------------------------------------------------

// xsimd 8.1's fnma on NEON multiplies and subtracts; its fma is the fused instruction already.
template <class A>
SEICHE_INLINE inline Floats mul_sub_from(const Floats& x, const Floats& y, const Floats& z,
                                         const xsimd::neon64&) {
  using F = xsimd::batch<float, A>;
  return F(vfmsq_f32(F(z), F(x), F(y)));
}

#endif  // SEICHE_SIMD_AARCH64

}  // namespace detail

/// x y + z, rounded once where the instruction set has FMA.
SEICHE_INLINE inline Floats multiply_add(const Floats& x, const Floats& y, const Floats& z) {
  return detail::multiply_add<Arch>(x, y, z, Arch{});
}
/// z - x y, rounded once where the instruction set has FMA.
SEICHE_INLINE inline Floats mul_sub_from(const Floats& x, const Floats& y, const Floats& z) {
  return detail::mul_sub_from<Arch>(x, y, z, Arch{});
}
/// acc += x y, rounded once where the instruction set has FMA.
SEICHE_INLINE inline void accumulate(Floats& acc, const Floats& x, const Floats& y) {
  acc = multiply_add(x, y, acc);
}
/// The scalar twin of multiply_add, with its rounding (for the scalar references of kernels).
inline float multiply_add(float x, float y, float z) {
  return multiply_add(Floats(x), Floats(y), Floats(z)).get(0);
}

/// The records index(0) .. index(kLanes - 1), transposed: lane l of the result is record index(l).
template <class Record, class Index>
SEICHE_INLINE inline Gathered4 gather4(const Record* records, const Index& index) {
  return detail::gather4<Arch>(records, index, Arch{});
}

/// Writes lane l of (x, y, z, w) to records[index(l)] for l < active: the transpose of gather4,
/// one 16-byte store per record.
template <class Record, class Index>
SEICHE_INLINE inline void scatter4(Record* records, const Index& index, const Floats& x,
                                   const Floats& y, const Floats& z, const Floats& w,
                                   std::size_t active = kLanes) {
  detail::scatter4<Arch>(records, index, x, y, z, w, active, Arch{});
}

/// Bit l set where lane l of the mask is (a mask of Arch's or of Arch256's batches).
template <class T, class A>
SEICHE_INLINE inline std::uint32_t lane_bits(const xsimd::batch_bool<T, A>& m) {
  return detail::lane_bits<A>(m, A{});
}

/// The lanes selected by `bits` (bit l = lane l), stored in lane order to out[0, popcount(bits)):
/// left_pack<A>(bits).store(out, v) for batches of instruction set A (Arch or Arch256). A store
/// may write a whole batch at out: leave room.
template <class A = Arch>
SEICHE_INLINE inline auto left_pack(std::uint32_t bits) {
  return detail::left_pack<A>(bits, A{});
}

/// v where m is set, else 0 (an AND of the compare mask: cheaper than a blend).
SEICHE_INLINE inline Floats keep_if(const Mask& m, const Floats& v) {
  return detail::keep_if<Arch>(m, v, Arch{});
}

/// dst[0, count) = src[0, count), with stores that bypass the caches where the instruction set
/// has them: for outputs far larger than the caches (they skip reading the destination in first,
/// half the memory traffic).
template <class A = Arch>
inline void stream_copy(std::uint32_t* dst, const std::uint32_t* src, std::size_t count) {
  detail::stream_copy<A>(dst, src, count, A{});
}

}  // namespace seiche::simd

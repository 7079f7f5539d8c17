// Particle-particle contacts (particle_contacts.hpp; Macklin et al. 2014, sec. 5 and 6.1), one
// Jacobi iteration with averaging. For particle i and each partner j closer than r:
//   d = |p_i - p_j|, n = (p_i - p_j) / d, share_i = w_i / (w_i + w_j)
//   normal:   dp_i += share_i (r - d) n
//   friction: the relative tangential motion of the substep
//               dx_t = t((p_i - x_i) - (p_j - x_j)),  t(v) = v - (v.n) n
//             (the normal push does not change it) is removed (|dx_t| <= mu (r - d)) or
//             scaled down to mu (r - d) of it:  dp_i -= share_i * keep * dx_t
// then dp_i /= (number of active contacts of i). Pass 1 computes every dp_i from the positions
// as they were (reads only), pass 2 adds them: no particle's result depends on another's
// update or on the thread count. Each pair is listed from both sides, so j gets the opposite
// share from its own entry.
#include "seiche/kernels/particle_contacts.hpp"

#include <tbb/parallel_for.h>

#include <cmath>

namespace seiche::kernels {

void solve_particle_contacts(const ParticleView& p, const ParticleContacts& c, float friction,
                             std::vector<float>& scratch) {
  const std::size_t groups = c.size();
  scratch.resize(3 * groups);
  float* dp = scratch.data();

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 512), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::uint32_t i = c.particle[g];
      const float wi = p.w[i];
      float sx = 0.0f, sy = 0.0f, sz = 0.0f;
      int active = 0;
      if (wi > 0.0f) {
        const float xi = p.px[i], yi = p.py[i], zi = p.pz[i];
        const float mi_x = xi - p.x[i], mi_y = yi - p.y[i], mi_z = zi - p.z[i];  // i's motion
        for (std::uint32_t k = c.start[g]; k < c.start[g + 1]; ++k) {
          const std::uint32_t j = c.partner[k];
          const float dx = xi - p.px[j], dy = yi - p.py[j], dz = zi - p.pz[j];
          const float d2 = dx * dx + dy * dy + dz * dz;
          const float rest = c.distance[k];
          if (!(d2 < rest * rest)) continue;  // apart (or NaN)
          const float d = std::sqrt(d2);
          if (d < 1e-9f) continue;  // coincident: no normal
          const float wj = p.w[j];
          const float share = wi / (wi + wj);  // wi > 0
          const float nx = dx / d, ny = dy / d, nz = dz / d;
          const float depth = rest - d;
          float cx = share * depth * nx, cy = share * depth * ny, cz = share * depth * nz;
          if (friction > 0.0f) {
            const float rx = mi_x - (p.px[j] - p.x[j]), ry = mi_y - (p.py[j] - p.y[j]),
                        rz = mi_z - (p.pz[j] - p.z[j]);
            const float rn = rx * nx + ry * ny + rz * nz;
            const float tx = rx - rn * nx, ty = ry - rn * ny, tz = rz - rn * nz;
            const float t_len = std::sqrt(tx * tx + ty * ty + tz * tz);
            if (t_len > 0.0f) {
              const float keep = t_len <= friction * depth ? 1.0f : friction * depth / t_len;
              cx -= share * keep * tx, cy -= share * keep * ty, cz -= share * keep * tz;
            }
          }
          sx += cx, sy += cy, sz += cz;
          ++active;
        }
      }
      const float inv = active > 0 ? 1.0f / float(active) : 0.0f;
      dp[3 * g] = sx * inv, dp[3 * g + 1] = sy * inv, dp[3 * g + 2] = sz * inv;
    }
  });

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 2048), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::uint32_t i = c.particle[g];
      p.px[i] += dp[3 * g], p.py[i] += dp[3 * g + 1], p.pz[i] += dp[3 * g + 2];
    }
  });
}

// The momentum-keeping contacts (particle_contacts.hpp, solve_sided_contacts): pass 1 per
// particle i, its pairs' impulses, normal and friction (averaged over its active contacts), and
// its own correction; pass 2 per partner j, the sum of its entries' reactions in its list's
// order; pass 3 applies both. Reads before writes: no result depends on the thread count.
void solve_sided_contacts(const ParticleView& p, const SidedContacts& c, float friction, std::vector<float>& scratch) {
  const ParticleContacts& f = c.first;
  const std::size_t groups = f.size(), entries = f.partner.size(), partners = c.second.size();
  if (groups == 0) return;
  scratch.resize(3 * (entries + groups + partners));
  float* impulse = scratch.data();                  // per entry
  float* dp_first = impulse + 3 * entries;          // per group
  float* dp_second = dp_first + 3 * groups;         // per partner
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 512), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::uint32_t i = f.particle[g];
      const float wi = p.w[i];
      const float xi = p.px[i], yi = p.py[i], zi = p.pz[i];
      const float mi_x = xi - p.x[i], mi_y = yi - p.y[i], mi_z = zi - p.z[i];  // i's motion
      int active = 0;
      for (std::uint32_t k = f.start[g]; k < f.start[g + 1]; ++k) {
        float* e = impulse + 3 * std::size_t(k);
        e[0] = e[1] = e[2] = 0.0f;
        const std::uint32_t j = f.partner[k];
        const float dx = xi - p.px[j], dy = yi - p.py[j], dz = zi - p.pz[j];
        const float d2 = dx * dx + dy * dy + dz * dz;
        const float rest = f.distance[k];
        const float w_sum = wi + p.w[j];
        if (!(d2 < rest * rest) || !(w_sum > 0.0f)) continue;  // apart (or NaN), or both fixed
        const float d = std::sqrt(d2);
        if (d < 1e-9f) continue;  // coincident: no normal
        const float lambda = (rest - d) / (w_sum * d);  // times (dx, dy, dz) = d n
        e[0] = lambda * dx, e[1] = lambda * dy, e[2] = lambda * dz;
        if (friction > 0.0f) {  // the pair's relative tangential motion u_t, kept within mu (r - d)
          const float nx = dx / d, ny = dy / d, nz = dz / d;
          const float rx = mi_x - (p.px[j] - p.x[j]), ry = mi_y - (p.py[j] - p.y[j]), rz = mi_z - (p.pz[j] - p.z[j]);
          const float rn = rx * nx + ry * ny + rz * nz;
          const float tx = rx - rn * nx, ty = ry - rn * ny, tz = rz - rn * nz;
          const float t_len = std::sqrt(tx * tx + ty * ty + tz * tz);
          const float depth = rest - d;
          if (t_len > 0.0f) {
            const float keep = (t_len <= friction * depth ? 1.0f : friction * depth / t_len) / w_sum;
            e[0] -= keep * tx, e[1] -= keep * ty, e[2] -= keep * tz;
          }
        }
        ++active;
      }
      const float inv = active > 0 ? 1.0f / float(active) : 0.0f;
      float sx = 0.0f, sy = 0.0f, sz = 0.0f;
      for (std::uint32_t k = f.start[g]; k < f.start[g + 1]; ++k) {
        float* e = impulse + 3 * std::size_t(k);
        e[0] *= inv, e[1] *= inv, e[2] *= inv;
        sx += e[0], sy += e[1], sz += e[2];
      }
      dp_first[3 * g] = wi * sx, dp_first[3 * g + 1] = wi * sy, dp_first[3 * g + 2] = wi * sz;
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, partners, 512), [&](const auto& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      float sx = 0.0f, sy = 0.0f, sz = 0.0f;
      for (std::uint32_t k = c.second_start[b]; k < c.second_start[b + 1]; ++k) {
        const float* e = impulse + 3 * std::size_t(c.second_entry[k]);
        sx += e[0], sy += e[1], sz += e[2];
      }
      const float wj = p.w[c.second[b]];
      dp_second[3 * b] = -wj * sx, dp_second[3 * b + 1] = -wj * sy, dp_second[3 * b + 2] = -wj * sz;
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 2048), [&](const auto& r) {
    for (std::size_t g = r.begin(); g != r.end(); ++g) {
      const std::uint32_t i = f.particle[g];
      p.px[i] += dp_first[3 * g], p.py[i] += dp_first[3 * g + 1], p.pz[i] += dp_first[3 * g + 2];
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, partners, 2048), [&](const auto& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const std::uint32_t j = c.second[b];
      p.px[j] += dp_second[3 * b], p.py[j] += dp_second[3 * b + 1], p.pz[j] += dp_second[3 * b + 2];
    }
  });
}

}  // namespace seiche::kernels

// Test reference: one linearized XPBD projection of distance constraints, solved densely in
// double. With n_e the unit direction of edge e = (i, j) at positions x, C_e = |x_i - x_j| - l_e,
// W the inverse masses and alpha~_e = compliance_e / dt^2:
//   (J W J^T + alpha~) dlambda = -C - alpha~ lambda,   dx = W J^T dlambda,
// J's row e holding +n_e at i and -n_e at j. Gaussian elimination without pivoting (the matrix
// is symmetric positive definite for a forest with at least one free particle per edge).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "seiche/kernels/distance_constraint.hpp"

namespace seiche::test {

using Positions = std::vector<std::array<double, 3>>;

struct DenseProjection {
  Positions dx;                 ///< per particle
  std::vector<double> dlambda;  ///< per constraint
};

inline DenseProjection dense_distance_projection(const kernels::DistanceConstraints& c, const Positions& x,
                                                 const std::vector<float>& w, const std::vector<float>& lambda,
                                                 float dt) {
  const std::size_t m = c.size();
  std::vector<std::array<double, 3>> normal(m);
  std::vector<double> A(m * m, 0.0), b(m);
  for (std::size_t e = 0; e < m; ++e) {
    const auto &xi = x[c.i[e]], &xj = x[c.j[e]];
    const double d[3] = {xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    normal[e] = {d[0] / len, d[1] / len, d[2] / len};
    const double alpha = double(c.compliance[e]) / (double(dt) * dt);
    b[e] = -(len - c.rest_length[e]) - alpha * lambda[e];
    A[e * m + e] += alpha;
  }
  for (std::size_t e = 0; e < m; ++e)
    for (std::size_t f = 0; f < m; ++f)
      for (std::uint32_t a : {c.i[e], c.j[e]})
        for (std::uint32_t q : {c.i[f], c.j[f]}) {
          if (a != q) continue;
          const double se = a == c.i[e] ? 1.0 : -1.0, sf = q == c.i[f] ? 1.0 : -1.0;
          const auto &ne = normal[e], &nf = normal[f];
          A[e * m + f] += w[a] * se * sf * (ne[0] * nf[0] + ne[1] * nf[1] + ne[2] * nf[2]);
        }
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t r = k + 1; r < m; ++r) {
      const double f = A[r * m + k] / A[k * m + k];
      for (std::size_t col = k; col < m; ++col) A[r * m + col] -= f * A[k * m + col];
      b[r] -= f * b[k];
    }
  DenseProjection s{Positions(x.size(), {0.0, 0.0, 0.0}), std::vector<double>(m)};
  for (std::size_t k = m; k-- > 0;) {
    double sum = b[k];
    for (std::size_t col = k + 1; col < m; ++col) sum -= A[k * m + col] * s.dlambda[col];
    s.dlambda[k] = sum / A[k * m + k];
  }
  for (std::size_t e = 0; e < m; ++e)
    for (int a = 0; a < 3; ++a) {
      s.dx[c.i[e]][a] += w[c.i[e]] * normal[e][a] * s.dlambda[e];
      s.dx[c.j[e]][a] -= w[c.j[e]] * normal[e][a] * s.dlambda[e];
    }
  return s;
}

}  // namespace seiche::test

// The implicit-Euler reference of `seiche bench` for cloth and chains: a time step solved to
// convergence as an optimization ("simulation as optimization", the seed chapter):
//   y   = x + h v + h^2 g                      (inertial prediction; pinned particles stay)
//   x'  = argmin_z  Phi(z) = 1/2 (z - y)^T M (z - y) + h^2 E(z)
//   v'  = (x' - x) / h
// with the elastic energy of the same constraints XPBD solves, U = C^2 / (2 alpha):
//   springs  C = |z_i - z_j| - l0                    (stretch edges, distance constraints)
//   hinges   C = |sum_k kappa_k z_k|                  (isometric bending, Bergou's Q = kappa kappa^T)
// Converged XPBD at step h solves exactly this problem, so as h -> 0 both approach the same
// trajectory; the reference takes many small steps, each solved by Newton's method in double
// precision: gradient M (z - y) + h^2 grad E, Hessian M + h^2 H_E with every spring's block
// projected to be positive semi-definite (its transverse stiffness 1 - l0/l clamped at 0), a
// sparse Cholesky factorization (Eigen's SimplicialLDLT, the pattern analysed once) and a
// backtracking line search on Phi. A zero compliance (an inextensible edge) is replaced by
// `min_compliance`: the reference is a very stiff spring, not a hard constraint.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace seiche {

/// The mechanical system of the reference, in double precision. Particle k's position is
/// x[3k..3k+2]; a particle with inv_mass 0 is pinned (never moves).
struct ImplicitEulerSystem {
  struct Spring {
    std::uint32_t i = 0, j = 0;
    double rest_length = 0.0;  ///< m
    double compliance = 0.0;   ///< m/N
  };
  struct Hinge {
    std::array<std::uint32_t, 4> v{};  ///< particles
    std::array<double, 4> kappa{};     ///< C = |sum_k kappa_k x_v[k]|, 1/m
    double compliance = 0.0;           ///< 1/(N m)
  };
  std::vector<double> x, v;     ///< 3 per particle (m, m/s)
  std::vector<double> inv_mass; ///< 1/kg, one per particle
  std::vector<Spring> springs;
  std::vector<Hinge> hinges;
  std::array<double, 3> gravity{0.0, -9.81, 0.0};  ///< m/s^2
};

/// Per-step statistics of the Newton solve.
struct ImplicitEulerStats {
  int newton_iterations = 0;  ///< of the last step
  double gradient_norm = 0.0; ///< |grad Phi|_inf / h^2 after the last step: the largest force left (N)
  /// The last step met the tolerance (or its gradient reached rounding noise) within
  /// max_newton_iterations; an unconverged step is kept, and the bench counts it.
  bool converged = false;
};

class ImplicitEulerStepper {
 public:
  /// tolerance: a step is converged when the largest Newton update is below tolerance (m).
  ImplicitEulerStepper(ImplicitEulerSystem system, double min_compliance = 1e-9, double tolerance = 1e-12,
                       int max_newton_iterations = 50);
  ~ImplicitEulerStepper();
  ImplicitEulerStepper(const ImplicitEulerStepper&) = delete;
  ImplicitEulerStepper& operator=(const ImplicitEulerStepper&) = delete;

  /// Advances one implicit-Euler step of length h (s). Throws std::runtime_error naming the step
  /// when Newton produces a non-finite value (the state is left as it was), and
  /// std::invalid_argument for h <= 0 or non-finite.
  ImplicitEulerStats step(double h);

  const std::vector<double>& positions() const;   ///< 3 per particle
  const std::vector<double>& velocities() const;  ///< 3 per particle
  /// E(x) + kinetic + gravitational energy (J) at the current state, for tests.
  double total_energy() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace seiche

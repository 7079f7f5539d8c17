// Tests of the implicit-Euler reference against closed forms: free fall, a pinned spring (a linear
// 1D equation), energy decay, a hanging chain's static tension, hinge energy and its linear
// solution, degenerate springs, the minimum compliance and non-finite input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/implicit_euler.hpp"

using namespace seiche;

namespace {

using Vec3 = std::array<double, 3>;

// Appends a particle (inv_mass 0 pins it).
void add_particle(ImplicitEulerSystem& s, Vec3 x, Vec3 v, double inv_mass) {
  s.x.insert(s.x.end(), x.begin(), x.end());
  s.v.insert(s.v.end(), v.begin(), v.end());
  s.inv_mass.push_back(inv_mass);
}

Vec3 particle(const std::vector<double>& values, std::size_t p) {
  return {values[3 * p], values[3 * p + 1], values[3 * p + 2]};
}

double distance(const std::vector<double>& x, std::size_t a, std::size_t b) {
  const Vec3 pa = particle(x, a), pb = particle(x, b);
  return std::hypot(pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]);
}

constexpr Vec3 kNoGravity{0.0, 0.0, 0.0};

}  // namespace

// Without constraints Phi is quadratic and one Newton iteration reaches its minimizer
// y = x + h v + h^2 g, so n steps give
// v_n = v0 + n h g and x_n = x0 + sum_{k=1..n} h v_k = x0 + n h v0 + h^2 g n (n + 1) / 2.
TEST(ImplicitEuler, FreeFallMatchesClosedForm) {
  ImplicitEulerSystem s;
  s.gravity = {0.5, -9.81, 0.25};
  add_particle(s, {1.0, 2.0, 3.0}, {0.3, 4.0, -1.0}, 2.0);
  add_particle(s, {-5.0, 0.5, 7.0}, {0.0, 0.0, 0.0}, 0.1);
  add_particle(s, {4.0, 4.0, 4.0}, {1.0, 1.0, 1.0}, 0.0);  // pinned: never moves
  const ImplicitEulerSystem initial = s;
  ImplicitEulerStepper stepper(s);
  const double initial_energy = stepper.total_energy();
  const double h = 0.01;
  const int n = 200;
  for (int k = 0; k < n; ++k) {
    const ImplicitEulerStats stats = stepper.step(h);
    ASSERT_TRUE(stats.converged);
    EXPECT_LE(stats.newton_iterations, 1);
  }
  const std::vector<double>& x = stepper.positions();
  const std::vector<double>& v = stepper.velocities();
  // v = (x_new - x) / h cancels: each step adds about one ulp of |x| divided by h, so after n
  // steps the velocity is known to n ulp(|x|) / h, not to 1e-12 relative.
  const double largest_coordinate = 32.0;
  const double velocity_tolerance =
      n * 2.0 * std::numeric_limits<double>::epsilon() * largest_coordinate / h;
  for (std::size_t p = 0; p < 2; ++p)
    for (int d = 0; d < 3; ++d) {
      const std::size_t c = 3 * p + d;
      const double v_expected = initial.v[c] + n * h * s.gravity[d];
      const double x_expected =
          initial.x[c] + n * h * initial.v[c] + h * h * s.gravity[d] * n * (n + 1) / 2.0;
      EXPECT_NEAR(x[c], x_expected, 1e-12 * std::max(1.0, std::abs(x_expected)))
          << "particle " << p;
      ASSERT_LT(std::abs(x[c]), largest_coordinate);
      EXPECT_NEAR(v[c], v_expected, velocity_tolerance) << "particle " << p;
    }
  // Kinetic plus gravitational energy: with x' - x = h v' each step changes it by
  // m/2 (v'^2 - v^2) - m g.(h v') = m/2 h g.(v' + v) - m h g.v' = -m h^2 |g|^2 / 2.
  const double g2 =
      s.gravity[0] * s.gravity[0] + s.gravity[1] * s.gravity[1] + s.gravity[2] * s.gravity[2];
  const double free_mass = 1.0 / 2.0 + 1.0 / 0.1;
  const double expected_energy = initial_energy - n * free_mass * h * h * g2 / 2.0;
  EXPECT_NEAR(stepper.total_energy(), expected_energy, 1e-10 * std::abs(initial_energy));
  for (int d = 0; d < 3; ++d) {
    EXPECT_EQ(x[6 + d], 4.0);
    EXPECT_EQ(v[6 + d], 0.0);
  }
}

// A mass on a spring pinned at p0, along x, zero gravity. Along the spring the problem is 1D and
// linear: with u the distance from p0, m (u - y_u) + h^2 (u - l0) / alpha = 0, so
// u = (m y_u + h^2 l0 / alpha) / (m + h^2 / alpha).
TEST(ImplicitEuler, PinnedSpringStepMatchesScalarSolution) {
  const double m = 0.5, l0 = 0.4, alpha = 1e-3, h = 0.01, u0 = 0.45, speed = 0.3;
  const Vec3 p0{1.0, 2.0, 3.0};
  ImplicitEulerSystem s;
  s.gravity = kNoGravity;
  add_particle(s, p0, {0.0, 0.0, 0.0}, 0.0);
  add_particle(s, {p0[0] + u0, p0[1], p0[2]}, {speed, 0.0, 0.0}, 1.0 / m);
  s.springs.push_back({0, 1, l0, alpha});
  ImplicitEulerStepper stepper(s);
  const ImplicitEulerStats stats = stepper.step(h);
  EXPECT_TRUE(stats.converged);
  EXPECT_EQ(stats.newton_iterations, 1);  // quadratic along the spring: one exact Newton step

  const double y_u = u0 + h * speed;
  const double u = (m * y_u + h * h * l0 / alpha) / (m + h * h / alpha);
  const Vec3 x1 = particle(stepper.positions(), 1), v1 = particle(stepper.velocities(), 1);
  EXPECT_NEAR(x1[0] - p0[0], u, 1e-10);
  EXPECT_EQ(x1[1], p0[1]);
  EXPECT_EQ(x1[2], p0[2]);
  EXPECT_NEAR(v1[0], (u - u0) / h, 1e-8);
  EXPECT_EQ(particle(stepper.positions(), 0), p0);
}

// A spring compressed to 0.9 l0 from a pinned particle at the origin, with gravity and a sideways
// velocity. Stationarity m (z - y) + c (|z| - l0) z/|z| = 0 (c = h^2 / alpha) makes z parallel to
// y, so z = u y/|y| with u = (m |y| + c l0) / (m + c). Newton starts at x + h v, off that ray,
// where the exact transverse part of Phi's Hessian, m + c (1 - l0/l) = m - 0.11 c, is negative:
// only the clamped (positive semi-definite) spring block gives descent directions there. (The
// clamp costs speed: near the solution Newton contracts the transverse error only by about the
// compression, 0.1 per iteration here.)
TEST(ImplicitEuler, CompressedSpringStepMatchesRadialSolution) {
  const double m = 0.01, l0 = 0.2, alpha = 1e-4, h = 0.01;
  const double start = 0.9 * l0 / std::sqrt(5.0);
  ImplicitEulerSystem s;
  s.gravity = {0.0, -9.81, 0.0};
  add_particle(s, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0);
  add_particle(s, {2.0 * start, start, 0.0}, {0.0, 0.0, 0.5}, 1.0 / m);
  s.springs.push_back({0, 1, l0, alpha});
  ImplicitEulerStepper stepper(s);
  const ImplicitEulerStats stats = stepper.step(h);
  EXPECT_TRUE(stats.converged);
  EXPECT_LE(stats.newton_iterations, 20);

  const Vec3 y{2.0 * start, start - h * h * 9.81, h * 0.5};
  const double y_length = std::hypot(y[0], y[1], y[2]);
  const double c = h * h / alpha;
  const double u = (m * y_length + c * l0) / (m + c);
  const Vec3 z = particle(stepper.positions(), 1);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(z[d], u * y[d] / y_length, 1e-10) << "coordinate " << d;
}

// Implicit Euler damps: for a convex energy (a 1D oscillator) the total energy cannot increase.
// Per step a mode of frequency w loses the factor 1 / (1 + (h w)^2) of its energy: here h w = 0.1,
// so 1000 steps leave about e^-10.
TEST(ImplicitEuler, OscillatorEnergyNeverIncreases) {
  const double m = 1.0, l0 = 1.0, alpha = 0.01, h = 0.01;
  ImplicitEulerSystem s;
  s.gravity = kNoGravity;
  add_particle(s, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0);
  add_particle(s, {l0 + 0.2, 0.0, 0.0}, {0.0, 0.0, 0.0}, 1.0 / m);
  s.springs.push_back({0, 1, l0, alpha});
  ImplicitEulerStepper stepper(s);
  const double initial = stepper.total_energy();
  EXPECT_NEAR(initial, 0.2 * 0.2 / (2.0 * alpha), 1e-12);
  double previous = initial;
  for (int k = 0; k < 1000; ++k) {
    ASSERT_TRUE(stepper.step(h).converged);
    const double energy = stepper.total_energy();
    ASSERT_LE(energy, previous + 1e-12 * initial) << "step " << k + 1;
    previous = energy;
  }
  EXPECT_LT(previous, 1e-3 * initial);
  EXPECT_GT(previous, 1e-6 * initial);  // the decay is the predicted one, not an instant collapse
}

// A chain hanging from a pinned particle: at rest, spring k carries the weight of the particles
// below it, T_k = (n - k) m g, so its strain is alpha T_k / l0.
TEST(ImplicitEuler, HangingChainStrainMatchesWeightBelow) {
  const int n = 10;
  const double m = 0.1, l0 = 0.1, alpha = 1e-8, g = 9.81;
  ImplicitEulerSystem s;
  s.gravity = {0.0, -g, 0.0};
  add_particle(s, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0);
  for (int k = 1; k <= n; ++k) {
    add_particle(s, {0.0, -k * l0, 0.0}, {0.0, 0.0, 0.0}, 1.0 / m);
    s.springs.push_back(
        {static_cast<std::uint32_t>(k - 1), static_cast<std::uint32_t>(k), l0, alpha});
  }
  ImplicitEulerStepper stepper(s);
  for (int k = 0; k < 200; ++k) ASSERT_TRUE(stepper.step(1e-3).converged) << "step " << k + 1;
  for (int k = 0; k < n; ++k) {
    const double strain = (distance(stepper.positions(), k, k + 1) - l0) / l0;
    const double expected = alpha * (n - k) * m * g / l0;
    EXPECT_NEAR(strain, expected, 0.01 * expected) << "spring " << k;
  }
  for (double v : stepper.velocities()) EXPECT_LT(std::abs(v), 1e-6);
}

// Hinge energy |sum_k kappa_k x_k|^2 / (2 alpha) with kappa = (1, -2, 1, 0) / a (a second
// difference): zero when straight, 2 d^2 / (alpha a^2) when the middle particle is lifted by d,
// unchanged by a translation, four times larger for 2 d.
TEST(ImplicitEuler, HingeEnergyMatchesHandComputedValues) {
  const double a = 0.1, alpha = 1e-4;
  auto hinge_energy = [&](double lift, Vec3 shift) {
    ImplicitEulerSystem s;
    s.gravity = kNoGravity;
    const Vec3 zero{0.0, 0.0, 0.0};
    add_particle(s, {shift[0], shift[1], shift[2]}, zero, 0.0);
    add_particle(s, {shift[0] + a, shift[1] + lift, shift[2]}, zero, 1.0);
    add_particle(s, {shift[0] + 2 * a, shift[1], shift[2]}, zero, 1.0);
    add_particle(s, {shift[0] + 3 * a, shift[1], shift[2]}, zero, 0.0);
    s.hinges.push_back({{0, 1, 2, 3}, {1.0 / a, -2.0 / a, 1.0 / a, 0.0}, alpha});
    return ImplicitEulerStepper(s).total_energy();
  };
  const double d = 0.01;
  EXPECT_NEAR(hinge_energy(0.0, {0.0, 0.0, 0.0}), 0.0, 1e-18);
  EXPECT_NEAR(hinge_energy(d, {0.0, 0.0, 0.0}), 2.0 * d * d / (alpha * a * a), 1e-9);  // 200 J
  EXPECT_NEAR(hinge_energy(d, {5.0, -3.0, 2.0}), 2.0 * d * d / (alpha * a * a), 1e-9);
  EXPECT_NEAR(hinge_energy(2.0 * d, {0.0, 0.0, 0.0}), 8.0 * d * d / (alpha * a * a), 1e-9);
}

// The hinge energy is quadratic, so a step with two free vertices solves, per coordinate, the
// linear 2x2 system  m_a (z_a - y_a) + c kappa_a q = 0  (a = 1, 2), q = kappa_0 x_0 + kappa_1 z_1 +
// kappa_2 z_2 + kappa_3 x_3, c = h^2 / alpha. Checks the solver's gradient and Hessian (including
// the cross term kappa_1 kappa_2) against Cramer's rule.
TEST(ImplicitEuler, HingeStepMatchesLinearSolution) {
  const std::array<double, 4> kappa{0.7, -1.9, 1.5, -0.3};
  const double alpha = 1e-2, h = 0.05, m1 = 0.2, m2 = 0.3;
  ImplicitEulerSystem s;
  s.gravity = {0.0, -9.81, 0.0};
  add_particle(s, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0);
  add_particle(s, {0.1, 0.05, -0.02}, {0.5, -0.2, 0.1}, 1.0 / m1);
  add_particle(s, {0.2, -0.03, 0.04}, {-0.3, 0.4, 0.0}, 1.0 / m2);
  add_particle(s, {0.3, 0.01, 0.0}, {0.0, 0.0, 0.0}, 0.0);
  s.hinges.push_back({{0, 1, 2, 3}, kappa, alpha});
  const ImplicitEulerSystem initial = s;
  ImplicitEulerStepper stepper(s);
  const ImplicitEulerStats stats = stepper.step(h);
  EXPECT_TRUE(stats.converged);
  EXPECT_EQ(stats.newton_iterations, 1);  // Phi is quadratic: the exact Hessian solves it at once

  const double c = h * h / alpha;
  for (int d = 0; d < 3; ++d) {
    const double y1 = initial.x[3 + d] + h * initial.v[3 + d] + h * h * s.gravity[d];
    const double y2 = initial.x[6 + d] + h * initial.v[6 + d] + h * h * s.gravity[d];
    const double q_pinned = kappa[0] * initial.x[d] + kappa[3] * initial.x[9 + d];
    // [m1 + c k1^2, c k1 k2; c k1 k2, m2 + c k2^2] (z1, z2) = (m1 y1 - c k1 qp, m2 y2 - c k2 qp)
    const double a11 = m1 + c * kappa[1] * kappa[1], a12 = c * kappa[1] * kappa[2];
    const double a22 = m2 + c * kappa[2] * kappa[2];
    const double b1 = m1 * y1 - c * kappa[1] * q_pinned, b2 = m2 * y2 - c * kappa[2] * q_pinned;
    const double det = a11 * a22 - a12 * a12;
    ASSERT_GT(det, 0.0);
    EXPECT_NEAR(stepper.positions()[3 + d], (b1 * a22 - a12 * b2) / det, 1e-10)
        << "coordinate " << d;
    EXPECT_NEAR(stepper.positions()[6 + d], (a11 * b2 - a12 * b1) / det, 1e-10)
        << "coordinate " << d;
  }
}

// Springs with a rest length between coincident particles have no direction. Particles 1 and 2
// fall together (their spring stays at length 0, so its Hessian block is the isotropic one) while
// the spring to the pinned particle 0 stretches.
TEST(ImplicitEuler, CoincidentParticlesStayFinite) {
  ImplicitEulerSystem s;
  s.gravity = {0.0, -9.81, 0.0};
  for (int k = 0; k < 3; ++k) add_particle(s, {0.5, 0.5, 0.5}, {0.0, 0.0, 0.0}, k == 0 ? 0.0 : 1.0);
  s.springs.push_back({0, 1, 0.1, 1e-4});
  s.springs.push_back({1, 2, 0.1, 1e-4});
  ImplicitEulerStepper stepper(s);
  for (int k = 0; k < 20; ++k) {
    ImplicitEulerStats stats;
    ASSERT_NO_THROW(stats = stepper.step(1e-3)) << "step " << k + 1;
    EXPECT_TRUE(std::isfinite(stats.gradient_norm));
  }
  for (double x : stepper.positions()) EXPECT_TRUE(std::isfinite(x));
  for (double v : stepper.velocities()) EXPECT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(stepper.total_energy()));
  EXPECT_LT(stepper.positions()[4], 0.5);  // the pair did move (down)
}

// A zero compliance is replaced by min_compliance: the same energy and the same step as a spring
// whose compliance is min_compliance, and a different one from twice that.
TEST(ImplicitEuler, ZeroComplianceUsesMinCompliance) {
  const double min_compliance = 1e-6, stretch = 0.5;
  auto stretched_spring = [&](double compliance) {
    ImplicitEulerSystem s;
    s.gravity = kNoGravity;
    add_particle(s, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0);
    add_particle(s, {1.0 + stretch, 0.0, 0.0}, {0.0, 0.0, 0.0}, 1.0);
    s.springs.push_back({0, 1, 1.0, compliance});
    return s;
  };
  ImplicitEulerStepper zero(stretched_spring(0.0), min_compliance);
  ImplicitEulerStepper minimum(stretched_spring(min_compliance), 1e-9);
  ImplicitEulerStepper twice(stretched_spring(2.0 * min_compliance), min_compliance);
  EXPECT_DOUBLE_EQ(zero.total_energy(), stretch * stretch / (2.0 * min_compliance));
  EXPECT_DOUBLE_EQ(zero.total_energy(), minimum.total_energy());
  EXPECT_DOUBLE_EQ(2.0 * twice.total_energy(), zero.total_energy());
  zero.step(1e-3);
  minimum.step(1e-3);
  twice.step(1e-3);
  EXPECT_DOUBLE_EQ(zero.positions()[3], minimum.positions()[3]);
  EXPECT_NE(zero.positions()[3], twice.positions()[3]);
}

// An overflow to infinity is reported as a runtime_error naming the step.
TEST(ImplicitEuler, NonFiniteValueThrowsNamingTheStep) {
  ImplicitEulerSystem s;
  s.gravity = kNoGravity;
  add_particle(s, {0.0, 0.0, 0.0}, {1e300, 0.0, 0.0}, 1.0);
  ImplicitEulerStepper stepper(s);
  EXPECT_NO_THROW(stepper.step(1e-3));  // x = 1e297: still finite
  try {
    stepper.step(1e10);  // x + h v = 1e297 + 1e310 overflows
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("step 2"), std::string::npos) << message;
    EXPECT_NE(message.find("non-finite"), std::string::npos) << message;
  }
}

// A hanging 8x8 sheet (stretch, shear and bending) pinned at two corners: Newton converges in every
// step, in a handful of iterations, to a residual force far below the weights, and the sheet
// keeps its stiff edges nearly inextensible.
TEST(ImplicitEuler, HangingSheetConvergesEveryStep) {
  const int n = 8;
  const double spacing = 0.1, mass = 0.01, alpha = 1e-6;
  ImplicitEulerSystem s;
  auto id = [&](int r, int c) { return static_cast<std::uint32_t>(r * n + c); };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const bool pinned = r == 0 && (c == 0 || c == n - 1);
      add_particle(s, {c * spacing, 1.0, r * spacing}, {0.0, 0.0, 0.0}, pinned ? 0.0 : 1.0 / mass);
    }
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      if (c + 1 < n) s.springs.push_back({id(r, c), id(r, c + 1), spacing, alpha});
      if (r + 1 < n) s.springs.push_back({id(r, c), id(r + 1, c), spacing, alpha});
      if (r + 1 < n && c + 1 < n)
        s.springs.push_back({id(r, c), id(r + 1, c + 1), spacing * std::sqrt(2.0), alpha});
      const std::array<double, 4> second_difference{1.0 / spacing, -2.0 / spacing, 1.0 / spacing,
                                                    0.0};
      if (c + 2 < n)
        s.hinges.push_back(
            {{id(r, c), id(r, c + 1), id(r, c + 2), id(r, c)}, second_difference, 1e-3});
      if (r + 2 < n)
        s.hinges.push_back(
            {{id(r, c), id(r + 1, c), id(r + 2, c), id(r, c)}, second_difference, 1e-3});
    }
  ImplicitEulerStepper stepper(s);
  for (int k = 0; k < 100; ++k) {
    const ImplicitEulerStats stats = stepper.step(1.0 / 200.0);
    ASSERT_TRUE(stats.converged) << "step " << k + 1;
    EXPECT_LE(stats.newton_iterations, 15) << "step " << k + 1;
    EXPECT_LT(stats.gradient_norm, 1e-6 * mass * 9.81) << "step " << k + 1;
  }
  for (const auto& spring : s.springs) {
    const double strain =
        distance(stepper.positions(), spring.i, spring.j) / spring.rest_length - 1.0;
    EXPECT_LT(std::abs(strain), 0.01);
  }
  EXPECT_LT(stepper.positions()[3 * id(n - 1, n / 2) + 1], 0.8);  // the free edge has fallen
}

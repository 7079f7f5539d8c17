// A deterministic colouring of the joints that Gauss-Seidel solves (joint.hpp), so that joints
// that share no movable body can be solved at once, in any order, with the bits of the serial
// solve in scene order.
//
// Joint k (in scene order) gets colour
//   c(k) = 1 + max{ c(j) : j < k, j and k share a movable body }   (0 when there is none),
// found in one pass by keeping, per body, the highest colour of a joint on it so far. Two joints
// of one colour share no movable body (else one of them would be above the other), and two
// joints that share one keep their scene order when the colours are solved in increasing order.
// A correction moves only the joint's own two bodies and reads nothing else that moves (a fixed
// body and the world never move: body_correction.hpp), so joints of one colour commute exactly
// and the colours in order give the serial solve's bits at any thread count. A chain is a colour
// per link; independent joints (pendulums hung from the world, a row of doors) share one colour.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace seiche::rigid {

/// A joint as the colouring sees it: its index, and its movable bodies (-1: the world or a fixed
/// body, which joints may share).
struct JointEnds {
  std::size_t joint = 0;
  int body_a = -1, body_b = -1;
};

class JointColours {
 public:
  JointColours() = default;
  /// Colours `joints` (in scene order) over `body_count` bodies.
  JointColours(std::span<const JointEnds> joints, std::size_t body_count);

  std::size_t colour_count() const { return colour_start_.empty() ? 0 : colour_start_.size() - 1; }
  /// The joints of colour c, in scene order.
  std::span<const std::size_t> colour(std::size_t c) const {
    return std::span<const std::size_t>(members_).subspan(colour_start_[c], colour_start_[c + 1] - colour_start_[c]);
  }

 private:
  std::vector<std::size_t> members_;       // colour by colour
  std::vector<std::size_t> colour_start_;  // colour c is members_[colour_start_[c], colour_start_[c + 1])
};

}  // namespace seiche::rigid

// The joints' colouring (the rule is in joint_colours.hpp).
#include "joint_colours.hpp"

#include <algorithm>

namespace seiche::rigid {

JointColours::JointColours(std::span<const JointEnds> joints, std::size_t body_count) {
  std::vector<int> highest(body_count, -1);  // per body: the highest colour of a joint on it so far
  std::vector<int> colour_of(joints.size());
  std::size_t colours = 0;
  for (std::size_t k = 0; k < joints.size(); ++k) {
    int c = 0;
    for (int body : {joints[k].body_a, joints[k].body_b})
      if (body >= 0) c = std::max(c, highest[std::size_t(body)] + 1);
    for (int body : {joints[k].body_a, joints[k].body_b})
      if (body >= 0) highest[std::size_t(body)] = c;
    colour_of[k] = c;
    colours = std::max(colours, std::size_t(c) + 1);
  }
  // Counting sort by colour, stable: scene order inside a colour.
  colour_start_.assign(colours + 1, 0);
  for (int c : colour_of) ++colour_start_[std::size_t(c) + 1];
  for (std::size_t c = 0; c < colours; ++c) colour_start_[c + 1] += colour_start_[c];
  members_.resize(joints.size());
  std::vector<std::size_t> next(colour_start_.begin(), colour_start_.end() - 1);
  for (std::size_t k = 0; k < joints.size(); ++k) members_[next[std::size_t(colour_of[k])]++] = joints[k].joint;
}

}  // namespace seiche::rigid

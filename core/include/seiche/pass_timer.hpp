// Wall time per pass: each pass of the substep is timed under its name; the table keeps the
// order in which passes first ran, so reports list them in pipeline order.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace seiche {

class PassTimer {
 public:
  struct Entry {
    std::string name;
    double frame_seconds = 0.0;  ///< in the current frame
    double total_seconds = 0.0;  ///< since the start of the run
  };

  template <class F>
  void time(const char* name, F&& f) {
    const auto start = std::chrono::steady_clock::now();
    f();
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    Entry& e = entry(name);
    e.frame_seconds += elapsed.count();
    e.total_seconds += elapsed.count();
  }

  void begin_frame() {
    for (Entry& e : entries_) e.frame_seconds = 0.0;
  }
  const std::vector<Entry>& entries() const { return entries_; }

 private:
  Entry& entry(const char* name) {
    for (Entry& e : entries_)
      if (e.name == name) return e;
    entries_.push_back({name});
    return entries_.back();
  }
  std::vector<Entry> entries_;
};

}  // namespace seiche

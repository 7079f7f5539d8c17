#include "seiche/thread_count.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace seiche {

int resolve_thread_count(int requested) {
  return requested > 0 ? requested : tbb::info::default_concurrency();
}

void run_with_threads(int threads, const std::function<void()>& work) {
  if (threads < 1)
    throw std::invalid_argument("run_with_threads: " + std::to_string(threads) +
                                " threads (at least 1)");
  using tbb::global_control;
  // Without this an arena of 8 slots on a 2-core machine gets 2 threads: TBB's default cap on its
  // worker threads is the core count. Never lower than the cap already in force, so that other
  // arenas of the process are not slowed down by a run that asks for fewer threads.
  const std::size_t cap = std::max(
      std::size_t(threads), global_control::active_value(global_control::max_allowed_parallelism));
  const global_control allow(global_control::max_allowed_parallelism, cap);
  tbb::task_arena arena(threads);
  arena.execute(work);
}

}  // namespace seiche

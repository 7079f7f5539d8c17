// Running work on an exact number of threads.
//
// A run's results never depend on its thread count (docs/design.md, "The determinism
// contract"), and the tests check that with counts above the machine's core count too (8 threads
// on 2 cores). tbb::global_control alone cannot do that: it only caps the threads TBB may use
// (its default cap is the core count) and leaves the count to the scheduler. So the work runs in
// a tbb::task_arena of exactly `threads` slots, under a global_control that lets TBB start that
// many.
#pragma once

#include <functional>
#include <optional>
#include <type_traits>
#include <utility>

namespace seiche {

/// The thread count of a run: `requested` if it is positive, else every core of the machine
/// (TBB's default concurrency).
int resolve_thread_count(int requested);

/// Runs `work` in a task arena of `threads` (>= 1) threads, the calling thread included, and
/// returns when it is done; an exception thrown by `work` passes through. Every TBB algorithm
/// that `work` starts stays in that arena. The cap TBB puts on all arenas of the process is raised
/// to at least `threads` for the call (global_control; the smallest of all active caps wins, so a
/// caller's lower cap still holds, and then fewer threads run: the results are the same anyway).
void run_with_threads(int threads, const std::function<void()>& work);

/// Work that returns a value (the other overload takes work that returns nothing).
template <class Work>
concept ValueWork = !std::is_void_v<std::invoke_result_t<Work&>>;

/// The same for work that returns a value: returns it.
template <ValueWork Work>
std::invoke_result_t<Work&> run_with_threads(int threads, Work&& work) {
  std::optional<std::invoke_result_t<Work&>> result;
  run_with_threads(threads, std::function<void()>([&] { result.emplace(work()); }));
  return std::move(*result);
}

}  // namespace seiche

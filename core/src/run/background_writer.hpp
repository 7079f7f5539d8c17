// Frame files written on a background thread, so that putting a frame on disk overlaps the
// simulation of the next one. write_file_atomically ends with fsync, a wait of about 2 ms per
// file on this kind of machine (5 % of a fast fluid frame), and it is waiting, not computing.
//
// Files are written in the order they are submitted, each atomically (write_file_atomically).
// At most `max_pending` files wait in memory: submit() blocks until there is room, so a disk
// slower than the simulation slows the simulation instead of filling the memory. The first
// failure (IoError: full disk, no permission) is kept, nothing submitted after it is written,
// and it is thrown by the next submit() or by finish(). `seiche run` calls finish() after
// simulating each frame, before the frame counts: a failure stops the run one frame later at
// most, and nothing of a later frame is written.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

namespace seiche {

class BackgroundWriter {
 public:
  explicit BackgroundWriter(std::size_t max_pending = 2);
  /// Writes what is still queued (unless a write failed) and stops; errors are dropped here, so
  /// call finish() first wherever they must be seen.
  ~BackgroundWriter();
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

  /// Queues `bytes` for `path`. Throws the first failure of an earlier file, if any.
  void submit(std::filesystem::path path, std::string bytes);
  /// Returns once every submitted file is written (or dropped after a failure); throws the first
  /// failure, if any. The writer stays usable; a failure stays in force.
  void finish();

 private:
  struct Job {
    std::filesystem::path path;
    std::string bytes;
  };
  void work();

  const std::size_t max_pending_;
  std::mutex mutex_;
  std::condition_variable changed_;  // queue, busy_ or stop_ changed
  std::deque<Job> queue_;
  bool busy_ = false;  // the worker holds a job outside the queue
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread worker_;  // last: starts after every other member exists
};

}  // namespace seiche

#include "background_writer.hpp"

#include <algorithm>
#include <utility>

#include "seiche/output_files.hpp"

namespace seiche {

BackgroundWriter::BackgroundWriter(std::size_t max_pending)
    : max_pending_(std::max<std::size_t>(max_pending, 1)), worker_([this] { work(); }) {}

BackgroundWriter::~BackgroundWriter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void BackgroundWriter::submit(std::filesystem::path path, std::string bytes) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return error_ || queue_.size() < max_pending_; });
  if (error_) std::rethrow_exception(error_);
  queue_.push_back({std::move(path), std::move(bytes)});
  changed_.notify_all();
}

void BackgroundWriter::finish() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
  if (error_) std::rethrow_exception(error_);
}

void BackgroundWriter::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stop_ and nothing left
    Job job = std::move(queue_.front());
    queue_.pop_front();
    changed_.notify_all();  // room in the queue
    if (error_) continue;   // nothing after a failure is written
    busy_ = true;
    lock.unlock();
    std::exception_ptr failure;
    try {
      write_file_atomically(job.path, job.bytes);
    } catch (...) {
      failure = std::current_exception();
    }
    lock.lock();
    busy_ = false;
    if (failure && !error_) error_ = failure;
    changed_.notify_all();
  }
}

}  // namespace seiche

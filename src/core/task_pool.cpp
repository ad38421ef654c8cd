#include "src/core/task_pool.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace estlab {

TaskPool::TaskPool(int jobs, size_t tasks, Work work, Options options)
    : tasks_(tasks),
      work_(std::move(work)),
      options_(std::move(options)),
      waiting_(tasks, 0),
      gates_(tasks),
      started_(tasks, 0),
      finished_(tasks, 0) {
  if (!options_.after.empty() && options_.after.size() != tasks)
    throw std::invalid_argument("TaskPool: 'after' must have one entry per task");
  for (size_t i = 0; i < options_.after.size(); ++i)
    for (size_t j : options_.after[i]) {
      if (j >= tasks || j == i)
        throw std::invalid_argument("TaskPool: task " + std::to_string(i) + " waits for task " +
                                    std::to_string(j));
      ++waiting_[i];
      gates_[j].push_back(i);
    }
  if (options_.order.empty()) {
    options_.order.resize(tasks);
    for (size_t i = 0; i < tasks; ++i) options_.order[i] = i;
  }
  std::vector<size_t> sorted = options_.order;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < sorted.size(); ++i)
    if (sorted.size() != tasks || sorted[i] != i)
      throw std::invalid_argument("TaskPool: 'order' is not a permutation of the tasks");
  const int workers = tasks == 0 ? 0 : std::max(1, int(std::min<size_t>(size_t(jobs), tasks)));
  for (int w = 0; w < workers; ++w) threads_.emplace_back([this, w] { Worker(w); });
}

TaskPool::~TaskPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    failed_ = true;  // start nothing more
  }
  changed_.notify_all();
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
}

bool TaskPool::StopRequested() const {
  return failed_ || (options_.stop != nullptr && options_.stop->load() != 0);
}

size_t TaskPool::NextReady() {
  while (first_unstarted_ < tasks_ && started_[options_.order[first_unstarted_]])
    ++first_unstarted_;
  for (size_t k = first_unstarted_; k < tasks_; ++k) {
    const size_t i = options_.order[k];
    if (!started_[i] && waiting_[i] == 0) return i;
  }
  return tasks_;
}

void TaskPool::Worker(int worker) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    size_t task = tasks_;
    // Wake at least every 100 ms to see a stop flag set by a signal handler.
    while (!StopRequested() && (task = NextReady()) == tasks_ && running_ > 0)
      changed_.wait_for(lock, std::chrono::milliseconds(100));
    if (StopRequested() || task == tasks_) break;  // stopped, or nothing left that can run
    started_[task] = 1;
    ++running_;
    lock.unlock();
    std::exception_ptr error;
    try {
      work_(task, worker);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    --running_;
    if (error) {
      if (!error_) error_ = error;
      failed_ = true;
    } else {
      finished_[task] = 1;
      for (size_t j : gates_[task]) --waiting_[j];
    }
    changed_.notify_all();
  }
  ++exited_;
  changed_.notify_all();
}

bool TaskPool::WaitFor(size_t i) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return finished_[i] || exited_ == int(threads_.size()); });
  return finished_[i] != 0;
}

bool TaskPool::WaitFor(size_t i, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return finished_[i] || exited_ == int(threads_.size()); });
  return finished_[i] != 0;
}

bool TaskPool::Ended() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return exited_ == int(threads_.size());
}

void TaskPool::Join() {
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

}  // namespace estlab

// One pool of worker threads for tasks that may wait on other tasks: a
// study's tunings and its runs (studies/run/study_runner.cpp: a run waits only
// for the tunings its scenario uses), and a tuner's starts
// (adaptive/tuner_starts.h). estlab has no other thread pool.
//
// Scheduling: task i is ready once every task in after[i] has finished; a
// free worker takes the first ready task in `order` (callers put long tasks
// first). Results never depend on the number of workers as long as a task
// writes only its own slot and reads only what the tasks it waits for
// wrote: finishing a task happens-before starting one that waits for it,
// and before WaitFor(i) returns true.
//
// Stopping: when *stop becomes nonzero (Ctrl-C) no new task starts and the
// running ones finish. A task that throws stops the pool the same way, and
// Join rethrows the first exception. Tasks that never ran are left
// unfinished (Finished(i) false).
//
// Usage:
//   std::vector<Result> results(n);
//   TaskPool pool(jobs, n, [&](size_t i, int worker) { results[i] = Work(i, worker); },
//                 {.after = deps, .stop = &stop_flag});
//   for (size_t i = 0; i < n && pool.WaitFor(i); ++i) Write(results[i]);  // in task order
//   pool.Join();  // rethrows a task's exception
#ifndef ESTLAB_CORE_TASK_POOL_H_
#define ESTLAB_CORE_TASK_POOL_H_

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace estlab {

struct TaskPoolOptions {
  std::vector<std::vector<size_t>> after;  // per task, the tasks it waits for; empty: none
  std::vector<size_t> order;               // the tasks in the order to start them; empty: 0..n-1
  const std::atomic<int>* stop = nullptr;  // nonzero: start no new task
};

class TaskPool {
 public:
  // work(task, worker): worker in 0..Workers()-1, for per-worker state.
  using Work = std::function<void(size_t task, int worker)>;

  using Options = TaskPoolOptions;

  // Starts min(jobs, tasks) workers (at least one when there is a task).
  // Throws std::invalid_argument for an `after` or `order` that names a
  // task out of range, or an `order` that is not a permutation.
  TaskPool(int jobs, size_t tasks, Work work, Options options = {});
  ~TaskPool();  // stops new tasks and waits for the running ones
  TaskPool(const TaskPool&) = delete;
  TaskPool& operator=(const TaskPool&) = delete;

  int Workers() const { return int(threads_.size()); }
  // Waits until task i has finished (true) or can no longer run because the
  // pool stopped (false).
  bool WaitFor(size_t i);
  // The same, giving up after `timeout` (false; Ended() tells which).
  bool WaitFor(size_t i, std::chrono::milliseconds timeout);
  // Whether every worker has exited: all tasks done, or the pool stopped.
  bool Ended() const;
  // Waits for the workers to exit; rethrows the first exception of a task.
  void Join();

 private:
  bool StopRequested() const;
  // The next ready task in order_ (tasks_ when none is ready yet); under mutex_.
  size_t NextReady();
  void Worker(int worker);

  size_t tasks_;
  Work work_;
  Options options_;
  std::vector<int> waiting_;                // per task, unfinished tasks it waits for
  std::vector<std::vector<size_t>> gates_;  // per task, the tasks waiting for it
  std::vector<char> started_, finished_;
  size_t first_unstarted_ = 0;  // in order_: every earlier task has started
  int running_ = 0, exited_ = 0;
  bool failed_ = false;
  std::exception_ptr error_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::thread> threads_;
};

}  // namespace estlab

#endif  // ESTLAB_CORE_TASK_POOL_H_

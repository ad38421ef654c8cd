// The task pool (src/core/task_pool.h): every task runs once and after the
// tasks it waits for, in any number of workers; results in task order are
// the same for 1, 2 and 8 workers; `order` decides which ready task starts
// first; a throwing task stops the pool and Join rethrows; the stop flag
// starts nothing new; bad graphs are refused.
#include "src/core/task_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace estlab {
namespace {

TaskPoolOptions After(std::vector<std::vector<size_t>> after) {
  TaskPoolOptions o;
  o.after = std::move(after);
  return o;
}

// A diamond-shaped graph of 40 tasks: task i waits for i/2 and i/3 (i > 0).
std::vector<std::vector<size_t>> Graph(size_t n) {
  std::vector<std::vector<size_t>> after(n);
  for (size_t i = 1; i < n; ++i) {
    after[i].push_back(i / 2);
    if (i / 3 != i / 2) after[i].push_back(i / 3);
  }
  return after;
}

TEST(TaskPool, EveryTaskRunsOnceAfterWhatItWaitsForAndResultsDoNotDependOnWorkers) {
  const size_t n = 40;
  const auto after = Graph(n);
  std::vector<long> reference;
  for (const int jobs : {1, 2, 8}) {
    std::vector<long> value(n, -1);
    std::vector<std::atomic<int>> runs(n);
    TaskPool pool(
        jobs, n,
        [&](size_t i, int worker) {
          EXPECT_GE(worker, 0);
          EXPECT_LT(worker, jobs);
          ++runs[i];
          long v = long(i);
          for (size_t j : after[i]) {
            EXPECT_GE(value[j], 0) << "task " << i << " ran before task " << j;
            v += 3 * value[j];
          }
          if (i % 7 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
          value[i] = v;
        },
        After(after));
    std::vector<long> in_order;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_TRUE(pool.WaitFor(i)) << i;
      in_order.push_back(value[i]);
    }
    pool.Join();
    EXPECT_TRUE(pool.Ended());
    for (size_t i = 0; i < n; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
    if (reference.empty())
      reference = in_order;
    else
      EXPECT_EQ(in_order, reference) << jobs << " workers";
  }
}

TEST(TaskPool, OneWorkerStartsTheFirstReadyTaskInOrder) {
  // Tasks 0..5, task 1 waits for task 4; order 4, 1, 0, 5, 2, 3 with one
  // worker runs them exactly so.
  std::vector<size_t> ran;
  TaskPool pool(1, 6, [&](size_t i, int) { ran.push_back(i); },
                {.after = {{}, {4}, {}, {}, {}, {}}, .order = {1, 4, 0, 5, 2, 3}});
  pool.Join();
  EXPECT_EQ(ran, (std::vector<size_t>{4, 1, 0, 5, 2, 3}));
}

TEST(TaskPool, AThrowingTaskStopsThePoolAndJoinRethrows) {
  std::atomic<int> ran{0};
  TaskPool pool(2, 200,
                [&](size_t i, int) {
                  ++ran;
                  if (i == 3) throw std::runtime_error("task 3 failed");
                  std::this_thread::sleep_for(std::chrono::milliseconds(1));
                },
                {});
  size_t finished = 0;
  while (finished < 200 && pool.WaitFor(finished)) ++finished;
  EXPECT_LT(finished, 200u);
  try {
    pool.Join();
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "task 3 failed");
  }
  EXPECT_LT(ran.load(), 200);
  EXPECT_TRUE(pool.Ended());
}

TEST(TaskPool, TheStopFlagStartsNothingNewAndTheWaitersAreReleased) {
  std::atomic<int> stop{0}, ran{0};
  TaskPool pool(2, 100,
                [&](size_t i, int) {
                  ++ran;
                  if (i == 5) stop = 1;
                },
                {.after = Graph(100), .order = {}, .stop = &stop});
  EXPECT_FALSE(pool.WaitFor(99));  // released although task 99 never runs
  pool.Join();
  EXPECT_LT(ran.load(), 100);
  EXPECT_GE(ran.load(), 6);
}

TEST(TaskPool, BadGraphsAreRefusedAndNoTasksIsNoWorker) {
  const auto work = [](size_t, int) {};
  EXPECT_THROW((TaskPool(2, 3, work, After({{}, {5}, {}}))), std::invalid_argument);
  EXPECT_THROW((TaskPool(2, 3, work, After({{}, {1}, {}}))), std::invalid_argument);
  EXPECT_THROW((TaskPool(2, 3, work, After({{}, {}}))), std::invalid_argument);
  EXPECT_THROW((TaskPool(2, 3, work, {.after = {}, .order = {0, 0, 1}})), std::invalid_argument);
  TaskPool none(4, 0, work);
  EXPECT_EQ(none.Workers(), 0);
  EXPECT_TRUE(none.Ended());
  none.Join();
  // A cycle never runs: the pool ends with those tasks unfinished.
  std::atomic<int> ran{0};
  TaskPool cycle(
      2, 3, [&](size_t, int) { ++ran; }, After({{}, {2}, {1}}));
  EXPECT_TRUE(cycle.WaitFor(0));
  EXPECT_FALSE(cycle.WaitFor(1));
  cycle.Join();
  EXPECT_EQ(ran.load(), 1);
}

}  // namespace
}  // namespace estlab

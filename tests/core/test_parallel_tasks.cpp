#include "core/parallel_tasks.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

using phantasm::run_tasks_in_parallel;

TEST(ParallelTasks, EveryTaskRunsOnceOnAsManyThreadsAsAsked) {
  std::vector<std::atomic<int>> runs(100);
  std::mutex mutex;
  std::set<std::thread::id> threads;
  run_tasks_in_parallel(runs.size(), 3, [&](std::size_t i) {
    ++runs[i];
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const std::lock_guard<std::mutex> lock(mutex);
    threads.insert(std::this_thread::get_id());
  });
  for (const std::atomic<int>& r : runs)
    EXPECT_EQ(r.load(), 1);
  EXPECT_GE(threads.size(), 2u);
  EXPECT_LE(threads.size(), 3u);
  EXPECT_EQ(threads.count(std::this_thread::get_id()), 1u); // the caller works too
}

TEST(ParallelTasks, OneThreadRunsTheTasksInOrderOnTheCaller) {
  std::vector<std::size_t> order;
  const std::thread::id caller = std::this_thread::get_id();
  run_tasks_in_parallel(5, 1, [&](std::size_t i) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    order.push_back(i);
  });
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  run_tasks_in_parallel(0, 2, [](std::size_t) { FAIL() << "no task to run"; });
}

TEST(ParallelTasks, TheFirstExceptionIsRethrownAndNoTaskStartsAfterIt) {
  std::atomic<int> started{0};
  EXPECT_THROW(run_tasks_in_parallel(1000, 2,
                                     [&](std::size_t i) {
                                       ++started;
                                       if (i == 3) throw std::runtime_error("task 3");
                                       std::this_thread::sleep_for(std::chrono::milliseconds(1));
                                     }),
               std::runtime_error);
  EXPECT_LT(started.load(), 200); // the other thread finishes the task it holds, then stops
}

// Cancellation asked of one helper thread: StopThisThreadWhen and StopOnFailure, as the run uses
// them for the reference state built beside the deformation.
#include "core/cancellation.hpp"
#include "core/error.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>

using namespace phantasm;

TEST(Cancellation, AStopForThisThreadIsSeenByItAloneAndOnlyWhileItLasts) {
  reset_cancellation();
  std::atomic<bool> stop{false}, inner_stop{false};
  {
    const StopThisThreadWhen scope(stop);
    EXPECT_FALSE(cancellation_requested());
    stop = true;
    EXPECT_TRUE(cancellation_requested());
    EXPECT_THROW(throw_if_cancelled(), Cancelled);
    bool other_thread_sees = true;
    std::thread([&] { other_thread_sees = cancellation_requested(); }).join();
    EXPECT_FALSE(other_thread_sees);
    {
      const StopThisThreadWhen nested(inner_stop); // the one made last is asked
      EXPECT_FALSE(cancellation_requested());
      inner_stop = true;
      EXPECT_TRUE(cancellation_requested());
      inner_stop = false;
    }
    EXPECT_TRUE(cancellation_requested()); // the outer one again
  }
  EXPECT_FALSE(cancellation_requested());
  EXPECT_NO_THROW(throw_if_cancelled());
}

TEST(Cancellation, AFailureReleasesTheHelperBeforeItsFutureWaits) {
  reset_cancellation();
  std::atomic<bool> unwanted{false};
  { const StopOnFailure guard(unwanted); }
  EXPECT_FALSE(unwanted.load()) << "a normal exit asks nothing";

  // The helper polls until it is stopped (or gives up after a minute, which the test would see).
  std::atomic<bool> helper_stopped{false};
  const auto fail_beside_a_helper = [&] {
    std::atomic<bool> stop{false};
    std::future<void> helper = std::async(std::launch::async, [&] {
      const StopThisThreadWhen scope(stop);
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(1);
      while (!cancellation_requested() && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      helper_stopped = cancellation_requested();
    });
    const StopOnFailure guard(stop);
    throw std::runtime_error("the work beside the helper failed");
  };
  EXPECT_THROW(fail_beside_a_helper(), std::runtime_error);
  EXPECT_TRUE(helper_stopped.load());
  EXPECT_FALSE(cancellation_requested()); // nothing was asked of the process
}

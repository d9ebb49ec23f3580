#include "core/progress.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace phantasm;

TEST(Progress, PlainLinesComeAtMostEveryFewSecondsWhenNotOnATerminal) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::lines);
  {
    ProgressBar bar(reporter, "voxelizing", 100);
    for (int i = 0; i < 100; ++i) {
      bar.advance();
      bar.set_detail("organ " + std::to_string(i));
    }
  }
  // A quick step writes one line, at its end (a log or pipe gets no line per unit of work).
  const std::string text = stream.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
  EXPECT_EQ(text.find('\r'), std::string::npos);
  EXPECT_NE(text.find("voxelizing 100% (100/100)"), std::string::npos);
}

TEST(Progress, ASlowStepShowsElapsedTimeTheTimeLeftAndItsDetailWhileItRuns) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::bar);
  {
    ProgressBar bar(reporter, "anatomy", 4);
    bar.advance();
    progress_detail("ball: tet meshing");
    // No call for over a second (a step inside a library): the ticker redraws the bar.
    std::this_thread::sleep_for(std::chrono::milliseconds(1300));
    const std::string text = stream.str();
    EXPECT_NE(text.find("ball: tet meshing"), std::string::npos) << text;
    EXPECT_NE(text.find(" left"), std::string::npos) << text;
    EXPECT_NE(text.rfind("25% (1/4) 1."), std::string::npos) << text; // redrawn after a second
  }
  EXPECT_FALSE(progress_detail_due()); // no bar lives any more
}

TEST(Progress, ABarUnwoundByAnExceptionStopsWhereTheWorkStopped) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::lines);
  try {
    ProgressBar bar(reporter, "mri", 4);
    bar.advance();
    throw std::runtime_error("cancelled");
  } catch (const std::runtime_error&) {
  }
  const std::string text = stream.str();
  EXPECT_EQ(text.find("100%"), std::string::npos) << text;
  EXPECT_NE(text.find("mri  25% (1/4)"), std::string::npos) << text;
  EXPECT_NE(text.find("stopped"), std::string::npos) << text;
}

TEST(Progress, BarRedrawsInPlaceOnATerminalAndEndsWithOneNewline) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::bar);
  {
    ProgressBar bar(reporter, "solving", 4);
    bar.advance(4);
  }
  const std::string text = stream.str();
  EXPECT_NE(text.find('\r'), std::string::npos);
  EXPECT_NE(text.find("[##############################]"), std::string::npos);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1);
}

// A log line printed while a bar is mid-line starts on a cleared line ("\r", erase to end of
// line) instead of running on after the bar; the bar's next step redraws it below.
TEST(Progress, ALogLineClearsABarLeftMidLine) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::bar);
  {
    ProgressBar bar(reporter, "solving", 4);
    std::this_thread::sleep_for(std::chrono::milliseconds(150)); // past the 100 ms redraw throttle
    bar.advance(1);
    ASSERT_NE(stream.str().find("solving ["), std::string::npos) << stream.str();
    reporter.warning("sim", "not converged");
    reporter.modelled("sim", "next");
    bar.advance(3);
  }
  const std::string text = stream.str();
  // A bar draw is "\r<bar>\033[K"; only a log line's clearing has "\r\033[K".
  EXPECT_NE(text.find("\033[K\r\033[K[sim] warning: not converged\n[sim] next\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("\r\033[K", text.find("[sim] next")), std::string::npos) << text;
  // The finished bar ends its line, so a line after it needs no clearing.
  reporter.note("done");
  EXPECT_EQ(stream.str().substr(text.size()), "done\n");
}

TEST(Progress, QuietPrintsNothingButKeepsTheLog) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::none);
  reporter.modelled("sim", "grey_matter: simulated");
  reporter.skipped("mri", "noise");
  {
    ProgressBar bar(reporter, "writing", 3);
    bar.advance(3);
  }
  EXPECT_TRUE(stream.str().empty());
  EXPECT_EQ(reporter.log_lines(),
            (std::vector<std::string>{"[sim] grey_matter: simulated", "[mri] skipped: noise"}));
}

TEST(Progress, AdvancingFromSeveralThreadsCountsEveryStep) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::lines);
  {
    ProgressBar bar(reporter, "work", 4000);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&] {
        for (int i = 0; i < 1000; ++i)
          bar.advance();
      });
    for (auto& t : threads)
      t.join();
  }
  EXPECT_NE(stream.str().find("work 100% (4000/4000)"), std::string::npos);
}

// Work run beside a stage on a thread of its own (the reference state while the deformation is
// solved): its unlisted bar does not take the stage's details while it lives, and its own details
// do not reach the stage's bar.
TEST(Progress, AnUnlistedBarAndQuietDetailsOnAnotherThreadLeaveTheStagesBarAlone) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::bar);
  Reporter silent = Reporter::silent();
  {
    ProgressBar stage(reporter, "deform", 2);
    std::promise<void> started, go_on;
    std::thread beside([&] {
      const QuietProgressDetails quiet;
      ProgressBar own(silent, "voxelize", 2, ProgressBar::Unlisted{});
      EXPECT_FALSE(progress_detail_due());
      started.set_value();
      go_on.get_future().wait();
      progress_detail("tissue fractions, slab 3/24"); // goes nowhere
      own.advance(2);
    });
    started.get_future().wait();
    // The other thread's bar lives: the stage's bar still takes this thread's details.
    progress_detail("iteration 4");
    stage.advance();
    std::this_thread::sleep_for(std::chrono::milliseconds(1300)); // the ticker redraws it
    EXPECT_NE(stream.str().find("iteration 4"), std::string::npos) << stream.str();
    go_on.set_value();
    beside.join();
    std::this_thread::sleep_for(std::chrono::milliseconds(1300)); // and again
  }
  const std::string text = stream.str();
  EXPECT_EQ(text.find("slab 3/24"), std::string::npos) << text;
  EXPECT_EQ(text.find("voxelize"), std::string::npos) << text;
  EXPECT_FALSE(progress_detail_due()); // no listed bar lives any more
}

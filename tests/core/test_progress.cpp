#include "core/progress.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <sstream>
#include <thread>
#include <vector>

using namespace phantasm;

TEST(Progress, PlainLinesAppearOncePerTenthWhenNotOnATerminal) {
  std::ostringstream stream;
  Reporter reporter(stream, ProgressStyle::lines);
  {
    ProgressBar bar(reporter, "voxelizing", 100);
    for (int i = 0; i < 100; ++i)
      bar.advance();
  }
  const std::string text = stream.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10);
  EXPECT_EQ(text.find('\r'), std::string::npos);
  EXPECT_NE(text.find("voxelizing 100% (100/100)"), std::string::npos);
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
    std::this_thread::sleep_for(std::chrono::milliseconds(60)); // past the redraw throttle
    bar.advance(1);
    ASSERT_NE(stream.str().find("solving ["), std::string::npos) << stream.str();
    reporter.warning("sim", "not converged");
    reporter.modelled("sim", "next");
    bar.advance(3);
  }
  const std::string text = stream.str();
  EXPECT_NE(text.find("s\r\033[K[sim] warning: not converged\n[sim] next\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("\033[K", text.find("[sim] next")), std::string::npos) << text;
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

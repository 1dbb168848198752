// mc-sim's progress report: plain per-frame lines off a terminal, '\r' updates on one, silence
// with --quiet.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "pipeline/stages/sim/sim_progress.h"

using namespace mudcrack;

namespace {
std::string contents(std::FILE* f) {
    std::fflush(f);
    std::rewind(f);
    std::string text;
    char buf[512];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
    return text;
}
}  // namespace

TEST(SimProgress, FormatsDurations) {
    EXPECT_EQ(SimProgress::format_duration(12.4), "12s");
    EXPECT_EQ(SimProgress::format_duration(187), "3m07s");
    EXPECT_EQ(SimProgress::format_duration(3720), "1h02m");
    EXPECT_EQ(SimProgress::format_duration(-1), "?");
}

TEST(SimProgress, PlainLinePerFrameOffATerminal) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    SimProgress progress(1000, 1, 4, 0.0, 4.0 / 24, true, f, false);
    progress.substep(1, 10, 0.01, 10, 0.5);  // no output between frames off a terminal
    progress.frame_done(1, 20, 1.0 / 24, 20, 1.0);
    progress.frame_done(2, 20, 2.0 / 24, 40, 2.0);
    progress.finish();
    const std::string text = contents(f);
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;
    EXPECT_EQ(text.find('\r'), std::string::npos) << text;
    EXPECT_NE(text.find("frame 1/4"), std::string::npos) << text;
    EXPECT_NE(text.find("frame 2/4"), std::string::npos) << text;
    // 40 substeps x 1000 particles in 2 s of stepping
    EXPECT_NE(text.find("0.02 M particle-steps/s"), std::string::npos) << text;
    EXPECT_NE(text.find("t = 0.0833 s"), std::string::npos) << text;
    EXPECT_NE(text.find("ETA"), std::string::npos) << text;
    std::fclose(f);
}

TEST(SimProgress, CarriageReturnOnATerminalAndSilentWhenQuiet) {
    std::FILE* f = std::tmpfile();
    ASSERT_NE(f, nullptr);
    {
        SimProgress progress(1000, 1, 2, 0.0, 2.0 / 24, true, f, true);
        progress.substep(1, 1, 0.001, 1, 0.01);
        progress.frame_done(1, 20, 1.0 / 24, 20, 1.0);
        progress.finish();
    }
    const std::string text = contents(f);
    EXPECT_EQ(text.front(), '\r') << text;
    EXPECT_EQ(text.back(), '\n') << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
    std::fclose(f);

    std::FILE* g = std::tmpfile();
    SimProgress quiet(1000, 1, 2, 0.0, 2.0 / 24, false, g, false);
    quiet.frame_done(1, 20, 1.0 / 24, 20, 1.0);
    quiet.finish();
    EXPECT_TRUE(contents(g).empty());
    std::fclose(g);
}

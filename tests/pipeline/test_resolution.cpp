// "WxH" and "A:B:S" as the command line spells them: whole, in range, or refused. sscanf's %d
// stopped at junk ("8x8junk" was 8x8) and wrapped overflow ("4294967304x8" was 8x8).
#include "pipeline/resolution.h"
#include <gtest/gtest.h>
#include <stdexcept>

using namespace lpt::pipeline;

TEST(Resolution, WholeTextInRangeOrAnErrorNamingTheOption) {
    int w = 0, h = 0;
    parse_resolution("16x9", w, h, "--res");
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 9);
    parse_resolution("2X3", w, h, "--res");
    EXPECT_EQ(w * 10 + h, 23);
    for (const char* bad : {"4294967304x8", "99999999999x8", "8x8x8", "8x8junk", "8x", "x8", "0x8", "-8x8", "8x-8",
                            " 8x8", "8 x 8", "", "x", "+8x8"}) {
        try {
            parse_resolution(bad, w, h, "--aov-res");
            ADD_FAILURE() << "'" << bad << "' was accepted as " << w << "x" << h;
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("--aov-res"), std::string::npos) << e.what();
        }
    }
}

TEST(Resolution, FrameRangesSplitIntoWholeIntegers) {
    EXPECT_EQ(split_integers("0:40:20", ':'), (std::vector<int>{0, 40, 20}));
    EXPECT_EQ(split_integers("7", ':'), (std::vector<int>{7}));
    for (const char* bad : {"0:4294967297", "0::2", ":3", "3:", "0:-1", "0:1x", "a:b"})
        EXPECT_FALSE(split_integers(bad, ':').has_value()) << bad;
}

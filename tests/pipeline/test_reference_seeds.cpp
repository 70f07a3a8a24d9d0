// The seeds and cache names of edited frames' references: every frame of every sequence its own
// stream, and a name no cache of the shared-seed scheme can hold.
#include "pipeline/reference.h"
#include <gtest/gtest.h>
#include <set>
#include <string>

using namespace lpt::pipeline;

TEST(ReferenceSeeds, EveryEditedFrameHasItsOwnSeed) {
    std::set<uint64_t> seeds;
    const uint64_t ref_seeds[] = {kReferenceSeed, 0, 1, 7};
    for (uint64_t s : ref_seeds) {
        seeds.insert(s);
        for (int frame = 0; frame < 5000; ++frame) seeds.insert(edited_frame_seed(s, frame));
    }
    EXPECT_EQ(seeds.size(), 4u * 5001u);  // no frame's seed repeats another's or a --ref-seed
    // Pinned: a cache named _own_seed holds references of this hash; another hash needs another tag.
    EXPECT_EQ(edited_frame_seed(kReferenceSeed, 20), 0x71d54e0e209f108aULL);
    EXPECT_EQ(edited_frame_seed(kReferenceSeed, 0), 0xd205b47ab6a49baaULL);
}

TEST(ReferenceSeeds, EditedFrameKeysAreMarkedAndDistinct) {
    const std::string k20 = edited_frame_reference_key("edits-light", 1024, 1024, 512, "clip", "frame_0020");
    EXPECT_EQ(k20, std::string("edits-light_1024x1024_512spp_clip_frame_0020") + kEditedFrameSeedTag);
    EXPECT_NE(k20, edited_frame_reference_key("edits-light", 1024, 1024, 512, "clip", "frame_0040"));
    EXPECT_NE(k20, edited_frame_reference_key("edits-camera", 1024, 1024, 512, "clip", "frame_0020"));
    EXPECT_EQ(training_reference_key(1024, 1024, 512, "clip"), "training_1024x1024_512spp_clip");
}

// The background's batched voxel updates against octomap's own updateNode, key by key.
#include "geofusion/background/octree_update.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace geofusion {
namespace {

// Every leaf of a tree: its key, depth and log-odds, in the iterator's order.
std::vector<std::tuple<unsigned, unsigned, unsigned, unsigned, float>> leaves(
    const octomap::OcTree& tree) {
  std::vector<std::tuple<unsigned, unsigned, unsigned, unsigned, float>> out;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const octomap::OcTreeKey k = it.getKey();
    out.emplace_back(k[0], k[1], k[2], it.getDepth(), it->getLogOdds());
  }
  return out;
}

TEST(OctreeUpdate, MortonCodesRoundTripAndSortBySubtree) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> coord(0, 65535);
  for (int i = 0; i < 1000; ++i) {
    const octomap::OcTreeKey key(coord(rng), coord(rng), coord(rng));
    EXPECT_EQ(keyOfMortonCode(mortonCode(key)), key);
  }
  // The code's top three bits are the root's child index of octomap.
  const octomap::OcTreeKey key(40000, 100, 50000);
  EXPECT_EQ(mortonCode(key) >> 45, octomap::computeChildIdx(key, 15));
}

TEST(OctreeUpdate, RadixSortGivesSortedCodesWithoutRepeats) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint64_t> code(0, (std::uint64_t(1) << 48) - 1);
  std::vector<std::uint64_t> codes;
  for (int i = 0; i < 20000; ++i) codes.push_back(code(rng) >> (i % 3 == 0 ? 40 : 0));
  std::vector<std::uint64_t> expected(codes);
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
  sortUnique(&codes);
  EXPECT_EQ(codes, expected);
}

// Rounds of free and occupied updates in a small region (so that voxels reach the clamping
// bounds and nodes are pruned and expanded again), on an empty tree and on a loaded one: every
// leaf, its depth and log-odds equal to those of octomap's updateNode one key at a time.
TEST(OctreeUpdate, GivesOctomapsTreeKeyByKey) {
  for (int seed = 0; seed < 4; ++seed) {
    octomap::OcTree batched(0.02), one_by_one(0.02);
    bool pruned = false;
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> coord(32768 - 4, 32768 + 4);  // 9^3 voxels
    std::bernoulli_distribution occupied(0.4);
    for (int round = 0; round < 40; ++round) {
      const bool hit = occupied(rng);
      std::set<std::uint64_t> picked;
      const int n = round % 5 == 0 ? 3000 : 300;  // some rounds cover (nearly) every voxel
      for (int i = 0; i < n; ++i)
        picked.insert(mortonCode(octomap::OcTreeKey(coord(rng), coord(rng), coord(rng))));
      std::vector<std::uint64_t> codes(picked.begin(), picked.end());
      for (std::uint64_t c : codes) one_by_one.updateNode(keyOfMortonCode(c), hit);
      updateSortedCodes(&batched, codes, hit);
      ASSERT_EQ(batched.size(), one_by_one.size()) << "seed " << seed << " round " << round;
      ASSERT_EQ(leaves(batched), leaves(one_by_one)) << "seed " << seed << " round " << round;
      for (const auto& leaf : leaves(batched)) pruned = pruned || std::get<3>(leaf) < 16;
    }
    EXPECT_TRUE(pruned) << "no round pruned a node: the test does not reach octomap's pruning";
  }
}

}  // namespace
}  // namespace geofusion

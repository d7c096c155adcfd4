#include "geofusion/background/octree_update.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <utility>

namespace geofusion {

namespace {

// The 16 bits of x spread to every third bit (bit i to bit 3i).
std::uint64_t spread(std::uint64_t x) {
  x &= 0xffff;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// The inverse of spread: every third bit (from bit 0) gathered into 16 bits.
std::uint64_t gather(std::uint64_t x) {
  x &= 0x1249249249249249ULL;
  x = (x ^ (x >> 2)) & 0x10c30c30c30c30c3ULL;
  x = (x ^ (x >> 4)) & 0x100f00f00f00f00fULL;
  x = (x ^ (x >> 8)) & 0x1f0000ff0000ffULL;
  x = (x ^ (x >> 16)) & 0x1f00000000ffffULL;
  return x & 0xffff;
}

// updateNodeRecurs of octomap (OccupancyOcTreeBase.hxx) for the keys [lo, hi) of the subtree of
// `node` at `depth`: a pruned node is expanded (or, at the clamping bound of this update, left
// as it is: updateNode's early abort for each of its keys), missing children are created, the
// children with keys updated, then the node pruned or given its children's maximum.
void updateSubtree(octomap::OcTree* tree, octomap::OcTreeNode* node, bool just_created,
                   unsigned depth, const std::uint64_t* lo, const std::uint64_t* hi, float update) {
  const bool at_bound = update >= 0 ? node->getLogOdds() >= tree->getClampingThresMaxLog()
                                    : node->getLogOdds() <= tree->getClampingThresMinLog();
  const unsigned tree_depth = tree->getTreeDepth();
  if (depth == tree_depth) {  // the voxel of the one key left
    if (!at_bound) tree->updateNodeLogOdds(node, update);
    return;
  }
  if (!tree->nodeHasChildren(node) && !just_created) {  // pruned: it is each voxel below it
    if (at_bound) return;
    tree->expandNode(node);
  }
  const unsigned shift = 3 * (tree_depth - 1 - depth);
  for (const std::uint64_t* first = lo; first < hi;) {
    const unsigned pos = static_cast<unsigned>(*first >> shift & 7);
    const std::uint64_t* last = first + 1;
    while (last < hi && static_cast<unsigned>(*last >> shift & 7) == pos) ++last;
    bool created = false;
    if (!tree->nodeChildExists(node, pos)) {
      tree->createNodeChild(node, pos);
      created = true;
    }
    updateSubtree(tree, tree->getNodeChild(node, pos), created, depth + 1, first, last, update);
    first = last;
  }
  if (!tree->pruneNode(node)) node->updateOccupancyChildren();
}

}  // namespace

std::uint64_t mortonCode(const octomap::OcTreeKey& key) {
  return spread(key[0]) | spread(key[1]) << 1 | spread(key[2]) << 2;
}

octomap::OcTreeKey keyOfMortonCode(std::uint64_t code) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(gather(code)),
                            static_cast<octomap::key_type>(gather(code >> 1)),
                            static_cast<octomap::key_type>(gather(code >> 2)));
}

// A least significant digit radix sort, 16 bits a pass: the free-space rays give some 10^5 codes
// an insertion, most of them repeats where the rays converge on the camera, and a comparison sort
// of them cost as much as the voxels' updates.
void sortUnique(std::vector<std::uint64_t>* codes) {
  constexpr int kDigits = 3, kBits = 16;
  constexpr std::size_t kBuckets = std::size_t(1) << kBits;
  std::vector<std::uint32_t> count(kDigits * kBuckets, 0);
  for (std::uint64_t k : *codes)
    for (int d = 0; d < kDigits; ++d) ++count[d * kBuckets + (k >> (kBits * d) & (kBuckets - 1))];
  std::vector<std::uint64_t> sorted(codes->size());
  for (int d = 0; d < kDigits; ++d) {
    std::uint32_t* c = count.data() + d * kBuckets;
    std::uint32_t start = 0;
    for (std::size_t b = 0; b < kBuckets; ++b) start += std::exchange(c[b], start);
    for (std::uint64_t k : *codes) sorted[c[k >> (kBits * d) & (kBuckets - 1)]++] = k;
    codes->swap(sorted);
  }
  codes->erase(std::unique(codes->begin(), codes->end()), codes->end());
}

void updateSortedCodes(octomap::OcTree* tree, const std::vector<std::uint64_t>& codes,
                       bool occupied) {
  if (codes.empty()) return;
  const float update = occupied ? tree->getProbHitLog() : tree->getProbMissLog();
  std::size_t first = 0;
  if (!tree->getRoot()) {  // an empty tree: octomap makes its root (protected) with the first key
    tree->updateNode(keyOfMortonCode(codes[0]), update);
    first = 1;
  }
  if (first < codes.size())
    updateSubtree(tree, tree->getRoot(), false, 0, codes.data() + first,
                  codes.data() + codes.size(), update);
}

}  // namespace geofusion

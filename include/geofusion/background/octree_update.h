// Many voxels of an octomap::OcTree updated at once, as octomap's own updateNode would update
// them one at a time: the background's scan insertion (background_map.cpp) uses it for the free
// and the occupied voxels of each keyframe. octomap's types are only declared here: include
// <octomap/OcTree.h> to call these.
#pragma once

#include <cstdint>
#include <vector>

namespace octomap {
class OcTree;
class OcTreeKey;
}  // namespace octomap

namespace geofusion {

/// The Morton code of a key: bit i of the key's x, y and z at bits 3i, 3i + 1 and 3i + 2, which
/// is the child index octomap takes at each level, so that sorted codes list the voxels of each
/// subtree together.
std::uint64_t mortonCode(const octomap::OcTreeKey& key);
octomap::OcTreeKey keyOfMortonCode(std::uint64_t code);

/// Sorts codes (48 bits) and drops repeats: a radix sort, linear in their number.
void sortUnique(std::vector<std::uint64_t>* codes);

/// octomap's OcTree::updateNode(key, occupied) (not lazy: inner nodes updated and pruned) for the
/// key of each code, `codes` sorted and without repeats (sortUnique): the same tree as the calls
/// one key at a time (the clamping early abort included), each node on the keys' paths visited
/// once instead of once a key.
void updateSortedCodes(octomap::OcTree* tree, const std::vector<std::uint64_t>& codes,
                       bool occupied);

}  // namespace geofusion

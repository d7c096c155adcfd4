// background_agreement: how far two background OctoMaps (.bt, e.g. run_offline --background with
// two configurations) agree, voxel by voxel at the finest resolution: the background benchmark's
// quality figure (docs/BENCHMARK.md, "Live").
//   background_agreement REFERENCE.bt OTHER.bt
// Prints the occupied voxels of each, those in both, intersection over union and the shares of
// each map the other has. Exit code 1 when a file cannot be read or the resolutions differ.
#include "geofusion/background/background_map.h"

#include <cstdio>
#include <memory>
#include <string>

namespace {

bool readMap(const std::string& path, std::unique_ptr<geofusion::BackgroundMap>* map) {
  // The file's resolution is not known before reading it: try the header's.
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) {
    std::fprintf(stderr, "background_agreement: cannot open %s\n", path.c_str());
    return false;
  }
  char line[256];
  double resolution = 0.0;
  while (std::fgets(line, sizeof line, f)) {
    if (std::sscanf(line, "res %lf", &resolution) == 1) break;
  }
  std::fclose(f);
  if (!(resolution > 0)) {
    std::fprintf(stderr, "background_agreement: %s is not an OctoMap .bt file\n", path.c_str());
    return false;
  }
  geofusion::BackgroundMapConfig config;
  config.resolution_m = resolution;
  config.threaded = false;
  *map = std::make_unique<geofusion::BackgroundMap>(config);
  std::string error;
  if (!(*map)->readBinary(path, &error)) {
    std::fprintf(stderr, "background_agreement: %s\n", error.c_str());
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: background_agreement REFERENCE.bt OTHER.bt\n");
    return 2;
  }
  std::unique_ptr<geofusion::BackgroundMap> ref, other;
  if (!readMap(argv[1], &ref) || !readMap(argv[2], &other)) return 1;
  if (ref->config().resolution_m != other->config().resolution_m) {
    std::fprintf(stderr, "background_agreement: the maps' voxels differ (%g and %g m)\n",
                 ref->config().resolution_m, other->config().resolution_m);
    return 1;
  }
  const geofusion::OccupiedAgreement r = geofusion::compareOccupied(*ref, *other);
  std::printf(
      "background_agreement: reference %zu occupied voxels, other %zu, both %zu: IoU %.3f, "
      "%.3f of the reference in the other, %.3f of the other in the reference\n",
      r.a, r.b, r.both, r.iou(), r.ofA(), r.ofB());
  return 0;
}

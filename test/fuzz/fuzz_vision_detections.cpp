#include "fuzz_targets.h"

#include "geofusion/model/object_model.h"
#include "geofusion/ros/vision_detections.h"

#include <geofusion/DetectionArray.h>

#include <cmath>
#include <map>
#include <string>

namespace geofusion {
namespace fuzz {

int fuzzVisionDetections(const std::uint8_t* data, std::size_t size) {
  // Class ids as vision_msgs.class_map's default maps them: the primitives' own ids.
  static const std::map<std::int64_t, ModelClass> class_map = [] {
    std::map<std::int64_t, ModelClass> map;
    std::string error;
    FUZZ_CHECK(makeVisionClassMap("", ModelSet::builtinPrimitives(), &map, &error));
    return map;
  }();
  VisionDetections decoded;
  std::string error;
  const bool ok = decodeVisionDetections(data, size, &decoded, &error);
  FUZZ_CHECK(ok == error.empty());
  if (ok) {
    FUZZ_CHECK(decoded.frames.size() == decoded.detections.size());
    // What was read is written back and read again the same (the encoder is the tests' and the
    // seeds' source of bytes).
    const std::vector<std::uint8_t> again = encodeVisionDetections(decoded);
    VisionDetections round;
    FUZZ_CHECK(decodeVisionDetections(again.data(), again.size(), &round, &error));
    FUZZ_CHECK(round.header.frame_id == decoded.header.frame_id);
    FUZZ_CHECK(round.frames == decoded.frames);
    FUZZ_CHECK(round.detections.size() == decoded.detections.size());
    for (std::size_t i = 0; i < round.detections.size(); ++i) {
      FUZZ_CHECK(round.detections[i].size() == decoded.detections[i].size());
      for (std::size_t k = 0; k < round.detections[i].size(); ++k)
        FUZZ_CHECK(round.detections[i][k].id == decoded.detections[i][k].id);
    }
  }
  // The converter: one message in, either converted (each detection used or counted dropped) or
  // refused with a reason and nothing written.
  VisionDetectionConverter converter(class_map);
  geofusion::DetectionArray out;
  const bool converted =
      converter.convert(kVisionDetectionsType, kVisionDetectionsMd5, data, size, &out, &error);
  FUZZ_CHECK(converted == ok);
  const VisionDetectionConverter::Counts& c = converter.counts();
  if (converted) {
    FUZZ_CHECK(c.messages == 1 && c.rejected == 0);
    FUZZ_CHECK(c.detections == out.detections.size());
    FUZZ_CHECK(c.detections + c.unmapped + c.no_hypothesis == decoded.detections.size());
    for (const auto& d : out.detections) FUZZ_CHECK(!d.class_name.empty());
  } else {
    FUZZ_CHECK(c.messages == 0 && c.rejected == 1 && out.detections.empty() && !error.empty());
  }
  (void)converter.droppedSummary();
  // Another type is refused whatever the bytes.
  FUZZ_CHECK(!converter.convert("geofusion/DetectionArray", "*", data, size, &out, &error));
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzVisionDetections(data, size);
}
#endif

// Detections from vision_msgs/Detection3DArray (the ROS Noetic layout, vision_msgs 0.0.x: each
// detection's `results` hold an int64 class id, a float64 score and a PoseWithCovariance) into the
// package's DetectionArray. No vision_msgs package is needed: the message arrives as bytes (a
// topic_tools::ShapeShifter live, a rosbag::MessageInstance offline), its type and MD5 sum are
// checked against the Noetic layout and its fields are read with roscpp's serialisers. One
// implementation for the adapter nodelet (VisionDetectionsAdapter) and run_offline.
#pragma once

#include <geofusion/DetectionArray.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace geofusion {

class ModelSet;

/// The Noetic vision_msgs/Detection3DArray the converter reads.
constexpr const char* kVisionDetectionsType = "vision_msgs/Detection3DArray";
constexpr const char* kVisionDetectionsMd5 = "05c51d9aea1fb4cfdc8effb94f197b6f";

/// A model-set class a detector's class id stands for.
struct ModelClass {
  std::string name;
  int id = -1;
};

/// Detector class id -> model-set class. `text` is the setting vision_msgs.class_map:
/// "" maps each id to the model-set class with that id (YCB-Video order for ycb_video and the
/// primitives); else comma-separated "id: class_name" pairs ("7: 003_cracker_box, 12: 024_bowl"),
/// and then only the listed ids are used. False, with the reason, for a malformed pair, a
/// repeated id or a class the model set does not have.
bool makeVisionClassMap(const std::string& text, const ModelSet& models,
                        std::map<std::int64_t, ModelClass>* map, std::string* error);

/// One hypothesis of a vision_msgs detection, as the bytes carry it.
struct VisionHypothesis {
  std::int64_t id = 0;
  double score = 0.0;
  geometry_msgs::Pose pose;
};

/// A vision_msgs/Detection3DArray's fields the estimator uses (bounding boxes and source clouds
/// are read past).
struct VisionDetections {
  std_msgs::Header header;
  std::vector<std::vector<VisionHypothesis>> detections;  ///< per detection, its results
  std::vector<std::string> frames;                        ///< per detection, its header frame
};

/// Reads the serialised bytes of a Noetic Detection3DArray. False, with the reason, for bytes
/// that end early or carry a length the message cannot hold.
bool decodeVisionDetections(const std::uint8_t* data, std::size_t size, VisionDetections* out,
                            std::string* error);

/// Serialised bytes of a Noetic Detection3DArray (tests, fuzz seeds): empty boxes and clouds.
std::vector<std::uint8_t> encodeVisionDetections(const VisionDetections& detections);

/// Converts messages one by one and counts what it could not use.
class VisionDetectionConverter {
 public:
  struct Counts {
    std::size_t messages = 0;       ///< converted
    std::size_t rejected = 0;       ///< wrong type or MD5 sum, undecodable bytes
    std::size_t detections = 0;     ///< converted into a Detection
    std::size_t unmapped = 0;       ///< no hypothesis with a mapped class id: dropped
    std::size_t no_hypothesis = 0;  ///< empty `results`: dropped
    std::map<std::int64_t, std::size_t> unmapped_ids;  ///< class id -> times seen unmapped
  };

  explicit VisionDetectionConverter(std::map<std::int64_t, ModelClass> class_map);

  /// The message of type `datatype` with MD5 sum `md5` as a DetectionArray: per detection the
  /// highest-scoring hypothesis whose class id is mapped, its pose in the detection array's frame
  /// (the first detection's frame when the array's is empty). False, with the reason, for another
  /// type or layout, or bytes that do not decode; nothing is then written to `out`.
  bool convert(const std::string& datatype, const std::string& md5, const std::uint8_t* data,
               std::size_t size, geofusion::DetectionArray* out, std::string* error);

  const Counts& counts() const { return counts_; }
  std::size_t classCount() const { return class_map_.size(); }
  /// "3 detections without a mapped class (ids 44 x2, 51 x1)": what was dropped, "" when nothing.
  std::string droppedSummary() const;

 private:
  std::map<std::int64_t, ModelClass> class_map_;
  Counts counts_;
};

}  // namespace geofusion

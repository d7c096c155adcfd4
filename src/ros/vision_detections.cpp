#include "geofusion/ros/vision_detections.h"

#include "geofusion/model/object_model.h"

#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/Vector3.h>
#include <ros/serialization.h>

#include <algorithm>
#include <cctype>
#include <exception>
#include <sstream>

namespace geofusion {
namespace ser = ros::serialization;

namespace {

std::string trimmed(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\n");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\n") - begin + 1);
}

// Bytes a hypothesis takes: int64 id, float64 score, PoseWithCovariance (7 + 36 float64).
constexpr std::size_t kHypothesisBytes = 8 + 8 + (7 + 36) * 8;
// The fewest bytes a Detection3D takes: an empty header, no results, the box, an empty cloud.
constexpr std::size_t kMinDetectionBytes = 16 + 4 + 80 + 42;

// A count of elements that the rest of the stream can hold at `min_bytes` each.
std::uint32_t readCount(ser::IStream& stream, std::size_t min_bytes, const char* what) {
  std::uint32_t n = 0;
  stream.next(n);
  if (static_cast<std::size_t>(n) * min_bytes > stream.getLength()) {
    throw std::runtime_error(std::string("the message says ") + std::to_string(n) + " " + what +
                             " but has only " + std::to_string(stream.getLength()) + " bytes left");
  }
  return n;
}

// A sensor_msgs/PointCloud2 read past (the converter does not use the source cloud).
void skipPointCloud(ser::IStream& stream) {
  std_msgs::Header header;
  ser::deserialize(stream, header);
  std::uint32_t height = 0, width = 0;
  stream.next(height);
  stream.next(width);
  const std::uint32_t fields = readCount(stream, 4 + 4 + 1 + 4, "point fields");
  for (std::uint32_t i = 0; i < fields; ++i) {
    std::string name;
    std::uint32_t offset = 0, count = 0;
    std::uint8_t datatype = 0;
    stream.next(name);
    stream.next(offset);
    stream.next(datatype);
    stream.next(count);
  }
  std::uint8_t is_bigendian = 0, is_dense = 0;
  std::uint32_t point_step = 0, row_step = 0, data = 0;
  stream.next(is_bigendian);
  stream.next(point_step);
  stream.next(row_step);
  stream.next(data);
  stream.advance(data);
  stream.next(is_dense);
}

}  // namespace

bool makeVisionClassMap(const std::string& text, const ModelSet& models,
                        std::map<std::int64_t, ModelClass>* map, std::string* error) {
  map->clear();
  if (trimmed(text).empty()) {
    for (const auto& m : models.models())
      if (m->id >= 0) (*map)[m->id] = ModelClass{m->name, m->id};
    return true;
  }
  std::stringstream pairs(text);
  std::string pair;
  while (std::getline(pairs, pair, ',')) {
    const auto colon = pair.find(':');
    const std::string id_text = trimmed(pair.substr(0, colon));
    const std::string name = colon == std::string::npos ? "" : trimmed(pair.substr(colon + 1));
    std::int64_t id = 0;
    std::size_t used = 0;
    try {
      id = std::stoll(id_text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (name.empty() || id_text.empty() || used != id_text.size()) {
      *error = "vision_msgs.class_map: '" + trimmed(pair) +
               "' is not 'id: class_name' (e.g. \"7: 003_cracker_box, 12: 024_bowl\")";
      return false;
    }
    const ObjectModel* model = models.find(name);
    if (!model) {
      *error = "vision_msgs.class_map: class '" + name + "' (id " + id_text +
               ") is not in the model set '" + models.name() + "'";
      return false;
    }
    if (!map->emplace(id, ModelClass{model->name, model->id}).second) {
      *error = "vision_msgs.class_map: id " + id_text + " is mapped twice";
      return false;
    }
  }
  return true;
}

bool decodeVisionDetections(const std::uint8_t* data, std::size_t size, VisionDetections* out,
                            std::string* error) {
  VisionDetections d;
  try {
    ser::IStream stream(const_cast<std::uint8_t*>(data), static_cast<std::uint32_t>(size));
    ser::deserialize(stream, d.header);
    const std::uint32_t n = readCount(stream, kMinDetectionBytes, "detections");
    for (std::uint32_t i = 0; i < n; ++i) {
      std_msgs::Header header;
      ser::deserialize(stream, header);
      d.frames.push_back(header.frame_id);
      std::vector<VisionHypothesis> results(readCount(stream, kHypothesisBytes, "results"));
      for (auto& h : results) {
        geometry_msgs::PoseWithCovariance pose;
        stream.next(h.id);
        stream.next(h.score);
        ser::deserialize(stream, pose);
        h.pose = pose.pose;
      }
      d.detections.push_back(std::move(results));
      geometry_msgs::Pose box_centre;
      geometry_msgs::Vector3 box_size;
      ser::deserialize(stream, box_centre);
      ser::deserialize(stream, box_size);
      skipPointCloud(stream);
    }
    if (stream.getLength() != 0) {
      throw std::runtime_error(std::to_string(stream.getLength()) +
                               " bytes after the message's end");
    }
  } catch (const std::exception& e) {
    *error = std::string("not a Noetic vision_msgs/Detection3DArray: ") + e.what();
    return false;
  }
  *out = std::move(d);
  return true;
}

std::vector<std::uint8_t> encodeVisionDetections(const VisionDetections& d) {
  geometry_msgs::Pose box_centre;
  box_centre.orientation.w = 1.0;
  const geometry_msgs::Vector3 box_size;
  const std_msgs::Header cloud_header;
  std::size_t size = ser::serializationLength(d.header) + 4;
  for (std::size_t i = 0; i < d.detections.size(); ++i) {
    std_msgs::Header header = d.header;
    if (i < d.frames.size()) header.frame_id = d.frames[i];
    size += ser::serializationLength(header) + 4 + d.detections[i].size() * kHypothesisBytes + 80 +
            (kMinDetectionBytes - 16 - 4 - 80);
  }
  std::vector<std::uint8_t> bytes(size);
  ser::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ser::serialize(stream, d.header);
  stream.next(static_cast<std::uint32_t>(d.detections.size()));
  for (std::size_t i = 0; i < d.detections.size(); ++i) {
    std_msgs::Header header = d.header;
    if (i < d.frames.size()) header.frame_id = d.frames[i];
    ser::serialize(stream, header);
    stream.next(static_cast<std::uint32_t>(d.detections[i].size()));
    for (const auto& h : d.detections[i]) {
      geometry_msgs::PoseWithCovariance pose;
      pose.pose = h.pose;
      stream.next(h.id);
      stream.next(h.score);
      ser::serialize(stream, pose);
    }
    ser::serialize(stream, box_centre);
    ser::serialize(stream, box_size);
    ser::serialize(stream, cloud_header);
    for (int k = 0; k < 3; ++k) stream.next(std::uint32_t{0});  // height, width, no fields
    stream.next(std::uint8_t{0});                               // is_bigendian
    for (int k = 0; k < 3; ++k) stream.next(std::uint32_t{0});  // steps, no data
    stream.next(std::uint8_t{1});                               // is_dense
  }
  return bytes;
}

VisionDetectionConverter::VisionDetectionConverter(std::map<std::int64_t, ModelClass> class_map)
    : class_map_(std::move(class_map)) {}

bool VisionDetectionConverter::convert(const std::string& datatype, const std::string& md5,
                                       const std::uint8_t* data, std::size_t size,
                                       geofusion::DetectionArray* out, std::string* error) {
  if (datatype != kVisionDetectionsType || (md5 != kVisionDetectionsMd5 && md5 != "*")) {
    *error = "expected " + std::string(kVisionDetectionsType) + " of the Noetic layout (MD5 " +
             kVisionDetectionsMd5 + "), got " + datatype + " (MD5 " + md5 + ")";
    ++counts_.rejected;
    return false;
  }
  VisionDetections in;
  if (!decodeVisionDetections(data, size, &in, error)) {
    ++counts_.rejected;
    return false;
  }
  geofusion::DetectionArray msg;
  msg.header = in.header;
  if (msg.header.frame_id.empty() && !in.frames.empty()) msg.header.frame_id = in.frames.front();
  for (const auto& results : in.detections) {
    const VisionHypothesis* best = nullptr;
    const ModelClass* best_class = nullptr;
    for (const auto& h : results) {
      const auto it = class_map_.find(h.id);
      if (it == class_map_.end()) {
        ++counts_.unmapped_ids[h.id];
        continue;
      }
      if (!best || h.score > best->score) {
        best = &h;
        best_class = &it->second;
      }
    }
    if (results.empty()) {
      ++counts_.no_hypothesis;
      continue;
    }
    if (!best) {
      ++counts_.unmapped;
      continue;
    }
    geofusion::Detection d;
    d.class_name = best_class->name;
    d.class_id = best_class->id;
    d.score = static_cast<float>(best->score);
    d.pose = best->pose;
    msg.detections.push_back(std::move(d));
    ++counts_.detections;
  }
  ++counts_.messages;
  *out = std::move(msg);
  return true;
}

std::string VisionDetectionConverter::droppedSummary() const {
  std::ostringstream s;
  if (counts_.unmapped > 0) {
    s << counts_.unmapped << " detections without a mapped class (ids";
    int listed = 0;
    for (const auto& [id, n] : counts_.unmapped_ids) {
      if (listed++ == 8) {
        s << " ...";
        break;
      }
      s << " " << id << " x" << n;
    }
    s << "; map them with vision_msgs.class_map)";
  }
  if (counts_.no_hypothesis > 0)
    s << (s.tellp() > 0 ? ", " : "") << counts_.no_hypothesis << " detections without results";
  if (counts_.rejected > 0)
    s << (s.tellp() > 0 ? ", " : "") << counts_.rejected << " messages rejected";
  return s.str();
}

}  // namespace geofusion

#include "geofusion/physics/scene_export.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "geofusion/model/object_model.h"
#include "geofusion/physics/rigid_world.h"

namespace geofusion {
namespace physics {
namespace {

/// Letters, digits and '_' only (SDF and URDF names, file names).
std::string sanitised(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  return out.empty() ? std::string("unnamed") : out;
}

bool makeFolder(const std::string& path, std::string* error) {
  if (path.empty()) {
    *error = "no export folder given";
    return false;
  }
  for (std::size_t at = path.find('/', 1);; at = path.find('/', at + 1)) {
    const std::string prefix = at == std::string::npos ? path : path.substr(0, at);
    if (::mkdir(prefix.c_str(), 0755) != 0 && errno != EEXIST) {
      *error = "cannot make the folder '" + prefix + "': " + std::strerror(errno);
      return false;
    }
    if (at == std::string::npos) break;
  }
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    *error = "'" + path + "' is not a folder";
    return false;
  }
  return true;
}

std::string absolute(const std::string& path) {
  if (!path.empty() && path[0] == '/') return path;
  char cwd[4096];
  return ::getcwd(cwd, sizeof cwd) ? std::string(cwd) + "/" + path : path;
}

/// "x y z" (metres, 10 significant digits: the round trip keeps the pose to far below 0.1 mm).
std::string triple(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << std::setprecision(10) << v.x() << ' ' << v.y() << ' ' << v.z();
  return s.str();
}

/// Roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll), the convention of SDF and URDF.
Eigen::Vector3d rollPitchYaw(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d ypr = R.eulerAngles(2, 1, 0);
  return Eigen::Vector3d(ypr[2], ypr[1], ypr[0]);
}

std::string sdfPose(const Eigen::Isometry3d& T) {
  return "<pose>" + triple(T.translation()) + " " + triple(rollPitchYaw(T.linear())) + "</pose>";
}

std::string urdfOrigin(const Eigen::Isometry3d& T) {
  return "<origin xyz=\"" + triple(T.translation()) + "\" rpy=\"" +
         triple(rollPitchYaw(T.linear())) + "\"/>";
}

/// One class's meshes on disk: its visual and its convex collision shapes.
struct ClassMeshes {
  std::string visual_uri;
  std::vector<std::string> collision_uris;
  MassProperties mass;
};

bool writeClassMeshes(const ObjectModel& model, const std::vector<TriangleMesh>& shapes,
                      const StabilityConfig& config, const std::string& folder, ClassMeshes* out,
                      SceneExport* result, std::string* error) {
  const std::string base = folder + "/meshes/" + sanitised(model.name);
  auto write = [&](const std::string& path, const TriangleMesh& mesh) {
    if (!saveMesh(path, mesh, "stlb", error)) return false;
    result->mesh_paths.push_back(path);
    return true;
  };
  const TriangleMesh& visual = model.mesh.empty() ? shapes.front() : model.mesh;
  if (!write(base + ".stl", visual)) return false;
  out->visual_uri = "file://" + base + ".stl";
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const std::string path = base + "_collision_" + std::to_string(k) + ".stl";
    if (!write(path, shapes[k])) return false;
    out->collision_uris.push_back("file://" + path);
  }
  out->mass = compoundMassProperties(shapes, config.density_kg_m3);
  return true;
}

std::string sdfSurface(const StabilityConfig& c) {
  std::ostringstream s;
  s << "<surface><friction><ode><mu>" << c.friction << "</mu><mu2>" << c.friction
    << "</mu2></ode><bullet><friction>" << c.friction << "</friction><friction2>" << c.friction
    << "</friction2><rolling_friction>" << c.rolling_friction
    << "</rolling_friction></bullet></friction></surface>";
  return s.str();
}

std::string sdfBody(const std::string& name, const Eigen::Isometry3d& T, const ClassMeshes& m,
                    const StabilityConfig& c) {
  std::ostringstream s;
  s << std::setprecision(10);
  const Eigen::Vector3d& I = m.mass.principal_inertia;
  s << "    <model name=\"" << name << "\">\n      " << sdfPose(T) << "\n"
    << "      <link name=\"link\">\n"
    << "        <inertial>" << sdfPose(m.mass.T_obj_com) << "<mass>" << m.mass.mass_kg
    << "</mass><inertia><ixx>" << I.x() << "</ixx><ixy>0</ixy><ixz>0</ixz><iyy>" << I.y()
    << "</iyy><iyz>0</iyz><izz>" << I.z() << "</izz></inertia></inertial>\n"
    << "        <velocity_decay><linear>" << c.linear_damping << "</linear><angular>"
    << c.angular_damping << "</angular></velocity_decay>\n";
  for (std::size_t k = 0; k < m.collision_uris.size(); ++k)
    s << "        <collision name=\"collision_" << k << "\"><geometry><mesh><uri>"
      << m.collision_uris[k] << "</uri></mesh></geometry>" << sdfSurface(c) << "</collision>\n";
  s << "        <visual name=\"visual\"><geometry><mesh><uri>" << m.visual_uri
    << "</uri></mesh></geometry></visual>\n      </link>\n    </model>\n";
  return s.str();
}

std::string urdfBody(const std::string& name, const Eigen::Isometry3d& T, const ClassMeshes& m) {
  std::ostringstream s;
  s << std::setprecision(10);
  const Eigen::Vector3d& I = m.mass.principal_inertia;
  s << "  <link name=\"" << name << "\">\n    <inertial>" << urdfOrigin(m.mass.T_obj_com)
    << "<mass value=\"" << m.mass.mass_kg << "\"/><inertia ixx=\"" << I.x()
    << "\" ixy=\"0\" ixz=\"0\" iyy=\"" << I.y() << "\" iyz=\"0\" izz=\"" << I.z()
    << "\"/></inertial>\n    <visual><geometry><mesh filename=\"" << m.visual_uri
    << "\"/></geometry></visual>\n";
  for (const std::string& uri : m.collision_uris)
    s << "    <collision><geometry><mesh filename=\"" << uri << "\"/></geometry></collision>\n";
  s << "  </link>\n  <joint name=\"" << name << "_joint\" type=\"floating\"><parent link=\"map\"/>"
    << "<child link=\"" << name << "\"/>" << urdfOrigin(T) << "</joint>\n";
  return s.str();
}

bool writeText(const std::string& path, const std::string& text, std::string* error) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  out.close();
  if (!out) {
    *error = "cannot write '" + path + "': " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace

std::string exportedBodyName(const StabilityBody& body) {
  return (body.model ? sanitised(body.model->name) : std::string("object")) + "_" +
         std::to_string(body.id);
}

bool exportScene(const std::vector<StabilityBody>& bodies, const StabilityPlane* plane,
                 const Eigen::Vector3d& gravity, const StabilityConfig& config,
                 const std::string& folder_given, SceneExport* result, std::string* error) {
  *result = SceneExport();
  result->warnings = validate(config);
  const StabilityConfig defaults;
  const StabilityConfig& c = result->warnings.empty() ? config : defaults;
  if (!result->warnings.empty())
    result->warnings.push_back("physics: the defaults are used instead");
  const std::string folder = absolute(folder_given);
  if (!makeFolder(folder, error) || !makeFolder(folder + "/meshes", error)) return false;

  std::ostringstream sdf_models, urdf_links;
  std::map<std::string, ClassMeshes> written;  // by model name
  std::vector<std::vector<TriangleMesh>> shapes_of;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const StabilityBody& body : bodies) {
    std::vector<TriangleMesh> shapes;
    std::string problem;
    if (!body.model)
      problem = "no model";
    else if (!body.T_world_obj.matrix().allFinite())
      problem = "pose not finite";
    else if ((shapes = bodyShapes(*body.model, c)).empty())
      problem = "no collision shape";
    const std::string name = exportedBodyName(body);
    if (!problem.empty()) {
      result->warnings.push_back("object " + name + ": " + problem + ", not exported");
      continue;
    }
    auto it = written.find(body.model->name);
    if (it == written.end()) {
      ClassMeshes meshes;
      if (!writeClassMeshes(*body.model, shapes, c, folder, &meshes, result, error)) return false;
      it = written.emplace(body.model->name, std::move(meshes)).first;
    }
    sdf_models << sdfBody(name, body.T_world_obj, it->second, c);
    urdf_links << urdfBody(name, body.T_world_obj, it->second);
    Eigen::AlignedBox3d box;
    for (const TriangleMesh& s : shapes)
      for (const Eigen::Vector3f& v : s.vertices) box.extend(body.T_world_obj * v.cast<double>());
    boxes.push_back(box);
    shapes_of.push_back(std::move(shapes));
    poses.push_back(body.T_world_obj);
    ++result->exported;
  }
  const Eigen::Vector3d g = gravityDirection(gravity, plane);
  StabilityPlane support = plane ? *plane : floorUnder(shapes_of, poses, -g);
  if (!plane)
    result->warnings.push_back("no support plane: a floor is put under the lowest object");
  const SupportSlab slab = supportSlab(support, boxes);
  std::ostringstream size;
  size << std::setprecision(10) << 2 * slab.half_extents.x() << ' ' << 2 * slab.half_extents.y()
       << ' ' << 2 * slab.half_extents.z();
  const std::string box = "<geometry><box><size>" + size.str() + "</size></box></geometry>";

  std::ostringstream sdf;
  sdf << "<?xml version=\"1.0\"?>\n<!-- Written by GeoFusion's export_scene (docs/scene_export.md)."
      << " -->\n<sdf version=\"1.6\">\n  <world name=\"geofusion_map\">\n    <gravity>"
      << triple(g * c.gravity_m_s2) << "</gravity>\n    <physics name=\"default\" type=\"ode\">"
      << "<max_step_size>" << c.time_step_s << "</max_step_size></physics>\n"
      << "    <model name=\"support_plane\">\n      <static>true</static>\n      "
      << sdfPose(slab.T_world_box) << "\n      <link name=\"link\"><collision name=\"collision\">"
      << box << sdfSurface(c) << "</collision><visual name=\"visual\">" << box
      << "</visual></link>\n    </model>\n"
      << sdf_models.str() << "  </world>\n</sdf>\n";
  std::ostringstream urdf;
  urdf
      << "<?xml version=\"1.0\"?>\n<!-- Written by GeoFusion's export_scene (docs/scene_export.md)."
      << " -->\n<robot name=\"geofusion_map\">\n  <link name=\"map\"/>\n"
      << "  <link name=\"support_plane\"><visual>" << box << "</visual><collision>" << box
      << "</collision></link>\n  <joint name=\"support_plane_joint\" type=\"fixed\">"
      << "<parent link=\"map\"/><child link=\"support_plane\"/>" << urdfOrigin(slab.T_world_box)
      << "</joint>\n"
      << urdf_links.str() << "</robot>\n";
  result->sdf_path = folder + "/scene.sdf";
  result->urdf_path = folder + "/scene.urdf";
  return writeText(result->sdf_path, sdf.str(), error) &&
         writeText(result->urdf_path, urdf.str(), error);
}

}  // namespace physics
}  // namespace geofusion

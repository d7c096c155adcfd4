# Library differences between the platforms GeoFusion builds on (README "Supported platforms",
# docs/platforms.md), each handled here once, after the find_package calls of CMakeLists.txt:
#   Ceres 1.14 (Ubuntu 20.04, Debian 11)  exports `ceres`, not `Ceres::ceres` (new in 2.0)
#   assimp 5.0.1 (Ubuntu 20.04, Debian 11) points assimp::assimp's include folder at a path that
#                                          does not exist (<prefix>/lib/include; assimp issue 4474)
#   meshoptimizer                          none on Ubuntu 20.04; 0.15 on Debian 11 (no
#                                          meshopt_simplifyScale, no error output)
#   pybind11 2.4 (Ubuntu 20.04)            no pybind11_extension()
#   qhull                                  Qhull::qhull_r from its CMake config where there is one,
#                                          else the library and header found by name
include(CheckCXXSourceCompiles)

if(NOT TARGET Qhull::qhull_r)
  find_path(GEOFUSION_QHULL_INCLUDE_DIR libqhull_r/qhull_ra.h)
  find_library(GEOFUSION_QHULL_R_LIBRARY NAMES qhull_r)
  if(NOT GEOFUSION_QHULL_INCLUDE_DIR OR NOT GEOFUSION_QHULL_R_LIBRARY)
    message(FATAL_ERROR "geofusion: qhull's reentrant library (libqhull_r, package libqhull-dev) not found")
  endif()
  add_library(Qhull::qhull_r INTERFACE IMPORTED)
  set_target_properties(Qhull::qhull_r PROPERTIES INTERFACE_LINK_LIBRARIES "${GEOFUSION_QHULL_R_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${GEOFUSION_QHULL_INCLUDE_DIR}")
endif()

# Ceres: one target name for every version.
if(NOT TARGET Ceres::ceres)
  if(TARGET ceres)
    add_library(Ceres::ceres INTERFACE IMPORTED)
    set_target_properties(Ceres::ceres PROPERTIES INTERFACE_LINK_LIBRARIES ceres)
  else()
    message(FATAL_ERROR "geofusion: Ceres found, but neither Ceres::ceres nor ceres is a target")
  endif()
endif()
message(STATUS "geofusion: Ceres ${Ceres_VERSION}")

# assimp: drop include folders that do not exist, and make sure the real one is there.
if(TARGET assimp::assimp)
  get_target_property(_gf_assimp_includes assimp::assimp INTERFACE_INCLUDE_DIRECTORIES)
  if(_gf_assimp_includes)
    set(_gf_kept)
    foreach(_gf_dir ${_gf_assimp_includes})
      if(EXISTS "${_gf_dir}")
        list(APPEND _gf_kept "${_gf_dir}")
      else()
        message(STATUS "geofusion: assimp's config names a missing include folder ${_gf_dir}: dropped")
      endif()
    endforeach()
    find_path(_GF_ASSIMP_HEADER_DIR assimp/scene.h HINTS ${ASSIMP_INCLUDE_DIRS})
    if(_GF_ASSIMP_HEADER_DIR)
      list(APPEND _gf_kept "${_GF_ASSIMP_HEADER_DIR}")
    endif()
    list(REMOVE_DUPLICATES _gf_kept)
    set_target_properties(assimp::assimp PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_gf_kept}")
  endif()
elseif(ASSIMP_LIBRARIES)
  add_library(assimp::assimp INTERFACE IMPORTED)
  set_target_properties(assimp::assimp PROPERTIES INTERFACE_LINK_LIBRARIES "${ASSIMP_LIBRARIES}"
    INTERFACE_INCLUDE_DIRECTORIES "${ASSIMP_INCLUDE_DIRS}")
else()
  message(FATAL_ERROR "geofusion: assimp found, but no assimp::assimp target nor ASSIMP_LIBRARIES")
endif()

# meshoptimizer: optional. Without it meshes are rendered whole (docs/platforms.md: the cost).
option(GEOFUSION_WITH_MESHOPTIMIZER "Simplify the models' render meshes with meshoptimizer" ON)
set(GEOFUSION_HAVE_MESHOPTIMIZER 0)
set(GEOFUSION_MESHOPT_ERROR_OUTPUT 0)
if(GEOFUSION_WITH_MESHOPTIMIZER)
  find_package(meshoptimizer QUIET)
  if(meshoptimizer_FOUND)
    set(GEOFUSION_HAVE_MESHOPTIMIZER 1)
    set(CMAKE_REQUIRED_LIBRARIES meshoptimizer::meshoptimizer)
    check_cxx_source_compiles("
      #include <meshoptimizer.h>
      int main() {
        float p[9] = {0}; unsigned int i[3] = {0, 1, 2}, o[3]; float e = 0.f;
        float s = meshopt_simplifyScale(p, 3, 12);
        return int(meshopt_simplify(o, i, 3, p, 3, 12, 3, 0.01f / s, 0, &e));
      }" GEOFUSION_MESHOPT_HAS_ERROR_OUTPUT)
    unset(CMAKE_REQUIRED_LIBRARIES)
    if(GEOFUSION_MESHOPT_HAS_ERROR_OUTPUT)
      set(GEOFUSION_MESHOPT_ERROR_OUTPUT 1)
    endif()
  endif()
endif()
message(STATUS "geofusion: meshoptimizer ${meshoptimizer_VERSION} used: ${GEOFUSION_HAVE_MESHOPTIMIZER}"
               " (error output: ${GEOFUSION_MESHOPT_ERROR_OUTPUT})")

# pybind11 2.4: the module's file name set by hand as pybind11_extension() does since 2.6.
function(geofusion_python_extension target)
  if(COMMAND pybind11_extension)
    pybind11_extension(${target})
  else()
    set_target_properties(${target} PROPERTIES PREFIX "${PYTHON_MODULE_PREFIX}"
      SUFFIX "${PYTHON_MODULE_EXTENSION}")
  endif()
endfunction()

# The Qt the rviz panel links: the one rviz itself was built with (rviz-extras.cmake's
# rviz_QT_VERSION: 5 on Noetic and Debian 11/12, 6 on Debian 13). A plugin on another Qt than
# rviz's loads a second QtWidgets and fails ("Must construct a QApplication before a QWidget").
# Call after find_package(rviz); sets GEOFUSION_QT_WIDGETS to the target to link.
macro(geofusion_find_rviz_qt)
  set(_geofusion_qt_major 5)
  if(rviz_QT_VERSION)
    string(REGEX MATCH "^[0-9]+" _geofusion_qt_major "${rviz_QT_VERSION}")
  endif()
  find_package(Qt${_geofusion_qt_major} REQUIRED COMPONENTS Widgets)
  set(GEOFUSION_QT_WIDGETS Qt${_geofusion_qt_major}::Widgets)
  message(STATUS "geofusion: rviz ${rviz_VERSION} built with Qt ${rviz_QT_VERSION}: the panel links ${GEOFUSION_QT_WIDGETS}")
endmacro()

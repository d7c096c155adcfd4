#include "geofusion/core/optimization.h"

#include "geofusion/core/association.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>

#include <array>
#include <cmath>
#include <memory>

namespace geofusion {
namespace {

// A pose as one Ceres parameter block: quaternion (Eigen order x, y, z, w), then translation;
// on the product of the unit-quaternion and Euclidean manifolds.
using PoseManifold =
    ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>;
struct PoseBlock {
  std::array<double, 7> x{};
  double* data() { return x.data(); }
  void set(const Eigen::Isometry3d& T) {
    Eigen::Quaterniond q(T.linear());
    q.normalize();
    x = {q.x(), q.y(), q.z(), q.w(), T.translation().x(), T.translation().y(), T.translation().z()};
  }
  Eigen::Isometry3d get() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(x[3], x[0], x[1], x[2]).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(x[4], x[5], x[6]);
    return T;
  }
};

ceres::LossFunction* makeLoss(const RobustLoss& loss) {
  if (loss.type == "huber") return new ceres::HuberLoss(loss.scale);
  if (loss.type == "cauchy") return new ceres::CauchyLoss(loss.scale);
  return nullptr;
}

template <typename T>
Eigen::Matrix<T, 3, 1> rotationResidual(const Eigen::Quaternion<T>& q_err) {
  // 2 vec(q) ~ rotation vector for small angles; the sign picks the short way round.
  Eigen::Matrix<T, 3, 1> v = T(2) * q_err.vec();
  if (q_err.w() < T(0)) v = -v;
  return v;
}

// Relative pose a^-1 b against a measured one: the odometry factor (a = x_{t-1}, b = x_t), the
// object measurement factor (a = x_t, b = o_j) and, with a fixed identity a, the object prior.
// Rotation residual in the measured frame; a continuous symmetry axis (model frame) is left free.
struct RelativePoseError {
  RelativePoseError(const Eigen::Isometry3d& measured, double w_p, double w_q, bool free_axis,
                    const Eigen::Vector3d& axis)
      : q_meas(measured.linear()),
        t_meas(measured.translation()),
        w_p(w_p),
        w_q(w_q),
        free_axis(free_axis),
        axis(axis.normalized()) {
    q_meas.normalize();
  }

  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> Qa(a), Qb(b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> Ta(a + 4), Tb(b + 4);
    const Eigen::Quaternion<T> q_pred = Qa.conjugate() * Qb;
    const Eigen::Matrix<T, 3, 1> t_pred = Qa.conjugate() * (Tb - Ta);
    const Eigen::Matrix<T, 3, 1> dt = t_pred - t_meas.cast<T>();
    Eigen::Matrix<T, 3, 1> v = rotationResidual<T>(q_meas.cast<T>().conjugate() * q_pred);
    if (free_axis) v -= axis.cast<T>() * axis.cast<T>().dot(v);
    for (int i = 0; i < 3; ++i) r[i] = T(w_p) * dt[i], r[3 + i] = T(w_q) * v[i];
    return true;
  }

  Eigen::Quaterniond q_meas;
  Eigen::Vector3d t_meas;
  double w_p, w_q;
  bool free_axis;
  Eigen::Vector3d axis;
};

ceres::Solver::Summary solveQuietly(
    ceres::Problem* problem, ceres::LinearSolverType solver, int max_iterations,
    std::shared_ptr<ceres::ParameterBlockOrdering> ordering = nullptr) {
  ceres::Solver::Options options;
  if (ordering) options.linear_solver_ordering = ordering;
  options.linear_solver_type = solver;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  return summary;
}

bool freeAxis(const ObjectModel* model, Eigen::Vector3d* axis) {
  if (model && model->symmetry.type == Symmetry::Type::kContinuous) {
    *axis = model->symmetry.axis;
    return true;
  }
  *axis = Eigen::Vector3d::UnitZ();
  return false;
}

}  // namespace

StageOneSummary optimizeStageOne(std::vector<Eigen::Isometry3d>* T_map_cam,
                                 const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                 std::vector<Eigen::Isometry3d>* T_map_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<StageOneMeasurement>& measurements,
                                 const StageOneConfig& config) {
  StageOneSummary summary;
  const std::size_t n_kf = T_map_cam->size(), n_obj = T_map_obj->size();
  if (n_kf == 0 || T_odom_cam.size() != n_kf || models.size() != n_obj) {
    summary.message = "inconsistent sizes";
    return summary;
  }
  std::vector<PoseBlock> cams(n_kf), objs(n_obj);
  for (std::size_t i = 0; i < n_kf; ++i) cams[i].set((*T_map_cam)[i]);
  for (std::size_t j = 0; j < n_obj; ++j) objs[j].set((*T_map_obj)[j]);

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  PoseManifold manifold;
  auto add_pose = [&](PoseBlock& b) { problem.AddParameterBlock(b.data(), 7, &manifold); };
  for (auto& c : cams) add_pose(c);
  const double wp_odo = 1.0 / config.odometry_sigma_position_m,
               wq_odo = 1.0 / config.odometry_sigma_rotation_rad;
  for (std::size_t i = 1; i < n_kf; ++i) {
    const Eigen::Isometry3d rel = T_odom_cam[i - 1].inverse() * T_odom_cam[i];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(
        new RelativePoseError(rel, wp_odo, wq_odo, false, Eigen::Vector3d::UnitZ()));
    problem.AddResidualBlock(cost, makeLoss(config.odometry_loss), cams[i - 1].data(),
                             cams[i].data());
  }
  std::vector<char> used(n_obj, 0);
  const double wp = 1.0 / config.measurement_sigma_position_m,
               wq = 1.0 / config.measurement_sigma_rotation_rad;
  for (const StageOneMeasurement& m : measurements) {
    if (m.keyframe < 0 || m.keyframe >= static_cast<int>(n_kf) || m.object < 0 ||
        m.object >= static_cast<int>(n_obj) || !(m.weight > 0.0)) {
      continue;
    }
    PoseBlock &cam = cams[static_cast<std::size_t>(m.keyframe)],
              &obj = objs[static_cast<std::size_t>(m.object)];
    if (!used[static_cast<std::size_t>(m.object)]) {
      add_pose(obj);
      used[static_cast<std::size_t>(m.object)] = 1;
    }
    const ObjectModel* model = models[static_cast<std::size_t>(m.object)];
    Eigen::Isometry3d z = m.T_cam_obj;
    if (model) {
      // Discrete symmetry: the equivalent closest to the current estimate.
      const Eigen::Matrix3d R_pred = (cam.get().inverse() * obj.get()).linear();
      z.linear() = closestSymmetricEquivalent(model->symmetry, R_pred, z.linear());
    }
    Eigen::Vector3d axis;
    const bool free = freeAxis(model, &axis);
    const double s = std::sqrt(m.weight);
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(
        new RelativePoseError(z, s * wp, s * wq, free, axis));
    problem.AddResidualBlock(cost, makeLoss(config.measurement_loss), cam.data(), obj.data());
  }
  // The first camera fixes the gauge; outside the window the cameras stay where they are.
  const std::size_t first_free =
      config.window_keyframes > 0 && n_kf > static_cast<std::size_t>(config.window_keyframes)
          ? n_kf - static_cast<std::size_t>(config.window_keyframes)
          : 1;
  for (std::size_t i = 0; i < std::max<std::size_t>(1, first_free); ++i) {
    problem.SetParameterBlockConstant(cams[i].data());
  }

  // Schur complement: the objects (no factor joins two of them) are eliminated first, the free
  // cameras of the window remain as one small dense system.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (std::size_t j = 0; j < n_obj; ++j) {
    if (!used[j]) continue;
    ordering->AddElementToGroup(objs[j].data(), 0);
  }
  for (auto& c : cams) ordering->AddElementToGroup(c.data(), 1);
  const ceres::Solver::Summary s =
      solveQuietly(&problem, ceres::DENSE_SCHUR, config.max_iterations, ordering);
  summary.solved = s.IsSolutionUsable();
  summary.iterations = static_cast<int>(s.iterations.size());
  summary.initial_cost = s.initial_cost;
  summary.final_cost = s.final_cost;
  summary.message = s.BriefReport();
  if (!summary.solved) return summary;
  for (std::size_t i = 0; i < n_kf; ++i) (*T_map_cam)[i] = cams[i].get();
  for (std::size_t j = 0; j < n_obj; ++j)
    if (used[j]) (*T_map_obj)[j] = objs[j].get();
  return summary;
}

// ---------------------------------------------------------------------------------------------
// Stage II.
namespace {

template <typename T>
struct Posed {
  Eigen::Quaternion<T> q;
  Eigen::Matrix<T, 3, 1> t;
  Eigen::Matrix<T, 3, 1> point(const Eigen::Vector3d& p) const { return q * p.cast<T>() + t; }
  Eigen::Matrix<T, 3, 1> dir(const Eigen::Vector3d& d) const { return q * d.cast<T>(); }
};

template <typename T>
Posed<T> posed(const T* q, const T* t) {
  return {Eigen::Quaternion<T>(q[3], q[0], q[1], q[2]), Eigen::Matrix<T, 3, 1>(t[0], t[1], t[2])};
}

// The paper's contact costs. P2P: omega_q |N_u . N_v + 1| + omega_p |N_u . (C_v - C_u)|, with the
// direction term as the vector N_u + N_v (zero at the same minimum, but its gradient does not
// vanish there). P2C: omega_q |N_p . N_c| + omega_p |N_p . (C_c - C_p) - r|. C2C: omega_p (axis
// distance - (r_u + r_v)).
struct ContactError {
  ContactType type;
  // Features in their models' frames; for P2C `a` is the plane and `b` the curve.
  Eigen::Vector3d c_a, n_a, c_b, n_b;
  double r_a = 0.0, r_b = 0.0;
  double w_p, w_q;

  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    const Posed<T> A = posed(a, a + 4), B = posed(b, b + 4);
    const Eigen::Matrix<T, 3, 1> Ca = A.point(c_a), Na = A.dir(n_a), Cb = B.point(c_b),
                                 Nb = B.dir(n_b);
    const Eigen::Matrix<T, 3, 1> d = Cb - Ca;
    switch (type) {
      case ContactType::kPlanePlane: {
        const Eigen::Matrix<T, 3, 1> s = Na + Nb;
        r[0] = T(w_q) * s[0], r[1] = T(w_q) * s[1], r[2] = T(w_q) * s[2];
        r[3] = T(w_p) * Na.dot(d);
        break;
      }
      case ContactType::kPlaneCurve:
        r[0] = T(w_q) * Na.dot(Nb);
        r[1] = T(w_p) * (Na.dot(d) - T(r_b));
        r[2] = r[3] = T(0);
        break;
      case ContactType::kCurveCurve: {
        const Eigen::Matrix<T, 3, 1> c = Na.cross(Nb);
        const T cn2 = c.squaredNorm();
        T dist;
        if (cn2 > T(0.01)) {  // skew axes (as contacts.cpp decides): along the common normal
          const T proj = c.dot(d);
          dist = sqrt(proj * proj / cn2 + T(1e-12));
        } else {  // parallel axes: distance between the lines
          const Eigen::Matrix<T, 3, 1> perp = d - Na * Na.dot(d);
          dist = sqrt(perp.squaredNorm() + T(1e-12));
        }
        r[0] = T(w_p) * (dist - T(r_a + r_b));
        r[1] = r[2] = r[3] = T(0);
        break;
      }
    }
    return true;
  }
};

}  // namespace

StageTwoSummary optimizeStageTwo(std::vector<Eigen::Isometry3d>* T_world_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<Eigen::Isometry3d>& priors,
                                 const std::vector<FeatureContact>& contacts,
                                 const PosedModel* ground, const StageTwoConfig& config) {
  StageTwoSummary summary;
  const std::size_t n = T_world_obj->size();
  if (models.size() != n || priors.size() != n) return summary;
  std::vector<PoseBlock> objs(n);
  for (std::size_t i = 0; i < n; ++i) objs[i].set((*T_world_obj)[i]);
  PoseBlock ground_block, identity;
  identity.set(Eigen::Isometry3d::Identity());
  if (ground) ground_block.set(ground->T_world_obj);

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  PoseManifold manifold;
  std::vector<char> in_problem(n, 0);
  auto block = [&](int index) -> PoseBlock* {
    if (index < 0) return ground ? &ground_block : nullptr;
    return index < static_cast<int>(n) ? &objs[static_cast<std::size_t>(index)] : nullptr;
  };
  auto model_of = [&](int index) -> const ObjectModel* {
    if (index < 0) return ground ? ground->model : nullptr;
    return models[static_cast<std::size_t>(index)];
  };
  auto add_object = [&](int index) {
    if (index < 0 || in_problem[static_cast<std::size_t>(index)]) return;
    PoseBlock& b = objs[static_cast<std::size_t>(index)];
    problem.AddParameterBlock(b.data(), 7, &manifold);
    in_problem[static_cast<std::size_t>(index)] = 1;
    Eigen::Vector3d axis;
    const bool free = freeAxis(models[static_cast<std::size_t>(index)], &axis);
    auto* prior = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(new RelativePoseError(
        priors[static_cast<std::size_t>(index)], 1.0 / config.prior_sigma_position_m,
        1.0 / config.prior_sigma_rotation_rad, free, axis));
    problem.AddResidualBlock(prior, nullptr, identity.data(), b.data());
  };
  bool uses_constants = false;
  for (const FeatureContact& c : contacts) {
    PoseBlock *a = block(c.object_a), *b = block(c.object_b);
    const ObjectModel *ma = model_of(c.object_a), *mb = model_of(c.object_b);
    if (!a || !b || !ma || !mb || a == b) continue;
    ContactError e;
    e.type = c.type;
    e.w_p = 1.0 / config.contact_sigma_distance_m;
    e.w_q = 1.0 / config.contact_sigma_direction;
    auto set_feature = [&](const ObjectModel& m, const FeatureRef& f, Eigen::Vector3d* centre,
                           Eigen::Vector3d* dir, double* radius) {
      if (f.plane) {
        if (f.index < 0 || f.index >= static_cast<int>(m.features.planes.size())) return false;
        const PlaneFeature& p = m.features.planes[static_cast<std::size_t>(f.index)];
        *centre = p.center, *dir = p.normal, *radius = 0.0;
      } else {
        if (f.index < 0 || f.index >= static_cast<int>(m.features.curves.size())) return false;
        const CurvedFeature& cv = m.features.curves[static_cast<std::size_t>(f.index)];
        *centre = cv.center, *dir = cv.axis, *radius = cv.radius_m;
      }
      return true;
    };
    bool swap = c.type == ContactType::kPlaneCurve && !c.feature_a.plane;
    const FeatureRef& fa = swap ? c.feature_b : c.feature_a;
    const FeatureRef& fb = swap ? c.feature_a : c.feature_b;
    if (!set_feature(swap ? *mb : *ma, fa, &e.c_a, &e.n_a, &e.r_a) ||
        !set_feature(swap ? *ma : *mb, fb, &e.c_b, &e.n_b, &e.r_b)) {
      continue;
    }
    if (swap) std::swap(a, b);
    add_object(swap ? c.object_b : c.object_a);
    add_object(swap ? c.object_a : c.object_b);
    if (a == &ground_block || b == &ground_block) uses_constants = true;
    if ((a == &ground_block || b == &ground_block) &&
        !problem.HasParameterBlock(ground_block.data())) {
      problem.AddParameterBlock(ground_block.data(), 7, &manifold);
    }
    auto* cost = new ceres::AutoDiffCostFunction<ContactError, 4, 7, 7>(new ContactError(e));
    problem.AddResidualBlock(cost, makeLoss(config.contact_loss), a->data(), b->data());
    ++summary.contacts;
  }
  if (summary.contacts == 0) {
    summary.solved = true;  // nothing to refine: the priors are the answer
    for (std::size_t i = 0; i < n; ++i) (*T_world_obj)[i] = priors[i];
    return summary;
  }
  problem.SetParameterBlockConstant(identity.data());
  if (uses_constants) {
    problem.SetParameterBlockConstant(ground_block.data());
  }
  const ceres::Solver::Summary s =
      solveQuietly(&problem, ceres::SPARSE_NORMAL_CHOLESKY, config.max_iterations);
  summary.solved = s.IsSolutionUsable();
  summary.initial_cost = s.initial_cost;
  summary.final_cost = s.final_cost;
  for (std::size_t i = 0; i < n; ++i) {
    (*T_world_obj)[i] = (summary.solved && in_problem[i]) ? objs[i].get() : priors[i];
  }
  return summary;
}

}  // namespace geofusion

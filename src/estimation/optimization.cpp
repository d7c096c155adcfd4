#include "geofusion/estimation/optimization.h"

#include "geofusion/estimation/depth_refinement.h"

#include "geofusion/estimation/association.h"
#include "geofusion/estimation/factors/contact_factor.h"
#include "geofusion/estimation/factors/pose_block.h"
#include "geofusion/estimation/factors/relative_pose_factor.h"
#include "geofusion/estimation/factors/separation_factor.h"
#include "geofusion/estimation/symmetry_axis.h"

#include "geofusion/common/ceres_compat.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

namespace geofusion {
namespace {

// The pose blocks (factors/pose_block.h) live on the product of the unit-quaternion and
// Euclidean manifolds (common/ceres_compat.h: Manifold or LocalParameterization by Ceres version).
using ceres_compat::PoseManifold;

ceres::LossFunction* makeLoss(const RobustLoss& loss) {
  if (loss.type == "huber") return new ceres::HuberLoss(loss.scale);
  if (loss.type == "cauchy") return new ceres::CauchyLoss(loss.scale);
  return nullptr;
}

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

// The outcome of a Ceres solve (SolveStatus).
SolveStatus statusOf(const ceres::Solver::Summary& s) {
  if (!s.IsSolutionUsable()) return SolveStatus::kFailed;
  if (s.final_cost > s.initial_cost) return SolveStatus::kCostIncreased;
  if (s.termination_type == ceres::NO_CONVERGENCE) return SolveStatus::kIterationLimit;
  return SolveStatus::kConverged;
}

}  // namespace

const char* toString(SolveStatus status) {
  switch (status) {
    case SolveStatus::kNotRun: return "not_run";
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kIterationLimit: return "iteration_limit";
    case SolveStatus::kNothingToSolve: return "nothing_to_solve";
    case SolveStatus::kFailed: return "failed";
    case SolveStatus::kCostIncreased: return "cost_increased";
    default: return "bad_input";
  }
}

bool parseSolveStatus(const std::string& name, SolveStatus* status) {
  for (SolveStatus s : {SolveStatus::kNotRun, SolveStatus::kConverged, SolveStatus::kIterationLimit,
                        SolveStatus::kNothingToSolve, SolveStatus::kFailed,
                        SolveStatus::kCostIncreased, SolveStatus::kBadInput}) {
    if (name == toString(s)) {
      *status = s;
      return true;
    }
  }
  return false;
}

bool usable(SolveStatus status) {
  return status == SolveStatus::kConverged || status == SolveStatus::kIterationLimit ||
         status == SolveStatus::kNothingToSolve;
}

namespace {

bool validMeasurement(const StageOneMeasurement& m, std::size_t n_kf, std::size_t n_obj) {
  return m.keyframe >= 0 && m.keyframe < static_cast<int>(n_kf) && m.object >= 0 &&
         m.object < static_cast<int>(n_obj);
}

// Square-root information of a measurement's translation in its camera frame (weight 1).
Eigen::Matrix3d measurementSqrtInformation(const StageOneMeasurement& m,
                                           const StageOneConfig& config) {
  if (m.ray_sigma_m > 0)
    return rayAlignedSqrtInformation(m.T_cam_obj.translation(), m.ray_sigma_m,
                                     config.measurement_sigma_position_m);
  return Eigen::Matrix3d::Identity() / config.measurement_sigma_position_m;
}

// The object measurement factor of m between the camera and object poses given (a discrete
// symmetry's equivalent closest to them; a continuous axis left free; a refined measurement tight
// along its ray), its weights scaled by `s`.
RelativePoseFactor measurementFactor(const StageOneMeasurement& m, const Eigen::Isometry3d& T_cam,
                                     const Eigen::Isometry3d& T_obj, const ObjectModel* model,
                                     const StageOneConfig& config, double s) {
  Eigen::Isometry3d z = m.T_cam_obj;
  if (model) {
    const Eigen::Matrix3d R_pred = (T_cam.inverse() * T_obj).linear();
    z.linear() = closestSymmetricEquivalent(model->symmetry, R_pred, z.linear());
  }
  Eigen::Vector3d axis;
  const bool free = freeAxis(model, &axis);
  return RelativePoseFactor(z, s * measurementSqrtInformation(m, config),
                            s / config.measurement_sigma_rotation_rad, free, axis);
}

RelativePoseFactor odometryFactor(const Eigen::Isometry3d& T_odom_a,
                                  const Eigen::Isometry3d& T_odom_b, const StageOneConfig& config) {
  return RelativePoseFactor(T_odom_a.inverse() * T_odom_b, 1.0 / config.odometry_sigma_position_m,
                            1.0 / config.odometry_sigma_rotation_rad, false,
                            Eigen::Vector3d::UnitZ());
}

// Squared norm of a factor's whitened residual at two poses.
double squaredResidual(const RelativePoseFactor& f, const Eigen::Isometry3d& a,
                       const Eigen::Isometry3d& b) {
  const PoseBlock pa = PoseBlock::of(a), pb = PoseBlock::of(b);
  double r[RelativePoseFactor::kResiduals];
  f(pa.data(), pb.data(), r);
  double sum = 0.0;
  for (double x : r) sum += x * x;
  return sum;
}

}  // namespace

Eigen::Matrix3d alignToReference(const Symmetry& symmetry, const Eigen::Matrix3d& R_reference,
                                 const Eigen::Matrix3d& R_measured) {
  if (symmetry.type != Symmetry::Type::kContinuous)
    return closestSymmetricEquivalent(symmetry, R_reference, R_measured);
  const Eigen::Vector3d a = symmetry.axis.normalized();
  return R_measured *
         Eigen::AngleAxisd(axialOffset(a, R_reference, R_measured), a).toRotationMatrix();
}

void FoldedMeasurements::add(const Eigen::Isometry3d& T_map_cam, const StageOneMeasurement& m,
                             const ObjectModel* model, const Eigen::Matrix3d& R_reference,
                             const StageOneConfig& config) {
  ++count_;
  if (!(m.weight > 0.0)) return;
  const Eigen::Isometry3d T_map_meas = T_map_cam * m.T_cam_obj;
  // Translation: W (R_cam' (t - t_cam) - z) = W R_cam' (t - t_meas), information
  // w R_cam W'W R_cam' about t_meas.
  const Eigen::Matrix3d W = measurementSqrtInformation(m, config) * T_map_cam.linear().transpose();
  const Eigen::Matrix3d information = m.weight * W.transpose() * W;
  translation_information_ += information;
  information_vector_ += information * T_map_meas.translation();
  const Eigen::Matrix3d R =
      model ? alignToReference(model->symmetry, R_reference, T_map_meas.linear())
            : T_map_meas.linear();
  const double w_rotation =
      m.weight / (config.measurement_sigma_rotation_rad * config.measurement_sigma_rotation_rad);
  rotation_sum_ += w_rotation * R;
  rotation_information_ += w_rotation;
}

void FoldedMeasurements::add(const FoldedMeasurements& other, const ObjectModel* model,
                             const Eigen::Matrix3d& R_reference) {
  if (other.empty()) {
    count_ += other.count_;
    return;
  }
  const Eigen::Matrix3d R_other = other.mean().linear();
  const Eigen::Matrix3d R =
      model ? alignToReference(model->symmetry, R_reference, R_other) : R_other;
  translation_information_ += other.translation_information_;
  information_vector_ += other.information_vector_;
  rotation_sum_ += other.rotation_information_ * R;
  rotation_information_ += other.rotation_information_;
  count_ += other.count_;
}

FoldedMeasurements FoldedMeasurements::fromPrior(const Eigen::Isometry3d& mean,
                                                 const Eigen::Matrix3d& translation_information,
                                                 double rotation_information, int count) {
  FoldedMeasurements f;
  f.count_ = std::max(0, count);
  const Eigen::Matrix3d I = 0.5 * (translation_information + translation_information.transpose());
  const bool usable =
      mean.matrix().allFinite() && I.allFinite() && std::isfinite(rotation_information) &&
      rotation_information > 0.0 &&
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues().minCoeff() > 0.0;
  if (!usable) return f;
  f.translation_information_ = I;
  f.information_vector_ = I * mean.translation();
  f.rotation_sum_ = rotation_information * mean.linear();
  f.rotation_information_ = rotation_information;
  return f;
}

Eigen::Isometry3d FoldedMeasurements::mean() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (empty()) return T;
  // Chordal mean: the rotation nearest the weighted sum (SVD projection onto SO(3)).
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation_sum_,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  T.linear() = svd.matrixU() * D * svd.matrixV().transpose();
  T.translation() = translation_information_.ldlt().solve(information_vector_);
  return T;
}

Eigen::Matrix3d FoldedMeasurements::translationSqrtInformation() const {
  // W'W = information with W = L' (Cholesky L L').
  return Eigen::LLT<Eigen::Matrix3d>(translation_information_).matrixU();
}

double FoldedMeasurements::rotationWeight() const {
  return std::sqrt(rotation_information_);
}

Eigen::Matrix<double, 6, 6> FoldedMeasurements::covariance() const {
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  if (empty()) return c;
  c.topLeftCorner<3, 3>() = translation_information_.inverse();
  c.bottomRightCorner<3, 3>() = Eigen::Matrix3d::Identity() / rotation_information_;
  return c;
}

std::size_t firstKeyframeInProblem(std::size_t n_keyframes, const StageOneConfig& config) {
  const bool windowed = config.window_keyframes > 0 &&
                        n_keyframes > static_cast<std::size_t>(config.window_keyframes);
  if (!windowed || !config.marginalise_outside_window) return 0;
  return n_keyframes - static_cast<std::size_t>(config.window_keyframes) - 1;
}

StageOneResiduals stageOneResiduals(const std::vector<Eigen::Isometry3d>& T_map_cam,
                                    const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                    const std::vector<Eigen::Isometry3d>& T_map_obj,
                                    const std::vector<const ObjectModel*>& models,
                                    const std::vector<StageOneMeasurement>& measurements,
                                    const StageOneConfig& config, std::size_t first_keyframe) {
  StageOneResiduals out;
  const std::size_t n_kf = std::min(T_map_cam.size(), T_odom_cam.size());
  for (std::size_t i = first_keyframe + 1; i < n_kf; ++i) {
    out.odometry.push_back(squaredResidual(odometryFactor(T_odom_cam[i - 1], T_odom_cam[i], config),
                                           T_map_cam[i - 1], T_map_cam[i]));
  }
  const std::size_t n_obj = std::min(T_map_obj.size(), models.size());
  for (const StageOneMeasurement& m : measurements) {
    if (!validMeasurement(m, n_kf, n_obj)) {
      out.measurements.push_back(0.0);
      continue;
    }
    const Eigen::Isometry3d& cam = T_map_cam[static_cast<std::size_t>(m.keyframe)];
    const Eigen::Isometry3d& obj = T_map_obj[static_cast<std::size_t>(m.object)];
    out.measurements.push_back(squaredResidual(
        measurementFactor(m, cam, obj, models[static_cast<std::size_t>(m.object)], config, 1.0),
        cam, obj));
  }
  return out;
}

StageOneSummary optimizeStageOne(std::vector<Eigen::Isometry3d>* T_map_cam,
                                 const std::vector<Eigen::Isometry3d>& T_odom_cam,
                                 std::vector<Eigen::Isometry3d>* T_map_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<StageOneMeasurement>& measurements,
                                 const StageOneConfig& config,
                                 const std::vector<FoldedMeasurements>* folded) {
  StageOneSummary summary;
  const std::size_t n_kf = T_map_cam->size(), n_obj = T_map_obj->size();
  if (n_kf == 0 || T_odom_cam.size() != n_kf || models.size() != n_obj ||
      (folded && folded->size() != n_obj)) {
    summary.message = "inconsistent sizes";
    summary.status = SolveStatus::kBadInput;
    return summary;
  }
  // The window: the latest window_keyframes cameras are free, the one before them anchors the
  // gauge (the first camera when the run is shorter). Marginalising, the older cameras leave the
  // problem and their measurements come as one folded prior per object, so the cost depends on
  // the window and not on the run.
  const bool windowed =
      config.window_keyframes > 0 && n_kf > static_cast<std::size_t>(config.window_keyframes);
  const std::size_t anchor =
      windowed ? n_kf - static_cast<std::size_t>(config.window_keyframes) - 1 : 0;
  const std::size_t first_cam = firstKeyframeInProblem(n_kf, config);
  std::vector<FoldedMeasurements> folded_here;
  if (first_cam > 0 && !folded) {
    folded_here.resize(n_obj);
    for (const StageOneMeasurement& m : measurements) {
      if (!validMeasurement(m, n_kf, n_obj) || static_cast<std::size_t>(m.keyframe) >= first_cam)
        continue;
      const std::size_t j = static_cast<std::size_t>(m.object);
      folded_here[j].add((*T_map_cam)[static_cast<std::size_t>(m.keyframe)], m, models[j],
                         (*T_map_obj)[j].linear(), config);
    }
    folded = &folded_here;
  }
  std::vector<PoseBlock> cams(n_kf), objs(n_obj);
  for (std::size_t i = first_cam; i < n_kf; ++i) cams[i].set((*T_map_cam)[i]);
  for (std::size_t j = 0; j < n_obj; ++j) objs[j].set((*T_map_obj)[j]);

  ceres::Problem problem(ceres_compat::optionsKeepingManifolds());
  PoseManifold manifold;
  auto add_pose = [&](PoseBlock& b) { problem.AddParameterBlock(b.data(), 7, &manifold); };
  for (std::size_t i = first_cam; i < n_kf; ++i) add_pose(cams[i]);
  for (std::size_t i = first_cam + 1; i < n_kf; ++i) {
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseFactor, 6, 7, 7>(
        new RelativePoseFactor(odometryFactor(T_odom_cam[i - 1], T_odom_cam[i], config)));
    problem.AddResidualBlock(cost, makeLoss(config.odometry_loss), cams[i - 1].data(),
                             cams[i].data());
  }
  std::vector<char> used(n_obj, 0);
  for (const StageOneMeasurement& m : measurements) {
    if (!validMeasurement(m, n_kf, n_obj) || !(m.weight > 0.0) ||
        static_cast<std::size_t>(m.keyframe) < first_cam)
      continue;
    PoseBlock &cam = cams[static_cast<std::size_t>(m.keyframe)],
              &obj = objs[static_cast<std::size_t>(m.object)];
    if (!used[static_cast<std::size_t>(m.object)]) {
      add_pose(obj);
      used[static_cast<std::size_t>(m.object)] = 1;
    }
    auto* cost =
        new ceres::AutoDiffCostFunction<RelativePoseFactor, 6, 7, 7>(new RelativePoseFactor(
            measurementFactor(m, cam.get(), obj.get(), models[static_cast<std::size_t>(m.object)],
                              config, std::sqrt(m.weight))));
    problem.AddResidualBlock(cost, makeLoss(config.measurement_loss), cam.data(), obj.data());
  }
  // The marginalised past as a prior on each object the window still observes (an object seen
  // only before the window keeps its pose: it is not in the problem).
  PoseBlock identity;
  identity.set(Eigen::Isometry3d::Identity());
  bool uses_identity = false;
  for (std::size_t j = 0; folded && j < n_obj; ++j) {
    const FoldedMeasurements& past = (*folded)[j];
    if (!used[j] || past.empty()) continue;
    if (!uses_identity) {
      problem.AddParameterBlock(identity.data(), 7, &manifold);
      problem.SetParameterBlockConstant(identity.data());
      uses_identity = true;
    }
    Eigen::Vector3d axis;
    const bool free = freeAxis(models[j], &axis);
    // The folded rotations' equivalent nearest the object's estimate (it may have settled on
    // another one since they were folded; the chordal mean commutes with the symmetries).
    Eigen::Isometry3d mean = past.mean();
    if (models[j])
      mean.linear() =
          closestSymmetricEquivalent(models[j]->symmetry, (*T_map_obj)[j].linear(), mean.linear());
    auto* prior =
        new ceres::AutoDiffCostFunction<RelativePoseFactor, 6, 7, 7>(new RelativePoseFactor(
            mean, past.translationSqrtInformation(), past.rotationWeight(), free, axis));
    problem.AddResidualBlock(prior, nullptr, identity.data(), objs[j].data());
  }
  // The anchor fixes the gauge; outside the window the cameras stay where they are.
  const std::size_t first_free = windowed ? anchor + 1 : 1;
  for (std::size_t i = first_cam; i < first_free; ++i) {
    problem.SetParameterBlockConstant(cams[i].data());
  }

  // Schur complement: the objects (no factor joins two of them) are eliminated first, the free
  // cameras of the window remain as one small dense system.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (std::size_t j = 0; j < n_obj; ++j) {
    if (!used[j]) continue;
    ordering->AddElementToGroup(objs[j].data(), 0);
  }
  for (std::size_t i = first_cam; i < n_kf; ++i) ordering->AddElementToGroup(cams[i].data(), 1);
  if (uses_identity) ordering->AddElementToGroup(identity.data(), 1);
  const ceres::Solver::Summary s =
      solveQuietly(&problem, ceres::DENSE_SCHUR, config.max_iterations, ordering);
  summary.status = statusOf(s);
  summary.solved = usable(summary.status);
  summary.iterations = static_cast<int>(s.iterations.size());
  summary.initial_cost = s.initial_cost;
  summary.final_cost = s.final_cost;
  summary.message = s.BriefReport();
  if (!summary.solved) return summary;
  for (std::size_t i = first_cam; i < n_kf; ++i) (*T_map_cam)[i] = cams[i].get();
  for (std::size_t j = 0; j < n_obj; ++j)
    if (used[j]) (*T_map_obj)[j] = objs[j].get();
  return summary;
}

// ---------------------------------------------------------------------------------------------
// Stage II.
namespace {

// A feature's centre, normal (plane) or axis (curve), and radius (0 for a plane), in its model's
// frame; false for an index the model does not have.
bool featureGeometry(const ObjectModel& m, const FeatureRef& f, Eigen::Vector3d* centre,
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
}

// The contact factor of a contact between models `ma` (object_a) and `mb` (object_b), weighted by
// the configuration. Plane-curve and plane-edge contacts take the plane first: `swapped` says when
// the factor's a is the contact's b.
bool contactFactorOf(const FeatureContact& c, const ObjectModel& ma, const ObjectModel& mb,
                     const StageTwoConfig& config, ContactFactor* e, bool* swapped) {
  e->type = c.type;
  e->w_p = 1.0 / config.contact_sigma_distance_m;
  e->w_q = 1.0 / config.contact_sigma_direction;
  *swapped = (c.type == ContactType::kPlaneCurve || c.type == ContactType::kPlaneEdge) &&
             !c.feature_a.plane;
  const FeatureRef& fa = *swapped ? c.feature_b : c.feature_a;
  const FeatureRef& fb = *swapped ? c.feature_a : c.feature_b;
  if (!featureGeometry(*swapped ? mb : ma, fa, &e->c_a, &e->n_a, &e->r_a)) return false;
  if (c.type == ContactType::kPlaneEdge) {
    e->c_b = c.edge_point;
    return true;
  }
  return featureGeometry(*swapped ? ma : mb, fb, &e->c_b, &e->n_b, &e->r_b);
}

// Stage II's problem: the object pose blocks (warm-started), the fixed support and identity
// blocks, and the factors; an object joins (with its prior) at its first factor, a held object
// as a fixed block (no prior), and a factor between fixed blocks is left out.
class StageTwoProblem {
 public:
  StageTwoProblem(const std::vector<Eigen::Isometry3d>& T_world_obj,
                  const std::vector<const ObjectModel*>& models,
                  const std::vector<Eigen::Isometry3d>& priors, const PosedModel* ground,
                  const StageTwoConfig& config, const std::vector<bool>& held,
                  const std::vector<double>& prior_weights)
      : problem_(ceres_compat::optionsKeepingManifolds()),  // manifold_ is constructed first
        models_(models),
        priors_(priors),
        ground_(ground),
        config_(config),
        held_(held),
        prior_weights_(prior_weights),
        objs_(T_world_obj.size()),
        in_problem_(T_world_obj.size(), 0) {
    for (std::size_t i = 0; i < objs_.size(); ++i) objs_[i].set(T_world_obj[i]);
    identity_.set(Eigen::Isometry3d::Identity());
    if (ground) ground_block_.set(ground->T_world_obj);
  }

  bool addContact(const FeatureContact& c) {
    if (c.held || (c.kind == ContactKind::kLeaning && !config_.leaning_contacts) ||
        (c.kind == ContactKind::kSide && !config_.side_contacts))
      return false;
    PoseBlock *a = block(c.object_a), *b = block(c.object_b);
    const ObjectModel *ma = modelOf(c.object_a), *mb = modelOf(c.object_b);
    if (!a || !b || !ma || !mb || a == b || (fixed(c.object_a) && fixed(c.object_b))) return false;
    ContactFactor e;
    bool swap = false;
    if (!contactFactorOf(c, *ma, *mb, config_, &e, &swap)) return false;
    if (swap) std::swap(a, b);
    join(c.object_a), join(c.object_b);
    auto* cost = new ceres::AutoDiffCostFunction<ContactFactor, 4, 7, 7>(new ContactFactor(e));
    problem_.AddResidualBlock(cost, makeLoss(config_.contact_loss), a->data(), b->data());
    return true;
  }

  bool addSeparation(const Separation& s) {
    PoseBlock *a = block(s.object_a), *b = block(s.object_b);
    if (!a || !b || a == b || !(s.depth > 0.0) || (fixed(s.object_a) && fixed(s.object_b)))
      return false;
    SeparationFactor f;
    f.p_a = s.p_a, f.p_b = s.p_b, f.normal = s.normal.normalized();
    f.depth = s.depth + config_.separation_margin_m;
    f.weight = 1.0 / config_.separation_sigma_m;
    join(s.object_a), join(s.object_b);
    auto* cost =
        new ceres::AutoDiffCostFunction<SeparationFactor, 1, 7, 7>(new SeparationFactor(f));
    problem_.AddResidualBlock(cost, nullptr, a->data(), b->data());
    return true;
  }

  // Solves; the objects without a factor take their priors, as do all when the solve fails; the
  // held ones keep their poses.
  void solve(std::vector<Eigen::Isometry3d>* T_world_obj, StageTwoSummary* summary) {
    problem_.SetParameterBlockConstant(identity_.data());
    if (problem_.HasParameterBlock(ground_block_.data()))
      problem_.SetParameterBlockConstant(ground_block_.data());
    const ceres::Solver::Summary s =
        solveQuietly(&problem_, ceres::SPARSE_NORMAL_CHOLESKY, config_.max_iterations);
    summary->status = statusOf(s);
    summary->solved = usable(summary->status);
    summary->iterations = static_cast<int>(s.iterations.size());
    summary->initial_cost = s.initial_cost;
    summary->final_cost = s.final_cost;
    for (std::size_t i = 0; i < objs_.size(); ++i)
      if (!fixed(static_cast<int>(i)))
        (*T_world_obj)[i] = (summary->solved && in_problem_[i]) ? objs_[i].get() : priors_[i];
  }

 private:
  PoseBlock* block(int index) {
    if (index < 0) return ground_ ? &ground_block_ : nullptr;
    return index < static_cast<int>(objs_.size()) ? &objs_[static_cast<std::size_t>(index)]
                                                  : nullptr;
  }
  bool fixed(int index) const {  // the ground or a held object
    return index < 0 || (!held_.empty() && held_[static_cast<std::size_t>(index)]);
  }
  const ObjectModel* modelOf(int index) const {
    if (index < 0) return ground_ ? ground_->model : nullptr;
    return index < static_cast<int>(models_.size()) ? models_[static_cast<std::size_t>(index)]
                                                    : nullptr;
  }
  // Puts the object's block (with its prior factor) or the ground's into the problem once.
  void join(int index) {
    if (index < 0) {
      if (!problem_.HasParameterBlock(ground_block_.data()))
        problem_.AddParameterBlock(ground_block_.data(), 7, &manifold_);
      return;
    }
    const std::size_t i = static_cast<std::size_t>(index);
    if (in_problem_[i]) return;
    problem_.AddParameterBlock(objs_[i].data(), 7, &manifold_);
    in_problem_[i] = 1;
    if (fixed(index)) {
      problem_.SetParameterBlockConstant(objs_[i].data());
      return;
    }
    Eigen::Vector3d axis;
    const bool free = freeAxis(models_[i], &axis);
    const double w = prior_weights_.empty() ? 1.0 : prior_weights_[i];
    auto* prior = new ceres::AutoDiffCostFunction<RelativePoseFactor, 6, 7, 7>(
        new RelativePoseFactor(priors_[i], w / config_.prior_sigma_position_m,
                               w / config_.prior_sigma_rotation_rad, free, axis));
    problem_.AddResidualBlock(prior, nullptr, identity_.data(), objs_[i].data());
  }

  PoseManifold manifold_;  // before the problem, which refers to it (not owned)
  ceres::Problem problem_;
  const std::vector<const ObjectModel*>& models_;
  const std::vector<Eigen::Isometry3d>& priors_;
  const PosedModel* ground_;
  const StageTwoConfig& config_;
  const std::vector<bool>& held_;
  const std::vector<double>& prior_weights_;
  std::vector<PoseBlock> objs_;
  std::vector<char> in_problem_;
  PoseBlock ground_block_, identity_;
};

}  // namespace

StageTwoSummary optimizeStageTwo(std::vector<Eigen::Isometry3d>* T_world_obj,
                                 const std::vector<const ObjectModel*>& models,
                                 const std::vector<Eigen::Isometry3d>& priors,
                                 const std::vector<FeatureContact>& contacts,
                                 const PosedModel* ground, const StageTwoConfig& config,
                                 const std::vector<Separation>& separations,
                                 const std::vector<bool>& held,
                                 const std::vector<double>& prior_weights) {
  StageTwoSummary summary;
  const std::size_t n = T_world_obj->size();
  const bool weights_ok =
      prior_weights.empty() || (prior_weights.size() == n &&
                                std::all_of(prior_weights.begin(), prior_weights.end(),
                                            [](double w) { return std::isfinite(w) && w > 0.0; }));
  if (models.size() != n || priors.size() != n || (!held.empty() && held.size() != n) ||
      !weights_ok) {
    summary.status = SolveStatus::kBadInput;
    return summary;
  }
  StageTwoProblem problem(*T_world_obj, models, priors, ground, config, held, prior_weights);
  for (const FeatureContact& c : contacts) summary.contacts += problem.addContact(c) ? 1 : 0;
  for (const Separation& s : separations) summary.separations += problem.addSeparation(s) ? 1 : 0;
  if (summary.contacts + summary.separations == 0) {
    summary.status = SolveStatus::kNothingToSolve;  // the priors are the answer
    summary.solved = true;
    for (std::size_t i = 0; i < n; ++i)
      if (held.empty() || !held[i]) (*T_world_obj)[i] = priors[i];
    return summary;
  }
  problem.solve(T_world_obj, &summary);
  return summary;
}

double priorWeight(int measurements, const StageTwoConfig& config) {
  if (config.prior_full_weight_measurements <= 0) return 1.0;
  const double w =
      std::sqrt(std::max(0, measurements) / double(config.prior_full_weight_measurements));
  return std::clamp(w, config.prior_min_weight, 1.0);
}

}  // namespace geofusion

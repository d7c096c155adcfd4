// The detector's persistent errors: the bias is correlated over neighbouring keyframes and not
// over distant ones, the colour-only preset errs along the viewing ray, swap, miss and phantom
// stretches have the configured lengths, and the independent presets draw nothing of it.
#include "geofusion/simulation/dataset.h"
#include "geofusion/simulation/detector_errors.h"
#include "geofusion/simulation/sequence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numeric>

namespace geofusion {
namespace {

// Pearson correlation of x[k] and y[k].
double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
    syy += (y[k] - my) * (y[k] - my);
  }
  return sxy / std::sqrt(sxx * syy);
}

// Lengths of the runs of `true` in a sequence (the last, unfinished one left out).
std::vector<int> runs(const std::vector<bool>& on) {
  std::vector<int> out;
  int length = 0;
  for (bool b : on) {
    if (b) {
      ++length;
    } else if (length > 0) {
      out.push_back(length);
      length = 0;
    }
  }
  return out;
}

TEST(PersistentErrors, BiasIsCorrelatedNearbyAndNotFarAway) {
  PersistentErrorModel m;
  m.bias_translation_m = 0.004;
  m.bias_correlation_keyframes = 30;
  const std::size_t objects = 300, steps = 400;
  std::mt19937 rng(5);
  PersistentErrors e(m, std::vector<bool>(objects, false), rng);
  std::vector<std::vector<double>> x(steps, std::vector<double>(objects));
  for (std::size_t t = 0; t < steps; ++t) {
    for (std::size_t i = 0; i < objects; ++i) x[t][i] = e.translationBias(i).x();
    e.step(rng);
  }
  std::vector<double> a, b, c;
  double sq = 0;
  for (std::size_t t = 0; t + 150 < steps; ++t) {
    for (std::size_t i = 0; i < objects; ++i) {
      a.push_back(x[t][i]);
      b.push_back(x[t + 1][i]);
      c.push_back(x[t + 150][i]);
      sq += x[t][i] * x[t][i];
    }
  }
  const double near = correlation(a, b), far = correlation(a, c);
  const double sigma = std::sqrt(sq / static_cast<double>(a.size()));
  std::cout << "bias autocorrelation: 1 keyframe " << near << ", 150 keyframes " << far << "; std "
            << sigma * 1000 << " mm\n";
  EXPECT_GT(near, 0.93);          // exp(-1/30) = 0.967
  EXPECT_LT(std::abs(far), 0.1);  // exp(-5) = 0.007
  EXPECT_NEAR(sigma, 0.004, 0.0006);
}

TEST(PersistentErrors, ColourOnlyErrorLiesAlongTheViewingRay) {
  const DetectorModel rgb = DetectorModel::rgbOnly();
  std::mt19937 rng(7);
  const std::size_t objects = 400;
  PersistentErrors e(rgb.persistence, std::vector<bool>(objects, false), rng);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double along = 0, across = 0, relative = 0;
  for (std::size_t i = 0; i < objects; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0.3 * u(rng), 0.2 * u(rng), 0.95 + 0.25 * u(rng));
    const Eigen::Vector3d ray = T.translation().normalized();
    const Eigen::Vector3d d = e.apply(i, T).translation() - T.translation();
    along += std::pow(d.dot(ray), 2);
    across += (d - ray * d.dot(ray)).squaredNorm();
    relative += std::pow(d.dot(ray) / T.translation().norm(), 2);
  }
  along = std::sqrt(along / objects), across = std::sqrt(across / objects);
  relative = std::sqrt(relative / objects);
  std::cout << "colour-only bias: along the ray " << along * 1000 << " mm rms (" << relative * 100
            << " % of the distance), across " << across * 1000 << " mm\n";
  EXPECT_GT(along, 3.0 * across);
  EXPECT_GT(along, 0.02);  // 2-4 cm at 0.7-1.2 m
  EXPECT_LT(along, 0.04);
}

TEST(PersistentErrors, StretchesHaveTheirConfiguredLengths) {
  PersistentErrorModel m;
  m.swap_stretch_rate = 0.02;
  m.miss_stretch_rate = 0.02;
  m.phantoms = 3;
  const std::size_t objects = 6, steps = 3000;
  std::mt19937 rng(11);
  const std::vector<bool> look_alike{true, true, true, false, false, false};
  PersistentErrors e(m, look_alike, rng);
  std::vector<std::vector<bool>> swapped(objects), missed(objects), phantom(3);
  for (std::size_t t = 0; t < steps; ++t) {
    e.step(rng);
    for (std::size_t i = 0; i < objects; ++i) {
      swapped[i].push_back(e.swapped(i));
      missed[i].push_back(e.missed(i));
    }
    for (std::size_t p = 0; p < 3; ++p) phantom[p].push_back(e.phantoms()[p].on);
  }
  int swap_runs = 0, miss_runs = 0, phantom_runs = 0;
  for (std::size_t i = 0; i < objects; ++i) {
    for (int length : runs(swapped[i])) {
      ++swap_runs;
      EXPECT_GE(length, m.swap_stretch_min);
      EXPECT_LE(length, m.swap_stretch_max + 1);
    }
    if (!look_alike[i]) {
      EXPECT_TRUE(runs(swapped[i]).empty()) << "object " << i;
    }
    for (int length : runs(missed[i])) {
      ++miss_runs;
      EXPECT_GE(length, m.miss_stretch_min);
      EXPECT_LE(length, m.miss_stretch_max + 1);
    }
  }
  for (const auto& p : phantom) {
    for (int length : runs(p)) {
      ++phantom_runs;
      EXPECT_GE(length, m.phantom_stretch_min);
      EXPECT_LE(length, m.phantom_stretch_max);
    }
  }
  for (const auto& p : e.phantoms()) {
    EXPECT_GE(p.offset_world.norm(), 0.03 - 1e-9);
    EXPECT_LE(p.offset_world.norm(), 0.06 + 1e-9);
    EXPECT_LT(p.host, static_cast<int>(objects));
  }
  std::cout << swap_runs << " swap, " << miss_runs << " miss, " << phantom_runs
            << " phantom stretches\n";
  EXPECT_GT(swap_runs, 20);
  EXPECT_GT(miss_runs, 40);
  EXPECT_GT(phantom_runs, 20);
}

TEST(PersistentErrors, TheIndependentPresetsHaveNone) {
  for (const std::string& name : DetectorModel::names()) {
    DetectorModel m;
    ASSERT_TRUE(DetectorModel::byName(name, &m)) << name;
    const bool persistent = name == "densefusion_persistent" || name == "rgb";
    EXPECT_EQ(m.persistence.enabled(), persistent) << name;
  }
  DetectorModel m;
  EXPECT_FALSE(DetectorModel::byName("yolo", &m));
  // A suite with an independent preset describes itself as before the persistent errors existed
  // (its cached recordings stay valid); a persistent one says so.
  SuiteSpec suite;
  ASSERT_TRUE(suiteByName("demo", &suite));
  EXPECT_EQ(describeSuite(suite).find("persistent"), std::string::npos);
  suite.detector = DetectorModel::rgbOnly();
  EXPECT_NE(describeSuite(suite).find("persistent"), std::string::npos);
}

}  // namespace
}  // namespace geofusion

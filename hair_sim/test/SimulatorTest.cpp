/// Strip dynamics, equations (1)-(7), against analytic numbers.
#include "hair_sim/core/Simulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "TestUtil.hpp"
#include "hair_sim/core/events/EventSchedule.hpp"
#include "hair_sim/core/geometry/Tessellator.hpp"
#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/core/util/YamlReader.hpp"

namespace hair_sim {
namespace {

using test::kPi;

PhysicsParameters bare() {
  PhysicsParameters p;
  p.hinge_stiffness = 0.0;
  p.hinge_damping = 0.0;
  p.air_drag = 0.0;
  p.compensate_rest_angles = false;
  return p;
}

/// The rotation helpers against their definitions: minimalRotation(a, b) is a proper rotation taking a
/// onto b about the axis a x b (so it fixes that axis) by the angle between them, the same rotation as
/// rotateByVector(rotationVectorBetween(a, b), .) and as Eigen's AngleAxis.
TEST(RotationHelpers, MinimalRotationIsTheRotationAboutAxB) {
  std::srand(7);
  for (int k = 0; k < 200; ++k) {
    const Vec3 a = Vec3::Random().normalized();
    Vec3 b = Vec3::Random().normalized();
    if (k % 50 == 0) b = (a + 1e-7 * Vec3::Random()).normalized();   // nearly parallel
    if (k % 50 == 1) b = (-a + 1e-3 * Vec3::Random()).normalized();  // nearly opposite
    const Mat3 R = minimalRotation(a, b);
    // Rodrigues divides by 1 + a.b: rounding grows as 1 / (1 + a.b) for nearly opposite vectors.
    const double tol = 1e-12 + 1e-15 / (1.0 + a.dot(b));
    EXPECT_LT((R * R.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff(), tol);
    EXPECT_NEAR(R.determinant(), 1.0, tol);
    EXPECT_LT((R * a - b).norm(), tol);
    const Vec3 axis = a.cross(b);
    if (axis.norm() > 1e-6) {
      EXPECT_LT((R * axis - axis).norm(), tol * (1.0 + axis.norm()));
      const Mat3 expected =
          Eigen::AngleAxisd(std::atan2(axis.norm(), a.dot(b)), axis.normalized()).toRotationMatrix();
      EXPECT_LT((R - expected).cwiseAbs().maxCoeff(), 10 * tol);
      const Vec3 v = Vec3::Random();
      EXPECT_LT((rotateByVector(rotationVectorBetween(a, b), v) - R * v).norm(), 10 * tol * (1.0 + v.norm()));
    }
  }
  // Exactly opposite: a half turn about a perpendicular axis.
  const Vec3 a = Vec3::UnitZ();
  const Mat3 R = minimalRotation(a, -a);
  EXPECT_LT((R * a + a).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

/// Signed angle of the first segment of column 0 about +x, from straight down (-z).
double firstAngle(const Simulator& sim) {
  const Vec3 d = sim.positionsHead()[2] - sim.positionsHead()[0];  // row 1, column 0 (2 columns)
  return std::atan2(d.y(), -d.z());
}

/// Times of upward zero crossings of a sampled signal (linear interpolation).
std::vector<double> upCrossings(const std::vector<double>& x, double dt) {
  std::vector<double> t;
  for (std::size_t i = 1; i < x.size(); ++i)
    if (x[i - 1] < 0.0 && x[i] >= 0.0) t.push_back(dt * ((i - 1) + x[i - 1] / (x[i - 1] - x[i])));
  return t;
}

TEST(SimulatorTest, RigidSegmentUnderGravitySwingsWithCompoundPendulumPeriod) {
  const double d = 0.08, g = 9.81;
  PhysicsParameters p = bare();
  Simulator sim(test::hangingStrip(2, 4, d, 0.05), p);
  std::vector<double> angle;
  StepInputs in;
  for (int i = 0; i < 240 * 4; ++i) {
    sim.step(in);
    angle.push_back(firstAngle(sim));
  }
  const std::vector<double> up = upCrossings(angle, p.substep);
  ASSERT_GE(up.size(), 5u);
  const double measured = (up.back() - up.front()) / (up.size() - 1);
  const double expected = 2.0 * kPi * std::sqrt(2.0 * d / (3.0 * g));  // I = rho d^3/3, lever d/2
  EXPECT_NEAR(measured, expected, 0.01 * expected);
}

TEST(SimulatorTest, HingeSpringOscillatesAtDampedFrequencyAndDecaysAtGammaOver2I) {
  const double d = 0.05, rho = 0.01;
  const double I = rho * d * d * d / 3.0;
  PhysicsParameters p = bare();
  p.gravity.setZero();
  p.hinge_stiffness = 1e-4;
  p.hinge_damping = 2.0 * I * 1.0;  // decay rate gamma / (2 I) = 1 /s
  const Hairstyle style = test::hangingStrip(2, 4, d, 0.0);
  Simulator sim(style, p);
  // Displace the whole chain by 0.1 rad about +x (every segment keeps its hinge bend).
  std::vector<Vec3> shape = sim.positionsHead();
  const Mat3 turn = Eigen::AngleAxisd(0.1, Vec3::UnitX()).toRotationMatrix();
  for (std::size_t i = 2; i < shape.size(); ++i) shape[i] = shape[i % 2] + turn * (shape[i] - shape[i % 2]);
  sim.setShape(shape);
  std::vector<double> angle;
  StepInputs in;
  for (int i = 0; i < 240 * 3; ++i) {
    sim.step(in);
    angle.push_back(firstAngle(sim));
  }
  const double k = p.hinge_stiffness, gamma = p.hinge_damping;
  const double omega = std::sqrt(k / I - std::pow(gamma / (2 * I), 2));
  const std::vector<double> up = upCrossings(angle, p.substep);
  ASSERT_GE(up.size(), 4u);
  const double period = (up.back() - up.front()) / (up.size() - 1);
  EXPECT_NEAR(2 * kPi / period, omega, 0.02 * omega);
  // Amplitude decay between the first and last positive peaks.
  std::vector<std::pair<double, double>> peaks;
  for (std::size_t i = 1; i + 1 < angle.size(); ++i)
    if (angle[i] > angle[i - 1] && angle[i] >= angle[i + 1] && angle[i] > 0)
      peaks.push_back({i * p.substep, angle[i]});
  ASSERT_GE(peaks.size(), 3u);
  const double rate =
      std::log(peaks.front().second / peaks.back().second) / (peaks.back().first - peaks.front().first);
  EXPECT_NEAR(rate, gamma / (2 * I), 0.02 * gamma / (2 * I));
}

TEST(SimulatorTest, ConstantWindForceDensityGivesEquilibriumTanThetaEqualsFOverRhoG) {
  PhysicsParameters p = bare();
  p.air_drag = 0.02;
  p.hinge_damping = 2e-6;
  const double wind = 3.0;
  Simulator sim(test::hangingStrip(2, 5, 0.05, 0.0), p);
  StepInputs in;
  in.wind = Vec3(0.0, wind, 0.0);
  for (int i = 0; i < 240 * 20; ++i) sim.step(in);
  const double f = p.air_drag * wind;  // still hair in a steady wind: f = air_drag * v_air
  const double expected = std::atan(f / (p.linear_density * 9.81));
  const std::vector<Vec3>& x = sim.positionsHead();
  for (std::size_t i = 2; i < x.size(); ++i) {
    const Vec3 seg = x[i] - x[i - 2];
    const double theta = std::atan2(seg.y(), -seg.z());
    EXPECT_NEAR(theta, expected, 0.1 * kPi / 180.0) << "segment ending at point " << i;
  }
}

Simulator defaultSimulator(bool compensate = true) {
  SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  config.physics.compensate_rest_angles = compensate;
  return Simulator(loadHairstyle(config.hairstyle_file), config.physics);
}

/// The largest distance between the points of a and b (the same size).
double maxDistance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

double maxDeviationAfterRest(Simulator& sim, double seconds) {
  StepInputs in;
  in.head.pose.translation() = Vec3(0.0, 0.0, 1.6);
  const int steps = static_cast<int>(seconds / sim.parameters().substep);
  for (int i = 0; i < steps; ++i) sim.step(in);
  return maxDistance(sim.positionsHead(), test::styledPoints(sim.hairstyle()));
}

TEST(SimulatorTest, StyledDefaultHairstyleIsTheEquilibriumAtRest) {
  Simulator sim = defaultSimulator(true);
  EXPECT_LT(maxDeviationAfterRest(sim, 5.0), 1e-3);
}

TEST(SimulatorTest, WithoutRestCompensationTheDefaultHairstyleSags) {
  // The equilibrium test above can fail: without compensation gravity pulls the styled shape away.
  Simulator sim = defaultSimulator(false);
  EXPECT_GT(maxDeviationAfterRest(sim, 5.0), 5e-3);
}

TEST(SimulatorTest, EveryHeadOrientationStaysFiniteWithoutSpins) {
  // A small hairstyle on a 15 degree grid of yaw, pitch, roll: the head holds each orientation for
  // 0.2 s starting from the styled shape (gravity now points anywhere relative to the hair).
  SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Hairstyle style = loadHairstyle(config.hairstyle_file);
  std::vector<Strip> some;  // strips from every ring: crown, sides, nape
  for (std::size_t i = 0; i < style.strips.size(); i += 17) some.push_back(style.strips[i]);
  style.strips = some;
  Simulator sim(style, config.physics);
  const PhysicsParameters& p = sim.parameters();
  const double g = p.gravity.norm();
  // Energy bound for each segment: at the start it holds at most the gravity energy of turning its
  // midpoint from the top to the bottom (rho d g d) plus the hinge energy of the rest compensation
  // (angle <= rho g d^2 / (2 k)); damping only removes energy, so I w^2 / 2 cannot exceed that:
  //   w <= sqrt(2 (rho g d^2 + k theta_c^2 / 2) / I).
  // Lower segments also feel their parent's rotation through the hinge; they get twice the bound.
  std::vector<double> bound(sim.positionsHead().size(), 0.0);
  for (std::size_t s = 0; s < style.strips.size(); ++s) {
    const Strip& st = style.strips[s];
    for (int r = 1; r < st.rows; ++r)
      for (int c = 0; c < st.columns; ++c) {
        const int k = sim.stripOffsets()[s] + st.index(r, c);
        const double d = (st.point(r, c) - st.point(r - 1, c)).norm();
        const double theta_c = p.linear_density * g * d * d / (2.0 * p.hinge_stiffness);
        const double e = p.linear_density * g * d * d + 0.5 * p.hinge_stiffness * theta_c * theta_c;
        bound[static_cast<std::size_t>(k)] = (r == 1 ? 1.0 : 2.0) * std::sqrt(2.0 * e / sim.inertia(k));
      }
  }
  double worst_ratio = 0.0;
  std::vector<Vec3> before;
  for (int yaw = -180; yaw < 180; yaw += 15)
    for (int pitch = -90; pitch <= 90; pitch += 15)
      for (int roll = -180; roll < 180; roll += 15) {
        sim.reset();
        StepInputs in;
        in.head.pose.linear() = rotationFromRpy(Vec3(roll, pitch, yaw) * kPi / 180.0);
        for (int i = 0; i < 48; ++i) {
          before = sim.positionsHead();
          sim.step(in);
          const std::vector<Vec3>& x = sim.positionsHead();
          for (std::size_t k = 0; k < x.size(); ++k) {
            if (bound[k] == 0.0) continue;     // roots
            const std::size_t parent = k - 2;  // 2 columns per strip in the default hairstyle
            const Vec3 a = (before[k] - before[parent]).normalized(), b = (x[k] - x[parent]).normalized();
            const double rate = test::angleBetween(a, b) / p.substep;
            worst_ratio = std::max(worst_ratio, rate / bound[k]);
          }
        }
        for (const Vec3& x : sim.positionsHead())
          ASSERT_TRUE(x.allFinite()) << yaw << " " << pitch << " " << roll;
      }
  EXPECT_LT(worst_ratio, 1.0);
  std::printf("worst segment rate / energy bound = %.3f\n", worst_ratio);
}

TEST(SimulatorTest, ContinuousTumbleStaysFiniteAndKeepsSegmentLengths) {
  SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Simulator sim(loadHairstyle(config.hairstyle_file), config.physics);
  HeadMotionEstimator head;
  head.reset(Iso3::Identity());
  const double dt = sim.parameters().substep;
  const Vec3 spin = Vec3(1.0, 0.7, 0.4).normalized() * 4.0;  // rad/s about a skew axis
  double worst_rate = 0.0;
  for (int i = 1; i <= 240 * 5; ++i) {
    Iso3 pose = Iso3::Identity();
    pose.linear() = Eigen::AngleAxisd(spin.norm() * i * dt, spin.normalized()).toRotationMatrix();
    StepInputs in;
    in.head = head.update(pose, dt);
    sim.step(in);
    worst_rate = std::max(worst_rate, sim.maxSegmentRate());
  }
  const std::vector<Vec3>& x = sim.positionsHead();
  for (const Vec3& p : x) ASSERT_TRUE(p.allFinite());
  int offset = 0;
  for (const Strip& s : sim.hairstyle().strips) {
    for (int r = 1; r < s.rows; ++r)
      for (int c = 0; c < s.columns; ++c) {
        const double now = (x[offset + s.index(r, c)] - x[offset + s.index(r - 1, c)]).norm();
        EXPECT_NEAR(now, (s.point(r, c) - s.point(r - 1, c)).norm(), 1e-9);
      }
    offset += s.pointCount();
  }
  // No flip or spin: no segment turns by a quarter turn or more within one substep (the dynamics
  // alone are clamped to max_angle_step; the spring band and collision corrections come on top).
  EXPECT_LT(worst_rate * dt, 0.5 * kPi);
  std::printf("tumble: largest segment rate %.1f rad/s (%.3f rad per substep)\n", worst_rate,
              worst_rate * dt);
}

TEST(SimulatorTest, IdenticalInputsGiveBitIdenticalResults) {
  auto run = [] {
    Simulator sim = defaultSimulator();
    HeadMotionEstimator head;
    head.reset(Iso3::Identity());
    for (int i = 1; i <= 480; ++i) {
      Iso3 pose = Iso3::Identity();
      pose.linear() = rotationFromRpy(Vec3(0.0, 0.0, 0.8 * std::sin(i * 0.03)));
      StepInputs in;
      in.head = head.update(pose, sim.parameters().substep);
      in.wind = Vec3(1.0, 2.0, 0.0);
      sim.step(in);
    }
    return sim.positionsHead();
  };
  const std::vector<Vec3> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)));
}

/// The default hairstyle with the default bodies, springs on, under a shaking and nodding head in wind: the
/// step paths of Simulator::StepPath on the same inputs. Returns the control points after `steps` substeps
/// and the strips that went to the exact step over the run.
/// The default hairstyle, or (generated_strips > 0) one generated with that many strips.
/// Substep i of the shake the path tests drive (about y and z, amplitude a) with wind, from the head pose
/// `rest`; the body frames of the config's bodies.
StepInputs shakeInputs(const SimConfig& config, const Iso3& rest, int i, double a, HeadMotionEstimator& head,
                       double substep) {
  Iso3 pose = rest;
  pose.linear() =
      rotationFromRpy(Vec3(0.0, 0.3 * a * std::sin(i * 0.05 * a), 0.9 * a * std::sin(i * 0.03 * a)));
  StepInputs in;
  in.head = head.update(pose, substep);
  in.wind = Vec3(2.0, 1.0, 0.0);
  for (const Body& b : config.bodies)
    in.body_frames.push_back(b.frame == config.head_frame ? pose : Iso3::Identity());
  return in;
}

/// Substeps [from, to) of the shake (shakeInputs, amplitude 1).
void shake(Simulator& sim, const SimConfig& config, const Iso3& rest, HeadMotionEstimator& head, int from,
           int to) {
  for (int i = from; i < to; ++i) sim.step(shakeInputs(config, rest, i, 1.0, head, sim.parameters().substep));
}

/// The default parameters without springs.
PhysicsParameters withoutSprings() {
  PhysicsParameters p;
  p.springs_within_strips = false;
  p.springs_between_strips = false;
  return p;
}

/// `style` without bodies on `path` for `substeps` substeps of a steady wind, the head still: the final
/// positions; *exact counts the strips that took the exact step.
std::vector<Vec3> runInWind(const Hairstyle& style, const PhysicsParameters& p, Simulator::StepPath path,
                            const Vec3& wind, int substeps, long* exact) {
  Simulator sim(style, p);
  sim.setStepPath(path);
  StepInputs in;
  in.wind = wind;
  *exact = 0;
  for (int i = 0; i < substeps; ++i) {
    sim.step(in);
    *exact += sim.exactStripCount();
  }
  return sim.positionsHead();
}

/// The head's rest pose in these tests: 1.6 m above the world's origin.
Iso3 headRest() {
  Iso3 rest = Iso3::Identity();
  rest.translation() = Vec3(0.0, 0.0, 1.6);
  return rest;
}

/// `strips` strips generated for `config` about the head at rest (headRest).
Hairstyle generatedHairstyle(const SimConfig& config, int strips) {
  GeneratorOptions generated;
  generated.strips = strips;
  return generateHairstyle(config, headRest(), generated);
}

/// measures: the spring measures after the last substep (minSpringRatio and maxSpringRatio within and
/// between strips, minStripGap).
std::vector<Vec3> runPath(Simulator::StepPath path, int steps, double amplitude, long* exact_strips = nullptr,
                          double* max_penetration = nullptr, int threads = 1, int generated_strips = 0,
                          std::vector<double>* measures = nullptr, const Hairstyle* style = nullptr) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Iso3 head_rest = Iso3::Identity();
  head_rest.translation() = Vec3(0.0, 0.0, 1.6);
  GeneratorOptions generated;
  generated.strips = generated_strips;
  Simulator sim(style                  ? *style
                : generated_strips > 0 ? generateHairstyle(config, head_rest, generated)
                                       : loadHairstyle(config.hairstyle_file),
                config.physics, config.bodies);
  sim.setStepPath(path);
  sim.setThreads(threads);
  HeadMotionEstimator head;
  Iso3 rest = Iso3::Identity();
  rest.translation() = Vec3(0.0, 0.0, 1.6);
  head.reset(rest);
  long exact = 0;
  double penetration = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const StepInputs in = shakeInputs(config, rest, i, amplitude, head, sim.parameters().substep);
    sim.step(in);
    exact += sim.exactStripCount();
    // From the geometry (not the Simulator's own count, which the lanes' committed points skip), and the
    // count must see it.
    const double deepest = test::deepestInside(sim.positionsHead(), sim.stripOffsets(), sim.hairstyle(),
                                               config.bodies, in.head.pose, in.body_frames);
    EXPECT_GE(sim.maxPenetration() + 1e-12, deepest) << "substep " << i;
    penetration = std::max(penetration, deepest);
  }
  if (exact_strips) *exact_strips = exact;
  if (max_penetration) *max_penetration = penetration;
  if (measures)
    *measures = {sim.minSpringRatio(true), sim.maxSpringRatio(true), sim.minSpringRatio(false),
                 sim.maxSpringRatio(false), sim.minStripGap()};
  return sim.positionsHead();
}

TEST(SimulatorTest, LanePathGivesTheSameBitsWithAndWithoutAvx2) {
  // The AVX-512VL, AVX2 and baseline kernels run the same operations in the same order without FMA. (On a
  // CPU without AVX-512VL the AVX2 run would be the first one again and is left out; without AVX2 there is
  // one kernel and the test is skipped.)
  using Path = Simulator::StepPath;
  const std::string best = Simulator::kernelInstructionSet(Path::Lanes);
  const std::string avx2 = Simulator::kernelInstructionSet(Path::LanesAvx2);
  const std::string baseline = Simulator::kernelInstructionSet(Path::LanesBaseline);
  if (best == baseline) GTEST_SKIP() << "one kernel on this CPU (" << best << "): nothing to compare";
  long exact = 0;
  const int steps = 480;
  const std::vector<Vec3> a = runPath(Path::Lanes, steps, 1.0, &exact);
  const std::vector<Vec3> b = runPath(Path::LanesBaseline, steps, 1.0);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3))) << best << " against " << baseline;
  if (avx2 != best) {
    const std::vector<Vec3> c = runPath(Path::LanesAvx2, steps, 1.0);
    ASSERT_EQ(a.size(), c.size());
    EXPECT_EQ(0, std::memcmp(a.data(), c.data(), a.size() * sizeof(Vec3))) << best << " against " << avx2;
  }
  // Both halves of the path were exercised: strips committed from the lanes and strips sent to the exact
  // step.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const long strip_steps = static_cast<long>(loadHairstyle(config.hairstyle_file).strips.size()) * steps;
  EXPECT_GT(exact, 0);
  EXPECT_LT(exact, strip_steps / 2);
}

TEST(SimulatorTest, LanePathGivesTheSameBitsForOtherStripShapes) {
  // Strips of three columns and strips of 5 and 7 rows mixed: blocks whose lanes are not two strips' two
  // columns (the kernel's load and store lane by lane, not by pairs of points) and lanes that idle below a
  // shorter chain. AVX2 and baseline give the same bits, and both follow the exact step within rounding
  // (1e-8 m after 40 substeps, as LanePathFollowsTheExactStep).
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Iso3 head_rest = Iso3::Identity();
  head_rest.translation() = Vec3(0.0, 0.0, 1.6);
  Hairstyle style;
  for (const auto& [columns, rows] : {std::pair{3, 5}, std::pair{2, 7}, std::pair{2, 5}}) {
    GeneratorOptions options;
    options.strips = 12;
    options.rings = 2;
    options.columns = columns;
    options.rows = rows;
    options.seed = static_cast<std::uint32_t>(columns * 10 + rows);
    Hairstyle part = generateHairstyle(config, head_rest, options);
    for (Strip& strip : part.strips) strip.name += "_" + std::to_string(columns) + "x" + std::to_string(rows);
    if (style.strips.empty()) style.scalp = part.scalp;
    style.strips.insert(style.strips.end(), part.strips.begin(), part.strips.end());
  }
  auto run = [&](Simulator::StepPath path, long* exact) {
    return runPath(path, 40, 1.0 / 3.0, exact, nullptr, 1, 0, nullptr, &style);
  };
  long exact_lanes = 0, exact_baseline = 0, exact_exact = 0;
  const std::vector<Vec3> lanes = run(Simulator::StepPath::Lanes, &exact_lanes);
  const std::vector<Vec3> baseline = run(Simulator::StepPath::LanesBaseline, &exact_baseline);
  const std::vector<Vec3> avx2 = run(Simulator::StepPath::LanesAvx2, nullptr);
  const std::vector<Vec3> exact = run(Simulator::StepPath::Exact, &exact_exact);
  ASSERT_EQ(lanes.size(), baseline.size());
  ASSERT_EQ(lanes.size(), avx2.size());
  EXPECT_EQ(0, std::memcmp(lanes.data(), baseline.data(), lanes.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(lanes.data(), avx2.data(), lanes.size() * sizeof(Vec3)));
  EXPECT_EQ(exact_lanes, exact_baseline);
  EXPECT_GT(exact_lanes, 0);            // some strips took the exact step,
  EXPECT_LT(exact_lanes, exact_exact);  // most were committed from the lanes
  EXPECT_LT(maxDistance(lanes, exact), 1e-8);
}

TEST(SimulatorTest, KernelInstructionSetsFollowTheCpuFlags) {
  // What the benchmarks report as the kernels' instruction sets, against the flags the kernel lists in
  // /proc/cpuinfo (x86-64 Linux): AVX-512VL needs avx512f and avx512vl, and the dispatch asks for AVX2 too.
#if !defined(__x86_64__)
  GTEST_SKIP() << "the kernels' dispatch is for x86-64";
#endif
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  std::set<std::string> flags;
  while (std::getline(cpuinfo, line))
    if (line.rfind("flags", 0) == 0) {
      std::istringstream words(line.substr(line.find(':') + 1));
      for (std::string w; words >> w;) flags.insert(w);
      break;
    }
  if (flags.empty()) GTEST_SKIP() << "no flags line in /proc/cpuinfo";
  const bool avx2 = flags.count("avx2") > 0;
  const bool avx512 = avx2 && flags.count("avx512f") > 0 && flags.count("avx512vl") > 0;
  using P = Simulator::StepPath;
  EXPECT_STREQ(Simulator::kernelInstructionSet(P::Lanes), avx512 ? "AVX-512VL" : avx2 ? "AVX2" : "x86-64");
  EXPECT_STREQ(Simulator::kernelInstructionSet(P::LanesAvx2), avx2 ? "AVX2" : "x86-64");
  EXPECT_STREQ(Simulator::kernelInstructionSet(P::LanesBaseline), "x86-64");
  EXPECT_STREQ(Simulator::kernelInstructionSet(P::Exact), "none");
  EXPECT_STREQ(Tessellator::instructionSet(), avx2 ? "AVX2" : "SSE2");
}

TEST(SimulatorTest, HelperThreadsGiveTheSameBits) {
  // A helper thread computes blocks of chains (each from its own chains' state at the start of the substep)
  // and sweeps the second group of strips (which shares no spring pair with the first: each point's forces
  // are added in the sweep order either way): any thread count gives the same hair and the same spring
  // measures. 600 strips (300 blocks of 4 chains): over the 128 blocks from which the helper takes part, and
  // over the 64 blocks of a run that one thread computes between the strips' commits
  // (Simulator::kBlocksPerRun).
  long exact1 = 0, exact2 = 0, exact3 = 0;
  const int steps = 120, strips = 600;
  std::vector<double> measures1, measures2, measures3;
  const std::vector<Vec3> one =
      runPath(Simulator::StepPath::Lanes, steps, 1.0, &exact1, nullptr, 1, strips, &measures1);
  const std::vector<Vec3> two =
      runPath(Simulator::StepPath::Lanes, steps, 1.0, &exact2, nullptr, 2, strips, &measures2);
  const std::vector<Vec3> three =
      runPath(Simulator::StepPath::Lanes, steps, 1.0, &exact3, nullptr, 3, strips, &measures3);
  EXPECT_EQ(measures1, measures2);
  EXPECT_EQ(measures1, measures3);
  ASSERT_EQ(measures1.size(), 5u);
  EXPECT_LT(measures1[0], measures1[1]);  // the strips' widths moved
  EXPECT_GT(measures1[4], 0.0);
  const std::vector<Vec3> baseline2 =
      runPath(Simulator::StepPath::LanesBaseline, steps, 1.0, nullptr, nullptr, 2, strips);
  ASSERT_EQ(one.size(), two.size());
  ASSERT_EQ(one.size(), three.size());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(one.data(), three.data(), one.size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(one.data(), baseline2.data(), one.size() * sizeof(Vec3)));
  EXPECT_GT(exact1, 0);  // the exact step ran between the blocks (strips the constraints moved)
  EXPECT_EQ(exact1, exact2);
  EXPECT_EQ(exact1, exact3);
}

TEST(SimulatorTest, SweepGroupsShareNoSpringPair) {
  // On 2 threads the first two sweep groups are swept at once (Simulator::sweepGroupOf): a spring pair
  // between them would be kept from both threads at once, so there must be none. Group 0 lies in the first
  // half of the blocks of chains and group 1 in the second, and chains go into blocks in strip order, so
  // every strip of group 0 comes before every strip of group 1. 600 generated strips (the hairstyle of
  // HelperThreadsGiveTheSameBits): both groups and the boundary are there, and the boundary, the part no
  // second thread shares, is a minority.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Simulator sim(generatedHairstyle(config, 600), config.physics, config.bodies);
  const std::size_t strips = sim.hairstyle().strips.size();
  ASSERT_GT(strips, 500u);  // (the generator places 599)
  std::vector<int> group(strips);
  int count[3] = {0, 0, 0};
  std::size_t last0 = 0, first1 = strips;
  for (std::size_t s = 0; s < strips; ++s) {
    group[s] = sim.sweepGroupOf(s);
    ASSERT_GE(group[s], 0);
    ASSERT_LE(group[s], 2);
    ++count[group[s]];
    if (group[s] == 0) last0 = s;
    if (group[s] == 1) first1 = std::min(first1, s);
  }
  EXPECT_LT(last0, first1);
  EXPECT_GT(count[0], 100);
  EXPECT_GT(count[1], 100);
  EXPECT_GT(count[2], 0);
  EXPECT_LT(count[2], static_cast<int>(strips / 2));
  std::vector<int> strip_of(static_cast<std::size_t>(sim.controlPointCount()));
  for (std::size_t s = 0; s < strips; ++s)
    for (int p = 0; p < sim.hairstyle().strips[s].pointCount(); ++p)
      strip_of[static_cast<std::size_t>(sim.stripOffsets()[s] + p)] = static_cast<int>(s);
  int between = 0;
  for (const SpringPair& pair : sim.springs()) {
    const int ga = group[static_cast<std::size_t>(strip_of[static_cast<std::size_t>(pair.a)])];
    const int gb = group[static_cast<std::size_t>(strip_of[static_cast<std::size_t>(pair.b)])];
    EXPECT_FALSE((ga == 0 && gb == 1) || (ga == 1 && gb == 0)) << "pair " << pair.a << "-" << pair.b;
    between += pair.within_strip ? 0 : 1;
  }
  EXPECT_GT(between, 1000);  // (the groups are not apart for want of pairs)
  EXPECT_THROW(sim.sweepGroupOf(strips), std::out_of_range);
}

TEST(SimulatorTest, PathSwitchesAndResetKeepTheBitsOnEveryThreadCount) {
  // The Lanes paths swap the state with their buffers; the Exact path works in the state alone. Switching
  // between them mid-run, and reset() in between, give the same hair on 1, 2 and 3 threads, and a run after
  // reset() is a fresh run's. 600 generated strips: the helpers take part.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Iso3 rest = headRest();
  const Hairstyle style = generatedHairstyle(config, 600);
  auto run = [&](int threads, bool with_reset) {
    Simulator sim(style, config.physics, config.bodies);
    sim.setThreads(threads);
    HeadMotionEstimator head;
    head.reset(rest);
    if (with_reset) {  // a history before the reset: the Exact path, then the Lanes path
      sim.setStepPath(Simulator::StepPath::Exact);
      shake(sim, config, rest, head, 0, 10);
      sim.setStepPath(Simulator::StepPath::Lanes);
      shake(sim, config, rest, head, 10, 30);
      sim.reset();
      head.reset(rest);
    }
    shake(sim, config, rest, head, 0, 40);
    sim.setStepPath(Simulator::StepPath::Exact);
    shake(sim, config, rest, head, 40, 45);
    sim.setStepPath(Simulator::StepPath::LanesBaseline);
    shake(sim, config, rest, head, 45, 60);
    sim.setStepPath(Simulator::StepPath::Lanes);
    shake(sim, config, rest, head, 60, 80);
    return sim.positionsHead();
  };
  const std::vector<Vec3> reference = run(1, false);
  for (int threads : {1, 2, 3})
    for (bool with_reset : {false, true}) {
      if (threads == 1 && !with_reset) continue;
      const std::vector<Vec3> other = run(threads, with_reset);
      ASSERT_EQ(other.size(), reference.size());
      EXPECT_EQ(0, std::memcmp(other.data(), reference.data(), other.size() * sizeof(Vec3)))
          << threads << " threads, reset " << with_reset;
    }
  // The hair after the switches: finite, every segment at its styled length.
  std::size_t offset = 0;
  for (const Strip& st : style.strips) {
    for (int r = 1; r < st.rows; ++r)
      for (int c = 0; c < st.columns; ++c) {
        const Vec3& p = reference[offset + static_cast<std::size_t>(st.index(r, c))];
        const Vec3& q = reference[offset + static_cast<std::size_t>(st.index(r - 1, c))];
        const double styled = (st.point(r, c) - st.point(r - 1, c)).norm();
        ASSERT_TRUE(p.allFinite());
        EXPECT_NEAR((p - q).norm(), styled, 1e-9 * styled);
      }
    offset += static_cast<std::size_t>(st.pointCount());
  }
}

TEST(SimulatorTest, SetThreadsTakesOneToSixtyFour) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Simulator sim(loadHairstyle(config.hairstyle_file), config.physics, config.bodies);
  EXPECT_EQ(sim.threads(), 1);
  sim.setThreads(2);
  EXPECT_EQ(sim.threads(), 2);
  for (int bad : {0, -1, 65}) {
    try {
      sim.setThreads(bad);
      ADD_FAILURE() << "setThreads(" << bad << ") accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("got " + std::to_string(bad)), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(sim.threads(), 2);  // a refused count changes nothing
  sim.setThreads(1);
  EXPECT_EQ(sim.threads(), 1);
  // A moved simulator (its helpers go with the state) steps on as one never moved: 600 generated strips (300
  // blocks: the helper sweeps) in a shake, 10 substeps before the move and 20 after it on 2 threads.
  const Iso3 rest = headRest();
  const Hairstyle style = generatedHairstyle(config, 600);
  HeadMotionEstimator head_a, head_b;
  head_a.reset(rest);
  head_b.reset(rest);
  Simulator before(style, config.physics, config.bodies), twin(style, config.physics, config.bodies);
  shake(before, config, rest, head_a, 0, 10);
  shake(twin, config, rest, head_b, 0, 10);
  Simulator moved(std::move(before));
  moved.setThreads(2);
  twin.setThreads(2);
  shake(moved, config, rest, head_a, 10, 30);
  shake(twin, config, rest, head_b, 10, 30);
  ASSERT_EQ(moved.positionsHead().size(), twin.positionsHead().size());
  EXPECT_EQ(0, std::memcmp(moved.positionsHead().data(), twin.positionsHead().data(),
                           twin.positionsHead().size() * sizeof(Vec3)));
  EXPECT_EQ(moved.stepCount(), 30);
  // The shake moved the hair (the comparison is not of two still states).
  EXPECT_GT(maxDistance(twin.positionsHead(), test::styledPoints(style)), 1e-3);
}

TEST(SimulatorTest, LanePathFollowsTheExactStep) {
  // The lanes take the exact step's decisions (which strips the constraints move, in the same order), so the
  // two differ only by rounding (operation order; atan2 against the lanes' rational approximation, both
  // within 2 ulp): below 1e-8 m after 40 substeps of a slow head turn in wind with strips against the bodies
  // (the jittering ones amplify rounding about tenfold per 10 substeps, so longer runs drift apart as any two
  // builds would).
  const std::vector<Vec3> lanes = runPath(Simulator::StepPath::Lanes, 40, 1.0 / 3.0);
  const std::vector<Vec3> exact = runPath(Simulator::StepPath::Exact, 40, 1.0 / 3.0);
  ASSERT_EQ(lanes.size(), exact.size());
  EXPECT_LT(maxDistance(lanes, exact), 1e-8);
  // Under violent input neither path leaves a control point inside a body.
  double pen_lanes = 1.0, pen_exact = 1.0;
  runPath(Simulator::StepPath::Lanes, 240, 1.0, nullptr, &pen_lanes);
  runPath(Simulator::StepPath::Exact, 240, 1.0, nullptr, &pen_exact);
  EXPECT_EQ(pen_lanes, 0.0);
  EXPECT_EQ(pen_exact, 0.0);
}

TEST(SimulatorTest, FreeStripsNeverNeedTheExactStep) {
  // No body, no spring: nothing for the exact step to do, every strip is committed from the lanes, and the
  // result is the exact step's within rounding after a second of swinging.
  const PhysicsParameters p = withoutSprings();
  const Hairstyle style = test::hangingStrip(3, 6, 0.05, 0.7);
  const Vec3 wind(0.0, 3.0, 0.0);
  long exact_lanes = -1, exact_exact = -1;
  const std::vector<Vec3> a = runInWind(style, p, Simulator::StepPath::Lanes, wind, 240, &exact_lanes);
  const std::vector<Vec3> b = runInWind(style, p, Simulator::StepPath::Exact, wind, 240, &exact_exact);
  EXPECT_EQ(exact_lanes, 0);
  EXPECT_EQ(exact_exact, 240);
  EXPECT_LT(maxDistance(a, b), 1e-9);
}

TEST(SimulatorTest, TheBendLimitActsAlikeOnEveryPath) {
  // A bend limit of 0.2 rad and a strong side wind, no body, no spring: the free steps bend over the limit,
  // the lanes flag those points (kPointBend) and the exact step limits the lanes' own free directions, as the
  // Exact path limits its own. The two follow each other within rounding after a second, and the limit
  // acted: with the default limit the strip ends centimetres away, and the root segments (whose rest
  // direction is their styled one, without rest compensation) lie at the limit, not beyond it.
  PhysicsParameters p = withoutSprings();
  p.compensate_rest_angles = false;
  const Hairstyle style = test::hangingStrip(2, 6, 0.05, 0.3);
  const Vec3 wind(0.0, 12.0, 0.0);
  PhysicsParameters limited = p;
  limited.max_bend = 0.2;
  long exact_lanes = 0, exact_exact = 0, exact_free = 0;
  const std::vector<Vec3> lanes =
      runInWind(style, limited, Simulator::StepPath::Lanes, wind, 240, &exact_lanes);
  const std::vector<Vec3> exact =
      runInWind(style, limited, Simulator::StepPath::Exact, wind, 240, &exact_exact);
  const std::vector<Vec3> free = runInWind(style, p, Simulator::StepPath::Lanes, wind, 240, &exact_free);
  for (const Vec3& x : lanes) EXPECT_TRUE(x.allFinite());
  EXPECT_GT(exact_lanes, 0);  // the bend flags sent the strip to the exact step
  EXPECT_EQ(exact_free, 0);   // nothing else does
  EXPECT_LT(maxDistance(lanes, exact), 1e-9);
  EXPECT_GT(maxDistance(lanes, free), 0.01);
  const std::vector<Vec3>& styled = style.strips[0].points;
  for (const std::vector<Vec3>* run : {&lanes, &exact, &free})
    for (std::size_t c = 0; c < 2; ++c) {
      const Vec3 rest = (styled[c + 2] - styled[c]).normalized();
      const Vec3 now = ((*run)[c + 2] - (*run)[c]).normalized();
      const double bend = test::angleBetween(rest, now);
      if (run == &free) {
        EXPECT_GT(bend, 0.3) << "column " << c;  // what the wind does without the limit
      } else {
        EXPECT_LE(bend, limited.max_bend + 1e-9) << "column " << c;
        EXPECT_GT(bend, limited.max_bend - 0.01) << "column " << c;
      }
    }
}

TEST(SimulatorTest, LanePathTakesTurbulenceAndMixedMargins) {
  // Turbulence is evaluated lane by lane at the segment midpoints (world points), and a block of chains
  // whose strips differ in thickness margin (so see differently inflated bodies) goes to the exact step
  // whole. The default hairstyle with every other strip's margin doubled, the bodies, a turbulence event:
  // the lanes follow the exact step within rounding (1e-8 m over 40 substeps, as above), the mixed blocks
  // reach the exact step, and nothing ends inside a body.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Hairstyle style = loadHairstyle(config.hairstyle_file);
  // Blocks of 4 chains are 2 strips of 2 columns: strips 1, 5, 9, ... doubled make blocks 0, 2, 4, ... mixed.
  std::size_t mixed_strips = 0;
  for (std::size_t i = 1; i < style.strips.size(); i += 4) {
    style.strips[i].thickness_margin *= 2.0;
    mixed_strips += 2;
  }
  EventSchedule events;
  Event turbulence;
  turbulence.type = EventType::Turbulence;
  turbulence.intensity = 2.0;
  turbulence.seed = 3;
  events.add(turbulence);
  auto run = [&](Simulator::StepPath path, long* exact) {
    Simulator sim(style, config.physics, config.bodies);
    sim.setStepPath(path);
    Iso3 rest = Iso3::Identity();
    rest.translation() = Vec3(0.0, 0.0, 1.6);
    HeadMotionEstimator head;
    head.reset(rest);
    *exact = 0;
    double penetration = 0.0;
    for (int i = 1; i <= 40; ++i) {
      const EventSample sample = events.sample(i * sim.parameters().substep, sim.parameters().gravity);
      StepInputs in;
      in.head = head.update(rest, sim.parameters().substep);
      in.wind = sample.wind + Vec3(1.0, 0.0, 0.0);
      in.turbulence = &sample.turbulence;
      for (const Body& b : config.bodies)
        in.body_frames.push_back(b.frame == config.head_frame ? rest : Iso3::Identity());
      sim.step(in);
      *exact += sim.exactStripCount();
      penetration = std::max(penetration, sim.maxPenetration());
      penetration =
          std::max(penetration, test::deepestInside(sim.positionsHead(), sim.stripOffsets(), sim.hairstyle(),
                                                    config.bodies, rest, in.body_frames));
    }
    EXPECT_EQ(penetration, 0.0);
    return sim.positionsHead();
  };
  long exact_lanes = 0, exact_exact = 0;
  const std::vector<Vec3> a = run(Simulator::StepPath::Lanes, &exact_lanes);
  const std::vector<Vec3> b = run(Simulator::StepPath::Exact, &exact_exact);
  double worst = 0.0, moved = 0.0;
  std::size_t k = 0;
  for (const Strip& s : style.strips)
    for (const Vec3& p : s.points) {
      worst = std::max(worst, (a[k] - b[k]).norm());
      moved = std::max(moved, (a[k] - p).norm());
      ++k;
    }
  EXPECT_LT(worst, 1e-8);
  EXPECT_GT(moved, 1e-3);  // the turbulence moved the hair
  EXPECT_EQ(exact_exact, 40 * static_cast<long>(style.strips.size()));
  EXPECT_GE(exact_lanes, 40 * static_cast<long>(mixed_strips));  // the mixed blocks, every substep
  EXPECT_LT(exact_lanes,
            exact_exact - 40 * static_cast<long>(style.strips.size()) / 4);  // lanes for the rest
}

TEST(SimulatorTest, RejectsBadParametersAndShapes) {
  PhysicsParameters p;
  p.substep = -1.0;
  EXPECT_NE(test::errorOf([&] { Simulator(test::hangingStrip(2, 4, 0.05, 0.0), p); }).find("substep"),
            std::string::npos);
  p = PhysicsParameters();
  p.hinge_stiffness = std::nan("");
  EXPECT_NE(test::errorOf([&] { Simulator(test::hangingStrip(2, 4, 0.05, 0.0), p); }).find("hinge_stiffness"),
            std::string::npos);
  Simulator sim(test::hangingStrip(2, 4, 0.05, 0.0), PhysicsParameters());
  EXPECT_NE(test::errorOf([&] { sim.setShape(std::vector<Vec3>(3)); }).find("3 points"), std::string::npos);
  // A non-finite point is named and changes nothing.
  const std::vector<Vec3> before = sim.positionsHead();
  std::vector<Vec3> shape = before;
  shape[5].y() = std::numeric_limits<double>::infinity();
  EXPECT_NE(test::errorOf([&] { sim.setShape(shape); }).find("point 5 is not finite"), std::string::npos);
  EXPECT_EQ(0, std::memcmp(before.data(), sim.positionsHead().data(), before.size() * sizeof(Vec3)));
  // A hairstyle without strips.
  EXPECT_NE(test::errorOf([&] { Simulator(Hairstyle(), PhysicsParameters()); }).find("has no strips"),
            std::string::npos);
}

TEST(SimulatorTest, StepRefusesNonFiniteInputsAndKeepsTheState) {
  // Each input of a substep made non-finite in turn: step() names it and takes no substep (the state's bits
  // and the step count stay); the next good substep gives the bits of a run that never saw the bad ones.
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle style = loadHairstyle(config.hairstyle_file);
  const Iso3 rest = headRest();
  Simulator sim(style, config.physics, config.bodies), twin(style, config.physics, config.bodies);
  HeadMotionEstimator head, head_twin;
  head.reset(rest);
  head_twin.reset(rest);
  shake(sim, config, rest, head, 0, 20);
  shake(twin, config, rest, head_twin, 0, 20);
  const StepInputs good = shakeInputs(config, rest, 20, 1.0, head, sim.parameters().substep);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Vec3 up_inf(0.0, 0.0, -inf);
  const std::vector<std::pair<std::string, std::function<void(StepInputs&)>>> cases = {
      {"head.pose", [&](StepInputs& in) { in.head.pose.translation().x() = nan; }},
      {"head.linear_velocity is (0, inf, 0)",
       [&](StepInputs& in) { in.head.linear_velocity = Vec3(0, inf, 0); }},
      {"head.linear_acceleration", [&](StepInputs& in) { in.head.linear_acceleration.z() = nan; }},
      {"head.angular_velocity", [&](StepInputs& in) { in.head.angular_velocity.x() = -inf; }},
      {"head.angular_acceleration", [&](StepInputs& in) { in.head.angular_acceleration.y() = nan; }},
      {"wind is (nan, 1, 0)", [&](StepInputs& in) { in.wind.x() = nan; }},
      {"gravity is (0, 0, -inf)", [&](StepInputs& in) { in.gravity = &up_inf; }},
      {"body_frames[2]", [&](StepInputs& in) { in.body_frames[2].linear()(1, 1) = nan; }},
  };
  const std::vector<Vec3> before = sim.positionsHead();
  for (const auto& c : cases) {
    StepInputs bad = good;
    c.second(bad);
    EXPECT_NE(test::errorOf([&] { sim.step(bad); }).find(c.first), std::string::npos) << c.first;
    EXPECT_EQ(sim.stepCount(), 20);
    EXPECT_EQ(0, std::memcmp(before.data(), sim.positionsHead().data(), before.size() * sizeof(Vec3)))
        << c.first;
  }
  sim.step(good);
  shake(twin, config, rest, head_twin, 20, 21);
  EXPECT_EQ(
      0, std::memcmp(twin.positionsHead().data(), sim.positionsHead().data(), before.size() * sizeof(Vec3)));
}

TEST(SimulatorTest, EveryBadParameterIsNamedWithItsValue) {
  // PhysicsParameters::validate (the constructor, and setParameters, which keeps the old set): a value just
  // outside each rule, or a NaN or infinity, named with the key and the value ("PhysicsParameters: key:
  // value ..."); the last good value at that edge passes.
  struct Case {
    const char* key;
    std::function<void(PhysicsParameters&, double)> set;
    double bad, edge;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto substep = [](PhysicsParameters& p, double v) { p.substep = v; };
  auto max_angle_step = [](PhysicsParameters& p, double v) { p.max_angle_step = v; };
  auto spring_stiffness = [](PhysicsParameters& p, double v) { p.spring_stiffness = v; };
  auto proximity = [](PhysicsParameters& p, double v) { p.spring_proximity_factor = v; };
  auto radius = [](PhysicsParameters& p, double v) { p.spring_radius = v; };
  auto max_pairs = [](PhysicsParameters& p, double v) { p.spring_max_pairs = static_cast<int>(v); };
  auto max_bend = [](PhysicsParameters& p, double v) { p.max_bend = v; };
  const std::vector<Case> cases = {
      {"substep", substep, 0.051, 0.05},
      {"substep", substep, 0.0, 1e-6},
      {"gravity", [](PhysicsParameters& p, double v) { p.gravity.z() = v; }, nan, -100.0},
      {"linear_density", [](PhysicsParameters& p, double v) { p.linear_density = v; }, 0.0, 1e-6},
      {"hinge_stiffness", [](PhysicsParameters& p, double v) { p.hinge_stiffness = v; }, -1e-9, 0.0},
      {"hinge_damping", [](PhysicsParameters& p, double v) { p.hinge_damping = v; }, -1e-9, 0.0},
      {"air_drag", [](PhysicsParameters& p, double v) { p.air_drag = v; }, inf, 100.0},
      {"max_angle_step", max_angle_step, 1.51, 1.5},
      {"max_angle_step", max_angle_step, 0.0, 1e-3},
      {"collision_stiffness", [](PhysicsParameters& p, double v) { p.collision_stiffness = v; }, -1.0, 0.0},
      {"collision_damping", [](PhysicsParameters& p, double v) { p.collision_damping = v; }, -1.0, 0.0},
      {"spring_stiffness", spring_stiffness, -1.0, 0.0},
      {"spring_stiffness", spring_stiffness, nan, 1.0},
      {"spring_proximity_factor", proximity, 1.01, 1.0},
      {"spring_proximity_factor", proximity, 0.0, 0.1},
      {"spring_far_factor", [](PhysicsParameters& p, double v) { p.spring_far_factor = v; }, 0.99, 1.0},
      {"spring_contact_fraction", [](PhysicsParameters& p, double v) { p.spring_contact_fraction = v; },
       0.009, 0.01},
      {"spring_radius", radius, 0.51, 0.5},
      {"spring_radius", radius, -0.01, 0.0},
      {"spring_max_pairs", max_pairs, 17.0, 16.0},
      {"spring_max_pairs", max_pairs, -1.0, 0.0},
      {"max_bend", max_bend, 3.01, 3.0},
      {"max_bend", max_bend, 0.0, 0.01},
  };
  const Hairstyle style = test::hangingStrip(2, 4, 0.05, 0.0);
  Simulator sim(style, PhysicsParameters());
  for (const Case& c : cases) {
    PhysicsParameters p;
    c.set(p, c.bad);
    const bool gravity = std::string(c.key) == "gravity";  // named by its norm
    const std::string expected = std::string("PhysicsParameters: ") + c.key + ": " +
                                 formatDouble(gravity ? p.gravity.norm() : c.bad) + " ";
    const std::string at_start = test::errorOf([&] { Simulator(style, p); });
    EXPECT_NE(at_start.find(expected), std::string::npos) << "expected '" << expected << "' in: " << at_start;
    const std::string live = test::errorOf([&] { sim.setParameters(p); });
    EXPECT_NE(live.find(expected), std::string::npos) << "expected '" << expected << "' in: " << live;
    PhysicsParameters good;
    c.set(good, c.edge);
    EXPECT_NO_THROW(good.validate()) << c.key << " = " << c.edge;
  }
  // Every refused set left the defaults in place.
  EXPECT_EQ(sim.parameters().max_bend, PhysicsParameters().max_bend);
  EXPECT_EQ(sim.parameters().substep, PhysicsParameters().substep);
}

TEST(SimulatorTest, SetParametersBetweenSubstepsReachesTheNewWindEquilibrium) {
  // tan(theta) = f / (rho g) with f = air_drag * v_air: doubling air_drag mid-run moves the strip from
  // the first equilibrium angle to the second one, state carried over (no reset).
  PhysicsParameters p = bare();
  p.air_drag = 0.01;
  p.hinge_damping = 2e-6;
  const double wind = 3.0;
  Simulator sim(test::hangingStrip(2, 5, 0.05, 0.0), p);
  StepInputs in;
  in.wind = Vec3(0.0, wind, 0.0);
  auto meanAngle = [&] {
    const std::vector<Vec3>& x = sim.positionsHead();
    double sum = 0.0;
    for (std::size_t i = 2; i < x.size(); ++i)
      sum += std::atan2((x[i] - x[i - 2]).y(), -(x[i] - x[i - 2]).z());
    return sum / static_cast<double>(x.size() - 2);
  };
  for (int i = 0; i < 240 * 20; ++i) sim.step(in);
  EXPECT_NEAR(meanAngle(), std::atan(0.01 * wind / (p.linear_density * 9.81)), 0.1 * kPi / 180.0);
  const long steps = sim.stepCount();
  p.air_drag = 0.02;
  sim.setParameters(p);
  EXPECT_EQ(sim.stepCount(), steps);  // state kept
  EXPECT_EQ(sim.parameters().air_drag, 0.02);
  for (int i = 0; i < 240 * 20; ++i) sim.step(in);
  EXPECT_NEAR(meanAngle(), std::atan(0.02 * wind / (p.linear_density * 9.81)), 0.1 * kPi / 180.0);
}

TEST(SimulatorTest, SetParametersWithTheSameValuesChangesNothing) {
  auto run = [](bool swap) {
    Simulator sim = defaultSimulator();
    HeadMotionEstimator head;
    head.reset(Iso3::Identity());
    for (int i = 1; i <= 240; ++i) {
      if (swap && i % 7 == 0) sim.setParameters(PhysicsParameters(sim.parameters()));
      Iso3 pose = Iso3::Identity();
      pose.linear() = rotationFromRpy(Vec3(0.0, 0.0, 0.8 * std::sin(i * 0.03)));
      StepInputs in;
      in.head = head.update(pose, sim.parameters().substep);
      sim.step(in);
    }
    return sim.positionsHead();
  };
  const std::vector<Vec3> a = run(false), b = run(true);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)));
}

TEST(SimulatorTest, SpringForcesComputedAfreshGiveTheSweepsBits) {
  // On the Lanes paths the sweeps add (11) as they find each pair's final length, strip by strip in the sweep
  // order; after setParameters (or reset, setShape, the Exact path) computeSpringForces computes them from
  // the points. Both must sum every point's forces in the same order: a run that forces the second way every
  // few substeps gives the bits of one that never does. 600 generated strips in a shake: hair pressed on
  // hair, where a point has three pairs or more outside their dead band, so that the order shows in the bits
  // (with computeSpringForces summing in pair order instead, this test fails; 2026-11-29).
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Iso3 rest = headRest();
  const Hairstyle style = generatedHairstyle(config, 600);
  auto run = [&](int threads, bool afresh) {
    Simulator sim(style, config.physics, config.bodies);
    sim.setThreads(threads);
    HeadMotionEstimator head;
    head.reset(rest);
    for (int i = 0; i < 120; ++i) {
      const bool set = afresh && i % 3 == 0;
      if (set) sim.setParameters(PhysicsParameters(sim.parameters()));
      sim.step(shakeInputs(config, rest, i, 1.0, head, sim.parameters().substep));
      // Which way ran: afresh on the first substep and after setParameters, else the sweeps' (so that both
      // ways are compared here, not one with itself).
      EXPECT_EQ(i > 0 && !set, sim.springForcesFromSweeps())
          << "substep " << i << ", " << threads << " threads";
    }
    return sim.positionsHead();
  };
  const std::vector<Vec3> reference = run(1, false);
  for (int threads : {1, 2}) {
    const std::vector<Vec3> other = run(threads, true);
    ASSERT_EQ(other.size(), reference.size());
    EXPECT_EQ(0, std::memcmp(other.data(), reference.data(), other.size() * sizeof(Vec3)))
        << threads << " threads";
  }
  // The other ways to the fresh computation: the Exact path (no sweeps of the lanes), reset and setShape.
  Simulator sim(style, config.physics, config.bodies);
  HeadMotionEstimator head;
  head.reset(rest);
  int i = 0;
  auto step = [&] {
    shake(sim, config, rest, head, i, i + 1);
    ++i;
  };
  step();
  step();
  EXPECT_TRUE(sim.springForcesFromSweeps());
  sim.setStepPath(Simulator::StepPath::Exact);
  step();  // (the sweeps of the substep before still count)
  EXPECT_TRUE(sim.springForcesFromSweeps());
  step();
  EXPECT_FALSE(sim.springForcesFromSweeps());
  sim.setStepPath(Simulator::StepPath::Lanes);
  step();
  EXPECT_FALSE(sim.springForcesFromSweeps());
  step();
  EXPECT_TRUE(sim.springForcesFromSweeps());
  sim.reset();
  step();
  EXPECT_FALSE(sim.springForcesFromSweeps());
  step();
  sim.setShape(sim.positionsHead());
  step();
  EXPECT_FALSE(sim.springForcesFromSweeps());
}

TEST(SimulatorTest, SetParametersStiffnessChangesTheHingeFrequency) {
  // Undamped hinge: omega = sqrt(k / I). Quadrupling k between two substeps doubles it.
  const double d = 0.05, rho = 0.01;
  const double I = rho * d * d * d / 3.0;
  PhysicsParameters p = bare();
  p.gravity.setZero();
  p.hinge_stiffness = 1e-4;
  Simulator sim(test::hangingStrip(2, 4, d, 0.0), p);
  const std::vector<Vec3> rest = sim.positionsHead();
  auto measuredOmega = [&] {
    // Displace the whole chain by 0.1 rad about +x, then time the upward zero crossings.
    std::vector<Vec3> shape = rest;
    const Mat3 turn = Eigen::AngleAxisd(0.1, Vec3::UnitX()).toRotationMatrix();
    for (std::size_t i = 2; i < shape.size(); ++i) shape[i] = shape[i % 2] + turn * (shape[i] - shape[i % 2]);
    sim.setShape(shape);
    std::vector<double> angle;
    StepInputs in;
    for (int i = 0; i < 240 * 2; ++i) {
      sim.step(in);
      angle.push_back(firstAngle(sim));
    }
    const std::vector<double> up = upCrossings(angle, p.substep);
    if (up.size() < 3) return 0.0;
    return 2 * kPi * (up.size() - 1) / (up.back() - up.front());
  };
  EXPECT_NEAR(measuredOmega(), std::sqrt(1e-4 / I), 0.02 * std::sqrt(1e-4 / I));
  p.hinge_stiffness = 4e-4;
  sim.setParameters(p);
  EXPECT_NEAR(measuredOmega(), std::sqrt(4e-4 / I), 0.02 * std::sqrt(4e-4 / I));
}

TEST(SimulatorTest, SetParametersRejectsBadSetsAndKeepsTheOldOne) {
  Simulator sim = defaultSimulator();
  const std::size_t springs = sim.springs().size();
  PhysicsParameters p = sim.parameters();
  p.spring_far_factor = 0.5;
  EXPECT_NE(test::errorOf([&] { sim.setParameters(p); }).find("spring_far_factor"), std::string::npos);
  EXPECT_EQ(sim.parameters().spring_far_factor, 1.5);
  for (const double bad : {0.0, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    p = sim.parameters();
    p.spring_contact_fraction = bad;
    const std::string m = test::errorOf([&] { sim.setParameters(p); });
    EXPECT_NE(m.find("spring_contact_fraction"), std::string::npos) << m;
    EXPECT_NE(m.find("must be in [0.01, 1]"), std::string::npos) << m;
    EXPECT_EQ(sim.parameters().spring_contact_fraction, 0.8);
  }
  p = sim.parameters();
  p.substep = 1.0 / 120.0;
  EXPECT_NE(test::errorOf([&] { sim.setParameters(p); }).find("substep"), std::string::npos);
  EXPECT_EQ(sim.parameters().substep, 1.0 / 240.0);
  // Pairing keys rebuild the springs.
  p = sim.parameters();
  p.springs_between_strips = false;
  sim.setParameters(p);
  EXPECT_LT(sim.springs().size(), springs);
  for (const SpringPair& pair : sim.springs()) EXPECT_TRUE(pair.within_strip);
  p.springs_between_strips = true;
  sim.setParameters(p);
  EXPECT_EQ(sim.springs().size(), springs);
}

TEST(SimulatorTest, SetParametersWithoutSpringsDropsTheirForce) {
  // Springs turned off between two substeps act no more: the next substep is the one of a Simulator built
  // without springs, bit for bit. The shape spreads the strip's two columns to 3x their rest width below
  // the root, beyond the far factor (1.5), so the springs pull in the substep before.
  PhysicsParameters on = bare();
  on.springs_within_strips = true;
  on.springs_between_strips = false;
  PhysicsParameters off = on;
  off.springs_within_strips = false;
  const Hairstyle style = test::hangingStrip(2, 5, 0.05, 0.0);
  std::vector<Vec3> shape = style.strips[0].points;
  for (int r = 1; r < 5; ++r)
    for (int c = 0; c < 2; ++c) shape[static_cast<std::size_t>(2 * r + c)].y() *= 1.0 + 2.0 * r / 4.0;
  StepInputs in;
  Simulator toggled(style, on);
  ASSERT_FALSE(toggled.springs().empty());
  toggled.setShape(shape);
  toggled.step(in);
  toggled.setParameters(off);
  ASSERT_TRUE(toggled.springs().empty());
  // Nor do their measures stay: those of a Simulator without springs.
  EXPECT_EQ(toggled.minSpringRatio(true), 1.0);
  EXPECT_EQ(toggled.maxSpringRatio(true), 1.0);
  EXPECT_EQ(toggled.minStripGap(), 0.0);
  toggled.setShape(shape);
  toggled.step(in);
  Simulator without(style, off);
  without.setShape(shape);
  without.step(in);
  const std::vector<Vec3>& a = toggled.positionsHead();
  const std::vector<Vec3>& b = without.positionsHead();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)));
  // The springs had moved the points: with them the same substep ends elsewhere.
  Simulator with(style, on);
  with.setShape(shape);
  with.step(in);
  EXPECT_GT((with.positionsHead()[9] - b[9]).norm(), 1e-6);
}

TEST(SimulatorTest, SpringRatiosAndGapAreThoseOfTheStateTheSubstepBegan) {
  // minSpringRatio, maxSpringRatio, minStripGap against the pairs measured directly on the positions the last
  // substep began from (the default hairstyle shaken: its strips' widths move), on every step path. Before
  // the last substep setShape spreads the hair sideways: the pairs' lengths that the lanes keep for the next
  // substep's scan must not outlive it.
  for (Simulator::StepPath path :
       {Simulator::StepPath::Lanes, Simulator::StepPath::LanesBaseline, Simulator::StepPath::Exact}) {
    Simulator sim = defaultSimulator();
    sim.setStepPath(path);
    HeadMotionEstimator head;
    head.reset(Iso3::Identity());
    std::vector<Vec3> before;
    for (int i = 1; i <= 120; ++i) {
      Iso3 pose = Iso3::Identity();
      pose.linear() = rotationFromRpy(Vec3(0.0, 0.0, 1.5 * std::sin(i * 0.08)));
      StepInputs in;
      in.head = head.update(pose, sim.parameters().substep);
      if (i == 120) {
        std::vector<Vec3> spread = sim.positionsHead();
        for (Vec3& q : spread) q.y() *= 1.25;
        sim.setShape(spread);
      }
      before = sim.positionsHead();
      sim.step(in);
    }
    double min_ratio[2] = {1e300, 1e300}, max_ratio[2] = {0.0, 0.0}, min_gap = 1e300;
    for (const SpringPair& p : sim.springs()) {
      const double length =
          (before[static_cast<std::size_t>(p.b)] - before[static_cast<std::size_t>(p.a)]).norm();
      const int w = p.within_strip ? 1 : 0;
      min_ratio[w] = std::min(min_ratio[w], length / p.rest);
      max_ratio[w] = std::max(max_ratio[w], length / p.rest);
      if (!p.within_strip) min_gap = std::min(min_gap, length);
    }
    ASSERT_LT(min_ratio[1], max_ratio[1]);
    ASSERT_LT(min_gap, 1e300);
    for (int w = 0; w < 2; ++w) {
      EXPECT_NEAR(sim.minSpringRatio(w == 1), min_ratio[w], 1e-12 * min_ratio[w]);
      EXPECT_NEAR(sim.maxSpringRatio(w == 1), max_ratio[w], 1e-12 * max_ratio[w]);
    }
    EXPECT_NEAR(sim.minStripGap(), min_gap, 1e-12 * min_gap);
  }
  // Without pairs: ratios 1, gap 0.
  PhysicsParameters p = bare();
  p.springs_within_strips = p.springs_between_strips = false;
  Simulator none(test::hangingStrip(2, 5, 0.05, 0.3), p);
  none.step(StepInputs());
  EXPECT_EQ(none.minSpringRatio(true), 1.0);
  EXPECT_EQ(none.maxSpringRatio(false), 1.0);
  EXPECT_EQ(none.minStripGap(), 0.0);
}

TEST(SimulatorTest, InertiaFloorOnlyBitesForUnstableCombinations) {
  // The explicit step (7) of a hinge of stiffness k_eff on a segment of inertia I is stable for
  // k_eff dt^2 / I < 1 (omega dt < 2 in the undamped limit); the floor keeps it at or below 0.5. k_eff is the
  // hinge plus the linear springs that can act at the lever d/2: the collision constraint and, with the
  // default parameters, two within-strip and spring_max_pairs between-strip springs.
  const PhysicsParameters p;  // the defaults
  const double dt = p.substep;
  auto stiffness = [&](double d) {
    return p.hinge_stiffness +
           (p.collision_stiffness + (2 + p.spring_max_pairs) * p.spring_stiffness) * 0.25 * d * d;
  };
  // Segments of 5 cm (the hairstyles' scale): the rod's own inertia about its end, rho d^3 / 3.
  {
    const double d = 0.05, rod = p.linear_density * d * d * d / 3.0;
    const Simulator sim(test::hangingStrip(2, 5, d, 0.3), p);
    for (int k = 2; k < sim.controlPointCount(); ++k) EXPECT_NEAR(sim.inertia(k), rod, 1e-12 * rod) << k;
    EXPECT_LT(stiffness(d) * dt * dt / rod, 0.5);
  }
  // Segments of 2 mm: the rod's inertia would make k_eff dt^2 / I = 265 (omega dt = 16); the floor raises it.
  const double d = 0.002, rod = p.linear_density * d * d * d / 3.0;
  ASSERT_GT(stiffness(d) * dt * dt / rod, 10.0);
  PhysicsParameters still = p;
  still.gravity.setZero();  // the styled shape is then the equilibrium
  Simulator sim(test::hangingStrip(2, 5, d, 0.3), still);
  for (int k = 2; k < sim.controlPointCount(); ++k) {
    EXPECT_GT(sim.inertia(k), 100.0 * rod) << k;
    EXPECT_LE(stiffness(d) * dt * dt / sim.inertia(k), 0.5 + 1e-12) << k;
  }
  // And the step stays stable: bent 0.5 rad away from its styled shape, the hair swings back and settles.
  std::vector<Vec3> styled = sim.hairstyle().strips[0].points;
  std::vector<Vec3> bent = styled;
  for (std::size_t k = 2; k < bent.size(); ++k) {
    const int row = static_cast<int>(k / 2);
    bent[k] = bent[k % 2] + row * d * Vec3(0.0, std::sin(0.8), -std::cos(0.8));
  }
  sim.setShape(bent);
  const double start = maxDistance(sim.positionsHead(), styled);
  ASSERT_GT(start, 1e-3);
  for (int i = 0; i < 480; ++i) {
    sim.step(StepInputs{});
    ASSERT_LE(maxDistance(sim.positionsHead(), styled), 1.5 * start) << "substep " << i;
  }
  EXPECT_LT(maxDistance(sim.positionsHead(), styled), 0.01 * start);
}

}  // namespace
}  // namespace hair_sim

/// The offline runner in-process and as the hair_sim_offline command.
#include "hair_sim/tools/OfflineRunner.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "TestUtil.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"

namespace hair_sim {
namespace {

using Frames = std::map<long, std::vector<Vec3>>;  // key: frame time in microseconds

Frames runAt(double rate, double duration = 1.0) {
  SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  Scenario scenario = Scenario::load(test::repoPath("config/scenarios/head_shake.yaml"));
  scenario.output_rate = rate;
  scenario.duration = duration;
  OfflineRunner runner(config, loadHairstyle(config.hairstyle_file), scenario);
  Frames frames;
  runner.run([&](const OutputFrame& f) { frames[std::lround(f.t * 1e6)] = *f.points_world; });
  return frames;
}

TEST(OfflineRunnerTest, OutputRateDoesNotChangeTheResults) {
  const Frames a = runAt(30.0), b = runAt(60.0);
  EXPECT_EQ(a.size(), 31u);
  EXPECT_EQ(b.size(), 61u);
  int shared = 0;
  for (const auto& [t, points] : a) {
    const auto it = b.find(t);
    ASSERT_NE(it, b.end()) << t;
    ASSERT_EQ(points.size(), it->second.size());
    EXPECT_EQ(0, std::memcmp(points.data(), it->second.data(), points.size() * sizeof(Vec3))) << "t = " << t;
    ++shared;
  }
  EXPECT_EQ(shared, 31);
  // The head shake really moved the hair (the comparison above is not between still frames).
  EXPECT_GT((a.rbegin()->second.back() - a.begin()->second.back()).norm(), 1e-3);
}

TEST(OfflineRunnerTest, TwoRunsAreBitIdentical) {
  const Frames a = runAt(30.0), b = runAt(30.0);
  for (const auto& [t, points] : a)
    EXPECT_EQ(0, std::memcmp(points.data(), b.at(t).data(), points.size() * sizeof(Vec3))) << t;
}

/// Mean of the tips (last row) of every strip, head frame, at the first and the last output frame.
struct TipMotion {
  Vec3 start, end;
  std::vector<Iso3> head_poses;  ///< one per output frame
};

TipMotion tipsOf(const Scenario& scenario) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  OfflineRunner runner(config, loadHairstyle(config.hairstyle_file), scenario);
  TipMotion m;
  auto meanTip = [&]() {
    Vec3 sum = Vec3::Zero();
    int n = 0;
    const Simulator& sim = runner.simulator();
    for (std::size_t s = 0; s < sim.hairstyle().strips.size(); ++s) {
      const Strip& strip = sim.hairstyle().strips[s];
      for (int c = 0; c < strip.columns; ++c, ++n)
        sum += sim.positionsHead()[static_cast<std::size_t>(sim.stripOffsets()[s] +
                                                            strip.index(strip.rows - 1, c))];
    }
    return Vec3(sum / n);
  };
  runner.run([&](const OutputFrame& f) {
    if (m.head_poses.empty()) m.start = meanTip();
    m.end = meanTip();
    m.head_poses.push_back(f.head_pose);
  });
  return m;
}

Scenario shipped(const std::string& name) {
  return Scenario::load(test::repoPath("config/scenarios/" + name + ".yaml"));
}

TEST(OfflineRunnerTest, WindFromBehindBlowsTheTipsForward) {
  // The head looks along +x; the gusts blow toward +x.
  const TipMotion m = tipsOf(shipped("wind_from_behind"));
  const Vec3 moved = m.end - m.start;
  EXPECT_GT(moved.x(), 0.02) << moved.transpose();
  EXPECT_GT(moved.x(), 3.0 * std::abs(moved.y())) << moved.transpose();
}

TEST(OfflineRunnerTest, SidewaysWindBlowsTheTipsSideways) {
  const TipMotion m = tipsOf(shipped("wind_sideways"));
  const Vec3 moved = m.end - m.start;
  EXPECT_GT(moved.y(), 0.02) << moved.transpose();
  EXPECT_GT(moved.y(), 3.0 * std::abs(moved.x())) << moved.transpose();
}

TEST(OfflineRunnerTest, GravityEventPointingUpLiftsTheHair) {
  Scenario s = shipped("still");
  s.duration = 3.0;
  Event up;
  up.type = EventType::Gravity;
  up.start = 0.5;
  up.ease = 0.5;
  up.vector = Vec3(0.0, 0.0, 9.81);
  s.events.push_back(up);
  const TipMotion m = tipsOf(s);
  EXPECT_GT(m.end.z() - m.start.z(), 0.05) << (m.end - m.start).transpose();
  // Without the event the hair stays where it is.
  const TipMotion still = tipsOf(shipped("still"));
  EXPECT_LT((still.end - still.start).norm(), 2e-3);
}

TEST(OfflineRunnerTest, ShakeEventTurnsTheHeadByItsAmplitudeAtItsFrequency) {
  // head_shake: shake 0.6 rad at 1.5 Hz from 0.5 s for 2 s with 0.3 s ease; frames at 30 Hz.
  const TipMotion m = tipsOf(shipped("head_shake"));
  auto yaw = [&](double t) {
    const Mat3 r = m.head_poses[static_cast<std::size_t>(std::lround(t * 30.0))].linear();
    return std::atan2(r(1, 0), r(0, 0));
  };
  // Crests a quarter period after each zero crossing, once eased in: +-0.6 rad.
  EXPECT_NEAR(yaw(0.5 + 1.25 / 1.5), 0.6, 1e-9);
  EXPECT_NEAR(yaw(0.5 + 1.75 / 1.5), -0.6, 1e-9);
  EXPECT_NEAR(yaw(0.5 + 2.25 / 1.5), 0.6, 1e-9);
  // Zero crossings every half period (1/3 s): count sign changes over the full-amplitude part.
  int crossings = 0;
  for (double t = 0.8; t + 1.0 / 30.0 <= 2.2; t += 1.0 / 30.0)
    if ((yaw(t) > 1e-9) != (yaw(t + 1.0 / 30.0) > 1e-9)) ++crossings;
  EXPECT_EQ(crossings, 5);  // zeros at 0.5 + k / 3 s: 0.83, 1.17, 1.5, 1.83, 2.17 (each counted once)
  EXPECT_NEAR(yaw(0.4), 0.0, 1e-12);
  EXPECT_NEAR(yaw(2.6), 0.0, 1e-12);
}

struct Command {
  int status;
  std::string out;
};

Command shell(const std::string& cmd) {
  Command r{0, ""};
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof(buf), p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

const std::string kBin = HAIR_SIM_OFFLINE_BIN;

TEST(OfflineRunnerTest, CommandWritesCsvPosesAndJsonSummary) {
  const std::string pts_path = test::tempPath("pts.csv"), poses_path = test::tempPath("poses.csv");
  const std::string scenario = test::writeTemp(
      "short.yaml",
      "duration: 0.5\noutput_rate: 20\nhead:\n  - {t: 0, position: [0, 0, 1.6], rpy: [0, 0, 0]}\n"
      "  - {t: 0.5, position: [0, 0.1, 1.6], rpy: [0, 0, 0.3]}\n");
  const Command c = shell(kBin + " --config " + test::repoPath("config/hair_sim.yaml") + " --scenario " +
                          scenario + " --out " + pts_path + " --poses-out " + poses_path);
  ASSERT_EQ(c.status, 0) << c.out;
  const std::string last = c.out.substr(c.out.rfind('{'));
  for (const char* key : {"\"steps\": 120", "\"control_points\"", "\"sim_seconds\": 0.5", "\"wall_seconds\"",
                          "\"ns_per_control_point_update\""})
    EXPECT_NE(last.find(key), std::string::npos) << key << " in " << last;
  std::ifstream pts(pts_path), poses(poses_path);
  std::string header;
  std::getline(pts, header);
  EXPECT_EQ(header, "t,strip,column,row,x,y,z");
  long lines = 0;
  std::string line, first;
  while (std::getline(pts, line)) {
    if (lines == 0) first = line;
    ++lines;
  }
  const int points = loadHairstyle(test::repoPath("config/hairstyles/default.yaml")).controlPointCount();
  EXPECT_EQ(lines, 11L * points);  // frames at 0, 0.05, ..., 0.5
  EXPECT_EQ(first.substr(0, 15), "0.000000,0,0,0,");
  std::getline(poses, header);
  EXPECT_EQ(header, "t,x,y,z,qx,qy,qz,qw");
  std::vector<std::string> pose_lines;
  while (std::getline(poses, line)) pose_lines.push_back(line);
  ASSERT_EQ(pose_lines.size(), 11u);
  EXPECT_EQ(pose_lines.back().substr(0, 22), "0.500000,0,0.1,1.6,0,0");
  // The summary line names every output written.
  EXPECT_NE(c.out.find("frames written to " + pts_path + ", " + poses_path + "\n"), std::string::npos)
      << c.out;
}

TEST(OfflineRunnerTest, CommandReportsBadInputAndUsage) {
  Command c = shell(kBin + " --help");
  EXPECT_EQ(c.status, 0);
  EXPECT_NE(c.out.find("--scenario"), std::string::npos);
  const std::string synopsis = c.out.substr(0, c.out.find("\n\n"));  // every flag in the synopsis
  for (const char* flag :
       {"--config", "--scenario", "--out", "--poses-out", "--mesh-out", "--bag", "--samples-across",
        "--samples-along", "--max-triangles", "--teleport-distance", "--teleport-angle"})
    EXPECT_NE(synopsis.find(flag), std::string::npos) << flag << " in " << synopsis;
  c = shell(kBin + " --config x.yaml");
  EXPECT_EQ(c.status, 2);
  EXPECT_NE(c.out.find("--scenario is required"), std::string::npos) << c.out;
  c = shell(kBin + " --bogus");
  EXPECT_EQ(c.status, 2);
  const std::string bad = test::writeTemp("bad_scenario.yaml", "duration: soon\nhead:\n  - {t: 0}\n");
  c = shell(kBin + " --config " + test::repoPath("config/hair_sim.yaml") + " --scenario " + bad +
            " --out /dev/null");
  EXPECT_EQ(c.status, 1);
  EXPECT_NE(c.out.find(bad + ": duration (line 1)"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("'soon'"), std::string::npos) << c.out;
  c = shell(kBin + " --config /nonexistent.yaml --scenario " + bad + " --out /dev/null");
  EXPECT_EQ(c.status, 1);
  EXPECT_NE(c.out.find("/nonexistent.yaml"), std::string::npos) << c.out;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

bool exists(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0;
}

/// A short scenario (duration s at 30 Hz, the head still).
std::string shortScenario(const std::string& name, double duration) {
  return test::writeTemp(name,
                         "duration: " + std::to_string(duration) +
                             "\noutput_rate: 30\nhead:\n  - {t: 0, position: [0, 0, 1.6], rpy: [0, 0, 0]}\n");
}

const std::string kConfigArg = " --config " + test::repoPath("config/hair_sim.yaml");

TEST(OfflineRunnerTest, CommandReportsAFailedBagWriteWithoutAborting) {
  // A full disk: rosbag throws from Bag::~Bag() while the first error unwinds (std::terminate before).
  const std::string scenario = shortScenario("bag_full.yaml", 0.1);
  Command c = shell(kBin + kConfigArg + " --scenario " + scenario + " --bag /dev/full");
  EXPECT_EQ(c.status, 1) << c.out;
  EXPECT_NE(c.out.find("hair_sim_offline: error: /dev/full: cannot write the bag: "), std::string::npos)
      << c.out;
  EXPECT_NE(c.out.find("No space left on device"), std::string::npos) << c.out;
  EXPECT_EQ(c.out.find("terminate"), std::string::npos) << c.out;
  // A file size limit reached mid-run: the same error, and the incomplete bag is removed.
  const std::string bag = test::tempPath("limited.bag");
  c = shell("trap '' XFSZ; ulimit -f 200; exec " + kBin + kConfigArg + " --scenario " +
            shortScenario("bag_limit.yaml", 0.5) + " --bag " + bag);
  EXPECT_EQ(c.status, 1) << c.out;
  EXPECT_NE(c.out.find("error: " + bag + ": cannot write the bag: "), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("File too large"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("removed the incomplete " + bag), std::string::npos) << c.out;
  EXPECT_FALSE(exists(bag));
}

TEST(OfflineRunnerTest, CommandWithABagAloneWritesNoPly) {
  // The bag needs meshes, and PLY files were written for them too, at "" + "/frame_00000.ply": in the
  // filesystem's root (as root), or the run failed there (as anyone else). 2026-11-29: 171 such files in /.
  std::remove("/frame_00000.ply");
  const std::string bag = test::tempPath("alone.bag");
  const Command c =
      shell(kBin + kConfigArg + " --scenario " + shortScenario("bag_alone.yaml", 0.1) + " --bag " + bag);
  EXPECT_EQ(c.status, 0) << c.out;
  EXPECT_TRUE(exists(bag));
  EXPECT_FALSE(exists("/frame_00000.ply"));
}

TEST(OfflineRunnerTest, CommandStopsAtTheFirstFailedCsvWriteAndRemovesTheFiles) {
  const std::string csv = test::tempPath("limited.csv"), poses = test::tempPath("limited_poses.csv");
  // 10 s of frames (about 16 MB of CSV) against a 100 kB limit: the first frame fails.
  const Command c = shell("trap '' XFSZ; ulimit -f 100; exec " + kBin + kConfigArg + " --scenario " +
                          shortScenario("csv_limit.yaml", 10.0) + " --out " + csv + " --poses-out " + poses);
  EXPECT_EQ(c.status, 1) << c.out;
  EXPECT_NE(c.out.find("hair_sim_offline: error: " + csv + ": cannot write: File too large"),
            std::string::npos)
      << c.out;
  EXPECT_EQ(c.out.find("\"steps\""), std::string::npos) << c.out;  // no summary: the run stopped
  EXPECT_FALSE(exists(csv));
  EXPECT_FALSE(exists(poses));
}

TEST(OfflineRunnerTest, CommandStoppedByASignalRemovesItsIncompleteOutputs) {
  // Ctrl-C (SIGINT) or SIGTERM in the middle of a 60 s scenario: the run stops between substeps, says
  // where, removes its incomplete CSV and PLY files and the folder it made, and exits 128 + the signal.
  for (const char* signal : {"INT", "TERM"}) {
    const std::string csv = test::tempPath(std::string("stopped_") + signal + ".csv");
    const std::string mesh = test::tempPath(std::string("stopped_mesh_") + signal);
    const Command c =
        shell(kBin + kConfigArg + " --scenario " + shortScenario("stopped.yaml", 60.0) + " --out " + csv +
              " --mesh-out " + mesh + " 2>&1 >/dev/null & pid=$!; for i in $(seq 200); do [ -e " + mesh +
              "/frame_00003.ply ] && break; sleep 0.05; done; kill -" + signal +
              " $pid; wait $pid; echo status=$?");
    const int expected = std::string(signal) == "INT" ? 130 : 143;
    EXPECT_NE(c.out.find("status=" + std::to_string(expected)), std::string::npos) << signal << ": " << c.out;
    EXPECT_NE(c.out.find(std::string("hair_sim_offline: ") +
                         (std::string(signal) == "INT" ? "Interrupt" : "Terminated") + " at t = "),
              std::string::npos)
        << c.out;
    EXPECT_NE(
        c.out.find(" s of the scenario's 60 s: the run stopped, and its incomplete outputs are removed"),
        std::string::npos)
        << c.out;
    EXPECT_NE(c.out.find("removed the incomplete " + csv), std::string::npos) << c.out;
    EXPECT_FALSE(exists(csv));
    EXPECT_FALSE(exists(mesh));
  }
}

TEST(OfflineRunnerTest, CommandRefusedRunLeavesTheOutputsUntouched) {
  const std::string csv = test::writeTemp("refused.csv", "old\n"),
                    poses = test::tempPath("refused_poses.csv");
  const std::string bag = test::tempPath("refused.bag"), mesh = test::tempPath("refused_mesh");
  const std::string outputs =
      " --out " + csv + " --poses-out " + poses + " --bag " + bag + " --mesh-out " + mesh;
  const std::string scenario = shortScenario("refused.yaml", 0.1);
  auto untouched = [&] {
    EXPECT_EQ(readFile(csv), "old\n");
    EXPECT_FALSE(exists(poses));
    EXPECT_FALSE(exists(bag));
    EXPECT_FALSE(exists(mesh));
  };
  // A body in a frame the offline runner does not know: named by file, key and line.
  std::string text = readFile(test::repoPath("config/hair_sim.yaml"));
  const std::string hairstyle_key = "hairstyle: hairstyles/default.yaml", neck = "{name: neck, frame: world";
  ASSERT_NE(text.find(hairstyle_key), std::string::npos);
  ASSERT_NE(text.find(neck), std::string::npos);
  text.replace(text.find(hairstyle_key), hairstyle_key.size(),
               "hairstyle: " + test::repoPath("config/hairstyles/default.yaml"));
  text.replace(text.find(neck), neck.size(), "{name: neck, frame: neck");
  const std::string config = test::writeTemp("body_frame.yaml", text);
  Command c = shell(kBin + " --config " + config + " --scenario " + scenario + outputs);
  EXPECT_EQ(c.status, 1) << c.out;
  EXPECT_NE(c.out.find("error: " + config + ": bodies[1].frame (line "), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("body 'neck' is in frame 'neck'"), std::string::npos) << c.out;
  untouched();
  // A triangle budget below the coarsest level of detail: a bad flag, exit 2.
  c = shell(kBin + kConfigArg + " --scenario " + scenario + outputs + " --max-triangles 100");
  EXPECT_EQ(c.status, 2) << c.out;
  EXPECT_NE(c.out.find("hair_sim_offline: --max-triangles: 100 is below the "), std::string::npos) << c.out;
  untouched();
  // One file given to two outputs: exit 2 (it was written interleaved before).
  c = shell(kBin + kConfigArg + " --scenario " + scenario + " --out " + csv + " --poses-out " + csv);
  EXPECT_EQ(c.status, 2) << c.out;
  EXPECT_NE(c.out.find("are the same file"), std::string::npos) << c.out;
  untouched();
  // An output that cannot be written is found before the others are opened.
  c = shell(kBin + kConfigArg + " --scenario " + scenario + " --out " + csv +
            " --bag /nonexistent_hair_sim/x.bag");
  EXPECT_EQ(c.status, 1) << c.out;
  EXPECT_NE(c.out.find("/nonexistent_hair_sim/x.bag: cannot open for writing: No such file or directory"),
            std::string::npos)
      << c.out;
  untouched();
}

TEST(OfflineRunnerTest, CommandWarnsWhenNoSubstepIsSimulated) {
  const std::string scenario = test::writeTemp(
      "no_step.yaml",
      "duration: 1\noutput_rate: 0.1\nhead:\n  - {t: 0, position: [0, 0, 1.6], rpy: [0, 0, 0]}\n");
  const Command c = shell(kBin + kConfigArg + " --scenario " + scenario + " --out /dev/null");
  EXPECT_EQ(c.status, 0) << c.out;
  EXPECT_NE(c.out.find("hair_sim_offline: warning: no substep was simulated"), std::string::npos) << c.out;
}

}  // namespace
}  // namespace hair_sim

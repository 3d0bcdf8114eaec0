/// Hairstyle model, YAML load/save and their error messages.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <limits>
#include <regex>

#include "TestUtil.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"

namespace hair_sim {
namespace {

const char* kGood =
    "format_version: 1\n"
    "scalp: {center: [0, 0, 0], rpy: [0, 0, 0], radii: [0.1, 0.1, 0.1]}\n"
    "strips:\n"
    "  - name: a\n"
    "    columns: 2\n"
    "    rows: 4\n"
    "    hair_length: 0.15\n"
    "    width: 0.02\n"
    "    thickness_margin: 0.004\n"
    "    color: [0.3, 0.2, 0.1, 1.0]\n"
    "    points: [[0, -0.01, 0.0994987437], [0, 0.01, 0.0994987437], [0, -0.01, 0.15], [0, 0.01, 0.15],\n"
    "             [0, -0.01, 0.2], [0, 0.01, 0.2], [0, -0.01, 0.25], [0, 0.01, 0.25]]\n";

TEST(HairstyleTest, LoadsAndRoundTripsBitIdentically) {
  const Hairstyle a = loadHairstyle(test::writeTemp("good.yaml", kGood));
  ASSERT_EQ(a.strips.size(), 1u);
  EXPECT_EQ(a.strips[0].columns, 2);
  EXPECT_EQ(a.strips[0].rows, 4);
  EXPECT_DOUBLE_EQ(a.strips[0].hair_length, 0.15);
  EXPECT_NEAR(a.strips[0].columnLength(0), 0.1505012563, 1e-9);
  const std::string path = test::tempPath("saved.yaml");
  saveHairstyle(a, path);
  const Hairstyle b = loadHairstyle(path);
  ASSERT_EQ(b.strips[0].points.size(), a.strips[0].points.size());
  EXPECT_EQ(0, std::memcmp(a.strips[0].points.data(), b.strips[0].points.data(), 8 * sizeof(Vec3)));
  EXPECT_EQ(a.scalp.radii(), b.scalp.radii());
  EXPECT_FLOAT_EQ(b.strips[0].color.r, 0.3f);
  // Against kGood's literals: points row-major (rows x columns), each [x, y, z], in and out.
  for (const Hairstyle* h : {&a, &b}) {
    const std::vector<Vec3>& p = h->strips[0].points;
    EXPECT_EQ(p[1], Vec3(0.0, 0.01, 0.0994987437));
    EXPECT_EQ(p[2], Vec3(0.0, -0.01, 0.15));
    EXPECT_EQ(p[6], Vec3(0.0, -0.01, 0.25));
    EXPECT_EQ(h->strips[0].point(2, 1), Vec3(0.0, 0.01, 0.2));  // row 2, column 1: points[5]
    EXPECT_EQ(h->scalp.center(), Vec3::Zero());
    EXPECT_EQ(h->scalp.radii(), Vec3(0.1, 0.1, 0.1));
  }
  // A scalp with a different number on every axis (the roots stay within the tolerance of it): centre,
  // radii and rpy (REP-103: R = Rz(yaw) Ry(pitch) Rx(roll)) as written, before and after a save.
  std::string text = kGood;
  const std::string scalp = "center: [0, 0, 0], rpy: [0, 0, 0], radii: [0.1, 0.1, 0.1]";
  text.replace(text.find(scalp), scalp.size(),
               "center: [0.0005, -0.0004, 0.0003], rpy: [0.1, -0.05, 0.2], radii: [0.12, 0.1, 0.101]");
  const Hairstyle c = loadHairstyle(test::writeTemp("scalp.yaml", text));
  const std::string saved = test::tempPath("scalp_saved.yaml");
  saveHairstyle(c, saved);
  const Hairstyle d = loadHairstyle(saved);
  const Mat3 rotation = (Eigen::AngleAxisd(0.2, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.05, Vec3::UnitY()) *
                         Eigen::AngleAxisd(0.1, Vec3::UnitX()))
                            .toRotationMatrix();
  for (const Hairstyle* h : {&c, &d}) {
    EXPECT_EQ(h->scalp.center(), Vec3(0.0005, -0.0004, 0.0003));
    EXPECT_EQ(h->scalp.radii(), Vec3(0.12, 0.1, 0.101));
    EXPECT_TRUE(h->scalp.rotation().isApprox(rotation, 1e-12)) << h->scalp.rotation();
  }
}

TEST(HairstyleTest, EveryMalformedKeyIsNamedWithItsValue) {
  const std::vector<test::FileEdit> cases = {
      {"rows: 4", "rows: 3", "strips[0].rows", "3"},
      {"columns: 2", "columns: 1", "strips[0].columns", "1"},
      {"columns: 2", "columns: two", "strips[0].columns", "two"},
      {"hair_length: 0.15", "hair_length: -0.15", "strips[0].hair_length", "-0.15"},
      {"width: 0.02", "width: .inf", "strips[0].width", ".inf"},
      {"thickness_margin: 0.004", "thickness_margin: 5", "strips[0].thickness_margin", "5"},
      {"color: [0.3, 0.2, 0.1, 1.0]", "color: [0.3, 2.0, 0.1]", "strips[0].color[1]", "2"},
      {"radii: [0.1, 0.1, 0.1]", "radii: [0.1, 0, 0.1]", "scalp.radii", "got 0"},
      {"radii: [0.1, 0.1, 0.1]", "radii: [0.1, 0.1]", "scalp.radii", "[0.1, 0.1]"},
      {"[0, 0.01, 0.25]]", "[0, 0.01]]", "strips[0].points[7]", "[0, 0.01]"},
      {"[0, 0.01, 0.25]]", "[0, 0.01, nan]]", "strips[0].points[7][2]", "nan"},
      {"[0, 0.01, 0.25]]", "[0, 0.01, 0.2]]", "strips[0].points[7] (line 12)", "segment length"},
      {", [0, 0.01, 0.25]]", "]", "strips[0].points", "7 points"},
      {"[[0, -0.01, 0.0994987437]", "[[0, -0.01, 0.2]", "strips[0].points[0] (line 11)", "off the scalp"},
      {"    width: 0.02\n", "    width: 0.02\n    lenght: 3\n", "strips[0].lenght", "unknown key"},
      {"format_version: 1", "format_version: 2", "format_version", "2"},
      // Found by fuzz_yaml: far coordinates overflowed the simulator's spring grid (undefined behaviour).
      {"[0, 0.01, 0.25]]", "[0, -0103062241852005262, 0.25]]", "strips[0].points[7]", "+-100 m"},
      {"radii: [0.1, 0.1, 0.1]", "radii: [0.1, 11, 0.1]", "scalp.radii", "(0, 10]"},
      {"center: [0, 0, 0], rpy", "center: [1e200, 0, 0], rpy", "scalp.center", "+-100 m"},
  };
  test::expectEditsNamed(kGood, cases, [](const std::string& path) { loadHairstyle(path); });
}

TEST(HairstyleTest, EmptyStripListIsRejected) {
  const std::string path = test::writeTemp(
      "empty.yaml",
      "format_version: 1\nscalp: {center: [0, 0, 0], rpy: [0, 0, 0], radii: [0.1, 0.1, 0.1]}\nstrips: []\n");
  const std::string m = test::errorOf([&] { loadHairstyle(path); });
  EXPECT_NE(m.find("strips"), std::string::npos) << m;
  EXPECT_NE(m.find("at least 1"), std::string::npos) << m;
}

TEST(HairstyleTest, AStripGivenTwiceIsRefused) {
  // kGood's strip again under another name: its points are the first's. (20,000 copies of one strip took
  // minutes in the springs' neighbour search before this check.)
  const std::string text = kGood;
  const std::size_t strip = text.find("  - name: a");
  ASSERT_NE(strip, std::string::npos);
  std::string copy = text.substr(strip);
  copy.replace(copy.find("name: a"), 7, "name: b");
  const std::string m = test::errorOf([&] { loadHairstyle(test::writeTemp("twice.yaml", text + copy)); });
  EXPECT_NE(
      m.find("twice.yaml: strips[1]: its points are those of strips[0] (within 1e-6 m): a strip given twice"),
      std::string::npos)
      << m;
  // Moved 2 um along the hair: another strip, taken.
  std::string moved = copy;
  for (const char* z : {"0.15]", "0.2]", "0.25]"})
    for (std::size_t at = moved.find(z); at != std::string::npos; at = moved.find(z, at + 1))
      moved.replace(at, std::strlen(z) - 1, std::string(z, std::strlen(z) - 1) + "00002");
  EXPECT_NO_THROW(loadHairstyle(test::writeTemp("moved.yaml", text + moved))) << moved;
}

TEST(HairstyleTest, ValidateHoldsTheLoadersBoundsForHairstylesMadeInCode) {
  // hair_sim_generate and code that builds a Hairstyle reach the Simulator without the loader, so validate
  // itself holds every bound the loader puts on a value (the loader names the line first).
  const Hairstyle good = test::hangingStrip(2, 5, 0.05, 0.0);
  EXPECT_NO_THROW(good.validate("good"));
  struct Case {
    const char* what;
    std::function<void(Hairstyle&)> spoil;
    const char* message;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Case> cases{
      {"hair_length", [](Hairstyle& h) { h.strips[0].hair_length = 20.0; },
       "code: strips[0].hair_length: 20 is outside [0.001, 10]"},
      {"hair_length NaN", [&](Hairstyle& h) { h.strips[0].hair_length = nan; },
       "code: strips[0].hair_length: nan is outside [0.001, 10]"},
      {"width", [](Hairstyle& h) { h.strips[0].width = 2.0; },
       "code: strips[0].width: 2 is outside [0.0001, 1]"},
      {"thickness_margin", [](Hairstyle& h) { h.strips[0].thickness_margin = 0.5; },
       "code: strips[0].thickness_margin: 0.5 is outside [0, 0.1]"},
      {"color", [](Hairstyle& h) { h.strips[0].color.g = 1.5f; },
       "code: strips[0].color[1]: 1.5 is outside [0, 1]"},
      {"columns", [](Hairstyle& h) { h.strips[0].columns = 65; },
       "code: strips[0].columns: 65 is outside [2, 64]"},
      {"rows", [](Hairstyle& h) { h.strips[0].rows = 257; }, "code: strips[0].rows: 257 is outside [4, 256]"},
      {"point", [](Hairstyle& h) { h.strips[0].points[7].x() = 150.0; },
       "code: strips[0].points[7]: [150, 0.005, -0.050125078222809136] has a coordinate beyond +-100 m"},
      {"point NaN", [&](Hairstyle& h) { h.strips[0].points[3].z() = nan; }, "code: strips[0].points[3]: "},
      {"scalp radius",
       [](Hairstyle& h) { h.scalp = Ellipsoid(Vec3::Zero(), Mat3::Identity(), Vec3(0.1, 20, 0.1)); },
       "code: scalp.radii: every radius must be in (0, 10] m, got [0.1, 20, 0.1]"},
      {"scalp center",
       [](Hairstyle& h) { h.scalp = Ellipsoid(Vec3(0, 0, -200), Mat3::Identity(), Vec3(0.1, 0.1, 0.1)); },
       "code: scalp.center: [0, 0, -200] has a coordinate beyond +-100 m"},
  };
  for (const Case& c : cases) {
    Hairstyle h = good;
    c.spoil(h);
    const std::string m = test::errorOf([&] { h.validate("code"); });
    EXPECT_NE(m.find(c.message), std::string::npos) << c.what << ": " << m;
  }
}

TEST(HairstyleTest, ShippedDefaultHairstyleIsValidAndPaperSized) {
  const SimConfig config = loadSimConfig(test::repoPath("config/hair_sim.yaml"));
  const Hairstyle h = loadHairstyle(config.hairstyle_file);
  EXPECT_GE(h.strips.size(), 80u);
  EXPECT_LE(h.strips.size(), 120u);
  for (const Strip& s : h.strips) EXPECT_EQ(s.pointCount(), 10);  // the paper's 10 control points
}

TEST(HairstyleTest, ConfigErrorsNameKeyAndValue) {
  const std::string base = test::repoPath("config/hair_sim.yaml");
  std::ifstream in(base);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::vector<test::FileEdit> cases = {
      {"hinge_stiffness: 4.0e-4", "hinge_stiffness: -1", "physics.hinge_stiffness", "-1"},
      {"substep: 0.004166666666666667", "substep: 0", "physics.substep", "value '0'"},
      {"publish_rate: 30.0", "publish_rate: fast", "publish_rate", "fast"},
      {"world_frame: world", "world_frame: ''", "world_frame", "valid tf frame"},
      {"air_drag: 0.02", "air_drag: 0.02\n  air_dragg: 1", "physics.air_dragg", "unknown key"},
      {"gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, -9.81]", "physics.gravity", "[0.0, -9.81]"},
      {"head_frame: head", "head_frame: world", "head_frame", "'world'"},
      {"gravity: [0.0, 0.0, -9.81]", "gravity: [600.0, 0.0, -800.5]", "physics.gravity",
       "[600, 0, -800.5]: magnitude 1000.4000449820062 m/s^2 is above 1000"},
      {"{name: head,", "{name: '',", "bodies[0].name", "must not be empty"},
      // One publication per substep at most: 1 / 0.004166666666666667 s = 240 Hz.
      {"publish_rate: 30.0", "publish_rate: 250", "publish_rate", "250 Hz"},
      {"hairstyle: hairstyles/default.yaml", "hairstyle: ''", "hairstyle (line 11)", "got an empty string"},
      {"center: [0.0, 0.0, 1.13]", "center: [0.0, 1e300, 1.13]", "bodies[2].center",
       "within +-100000 m, got [0.0, 1e300, 1.13]"},
      {"center: [-0.01, 0.0, 1.45], rpy: [0.0, 0.0, 0.0]",
       "center: [-0.01, 0.0, 1.45], rpy: [0.0, 12.6, 0.0]", "bodies[1].rpy",
       "within +-12.566370614359172 rad (4 pi), got [0.0, 12.6, 0.0]"},
      {"air_drag: 0.02", "air_drag: 0.02\n  air_drag: 5", "physics.air_drag",
       "key 'air_drag' given twice (first on line"},
  };
  test::expectEditsNamed(good, cases, [](const std::string& path) { loadSimConfig(path); });
  // Just inside those limits.
  for (const auto& edit : std::vector<std::pair<std::string, std::string>>{
           {"gravity: [0.0, 0.0, -9.81]", "gravity: [600.0, 0.0, -800.0]"},  // exactly 1000 m/s^2
           {"publish_rate: 30.0", "publish_rate: 240"},
           {"center: [0.0, 0.0, 1.13]", "center: [0.0, -100000, 1.13]"},
           {"center: [-0.01, 0.0, 1.45], rpy: [0.0, 0.0, 0.0]",
            "center: [-0.01, 0.0, 1.45], rpy: [0.0, -12.56, 0.0]"}}) {
    std::string text = good;
    const std::size_t at = text.find(edit.first);
    ASSERT_NE(at, std::string::npos) << edit.first;
    text.replace(at, edit.first.size(), edit.second);
    EXPECT_NO_THROW(loadSimConfig(test::writeTemp("inside.yaml", text))) << edit.second;
  }
}

}  // namespace
}  // namespace hair_sim

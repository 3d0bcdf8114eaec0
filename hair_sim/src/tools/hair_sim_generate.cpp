/// hair_sim_generate: writes a procedural hairstyle YAML (config/hairstyles/default.yaml is made by it).
#include <cstdint>
#include <exception>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"
#include "hair_sim/core/util/YamlReader.hpp"
#include "hair_sim/tools/Arguments.hpp"

namespace {

// Caps that keep memory and time bounded (a million control points: about 125 MB and 20 s; --rows
// 10000000 used to take 18 GB): strips, rings (each has 3 strips at least) and all the strips' control
// points. The generator itself has no such cap (hair_sim_step_profile asks it for up to 1e6 strips).
constexpr int kMaxStrips = 100000;
constexpr int kMaxRings = 1000;
constexpr long long kMaxControlPoints = 1000000;
// Hair lengths (m): the loader takes hair_length in [0.001, 10] m, and the generator varies each strip's
// length by +-8 % (GeneratorOptions::length_jitter) and ends it where its spline ends (a little short of
// its control polygon), so the flags stay that far inside.
constexpr double kMinLength = 0.002;
constexpr double kMaxLength = 9.0;
// The head frame's height (m): within the hairstyle format's coordinate bound.
constexpr double kMaxHeadZ = 100.0;

const char* kUsage =
    "Usage: hair_sim_generate --out FILE.yaml [--strips N] [--rings N] [--columns N] [--rows N]\n"
    "                         [--length-front M] [--length-back M] [--seed N]\n"
    "                         [--config FILE [--head-z M]]\n"
    "Covers an adult scalp ellipsoid (radii 0.095 0.075 0.115 m, head frame) with about N strips\n"
    "(default 100) in rings, with a parting and lengths growing from the front to the back.\n"
    "With --config, the strips are draped clear of the config's bodies (the body named 'head' is\n"
    "the scalp), with the head frame at height --head-z (default 1.6 m) in the world frame.\n"
    "Limits: --strips 1..100000, --rings 1..1000 (at least 3 strips a ring), --columns 2..64,\n"
    "--rows 4..256, at most 1000000 control points (strips x columns x rows), --length-front and\n"
    "--length-back 0.002..9 m, --seed 0..4294967295, --head-z -100..100 m.\n"
    "The file is written only if it passes the checks hair_sim_offline and the node make on loading.\n"
    "Exit status 0 on success, 1 on failure (a bad config, a hairstyle that fails the checks, a file\n"
    "that cannot be written), 2 on bad usage (an unknown flag, a missing or bad value).\n";

int usageError(const std::string& message) {
  std::cerr << "hair_sim_generate: " << message << "\n" << kUsage;
  return 2;
}

/// Checks the hairstyle as hair_sim_offline and the node will when they load it (Hairstyle::validate, which
/// the loader ends with and which holds every bound the loader puts on a value), so that nothing they would
/// refuse is written. Throws std::runtime_error naming `recipe` (the flags that made the hairstyle).
void checkAsLoaded(const hair_sim::Hairstyle& style, const std::string& out, const std::string& recipe) {
  const std::string source = "the hairstyle made by " + recipe;
  try {
    style.validate(source);
  } catch (const std::invalid_argument& e) {
    // "<source>: strips[0].hair_length: ..." -> "strips[0].hair_length: ..."
    std::string what = e.what();
    if (what.compare(0, source.size() + 2, source + ": ") == 0) what.erase(0, source.size() + 2);
    throw std::runtime_error(source + " fails the hairstyle loader's checks, so " + out +
                             " was not written: " + what);
  }
}

}  // namespace

int main(int argc, char** argv) {
  hair_sim::GeneratorOptions o;
  std::string out, config_path;
  double head_z = 1.6;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        std::cout << kUsage;
        return 0;
      }
      if (i + 1 >= argc) return usageError(a + " needs a value");
      const std::string v = argv[++i];
      using hair_sim::integerArgument;
      using hair_sim::realArgument;
      if (a == "--out")
        out = v;
      else if (a == "--strips")
        o.strips = static_cast<int>(integerArgument(a, v, 1, kMaxStrips));
      else if (a == "--rings")
        o.rings = static_cast<int>(integerArgument(a, v, 1, kMaxRings));
      else if (a == "--columns")
        o.columns = static_cast<int>(
            integerArgument(a, v, hair_sim::Strip::kMinColumns, hair_sim::Strip::kMaxColumns));
      else if (a == "--rows")
        o.rows =
            static_cast<int>(integerArgument(a, v, hair_sim::Strip::kMinRows, hair_sim::Strip::kMaxRows));
      else if (a == "--length-front")
        o.length_front = realArgument(a, v, kMinLength, kMaxLength, " m");
      else if (a == "--length-back")
        o.length_back = realArgument(a, v, kMinLength, kMaxLength, " m");
      else if (a == "--seed")
        o.seed = static_cast<std::uint32_t>(hair_sim::unsignedArgument(a, v, UINT32_MAX));
      else if (a == "--config")
        config_path = v;
      else if (a == "--head-z")
        head_z = realArgument(a, v, -kMaxHeadZ, kMaxHeadZ, " m");
      else
        return usageError("unknown argument '" + a + "'");
    }
    if (out.empty()) return usageError("--out is required");
    const long long strips = hair_sim::generatedStripCount(o);
    const long long points = strips * o.columns * o.rows;
    if (points > kMaxControlPoints)
      return usageError("--strips " + std::to_string(o.strips) + " --rings " + std::to_string(o.rings) +
                        " --columns " + std::to_string(o.columns) + " --rows " + std::to_string(o.rows) +
                        ": " + std::to_string(strips) + " strips of " + std::to_string(o.columns * o.rows) +
                        " = " + std::to_string(points) + " control points, above the maximum " +
                        std::to_string(kMaxControlPoints));
  } catch (const hair_sim::UsageError& e) {
    return usageError(e.what());
  }
  // The flags that made the hairstyle, for a message about it (the file was never written).
  std::ostringstream recipe;
  recipe << "--strips " << o.strips << " --rings " << o.rings << " --columns " << o.columns << " --rows "
         << o.rows << " --length-front " << hair_sim::formatDouble(o.length_front) << " --length-back "
         << hair_sim::formatDouble(o.length_back) << " --seed " << o.seed;
  if (!config_path.empty())
    recipe << " --config " << config_path << " --head-z " << hair_sim::formatDouble(head_z);
  try {
    hair_sim::SimConfig config;  // no bodies: the default scalp only
    if (!config_path.empty()) config = hair_sim::loadSimConfig(config_path);
    hair_sim::Iso3 head_in_world = hair_sim::Iso3::Identity();
    head_in_world.translation() = hair_sim::Vec3(0.0, 0.0, head_z);
    hair_sim::Hairstyle style;
    try {
      style = hair_sim::generateHairstyle(config, head_in_world, o);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error((config_path.empty() ? "" : config_path + ": ") + e.what());
    }
    checkAsLoaded(style, out, recipe.str());
    hair_sim::saveHairstyle(style, out);
    std::cout << "hair_sim_generate: " << style.strips.size() << " strips, " << style.controlPointCount()
              << " control points -> " << out << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "hair_sim_generate: error: " << e.what() << "\n";
    return 1;
  }
}

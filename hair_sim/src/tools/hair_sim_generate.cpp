/// hair_sim_generate: writes a procedural hairstyle YAML (config/hairstyles/default.yaml is made by it).
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "hair_sim/core/model/HairstyleGenerator.hpp"
#include "hair_sim/core/model/HairstyleIO.hpp"
#include "hair_sim/core/model/SimConfig.hpp"

namespace {
const char* kUsage =
    "Usage: hair_sim_generate --out FILE.yaml [--strips N] [--rings N] [--columns N] [--rows N]\n"
    "                         [--length-front M] [--length-back M] [--seed N]\n"
    "                         [--config FILE [--head-z M]]\n"
    "Covers an adult scalp ellipsoid (radii 0.095 0.075 0.115 m, head frame) with about N strips\n"
    "(default 100) in rings, with a parting and lengths growing from the front to the back.\n"
    "With --config, the strips are draped clear of the config's bodies (the body named 'head' is\n"
    "the scalp), with the head frame at height --head-z (default 1.6 m) in the world frame.\n";
}

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
      if (i + 1 >= argc) {
        std::cerr << "hair_sim_generate: " << a << " needs a value\n" << kUsage;
        return 2;
      }
      const std::string v = argv[++i];
      if (a == "--out")
        out = v;
      else if (a == "--strips")
        o.strips = std::stoi(v);
      else if (a == "--rings")
        o.rings = std::stoi(v);
      else if (a == "--columns")
        o.columns = std::stoi(v);
      else if (a == "--rows")
        o.rows = std::stoi(v);
      else if (a == "--length-front")
        o.length_front = std::stod(v);
      else if (a == "--length-back")
        o.length_back = std::stod(v);
      else if (a == "--seed")
        o.seed = static_cast<std::uint32_t>(std::stoul(v));
      else if (a == "--config")
        config_path = v;
      else if (a == "--head-z")
        head_z = std::stod(v);
      else {
        std::cerr << "hair_sim_generate: unknown argument '" << a << "'\n" << kUsage;
        return 2;
      }
    }
    if (out.empty()) {
      std::cerr << "hair_sim_generate: --out is required\n" << kUsage;
      return 2;
    }
    hair_sim::SimConfig config;  // no bodies: the default scalp only
    if (!config_path.empty()) config = hair_sim::loadSimConfig(config_path);
    hair_sim::Iso3 head_in_world = hair_sim::Iso3::Identity();
    head_in_world.translation() = hair_sim::Vec3(0.0, 0.0, head_z);
    const hair_sim::Hairstyle style = hair_sim::generateHairstyle(config, head_in_world, o);
    style.validate(out);
    hair_sim::saveHairstyle(style, out);
    std::cout << "hair_sim_generate: " << style.strips.size() << " strips, " << style.controlPointCount()
              << " control points -> " << out << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "hair_sim_generate: error: " << e.what() << "\n";
    return 1;
  }
}
